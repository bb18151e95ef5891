//! The Wolfs 2018 cylinder and the 60-layer buildability benchmark, printed as a table:
//! `cargo run --release -p kappe --example buildability`.
//!
//! 1. The example spec (`kappe init --kind buildability`): Wolfs, Bos & Salet 2018 cylinder,
//!    predicted failure layer and mode next to the five observed failures (30, 25, 31, 27, 31).
//! 2. Speed: the same cylinder with every layer count 1..60 checked (`stop_at_failure = false`),
//!    wall-clock seconds (target ≤ 5 s in release).

use std::time::Instant;

use kappe::buildability::{BuildabilitySpec, EXAMPLE_TOML, run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let r = BuildabilitySpec::from_toml_str(EXAMPLE_TOML)?;
    let t0 = Instant::now();
    let b = run(&r, &|_| {})?;
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "Wolfs 2018 cylinder (R = 0.25 m, t = 0.04 m, h = 0.01 m, T = {:.2} s/layer, {} segments)",
        b.layer_time_s, b.segments
    );
    println!("  observed failures: 30, 25, 31, 27, 31 layers (mean 28.8)");
    println!(
        "  predicted: failure at layer {:?} by {:?} ({secs:.2} s); uniaxial plastic-collapse estimate {:?}",
        b.failure_layer,
        b.failure_mode.map(|m| m.name()),
        b.plastic_collapse_estimate
    );
    println!(
        "  {:>4} {:>8} {:>10} {:>10} {:>10} {:>10}",
        "n", "H [m]", "BLF", "strength", "sliding", "governs"
    );
    for s in &b.states {
        if s.layers % 5 == 0 || s.failure.is_some() {
            println!(
                "  {:>4} {:>8.3} {:>10.4} {:>10.4} {:>10.4} {:>10}",
                s.layers,
                s.height_m,
                s.blf.unwrap_or(f64::NAN),
                s.strength_utilisation.unwrap_or(f64::NAN),
                s.sliding_utilisation.unwrap_or(f64::NAN),
                s.governing.map_or("-", |m| m.name())
            );
        }
    }
    let mut spec = r.spec.clone();
    spec.checks.stop_at_failure = false;
    spec.object.max_layers = 60;
    let r60 = spec.resolve()?;
    let t0 = Instant::now();
    let b60 = run(&r60, &|_| {})?;
    println!(
        "benchmark: 60-layer cylinder, every layer count checked ({} states): {:.2} s (target ≤ 5 s)",
        b60.states.len(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
