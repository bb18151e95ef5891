//! scratch: cost of split-n solves over all states
use kappe::analysis::shell::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::states::build_state;
use kappe_fe::{BucklingOptions, ElementKind};
use std::time::Instant;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args().nth(1).unwrap().parse()?;
    let tol: f64 = std::env::args().nth(2).unwrap().parse()?;
    let design = kappe::Design::default();
    let cap = kappe::design_cap(&design, &|_| {})?;
    let options = AnalysisOptions::default();
    let (mut tf, mut te, mut ta, mut steps, mut tot) = (0.0, 0.0, 0.0, 0, 0.0);
    for top in 1..cap.states.len() {
        let t = Instant::now();
        let state = build_state(&cap.sections, &cap.frame, design.print.start_arch_fraction, top)?;
        let mut sh = state_shell(&state, &state_material(&cap, &options, top).unwrap(), 1).map_err(|e| format!("{e:?}"))?;
        sh.model.element = ElementKind::AndesDkmt;
        let m = kappe_fe::refine::split(&sh.model, n).model;
        let r = kappe_fe::buckling(&m, &BucklingOptions { modes: 1, tolerance: tol, sturm_check: false, ..Default::default() })?;
        tf += r.stats.t_factor; te += r.stats.t_eigen; ta += r.stats.t_assembly + r.stats.t_geometric + r.stats.t_symbolic; steps += r.stats.operator_applications;
        tot += t.elapsed().as_secs_f64();
        if top % 16 == 0 { eprintln!("{top} {:.5}", r.factors[0]); }
    }
    println!("n {n} tol {tol}: total {tot:.2} factor {tf:.2} eigen {te:.2} asm+geo+sym {ta:.2} steps {steps}");
    Ok(())
}
