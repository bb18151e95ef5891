//! scratch: boundary-layer refinement
use kappe::analysis::shell::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::states::build_state;
use kappe_fe::{BucklingOptions, ElementKind, ShellModel};
use std::time::Instant;
use std::collections::HashMap;

fn blf(m: &ShellModel) -> (f64, f64, usize) {
    let t = Instant::now();
    let r = kappe_fe::buckling(m, &BucklingOptions { modes: 1, tolerance: 1e-9, sturm_check: false, ..Default::default() }).unwrap();
    (r.factors[0], t.elapsed().as_secs_f64(), r.stats.n_free_dofs)
}

fn boundary_nodes(m: &ShellModel, supports: bool, free: bool) -> Vec<bool> {
    let mut cnt: HashMap<(usize,usize), usize> = HashMap::new();
    for t in &m.triangles { for (a,b) in [(t[0],t[1]),(t[1],t[2]),(t[2],t[0])] { *cnt.entry((a.min(b),a.max(b))).or_default() += 1; } }
    let fixed = m.fixed_mask();
    let mut on = vec![false; m.nodes.len()];
    for ((a,b),c) in cnt { if c == 1 {
        let sa = fixed[a][0] && fixed[b][0];
        if (sa && supports) || (!sa && free) { on[a] = true; on[b] = true; }
    } }
    on
}

fn band(m: &ShellModel, seed: &[bool], layers: usize) -> Vec<bool> {
    let mut near = seed.to_vec();
    for _ in 1..layers {
        let mut next = near.clone();
        for t in &m.triangles { if t.iter().any(|&n| near[n]) { for &n in t { next[n] = true; } } }
        near = next;
    }
    m.triangles.iter().map(|t| t.iter().any(|&n| near[n])).collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut design = kappe::Design::default();
    if let Ok(l) = std::env::var("LEN") { design.cap.length = l.parse()?; }
    let cap = kappe::design_cap(&design, &|_| {})?;
    let options = AnalysisOptions::default();
    for a in &args {
        let top: usize = a.parse()?;
        let state = build_state(&cap.sections, &cap.frame, design.print.start_arch_fraction, top)?;
        let mut shell = state_shell(&state, &state_material(&cap, &options, top).unwrap(), 1).map_err(|e| format!("{e:?}"))?;
        shell.model.element = ElementKind::AndesDkmt;
        let m0 = shell.model.clone();
        let (l1, t1, d1) = blf(&m0);
        println!("state {top}: base {l1:.5} ({d1} dofs {t1:.2}s)");
        for (sup, free, name) in [(true, true, "all"), (true, false, "supports"), (false, true, "free")] {
          for width in [1usize, 2] {
            let mut m = m0.clone();
            for lvl in 1..=3 {
                let seed = boundary_nodes(&m, sup, free);
                let mk = band(&m, &seed, width);
                m = kappe_fe::refine::red_green(&m, &mk).model;
                let (l, t, d) = blf(&m);
                println!("  {name} w{width} lvl {lvl}: blf {l:.5} ({:+.3} % vs base) ({d} dofs {t:.2}s)", 100.0*(l/l1-1.0));
            }
          }
        }
    }
    Ok(())
}
