//! Wall-clock split of the whole default design in release:
//! `cargo run --release -p kappe --example timings`.

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let design = kappe::Design::default();
    let t = Instant::now();
    let cap = kappe::design_cap(&design, &|_| {})?;
    let t_design = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let analysis = kappe::analysis::analyze(&cap, &Default::default(), &|_| {})?;
    let t_analysis = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let plan = kappe::robot_plan::plan_robot(&cap)?;
    let t_plan = t.elapsed().as_secs_f64();
    println!("| stage | seconds |");
    println!("|---|---:|");
    println!(
        "| form-finding + {} states + force passes + path + mesh | {t_design:.3} |",
        cap.states.len()
    );
    println!(
        "| analysis: stresses (wall) | {:.3} |",
        analysis.timings.stresses
    );
    println!(
        "| analysis: shell buckling, every state (wall) | {:.3} |",
        analysis.timings.fe
    );
    println!("| analysis total | {t_analysis:.3} |");
    println!(
        "| robot plan ({} stations, verified) | {t_plan:.3} |",
        plan.stations.len()
    );
    println!(
        "verdict: {}",
        if analysis.ok {
            "passes every constraint"
        } else {
            "FAILS"
        }
    );
    Ok(())
}
