//! The robot stages of the default cap, timed in release (issue 13's speed target: planning,
//! timing and linting ≤ 3 s): `cargo run --release -p kappe --example robot_timings [-- OUT.json]`.
//! With OUT.json it also writes the planner's inputs (layers, setup, options) for
//! `cargo run --release -p kappe-robot --example plan_file -- OUT.json`.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let cap = kappe::design_cap(&kappe::Design::default(), kappe::Context::default())?;
    let (setup, options) = kappe::robot_plan::robot_inputs(&cap);
    let layers = kappe::robot_plan::print_layers(&cap.path);
    if let Some(out) = std::env::args().nth(1) {
        let v = serde_json::json!({ "layers": layers, "setup": setup, "options": options });
        std::fs::write(&out, serde_json::to_string(&v)?)?;
    }
    // Planning (ladder, stations) + timing + the independent check, all inside plan_print.
    let load = load_average();
    let cpu0 = cpu_seconds();
    let t = Instant::now();
    let plan = kappe_robot::plan_print(&layers, &setup, &options)?;
    let t_plan = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let files = kappe_robot::program_files(&plan, "program_part")?;
    let t_prog = t.elapsed().as_secs_f64();
    let t = Instant::now();
    for f in &files {
        let rep = kappe_robot::lint(&f.text, options.program.max_moves_per_program);
        if !rep.ok() {
            return Err(format!("{}: {:?}", f.name, rep.problems).into());
        }
    }
    let t_lint = t.elapsed().as_secs_f64();
    let cpu = cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
    let t = Instant::now();
    let meshes = kappe_robot::meshes::verify_meshes(&plan, 1)?;
    let t_mesh = t.elapsed().as_secs_f64();
    println!(
        "default cap: {} stations, {} waypoints, {} programs, print {:.1} s, total {:.1} s, {} slowdowns",
        plan.stations.len(),
        plan.waypoint_count(),
        files.len(),
        plan.print_time,
        plan.total_time,
        plan.slowdowns.len()
    );
    println!("| stage | seconds |\n|---|---:|");
    println!("| plan + timing + check (plan_print) | {t_plan:.3} |");
    println!("| write the programs | {t_prog:.3} |");
    println!("| lint every program | {t_lint:.3} |");
    println!(
        "| **planning + timing + linting** | **{:.3}** wall, {} CPU (load average {load} before) |",
        t_plan + t_prog + t_lint,
        cpu.map_or_else(|| "?".to_string(), |c| format!("{c:.2} s"))
    );
    println!(
        "| mesh verification ({} waypoints) | {t_mesh:.3} |",
        meshes.waypoints_checked
    );
    if let Some(c) = &plan.certified {
        println!(
            "capsules, certified along the motion: environment ≥ {:.4} m (approaches and retracts ≥ {:.4} m), self ≥ {:.4} m ({} configurations)",
            c.clearance, c.approach_clearance, c.self_distance, c.configurations
        );
    }
    if let Some(a) = &meshes.along_motion {
        println!(
            "meshes at waypoints: environment {:.4} m, self {:.4} m; certified along the motion: environment ≥ {:.4} m, nozzle ≥ {:.4} m, self ≥ {:.4} m",
            meshes.meshes.environment.distance,
            meshes.meshes.self_distance.distance,
            a.environment.distance,
            a.nozzle.distance,
            a.self_distance.distance
        );
    }
    let sizes: Vec<usize> = plan.parts.iter().map(|p| p.targets).collect();
    println!("program files (targets): {sizes:?}");
    Ok(())
}
