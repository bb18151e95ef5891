//! The default cap's analysis (every state) without and with a time model, wall-clock seconds:
//! `cargo run --release -p kappe --example green_timing` (issue 11 target: ≤ 1.3×).
//!
//! The time model: linear E(t) from 5 MPa (+2 kPa/s) with a Mohr–Coulomb strength
//! (c = 10 kPa, φ = 20°), so every state gets aged moduli and the strength and sliding checks.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

/// Wall-clock and CPU seconds of the analysis.
fn run(toml: &str) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let design = kappe::Design::from_toml_str(toml)?;
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let (t0, c0) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
    kappe::analysis::analyze(&cap, &design.analysis, kappe::analysis::Request::default())?;
    Ok((
        t0.elapsed().as_secs_f64(),
        cpu_seconds().unwrap_or(f64::NAN) - c0,
    ))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let plain = "name = \"default\"\n";
    let timed = "name = \"default\"\n[material.time]\nmodel = \"linear\"\nyoungs_modulus = 5.0e6\n\
                 youngs_modulus_rate = 2000.0\ncohesion = 10000.0\nfriction_angle_deg = 20.0\n";
    // Best of two runs each, interleaved (the machine is shared): wall clock and CPU time.
    let mut wall = [f64::INFINITY; 2];
    let mut cpu = [f64::INFINITY; 2];
    for _ in 0..2 {
        for (i, t) in [plain, timed].iter().enumerate() {
            let (w, c) = run(t)?;
            wall[i] = wall[i].min(w);
            cpu[i] = cpu[i].min(c);
        }
    }
    println!(
        "default cap, every state: analysis {:.2} s wall / {:.2} s CPU without, {:.2} s wall / \
         {:.2} s CPU with the time model (ratio {:.2} wall, {:.2} CPU; target ≤ 1.3), load average {}",
        wall[0],
        cpu[0],
        wall[1],
        cpu[1],
        wall[1] / wall[0],
        cpu[1] / cpu[0],
        load_average()
    );
    Ok(())
}
