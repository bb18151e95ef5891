//! Typed errors of the CEM crate.
//!
//! Every variant names the node or edge that is wrong, the offending value where there is one,
//! and what would be allowed. compas_cem reports most of these as bare `AssertionError`s or
//! not at all (cem.md §2); Kappe rejects them up front so that no partial result is produced.

use crate::ids::NodeId;

/// Everything that can go wrong when reading, validating, solving or optimizing a topology.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CemError {
    /// The input is not valid JSON or does not have the expected shape.
    #[error("malformed input JSON at `{path}`: {message}")]
    MalformedJson {
        /// JSON path of the offending value (`.` for the document).
        path: String,
        /// What the parser said.
        message: String,
    },
    /// `format`/`version` are not the ones this reader understands.
    #[error("unsupported format {format:?} version {version}; expected {expected:?} version 1")]
    UnsupportedFormat {
        /// The `format` string found.
        format: String,
        /// The `version` found.
        version: u64,
        /// The format that was expected.
        expected: &'static str,
    },
    /// Two nodes share an id.
    #[error("duplicate node id {id}: node ids must be unique")]
    DuplicateNode {
        /// The repeated id.
        id: NodeId,
    },
    /// An edge, shift, parameter or goal refers to a node id that does not exist.
    #[error("{context} refers to unknown node {id}; only ids listed in `nodes` are allowed")]
    UnknownNode {
        /// The unknown id.
        id: NodeId,
        /// Where it was referenced (for example `trail edge (3, 4)`).
        context: String,
    },
    /// A parameter or goal refers to an edge that does not exist (in either orientation).
    #[error(
        "{context} refers to unknown {kind} edge ({u}, {v}); it must be listed in `{kind}_edges`"
    )]
    UnknownEdge {
        /// First node of the edge as given.
        u: NodeId,
        /// Second node of the edge as given.
        v: NodeId,
        /// `trail` or `deviation`.
        kind: &'static str,
        /// Where it was referenced.
        context: String,
    },
    /// A value that must be a finite number is NaN or infinite.
    #[error("{what} is {value}; only finite numbers are allowed")]
    NonFinite {
        /// Which value (node, edge and field).
        what: String,
        /// The value.
        value: f64,
    },
    /// A trail-edge plane has a zero normal.
    #[error(
        "trail edge ({u}, {v}) has a plane with zero normal; the normal must be a non-zero vector"
    )]
    ZeroPlaneNormal {
        /// One end.
        u: NodeId,
        /// Other end.
        v: NodeId,
    },
    /// An edge joins a node to itself.
    #[error("{kind} edge ({u}, {u}) joins node {u} to itself; an edge needs two distinct nodes")]
    SelfLoop {
        /// `trail` or `deviation`.
        kind: &'static str,
        /// The node.
        u: NodeId,
    },
    /// Two edges join the same pair of nodes.
    #[error(
        "edges {first} and {second} both join nodes {u} and {v}; at most one edge per pair of nodes is allowed"
    )]
    DuplicateEdge {
        /// One end.
        u: NodeId,
        /// Other end.
        v: NodeId,
        /// Description of the first edge.
        first: String,
        /// Description of the second edge.
        second: String,
    },
    /// No node is marked as a support (and no auxiliary trail created one).
    #[error(
        "no supports assigned: at least one node must have `support: true` (every trail ends at a support)"
    )]
    NoSupport,
    /// A node lies on no trail and auxiliary trails are off.
    #[error(
        "node {id} is on no trail (it has no trail edge and is not a support); give it a trail edge to a support, mark it as a support, or enable `auxiliary_trails`"
    )]
    UnassignedNode {
        /// The node.
        id: NodeId,
    },
    /// A chain of trail edges ends without reaching any support.
    #[error(
        "the trail through nodes {nodes:?} has no support; exactly one end of every trail must be a support"
    )]
    TrailWithoutSupport {
        /// The nodes of the chain.
        nodes: Vec<NodeId>,
    },
    /// A node has three or more trail edges, i.e. it would lie on two trails.
    #[error(
        "node {id} has {count} trail edges ({edges}); a node lies on exactly one trail, so at most 2 trail edges are allowed"
    )]
    NodeOnTwoTrails {
        /// The node.
        id: NodeId,
        /// Its number of trail edges.
        count: usize,
        /// The edges, listed.
        edges: String,
    },
    /// A support has two trail edges: it sits inside a trail instead of at its end.
    #[error(
        "support {id} has 2 trail edges; a support must be the last node of its trail (0 or 1 trail edges)"
    )]
    SupportInsideTrail {
        /// The support.
        id: NodeId,
    },
    /// One trail runs from one support to another.
    #[error(
        "the trail from support {first} runs into support {second}; a trail has exactly one support (remove one support flag or split the trail)"
    )]
    TrailWithTwoSupports {
        /// The support the walk started from.
        first: NodeId,
        /// The support it ran into.
        second: NodeId,
    },
    /// Trail edges form a closed loop.
    #[error(
        "trail edges form a cycle through nodes {nodes:?}; trails must be open paths ending at a support"
    )]
    TrailCycle {
        /// Nodes of the cycle.
        nodes: Vec<NodeId>,
    },
    /// A node's `origin` flag disagrees with the derived role.
    #[error(
        "node {id} has `origin: {given}` but the trails make it {derived}; remove the flag or fix the trail"
    )]
    OriginMismatch {
        /// The node.
        id: NodeId,
        /// The flag in the input.
        given: bool,
        /// What the trail building derived.
        derived: &'static str,
    },
    /// A trail shift names a node that is not the origin of a trail.
    #[error(
        "trail shift for node {id}: {id} is not the origin of a trail; shifts are keyed by trail origins"
    )]
    ShiftNotOrigin {
        /// The node.
        id: NodeId,
    },
    /// A trail shift is given twice for the same origin.
    #[error("trail shift for origin {id} is given twice; at most one shift per trail is allowed")]
    DuplicateShift {
        /// The origin.
        id: NodeId,
    },
    /// A solver option is out of range.
    #[error("solver option {name} = {value}; {allowed}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Given value.
        value: f64,
        /// What is allowed.
        allowed: &'static str,
    },
    /// The indirect-edge iteration did not converge.
    #[error(
        "equilibrium not converged after {tmax} sweeps: residual distance {residual:e} > eta {eta:e}; raise `tmax` or `eta`"
    )]
    NotConverged {
        /// Sweeps run.
        tmax: usize,
        /// Σ‖x_t − x_{t−1}‖ of the last sweep.
        residual: f64,
        /// Threshold.
        eta: f64,
    },
    /// The solve produced a non-finite number (overflow).
    #[error(
        "the solve produced a non-finite value at node {id}; check loads, lengths and forces for extreme magnitudes"
    )]
    NumericalBreakdown {
        /// The first node with a non-finite position or force.
        id: NodeId,
    },
    /// Prescribed positions do not match the topology (fixed-geometry force pass).
    #[error("{0}")]
    PositionMismatch(String),
    /// The arrays of a network given by index ([`crate::model::IndexedNetwork`]) disagree.
    #[error("network given by index: {0}")]
    InvalidNetwork(String),
    /// A constrained form-finding problem is ill-posed.
    #[error("optimization problem: {0}")]
    InvalidProblem(String),
}

impl CemError {
    /// A short stable name of the error kind (used by the CLI and the tests to match the
    /// `err_*` fixtures).
    pub fn kind(&self) -> &'static str {
        match self {
            Self::MalformedJson { .. } => "malformed_json",
            Self::UnsupportedFormat { .. } => "unsupported_format",
            Self::DuplicateNode { .. } => "duplicate_node",
            Self::UnknownNode { .. } => "unknown_node",
            Self::UnknownEdge { .. } => "unknown_edge",
            Self::NonFinite { .. } => "non_finite",
            Self::SelfLoop { .. } => "self_loop",
            Self::ZeroPlaneNormal { .. } => "zero_plane_normal",
            Self::DuplicateEdge { .. } => "duplicate_edge",
            Self::NoSupport => "no_support",
            Self::UnassignedNode { .. } => "unassigned_node",
            Self::TrailWithoutSupport { .. } => "trail_without_support",
            Self::NodeOnTwoTrails { .. } => "node_on_two_trails",
            Self::SupportInsideTrail { .. } => "support_inside_trail",
            Self::TrailWithTwoSupports { .. } => "trail_with_two_supports",
            Self::TrailCycle { .. } => "trail_cycle",
            Self::OriginMismatch { .. } => "origin_mismatch",
            Self::ShiftNotOrigin { .. } => "shift_not_origin",
            Self::DuplicateShift { .. } => "duplicate_shift",
            Self::InvalidOption { .. } => "invalid_option",
            Self::NotConverged { .. } => "not_converged",
            Self::NumericalBreakdown { .. } => "numerical_breakdown",
            Self::PositionMismatch(_) => "position_mismatch",
            Self::InvalidNetwork(_) => "invalid_network",
            Self::InvalidProblem(_) => "invalid_problem",
        }
    }
}
