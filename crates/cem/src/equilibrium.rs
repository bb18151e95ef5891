//! The sequential nodal equilibrium of CEM (cem.md §4), written once, generic over the
//! scalar: plain `f64` for solves, [`num_dual::Dual64`] for exact forward-mode gradients.
//!
//! No crate implements CEM, hence this hand-written solver. Per sweep `t`, for
//! `k = 0..=K`, for each trail in trail order, the node `n` at sequence `k` does
//!
//! ```text
//! D_n = Σ_{deviation edges {n,m}} μ_e · û(x_m − x_n)     (indirect edges only when t ≥ 1)
//! r_n = r_in[n] − q_n − D_n                                (force of the next trail edge on n)
//! support:      R_n = r_n                                  (force of the support on the structure)
//! otherwise:    λ = λ_e  (or the plane cut, §4.4)
//!               x_s = x_n + λ · û(r_n),   F_e = copysign(‖r_n‖, λ),   r_in[s] = r_n
//! ```
//!
//! with `û(0) = 0` and a zero derivative there ("safe normalize", so zero residuals do not
//! poison gradients, cem.md §7). Positions are updated in place (Gauss–Seidel, as compas).
//! After sweep `t ≥ 1` the loop stops when `δ = Σ_n ‖x_n − x_prev,n‖ < η`; if after `tmax`
//! sweeps `δ > η`, the solve fails with [`CemError::NotConverged`]. Without indirect edges
//! the second sweep would repeat the first exactly, so it is skipped and reported as done
//! (`sweeps = 2`, `δ = 0`), as compas reports it.
//!
//! Signs: trail force `F < 0` is compression; the reaction is the force the support exerts
//! on the structure; every node satisfies `q_n + Σ_e F_e û(x_other − x_n) + R_n = 0`.

use nalgebra::Vector3;
use num_dual::DualNum;

use crate::error::CemError;
use crate::model::Model;
use crate::topology::{NodeId, Topology};

/// The scalar the solver is generic over: `f64` or a dual number on `f64`.
pub trait Scalar: DualNum<Primitive = f64> + Copy + nalgebra::Scalar {}
impl<T: DualNum<Primitive = f64> + Copy + nalgebra::Scalar> Scalar for T {}

/// Solver options (compas_cem `static_equilibrium(tmax, eta)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverOptions {
    /// Maximum number of sweeps (≥ 1). `tmax = 1` ignores indirect edges (compas behaviour).
    pub tmax: usize,
    /// Convergence threshold on `Σ_n ‖x_t − x_{t−1}‖` (≥ 0).
    pub eta: f64,
}

impl Default for SolverOptions {
    /// compas_cem's defaults: `tmax = 100`, `eta = 1e-6`.
    fn default() -> Self {
        Self {
            tmax: 100,
            eta: 1e-6,
        }
    }
}

impl SolverOptions {
    /// Check the ranges.
    pub fn validate(&self) -> Result<(), CemError> {
        if self.tmax == 0 {
            return Err(CemError::InvalidOption {
                name: "tmax",
                value: 0.0,
                allowed: "at least 1 sweep",
            });
        }
        if !(self.eta.is_finite() && self.eta >= 0.0) {
            return Err(CemError::InvalidOption {
                name: "eta",
                value: self.eta,
                allowed: "a finite number ≥ 0",
            });
        }
        Ok(())
    }
}

/// Sweep statistics, as compas prints them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Iterations {
    /// Index of the last sweep run (compas `k`).
    pub last_t: usize,
    /// Number of sweeps, `last_t + 1`.
    pub sweeps: usize,
    /// `Σ_n ‖x_n − x_prev,n‖` of the last sweep (0 after a single sweep).
    pub residual_distance: f64,
}

#[inline]
pub(crate) fn dot<T: Scalar>(a: &Vector3<T>, b: &Vector3<T>) -> T {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// ‖v‖ with a zero value and zero derivative at `v = 0`.
#[inline]
pub(crate) fn safe_norm<T: Scalar>(v: &Vector3<T>) -> T {
    let n2 = dot(v, v);
    if n2.re() == 0.0 { T::zero() } else { n2.sqrt() }
}

/// û(v) = v/‖v‖, and 0 (with zero derivative) at `v = 0`.
#[inline]
pub(crate) fn safe_unit<T: Scalar>(v: &Vector3<T>) -> Vector3<T> {
    let n2 = dot(v, v);
    if n2.re() == 0.0 {
        Vector3::zeros()
    } else {
        let inv = n2.sqrt().recip();
        Vector3::new(v.x * inv, v.y * inv, v.z * inv)
    }
}

#[inline]
fn lift<T: Scalar>(v: &Vector3<f64>) -> Vector3<T> {
    Vector3::new(T::from(v.x), T::from(v.y), T::from(v.z))
}

/// The raw state after a solve, in model indices.
#[derive(Debug, Clone)]
pub(crate) struct State<T: Scalar> {
    pub positions: Vec<Vector3<T>>,
    /// Residual entering each node (force the previous trail edge carries, as r of the
    /// previous node); 0 at origins.
    pub r_in: Vec<Vector3<T>>,
    /// Residual leaving each node; at supports this is the reaction.
    pub r_out: Vec<Vector3<T>>,
    /// Signed force per trail edge (model order).
    pub trail_forces: Vec<T>,
    pub iterations: Iterations,
}

/// Inputs that may be parameters: everything numeric about the model.
pub(crate) struct Inputs<'a, T> {
    pub xyz0: &'a [Vector3<T>],
    pub loads: &'a [Vector3<T>],
    pub lengths: &'a [T],
    pub forces: &'a [T],
}

/// Deviation resultant `D_n` over `adj[range]` at the current positions.
#[inline]
fn deviation<T: Scalar>(
    model: &Model,
    range: std::ops::Range<usize>,
    n: usize,
    pos: &[Vector3<T>],
    forces: &[T],
) -> Vector3<T> {
    let mut d = Vector3::zeros();
    let xn = pos[n];
    for a in &model.adj[range] {
        let u = safe_unit(&(pos[a.other] - xn));
        d += u * forces[a.edge];
    }
    d
}

/// One sweep over the schedule (cem.md §4.3, §4.5).
fn sweep<T: Scalar>(model: &Model, inp: &Inputs<'_, T>, with_indirect: bool, st: &mut State<T>) {
    for step in &model.steps {
        let n = step.node;
        let split = model.adj_split[n];
        let mut r = st.r_in[n] - inp.loads[n];
        r -= deviation(
            model,
            model.adj_start[n]..split,
            n,
            &st.positions,
            inp.forces,
        );
        if with_indirect {
            r -= deviation(
                model,
                split..model.adj_start[n + 1],
                n,
                &st.positions,
                inp.forces,
            );
        }
        st.r_out[n] = r;
        let Some((e, s)) = step.out else { continue };
        let u = safe_unit(&r);
        let mut lambda = inp.lengths[e];
        if let Some(Some(plane)) = model.planes.get(e) {
            let nrm: Vector3<T> = lift(&plane.normal);
            let c = dot(&nrm, &u);
            // compas: no intersection when |c| < 1e-6 (keep λ_e); a cut of exactly 0 is
            // "falsy" in Python and also keeps λ_e.
            if c.re().abs() >= 1e-6 {
                let cut = dot(&nrm, &(lift::<T>(&plane.origin) - st.positions[n])) / c;
                if cut.re() != 0.0 {
                    lambda = cut;
                }
            }
        }
        st.positions[s] = st.positions[n] + u * lambda;
        let mag = safe_norm(&r);
        st.trail_forces[e] = if lambda.re().is_sign_negative() {
            -mag
        } else {
            mag
        };
        st.r_in[s] = r;
    }
}

/// Run the equilibrium on `model` with the numeric inputs `inp` (generic core).
pub(crate) fn run<T: Scalar>(
    model: &Model,
    inp: &Inputs<'_, T>,
    opts: &SolverOptions,
) -> Result<State<T>, CemError> {
    opts.validate()?;
    let n = model.ids.len();
    let mut st = State {
        positions: inp.xyz0.to_vec(),
        r_in: vec![Vector3::zeros(); n],
        r_out: vec![Vector3::zeros(); n],
        trail_forces: vec![T::zero(); model.trail_u.len()],
        iterations: Iterations {
            last_t: 0,
            sweeps: 1,
            residual_distance: 0.0,
        },
    };
    sweep(model, inp, false, &mut st);
    if opts.tmax >= 2 {
        if model.has_indirect {
            let mut prev: Vec<Vector3<f64>> =
                st.positions.iter().map(|p| p.map(|c| c.re())).collect();
            let mut delta = 0.0;
            let mut last_t = 1;
            for t in 1..opts.tmax {
                last_t = t;
                sweep(model, inp, true, &mut st);
                delta = 0.0;
                for (p, q) in st.positions.iter().zip(prev.iter_mut()) {
                    let now = p.map(|c| c.re());
                    delta += (now - *q).norm();
                    *q = now;
                }
                if delta < opts.eta {
                    break;
                }
            }
            if delta > opts.eta || delta.is_nan() {
                return Err(CemError::NotConverged {
                    tmax: opts.tmax,
                    residual: delta,
                    eta: opts.eta,
                });
            }
            st.iterations = Iterations {
                last_t,
                sweeps: last_t + 1,
                residual_distance: delta,
            };
        } else {
            st.iterations = Iterations {
                last_t: 1,
                sweeps: 2,
                residual_distance: 0.0,
            };
        }
    }
    for (i, p) in st.positions.iter().enumerate() {
        if !(p.iter().all(|c| c.re().is_finite()) && st.r_out[i].iter().all(|c| c.re().is_finite()))
        {
            return Err(CemError::NumericalBreakdown { id: model.ids[i] });
        }
    }
    Ok(st)
}

/// Solve a topology: validate and build trails ([`Model::new`]), then run the equilibrium.
pub fn solve(topology: &Topology, options: &SolverOptions) -> Result<Equilibrium, CemError> {
    Model::new(topology)?.solve(options)
}

impl Model {
    /// Solve the model with its own lengths, forces, loads and origin positions.
    pub fn solve(&self, options: &SolverOptions) -> Result<Equilibrium, CemError> {
        let inp = Inputs {
            xyz0: &self.xyz0,
            loads: &self.loads,
            lengths: &self.lengths,
            forces: &self.forces,
        };
        let st = run(self, &inp, options)?;
        Ok(Equilibrium::from_state(self, st))
    }
}

/// Result for one trail edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrailEdgeResult {
    /// First node as stored in the topology.
    pub u: NodeId,
    /// Second node as stored.
    pub v: NodeId,
    /// Signed force `F = copysign(‖r‖, λ)`: negative is compression.
    pub force: f64,
    /// Signed realized length `copysign(‖x_u − x_v‖, F)`.
    pub length: f64,
    /// `true` for edges created as auxiliary trails.
    pub auxiliary: bool,
}

/// Result for one deviation edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviationEdgeResult {
    /// First node as stored.
    pub u: NodeId,
    /// Second node as stored.
    pub v: NodeId,
    /// The input force μ (echoed).
    pub force: f64,
    /// Signed realized length `copysign(‖x_u − x_v‖, μ)`.
    pub length: f64,
    /// Both ends at the same sequence.
    pub direct: bool,
}

/// Per-node data of a solved network.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeResult {
    /// Node id.
    pub id: NodeId,
    /// Final position.
    pub xyz: Vector3<f64>,
    /// Sequence along its trail.
    pub sequence: usize,
    /// Derived origin role.
    pub origin: bool,
    /// Support role.
    pub support: bool,
    /// Applied load.
    pub load: Vector3<f64>,
    /// Reaction (force of the support on the structure); zero for non-supports.
    pub reaction: Vector3<f64>,
    /// Residual entering the node from the previous trail edge (0 at origins).
    pub r_in: Vector3<f64>,
    /// Residual leaving the node (the next trail edge's force on it; the reaction at supports).
    pub r_out: Vector3<f64>,
    /// Independent equilibrium check `‖q + Σ_e F_e û(x_other − x) + R‖` from the final
    /// geometry; `None` if the node touches an edge of zero realized length (no direction).
    pub residual: Option<f64>,
}

/// One side of a node's force polygon.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PolygonSide {
    /// The applied load `q_n`.
    Load(Vector3<f64>),
    /// A deviation edge (index in the topology), force on the node `μ·û(x_m − x_n)`.
    Deviation(usize, Vector3<f64>),
    /// The incoming trail edge (model trail-edge index), force on the node `−r_in`.
    TrailIn(usize, Vector3<f64>),
    /// The outgoing trail edge, force on the node `r_out`.
    TrailOut(usize, Vector3<f64>),
    /// The support reaction `R_n`.
    Reaction(Vector3<f64>),
}

impl PolygonSide {
    /// The force vector of this side.
    pub fn vector(&self) -> Vector3<f64> {
        match *self {
            Self::Load(v)
            | Self::Deviation(_, v)
            | Self::TrailIn(_, v)
            | Self::TrailOut(_, v)
            | Self::Reaction(v) => v,
        }
    }
}

/// The closed force polygon of a node (the force diagram of the CEM paper, per node): the
/// sides are the forces acting on the node; they sum to (nearly) zero.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcePolygon {
    /// Node id.
    pub node: NodeId,
    /// Sides in drawing order: load, deviation edges, incoming trail, outgoing trail or reaction.
    pub sides: Vec<PolygonSide>,
}

impl ForcePolygon {
    /// Vector sum of the sides (the closing error).
    pub fn closure(&self) -> Vector3<f64> {
        self.sides.iter().map(PolygonSide::vector).sum()
    }
}

/// Global checks of a solved network.
#[derive(Debug, Clone, PartialEq)]
pub struct Checks {
    /// Largest per-node residual (nodes with a zero-length edge excluded).
    pub max_node_residual: f64,
    /// Trail and deviation edges of zero realized length, as `(u, v)`.
    pub zero_length_edges: Vec<(NodeId, NodeId)>,
    /// Σ q.
    pub sum_loads: Vector3<f64>,
    /// Σ R.
    pub sum_reactions: Vector3<f64>,
    /// Largest |F| over trail and deviation edges (scale for residual tolerances).
    pub max_abs_force: f64,
}

/// A solved CEM network: positions, forces, reactions and checks, addressable by node id
/// and by edge `(u, v)` in either orientation.
#[derive(Debug, Clone)]
pub struct Equilibrium {
    /// Topology name.
    pub name: String,
    /// Nodes in model order (topology order, then auxiliary nodes).
    pub nodes: Vec<NodeResult>,
    /// Trail edges in topology order, then auxiliary trail edges.
    pub trail_edges: Vec<TrailEdgeResult>,
    /// Deviation edges in topology order.
    pub deviation_edges: Vec<DeviationEdgeResult>,
    /// Trails as node-id lists (origin → support), in processing order.
    pub trails: Vec<Vec<NodeId>>,
    /// Auxiliary trails `(node, auxiliary support)`.
    pub auxiliary_trails: Vec<(NodeId, NodeId)>,
    /// Sweep statistics.
    pub iterations: Iterations,
    /// Global checks.
    pub checks: Checks,
    index: crate::topology::IdIndex,
    dev_adj: Vec<Vec<usize>>,
    trail_adj: Vec<Vec<usize>>,
}

impl Equilibrium {
    pub(crate) fn from_state(model: &Model, st: State<f64>) -> Self {
        let n = model.ids.len();
        let mut trail_adj = vec![Vec::new(); n];
        let mut trail_edges = Vec::with_capacity(model.trail_u.len());
        for e in 0..model.trail_u.len() {
            let (u, v) = (model.trail_u[e], model.trail_v[e]);
            trail_adj[u].push(e);
            trail_adj[v].push(e);
            let f = st.trail_forces[e];
            let len = (st.positions[u] - st.positions[v]).norm();
            trail_edges.push(TrailEdgeResult {
                u: model.ids[u],
                v: model.ids[v],
                force: f,
                length: len.copysign(f),
                auxiliary: e >= model.n_input_trail_edges,
            });
        }
        let mut dev_adj = vec![Vec::new(); n];
        let mut deviation_edges = Vec::with_capacity(model.dev_u.len());
        for e in 0..model.dev_u.len() {
            let (u, v) = (model.dev_u[e], model.dev_v[e]);
            dev_adj[u].push(e);
            dev_adj[v].push(e);
            let f = model.forces[e];
            let len = (st.positions[u] - st.positions[v]).norm();
            deviation_edges.push(DeviationEdgeResult {
                u: model.ids[u],
                v: model.ids[v],
                force: f,
                length: len.copysign(f),
                direct: model.direct[e],
            });
        }
        let mut zero_len = vec![false; n];
        let mut zero_length_edges = Vec::new();
        for (u, v, len) in trail_edges
            .iter()
            .map(|e| (e.u, e.v, e.length))
            .chain(deviation_edges.iter().map(|e| (e.u, e.v, e.length)))
        {
            if len == 0.0 {
                zero_length_edges.push((u, v));
                for id in [u, v] {
                    if let Some(&i) = model.index.get(&id) {
                        zero_len[i] = true;
                    }
                }
            }
        }
        let mut nodes = Vec::with_capacity(n);
        let mut max_res: f64 = 0.0;
        let mut sum_loads = Vector3::zeros();
        let mut sum_reactions = Vector3::zeros();
        for i in 0..n {
            let x = st.positions[i];
            let reaction = if model.is_support[i] {
                st.r_out[i]
            } else {
                Vector3::zeros()
            };
            let residual = if zero_len[i] {
                None
            } else {
                let mut v = model.loads[i] + reaction;
                for &e in &trail_adj[i] {
                    let o = if model.trail_u[e] == i {
                        model.trail_v[e]
                    } else {
                        model.trail_u[e]
                    };
                    v += safe_unit(&(st.positions[o] - x)) * st.trail_forces[e];
                }
                for &e in &dev_adj[i] {
                    let o = if model.dev_u[e] == i {
                        model.dev_v[e]
                    } else {
                        model.dev_u[e]
                    };
                    v += safe_unit(&(st.positions[o] - x)) * model.forces[e];
                }
                Some(v.norm())
            };
            if let Some(r) = residual {
                max_res = max_res.max(r);
            }
            sum_loads += model.loads[i];
            sum_reactions += reaction;
            nodes.push(NodeResult {
                id: model.ids[i],
                xyz: x,
                sequence: model.sequence[i],
                origin: model.is_origin[i],
                support: model.is_support[i],
                load: model.loads[i],
                reaction,
                r_in: st.r_in[i],
                r_out: st.r_out[i],
                residual,
            });
        }
        let max_abs_force = trail_edges
            .iter()
            .map(|e| e.force.abs())
            .chain(deviation_edges.iter().map(|e| e.force.abs()))
            .fold(0.0, f64::max);
        Self {
            name: model.name.clone(),
            nodes,
            trail_edges,
            deviation_edges,
            trails: model.trails(),
            auxiliary_trails: model.auxiliary_trails(),
            iterations: st.iterations,
            checks: Checks {
                max_node_residual: max_res,
                zero_length_edges,
                sum_loads,
                sum_reactions,
                max_abs_force,
            },
            index: model.index.clone(),
            dev_adj,
            trail_adj,
        }
    }

    /// The node result of id `id`.
    pub fn node(&self, id: NodeId) -> Option<&NodeResult> {
        self.index.get(&id).and_then(|&i| self.nodes.get(i))
    }

    /// Final position of node `id`.
    pub fn position(&self, id: NodeId) -> Option<Vector3<f64>> {
        self.node(id).map(|n| n.xyz)
    }

    /// Reaction at node `id` (zero for non-supports), `None` for unknown ids.
    pub fn reaction(&self, id: NodeId) -> Option<Vector3<f64>> {
        self.node(id).map(|n| n.reaction)
    }

    /// The trail edge joining `a` and `b` (either orientation).
    pub fn trail_edge(&self, a: NodeId, b: NodeId) -> Option<&TrailEdgeResult> {
        let i = *self.index.get(&a)?;
        self.trail_adj.get(i)?.iter().find_map(|&e| {
            let r = self.trail_edges.get(e)?;
            ((r.u == a && r.v == b) || (r.u == b && r.v == a)).then_some(r)
        })
    }

    /// The deviation edge joining `a` and `b` (either orientation).
    pub fn deviation_edge(&self, a: NodeId, b: NodeId) -> Option<&DeviationEdgeResult> {
        let i = *self.index.get(&a)?;
        self.dev_adj.get(i)?.iter().find_map(|&e| {
            let r = self.deviation_edges.get(e)?;
            ((r.u == a && r.v == b) || (r.u == b && r.v == a)).then_some(r)
        })
    }

    /// Signed force of the edge (trail or deviation) joining `a` and `b`.
    pub fn edge_force(&self, a: NodeId, b: NodeId) -> Option<f64> {
        self.trail_edge(a, b)
            .map(|e| e.force)
            .or_else(|| self.deviation_edge(a, b).map(|e| e.force))
    }

    /// The force polygon of node `id`: load, deviation forces `μ·û(x_m − x_n)`, incoming
    /// trail force `−r_in`, outgoing trail force `r_out` (or the reaction at a support).
    pub fn force_polygon(&self, id: NodeId) -> Option<ForcePolygon> {
        let i = *self.index.get(&id)?;
        let node = self.nodes.get(i)?;
        let mut sides = vec![PolygonSide::Load(node.load)];
        for &e in self.dev_adj.get(i)? {
            let d = self.deviation_edges.get(e)?;
            let other = if d.u == id { d.v } else { d.u };
            let xo = self.position(other)?;
            sides.push(PolygonSide::Deviation(
                e,
                safe_unit(&(xo - node.xyz)) * d.force,
            ));
        }
        let mut incoming = None;
        let mut outgoing = None;
        for &e in self.trail_adj.get(i)? {
            let t = self.trail_edges.get(e)?;
            let other = if t.u == id { t.v } else { t.u };
            let o = self.node(other)?;
            if o.sequence < node.sequence {
                incoming = Some(e);
            } else {
                outgoing = Some(e);
            }
        }
        if let Some(e) = incoming {
            sides.push(PolygonSide::TrailIn(e, -node.r_in));
        }
        if node.support {
            sides.push(PolygonSide::Reaction(node.reaction));
        } else if let Some(e) = outgoing {
            sides.push(PolygonSide::TrailOut(e, node.r_out));
        }
        Some(ForcePolygon { node: id, sides })
    }

    /// Force polygons of all nodes in model order.
    pub fn force_polygons(&self) -> Vec<ForcePolygon> {
        self.nodes
            .iter()
            .filter_map(|n| self.force_polygon(n.id))
            .collect()
    }
}
