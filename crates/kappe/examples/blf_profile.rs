//! scratch: profile converge_factor phases on states
use kappe::analysis::shell::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::states::build_state;
use kappe_fe::{BucklingOptions, ElementKind};
use std::time::Instant;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let design = kappe::Design::default();
    let cap = kappe::design_cap(&design, &|_| {})?;
    let options = AnalysisOptions::default();
    for a in std::env::args().skip(1) {
        let top: usize = a.parse()?;
        let state = build_state(&cap.sections, &cap.frame, design.print.start_arch_fraction, top)?;
        let mut sh = state_shell(&state, &state_material(&cap, &options, top).unwrap(), 1).map_err(|e| format!("{e:?}"))?;
        sh.model.element = ElementKind::AndesDkmt;
        let o = BucklingOptions { modes: 1, tolerance: 1e-6, sturm_check: false, ..Default::default() };
        let t = Instant::now();
        let r = kappe_fe::buckling(&sh.model, &o)?;
        let tc = t.elapsed().as_secs_f64();
        let s = r.stats;
        println!("state {top} coarse {tc:.3}s dofs {} sym {:.3} asm {:.3} fac {:.3} geo {:.3} eig {:.3} steps {}", s.n_free_dofs, s.t_symbolic, s.t_assembly, s.t_factor, s.t_geometric, s.t_eigen, s.operator_applications);
        let t = Instant::now();
        let rf = kappe_fe::refine::split(&sh.model, 2);
        let tsplit = t.elapsed().as_secs_f64();
        let start = rf.prolong(&r.modes[0]);
        for st in [None, Some(start)] {
            let t = Instant::now();
            let warm = st.is_some();
            let r2 = kappe_fe::buckling(&rf.model, &BucklingOptions { start: st, ..o.clone() })?;
            let s = r2.stats;
            println!("   fine warm {warm} {:.3}s (split {tsplit:.3}) dofs {} sym {:.3} asm {:.3} fac {:.3} geo {:.3} eig {:.3} steps {} blf {:.6}", t.elapsed().as_secs_f64(), s.n_free_dofs, s.t_symbolic, s.t_assembly, s.t_factor, s.t_geometric, s.t_eigen, s.operator_applications, r2.factors[0]);
        }
    }
    Ok(())
}
