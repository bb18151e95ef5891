//! The Monte Carlo of a design's governing states against FORM (issue 24: "on the default cap
//! … FORM P_f against Monte Carlo with ≥ 10⁴ samples"), printed as a table:
//! `cargo run --release -p kappe --example design_mc -- [samples] [rows]` (samples 0: the runs
//! with FORM and SORM only, no sampling).
//!
//! Rows: `1` study No. 14's small cap (E₀ lognormal cov 0.15, γ normal cov 0.05, E₀ drifting
//! −12 %/h; print P_f ≈ 2e-2), crude and importance sampling; `3` the default cap with
//! form_cost's time parameters (E(t) = 10 MPa + 1 kPa/s·t, E₀ lognormal cov 0.2, Ė lognormal
//! cov 0.3, γ normal cov 0.05, E₀ drifting −20 %/h; P_f ≈ 2e-9), importance sampling (crude
//! sampling of 10⁴ cannot see 2e-9). Per row: FORM's P_f (the run's), the sampled P_f with its
//! 95 % interval, the governing states, the tables' shell solves, the re-solved samples, and the
//! seconds of FORM and of the Monte Carlo (tables, centres, samples), the CPU seconds of the
//! whole run, with the load average.

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::{Design, Options, no_progress, run};

const STUDY14: &str = "name = \"mc\"\n[cap]\nlength = 0.15\n[print]\npath_sampling = 0.04\n\
    print_speed = 0.01\n[robot]\nenabled = false\n[analysis]\nrow_stride = 8\n\
    [material.time]\nmodel = \"linear\"\nyoungs_modulus = 1.3e6\nyoungs_modulus_rate = 400.0\n\
    [uncertainty]\n\"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.15 }\n\
    \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n";

const DEFAULT_CAP: &str = "name = \"default\"\n[material.time]\nmodel = \"linear\"\n\
    youngs_modulus = 1.0e7\nyoungs_modulus_rate = 1000.0\n[uncertainty]\n\
    \"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.2 }\n\
    \"material.time.youngs_modulus_rate\" = { dist = \"lognormal\", cov = 0.3 }\n\
    \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n";

fn design(
    base: &str,
    drift: f64,
    samples: u64,
    method: &str,
) -> Result<Design, kappe::DesignError> {
    // N = 0: the run with FORM and SORM only (seed 1 as the sampled rows), no sampling.
    let mc = if samples == 0 {
        String::new()
    } else {
        format!("monte_carlo = {samples}\nmonte_carlo_method = \"{method}\"\n")
    };
    Design::from_toml_str(&format!(
        "{base}{mc}seed = 1\n\
         [uncertainty.drift]\n\"material.time.youngs_modulus\" = {{ percent_per_hour = {drift:?} }}\n"
    ))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let samples: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let rows = std::env::args().nth(2).unwrap_or_else(|| "13".into());
    println!(
        "row | method | N | FORM P_f | MC P_f | 95 % interval | FORM inside | governing states | \
         excluded share | table solves | re-solved samples | centres | FORM s | MC s | run CPU s | \
         SORM P_f | SORM inside | load"
    );
    let mut cases = Vec::new();
    if rows.contains('1') {
        cases.push(("study 14, E0 + gamma, -12 %/h", STUDY14, -12.0, "crude"));
        cases.push((
            "study 14, E0 + gamma, -12 %/h",
            STUDY14,
            -12.0,
            "importance",
        ));
    }
    if rows.contains('3') {
        cases.push((
            "default cap, time parameters",
            DEFAULT_CAP,
            -20.0,
            "importance",
        ));
    }
    for (name, base, drift, method) in cases {
        let d = design(base, drift, samples, method)?;
        let c0 = cpu_seconds().unwrap_or(f64::NAN);
        let out = run(&d, &Options::of(&d), &no_progress)?;
        let cpu = cpu_seconds().unwrap_or(f64::NAN) - c0;
        let r = out.reliability.as_ref().ok_or("no reliability")?;
        if samples == 0 {
            println!(
                "{name} | FORM P_f {:.4e} | SORM P_f {:?} (FORM-only components {:?}) | FORM s {:.1} | \
                 run CPU s {cpu:.1} | {}",
                r.pf,
                r.sorm.as_ref().map(|s| s.pf),
                r.sorm.as_ref().map(|s| &s.form_only),
                r.seconds,
                load_average()
            );
            continue;
        }
        let mc = r.monte_carlo.as_ref().ok_or("no Monte Carlo")?;
        println!(
            "{name} | {method} | {} | {:.4e} | {:.4e} | [{:.4e}, {:.4e}] | {} | {} {:?} | {:.1e} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.4e} | {:?} | {}",
            mc.samples,
            r.pf,
            mc.pf,
            mc.pf_interval[0],
            mc.pf_interval[1],
            mc.form_in_interval,
            mc.states.len(),
            mc.states,
            mc.excluded_share,
            mc.table_solves,
            mc.resolved_samples,
            mc.centers,
            r.seconds,
            mc.seconds,
            cpu,
            mc.sorm_pf.unwrap_or(f64::NAN),
            mc.sorm_in_interval,
            load_average()
        );
    }
    Ok(())
}
