//! The as-printed shape on a graded mesh against the full print-layer mesh (docs/as-printed.md
//! §6): per cap, the largest deviation and crown sag of both, the largest per-state relative
//! difference of each, and the wall time of the stand-alone as-printed pass on each mesh.
//!
//! `cargo run --release -p kappe --example as_printed_graded [-- default|1.2|bay]`

use std::time::Instant;

#[path = "common/caps.rs"]
mod caps;

fn compare(name: &str, d: &kappe::Design) -> Result<(), Box<dyn std::error::Error>> {
    let cap = kappe::design_cap(d, kappe::Context::default())?;
    let mut graded = d.analysis.clone();
    graded.grading.get_or_insert_with(Default::default);
    let full = kappe::analysis::AnalysisOptions {
        grading: None,
        ..graded.clone()
    };
    let none = || Ok(());
    let t = Instant::now();
    let g = kappe::analysis::cap_as_printed(&cap, &graded, None, &none)?;
    let tg = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let f = kappe::analysis::cap_as_printed(&cap, &full, None, &none)?;
    let tf = t.elapsed().as_secs_f64();
    // Largest |graded/full − 1| over the states, signed, with its state.
    let worst = |pick: fn(&kappe::analysis::StateDeviation) -> f64| {
        g.states
            .iter()
            .zip(&f.states)
            .filter(|(_, b)| pick(b) > 1e-9)
            .map(|(a, b)| (pick(a) / pick(b) - 1.0, b.state))
            .max_by(|x, y| x.0.abs().total_cmp(&y.0.abs()))
            .unwrap_or((0.0, 0))
    };
    let (dev, dev_at) = worst(|s| s.deviation_m);
    let (sag, sag_at) = worst(|s| s.crown_sag_m);
    let state = |s: Option<usize>| s.map_or("-".into(), |s| s.to_string());
    println!(
        "| {name} | {} | {:.4} mm (state {}) / {:.4} mm (state {}) | {:+.3} % (state {dev_at}) | {:.4} / {:.4} mm | {:+.3} % (state {sag_at}) | {tg:.1} / {tf:.1} s |",
        cap.states.len(),
        1e3 * g.deviation_m,
        state(g.state),
        1e3 * f.deviation_m,
        state(f.state),
        100.0 * dev,
        1e3 * g.crown_sag_m,
        1e3 * f.crown_sag_m,
        100.0 * sag,
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let which = std::env::args().nth(1).unwrap_or_default();
    println!(
        "| cap | states | largest deviation graded / full | largest per-state deviation difference | largest crown sag graded / full | largest per-state sag difference | as-printed pass alone, wall graded / full |"
    );
    println!("|---|---|---|---|---|---|---|");
    if which.is_empty() || which == "default" {
        compare("default 0.6 m", &kappe::Design::default())?;
    }
    if which.is_empty() || which == "1.2" {
        compare(
            "1.2 m",
            &kappe::Design::from_toml_str("[cap]\nlength = 1.2\n")?,
        )?;
    }
    if which.is_empty() || which == "bay" {
        compare("1.5 m × 4 m bay (one half)", &caps::bay_half()?)?;
    }
    Ok(())
}
