//! The ladder fixture (robot.md §7 "Ladder DP"): optimal cost 0.393167, path, random ≥ optimal.

use std::f64::consts::TAU;

use kappe_robot::kinematics::wrap;
use kappe_robot::ladder::{solve_optimal, solve_random};
use kappe_robot::{Iso, UR10E};

use crate::common::*;

struct Ladder {
    rungs: Vec<Vec<[f64; 6]>>,
    eps: f64,
    data: serde_json::Value,
}

fn ladder() -> Ladder {
    let f = fixture("ur10e_ladder.json");
    let l = &f["ladder"];
    let tcp_from_flange = iso(&l["T_flange_tcp"]).inverse();
    let n_rot = l["n_rot"].as_u64().unwrap() as usize;
    // Vertices computed by our own IK from the fixture's targets (fixture convention:
    // T_base_tcp(k, j) = targets[k]·Rz(2πj/n_rot)).
    let rungs: Vec<Vec<[f64; 6]>> = l["targets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            let target = iso(t);
            (0..n_rot)
                .flat_map(|j| {
                    let tj = target.mul(&Iso::rot_z(TAU * j as f64 / n_rot as f64));
                    UR10E.ik_tcp(&tj, &tcp_from_flange).as_slice().to_vec()
                })
                .collect()
        })
        .collect();
    Ladder {
        rungs,
        eps: l["epsilon"].as_f64().unwrap(),
        data: l.clone(),
    }
}

fn step_cost(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    (0..6).map(|j| wrap(b[j] - a[j]).powi(2)).sum()
}

#[test]
fn optimal_cost_path_and_random_never_better() {
    let l = ladder();
    let sizes: Vec<usize> = l.rungs.iter().map(Vec::len).collect();
    let want_sizes: Vec<usize> = l.data["rung_sizes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(sizes, want_sizes);
    let edge = |k: usize, i: usize, j: usize| {
        let c = step_cost(&l.rungs[k][i], &l.rungs[k + 1][j]);
        (c <= l.eps).then_some(c)
    };
    let opt = solve_optimal(&sizes, edge).unwrap();
    let want = l.data["optimal_cost"].as_f64().unwrap();
    // Relative 1e-9 (robot.md §7): the same sums over IK solutions equal to 1e-13.
    assert!(
        (opt.cost - want).abs() <= 1e-9 * want,
        "{} vs {want}",
        opt.cost
    );
    // The reported cost is the recomputed cost of the returned path.
    let path: Vec<[f64; 6]> = opt
        .vertices
        .iter()
        .enumerate()
        .map(|(k, &v)| l.rungs[k][v])
        .collect();
    let recomputed: f64 = path.windows(2).map(|w| step_cost(&w[0], &w[1])).sum();
    assert!((recomputed - opt.cost).abs() < 1e-12);
    for (k, q) in joints_list(&l.data["optimal_path_q_canonical"])
        .iter()
        .enumerate()
    {
        // 1e-9 rad: robot.md §7 (our IK matches the fixture IK to ~1e-14).
        assert!(
            (0..6).all(|j| wrap(path[k][j] - q[j]).abs() < 1e-9),
            "rung {k}"
        );
    }
    for seed in 0..20 {
        let r = solve_random(&sizes, edge, 10, seed).unwrap();
        assert!(
            r.cost >= opt.cost - 1e-12,
            "seed {seed}: random {} < optimal {}",
            r.cost,
            opt.cost
        );
        // Both respect ε on every step.
        for (k, w) in r.vertices.windows(2).enumerate() {
            assert!(step_cost(&l.rungs[k][w[0]], &l.rungs[k + 1][w[1]]) <= l.eps);
        }
    }
    // Same seed, same answer.
    assert_eq!(
        solve_random(&sizes, edge, 5, 7).unwrap(),
        solve_random(&sizes, edge, 5, 7).unwrap()
    );
}

#[test]
fn failures_name_the_rung() {
    use kappe_robot::ladder::LadderFailure;
    let r = solve_optimal(&[2, 0, 3], |_, _, _| Some(1.0));
    assert_eq!(r, Err(LadderFailure::EmptyRung { rung: 1 }));
    let r = solve_optimal(&[2, 2, 3], |k, _, _| (k == 0).then_some(1.0));
    assert_eq!(r, Err(LadderFailure::NoEdge { rung: 2 }));
    let r = solve_random(&[2, 2, 3], |k, _, _| (k == 0).then_some(1.0), 3, 1);
    assert_eq!(r, Err(LadderFailure::NoEdge { rung: 2 }));
}
