//! The lowest buckling factor of print states of the default cap on n×n splits of their
//! print-layer mesh (`kappe_fe::refine::split`, the same flat facets), n = 1 … MAXN: the mesh
//! sequences of docs/convergence.md.
//!
//! `MAXN=8 cargo run --release -p kappe --example blf_split -- STATE [STATE …]` (environment:
//! `LEN` the cap length, m; `EL` the element name, default `andes_dkmt`).

use std::time::Instant;

use kappe::analysis::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::build_state;
use kappe_fe::{BucklingOptions, ElementKind};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut design = kappe::Design::default();
    if let Ok(l) = std::env::var("LEN") {
        design.cap.length = l.parse()?;
    }
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let options = AnalysisOptions::default();
    let el = std::env::var("EL")
        .ok()
        .and_then(|e| ElementKind::from_name(&e))
        .unwrap_or(ElementKind::AndesDkmt);
    let maxn: usize = std::env::var("MAXN")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(4);
    println!("| state | n | nodes | free DOFs | λ₁ | λ₂ | s | change |");
    println!("|---|---|---|---|---|---|---|---|");
    for a in std::env::args().skip(1) {
        let top: usize = a.parse()?;
        let state = build_state(
            &cap.sections,
            &cap.frame,
            design.print.start_arch_fraction,
            top,
        )?;
        let mut shell = state_shell(
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
        shell.model.element = el;
        let mut prev: Option<f64> = None;
        for n in 1..=maxn {
            let m = kappe_fe::refine::split(&shell.model, n).model;
            let t = Instant::now();
            let r = kappe_fe::buckling(
                &m,
                &BucklingOptions {
                    modes: 2,
                    tolerance: 1e-9,
                    sturm_check: false,
                    ..Default::default()
                },
            )?;
            let l = r.factors[0];
            println!(
                "| {top} | {n} | {} | {} | {l:.5} | {:.5} | {:.2} | {} |",
                m.nodes.len(),
                r.stats.n_free_dofs,
                r.factors.get(1).copied().unwrap_or(f64::NAN),
                t.elapsed().as_secs_f64(),
                prev.map_or(String::new(), |p| format!("{:+.5}", l - p))
            );
            prev = Some(l);
        }
    }
    Ok(())
}
