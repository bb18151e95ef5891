//! The two-level split solver (`kappe_fe::twolevel`) against the direct split solve on meshes
//! in the fixture format (e.g. print states written by `kappe`'s `blf_twolevel` example with
//! `DUMP=DIR`): per mesh, the print-layer factor, the split's by both solvers with their wall
//! seconds, the relative difference, the two-level counts and phase seconds.
//!
//! `cargo run --release -p fe --example twolevel_mesh -- MESH.json…`; options from the
//! environment (defaults: `TwoLevelOptions::default()`): `BLOCK`, `SWEEPS`, `GAP`, `STOL`;
//! `ETOL` the direct Lanczos residual (1e-5, as `kappe design`), `TL_ETOL` the two-level η
//! (default ETOL, as `kappe_fe::converge_from_with` passes it).

use std::time::Instant;

use kappe_fe::twolevel::{TwoLevel, TwoLevelOptions, split_buckling};
use kappe_fe::{BucklingOptions, buckling, mesh_json::parse_mesh, refine::split};

fn env<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let opts = BucklingOptions {
        modes: 1,
        tolerance: env("ETOL", 1e-5),
        sturm_check: false,
        ..Default::default()
    };
    let d = TwoLevelOptions::default();
    let tl = TwoLevelOptions {
        block: env("BLOCK", d.block),
        sweeps: env("SWEEPS", d.sweeps),
        gap: env("GAP", d.gap),
        static_tolerance: env("STOL", d.static_tolerance),
        eigen_tolerance: env("TL_ETOL", opts.tolerance),
        ..d
    };
    println!("{tl:?}");
    println!(
        "| mesh | DOFs coarse / split | λ_c | direct λ_f | direct s | two-level λ_f | two-level s (setup, static, eigen) | rel. diff | PCG | LOBPCG | cycles | coarse steps | coarse-space λᴳ | outcome |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for path in std::env::args().skip(1) {
        let model = parse_mesh(&std::fs::read_to_string(&path)?)?;
        let coarse = buckling(&model, &opts)?;
        let mode = coarse.modes.first().cloned();
        let refined = split(&model, 2);
        let t = Instant::now();
        let direct = buckling(
            &refined.model,
            &BucklingOptions {
                start: mode.as_ref().map(|m| refined.prolong(m)),
                ..opts.clone()
            },
        )?;
        let t_direct = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let two = split_buckling(&model, &refined, mode.as_deref(), &tl)?;
        let t_two = t.elapsed().as_secs_f64();
        let lf = direct.factors[0];
        let name = std::path::Path::new(&path)
            .file_name()
            .map_or(path.clone(), |f| f.to_string_lossy().into_owned());
        let (factor, outcome, st, coarse_f) = match &two {
            TwoLevel::Solved(s) => (
                s.factor,
                "solved".to_string(),
                s.stats,
                s.coarse_factors.clone(),
            ),
            TwoLevel::Declined { reason, stats } => (
                f64::NAN,
                reason.clone(),
                *stats,
                vec![stats.coarse_factor_1, stats.coarse_factor_next],
            ),
        };
        println!(
            "| {name} | {} / {} | {:.6} | {lf:.9} | {t_direct:.3} | {factor:.9} | {t_two:.3} ({:.3}, {:.3}, {:.3}) | {:.2e} | {} | {} | {} | {} | {coarse_f:.5?} | {outcome} |",
            st.n_free_coarse,
            st.n_free_fine,
            coarse.factors[0],
            st.t_setup,
            st.t_static,
            st.t_eigen,
            (factor - lf) / lf,
            st.pcg_iterations,
            st.lobpcg_iterations,
            st.cycles,
            st.coarse_steps,
        );
    }
    Ok(())
}
