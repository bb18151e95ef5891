//! The default cap's analysis (every state) without and with a time model, wall-clock seconds:
//! `cargo run --release -p kappe --example green_timing` (issue 11 target: ≤ 1.3×).
//!
//! The time model: linear E(t) from 5 MPa (+2 kPa/s) with a Mohr–Coulomb strength
//! (c = 10 kPa, φ = 20°), so every state gets aged moduli and the strength and sliding checks.

use std::time::Instant;

fn run(toml: &str) -> Result<(f64, bool), Box<dyn std::error::Error>> {
    let design = kappe::Design::from_toml_str(toml)?;
    let cap = kappe::design_cap(&design, &|_| {})?;
    let t0 = Instant::now();
    let a = kappe::analysis::analyze(&cap, &design.analysis, &|_| {})?;
    Ok((t0.elapsed().as_secs_f64(), a.ok))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let plain = "name = \"default\"\n";
    let timed = "name = \"default\"\n[material.time]\nmodel = \"linear\"\nyoungs_modulus = 5.0e6\n\
                 youngs_modulus_rate = 2000.0\ncohesion = 10000.0\nfriction_angle_deg = 20.0\n";
    // Best of two runs each (the machine is shared).
    let mut best = [f64::INFINITY; 2];
    for _ in 0..2 {
        for (i, t) in [plain, timed].iter().enumerate() {
            let (s, _) = run(t)?;
            best[i] = best[i].min(s);
        }
    }
    println!(
        "default cap, every state: analysis {:.2} s without, {:.2} s with the time model (ratio {:.2}; target ≤ 1.3)",
        best[0],
        best[1],
        best[1] / best[0]
    );
    Ok(())
}
