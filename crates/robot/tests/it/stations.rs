//! Stations along the work and the base-pose tolerance check (issue 15).

use kappe_robot::collision::Obstacle;
use kappe_robot::frames::Iso;
use kappe_robot::stations::{DriveSpec, fewest_stations, station_schedule};
use kappe_robot::synthetic::cap_path;
use kappe_robot::tolerance::{BaseTolerance, check_base_tolerance, station_margins};
use kappe_robot::*;

/// Fewest contiguous ranges covering 0..n by dynamic programming over every split (the
/// independent oracle for the greedy rule).
fn brute_force(n: usize, reach: &[usize]) -> Option<usize> {
    let mut best = vec![usize::MAX; n + 1];
    best[0] = 0;
    for s in 0..n {
        if best[s] == usize::MAX {
            continue;
        }
        for e in s + 1..=reach[s].min(n) {
            best[e] = best[e].min(best[s] + 1);
        }
    }
    (best[n] != usize::MAX).then_some(best[n])
}

/// Greedy = optimum on seeded random monotone reach functions (xorshift, seed fixed).
#[test]
fn greedy_stations_are_fewest() {
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut rnd = |m: u64| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x % m
    };
    for _ in 0..300 {
        let n = 1 + rnd(40) as usize;
        // Monotone reach: r(s) = max(r(s − 1), s + random length), sometimes s (a gap).
        let mut prev = 0usize;
        let reach: Vec<usize> = (0..n)
            .map(|s| {
                prev = prev.max(s + rnd(8) as usize);
                prev
            })
            .collect();
        let greedy = fewest_stations(n, |s| reach[s]);
        match brute_force(n, &reach) {
            Some(k) => {
                let g = greedy.unwrap();
                assert_eq!(g.len(), k, "reach {reach:?}");
                // Contiguous, ordered, covering 0..n.
                assert_eq!(g[0].start, 0);
                assert!(g.windows(2).all(|w| w[0].end == w[1].start));
                assert_eq!(g.last().unwrap().end, n);
            }
            None => assert!(greedy.is_err()),
        }
    }
}

fn small(layers: usize) -> (Vec<PrintLayer>, RobotSetup, PlanOptions) {
    let layers = cap_path(0.8, 0.2, 25.0, 0.008, layers, 12);
    let setup = kappe_robot::synthetic::fixed_base_setup();
    (layers, setup, PlanOptions::default())
}

/// A wall `gap` behind the mobile-base body of the `small` set-up. The body (robot.md §5,
/// `RobotSetup::default`) extends 1.085 m behind the arm base along the base's −x, which is world
/// +y for yaw 270°: its back face is at y = 1.0 + 1.085 = 2.085 m.
fn wall_behind(gap: f64) -> Obstacle {
    Obstacle::Box {
        name: "end_wall".into(),
        center: [0.0, 2.085 + gap + 0.05, -0.3],
        half_extents: [1.0, 0.05, 0.5],
        yaw: 0.0,
    }
}

/// A plan that is valid as planned but whose base clearance is smaller than the tolerance
/// allows fails the tolerance check; with room to spare it passes.
///
/// 5 mm gap: a 10 mm drive error toward the wall closes it, so the check must fail. 40 mm gap:
/// the body's back corners move by at most 10 mm + 0.41 m · sin 1° = 17.2 mm, so it must pass.
#[test]
fn base_tolerance_fails_a_plan_with_too_little_clearance() {
    let (layers, setup, opts) = small(3);
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    for (gap, ok) in [(0.005, false), (0.040, true)] {
        let mut p = plan.clone();
        p.setup.obstacles.push(wall_behind(gap));
        // As planned, the plan is valid: the wall does not touch the base and the arm is clear.
        let rep = check_plan(&p);
        assert!(rep.problems.is_empty(), "gap {gap}: {:?}", rep.problems);
        let tol = check_base_tolerance(&p, &BaseTolerance::default());
        assert_eq!(tol.poses_per_station, 9);
        assert_eq!(tol.ok(), ok, "gap {gap}: {:?}", tol.problems);
        if !ok {
            assert!(
                tol.problems
                    .iter()
                    .any(|m| m.contains("mobile base body") && m.contains("end_wall")),
                "{:?}",
                tol.problems
            );
        }
        // The body's distance to the wall under the errors is the gap less the shift, at least
        // gap − 17.2 mm and at most gap − 10 mm, clamped at 0 (parry reports 0 for overlap);
        // 1e-4 m: parry's box distance is exact to ~1e-12, the 17.2 mm bound is rounded.
        let d = tol.min_body_distance.unwrap();
        let (lo, hi) = (
            (gap - 0.0173_f64).max(0.0),
            (gap - 0.010_f64).max(0.0) + 1e-4,
        );
        assert!(d <= hi && d >= lo, "gap {gap}: {d}");
        assert!(tol.min_clearance >= opts.clearance);
    }
    // A zero tolerance only checks the plan as planned: the 5 mm gap then passes.
    let mut p = plan.clone();
    p.setup.obstacles.push(wall_behind(0.005));
    let zero = BaseTolerance {
        position: 0.0,
        yaw_deg: 0.0,
        ..BaseTolerance::default()
    };
    assert!(check_base_tolerance(&p, &zero).ok());
}

/// The largest base error a station survives (issue 28): with a wall 40 mm behind the base body,
/// the body's back corners move toward it by about s · (10 mm + 0.41 m · sin 1°) = s · 17.2 mm
/// at s times the default box, so the body touches at s ≈ 40 / 17.2 = 2.33. The margin must be
/// the smaller of that and the station's margin without the wall, to within the search's
/// resolution (0.125) and the rounding of the 0.41 m lever (≤ 0.05 in s); and the check at the
/// found box must pass while a box 0.25 larger fails.
#[test]
fn station_margin_stops_where_the_base_would_touch_the_wall() {
    let (layers, setup, opts) = small(3);
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    let tol = BaseTolerance::default();
    let free = station_margins(&plan, &tol);
    assert_eq!(free.len(), plan.stations.len());
    let mut p = plan.clone();
    p.setup.obstacles.push(wall_behind(0.040));
    let walled = station_margins(&p, &tol);
    let touch = 0.040 / (0.010 + 0.41 * 1f64.to_radians().sin());
    for (f, w) in free.iter().zip(&walled) {
        assert_eq!(f.station, w.station);
        let expected = f.scale.min(touch);
        assert!(
            (w.scale - expected).abs() <= 0.125 + 0.05,
            "station {}: margin {} against {expected} (free {})",
            w.station,
            w.scale,
            f.scale
        );
        assert!(!w.at_least);
        assert!((w.position_m - w.scale * tol.position).abs() < 1e-15);
        let at = |s: f64| BaseTolerance {
            position: s * tol.position,
            yaw_deg: s * tol.yaw_deg,
            ..tol.clone()
        };
        assert!(check_base_tolerance(&p, &at(w.scale)).ok());
        assert!(!check_base_tolerance(&p, &at(w.scale + 0.25)).ok());
    }
}

/// The schedule of a plan: ranges contiguous and ordered, relocation = distance / speed + settle.
#[test]
fn schedule_of_a_two_station_plan() {
    let (layers, _, opts) = small(4);
    // Two stations from two fixed poses 0.05 m apart: plan each half and join them.
    let pose = |y: f64| {
        Iso::translation(0.0, y, 0.0)
            .mul(&Iso::rot_z(1.5 * std::f64::consts::PI))
            .to_mat4()
    };
    let mk = |y: f64| RobotSetup {
        base: BasePlacement::Fixed {
            world_from_base: pose(y),
        },
        ..RobotSetup::default()
    };
    let a = plan_print(&layers[..2], &mk(1.0), &opts).unwrap();
    let b = plan_print(&layers[2..], &mk(1.05), &opts).unwrap();
    let mut joined = a.clone();
    let shift = a.total_time + 1.0;
    let mut st = b.stations[0].clone();
    for l in &mut st.layers {
        for w in &mut l.waypoints {
            w.t += shift;
        }
    }
    joined.stations.push(st);
    let drive = DriveSpec {
        speed: 0.1,
        settle_time: 30.0,
    };
    let s = station_schedule(&joined, &drive).unwrap();
    assert_eq!(s.stations.len(), 2);
    assert_eq!(s.stations[0].range, [0, 2]);
    assert_eq!(s.stations[1].range, [2, 4]);
    // 0.05 m at 0.1 m/s + 30 s (1e-9: two subtractions of O(1) coordinates).
    assert!((s.stations[0].relocation_time - 30.5).abs() < 1e-9);
    assert_eq!(s.stations[1].relocation_time, 0.0);
    assert!((s.total_time - s.station_time - 30.5).abs() < 1e-9);
    let bad = DriveSpec {
        speed: 0.0,
        settle_time: 1.0,
    };
    assert!(
        station_schedule(&joined, &bad)
            .unwrap_err()
            .contains("speed")
    );
}
