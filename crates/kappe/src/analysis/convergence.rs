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
//! print sequence ([`sample`]) from initial samples whose spacing doubles ([`SAMPLE_FIRST`]):
//! the midpoint of an interval is solved with its quarter points (in one batch);
//! if their ratios agree with the quadratic through the ends and the midpoint to within
//! `tolerance/10`, the interval's other states are interpolated on that quadratic, otherwise
//! both halves are bisected, until every state is either solved or inside an accepted interval
//! (intervals under 4 states: the midpoint against the straight line). Probing the midpoint
//! alone missed single-state jumps of the start section. An
//! interpolated state's factor is still its own mesh's factor, corrected by the interpolated
//! ratio; its bracket is widened on both sides by 2 × [`SAMPLE_SAFETY`] × the probes'
//! disagreement, and its reported value moved down by the same amount (the safe side).
//!
//! **Spending the budget.** A wider disagreement (up to `tolerance/2`) is still interpolated
//! when the widened bracket keeps every state of
//! the interval within the contract: its `blf_error` within the tolerance, or its safe value
//! above the smallest upper bracket end of the states solved so far, so that it cannot govern.
//! That spares the split where the ratio wobbles but the factor is far from governing: the
//! start section, and the corrugated cap's wave (docs/convergence.md, `speed4`).
//!
//! **The governing states are always solved.** After the sampling, every state whose safe value
//! is not above the smallest upper bracket end (so it could govern) is solved on the split mesh
//! if it was interpolated, and refined further (4×4, up to `blf_max_split`) while its error
//! estimate exceeds `blf_tolerance`. A state left interpolated or unconverged therefore cannot
//! govern the verdict.

use kappe_fe::{ConvergedFactor, MeshLevel};

/// The interpolation test of [`sample`] that accepts an interval whatever its states' brackets:
/// the probes' ratios within this share of the tolerance of the interpolated ones.
pub const SAMPLE_SHARE: f64 = 1.0 / 10.0;

/// The largest probe disagreement (as a share of the tolerance) at which [`sample`] still
/// interpolates an interval whose states' widened brackets meet the contract (each within the
/// tolerance, or provably unable to govern). Beyond it the quadratic is not trusted to describe
/// the states between the probes, whatever the budget: the widening (2e on each side) is a
/// measured disagreement times a safety factor of two, not a bound, and it stays credible only
/// while the ratio is smooth on the scale of the probe spacing.
pub const SAMPLE_SHARE_MAX: f64 = 1.0 / 2.0;

/// The safety factor on the probe disagreement e of an interpolated interval: its states'
/// brackets are widened by 2 × this × e on each side (2: Richardson doubles an error of the
/// ratio). Under the relaxed test (`SAMPLE_SHARE` < e ≤ `SAMPLE_SHARE_MAX`) on the default,
/// corrugated and 1.2 m caps, 1 left interpolated start-section and wave states up to 0.3 %
/// above their value with the split in every state (a foot merge or a mode change between the
/// probes); 2 left none (docs/convergence.md, "Levers on the `speed4` branch"). Since session 14
/// it applies under the strict test too: with the doubling initial spacing a strictly accepted
/// interval of a wobbling ratio left a state 0.002 % above its own pair at 1 (the unit test
/// `a_wobbling_ratio_is_interpolated_only_where_it_cannot_govern`).
pub const SAMPLE_SAFETY: f64 = 2.0;

/// The first sample after the first state, before bisection: the initial samples are the
/// first state, this position, and every doubling of it, and the last state (0, 16, 32, 64,
/// 128, …, n − 1). The ratio changes with the shell's shape, and one more row changes a shell
/// of k rows by about 1/k of itself: a spacing that grows with the position keeps the change
/// per interval about the same, where a fixed stride over-samples the large, smooth and costly
/// late states (docs/convergence.md, "Session 14").
pub const SAMPLE_FIRST: usize = 16;

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
    let first = initial(n, sampling);
    run(first.clone(), &mut solved)?;
    // (a, b): the midpoint is probed and, in an interval of 4 or more, the quarter points with
    // it, tested against the quadratic through the ends and the midpoint (a short interval's
    // midpoint against the straight line). An interval of 4 or more always needs its quarters
    // (the midpoint alone cannot accept it, and its halves' midpoints are the same states), so
    // they are solved in the midpoint's batch: one round fewer per level, the same states.
    let mut intervals: Vec<(usize, usize)> = first.windows(2).map(|w| (w[0], w[1])).collect();
    let tau = tolerance * SAMPLE_SHARE;
    let tau_max = tolerance * SAMPLE_SHARE_MAX;
    while !intervals.is_empty() {
        let todo: Vec<usize> = intervals
            .iter()
            .filter(|(a, b)| b - a >= 2)
            .flat_map(|&(a, b)| {
                let m = (a + b) / 2;
                if b - a >= 4 {
                    vec![(a + m) / 2, m, (m + b) / 2]
                } else {
                    vec![m]
                }
            })
            .collect();
        run(todo, &mut solved)?;
        // The highest the governing state's converged factor can be, from the states solved so
        // far: the final value (over all states) is at most this, so a state whose safe value is
        // above it cannot govern (and `converge_fe` will not solve it again).
        let upper = solved
            .iter()
            .flatten()
            .map(|c| c.upper)
            .fold(f64::INFINITY, f64::min);
        // An interval is interpolated when its probes agree to within `tau` (every state's
        // bracket then stays close to its own pair's), or to within `tau_max` when every state of
        // it, with its bracket widened by `SAMPLE_SAFETY` times that disagreement, is either
        // within the tolerance or above `upper`: the contract (docs/convergence.md) asks the
        // tolerance only of the states that could govern. Returns the half-width of the
        // interpolated ratios' bracket when the interval is accepted.
        let fits = |a: usize, b: usize, e: f64| {
            let widened = SAMPLE_SAFETY * e;
            if e <= tau {
                return Some(widened);
            }
            (e <= tau_max
                && (a + 1..b).all(|p| {
                    estimate(coarse, &solved, a, b, p, widened, tolerance)
                        .is_some_and(|c| c.converged || c.extrapolated > upper)
                }))
            .then_some(widened)
        };
        let mut next = Vec::new();
        for (a, b) in intervals {
            if b - a < 2 {
                continue;
            }
            let m = (a + b) / 2;
            let r = |p: usize| solved[p].as_ref().map(ratio);
            // The worst disagreement of the probes with the interpolation of the others (a
            // solve without a factor counts as a disagreement).
            let e = if b - a >= 4 {
                [(a + m) / 2, (m + b) / 2]
                    .into_iter()
                    .map(|p| Some((interp(a, m, b, r(a)?, r(m)?, r(b)?, p) - r(p)?).abs()))
                    .try_fold(0.0_f64, |acc, x| x.map(|x| acc.max(x)))
            } else {
                (|| Some((interp(a, a, b, r(a)?, r(a)?, r(b)?, m) - r(m)?).abs()))()
            };
            match e.and_then(|e| fits(a, b, e)) {
                Some(w) => {
                    for slot in accepted.iter_mut().take(b).skip(a + 1) {
                        *slot = Some((a, b, w));
                    }
                }
                None => {
                    next.push((a, m));
                    next.push((m, b));
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
        if let Some(c) = estimate(coarse, &solved, a, b, p, e, tolerance) {
            out.push((coarse[p].0, c, false));
        }
    }
    Ok(out)
}

/// The positions (in print order, among `n` states) that [`sample`] solves first, before any
/// result is known: the first, [`SAMPLE_FIRST`] and its doublings, and the last; every position
/// without `sampling`.
fn initial(n: usize, sampling: bool) -> Vec<usize> {
    if n == 0 {
        return Vec::new();
    }
    let mut first: Vec<usize> = if sampling {
        std::iter::once(0)
            .chain(std::iter::successors(Some(SAMPLE_FIRST), |p| {
                p.checked_mul(2)
            }))
            .take_while(|&p| p < n)
            .collect()
    } else {
        (0..n).collect()
    };
    first.push(n - 1);
    first.dedup();
    first
}

/// The mesh-correction ratio λ_f/λ_c of a solved state (1 without a split level).
fn ratio(c: &ConvergedFactor) -> f64 {
    let l = &c.levels;
    l.get(1).map_or(1.0, |f| f.factor) / l[0].factor
}

/// The interpolated estimate of position `p` inside the interval (a, b) whose probes disagree
/// with the interpolation by `e`: the quadratic through the ends and the midpoint where the
/// quarters were checked against it, the straight line (a short interval) otherwise; `None`
/// when an end or the midpoint has no split factor.
fn estimate(
    coarse: &[(usize, f64)],
    solved: &[Option<ConvergedFactor>],
    a: usize,
    b: usize,
    p: usize,
    e: f64,
    tolerance: f64,
) -> Option<ConvergedFactor> {
    let m = (a + b) / 2;
    let r = |q: usize| solved[q].as_ref().map(ratio);
    let rp = if b - a >= 4 {
        interp(a, m, b, r(a)?, r(m)?, r(b)?, p)
    } else {
        interp(a, a, b, r(a)?, r(a)?, r(b)?, p)
    };
    Some(interpolated(
        coarse[p].1,
        rp,
        e.max(f64::EPSILON),
        tolerance,
    ))
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

    /// [`sample`] of `coarse` at the default tolerance (0.5 %) whose split solves are the exact
    /// pairs of `ratio`: the result and the number of states solved on the split.
    fn sample_exact(
        coarse: &[(usize, f64)],
        ratio: &dyn Fn(usize) -> f64,
    ) -> (Vec<(usize, ConvergedFactor, bool)>, usize) {
        let mut calls = 0usize;
        let mut solve = |batch: &[usize]| -> Result<Vec<(usize, ConvergedFactor)>, ()> {
            calls += batch.len();
            Ok(batch
                .iter()
                .map(|&i| (i, exact(coarse[i].1, ratio(i))))
                .collect())
        };
        let out = sample(coarse, 0.005, true, &mut solve).unwrap();
        (out, calls)
    }

    /// The relaxed test spends the budget where it may: a ratio that wobbles by more than
    /// `tolerance/10` between the probes is interpolated among states far above the governing
    /// one, but solved where every state could govern; either way every bracket covers the pair
    /// of the state's own split, and an interpolated state meets the tolerance or cannot govern.
    #[test]
    fn a_wobbling_ratio_is_interpolated_only_where_it_cannot_govern() {
        let n = 100;
        // About 0.2 % own error (ratio ≈ 0.997), a wobble of ±0.05 % of the ratio with a period
        // of 24 states: the quadratic over 8 or 16 states misses it by 0.005–0.1 %, between
        // `tolerance/10` and `tolerance/2`.
        let ratio = |i: usize| 0.997 + 5e-4 * (i as f64 * std::f64::consts::TAU / 24.0).sin();
        let run = |coarse: &Vec<(usize, f64)>, slack: f64| {
            let (out, calls) = sample_exact(coarse, &ratio);
            assert_eq!(out.len(), n);
            let upper = out.iter().map(|o| o.1.upper).fold(f64::INFINITY, f64::min);
            for (i, c, solved) in &out {
                let truth = exact(coarse[*i].1, ratio(*i));
                assert!(
                    c.extrapolated <= truth.extrapolated * (1.0 + slack) + 1e-12,
                    "state {i}: {c:?}, its own pair {truth:?}"
                );
                assert!(c.upper >= truth.upper * (1.0 - slack) - 1e-12, "state {i}");
                if !solved {
                    assert!(c.converged || c.extrapolated > upper, "state {i}: {c:?}");
                }
            }
            calls
        };
        // Far from governing except the last few states (the default cap's shape)...
        let falling: Vec<(usize, f64)> = (0..n).map(|i| (i, 10.0 - 0.05 * i as f64)).collect();
        // ...and every state within 0.1 % of the lowest, so each could govern.
        let flat: Vec<(usize, f64)> = (0..n).map(|i| (i, 5.0 + 5e-5 * i as f64)).collect();
        // Where the relaxed test interpolates (far), the brackets cover the states' own pairs.
        // Where only the strict test may (near), an interval whose probes agree to within
        // `tolerance/10` is interpolated with its bracket widened by `SAMPLE_SAFETY` times that
        // agreement, and a state between the probes could still miss it (a smooth wobble like
        // this one: by at most 2·Richardson·(tolerance/10) = 0.2 % of the factor; a jump between
        // the probes can miss it by more, as before the relaxed test; docs/convergence.md).
        let (far, near) = (run(&falling, 0.0), run(&flat, 0.002));
        assert!(
            far < near,
            "{far} solves far from governing, {near} near it"
        );
        assert!(far <= n / 3, "{far} solves");
    }

    /// The first batch: dense at the start, doubling after, always the first and the last
    /// state; every state without sampling; nothing for no states.
    #[test]
    fn the_first_batch_doubles_its_spacing() {
        assert_eq!(initial(113, true), vec![0, 16, 32, 64, 112]);
        assert_eq!(initial(197, true), vec![0, 16, 32, 64, 128, 196]);
        assert_eq!(initial(17, true), vec![0, 16]);
        assert_eq!(initial(10, true), vec![0, 9]);
        assert_eq!(initial(1, true), vec![0]);
        assert_eq!(initial(0, true), Vec::<usize>::new());
        assert_eq!(initial(5, false), vec![0, 1, 2, 3, 4]);
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
        let (out, calls) = sample_exact(&coarse, &ratio);
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
