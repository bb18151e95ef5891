//! Mode-1 amplitude per row of a state's shell (issue 15: is the buckling mode local to the
//! newest layers?). `cargo run --release -p kappe --example mode_profile -- LENGTH STATE`
use kappe::analysis::state_shell;
use kappe::analysis::{AnalysisOptions, state_material};
use kappe::form::build_state;
use kappe::{Design, design_cap};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let length: f64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(0.6);
    let mut d = Design::default();
    d.cap.length = length;
    if std::env::var("KAPPE_END").is_ok_and(|e| e == "end_wall") {
        d.cap.end = kappe::form::EndKind::EndWall;
    }
    let cap = design_cap(&d, kappe::Context::default()).expect("design");
    let total = cap.states.len();
    let top: usize = args
        .get(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(total - 1);
    let opts = AnalysisOptions::default();
    let st = build_state(&cap.sections, &cap.frame, 0.0, top).unwrap();
    let shell = state_shell(
        &st,
        &state_material(
            &cap,
            &opts,
            top,
            Some(&kappe::analysis::CapGreen::new(&cap).unwrap()),
        ),
        1,
    )
    .unwrap();
    let r = kappe_fe::buckling(
        &shell.model,
        &kappe_fe::BucklingOptions {
            modes: 3,
            tolerance: 1e-8,
            ..Default::default()
        },
    )
    .unwrap();
    println!("state {top}: factors {:?}", r.factors);
    for (k, m) in r.modes.iter().enumerate() {
        let amp = |i: usize| {
            let d = m[i];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        };
        let rows: Vec<f64> = shell
            .rows
            .iter()
            .map(|(_, r)| r.iter().map(|&i| amp(i)).fold(0.0, f64::max))
            .collect();
        let peak = rows.iter().copied().fold(0.0, f64::max);
        let line: Vec<String> = rows
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 5 == 0 || *i + 1 == rows.len())
            .map(|(i, a)| format!("{}:{:.2}", shell.rows[i].0, a / peak))
            .collect();
        println!("mode {k}: {}", line.join(" "));
    }
}
