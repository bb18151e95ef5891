//! `network.json`: the final state in the `kappe cem solve` result shape, every node with its
//! `layer`. The one writer of the CEM result format for a cap.

use serde_json::{Value, json};

use crate::form::cap::Cap;
use crate::form::states::Role;
use crate::input::error::DesignError;

fn v3(v: &nalgebra::Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

/// The final state as a `kappe.cem.expected`-shaped document (nodes with `id`, `xyz`, `sequence`,
/// `origin`, `support`, `load`, `reaction`, `layer`, `role`, `residual`; trail and deviation edges
/// with `u`, `v`, signed `force` and `length`, `direct`).
pub fn network_json(cap: &Cap) -> Result<Value, DesignError> {
    let topo = &cap.final_topology;
    let fp = &cap.final_forces;
    let model = kappe_cem::Model::new(topo)?;
    let seq = model.sequences();
    let direct = model.direct_flags();
    let net = &cap.final_state.network;
    let origins: std::collections::HashSet<u64> = net
        .trails
        .iter()
        .filter_map(|t| t.first())
        .map(|&i| i as u64)
        .collect();
    let nodes: Vec<Value> = net
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let support = matches!(n.role, Role::Foot | Role::ColumnEnd);
            let mut m = json!({
                "id": i,
                "xyz": v3(&n.xyz),
                "sequence": seq.get(i).copied().unwrap_or(0),
                "origin": origins.contains(&(i as u64)),
                "support": support,
                "load": v3(&n.load),
                "layer": n.layer,
                "role": match n.role { Role::Column => "column", Role::Foot => "foot", Role::ColumnEnd => "column_end" },
                "residual": fp.node_residuals.get(i).copied().unwrap_or(0.0),
            });
            if let (true, Some(r), Some(obj)) = (support, fp.reactions.get(i), m.as_object_mut()) {
                obj.insert("reaction".into(), v3(r));
            }
            m
        })
        .collect();
    let length = |u: u64, v: u64, force: f64| -> f64 {
        let d = (net.nodes[v as usize].xyz - net.nodes[u as usize].xyz).norm();
        if force < 0.0 { -d } else { d }
    };
    let trail_edges: Vec<Value> = topo
        .trail_edges
        .iter()
        .zip(&fp.trail_forces)
        .map(|(e, &f)| json!({"u": e.u, "v": e.v, "force": f, "length": length(e.u, e.v, f)}))
        .collect();
    let deviation_edges: Vec<Value> = topo
        .deviation_edges
        .iter()
        .enumerate()
        .map(|(k, e)| {
            json!({"u": e.u, "v": e.v, "force": e.force, "length": length(e.u, e.v, e.force),
                   "direct": direct.get(k).copied().unwrap_or(true),
                   "layer": net.deviation_edges.get(k).map(|d| d.layer)})
        })
        .collect();
    Ok(json!({
        "format": "kappe.cem.expected",
        "version": 1,
        "name": format!("{} final state", cap.design.name),
        "description": "Final print state (100 %) of the cap: forces from the fixed-geometry force pass; \
                        node `layer` < 0 for start layers, 0..N-1 for the centre",
        "iterations": {"last_t": 0, "sweeps": 1, "residual_distance": 0.0},
        "trails": net.trails,
        "nodes": nodes,
        "trail_edges": trail_edges,
        "deviation_edges": deviation_edges,
        "checks": {"max_node_residual": fp.max_node_residual, "max_abs_force": fp.max_abs_force},
    }))
}
