//! The lowest buckling pair of a 2×2 split ([`crate::refine::split`]) **without factorizing
//! the split's K**: a two-level (two-grid) method whose coarse level is the model the split was
//! made from (docs/convergence.md, "The `twogrid` branch").
//!
//! **Coarse space.** P prolongs a vector of the coarse model's free DOFs onto the split: a coarse
//! node keeps its six DOFs, an edge midpoint takes the cubic (Hermite) interpolation along its
//! coarse edge ([`node_prolongation`]; rigid-body motions and a facet's constant-curvature
//! bending are reproduced exactly). The coarse operators are the **Galerkin** products
//! A_c = Pᵀ K P and G_c = Pᵀ K_G P, assembled element by element (a coarse triangle's matrix is
//! Σ over its four children of Qᵀ k_child Q), so they have the coarse mesh's sparsity. A_c is
//! SPD when K is (P has full column rank: a coarse node is its own split node). The print-layer
//! LLᵀ of the first pass is not kept alive (a 113-state pass would hold every factor), and it
//! factorizes the coarse element's own K, not Pᵀ K P: the coarse LLᵀ is redone here (its
//! symbolic analysis and factor are the size of the print-layer solve's).
//!
//! **Preconditioner** (the symmetric multiplicative two-grid cycle): `sweeps` forward node-block
//! Gauss–Seidel sweeps on K (6×6 diagonal blocks), the coarse correction P A_c⁻¹ Pᵀ, as many
//! backward sweeps. With a Galerkin coarse operator and a convergent symmetric smoother this B
//! is SPD and 0 < BK ≤ I (Hackbusch, *Multi-grid Methods and Applications*, 1985, §10.6), so it
//! serves PCG and LOBPCG.
//!
//! **Static solve.** PCG on K u = f from u₀ = P A_c⁻¹ Pᵀ f, until ‖f − K u‖₂ ≤ τ_s ‖f‖₂. The
//! membrane forces and hence K_G follow from u; a buckling factor's first-order sensitivity to
//! K_G is λ φᵀ δK_G φ / φᵀ K_G φ, so the factor's error is of the order of the stresses'
//! relative error: τ_s = 1e-6 moved the default cap's state 40 by 7.5e-10 relative against
//! 1e-9; the default τ_s = 1e-8.
//!
//! **Eigen-solve.** The largest μ = 1/λ of (−K_G) x = μ K x (K SPD). First the top `block` + 1
//! Ritz pairs of the Galerkin pencil (A_c, −G_c) by the crate's Lanczos on the LLᵀ of A_c
//! (warm-started from the coarse model's own mode when given); the first `block` of them,
//! prolonged, start LOBPCG (Knyazev 2001) with the preconditioner B and a Rayleigh–Ritz step on
//! [X, B R, P] in the K-metric. Stop when pair 1's residual s = −K_G x − μ K x satisfies
//! η = √(sᵀBs) / (μ ‖x‖_K) ≤ τ_e. Since BK ≤ I, ‖s‖²_{K⁻¹} ≤ sᵀBs / λ_min(BK), and by the
//! Kato–Temple inequality the Ritz value's error is
//!
//! 0 ≤ μ₁ − μ̃₁ ≤ ‖s‖²_{K⁻¹} / (μ̃₁ − μ₂)  ⇒  (λ̃₁ − λ₁)/λ₁ ≲ η² / (λ_min(BK) · (1 − μ₂/μ̃₁)),
//!
//! quadratic in η and one-sided: a Ritz value of the K-definite pencil is never below λ₁. The
//! bound rests on μ₂ (the next eigenvalue), which is not known, only estimated by the gap test
//! below, and on λ_min(BK), which the PCG's convergence rate (0.3–0.45 per iteration measured)
//! puts near 0.5. With τ_e = 1e-5 (what `crate::convergence::converge_from_with` passes: the
//! direct Lanczos's residual) and a gap of 10 % it is 2e-9; measured against the direct solve:
//! 1e-13 to 3.5e-10.
//!
//! **Soundness: never a higher mode.** A Ritz value can sit on mode 2 with a small residual
//! when the start lacks mode 1. The guards, each a decline (the caller then solves the split
//! directly; [`crate::convergence::LevelSolve::Fallback`] counts it):
//! - the gap test: the coarse-space factor of mode k + 1 (k = `block`) must exceed the found
//!   λ̃₁ by the factor 1 + `gap`. A split mode 1 missed by the block would be a coarse-space mode
//!   j > k, with a coarse-space factor at least λᴳ_{k+1} > λ̃₁ (1 + `gap`) ≥ λ₁ (1 + `gap`): the
//!   coarse space would over-stiffen it by more than `gap` (default 10 %). That is the
//!   assumption, checked on the state itself by the next guard;
//! - the found mode's own coarse-space factor λᴳ₁ must be within 1 + `gap`/2 of λ̃₁;
//! - PCG or LOBPCG not converged within `max_iterations`, or a non-positive pivot of A_c or of
//!   a node block.
//!
//! A mode swap between the coarse space's modes 1…k and the split is inside the block and found
//! (test `twolevel::a_mode_swap_between_the_meshes_is_found_or_declined_never_missed`).

//! Hand-written: no Rust crate has a two-grid preconditioner or LOBPCG for a pencil with an
//! indefinite matrix.

use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

use crate::assembly::{DofMap, Pattern, geometries, load_vector, scatter};
use crate::clock::Instant;
use crate::element::{Mat18, ShellElement, TriangleGeometry};
use crate::error::FeError;
use crate::factor::{Llt, LltFailure, Symbolic};
use crate::model::ShellModel;
use crate::refine::Refined;
use crate::solver::{BucklingOptions, Ops, SolveStats, dot, lanczos, mode_shape, start_vector};

/// Options of [`split_buckling`].
#[derive(Debug, Clone, PartialEq)]
pub struct TwoLevelOptions {
    /// Relative residual of the static PCG, ‖f − K u‖₂ ≤ this · ‖f‖₂ (default 1e-8; 1e-6 moved
    /// the default cap's state 40 factor by 7.5e-10 relative against 1e-9).
    pub static_tolerance: f64,
    /// Relative residual η of the eigenpair (module docs; default 1e-5).
    pub eigen_tolerance: f64,
    /// Vectors in the LOBPCG block, from the coarse-space modes 1…block (≥ 1; default 1); the
    /// gap test uses mode block + 1.
    pub block: usize,
    /// Gauss–Seidel sweeps before and after the coarse correction (≥ 1; default 2: on the cap's
    /// states 15 PCG iterations instead of 23 for 1e-7, fewer seconds).
    pub sweeps: usize,
    /// Iterations allowed to each of PCG and LOBPCG before declining (default 300).
    pub max_iterations: usize,
    /// The gap test's margin (module docs; default 0.10).
    pub gap: f64,
    /// Seed of the random part of the coarse Lanczos start.
    pub seed: u64,
}

impl Default for TwoLevelOptions {
    fn default() -> Self {
        Self {
            static_tolerance: 1e-8,
            eigen_tolerance: 1e-5,
            block: 1,
            sweeps: 2,
            max_iterations: 300,
            gap: 0.10,
            seed: BucklingOptions::default().seed,
        }
    }
}

/// Counts and times of a two-level solve.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TwoLevelStats {
    /// Free DOFs of the split.
    pub n_free_fine: usize,
    /// Free DOFs of the coarse model.
    pub n_free_coarse: usize,
    /// PCG iterations of the static solve.
    pub pcg_iterations: usize,
    /// LOBPCG iterations.
    pub lobpcg_iterations: usize,
    /// Applications of the two-grid preconditioner (PCG and LOBPCG).
    pub cycles: usize,
    /// Lanczos steps on the coarse space.
    pub coarse_steps: usize,
    /// The coarse-space factor of mode 1 (0 before it is solved).
    pub coarse_factor_1: f64,
    /// The coarse-space factor of mode block + 1, the gap test's (0 before it is solved).
    pub coarse_factor_next: f64,
    /// Seconds: DOF maps, patterns, symbolic analysis of the coarse mesh, assembly, LLᵀ of A_c.
    pub t_setup: f64,
    /// Seconds: the static PCG, stresses, K_G and G_c.
    pub t_static: f64,
    /// Seconds: coarse Lanczos and LOBPCG.
    pub t_eigen: f64,
}

/// A two-level solve's result.
#[derive(Debug, Clone, PartialEq)]
pub struct TwoLevelSolve {
    /// The split's lowest positive factor λ̃₁ (a Ritz value: never below the exact one).
    pub factor: f64,
    /// Its mode per split node, largest entry +1.
    pub mode: Vec<[f64; 6]>,
    /// The block's Ritz factors, ascending.
    pub block_factors: Vec<f64>,
    /// The coarse-space (Galerkin) factors that started the block, ascending.
    pub coarse_factors: Vec<f64>,
    /// Pair 1's relative residual η at the stop.
    pub residual: f64,
    /// Counts and times.
    pub stats: TwoLevelStats,
}

/// What [`split_buckling`] concluded.
#[derive(Debug, Clone, PartialEq)]
pub enum TwoLevel {
    /// The split's lowest pair, every guard passed.
    Solved(TwoLevelSolve),
    /// A guard failed; the split must be solved directly.
    Declined {
        /// Which guard, with its numbers.
        reason: String,
        /// What the attempt cost.
        stats: TwoLevelStats,
    },
}

/// The lowest buckling pair of `refined` (a 2×2 split of `coarse`, [`crate::refine::split`])
/// by the two-level method of the module docs, started from `start` (the coarse model's mode
/// 1 per node) when given.
///
/// # Errors
/// An invalid model. A failing guard is a [`TwoLevel::Declined`], not an error.
pub fn split_buckling(
    coarse: &ShellModel,
    refined: &Refined,
    start: Option<&[[f64; 6]]>,
    options: &TwoLevelOptions,
) -> Result<TwoLevel, FeError> {
    if options.block < 1 || options.sweeps < 1 {
        return Err(FeError::BadOption {
            field: "block, sweeps",
            value: options.block.min(options.sweeps) as f64,
            allowed: ">= 1",
        });
    }
    for (field, v) in [
        ("static_tolerance", options.static_tolerance),
        ("eigen_tolerance", options.eigen_tolerance),
    ] {
        if !(v > 0.0 && v < 1e-2) {
            return Err(FeError::BadOption {
                field,
                value: v,
                allowed: "0 < tolerance < 1e-2",
            });
        }
    }
    if !(options.gap > 0.0 && options.gap.is_finite()) {
        return Err(FeError::BadOption {
            field: "gap",
            value: options.gap,
            allowed: "> 0",
        });
    }
    coarse.validate()?;
    let fine = &refined.model;
    fine.validate()?;
    let mut stats = TwoLevelStats::default();
    let t0 = Instant::now();
    let Some(levels) = Levels::new(coarse, refined)? else {
        return Ok(TwoLevel::Declined {
            reason: "not a 2×2 split of the coarse model".into(),
            stats,
        });
    };
    let element = fine.element.implementation();
    let el: &dyn ShellElement = &*element;
    let alpha = fine.drilling_alpha;
    let (kf, kc) = levels.assemble(|e| {
        el.stiffness(
            &levels.geo[e],
            fine.thickness_of(e),
            &fine.material_of(e),
            alpha,
        )
    })?;
    let symbolic = Symbolic::new(&levels.pat_c)?;
    let llt = match symbolic.llt(&levels.pat_c, &kc) {
        Ok(l) => l,
        Err(LltFailure::NotPositive(_)) => {
            return Ok(TwoLevel::Declined {
                reason: "the coarse-space stiffness is not positive definite".into(),
                stats,
            });
        }
        Err(LltFailure::Other(e)) => return Err(e),
    };
    let smoother = Smoother::new(&levels.pat_f, &kf, &levels.block_ptr);
    let Some(smoother) = smoother else {
        return Ok(TwoLevel::Declined {
            reason: "a node block of the split's K is not positive definite".into(),
            stats,
        });
    };
    let cycle = TwoGrid {
        levels: &levels,
        k: &smoother,
        llt: &llt,
        sweeps: options.sweeps,
    };
    stats.n_free_fine = levels.dofs_f.n_free();
    stats.n_free_coarse = levels.dofs_c.n_free();
    stats.t_setup = t0.elapsed().as_secs_f64();

    // Static solve.
    let t1 = Instant::now();
    let f_all = load_vector(fine, &levels.geo);
    let f: Vec<f64> = levels.dofs_f.free.iter().map(|&g| f_all[g]).collect();
    let Some(u) = pcg(&cycle, &f, options, &mut stats)? else {
        return Ok(TwoLevel::Declined {
            reason: format!(
                "the static PCG did not reach {:e} in {} iterations",
                options.static_tolerance, options.max_iterations
            ),
            stats,
        });
    };
    let mut disp = vec![[0.0; 6]; fine.nodes.len()];
    for (i, &g) in levels.dofs_f.free.iter().enumerate() {
        disp[g / 6][g % 6] = u[i];
    }
    let membrane: Vec<[f64; 3]> = fine
        .triangles
        .par_iter()
        .enumerate()
        .map(|(e, tri)| {
            let ue: [f64; 18] = std::array::from_fn(|k| disp[tri[k / 6]][k % 6]);
            el.resultants(
                &levels.geo[e],
                fine.thickness_of(e),
                &fine.material_of(e),
                &ue,
            )
            .membrane
        })
        .collect();
    let (gf, gc) = levels.assemble(|e| {
        el.geometric_stiffness(
            &levels.geo[e],
            fine.thickness_of(e),
            &fine.material_of(e),
            &membrane[e],
        )
    })?;
    stats.t_static = t1.elapsed().as_secs_f64();

    // The block's start: the coarse-space pencil's top pairs.
    let t2 = Instant::now();
    let lanczos_opts = BucklingOptions {
        modes: options.block + 1,
        tolerance: 1e-8,
        sturm_check: false,
        seed: options.seed,
        ..Default::default()
    };
    let guess = start.map(|g| start_vector(&levels.dofs_c, g, options.seed));
    let mut lstats = SolveStats::default();
    let ops_c = Ops {
        pattern: &levels.pat_c,
        k: &kc,
        kg: &gc,
    };
    let max_steps = 20 * (options.block + 1) + 400;
    let pairs = lanczos(
        &ops_c,
        &llt,
        options.block + 1,
        &lanczos_opts,
        guess,
        &[],
        max_steps,
        &mut lstats,
    )?;
    stats.coarse_steps = lstats.operator_applications;
    if pairs.len() < options.block + 1 {
        return Ok(TwoLevel::Declined {
            reason: format!(
                "the coarse space has {} positive factors, the gap test needs {}",
                pairs.len(),
                options.block + 1
            ),
            stats,
        });
    }
    let coarse_factors: Vec<f64> = pairs.iter().map(|p| p.lambda).collect();
    stats.coarse_factor_1 = coarse_factors[0];
    stats.coarse_factor_next = coarse_factors[options.block];
    let x0: Vec<Vec<f64>> = pairs
        .iter()
        .take(options.block)
        .map(|p| levels.prolong(&p.vector))
        .collect();
    let ops_f = Ops {
        pattern: &levels.pat_f,
        k: &kf,
        kg: &gf,
    };
    let Some(eig) = lobpcg(&cycle, &ops_f, x0, options, &mut stats) else {
        return Ok(TwoLevel::Declined {
            reason: format!(
                "LOBPCG did not reach η ≤ {:e} in {} iterations",
                options.eigen_tolerance, options.max_iterations
            ),
            stats,
        });
    };
    stats.t_eigen = t2.elapsed().as_secs_f64();
    let lam1 = eig.factors[0];
    let lg_k = coarse_factors[options.block];
    if !(lam1 > 0.0 && lam1.is_finite()) {
        return Ok(TwoLevel::Declined {
            reason: "no positive factor on the split".into(),
            stats,
        });
    }
    if lg_k < lam1 * (1.0 + options.gap) {
        return Ok(TwoLevel::Declined {
            reason: format!(
                "gap test: coarse-space factor {} = {lg_k} within {} of the split's {lam1}",
                options.block + 1,
                options.gap
            ),
            stats,
        });
    }
    if coarse_factors[0] > lam1 * (1.0 + options.gap / 2.0) {
        return Ok(TwoLevel::Declined {
            reason: format!(
                "the split changes mode 1's coarse-space factor {} by more than {} (to {lam1})",
                coarse_factors[0],
                options.gap / 2.0
            ),
            stats,
        });
    }
    Ok(TwoLevel::Solved(TwoLevelSolve {
        factor: lam1,
        mode: mode_shape(&levels.dofs_f, fine.nodes.len(), &eig.vector),
        block_factors: eig.factors,
        coarse_factors,
        residual: eig.residual,
        stats,
    }))
}

/// A 6 × 6 block of P (row-major): a split node's DOFs from one coarse node's.
type Block6 = [[f64; 6]; 6];

/// A split triangle's prolongation: per node, up to two (coarse corner index, block) pairs.
type ChildQ = [[Option<(usize, Block6)>; 2]; 3];

/// The two meshes, their free DOFs and patterns, and the prolongation.
struct Levels<'a> {
    coarse: &'a ShellModel,
    fine: &'a ShellModel,
    dofs_c: DofMap,
    pat_c: Pattern,
    dofs_f: DofMap,
    pat_f: Pattern,
    geo: Vec<TriangleGeometry>,
    /// Per split triangle and node k: up to two (coarse corner index 0..3, block) pairs, the
    /// block's rows of fixed split DOFs zeroed.
    q: Vec<ChildQ>,
    /// P by rows (split free DOFs): `p_ptr`, coarse free index, weight.
    p_ptr: Vec<usize>,
    p_col: Vec<usize>,
    p_val: Vec<f64>,
    /// Split free DOFs of node block b: `block_ptr[b]..block_ptr[b + 1]`.
    block_ptr: Vec<usize>,
}

/// Children of a coarse triangle in a 2×2 split.
const CHILDREN: usize = 4;

/// The prolongation of a split node from its parents: a coarse node keeps its DOFs; an edge
/// midpoint m of the coarse edge (a, b) (unit vector e from a to b, length ℓ) takes the
/// cubic (Hermite) interpolation along the edge of the displacement, whose slope is θ × e
/// (`HERMITE`), or the linear one (both DOFs halved):
///
/// u_m = (u_a + u_b)/2 + (ℓ/8)(θ_a − θ_b) × e,
/// θ_m = ((θ_a + θ_b)·e) e/2 − (θ_a + θ_b)_⊥/4 + (3/(2ℓ)) e × (u_b − u_a),
///
/// (⊥: the part normal to e; the twist about e is linear). Both reproduce rigid-body motions
/// exactly; the cubic one also a facet's constant-curvature bending, which the linear one
/// misses (its coarse space is much stiffer in bending: 20 % on the cap's states).
fn node_prolongation(
    coarse: &ShellModel,
    parents: &[(usize, f64); 3],
) -> Option<Vec<(usize, Block6)>> {
    let nz: Vec<(usize, f64)> = parents.iter().copied().filter(|p| p.1 != 0.0).collect();
    let eye = |s: f64| -> Block6 {
        std::array::from_fn(|i| std::array::from_fn(|j| if i == j { s } else { 0.0 }))
    };
    match nz.as_slice() {
        [(a, w)] if (*w - 1.0).abs() < 1e-12 => Some(vec![(*a, eye(1.0))]),
        [(a, wa), (b, wb)] if (wa - 0.5).abs() < 1e-12 && (wb - 0.5).abs() < 1e-12 => {
            if !HERMITE {
                return Some(vec![(*a, eye(0.5)), (*b, eye(0.5))]);
            }
            let (xa, xb) = (coarse.nodes.get(*a)?, coarse.nodes.get(*b)?);
            let d: [f64; 3] = std::array::from_fn(|c| xb[c] - xa[c]);
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if l.is_nan() || l <= 0.0 {
                return None;
            }
            let e = d.map(|c| c / l);
            // [e]× v = e × v.
            let ex = [[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]];
            let block = |sign: f64| -> Block6 {
                let mut m = [[0.0; 6]; 6];
                for i in 0..3 {
                    m[i][i] = 0.5;
                    for j in 0..3 {
                        // u_m: ∓(ℓ/8) e × θ (θ × e = −e × θ; + for a, − for b).
                        m[i][3 + j] = -sign * l / 8.0 * ex[i][j];
                        // θ_m: ±(3/(2ℓ)) e × u (− for a, + for b).
                        m[3 + i][j] = -sign * 1.5 / l * ex[i][j];
                        // Twist halved, the normal part quartered with a minus sign.
                        let par = e[i] * e[j];
                        let perp = if i == j { 1.0 } else { 0.0 } - par;
                        m[3 + i][3 + j] = 0.5 * par - 0.25 * perp;
                    }
                }
                m
            };
            Some(vec![(*a, block(1.0)), (*b, block(-1.0))])
        }
        _ => None,
    }
}

/// Whether midpoints take the cubic edge interpolation ([`node_prolongation`]).
const HERMITE: bool = true;

impl<'a> Levels<'a> {
    /// `None` when `refined` is not a 2×2 split of `coarse` (children not grouped by parent,
    /// a parent that is not a corner of the child's coarse triangle, a node other than a
    /// coarse node or an edge midpoint).
    fn new(coarse: &'a ShellModel, refined: &'a Refined) -> Result<Option<Self>, FeError> {
        let fine = &refined.model;
        if fine.triangles.len() != CHILDREN * coarse.triangles.len()
            || refined.parents.len() != fine.nodes.len()
        {
            return Ok(None);
        }
        let mut prol = Vec::with_capacity(fine.nodes.len());
        for p in &refined.parents {
            let Some(b) = node_prolongation(coarse, p) else {
                return Ok(None);
            };
            prol.push(b);
        }
        let dofs_c = DofMap::new(coarse);
        let dofs_f = DofMap::new(fine);
        if dofs_c.n_free() == 0 || dofs_f.n_free() == 0 {
            return Err(FeError::NoFreeDofs);
        }
        let mut q = Vec::with_capacity(fine.triangles.len());
        for (t, tri) in fine.triangles.iter().enumerate() {
            let corners = coarse.triangles[t / CHILDREN];
            let mut qt: ChildQ = [[None; 2]; 3];
            for (k, &node) in tri.iter().enumerate() {
                for (slot, &(c, mut b)) in prol[node].iter().enumerate() {
                    let Some(a) = corners.iter().position(|&x| x == c) else {
                        return Ok(None);
                    };
                    for (d, row) in b.iter_mut().enumerate() {
                        if dofs_f.map[6 * node + d] == usize::MAX {
                            *row = [0.0; 6];
                        }
                    }
                    if let Some(s) = qt[k].get_mut(slot) {
                        *s = Some((a, b));
                    }
                }
            }
            q.push(qt);
        }
        let pat_c = Pattern::new(coarse, &dofs_c);
        let pat_f = Pattern::new(fine, &dofs_f);
        let mut p_ptr = vec![0];
        let mut p_col = Vec::new();
        let mut p_val = Vec::new();
        for &g in &dofs_f.free {
            let (node, d) = (g / 6, g % 6);
            for (c, b) in &prol[node] {
                for (d2, &v) in b[d].iter().enumerate() {
                    let col = dofs_c.map[6 * c + d2];
                    if v != 0.0 && col != usize::MAX {
                        p_col.push(col);
                        p_val.push(v);
                    }
                }
            }
            p_ptr.push(p_col.len());
        }
        let mut block_ptr = vec![0];
        for i in 1..=dofs_f.n_free() {
            if i == dofs_f.n_free() || dofs_f.free[i] / 6 != dofs_f.free[i - 1] / 6 {
                block_ptr.push(i);
            }
        }
        Ok(Some(Self {
            coarse,
            fine,
            dofs_c,
            pat_c,
            dofs_f,
            pat_f,
            geo: geometries(fine),
            q,
            p_ptr,
            p_col,
            p_val,
            block_ptr,
        }))
    }

    /// The split's matrix Σ_e `matrix(e)` (lower values in `pat_f`) and its Galerkin product
    /// Pᵀ · · P (lower values in `pat_c`), each element matrix computed once.
    fn assemble<F>(&self, matrix: F) -> Result<(Vec<f64>, Vec<f64>), FeError>
    where
        F: Fn(usize) -> Mat18 + Sync,
    {
        let mut vf = vec![0.0; self.pat_f.nnz()];
        let mut vc = vec![0.0; self.pat_c.nnz()];
        const CHUNK: usize = 512;
        let n_c = self.coarse.triangles.len();
        let mut start = 0;
        while start < n_c {
            let end = (start + CHUNK).min(n_c);
            let mats: Vec<([Mat18; CHILDREN], Mat18)> = (start..end)
                .into_par_iter()
                .map(|e| {
                    let children: [Mat18; CHILDREN] =
                        std::array::from_fn(|s| matrix(CHILDREN * e + s));
                    let mut g = Mat18::zeros();
                    for (s, ke) in children.iter().enumerate() {
                        galerkin_add(&mut g, ke, &self.q[CHILDREN * e + s]);
                    }
                    (children, g)
                })
                .collect();
            for (e, (children, g)) in (start..end).zip(mats.iter()) {
                for (s, ke) in children.iter().enumerate() {
                    scatter(
                        self.fine,
                        &self.dofs_f,
                        &self.pat_f,
                        CHILDREN * e + s,
                        ke,
                        &mut vf,
                    )?;
                }
                scatter(self.coarse, &self.dofs_c, &self.pat_c, e, g, &mut vc)?;
            }
            start = end;
        }
        Ok((vf, vc))
    }

    /// P x (coarse free DOFs → split free DOFs).
    fn prolong(&self, x: &[f64]) -> Vec<f64> {
        (0..self.dofs_f.n_free())
            .map(|i| {
                (self.p_ptr[i]..self.p_ptr[i + 1])
                    .map(|q| self.p_val[q] * x[self.p_col[q]])
                    .sum()
            })
            .collect()
    }

    /// Pᵀ r (split free DOFs → coarse free DOFs).
    fn restrict(&self, r: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.dofs_c.n_free()];
        for (i, ri) in r.iter().enumerate() {
            for q in self.p_ptr[i]..self.p_ptr[i + 1] {
                y[self.p_col[q]] += self.p_val[q] * ri;
            }
        }
        y
    }
}

/// `g += Qᵀ k Q`, Q the child's 18 × 18 prolongation from its coarse triangle's corners (per
/// child node k up to two (corner, 6 × 6 block) pairs).
fn galerkin_add(g: &mut Mat18, k: &Mat18, q: &ChildQ) {
    // T = K Q (18 × 18).
    let mut t = Mat18::zeros();
    for (kn, pairs) in q.iter().enumerate() {
        for &(a, b) in pairs.iter().flatten() {
            for r in 0..18 {
                for j in 0..6 {
                    let mut s = 0.0;
                    for i in 0..6 {
                        s += k[(r, 6 * kn + i)] * b[i][j];
                    }
                    t[(r, 6 * a + j)] += s;
                }
            }
        }
    }
    // g += Qᵀ T.
    for (kn, pairs) in q.iter().enumerate() {
        for &(a, b) in pairs.iter().flatten() {
            for j in 0..6 {
                for c in 0..18 {
                    let mut s = 0.0;
                    for i in 0..6 {
                        s += b[i][j] * t[(6 * kn + i, c)];
                    }
                    g[(6 * a + j, c)] += s;
                }
            }
        }
    }
}

/// The split's K by full rows (both triangles), for the Gauss–Seidel sweeps and K·x, and the
/// inverses of its node blocks.
struct Smoother {
    row_ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
    block_ptr: Vec<usize>,
    /// Per node block, its inverse (row-major, 6 × 6, the block's size used).
    dinv: Vec<[f64; 36]>,
}

impl Smoother {
    /// `None` when a node block is not positive definite.
    fn new(p: &Pattern, vals: &[f64], block_ptr: &[usize]) -> Option<Self> {
        let n = p.n;
        let mut count = vec![0usize; n + 1];
        for j in 0..n {
            for q in p.col_ptr[j]..p.col_ptr[j + 1] {
                let i = p.row_idx[q];
                count[i] += 1;
                if i != j {
                    count[j] += 1;
                }
            }
        }
        let mut row_ptr = vec![0usize; n + 1];
        for i in 0..n {
            row_ptr[i + 1] = row_ptr[i] + count[i];
        }
        let mut next = row_ptr.clone();
        let nnz = row_ptr[n];
        let mut col = vec![0u32; nnz];
        let mut val = vec![0.0; nnz];
        // Column order j ascending puts each row's entries in ascending column order.
        for j in 0..n {
            for q in p.col_ptr[j]..p.col_ptr[j + 1] {
                let i = p.row_idx[q];
                col[next[i]] = j as u32;
                val[next[i]] = vals[q];
                next[i] += 1;
                if i != j {
                    col[next[j]] = i as u32;
                    val[next[j]] = vals[q];
                    next[j] += 1;
                }
            }
        }
        let mut dinv = Vec::with_capacity(block_ptr.len().saturating_sub(1));
        for b in 0..block_ptr.len().saturating_sub(1) {
            let (lo, hi) = (block_ptr[b], block_ptr[b + 1]);
            let m = hi - lo;
            let mut d = DMatrix::<f64>::zeros(m, m);
            for i in lo..hi {
                for q in row_ptr[i]..row_ptr[i + 1] {
                    let j = col[q] as usize;
                    if (lo..hi).contains(&j) {
                        d[(i - lo, j - lo)] = val[q];
                    }
                }
            }
            let inv = d.cholesky()?.inverse();
            let mut out = [0.0; 36];
            for a in 0..m {
                for c in 0..m {
                    out[6 * a + c] = inv[(a, c)];
                }
            }
            dinv.push(out);
        }
        Some(Self {
            row_ptr,
            col,
            val,
            block_ptr: block_ptr.to_vec(),
            dinv,
        })
    }

    /// y = K x.
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            let mut s = 0.0;
            for q in self.row_ptr[i]..self.row_ptr[i + 1] {
                s += self.val[q] * x[self.col[q] as usize];
            }
            *yi = s;
        }
    }

    /// One node-block Gauss–Seidel sweep on K x = b, forward or backward, updating `x`.
    fn sweep(&self, b: &[f64], x: &mut [f64], forward: bool) {
        let nb = self.block_ptr.len() - 1;
        let mut s = [0.0; 6];
        for k in 0..nb {
            let blk = if forward { k } else { nb - 1 - k };
            let (lo, hi) = (self.block_ptr[blk], self.block_ptr[blk + 1]);
            for i in lo..hi {
                let mut acc = b[i];
                for q in self.row_ptr[i]..self.row_ptr[i + 1] {
                    let j = self.col[q] as usize;
                    if j < lo || j >= hi {
                        acc -= self.val[q] * x[j];
                    }
                }
                s[i - lo] = acc;
            }
            let d = &self.dinv[blk];
            let m = hi - lo;
            for a in 0..m {
                let mut v = 0.0;
                for c in 0..m {
                    v += d[6 * a + c] * s[c];
                }
                x[lo + a] = v;
            }
        }
    }
}

/// The symmetric multiplicative two-grid cycle (module docs).
struct TwoGrid<'a> {
    levels: &'a Levels<'a>,
    k: &'a Smoother,
    llt: &'a Llt<'a>,
    sweeps: usize,
}

impl TwoGrid<'_> {
    /// P A_c⁻¹ Pᵀ r.
    fn coarse(&self, r: &[f64]) -> Result<Vec<f64>, FeError> {
        let c = self.levels.restrict(r);
        let mut m = faer::Mat::<f64>::from_fn(c.len(), 1, |i, _| c[i]);
        self.llt.solve_in_place(m.as_mut())?;
        let c: Vec<f64> = (0..c.len()).map(|i| m[(i, 0)]).collect();
        Ok(self.levels.prolong(&c))
    }

    /// z = B r.
    fn apply(&self, r: &[f64]) -> Result<Vec<f64>, FeError> {
        let n = r.len();
        let mut z = vec![0.0; n];
        for _ in 0..self.sweeps {
            self.k.sweep(r, &mut z, true);
        }
        let mut t = vec![0.0; n];
        self.k.mul(&z, &mut t);
        t.iter_mut().zip(r).for_each(|(t, r)| *t = r - *t);
        let c = self.coarse(&t)?;
        z.iter_mut().zip(&c).for_each(|(z, c)| *z += c);
        for _ in 0..self.sweeps {
            self.k.sweep(r, &mut z, false);
        }
        Ok(z)
    }
}

/// PCG on K u = f (module docs); `None` when not converged within the iterations allowed.
fn pcg(
    cycle: &TwoGrid<'_>,
    f: &[f64],
    options: &TwoLevelOptions,
    stats: &mut TwoLevelStats,
) -> Result<Option<Vec<f64>>, FeError> {
    let n = f.len();
    let fnorm = dot(f, f).sqrt();
    let mut u = cycle.coarse(f)?;
    if fnorm == 0.0 {
        return Ok(Some(vec![0.0; n]));
    }
    let mut r = vec![0.0; n];
    cycle.k.mul(&u, &mut r);
    r.iter_mut().zip(f).for_each(|(r, f)| *r = f - *r);
    let tol = options.static_tolerance * fnorm;
    if dot(&r, &r).sqrt() <= tol {
        return Ok(Some(u));
    }
    let mut z = cycle.apply(&r)?;
    stats.cycles += 1;
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut q = vec![0.0; n];
    for it in 1..=options.max_iterations {
        cycle.k.mul(&p, &mut q);
        let pq = dot(&p, &q);
        if !(pq > 0.0 && rz.is_finite()) {
            return Ok(None);
        }
        let a = rz / pq;
        u.iter_mut().zip(&p).for_each(|(u, p)| *u += a * p);
        r.iter_mut().zip(&q).for_each(|(r, q)| *r -= a * q);
        stats.pcg_iterations = it;
        if dot(&r, &r).sqrt() <= tol {
            return Ok(Some(u));
        }
        z = cycle.apply(&r)?;
        stats.cycles += 1;
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        p.iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
    }
    Ok(None)
}

/// LOBPCG's converged block.
struct Eig {
    /// Ritz factors λ = 1/μ of the block, ascending.
    factors: Vec<f64>,
    /// Pair 1's vector.
    vector: Vec<f64>,
    /// Pair 1's η.
    residual: f64,
}

/// Columns with their K and M = −K_G products.
struct Block {
    x: Vec<Vec<f64>>,
    kx: Vec<Vec<f64>>,
    mx: Vec<Vec<f64>>,
}

impl Block {
    fn of(x: Vec<Vec<f64>>, cycle: &TwoGrid<'_>, ops: &Ops<'_>) -> Self {
        let n = x.first().map_or(0, Vec::len);
        let kx = x
            .iter()
            .map(|v| {
                let mut y = vec![0.0; n];
                cycle.k.mul(v, &mut y);
                y
            })
            .collect();
        let mx = x
            .iter()
            .map(|v| {
                let mut y = vec![0.0; n];
                ops.kg_mul(v, &mut y);
                y.iter_mut().for_each(|a| *a = -*a);
                y
            })
            .collect();
        Self { x, kx, mx }
    }

    /// Σ_j c[j] · columns j, for x, Kx and Mx.
    fn combine(parts: &[&Block], c: &DMatrix<f64>, col: usize, row0: usize) -> [Vec<f64>; 3] {
        let n = parts.iter().find_map(|b| b.x.first()).map_or(0, Vec::len);
        let mut out = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut j = row0;
        for b in parts {
            for ((x, kx), mx) in b.x.iter().zip(&b.kx).zip(&b.mx) {
                let w = c[(j, col)];
                j += 1;
                if w == 0.0 {
                    continue;
                }
                for (o, v) in out.iter_mut().zip([x, kx, mx]) {
                    o.iter_mut().zip(v).for_each(|(o, v)| *o += w * v);
                }
            }
        }
        out
    }
}

/// LOBPCG for the largest μ of (−K_G) x = μ K x from the block `x0` (module docs); `None` when
/// pair 1 does not converge.
fn lobpcg(
    cycle: &TwoGrid<'_>,
    ops: &Ops<'_>,
    x0: Vec<Vec<f64>>,
    options: &TwoLevelOptions,
    stats: &mut TwoLevelStats,
) -> Option<Eig> {
    let k = x0.len();
    let mut x = Block::of(x0, cycle, ops);
    let mut p: Option<Block> = None;
    // Rayleigh–Ritz of the start block.
    let (theta, c) = rayleigh_ritz(&[&x], k)?;
    let mut x_new = Block {
        x: Vec::new(),
        kx: Vec::new(),
        mx: Vec::new(),
    };
    for i in 0..k {
        let [a, b, m] = Block::combine(&[&x], &c, i, 0);
        x_new.x.push(a);
        x_new.kx.push(b);
        x_new.mx.push(m);
    }
    x = x_new;
    let mut theta = theta;
    for it in 1..=options.max_iterations {
        stats.lobpcg_iterations = it;
        // Residuals s = M x − μ K x and their preconditioned directions.
        let mut w = Vec::with_capacity(k);
        let mut eta1 = f64::INFINITY;
        for i in 0..k {
            let s: Vec<f64> = x.mx[i]
                .iter()
                .zip(&x.kx[i])
                .map(|(m, kx)| m - theta[i] * kx)
                .collect();
            let bs = cycle.apply(&s).ok()?;
            stats.cycles += 1;
            if i == 0 {
                let xkx = dot(&x.x[0], &x.kx[0]);
                eta1 = dot(&s, &bs).max(0.0).sqrt() / (theta[0].abs() * xkx.sqrt());
            }
            w.push(bs);
        }
        if eta1 <= options.eigen_tolerance {
            let factors: Vec<f64> = theta.iter().map(|t| 1.0 / t).collect();
            return Some(Eig {
                factors,
                vector: x.x.swap_remove(0),
                residual: eta1,
            });
        }
        if !eta1.is_finite() {
            return None;
        }
        let wb = Block::of(w, cycle, ops);
        let parts: Vec<&Block> = match &p {
            Some(pb) => vec![&x, &wb, pb],
            None => vec![&x, &wb],
        };
        let (th, c) = rayleigh_ritz(&parts, k)?;
        let mut xn = Block {
            x: Vec::new(),
            kx: Vec::new(),
            mx: Vec::new(),
        };
        let mut pn = Block {
            x: Vec::new(),
            kx: Vec::new(),
            mx: Vec::new(),
        };
        for i in 0..k {
            let [a, b, m] = Block::combine(&parts, &c, i, 0);
            xn.x.push(a);
            xn.kx.push(b);
            xn.mx.push(m);
            let [a, b, m] = Block::combine(&parts[1..], &c, i, k);
            pn.x.push(a);
            pn.kx.push(b);
            pn.mx.push(m);
        }
        x = xn;
        p = Some(pn);
        theta = th;
    }
    None
}

/// Rayleigh–Ritz on the columns of `parts` in the K-metric: the top `k` pairs of
/// (Sᵀ M S) y = μ (Sᵀ K S) y, μ descending, with coefficient columns K-orthonormal. Directions
/// that are numerically dependent (an eigenvalue of the scaled Sᵀ K S below 1e-12 of its
/// largest) are dropped. `None` when fewer than `k` directions remain.
fn rayleigh_ritz(parts: &[&Block], k: usize) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let cols: Vec<(&Vec<f64>, &Vec<f64>, &Vec<f64>)> = parts
        .iter()
        .flat_map(|b| {
            b.x.iter()
                .zip(&b.kx)
                .zip(&b.mx)
                .map(|((x, kx), mx)| (x, kx, mx))
        })
        .collect();
    let m = cols.len();
    let mut ks = DMatrix::<f64>::zeros(m, m);
    let mut ms = DMatrix::<f64>::zeros(m, m);
    for i in 0..m {
        for j in i..m {
            let a = dot(cols[i].0, cols[j].1);
            let b = dot(cols[i].0, cols[j].2);
            ks[(i, j)] = a;
            ks[(j, i)] = a;
            ms[(i, j)] = b;
            ms[(j, i)] = b;
        }
    }
    let d: Vec<f64> = (0..m)
        .map(|i| {
            let v = ks[(i, i)];
            if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 }
        })
        .collect();
    let dm = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(d));
    let kss = &dm * &ks * &dm;
    let e = SymmetricEigen::try_new(kss, f64::EPSILON, 1000 * m.max(1))?;
    let top = e.eigenvalues.iter().copied().fold(0.0_f64, f64::max);
    let keep: Vec<usize> = (0..m).filter(|&i| e.eigenvalues[i] > 1e-12 * top).collect();
    if keep.len() < k {
        return None;
    }
    // Basis V Λ^{-1/2}: K-orthonormal combinations of the scaled columns.
    let mut basis = DMatrix::<f64>::zeros(m, keep.len());
    for (c, &i) in keep.iter().enumerate() {
        let s = 1.0 / e.eigenvalues[i].sqrt();
        for r in 0..m {
            basis[(r, c)] = e.eigenvectors[(r, i)] * s;
        }
    }
    let t = &dm * &basis;
    let reduced = t.transpose() * &ms * &t;
    let r = SymmetricEigen::try_new(reduced, f64::EPSILON, 1000 * m.max(1))?;
    let mut order: Vec<usize> = (0..keep.len()).collect();
    order.sort_by(|&a, &b| r.eigenvalues[b].total_cmp(&r.eigenvalues[a]));
    let theta: Vec<f64> = order.iter().take(k).map(|&i| r.eigenvalues[i]).collect();
    if theta.iter().any(|t| t.is_nan() || *t <= 0.0) {
        return None;
    }
    let mut c = DMatrix::<f64>::zeros(m, k);
    for (col, &i) in order.iter().take(k).enumerate() {
        let y = &t * r.eigenvectors.column(i);
        for row in 0..m {
            c[(row, col)] = y[row];
        }
    }
    Some((theta, c))
}
