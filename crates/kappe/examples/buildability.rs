//! The Wolfs 2018 cylinder and the 60-layer buildability benchmark, printed as a table:
//! `cargo run --release -p kappe --example buildability`.
//!
//! 1. The example spec (`kappe init --kind buildability`): Wolfs, Bos & Salet 2018 cylinder,
//!    predicted failure layer and mode next to the five observed failures (30, 25, 31, 27, 31).
//! 2. Speed: the same cylinder with every layer count 1..60 checked (`stop_at_failure = false`),
//!    wall-clock and CPU seconds, best of three, with the load average (target ≤ 5 s in release).

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use rayon::prelude::*;

use kappe::commands::buildability::{BuildabilitySpec, EXAMPLE_TOML, run};

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
    // Best of three (the machine is shared): wall clock and the process's CPU time.
    let mut best = (f64::INFINITY, 0.0, 0);
    for _ in 0..3 {
        let (t0, c0) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
        let b60 = run(&r60, &|_| {})?;
        let wall = t0.elapsed().as_secs_f64();
        if wall < best.0 {
            best = (
                wall,
                cpu_seconds().unwrap_or(f64::NAN) - c0,
                b60.states.len(),
            );
        }
    }
    println!(
        "benchmark: 60-layer cylinder, every layer count checked ({} states): {:.2} s wall, \
         {:.2} s CPU, {} threads, load average {} (target ≤ 5 s)",
        best.2,
        best.0,
        best.1,
        rayon::current_num_threads(),
        load_average()
    );
    // The same states each solved from a random start, in parallel (what `run` did before the
    // warm-started chains): the baseline, and the check that the chains find the same BLFs.
    let warm = run(&r60, &|_| {})?;
    let (t0, c0) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
    let cold: Vec<_> = (1..=60)
        .into_par_iter()
        .map(|n| kappe::commands::buildability::check_layers(&r60, n))
        .collect::<Result<_, _>>()?;
    println!(
        "baseline, every state from a random start: {:.2} s wall, {:.2} s CPU, load average {}",
        t0.elapsed().as_secs_f64(),
        cpu_seconds().unwrap_or(f64::NAN) - c0,
        load_average()
    );
    let mut worst: f64 = 0.0;
    for (s, c) in warm.states.iter().zip(&cold) {
        if let (Some(a), Some(b)) = (s.blf, c.blf) {
            worst = worst.max((a / b - 1.0).abs());
        }
    }
    println!("warm-started BLFs vs cold starts: largest relative difference {worst:.2e}");
    Ok(())
}
