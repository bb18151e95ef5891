//! The chance the Wolfs 2018 cylinder stands (issue 24), printed as tables:
//! `cargo run --release -p kappe --example buildability_mc`.
//!
//! The example spec (`kappe init --kind buildability`, 60 layers, every layer count checked)
//! with the illustrative scatter of `example_scatter` (not calibrated to the five
//! specimens): E₀, Ė, f₀, ḟ lognormal with coefficients of variation 0.15, 0.15, 0.10, 0.10, γ
//! normal with 0.02 and the layer time lognormal with 0.05.
//!
//! 1. Speed: the interpolation tables (9 points of ρ per layer count, 540 shell solves) and
//!    10⁴ Monte Carlo samples of the whole print (60 layer counts each); target ≤ 60 s.
//! 2. The tables against re-solves at seeded random points (relative errors).
//! 3. FORM P_f of each layer count against the Monte Carlo P_f and its 95 % interval.
//! 4. Batches: the run cut into 3 batches merges into the single run bit for bit.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::commands::buildability::{BuildabilitySpec, run};
use kappe::commands::buildability_reliability::{
    Surrogate, example_scatter, example_spec, monte_carlo, monte_carlo_batch, monte_carlo_result,
    prepare, reliability,
};
use kappe_reliability::{Batch, SamplingOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let samples: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let mut spec = BuildabilitySpec::parse(&format!(
        "{}{}",
        example_spec(60, None, None),
        example_scatter(1)
    ))?;
    let table = spec.uncertainty.take().ok_or("no [uncertainty]")?;
    let r = spec.resolve()?;
    let det = run(&r, &|_| {})?;
    println!(
        "Wolfs 2018 cylinder, 60 layers, T = {:.2} s: deterministic failure at layer {:?} by {:?}",
        r.layer_time,
        det.failure_layer,
        det.failure_mode.map(|m| m.name())
    );

    let (t0, c0) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
    let sur = Surrogate::build(&r, prepare(&r, &table)?)?;
    let t_build = t0.elapsed().as_secs_f64();
    let mc = monte_carlo(&r, &sur, samples, 7)?;
    let wall = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds().unwrap_or(f64::NAN) - c0;
    println!(
        "benchmark: tables {t_build:.2} s + {samples} samples {:.2} s = {wall:.2} s wall, \
         {cpu:.2} s CPU, {} threads, load average {} (target ≤ 60 s); {} samples re-solved",
        wall - t_build,
        rayon::current_num_threads(),
        load_average(),
        mc.resolves
    );
    println!(
        "  print P_f (fails by layer 60) = {:.4} [{:.4}, {:.4}]; failure layer mean {:.2}, std {:.2} \
         (specimens: 30, 25, 31, 27, 31: mean 28.8, std 2.7)",
        mc.pf,
        mc.pf_interval[0],
        mc.pf_interval[1],
        mc.failure_layer_mean.unwrap_or(f64::NAN),
        mc.failure_layer_std.unwrap_or(f64::NAN)
    );

    let t1 = Instant::now();
    let err = sur.verify(&r, 6, 99, 5)?;
    println!(
        "tables vs re-solves (6 random points × every 5th layer count, {:.1} s): max relative \
         error BLF {:.2e}, strength {:.2e}, sliding {:.2e}",
        t1.elapsed().as_secs_f64(),
        err[0],
        err[1],
        err[2]
    );

    let t2 = Instant::now();
    let values: Vec<_> = det
        .states
        .iter()
        .map(|s| {
            (
                s.layers,
                (s.blf, s.strength_utilisation, s.sliding_utilisation),
            )
        })
        .collect();
    let rel = reliability(&r, &sur, &values, &table)?;
    println!(
        "FORM of {} layer counts ({} components): {:.2} s; FORM vs Monte Carlo per layer count:",
        rel.states.len(),
        rel.components,
        t2.elapsed().as_secs_f64()
    );
    println!(
        "  {:>3} {:>8} {:>10} {:>10} {:>10} {:>21}  FORM / SORM within",
        "n", "beta", "FORM pf", "SORM pf", "MC pf", "MC 95 % interval"
    );
    let mut inside = 0;
    let mut inside_sorm = 0;
    let mut compared = 0;
    for s in &rel.states {
        let Some(m) = mc.state_pf.get(s.index - 1) else {
            continue;
        };
        // Compared where the Monte Carlo sees the event at all (≥ 10 failures of 10⁴) and
        // does not see it always.
        let informative = m[0] * samples as f64 >= 10.0 && m[0] < 0.999;
        let ok = s.pf >= m[1] && s.pf <= m[2];
        let ok_sorm = s.pf_sorm.is_some_and(|p| p >= m[1] && p <= m[2]);
        if informative {
            compared += 1;
            inside += usize::from(ok);
            inside_sorm += usize::from(ok_sorm);
        }
        if informative || s.index % 10 == 0 {
            println!(
                "  {:>3} {:>8.3} {:>10.4} {:>10} {:>10.4} [{:>8.4}, {:>8.4}]  {} / {}",
                s.index,
                s.beta,
                s.pf,
                s.pf_sorm.map_or("-".into(), |p| format!("{p:.4}")),
                m[0],
                m[1],
                m[2],
                if ok { "yes" } else { "no" },
                if ok_sorm { "yes" } else { "no" }
            );
        }
    }
    println!(
        "  FORM inside the 95 % interval at {inside} of {compared} informative layer counts, \
         SORM at {inside_sorm}"
    );

    let opts = SamplingOptions::new(samples.min(3000), 7);
    let one = monte_carlo_batch(&r, &sur, &opts, Batch { index: 0, count: 1 })?;
    let parts = (0..3)
        .map(|i| monte_carlo_batch(&r, &sur, &opts, Batch { index: i, count: 3 }))
        .collect::<Result<Vec<_>, _>>()?;
    let a = monte_carlo_result(&[one], 0, [0.0; 2])?;
    let b = monte_carlo_result(&parts, 0, [0.0; 2])?;
    println!(
        "batches: 3 batches of {} samples merge into the single run bit for bit: {}",
        opts.samples,
        a == b
    );
    Ok(())
}
