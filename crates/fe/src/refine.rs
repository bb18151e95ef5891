//! Uniform refinement of a facet mesh: every triangle split into n² congruent sub-triangles on
//! the **same flat facets** (no new geometry), so a sequence of splits converges to the buckling
//! factor of the model's own faceted surface — the value CalculiX S8R or 20-node solids give on
//! the identical geometry. Used for the mesh-error control of the print states (`kappe`'s
//! `analysis::convergence`) and its verification examples.
//!
//! Rules:
//! - A node on an edge takes the DOFs fixed at **both** ends of the edge; a node inside a
//!   triangle the DOFs fixed at all three corners (a pinned support line stays pinned along
//!   its whole length, as the coarse element's edge interpolation held it).
//! - Sub-triangles keep their parent's thickness and material and its orientation.
//! - Nodal loads stay on the original nodes; self-weight is per area, so it is unchanged.
//!
//! Hand-written: it is a few lines of index bookkeeping.

use std::collections::HashMap;

use crate::model::{ShellModel, Support};

/// A refined model and, for every node of it, the parent triangle's corners and barycentric
/// weights (for an original node: itself with weight 1), to map fields between the meshes.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The refined model.
    pub model: ShellModel,
    /// Per refined node: up to three (parent node, weight) pairs, weights summing to 1.
    pub parents: Vec<[(usize, f64); 3]>,
}

/// Split every triangle of `model` into `n × n` sub-triangles (`n ≥ 1`; 1 returns a copy).
pub fn split(model: &ShellModel, n: usize) -> Refined {
    let n = n.max(1);
    let n0 = model.nodes.len();
    let mut nodes = model.nodes.clone();
    let mut parents: Vec<[(usize, f64); 3]> =
        (0..n0).map(|i| [(i, 1.0), (i, 0.0), (i, 0.0)]).collect();
    let fixed0 = model.fixed_mask();
    let mut fixed: Vec<[bool; 6]> = fixed0.clone();
    // Interior points of edge (a, b), a < b: n − 1 nodes from a to b.
    let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
    let mut triangles = Vec::with_capacity(model.triangles.len() * n * n);
    let mut thickness = Vec::new();
    let mut materials = Vec::new();
    let per_element_t = model.thickness.len() > 1;
    let per_element_m = model.materials.len() > 1;
    let lerp = |p: [f64; 3], q: [f64; 3], r: [f64; 3], w: [f64; 3]| {
        std::array::from_fn(|c| w[0] * p[c] + w[1] * q[c] + w[2] * r[c])
    };
    for (e, tri) in model.triangles.iter().enumerate() {
        let [a, b, c] = *tri;
        let (pa, pb, pc) = (model.nodes[a], model.nodes[b], model.nodes[c]);
        // Grid node (i, j): barycentric (1 − (i+j)/n, i/n, j/n) towards (a, b, c).
        let mut grid = vec![usize::MAX; (n + 1) * (n + 1)];
        let gi = |i: usize, j: usize| i * (n + 1) + j;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let k = n - i - j;
                let id = if i == 0 && j == 0 {
                    a
                } else if i == n {
                    b
                } else if j == n {
                    c
                } else if j == 0 || i == 0 || k == 0 {
                    // On an edge: (a,b) when j = 0 at position i; (a,c) when i = 0 at j;
                    // (b,c) when k = 0 at position j from b.
                    let (p, q, s) = if j == 0 {
                        (a, b, i)
                    } else if i == 0 {
                        (a, c, j)
                    } else {
                        (b, c, j)
                    };
                    let (lo, hi, pos) = if p < q { (p, q, s) } else { (q, p, n - s) };
                    let base = *edges.entry((lo, hi)).or_insert_with(|| {
                        let first = nodes.len();
                        for m in 1..n {
                            let t = m as f64 / n as f64;
                            let (pl, ph) = (model.nodes[lo], model.nodes[hi]);
                            nodes.push(std::array::from_fn(|d| (1.0 - t) * pl[d] + t * ph[d]));
                            parents.push([(lo, 1.0 - t), (hi, t), (hi, 0.0)]);
                            fixed.push(std::array::from_fn(|d| fixed0[lo][d] && fixed0[hi][d]));
                        }
                        first
                    });
                    base + pos - 1
                } else {
                    let w = [
                        k as f64 / n as f64,
                        i as f64 / n as f64,
                        j as f64 / n as f64,
                    ];
                    nodes.push(lerp(pa, pb, pc, w));
                    parents.push([(a, w[0]), (b, w[1]), (c, w[2])]);
                    fixed.push(std::array::from_fn(|d| {
                        fixed0[a][d] && fixed0[b][d] && fixed0[c][d]
                    }));
                    nodes.len() - 1
                };
                grid[gi(i, j)] = id;
            }
        }
        let before = triangles.len();
        for i in 0..n {
            for j in 0..(n - i) {
                // Upright: (i,j), (i+1,j), (i,j+1) — same orientation as (a, b, c).
                triangles.push([grid[gi(i, j)], grid[gi(i + 1, j)], grid[gi(i, j + 1)]]);
                if i + j + 1 < n {
                    triangles.push([
                        grid[gi(i + 1, j)],
                        grid[gi(i + 1, j + 1)],
                        grid[gi(i, j + 1)],
                    ]);
                }
            }
        }
        let added = triangles.len() - before;
        if per_element_t {
            thickness.extend(std::iter::repeat_n(model.thickness[e], added));
        }
        if per_element_m {
            materials.extend(std::iter::repeat_n(model.materials[e], added));
        }
    }
    assemble(
        model,
        nodes,
        triangles,
        (
            per_element_t.then_some(thickness),
            per_element_m.then_some(materials),
        ),
        &fixed,
        parents,
    )
}

/// One level of conforming **red–green** refinement: every `marked` triangle (and every
/// triangle with two or more refined edges, until none is left: the closure) is split into four
/// by its edge midpoints ("red"); a triangle with exactly one refined edge is bisected from that
/// edge's midpoint to the opposite corner ("green"), so the mesh has no hanging node. Supports,
/// materials, thickness and orientation follow the rules of [`split`].
pub fn red_green(model: &ShellModel, marked: &[bool]) -> Refined {
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    let nt = model.triangles.len();
    let mut red: Vec<bool> = (0..nt)
        .map(|e| marked.get(e).copied().unwrap_or(false))
        .collect();
    let mut cut: std::collections::HashSet<(usize, usize)> = std::collections::HashSet::new();
    let edges_of = |t: &[usize; 3]| [key(t[0], t[1]), key(t[1], t[2]), key(t[2], t[0])];
    for (e, t) in model.triangles.iter().enumerate() {
        if red[e] {
            cut.extend(edges_of(t));
        }
    }
    loop {
        let mut changed = false;
        for (e, t) in model.triangles.iter().enumerate() {
            if red[e] {
                continue;
            }
            if edges_of(t).iter().filter(|k| cut.contains(k)).count() >= 2 {
                red[e] = true;
                cut.extend(edges_of(t));
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let fixed0 = model.fixed_mask();
    let mut nodes = model.nodes.clone();
    let mut parents: Vec<[(usize, f64); 3]> = (0..nodes.len())
        .map(|i| [(i, 1.0), (i, 0.0), (i, 0.0)])
        .collect();
    let mut fixed = fixed0.clone();
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut cut_sorted: Vec<(usize, usize)> = cut.into_iter().collect();
    cut_sorted.sort_unstable();
    for (a, b) in cut_sorted {
        let (p, q) = (model.nodes[a], model.nodes[b]);
        mid.insert((a, b), nodes.len());
        nodes.push(std::array::from_fn(|d| 0.5 * (p[d] + q[d])));
        parents.push([(a, 0.5), (b, 0.5), (b, 0.0)]);
        fixed.push(std::array::from_fn(|d| fixed0[a][d] && fixed0[b][d]));
    }
    let per_element_t = model.thickness.len() > 1;
    let per_element_m = model.materials.len() > 1;
    let mut triangles = Vec::with_capacity(nt * 2);
    let mut thickness = Vec::new();
    let mut materials = Vec::new();
    for (e, t) in model.triangles.iter().enumerate() {
        let before = triangles.len();
        let m = |a: usize, b: usize| mid.get(&key(a, b)).copied();
        let [a, b, c] = *t;
        if red[e] {
            let (ab, bc, ca) = (m(a, b).unwrap(), m(b, c).unwrap(), m(c, a).unwrap());
            triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        } else if let Some(ab) = m(a, b) {
            triangles.extend([[a, ab, c], [ab, b, c]]);
        } else if let Some(bc) = m(b, c) {
            triangles.extend([[a, b, bc], [a, bc, c]]);
        } else if let Some(ca) = m(c, a) {
            triangles.extend([[a, b, ca], [ca, b, c]]);
        } else {
            triangles.push(*t);
        }
        let added = triangles.len() - before;
        if per_element_t {
            thickness.extend(std::iter::repeat_n(model.thickness[e], added));
        }
        if per_element_m {
            materials.extend(std::iter::repeat_n(model.materials[e], added));
        }
    }
    assemble(
        model,
        nodes,
        triangles,
        (
            per_element_t.then_some(thickness),
            per_element_m.then_some(materials),
        ),
        &fixed,
        parents,
    )
}

impl Refined {
    /// A nodal field of the parent mesh (e.g. a buckling mode, 6 values per node) interpolated
    /// onto the refined nodes with the barycentric weights of [`Refined::parents`].
    pub fn prolong(&self, field: &[[f64; 6]]) -> Vec<[f64; 6]> {
        self.parents
            .iter()
            .map(|p| {
                let mut v = [0.0; 6];
                for &(node, w) in p {
                    if w == 0.0 {
                        continue;
                    }
                    if let Some(f) = field.get(node) {
                        for d in 0..6 {
                            v[d] += w * f[d];
                        }
                    }
                }
                v
            })
            .collect()
    }
}

/// The refined model from its parts: `model`'s data with the new nodes and triangles, the
/// per-element thickness and materials where `model` has them per element, and a support on
/// every node with a fixed DOF.
fn assemble(
    model: &ShellModel,
    nodes: Vec<[f64; 3]>,
    triangles: Vec<[usize; 3]>,
    (thickness, materials): (Option<Vec<f64>>, Option<Vec<crate::model::Material>>),
    fixed: &[[bool; 6]],
    parents: Vec<[(usize, f64); 3]>,
) -> Refined {
    let mut out = model.clone();
    out.nodes = nodes;
    out.triangles = triangles;
    if let Some(t) = thickness {
        out.thickness = t;
    }
    if let Some(m) = materials {
        out.materials = m;
    }
    out.supports = fixed
        .iter()
        .enumerate()
        .filter(|(_, f)| f.iter().any(|x| *x))
        .map(|(i, f)| Support { node: i, fixed: *f })
        .collect();
    Refined {
        model: out,
        parents,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::ss_plate;

    #[test]
    fn split_counts_and_area() {
        let m = ss_plate(4);
        for n in 1..=4 {
            let r = split(&m, n);
            assert_eq!(r.model.triangles.len(), m.triangles.len() * n * n);
            // Euler: V = original + edges·(n−1) + faces·(n−1)(n−2)/2.
            let mut e = std::collections::HashSet::new();
            for t in &m.triangles {
                for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    e.insert((a.min(b), a.max(b)));
                }
            }
            let expect = m.nodes.len()
                + e.len() * (n - 1)
                + m.triangles.len() * (n - 1) * n.saturating_sub(2) / 2;
            assert_eq!(r.model.nodes.len(), expect, "n = {n}");
            assert!(r.model.validate().is_ok());
        }
    }

    #[test]
    fn red_green_is_conforming() {
        let m = ss_plate(4);
        let mut marked = vec![false; m.triangles.len()];
        marked[0] = true;
        marked[5] = true;
        let r = red_green(&m, &marked);
        assert!(r.model.validate().is_ok());
        // Every interior edge is shared by exactly two triangles (no hanging node).
        let mut count = std::collections::HashMap::new();
        for t in &r.model.triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        assert!(count.values().all(|&c| c <= 2));
        let area = |m: &ShellModel| -> f64 {
            m.triangles
                .iter()
                .map(|t| crate::element::TriangleGeometry::new(&t.map(|n| m.nodes[n])).area)
                .sum()
        };
        assert!((area(&r.model) - area(&m)).abs() < 1e-12);
    }
}
