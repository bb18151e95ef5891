//! The topology diagram (cem.md §1): nodes with loads and roles, trail edges with signed
//! lengths, deviation edges with signed forces, plus the options that change how trails are
//! built (auxiliary trails, trail shifts).
//!
//! A [`Topology`] is plain data with public fields, so callers may build it directly, mutate
//! lengths/forces between solves, or use the chaining [`TopologyBuilder`]. Nothing is
//! validated here except by [`TopologyBuilder::build`]; every solve validates again through
//! [`crate::Model::new`].
//!
//! Sign conventions: trail length `λ < 0` and deviation force `μ < 0` mean compression,
//! positive means tension.

use std::collections::HashMap;

use nalgebra::Vector3;

use crate::error::CemError;

pub use crate::ids::NodeId;

/// A node of the topology diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Unique id.
    pub id: NodeId,
    /// Coordinates. Only read for origin nodes (the prescribed positions); for every other
    /// node it is a starting guess that the solver overwrites.
    pub xyz: Vector3<f64>,
    /// Point load (a force vector) applied to the node.
    pub load: Vector3<f64>,
    /// `true` if the node ends a trail. A support with no trail edge is a *reaction node*
    /// (Kappe's extension, see [`crate::Model`]).
    pub support: bool,
    /// Optional check: if `Some`, must match the derived origin role.
    pub origin: Option<bool>,
}

/// A plane given by a point and a normal (the normal need not be unit length).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point on the plane.
    pub origin: Vector3<f64>,
    /// The plane normal (normalized on use).
    pub normal: Vector3<f64>,
}

/// A trail edge with its signed target length.
#[derive(Debug, Clone, PartialEq)]
pub struct TrailEdge {
    /// One end (orientation carries no meaning).
    pub u: NodeId,
    /// Other end.
    pub v: NodeId,
    /// Signed length λ: `< 0` compression, `> 0` tension.
    pub length: f64,
    /// Optional plane: the edge length becomes the signed distance along the residual from
    /// the node to this plane (cem.md §4.4); `length` is the fallback when the ray is parallel.
    pub plane: Option<Plane>,
}

/// A deviation edge with its signed force.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviationEdge {
    /// One end.
    pub u: NodeId,
    /// Other end.
    pub v: NodeId,
    /// Signed force μ: `< 0` compression, `> 0` tension.
    pub force: f64,
}

/// Options of automatically generated auxiliary trails (cem.md §1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AuxiliaryTrails {
    /// Signed length of every auxiliary trail edge (compas default −1).
    pub length: f64,
    /// Direction used only for the initial position of the auxiliary support (never the result).
    pub vector: Vector3<f64>,
}

impl Default for AuxiliaryTrails {
    fn default() -> Self {
        Self {
            length: -1.0,
            vector: Vector3::new(1.0, 1.0, 1.0),
        }
    }
}

/// Shift of a trail: its nodes get sequences `start, start+1, …` (compas `shift_trail`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrailShift {
    /// The origin node of the trail.
    pub origin: NodeId,
    /// Sequence of the origin.
    pub start: usize,
}

/// A complete topology diagram. Node order matters: trails are processed in the order in
/// which their supports appear in `nodes` (compas_cem's order, cem.md §2).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Topology {
    /// Free-text name (copied to outputs).
    pub name: String,
    /// Nodes in insertion order.
    pub nodes: Vec<Node>,
    /// Trail edges.
    pub trail_edges: Vec<TrailEdge>,
    /// Deviation edges.
    pub deviation_edges: Vec<DeviationEdge>,
    /// `Some` to generate auxiliary trails for nodes that have no trail edge.
    pub auxiliary_trails: Option<AuxiliaryTrails>,
    /// Trail shifts, applied after the trails are built.
    pub trail_shifts: Vec<TrailShift>,
}

impl Topology {
    /// Start a [`TopologyBuilder`].
    pub fn builder() -> TopologyBuilder {
        TopologyBuilder::default()
    }

    /// Index of the node with this id in `nodes` (linear search; [`crate::Model`] keeps a map).
    pub fn node_index(&self, id: NodeId) -> Option<usize> {
        self.nodes.iter().position(|n| n.id == id)
    }

    /// Index of the trail edge joining `a` and `b` in either orientation.
    pub fn trail_edge_index(&self, a: NodeId, b: NodeId) -> Option<usize> {
        self.trail_edges
            .iter()
            .position(|e| (e.u == a && e.v == b) || (e.u == b && e.v == a))
    }

    /// Index of the deviation edge joining `a` and `b` in either orientation.
    pub fn deviation_edge_index(&self, a: NodeId, b: NodeId) -> Option<usize> {
        self.deviation_edges
            .iter()
            .position(|e| (e.u == a && e.v == b) || (e.u == b && e.v == a))
    }
}

/// Chaining builder for a [`Topology`] in code.
///
/// ```
/// use kappe_cem::{Topology, SolverOptions, solve};
/// // Two one-edge compression trails joined by a compression deviation edge
/// // (compas_cem's "threebar funicular").
/// let topo = Topology::builder()
///     .node(0, [0.0, 0.0, 0.0]).support(0)
///     .node(1, [1.0, 0.0, 0.0]).load(1, [0.0, -1.0, 0.0])
///     .node(2, [2.5, 0.0, 0.0]).load(2, [0.0, -1.0, 0.0])
///     .node(3, [3.5, 0.0, 0.0]).support(3)
///     .trail_edge(0, 1, -1.0)
///     .trail_edge(2, 3, -1.0)
///     .deviation_edge(1, 2, -1.0)
///     .build()?;
/// let eq = solve(&topo, &SolverOptions::default())?;
/// let r = eq.reaction(0).unwrap();
/// assert!((r - nalgebra::Vector3::new(1.0, 1.0, 0.0)).norm() < 1e-12);
/// # Ok::<(), kappe_cem::CemError>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct TopologyBuilder {
    topo: Topology,
    /// Id references to unknown nodes are recorded here and reported by `build`.
    pending_error: Option<CemError>,
}

impl TopologyBuilder {
    /// Set the name.
    pub fn name(mut self, name: impl Into<String>) -> Self {
        self.topo.name = name.into();
        self
    }

    /// Add a plain node (no load, not a support).
    pub fn node(mut self, id: NodeId, xyz: [f64; 3]) -> Self {
        self.topo.nodes.push(Node {
            id,
            xyz: Vector3::from(xyz),
            load: Vector3::zeros(),
            support: false,
            origin: None,
        });
        self
    }

    fn with_node(mut self, id: NodeId, what: &str, f: impl FnOnce(&mut Node)) -> Self {
        // Last match: a duplicate id is reported by `build`, so which one we touch is moot.
        match self.topo.nodes.iter_mut().rev().find(|n| n.id == id) {
            Some(n) => f(n),
            None => {
                self.pending_error.get_or_insert(CemError::UnknownNode {
                    id,
                    context: format!("builder `{what}`"),
                });
            }
        }
        self
    }

    /// Add `q` to the load of node `id`.
    pub fn load(self, id: NodeId, q: [f64; 3]) -> Self {
        self.with_node(id, "load", |n| n.load += Vector3::from(q))
    }

    /// Mark node `id` as a support.
    pub fn support(self, id: NodeId) -> Self {
        self.with_node(id, "support", |n| n.support = true)
    }

    /// Add a trail edge with signed length λ.
    pub fn trail_edge(mut self, u: NodeId, v: NodeId, length: f64) -> Self {
        self.topo.trail_edges.push(TrailEdge {
            u,
            v,
            length,
            plane: None,
        });
        self
    }

    /// Add a trail edge whose length is cut by a plane (cem.md §4.4).
    pub fn trail_edge_to_plane(mut self, u: NodeId, v: NodeId, length: f64, plane: Plane) -> Self {
        self.topo.trail_edges.push(TrailEdge {
            u,
            v,
            length,
            plane: Some(plane),
        });
        self
    }

    /// Add a deviation edge with signed force μ.
    pub fn deviation_edge(mut self, u: NodeId, v: NodeId, force: f64) -> Self {
        self.topo
            .deviation_edges
            .push(DeviationEdge { u, v, force });
        self
    }

    /// Enable auxiliary trails.
    pub fn auxiliary_trails(mut self, aux: AuxiliaryTrails) -> Self {
        self.topo.auxiliary_trails = Some(aux);
        self
    }

    /// Shift the trail starting at `origin` to start at sequence `start`.
    pub fn shift_trail(mut self, origin: NodeId, start: usize) -> Self {
        self.topo.trail_shifts.push(TrailShift { origin, start });
        self
    }

    /// Finish, checking ids, finiteness and edge endpoints (trail building is checked by
    /// [`crate::Model::new`]).
    pub fn build(self) -> Result<Topology, CemError> {
        if let Some(e) = self.pending_error {
            return Err(e);
        }
        check_elements(&self.topo)?;
        Ok(self.topo)
    }
}

/// Node id → model index. Ids are usually dense small integers, so ids below a cap
/// (4·n + 1024) live in a plain table and only the rest in a hash map: the lookups of
/// trail building dominated a 500-node solve with a hash map alone.
#[derive(Debug, Clone, Default)]
pub(crate) struct IdIndex {
    dense: Vec<usize>,
    sparse: HashMap<NodeId, usize>,
}

impl IdIndex {
    fn with_capacity(n: usize) -> Self {
        Self {
            dense: vec![usize::MAX; 4 * n + 1024],
            sparse: HashMap::new(),
        }
    }

    /// Ids `0..n` at indices `0..n` (a network given by index, [`crate::Model::from_trails`]).
    pub(crate) fn identity(n: usize) -> Self {
        Self {
            dense: (0..n).collect(),
            sparse: HashMap::new(),
        }
    }

    pub(crate) fn get(&self, id: &NodeId) -> Option<&usize> {
        match usize::try_from(*id).ok().and_then(|k| self.dense.get(k)) {
            Some(i) if *i != usize::MAX => Some(i),
            Some(_) => None,
            None => self.sparse.get(id),
        }
    }

    pub(crate) fn contains_key(&self, id: &NodeId) -> bool {
        self.get(id).is_some()
    }

    /// Insert; returns the previous index if the id was present.
    pub(crate) fn insert(&mut self, id: NodeId, i: usize) -> Option<usize> {
        match usize::try_from(id).ok().and_then(|k| self.dense.get_mut(k)) {
            Some(slot) => {
                let old = *slot;
                *slot = i;
                (old != usize::MAX).then_some(old)
            }
            None => self.sparse.insert(id, i),
        }
    }
}

fn finite(what: impl FnOnce() -> String, value: f64) -> Result<(), CemError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(CemError::NonFinite {
            what: what(),
            value,
        })
    }
}

fn finite3(what: impl Fn() -> String, v: &Vector3<f64>) -> Result<(), CemError> {
    for (i, c) in v.iter().enumerate() {
        finite(|| format!("{}[{i}]", what()), *c)?;
    }
    Ok(())
}

/// Whether two of `ends` (node index pairs, lower first, indices below `n`) join the same two
/// nodes: bucket the pairs by their lower end, then mark the upper ends per bucket. O(n + edges).
fn has_duplicate(n: usize, ends: &[(usize, usize)]) -> bool {
    let mut start = vec![0usize; n + 1];
    for &(a, _) in ends {
        start[a + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut upper = vec![0usize; ends.len()];
    for &(a, b) in ends {
        upper[fill[a]] = b;
        fill[a] += 1;
    }
    let mut seen = vec![usize::MAX; n];
    (0..n).any(|a| {
        upper[start[a]..start[a + 1]].iter().any(|&b| {
            let again = seen[b] == a;
            seen[b] = a;
            again
        })
    })
}

/// Element-level checks shared by [`crate::TopologyBuilder::build`] and [`Model::new`].
pub(crate) fn check_elements(topo: &Topology) -> Result<IdIndex, CemError> {
    let mut index = IdIndex::with_capacity(topo.nodes.len());
    for (i, n) in topo.nodes.iter().enumerate() {
        if index.insert(n.id, i).is_some() {
            return Err(CemError::DuplicateNode { id: n.id });
        }
        finite3(|| format!("node {} xyz", n.id), &n.xyz)?;
        finite3(|| format!("node {} load", n.id), &n.load)?;
    }
    // Duplicate pairs are found by sorting after the loop; descriptions are only formatted
    // on error (this check runs on every solve).
    let mut pairs: Vec<((NodeId, NodeId), usize)> =
        Vec::with_capacity(topo.trail_edges.len() + topo.deviation_edges.len());
    // Node indices of every edge's ends, lower first: the linear-time duplicate check below.
    let mut ends: Vec<(usize, usize)> = Vec::with_capacity(pairs.capacity());
    let check_pair = |pairs: &mut Vec<((NodeId, NodeId), usize)>,
                      ends: &mut Vec<(usize, usize)>,
                      kind: &'static str,
                      u: NodeId,
                      v: NodeId|
     -> Result<(), CemError> {
        let mut at = [0usize; 2];
        for (slot, id) in at.iter_mut().zip([u, v]) {
            *slot = *index.get(&id).ok_or_else(|| CemError::UnknownNode {
                id,
                context: format!("{kind} edge ({u}, {v})"),
            })?;
        }
        if u == v {
            return Err(CemError::SelfLoop { kind, u });
        }
        let k = pairs.len();
        pairs.push(((u.min(v), u.max(v)), k));
        ends.push((at[0].min(at[1]), at[0].max(at[1])));
        Ok(())
    };
    for e in &topo.trail_edges {
        check_pair(&mut pairs, &mut ends, "trail", e.u, e.v)?;
        finite(|| format!("trail edge ({}, {}) length", e.u, e.v), e.length)?;
        if let Some(p) = &e.plane {
            finite3(
                || format!("trail edge ({}, {}) plane origin", e.u, e.v),
                &p.origin,
            )?;
            finite3(
                || format!("trail edge ({}, {}) plane normal", e.u, e.v),
                &p.normal,
            )?;
            if p.normal.norm() == 0.0 {
                return Err(CemError::ZeroPlaneNormal { u: e.u, v: e.v });
            }
        }
    }
    for e in &topo.deviation_edges {
        check_pair(&mut pairs, &mut ends, "deviation", e.u, e.v)?;
        finite(
            || format!("deviation edge ({}, {}) force", e.u, e.v),
            e.force,
        )?;
    }
    // The sort names the first duplicate in id order; it runs only when the linear check
    // found one (sorting every solve's edges was a fifth of a cap's form-finding).
    if has_duplicate(topo.nodes.len(), &ends) {
        pairs.sort_unstable();
    }
    if let Some(w) = pairs.windows(2).find(|w| w[0].0 == w[1].0) {
        let n_trail = topo.trail_edges.len();
        let describe = |k: usize| match k.checked_sub(n_trail) {
            None => topo
                .trail_edges
                .get(k)
                .map_or_else(String::new, |e| format!("trail edge ({}, {})", e.u, e.v)),
            Some(d) => topo.deviation_edges.get(d).map_or_else(String::new, |e| {
                format!("deviation edge ({}, {})", e.u, e.v)
            }),
        };
        let ((u, v), _) = w[1];
        return Err(CemError::DuplicateEdge {
            u,
            v,
            first: describe(w[0].1),
            second: describe(w[1].1),
        });
    }
    if let Some(aux) = &topo.auxiliary_trails {
        finite(|| "auxiliary_trails.length".to_string(), aux.length)?;
        finite3(|| "auxiliary_trails.vector".to_string(), &aux.vector)?;
    }
    for s in &topo.trail_shifts {
        if !index.contains_key(&s.origin) {
            return Err(CemError::UnknownNode {
                id: s.origin,
                context: "trail shift".to_string(),
            });
        }
    }
    Ok(index)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The linear-time check agrees with a brute-force comparison of every two edges, on random
    /// small graphs (seeded) where duplicates are common and on ones without any.
    #[test]
    fn linear_duplicate_check_agrees_with_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut found = [0usize; 2];
        for _ in 0..2000 {
            let n = rng.random_range(2..12usize);
            let m = rng.random_range(0..2 * n);
            let ends: Vec<(usize, usize)> = (0..m)
                .map(|_| {
                    let a = rng.random_range(0..n);
                    let b = (a + rng.random_range(1..n)) % n;
                    (a.min(b), a.max(b))
                })
                .collect();
            let brute = (0..m).any(|i| (i + 1..m).any(|j| ends[i] == ends[j]));
            assert_eq!(has_duplicate(n, &ends), brute, "{ends:?}");
            found[usize::from(brute)] += 1;
        }
        // Both outcomes occurred, so the comparison tested each.
        assert!(found[0] > 100 && found[1] > 100, "{found:?}");
    }

    /// A trail edge and a deviation edge joining the same two nodes (given in either order)
    /// are one duplicate, named with both edges; node ids far from dense (the hash-map part
    /// of the index) behave the same.
    #[test]
    fn a_duplicate_edge_is_named_with_both_edges() {
        for base in [0u64, 1 << 40] {
            let t = TopologyBuilder::default()
                .node(base, [0.0, 0.0, 0.0])
                .node(base + 1, [1.0, 0.0, 0.0])
                .node(base + 2, [2.0, 0.0, 0.0])
                .support(base + 1)
                .trail_edge(base, base + 1, -1.0)
                .deviation_edge(base + 2, base, 1.0)
                .deviation_edge(base + 1, base, 1.0)
                .build();
            match t {
                Err(CemError::DuplicateEdge {
                    u,
                    v,
                    first,
                    second,
                }) => {
                    assert_eq!((u, v), (base, base + 1));
                    assert_eq!(first, format!("trail edge ({base}, {})", base + 1));
                    assert_eq!(second, format!("deviation edge ({}, {base})", base + 1));
                }
                other => panic!("expected a duplicate edge, got {other:?}"),
            }
        }
    }
}
