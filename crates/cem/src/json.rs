//! The interchange formats of `shared/fixtures/cem/README.md`:
//! `kappe.cem.topology` v1 (input, read and written) and `kappe.cem.expected` v1 (the shape
//! of a solve result, written).
//!
//! Node objects, edges, planes, shifts and solver options reject unknown fields (typos);
//! unknown top-level keys are ignored so that metadata such as `generator` may be added.
//! JSON cannot encode NaN; numbers out of the f64 range are rejected by the parser.

use nalgebra::Vector3;
use serde::Deserialize;
use serde_json::{Map, Value, json};

use crate::equilibrium::{Equilibrium, PolygonSide, SolverOptions};
use crate::error::CemError;
use crate::topology::{
    AuxiliaryTrails, DeviationEdge, Node, NodeId, Plane, Topology, TrailEdge, TrailShift,
};

/// Format name of topology inputs.
pub const TOPOLOGY_FORMAT: &str = "kappe.cem.topology";
/// Format name of solve results.
pub const RESULT_FORMAT: &str = "kappe.cem.expected";

#[derive(Deserialize)]
struct TopologyJson {
    format: String,
    version: u64,
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    description: Option<String>,
    nodes: Vec<NodeJson>,
    #[serde(default)]
    trail_edges: Vec<TrailEdgeJson>,
    #[serde(default)]
    deviation_edges: Vec<DeviationEdgeJson>,
    #[serde(default)]
    auxiliary_trails: Option<AuxJson>,
    #[serde(default)]
    trail_shifts: Option<Vec<ShiftJson>>,
    #[serde(default)]
    solver: Option<SolverJson>,
    #[serde(default)]
    optimization: Option<Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NodeJson {
    id: NodeId,
    xyz: [f64; 3],
    #[serde(default)]
    load: Option<[f64; 3]>,
    #[serde(default)]
    support: Option<bool>,
    #[serde(default)]
    origin: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneJson {
    origin: [f64; 3],
    normal: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrailEdgeJson {
    u: NodeId,
    v: NodeId,
    length: f64,
    #[serde(default)]
    plane: Option<PlaneJson>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DeviationEdgeJson {
    u: NodeId,
    v: NodeId,
    force: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AuxJson {
    #[serde(default)]
    length: Option<f64>,
    #[serde(default)]
    vector: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShiftJson {
    origin: NodeId,
    start: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SolverJson {
    #[serde(default)]
    tmax: Option<usize>,
    #[serde(default)]
    eta: Option<f64>,
}

/// A parsed `kappe.cem.topology` document.
#[derive(Debug, Clone)]
pub struct TopologyFile {
    /// The topology.
    pub topology: Topology,
    /// Free-text description.
    pub description: Option<String>,
    /// Solver options (`solver` block, compas defaults when absent).
    pub solver: SolverOptions,
    /// The raw `optimization` block, if any (parsed by [`crate::optimize::Problem::from_json`]).
    pub optimization: Option<Value>,
}

/// Parse a `kappe.cem.topology` v1 document and check its elements (ids, finiteness, edge
/// ends). Trail building is checked when the topology is solved.
pub fn read_topology(text: &str) -> Result<TopologyFile, CemError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let raw: TopologyJson =
        serde_path_to_error::deserialize(de).map_err(|e| CemError::MalformedJson {
            path: e.path().to_string(),
            message: e.inner().to_string(),
        })?;
    if raw.format != TOPOLOGY_FORMAT || raw.version != 1 {
        return Err(CemError::UnsupportedFormat {
            format: raw.format,
            version: raw.version,
            expected: TOPOLOGY_FORMAT,
        });
    }
    let defaults = SolverOptions::default();
    let solver = SolverOptions {
        tmax: raw
            .solver
            .as_ref()
            .and_then(|s| s.tmax)
            .unwrap_or(defaults.tmax),
        eta: raw
            .solver
            .as_ref()
            .and_then(|s| s.eta)
            .unwrap_or(defaults.eta),
    };
    solver.validate()?;
    let aux_default = AuxiliaryTrails::default();
    let topology = Topology {
        name: raw.name.unwrap_or_default(),
        nodes: raw
            .nodes
            .into_iter()
            .map(|n| Node {
                id: n.id,
                xyz: Vector3::from(n.xyz),
                load: n.load.map_or_else(Vector3::zeros, Vector3::from),
                support: n.support.unwrap_or(false),
                origin: n.origin,
            })
            .collect(),
        trail_edges: raw
            .trail_edges
            .into_iter()
            .map(|e| TrailEdge {
                u: e.u,
                v: e.v,
                length: e.length,
                plane: e.plane.map(|p| Plane {
                    origin: Vector3::from(p.origin),
                    normal: Vector3::from(p.normal),
                }),
            })
            .collect(),
        deviation_edges: raw
            .deviation_edges
            .into_iter()
            .map(|e| DeviationEdge {
                u: e.u,
                v: e.v,
                force: e.force,
            })
            .collect(),
        auxiliary_trails: raw.auxiliary_trails.map(|a| AuxiliaryTrails {
            length: a.length.unwrap_or(aux_default.length),
            vector: a.vector.map_or(aux_default.vector, Vector3::from),
        }),
        trail_shifts: raw
            .trail_shifts
            .unwrap_or_default()
            .into_iter()
            .map(|s| TrailShift {
                origin: s.origin,
                start: s.start,
            })
            .collect(),
    };
    crate::topology::check_elements(&topology)?;
    Ok(TopologyFile {
        topology,
        description: raw.description,
        solver,
        optimization: raw.optimization,
    })
}

fn v3(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

/// Write a topology as a `kappe.cem.topology` v1 document.
pub fn topology_to_json(topology: &Topology, solver: &SolverOptions) -> Value {
    let nodes: Vec<Value> = topology
        .nodes
        .iter()
        .map(|n| {
            let mut m = Map::new();
            m.insert("id".into(), json!(n.id));
            m.insert("xyz".into(), v3(&n.xyz));
            if n.load != Vector3::zeros() {
                m.insert("load".into(), v3(&n.load));
            }
            if n.support {
                m.insert("support".into(), json!(true));
            }
            if let Some(o) = n.origin {
                m.insert("origin".into(), json!(o));
            }
            Value::Object(m)
        })
        .collect();
    let trail: Vec<Value> = topology
        .trail_edges
        .iter()
        .map(|e| {
            let mut m = Map::new();
            m.insert("u".into(), json!(e.u));
            m.insert("v".into(), json!(e.v));
            m.insert("length".into(), json!(e.length));
            if let Some(p) = &e.plane {
                m.insert(
                    "plane".into(),
                    json!({"origin": v3(&p.origin), "normal": v3(&p.normal)}),
                );
            }
            Value::Object(m)
        })
        .collect();
    let dev: Vec<Value> = topology
        .deviation_edges
        .iter()
        .map(|e| json!({"u": e.u, "v": e.v, "force": e.force}))
        .collect();
    json!({
        "format": TOPOLOGY_FORMAT,
        "version": 1,
        "name": topology.name,
        "nodes": nodes,
        "trail_edges": trail,
        "deviation_edges": dev,
        "auxiliary_trails": topology.auxiliary_trails.map(|a| json!({"length": a.length, "vector": v3(&a.vector)})),
        "trail_shifts": topology.trail_shifts.iter().map(|s| json!({"origin": s.origin, "start": s.start})).collect::<Vec<_>>(),
        "solver": {"tmax": solver.tmax, "eta": solver.eta},
    })
}

/// Write a solve result in the shape of `kappe.cem.expected` v1 (nodes with `id`, `xyz`,
/// `sequence`, `origin`, `support`, `load`, `reaction` on supports; edges with signed `force`
/// and `length`; `direct` on deviation edges; `iterations`; `trails`; `checks`). With
/// `force_polygons`, every node's force polygon is added.
pub fn equilibrium_to_json(
    eq: &Equilibrium,
    solver: &SolverOptions,
    force_polygons: bool,
) -> Value {
    let nodes: Vec<Value> = eq
        .nodes
        .iter()
        .map(|n| {
            let mut m = Map::new();
            m.insert("id".into(), json!(n.id));
            m.insert("xyz".into(), v3(&n.xyz));
            m.insert("sequence".into(), json!(n.sequence));
            m.insert("origin".into(), json!(n.origin));
            m.insert("support".into(), json!(n.support));
            m.insert("load".into(), v3(&n.load));
            if n.support {
                m.insert("reaction".into(), v3(&n.reaction));
            }
            m.insert("residual".into(), json!(n.residual));
            Value::Object(m)
        })
        .collect();
    let trail: Vec<Value> = eq
        .trail_edges
        .iter()
        .map(|e| {
            let mut m = Map::new();
            m.insert("u".into(), json!(e.u));
            m.insert("v".into(), json!(e.v));
            m.insert("force".into(), json!(e.force));
            m.insert("length".into(), json!(e.length));
            if e.auxiliary {
                m.insert("auxiliary".into(), json!(true));
            }
            Value::Object(m)
        })
        .collect();
    let dev: Vec<Value> = eq
        .deviation_edges
        .iter()
        .map(|e| json!({"u": e.u, "v": e.v, "force": e.force, "length": e.length, "direct": e.direct}))
        .collect();
    let aux: Vec<Value> = eq
        .auxiliary_trails
        .iter()
        .map(|(n, a)| json!({"node": n, "aux_node": a, "edge": [n, a]}))
        .collect();
    let mut doc = json!({
        "format": RESULT_FORMAT,
        "version": 1,
        "name": eq.name,
        "solver": {"tmax": solver.tmax, "eta": solver.eta},
        "iterations": {
            "last_t": eq.iterations.last_t,
            "sweeps": eq.iterations.sweeps,
            "residual_distance": eq.iterations.residual_distance,
        },
        "trails": eq.trails,
        "nodes": nodes,
        "trail_edges": trail,
        "deviation_edges": dev,
        "auxiliary_trails": aux,
        "checks": {
            "max_node_residual": eq.checks.max_node_residual,
            "zero_length_edges": eq.checks.zero_length_edges.iter().map(|(u, v)| json!([u, v])).collect::<Vec<_>>(),
            "sum_loads": v3(&eq.checks.sum_loads),
            "sum_reactions": v3(&eq.checks.sum_reactions),
        },
    });
    if force_polygons && let Value::Object(m) = &mut doc {
        let polys: Vec<Value> = eq
            .force_polygons()
            .iter()
            .map(|p| {
                let sides: Vec<Value> = p
                    .sides
                    .iter()
                    .map(|s| {
                        let (kind, edge) = match s {
                            PolygonSide::Load(_) => ("load", Value::Null),
                            PolygonSide::Deviation(e, _) => (
                                "deviation",
                                eq.deviation_edges
                                    .get(*e)
                                    .map_or(Value::Null, |d| json!([d.u, d.v])),
                            ),
                            PolygonSide::TrailIn(e, _) => (
                                "trail_in",
                                eq.trail_edges
                                    .get(*e)
                                    .map_or(Value::Null, |d| json!([d.u, d.v])),
                            ),
                            PolygonSide::TrailOut(e, _) => (
                                "trail_out",
                                eq.trail_edges
                                    .get(*e)
                                    .map_or(Value::Null, |d| json!([d.u, d.v])),
                            ),
                            PolygonSide::Reaction(_) => ("reaction", Value::Null),
                        };
                        json!({"kind": kind, "edge": edge, "vector": v3(&s.vector())})
                    })
                    .collect();
                json!({"node": p.node, "sides": sides})
            })
            .collect();
        m.insert("force_polygons".into(), Value::Array(polys));
    }
    doc
}
