//! Mirror symmetry of a model about a vertical plane, and whether a shape is antisymmetric
//! about it (docs/nonlinear.md, "One imperfection sign"). If the model (nodes, elements and
//! their properties, supports, loads) is its own mirror image and the imperfection shape φ is
//! mirror-antisymmetric, then X − w0·φ is the mirror image of X + w0·φ under the same loads, so
//! the two imperfect paths are mirror images of each other and have the same load factors: one
//! sign suffices.

use std::collections::HashMap;

use crate::model::ShellModel;

/// A reflection `x ↦ x − 2((x − c)·n) n` that maps a model onto itself.
#[derive(Debug, Clone, PartialEq)]
pub struct Mirror {
    /// Unit normal of the plane.
    pub normal: [f64; 3],
    /// A point on the plane (the node centroid).
    pub point: [f64; 3],
    /// The mirror node of every node.
    pub node_map: Vec<usize>,
    /// The mirror element of every element.
    pub element_map: Vec<usize>,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Mirror {
    /// The reflection of a vector (a translation, not a point).
    pub fn reflect(&self, v: [f64; 3]) -> [f64; 3] {
        let d = 2.0 * dot(v, self.normal);
        [0, 1, 2].map(|c| v[c] - d * self.normal[c])
    }

    /// Whether the translations of `shape` (per node) are mirror-antisymmetric,
    /// `R φ_i = −φ_m(i)`, to within `tol` times the largest translation.
    pub fn is_antisymmetric(&self, shape: &[[f64; 6]], tol: f64) -> bool {
        if shape.len() != self.node_map.len() {
            return false;
        }
        let amax = shape
            .iter()
            .map(|d| dot([d[0], d[1], d[2]], [d[0], d[1], d[2]]).sqrt())
            .fold(0.0, f64::max);
        if !(amax.is_finite() && amax > 0.0) {
            return false;
        }
        shape.iter().zip(&self.node_map).all(|(d, &j)| {
            let r = self.reflect([d[0], d[1], d[2]]);
            let o = shape[j];
            let e = [r[0] + o[0], r[1] + o[1], r[2] + o[2]];
            dot(e, e).sqrt() <= tol * amax
        })
    }
}

/// The vertical mirror planes (containing the gravity direction) that map `model` onto itself:
/// every node onto a node within `tol` (m), every triangle onto a triangle with the same
/// thickness and material (relative 1e-9), supports onto equal supports (translations and
/// rotations each all held or all free), nodal forces onto their reflections (no applied
/// moments). Candidate planes pass through the node centroid with normals along the two
/// horizontal axes of the global frame and the two principal axes of the nodes' horizontal
/// spread. Empty when none does (or the model has no gravity direction).
pub fn mirror_symmetries(model: &ShellModel, tol: f64) -> Vec<Mirror> {
    let g = model.gravity;
    let gn = dot(g, g).sqrt();
    let n_nodes = model.nodes.len();
    if gn == 0.0 || n_nodes == 0 || !(tol.is_finite() && tol > 0.0) {
        return Vec::new();
    }
    let gu = g.map(|v| v / gn);
    let c = {
        let mut s = [0.0; 3];
        for p in &model.nodes {
            (0..3).for_each(|k| s[k] += p[k]);
        }
        s.map(|v| v / n_nodes as f64)
    };
    // Horizontal unit vectors: the global axes and the principal axes of the horizontal spread.
    let horiz = |v: [f64; 3]| -> Option<[f64; 3]> {
        let d = dot(v, gu);
        let h = [v[0] - d * gu[0], v[1] - d * gu[1], v[2] - d * gu[2]];
        let l = dot(h, h).sqrt();
        (l > 1e-6).then(|| h.map(|x| x / l))
    };
    let mut cands: Vec<[f64; 3]> = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .into_iter()
        .filter_map(horiz)
        .collect();
    if let (Some(a), Some(b)) = (cands.first().copied(), cands.get(1).copied()) {
        // 2×2 covariance in the (a, b) basis.
        let b = {
            // Orthogonalise b against a.
            let d = dot(a, b);
            let v = [b[0] - d * a[0], b[1] - d * a[1], b[2] - d * a[2]];
            let l = dot(v, v).sqrt();
            v.map(|x| x / l)
        };
        let (mut saa, mut sab, mut sbb) = (0.0, 0.0, 0.0);
        for p in &model.nodes {
            let r = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            let (x, y) = (dot(r, a), dot(r, b));
            saa += x * x;
            sab += x * y;
            sbb += y * y;
        }
        let th = 0.5 * (2.0 * sab).atan2(saa - sbb);
        let (ct, st) = (th.cos(), th.sin());
        for (u, v) in [(ct, st), (-st, ct)] {
            cands.push([0, 1, 2].map(|k| u * a[k] + v * b[k]));
        }
    }
    let mut unique: Vec<[f64; 3]> = Vec::new();
    for n in cands {
        if unique.iter().all(|u| dot(*u, n).abs() < 1.0 - 1e-9) {
            unique.push(n);
        }
    }
    unique
        .into_iter()
        .filter_map(|n| try_plane(model, n, c, tol))
        .collect()
}

fn try_plane(model: &ShellModel, n: [f64; 3], c: [f64; 3], tol: f64) -> Option<Mirror> {
    let cell = tol * 4.0;
    let key = |p: [f64; 3]| p.map(|v| (v / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in model.nodes.iter().enumerate() {
        grid.entry(key(*p)).or_default().push(i);
    }
    let mirror = Mirror {
        normal: n,
        point: c,
        node_map: Vec::new(),
        element_map: Vec::new(),
    };
    let mut node_map = Vec::with_capacity(model.nodes.len());
    for p in &model.nodes {
        let d = 2.0 * dot([p[0] - c[0], p[1] - c[1], p[2] - c[2]], n);
        let q = [0, 1, 2].map(|k| p[k] - d * n[k]);
        let k = key(q);
        let mut best: Option<(f64, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                        continue;
                    };
                    for &j in list {
                        let r = model.nodes[j];
                        let e = [r[0] - q[0], r[1] - q[1], r[2] - q[2]];
                        let dist = dot(e, e).sqrt();
                        if dist <= tol && best.is_none_or(|b| dist < b.0) {
                            best = Some((dist, j));
                        }
                    }
                }
            }
        }
        node_map.push(best?.1);
    }
    let mut tri: HashMap<[usize; 3], usize> = HashMap::new();
    for (e, t) in model.triangles.iter().enumerate() {
        let mut s = *t;
        s.sort_unstable();
        tri.insert(s, e);
    }
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    let mut element_map = Vec::with_capacity(model.triangles.len());
    for (e, t) in model.triangles.iter().enumerate() {
        let mut s = t.map(|i| node_map[i]);
        s.sort_unstable();
        let &f = tri.get(&s)?;
        let (ma, mb) = (model.material_of(e), model.material_of(f));
        if !(close(model.thickness_of(e), model.thickness_of(f))
            && close(ma.youngs_modulus, mb.youngs_modulus)
            && close(ma.poisson_ratio, mb.poisson_ratio)
            && close(ma.unit_weight, mb.unit_weight))
        {
            return None;
        }
        element_map.push(f);
    }
    // Supports: combined per node, translations and rotations each all held or all free (a
    // single held direction would have to be mirrored too; not needed by any model here).
    let mut fixed: Vec<[bool; 6]> = vec![[false; 6]; model.nodes.len()];
    for s in &model.supports {
        let f = fixed.get_mut(s.node)?;
        (0..6).for_each(|k| f[k] |= s.fixed[k]);
    }
    for (i, f) in fixed.iter().enumerate() {
        let uniform = f[0] == f[1] && f[1] == f[2] && f[3] == f[4] && f[4] == f[5];
        if !uniform || fixed[node_map[i]] != *f {
            return None;
        }
    }
    let mut loads: Vec<[f64; 3]> = vec![[0.0; 3]; model.nodes.len()];
    for l in &model.nodal_loads {
        if l.moment.iter().any(|m| *m != 0.0) {
            return None;
        }
        let f = loads.get_mut(l.node)?;
        (0..3).for_each(|k| f[k] += l.force[k]);
    }
    let fmax = loads.iter().map(|f| dot(*f, *f).sqrt()).fold(0.0, f64::max);
    for (i, f) in loads.iter().enumerate() {
        let r = mirror.reflect(*f);
        let o = loads[node_map[i]];
        let e = [r[0] - o[0], r[1] - o[1], r[2] - o[2]];
        if dot(e, e).sqrt() > 1e-9 * fmax {
            return None;
        }
    }
    Some(Mirror {
        node_map,
        element_map,
        ..mirror
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Material, Support};

    fn plate(skew: f64) -> ShellModel {
        // A 4×2 grid of squares split into triangles, symmetric about x = 2 unless skewed.
        let mut nodes = Vec::new();
        for j in 0..3 {
            for i in 0..5 {
                let x = i as f64 + if i == 4 && j == 2 { skew } else { 0.0 };
                nodes.push([x, j as f64, 0.0]);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..2 {
            for i in 0..4 {
                let a = j * 5 + i;
                // Diagonals mirrored about the middle so the mesh is symmetric.
                if i < 2 {
                    triangles.push([a, a + 1, a + 6]);
                    triangles.push([a, a + 6, a + 5]);
                } else {
                    triangles.push([a, a + 1, a + 5]);
                    triangles.push([a + 1, a + 6, a + 5]);
                }
            }
        }
        let mat = Material {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            unit_weight: 2e4,
        };
        ShellModel {
            supports: (0..5).map(Support::pinned).collect(),
            gravity: [0.0, -1.0, 0.0],
            ..ShellModel::new(nodes, triangles, 0.02, mat)
        }
    }

    #[test]
    fn finds_the_plane_and_tells_antisymmetric_shapes() {
        let m = plate(0.0);
        let all = mirror_symmetries(&m, 1e-9);
        // About x = 2 and about the plate's own plane z = 0 (both contain gravity, −y).
        assert_eq!(all.len(), 2, "{all:?}");
        let mir = &all[0];
        assert!((mir.normal[0].abs() - 1.0).abs() < 1e-12);
        // Sway (the same x translation everywhere) is antisymmetric about x = 2; a vertical
        // bulge even in x is symmetric.
        let sway: Vec<[f64; 6]> = m
            .nodes
            .iter()
            .map(|_| [1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            .collect();
        let bulge: Vec<[f64; 6]> = m
            .nodes
            .iter()
            .map(|p| [0.0, 0.0, 1.0 - (p[0] - 2.0).abs() / 2.0, 0.0, 0.0, 0.0])
            .collect();
        assert!(mir.is_antisymmetric(&sway, 1e-9));
        assert!(!mir.is_antisymmetric(&bulge, 1e-9));
        // The plate's own plane: a bulge out of it is antisymmetric.
        assert!(all[1].is_antisymmetric(&bulge, 1e-9));
        // A node moved in x by more than the tolerance breaks the x = 2 symmetry only.
        let skewed = mirror_symmetries(&plate(1e-3), 1e-6);
        assert_eq!(skewed.len(), 1);
        assert!(skewed[0].normal[2].abs() > 0.99);
    }
}
