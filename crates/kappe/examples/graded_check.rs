//! Graded shell meshes against the full analysis, state by state (issue 15, `kappe::window`).
//!
//! `cargo run --release -p kappe --example graded_check -- LENGTH FINE:MAX_STRIDE ...`
//! (e.g. `0.6 16:8 16:32`): per grading, the largest relative BLF difference over every state,
//! the governing state and BLF, and the FE wall time, against the full mesh. `KAPPE_END=end_wall`
//! for an end-wall cap.

use std::time::Instant;

use kappe::analysis::{AnalysisOptions, state_buckling, state_material};
use kappe::states::build_state;
use kappe::window::{Grading, graded_state};
use kappe::{Design, design_cap};
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let length: f64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(0.6);
    let gradings: Vec<Grading> = args
        .iter()
        .skip(1)
        .filter_map(|a| {
            let (f, s) = a.split_once(':')?;
            Some(Grading {
                fine: f.parse().ok()?,
                max_stride: s.parse().ok()?,
            })
        })
        .collect();
    let mut d = Design::default();
    d.cap.length = length;
    if std::env::var("KAPPE_END").is_ok_and(|e| e == "end_wall") {
        d.cap.end = kappe::ends::EndKind::EndWall;
    }
    let cap = design_cap(&d, &|_| {}).expect("design");
    let opts = AnalysisOptions::default();
    let total = cap.states.len();
    let blf = |g: Option<&Grading>| -> (Vec<Option<f64>>, f64) {
        let t0 = Instant::now();
        let v = (0..total)
            .into_par_iter()
            .rev()
            .map(|top| {
                let st = build_state(&cap.sections, &cap.frame, 0.0, top).unwrap();
                let st = match g {
                    Some(g) => graded_state(&st, g),
                    None => st,
                };
                let m = state_material(&cap, &opts, top);
                state_buckling(&st, &m, &opts)
                    .unwrap()
                    .factors
                    .first()
                    .copied()
            })
            .collect::<Vec<_>>();
        let mut v = v;
        v.reverse();
        (v, t0.elapsed().as_secs_f64())
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
        blf(None)
    };
    println!(
        "length {length} m, end {:?}, {total} states; full mesh: FE {t_full:.2} s, governing {:?}",
        d.cap.end,
        argmin(&full)
    );
    println!("| fine:max_stride | max rel BLF diff | at state | governing (state, BLF) | FE s |");
    println!("|---|---|---|---|---|");
    for g in &gradings {
        let (v, t) = blf(Some(g));
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
            "| {}:{} | {:.3e} | {} | {:?} | {t:.2} |",
            g.fine,
            g.max_stride,
            worst.0,
            worst.1,
            argmin(&v)
        );
    }
}
