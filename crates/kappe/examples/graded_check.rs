//! Graded shell meshes against the full analysis, state by state (issue 15, `kappe::analysis::graded`).
//!
//! `cargo run --release -p kappe --example graded_check -- LENGTH [FINE:MAX_STRIDE[:ZONE_ROWS[:TRANSVERSE[:START_STRIDE]]]] ...`
//! (e.g. `1.2 32:32:8:4:1`; fields left out take the default grading's values; no grading given:
//! the default one): per grading, the largest relative
//! BLF difference over the checked states, the governing state and BLF, and the buckling wall
//! time (`kappe::analysis::analyze`, so the graded runs are warm-started as in `kappe design`),
//! against the full mesh. Environment: `KAPPE_END=end_wall` for an end-wall cap,
//! `KAPPE_STATES=every:N` to check every N-th state only (long caps), `KAPPE_NO_FULL=1` to time
//! the gradings alone.

use kappe::analysis::Grading;
use kappe::analysis::{AnalysisOptions, StateSelection, analyze};
use kappe::{Design, design_cap};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let length: f64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(0.6);
    let mut gradings: Vec<Grading> = args
        .iter()
        .skip(1)
        .filter_map(|a| {
            let v: Vec<usize> = a.split(':').filter_map(|x| x.parse().ok()).collect();
            let d = Grading::default();
            Some(Grading {
                fine: *v.first()?,
                max_stride: *v.get(1)?,
                zone_rows: v.get(2).copied().unwrap_or(d.zone_rows),
                transverse: v.get(3).copied().unwrap_or(d.transverse),
                start_stride: v.get(4).copied().unwrap_or(d.start_stride),
                ..d
            })
        })
        .collect();
    if gradings.is_empty() {
        gradings.push(Grading::default());
    }
    let mut d = Design::default();
    d.cap.length = length;
    if std::env::var("KAPPE_END").is_ok_and(|e| e == "end_wall") {
        d.cap.end = kappe::form::EndKind::EndWall;
    }
    let states: StateSelection = std::env::var("KAPPE_STATES")
        .ok()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or_default();
    let cap = design_cap(&d, kappe::Context::default())?;
    let total = cap.states.len();
    let run = |grading: Option<Grading>| -> Result<(Vec<Option<f64>>, f64), String> {
        let o = AnalysisOptions {
            states,
            grading,
            ..AnalysisOptions::default()
        };
        let a =
            analyze(&cap, &o, kappe::analysis::Request::default()).map_err(|e| e.to_string())?;
        Ok((a.states.iter().map(|s| s.blf).collect(), a.timings.fe))
    };
    let argmin = |v: &[Option<f64>]| {
        v.iter()
            .enumerate()
            .filter_map(|(i, b)| b.map(|b| (i, b)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    };
    let (full, t_full) = if std::env::var("KAPPE_NO_FULL").is_ok() {
        (vec![None; total], 0.0)
    } else {
        run(None)?
    };
    println!(
        "length {length} m, end {:?}, {total} states, states {states}; full mesh: FE {t_full:.2} s, governing {:?}",
        d.cap.end,
        argmin(&full)
    );
    println!(
        "| fine:max_stride:zone_rows:transverse:start_stride | max rel BLF diff | at state | governing (state, BLF) | FE s |"
    );
    println!("|---|---|---|---|---|");
    for g in &gradings {
        let (v, t) = run(Some(*g))?;
        let mut worst = (0.0_f64, 0usize);
        for (i, (a, b)) in full.iter().zip(&v).enumerate() {
            if let (Some(a), Some(b)) = (a, b) {
                let r = (b - a).abs() / a.abs();
                if r > worst.0 {
                    worst = (r, i);
                }
            }
        }
        println!(
            "| {}:{}:{}:{}:{} | {:.3e} | {} | {:?} | {t:.2} |",
            g.fine,
            g.max_stride,
            g.zone_rows,
            g.transverse,
            g.start_stride,
            worst.0,
            worst.1,
            argmin(&v)
        );
    }
    Ok(())
}
