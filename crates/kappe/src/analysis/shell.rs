//! The shell model of a print state (paper §3.2, buckling.md §1): the printed layers as rows of
//! a facet-shell mesh for `kappe_fe`, so that the linear buckling factor (BLF) of every state can
//! be checked against BLF_min.
//!
//! Built from the state's form diagram ([`Network`]):
//! - **Rows.** Every printed layer is one mesh row: its polyline foot → crown → foot (the arch
//!   segments, i.e. the deviation edges of the layer). The column ends of the network (where the
//!   columns are grounded below the start section) are not shell nodes: in the shell the start
//!   layers' feet carry the surface down to the base plane.
//! - **Strips.** Consecutive rows are joined by a triangle strip. Rows of the start section have
//!   different node counts (they are trimmed by z = 0), so the strip is a *zipper* over the
//!   x coordinate: layers are translates of layer 0 in the y–z plane (method.md §5–6), so a column
//!   keeps its x in every layer and merging by x joins node i of one layer to node i of the next.
//!   Triangles are wound the same way in every strip (earlier row, then later row, x increasing),
//!   so the mesh is consistently oriented as `kappe_fe` requires.
//! - **Thickness** lw (method.md §2: bead width = shell thickness), self-weight γ·lw per unit
//!   area along −z, E and ν from the design — or E per layer from its age (buckling.md §6).
//! - **Element** from the analysis options: by default the shear-deformable ANDES+DKMT
//!   (`kappe_fe::element::dkmt`, issue 17), since span/t ≈ 40 makes transverse shear lower the
//!   BLF by ≈ 2 % on the final state (more on the narrow early strips, whose width is only a
//!   few bead heights); `cst_dkt` (Kirchhoff) stays selectable.
//! - **Supports.** Pinned (translations fixed, rotations free) where the structure meets the
//!   base plane: every foot (the feet of centre layers lie on the beams, the springing lines
//!   x = ±Cs/2, z = 0; the feet of start layers on the base plane) and every node of the first
//!   start layer −K, which is printed on the bed.
//!
//! A start-layer foot is where a chord of the translated arch crosses the base plane; it can fall
//! arbitrarily close to the next node above the base. Such a sliver would be a degenerate facet,
//! so a foot closer than [`FOOT_MERGE_FRACTION`] of the layer's segment length to its neighbour is
//! dropped and the neighbour (then at most that fraction of a segment above the base) is pinned
//! in its place.
//!
//! Hand-written because it is Kappe's own meshing rule (no meshing crate knows print layers).

use std::collections::HashMap;

use kappe_fe::{ElementKind, Material, ShellModel, Support};

use crate::form::states::{Network, Role, State};

/// A start-layer foot closer than this fraction of the segment length to its neighbour is merged
/// into the neighbour (see the module docs). 0.25 keeps every facet's smallest height above
/// ~0.2 of its longest edge at the feet while moving a support by at most a quarter segment.
pub const FOOT_MERGE_FRACTION: f64 = 0.25;

/// Material of the shell: thickness, Poisson's ratio, unit weight, and E per layer.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellMaterial {
    /// Shell thickness = bead width lw, m.
    pub thickness: f64,
    /// ν.
    pub poisson_ratio: f64,
    /// γ, N/m³.
    pub unit_weight: f64,
    /// E of every layer, Pa, keyed by layer id (a layer missing here takes `youngs_modulus`).
    pub layer_modulus: HashMap<i32, f64>,
    /// E, Pa, of layers not in `layer_modulus`.
    pub youngs_modulus: f64,
    /// The facet shell element of the model (`AnalysisOptions::element`).
    pub element: ElementKind,
}

impl ShellMaterial {
    /// E of layer `id`.
    pub fn modulus_of(&self, id: i32) -> f64 {
        self.layer_modulus
            .get(&id)
            .copied()
            .unwrap_or(self.youngs_modulus)
    }
}

/// The shell model of one state and the bookkeeping that maps it back to the network.
#[derive(Debug, Clone)]
pub struct StateShell {
    /// The `kappe_fe` model.
    pub model: ShellModel,
    /// Layer id of every shell node.
    pub node_layer: Vec<i32>,
    /// Network node index of every shell node.
    pub network_node: Vec<usize>,
    /// Layer ids of the two rows every triangle joins (earlier, later).
    pub element_layers: Vec<(i32, i32)>,
    /// Rows (layers) in print order: layer id and shell node indices, foot → foot.
    pub rows: Vec<(i32, Vec<usize>)>,
    /// Feet merged into their neighbour (see [`FOOT_MERGE_FRACTION`]).
    pub merged_feet: usize,
}

/// Why a state has no shell model.
#[derive(Debug, Clone, PartialEq)]
pub enum NoShell {
    /// Only one layer is printed: it rests on the bed, there is no surface to buckle.
    SingleLayer,
}

/// The layer rows of a network in print order (earliest first): layer id and network node
/// indices foot → foot. Column ends are left out.
pub fn layer_rows(net: &Network) -> Vec<(i32, Vec<usize>)> {
    // The network stores the layers top-down, each contiguous and foot → foot.
    let mut rows: Vec<(i32, Vec<usize>)> = Vec::new();
    for (i, n) in net.nodes.iter().enumerate() {
        if n.role == Role::ColumnEnd {
            continue;
        }
        match rows.last_mut() {
            Some((id, nodes)) if *id == n.layer => nodes.push(i),
            _ => rows.push((n.layer, vec![i])),
        }
    }
    rows.reverse();
    rows
}

/// Build the shell model of `state` (see the module docs). `Ok(Err(NoShell))` when the state
/// has no surface (a single layer on the bed).
pub fn state_shell(
    state: &State,
    material: &ShellMaterial,
    row_stride: usize,
) -> Result<StateShell, NoShell> {
    let net = &state.network;
    let all_rows = layer_rows(net);
    if all_rows.len() < 2 {
        return Err(NoShell::SingleLayer);
    }
    // Rows at print indices 0, stride, 2·stride, … and always the top layer, so the mesh of a
    // state is the mesh of the previous one plus (at most) one strip.
    let stride = row_stride.max(1);
    let top = all_rows.len() - 1;
    let rows: Vec<(i32, Vec<usize>)> = all_rows
        .into_iter()
        .enumerate()
        .filter(|(q, _)| q % stride == 0 || *q == top)
        .map(|(_, r)| r)
        .collect();
    let first_layer = rows.first().map(|r| r.0);
    let mut nodes: Vec<[f64; 3]> = Vec::new();
    let mut node_layer = Vec::new();
    let mut network_node = Vec::new();
    let mut pinned: Vec<bool> = Vec::new();
    let mut shell_rows: Vec<(i32, Vec<usize>)> = Vec::with_capacity(rows.len());
    let mut merged_feet = 0;
    for (id, row) in &rows {
        let mut keep: Vec<usize> = row.clone();
        let mut pin_first = false;
        let mut pin_last = false;
        // Merge feet that sit (almost) on their neighbour; keep at least two nodes per row.
        let seg = mean_segment(net, row);
        if keep.len() > 3 {
            let d0 = dist(net, keep[0], keep[1]);
            if net.nodes[keep[0]].role == Role::Foot && d0 < FOOT_MERGE_FRACTION * seg {
                keep.remove(0);
                pin_first = true;
                merged_feet += 1;
            }
        }
        if keep.len() > 3 {
            let n = keep.len();
            let d1 = dist(net, keep[n - 2], keep[n - 1]);
            if net.nodes[keep[n - 1]].role == Role::Foot && d1 < FOOT_MERGE_FRACTION * seg {
                keep.pop();
                pin_last = true;
                merged_feet += 1;
            }
        }
        let on_bed = Some(*id) == first_layer;
        let mut shell_row = Vec::with_capacity(keep.len());
        let last = keep.len().saturating_sub(1);
        for (k, &ni) in keep.iter().enumerate() {
            let n = &net.nodes[ni];
            shell_row.push(nodes.len());
            nodes.push([n.xyz.x, n.xyz.y, n.xyz.z]);
            node_layer.push(*id);
            network_node.push(ni);
            pinned.push(
                on_bed || n.role == Role::Foot || (k == 0 && pin_first) || (k == last && pin_last),
            );
        }
        shell_rows.push((*id, shell_row));
    }

    let mut triangles = Vec::new();
    let mut element_layers = Vec::new();
    for w in shell_rows.windows(2) {
        let (lo_id, lo) = (&w[0].0, &w[0].1);
        let (hi_id, hi) = (&w[1].0, &w[1].1);
        let before = triangles.len();
        zipper(&nodes, lo, hi, &mut triangles);
        element_layers.extend(std::iter::repeat_n(
            (*lo_id, *hi_id),
            triangles.len() - before,
        ));
    }

    let materials: Vec<Material> = element_layers
        .iter()
        .map(|&(a, b)| Material {
            // The facet joins two beads: their mean stiffness.
            youngs_modulus: 0.5 * (material.modulus_of(a) + material.modulus_of(b)),
            poisson_ratio: material.poisson_ratio,
            unit_weight: material.unit_weight,
        })
        .collect();
    let uniform = materials.windows(2).all(|w| w[0] == w[1]);
    let mut model = ShellModel::new(
        nodes,
        triangles,
        material.thickness,
        materials.first().copied().unwrap_or(Material {
            youngs_modulus: material.youngs_modulus,
            poisson_ratio: material.poisson_ratio,
            unit_weight: material.unit_weight,
        }),
    );
    if !uniform {
        model.materials = materials;
    }
    model.element = material.element;
    model.supports = pinned
        .iter()
        .enumerate()
        .filter(|(_, p)| **p)
        .map(|(i, _)| Support::pinned(i))
        .collect();
    Ok(StateShell {
        model,
        node_layer,
        network_node,
        element_layers,
        rows: shell_rows,
        merged_feet,
    })
}

fn dist(net: &Network, a: usize, b: usize) -> f64 {
    (net.nodes[a].xyz - net.nodes[b].xyz).norm()
}

fn mean_segment(net: &Network, row: &[usize]) -> f64 {
    if row.len() < 2 {
        return 0.0;
    }
    let total: f64 = row.windows(2).map(|w| dist(net, w[0], w[1])).sum();
    // Interior segments are the arch's common length s; the cut end chords are shorter, so the
    // median would be better, but the mean over ≥ 3 segments is within a factor 2 of s.
    total / (row.len() - 1) as f64
}

/// Triangulate the strip between row `lo` (printed earlier) and row `hi` (printed later), both
/// ordered by increasing x. The next triangle advances the row whose next node has the smaller
/// x (ties: the shorter new diagonal), so node i of one layer meets node i of the next.
/// Winding: `[lo_j, lo_j+1, hi_i]` and `[lo_j, hi_i+1, hi_i]`, the same in every strip.
fn zipper(nodes: &[[f64; 3]], lo: &[usize], hi: &[usize], out: &mut Vec<[usize; 3]>) {
    let (mut i, mut j) = (0usize, 0usize);
    let x = |n: usize| nodes[n][0];
    let d2 = |a: usize, b: usize| {
        let (p, q) = (nodes[a], nodes[b]);
        (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)
    };
    while i + 1 < hi.len() || j + 1 < lo.len() {
        let advance_lo = if i + 1 >= hi.len() {
            true
        } else if j + 1 >= lo.len() {
            false
        } else {
            let (xl, xh) = (x(lo[j + 1]), x(hi[i + 1]));
            let tol = 1e-9 * (xl.abs() + xh.abs() + 1.0);
            if (xl - xh).abs() <= tol {
                d2(lo[j + 1], hi[i]) <= d2(hi[i + 1], lo[j])
            } else {
                xl < xh
            }
        };
        if advance_lo {
            out.push([lo[j], lo[j + 1], hi[i]]);
            j += 1;
        } else {
            out.push([lo[j], hi[i + 1], hi[i]]);
            i += 1;
        }
    }
}
