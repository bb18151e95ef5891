//! Timings of the reliability engine on cheap limit states (so the numbers are the engine's own
//! cost): FORM evaluation counts and times, Monte Carlo with 10⁴/10⁵ samples, importance
//! sampling, a series system, and building a correlated Nataf model.
//!
//! `cargo run --release -p reliability --example bench_reliability`

use kappe_reliability::{
    Batch, Component, Correlation, FormOptions, Model, RandomVariable, SamplingMethod,
    SamplingOptions, SystemOptions, form, importance_sampling, merge, monte_carlo,
    sample_batch_parallel, series_system,
};
use std::time::Instant;

/// Best of `repeat` runs, seconds, and the last result.
fn best<T>(repeat: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeat {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.expect("repeat ≥ 1"))
}

fn main() -> Result<(), kappe_reliability::Error> {
    let r_s = Model::independent(vec![
        RandomVariable::normal("R", 200.0, 20.0)?,
        RandomVariable::normal("S", 150.0, 10.0)?,
    ])?;
    let dk = Model::new(
        vec![
            RandomVariable::normal("x1", 10.0, 2.0)?,
            RandomVariable::normal("x2", 20.0, 5.0)?,
        ],
        &Correlation::Pairs(vec![("x1".into(), "x2".into(), 0.5)]),
    )?;
    // 10 correlated lognormal/uniform variables, equicorrelated 0.3 (Nataf for every pair).
    let ten_vars: Vec<RandomVariable> = (0..10)
        .map(|i| {
            if i % 3 == 2 {
                RandomVariable::uniform(format!("v{i}"), 0.8, 1.2)
            } else {
                RandomVariable::lognormal_cov(format!("v{i}"), 1.0, 0.2)
            }
        })
        .collect::<Result<_, _>>()?;
    let pairs: Vec<(String, String, f64)> = (0..10)
        .flat_map(|i| (0..i).map(move |j| (format!("v{i}"), format!("v{j}"), 0.3)))
        .collect();
    let (t_nataf, ten) = best(3, || {
        Model::new(ten_vars.clone(), &Correlation::Pairs(pairs.clone()))
    });
    let ten = ten?;
    // Resistance (product of the first five) minus load (sum of the other five / 2.5).
    let g10 = |x: &[f64]| x[..5].iter().product::<f64>() - x[5..].iter().sum::<f64>() / 8.0;

    println!(
        "Nataf model, 10 variables, 45 correlated non-normal pairs: {:.1} ms",
        t_nataf * 1e3
    );
    println!();
    println!("FORM (iHL-RF, central differences)");
    println!(
        "{:<34} {:>4} {:>6} {:>6} {:>10} {:>10}",
        "case", "n", "iter", "evals", "beta", "time µs"
    );
    let o = FormOptions::default();
    type Case<'a> = (&'a str, &'a Model, Box<dyn Fn(&[f64]) -> f64>);
    let cases: Vec<Case> = vec![
        ("R − S, normal", &r_s, Box::new(|x: &[f64]| x[0] - x[1])),
        (
            "Der Kiureghian Ex. 5.2",
            &dk,
            Box::new(|x: &[f64]| x[0] * x[0] - 2.0 * x[1]),
        ),
        ("10 correlated lognormal/uniform", &ten, Box::new(g10)),
    ];
    for (name, model, g) in &cases {
        let (t, r) = best(20, || form(model, &mut |x: &[f64]| g(x), &o));
        let r = r?;
        println!(
            "{name:<34} {:>4} {:>6} {:>6} {:>10.5} {:>10.1}",
            model.len(),
            r.iterations,
            r.evaluations,
            r.beta,
            t * 1e6
        );
    }
    println!();
    println!(
        "Sampling on R − S (P_f = {:.5})",
        form(&r_s, &mut |x: &[f64]| x[0] - x[1], &o)?.pf
    );
    println!(
        "{:<26} {:>9} {:>10} {:>8} {:>10} {:>12}",
        "method", "samples", "pf", "cov", "time ms", "samples/s"
    );
    let linear = |x: &[f64]| x[0] - x[1];
    for samples in [10_000u64, 100_000] {
        let (t, r) = best(3, || {
            monte_carlo(&r_s, &mut linear.clone(), &SamplingOptions::new(samples, 1))
        });
        let r = r?;
        println!(
            "{:<26} {:>9} {:>10.5} {:>8.4} {:>10.2} {:>12.3e}",
            "Monte Carlo",
            samples,
            r.pf,
            r.cov,
            t * 1e3,
            samples as f64 / t
        );
    }
    let u_star = form(&r_s, &mut linear.clone(), &o)?.u_star;
    let (t, r) = best(3, || {
        importance_sampling(
            &r_s,
            &mut linear.clone(),
            &u_star,
            &SamplingOptions::new(10_000, 1),
        )
    });
    let r = r?;
    println!(
        "{:<26} {:>9} {:>10.5} {:>8.4} {:>10.2} {:>12.3e}",
        "importance sampling",
        10_000,
        r.pf,
        r.cov,
        t * 1e3,
        1e4 / t
    );
    let (t, r) = best(3, || {
        monte_carlo(&ten, &mut g10.clone(), &SamplingOptions::new(100_000, 1))
    });
    let r = r?;
    println!(
        "{:<26} {:>9} {:>10.5} {:>8.4} {:>10.2} {:>12.3e}",
        "MC, 10 correlated vars",
        100_000,
        r.pf,
        r.cov,
        t * 1e3,
        1e5 / t
    );
    let (t, b) = best(3, || {
        sample_batch_parallel(
            &ten,
            &|x: &[f64]| Ok(g10(x)),
            &SamplingMethod::MonteCarlo,
            &SamplingOptions::new(100_000, 1),
            Batch { index: 0, count: 1 },
        )
    });
    let r = merge(&[b?])?;
    println!(
        "{:<26} {:>9} {:>10.5} {:>8.4} {:>10.2} {:>12.3e}",
        format!("  same, rayon ({} thr.)", rayon::current_num_threads()),
        100_000,
        r.pf,
        r.cov,
        t * 1e3,
        1e5 / t
    );
    println!();
    println!("Series system (union importance sampling, 20 000 samples, + Ditlevsen bounds)");
    println!(
        "{:>11} {:>4} {:>12} {:>8} {:>10} {:>14}",
        "components", "n", "pf", "cov", "time ms", "of which bounds"
    );
    for (m, n) in [(10usize, 4usize), (100, 10), (1000, 10)] {
        let comps: Vec<Component> = (0..m)
            .map(|k| {
                let mut a: Vec<f64> = (0..n)
                    .map(|i| ((k * 7 + i * 3) % 11) as f64 - 5.0)
                    .collect();
                let norm = a.iter().map(|v| v * v).sum::<f64>().sqrt();
                a.iter_mut().for_each(|v| *v /= norm);
                Component {
                    beta: 3.0 + (k % 5) as f64 * 0.2,
                    alpha: a,
                }
            })
            .collect();
        let (t, r) = best(1, || series_system(&comps, &SystemOptions::default()));
        let r = r?;
        let no_bounds = SystemOptions {
            ditlevsen: false,
            ..SystemOptions::default()
        };
        let (t_nb, _) = best(1, || series_system(&comps, &no_bounds));
        println!(
            "{m:>11} {n:>4} {:>12.4e} {:>8.4} {:>10.1} {:>14.1}",
            r.pf,
            r.cov,
            t * 1e3,
            (t - t_nb) * 1e3
        );
    }
    Ok(())
}
