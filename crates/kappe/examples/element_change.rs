//! The BLF of every print state of the default cap with the Kirchhoff element (CST+DKT, the
//! element before issue 17) and the Reissner–Mindlin ANDES+DKMT (the default since), on the
//! same shell meshes (`state_shell`, the design's row stride), and the factor change per state.
//! Prints a markdown table, the final state's BLF and the summary of the changes, and the FE
//! wall time of each element summed over the states.
//!
//! `cargo run --release -p kappe --example element_change [-- STRIDE]`

use std::time::Instant;

use kappe::analysis::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::build_state;
use kappe_fe::{BucklingOptions, ElementKind};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let design = kappe::Design::default();
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let mut options = AnalysisOptions::default();
    if let Some(s) = std::env::args().nth(1) {
        options.row_stride = s.parse()?;
    }
    let phi = design.print.start_arch_fraction;
    let fe = BucklingOptions {
        modes: options.modes,
        tolerance: 1e-8,
        sturm_check: false,
        ..Default::default()
    };
    let elements = [ElementKind::CstDkt, ElementKind::AndesDkmt];
    let mut secs = [0.0; 2];
    let mut ratios = Vec::new();
    println!(
        "default cap, {} states, row stride {}\n",
        cap.states.len(),
        options.row_stride
    );
    println!("| state | top layer | shell nodes | BLF CST+DKT | BLF ANDES+DKMT | change |");
    println!("|---|---|---|---|---|---|");
    for top in 0..cap.states.len() {
        let state = build_state(&cap.sections, &cap.frame, phi, top)?;
        let mat = state_material(
            &cap,
            &options,
            top,
            Some(&kappe::analysis::CapGreen::new(&cap).unwrap()),
        );
        let Ok(shell) = state_shell(&state, &mat, options.row_stride) else {
            println!("| {top} | {} | – | – | – | – |", state.top_layer);
            continue;
        };
        let mut blf = [f64::NAN; 2];
        for (k, &el) in elements.iter().enumerate() {
            let mut m = shell.model.clone();
            m.element = el;
            let t0 = Instant::now();
            let r = kappe_fe::buckling(&m, &fe);
            secs[k] += t0.elapsed().as_secs_f64();
            blf[k] = match r {
                Ok(r) => r.factors.first().copied().unwrap_or(f64::NAN),
                Err(_) => f64::NAN,
            };
        }
        let ratio = blf[1] / blf[0];
        if ratio.is_finite() {
            ratios.push((top, ratio));
        }
        println!(
            "| {top} | {} | {} | {:.4} | {:.4} | {:+.2} % |",
            state.top_layer,
            shell.model.nodes.len(),
            blf[0],
            blf[1],
            100.0 * (ratio - 1.0)
        );
    }
    let min = ratios.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1));
    let max = ratios.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
    let mean = ratios.iter().map(|r| r.1).sum::<f64>() / ratios.len().max(1) as f64;
    println!(
        "\nchange over {} analysed states: mean {:+.2} %, min {:+.2} % (state {}), max {:+.2} % (state {})",
        ratios.len(),
        100.0 * (mean - 1.0),
        100.0 * (min.map_or(f64::NAN, |m| m.1) - 1.0),
        min.map_or(0, |m| m.0),
        100.0 * (max.map_or(f64::NAN, |m| m.1) - 1.0),
        max.map_or(0, |m| m.0),
    );
    if let Some(&(top, r)) = ratios.last() {
        println!("final state {top}: ANDES+DKMT / CST+DKT = {r:.5}");
    }
    println!(
        "FE wall time summed over states (one thread): CST+DKT {:.2} s, ANDES+DKMT {:.2} s",
        secs[0], secs[1]
    );
    Ok(())
}
