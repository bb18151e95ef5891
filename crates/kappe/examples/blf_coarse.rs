//! The coarse-mesh screen's premise (issue 25 item 1, docs/convergence.md "The `speed5`
//! branch"): per state, the lowest buckling factor on the meshes 4h and 2h (every 4th / 2nd
//! layer row and every 4th / 2nd node along each row, `kappe::analysis::coarsened_state`), h
//! (the print-layer mesh) and h/2 (its 2×2 split, started from h's mode as `kappe design` does),
//! with each solve's wall seconds and free DOFs; whether the sequence is monotone from above,
//! the observed ratios r = (λ_2h − λ_h)/(λ_h − λ_h/2) and (λ_4h − λ_2h)/(λ_2h − λ_h) (≥ 2 means
//! order p ≥ 1 between those meshes), and the (2h,h) lower bound λ_h − (λ_2h − λ_h) against the
//! (h,h/2) estimate 2λ_h/2 − λ_h that `kappe design` reports.
//!
//! `cargo run --release -p kappe --example blf_coarse -- KIND LENGTH STATE…`
//! `COARSEN=rows` or `COARSEN=nodes` coarsens in one direction only (2h then means every other
//! row, or every other node along each row).
//! (KIND: `smooth` = `kappe init`, `corrugated` = `kappe init --kind corrugated`; LENGTH the
//! cap length, m).

#[path = "common/caps.rs"]
mod caps;

use std::time::Instant;

use kappe::analysis::{AnalysisOptions, coarsened_state, state_material, state_shell};
use kappe_fe::BucklingOptions;

/// One mesh's factor, free DOFs and solve seconds.
struct Level {
    lambda: f64,
    dofs: usize,
    secs: f64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(kind), Some(length)) = (args.first(), args.get(1)) else {
        return Err("usage: blf_coarse KIND LENGTH STATE…".into());
    };
    let cap = caps::cap_of(kind, length)?;
    let options = AnalysisOptions::default();
    let green = kappe::analysis::CapGreen::new(&cap)?;
    // Residual 1e-8: the eigenvalue error (≈ residual², relative) far below the differences
    // between meshes measured here (≥ 1e-4 relative).
    let opts = BucklingOptions {
        modes: 1,
        tolerance: 1e-8,
        sturm_check: false,
        ..Default::default()
    };
    println!("{kind} cap, length {length} m, {} states", cap.states.len());
    println!(
        "| state | λ_4h (DOFs, s) | λ_2h (DOFs, s) | λ_h (DOFs, s) | λ_h/2 (DOFs, s) | monotone 2h ≥ h ≥ h/2 | r(2h,h,h/2) | r(4h,2h,h) | lower bound λ_h − (λ_2h − λ_h) | estimate 2λ_h/2 − λ_h | bound ≤ estimate |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for a in args.iter().skip(2) {
        let top: usize = a.parse()?;
        let state = cap.state(top)?;
        let material = state_material(&cap, &options, top, Some(&green));
        let level = |c: usize| -> Result<(Level, Option<Level>), String> {
            let s = match std::env::var("COARSEN").as_deref() {
                Ok("rows") => coarsened_state(&state, c, 1),
                Ok("nodes") => coarsened_state(&state, 1, c),
                _ => coarsened_state(&state, c, c),
            };
            let shell = state_shell(&s, &material, 1).map_err(|e| format!("{e:?}"))?;
            let t = Instant::now();
            let r = kappe_fe::buckling(&shell.model, &opts).map_err(|e| format!("{e}"))?;
            let coarse = Level {
                lambda: r.factors[0],
                dofs: r.stats.n_free_dofs,
                secs: t.elapsed().as_secs_f64(),
            };
            if c > 1 {
                return Ok((coarse, None));
            }
            // h/2: the split started from h's mode, as the mesh-error pass runs it.
            let refined = kappe_fe::refine::split(&shell.model, 2);
            let t = Instant::now();
            let f = kappe_fe::buckling(
                &refined.model,
                &BucklingOptions {
                    start: r.modes.first().map(|m| refined.prolong(m)),
                    ..opts.clone()
                },
            )
            .map_err(|e| format!("{e}"))?;
            let fine = Level {
                lambda: f.factors[0],
                dofs: f.stats.n_free_dofs,
                secs: t.elapsed().as_secs_f64(),
            };
            Ok((coarse, Some(fine)))
        };
        let ((c4, _), (c2, _)) = (level(4)?, level(2)?);
        let (c1, cf) = level(1)?;
        let cf = cf.ok_or("no h/2 level")?;
        let (l4, n4, t4) = (c4.lambda, c4.dofs, c4.secs);
        let (l2, n2, t2) = (c2.lambda, c2.dofs, c2.secs);
        let (l1, n1, t1) = (c1.lambda, c1.dofs, c1.secs);
        let (lf, nf, tf) = (cf.lambda, cf.dofs, cf.secs);
        let mono = l2 >= l1 && l1 >= lf;
        let r21 = (l2 - l1) / (l1 - lf);
        let r42 = (l4 - l2) / (l2 - l1);
        let bound = l1 - (l2 - l1);
        let est = 2.0 * lf - l1;
        println!(
            "| {top} | {l4:.5} ({n4}, {t4:.3}) | {l2:.5} ({n2}, {t2:.3}) | {l1:.5} ({n1}, {t1:.3}) | {lf:.5} ({nf}, {tf:.3}) | {} | {r21:.2} | {r42:.2} | {bound:.5} | {est:.5} | {} |",
            if mono { "yes" } else { "**no**" },
            if bound <= est { "yes" } else { "**no**" },
        );
    }
    Ok(())
}
