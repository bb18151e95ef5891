//! Trail building and validation (cem.md §2): from a [`Topology`] to a [`Model`], the
//! flat, index-based form the solver sweeps over.
//!
//! Steps, in order:
//! 1. element checks: unique finite nodes, known edge ends, no self loops, one edge per pair;
//! 2. auxiliary trails (if enabled): every non-support node without a trail edge gets a new
//!    support `max_id + 1, …` (ascending in the id of the node it hangs from) and a trail edge
//!    of the auxiliary length;
//! 3. trails: from each support in node order, walk trail edges to the far end, the origin.
//!    A support with **no** trail edge is a *reaction node*: a one-node trail whose origin is
//!    the support itself. Its position is prescribed (like any origin) and its reaction is
//!    `R = −q − D` (Kappe's extension over compas_cem, needed for the cap's arch feet);
//! 4. trail shifts; a reaction node without an explicit shift takes the largest sequence of
//!    the trail nodes it is joined to by deviation edges (or 0), so that it is processed
//!    together with them and its edges are direct when the neighbours share one sequence;
//! 5. direct/indirect classification (`k(u) == k(v)`) and the step schedule: for `k = 0..=K`,
//!    for each trail in trail order, the node of that trail at sequence `k`.
//!
//! Everything compas_cem accepts silently but gets wrong (two supports on one chain,
//! T-junctions, cycles, supports inside a trail) is a typed [`CemError`] here.

use nalgebra::Vector3;

use crate::error::CemError;
use crate::topology::{IdIndex, NodeId, Topology, check_elements};

/// One node step of a sweep: the node, and for non-supports the outgoing trail edge and the
/// next node of the trail.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Step {
    pub node: usize,
    pub out: Option<(usize, usize)>,
}

/// A deviation-edge entry of a node's adjacency list.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Adj {
    pub other: usize,
    pub edge: usize,
}

/// A plane with a unit normal, for plane-cut trail edges.
#[derive(Debug, Clone, Copy)]
pub(crate) struct UnitPlane {
    pub origin: Vector3<f64>,
    pub normal: Vector3<f64>,
}

/// A trail as built: node indices from origin to support, the trail edge index between
/// consecutive nodes, and the sequence of its origin.
#[derive(Debug, Clone)]
pub(crate) struct TrailData {
    pub nodes: Vec<usize>,
    pub edges: Vec<usize>,
    pub start: usize,
}

/// An auxiliary trail added by the model: (node index, aux node index).
#[derive(Debug, Clone, Copy)]
pub(crate) struct AuxData {
    pub node: usize,
    pub aux: usize,
}

/// A validated topology with its trails, sequences and schedule, ready to be solved many
/// times (with changed lengths, forces, loads or origin positions).
///
/// Node indices: the topology's nodes in order, then the auxiliary nodes. Trail-edge
/// indices: the topology's trail edges in order, then the auxiliary edges. Deviation-edge
/// indices: as in the topology.
#[derive(Debug, Clone)]
pub struct Model {
    pub(crate) name: String,
    pub(crate) ids: Vec<NodeId>,
    pub(crate) index: IdIndex,
    pub(crate) xyz0: Vec<Vector3<f64>>,
    pub(crate) loads: Vec<Vector3<f64>>,
    pub(crate) is_support: Vec<bool>,
    pub(crate) is_origin: Vec<bool>,
    pub(crate) sequence: Vec<usize>,
    pub(crate) trail_u: Vec<usize>,
    pub(crate) trail_v: Vec<usize>,
    pub(crate) lengths: Vec<f64>,
    /// Per trail edge; empty when no edge is plane-cut ([`Model::from_trails`]).
    pub(crate) planes: Vec<Option<UnitPlane>>,
    pub(crate) dev_u: Vec<usize>,
    pub(crate) dev_v: Vec<usize>,
    pub(crate) forces: Vec<f64>,
    pub(crate) direct: Vec<bool>,
    pub(crate) trails: Vec<TrailData>,
    pub(crate) steps: Vec<Step>,
    /// CSR adjacency of deviation edges: node `n` owns `adj[adj_start[n]..adj_start[n+1]]`,
    /// direct entries first, indirect ones from `adj_split[n]`.
    pub(crate) adj_start: Vec<usize>,
    pub(crate) adj_split: Vec<usize>,
    pub(crate) adj: Vec<Adj>,
    pub(crate) has_indirect: bool,
    pub(crate) aux: Vec<AuxData>,
    pub(crate) n_input_trail_edges: usize,
}

/// A network given by node index, for [`Model::from_trails`]: nodes `0..n` (positions, loads,
/// support flags), its trails and its deviation edges.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct IndexedNetwork {
    /// Free-text name (copied to outputs).
    pub name: String,
    /// Node positions (the prescribed ones of origins; starting guesses elsewhere).
    pub positions: Vec<Vector3<f64>>,
    /// Node loads (force vectors).
    pub loads: Vec<Vector3<f64>>,
    /// Whether each node is a support; a support on no trail is a reaction node.
    pub supports: Vec<bool>,
    /// Every trail of two or more nodes: node indices from the origin to the support.
    pub trails: Vec<Vec<usize>>,
    /// Signed length λ of every trail edge (`< 0` compression), trail by trail, origin end first.
    pub lengths: Vec<f64>,
    /// Deviation edges: the two node indices and the signed force μ (`< 0` compression).
    pub deviation_edges: Vec<(usize, usize, f64)>,
}

/// compas `normalize_vector`: v/‖v‖, and the zero vector for v = 0.
fn unit_f64(v: Vector3<f64>) -> Vector3<f64> {
    let n = v.norm();
    if n == 0.0 { v } else { v / n }
}

/// The steps in ascending sequence, trail order within a sequence (a stable sort by sequence):
/// a counting sort when the sequences are dense (every model built from a topology without
/// far-shifted trails), else the library's stable sort.
fn by_sequence(steps: Vec<(usize, Step)>) -> Vec<Step> {
    let len = steps.len();
    let top = steps.iter().map(|(k, _)| *k).max().unwrap_or(0);
    if top > 4 * len + 1024 {
        let mut steps = steps;
        steps.sort_by_key(|(k, _)| *k);
        return steps.into_iter().map(|(_, s)| s).collect();
    }
    let mut start = vec![0usize; top + 2];
    for (k, _) in &steps {
        start[k + 1] += 1;
    }
    for k in 0..=top {
        start[k + 1] += start[k];
    }
    // Every slot is written once: the counts place each step in its own slot.
    let mut out = vec![Step { node: 0, out: None }; len];
    for (k, s) in steps {
        out[start[k]] = s;
        start[k] += 1;
    }
    out
}

/// Whether each node is the origin (first node) of a trail.
fn origins(n: usize, trails: &[TrailData]) -> Vec<bool> {
    let mut is_origin = vec![false; n];
    for t in trails {
        if let Some(&o) = t.nodes.first() {
            is_origin[o] = true;
        }
    }
    is_origin
}

/// What both constructors derive from the built trails (steps 4–5 of the module docs): the
/// sequences, the direct/indirect flags, the deviation adjacency and the step schedule.
struct Schedule {
    sequence: Vec<usize>,
    direct: Vec<bool>,
    has_indirect: bool,
    adj_start: Vec<usize>,
    adj_split: Vec<usize>,
    adj: Vec<Adj>,
    steps: Vec<Step>,
}

impl Schedule {
    /// `trails` in processing order with their (shifted) starts, `shifted[k]` whether trail `k`
    /// has an explicit shift, `tdeg` the trail-edge count of every node, and the deviation edges'
    /// ends. Unshifted reaction nodes get their start here.
    fn new(
        trails: &mut [TrailData],
        shifted: &[bool],
        is_support: &[bool],
        tdeg: &[usize],
        dev_u: &[usize],
        dev_v: &[usize],
    ) -> Self {
        let n = is_support.len();
        let mut sequence = vec![0usize; n];
        for t in trails.iter() {
            for (j, &node) in t.nodes.iter().enumerate() {
                sequence[node] = t.start + j;
            }
        }

        // Reaction nodes follow the sequence of their (trail) neighbours.
        let is_reaction: Vec<bool> = (0..n).map(|i| is_support[i] && tdeg[i] == 0).collect();
        // usize::MAX: no trail neighbour (the start stays 0).
        let mut reaction_seq = vec![usize::MAX; n];
        for (&u, &v) in dev_u.iter().zip(dev_v) {
            for (a, b) in [(u, v), (v, u)] {
                if is_reaction[a] && !is_reaction[b] {
                    reaction_seq[a] = match reaction_seq[a] {
                        usize::MAX => sequence[b],
                        s => s.max(sequence[b]),
                    };
                }
            }
        }
        for (k, t) in trails.iter_mut().enumerate() {
            if let [only] = t.nodes[..]
                && is_reaction[only]
                && !shifted[k]
            {
                t.start = match reaction_seq[only] {
                    usize::MAX => 0,
                    s => s,
                };
                sequence[only] = t.start;
            }
        }

        // Deviation adjacency (CSR), direct entries first.
        let direct: Vec<bool> = dev_u
            .iter()
            .zip(dev_v)
            .map(|(&u, &v)| sequence[u] == sequence[v])
            .collect();
        let has_indirect = direct.iter().any(|d| !d);
        let mut count = vec![0usize; n + 1];
        for (&u, &v) in dev_u.iter().zip(dev_v) {
            count[u + 1] += 1;
            count[v + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let adj_start = count;
        let mut fill = adj_start.clone();
        let mut adj = vec![Adj { other: 0, edge: 0 }; adj_start[n]];
        for pass_direct in [true, false] {
            for (e, (&u, &v)) in dev_u.iter().zip(dev_v).enumerate() {
                if direct[e] != pass_direct {
                    continue;
                }
                for (a, b) in [(u, v), (v, u)] {
                    adj[fill[a]] = Adj { other: b, edge: e };
                    fill[a] += 1;
                }
            }
        }
        let mut adj_split = vec![0usize; n];
        for i in 0..n {
            let range = adj_start[i]..adj_start[i + 1];
            adj_split[i] = range.start
                + adj[range.clone()]
                    .iter()
                    .take_while(|a| direct[a.edge])
                    .count();
        }

        // Schedule: k-major, trail order within a sequence (stable sort keeps trail order).
        let mut steps: Vec<(usize, Step)> = Vec::with_capacity(n);
        for t in trails.iter() {
            for (j, &node) in t.nodes.iter().enumerate() {
                let out = match (t.edges.get(j), t.nodes.get(j + 1)) {
                    (Some(&e), Some(&next)) => Some((e, next)),
                    _ => None,
                };
                steps.push((t.start + j, Step { node, out }));
            }
        }
        let steps = by_sequence(steps);
        Schedule {
            sequence,
            direct,
            has_indirect,
            adj_start,
            adj_split,
            adj,
            steps,
        }
    }
}

impl Model {
    /// Validate `topo`, build its trails and the solve schedule (see the module docs).
    pub fn new(topo: &Topology) -> Result<Self, CemError> {
        let mut index = check_elements(topo)?;

        let mut ids: Vec<NodeId> = topo.nodes.iter().map(|n| n.id).collect();
        let mut xyz0: Vec<Vector3<f64>> = topo.nodes.iter().map(|n| n.xyz).collect();
        let mut loads: Vec<Vector3<f64>> = topo.nodes.iter().map(|n| n.load).collect();
        let mut is_support: Vec<bool> = topo.nodes.iter().map(|n| n.support).collect();
        let mut trail_u = Vec::with_capacity(topo.trail_edges.len());
        let mut trail_v = Vec::with_capacity(topo.trail_edges.len());
        let mut lengths = Vec::with_capacity(topo.trail_edges.len());
        let mut planes = Vec::with_capacity(topo.trail_edges.len());
        for e in &topo.trail_edges {
            // Ends are known: check_elements verified them.
            trail_u.push(index.get(&e.u).copied().unwrap_or_default());
            trail_v.push(index.get(&e.v).copied().unwrap_or_default());
            lengths.push(e.length);
            planes.push(e.plane.map(|p| UnitPlane {
                origin: p.origin,
                normal: p.normal / p.normal.norm(),
            }));
        }
        let n_input_trail_edges = trail_u.len();

        let mut degree = vec![0usize; ids.len()];
        for (&u, &v) in trail_u.iter().zip(&trail_v) {
            degree[u] += 1;
            degree[v] += 1;
        }

        // Auxiliary trails for non-support nodes without trail edges.
        let mut aux = Vec::new();
        if let Some(a) = &topo.auxiliary_trails {
            let mut hang: Vec<usize> = (0..ids.len())
                .filter(|&i| degree[i] == 0 && !is_support[i])
                .collect();
            hang.sort_by_key(|&i| ids[i]);
            let mut next_id = ids.iter().copied().max().unwrap_or(0);
            let dir = unit_f64(a.vector);
            for i in hang {
                next_id = next_id.checked_add(1).ok_or(CemError::InvalidOption {
                    name: "auxiliary node id",
                    value: next_id as f64,
                    allowed: "node ids must leave room for auxiliary node ids below u64::MAX",
                })?;
                let k = ids.len();
                ids.push(next_id);
                index.insert(next_id, k);
                xyz0.push(xyz0[i] + dir * a.length);
                loads.push(Vector3::zeros());
                is_support.push(true);
                degree.push(1);
                degree[i] += 1;
                aux.push(AuxData { node: i, aux: k });
                trail_u.push(i);
                trail_v.push(k);
                lengths.push(a.length);
                planes.push(None);
            }
        }
        let n = ids.len();

        // Trail adjacency, at most two trail edges per node.
        let mut tadj: Vec<[(usize, usize); 2]> = vec![[(usize::MAX, usize::MAX); 2]; n];
        let mut tdeg = vec![0usize; n];
        for (e, (&u, &v)) in trail_u.iter().zip(&trail_v).enumerate() {
            for (a, b) in [(u, v), (v, u)] {
                if tdeg[a] >= 2 {
                    let edges: Vec<String> = (0..trail_u.len())
                        .filter(|&k| trail_u[k] == a || trail_v[k] == a)
                        .map(|k| format!("({}, {})", ids[trail_u[k]], ids[trail_v[k]]))
                        .collect();
                    return Err(CemError::NodeOnTwoTrails {
                        id: ids[a],
                        count: edges.len(),
                        edges: edges.join(", "),
                    });
                }
                tadj[a][tdeg[a]] = (e, b);
                tdeg[a] += 1;
            }
        }

        if !is_support.iter().any(|&s| s) {
            // compas checks supports before unassigned nodes ("No supports assigned!").
            return Err(CemError::NoSupport);
        }

        // Walk from each support in node order.
        let mut visited = vec![false; n];
        let mut trails: Vec<TrailData> = Vec::new();
        for s in 0..n {
            if !is_support[s] {
                continue;
            }
            if tdeg[s] == 2 {
                return Err(CemError::SupportInsideTrail { id: ids[s] });
            }
            let mut nodes = vec![s];
            let mut edges = Vec::new();
            visited[s] = true;
            let mut cur = s;
            let mut prev_edge = usize::MAX;
            loop {
                let next = tadj[cur][..tdeg[cur]]
                    .iter()
                    .copied()
                    .find(|&(e, _)| e != prev_edge);
                let Some((e, m)) = next else { break };
                if is_support[m] {
                    return Err(CemError::TrailWithTwoSupports {
                        first: ids[s],
                        second: ids[m],
                    });
                }
                // Degree ≤ 2 and the walk starts at a degree-1 end, so it cannot revisit;
                // keep the check anyway as a guard against an infinite loop.
                if visited[m] {
                    return Err(CemError::TrailCycle {
                        nodes: nodes.iter().map(|&i| ids[i]).collect(),
                    });
                }
                visited[m] = true;
                nodes.push(m);
                edges.push(e);
                prev_edge = e;
                cur = m;
            }
            nodes.reverse();
            edges.reverse();
            trails.push(TrailData {
                nodes,
                edges,
                start: 0,
            });
        }

        if let Some(first) = (0..n).find(|&i| !visited[i]) {
            if tdeg[first] == 0 {
                return Err(CemError::UnassignedNode { id: ids[first] });
            }
            // Collect the connected chain of trail edges through `first`.
            let mut comp = vec![first];
            let mut seen = vec![first];
            let mut stack = vec![first];
            while let Some(a) = stack.pop() {
                for &(_, b) in &tadj[a][..tdeg[a]] {
                    if !seen.contains(&b) {
                        seen.push(b);
                        comp.push(b);
                        stack.push(b);
                    }
                }
            }
            let nodes: Vec<NodeId> = comp.iter().map(|&i| ids[i]).collect();
            return Err(if comp.iter().all(|&i| tdeg[i] == 2) {
                CemError::TrailCycle { nodes }
            } else {
                CemError::TrailWithoutSupport { nodes }
            });
        }

        let is_origin = origins(n, &trails);
        for (i, node) in topo.nodes.iter().enumerate() {
            if let Some(given) = node.origin
                && given != is_origin[i]
            {
                return Err(CemError::OriginMismatch {
                    id: node.id,
                    given,
                    derived: if is_origin[i] {
                        "an origin"
                    } else {
                        "a non-origin node"
                    },
                });
            }
        }

        // Shifts.
        let mut trail_of_origin: Vec<Option<usize>> = vec![None; n];
        for (k, t) in trails.iter().enumerate() {
            if let Some(&o) = t.nodes.first() {
                trail_of_origin[o] = Some(k);
            }
        }
        let mut shifted = vec![false; trails.len()];
        for s in &topo.trail_shifts {
            let o = index.get(&s.origin).copied().unwrap_or(usize::MAX);
            let Some(k) = trail_of_origin.get(o).copied().flatten() else {
                return Err(CemError::ShiftNotOrigin { id: s.origin });
            };
            if shifted[k] {
                return Err(CemError::DuplicateShift { id: s.origin });
            }
            shifted[k] = true;
            trails[k].start = s.start;
        }
        let dev_u: Vec<usize> = topo
            .deviation_edges
            .iter()
            .map(|e| index.get(&e.u).copied().unwrap_or_default())
            .collect();
        let dev_v: Vec<usize> = topo
            .deviation_edges
            .iter()
            .map(|e| index.get(&e.v).copied().unwrap_or_default())
            .collect();
        let forces: Vec<f64> = topo.deviation_edges.iter().map(|e| e.force).collect();
        let schedule = Schedule::new(&mut trails, &shifted, &is_support, &tdeg, &dev_u, &dev_v);

        Ok(Self {
            name: topo.name.clone(),
            ids,
            index,
            xyz0,
            loads,
            is_support,
            is_origin,
            sequence: schedule.sequence,
            trail_u,
            trail_v,
            lengths,
            planes,
            dev_u,
            dev_v,
            forces,
            direct: schedule.direct,
            trails,
            steps: schedule.steps,
            adj_start: schedule.adj_start,
            adj_split: schedule.adj_split,
            adj: schedule.adj,
            has_indirect: schedule.has_indirect,
            aux,
            n_input_trail_edges,
        })
    }

    /// Build the model of a network its caller constructed by node index ([`IndexedNetwork`]),
    /// without the element checks and the trail search of [`Model::new`]: for programs that
    /// build many valid networks (Kappe's print states, one per printed layer, on every change of
    /// a design) and would otherwise spend most of a force pass validating them.
    ///
    /// The model is the one [`Model::new`] builds from the equivalent [`Topology`] (node ids
    /// `0..n`, the trails' edges in the order given, origin end first, then the deviation edges;
    /// no auxiliary trails or shifts): the same trails, in the order of their supports' indices,
    /// the same sequences, adjacency and schedule (one implementation builds them), so a solve or
    /// force pass gives the same numbers bit for bit.
    ///
    /// Checked (linear time, no hashing): the arrays agree in length, every index names a node,
    /// every trail has at least two nodes, ends at a support and holds no other support, no node
    /// is on two trails, every non-support node is on a trail, there is a support, no deviation
    /// edge joins a node to itself. **Not** checked (the caller's construction guarantees them;
    /// use [`Model::new`] for anything a user can feed in): finite loads, lengths and forces, and
    /// no two edges joining the same two nodes.
    ///
    /// # Errors
    /// The first failed check, as [`Model::new`] would name it ([`CemError::InvalidNetwork`] for
    /// arrays of different lengths).
    pub fn from_trails(net: IndexedNetwork) -> Result<Self, CemError> {
        let IndexedNetwork {
            name,
            positions,
            loads,
            supports,
            trails: given,
            lengths,
            deviation_edges,
        } = net;
        let n = positions.len();
        if loads.len() != n || supports.len() != n {
            return Err(CemError::InvalidNetwork(format!(
                "{n} positions, {} loads and {} support flags; give one of each per node",
                loads.len(),
                supports.len()
            )));
        }
        let n_edges: usize = given.iter().map(|t| t.len().saturating_sub(1)).sum();
        if lengths.len() != n_edges {
            return Err(CemError::InvalidNetwork(format!(
                "{} trail lengths for {n_edges} trail edges; give one per edge, trail by trail",
                lengths.len()
            )));
        }
        let id = |i: usize| i as NodeId;
        // Each node's trail and the first edge index of every trail (edges numbered trail by
        // trail, as the equivalent topology lists them).
        let mut trail_of = vec![usize::MAX; n];
        let mut tdeg = vec![0usize; n];
        let mut trail_u = Vec::with_capacity(n_edges);
        let mut trail_v = Vec::with_capacity(n_edges);
        let mut first_edge = Vec::with_capacity(given.len());
        for (k, t) in given.iter().enumerate() {
            let (Some(&support), true) = (t.last(), t.len() >= 2) else {
                return Err(CemError::InvalidNetwork(format!(
                    "trail {k} has {} node(s); a trail has at least two (a support alone is a \
                     reaction node)",
                    t.len()
                )));
            };
            for (j, &i) in t.iter().enumerate() {
                if i >= n {
                    return Err(CemError::UnknownNode {
                        id: id(i),
                        context: format!("trail {k}"),
                    });
                }
                if trail_of[i] != usize::MAX {
                    return Err(CemError::NodeOnTwoTrails {
                        id: id(i),
                        count: 2,
                        edges: format!("trails {} and {k}", trail_of[i]),
                    });
                }
                trail_of[i] = k;
                tdeg[i] = if j == 0 || j + 1 == t.len() { 1 } else { 2 };
                if supports[i] && i != support {
                    return Err(if j == 0 {
                        CemError::TrailWithTwoSupports {
                            first: id(support),
                            second: id(i),
                        }
                    } else {
                        CemError::SupportInsideTrail { id: id(i) }
                    });
                }
            }
            if !supports[support] {
                return Err(CemError::TrailWithoutSupport {
                    nodes: t.iter().map(|&i| id(i)).collect(),
                });
            }
            first_edge.push(trail_u.len());
            for w in t.windows(2) {
                trail_u.push(w[0]);
                trail_v.push(w[1]);
            }
        }
        if !supports.iter().any(|&s| s) {
            return Err(CemError::NoSupport);
        }
        if let Some(i) = (0..n).find(|&i| trail_of[i] == usize::MAX && !supports[i]) {
            return Err(CemError::UnassignedNode { id: id(i) });
        }
        let mut dev_u = Vec::with_capacity(deviation_edges.len());
        let mut dev_v = Vec::with_capacity(deviation_edges.len());
        let mut forces = Vec::with_capacity(deviation_edges.len());
        for &(u, v, force) in &deviation_edges {
            for i in [u, v] {
                if i >= n {
                    return Err(CemError::UnknownNode {
                        id: id(i),
                        context: format!("deviation edge ({u}, {v})"),
                    });
                }
            }
            if u == v {
                return Err(CemError::SelfLoop {
                    kind: "deviation",
                    u: id(u),
                });
            }
            dev_u.push(u);
            dev_v.push(v);
            forces.push(force);
        }

        // Trails in the order of their supports (Model::new walks from each support in node
        // order); a support on no trail is a reaction node's one-node trail.
        let mut given = given;
        let mut trails = Vec::with_capacity(given.len() + n / 8);
        for s in (0..n).filter(|&s| supports[s]) {
            trails.push(match trail_of[s] {
                usize::MAX => TrailData {
                    nodes: vec![s],
                    edges: Vec::new(),
                    start: 0,
                },
                k => {
                    let nodes = std::mem::take(&mut given[k]);
                    let edges = (first_edge[k]..first_edge[k] + nodes.len() - 1).collect();
                    TrailData {
                        nodes,
                        edges,
                        start: 0,
                    }
                }
            });
        }
        let is_origin = origins(n, &trails);
        let shifted = vec![false; trails.len()];
        let schedule = Schedule::new(&mut trails, &shifted, &supports, &tdeg, &dev_u, &dev_v);
        let n_input_trail_edges = trail_u.len();
        Ok(Self {
            name,
            ids: (0..n).map(id).collect(),
            index: IdIndex::identity(n),
            xyz0: positions,
            loads,
            is_support: supports,
            is_origin,
            sequence: schedule.sequence,
            trail_u,
            trail_v,
            // No plane-cut edges (an empty list: no per-edge `None` to write for every state).
            planes: Vec::new(),
            lengths,
            dev_u,
            dev_v,
            forces,
            direct: schedule.direct,
            trails,
            steps: schedule.steps,
            adj_start: schedule.adj_start,
            adj_split: schedule.adj_split,
            adj: schedule.adj,
            has_indirect: schedule.has_indirect,
            aux: Vec::new(),
            n_input_trail_edges,
        })
    }

    /// Number of nodes including auxiliary nodes.
    pub fn node_count(&self) -> usize {
        self.ids.len()
    }

    /// The positions the model was built with (topology order, then auxiliary nodes): the
    /// prescribed ones of origins, starting guesses elsewhere; all of them for a network whose
    /// geometry is fixed ([`Model::force_pass`]).
    pub fn initial_positions(&self) -> &[Vector3<f64>] {
        &self.xyz0
    }

    /// Node ids in model order (topology order, then auxiliary nodes).
    pub fn node_ids(&self) -> &[NodeId] {
        &self.ids
    }

    /// Model index of a node id.
    pub fn node_index(&self, id: NodeId) -> Option<usize> {
        self.index.get(&id).copied()
    }

    /// Sequence `k(n)` of every node, in model order.
    pub fn sequences(&self) -> &[usize] {
        &self.sequence
    }

    /// The trails as node-id lists from origin to support, in processing order.
    pub fn trails(&self) -> Vec<Vec<NodeId>> {
        self.trails
            .iter()
            .map(|t| t.nodes.iter().map(|&i| self.ids[i]).collect())
            .collect()
    }

    /// `true` for each deviation edge (topology order) whose ends share a sequence.
    pub fn direct_flags(&self) -> &[bool] {
        &self.direct
    }

    /// Whether any deviation edge is indirect (the solve then iterates).
    pub fn has_indirect_edges(&self) -> bool {
        self.has_indirect
    }

    /// Auxiliary trails created: `(node, auxiliary support)` id pairs.
    pub fn auxiliary_trails(&self) -> Vec<(NodeId, NodeId)> {
        self.aux
            .iter()
            .map(|a| (self.ids[a.node], self.ids[a.aux]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The counting sort equals the library's stable sort by sequence (ties keep their order),
    /// for dense sequences and for far-shifted ones (the fallback), on seeded random inputs.
    #[test]
    fn by_sequence_is_a_stable_sort_by_sequence() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for spread in [8usize, 1 << 20] {
            for _ in 0..200 {
                let len = rng.random_range(0..60usize);
                let steps: Vec<(usize, Step)> = (0..len)
                    .map(|node| {
                        let k = rng.random_range(0..spread);
                        (k, Step { node, out: None })
                    })
                    .collect();
                let mut expected = steps.clone();
                expected.sort_by_key(|(k, _)| *k);
                let got: Vec<usize> = by_sequence(steps).iter().map(|s| s.node).collect();
                let want: Vec<usize> = expected.iter().map(|(_, s)| s.node).collect();
                assert_eq!(got, want);
            }
        }
    }
}
