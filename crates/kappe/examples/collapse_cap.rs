//! The collapse check of the default cap (docs/collapse.md §5): per state run, the collapse
//! factor next to its BLF, and the analysis time with and without the check:
//! `cargo run --release -p kappe --example collapse_cap`.

use std::time::Instant;

use kappe::analysis::analyze;
use kappe::analysis::cap_state_collapse;
use kappe::input::AnalysisOptions;
use kappe::input::NonlinearSpec;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let design = kappe::Design::from_toml_str(kappe::input::EXAMPLE_TOML)?;
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let off = AnalysisOptions {
        nonlinear: Some(NonlinearSpec {
            enabled: false,
            ..Default::default()
        }),
        ..Default::default()
    };
    let t0 = Instant::now();
    let a = analyze(&cap, &off, kappe::analysis::Request::default())?;
    let t_off = t0.elapsed().as_secs_f64();
    let mut by_bound: Vec<(usize, f64)> = a
        .states
        .iter()
        .filter_map(|s| s.blf.map(|b| (s.index, b)))
        .collect();
    by_bound.sort_by(|x, y| x.1.total_cmp(&y.1));
    println!("analysis without the collapse check: {t_off:.2} s");
    let spec = NonlinearSpec::default();
    println!(
        "  {:>5} {:>8} {:>9} {:>14} {:>6} {:>7} {:>8}",
        "state", "BLF", "collapse", "mode", "steps", "asm", "t [s]"
    );
    for &(q, b) in by_bound.iter().take(
        std::env::args()
            .nth(1)
            .and_then(|a| a.parse().ok())
            .unwrap_or(3),
    ) {
        let t = Instant::now();
        let c = cap_state_collapse(&cap, &AnalysisOptions::default(), &spec, None, q)?;
        if let Some(c) = c {
            println!(
                "  {q:>5} {b:>8.3} {:>9.3} {:>14} {:>6} {:>7} {:>8.2}",
                c.factor,
                c.mode.name(),
                c.steps,
                c.assemblies,
                t.elapsed().as_secs_f64()
            );
        }
    }
    let t1 = Instant::now();
    let on = AnalysisOptions {
        nonlinear: Some(NonlinearSpec::default()),
        ..Default::default()
    };
    let a2 = analyze(&cap, &on, kappe::analysis::Request::default())?;
    let t_on = t1.elapsed().as_secs_f64();
    let run: Vec<String> = a2
        .states
        .iter()
        .filter_map(|s| {
            s.collapse_factor
                .map(|c| format!("{}: {c:.3} (BLF {:.3})", s.index, s.blf.unwrap_or(f64::NAN)))
        })
        .collect();
    println!(
        "analysis with the collapse check: {t_on:.2} s ({:.2}× without); states run: {}",
        t_on / t_off,
        run.join(", ")
    );
    Ok(())
}
