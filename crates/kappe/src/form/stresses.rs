//! Element normal stresses of a print state (method.md §3): σ = N / A, compression negative,
//! with A = lw·lh for arch segments (along a layer) and A = lw·l_trib for the bed joints
//! between layers (the column edges), l_trib the tributary length of the column node along its
//! layer. The forces come from CEM's fixed-geometry force pass ([`crate::form::forces`]).

use std::borrow::Borrow;

use serde::Serialize;

use kappe_cem::fixed_geometry::ForcePass;

use crate::form::forces::{Sections2D, state_pass};
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
    let (fp, _) = state_pass(state, areas)?;
    Ok(element_stresses_of(state, &fp, areas).collect())
}

/// [`element_stresses`] of a state whose force pass `fp` is at hand, one by one: arch segments
/// (the network's deviation edges), then the column edges (its trails' edges top down, the
/// order of the force pass's trail forces, [`crate::form::states::Network::to_topology`]).
pub(crate) fn element_stresses_of<'a>(
    state: &'a State,
    fp: &'a ForcePass,
    areas: Sections2D,
) -> impl Iterator<Item = ElementStress> + 'a {
    let net = &state.network;
    // Segment index of a node within its layer: nodes of a layer are contiguous, foot first.
    let starts = net.layer_starts();
    let segments = net.deviation_edges.iter().map(move |e| {
        let first = starts.get(e.layer).unwrap_or(e.u);
        ElementStress {
            kind: ElementKind::ArchSegment {
                layer: e.layer,
                segment: e.u.min(e.v).saturating_sub(first),
            },
            nodes: [e.u, e.v],
            force: e.force,
            area: areas.along_layer,
            stress: e.force / areas.along_layer,
        }
    });
    let edges = net.trails.iter().flat_map(|t| t.windows(2));
    let columns = edges.zip(&fp.trail_forces).filter_map(move |(w, &f)| {
        let (u, v) = (w[0], w[1]);
        let (nu, nv) = (net.nodes.get(u)?, net.nodes.get(v)?);
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
        Some(ElementStress {
            kind,
            nodes: [u, v],
            force: f,
            area: areas.bed_joint,
            stress: f / areas.bed_joint,
        })
    });
    segments.chain(columns)
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
    pub fn of<S: Borrow<ElementStress>>(stresses: impl IntoIterator<Item = S>) -> Self {
        let mut e = StressExtremes::default();
        for s in stresses {
            let s = s.borrow();
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
