//! Sparse assembly of the reduced (supported DOFs eliminated) stiffness and geometric
//! stiffness, lower triangle in CSC form.
//!
//! Hand-written on purpose: triplet assembly (`try_new_from_triplets`) sorts ~170 entries per
//! element every time. Shell topology is fixed across the ~100 print states of a vault, so
//! the pattern is derived once from node adjacency (6×6 blocks) and element matrices are
//! scattered into it; K and K_G share it, and so does `K + σ K_G` for the Sturm check.

use rayon::prelude::*;

use crate::element::{Mat18, TriangleGeometry};
use crate::error::FeError;
use crate::model::ShellModel;

/// Numbering of the free DOFs: `map[6·node + d]` = free index or `usize::MAX` if fixed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DofMap {
    /// Global DOF → free index (or `usize::MAX`).
    pub map: Vec<usize>,
    /// Free index → global DOF `6·node + d`.
    pub free: Vec<usize>,
}

impl DofMap {
    /// Number the free DOFs node-major.
    pub fn new(model: &ShellModel) -> Self {
        let fixed = model.fixed_mask();
        let mut map = vec![usize::MAX; 6 * model.nodes.len()];
        let mut free = Vec::with_capacity(map.len());
        for (n, f) in fixed.iter().enumerate() {
            for d in 0..6 {
                if !f[d] {
                    map[6 * n + d] = free.len();
                    free.push(6 * n + d);
                }
            }
        }
        Self { map, free }
    }
    /// Number of free DOFs.
    pub fn n_free(&self) -> usize {
        self.free.len()
    }
}

/// Lower-triangular CSC pattern of the reduced matrices (rows sorted in each column).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pattern {
    /// Dimension.
    pub n: usize,
    /// Column pointers (n + 1).
    pub col_ptr: Vec<usize>,
    /// Row indices (≥ column).
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// Pattern of all DOF pairs of nodes sharing a triangle.
    pub fn new(model: &ShellModel, dofs: &DofMap) -> Self {
        let n_nodes = model.nodes.len();
        let mut adj: Vec<Vec<usize>> = (0..n_nodes).map(|i| vec![i]).collect();
        for tri in &model.triangles {
            for &a in tri {
                for &b in tri {
                    if let Some(v) = adj.get_mut(a) {
                        v.push(b);
                    }
                }
            }
        }
        for v in &mut adj {
            v.sort_unstable();
            v.dedup();
        }
        let n = dofs.n_free();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        for &g in &dofs.free {
            let j = dofs.map[g];
            for &b in &adj[g / 6] {
                for e in 0..6 {
                    let i = dofs.map[6 * b + e];
                    if i != usize::MAX && i >= j {
                        row_idx.push(i);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            n,
            col_ptr,
            row_idx,
        }
    }

    /// Number of stored (lower) entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// `y = A x` for the symmetric matrix whose lower triangle is `vals`.
    pub fn sym_matvec(&self, vals: &[f64], x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..self.n {
            let xj = x[j];
            let mut acc = 0.0;
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                let a = vals[p];
                if i == j {
                    acc += a * xj;
                } else {
                    y[i] += a * xj;
                    acc += a * x[i];
                }
            }
            y[j] += acc;
        }
    }
}

/// Geometry of every triangle.
pub(crate) fn geometries(model: &ShellModel) -> Vec<TriangleGeometry> {
    model
        .triangles
        .par_iter()
        .map(|t| TriangleGeometry::new(&[model.nodes[t[0]], model.nodes[t[1]], model.nodes[t[2]]]))
        .collect()
}

/// Global DOF numbers (6·node + d) of an element's 18 DOFs.
#[inline]
pub(crate) fn element_dofs(tri: &[usize; 3]) -> [usize; 18] {
    let mut d = [0; 18];
    for (a, &n) in tri.iter().enumerate() {
        for k in 0..6 {
            d[6 * a + k] = 6 * n + k;
        }
    }
    d
}

/// Assemble the reduced lower-triangle values of Σ_e `matrix(e)` into `pattern`.
pub(crate) fn assemble<F>(
    model: &ShellModel,
    dofs: &DofMap,
    pattern: &Pattern,
    matrix: F,
) -> Result<Vec<f64>, FeError>
where
    F: Fn(usize) -> Mat18 + Sync,
{
    let mut vals = vec![0.0; pattern.nnz()];
    const CHUNK: usize = 2048;
    let n_el = model.triangles.len();
    let mut start = 0;
    while start < n_el {
        let end = (start + CHUNK).min(n_el);
        let mats: Vec<Mat18> = (start..end).into_par_iter().map(&matrix).collect();
        for (e, ke) in (start..end).zip(mats.iter()) {
            scatter(model, dofs, pattern, e, ke, &mut vals)?;
        }
        start = end;
    }
    Ok(vals)
}

/// Add the free-DOF lower-triangle entries of element `e`'s matrix `ke` into `vals`.
pub(crate) fn scatter(
    model: &ShellModel,
    dofs: &DofMap,
    pattern: &Pattern,
    e: usize,
    ke: &Mat18,
    vals: &mut [f64],
) -> Result<(), FeError> {
    scatter_with(model, dofs, pattern, e, |p, q| ke[(p, q)], vals)
}

/// As [`scatter`], with entry `(p, q)` of the element matrix given by `ke(p, q)`: only the
/// entries scattered are computed (e.g. a symmetric part `½(K_pq + K_qp)` without forming it).
pub(crate) fn scatter_with(
    model: &ShellModel,
    dofs: &DofMap,
    pattern: &Pattern,
    e: usize,
    ke: impl Fn(usize, usize) -> f64,
    vals: &mut [f64],
) -> Result<(), FeError> {
    let gd = element_dofs(&model.triangles[e]);
    let fd: [usize; 18] = std::array::from_fn(|k| dofs.map[gd[k]]);
    for q in 0..18 {
        let j = fd[q];
        if j == usize::MAX {
            continue;
        }
        let (c0, c1) = (pattern.col_ptr[j], pattern.col_ptr[j + 1]);
        let rows = &pattern.row_idx[c0..c1];
        // The free DOFs of one node are consecutive numbers, hence consecutive rows:
        // one binary search per node block instead of one per entry.
        for a in 0..3 {
            let mut pos: Option<usize> = None;
            for p in 6 * a..6 * a + 6 {
                let i = fd[p];
                if i == usize::MAX || i < j {
                    continue;
                }
                let at = match pos {
                    Some(x) => x + 1,
                    None => c0 + rows.partition_point(|&r| r < i),
                };
                if pattern.row_idx.get(at) != Some(&i) || at >= c1 {
                    return Err(FeError::Numerical {
                        stage: "assembly",
                        detail: format!("entry ({i}, {j}) missing from the sparsity pattern"),
                    });
                }
                vals[at] += ke(p, q);
                pos = Some(at);
            }
        }
    }
    Ok(())
}

/// Global load vector (6 per node): lumped self-weight `γ t A/3 · gravity` per node plus
/// nodal forces and moments (buckling.md §2 item 6; for CST the consistent load is the same).
pub(crate) fn load_vector(model: &ShellModel, geo: &[TriangleGeometry]) -> Vec<f64> {
    let mut f = vec![0.0; 6 * model.nodes.len()];
    for (e, tri) in model.triangles.iter().enumerate() {
        let w = model.material_of(e).unit_weight * model.thickness_of(e) * geo[e].area / 3.0;
        if w == 0.0 {
            continue;
        }
        for &n in tri {
            for c in 0..3 {
                f[6 * n + c] += w * model.gravity[c];
            }
        }
    }
    for l in &model.nodal_loads {
        for c in 0..3 {
            f[6 * l.node + c] += l.force[c];
            f[6 * l.node + 3 + c] += l.moment[c];
        }
    }
    f
}
