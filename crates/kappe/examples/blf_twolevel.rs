//! The split pass's two solvers side by side (docs/convergence.md, "The `twogrid` branch"): per
//! state, the 2×2 split's lowest factor by the direct solve (LLᵀ of the split's K, Lanczos
//! started from the print-layer mode prolonged, as `kappe design` runs it by default) and by the
//! two-level solver (`kappe_fe::twolevel::split_buckling`: PCG + LOBPCG preconditioned by the
//! print-layer mesh's Galerkin LLᵀ), each from the print-layer solve's mode, with their wall
//! seconds, the relative difference and the two-level solve's counts (or why it declined).
//!
//! `cargo run --release -p kappe --example blf_twolevel -- KIND LENGTH STATE…`
//! (KIND: `smooth` = `kappe init`, `corrugated` = `kappe init --kind corrugated`; LENGTH the
//! cap length, m). `BLOCK=k` sets the LOBPCG block (default 2).

#[path = "common/caps.rs"]
mod caps;

use std::time::Instant;

use kappe::analysis::{AnalysisOptions, state_material, state_shell};
use kappe_fe::BucklingOptions;
use kappe_fe::twolevel::{TwoLevel, TwoLevelOptions, split_buckling};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(kind), Some(length)) = (args.first(), args.get(1)) else {
        return Err("usage: blf_twolevel KIND LENGTH STATE…".into());
    };
    let cap = caps::cap_of(kind, length)?;
    let options = AnalysisOptions::default();
    let green = kappe::analysis::CapGreen::new(&cap)?;
    // The analysis's own eigen-solver settings for the converged factor (residual 1e-5).
    let opts = BucklingOptions {
        modes: 1,
        tolerance: 1e-5,
        sturm_check: false,
        ..Default::default()
    };
    let mut tl = TwoLevelOptions {
        eigen_tolerance: opts.tolerance,
        ..TwoLevelOptions::default()
    };
    if let Ok(b) = std::env::var("BLOCK") {
        tl.block = b.parse()?;
    }
    println!(
        "{kind} cap, length {length} m, {} states; two-level {tl:?}",
        cap.states.len()
    );
    println!(
        "| state | free DOFs coarse / split | λ_c | direct λ_f | direct s | two-level λ_f | two-level s (setup, static, eigen) | rel. diff | PCG its | LOBPCG its | cycles | coarse steps | coarse-space λᴳ | η |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for a in args.iter().skip(2) {
        let top: usize = a.parse()?;
        let state = cap.state(top)?;
        let material = state_material(&cap, &options, top, Some(&green));
        let shell = state_shell(&state, &material, 1).map_err(|e| format!("{e:?}"))?;
        if let Ok(dir) = std::env::var("DUMP") {
            std::fs::write(
                format!("{dir}/{kind}_{length}_{top}.mesh.json"),
                mesh_json(&shell.model),
            )?;
        }
        let coarse = kappe_fe::buckling(&shell.model, &opts)?;
        let mode = coarse.modes.first().cloned();
        let refined = kappe_fe::refine::split(&shell.model, 2);
        let t = Instant::now();
        let direct = kappe_fe::buckling(
            &refined.model,
            &BucklingOptions {
                start: mode.as_ref().map(|m| refined.prolong(m)),
                ..opts.clone()
            },
        )?;
        let t_direct = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let two = split_buckling(&shell.model, &refined, mode.as_deref(), &tl)?;
        let t_two = t.elapsed().as_secs_f64();
        let lf = direct.factors[0];
        match two {
            TwoLevel::Solved(s) => {
                let st = s.stats;
                println!(
                    "| {top} | {} / {} | {:.6} | {lf:.9} | {t_direct:.3} | {:.9} | {t_two:.3} ({:.3}, {:.3}, {:.3}) | {:.2e} | {} | {} | {} | {} | {:?} | {:.1e} |",
                    st.n_free_coarse,
                    st.n_free_fine,
                    coarse.factors[0],
                    s.factor,
                    st.t_setup,
                    st.t_static,
                    st.t_eigen,
                    (s.factor - lf) / lf,
                    st.pcg_iterations,
                    st.lobpcg_iterations,
                    st.cycles,
                    st.coarse_steps,
                    s.coarse_factors,
                    s.residual,
                );
            }
            TwoLevel::Declined { reason: why, .. } => println!(
                "| {top} | | {:.6} | {lf:.9} | {t_direct:.3} | declined: {why} | {t_two:.3} | | | | | | | |",
                coarse.factors[0]
            ),
        }
    }
    Ok(())
}

/// `model` in the fixture mesh format (`kappe_fe::mesh_json`), so a state can be solved by the
/// fe crate's own examples (`DUMP=DIR`).
fn mesh_json(m: &kappe_fe::ShellModel) -> String {
    let n_el = m.triangles.len();
    let mats: Vec<kappe_fe::Material> = (0..n_el).map(|e| m.material_of(e)).collect();
    let t: Vec<f64> = (0..n_el).map(|e| m.thickness_of(e)).collect();
    let fixed = m.fixed_mask();
    let names = ["ux", "uy", "uz", "rx", "ry", "rz"];
    let supports: serde_json::Map<String, serde_json::Value> = (0..6)
        .map(|d| {
            let nodes: Vec<usize> = (0..fixed.len()).filter(|&n| fixed[n][d]).collect();
            (names[d].to_string(), serde_json::json!(nodes))
        })
        .collect();
    let forces: Vec<serde_json::Value> = m
        .nodal_loads
        .iter()
        .map(|l| {
            serde_json::json!([
                l.node,
                [
                    l.force[0],
                    l.force[1],
                    l.force[2],
                    l.moment[0],
                    l.moment[1],
                    l.moment[2]
                ]
            ])
        })
        .collect();
    let mut load = vec![serde_json::json!({"type": "self_weight", "direction": m.gravity})];
    if !forces.is_empty() {
        load.push(serde_json::json!({"type": "nodal_forces", "forces": forces}));
    }
    serde_json::json!({
        "nodes": m.nodes,
        "triangles": m.triangles,
        "thickness": t,
        "E": mats.iter().map(|x| x.youngs_modulus).collect::<Vec<_>>(),
        "nu": mats.iter().map(|x| x.poisson_ratio).collect::<Vec<_>>(),
        "gamma": mats.iter().map(|x| x.unit_weight).collect::<Vec<_>>(),
        "supports": supports,
        "load": load,
        "drilling_alpha": m.drilling_alpha,
        "element": m.element.name(),
    })
    .to_string()
}
