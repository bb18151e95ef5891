//! Linear statics and linear buckling on one sparse Cholesky factorization.
//!
//! **Statics**: `K u = f` with supported DOFs eliminated (no penalty), sparse LLᵀ (faer).
//!
//! **Buckling** (buckling.md §3): `(K + λ K_G) φ = 0`, K SPD, K_G from the pre-buckling
//! membrane forces. With μ = 1/λ this is `(−K_G) φ = μ K φ`; the operator `W = K⁻¹(−K_G)` is
//! self-adjoint in the K-inner product, so a Lanczos iteration in that inner product (one
//! solve with the **same** factor of K per step, full re-orthogonalisation) gives Ritz values
//! at both ends of the spectrum. The wanted factors are the largest positive μ (smallest
//! positive λ); negative μ are tension modes (buckling under the reversed load) and are
//! skipped. Hand-written because no Rust crate solves a sparse generalized symmetric-definite
//! eigenproblem, and faer's Krylov–Schur targets the largest |μ| (tension modes could crowd
//! out the positive end) and would need separate triangular solves.
//!
//! **Sturm check**: LDLᵀ of `K + σ K_G` (same symbolic analysis); its number of negative
//! pivots equals the number of factors in (0, σ) (Sylvester inertia, K SPD). If it exceeds the
//! factors found (a repeated or missed eigenvalue), Lanczos is restarted K-orthogonal to the
//! modes already found until the counts agree.

use crate::clock::Instant;

use faer::Mat;
use nalgebra::{DMatrix, SymmetricEigen};

use crate::assembly::{DofMap, Pattern, assemble, element_dofs, geometries, load_vector};
use crate::element::{Resultants, ShellElement, TriangleGeometry};
use crate::error::{FeError, NodeDof};
use crate::factor::{Llt, LltFailure, Symbolic};
use crate::model::{ElementKind, NodalLoad, ShellModel};

/// A further load case of a buckling solve ([`BucklingSolver::buckling_with_cases`]), solved
/// with its factor of K.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadCase {
    /// Per triangle, whether its self-weight (`model.gravity`, its unit weight) is in the case;
    /// empty: no self-weight.
    pub weight: Vec<bool>,
    /// The case's nodal loads (in place of the model's).
    pub nodal_loads: Vec<NodalLoad>,
}

/// Results of a linear static analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticResult {
    /// Displacements per node `[ux, uy, uz, rx, ry, rz]` (global frame).
    pub displacements: Vec<[f64; 6]>,
    /// Stress resultants per element (element local frame, see [`ElementResult`]).
    pub elements: Vec<ElementResult>,
    /// Support reactions per node (zero where nothing is fixed), `[Fx, Fy, Fz, Mx, My, Mz]`.
    pub reactions: Vec<[f64; 6]>,
    /// Sum of the reaction forces (equals minus the sum of applied forces).
    pub reactions_sum: [f64; 3],
    /// Sum of applied forces (self-weight + nodal).
    pub load_sum: [f64; 3],
    /// Largest translation magnitude over the nodes (m).
    pub max_displacement: f64,
    /// Number of free DOFs.
    pub n_free_dofs: usize,
}

/// Resultants of one element plus its local frame (rows e1, e2, e3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementResult {
    /// Local frame: x along the first edge, z the facet normal.
    pub frame: [[f64; 3]; 3],
    /// Membrane forces and bending moments.
    pub resultants: Resultants,
    /// Thickness (m), to turn resultants into stresses.
    pub thickness: f64,
}

impl ElementResult {
    /// Membrane (mid-surface) stresses `[σx, σy, τxy] = N/t` (Pa).
    pub fn membrane_stress(&self) -> [f64; 3] {
        self.resultants.membrane.map(|n| n / self.thickness)
    }
    /// Surface stresses at z = ±t/2 (`top` = +z side): `N/t ± 6M/t²` (Pa).
    pub fn surface_stress(&self, top: bool) -> [f64; 3] {
        let t = self.thickness;
        let s = if top { 1.0 } else { -1.0 };
        std::array::from_fn(|i| {
            self.resultants.membrane[i] / t + s * 6.0 * self.resultants.moment[i] / (t * t)
        })
    }
}

/// Options of the buckling solve.
#[derive(Debug, Clone, PartialEq)]
pub struct BucklingOptions {
    /// Number of lowest positive factors wanted (≥ 1).
    pub modes: usize,
    /// Relative residual of the Ritz pairs, ‖W y − μ y‖_K ≤ tol·|μ| (default 1e-10).
    pub tolerance: f64,
    /// Verify with a Sturm count that no lower factor was missed (default true; costs one
    /// extra LDLᵀ factorization).
    pub sturm_check: bool,
    /// Seed of the Lanczos start vector.
    pub seed: u64,
    /// Upper bound on Lanczos steps over all restarts (0 = automatic).
    pub max_steps: usize,
    /// Largest Lanczos basis before a restart (0 = automatic: ~320 MB of vectors, 30…300).
    pub max_basis: usize,
    /// Start the Lanczos iteration from this guess of mode 1 (per node `[ux, uy, uz, rx, ry,
    /// rz]`, any scale; supported DOFs are ignored) instead of a random vector, and test the
    /// Ritz pairs for convergence after every step. A good guess (e.g. the mode of the previous
    /// print state mapped onto this mesh) cuts the steps to a few; a bad one only costs steps,
    /// never accuracy: the stopping test is the same residual bound, and the guess is blended
    /// with the seeded random vector (0.1 % of its largest entry), so a guess that is another
    /// mode exactly still leads to mode 1. `None` (default): the seeded random start, tested
    /// every 5–10 steps.
    pub start: Option<Vec<[f64; 6]>>,
}

impl Default for BucklingOptions {
    fn default() -> Self {
        Self {
            modes: 3,
            tolerance: 1e-10,
            sturm_check: true,
            seed: 0x006b_6170_7065,
            max_steps: 0,
            max_basis: 0,
            start: None,
        }
    }
}

/// Result of the Sturm-sequence check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SturmCheck {
    /// Shift σ (slightly above the largest returned factor).
    pub sigma: f64,
    /// Negative pivots of LDLᵀ(K + σ K_G) = number of factors in (0, σ).
    pub negative_pivots: usize,
    /// Factors found ≤ σ (equal to `negative_pivots` on success; may exceed the number
    /// returned when a factor at the cut-off is repeated).
    pub found_below: usize,
}

/// Timings and sizes, for benchmarks and logs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolveStats {
    /// Free DOFs.
    pub n_free_dofs: usize,
    /// Stored entries of the lower triangle of K.
    pub nnz_k: usize,
    /// Stored entries of the Cholesky factor.
    pub nnz_l: usize,
    /// Lanczos steps (= applications of K⁻¹(−K_G)).
    pub operator_applications: usize,
    /// Seconds: symbolic analysis (0 when reused).
    pub t_symbolic: f64,
    /// Seconds: assembly of K and the load.
    pub t_assembly: f64,
    /// Seconds: numeric factorization of K and the static solve.
    pub t_factor: f64,
    /// Seconds: stress recovery and K_G assembly.
    pub t_geometric: f64,
    /// Seconds: Lanczos.
    pub t_eigen: f64,
    /// Seconds: Sturm check (LDLᵀ and any deflated restarts).
    pub t_sturm: f64,
}

/// Result of a linear buckling analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct BucklingResult {
    /// Lowest positive buckling load factors, ascending (may be fewer than requested if the
    /// load produces fewer compressive modes).
    pub factors: Vec<f64>,
    /// Mode shapes per factor, per node `[ux, uy, uz, rx, ry, rz]`, scaled to max |·| = 1.
    pub modes: Vec<Vec<[f64; 6]>>,
    /// ‖(K + λK_G)φ‖ / ‖Kφ‖ per mode.
    pub residuals: Vec<f64>,
    /// The Sturm check, if requested.
    pub sturm: Option<SturmCheck>,
    /// The pre-buckling static state.
    pub static_result: StaticResult,
    /// Sizes and timings.
    pub stats: SolveStats,
}

/// A solver bound to one mesh + support pattern. It caches the DOF numbering, the sparsity
/// pattern and the symbolic Cholesky analysis (AMD ordering), so models that differ only in
/// coordinates, thickness, material or loads (e.g. the print states of one vault mesh) skip
/// the symbolic step.
pub struct BucklingSolver {
    triangles: Vec<[usize; 3]>,
    fixed: Vec<[bool; 6]>,
    dofs: DofMap,
    pattern: Pattern,
    symbolic: Symbolic,
    element: Box<dyn ShellElement>,
    /// `Some` when the element came from `model.element` ([`BucklingSolver::new`]): later
    /// states must name the same element.
    kind: Option<ElementKind>,
    t_symbolic: f64,
}

impl std::fmt::Debug for BucklingSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BucklingSolver")
            .field("n_free_dofs", &self.dofs.n_free())
            .field("nnz_k", &self.pattern.nnz())
            .finish()
    }
}

/// Linear static analysis with `model.element` (default CST + DKT + drilling).
pub fn linear_static(model: &ShellModel) -> Result<StaticResult, FeError> {
    BucklingSolver::new(model)?.linear_static(model)
}

/// Linear buckling analysis with `model.element` (default CST + DKT + drilling).
pub fn buckling(model: &ShellModel, options: &BucklingOptions) -> Result<BucklingResult, FeError> {
    BucklingSolver::new(model)?.buckling(model, options)
}

struct StaticInternal<'a> {
    result: StaticResult,
    llt: Llt<'a>,
    kvals: Vec<f64>,
    geo: Vec<TriangleGeometry>,
}

impl BucklingSolver {
    /// Validate `model` and analyse its pattern; the element is `model.element` (default: the
    /// reference CST+DKT element). States solved later must have the same `element`
    /// (`PatternMismatch` otherwise).
    pub fn new(model: &ShellModel) -> Result<Self, FeError> {
        let mut s = Self::with_element(model, model.element.implementation())?;
        s.kind = Some(model.element);
        Ok(s)
    }

    /// As [`BucklingSolver::new`] with another element formulation (`model.element` is then
    /// not used).
    pub fn with_element(
        model: &ShellModel,
        element: Box<dyn ShellElement>,
    ) -> Result<Self, FeError> {
        Self::build(model, element, None)
    }

    /// As [`BucklingSolver::new`], eliminating the nodes in the order of `node_rank` (one rank
    /// per node of `model`, lowest first; a node's free DOFs together) instead of computing an
    /// AMD ordering: for a mesh nested in one already ordered (the print states of a cap, each
    /// the next one's mesh less its top row), the larger mesh's order restricted to this one
    /// ([`BucklingSolver::node_order`]). The factors are the same up to round-off (another
    /// elimination order); the fill may differ (docs/convergence.md, the `speed5` branch).
    pub fn with_node_order(model: &ShellModel, node_rank: &[usize]) -> Result<Self, FeError> {
        let mut s = Self::build(model, model.element.implementation(), Some(node_rank))?;
        s.kind = Some(model.element);
        Ok(s)
    }

    /// Every node's place in this solver's elimination order (its first free DOF's), for
    /// [`BucklingSolver::with_node_order`] on a nested mesh; `usize::MAX` for a node without
    /// free DOFs.
    pub fn node_order(&self) -> Vec<usize> {
        let mut rank = vec![usize::MAX; self.fixed.len()];
        let order = self
            .symbolic
            .order()
            .unwrap_or_else(|| (0..self.dofs.n_free()).collect());
        for (k, &i) in order.iter().enumerate() {
            if let Some(r) = self.dofs.free.get(i).and_then(|g| rank.get_mut(g / 6)) {
                *r = (*r).min(k);
            }
        }
        rank
    }

    fn build(
        model: &ShellModel,
        element: Box<dyn ShellElement>,
        node_rank: Option<&[usize]>,
    ) -> Result<Self, FeError> {
        model.validate()?;
        let t0 = Instant::now();
        let dofs = DofMap::new(model);
        if dofs.n_free() == 0 {
            return Err(FeError::NoFreeDofs);
        }
        let pattern = Pattern::new(model, &dofs);
        let order = match node_rank {
            None => None,
            Some(rank) => {
                if rank.len() != model.nodes.len() {
                    return Err(FeError::PatternMismatch {
                        reason: "a node order must rank every node of the model",
                    });
                }
                // Free DOFs by their node's rank, a node's DOFs together (a stable sort keeps
                // them in DOF order); the ranks need not be distinct or dense.
                let mut fwd: Vec<usize> = (0..dofs.n_free()).collect();
                fwd.sort_by_key(|&k| rank[dofs.free[k] / 6]);
                let mut inv = vec![0; fwd.len()];
                for (k, &i) in fwd.iter().enumerate() {
                    inv[i] = k;
                }
                Some((fwd, inv))
            }
        };
        let symbolic = Symbolic::ordered(
            &pattern,
            order.as_ref().map(|(f, i)| (f.as_slice(), i.as_slice())),
        )?;
        Ok(Self {
            triangles: model.triangles.clone(),
            fixed: model.fixed_mask(),
            dofs,
            pattern,
            symbolic,
            element,
            kind: None,
            t_symbolic: t0.elapsed().as_secs_f64(),
        })
    }

    /// Number of free DOFs.
    pub fn n_free_dofs(&self) -> usize {
        self.dofs.n_free()
    }

    fn check(&self, model: &ShellModel) -> Result<(), FeError> {
        model.validate()?;
        if model.triangles != self.triangles {
            return Err(FeError::PatternMismatch {
                reason: "different triangles",
            });
        }
        if model.fixed_mask() != self.fixed {
            return Err(FeError::PatternMismatch {
                reason: "different supports",
            });
        }
        if self.kind.is_some_and(|k| k != model.element) {
            return Err(FeError::PatternMismatch {
                reason: "different element",
            });
        }
        Ok(())
    }

    /// Linear static analysis of `model` (same mesh and supports as the solver's).
    pub fn linear_static(&self, model: &ShellModel) -> Result<StaticResult, FeError> {
        self.check(model)?;
        let mut stats = SolveStats::default();
        Ok(self.static_internal(model, &mut stats)?.result)
    }

    fn static_internal(
        &self,
        model: &ShellModel,
        stats: &mut SolveStats,
    ) -> Result<StaticInternal<'_>, FeError> {
        let t0 = Instant::now();
        let geo = geometries(model);
        let el = &*self.element;
        let alpha = model.drilling_alpha;
        let kvals = assemble(model, &self.dofs, &self.pattern, |e| {
            el.stiffness(&geo[e], model.thickness_of(e), &model.material_of(e), alpha)
        })?;
        let f = load_vector(model, &geo);
        stats.t_assembly = t0.elapsed().as_secs_f64();

        let t1 = Instant::now();
        let kdiag = self.diagonal(&kvals);
        let llt = match self.symbolic.llt(&self.pattern, &kvals) {
            Ok(l) => l,
            Err(LltFailure::NotPositive(idx)) => {
                return Err(self.mechanism(&kvals, &kdiag, idx));
            }
            Err(LltFailure::Other(e)) => return Err(e),
        };
        // LLᵀ can push a singular K through with round-off pivots; a pivot keeping less than
        // 1e-13 of its diagonal is far below any physical conditioning of a shell
        // (t/L = 1e-3 gives ~1e-9) and is treated as a mechanism.
        let (ratio, at) = llt.min_pivot_ratio(&kdiag);
        if ratio < 1e-13 {
            return Err(self.mechanism(&kvals, &kdiag, Some(at)));
        }
        stats.t_factor = t1.elapsed().as_secs_f64();
        let result = self.static_solve(model, &llt, &f, &geo, stats)?;
        Ok(StaticInternal {
            result,
            llt,
            kvals,
            geo,
        })
    }

    /// The static solution of `model` under the load vector `f` (all DOFs, as
    /// `load_vector`) with the factor `llt` of its K: displacements, resultants, reactions.
    /// `stats` gets the solve's time in `t_factor` and the recovery's in `t_geometric`.
    fn static_solve(
        &self,
        model: &ShellModel,
        llt: &Llt<'_>,
        f: &[f64],
        geo: &[TriangleGeometry],
        stats: &mut SolveStats,
    ) -> Result<StaticResult, FeError> {
        let t1 = Instant::now();
        let n = self.dofs.n_free();
        let el = &*self.element;
        let alpha = model.drilling_alpha;
        let mut u = Mat::<f64>::zeros(n, 1);
        for (i, &g) in self.dofs.free.iter().enumerate() {
            u[(i, 0)] = f[g];
        }
        llt.solve_in_place(u.as_mut())?;
        let mut disp = vec![[0.0; 6]; model.nodes.len()];
        for (i, &g) in self.dofs.free.iter().enumerate() {
            disp[g / 6][g % 6] = u[(i, 0)];
        }
        stats.t_factor += t1.elapsed().as_secs_f64();

        let t2 = Instant::now();
        let elements: Vec<ElementResult> = {
            use rayon::prelude::*;
            model
                .triangles
                .par_iter()
                .enumerate()
                .map(|(e, tri)| {
                    let ue: [f64; 18] = std::array::from_fn(|k| disp[tri[k / 6]][k % 6]);
                    let t = model.thickness_of(e);
                    ElementResult {
                        frame: geo[e].frame,
                        resultants: el.resultants(&geo[e], t, &model.material_of(e), &ue),
                        thickness: t,
                    }
                })
                .collect()
        };
        // Reactions R = K u − f on fixed DOFs; only elements touching a support contribute.
        let mut reactions = vec![[0.0; 6]; model.nodes.len()];
        let fixed_any: Vec<bool> = self.fixed.iter().map(|f| f.iter().any(|b| *b)).collect();
        for (e, tri) in model.triangles.iter().enumerate() {
            if !tri.iter().any(|&n| fixed_any[n]) {
                continue;
            }
            let ke = el.stiffness(&geo[e], model.thickness_of(e), &model.material_of(e), alpha);
            let ue = nalgebra::SVector::<f64, 18>::from_fn(|k, _| disp[tri[k / 6]][k % 6]);
            let fe = ke * ue;
            for (k, g) in element_dofs(tri).iter().enumerate() {
                if self.dofs.map[*g] == usize::MAX {
                    reactions[g / 6][g % 6] += fe[k];
                }
            }
        }
        for (node, fx) in self.fixed.iter().enumerate() {
            for d in 0..6 {
                if fx[d] {
                    reactions[node][d] -= f[6 * node + d];
                } else {
                    reactions[node][d] = 0.0;
                }
            }
        }
        let mut reactions_sum = [0.0; 3];
        let mut load_sum = [0.0; 3];
        for node in 0..model.nodes.len() {
            for c in 0..3 {
                reactions_sum[c] += reactions[node][c];
                load_sum[c] += f[6 * node + c];
            }
        }
        let max_displacement = disp
            .iter()
            .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
            .fold(0.0, f64::max);
        stats.t_geometric += t2.elapsed().as_secs_f64();
        Ok(StaticResult {
            displacements: disp,
            elements,
            reactions,
            reactions_sum,
            load_sum,
            max_displacement,
            n_free_dofs: n,
        })
    }

    fn diagonal(&self, vals: &[f64]) -> Vec<f64> {
        let p = &self.pattern;
        (0..p.n)
            .map(|j| {
                (p.col_ptr[j]..p.col_ptr[j + 1])
                    .find(|&q| p.row_idx[q] == j)
                    .map_or(0.0, |q| vals[q])
            })
            .collect()
    }

    /// Diagnose a singular K: inverse iteration on `(K + δ D, D)` (D = diag K, δ = 1e-10)
    /// converges to the zero-energy mode; the DOFs carrying it are reported.
    fn mechanism(&self, kvals: &[f64], kdiag: &[f64], pivot: Option<usize>) -> FeError {
        let fallback = || FeError::Mechanism {
            free_dofs: pivot
                .and_then(|i| self.dofs.free.get(i))
                .map(|&g| NodeDof {
                    node: g / 6,
                    dof: g % 6,
                })
                .into_iter()
                .collect(),
        };
        let p = &self.pattern;
        let mut reg = kvals.to_vec();
        for j in 0..p.n {
            for q in p.col_ptr[j]..p.col_ptr[j + 1] {
                if p.row_idx[q] == j {
                    reg[q] += 1e-10 * kdiag[j].abs().max(f64::MIN_POSITIVE);
                }
            }
        }
        let Ok(llt) = self.symbolic.llt(&self.pattern, &reg) else {
            return fallback();
        };
        let n = p.n;
        let mut x = Mat::<f64>::from_fn(n, 1, |i, _| random_unit(0x5eed, i as u64));
        for _ in 0..4 {
            for i in 0..n {
                x[(i, 0)] *= kdiag[i];
            }
            if llt.solve_in_place(x.as_mut()).is_err() {
                return fallback();
            }
            let nrm = x.norm_l2();
            if !(nrm.is_finite() && nrm > 0.0) {
                return fallback();
            }
            x /= faer::Scale(nrm);
        }
        let xs: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
        let mut kx = vec![0.0; n];
        p.sym_matvec(kvals, &xs, &mut kx);
        let num: f64 = xs.iter().zip(&kx).map(|(a, b)| a * b).sum();
        let den: f64 = xs.iter().zip(kdiag).map(|(a, d)| a * a * d).sum();
        if !(den > 0.0 && num / den < 1e-8) {
            return fallback();
        }
        let amp: Vec<f64> = xs
            .iter()
            .zip(kdiag)
            .map(|(a, d)| a.abs() * d.abs().sqrt())
            .collect();
        let max = amp.iter().copied().fold(0.0, f64::max);
        let mut idx: Vec<usize> = (0..n).filter(|&i| amp[i] > 0.1 * max).collect();
        idx.sort_by(|&a, &b| amp[b].total_cmp(&amp[a]));
        FeError::Mechanism {
            free_dofs: idx
                .iter()
                .map(|&i| {
                    let g = self.dofs.free[i];
                    NodeDof {
                        node: g / 6,
                        dof: g % 6,
                    }
                })
                .collect(),
        }
    }

    /// Linear buckling analysis of `model` (same mesh and supports as the solver's).
    pub fn buckling(
        &self,
        model: &ShellModel,
        options: &BucklingOptions,
    ) -> Result<BucklingResult, FeError> {
        self.buckling_cases(model, options, &|_| Vec::new())
            .map(|(r, _)| r)
    }

    /// [`BucklingSolver::buckling`] and a second load case solved with the same factor of K:
    /// the self-weight of the triangles `e` with `weight[e]` alone (plus `model`'s nodal loads).
    /// The result is exactly [`BucklingSolver::linear_static`] of `model` with the other
    /// triangles' unit weight set to zero (K does not depend on the unit weight), for one
    /// triangular solve instead of a second factorization: e.g. the weight a print state adds,
    /// whose static increment the as-printed shape sums (docs/as-printed.md).
    ///
    /// # Errors
    /// As [`BucklingSolver::buckling_with_cases`].
    pub fn buckling_with_weight_case(
        &self,
        model: &ShellModel,
        options: &BucklingOptions,
        weight: &[bool],
    ) -> Result<(BucklingResult, StaticResult), FeError> {
        let case = LoadCase {
            weight: weight.to_vec(),
            nodal_loads: model.nodal_loads.clone(),
        };
        let (r, mut cases) =
            self.buckling_with_cases(model, options, std::slice::from_ref(&case))?;
        cases.pop().map(|c| (r, c)).ok_or(FeError::Numerical {
            stage: "weight case",
            detail: "the second load case was not solved".into(),
        })
    }

    /// [`BucklingSolver::buckling`] and further load cases solved with the same factor of K,
    /// one triangular solve each instead of a factorization: case `i`'s result is exactly
    /// [`BucklingSolver::linear_static`] of `model` with the unit weight of the triangles not
    /// in `cases[i].weight` set to zero and `cases[i].nodal_loads` for the model's (K depends
    /// on neither). E.g. the weight a print state adds (docs/as-printed.md) and the unbalanced
    /// forces a corrugated state's shell carries (docs/corrugation.md).
    ///
    /// # Errors
    /// As [`BucklingSolver::buckling`]; a case's `weight` must have one entry per triangle (or
    /// none), its nodal loads must name nodes of the model with finite values.
    pub fn buckling_with_cases(
        &self,
        model: &ShellModel,
        options: &BucklingOptions,
        cases: &[LoadCase],
    ) -> Result<(BucklingResult, Vec<StaticResult>), FeError> {
        for c in cases {
            if !c.weight.is_empty() && c.weight.len() != model.triangles.len() {
                return Err(FeError::BadOption {
                    field: "weight (one entry per triangle)",
                    value: c.weight.len() as f64,
                    allowed: "none, or as many entries as the model has triangles",
                });
            }
        }
        let (r, solved) = self.buckling_cases(model, options, &|_| cases.to_vec())?;
        if solved.len() != cases.len() {
            return Err(FeError::Numerical {
                stage: "load cases",
                detail: "a load case was not solved".into(),
            });
        }
        Ok((r, solved))
    }

    /// [`BucklingSolver::buckling_with_cases`] with the further load cases made from the
    /// pre-buckling static solution by `cases`, and solved with the same factor of K: e.g. the
    /// loads −(∂K/∂p)·u of the displacement sensitivities ∂u/∂p a buckling factor's exact
    /// derivative needs (kappe's docs/reliability.md), one triangular solve each instead of a
    /// factorization.
    ///
    /// # Errors
    /// As [`BucklingSolver::buckling_with_cases`].
    pub fn buckling_with_derived_cases(
        &self,
        model: &ShellModel,
        options: &BucklingOptions,
        cases: &dyn Fn(&StaticResult) -> Vec<LoadCase>,
    ) -> Result<(BucklingResult, Vec<StaticResult>), FeError> {
        self.buckling_cases(model, options, cases)
    }

    fn buckling_cases(
        &self,
        model: &ShellModel,
        options: &BucklingOptions,
        cases: &dyn Fn(&StaticResult) -> Vec<LoadCase>,
    ) -> Result<(BucklingResult, Vec<StaticResult>), FeError> {
        self.check(model)?;
        if options.modes == 0 {
            return Err(FeError::BadOption {
                field: "modes",
                value: 0.0,
                allowed: ">= 1",
            });
        }
        if !(options.tolerance > 0.0 && options.tolerance < 1e-2) {
            return Err(FeError::BadOption {
                field: "tolerance",
                value: options.tolerance,
                allowed: "0 < tolerance < 1e-2",
            });
        }
        let mut stats = SolveStats {
            n_free_dofs: self.dofs.n_free(),
            nnz_k: self.pattern.nnz(),
            nnz_l: self.symbolic.nnz_l(),
            t_symbolic: self.t_symbolic,
            ..SolveStats::default()
        };
        let StaticInternal {
            result: static_result,
            llt,
            kvals,
            geo,
        } = self.static_internal(model, &mut stats)?;
        let cases = cases(&static_result);
        let mut solved = Vec::with_capacity(cases.len());
        for c in &cases {
            if !c.weight.is_empty() && c.weight.len() != model.triangles.len() {
                return Err(FeError::BadOption {
                    field: "weight (one entry per triangle)",
                    value: c.weight.len() as f64,
                    allowed: "none, or as many entries as the model has triangles",
                });
            }
            let mut only = model.clone();
            only.materials = (0..model.triangles.len())
                .map(|e| {
                    let mut m = model.material_of(e);
                    if !c.weight.get(e).copied().unwrap_or(false) {
                        m.unit_weight = 0.0;
                    }
                    m
                })
                .collect();
            only.nodal_loads.clone_from(&c.nodal_loads);
            // The loads are validated as the model's own would be.
            only.validate()?;
            let f = load_vector(&only, &geo);
            solved.push(self.static_solve(&only, &llt, &f, &geo, &mut stats)?);
        }
        let t0 = Instant::now();
        let el = &*self.element;
        let elements = &static_result.elements;
        let kg = assemble(model, &self.dofs, &self.pattern, |e| {
            el.geometric_stiffness(
                &geo[e],
                model.thickness_of(e),
                &model.material_of(e),
                &elements[e].resultants.membrane,
            )
        })?;
        drop(geo);
        stats.t_geometric += t0.elapsed().as_secs_f64();

        let t1 = Instant::now();
        let n = self.dofs.n_free();
        let k = options.modes.min(n);
        let max_steps = if options.max_steps == 0 {
            (20 * k + 400).min(20 * n + 20)
        } else {
            options.max_steps
        };
        let ops = Ops {
            pattern: &self.pattern,
            k: &kvals,
            kg: &kg,
        };
        let guess = options
            .start
            .as_ref()
            .map(|g| start_vector(&self.dofs, g, options.seed));
        let mut found = lanczos(&ops, &llt, k, options, guess, &[], max_steps, &mut stats)?;
        // The factor of K is released before the Sturm LDLᵀ so the two never coexist (peak
        // memory at 10⁵ nodes); a deflated restart re-factors K, which is rarely needed.
        drop(llt);
        stats.t_eigen = t1.elapsed().as_secs_f64();

        let t2 = Instant::now();
        let mut sturm = None;
        if options.sturm_check && !found.is_empty() {
            // σ just above the largest returned factor; the count at this fixed σ is computed
            // once, and missing factors below it are searched until the counts agree.
            let lam_max = found.iter().map(|p| p.lambda).fold(0.0, f64::max);
            let (sigma, neg) = self.sturm_count(&kvals, &kg, lam_max * (1.0 + 1e-4))?;
            let mut rounds = 0;
            loop {
                let below = found.iter().filter(|p| p.lambda <= sigma).count();
                sturm = Some(SturmCheck {
                    sigma,
                    negative_pivots: neg,
                    found_below: below,
                });
                if neg == below {
                    break;
                }
                rounds += 1;
                if neg < below || rounds > 3 {
                    return Err(FeError::SturmMismatch {
                        sigma,
                        negative: neg,
                        found: below,
                    });
                }
                // Deflated restart: the Krylov space is kept K-orthogonal to the found modes,
                // so it converges to the missed (e.g. repeated) factors.
                let locked: Vec<Vec<f64>> = found.iter().map(|p| p.vector.clone()).collect();
                let llt = match self.symbolic.llt(&self.pattern, &kvals) {
                    Ok(l) => l,
                    Err(LltFailure::NotPositive(idx)) => {
                        return Err(self.mechanism(&kvals, &self.diagonal(&kvals), idx));
                    }
                    Err(LltFailure::Other(e)) => return Err(e),
                };
                let extra = lanczos(
                    &ops,
                    &llt,
                    neg - below,
                    options,
                    None,
                    &locked,
                    max_steps,
                    &mut stats,
                )?;
                if extra.is_empty() {
                    return Err(FeError::SturmMismatch {
                        sigma,
                        negative: neg,
                        found: below,
                    });
                }
                found.extend(extra);
                found.sort_by(|a, b| a.lambda.total_cmp(&b.lambda));
            }
            found.truncate(k);
        }
        stats.t_sturm = t2.elapsed().as_secs_f64();

        let mut factors = Vec::new();
        let mut modes = Vec::new();
        let mut residuals = Vec::new();
        for p in found.iter().take(k) {
            factors.push(p.lambda);
            residuals.push(ops.pencil_residual(p.lambda, &p.vector));
            modes.push(mode_shape(&self.dofs, model.nodes.len(), &p.vector));
        }
        Ok((
            BucklingResult {
                factors,
                modes,
                residuals,
                sturm,
                static_result,
                stats,
            },
            solved,
        ))
    }

    /// Sturm count at σ (perturbed slightly if a pivot is exactly zero).
    fn sturm_count(&self, k: &[f64], kg: &[f64], sigma: f64) -> Result<(f64, usize), FeError> {
        let mut s = sigma;
        for _ in 0..4 {
            let vals: Vec<f64> = k.iter().zip(kg).map(|(a, b)| a + s * b).collect();
            if let Some(neg) = self.symbolic.negative_pivots(&self.pattern, &vals)? {
                return Ok((s, neg));
            }
            s *= 1.0 + 1e-5;
        }
        Err(FeError::Numerical {
            stage: "Sturm check",
            detail: format!("LDLᵀ of K + σK_G hit zero pivots near σ = {sigma:e}"),
        })
    }

    /// Sturm count of `K + σ K_G` for a given σ: the number of buckling factors in (0, σ).
    /// Exposed for verification (acceptance check A8).
    pub fn count_factors_below(&self, model: &ShellModel, sigma: f64) -> Result<usize, FeError> {
        self.check(model)?;
        let mut stats = SolveStats::default();
        let st = self.static_internal(model, &mut stats)?;
        let el = &*self.element;
        let kg = assemble(model, &self.dofs, &self.pattern, |e| {
            el.geometric_stiffness(
                &st.geo[e],
                model.thickness_of(e),
                &model.material_of(e),
                &st.result.elements[e].resultants.membrane,
            )
        })?;
        Ok(self.sturm_count(&st.kvals, &kg, sigma)?.1)
    }

    /// Reduced K and K_G of `model` as dense lower-triangle-complete matrices (row-major
    /// n×n), for test oracles on small models.
    pub fn dense_matrices(
        &self,
        model: &ShellModel,
    ) -> Result<(usize, Vec<f64>, Vec<f64>), FeError> {
        self.check(model)?;
        let mut stats = SolveStats::default();
        let st = self.static_internal(model, &mut stats)?;
        let el = &*self.element;
        let kg = assemble(model, &self.dofs, &self.pattern, |e| {
            el.geometric_stiffness(
                &st.geo[e],
                model.thickness_of(e),
                &model.material_of(e),
                &st.result.elements[e].resultants.membrane,
            )
        })?;
        let n = self.pattern.n;
        let mut kd = vec![0.0; n * n];
        let mut gd = vec![0.0; n * n];
        for j in 0..n {
            for q in self.pattern.col_ptr[j]..self.pattern.col_ptr[j + 1] {
                let i = self.pattern.row_idx[q];
                kd[i * n + j] = st.kvals[q];
                kd[j * n + i] = st.kvals[q];
                gd[i * n + j] = kg[q];
                gd[j * n + i] = kg[q];
            }
        }
        Ok((n, kd, gd))
    }
}

/// The operators of the pencil on the free DOFs.
pub(crate) struct Ops<'a> {
    pub(crate) pattern: &'a Pattern,
    pub(crate) k: &'a [f64],
    pub(crate) kg: &'a [f64],
}

impl Ops<'_> {
    pub(crate) fn k_mul(&self, x: &[f64], y: &mut [f64]) {
        self.pattern.sym_matvec(self.k, x, y);
    }
    pub(crate) fn kg_mul(&self, x: &[f64], y: &mut [f64]) {
        self.pattern.sym_matvec(self.kg, x, y);
    }
    fn pencil_residual(&self, lambda: f64, phi: &[f64]) -> f64 {
        let n = phi.len();
        let mut kx = vec![0.0; n];
        let mut gx = vec![0.0; n];
        self.k_mul(phi, &mut kx);
        self.kg_mul(phi, &mut gx);
        let r: f64 = kx
            .iter()
            .zip(&gx)
            .map(|(a, b)| (a + lambda * b).powi(2))
            .sum::<f64>()
            .sqrt();
        let d: f64 = kx.iter().map(|a| a * a).sum::<f64>().sqrt();
        if d > 0.0 { r / d } else { f64::INFINITY }
    }
}

/// A converged eigenpair: λ and the K-normalised vector on the free DOFs.
pub(crate) struct Pair {
    pub(crate) lambda: f64,
    pub(crate) vector: Vec<f64>,
}

/// Size of the seeded random part of a warm start, relative to the guess's largest entry. It is
/// far above the residual tolerances in use (the default 1e-10, Kappe's 1e-8), so a guess that
/// is exactly another mode cannot pass the stopping test at the first step, and from the second
/// step on Lanczos carries the normalised random direction (which holds every mode) at full
/// weight (`warm_start_on_mode_two_still_finds_mode_one`). Small, so the guess keeps most of its
/// saving: on a 4.8 m cap's 544 states 1e-3 costs 6 % more Lanczos time than no noise, 1e-1 12 %.
const WARM_START_NOISE: f64 = 1e-3;

/// A vector on the free DOFs `dofs` as a mode per node (`n_nodes` of them), scaled so that its
/// largest entry is +1.
pub(crate) fn mode_shape(dofs: &DofMap, n_nodes: usize, vector: &[f64]) -> Vec<[f64; 6]> {
    let mut shape = vec![[0.0; 6]; n_nodes];
    let scale = vector
        .iter()
        .copied()
        .fold(0.0_f64, |m, v| if v.abs() > m.abs() { v } else { m });
    let scale = if scale == 0.0 { 1.0 } else { scale };
    for (i, &g) in dofs.free.iter().enumerate() {
        if let (Some(s), Some(v)) = (shape.get_mut(g / 6), vector.get(i)) {
            s[g % 6] = v / scale;
        }
    }
    shape
}

/// A mode guess per node (`[ux, uy, uz, rx, ry, rz]`) as a Lanczos start on the free DOFs
/// `dofs`, blended with the seeded random vector. The guess alone can lack mode 1 entirely (the
/// previous state's mode may be this state's second, or of another symmetry): the seeded random
/// part keeps every mode in the Krylov space, so the top Ritz pair cannot converge to a higher
/// mode first.
pub(crate) fn start_vector(dofs: &DofMap, g: &[[f64; 6]], seed: u64) -> Vec<f64> {
    let mut v: Vec<f64> = dofs
        .free
        .iter()
        .map(|&d| g.get(d / 6).map_or(0.0, |v| v[d % 6]))
        .collect();
    let scale = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if scale > 0.0 {
        for (i, x) in v.iter_mut().enumerate() {
            *x += scale * WARM_START_NOISE * random_unit(seed ^ 0x5eed, i as u64);
        }
    }
    v
}

/// Uniform pseudo-random number in [−1, 1] from (seed, i) (SplitMix64 finaliser), so the start
/// vector is reproducible without a generator dependency.
pub(crate) fn random_unit(seed: u64, i: u64) -> f64 {
    let mut z = seed
        .wrapping_add(0x9e37_79b9_7f4a_7c15)
        .wrapping_add(i.wrapping_mul(0xbf58_476d_1ce4_e5b9));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `r ← r − Σ (bᵢᵀ K r) bᵢ` over the K-orthonormal `basis`, twice (CGS2), given `kr = K r` and
/// `kbasis = K·basis`; `kr` is updated alongside, so no K product is needed. Returns ‖r‖_K.
fn k_orthogonalize(basis: &[&[f64]], kbasis: &[&[f64]], r: &mut [f64], kr: &mut [f64]) -> f64 {
    for _ in 0..2 {
        let c: Vec<f64> = kbasis.iter().map(|z| dot(z, r)).collect();
        for ((b, z), ci) in basis.iter().zip(kbasis).zip(&c) {
            for (ri, bi) in r.iter_mut().zip(b.iter()) {
                *ri -= ci * bi;
            }
            for (ki, zi) in kr.iter_mut().zip(z.iter()) {
                *ki -= ci * zi;
            }
        }
    }
    dot(r, kr).max(0.0).sqrt()
}

/// Lanczos in the K-inner product on `W = K⁻¹(−K_G)` with full re-orthogonalisation and
/// explicit restarts (locking converged pairs). Returns up to `want` pairs with the largest
/// positive μ = 1/λ, K-orthogonal to `locked_in`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn lanczos(
    ops: &Ops<'_>,
    llt: &Llt<'_>,
    want: usize,
    options: &BucklingOptions,
    guess: Option<Vec<f64>>,
    locked_in: &[Vec<f64>],
    max_steps: usize,
    stats: &mut SolveStats,
) -> Result<Vec<Pair>, FeError> {
    let n = ops.pattern.n;
    // Memory cap on the basis Q and K·Q: ~320 MB, between 30 and 300 vectors each.
    let m_cap = if options.max_basis == 0 {
        (20_000_000 / n.max(1)).clamp(30, 300)
    } else {
        options.max_basis.max(want + 2)
    }
    .min(n);
    let mut converged: Vec<Pair> = Vec::new();
    let mut steps = 0usize;
    // A warm start (mode guess) is one operator application away from range(W), like the
    // random start; a restart vector is already a Ritz combination.
    let mut guess: Option<Vec<f64>> = guess.filter(|g| g.len() == n && g.iter().any(|v| *v != 0.0));
    let warm = guess.is_some();
    let mut start: Option<Vec<f64>> = None;
    let mut restart = 0u64;
    let mut kr = vec![0.0; n];
    let mut tmp = vec![0.0; n];
    loop {
        let locked: Vec<Vec<f64>> = locked_in
            .iter()
            .cloned()
            .chain(converged.iter().map(|p| p.vector.clone()))
            .collect();
        if locked.len() >= n {
            break;
        }
        let locked_k: Vec<Vec<f64>> = locked
            .iter()
            .map(|v| {
                let mut z = vec![0.0; n];
                ops.k_mul(v, &mut z);
                z
            })
            .collect();
        let m_max = m_cap.min(n - locked.len());
        // Start vector: W applied to a random (or restart) vector, so it lies in range(W).
        let mut q: Vec<Vec<f64>> = Vec::with_capacity(m_max + 1);
        let mut z: Vec<Vec<f64>> = Vec::with_capacity(m_max + 1);
        let mut alpha: Vec<f64> = Vec::new();
        let mut beta: Vec<f64> = Vec::new();
        let x0: Vec<f64> = match start.take() {
            Some(v) => {
                ops.k_mul(&v, &mut kr);
                v
            }
            None => {
                let x: Vec<f64> = match guess.take() {
                    Some(g) => g,
                    None => (0..n)
                        .map(|i| random_unit(options.seed.wrapping_add(restart), i as u64))
                        .collect(),
                };
                let mut y = vec![0.0; n];
                ops.kg_mul(&x, &mut y);
                y.iter_mut().for_each(|v| *v = -*v);
                let mut m = Mat::<f64>::from_fn(n, 1, |i, _| y[i]);
                llt.solve_in_place(m.as_mut())?;
                stats.operator_applications += 1;
                kr.copy_from_slice(&y);
                (0..n).map(|i| m[(i, 0)]).collect()
            }
        };
        let mut r = x0;
        let lref: Vec<&[f64]> = locked.iter().map(|v| v.as_slice()).collect();
        let lkref: Vec<&[f64]> = locked_k.iter().map(|v| v.as_slice()).collect();
        let mut nr = k_orthogonalize(&lref, &lkref, &mut r, &mut kr);
        if !(nr.is_finite() && nr > 0.0) {
            // The random vector had no component outside the locked space / null space.
            restart += 1;
            if restart > 3 {
                break;
            }
            continue;
        }
        let mut result_pairs: Option<Vec<(f64, Vec<f64>)>> = None;
        let mut check_every = if warm { 1 } else { 5 };
        loop {
            r.iter_mut().for_each(|v| *v /= nr);
            q.push(std::mem::take(&mut r));
            z.push(kr.iter().map(|v| v / nr).collect());
            let j = q.len() - 1;
            // a = −K_G q_j ; r = K⁻¹ a ; α = q_jᵀ a
            ops.kg_mul(&q[j], &mut tmp);
            tmp.iter_mut().for_each(|v| *v = -*v);
            alpha.push(dot(&q[j], &tmp));
            let mut m = Mat::<f64>::from_fn(n, 1, |i, _| tmp[i]);
            llt.solve_in_place(m.as_mut())?;
            stats.operator_applications += 1;
            steps += 1;
            r = (0..n).map(|i| m[(i, 0)]).collect();
            // K r = a exactly, carried through the orthogonalisation.
            kr.copy_from_slice(&tmp);
            let basis: Vec<&[f64]> = lref
                .iter()
                .copied()
                .chain(q.iter().map(|v| v.as_slice()))
                .collect();
            let kbasis: Vec<&[f64]> = lkref
                .iter()
                .copied()
                .chain(z.iter().map(|v| v.as_slice()))
                .collect();
            nr = k_orthogonalize(&basis, &kbasis, &mut r, &mut kr);
            let dim = q.len();
            let exhausted = dim >= m_max || steps >= max_steps;
            let scale = alpha.iter().map(|a| a.abs()).fold(0.0, f64::max);
            let breakdown = nr.is_nan() || nr <= 1e-12 * scale.max(f64::MIN_POSITIVE);
            if exhausted || breakdown || (dim >= want.min(m_max) && dim.is_multiple_of(check_every))
            {
                let Some((theta, s)) = tridiag_eigen(&alpha, &beta) else {
                    return Err(FeError::NoConvergence {
                        iterations: steps,
                        detail: "the Lanczos tridiagonal eigenproblem failed (non-finite entries)"
                            .into(),
                    });
                };
                // Positive Ritz values, largest first; values below 1e-10 of the spectral
                // radius are null-space round-off, not compressive modes.
                let radius = theta.iter().map(|t| t.abs()).fold(0.0, f64::max);
                let mut idx: Vec<usize> = (0..dim).filter(|&i| theta[i] > 1e-10 * radius).collect();
                idx.sort_by(|&a, &b| theta[b].total_cmp(&theta[a]));
                let need = want - converged.len();
                let bnd = if breakdown { 0.0 } else { nr };
                let ok = |i: usize| bnd * s[(dim - 1, i)].abs() <= options.tolerance * theta[i];
                let top: Vec<usize> = idx.iter().copied().take(need).collect();
                let all_ok = !top.is_empty() && top.iter().all(|&i| ok(i));
                let complete = all_ok && top.len() == need;
                if complete || exhausted || breakdown {
                    // Lock the leading run of converged Ritz pairs.
                    let mut pairs = Vec::new();
                    for &i in &top {
                        if !ok(i) {
                            break;
                        }
                        pairs.push((theta[i], ritz_vector(&q, &s, i)));
                    }
                    // Restart vector: the best unconverged Ritz vectors combined.
                    if !complete {
                        let rest: Vec<usize> = top.iter().copied().skip(pairs.len()).collect();
                        if !rest.is_empty() {
                            let mut v = vec![0.0; n];
                            for &i in &rest {
                                let y = ritz_vector(&q, &s, i);
                                v.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
                            }
                            start = Some(v);
                        }
                    }
                    result_pairs = Some(pairs);
                    break;
                }
                if !warm {
                    check_every = if dim < 40 { 5 } else { 10 };
                }
            }
            if breakdown {
                break;
            }
            beta.push(nr);
        }
        let pairs = result_pairs.unwrap_or_default();
        let n_new = pairs.len();
        for (mu, v) in pairs {
            converged.push(Pair {
                lambda: 1.0 / mu,
                vector: v,
            });
        }
        if converged.len() >= want {
            break;
        }
        if steps >= max_steps {
            if converged.is_empty() {
                return Err(FeError::NoConvergence {
                    iterations: steps,
                    detail: format!(
                        "no positive buckling factor converged to a relative residual of {:e}",
                        options.tolerance
                    ),
                });
            }
            break;
        }
        if n_new == 0 && start.is_none() {
            // Krylov space exhausted with no further positive Ritz values: the load has fewer
            // compressive modes than requested.
            break;
        }
        restart += 1;
    }
    converged.sort_by(|a, b| a.lambda.total_cmp(&b.lambda));
    Ok(converged)
}

/// Eigen-decomposition of the symmetric tridiagonal matrix (α on the diagonal, β below).
fn tridiag_eigen(alpha: &[f64], beta: &[f64]) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let m = alpha.len();
    let t = DMatrix::from_fn(m, m, |i, j| {
        if i == j {
            alpha[i]
        } else if i == j + 1 {
            beta[j]
        } else if j == i + 1 {
            beta[i]
        } else {
            0.0
        }
    });
    // Bounded iterations: non-finite input (which validation should exclude) must end in an
    // error, not an endless QR sweep.
    let e = SymmetricEigen::try_new(t, f64::EPSILON, 1000 * m.max(1))?;
    Some((e.eigenvalues.iter().copied().collect(), e.eigenvectors))
}

/// Ritz vector `Q s_i` (K-normalised since Q is K-orthonormal and s_i has unit norm).
fn ritz_vector(q: &[Vec<f64>], s: &DMatrix<f64>, i: usize) -> Vec<f64> {
    let n = q.first().map_or(0, Vec::len);
    let mut v = vec![0.0; n];
    for (j, qj) in q.iter().enumerate() {
        let c = s[(j, i)];
        v.iter_mut().zip(qj).for_each(|(a, b)| *a += c * b);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Material, Support};

    /// A clamped vertical strip under self-weight (the crate's doc example, finer).
    fn strip() -> ShellModel {
        let (h, b, ny) = (1.0, 0.1, 24);
        let mut nodes = Vec::new();
        for j in 0..=ny {
            for x in [0.0, b / 2.0, b] {
                nodes.push([x, 0.0, h * j as f64 / ny as f64]);
            }
        }
        let mut tris = Vec::new();
        for j in 0..ny {
            for i in 0..2 {
                let a = 3 * j + i;
                tris.push([a, a + 1, a + 4]);
                tris.push([a, a + 4, a + 3]);
            }
        }
        let mat = Material {
            youngs_modulus: 1e6,
            poisson_ratio: 0.0,
            unit_weight: 2e4,
        };
        let mut m = ShellModel::new(nodes, tris, 0.01, mat);
        m.supports = (0..3).map(Support::clamped).collect();
        m
    }

    /// A given node order is another elimination order of the same matrix: the same factor up
    /// to round-off, whatever the order's quality. The barrel vault's nodes in reverse, and a
    /// larger vault's AMD order restricted to a nested one (the print states' use), against each
    /// model's own AMD.
    #[test]
    fn a_given_node_order_gives_the_same_factor() {
        let opts = BucklingOptions {
            modes: 1,
            tolerance: 1e-8,
            sturm_check: false,
            ..Default::default()
        };
        let small = crate::generate::barrel_vault(12, 6);
        let amd = BucklingSolver::new(&small).unwrap();
        let reference = amd.buckling(&small, &opts).unwrap().factors[0];
        let reverse: Vec<usize> = (0..small.nodes.len()).rev().collect();
        // The larger vault (n_len 12) has the small one's nodes first (row-major in y), so its
        // order restricted to them is an order of the small vault.
        let large = crate::generate::barrel_vault(12, 12);
        let restricted: Vec<usize> =
            BucklingSolver::new(&large).unwrap().node_order()[..small.nodes.len()].to_vec();
        for rank in [&reverse, &restricted] {
            let s = BucklingSolver::with_node_order(&small, rank).unwrap();
            assert_eq!(s.n_free_dofs(), amd.n_free_dofs());
            // The order was used: nodes with free DOFs are eliminated in the given rank order.
            let used = s.node_order();
            let mut free: Vec<usize> = (0..small.nodes.len())
                .filter(|&n| used[n] != usize::MAX)
                .collect();
            free.sort_by_key(|&n| rank[n]);
            assert!(free.windows(2).all(|w| used[w[0]] < used[w[1]]));
            let f = s.buckling(&small, &opts).unwrap().factors[0];
            // Both Ritz values meet the residual bound 1e-8 on the same matrix; the eigenvalue
            // error is of the order of its square, so 1e-9 relative bounds the difference.
            assert!(
                (f - reference).abs() <= 1e-9 * reference,
                "{f} vs {reference}"
            );
        }
        // A node order must rank every node.
        assert!(matches!(
            BucklingSolver::with_node_order(&small, &reverse[1..]),
            Err(FeError::PatternMismatch { .. })
        ));
    }

    /// A warm start from the converged mode ends in fewer Lanczos steps at the same factor (the
    /// stopping test is the same residual bound, so the factors agree to far below 1e-8).
    #[test]
    fn warm_start_saves_steps_not_accuracy() {
        let m = strip();
        let cold_opts = BucklingOptions {
            modes: 1,
            tolerance: 1e-8,
            sturm_check: false,
            ..Default::default()
        };
        let cold = buckling(&m, &cold_opts).unwrap();
        let warm = buckling(
            &m,
            &BucklingOptions {
                start: cold.modes.first().cloned(),
                ..cold_opts.clone()
            },
        )
        .unwrap();
        let (a, b) = (cold.factors[0], warm.factors[0]);
        // Both Ritz values meet ‖Wy − μy‖ ≤ 1e-8·μ; the eigenvalue error is of the order of the
        // squared residual, so 1e-9 relative is a safe bound on their difference.
        assert!((a - b).abs() <= 1e-9 * a, "{a} vs {b}");
        assert!(
            warm.stats.operator_applications < cold.stats.operator_applications,
            "warm {} vs cold {} steps",
            warm.stats.operator_applications,
            cold.stats.operator_applications
        );
        // A start of the wrong length is ignored (random start), not an error.
        let bad = buckling(
            &m,
            &BucklingOptions {
                start: Some(vec![[1.0; 6]; 2]),
                ..cold_opts
            },
        )
        .unwrap();
        assert!((bad.factors[0] - a).abs() <= 1e-9 * a);
    }

    /// A warm start that is exactly mode 2 (no mode-1 content) still finds mode 1: the start is
    /// blended with the seeded random vector, so mode 1 is in the Krylov space and the top Ritz
    /// pair cannot converge to mode 2 first (it did before: a cap state's BLF came out 2 % high
    /// when the previous state's mode was this state's second one).
    #[test]
    fn warm_start_on_mode_two_still_finds_mode_one() {
        let m = strip();
        let two = buckling(
            &m,
            &BucklingOptions {
                modes: 2,
                tolerance: 1e-8,
                sturm_check: true,
                ..Default::default()
            },
        )
        .unwrap();
        let (l1, l2) = (two.factors[0], two.factors[1]);
        assert!(l2 > 1.5 * l1, "modes 1 and 2 are distinct: {l1} {l2}");
        let warm = buckling(
            &m,
            &BucklingOptions {
                modes: 1,
                tolerance: 1e-8,
                sturm_check: false,
                start: two.modes.get(1).cloned(),
                ..Default::default()
            },
        )
        .unwrap();
        // Same residual bound as above: 1e-9 relative.
        assert!(
            (warm.factors[0] - l1).abs() <= 1e-9 * l1,
            "{} vs {l1} (mode 2 {l2})",
            warm.factors[0]
        );
    }
}
