//! Plan, time and write the programs of a print given as JSON `{layers, setup, options}` (e.g.
//! dumped from a design), printing the stage times:
//! `cargo run --release -p kappe-robot --example plan_file -- INPUTS.json [OUT_DIR]`.

use std::time::Instant;

use kappe_robot::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: plan_file INPUTS.json [OUT_DIR]")?;
    let out = std::env::args().nth(2);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path)?)?;
    let layers: Vec<PrintLayer> = serde_json::from_value(v["layers"].clone())?;
    let setup: RobotSetup = serde_json::from_value(v["setup"].clone())?;
    let opts: PlanOptions = serde_json::from_value(v["options"].clone())?;
    let t = Instant::now();
    let plan = plan_print(&layers, &setup, &opts)?;
    let t_plan = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let rep = check_plan(&plan);
    println!(
        "check_plan alone: {:.3} s ({} problems); at waypoints: clearance {:.4} m, self {:.4} m; certified along the motion: clearance {:.4} m (approach/retract {:.4} m), self {:.4} m ({} configurations)",
        t.elapsed().as_secs_f64(),
        rep.problems.len(),
        rep.min_clearance,
        rep.min_self_distance,
        rep.certified_clearance,
        rep.certified_approach_clearance,
        rep.certified_self_distance,
        rep.certified_configurations
    );
    for p in rep.problems.iter().take(5) {
        println!("  {p}");
    }
    let t = Instant::now();
    let files = program_files(&plan, "program_part")?;
    let t_prog = t.elapsed().as_secs_f64();
    let t = Instant::now();
    for f in &files {
        let rep = lint(&f.text, plan.options.program.max_moves_per_program);
        if !rep.ok() {
            return Err(format!("{}: {:?}", f.name, rep.problems).into());
        }
    }
    let t_lint = t.elapsed().as_secs_f64();
    println!(
        "stations {}, waypoints {}, parts {}, print {:.1} s, total {:.1} s, max v ratio {:.3}, max a ratio {:.3}, slowdowns {}",
        plan.stations.len(),
        plan.waypoint_count(),
        files.len(),
        plan.print_time,
        plan.total_time,
        plan.max_speed_ratio,
        plan.max_acceleration_ratio,
        plan.slowdowns.len()
    );
    for s in plan.slowdowns.iter().take(10) {
        println!("  {s:?}");
    }
    println!(
        "| plan + timing + check | programs | lint | total |\n|---|---|---|---|\n| {t_plan:.3} s | {t_prog:.3} s | {t_lint:.3} s | {:.3} s |",
        t_plan + t_prog + t_lint
    );
    let t = Instant::now();
    let m = kappe_robot::meshes::verify_meshes(&plan, 1)?;
    println!(
        "meshes ({:.3} s, {} waypoints): arm capsules env {:.4} m ({}), self {:.4} m ({}); arm meshes env {:.4} m ({}), self {:.4} m ({}); nozzle {:.4} m ({}); problems {}",
        t.elapsed().as_secs_f64(),
        m.waypoints_checked,
        m.capsules.environment.distance,
        m.capsules.environment.what,
        m.capsules.self_distance.distance,
        m.capsules.self_distance.what,
        m.meshes.environment.distance,
        m.meshes.environment.what,
        m.meshes.self_distance.distance,
        m.meshes.self_distance.what,
        m.nozzle.distance,
        m.nozzle.what,
        m.problems.len()
    );
    if let Some(a) = &m.along_motion {
        println!(
            "meshes along the motion (certified, {} configurations): arm {:.4} m (layer {}), nozzle {:.4} m (layer {}), self {:.4} m (layer {})",
            a.configurations,
            a.environment.distance,
            a.environment.layer,
            a.nozzle.distance,
            a.nozzle.layer,
            a.self_distance.distance,
            a.self_distance.layer
        );
    }
    if let Some(dir) = out {
        std::fs::create_dir_all(&dir)?;
        for f in &files {
            std::fs::write(format!("{dir}/{}", f.name), &f.text)?;
        }
        std::fs::write(format!("{dir}/programs.json"), index_json(&files))?;
        let mut csv = Vec::new();
        write_trajectory_csv(&plan, &mut csv)?;
        std::fs::write(format!("{dir}/trajectory.csv"), csv)?;
        let mut json = Vec::new();
        write_plan_json(&plan, &mut json)?;
        std::fs::write(format!("{dir}/plan.json"), json)?;
    }
    Ok(())
}
