//! # kappe-cem: Combinatorial Equilibrium Modeling
//!
//! A Rust implementation of Combinatorial Equilibrium Modeling (CEM; Ohlbrock & D'Acunto,
//! *Computer-Aided Design* 121, 2020) and of constrained CEM form-finding (Pastrana et al.,
//! *Computer-Aided Design* 155, 2023), reproducing compas_cem 0.8.6 (see
//! `shared/reference/cem.md`).
//!
//! * [`Topology`] / [`TopologyBuilder`]: nodes with loads and supports, trail edges with
//!   signed lengths λ, deviation edges with signed forces μ (negative = compression).
//! * [`Model`]: validated trails, sequences and the solve schedule ([`Model::new`]; for
//!   networks a program builds by index, [`Model::from_trails`]).
//! * [`solve`] / [`Model::solve`]: the sequential nodal equilibrium
//!   `r_n = r_in − q_n − D_n`, `x_next = x_n + λ·û(r_n)`, giving an [`Equilibrium`]
//!   with positions, trail forces `F = copysign(‖r‖, λ)`, reactions `R = r` at supports,
//!   realized lengths, per-node residuals and force polygons.
//! * [`fixed_geometry::force_pass`]: forces of a network whose positions are all prescribed.
//! * [`optimize::optimize`]: constrained form-finding with exact forward-mode gradients.
//! * [`json`]: the `kappe.cem.topology` / `kappe.cem.expected` interchange formats.
//!
//! Kappe extension: a support without a trail edge is a *reaction node* (a one-node trail
//! whose origin is the support); its position is prescribed and its reaction is `−q − D`.
//!
//! ```
//! use kappe_cem::{Topology, SolverOptions, solve};
//! // A two-edge compression trail hanging from origin 0 with a unit load at every node but
//! // the support; without deviation edges the trail is straight and vertical.
//! let topo = Topology::builder()
//!     .node(0, [0.0, 0.0, 2.0]).load(0, [0.0, 0.0, -1.0])
//!     .node(1, [0.0, 0.0, 1.0]).load(1, [0.0, 0.0, -1.0])
//!     .node(2, [0.0, 0.0, 0.0]).support(2)
//!     .trail_edge(0, 1, -1.0)
//!     .trail_edge(1, 2, -1.0)
//!     .build()?;
//! let eq = solve(&topo, &SolverOptions::default())?;
//! // Node 1 lies 1 below node 0, the support carries both loads upward.
//! assert!((eq.position(1).unwrap().z - 1.0).abs() < 1e-12);
//! assert!((eq.reaction(2).unwrap().z - 2.0).abs() < 1e-12);
//! // The lower edge carries both loads in compression.
//! assert!((eq.trail_edge(2, 1).unwrap().force + 2.0).abs() < 1e-12);
//! # Ok::<(), kappe_cem::CemError>(())
//! ```

pub mod equilibrium;
pub mod error;
pub mod example;
pub mod fixed_geometry;
mod ids;
pub mod json;
pub mod model;
pub mod optimize;
pub mod report;
pub mod topology;

pub use equilibrium::{
    Checks, DeviationEdgeResult, Equilibrium, ForcePolygon, Iterations, NodeResult, PolygonSide,
    Scalar, SolverOptions, TrailEdgeResult, solve,
};
pub use error::CemError;
pub use fixed_geometry::{ForcePass, force_pass};
pub use model::{IndexedNetwork, Model};
pub use optimize::{
    Bounds, Goal, OptimizeOptions, OptimizeResult, OptimizeStatus, Parameter, ParameterKind,
    Problem, WeightedGoal, optimize,
};
pub use topology::{
    AuxiliaryTrails, DeviationEdge, Node, NodeId, Plane, Topology, TopologyBuilder, TrailEdge,
    TrailShift,
};
