//! The fixed-geometry force pass (method.md §5): forces of a CEM network whose node
//! positions are **all** prescribed (for example a constructed print state of the cap).
//!
//! The CEM sweep is run at the given positions, once (no iteration: nothing moves).
//! For the node `n` of a trail, with incoming trail force vector `t_in` (0 at an origin):
//!
//! ```text
//! r_out = t_in − q_n − D_n,       D_n = Σ_e μ_e · û(x_m − x_n)   (all deviation edges)
//! ê     = û(x_s − x_n)             (unit vector from n to the next node s of the trail)
//! F_e   = r_out · ê                (signed: > 0 tension, < 0 compression, as in CEM)
//! ρ_n   = ‖r_out − F_e ê‖          (node residual: the part the trail edge cannot carry)
//! t_in(s) = F_e ê                  (what the edge actually transmits to s)
//! ```
//!
//! At a support (and at a reaction node, whose `t_in` is 0) the reaction is `R = r_out`, so
//! supports have zero residual by definition. If the geometry is a CEM equilibrium, `r_out`
//! is parallel to ê, ρ = 0 and the forces equal the solver's.
//!
//! A trail edge of zero length has no direction: its force is reported as 0 and the whole
//! `r_out` as residual.

use nalgebra::Vector3;

use crate::equilibrium::{dot, safe_unit};
use crate::error::CemError;
use crate::model::Model;
use crate::topology::{NodeId, Topology};

/// Forces of a network at prescribed positions.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcePass {
    /// Signed force per trail edge, in topology order (> 0 tension, < 0 compression).
    pub trail_forces: Vec<f64>,
    /// Reaction per node in topology order (force of the support on the structure; zero for
    /// non-supports).
    pub reactions: Vec<Vector3<f64>>,
    /// Node residual ρ_n per node in topology order (0 at supports).
    pub node_residuals: Vec<f64>,
    /// max ρ_n.
    pub max_node_residual: f64,
    /// Node id of the largest residual.
    pub max_residual_node: Option<NodeId>,
    /// Largest |F| over trail and deviation edges (scale for residual tolerances).
    pub max_abs_force: f64,
}

/// Run the force pass on `topology` with `positions[i]` the position of `topology.nodes[i]`.
///
/// Auxiliary trails are not supported here (their nodes have no prescribed position):
/// a topology with `auxiliary_trails` that creates any is rejected.
pub fn force_pass(topology: &Topology, positions: &[Vector3<f64>]) -> Result<ForcePass, CemError> {
    Model::new(topology)?.force_pass(positions)
}

impl Model {
    /// The force pass on an already built model; `positions` in topology node order.
    pub fn force_pass(&self, positions: &[Vector3<f64>]) -> Result<ForcePass, CemError> {
        if !self.aux.is_empty() {
            return Err(CemError::PositionMismatch(format!(
                "the fixed-geometry force pass needs every node position, but the topology \
                 creates {} auxiliary trail(s); give those nodes explicit trail edges",
                self.aux.len()
            )));
        }
        let n = self.ids.len();
        if positions.len() != n {
            return Err(CemError::PositionMismatch(format!(
                "{} positions given for {n} nodes; give one position per topology node, in node order",
                positions.len()
            )));
        }
        for (i, p) in positions.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(CemError::NonFinite {
                    what: format!("prescribed position of node {}", self.ids[i]),
                    value: p
                        .iter()
                        .copied()
                        .find(|c| !c.is_finite())
                        .unwrap_or(f64::NAN),
                });
            }
        }
        let mut t_in = vec![Vector3::zeros(); n];
        let mut trail_forces = vec![0.0; self.trail_u.len()];
        let mut reactions = vec![Vector3::zeros(); n];
        let mut node_residuals = vec![0.0; n];
        for step in &self.steps {
            let i = step.node;
            let xi = positions[i];
            let mut r = t_in[i] - self.loads[i];
            for a in &self.adj[self.adj_start[i]..self.adj_start[i + 1]] {
                r -= safe_unit(&(positions[a.other] - xi)) * self.forces[a.edge];
            }
            match step.out {
                None => reactions[i] = r,
                Some((e, s)) => {
                    let ehat = safe_unit(&(positions[s] - xi));
                    let f = dot(&r, &ehat);
                    let carried = ehat * f;
                    trail_forces[e] = f;
                    node_residuals[i] = (r - carried).norm();
                    t_in[s] = carried;
                }
            }
        }
        let (mut max_node_residual, mut max_residual_node) = (0.0, None);
        for (i, &r) in node_residuals.iter().enumerate() {
            if r > max_node_residual || max_residual_node.is_none() {
                max_node_residual = r;
                max_residual_node = Some(self.ids[i]);
            }
        }
        let max_abs_force = trail_forces
            .iter()
            .chain(self.forces.iter())
            .fold(0.0_f64, |m, f| m.max(f.abs()));
        Ok(ForcePass {
            trail_forces,
            reactions,
            node_residuals,
            max_node_residual,
            max_residual_node,
            max_abs_force,
        })
    }
}
