//! Benchmark of the default verdict without the robot (issue 25 item 1) and of a 1.5 m × 4 m
//! bay's analysis, with the converged buckling factor (docs/convergence.md) and, for
//! comparison, the print-layer mesh alone.
//!
//! `cargo run --release -p kappe --example blf_bench [-- default|bay]` prints, per case and
//! mode, the design + analysis wall time, the process CPU time, the FE wall and summed seconds,
//! the states whose 2×2 split was solved, the governing state and its factor, and the load
//! average (the machine may be shared: read CPU next to wall).

use std::time::Instant;

use kappe::analysis::{AnalysisOptions, analyze};

#[path = "common/caps.rs"]
mod caps;
#[path = "common/measure.rs"]
mod measure;

fn run(name: &str, design: &kappe::Design) -> Result<(), Box<dyn std::error::Error>> {
    for (mode, options) in [
        ("converged (default)", design.analysis.clone()),
        (
            "print-layer mesh only",
            AnalysisOptions {
                converged_blf: false,
                ..design.analysis.clone()
            },
        ),
    ] {
        let cpu0 = measure::cpu_seconds().unwrap_or(0.0);
        let t = Instant::now();
        let cap = kappe::design_cap(design, kappe::Context::default())?;
        let a = analyze(&cap, &options, kappe::analysis::Request::default())?;
        let wall = t.elapsed().as_secs_f64();
        let cpu = measure::cpu_seconds().unwrap_or(0.0) - cpu0;
        let solved = a
            .states
            .iter()
            .filter(|s| s.blf_interpolated == Some(false))
            .count();
        let gov = a
            .states
            .iter()
            .filter_map(|s| Some((s.index, s.blf?, s.blf_error)))
            .min_by(|x, y| x.1.total_cmp(&y.1));
        println!(
            "| {name} | {mode} | {} | {wall:.2} | {cpu:.2} | {:.2} | {:.2} | {solved} | {} | {} |",
            cap.states.len(),
            a.timings.fe,
            a.timings.fe_sum,
            gov.map_or("-".into(), |g| format!(
                "{}: {:.4}{}",
                g.0,
                g.1,
                g.2.map_or(String::new(), |e| format!(" (error ≤ {:.2} %)", 100.0 * e))
            )),
            measure::load_average()
        );
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let which = std::env::args().nth(1).unwrap_or_default();
    println!(
        "| case | BLF | states | design + analysis wall s | CPU s | FE wall s | FE sum s | split solved in | governing state: BLF | load |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    if which.is_empty() || which == "default" {
        run("default cap", &kappe::Design::default())?;
    }
    if which.is_empty() || which == "bay" {
        let d = &caps::bay_half()?;
        run("1.5 m × 4 m bay (one half)", d)?;
    }
    Ok(())
}
