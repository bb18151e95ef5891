//! Verification of the converged buckling factor (issue 23, docs/convergence.md).
//!
//! `cargo run --release -p kappe --example blf_convergence -- states LENGTH MAXSPLIT STATE…`:
//! per state, the factor on the print-layer mesh and its 2×2, 4×4 (… up to MAXSPLIT) splits,
//! the observed order of the last three, the reference (the finest two levels extrapolated at
//! the observed order, clamped to [1, 2]), and Kappe's converged estimate (what `kappe design`
//! reports: 1×1 and 2×2 at order 1) with its error estimate and its deviation from the
//! reference.
//!
//! `-- table LENGTH [EVERY]`: the analysis as `kappe design` runs it (adaptive sampling of the
//! split, `kappe::analysis::convergence`) against the same analysis with the split solved in
//! every state, every state's factor and the governing state, and against the split-4
//! reference on every EVERY-th state (default 0: none) and the governing state.

use std::time::Instant;

use kappe::analysis::state_shell;
use kappe::analysis::{AnalysisOptions, analyze, state_material};
use kappe::form::build_state;
use kappe_fe::{BucklingOptions, ConvergedFactor};

fn design(length: f64) -> kappe::Design {
    let mut d = kappe::Design::default();
    d.cap.length = length;
    d
}

/// Per mesh: splits per edge, factor, free DOFs, seconds.
type Level = (usize, f64, usize, f64);

/// The factors of `state` on splits 1, 2, 4, … ≤ `max_split`.
fn splits(
    cap: &kappe::form::Cap,
    d: &kappe::Design,
    top: usize,
    max_split: usize,
) -> Result<Vec<Level>, Box<dyn std::error::Error>> {
    let options = AnalysisOptions::default();
    let state = build_state(&cap.sections, &cap.frame, d.print.start_arch_fraction, top)?;
    let shell = state_shell(
        &state,
        &state_material(
            cap,
            &options,
            top,
            Some(&kappe::analysis::CapGreen::new(cap)?),
        ),
        1,
    )
    .map_err(|e| format!("{e:?}"))?;
    let mut out = Vec::new();
    let mut n = 1;
    let opts = BucklingOptions {
        modes: 1,
        tolerance: 1e-8,
        sturm_check: false,
        ..Default::default()
    };
    let mut model = shell.model.clone();
    let mut mode: Option<Vec<[f64; 6]>> = None;
    while n <= max_split {
        let t = Instant::now();
        let r = kappe_fe::buckling(
            &model,
            &BucklingOptions {
                start: mode.clone(),
                ..opts.clone()
            },
        )?;
        out.push((
            n,
            r.factors[0],
            r.stats.n_free_dofs,
            t.elapsed().as_secs_f64(),
        ));
        let refined = kappe_fe::refine::split(&model, 2);
        mode = r.modes.first().map(|m| refined.prolong(m));
        model = refined.model;
        n *= 2;
    }
    Ok(out)
}

/// The reference from the finest levels: the last two extrapolated at the order observed on the
/// last three (clamped to [1, 2]); with two levels, order 1.
fn reference(levels: &[Level]) -> (f64, f64) {
    let n = levels.len();
    let f = |i: usize| levels[i].1;
    let p = if n >= 3 {
        let r = (f(n - 3) - f(n - 2)) / (f(n - 2) - f(n - 1));
        if r > 0.0 {
            r.log2().clamp(1.0, 2.0)
        } else {
            1.0
        }
    } else {
        1.0
    };
    (f(n - 1) - (f(n - 2) - f(n - 1)) / (2f64.powf(p) - 1.0), p)
}

fn states(
    length: f64,
    max_split: usize,
    picks: &[usize],
) -> Result<(), Box<dyn std::error::Error>> {
    let d = design(length);
    let cap = kappe::design_cap(&d, kappe::Context::default())?;
    println!("cap length {length} m, {} states", cap.states.len());
    println!(
        "| state | splits: factor (DOFs, s) | order | reference | Kappe estimate | its error estimate | Kappe vs reference | mesh vs reference |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for &top in picks {
        let levels = splits(&cap, &d, top, max_split)?;
        let (r, p) = reference(&levels);
        let k = ConvergedFactor::from_pair(
            levels
                .iter()
                .take(2)
                .map(|l| kappe_fe::MeshLevel {
                    split: l.0,
                    factor: l.1,
                    n_free_dofs: l.2,
                    steps: 0,
                    solver: kappe_fe::LevelSolve::Direct,
                })
                .collect(),
            AnalysisOptions::default().blf_tolerance,
        )
        .ok_or("one level only")?;
        let cells: Vec<String> = levels
            .iter()
            .map(|l| format!("{}: {:.4} ({}, {:.1})", l.0, l.1, l.2, l.3))
            .collect();
        println!(
            "| {top} | {} | {p:.2} | {r:.4} | {:.4} | {:.2} % | {:+.2} % | {:+.2} % |",
            cells.join("; "),
            k.extrapolated,
            100.0 * k.error,
            100.0 * (k.extrapolated / r - 1.0),
            100.0 * (levels[0].1 / r - 1.0)
        );
    }
    Ok(())
}

fn table(length: f64, every: usize) -> Result<(), Box<dyn std::error::Error>> {
    let d = design(length);
    let cap = kappe::design_cap(&d, kappe::Context::default())?;
    let run = |o: &AnalysisOptions| -> Result<(kappe::analysis::Analysis, f64), String> {
        let t = Instant::now();
        let a = analyze(&cap, o, kappe::analysis::Request::default()).map_err(|e| e.to_string())?;
        Ok((a, t.elapsed().as_secs_f64()))
    };
    let (sampled, t_sampled) = run(&AnalysisOptions::default())?;
    let (all, t_all) = run(&AnalysisOptions {
        blf_sampling: false,
        ..Default::default()
    })?;
    let (mesh, t_mesh) = run(&AnalysisOptions {
        converged_blf: false,
        ..Default::default()
    })?;
    let gov = |a: &kappe::analysis::Analysis| {
        a.states
            .iter()
            .filter_map(|s| Some((s.index, s.blf?)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    };
    println!(
        "cap length {length} m, {} states; analysis wall s: converged (sampled) {t_sampled:.1}, split in every state {t_all:.1}, print-layer mesh only {t_mesh:.1}",
        cap.states.len()
    );
    println!(
        "governing (state, BLF): converged (sampled) {:?}, split in every state {:?}, print-layer mesh {:?}",
        gov(&sampled),
        gov(&all),
        gov(&mesh)
    );
    // Sampled against split-in-every-state, every state.
    let mut w = (0.0_f64, 0usize);
    let mut up = (f64::NEG_INFINITY, 0usize);
    for (a, b) in sampled.states.iter().zip(&all.states) {
        if let (Some(x), Some(y)) = (a.blf, b.blf) {
            let d = x / y - 1.0;
            if d.abs() > w.0 {
                w = (d.abs(), a.index);
            }
            if d > up.0 {
                up = (d, a.index);
            }
        }
    }
    println!(
        "sampled vs split in every state, every state: largest |difference| {:.4} % (state {}), largest above {:+.4} % (state {})",
        100.0 * w.0,
        w.1,
        100.0 * up.0,
        up.1
    );
    let solved = sampled
        .states
        .iter()
        .filter(|s| s.blf_interpolated == Some(false))
        .count();
    let worst_err = sampled
        .states
        .iter()
        .filter_map(|s| Some((s.blf_error?, s.index)))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    println!(
        "split solved in {solved} states, the others interpolated; largest error estimate {worst_err:?}"
    );
    if every == 0 {
        return Ok(());
    }
    println!(
        "| state | interpolated | Kappe BLF | error estimate | reference (splits 1, 2, 4) | order | Kappe vs reference | print-layer mesh vs reference |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let g = gov(&sampled).map(|g| g.0);
    let mut worst: (f64, usize) = (0.0, 0);
    let mut unsafe_side: (f64, usize) = (f64::NEG_INFINITY, 0);
    for s in &sampled.states {
        if !(s.index % every == 0 || Some(s.index) == g) {
            continue;
        }
        let Some(blf) = s.blf else { continue };
        let levels = splits(&cap, &d, s.index, 4)?;
        let (r, p) = reference(&levels);
        let dev = blf / r - 1.0;
        if dev.abs() > worst.0 {
            worst = (dev.abs(), s.index);
        }
        if dev > unsafe_side.0 {
            unsafe_side = (dev, s.index);
        }
        println!(
            "| {} | {} | {blf:.4} | {:.2} % | {r:.4} | {p:.2} | {:+.2} % | {:+.2} % |",
            s.index,
            s.blf_interpolated.unwrap_or(false),
            100.0 * s.blf_error.unwrap_or(f64::NAN),
            100.0 * dev,
            100.0 * (levels[0].1 / r - 1.0)
        );
    }
    println!(
        "largest |Kappe − reference| {:.3} % (state {}), largest on the unsafe side {:+.3} % (state {})",
        100.0 * worst.0,
        worst.1,
        100.0 * unsafe_side.0,
        unsafe_side.1
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, d: f64| args.get(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    match args.first().map(String::as_str) {
        Some("table") => table(num(1, 0.6), num(2, 0.0) as usize),
        _ => {
            let picks: Vec<usize> = args.iter().skip(3).filter_map(|a| a.parse().ok()).collect();
            let picks = if picks.is_empty() {
                vec![10, 40, 112]
            } else {
                picks
            };
            states(num(1, 0.6), num(2, 4.0) as usize, &picks)
        }
    }
}
