//! Benchmark of the full analysis of the default design (every state), with the time split
//! (form-finding, stresses, FE per state), and a mesh study of the final state's BLF against the
//! number of layers per shell mesh row.
//!
//! `cargo run --release -p kappe --example analysis_bench [-- STRIDE]`

use std::time::Instant;

use kappe::analysis::{AnalysisOptions, analyze, state_buckling, state_material};

/// `-- profile FILE.toml [STATES]`: per-state split of the buckling check of a design file
/// (build state, force pass, graded reduction, shell, FE phases, Lanczos steps).
fn profile(file: &str, states: &[usize]) -> Result<(), Box<dyn std::error::Error>> {
    let design = kappe::Design::from_toml_str(&std::fs::read_to_string(file)?)?;
    let t = Instant::now();
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    println!(
        "{file}: {} states, design_cap {:.2} s",
        cap.states.len(),
        t.elapsed().as_secs_f64()
    );
    let o = design.analysis.clone();
    let phi = design.print.start_arch_fraction;
    let total = cap.states.len();
    let picks: Vec<usize> = if states.is_empty() {
        (1..=4).map(|k| k * (total - 1) / 4).collect()
    } else {
        states.to_vec()
    };
    println!(
        "| state | build | stresses | graded | shell | nodes | DOFs | nnz(L) | symbolic | assembly | factor | K_G | Lanczos (steps) | BLF |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for top in picks {
        let t = Instant::now();
        let state = kappe::form::build_state(&cap.sections, &cap.frame, phi, top)?;
        let t_build = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let _ = kappe::analysis::element_stresses(&state, cap.areas())?;
        let t_stress = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let reduced = match &o.grading {
            Some(g) => kappe::analysis::graded_state(&state, g),
            None => state.clone(),
        };
        let t_graded = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mat = state_material(&cap, &o, top, Some(&kappe::analysis::CapGreen::new(&cap)?));
        let Ok(shell) = kappe::analysis::state_shell(&reduced, &mat, o.row_stride) else {
            continue;
        };
        let t_shell = t.elapsed().as_secs_f64();
        let fe_opts = kappe_fe::BucklingOptions {
            modes: o.modes,
            tolerance: 1e-8,
            sturm_check: false,
            ..Default::default()
        };
        let r = kappe_fe::buckling(&shell.model, &fe_opts)?;
        let s = &r.stats;
        println!(
            "| {top} | {t_build:.3} | {t_stress:.3} | {t_graded:.3} | {t_shell:.3} | {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} ({}) | {:.4} |",
            shell.model.nodes.len(),
            s.n_free_dofs,
            s.nnz_l,
            s.t_symbolic,
            s.t_assembly,
            s.t_factor,
            s.t_geometric,
            s.t_eigen,
            s.operator_applications,
            r.factors.first().copied().unwrap_or(f64::NAN)
        );
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "profile") {
        let file = args.get(1).ok_or("profile FILE.toml [STATES]")?;
        let states: Vec<usize> = args.iter().skip(2).filter_map(|a| a.parse().ok()).collect();
        return profile(file, &states);
    }
    let stride: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(AnalysisOptions::default().row_stride);
    let design = kappe::Design::default();
    let t0 = Instant::now();
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let t_form = t0.elapsed().as_secs_f64();
    let options = AnalysisOptions {
        row_stride: stride,
        ..AnalysisOptions::default()
    };
    let t1 = Instant::now();
    let analysis = analyze(&cap, &options, kappe::analysis::Request::default())?;
    let t_analysis = t1.elapsed().as_secs_f64();
    println!(
        "default design, {} states, row stride {stride}",
        cap.states.len()
    );
    println!("{:<44} {:>9}", "phase", "seconds");
    println!(
        "{:<44} {:>9.3}",
        "form-finding + states + forces (design_cap)", t_form
    );
    println!(
        "{:<44} {:>9.3}",
        "stresses, wall (all states)", analysis.timings.stresses
    );
    println!(
        "{:<44} {:>9.3}",
        "stresses, sum over states", analysis.timings.stresses_sum
    );
    println!(
        "{:<44} {:>9.3}",
        "FE, wall (all states)", analysis.timings.fe
    );
    println!(
        "{:<44} {:>9.3}",
        "FE, sum over states", analysis.timings.fe_sum
    );
    println!("{:<44} {:>9.3}", "analysis total (wall)", t_analysis);
    println!(
        "{:<44} {:>9.3}",
        "design + analysis total (wall)",
        t_form + t_analysis
    );
    println!();
    println!(
        "{:>6} {:>6} {:>7} {:>9} {:>9}",
        "state", "layer", "nodes", "BLF", "FE s"
    );
    for s in analysis
        .states
        .iter()
        .step_by(8)
        .chain(analysis.states.last())
    {
        println!(
            "{:>6} {:>6} {:>7} {:>9.4} {:>9.3}",
            s.index,
            s.top_layer,
            s.shell_nodes,
            s.blf.unwrap_or(f64::NAN),
            s.fe_seconds
        );
    }
    println!();
    print!("{}", analysis.report());

    println!("\nmesh study, final state: BLF vs layers per mesh row");
    let last = cap.states.len() - 1;
    let state = kappe::form::build_state(
        &cap.sections,
        &cap.frame,
        design.print.start_arch_fraction,
        last,
    )?;
    for stride in [1usize, 2, 3, 4] {
        let o = AnalysisOptions {
            row_stride: stride,
            modes: 3,
            sturm_check: true,
            ..AnalysisOptions::default()
        };
        let t = Instant::now();
        let b = state_buckling(
            &state,
            &state_material(&cap, &o, last, Some(&kappe::analysis::CapGreen::new(&cap)?)),
            &o.with_split_at_most(2),
            &Default::default(),
        )?
        .buckling;
        println!(
            "  stride {stride}: {:>5} nodes, BLF {:?}, {:.3} s (3 modes + Sturm check)",
            b.shell_nodes,
            b.factors,
            t.elapsed().as_secs_f64()
        );
    }

    // Split of one FE solve (final state, every layer a row), and what reusing the symbolic
    // factorization saves: states have different meshes, so kappe_fe::BucklingSolver can reuse
    // it only for models with the same mesh (e.g. another E or thickness of the same state).
    let o = AnalysisOptions::default();
    let shell = kappe::analysis::state_shell(
        &state,
        &state_material(&cap, &o, last, Some(&kappe::analysis::CapGreen::new(&cap)?)),
        1,
    )
    .map_err(|e| format!("{e:?}"))?;
    let fe_opts = kappe_fe::BucklingOptions {
        modes: 1,
        tolerance: 1e-8,
        sturm_check: false,
        ..Default::default()
    };
    let t = Instant::now();
    let solver = kappe_fe::BucklingSolver::new(&shell.model)?;
    let t_new = t.elapsed().as_secs_f64();
    let r = solver.buckling(&shell.model, &fe_opts)?;
    let s = &r.stats;
    println!(
        "\nFE split, final state ({} free DOFs, nnz(L) = {}):",
        s.n_free_dofs, s.nnz_l
    );
    println!(
        "  symbolic {:.3} s (solver set-up {t_new:.3} s), assembly {:.3} s, factor + static {:.3} s, \
         K_G {:.3} s, Lanczos {:.3} s ({} operator applications)",
        s.t_symbolic, s.t_assembly, s.t_factor, s.t_geometric, s.t_eigen, s.operator_applications
    );
    let mut stiffer = shell.model.clone();
    for m in &mut stiffer.materials {
        m.youngs_modulus *= 2.0;
    }
    let t = Instant::now();
    let r2 = solver.buckling(&stiffer, &fe_opts)?;
    println!(
        "  same mesh, 2E, reused symbolic: {:.3} s, BLF {:.4} (= 2 × {:.4})",
        t.elapsed().as_secs_f64(),
        r2.factors[0],
        r.factors[0]
    );
    Ok(())
}
