//! Constrained CEM form-finding (Pastrana et al. 2023; compas_cem `optimization/`, cem.md §6).
//!
//! Design variables ([`Parameter`]) are scalar attributes of the topology: signed trail
//! lengths (per edge, or **one shared length for several edges**, [`ParameterKind::TrailLengths`]),
//! signed deviation forces, origin coordinates and load components. Goals ([`Goal`]) are soft:
//! the objective is
//!
//! ```text
//! f(x) = Σ_g w_g · e_g(x)²
//! ```
//!
//! evaluated on the equilibrium at `x`. The gradient is exact: the same generic solver
//! ([`crate::equilibrium`]) runs on forward-mode dual numbers ([`num_dual::Dual64`]), one pass
//! per parameter (cheap for the few parameters of form-finding; the number of sweeps is set
//! by the value pass and not differentiated, as in compas_cem). The minimizer is SLSQP from the
//! `slsqp` crate (a Rust port of NLopt's LD_SLSQP, compas_cem's default), with box bounds.
//!
//! Bounds: the Rust API takes [`Bounds::Absolute`] or compas-style [`Bounds::Relative`]
//! (`[x0 − |below|, x0 + |above|]`, converted at the start value); the JSON reader uses relative
//! bounds as the fixture format does. With [`OptimizeOptions::keep_states`] the bounds of length
//! and force parameters are also clipped so that their sign (tension/compression) cannot change.
//!
//! compas_cem's `stopval = eps` is emulated: SLSQP has no stop value in the `slsqp` crate, so
//! an objective `≤ eps` at the end counts as converged (even when SLSQP reports
//! `RoundoffLimited`, which it does when it cannot improve an essentially zero objective).

use std::cell::{Cell, RefCell};

use nalgebra::Vector3;
use num_dual::Dual64;
use serde_json::Value;

use crate::equilibrium::{
    Equilibrium, Inputs, Scalar, SolverOptions, State, dot, run, safe_norm, safe_unit,
};
use crate::error::CemError;
use crate::model::Model;
use crate::topology::{NodeId, Topology};

/// What a parameter controls.
#[derive(Debug, Clone, PartialEq)]
pub enum ParameterKind {
    /// Signed length λ of the trail edge `(u, v)` (either orientation).
    TrailLength(NodeId, NodeId),
    /// One signed length shared by all these trail edges (start value: the first edge's).
    TrailLengths(Vec<(NodeId, NodeId)>),
    /// Signed force μ of the deviation edge `(u, v)`.
    DeviationForce(NodeId, NodeId),
    /// One signed force shared by all these deviation edges (start value: the first edge's).
    DeviationForces(Vec<(NodeId, NodeId)>),
    /// x coordinate of an origin node.
    OriginX(NodeId),
    /// y coordinate of an origin node.
    OriginY(NodeId),
    /// z coordinate of an origin node.
    OriginZ(NodeId),
    /// x component of a node load.
    LoadX(NodeId),
    /// y component of a node load.
    LoadY(NodeId),
    /// z component of a node load.
    LoadZ(NodeId),
}

impl ParameterKind {
    fn describe(&self) -> String {
        match self {
            Self::TrailLength(u, v) => format!("trail_length ({u}, {v})"),
            Self::TrailLengths(e) => format!("trail_lengths ({} edges)", e.len()),
            Self::DeviationForce(u, v) => format!("deviation_force ({u}, {v})"),
            Self::DeviationForces(e) => format!("deviation_forces ({} edges)", e.len()),
            Self::OriginX(n) => format!("origin_x {n}"),
            Self::OriginY(n) => format!("origin_y {n}"),
            Self::OriginZ(n) => format!("origin_z {n}"),
            Self::LoadX(n) => format!("load_x {n}"),
            Self::LoadY(n) => format!("load_y {n}"),
            Self::LoadZ(n) => format!("load_z {n}"),
        }
    }
}

/// Box bounds of a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bounds {
    /// Unbounded.
    Free,
    /// `[lower, upper]` in absolute values (±∞ allowed).
    Absolute {
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// compas_cem style: `[x0 − |below|, x0 + |above|]`; `None` is unbounded on that side.
    Relative {
        /// Distance allowed below the start value.
        below: Option<f64>,
        /// Distance allowed above the start value.
        above: Option<f64>,
    },
}

/// A design variable.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// What it controls.
    pub kind: ParameterKind,
    /// Its bounds.
    pub bounds: Bounds,
}

impl Parameter {
    /// A parameter with the given bounds.
    pub fn new(kind: ParameterKind, bounds: Bounds) -> Self {
        Self { kind, bounds }
    }
}

/// A soft goal; its error `e` enters the objective as `w·e²`.
#[derive(Debug, Clone, PartialEq)]
pub enum Goal {
    /// `e = ‖x_n − p‖`.
    Point {
        /// Node.
        node: NodeId,
        /// Target point.
        target: Vector3<f64>,
    },
    /// `e` = distance from `x_n` to the infinite line through `start`, `end`.
    Line {
        /// Node.
        node: NodeId,
        /// A point of the line.
        start: Vector3<f64>,
        /// Another point of the line.
        end: Vector3<f64>,
    },
    /// `e = |n̂·(x_n − o)|`.
    Plane {
        /// Node.
        node: NodeId,
        /// A point of the plane.
        origin: Vector3<f64>,
        /// Plane normal.
        normal: Vector3<f64>,
    },
    /// `e = F_e − F*` (signed trail force).
    TrailForce {
        /// Trail edge.
        edge: (NodeId, NodeId),
        /// Target force.
        target: f64,
    },
    /// `e = ‖x_u − x_v‖ − L`.
    DeviationLength {
        /// Deviation edge.
        edge: (NodeId, NodeId),
        /// Target length.
        target: f64,
    },
    /// `e = ‖R_n − R*‖`.
    Reaction {
        /// Support node.
        node: NodeId,
        /// Target reaction vector.
        target: Vector3<f64>,
    },
    /// `e = ‖û(x_v − x_u) − s·v̂‖`, `s = ±1` with `s·v̂·û ≥ 0` (direction up to orientation).
    EdgeDirection {
        /// Edge (trail or deviation) as `(u, v)`.
        edge: (NodeId, NodeId),
        /// Target direction.
        target: Vector3<f64>,
    },
}

impl Goal {
    fn describe(&self) -> String {
        match self {
            Self::Point { node, .. } => format!("point node {node}"),
            Self::Line { node, .. } => format!("line node {node}"),
            Self::Plane { node, .. } => format!("plane node {node}"),
            Self::TrailForce { edge, .. } => format!("trail_force ({}, {})", edge.0, edge.1),
            Self::DeviationLength { edge, .. } => {
                format!("deviation_length ({}, {})", edge.0, edge.1)
            }
            Self::Reaction { node, .. } => format!("reaction node {node}"),
            Self::EdgeDirection { edge, .. } => {
                format!("edge_direction ({}, {})", edge.0, edge.1)
            }
        }
    }
}

/// A goal with its weight (> 0).
#[derive(Debug, Clone, PartialEq)]
pub struct WeightedGoal {
    /// The goal.
    pub goal: Goal,
    /// Weight w > 0.
    pub weight: f64,
}

/// A constrained form-finding problem.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Problem {
    /// Parameters, in the order of the vector x.
    pub parameters: Vec<Parameter>,
    /// Goals.
    pub goals: Vec<WeightedGoal>,
}

/// Optimizer options (compas_cem `Optimizer.solve` names in brackets).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimizeOptions {
    /// Equilibrium options of every evaluation (`tmax`, `eta`).
    pub solver: SolverOptions,
    /// Maximum number of objective evaluations (`iters`).
    pub max_evaluations: usize,
    /// Objective value counted as converged (`eps`, NLopt `stopval`).
    pub stopval: f64,
    /// Absolute tolerance on the change of the objective (`kappa`, NLopt `ftol_abs`).
    pub ftol_abs: f64,
    /// Relative tolerance on the change of the objective.
    pub ftol_rel: f64,
    /// Relative tolerance on the change of x.
    pub xtol_rel: f64,
    /// Keep the sign (tension/compression) of length and force parameters.
    pub keep_states: bool,
}

impl Default for OptimizeOptions {
    /// Tight defaults (the fixtures' `eps = kappa = 1e-20`), 200 evaluations.
    fn default() -> Self {
        Self {
            solver: SolverOptions::default(),
            max_evaluations: 200,
            stopval: 1e-20,
            ftol_abs: 1e-20,
            ftol_rel: 0.0,
            xtol_rel: 0.0,
            keep_states: false,
        }
    }
}

/// How the optimizer stopped (NLopt code names).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OptimizeStatus {
    /// Objective ≤ stopval.
    StopvalReached,
    /// Objective change below ftol.
    FtolReached,
    /// Step below xtol.
    XtolReached,
    /// SLSQP reported success (KKT conditions met).
    Success,
    /// Evaluation budget used up.
    MaxEvalReached,
    /// SLSQP could not make progress due to rounding.
    RoundoffLimited,
    /// SLSQP failed.
    Failure,
}

impl OptimizeStatus {
    /// NLopt-style name, e.g. `NLOPT_FTOL_REACHED`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::StopvalReached => "NLOPT_STOPVAL_REACHED",
            Self::FtolReached => "NLOPT_FTOL_REACHED",
            Self::XtolReached => "NLOPT_XTOL_REACHED",
            Self::Success => "NLOPT_SUCCESS",
            Self::MaxEvalReached => "NLOPT_MAXEVAL_REACHED",
            Self::RoundoffLimited => "NLOPT_ROUNDOFF_LIMITED",
            Self::Failure => "NLOPT_FAILURE",
        }
    }
}

/// One row of the per-goal table.
#[derive(Debug, Clone, PartialEq)]
pub struct GoalReport {
    /// Goal description (kind and node/edge).
    pub goal: String,
    /// Weight.
    pub weight: f64,
    /// Error `e` (length, force or direction units), ≥ 0 except signed forces/lengths.
    pub error: f64,
    /// `w·e²`.
    pub weighted_squared_error: f64,
}

/// Result of [`optimize`].
#[derive(Debug, Clone)]
pub struct OptimizeResult {
    /// Start values.
    pub x0: Vec<f64>,
    /// Absolute lower bounds used.
    pub bounds_low: Vec<f64>,
    /// Absolute upper bounds used.
    pub bounds_up: Vec<f64>,
    /// f(x0).
    pub objective_at_x0: f64,
    /// ∇f(x0) (exact, forward mode).
    pub gradient_at_x0: Vec<f64>,
    /// Best parameters.
    pub x_opt: Vec<f64>,
    /// f(x_opt).
    pub objective_at_x_opt: f64,
    /// ∇f(x_opt).
    pub gradient_at_x_opt: Vec<f64>,
    /// How SLSQP stopped.
    pub status: OptimizeStatus,
    /// Converged: status is a success code, or the objective is ≤ stopval.
    pub converged: bool,
    /// Gradient evaluations (one per SLSQP major iteration, plus the start).
    pub iterations: usize,
    /// Objective evaluations requested by SLSQP.
    pub evaluations: usize,
    /// Per-goal errors at x_opt.
    pub goals: Vec<GoalReport>,
    /// The topology with x_opt written in.
    pub topology: Topology,
    /// The equilibrium at x_opt.
    pub equilibrium: Equilibrium,
}

#[derive(Debug, Clone)]
enum Target {
    Lengths(Vec<usize>),
    Forces(Vec<usize>),
    Origin(usize, usize),
    Load(usize, usize),
}

#[derive(Debug, Clone)]
enum ResolvedGoal {
    Point(usize, Vector3<f64>),
    Line(usize, Vector3<f64>, Vector3<f64>),
    Plane(usize, Vector3<f64>, Vector3<f64>),
    TrailForce(usize, f64),
    DeviationLength(usize, usize, f64),
    Reaction(usize, Vector3<f64>),
    Direction(usize, usize, Vector3<f64>),
}

/// A problem bound to a model: evaluates the objective and its exact gradient.
#[derive(Debug, Clone)]
pub struct Evaluator {
    model: Model,
    targets: Vec<Target>,
    goals: Vec<(ResolvedGoal, f64)>,
    descriptions: Vec<String>,
    x0: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    solver: SolverOptions,
}

fn check_finite(what: impl FnOnce() -> String, v: f64) -> Result<(), CemError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(CemError::NonFinite {
            what: what(),
            value: v,
        })
    }
}

impl Evaluator {
    /// Validate `problem` against `topology` (unknown nodes/edges, empty parameter list,
    /// bounds, weights) and build the model.
    pub fn new(
        topology: &Topology,
        problem: &Problem,
        options: &OptimizeOptions,
    ) -> Result<Self, CemError> {
        options.solver.validate()?;
        let model = Model::new(topology)?;
        if problem.parameters.is_empty() {
            return Err(CemError::InvalidProblem(
                "the parameter list is empty; give at least one parameter".into(),
            ));
        }
        let node = |id: NodeId, ctx: &str| {
            model.node_index(id).ok_or_else(|| CemError::UnknownNode {
                id,
                context: ctx.to_string(),
            })
        };
        let trail = |(u, v): (NodeId, NodeId), ctx: &str| {
            let a = model.node_index(u);
            let b = model.node_index(v);
            a.zip(b)
                .and_then(|(a, b)| {
                    (0..model.trail_u.len()).find(|&e| {
                        (model.trail_u[e] == a && model.trail_v[e] == b)
                            || (model.trail_u[e] == b && model.trail_v[e] == a)
                    })
                })
                .ok_or_else(|| CemError::UnknownEdge {
                    u,
                    v,
                    kind: "trail",
                    context: ctx.to_string(),
                })
        };
        let deviation = |(u, v): (NodeId, NodeId), ctx: &str| {
            let a = model.node_index(u);
            let b = model.node_index(v);
            a.zip(b)
                .and_then(|(a, b)| {
                    (0..model.dev_u.len()).find(|&e| {
                        (model.dev_u[e] == a && model.dev_v[e] == b)
                            || (model.dev_u[e] == b && model.dev_v[e] == a)
                    })
                })
                .ok_or_else(|| CemError::UnknownEdge {
                    u,
                    v,
                    kind: "deviation",
                    context: ctx.to_string(),
                })
        };
        let mut targets = Vec::new();
        let (mut x0, mut lower, mut upper) = (Vec::new(), Vec::new(), Vec::new());
        for (k, p) in problem.parameters.iter().enumerate() {
            let ctx = format!("parameter {k} ({})", p.kind.describe());
            let origin = |id: NodeId| -> Result<usize, CemError> {
                let i = node(id, &ctx)?;
                if model.is_origin[i] {
                    Ok(i)
                } else {
                    Err(CemError::InvalidProblem(format!(
                        "{ctx}: node {id} is not a trail origin; origin coordinates are parameters only on origins"
                    )))
                }
            };
            let (t, start) = match &p.kind {
                ParameterKind::TrailLength(u, v) => {
                    let e = trail((*u, *v), &ctx)?;
                    (Target::Lengths(vec![e]), model.lengths[e])
                }
                ParameterKind::TrailLengths(edges) => {
                    let es = edges
                        .iter()
                        .map(|&e| trail(e, &ctx))
                        .collect::<Result<Vec<_>, _>>()?;
                    let Some(&first) = es.first() else {
                        return Err(CemError::InvalidProblem(format!(
                            "{ctx}: the edge list is empty"
                        )));
                    };
                    (Target::Lengths(es), model.lengths[first])
                }
                ParameterKind::DeviationForce(u, v) => {
                    let e = deviation((*u, *v), &ctx)?;
                    (Target::Forces(vec![e]), model.forces[e])
                }
                ParameterKind::DeviationForces(edges) => {
                    let es = edges
                        .iter()
                        .map(|&e| deviation(e, &ctx))
                        .collect::<Result<Vec<_>, _>>()?;
                    let Some(&first) = es.first() else {
                        return Err(CemError::InvalidProblem(format!(
                            "{ctx}: the edge list is empty"
                        )));
                    };
                    (Target::Forces(es), model.forces[first])
                }
                ParameterKind::OriginX(n) => {
                    let i = origin(*n)?;
                    (Target::Origin(i, 0), model.xyz0[i].x)
                }
                ParameterKind::OriginY(n) => {
                    let i = origin(*n)?;
                    (Target::Origin(i, 1), model.xyz0[i].y)
                }
                ParameterKind::OriginZ(n) => {
                    let i = origin(*n)?;
                    (Target::Origin(i, 2), model.xyz0[i].z)
                }
                ParameterKind::LoadX(n) => {
                    let i = node(*n, &ctx)?;
                    (Target::Load(i, 0), model.loads[i].x)
                }
                ParameterKind::LoadY(n) => {
                    let i = node(*n, &ctx)?;
                    (Target::Load(i, 1), model.loads[i].y)
                }
                ParameterKind::LoadZ(n) => {
                    let i = node(*n, &ctx)?;
                    (Target::Load(i, 2), model.loads[i].z)
                }
            };
            let (mut lo, mut hi) = match p.bounds {
                Bounds::Free => (f64::NEG_INFINITY, f64::INFINITY),
                Bounds::Absolute { lower, upper } => (lower, upper),
                Bounds::Relative { below, above } => (
                    below.map_or(f64::NEG_INFINITY, |b| start - b.abs()),
                    above.map_or(f64::INFINITY, |b| start + b.abs()),
                ),
            };
            if lo.is_nan() || hi.is_nan() || lo > hi {
                return Err(CemError::InvalidProblem(format!(
                    "{ctx}: bounds [{lo}, {hi}] are inconsistent; need lower ≤ upper, no NaN"
                )));
            }
            if !(lo <= start && start <= hi) {
                return Err(CemError::InvalidProblem(format!(
                    "{ctx}: start value {start} lies outside its bounds [{lo}, {hi}]"
                )));
            }
            if options.keep_states && matches!(t, Target::Lengths(_) | Target::Forces(_)) {
                // Keep the sign: clip the box to the start value's half-line (a tiny margin
                // keeps the value off zero, where the state is undefined).
                let margin = 1e-9 * start.abs().max(1e-9);
                if start < 0.0 {
                    hi = hi.min(-margin);
                } else if start > 0.0 {
                    lo = lo.max(margin);
                }
            }
            targets.push(t);
            x0.push(start);
            lower.push(lo);
            upper.push(hi);
        }
        let mut goals = Vec::new();
        let mut descriptions = Vec::new();
        for (k, g) in problem.goals.iter().enumerate() {
            let ctx = format!("goal {k} ({})", g.goal.describe());
            if !(g.weight.is_finite() && g.weight > 0.0) {
                return Err(CemError::InvalidProblem(format!(
                    "{ctx}: weight {} is not allowed; weights must be finite and > 0",
                    g.weight
                )));
            }
            let v3 = |name: &str, v: &Vector3<f64>| -> Result<(), CemError> {
                for c in v.iter() {
                    check_finite(|| format!("{ctx} {name}"), *c)?;
                }
                Ok(())
            };
            let r = match &g.goal {
                Goal::Point { node: n, target } => {
                    v3("target", target)?;
                    ResolvedGoal::Point(node(*n, &ctx)?, *target)
                }
                Goal::Line {
                    node: n,
                    start,
                    end,
                } => {
                    v3("start", start)?;
                    v3("end", end)?;
                    let d = end - start;
                    if d.norm() == 0.0 {
                        return Err(CemError::InvalidProblem(format!(
                            "{ctx}: start and end coincide; a line needs two distinct points"
                        )));
                    }
                    ResolvedGoal::Line(node(*n, &ctx)?, *start, d / d.norm())
                }
                Goal::Plane {
                    node: n,
                    origin,
                    normal,
                } => {
                    v3("origin", origin)?;
                    v3("normal", normal)?;
                    if normal.norm() == 0.0 {
                        return Err(CemError::InvalidProblem(format!(
                            "{ctx}: the normal is zero; give a non-zero normal"
                        )));
                    }
                    ResolvedGoal::Plane(node(*n, &ctx)?, *origin, normal / normal.norm())
                }
                Goal::TrailForce { edge, target } => {
                    check_finite(|| format!("{ctx} target"), *target)?;
                    ResolvedGoal::TrailForce(trail(*edge, &ctx)?, *target)
                }
                Goal::DeviationLength { edge, target } => {
                    check_finite(|| format!("{ctx} target"), *target)?;
                    let e = deviation(*edge, &ctx)?;
                    ResolvedGoal::DeviationLength(model.dev_u[e], model.dev_v[e], *target)
                }
                Goal::Reaction { node: n, target } => {
                    v3("target", target)?;
                    let i = node(*n, &ctx)?;
                    if !model.is_support[i] {
                        return Err(CemError::InvalidProblem(format!(
                            "{ctx}: node {n} is not a support; reaction goals need a support"
                        )));
                    }
                    ResolvedGoal::Reaction(i, *target)
                }
                Goal::EdgeDirection { edge, target } => {
                    v3("target", target)?;
                    if target.norm() == 0.0 {
                        return Err(CemError::InvalidProblem(format!(
                            "{ctx}: the target direction is zero"
                        )));
                    }
                    let (u, v) = (node(edge.0, &ctx)?, node(edge.1, &ctx)?);
                    let known = trail(*edge, &ctx).is_ok() || deviation(*edge, &ctx).is_ok();
                    if !known {
                        return Err(CemError::UnknownEdge {
                            u: edge.0,
                            v: edge.1,
                            kind: "trail or deviation",
                            context: ctx,
                        });
                    }
                    ResolvedGoal::Direction(u, v, target / target.norm())
                }
            };
            goals.push((r, g.weight));
            descriptions.push(g.goal.describe());
        }
        if goals.is_empty() {
            return Err(CemError::InvalidProblem(
                "the goal list is empty; give at least one goal".into(),
            ));
        }
        Ok(Self {
            model,
            targets,
            goals,
            descriptions,
            x0,
            lower,
            upper,
            solver: options.solver,
        })
    }

    /// Start values x0.
    pub fn x0(&self) -> &[f64] {
        &self.x0
    }

    /// Absolute bounds `(lower, upper)`.
    pub fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lower, &self.upper)
    }

    /// Run the generic equilibrium with the parameters `x` written in.
    fn state<T: Scalar>(&self, x: &[T]) -> Result<State<T>, CemError> {
        let m = &self.model;
        let lift3 = |v: &Vector3<f64>| Vector3::new(T::from(v.x), T::from(v.y), T::from(v.z));
        let mut xyz0: Vec<Vector3<T>> = m.xyz0.iter().map(lift3).collect();
        let mut loads: Vec<Vector3<T>> = m.loads.iter().map(lift3).collect();
        let mut lengths: Vec<T> = m.lengths.iter().map(|&l| T::from(l)).collect();
        let mut forces: Vec<T> = m.forces.iter().map(|&f| T::from(f)).collect();
        for (t, &xi) in self.targets.iter().zip(x) {
            match t {
                Target::Lengths(es) => es.iter().for_each(|&e| lengths[e] = xi),
                Target::Forces(es) => es.iter().for_each(|&e| forces[e] = xi),
                Target::Origin(i, a) => xyz0[*i][*a] = xi,
                Target::Load(i, a) => loads[*i][*a] = xi,
            }
        }
        let inp = Inputs {
            xyz0: &xyz0,
            loads: &loads,
            lengths: &lengths,
            forces: &forces,
        };
        run(m, &inp, &self.solver)
    }

    /// Goal errors `e_g` on a state.
    fn errors<T: Scalar>(&self, st: &State<T>) -> Vec<T> {
        let lift3 = |v: &Vector3<f64>| Vector3::new(T::from(v.x), T::from(v.y), T::from(v.z));
        self.goals
            .iter()
            .map(|(g, _)| match g {
                ResolvedGoal::Point(n, p) => safe_norm(&(st.positions[*n] - lift3(p))),
                ResolvedGoal::Line(n, a, d) => {
                    let w = st.positions[*n] - lift3(a);
                    let d = lift3(d);
                    safe_norm(&(w - d * dot(&w, &d)))
                }
                ResolvedGoal::Plane(n, o, nrm) => dot(&lift3(nrm), &(st.positions[*n] - lift3(o))),
                ResolvedGoal::TrailForce(e, f) => st.trail_forces[*e] - T::from(*f),
                ResolvedGoal::DeviationLength(u, v, l) => {
                    safe_norm(&(st.positions[*u] - st.positions[*v])) - T::from(*l)
                }
                ResolvedGoal::Reaction(n, r) => safe_norm(&(st.r_out[*n] - lift3(r))),
                ResolvedGoal::Direction(u, v, dir) => {
                    let uh = safe_unit(&(st.positions[*v] - st.positions[*u]));
                    let d = lift3(dir);
                    let s = if dot(&uh, &d).re() >= 0.0 { 1.0 } else { -1.0 };
                    safe_norm(&(uh - d * T::from(s)))
                }
            })
            .collect()
    }

    fn objective_of<T: Scalar>(&self, e: &[T]) -> T {
        e.iter()
            .zip(&self.goals)
            .fold(T::zero(), |acc, (&ei, (_, w))| acc + ei * ei * T::from(*w))
    }

    /// Objective `f(x) = Σ w·e²`.
    pub fn objective(&self, x: &[f64]) -> Result<f64, CemError> {
        let st = self.state(x)?;
        Ok(self.objective_of(&self.errors(&st)))
    }

    /// Objective and its exact gradient (one dual-number pass per parameter).
    pub fn objective_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>), CemError> {
        let mut grad = vec![0.0; x.len()];
        let mut value = None;
        for (j, gj) in grad.iter_mut().enumerate() {
            let xd: Vec<Dual64> = x
                .iter()
                .enumerate()
                .map(|(i, &v)| Dual64::new(v, if i == j { 1.0 } else { 0.0 }))
                .collect();
            let st = self.state(&xd)?;
            let f = self.objective_of(&self.errors(&st));
            *gj = f.eps;
            value = Some(f.re);
        }
        match value {
            Some(v) => Ok((v, grad)),
            None => Ok((self.objective(x)?, grad)),
        }
    }

    /// The per-goal table at `x`.
    pub fn goal_reports(&self, x: &[f64]) -> Result<Vec<GoalReport>, CemError> {
        let st = self.state(x)?;
        let e = self.errors(&st);
        Ok(e.iter()
            .zip(&self.goals)
            .zip(&self.descriptions)
            .map(|((&ei, (_, w)), d)| GoalReport {
                goal: d.clone(),
                weight: *w,
                error: ei,
                weighted_squared_error: w * ei * ei,
            })
            .collect())
    }

    /// The topology with the parameters `x` written in.
    pub fn topology_at(&self, topology: &Topology, x: &[f64]) -> Topology {
        let mut t = topology.clone();
        let n_trail = t.trail_edges.len();
        for (target, &xi) in self.targets.iter().zip(x) {
            match target {
                Target::Lengths(es) => {
                    for &e in es {
                        if e < n_trail {
                            t.trail_edges[e].length = xi;
                        } else if let Some(a) = t.auxiliary_trails.as_mut() {
                            // Auxiliary edges share one length in the topology.
                            a.length = xi;
                        }
                    }
                }
                Target::Forces(es) => es.iter().for_each(|&e| t.deviation_edges[e].force = xi),
                Target::Origin(i, a) => {
                    if let Some(n) = t.nodes.get_mut(*i) {
                        n.xyz[*a] = xi;
                    }
                }
                Target::Load(i, a) => {
                    if let Some(n) = t.nodes.get_mut(*i) {
                        n.load[*a] = xi;
                    }
                }
            }
        }
        t
    }
}

/// Minimize `Σ w·e²` over the parameters of `problem` with SLSQP and exact gradients.
///
/// The equilibrium is re-solved at `x_opt`; an evaluation that fails (for example a
/// non-converging indirect iteration) is given a huge objective so that SLSQP backs off.
pub fn optimize(
    topology: &Topology,
    problem: &Problem,
    options: &OptimizeOptions,
) -> Result<OptimizeResult, CemError> {
    let ev = Evaluator::new(topology, problem, options)?;
    let (f0, g0) = ev.objective_and_gradient(&ev.x0)?;
    let evaluations = Cell::new(0usize);
    let gradients = Cell::new(1usize);
    let best: RefCell<(f64, Vec<f64>)> = RefCell::new((f0, ev.x0.clone()));
    let func = |x: &[f64], grad: Option<&mut [f64]>, _: &mut ()| -> f64 {
        evaluations.set(evaluations.get() + 1);
        let out = match grad {
            Some(g) => {
                gradients.set(gradients.get() + 1);
                ev.objective_and_gradient(x).map(|(f, gr)| {
                    g.copy_from_slice(&gr);
                    f
                })
            }
            None => ev.objective(x),
        };
        match out {
            Ok(f) => {
                let mut b = best.borrow_mut();
                if f < b.0 {
                    *b = (f, x.to_vec());
                }
                f
            }
            Err(_) => 1e300,
        }
    };
    let bounds: Vec<(f64, f64)> = ev
        .lower
        .iter()
        .copied()
        .zip(ev.upper.iter().copied())
        .collect();
    let tols = slsqp::StopTols {
        ftol_rel: options.ftol_rel,
        ftol_abs: options.ftol_abs,
        xtol_rel: options.xtol_rel,
        xtol_abs: Vec::new(),
    };
    let no_constraints: [Constraint; 0] = [];
    let outcome = slsqp::minimize(
        func,
        &ev.x0,
        &bounds,
        &no_constraints,
        (),
        options.max_evaluations.max(1),
        Some(tols),
    );
    let (status, x_last) = match outcome {
        Ok((s, x, _)) => (
            match s {
                slsqp::SuccessStatus::Success => OptimizeStatus::Success,
                slsqp::SuccessStatus::StopValReached => OptimizeStatus::StopvalReached,
                slsqp::SuccessStatus::FtolReached => OptimizeStatus::FtolReached,
                slsqp::SuccessStatus::XtolReached => OptimizeStatus::XtolReached,
                slsqp::SuccessStatus::MaxEvalReached | slsqp::SuccessStatus::MaxTimeReached => {
                    OptimizeStatus::MaxEvalReached
                }
            },
            x,
        ),
        Err((s, x, _)) => (
            match s {
                slsqp::FailStatus::RoundoffLimited => OptimizeStatus::RoundoffLimited,
                _ => OptimizeStatus::Failure,
            },
            x,
        ),
    };
    // Keep the best point seen (SLSQP's last iterate can be a rejected line-search trial).
    let (fbest, xbest) = best.into_inner();
    let x_opt = match ev.objective(&x_last) {
        Ok(f) if f <= fbest => x_last,
        _ => xbest,
    };
    let (f_opt, g_opt) = ev.objective_and_gradient(&x_opt)?;
    let status = if f_opt <= options.stopval {
        OptimizeStatus::StopvalReached
    } else {
        status
    };
    let converged = matches!(
        status,
        OptimizeStatus::StopvalReached
            | OptimizeStatus::FtolReached
            | OptimizeStatus::XtolReached
            | OptimizeStatus::Success
    );
    let topo_opt = ev.topology_at(topology, &x_opt);
    let equilibrium = Model::new(&topo_opt)?.solve(&options.solver)?;
    Ok(OptimizeResult {
        x0: ev.x0.clone(),
        bounds_low: ev.lower.clone(),
        bounds_up: ev.upper.clone(),
        objective_at_x0: f0,
        gradient_at_x0: g0,
        goals: ev.goal_reports(&x_opt)?,
        x_opt,
        objective_at_x_opt: f_opt,
        gradient_at_x_opt: g_opt,
        status,
        converged,
        iterations: gradients.get(),
        evaluations: evaluations.get(),
        topology: topo_opt,
        equilibrium,
    })
}

/// SLSQP constraint callback type (none are used: all goals are soft).
type Constraint = fn(&[f64], Option<&mut [f64]>, &mut ()) -> f64;

fn edge_pair(v: &Value, ctx: &str) -> Result<(NodeId, NodeId), CemError> {
    let bad = || CemError::MalformedJson {
        path: ctx.to_string(),
        message: "expected an edge [u, v] of two node ids".into(),
    };
    let a = v.as_array().ok_or_else(bad)?;
    match a.as_slice() {
        [u, v] => Ok((u.as_u64().ok_or_else(bad)?, v.as_u64().ok_or_else(bad)?)),
        _ => Err(bad()),
    }
}

fn num(v: &Value, key: &str, ctx: &str) -> Result<f64, CemError> {
    v.get(key)
        .and_then(Value::as_f64)
        .ok_or_else(|| CemError::MalformedJson {
            path: format!("{ctx}.{key}"),
            message: "expected a number".into(),
        })
}

fn opt_num(v: &Value, key: &str, ctx: &str) -> Result<Option<f64>, CemError> {
    match v.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(x) => x.as_f64().map(Some).ok_or_else(|| CemError::MalformedJson {
            path: format!("{ctx}.{key}"),
            message: "expected a number or null".into(),
        }),
    }
}

fn vec3(v: &Value, key: &str, ctx: &str) -> Result<Vector3<f64>, CemError> {
    let bad = || CemError::MalformedJson {
        path: format!("{ctx}.{key}"),
        message: "expected [x, y, z]".into(),
    };
    let a = v.get(key).and_then(Value::as_array).ok_or_else(bad)?;
    match a.as_slice() {
        [x, y, z] => Ok(Vector3::new(
            x.as_f64().ok_or_else(bad)?,
            y.as_f64().ok_or_else(bad)?,
            z.as_f64().ok_or_else(bad)?,
        )),
        _ => Err(bad()),
    }
}

fn node_id(v: &Value, ctx: &str) -> Result<NodeId, CemError> {
    v.get("node")
        .and_then(Value::as_u64)
        .ok_or_else(|| CemError::MalformedJson {
            path: format!("{ctx}.node"),
            message: "expected a node id (non-negative integer)".into(),
        })
}

impl Problem {
    /// Parse the `optimization` block of a `kappe.cem.topology` document (relative bounds),
    /// returning the problem and the optimizer options of its `solver` block.
    pub fn from_json(block: &Value) -> Result<(Problem, OptimizeOptions), CemError> {
        let mut problem = Problem::default();
        let params = block
            .get("parameters")
            .and_then(Value::as_array)
            .ok_or_else(|| CemError::MalformedJson {
                path: "optimization.parameters".into(),
                message: "expected a list of parameters".into(),
            })?;
        for (k, p) in params.iter().enumerate() {
            let ctx = format!("optimization.parameters[{k}]");
            let kind_s = p.get("kind").and_then(Value::as_str).unwrap_or("");
            let edge = || {
                edge_pair(
                    p.get("edge").unwrap_or(&Value::Null),
                    &format!("{ctx}.edge"),
                )
            };
            let node = || node_id(p, &ctx);
            let kind = match kind_s {
                "trail_length" => {
                    let (u, v) = edge()?;
                    ParameterKind::TrailLength(u, v)
                }
                "deviation_force" => {
                    let (u, v) = edge()?;
                    ParameterKind::DeviationForce(u, v)
                }
                "trail_lengths" | "deviation_forces" => {
                    let edges = p.get("edges").and_then(Value::as_array).ok_or_else(|| {
                        CemError::MalformedJson {
                            path: format!("{ctx}.edges"),
                            message: "expected a list of edges".into(),
                        }
                    })?;
                    let es = edges
                        .iter()
                        .enumerate()
                        .map(|(i, e)| edge_pair(e, &format!("{ctx}.edges[{i}]")))
                        .collect::<Result<Vec<_>, _>>()?;
                    if kind_s == "trail_lengths" {
                        ParameterKind::TrailLengths(es)
                    } else {
                        ParameterKind::DeviationForces(es)
                    }
                }
                "origin_x" => ParameterKind::OriginX(node()?),
                "origin_y" => ParameterKind::OriginY(node()?),
                "origin_z" => ParameterKind::OriginZ(node()?),
                "load_x" => ParameterKind::LoadX(node()?),
                "load_y" => ParameterKind::LoadY(node()?),
                "load_z" => ParameterKind::LoadZ(node()?),
                other => {
                    return Err(CemError::MalformedJson {
                        path: format!("{ctx}.kind"),
                        message: format!(
                            "unknown parameter kind {other:?}; allowed: trail_length, trail_lengths, deviation_force, deviation_forces, origin_x/y/z, load_x/y/z"
                        ),
                    });
                }
            };
            let below = opt_num(p, "bound_low", &ctx)?;
            let above = opt_num(p, "bound_up", &ctx)?;
            for b in [below, above].into_iter().flatten() {
                check_finite(|| format!("{ctx} bound"), b)?;
            }
            problem.parameters.push(Parameter {
                kind,
                bounds: Bounds::Relative { below, above },
            });
        }
        let goals = block
            .get("constraints")
            .or_else(|| block.get("goals"))
            .and_then(Value::as_array)
            .ok_or_else(|| CemError::MalformedJson {
                path: "optimization.constraints".into(),
                message: "expected a list of goals".into(),
            })?;
        for (k, g) in goals.iter().enumerate() {
            let ctx = format!("optimization.constraints[{k}]");
            let edge = || {
                edge_pair(
                    g.get("edge").unwrap_or(&Value::Null),
                    &format!("{ctx}.edge"),
                )
            };
            let goal = match g.get("kind").and_then(Value::as_str).unwrap_or("") {
                "point" => Goal::Point {
                    node: node_id(g, &ctx)?,
                    target: vec3(g, "target", &ctx)?,
                },
                "line" => Goal::Line {
                    node: node_id(g, &ctx)?,
                    start: vec3(g, "start", &ctx)?,
                    end: vec3(g, "end", &ctx)?,
                },
                "plane" => Goal::Plane {
                    node: node_id(g, &ctx)?,
                    origin: vec3(g, "origin", &ctx)?,
                    normal: vec3(g, "normal", &ctx)?,
                },
                "trail_force" => Goal::TrailForce {
                    edge: edge()?,
                    target: num(g, "target", &ctx)?,
                },
                "deviation_length" => Goal::DeviationLength {
                    edge: edge()?,
                    target: num(g, "target", &ctx)?,
                },
                "reaction" => Goal::Reaction {
                    node: node_id(g, &ctx)?,
                    target: vec3(g, "target", &ctx)?,
                },
                "edge_direction" => Goal::EdgeDirection {
                    edge: edge()?,
                    target: vec3(g, "target", &ctx)?,
                },
                other => {
                    return Err(CemError::MalformedJson {
                        path: format!("{ctx}.kind"),
                        message: format!(
                            "unknown goal kind {other:?}; allowed: point, line, plane, trail_force, deviation_length, reaction, edge_direction"
                        ),
                    });
                }
            };
            let weight = opt_num(g, "weight", &ctx)?.unwrap_or(1.0);
            problem.goals.push(WeightedGoal { goal, weight });
        }
        let mut opts = OptimizeOptions::default();
        if let Some(s) = block.get("solver") {
            let ctx = "optimization.solver";
            if let Some(a) = s.get("algorithm").and_then(Value::as_str)
                && !a.eq_ignore_ascii_case("SLSQP")
            {
                return Err(CemError::InvalidProblem(format!(
                    "algorithm {a:?} is not available; only SLSQP is"
                )));
            }
            if let Some(i) = s.get("iters").and_then(Value::as_u64) {
                opts.max_evaluations = usize::try_from(i).unwrap_or(usize::MAX);
            }
            if let Some(v) = opt_num(s, "eps", ctx)? {
                opts.stopval = v;
            }
            if let Some(v) = opt_num(s, "kappa", ctx)? {
                opts.ftol_abs = v;
            }
            if let Some(t) = s.get("tmax").and_then(Value::as_u64) {
                opts.solver.tmax = usize::try_from(t).unwrap_or(usize::MAX);
            }
            if let Some(v) = opt_num(s, "eta", ctx)? {
                opts.solver.eta = v;
            }
        }
        Ok((problem, opts))
    }
}
