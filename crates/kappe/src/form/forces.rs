//! Forces of a print state: CEM's fixed-geometry force pass over the constructed network
//! (method.md §5: marching CEM down a deep stack is unstable, so the geometry is prescribed and
//! only the forces are swept), then the per-state extremes, stresses and base reactions.

use kappe_cem::fixed_geometry::ForcePass;
use kappe_cem::topology::Topology;

use crate::form::frame::V3;
use crate::form::states::{Role, State};
use crate::input::error::DesignError;

/// The forces of one state and what a designer reads off them.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StateForces {
    /// Most negative (compressive) edge force, N (0 if none).
    pub max_compression_force: f64,
    /// Largest positive (tensile) edge force, N (0 if none).
    pub max_tension_force: f64,
    /// Most negative normal stress, Pa.
    pub max_compression_stress: f64,
    /// Largest normal stress, Pa.
    pub max_tension_stress: f64,
    /// Largest node residual |q + ΣF·û + R|, N.
    pub max_residual: f64,
    /// Residual tolerance 1e-9·(1 + max|F|) of method.md §9.
    pub residual_tolerance: f64,
    /// Sum of the base reactions (feet and column ends), N.
    pub base_reaction: [f64; 3],
    /// Sum of the reactions of the column ends (the start section's bed on the base), N.
    pub column_end_reaction: [f64; 3],
    /// |H| / V of the summed column-end reactions (the start section's aggregate thrust ratio).
    pub column_end_hv_ratio: f64,
    /// Sum of the longitudinal (y) components of the feet reactions, N.
    pub feet_longitudinal_reaction: f64,
    /// Largest H/V ratio of a single column end.
    pub max_column_hv_ratio: f64,
    /// Smallest H/V ratio of a single column end.
    pub min_column_hv_ratio: f64,
    /// Smallest and largest start-layer factor d of the state.
    pub factor_range: [f64; 2],
}

/// Cross-section areas used for stresses (method.md §3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sections2D {
    /// lw·lh, the area of an arch segment (along a layer), m².
    pub along_layer: f64,
    /// lw·l_trib, the bed-joint area of a column edge, m².
    pub bed_joint: f64,
}

/// Run the force pass of a state and summarize it.
pub fn state_forces(
    state: &State,
    areas: Sections2D,
) -> Result<(Topology, ForcePass, StateForces), DesignError> {
    let net = &state.network;
    let topo = net.to_topology(&format!("state {}", state.index));
    let fp = kappe_cem::fixed_geometry::force_pass(&topo, &net.positions())?;
    let summary = summarize(state, &topo, &fp, areas);
    Ok((topo, fp, summary))
}

fn summarize(state: &State, topo: &Topology, fp: &ForcePass, areas: Sections2D) -> StateForces {
    let mut cmin: f64 = 0.0;
    let mut cmax: f64 = 0.0;
    let mut smin: f64 = 0.0;
    let mut smax: f64 = 0.0;
    let mut max_abs: f64 = 0.0;
    for &f in &fp.trail_forces {
        cmin = cmin.min(f);
        cmax = cmax.max(f);
        smin = smin.min(f / areas.bed_joint);
        smax = smax.max(f / areas.bed_joint);
        max_abs = max_abs.max(f.abs());
    }
    for e in &topo.deviation_edges {
        let f = e.force;
        cmin = cmin.min(f);
        cmax = cmax.max(f);
        smin = smin.min(f / areas.along_layer);
        smax = smax.max(f / areas.along_layer);
        max_abs = max_abs.max(f.abs());
    }
    let mut base = V3::zeros();
    let mut ends = V3::zeros();
    let mut feet_y = 0.0;
    let mut hv_min = f64::INFINITY;
    let mut hv_max: f64 = 0.0;
    for (node, reaction) in state.network.nodes.iter().zip(&fp.reactions) {
        if matches!(node.role, Role::Foot | Role::ColumnEnd) {
            base += reaction;
        }
        match node.role {
            Role::ColumnEnd => ends += reaction,
            Role::Foot => feet_y += reaction.y,
            Role::Column => {}
        }
        if node.role == Role::ColumnEnd && reaction.z.abs() > 0.0 {
            let hv = reaction.xy().norm() / reaction.z.abs();
            hv_min = hv_min.min(hv);
            hv_max = hv_max.max(hv);
        }
    }
    let fmin = state.factors.iter().copied().fold(f64::INFINITY, f64::min);
    let fmax = state
        .factors
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    StateForces {
        max_compression_force: cmin,
        max_tension_force: cmax,
        max_compression_stress: smin,
        max_tension_stress: smax,
        max_residual: fp.max_node_residual,
        residual_tolerance: 1e-9 * (1.0 + max_abs),
        base_reaction: [base.x, base.y, base.z],
        column_end_reaction: [ends.x, ends.y, ends.z],
        column_end_hv_ratio: if ends.z.abs() > 0.0 {
            ends.xy().norm() / ends.z.abs()
        } else {
            0.0
        },
        feet_longitudinal_reaction: feet_y,
        max_column_hv_ratio: hv_max,
        min_column_hv_ratio: if hv_min.is_finite() { hv_min } else { 0.0 },
        factor_range: [fmin, fmax],
    }
}
