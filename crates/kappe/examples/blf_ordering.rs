//! Ordering reuse across nested print states (issue 25 item 1, docs/convergence.md "The
//! `speed5` branch"): each state's print-layer mesh is the final state's mesh less its later
//! rows, so the final state's elimination order restricted to a state's nodes is an ordering of
//! that state (`kappe_fe::BucklingSolver::with_node_order`) with no AMD of its own. Per state:
//! the solve with its own AMD ordering and with the final state's order restricted, each with
//! the factor's entries, the seconds of each phase (`kappe_fe::SolveStats`) and λ₁.
//!
//! `cargo run --release -p kappe --example blf_ordering -- KIND LENGTH STATE…`
//! (KIND `smooth` or `corrugated`, as `blf_coarse`).

#[path = "common/caps.rs"]
mod caps;

use std::collections::HashMap;
use std::time::Instant;

use kappe::analysis::{AnalysisOptions, state_material, state_shell};
use kappe_fe::{BucklingOptions, BucklingSolver};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(kind), Some(length)) = (args.first(), args.get(1)) else {
        return Err("usage: blf_ordering KIND LENGTH STATE…".into());
    };
    let cap = caps::cap_of(kind, length)?;
    let options = AnalysisOptions::default();
    let green = kappe::analysis::CapGreen::new(&cap)?;
    let shell = |top: usize| -> Result<kappe::analysis::StateShell, String> {
        let state = cap.state(top).map_err(|e| e.to_string())?;
        state_shell(
            &state,
            &state_material(&cap, &options, top, Some(&green)),
            1,
        )
        .map_err(|e| format!("{e:?}"))
    };
    // The analysis's own eigen-solver settings (residual 1e-5, one mode, cold start).
    let opts = BucklingOptions {
        modes: 1,
        tolerance: 1e-5,
        sturm_check: false,
        ..Default::default()
    };
    let last = cap.states.len() - 1;
    let t = Instant::now();
    let final_shell = shell(last)?;
    let final_order = BucklingSolver::new(&final_shell.model)?.node_order();
    // A shell node is (layer id, place in its row foot → foot): the same in every state.
    let mut rank: HashMap<(i32, usize), usize> = HashMap::new();
    for (id, row) in &final_shell.rows {
        for (j, &n) in row.iter().enumerate() {
            rank.insert((*id, j), final_order[n]);
        }
    }
    println!(
        "{kind} cap, length {length} m, final state {last}: its order in {:.3} s",
        t.elapsed().as_secs_f64()
    );
    println!(
        "| state | ordering | free DOFs | nnz L | symbolic s | LLᵀ + static s | Lanczos s | solve s | λ₁ |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    if args.get(2).map(String::as_str) == Some("all") {
        // Every state once per ordering (cold start, one thread), alternating which goes first:
        // the sums are the first pass's share an ordering reuse could change.
        let (mut sum, mut nnz) = ([0.0f64; 2], [0usize; 2]);
        let mut worst = 0.0f64;
        for top in 1..=last {
            let Ok(sh) = shell(top) else { continue };
            let mut node_rank = vec![usize::MAX; sh.model.nodes.len()];
            for (id, row) in &sh.rows {
                for (j, &n) in row.iter().enumerate() {
                    node_rank[n] = rank.get(&(*id, j)).copied().unwrap_or(usize::MAX);
                }
            }
            let mut lambda = [0.0; 2];
            for k in [top % 2, 1 - top % 2] {
                let t = Instant::now();
                let solver = if k == 1 {
                    BucklingSolver::with_node_order(&sh.model, &node_rank)?
                } else {
                    BucklingSolver::new(&sh.model)?
                };
                let r = solver.buckling(&sh.model, &opts)?;
                sum[k] += t.elapsed().as_secs_f64();
                nnz[k] += r.stats.nnz_l;
                lambda[k] = r.factors.first().copied().unwrap_or(f64::NAN);
            }
            worst = worst.max(((lambda[1] - lambda[0]) / lambda[0]).abs());
        }
        println!(
            "states 1…{last}: own AMD {:.3} s, Σ nnz L {}; final state's restricted {:.3} s, Σ nnz L {} ({:+.1} %); largest |Δλ₁|/λ₁ {worst:.1e}",
            sum[0],
            nnz[0],
            sum[1],
            nnz[1],
            100.0 * (nnz[1] as f64 / nnz[0] as f64 - 1.0)
        );
        return Ok(());
    }
    for a in args.iter().skip(2) {
        let top: usize = a.parse()?;
        let sh = shell(top)?;
        let mut node_rank = vec![usize::MAX; sh.model.nodes.len()];
        for (id, row) in &sh.rows {
            for (j, &n) in row.iter().enumerate() {
                node_rank[n] = rank.get(&(*id, j)).copied().unwrap_or(usize::MAX);
            }
        }
        // State top − d's own order, the d newer rows appended (row by row): the reuse a warm
        // run of consecutive states could make.
        let earlier = |d: usize| -> Result<Vec<usize>, Box<dyn std::error::Error>> {
            let base = shell(top.saturating_sub(d))?;
            let order = BucklingSolver::new(&base.model)?.node_order();
            let mut known: HashMap<(i32, usize), usize> = HashMap::new();
            for (id, row) in &base.rows {
                for (j, &n) in row.iter().enumerate() {
                    known.insert((*id, j), order[n]);
                }
            }
            let after = base.model.nodes.len() * 6;
            let mut r = vec![usize::MAX; sh.model.nodes.len()];
            for (q, (id, row)) in sh.rows.iter().enumerate() {
                for (j, &n) in row.iter().enumerate() {
                    r[n] = known
                        .get(&(*id, j))
                        .copied()
                        .unwrap_or(after + 1000 * q + j);
                }
            }
            Ok(r)
        };
        let prev1 = earlier(1)?;
        let prev8 = earlier(8)?;
        for (what, reuse) in [
            ("own AMD", None),
            ("final state's, restricted", Some(&node_rank)),
            ("state − 1's + 1 row", Some(&prev1)),
            ("state − 8's + 8 rows", Some(&prev8)),
        ] {
            let t = Instant::now();
            let solver = match reuse {
                Some(r) => BucklingSolver::with_node_order(&sh.model, r)?,
                None => BucklingSolver::new(&sh.model)?,
            };
            let t_sym = t.elapsed().as_secs_f64();
            let r = solver.buckling(&sh.model, &opts)?;
            let s = &r.stats;
            println!(
                "| {top} | {what} | {} | {} | {t_sym:.4} | {:.4} | {:.4} | {:.4} | {:.9} |",
                s.n_free_dofs,
                s.nnz_l,
                s.t_factor,
                s.t_eigen,
                t.elapsed().as_secs_f64(),
                r.factors.first().copied().unwrap_or(f64::NAN),
            );
        }
    }
    Ok(())
}
