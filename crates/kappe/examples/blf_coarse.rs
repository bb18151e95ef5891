//! scratch: coarsened meshes 4h, 2h, h
use kappe::analysis::shell::{layer_rows, state_shell};
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::states::{build_state, State, Network};
use kappe_fe::{BucklingOptions, ElementKind, ShellModel};

fn blf(m: &ShellModel) -> f64 {
    kappe_fe::buckling(m, &BucklingOptions { modes: 1, tolerance: 1e-9, sturm_check: false, ..Default::default() }).unwrap().factors[0]
}
fn thinned(len: usize, c: usize) -> Vec<usize> {
    if c <= 1 || len <= 2 { return (0..len).collect(); }
    let m = (len - 1).div_ceil(c).max(1);
    (0..=m).map(|j| (j * (len - 1) + m / 2) / m).collect()
}
fn coarsen(state: &State, c: usize) -> State {
    let rows = layer_rows(&state.network);
    let n = rows.len();
    let mut map = Vec::new();
    for (q, (_, row)) in rows.iter().enumerate() {
        if q % c == 0 || q + 1 == n {
            map.extend(thinned(row.len(), c).into_iter().map(|j| row[j]));
        }
    }
    map.sort_unstable();
    let mut s = state.clone();
    s.network = Network { nodes: map.iter().map(|&i| state.network.nodes[i].clone()).collect(), trails: vec![], deviation_edges: vec![] };
    s
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
        let mat = state_material(&cap, &options, top).unwrap();
        let mut v = vec![];
        for c in [4usize, 2, 1] {
            let s = coarsen(&state, c);
            let mut sh = state_shell(&s, &mat, 1).map_err(|e| format!("{e:?}"))?;
            sh.model.element = ElementKind::AndesDkmt;
            v.push((c, blf(&sh.model), sh.model.nodes.len()));
        }
        let mut sh = state_shell(&state, &mat, 1).map_err(|e| format!("{e:?}"))?;
        sh.model.element = ElementKind::AndesDkmt;
        let l2 = blf(&kappe_fe::refine::split(&sh.model, 2).model);
        println!("state {top}: {:?} split2 {l2:.5}  R(2h,h) {:.5} R(h,h/2) {:.5}", v, 2.0*v[2].1 - v[1].1, 2.0*l2 - v[2].1);
    }
    Ok(())
}
