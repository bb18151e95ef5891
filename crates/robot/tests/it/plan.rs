//! Planning a small synthetic cap (robot.md §7 "Planning on a cap") and bad input.

use kappe_robot::frames::Iso;
use kappe_robot::synthetic::cap_path;
use kappe_robot::*;

/// A short cap: 16 layers of 12 points, base 1.0 m in front of the first layer (see
/// `examples/try_bases.rs`: from there the first ~60 layers are reachable).
fn small() -> (Vec<PrintLayer>, RobotSetup, PlanOptions) {
    let layers = cap_path(0.8, 0.2, 25.0, 0.008, 16, 12);
    let setup = kappe_robot::synthetic::fixed_base_setup();
    (layers, setup, PlanOptions::default())
}

#[test]
fn plans_and_verifies_a_small_cap() {
    let (layers, setup, opts) = small();
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    assert_eq!(plan.waypoint_count(), 16 * 12);
    let rep = check_plan(&plan);
    assert!(rep.problems.is_empty(), "{:?}", rep.problems);
    // Acceptance: TCP on target ≤ 1e-6 m and axis ≤ 1e-6 rad (closed-form IK gives ~1e-15).
    assert!(rep.max_position_error <= 1e-6 && rep.max_axis_error <= 1e-6);
    assert!(rep.min_clearance >= opts.clearance);
    assert!(rep.max_speed_ratio <= opts.speed_fraction);
    // Layers keep their ids and point indices, times increase.
    let ls: Vec<i64> = plan.stations[0].layers.iter().map(|l| l.layer).collect();
    assert_eq!(ls, (0..16).collect::<Vec<_>>());
    // The random planner is never better than the optimal one on the same graph.
    let rnd = plan_print(
        &layers,
        &setup,
        &PlanOptions {
            planner: PlannerKind::Random,
            random_trials: 3,
            ..opts.clone()
        },
    )
    .unwrap();
    assert!(
        rnd.cost >= plan.cost - 1e-9,
        "random {} < optimal {}",
        rnd.cost,
        plan.cost
    );
}

#[test]
fn tampered_plan_fails_the_check() {
    let (layers, setup, opts) = small();
    let mut plan = plan_print(&layers[..3], &setup, &opts).unwrap();
    plan.stations[0].layers[1].waypoints[4].q[1] += 1e-3;
    let rep = check_plan(&plan);
    assert!(
        rep.problems
            .iter()
            .any(|p| p.contains("layer 1 point 4") && p.contains("misses the target")),
        "{:?}",
        rep.problems
    );
}

#[test]
fn bad_input_is_named() {
    let (layers, mut setup, opts) = small();
    let e = plan_print(
        &layers,
        &setup,
        &PlanOptions {
            epsilon: 0.0,
            ..opts.clone()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("epsilon"), "{e}");
    let mut zero = setup.clone();
    zero.tool.flange_from_tcp = Iso::IDENTITY.to_mat4();
    let e = plan_print(&layers, &zero, &opts).unwrap_err().to_string();
    assert!(e.contains("zero length"), "{e}");
    // Base inside an obstacle.
    setup.obstacles.push(kappe_robot::collision::Obstacle::Box {
        name: "pillar".into(),
        center: [0.0, 1.0, 0.0],
        half_extents: [0.3, 0.3, 1.0],
        yaw: 0.0,
    });
    let e = plan_print(&layers, &setup, &opts).unwrap_err();
    assert!(
        matches!(&e, RobotError::Unplannable(f) if f.kind == FailureKind::BasePlacement),
        "{e}"
    );
    assert!(e.to_string().contains("pillar"), "{e}");
    // Unreachable: a layer 3 m away names its first point.
    let mut far = layers[..2].to_vec();
    far[1].points[3].position[0] += 3.0;
    setup.obstacles.clear();
    let e = plan_print(&far, &setup, &opts).unwrap_err();
    match e {
        RobotError::Unplannable(f) => {
            assert_eq!(
                (f.layer, f.index, f.kind.clone()),
                (1, 3, FailureKind::Unreachable),
                "{f}"
            );
        }
        other => panic!("{other}"),
    }
}

#[test]
fn exports_round_trip() {
    let (layers, setup, opts) = small();
    let opts = PlanOptions {
        program: ProgramOptions {
            max_moves_per_program: 50,
            ..Default::default()
        },
        ..opts
    };
    let plan = plan_print(&layers[..8], &setup, &opts).unwrap();
    // CSV: same joint values (exact round trip, checked at 1e-12) in plan order.
    let mut csv = Vec::new();
    write_trajectory_csv(&plan, &mut csv).unwrap();
    let text = String::from_utf8(csv).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // Hold rows (priming, program change) repeat their waypoint at its departure time.
    let rows: Vec<Vec<f64>> = rows
        .iter()
        .enumerate()
        .filter(|(k, r)| *k == 0 || rows[k - 1][1..3] != r[1..3])
        .map(|(_, r)| r.clone())
        .collect();
    let wps: Vec<(i64, &Waypoint)> = plan.stations[0]
        .layers
        .iter()
        .flat_map(|l| l.waypoints.iter().map(move |w| (l.layer, w)))
        .collect();
    assert_eq!(rows.len(), wps.len());
    for (r, (layer, w)) in rows.iter().zip(&wps) {
        assert_eq!((r[1] as i64, r[2] as usize), (*layer, w.index));
        for j in 0..6 {
            assert!((r[4 + j] - w.q[j]).abs() <= 1e-12);
        }
    }
    // URScript: one move per waypoint after the first, plus the approach (movej + movel) and
    // the final retract; whole layers of 12 points in parts of ≤ 50 moves: the first part holds
    // 2 + 11 + 36 = 49 (4 layers; a 5th would need 61), each continuing part 1 + 4·12 = 49 but
    // the last also retracts (1 + 12·k + 1 ≤ 50 → 4 layers, 50), so 8 layers → 2 parts.
    let parts = urscript_programs(&plan).unwrap();
    assert_eq!(parts.len(), 2);
    let moves: Vec<usize> = parts
        .iter()
        .map(|p| {
            p.lines()
                .filter(|l| l.trim_start().starts_with("move"))
                .count()
        })
        .collect();
    assert_eq!(moves, vec![49, 50]);
    assert_eq!(
        moves.iter().sum::<usize>(),
        plan.waypoint_count() - 1 + 2 + 1 + 1
    );
    // JSON round trip re-verifies.
    let mut json = Vec::new();
    write_plan_json(&plan, &mut json).unwrap();
    let back: Plan = serde_json::from_slice(&json).unwrap();
    assert!(check_plan(&back).problems.is_empty());
}

#[test]
fn joint_position_limits_are_validated_and_used_by_planner_check_and_lint() {
    let (layers, setup, opts) = small();
    let layers = &layers[..3];
    let with = |j: usize, r: [f64; 2]| {
        let mut o = opts.clone();
        o.limits.position_deg[j] = r;
        o
    };
    // Bad values: each is the named error, with the joint (1-based) and the range.
    for (j, r) in [
        (0, [10.0, 10.0]),
        (1, [f64::NAN, 90.0]),
        (2, [-190.0, 361.0]),
        (5, [-400.0, 0.0]),
    ] {
        let e = plan_print(layers, &setup, &with(j, r)).unwrap_err();
        assert!(
            matches!(e, RobotError::JointPositionLimit { joint, .. } if joint == j + 1),
            "{e}"
        );
        assert!(e.to_string().contains("±360°"), "{e}");
    }
    // The default plan, and the range its base joint actually uses.
    let plan = plan_print(layers, &setup, &opts).unwrap();
    let q1: Vec<f64> = plan.stations[0]
        .layers
        .iter()
        .flat_map(|l| &l.waypoints)
        .map(|w| w.q[0].to_degrees())
        .collect();
    let (lo, hi) = q1
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    // Limits that leave the base joint 1° short of its range: no plan (whole turns do not help
    // a range narrower than a turn).
    let e = plan_print(layers, &setup, &with(0, [lo + 1.0, hi + 1.0]));
    assert!(e.is_err(), "planned inside too narrow limits");
    // Limits that hold the used range (and the approach and retract, 10° more) plan the same
    // print, and the check holds them.
    let ok = plan_print(layers, &setup, &with(0, [lo - 10.0, hi + 10.0])).unwrap();
    assert_eq!(ok.waypoint_count(), plan.waypoint_count());
    // Narrowing the limits after planning makes the check fail on the same plan.
    let mut narrowed = ok.clone();
    narrowed.options.limits.position_deg[0] = [lo + 1.0, hi + 1.0];
    let rep = check_plan(&narrowed);
    assert!(
        rep.problems
            .iter()
            .any(|p| p.contains("outside the limits")),
        "{:?}",
        rep.problems
    );
    // Lint: the same movej is fine with the UR10e limits and rejected beyond narrowed ones.
    let prog = "def p():\n  movej([0.5, -1.0, 1.0, -1.5, -1.57, 0.0], a=1.0, v=0.5)\nend\np()\n";
    assert!(lint(prog, 10).ok());
    let mut lim = kappe_robot::setup::JointLimitOptions::default().position();
    lim[0] = [-0.2, 0.2];
    let rep = lint_with_limits(prog, 10, &lim);
    assert!(
        rep.problems
            .iter()
            .any(|p| p.contains("joint 1") && p.contains("beyond its limits")),
        "{:?}",
        rep.problems
    );
}
