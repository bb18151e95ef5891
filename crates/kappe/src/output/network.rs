//! Machine-readable outputs of a designed cap: `summary.json` and `network.json` (the final state
//! in the `kappe cem solve` result shape, every node with its `layer`).

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

/// `summary.json`: the resolved design, counts, fabrication figures, the layer arch against its
/// closed form, and one entry per state.
pub fn summary_json(cap: &Cap) -> Value {
    let d = &cap.design;
    let area = d.print.layer_width * d.print.layer_height;
    let nc = cap.arch.segments() / 2;
    let crown = cap.arch.segment_forces.get(nc).copied().unwrap_or(0.0);
    let final_state = cap.states.last();
    let mut out = json!({
        "format": "kappe.design.summary",
        "version": 1,
        "design": d,
        "counts": {
            "start_layers": cap.sections.n_start,
            "centre_layers": cap.sections.n_centre,
            "layers": cap.sections.layers.len(),
            "states": cap.states.len(),
            "nodes": cap.final_state.network.nodes.len(),
            "trail_edges": cap.final_topology.trail_edges.len(),
            "deviation_edges": cap.final_topology.deviation_edges.len(),
            "edges": cap.final_topology.trail_edges.len() + cap.final_topology.deviation_edges.len(),
            "path_points": cap.path.points.len(),
        },
        "layer": {
            "segments": cap.arch.segments(),
            "segment_length_m": cap.arch.segment_length,
            "crown_force_n": cap.arch.crown_force,
            "weight_iterations": cap.arch.weight_iterations,
            "crown_stress_pa": crown / area,
            "springing_stress_pa": cap.arch.segment_forces.first().copied().unwrap_or(0.0) / area,
            "catenary_a_m": cap.catenary.a,
            "catenary_crown_stress_pa": -cap.catenary.crown_stress,
            "catenary_springing_stress_pa": -cap.catenary.springing_stress,
        },
        "path_length_m": cap.path.print_length,
        "travel_length_m": cap.path.travel_length,
        "volume_m3": cap.path.volume,
        "mass_kg": cap.path.mass,
        "print_time_s": cap.path.time,
        "max_overhang_m": cap.overhangs.iter().fold(0.0_f64, |m, o| m.max(o.abs())),
        "base": final_state.map(|s| json!({
            "column_end_reaction_n": s.forces.column_end_reaction,
            "column_end_hv_ratio": s.forces.column_end_hv_ratio,
            "column_hv_ratio_range": [s.forces.min_column_hv_ratio, s.forces.max_column_hv_ratio],
            "feet_longitudinal_reaction_n": s.forces.feet_longitudinal_reaction,
        })),
        "states": cap.states.iter().map(|s| json!({
            "index": s.index,
            "progress": s.progress,
            "layers_printed": s.layers_printed,
            "top_layer": s.top_layer,
            "nodes": s.nodes,
            "max_compression_force_n": s.forces.max_compression_force,
            "max_tension_force_n": s.forces.max_tension_force,
            "max_node_residual_n": s.forces.max_residual,
            "max_compression_stress_pa": s.forces.max_compression_stress,
            "max_tension_stress_pa": s.forces.max_tension_stress,
            "start_factor_range": s.forces.factor_range,
            "base_reaction_n": s.forces.base_reaction,
            "column_end_hv_ratio": s.forces.column_end_hv_ratio,
        })).collect::<Vec<_>>(),
    });
    // Only end-wall caps get the block, so the default summary stays byte-identical.
    if let (Some(w), Some(obj)) = (crate::form::ends::cap_wall_load(cap), out.as_object_mut()) {
        obj.insert("end_wall".into(), json!(w));
    }
    out
}

/// Merge an analysis into `summary.json`: per state `blf`, `max_compression_stress_pa`,
/// `max_tension_stress_pa` (element stresses of the analysis), `max_overhang_m`, `ok`, and the
/// top-level `constraints` report and `analysis_ok` verdict.
pub fn add_analysis(summary: &mut Value, analysis: &crate::analysis::Analysis) {
    if let Some(states) = summary.get_mut("states").and_then(Value::as_array_mut) {
        for (s, a) in states.iter_mut().zip(&analysis.states) {
            if let Some(obj) = s.as_object_mut() {
                obj.insert("blf".into(), json!(a.blf));
                obj.insert("buckling".into(), json!(a.buckling));
                obj.insert(
                    "max_compression_stress_pa".into(),
                    json!(a.max_compression_stress_pa),
                );
                obj.insert(
                    "max_tension_stress_pa".into(),
                    json!(a.max_tension_stress_pa),
                );
                obj.insert("max_overhang_m".into(), json!(a.max_overhang_m));
                obj.insert("ok".into(), json!(a.ok));
                if let Some(m) = &a.mechanism {
                    obj.insert("mechanism".into(), json!(m));
                }
            }
        }
    }
    if let Some(obj) = summary.as_object_mut() {
        obj.insert("constraints".into(), json!(analysis.constraints));
        obj.insert("analysis_ok".into(), json!(analysis.ok));
        obj.insert(
            "analysis_options".into(),
            json!(analysis.options.states.to_string()),
        );
        obj.insert("analysis_timings_s".into(), json!(analysis.timings));
    }
}
