//! Element normal stresses of a print state (method.md §3): σ = N / A, compression negative,
//! with A = lw·lh for arch segments (along a layer) and A = lw·l_trib for the bed joints
//! between layers (the column edges), l_trib the tributary length of the column node along its
//! layer. The forces come from CEM's fixed-geometry force pass ([`crate::form::forces`]).

use std::collections::HashMap;

use serde::Serialize;

use kappe_cem::fixed_geometry::ForcePass;
use kappe_cem::topology::Topology;

use crate::form::forces::{Sections2D, state_forces};
use crate::form::states::{Role, State};
use crate::input::error::DesignError;

/// Relative tolerance on stress limits: a stress passes if it is within `1e-9·max|σ|` of its
/// limit (the relative size of the force pass's residuals, method.md §9), so that σ_max = 0 is
/// not failed by round-off.
pub const STRESS_REL_TOL: f64 = 1e-9;

/// Kind and place of an element of a state network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ElementKind {
    /// Arch segment `segment` (0 = from the left foot) of layer `layer`: A = lw·lh.
    ArchSegment {
        /// Layer id.
        layer: i32,
        /// Segment index along the layer.
        segment: usize,
    },
    /// Column edge from layer `upper` to layer `lower` (a bed joint): A = lw·l_trib.
    BedJoint {
        /// Layer id of the upper node.
        upper: i32,
        /// Layer id of the lower node.
        lower: i32,
    },
    /// The last column edge below layer `layer`, to the base plane: A = lw·l_trib.
    ColumnFoot {
        /// Layer id.
        layer: i32,
    },
    /// The bed joint of layer `layer` (0) on the end wall (`crate::form::ends`): A = lw·l_trib.
    WallJoint {
        /// Layer id.
        layer: i32,
    },
}

impl std::fmt::Display for ElementKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ElementKind::ArchSegment { layer, segment } => {
                write!(f, "arch segment {segment} of layer {layer}")
            }
            ElementKind::BedJoint { upper, lower } => {
                write!(f, "bed joint between layers {lower} and {upper}")
            }
            ElementKind::ColumnFoot { layer } => {
                write!(f, "column foot below layer {layer} (on the base plane)")
            }
            ElementKind::WallJoint { layer } => {
                write!(f, "bed joint of layer {layer} on the end wall")
            }
        }
    }
}

/// Normal stress of one element of a state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ElementStress {
    /// What and where.
    pub kind: ElementKind,
    /// Network node indices.
    pub nodes: [usize; 2],
    /// Signed force, N.
    pub force: f64,
    /// Area, m².
    pub area: f64,
    /// σ = N / A, Pa.
    pub stress: f64,
}

/// The normal stress of every element of `state` (method.md §3): arch segments with
/// A = lw·lh, column edges with A = lw·l_trib.
pub fn element_stresses(
    state: &State,
    areas: Sections2D,
) -> Result<Vec<ElementStress>, DesignError> {
    let (topo, fp, _) = state_forces(state, areas)?;
    Ok(element_stresses_of(state, &topo, &fp, areas))
}

/// [`element_stresses`] of a state whose force pass (`topo`, `fp`) is at hand.
pub(crate) fn element_stresses_of(
    state: &State,
    topo: &Topology,
    fp: &ForcePass,
    areas: Sections2D,
) -> Vec<ElementStress> {
    let net = &state.network;
    let mut out = Vec::with_capacity(topo.trail_edges.len() + topo.deviation_edges.len());
    // Segment index of a node within its layer: nodes of a layer are contiguous, foot first.
    let mut first_of_layer: HashMap<i32, usize> = HashMap::new();
    let mut last = None;
    for (i, n) in net.nodes.iter().enumerate() {
        // One map entry per layer, not per node (this runs for every state of a design).
        if n.role != Role::ColumnEnd && last != Some(n.layer) {
            first_of_layer.entry(n.layer).or_insert(i);
            last = Some(n.layer);
        }
    }
    for e in &net.deviation_edges {
        let first = first_of_layer.get(&e.layer).copied().unwrap_or(e.u);
        out.push(ElementStress {
            kind: ElementKind::ArchSegment {
                layer: e.layer,
                segment: e.u.min(e.v).saturating_sub(first),
            },
            nodes: [e.u, e.v],
            force: e.force,
            area: areas.along_layer,
            stress: e.force / areas.along_layer,
        });
    }
    for (edge, &f) in topo.trail_edges.iter().zip(&fp.trail_forces) {
        let (u, v) = (edge.u as usize, edge.v as usize);
        let (Some(nu), Some(nv)) = (net.nodes.get(u), net.nodes.get(v)) else {
            continue;
        };
        // A column end above the base plane lies on an end-wall face (`crate::form::ends`).
        let kind = if nv.role == Role::ColumnEnd && nv.xyz.z > 0.0 {
            ElementKind::WallJoint { layer: nu.layer }
        } else if nv.role == Role::ColumnEnd {
            ElementKind::ColumnFoot { layer: nu.layer }
        } else {
            ElementKind::BedJoint {
                upper: nu.layer.max(nv.layer),
                lower: nu.layer.min(nv.layer),
            }
        };
        out.push(ElementStress {
            kind,
            nodes: [u, v],
            force: f,
            area: areas.bed_joint,
            stress: f / areas.bed_joint,
        });
    }
    out
}

/// The extremes of one state's element stresses: the first element with the lowest and with the
/// highest stress (the order [`element_stresses`] gives), and the largest |σ|.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StressExtremes {
    /// The lowest σ (Pa) and its element.
    pub min: Option<(f64, ElementKind)>,
    /// The highest σ (Pa) and its element.
    pub max: Option<(f64, ElementKind)>,
    /// The largest |σ|, Pa.
    pub abs_max: f64,
}

impl StressExtremes {
    /// The extremes of `stresses`, in their order.
    pub fn of(stresses: &[ElementStress]) -> Self {
        let mut e = StressExtremes::default();
        for s in stresses {
            e.add(s.stress, s.kind);
        }
        e
    }

    /// Take `stress` of `kind` as the next element in order (the first of equal values stays).
    fn add(&mut self, stress: f64, kind: ElementKind) {
        if self.min.is_none_or(|m| stress < m.0) {
            self.min = Some((stress, kind));
        }
        if self.max.is_none_or(|m| stress > m.0) {
            self.max = Some((stress, kind));
        }
        self.abs_max = self.abs_max.max(stress.abs());
    }
}
