//! The collapse check on the Wolfs 2018 cylinder (docs/collapse.md §4), printed as tables:
//! `cargo run --release -p kappe --example collapse [-- default|matrix|speed]`.
//!
//! * `default`: the failure layer with the default imperfection rule and the clamped base,
//!   next to the five observed failures (25, 27, 30, 31, 31).
//! * `matrix`: w0 = rule, 0, 1, 2, 5 mm, each with the clamped and the pinned base.
//! * `speed`: per layer count 10, 20, 30, 40: one LBA solve against one collapse path (best of
//!   three), and `kappe buildability` of the 60-layer cylinder with the collapse check at every
//!   layer (wall-clock, CPU).
//! * `diag`: the 12-layer state (material check off, w0 = 0) on 24, 48, 96 segments and on
//!   48 segments split 2×2: λ_LBA, the critical factor of the co-rotational tangent linearised
//!   at the reference state (`kappe_fe::linearised_critical_factor`) and the perfect path's
//!   bifurcation (docs/collapse.md §4, the λ_c → λ_LBA check).

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::commands::buildability::{BuildabilitySpec, EXAMPLE_TOML, Resolved, run};

fn spec(extra_checks: &str, nonlinear: &str) -> Result<Resolved, Box<dyn std::error::Error>> {
    let text = format!("{EXAMPLE_TOML}{extra_checks}\n[analysis.nonlinear]\n{nonlinear}\n");
    Ok(BuildabilitySpec::from_toml_str(&text)?)
}

fn failure(r: &Resolved) -> Result<String, Box<dyn std::error::Error>> {
    let t0 = Instant::now();
    let b = run(r, &|_| {})?;
    let secs = t0.elapsed().as_secs_f64();
    let at = |n: usize| {
        b.states
            .iter()
            .find(|s| s.layers == n)
            .and_then(|s| s.collapse.as_ref())
            .map_or("-".to_string(), |c| {
                format!("{:.3} {} (LBA {:.3})", c.factor, c.mode.name(), c.lba)
            })
    };
    let last = b.states.last();
    Ok(format!(
        "fails at {:?} by {:?}{}; n=25: {}; n=28: {}; ({secs:.1} s)",
        b.failure_layer,
        b.failure_mode.map(|m| m.name()),
        last.and_then(|s| s.collapse.as_ref())
            .map_or(String::new(), |c| format!(
                " [collapse {:.3} {} w0 {:.2} mm]",
                c.factor,
                c.mode.name(),
                c.w0 * 1e3
            )),
        at(25),
        at(28)
    ))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let what = std::env::args().nth(1).unwrap_or_else(|| "default".into());
    println!("Wolfs 2018 cylinder: observed failures 25, 27, 30, 31, 31 layers (mean 28.8)");
    if what == "default" || what == "matrix" {
        println!("  rule, clamped: {}", failure(&spec("", "")?)?);
    }
    if what == "matrix" {
        println!(
            "  rule, pinned: {}",
            failure(&spec("", "base = \"pinned\"")?)?
        );
        for w in [0.0, 1.0, 2.0, 5.0] {
            for base in ["clamped", "pinned"] {
                let r = spec(
                    "",
                    &format!("imperfection = {}\nbase = \"{base}\"", w * 1e-3),
                )?;
                println!("  w0 = {w} mm, {base}: {}", failure(&r)?);
            }
        }
        let r = spec("", "material = false")?;
        println!(
            "  rule, clamped, no material check along the path: {}",
            failure(&r)?
        );
    }
    if what == "diag" {
        diag()?;
    }
    if what == "speed" {
        let r = spec("", "")?;
        println!(
            "  {:>4} {:>8} {:>10} {:>10} {:>8} {:>6}",
            "n", "DOFs", "t_LBA [s]", "t_path [s]", "ratio", "steps"
        );
        for n in [10, 20, 30, 40] {
            let mut t_lba = f64::INFINITY;
            let mut t_all = f64::INFINITY;
            let mut steps = 0;
            for _ in 0..3 {
                let t0 = Instant::now();
                let mut plain = r.clone();
                plain.spec.analysis = None;
                let _ = kappe::commands::buildability::check_layers(&plain, n)?;
                t_lba = t_lba.min(t0.elapsed().as_secs_f64());
                let t1 = Instant::now();
                let s = kappe::commands::buildability::check_layers(&r, n)?;
                t_all = t_all.min(t1.elapsed().as_secs_f64());
                steps = s.collapse.map_or(0, |c| c.steps);
            }
            let dofs = 6 * r.segments * n;
            println!(
                "  {n:>4} {dofs:>8} {t_lba:>10.3} {:>10.3} {:>8.1} {steps:>6}",
                t_all - t_lba,
                (t_all - t_lba) / t_lba
            );
        }
        let mut every = r.clone();
        every.spec.checks.stop_at_failure = false;
        let (c0, t0) = (cpu_seconds(), Instant::now());
        let b = run(&every, &|_| {})?;
        println!(
            "  60 layers, collapse at every layer: {:.1} s wall, {:.1} s CPU (load {}); fails first at {:?}",
            t0.elapsed().as_secs_f64(),
            cpu_seconds().zip(c0).map_or(f64::NAN, |(a, b)| a - b),
            load_average(),
            b.failure_layer
        );
    }
    Ok(())
}

/// The `diag` table (module docs).
fn diag() -> Result<(), Box<dyn std::error::Error>> {
    use kappe::analysis::green::{GreenOptions, check_state};
    use kappe::commands::buildability::object_shell;
    use kappe_fe::{BucklingOptions, Linearisation, PathOptions, buckling, nonlinear_path};
    let n = 12;
    println!(
        "  {:>4} {:>5} {:>7} {:>6} {:>9} {:>9} {:>9} {:>9} {:>8} {:>6}",
        "segs", "split", "DOFs", "local", "λ_LBA", "K_σ/LBA", "dK/LBA", "λ_path", "path/LBA", "LDLᵀ"
    );
    for (segs, split) in [(24, 1), (48, 1), (96, 1), (48, 2)] {
        let text = EXAMPLE_TOML.replace("# segments = 48", &format!("segments = {segs}"));
        let r = BuildabilitySpec::from_toml_str(&text)?;
        let (mut model, layers) = object_shell(&r, n);
        let ages = r.schedule.ages(n);
        check_state(&mut model, &layers, &ages, &r.time, &GreenOptions::default())?;
        let model = kappe_fe::refine::split(&model, split).model;
        let lba = buckling(
            &model,
            &BucklingOptions {
                modes: 1,
                ..Default::default()
            },
        )?;
        let l = lba.factors[0];
        for local_geometric in [false, true] {
            let lin = |which| -> Result<f64, Box<dyn std::error::Error>> {
                Ok(kappe_fe::linearised_critical_factor(&model, l, 1e-5, which)?.lambda)
            };
            let sigma = lin(Linearisation::InitialStress { local_geometric })?;
            let deriv = lin(Linearisation::Derivative { local_geometric })?;
            let opt = PathOptions {
                initial_increment: 0.5 * l,
                lambda_max: 1.5 * l,
                local_geometric,
                ..Default::default()
            };
            let path =
                nonlinear_path(&model, &opt, &mut |_| std::ops::ControlFlow::Continue(()))?;
            let lp = path.limit.map_or(f64::NAN, |x| x.lambda);
            println!(
                "  {segs:>4} {split:>5} {:>7} {:>6} {l:>9.4} {:>9.4} {:>9.4} {lp:>9.4} {:>8.4} {:>6}",
                6 * model.nodes.len(),
                if local_geometric { "yes" } else { "no" },
                sigma / l,
                deriv / l,
                lp / l,
                path.stats.factorizations,
            );
        }
    }
    Ok(())
}
