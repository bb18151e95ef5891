//! Cross-check of a print state's BLF with CalculiX (measuring only; needs `ccx` on PATH,
//! e.g. `apt-get install calculix-ccx`; never used by tests): the state's shell mesh
//! (`state_shell`, row stride 1) as quadratic S6 triangles (mid-side nodes on the straight
//! facet edges; ccx expands them to C3D15 solids, shear-deformable), the same pinned supports
//! (mid-side nodes of supported edges pinned too) and self-weight, against Kappe's CST+DKT and
//! ANDES+DKMT on the same mesh.
//!
//! `cargo run --release -p kappe --example ccx_state -- STATE [STATE …]`

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use kappe::analysis::{AnalysisOptions, state_material};
use kappe::shell::state_shell;
use kappe::states::build_state;
use kappe_fe::{BucklingOptions, ElementKind, ShellModel};

fn deck(m: &ShellModel, scale: f64) -> String {
    let mut s = String::from("*HEADING\nstate\n*NODE\n");
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
    for (i, p) in nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {:.12e}, {:.12e}, {:.12e}", i + 1, p[0], p[1], p[2]);
    }
    s.push_str("*ELEMENT, TYPE=S6, ELSET=EALL\n");
    for (k, e) in elems.iter().enumerate() {
        let ids: Vec<String> = e.iter().map(|n| (n + 1).to_string()).collect();
        let _ = writeln!(s, "{}, {}", k + 1, ids.join(", "));
    }
    s.push_str("*NSET, NSET=SUP\n");
    let sup: Vec<String> = (0..nodes.len())
        .filter(|&n| pinned[n])
        .map(|n| (n + 1).to_string())
        .collect();
    for c in sup.chunks(10) {
        let _ = writeln!(s, "{}", c.join(", "));
    }
    let mat = m.materials[0];
    let g = 9.81;
    let _ = write!(
        s,
        "*BOUNDARY\nSUP, 1, 3\n*MATERIAL, NAME=M\n*ELASTIC\n{:e}, {}\n*DENSITY\n{:e}\n\
         *SHELL SECTION, ELSET=EALL, MATERIAL=M\n{}\n*STEP\n*BUCKLE\n2, 1e-6\n\
         *DLOAD\nEALL, GRAV, {:.8e}, 0., 0., -1.\n*END STEP\n",
        mat.youngs_modulus,
        mat.poisson_ratio,
        mat.unit_weight / g,
        m.thickness[0],
        g * scale
    );
    s
}

fn factors(dat: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(dat).unwrap_or_default();
    let mut out = Vec::new();
    let mut on = false;
    for line in text.lines() {
        if line.contains("B U C K L I N G") {
            on = true;
            continue;
        }
        if on {
            let w: Vec<&str> = line.split_whitespace().collect();
            if let [a, b] = w.as_slice()
                && let (Ok(_), Ok(f)) = (a.parse::<usize>(), b.parse::<f64>())
            {
                out.push(f);
            }
        }
    }
    out
}

fn ccx(dir: &Path, m: &ShellModel, scale: f64) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    std::fs::write(dir.join("state.inp"), deck(m, scale))?;
    let t = Instant::now();
    Command::new("ccx")
        .arg("state")
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "2")
        .stdout(std::process::Stdio::null())
        .status()?;
    let f = factors(&dir.join("state.dat"));
    Ok((
        f.first().map_or(f64::NAN, |x| x * scale),
        t.elapsed().as_secs_f64(),
    ))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let design = kappe::Design::default();
    let cap = kappe::design_cap(&design, &|_| {})?;
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
        let shell = state_shell(&state, &state_material(&cap, &options, top), 1)
            .map_err(|e| format!("{e:?}"))?;
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
        let (a, _) = ccx(dir, &shell.model, l[1] / 2.0)?;
        let (b, secs) = ccx(dir, &shell.model, a / 2.0)?;
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
