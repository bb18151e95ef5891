//! Sparse factorizations on the shared pattern (faer low-level API): one symbolic analysis
//! (AMD ordering, supernodal or simplicial by flop count), then numeric LLᵀ of K and LDLᵀ of
//! `K + σ K_G` for the Sturm count. The symbolic part is what [`crate::BucklingSolver`] caches.

use std::sync::Mutex;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::assembly::Pattern;
use crate::error::FeError;

/// Symbolic Cholesky of a pattern. The pattern itself is borrowed from [`Pattern`] at each
/// numeric step (no second copy of the index arrays: ~100 MB at 10⁵ nodes).
#[derive(Debug)]
pub(crate) struct Symbolic {
    pub(crate) chol: SymbolicCholesky<usize>,
}

fn pattern_ref(p: &Pattern) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(p.n, p.n, &p.col_ptr, None, &p.row_idx)
}

/// Why a numeric LLᵀ failed.
pub(crate) enum LltFailure {
    /// Non-positive pivot at this (original, un-permuted) free-DOF index.
    NotPositive(Option<usize>),
    /// Anything else.
    Other(FeError),
}

/// faer's parallelism: always sequential. A factorization's floating-point sums then come out
/// in one order whichever thread runs it, so the CLI, Python, a Dask worker and the browser
/// compute bit-identical factors (a parallel factorization on a calling thread summed
/// differently from the sequential one inside rayon workers: a study row differed in its last
/// digit between Dask and the CLI). Parallelism comes from the print states solved side by side;
/// nested fork–join on small triangular solves cost more than it saved there anyway.
fn par() -> Par {
    Par::Seq
}

impl Symbolic {
    pub(crate) fn new(p: &Pattern) -> Result<Self, FeError> {
        Self::ordered(p, None)
    }

    /// As [`Symbolic::new`] with a given fill-reducing ordering (`order[k]` = the free DOF
    /// eliminated k-th; the caller has checked it is a permutation of `0..p.n`), or AMD.
    pub(crate) fn ordered(
        p: &Pattern,
        order: Option<(&[usize], &[usize])>,
    ) -> Result<Self, FeError> {
        let ordering = match order {
            Some((fwd, inv)) => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, inv, p.n))
            }
            None => SymmetricOrdering::Amd,
        };
        let chol =
            factorize_symbolic_cholesky(pattern_ref(p), Side::Lower, ordering, Default::default())
                .map_err(|e| FeError::Numerical {
                    stage: "symbolic Cholesky",
                    detail: format!("{e:?}"),
                })?;
        Ok(Self { chol })
    }

    /// The elimination order (`order[k]` = the free DOF eliminated k-th).
    pub(crate) fn order(&self) -> Option<Vec<usize>> {
        self.chol.perm().map(|p| p.arrays().0.to_vec())
    }

    /// Number of stored entries of the factor L.
    pub(crate) fn nnz_l(&self) -> usize {
        self.chol.len_val()
    }

    fn mat<'a>(p: &'a Pattern, vals: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        SparseColMatRef::new(pattern_ref(p), vals)
    }

    /// Numeric LLᵀ of the matrix with lower values `vals`.
    pub(crate) fn llt(&self, p: &Pattern, vals: &[f64]) -> Result<Llt<'_>, LltFailure> {
        let mut l = Vec::new();
        l.try_reserve_exact(self.chol.len_val()).map_err(|_| {
            LltFailure::Other(FeError::Numerical {
                stage: "Cholesky",
                detail: "out of memory for the factor".into(),
            })
        })?;
        l.resize(self.chol.len_val(), 0.0);
        let req = self
            .chol
            .factorize_numeric_llt_scratch::<f64>(par(), Default::default());
        let mut buf = MemBuffer::try_new(req).map_err(|_| {
            LltFailure::Other(FeError::Numerical {
                stage: "Cholesky",
                detail: "out of memory for the workspace".into(),
            })
        })?;
        let res = self.chol.factorize_numeric_llt::<f64>(
            &mut l,
            Self::mat(p, vals),
            Side::Lower,
            Default::default(),
            par(),
            MemStack::new(&mut buf),
            Default::default(),
        );
        match res {
            Ok(_) => Ok(Llt { sym: self, l }),
            Err(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index }) => {
                let orig = match self.chol.perm() {
                    Some(p) => p.arrays().0.get(index).copied(),
                    None => Some(index),
                };
                Err(LltFailure::NotPositive(orig))
            }
        }
    }

    /// Number of negative pivots of an LDLᵀ factorization (no pivoting) of the symmetric
    /// matrix with lower values `vals`. By Sylvester's law of inertia this is the number of
    /// negative eigenvalues. Returns `None` on a zero pivot (caller perturbs the shift).
    pub(crate) fn negative_pivots(
        &self,
        p: &Pattern,
        vals: &[f64],
    ) -> Result<Option<usize>, FeError> {
        let Some(l) = self.numeric_ldlt(p, vals, "LDLᵀ (Sturm check)", None)? else {
            return Ok(None);
        };
        Ok(self.count_negative(&l))
    }

    /// The numeric LDLᵀ values (no pivoting) of the matrix with lower values `vals`; `None` when
    /// faer rejects the factorization (a zero pivot). `stage` names the caller in an
    /// out-of-memory error. With `buffers`, the value array and the workspace come from (and
    /// the workspace returns to) there instead of fresh allocations.
    fn numeric_ldlt(
        &self,
        p: &Pattern,
        vals: &[f64],
        stage: &'static str,
        buffers: Option<&FactorBuffers>,
    ) -> Result<Option<Vec<f64>>, FeError> {
        let oom = |what: &str| FeError::Numerical {
            stage,
            detail: format!("out of memory for the {what}"),
        };
        let len = self.chol.len_val();
        // faer sets every value of L itself (`L_values.fill(0)` before the supernodal and
        // simplicial factorizations), so a recycled array needs no clearing and gives the
        // same factor bit for bit.
        let mut l = match buffers.and_then(|b| b.take_values(len)) {
            Some(l) => l,
            None => {
                let mut l = Vec::new();
                l.try_reserve_exact(len).map_err(|_| oom("factor"))?;
                l.resize(len, 0.0);
                l
            }
        };
        let req = self
            .chol
            .factorize_numeric_ldlt_scratch::<f64>(par(), Default::default());
        let mut buf = match buffers.and_then(|b| b.take_scratch(req)) {
            Some(b) => b,
            None => MemBuffer::try_new(req).map_err(|_| oom("workspace"))?,
        };
        let res = self.chol.factorize_numeric_ldlt::<f64>(
            &mut l,
            Self::mat(p, vals),
            Side::Lower,
            Default::default(),
            par(),
            MemStack::new(&mut buf),
            Default::default(),
        );
        if let Some(b) = buffers {
            b.put_scratch(req, buf);
        }
        match res {
            Ok(_) => Ok(Some(l)),
            Err(_) => {
                if let Some(b) = buffers {
                    b.put_values(l);
                }
                Ok(None)
            }
        }
    }

    /// Negative diagonal entries of D in the LDLᵀ values `l` (`None` on a zero or non-finite
    /// pivot).
    fn count_negative(&self, l: &[f64]) -> Option<usize> {
        // D sits on the diagonal of L (unit lower triangular otherwise).
        let mut neg = 0;
        match self.chol.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let cp = s.col_ptr();
                let ri = s.row_idx();
                for j in 0..s.nrows() {
                    for p in cp[j]..cp[j + 1] {
                        if ri[p] == j {
                            let d = l[p];
                            if d == 0.0 || !d.is_finite() {
                                return None;
                            }
                            if d < 0.0 {
                                neg += 1;
                            }
                        }
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let f = faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef::new(s, l);
                for k in 0..s.n_supernodes() {
                    let sn = f.supernode(k);
                    let v = sn.val();
                    for i in 0..v.ncols() {
                        let d = v[(i, i)];
                        if d == 0.0 || !d.is_finite() {
                            return None;
                        }
                        if d < 0.0 {
                            neg += 1;
                        }
                    }
                }
            }
        }
        Some(neg)
    }

    /// Numeric LDLᵀ (no pivoting) of a symmetric, possibly indefinite matrix with lower values
    /// `vals`, kept for solves; `None` on a zero or non-finite pivot (a singular tangent).
    pub(crate) fn ldlt(&self, p: &Pattern, vals: &[f64]) -> Result<Option<Ldlt<'_>>, FeError> {
        self.ldlt_with(p, vals, None)
    }

    /// As [`Symbolic::ldlt`], with the value array and workspace taken from `buffers`; the
    /// factor gives its values back there when dropped. For a sequence of factorizations on
    /// one pattern (a nonlinear path: 5·10⁶ values of L, 40 MB, and a ~20 MB workspace on the
    /// default cap): each fresh allocation of that size is a new mapping from the system,
    /// whose first touch page-faults and clears every page again.
    pub(crate) fn ldlt_with<'a>(
        &'a self,
        p: &Pattern,
        vals: &[f64],
        buffers: Option<&'a FactorBuffers>,
    ) -> Result<Option<Ldlt<'a>>, FeError> {
        let Some(l) = self.numeric_ldlt(p, vals, "LDLᵀ (tangent)", buffers)? else {
            return Ok(None);
        };
        match self.count_negative(&l) {
            Some(negative) => Ok(Some(Ldlt {
                sym: self,
                l,
                negative,
                buffers,
            })),
            None => {
                if let Some(b) = buffers {
                    b.put_values(l);
                }
                Ok(None)
            }
        }
    }
}

/// Value arrays of dropped LDLᵀ factors and the factorization workspace, kept for the next
/// factorization on the same symbolic structure ([`Symbolic::ldlt_with`]). Holds at most
/// [`FactorBuffers::SPARE`] arrays: never more than were alive at once before, so the peak
/// memory does not grow, only its release waits for the owner (the path) to end.
#[derive(Default)]
pub(crate) struct FactorBuffers {
    values: Mutex<Vec<Vec<f64>>>,
    /// The workspace with the request it was allocated for.
    scratch: Mutex<Option<(StackReq, MemBuffer)>>,
}

impl FactorBuffers {
    /// Spare value arrays kept (a path holds at most three factors at once: the step's
    /// start, an iteration's own, and a converged point's under test).
    const SPARE: usize = 3;

    fn take_values(&self, len: usize) -> Option<Vec<f64>> {
        let mut v = self.values.lock().unwrap_or_else(|e| e.into_inner());
        let i = v.iter().position(|l| l.len() == len)?;
        Some(v.swap_remove(i))
    }

    fn put_values(&self, l: Vec<f64>) {
        let mut v = self.values.lock().unwrap_or_else(|e| e.into_inner());
        if v.len() < Self::SPARE {
            v.push(l);
        }
    }

    fn take_scratch(&self, req: StackReq) -> Option<MemBuffer> {
        let mut s = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        // Only for the request it was allocated for (one symbolic structure: always).
        match s.take() {
            Some((r, b)) if r == req => Some(b),
            other => {
                *s = other;
                None
            }
        }
    }

    fn put_scratch(&self, req: StackReq, b: MemBuffer) {
        *self.scratch.lock().unwrap_or_else(|e| e.into_inner()) = Some((req, b));
    }
}

/// Numeric LDLᵀ factor of a symmetric (possibly indefinite) matrix, with its inertia.
pub(crate) struct Ldlt<'a> {
    sym: &'a Symbolic,
    l: Vec<f64>,
    /// Number of negative pivots = negative eigenvalues (Sylvester).
    pub(crate) negative: usize,
    /// Where the values go when the factor is dropped.
    buffers: Option<&'a FactorBuffers>,
}

impl Drop for Ldlt<'_> {
    fn drop(&mut self) {
        if let Some(b) = self.buffers {
            b.put_values(std::mem::take(&mut self.l));
        }
    }
}

impl Ldlt<'_> {
    /// Solve `A X = B` in place for all columns of `rhs`.
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) -> Result<(), FeError> {
        let req = self
            .sym
            .chol
            .solve_in_place_scratch::<f64>(rhs.ncols(), par());
        let mut buf = MemBuffer::try_new(req).map_err(|_| FeError::Numerical {
            stage: "solve",
            detail: "out of memory for the workspace".into(),
        })?;
        LdltRef::<'_, usize, f64>::new(&self.sym.chol, &self.l).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par(),
            MemStack::new(&mut buf),
        );
        Ok(())
    }
}

/// Numeric LLᵀ factor of K.
pub(crate) struct Llt<'a> {
    sym: &'a Symbolic,
    l: Vec<f64>,
}

impl Llt<'_> {
    /// Smallest ratio `L_ii² / A_ii` over the pivots, and the original free-DOF index where
    /// it occurs. For an SPD stiffness this is the fraction of a DOF's own stiffness left
    /// after eliminating its predecessors; ~1e-16 means a (numerically) singular matrix that
    /// LLᵀ happened to push through with round-off-sized pivots.
    pub(crate) fn min_pivot_ratio(&self, a_diag: &[f64]) -> (f64, usize) {
        let fwd: Option<&[usize]> = self.sym.chol.perm().map(|p| p.arrays().0);
        let orig = |i: usize| fwd.and_then(|f| f.get(i).copied()).unwrap_or(i);
        let mut best = (f64::INFINITY, 0usize);
        let mut visit = |i: usize, lii: f64| {
            let o = orig(i);
            let d = a_diag.get(o).copied().unwrap_or(1.0);
            let r = lii * lii / d;
            if r < best.0 {
                best = (r, o);
            }
        };
        match self.sym.chol.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let cp = s.col_ptr();
                let ri = s.row_idx();
                for j in 0..s.nrows() {
                    for p in cp[j]..cp[j + 1] {
                        if ri[p] == j {
                            visit(j, self.l[p]);
                        }
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let f =
                    faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef::new(s, &self.l);
                for k in 0..s.n_supernodes() {
                    let sn = f.supernode(k);
                    let v = sn.val();
                    for i in 0..v.ncols() {
                        visit(sn.start() + i, v[(i, i)]);
                    }
                }
            }
        }
        best
    }

    /// Solve `K X = B` in place for all columns of `rhs`.
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) -> Result<(), FeError> {
        let req = self
            .sym
            .chol
            .solve_in_place_scratch::<f64>(rhs.ncols(), par());
        let mut buf = MemBuffer::try_new(req).map_err(|_| FeError::Numerical {
            stage: "solve",
            detail: "out of memory for the workspace".into(),
        })?;
        LltRef::<'_, usize, f64>::new(&self.sym.chol, &self.l).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par(),
            MemStack::new(&mut buf),
        );
        Ok(())
    }
}
