//! scratch: BLF of states on n×n splits
use kappe::analysis::shell::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::states::build_state;
use kappe_fe::{BucklingOptions, ElementKind};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut design = kappe::Design::default();
    if let Ok(l) = std::env::var("LEN") { design.cap.length = l.parse()?; }
    let cap = kappe::design_cap(&design, &|_| {})?;
    let options = AnalysisOptions::default();
    let el = std::env::var("EL").ok().and_then(|e| ElementKind::from_name(&e)).unwrap_or(ElementKind::AndesDkmt);
    let maxn: usize = std::env::var("MAXN").ok().and_then(|s| s.parse().ok()).unwrap_or(4);
    for a in &args {
        let top: usize = a.parse()?;
        let state = build_state(&cap.sections, &cap.frame, design.print.start_arch_fraction, top)?;
        let mut shell = state_shell(&state, &state_material(&cap, &options, top).unwrap(), 1).map_err(|e| format!("{e:?}"))?;
        shell.model.element = el;
        let mut prev = None;
        for n in 1..=maxn {
            if n == 3 && maxn > 4 { continue; }
            let m = kappe_fe::refine::split(&shell.model, n).model;
            let t = Instant::now();
            let r = kappe_fe::buckling(&m, &BucklingOptions { modes: 2, tolerance: 1e-9, sturm_check: false, ..Default::default() })?;
            let l = r.factors[0];
            println!("state {top} n {n} nodes {} dofs {} blf {:.5} l2 {:.5} t {:.3} steps {} fac {:.3} eig {:.3} d {:?}", m.nodes.len(), r.stats.n_free_dofs, l, r.factors.get(1).copied().unwrap_or(0.0), t.elapsed().as_secs_f64(), r.stats.operator_applications, r.stats.t_factor, r.stats.t_eigen, prev.map(|p: f64| l - p));
            prev = Some(l);
        }
    }
    Ok(())
}
