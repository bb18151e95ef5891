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
    /// Largest node load the network does not carry axially and hands to the shell's bending
    /// ([`split_state_forces`], corrugated caps), N; 0 (and not serialized) for a network in
    /// exact equilibrium under its own loads.
    #[serde(skip_serializing_if = "is_zero")]
    pub out_of_funicular: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// Cross-section areas used for stresses (method.md §3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sections2D {
    /// lw·lh, the area of an arch segment (along a layer), m².
    pub along_layer: f64,
    /// lw·l_trib, the bed-joint area of a column edge, m².
    pub bed_joint: f64,
}

/// Run the force pass of a state and summarize it; with the state's CEM topology.
pub fn state_forces(
    state: &State,
    areas: Sections2D,
) -> Result<(Topology, ForcePass, StateForces), DesignError> {
    let (fp, summary) = state_pass(state, areas)?;
    let topo = state.network.to_topology(&format!("state {}", state.index));
    Ok((topo, fp, summary))
}

/// [`state_forces`] without the topology: the force pass over the model built from the
/// network's trails ([`crate::form::states::Network::to_model`]; the same numbers as the pass
/// over the topology, without validating again what the construction guarantees).
pub fn state_pass(
    state: &State,
    areas: Sections2D,
) -> Result<(ForcePass, StateForces), DesignError> {
    let model = state.network.to_model(&format!("state {}", state.index))?;
    let fp = model.force_pass(model.initial_positions())?;
    let summary = summarize(state, &fp, areas);
    Ok((fp, summary))
}

fn summarize(state: &State, fp: &ForcePass, areas: Sections2D) -> StateForces {
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
    // The arch segments' forces as the topology's deviation edges carry them.
    for e in &state.network.deviation_edges {
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
        out_of_funicular: 0.0,
    }
}

/// The unbalanced force of every node of a force pass: `q_n + Σ_e F_e·û(x_m − x_n) + R_n` over
/// the node's trail and deviation edges (tension positive), in topology node order. Its norm is
/// the pass's node residual ρ_n (docs/corrugation.md, "State equilibrium"); it is zero at
/// supports by construction.
pub fn unbalanced_forces(topo: &Topology, fp: &ForcePass) -> Vec<V3> {
    let mut out: Vec<V3> = topo
        .nodes
        .iter()
        .zip(&fp.reactions)
        .map(|(n, r)| n.load + r)
        .collect();
    let unit = |d: V3| {
        let l = d.norm();
        if l > 0.0 { d / l } else { V3::zeros() }
    };
    let mut add = |u: usize, v: usize, f: f64| {
        let (Some(xu), Some(xv)) = (topo.nodes.get(u), topo.nodes.get(v)) else {
            return;
        };
        let e = unit(xv.xyz - xu.xyz);
        out[u] += e * f;
        out[v] -= e * f;
    };
    for (e, &f) in topo.trail_edges.iter().zip(&fp.trail_forces) {
        add(e.u as usize, e.v as usize, f);
    }
    for e in &topo.deviation_edges {
        add(e.u as usize, e.v as usize, e.force);
    }
    out
}

/// The force pass of a state whose fixed geometry is not funicular for its loads (a corrugated
/// cap, docs/corrugation.md "State equilibrium"): the first pass gives every node's unbalanced
/// force `s_n` ([`unbalanced_forces`]); each node's load is split into `q_n − s_n`, which the
/// network carries (a second pass under those loads, whose residual is round-off), and `s_n`,
/// which the shell carries by bending (`crate::analysis::bending`). The member forces of both
/// passes are the same (the split removes exactly what no edge took). Returns the second pass,
/// its summary (`out_of_funicular` = max |s_n|) and `s_n` per node.
pub fn split_state_forces(
    state: &State,
    areas: Sections2D,
) -> Result<(Topology, ForcePass, StateForces, Vec<V3>), DesignError> {
    let net = &state.network;
    let positions = net.positions();
    let mut topo = net.to_topology(&format!("state {}", state.index));
    let first = kappe_cem::fixed_geometry::force_pass(&topo, &positions)?;
    let unbalanced = unbalanced_forces(&topo, &first);
    for (node, s) in topo.nodes.iter_mut().zip(&unbalanced) {
        node.load -= s;
    }
    let fp = kappe_cem::fixed_geometry::force_pass(&topo, &positions)?;
    let mut summary = summarize(state, &fp, areas);
    summary.out_of_funicular = unbalanced.iter().fold(0.0, |m, s| m.max(s.norm()));
    Ok((topo, fp, summary, unbalanced))
}
