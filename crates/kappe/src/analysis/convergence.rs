//! The converged buckling factor of every print state at the lowest cost (issues 23 and 25;
//! docs/convergence.md).
//!
//! Every state's factor is solved on its print-layer shell mesh (λ_c). The mesh error is then
//! controlled with the mesh's 2×2 split (λ_f, `kappe_fe::refine::split`, the same flat facets)
//! and Richardson extrapolation at order 1 (`kappe_fe::convergence`): the reported factor
//! λ̂ = 2λ_f − λ_c lies on the safe side of the converged value, which lies in
//! [λ̂, λ̂·(1 + error)].
//!
//! **What is sampled.** The split mesh has four times the DOFs, so its solve costs about eight
//! coarse ones. Consecutive states differ by one row, and the *ratio* c = λ_f/λ_c (the mesh
//! correction, not the factor) changes smoothly from state to state once the shell is more than
//! a narrow strip: on the default cap linear interpolation of c over 4 states is off by less than
//! 0.005 % from state 60 on, while the start section's first 40 states jump by up to 0.7 %.
//! So the split is solved on a sample of states chosen adaptively, by bisection along the
//! print sequence ([`sample`]): the midpoint of an interval is solved, then its quarter points;
//! if their ratios agree with the quadratic through the ends and the midpoint to within
//! `tolerance/10`, the interval's other states are interpolated on that quadratic, otherwise
//! both halves are bisected, until every state is either solved or inside an accepted interval
//! (intervals under 4 states: the midpoint against the straight line). Probing the midpoint
//! alone missed single-state jumps of the start section. An
//! interpolated state's factor is still its own mesh's factor, corrected by the interpolated
//! ratio; its bracket is widened by twice the midpoint disagreement on both sides, and its
//! reported value moved down by the same amount (the safe side).
//!
//! **The governing states are always solved.** After the sampling, every state whose safe value
//! is not above the smallest upper bracket end (so it could govern) is solved on the split mesh
//! if it was interpolated, and refined further (4×4, up to `blf_max_split`) while its error
//! estimate exceeds `blf_tolerance`. A state left interpolated or unconverged therefore cannot
//! govern the verdict.

use kappe_fe::{ConvergedFactor, MeshLevel};

/// The interpolation test of [`sample`]: the midpoint's ratio within this share of the
/// tolerance of the interpolated one.
pub const SAMPLE_SHARE: f64 = 1.0 / 10.0;

/// Initial spacing of the samples (states), before bisection.
pub const SAMPLE_STRIDE: usize = 32;

/// Solves the split mesh of a batch of states: (state, converged estimate) per state.
pub type SplitSolve<'a, E> = dyn FnMut(&[usize]) -> Result<Vec<(usize, ConvergedFactor)>, E> + 'a;

/// Adaptive sampling of the mesh-correction ratio over the states `coarse` (in print order:
/// state index, its print-layer mesh factor). `solve(batch)` solves the split mesh of every
/// state in `batch` (in parallel) and returns, per state, its converged estimate (levels 1×1
/// and 2×2). Returns a converged estimate for every state of `coarse`, and whether it was
/// solved (`true`) or interpolated. `sampling` false: every state is solved.
pub fn sample<E>(
    coarse: &[(usize, f64)],
    tolerance: f64,
    sampling: bool,
    solve: &mut SplitSolve<'_, E>,
) -> Result<Vec<(usize, ConvergedFactor, bool)>, E> {
    let n = coarse.len();
    let mut solved: Vec<Option<ConvergedFactor>> = vec![None; n];
    // Per position: the accepted interval (a, b) it is interpolated in and the error bound.
    let mut accepted: Vec<Option<(usize, usize, f64)>> = vec![None; n];
    let ratio = |c: &ConvergedFactor| {
        let l = &c.levels;
        l.get(1).map_or(1.0, |f| f.factor) / l[0].factor
    };
    let mut run =
        |positions: Vec<usize>, solved: &mut Vec<Option<ConvergedFactor>>| -> Result<(), E> {
            let mut todo: Vec<usize> = positions
                .into_iter()
                .filter(|&p| solved[p].is_none())
                .collect();
            todo.sort_unstable();
            todo.dedup();
            if todo.is_empty() {
                return Ok(());
            }
            let states: Vec<usize> = todo.iter().map(|&p| coarse[p].0).collect();
            for (state, c) in solve(&states)? {
                if let Some(p) = todo.iter().copied().find(|&p| coarse[p].0 == state) {
                    solved[p] = Some(c);
                }
            }
            Ok(())
        };
    if n == 0 {
        return Ok(Vec::new());
    }
    // Without sampling every state is a sample.
    let stride = if sampling { SAMPLE_STRIDE } else { 1 };
    let mut first: Vec<usize> = (0..n).step_by(stride).collect();
    first.push(n - 1);
    first.dedup();
    run(first.clone(), &mut solved)?;
    // (a, b, quarters): the midpoint is probed first, then (intervals of 4 or more) the quarter
    // points, against the quadratic through the ends and the midpoint.
    let mut intervals: Vec<(usize, usize, bool)> =
        first.windows(2).map(|w| (w[0], w[1], false)).collect();
    let tau = tolerance * SAMPLE_SHARE;
    while !intervals.is_empty() {
        let todo: Vec<usize> = intervals
            .iter()
            .filter(|(a, b, _)| b - a >= 2)
            .flat_map(|&(a, b, quarters)| {
                let m = (a + b) / 2;
                if quarters {
                    vec![(a + m) / 2, (m + b) / 2]
                } else {
                    vec![m]
                }
            })
            .collect();
        run(todo, &mut solved)?;
        let mut next = Vec::new();
        for (a, b, quarters) in intervals {
            if b - a < 2 {
                continue;
            }
            let m = (a + b) / 2;
            let r = |p: usize| solved[p].as_ref().map(&ratio);
            // The worst disagreement of the probes with the interpolation of the others (a
            // solve without a factor counts as a disagreement).
            let e = if quarters {
                [(a + m) / 2, (m + b) / 2]
                    .into_iter()
                    .map(|p| Some((interp(a, m, b, r(a)?, r(m)?, r(b)?, p) - r(p)?).abs()))
                    .try_fold(0.0_f64, |acc, x| x.map(|x| acc.max(x)))
            } else {
                (|| Some((interp(a, a, b, r(a)?, r(a)?, r(b)?, m) - r(m)?).abs()))()
            };
            match e {
                Some(e) if e <= tau && (quarters || b - a < 4) => {
                    for slot in accepted.iter_mut().take(b).skip(a + 1) {
                        *slot = Some((a, b, e));
                    }
                }
                Some(_) if !quarters && b - a >= 4 => next.push((a, b, true)),
                _ => {
                    next.push((a, m, false));
                    next.push((m, b, false));
                }
            }
        }
        intervals = next;
    }
    let mut out = Vec::with_capacity(n);
    for p in 0..n {
        if let Some(c) = &solved[p] {
            out.push((coarse[p].0, c.clone(), true));
            continue;
        }
        let Some((a, b, e)) = accepted[p] else {
            continue;
        };
        let m = (a + b) / 2;
        let r = |q: usize| solved[q].as_ref().map(&ratio);
        let (Some(ra), Some(rm), Some(rb)) = (r(a), r(m), r(b)) else {
            continue;
        };
        // Quadratic through the ends and the midpoint where the quarters were checked against
        // it, linear (a short interval) otherwise; `e` bounds the disagreement either way.
        let rp = if b - a >= 4 {
            interp(a, m, b, ra, rm, rb, p)
        } else {
            interp(a, a, b, ra, ra, rb, p)
        };
        out.push((
            coarse[p].0,
            interpolated(coarse[p].1, rp, e.max(f64::EPSILON), tolerance),
            false,
        ));
    }
    Ok(out)
}

/// The value at `p` of the quadratic through (a, ra), (m, rm), (b, rb); linear through the ends
/// when `m == a`.
fn interp(a: usize, m: usize, b: usize, ra: f64, rm: f64, rb: f64, p: usize) -> f64 {
    let (a, m, b, p) = (a as f64, m as f64, b as f64, p as f64);
    if m == a || m == b {
        return ra + (p - a) / (b - a) * (rb - ra);
    }
    ra * (p - m) * (p - b) / ((a - m) * (a - b))
        + rm * (p - a) * (p - b) / ((m - a) * (m - b))
        + rb * (p - a) * (p - m) / ((b - a) * (b - m))
}

/// The converged estimate of a state whose split factor is `ratio`·`coarse` to within `e`
/// (relative): the bracket of the pair, widened by 2e·λ_c on both sides (Richardson doubles the
/// correction), the reported value at its lower end.
pub fn interpolated(coarse: f64, ratio: f64, e: f64, tolerance: f64) -> ConvergedFactor {
    let level = |split: usize, factor: f64| MeshLevel {
        split,
        factor,
        n_free_dofs: 0,
        steps: 0,
    };
    let pair = vec![level(1, coarse), level(2, ratio * coarse)];
    let mut c = ConvergedFactor::from_pair(pair, tolerance).unwrap_or(ConvergedFactor {
        levels: Vec::new(),
        extrapolated: coarse,
        upper: coarse,
        error: 0.0,
        converged: true,
    });
    let widen = 2.0 * e * coarse;
    c.extrapolated -= widen;
    c.upper += widen;
    c.error = if c.extrapolated > 0.0 {
        (c.upper - c.extrapolated) / c.extrapolated
    } else {
        f64::INFINITY
    };
    c.converged = c.error <= tolerance;
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exact(coarse: f64, r: f64) -> ConvergedFactor {
        ConvergedFactor::from_pair(
            vec![
                MeshLevel {
                    split: 1,
                    factor: coarse,
                    n_free_dofs: 0,
                    steps: 0,
                },
                MeshLevel {
                    split: 2,
                    factor: r * coarse,
                    n_free_dofs: 0,
                    steps: 0,
                },
            ],
            0.005,
        )
        .unwrap()
    }

    /// A smooth ratio is sampled sparsely and interpolated within the widened bracket; a jump
    /// is found by bisection and every state around it solved.
    #[test]
    fn smooth_ratios_are_interpolated_and_jumps_are_solved() {
        let n = 100;
        let coarse: Vec<(usize, f64)> = (0..n).map(|i| (i, 10.0 - 0.05 * i as f64)).collect();
        let ratio = |i: usize| {
            let smooth = 0.99 + 1e-4 * i as f64;
            if i >= 61 { smooth - 0.01 } else { smooth }
        };
        let mut calls = 0usize;
        let mut solve = |batch: &[usize]| -> Result<Vec<(usize, ConvergedFactor)>, ()> {
            calls += batch.len();
            Ok(batch
                .iter()
                .map(|&i| (i, exact(coarse[i].1, ratio(i))))
                .collect())
        };
        let out = sample(&coarse, 0.005, true, &mut solve).unwrap();
        assert_eq!(out.len(), n);
        assert!(calls < n / 2, "{calls} solves");
        for (i, c, solved) in &out {
            let truth = exact(coarse[*i].1, ratio(*i));
            assert!(c.extrapolated <= truth.extrapolated + 1e-12, "state {i}");
            assert!(c.upper >= truth.upper - 1e-12, "state {i}");
            if (60..=62).contains(i) {
                assert!(*solved, "state {i} next to the jump is solved");
            }
        }
    }
}
