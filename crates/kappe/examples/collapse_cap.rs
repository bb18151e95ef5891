//! The collapse check of the default cap (docs/collapse.md §5–6): per state run, the collapse
//! factor next to its BLF, the time of its path against its own linear buckling solve (wall and
//! CPU) and against a fixed reference solve of the same model (1e-8 with a Sturm count: the
//! check's own LBA until session 8, `ref`), and the analysis time with and without the check:
//! `cargo run --release -p kappe --example collapse_cap [-- STATES [SIGNS [as_printed]]]`
//! (STATES: how many of the least-BLF states, default 3; SIGNS: force 1 or 2 imperfection
//! signs, 0 = the rule; `as_printed`: also each state's path from the as-printed shape,
//! docs/collapse.md §8). STATES = 0 skips the table; the analysis with the check runs last
//! unless `NO_FULL` is the fourth argument. `state=N` (repeatable) runs the table for those
//! states alone, without either analysis. `first`: the table's check takes the state's mode and
//! factor from the analysis's first-pass LBA (solved beforehand, untimed), as `analyze` does
//! (docs/collapse.md §6, session 9), instead of its own LBA. `above=X`: the table's checks stop
//! at λ* = X, as the states after the state rule's first batch do.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::analysis::analyze;
use kappe::analysis::{FirstPass, cap_state_collapse, cap_state_collapse_from, cap_state_lba};
use kappe::input::AnalysisOptions;
use kappe::input::NonlinearSpec;

fn cpu() -> f64 {
    cpu_seconds().unwrap_or(f64::NAN)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize| {
        std::env::args()
            .nth(i)
            .and_then(|a| a.parse::<usize>().ok())
    };
    let design = kappe::Design::from_toml_str(kappe::input::EXAMPLE_TOML)?;
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let off = AnalysisOptions {
        nonlinear: Some(NonlinearSpec {
            enabled: false,
            ..Default::default()
        }),
        ..Default::default()
    };
    let words: Vec<String> = std::env::args().collect();
    // `state=N`: that state alone, without the analyses (its BLF column is then NaN).
    let only: Vec<usize> = words
        .iter()
        .filter_map(|w| w.strip_prefix("state=")?.parse().ok())
        .collect();
    let (mut t_off, mut c_off) = (f64::NAN, f64::NAN);
    let mut by_bound: Vec<(usize, f64)> = only.iter().map(|&q| (q, f64::NAN)).collect();
    if only.is_empty() {
        let (t0, c0) = (Instant::now(), cpu());
        let a = analyze(&cap, &off, kappe::analysis::Request::default())?;
        (t_off, c_off) = (t0.elapsed().as_secs_f64(), cpu() - c0);
        by_bound = a
            .states
            .iter()
            .filter_map(|s| s.blf.map(|b| (s.index, b)))
            .collect();
        by_bound.sort_by(|x, y| x.1.total_cmp(&y.1));
        println!(
            "analysis without the collapse check: {t_off:.2} s wall, {c_off:.2} s CPU (load {})",
            load_average()
        );
    }
    let spec = NonlinearSpec {
        signs: arg(2).filter(|s| *s > 0),
        ..Default::default()
    };
    let as_printed = words.iter().any(|w| w == "as_printed");
    let from_first = words.iter().any(|w| w == "first");
    // `above=X`: the table's checks stop at X as the state rule's stopped states do
    // (docs/collapse.md §3), to time one of them alone.
    let above = words
        .iter()
        .find_map(|w| w.strip_prefix("above=")?.parse::<f64>().ok())
        .unwrap_or(f64::INFINITY);
    println!(
        "  {:>5} {:>8} {:>9} {:>14} {:>5} {:>5} {:>5} {:>9} {:>9} {:>9} {:>9} {:>7} {:>7} {:>8} {:>7}",
        "state",
        "BLF",
        "collapse",
        "mode",
        "steps",
        "asm",
        "LDLt",
        "LBA wall",
        "LBA CPU",
        "path wall",
        "path CPU",
        "wall ×",
        "CPU ×",
        "ref CPU",
        "ref ×"
    );
    let options = AnalysisOptions::default();
    for &(q, b) in by_bound.iter().take(arg(1).unwrap_or(3)) {
        // The state's linear buckling solve alone (the collapse check's first half), best of
        // two so a cold cache does not count against the LBA.
        let (mut tl, mut cl) = (f64::INFINITY, f64::INFINITY);
        // The reference solve of the same model, fixed across sessions: 1e-8 with a Sturm
        // count (the collapse check's own LBA until session 8).
        let (mut tr, mut cr) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..2 {
            let (t, c) = (Instant::now(), cpu());
            let lba = cap_state_lba(&cap, &options, None, q)?;
            tl = tl.min(t.elapsed().as_secs_f64());
            cl = cl.min(cpu() - c);
            if let Some(l) = lba {
                let (t, c) = (Instant::now(), cpu());
                let _ = kappe_fe::buckling(
                    &l.shell.model,
                    &kappe_fe::BucklingOptions {
                        modes: 1,
                        tolerance: 1e-8,
                        sturm_check: true,
                        ..Default::default()
                    },
                )?;
                tr = tr.min(t.elapsed().as_secs_f64());
                cr = cr.min(cpu() - c);
            }
        }
        // With `first`: the check as `analyze` runs it, from the analysis's own first-pass
        // LBA of the state (solved here, untimed, as the first pass solves it), so no LBA of
        // its own; the ratio then is the check's cost on top of the analysis.
        let kept = if from_first {
            let mut guess = None;
            let f = kappe::analysis::state_fe(
                &cap,
                &options.with_split_at_most(1),
                q,
                &mut guess,
                &kappe::analysis::FeRequest::default(),
            )?;
            f.fe.buckling.factors.first().copied().zip(guess)
        } else {
            None
        };
        let first = kept.as_ref().map(|(factor, mode)| FirstPass {
            factor: *factor,
            mode,
        });
        let (t, c0) = (Instant::now(), cpu());
        let c = cap_state_collapse_from(&cap, &options, &spec, None, q, above, first)?;
        let (tp, cp) = (t.elapsed().as_secs_f64(), cpu() - c0);
        if let Some(c) = c {
            println!(
                "  {q:>5} {b:>8.4} {:>9.4} {:>14} {:>5} {:>5} {:>5} {tl:>9.2} {cl:>9.2} {tp:>9.2} {cp:>9.2} {:>7.1} {:>7.1} {cr:>8.2} {:>7.1}",
                c.factor,
                format!("{} {:+}", c.mode.name(), c.sign),
                c.steps,
                c.assemblies,
                c.factorizations,
                tp / tl,
                cp / cl,
                cp / cr
            );
        }
        if as_printed {
            let ap = NonlinearSpec {
                start: kappe::input::PathStart::AsPrinted,
                ..spec
            };
            let (t, c0) = (Instant::now(), cpu());
            if let Some(c) = cap_state_collapse(&cap, &options, &ap, None, q, f64::INFINITY)? {
                println!(
                    "  {q:>5} as-printed start: collapse {:.4} {} ({} steps, {} LDLt; {:.2} s wall, {:.2} s CPU)",
                    c.factor,
                    c.mode.name(),
                    c.steps,
                    c.factorizations,
                    t.elapsed().as_secs_f64(),
                    cpu() - c0
                );
            }
        }
    }
    if words.iter().any(|w| w == "NO_FULL") || !only.is_empty() {
        return Ok(());
    }
    let (t1, c1) = (Instant::now(), cpu());
    let on = AnalysisOptions {
        nonlinear: Some(spec),
        ..Default::default()
    };
    let a2 = analyze(&cap, &on, kappe::analysis::Request::default())?;
    let (t_on, c_on) = (t1.elapsed().as_secs_f64(), cpu() - c1);
    let run: Vec<String> = a2
        .states
        .iter()
        .filter_map(|s| {
            s.collapse_factor
                .map(|c| format!("{}: {c:.4} (BLF {:.4})", s.index, s.blf.unwrap_or(f64::NAN)))
        })
        .collect();
    println!(
        "analysis with the collapse check: {t_on:.2} s wall ({:.2}× without), {c_on:.2} s CPU ({:.2}× without; load {}); states run: {}",
        t_on / t_off,
        c_on / c_off,
        load_average(),
        run.join(", ")
    );
    Ok(())
}
