//! FK and IK against `ur10e_ik.json` (robot.md §7 "FK", "IK", "Unreachable", "Singular",
//! "Free axis", "Properties").

use std::f64::consts::PI;

use kappe_robot::frames::frame_from_z;
use kappe_robot::kinematics::{JOINT_LIMITS, equivalents_in_limits, within_limits, wrap};
use kappe_robot::{Iso, UR10E};
use parry3d_f64::glamx::DVec3;
use proptest::prelude::*;

use crate::common::*;

/// Match fixture solutions to computed ones one-to-one by max_j |wrap(Δq_j)| ≤ `tol`, and check
/// the counts agree exactly.
fn assert_same_set(id: &str, computed: &[[f64; 6]], expected: &[[f64; 6]], tol: f64) {
    assert_eq!(computed.len(), expected.len(), "{id}: solution count");
    let mut used = vec![false; computed.len()];
    for e in expected {
        let hit = computed
            .iter()
            .enumerate()
            .find(|(i, c)| !used[*i] && (0..6).all(|j| wrap(c[j] - e[j]).abs() <= tol));
        let (i, _) =
            hit.unwrap_or_else(|| panic!("{id}: fixture solution {e:?} not found in {computed:?}"));
        used[i] = true;
    }
}

/// FK·tool reproduces the target: position ≤ `tol` m and rotation angle ≤ `tol` rad.
fn assert_reproduces(id: &str, q: &[f64; 6], flange_from_tcp: &Iso, target: &Iso, tol: f64) {
    let tcp = UR10E.fk(q).mul(flange_from_tcp);
    let dp = (tcp.t - target.t).length();
    let da = tcp.rotation_angle_to(target);
    assert!(
        dp <= tol && da <= tol,
        "{id}: q {q:?} misses the target by {dp:.2e} m, {da:.2e} rad"
    );
}

#[test]
fn fk_matches_fixture_and_anchor() {
    let f = fixture("ur10e_ik.json");
    // Anchor q = 0: flange at (a2+a3, −(d4+d6), d1−d5) with R = [[1,0,0],[0,0,−1],[0,1,0]].
    let t0 = UR10E.fk(&[0.0; 6]);
    let want = Iso::from_mat4_unchecked(&[
        [1.0, 0.0, 0.0, -1.18425],
        [0.0, 0.0, -1.0, -0.2907],
        [0.0, 1.0, 0.0, 0.06085],
        [0.0, 0.0, 0.0, 1.0],
    ]);
    // 1e-15: exact arithmetic on exact cos/sin of 0 gives the anchor up to one rounding.
    assert!(t0.max_abs_diff(&want) < 1e-15);
    let cases = f["fk_cases"].as_array().unwrap();
    assert_eq!(cases.len(), 200);
    for c in cases {
        let q = joints(&c["q"]);
        let t = UR10E.fk(&q);
        // 1e-9: the fixture comes from pinocchio on a URDF that rounds π/2 to 1.570796327,
        // which alone moves entries by ~6e-10 (robot.md §7).
        assert!(
            t.max_abs_diff(&iso(&c["T_base_flange"])) <= 1e-9,
            "{}",
            c["id"]
        );
        let frames = UR10E.fk_frames(&q);
        for (i, o) in c["dh_frame_origins_1_to_6"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
        {
            let o = DVec3::from(vec3(o));
            assert!(
                (frames[i + 1].t - o).abs().max_element() <= 1e-9,
                "{} frame {}",
                c["id"],
                i + 1
            );
        }
        assert!(frames[6].max_abs_diff(&t) < 1e-15);
    }
}

#[test]
fn ik_matches_fixture_sets() {
    let f = fixture("ur10e_ik.json");
    let cases = f["ik_cases"].as_array().unwrap();
    assert_eq!(cases.len(), 200);
    let mut worst = 0.0f64;
    for c in cases {
        let id = c["id"].as_str().unwrap();
        let target = iso(&c["T_base_flange"]);
        let sols = UR10E.ik(&target);
        assert_eq!(
            sols.len() as u64,
            c["n_solutions"].as_u64().unwrap(),
            "{id}"
        );
        // 1e-6 rad: robot.md §7 (the fixture's own two solvers agree to 1e-7).
        assert_same_set(id, sols.as_slice(), &joints_list(&c["solutions"]), 1e-6);
        for q in sols.as_slice() {
            assert!(
                q.iter().all(|v| *v > -PI && *v <= PI),
                "{id}: not canonical {q:?}"
            );
            // 1e-8 m / rad: closed form in f64 on well-conditioned poses (margins in the fixture).
            assert_reproduces(id, q, &Iso::IDENTITY, &target, 1e-8);
            let t = UR10E.fk(q);
            worst = worst.max((t.t - target.t).length());
        }
    }
    assert!(worst < 1e-8);
}

#[test]
fn ik_tcp_cases_straight_and_offset_tilted() {
    let f = fixture("ur10e_ik.json");
    for set in ["straight_nozzle", "offset_tilted_nozzle"] {
        let s = &f["tcp_cases"][set];
        let flange_from_tcp = iso(&s["T_flange_tcp"]);
        let tcp_from_flange = flange_from_tcp.inverse();
        let cases = s["cases"].as_array().unwrap();
        assert_eq!(cases.len(), 50);
        for c in cases {
            let id = format!("{set}/{}", c["id"].as_str().unwrap());
            let target = iso(&c["T_base_tcp"]);
            let sols = UR10E.ik_tcp(&target, &tcp_from_flange);
            assert_same_set(&id, sols.as_slice(), &joints_list(&c["solutions"]), 1e-6);
            for q in sols.as_slice() {
                assert_reproduces(&id, q, &flange_from_tcp, &target, 1e-8);
            }
        }
    }
}

#[test]
fn unreachable_gives_no_solution() {
    let f = fixture("ur10e_ik.json");
    for c in f["unreachable_cases"].as_array().unwrap() {
        let sols = UR10E.ik(&iso(&c["T_base_flange"]));
        assert!(sols.is_empty(), "{}", c["id"]);
    }
    // Non-finite input: no panic, no solution.
    let mut bad = Iso::IDENTITY;
    bad.t.x = f64::NAN;
    assert!(UR10E.ik(&bad).is_empty());
}

#[test]
fn singular_poses_return_valid_solutions() {
    let f = fixture("ur10e_ik.json");
    for c in f["singular_cases"].as_array().unwrap() {
        let id = c["id"].as_str().unwrap();
        let target = iso(&c["T_base_flange"]);
        let sols = UR10E.ik(&target);
        assert!(!sols.is_empty(), "{id}");
        for q in sols.as_slice() {
            // 1e-6: robot.md §7 for exactly singular poses (acos near ±1 loses half the digits).
            assert_reproduces(id, q, &Iso::IDENTITY, &target, 1e-6);
        }
    }
}

#[test]
fn free_axis_rotations_match_fixture() {
    let f = fixture("ur10e_ik.json");
    let cases = f["free_axis_cases"].as_array().unwrap();
    assert_eq!(cases.len(), 12);
    for c in cases {
        let flange_from_tcp = iso(&c["T_flange_tcp"]);
        let tcp_from_flange = flange_from_tcp.inverse();
        let point = DVec3::from(vec3(&c["point"]));
        let axis = DVec3::from(vec3(&c["tool_axis"]));
        let x_ref = DVec3::from(vec3(&c["x_ref"]));
        let base = frame_from_z(point, axis, x_ref);
        for r in c["rotations"].as_array().unwrap() {
            let id = format!("{}/{}", c["id"].as_str().unwrap(), r["j"]);
            let phi = r["phi"].as_f64().unwrap();
            let target = base.mul(&Iso::rot_z(phi));
            // Our frame construction must equal the fixture's target frame (1e-12: same
            // formula, a few roundings).
            assert!(target.max_abs_diff(&iso(&r["T_base_tcp"])) < 1e-12, "{id}");
            let sols = UR10E.ik_tcp(&target, &tcp_from_flange);
            assert_same_set(&id, sols.as_slice(), &joints_list(&r["solutions"]), 1e-6);
        }
    }
}

#[test]
fn equivalents_stay_in_limits() {
    let q = [0.0, 1.0, -1.0, 3.0, -0.5, 2.0];
    let all = equivalents_in_limits(&q, &JOINT_LIMITS);
    // joint 1: 0, ±2π (3); joints 2, 4, 5, 6: 2 each; elbow held to ±π: 1 → 3·2⁴ = 48.
    assert_eq!(all.len(), 48);
    for v in &all {
        assert!(within_limits(v, &JOINT_LIMITS));
        assert!(UR10E.fk(v).max_abs_diff(&UR10E.fk(&q)) < 1e-12);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// IK(FK(q)) contains q mod 2π (robot.md §7 properties), away from the singularities.
    #[test]
    fn ik_inverts_fk(q in proptest::array::uniform6(-PI..PI)) {
        let t = UR10E.fk(&q);
        prop_assume!(q[4].sin().abs() > 1e-3 && q[2].sin().abs() > 1e-3);
        prop_assume!(UR10E.shoulder_margin(&t) > 1e-4);
        let sols = UR10E.ik(&t);
        // 1e-6 rad: conditioning near (but outside) the singular margins above.
        let found = sols.as_slice().iter().any(|s| (0..6).all(|j| wrap(s[j] - q[j]).abs() < 1e-6));
        prop_assert!(found, "q {:?} not in {:?}", q, sols.as_slice());
    }

    /// Coaxial tool: IK(T·Rz(φ)) = IK(T) with q6 shifted by φ (robot.md §1.4), within 1e-9.
    #[test]
    fn coaxial_rotation_shifts_q6(q in proptest::array::uniform6(-PI..PI), phi in -PI..PI) {
        prop_assume!(q[4].sin().abs() > 1e-2 && q[2].sin().abs() > 1e-2);
        let tool = Iso::translation(0.0, 0.0, 0.2);
        let tcp_from_flange = tool.inverse();
        let t = UR10E.fk(&q).mul(&tool);
        prop_assume!(UR10E.shoulder_margin(&UR10E.fk(&q)) > 1e-3);
        let a = UR10E.ik_tcp(&t, &tcp_from_flange);
        let b = UR10E.ik_tcp(&t.mul(&Iso::rot_z(phi)), &tcp_from_flange);
        prop_assert_eq!(a.len(), b.len());
        for s in a.as_slice() {
            let mut shifted = *s;
            shifted[5] += phi;
            let found = b.as_slice().iter().any(|r| (0..6).all(|j| wrap(r[j] - shifted[j]).abs() < 1e-9));
            prop_assert!(found);
        }
    }
}
