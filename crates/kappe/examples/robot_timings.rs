//! The robot stages of the default cap, timed in release (issue 13's speed target: planning,
//! timing and linting ≤ 3 s): `cargo run --release -p kappe --example robot_timings [-- OUT.json]`.
//! With OUT.json it also writes the planner's inputs (layers, setup, options) for
//! `cargo run --release -p kappe-robot --example plan_file -- OUT.json`.

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let cap = kappe::design_cap(&kappe::Design::default(), &|_| {})?;
    let (setup, options) = kappe::robot_plan::robot_inputs(&cap);
    let layers = kappe::robot_plan::print_layers(&cap.path);
    if let Some(out) = std::env::args().nth(1) {
        let v = serde_json::json!({ "layers": layers, "setup": setup, "options": options });
        std::fs::write(&out, serde_json::to_string(&v)?)?;
    }
    // Planning (ladder, stations) + timing + the independent check, all inside plan_print.
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
        "| **planning + timing + linting** | **{:.3}** |",
        t_plan + t_prog + t_lint
    );
    println!(
        "| mesh verification ({} waypoints) | {t_mesh:.3} |",
        meshes.waypoints_checked
    );
    Ok(())
}
