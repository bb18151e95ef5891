//! The collapse factor of the Wolfs 2018 cylinder as a limit state (issue 24), printed as
//! tables: `cargo run --release -p kappe --example buildability_collapse -- [LAYERS] [SAMPLES]`
//! (defaults 32 layers, 10⁴ samples).
//!
//! The example spec (`kappe init --kind buildability`, every layer count up to LAYERS checked)
//! with `[analysis.nonlinear]` (the rule's w0, clamped base) and two uncertain inputs, chosen
//! before this example was first run (docs/reliability.md, "Collapse as a limit state"):
//! - the imperfection, a factor on the rule's w0, lognormal with mean 1 and cov 0.5;
//! - E₀, lognormal with cov 0.15, and γ, normal with cov 0.02 (the values of the project's
//!   illustrative scatter, `example_scatter`; γ scales λ_c exactly and adds no table axis).
//!
//! 1. `kappe buildability`'s run without and with the uncertainty: wall and CPU time.
//! 2. Per layer count: the nominal collapse factor, FORM's collapse β and P_f, the Monte Carlo's
//!    P(state n fails) and P(failed by layer n) on the same tables.
//! 3. The failure layer's mean and standard deviation against the five printed cylinders
//!    (25, 27, 30, 31, 31 layers: mean 28.8, sd 2.7).
//! 4. The tables against direct paths at every state's design point.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::commands::buildability::{BuildabilitySpec, run};
use kappe::commands::buildability_collapse::IMPERFECTION;
use kappe::commands::buildability_reliability::example_spec;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u64| {
        std::env::args()
            .nth(i)
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let layers = arg(1, 32) as usize;
    let samples = arg(2, 10_000);
    let base = format!(
        "{}\n[analysis.nonlinear]\n",
        example_spec(layers, None, None)
    );
    let scatter = format!(
        "\n[uncertainty]\n\"{IMPERFECTION}\" = {{ dist = \"lognormal\", cov = 0.5 }}\n\
         \"material.time.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}\n\
         \"material.specific_weight\" = {{ dist = \"normal\", cov = 0.02 }}\n\
         monte_carlo = {samples}\nseed = 1\n"
    );
    println!(
        "Wolfs 2018 cylinder, {layers} layers, 48 segments, w0 by the rule (clamped); {} threads, \
         load average {}",
        rayon::current_num_threads(),
        load_average()
    );
    let r0 = BuildabilitySpec::from_toml_str(&base)?;
    let (t0, c0) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
    let det = run(&r0, &|_| {})?;
    let (w0, cpu0) = (
        t0.elapsed().as_secs_f64(),
        cpu_seconds().unwrap_or(f64::NAN) - c0,
    );
    println!(
        "without [uncertainty]: {w0:.1} s wall, {cpu0:.1} s CPU; fails at layer {:?} by {:?}",
        det.failure_layer,
        det.failure_mode.map(|m| m.name())
    );
    let r = BuildabilitySpec::from_toml_str(&format!("{base}{scatter}"))?;
    let (t1, c1) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
    let b = run(&r, &|_| {})?;
    let (w1, cpu1) = (
        t1.elapsed().as_secs_f64(),
        cpu_seconds().unwrap_or(f64::NAN) - c1,
    );
    println!(
        "with [uncertainty] (w0 factor cov 0.5, E₀ cov 0.15, γ cov 0.02, {samples} samples): {w1:.1} s wall, \
         {cpu1:.1} s CPU ({:.1}× the CPU without); load average {}",
        cpu1 / cpu0,
        load_average()
    );
    let (Some(rel), Some(mc), Some(col)) =
        (&b.reliability, &b.monte_carlo, &b.collapse_reliability)
    else {
        return Err("no reliability block".into());
    };
    println!(
        "collapse tables: {} layer counts {:?} over {:?}, {} paths, {:.1} s wall; span D = {:.3}; \
         mixed modes at {:?}",
        col.states.len(),
        col.states,
        col.parameters,
        col.solves,
        col.seconds,
        col.span,
        col.mixed_modes
    );
    println!(
        "\n{:>3} {:>9} {:>12} {:>8} {:>10} {:>10} {:>10} {:>10}",
        "n", "λ_c", "mode", "β_coll", "P_f FORM", "state SORM", "P_f MC", "failed by"
    );
    for s in &b.states {
        let beta = s
            .beta_by_check
            .as_ref()
            .and_then(|m| m.get("collapse"))
            .copied();
        let n = s.layers;
        println!(
            "{n:>3} {:>9.4} {:>12} {:>8} {:>10} {:>10} {:>10.4} {:>10.4}",
            s.collapse_factor.unwrap_or(f64::NAN),
            s.collapse_mode.map_or("-", |m| m.name()),
            beta.map_or("-".into(), |b| format!("{b:.3}")),
            beta.map_or("-".into(), |b| format!(
                "{:.4}",
                kappe_reliability::stdnormal::cdf(-b)
            )),
            s.pf_sorm.map_or("-".into(), |p| format!("{p:.4}")),
            mc.state_pf.get(n - 1).map_or(f64::NAN, |v| v[0]),
            mc.failed_by.get(n - 1).copied().unwrap_or(f64::NAN),
        );
    }
    println!(
        "\nprint: FORM β {:.3}, P_f {:.4e} (governing layer {} {}); Monte Carlo P_f {:.4} [{:.4}, \
         {:.4}], {} samples re-solved",
        rel.beta,
        rel.pf,
        rel.governing_state,
        rel.governing_check,
        mc.pf,
        mc.pf_interval[0],
        mc.pf_interval[1],
        mc.resolves
    );
    if let Some(so) = &rel.sorm {
        println!(
            "print: SORM β {:.3}, P_f {:.4e} (governing layer {} {}); components left at FORM: \
             {:?}",
            so.beta, so.pf, so.governing_state, so.governing_check, so.form_only
        );
    }
    println!(
        "failure layer: mean {:.2}, sd {:.2} (Monte Carlo, the failing samples); printed \
         cylinders 25, 27, 30, 31, 31: mean 28.8, sd 2.7",
        mc.failure_layer_mean.unwrap_or(f64::NAN),
        mc.failure_layer_std.unwrap_or(f64::NAN)
    );
    println!("design point of the print: {:?}", rel.design_point);
    println!(
        "\ntables vs direct paths at the design points: max relative error {:.2e}, max Δβ {:.4} \
         (tolerance {})",
        col.max_relative_error,
        col.max_beta_error,
        kappe::commands::buildability_collapse::DESIGN_POINT_BETA_TOLERANCE
    );
    for d in &col.design_points {
        println!(
            "  n = {:>2}: β {:>7.3}, table {:.5}, path {:.5} ({}), rel {:.2e}, Δβ {:.4}",
            d.layers,
            d.beta,
            d.table,
            d.path,
            d.mode.name(),
            d.relative_error,
            d.beta_error
        );
    }
    Ok(())
}
