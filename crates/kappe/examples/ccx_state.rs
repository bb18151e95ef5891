//! Cross-check of a print state's BLF with CalculiX (measuring only; needs `ccx` on PATH,
//! e.g. `apt-get install calculix-ccx`; never used by tests): the state's shell mesh
//! (`state_shell`, row stride 1) as quadratic S6 triangles (mid-side nodes on the straight
//! facet edges; ccx expands them to C3D15 solids, shear-deformable), the same pinned supports
//! (mid-side nodes of supported edges pinned too) and self-weight, against Kappe's CST+DKT and
//! ANDES+DKMT on the same mesh.
//!
//! `cargo run --release -p kappe --example ccx_state -- STATE [STATE …]`; `SPLIT=n` in the
//! environment meshes the state's shell split n×n (`kappe_fe::refine::split`, the same flat
//! facets) for both codes (docs/convergence.md records the numbers).
//! (`KAPPE_DESIGN=file.toml` checks that design instead of the default, e.g. a corrugated cap).

use std::collections::HashMap;
use std::path::Path;

use kappe::analysis::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::build_state;
use kappe_fe::{BucklingOptions, ElementKind, ShellModel, ccx};

fn deck(m: &ShellModel, scale: f64) -> String {
    let mut s = String::from("*HEADING\nstate\n");
    let mut nodes = m.nodes.clone();
    let fixed = m.fixed_mask();
    let mut pinned: Vec<bool> = fixed.iter().map(|f| f[0]).collect();
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut elems = Vec::new();
    for t in &m.triangles {
        let mut e = vec![t[0], t[1], t[2]];
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let key = (a.min(b), a.max(b));
            let id = *mid.entry(key).or_insert_with(|| {
                let (p, q) = (nodes[a], nodes[b]);
                nodes.push([
                    0.5 * (p[0] + q[0]),
                    0.5 * (p[1] + q[1]),
                    0.5 * (p[2] + q[2]),
                ]);
                pinned.push(pinned[a] && pinned[b]);
                nodes.len() - 1
            });
            e.push(id);
        }
        elems.push(e);
    }
    ccx::write_nodes(&mut s, &nodes);
    ccx::write_elements(
        &mut s,
        "S6",
        elems.iter().map(|e| e.iter().map(|n| n + 1).collect()),
    );
    ccx::write_supports(
        &mut s,
        (0..nodes.len()).filter(|&n| pinned[n]).map(|n| n + 1),
    );
    let step = ccx::BuckleStep::of(m, 2);
    ccx::write_buckle_step(&mut s, &step, scale);
    s
}

/// ccx's λ₁ of the state with the load scaled by `scale`, and its wall time.
fn ccx_run(
    dir: &Path,
    m: &ShellModel,
    scale: f64,
) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let (wall, f, _) = ccx::run(dir, "state", &deck(m, scale), scale)?;
    Ok((f.first().copied().unwrap_or(f64::NAN), wall))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let design = match std::env::var_os("KAPPE_DESIGN") {
        Some(path) => kappe::Design::from_toml_str(&std::fs::read_to_string(path)?)?,
        None => kappe::Design::default(),
    };
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let options = AnalysisOptions::default();
    let dir = Path::new("target/ccx_state");
    std::fs::create_dir_all(dir)?;
    println!(
        "| state | shell nodes | CST+DKT | ANDES+DKMT | ccx S6 | DKT vs S6 | DKMT vs S6 | ccx s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for arg in std::env::args().skip(1) {
        let top: usize = arg.parse()?;
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
                Some(&kappe::analysis::CapGreen::new(&cap).unwrap()),
            ),
            1,
        )
        .map_err(|e| format!("{e:?}"))?;
        let n_split: usize = std::env::var("SPLIT")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1);
        shell.model = kappe_fe::refine::split(&shell.model, n_split).model;
        let mut l = [0.0; 2];
        for (k, el) in [ElementKind::CstDkt, ElementKind::AndesDkmt]
            .into_iter()
            .enumerate()
        {
            let mut m = shell.model.clone();
            m.element = el;
            l[k] = kappe_fe::buckling(
                &m,
                &BucklingOptions {
                    modes: 1,
                    ..Default::default()
                },
            )?
            .factors[0];
        }
        let (a, _) = ccx_run(dir, &shell.model, l[1] / 2.0)?;
        let (b, secs) = ccx_run(dir, &shell.model, a / 2.0)?;
        println!(
            "| {top} | {} | {:.4} | {:.4} | {b:.4} | {:+.2} % | {:+.2} % | {secs:.1} |",
            shell.model.nodes.len(),
            l[0],
            l[1],
            100.0 * (l[0] / b - 1.0),
            100.0 * (l[1] / b - 1.0)
        );
    }
    Ok(())
}
