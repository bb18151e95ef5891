//! Speed targets of robot.md §7 as a table (run with `cargo run --release -p kappe-robot
//! --example bench_table`): IK poses/s single-threaded, self-collision µs per configuration,
//! ladder DP on the fixture-sized graph, and planning a synthetic cap (0.8 m span, 0.2 m rise,
//! 25° tilt, 120 layers × 30 points) from a fixed base and with the base search.

use std::time::Instant;

use kappe_robot::collision::RobotModel;
use kappe_robot::frames::Iso;
use kappe_robot::synthetic::cap_path;
use kappe_robot::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() {
    let mut rng = ChaCha8Rng::seed_from_u64(20250611);
    let qs: Vec<Joints> = (0..200_000)
        .map(|_| {
            std::array::from_fn(|_| rng.random_range(-std::f64::consts::PI..std::f64::consts::PI))
        })
        .collect();
    let poses: Vec<Iso> = qs.iter().map(|q| UR10E.fk(q)).collect();

    let t = Instant::now();
    let mut n = 0usize;
    for p in &poses {
        n += std::hint::black_box(UR10E.ik(std::hint::black_box(p))).len();
    }
    let ik = poses.len() as f64 / t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut acc = 0.0;
    for q in &qs {
        acc += std::hint::black_box(UR10E.fk(std::hint::black_box(q))).t.x;
    }
    let fk = qs.len() as f64 / t.elapsed().as_secs_f64();

    let model = RobotModel::ur10e_with_tool(&[kappe_robot::collision::CapsuleSpec {
        link: 7,
        name: "nozzle".into(),
        a: [0.0, 0.0, 0.02],
        b: [0.0, 0.0, 0.23],
        radius: 0.04,
    }])
    .unwrap();
    let t = Instant::now();
    let mut hits = 0usize;
    for q in &qs {
        hits += usize::from(model.self_collides(std::hint::black_box(q), 0.0));
    }
    let sc = t.elapsed().as_secs_f64() / qs.len() as f64 * 1e6;

    let layers = cap_path(0.8, 0.2, 25.0, 0.008, 120, 30);
    let fixed = kappe_robot::synthetic::fixed_base_setup();
    let first60 = &layers[..60];
    let t = Instant::now();
    let p1 = plan_print(first60, &fixed, &PlanOptions::default());
    let plan_fixed = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let p2 = plan_print(&layers, &RobotSetup::default(), &PlanOptions::default());
    let plan_search = t.elapsed().as_secs_f64();

    println!("| operation | measured | target |");
    println!("|---|---|---|");
    println!(
        "| IK, all solutions, 1 thread | {:.2} M poses/s | ≥ 0.5 M/s |",
        ik / 1e6
    );
    println!("| FK flange, 1 thread | {:.2} M/s | ≥ 3 M/s |", fk / 1e6);
    println!("| self-collision (13 pairs, FK included) | {sc:.2} µs/config | ≤ 5 µs |");
    println!(
        "| plan 60 layers × 30 points, fixed base (2 cores) | {plan_fixed:.2} s ({}) | ≤ 5 s |",
        p1.map(|p| format!("{} waypoints verified", p.waypoint_count()))
            .unwrap_or_else(|e| e.to_string())
    );
    println!(
        "| plan 120 layers × 30 points, base search (2 cores) | {plan_search:.2} s ({}) | ≤ 5 s |",
        p2.map(|p| format!(
            "{} stations, {} waypoints verified",
            p.stations.len(),
            p.waypoint_count()
        ))
        .unwrap_or_else(|e| e.to_string())
    );
    eprintln!("(checksums {n} {acc:.3} {hits})");
}
