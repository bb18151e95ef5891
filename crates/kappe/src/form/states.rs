//! Print states (method.md §5–7): the network of every "layers printed so far" state, with its
//! geometry constructed from the sections and one layer factor d per start layer solved top-down.
//!
//! For a layer with incoming trail force `r` (per unit node weight, the force the trail edge from
//! the layer above exerts... carried down the column), the start-layer factor `d_m` solves
//!
//! ```text
//! (r + e_z + d_m (tan(am) e_y − e_z)) × ê_m = 0,   ê_m = −unit(T_{m+1} − T_m),
//! ```
//!
//! so the column force stays along the trail edge to the next layer; then
//! `r ← r + e_z + d_m (tan(am) e_y − e_z)`. Centre layers have d = 1 (r grows by tan(am) e_y), the
//! last start layer −K is free and takes d = φ; its column edges run along r to the base plane.
//! Against an end wall there are no start layers; every column ends with the horizontal bed joint
//! from layer 0 to the wall face ([`crate::form::ends`]).

use crate::form::ends::EndKind;
use crate::form::frame::{LayerFrame, V3};
use crate::form::section::{NodeKind, Sections};
use crate::input::error::DesignError;

/// The role of a node in a state network.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A layer node on a column (trail).
    Column,
    /// A layer foot on the base plane: a reaction node (support without trail edge).
    Foot,
    /// The end of a column: the support of that trail, on the base plane (start section) or on
    /// the end-wall face (end wall, `crate::form::ends`).
    ColumnEnd,
}

impl Role {
    /// Feet (reaction nodes) and column ends are the network's supports.
    pub fn is_support(self) -> bool {
        matches!(self, Role::Foot | Role::ColumnEnd)
    }
}

/// A node of a state network.
#[derive(Debug, Clone, PartialEq)]
pub struct NetNode {
    /// Position, m.
    pub xyz: V3,
    /// Gravity load, N.
    pub load: V3,
    /// Layer id (the column end takes the id of the layer above it).
    pub layer: i32,
    /// Column, foot or column end.
    pub role: Role,
}

/// An arch segment of a layer: a deviation edge with a prescribed force.
#[derive(Debug, Clone, PartialEq)]
pub struct DevEdge {
    /// End nodes (indices into `nodes`).
    pub u: usize,
    /// End nodes (indices into `nodes`).
    pub v: usize,
    /// Signed force, N (compression < 0).
    pub force: f64,
    /// Layer id.
    pub layer: i32,
}

/// [`Network::layer_starts`]: the first network index of every layer, by layer id.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerStarts {
    low: i32,
    first: Vec<usize>,
}

impl LayerStarts {
    fn slot(&self, layer: i32) -> Option<usize> {
        usize::try_from(i64::from(layer) - i64::from(self.low)).ok()
    }

    /// The network index of layer `layer`'s first node (`None`: no such layer).
    pub fn get(&self, layer: i32) -> Option<usize> {
        self.slot(layer)
            .and_then(|k| self.first.get(k))
            .copied()
            .filter(|&f| f != usize::MAX)
    }
}

/// The CEM network of one print state, with constructed geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct Network {
    /// All nodes.
    pub nodes: Vec<NetNode>,
    /// Columns as trails, origin (top layer) → support (column end on the base plane).
    pub trails: Vec<Vec<usize>>,
    /// Arch segments.
    pub deviation_edges: Vec<DevEdge>,
}

/// One print state: the first `layers_printed` layers in print order.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// 0-based state index (= print index of the top layer).
    pub index: usize,
    /// Number of layers printed.
    pub layers_printed: usize,
    /// Id of the top (last printed) layer.
    pub top_layer: i32,
    /// Print progress Pp in (0, 1].
    pub progress: f64,
    /// Layer factor d of every printed layer, in print order (1 for centre layers).
    pub factors: Vec<f64>,
    /// Column force per unit node weight below each printed layer, in print order.
    pub column_force_per_weight: Vec<V3>,
    /// The network.
    pub network: Network,
}

/// Build the state whose top layer has print index `top`.
pub fn build_state(
    sections: &Sections,
    frame: &LayerFrame,
    phi: f64,
    top: usize,
) -> Result<State, DesignError> {
    let total = sections.layers.len();
    let Some(top_layer) = sections.layers.get(top) else {
        return Err(DesignError::State {
            state: top,
            message: format!("no such state (there are {total})"),
        });
    };
    let k_start = sections.n_start;
    let ez = V3::z();
    let lean = frame.lean();
    let b = lean - ez;

    // Top-down: layer factors and column forces.
    let mut factors = vec![0.0; top + 1];
    let mut r_below = vec![V3::zeros(); top + 1];
    let mut r = V3::zeros();
    for q in (0..=top).rev() {
        let id = sections.layers[q].id;
        let a = r + ez;
        // Round-off in d (0 for the free last layer, whose d = φ is exact).
        let mut d_tol = 0.0;
        let d = if id >= 0 {
            1.0
        } else {
            let m = (-id) as usize;
            if m == k_start {
                phi
            } else {
                let step = sections.translations[m + 1] - sections.translations[m];
                let e = -step.normalize();
                // Planar problem in the y–z plane: the x-component of the cross product.
                let ax = a.y * e.z - a.z * e.y;
                let bx = b.y * e.z - b.z * e.y;
                if bx.abs() < 1e-300 {
                    return Err(DesignError::State {
                        state: top,
                        message: format!("layer {id}: the layer factor is undetermined"),
                    });
                }
                d_tol = factor_round_off(&a, bx, top - q + 1, &sections.translations[m + 1], &step);
                -ax / bx
            }
        };
        r = a + b * d;
        if id < 0 {
            let m = (-id) as usize;
            let e = if m == k_start {
                r.normalize()
            } else {
                -(sections.translations[m + 1] - sections.translations[m]).normalize()
            };
            if !(-d_tol..=1.0 + d_tol).contains(&d) || r.dot(&e) <= 0.0 {
                return Err(DesignError::State {
                    state: top,
                    message: format!(
                        "layer {id}: factor d = {d:.4} outside [0, 1] or column force not compressive; \
                         the start section cannot carry this state in compression"
                    ),
                });
            }
        }
        factors[q] = d;
        r_below[q] = r;
    }

    // Nodes, layer by layer, top-down (sized up front: this runs for every state on every
    // change of a design, and growing the vectors was a tenth of it).
    let printed = &sections.layers[..=top];
    let n_layer_nodes: usize = printed.iter().map(|l| l.nodes.len()).sum();
    let n_segments: usize = printed.iter().map(|l| l.segment_forces.len()).sum();
    // Column ids are the indices of layer 0's nodes; node indices of each column, top-down.
    let n_cols = sections
        .print_index(0)
        .and_then(|q| sections.layers.get(q))
        .map_or(0, |l| l.nodes.len());
    let mut nodes = Vec::with_capacity(n_layer_nodes + n_cols);
    let mut deviation_edges = Vec::with_capacity(n_segments);
    let mut columns: Vec<Vec<usize>> = (0..n_cols).map(|_| Vec::with_capacity(top + 2)).collect();
    let mut last_layer_of_col: Vec<Option<usize>> = vec![None; n_cols];
    for q in (0..=top).rev() {
        let layer = &sections.layers[q];
        let base = nodes.len();
        for node in &layer.nodes {
            let role = match node.kind {
                NodeKind::Column(i) => {
                    if let Some(col) = columns.get_mut(i) {
                        col.push(nodes.len());
                    }
                    if let Some(slot) = last_layer_of_col.get_mut(i) {
                        *slot = Some(q);
                    }
                    Role::Column
                }
                NodeKind::Foot => Role::Foot,
            };
            nodes.push(NetNode {
                xyz: node.xyz,
                load: -ez * node.weight,
                layer: layer.id,
                role,
            });
        }
        for (s, f) in layer.segment_forces.iter().enumerate() {
            deviation_edges.push(DevEdge {
                u: base + s,
                v: base + s + 1,
                force: f * factors[q],
                layer: layer.id,
            });
        }
    }

    // Column ends on the base plane.
    let mut trails = Vec::with_capacity(n_cols);
    for (i, col) in columns.iter_mut().enumerate() {
        let (Some(&last), Some(q)) = (col.last(), last_layer_of_col[i]) else {
            continue;
        };
        let x = nodes[last].xyz;
        let id = sections.layers[q].id;
        if sections.end == EndKind::EndWall {
            // The wall face is the plane of layer −1: the last bed joint is the horizontal step
            // back from layer 0 (see `crate::form::ends`).
            if id != 0 {
                return Err(DesignError::State {
                    state: top,
                    message: format!(
                        "column {i} ends in layer {id}, not on layer 0 at the end wall"
                    ),
                });
            }
            let end = x + sections
                .translations
                .get(1)
                .copied()
                .unwrap_or_else(V3::zeros);
            col.push(nodes.len());
            nodes.push(NetNode {
                xyz: end,
                load: V3::zeros(),
                layer: id,
                role: Role::ColumnEnd,
            });
            trails.push(std::mem::take(col));
            continue;
        }
        let dir = if id >= 0 {
            return Err(DesignError::State {
                state: top,
                message: format!("column {i} ends in centre layer {id}, not in the start section"),
            });
        } else {
            let m = (-id) as usize;
            if m == k_start {
                -r_below[q]
            } else {
                sections.translations[m + 1] - sections.translations[m]
            }
        };
        if dir.z >= 0.0 {
            return Err(DesignError::State {
                state: top,
                message: format!("column {i} below layer {id} does not descend to the base plane"),
            });
        }
        let mut end = x + dir * (x.z / -dir.z);
        end.z = 0.0;
        col.push(nodes.len());
        nodes.push(NetNode {
            xyz: end,
            load: V3::zeros(),
            layer: id,
            role: Role::ColumnEnd,
        });
        trails.push(std::mem::take(col));
    }

    Ok(State {
        index: top,
        layers_printed: top + 1,
        top_layer: top_layer.id,
        progress: (top + 1) as f64 / total as f64,
        factors,
        column_force_per_weight: r_below,
        network: Network {
            nodes,
            trails,
            deviation_edges,
        },
    })
}

/// The round-off bound of a start layer's factor `d = −(a × ê)_x / (b × ê)_x`.
///
/// The final state's start layers have `d = φ` exactly (the start section is shaped by that
/// state's thrust line), so at the default φ = 0 the check `d ≥ 0` sits on its bound and only
/// round-off decides it. Two inputs carry round-off: `a`, a sum of `layers` terms (relative error
/// ≤ layers·ε), and `ê`, the difference of two accumulated translations `T_{m+1} − T_m` (angle
/// error ≤ ε·|T_{m+1}|/|ΔT| per accumulation step, of which there are at most `layers`). Each
/// moves `d` by its relative error times `|a| / |(b × ê)_x|`. A 1.5 m × 4 m bay (453 centre
/// layers, 147 start layers) has `|a| ≈ 211` and meets `d ≈ −1e-11` in its final state, beyond
/// the fixed 1e-12 used before; the bound here is ≈ 4e-8 for it and ≈ 1e-10 at the defaults,
/// far below any factor that carries load (d multiplies arch forces of a few N).
fn factor_round_off(a: &V3, bx: f64, layers: usize, t_next: &V3, step: &V3) -> f64 {
    let layers = layers as f64;
    let cond = a.norm() / bx.abs();
    let steps = t_next.norm() / step.norm().max(f64::MIN_POSITIVE);
    // 4: a safety factor over the first-order bound (the products and the normalisation add a
    // few ε each); 1e-12 keeps the old floor for tiny caps.
    (4.0 * f64::EPSILON * cond * layers * (1.0 + steps)).max(1e-12)
}

impl Network {
    /// The CEM topology of this network: node ids are the node indices, columns are trails of
    /// compression edges (their lengths are the constructed ones), arch segments are deviation
    /// edges, feet are reaction nodes (supports without a trail edge) and column ends supports.
    pub fn to_topology(&self, name: &str) -> kappe_cem::Topology {
        use kappe_cem::topology::{DeviationEdge, Node, Topology, TrailEdge};
        let nodes = self
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| Node {
                id: i as u64,
                xyz: n.xyz,
                load: n.load,
                support: n.role.is_support(),
                origin: None,
            })
            .collect();
        let mut lengths = self.trail_lengths();
        let mut trail_edges = Vec::new();
        for t in &self.trails {
            for w in t.windows(2) {
                trail_edges.push(TrailEdge {
                    u: w[0] as u64,
                    v: w[1] as u64,
                    length: lengths.next().unwrap_or_default(),
                    plane: None,
                });
            }
        }
        let deviation_edges = self
            .deviation_edges
            .iter()
            .map(|e| DeviationEdge {
                u: e.u as u64,
                v: e.v as u64,
                force: e.force,
            })
            .collect();
        Topology {
            name: name.to_string(),
            nodes,
            trail_edges,
            deviation_edges,
            auxiliary_trails: None,
            trail_shifts: Vec::new(),
        }
    }

    /// The CEM model of this network, built from its trails by index
    /// ([`kappe_cem::Model::from_trails`]): the model [`kappe_cem::Model::new`] builds from
    /// [`Self::to_topology`], without validating and searching again what `build_state`
    /// constructed (node ids are the node indices here too). This runs for every print state on
    /// every change of a design.
    ///
    /// # Errors
    /// A network that breaks the construction's invariants (an internal error).
    pub fn to_model(&self, name: &str) -> Result<kappe_cem::Model, kappe_cem::CemError> {
        kappe_cem::Model::from_trails(kappe_cem::IndexedNetwork {
            name: name.to_string(),
            positions: self.positions(),
            loads: self.nodes.iter().map(|n| n.load).collect(),
            supports: self.nodes.iter().map(|n| n.role.is_support()).collect(),
            trails: self.trails.clone(),
            lengths: self.trail_lengths().collect(),
            deviation_edges: self
                .deviation_edges
                .iter()
                .map(|e| (e.u, e.v, e.force))
                .collect(),
        })
    }

    /// The signed length of every column edge (compression: minus the constructed length),
    /// trail by trail, top down.
    fn trail_lengths(&self) -> impl Iterator<Item = f64> + '_ {
        let at = |i: usize| self.nodes.get(i).map_or_else(V3::zeros, |n| n.xyz);
        self.trails
            .iter()
            .flat_map(|t| t.windows(2))
            .map(move |w| -(at(w[1]) - at(w[0])).norm())
    }

    /// The network index of every layer's first node (each layer is stored contiguously, foot
    /// first; column ends are not layer nodes), by layer id: so a node's index within its layer
    /// is its network index less its layer's start. A table over the short range of layer ids,
    /// no hashing: it is read for every print state on every change of a design.
    pub fn layer_starts(&self) -> LayerStarts {
        let (low, high) = self.nodes.iter().fold((i32::MAX, i32::MIN), |(lo, hi), n| {
            (lo.min(n.layer), hi.max(n.layer))
        });
        let span = usize::try_from(i64::from(high) - i64::from(low) + 1).unwrap_or(0);
        let mut starts = LayerStarts {
            low,
            first: vec![usize::MAX; span],
        };
        for (i, n) in self.nodes.iter().enumerate() {
            if n.role != Role::ColumnEnd
                && let Some(f) = starts.slot(n.layer).and_then(|k| starts.first.get_mut(k))
                && *f == usize::MAX
            {
                *f = i;
            }
        }
        starts
    }

    /// Positions of all nodes, in node order.
    pub fn positions(&self) -> Vec<V3> {
        self.nodes.iter().map(|n| n.xyz).collect()
    }
}
