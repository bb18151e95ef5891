//! Mesh-error control of the lowest buckling factor: the model's own mesh and its nested 2×2
//! splits ([`crate::refine::split`], the same flat facets), and Richardson extrapolation of the
//! last two levels (docs/convergence.md).
//!
//! **Why order 1.** On the print states of a cap the factor falls monotonically under
//! refinement, at an observed order p between 1 and 1.6 (the layer mesh of the default cap's
//! state 10: 33.427, 32.801, 32.485, 32.374 on 1×1, 2×2, 4×4, 8×8 splits): the pinned support
//! lines end at free edges, and such mixed corners and the Reissner–Mindlin boundary layers
//! (width ≈ t, under-resolved by facets of about t) limit the rate. Richardson extrapolation
//! at order 1 from a coarse value λ_c and its 2×2 split λ_f,
//!
//! λ̂₁ = λ_f − (λ_c − λ_f) = 2 λ_f − λ_c,
//!
//! is the lowest value any order p ≥ 1 allows, so with a monotone sequence it lies on the safe
//! side of the converged factor; at order 2 the same pair gives λ̂₂ = λ_f − (λ_c − λ_f)/3. The
//! converged factor lies in [λ̂₁, λ̂₂] for 1 ≤ p ≤ 2: the reported factor is λ̂₁, and its error
//! estimate `(λ̂₂ − λ̂₁)/λ̂₁ = ⅔ (λ_c − λ_f)/λ̂₁` bounds how far below the converged value it can
//! be. A level that does not decrease (λ_f > λ_c: out of the asymptotic range, or a mode switch)
//! is reported with the lower (coarse) value and the step as its error, never extrapolated upwards.
//!
//! Hand-written: a loop over [`crate::buckling`] on [`crate::refine::split`] meshes.

use crate::error::FeError;
use crate::model::ShellModel;
use crate::refine::split;
use crate::solver::{BucklingOptions, BucklingResult, buckling};
use crate::twolevel::{TwoLevel, TwoLevelOptions, split_buckling};

/// One mesh of the sequence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshLevel {
    /// Splits per edge of the model's own mesh (1, 2, 4, …).
    pub split: usize,
    /// Lowest positive factor on this mesh.
    pub factor: f64,
    /// Free DOFs.
    pub n_free_dofs: usize,
    /// Lanczos steps of its solve (a two-level solve: applications of its two-grid cycle).
    pub steps: usize,
    /// How this level was solved.
    pub solver: LevelSolve,
}

/// How a mesh level was solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LevelSolve {
    /// Its own LLᵀ and Lanczos (the model's own mesh, and every split with
    /// [`SplitSolver::Direct`]).
    #[default]
    Direct,
    /// The two-level solver ([`crate::twolevel`]), every guard passed.
    TwoLevel,
    /// The two-level solver declined (a guard failed, or it could not run) and the split was
    /// solved directly.
    Fallback,
}

/// The solver of the split levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SplitSolver {
    /// LLᵀ of the split's K and Lanczos started from the coarser level's mode.
    #[default]
    Direct,
    /// [`crate::twolevel::split_buckling`] preconditioned by the coarser level, falling back to
    /// the direct solve when it declines.
    TwoLevel,
}

/// The converged estimate of the lowest factor.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvergedFactor {
    /// The meshes solved, coarsest first.
    pub levels: Vec<MeshLevel>,
    /// λ̂₁: Richardson at order 1 of the last two levels (the safe end; the reported factor).
    pub extrapolated: f64,
    /// λ̂₂: the same pair at order 2 (the other end of the bracket).
    pub upper: f64,
    /// Relative error estimate `(λ̂₂ − λ̂₁)/λ̂₁` of [`Self::extrapolated`].
    pub error: f64,
    /// `error ≤ tolerance`.
    pub converged: bool,
}

impl ConvergedFactor {
    /// The estimate from a coarse and a fine factor of nested meshes (fine = 2×2 split).
    pub fn from_pair(levels: Vec<MeshLevel>, tolerance: f64) -> Option<Self> {
        let n = levels.len();
        if n < 2 {
            return None;
        }
        let (c, f) = (levels[n - 2].factor, levels[n - 1].factor);
        let step = c - f;
        let (lo, hi, error) = if step >= 0.0 {
            let lo = f - step;
            let hi = f - step / 3.0;
            (
                lo,
                hi,
                if lo > 0.0 {
                    (hi - lo) / lo
                } else {
                    f64::INFINITY
                },
            )
        } else {
            // Not decreasing (out of the asymptotic range, e.g. a graded mesh's coarse rows, or
            // a mode switch): no extrapolation; the lower value (the coarse one), the step as
            // the error.
            (c, f, -step / c)
        };
        Some(Self {
            levels,
            extrapolated: lo,
            upper: hi,
            error,
            converged: error <= tolerance,
        })
    }
}

/// Continue the mesh sequence of `model` whose own solve is `coarse` (level 1): solve 2×2
/// splits (each started from the previous level's mode) until the error estimate is at most
/// `tolerance` or `max_split` splits per edge are reached (at least one split is solved).
/// `options` are those of the coarse solve (one mode is enough: the start is mode 1).
pub fn converge_factor(
    model: &ShellModel,
    coarse: &BucklingResult,
    options: &BucklingOptions,
    tolerance: f64,
    max_split: usize,
) -> Result<Option<ConvergedFactor>, FeError> {
    let Some(&f0) = coarse.factors.first() else {
        return Ok(None);
    };
    let level = MeshLevel {
        split: 1,
        factor: f0,
        n_free_dofs: coarse.stats.n_free_dofs,
        steps: coarse.stats.operator_applications,
        solver: LevelSolve::Direct,
    };
    converge_from(
        model,
        level,
        coarse.modes.first().cloned(),
        options,
        tolerance,
        max_split,
    )
}

/// [`converge_factor`] from a coarse solve done earlier: its level `coarse` and its mode 1
/// (per node of `model`, the start of the first split's Lanczos; `None`: a random start). The
/// print states' mesh-error pass solves the print-layer meshes once, in its first pass, and
/// continues here without solving them again (docs/convergence.md, "Speed").
///
/// # Errors
/// A split mesh that cannot be solved.
pub fn converge_from(
    model: &ShellModel,
    coarse: MeshLevel,
    mode: Option<Vec<[f64; 6]>>,
    options: &BucklingOptions,
    tolerance: f64,
    max_split: usize,
) -> Result<Option<ConvergedFactor>, FeError> {
    converge_from_with(
        model,
        coarse,
        mode,
        options,
        tolerance,
        max_split,
        SplitSolver::Direct,
    )
}

/// [`converge_from`] with the split levels solved by `solver`. [`SplitSolver::TwoLevel`] solves
/// each split with [`crate::twolevel::split_buckling`] on the level below it (default
/// [`crate::twolevel::TwoLevelOptions`], its eigen-tolerance `options.tolerance`), and directly
/// where that declines ([`LevelSolve::Fallback`]): the result is the direct solve's to within
/// the eigen-solvers' tolerances (docs/convergence.md, "The `twogrid` branch").
///
/// # Errors
/// A split mesh that cannot be solved.
pub fn converge_from_with(
    model: &ShellModel,
    coarse: MeshLevel,
    mode: Option<Vec<[f64; 6]>>,
    options: &BucklingOptions,
    tolerance: f64,
    max_split: usize,
    solver: SplitSolver,
) -> Result<Option<ConvergedFactor>, FeError> {
    let mut levels = vec![coarse];
    let mut current = model.clone();
    let mut mode = mode.filter(|m| m.len() == model.nodes.len());
    let mut split_n = 1;
    loop {
        let refined = split(&current, 2);
        split_n *= 2;
        let two_level = match solver {
            SplitSolver::Direct => None,
            SplitSolver::TwoLevel => {
                let opts = TwoLevelOptions {
                    eigen_tolerance: options.tolerance,
                    seed: options.seed,
                    ..TwoLevelOptions::default()
                };
                // An error of the two-level solve (e.g. a split that is a mechanism) is the
                // direct solve's to report: it falls back.
                match split_buckling(&current, &refined, mode.as_deref(), &opts) {
                    Ok(TwoLevel::Solved(s)) => Some(Some(s)),
                    Ok(TwoLevel::Declined { .. }) | Err(_) => Some(None),
                }
            }
        };
        let (level, next_mode) = match two_level {
            Some(Some(s)) => (
                MeshLevel {
                    split: split_n,
                    factor: s.factor,
                    n_free_dofs: s.stats.n_free_fine,
                    steps: s.stats.cycles,
                    solver: LevelSolve::TwoLevel,
                },
                Some(s.mode),
            ),
            declined => {
                let start = mode.as_ref().map(|m| refined.prolong(m));
                let r = buckling(
                    &refined.model,
                    &BucklingOptions {
                        modes: 1,
                        start,
                        sturm_check: false,
                        ..options.clone()
                    },
                )?;
                let Some(&f) = r.factors.first() else {
                    return Ok(None);
                };
                (
                    MeshLevel {
                        split: split_n,
                        factor: f,
                        n_free_dofs: r.stats.n_free_dofs,
                        steps: r.stats.operator_applications,
                        solver: if declined.is_some() {
                            LevelSolve::Fallback
                        } else {
                            LevelSolve::Direct
                        },
                    },
                    r.modes.into_iter().next(),
                )
            }
        };
        levels.push(level);
        let est = ConvergedFactor::from_pair(levels.clone(), tolerance);
        let done = est.as_ref().is_none_or(|e| e.converged) || 2 * split_n > max_split.max(2);
        if done {
            return Ok(est);
        }
        mode = next_mode;
        current = refined.model;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(split: usize, factor: f64) -> MeshLevel {
        MeshLevel {
            split,
            factor,
            n_free_dofs: 0,
            steps: 0,
            solver: LevelSolve::Direct,
        }
    }

    #[test]
    fn order_one_extrapolation_and_bracket() {
        // λ = 1 + 0.1 h: exact at order 1.
        let e = ConvergedFactor::from_pair(vec![level(1, 1.1), level(2, 1.05)], 0.05).unwrap();
        assert!((e.extrapolated - 1.0).abs() < 1e-12);
        assert!((e.upper - (1.05 - 0.05 / 3.0)).abs() < 1e-12);
        assert!((e.error - (e.upper - 1.0)).abs() < 1e-12);
        assert!(e.converged);
        // λ = 1 + 0.1 h²: the order-1 value is below the limit (the safe side), within the error.
        let e = ConvergedFactor::from_pair(vec![level(1, 1.1), level(2, 1.025)], 0.01).unwrap();
        assert!(e.extrapolated < 1.0 && e.upper >= 1.0 - 1e-12);
        assert!(1.0 / e.extrapolated - 1.0 <= e.error + 1e-12);
        assert!(!e.converged);
        // Increasing: never extrapolated upwards, the lower value reported.
        let e = ConvergedFactor::from_pair(vec![level(1, 1.0), level(2, 1.01)], 0.05).unwrap();
        assert_eq!(e.extrapolated, 1.0);
        assert!((e.error - 0.01).abs() < 1e-12);
    }

    #[test]
    fn vault_converges_towards_the_reference() {
        // The barrel vault of the acceptance checks (CalculiX S8R converged 0.068970): the
        // order-1 estimate from 10×6 and 20×12 is closer to it than the 20×12 mesh itself.
        let m = crate::generate::barrel_vault(10, 6);
        let opts = BucklingOptions {
            modes: 1,
            tolerance: 1e-8,
            sturm_check: false,
            ..Default::default()
        };
        let coarse = buckling(&m, &opts).unwrap();
        let c = converge_factor(&m, &coarse, &opts, 1e-9, 2)
            .unwrap()
            .unwrap();
        assert_eq!(c.levels.len(), 2);
        let reference = 0.068_970_4;
        let fine = c.levels[1].factor;
        assert!(
            (c.extrapolated - reference).abs() < (fine - reference).abs(),
            "{c:?}"
        );
    }
}
