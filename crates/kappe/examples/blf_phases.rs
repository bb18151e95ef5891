//! Where one print state's buckling solve spends its time (issue 25 item 1): the print-layer
//! mesh from a cold and from a warm start (the state's own mode, as the previous state's mode
//! is close to it), and its 2×2 split started from the mode prolonged onto it (the mesh-error
//! pass, docs/convergence.md). One row per solve: free DOFs, entries of L, Lanczos steps and the
//! seconds of each phase (`kappe_fe::SolveStats`; pattern + AMD + symbolic, assembly of K,
//! numeric LLᵀ + static solve, stresses + K_G, Lanczos).
//!
//! `cargo run --release -p kappe --example blf_phases -- STATE [STATE …]` (default 40 112).

use std::time::Instant;

use kappe::analysis::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::build_state;
use kappe_fe::{BucklingOptions, BucklingResult};

fn row(top: usize, what: &str, r: &BucklingResult, wall: f64) {
    let s = &r.stats;
    println!(
        "| {top} | {what} | {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {wall:.3} | {:.5} |",
        s.n_free_dofs,
        s.nnz_l,
        s.operator_applications,
        s.t_symbolic,
        s.t_assembly,
        s.t_factor,
        s.t_geometric,
        s.t_eigen,
        r.factors.first().copied().unwrap_or(f64::NAN),
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let design = kappe::Design::default();
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let options = AnalysisOptions::default();
    let mut states: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    if states.is_empty() {
        states = vec![40, 112];
    }
    // The analysis's own eigen-solver settings (converged factor: residual 1e-5, one mode).
    let opts = BucklingOptions {
        modes: options.modes,
        tolerance: 1e-5,
        sturm_check: false,
        ..Default::default()
    };
    println!(
        "| state | solve | free DOFs | nnz L | Lanczos steps | symbolic s | assembly s | LLᵀ + static s | K_G s | Lanczos s | wall s | λ₁ |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for top in states {
        let state = build_state(
            &cap.sections,
            &cap.frame,
            design.print.start_arch_fraction,
            top,
        )?;
        let shell = state_shell(
            &state,
            &state_material(
                &cap,
                &options,
                top,
                Some(&kappe::analysis::CapGreen::new(&cap)?),
            ),
            1,
        )
        .map_err(|e| format!("{e:?}"))?;
        let t = Instant::now();
        let cold = kappe_fe::buckling(&shell.model, &opts)?;
        row(top, "layer mesh, cold", &cold, t.elapsed().as_secs_f64());
        let t = Instant::now();
        let warm = kappe_fe::buckling(
            &shell.model,
            &BucklingOptions {
                start: cold.modes.first().cloned(),
                ..opts.clone()
            },
        )?;
        row(top, "layer mesh, warm", &warm, t.elapsed().as_secs_f64());
        let t = Instant::now();
        let refined = kappe_fe::refine::split(&shell.model, 2);
        let t_split = t.elapsed().as_secs_f64();
        let start = cold.modes.first().map(|m| refined.prolong(m));
        let t = Instant::now();
        let fine = kappe_fe::buckling(
            &refined.model,
            &BucklingOptions {
                modes: 1,
                start,
                ..opts.clone()
            },
        )?;
        row(
            top,
            &format!("2×2 split, prolonged (split {t_split:.3} s)"),
            &fine,
            t.elapsed().as_secs_f64(),
        );
    }
    Ok(())
}
