//! Wall-clock split of the whole default design in release:
//! `cargo run --release -p kappe --example timings`.
//!
//! `-- ceiling [FILE]`: a ceiling end to end as `kappe design` runs it (every bay designed,
//! analysed, both halves planned, the base-pose tolerance checked), bay by bay; without FILE the
//! full-size example of `kappe init --kind ceiling` (three 1.2 m bays, 3 m between end walls).

use std::time::Instant;

/// A ceiling end to end, bay by bay (issue 15: the full-size example is a benchmark).
fn ceiling(file: Option<&String>) -> Result<(), Box<dyn std::error::Error>> {
    let text = match file {
        Some(f) => std::fs::read_to_string(f)?,
        None => kappe::commands::ceiling::EXAMPLE_TOML.to_string(),
    };
    let c = kappe::commands::ceiling::CeilingDesign::from_toml_str(&text)?;
    let designs = c.bay_designs()?;
    let first = designs.first().ok_or("no bay")?;
    let options = kappe::Options::of(first);
    println!(
        "| bay | span m | states per half | analysis s | robot + tolerance s | total s | ok |"
    );
    println!("|---|---|---|---|---|---|---|");
    let t_all = Instant::now();
    let mut bays = Vec::new();
    for i in 0..designs.len() {
        let t = Instant::now();
        let bay = kappe::commands::ceiling::run_bay(&c, i, &options, &|_| {
            std::ops::ControlFlow::Continue(())
        })?;
        let total = t.elapsed().as_secs_f64();
        let fe = bay
            .outcome
            .analysis
            .as_ref()
            .map_or(0.0, |a| a.timings.total);
        println!(
            "| {} | {:.3} | {} | {fe:.1} | {:.1} | {total:.1} | {} |",
            i + 1,
            bay.design.cap.span,
            bay.outcome.cap.states.len(),
            total - fe,
            bay.outcome.verdict.ok
        );
        bays.push(bay);
    }
    let out = kappe::commands::ceiling::CeilingOutcome::from_bays(&c, bays);
    println!(
        "ceiling: {} bays, {:.1} s, {}",
        out.bays.len(),
        t_all.elapsed().as_secs_f64(),
        if out.ok { "passes" } else { "FAILS" }
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "ceiling") {
        return ceiling(args.get(1));
    }
    let design = kappe::Design::default();
    let t = Instant::now();
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let t_design = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let analysis = kappe::analysis::analyze(
        &cap,
        &Default::default(),
        kappe::analysis::Request::default(),
    )?;
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
    let t = Instant::now();
    let tol = kappe_robot::tolerance::check_base_tolerance(
        &plan,
        &kappe_robot::tolerance::BaseTolerance::default(),
    );
    println!(
        "| base-pose tolerance ±{} m, ±{}° ({} poses/station, {} waypoints; min clearance {:.4} m; {}) | {:.3} |",
        tol.tolerance.position,
        tol.tolerance.yaw_deg,
        tol.poses_per_station,
        tol.waypoints_checked,
        tol.min_clearance,
        if tol.ok() {
            "ok".to_string()
        } else {
            tol.problems.join("; ")
        },
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let margins = kappe_robot::tolerance::station_margins(
        &plan,
        &kappe_robot::tolerance::BaseTolerance::default(),
    );
    let text: Vec<String> = margins
        .iter()
        .map(|m| {
            format!(
                "station {}: {}±{:.1} mm, ±{:.2}°",
                m.station,
                if m.at_least { "≥ " } else { "" },
                m.position_m * 1e3,
                m.yaw_deg
            )
        })
        .collect();
    println!(
        "| largest base error per station ({}) | {:.3} |",
        text.join("; "),
        t.elapsed().as_secs_f64()
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
