//! Element normal stresses of a print state (method.md §3): σ = N / A, compression negative,
//! with A = lw·lh for arch segments (along a layer) and A = lw·l_trib for the bed joints
//! between layers (the column edges), l_trib the tributary length of the column node along its
//! layer. The forces come from CEM's fixed-geometry force pass ([`crate::form::forces`]).

use std::collections::HashMap;

use serde::Serialize;

use crate::form::ends::EndKind;
use crate::form::forces::{Sections2D, state_forces};
use crate::form::section::Sections;
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
    let net = &state.network;
    let (topo, fp, _) = state_forces(state, areas)?;
    let mut out = Vec::with_capacity(topo.trail_edges.len() + topo.deviation_edges.len());
    // Segment index of a node within its layer: nodes of a layer are contiguous, foot first.
    let mut first_of_layer: HashMap<i32, usize> = HashMap::new();
    for (i, n) in net.nodes.iter().enumerate() {
        if n.role != Role::ColumnEnd {
            first_of_layer.entry(n.layer).or_insert(i);
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
    Ok(out)
}

/// The extremes of one state's element stresses: the first element with the lowest and with the
/// highest stress (the order [`element_stresses`] gives), and the largest |σ|.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct StressExtremes {
    pub(crate) min: Option<(f64, ElementKind)>,
    pub(crate) max: Option<(f64, ElementKind)>,
    pub(crate) abs_max: f64,
}

impl StressExtremes {
    pub(crate) fn of(stresses: &[ElementStress]) -> Self {
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

/// The first lowest and first highest of a run of elements of one family, each as (σ, depth,
/// index of the element within the family at that depth); merged in element order.
#[derive(Debug, Clone, Copy)]
struct FamilyExtremes {
    min: (f64, usize, usize),
    max: (f64, usize, usize),
}

impl FamilyExtremes {
    fn one(item: (f64, usize, usize)) -> Self {
        FamilyExtremes {
            min: item,
            max: item,
        }
    }

    /// `a` then `b` in element order: on equal values the earlier element stays.
    fn merge(a: Option<Self>, b: Option<Self>) -> Option<Self> {
        match (a, b) {
            (Some(a), Some(b)) => Some(FamilyExtremes {
                min: if b.min.0 < a.min.0 { b.min } else { a.min },
                max: if b.max.0 > a.max.0 { b.max } else { a.max },
            }),
            (a, b) => a.or(b),
        }
    }

    /// The largest |σ| of the run.
    fn abs_max(e: Option<Self>) -> f64 {
        e.map_or(0.0, |e| e.min.0.abs().max(e.max.0.abs()))
    }
}

/// Whether every state's layer forces depend only on the layer's depth below the state's top:
/// against an end wall, with no start section ([`extremes_by_depth`]).
pub(crate) fn depth_invariant(sections: &Sections) -> bool {
    sections.end == EndKind::EndWall && sections.n_start == 0
}

/// The stress extremes of **every** state of an end-wall cap from one force pass, that of the
/// final state (`final_stresses`, [`element_stresses`] of it); `None` when the cap has a start
/// section (its layers' forces depend on the state), so the caller runs every state's force pass.
///
/// Why it is exact: the force pass sweeps each column from the top down (method.md §5), so a
/// layer's forces depend only on the layers above it, and against an end wall every layer is
/// layer 0 translated by k·step, with the same loads and arch forces. So in every state the
/// layer d layers below the top carries the forces of the final state's layer at depth d, and the
/// bed joint under the state's layer 0 (on the wall) carries what the final state's bed joint at
/// that depth carries (both run along −step). The extremes of state `t` are then prefix extremes
/// over the depths 0..=t: O(1) per state instead of a force pass over the whole state, which
/// made checking every state quadratic in the bay length (issue 15). The values agree with the
/// per-state force passes to round-off (the translated coordinates differ in their last bits;
/// `tests` compares every state); among elements of equal stress the one named may then differ
/// (e.g. an arch's mirror column).
pub(crate) fn extremes_by_depth(
    sections: &Sections,
    final_stresses: &[ElementStress],
) -> Option<Vec<StressExtremes>> {
    if !depth_invariant(sections) {
        return None;
    }
    let n = sections.layers.len();
    let id_of = |q: usize| sections.layers.get(q).map(|l| l.id);
    let top_id = id_of(n.checked_sub(1)?)?;
    // Depth in the final state of the layer with id `id` (print index = id without a start).
    let depth = |id: i32| -> Option<usize> {
        let d = top_id.checked_sub(id)?;
        usize::try_from(d).ok().filter(|&d| d < n)
    };
    // Per depth, in element order: arch segments (σ, segment) and the column edges below the
    // layer (σ, their index at that depth).
    let mut arch: Vec<Vec<(f64, usize)>> = vec![Vec::new(); n];
    let mut below: Vec<Vec<(f64, usize)>> = vec![Vec::new(); n];
    for s in final_stresses {
        let (family, d, i) = match s.kind {
            ElementKind::ArchSegment { layer, segment } => (&mut arch, depth(layer)?, segment),
            ElementKind::BedJoint { upper: layer, .. } | ElementKind::WallJoint { layer } => {
                let d = depth(layer)?;
                let i = below.get(d)?.len();
                (&mut below, d, i)
            }
            ElementKind::ColumnFoot { .. } => return None,
        };
        family.get_mut(d)?.push((s.stress, i));
    }
    // Per depth, then over the depths 0..=d (the elements of a state whose top is d deep).
    let at = |v: &[Vec<(f64, usize)>]| -> Vec<Option<FamilyExtremes>> {
        v.iter()
            .enumerate()
            .map(|(d, xs)| {
                xs.iter().fold(None, |e, &(x, i)| {
                    FamilyExtremes::merge(e, Some(FamilyExtremes::one((x, d, i))))
                })
            })
            .collect()
    };
    let prefix = |at: &[Option<FamilyExtremes>]| -> Vec<Option<FamilyExtremes>> {
        at.iter()
            .scan(None, |acc, e| {
                *acc = FamilyExtremes::merge(*acc, *e);
                Some(*acc)
            })
            .collect()
    };
    let arch_prefix = prefix(&at(&arch));
    let below_at = at(&below);
    let below_prefix = prefix(&below_at);
    let mut out = Vec::with_capacity(n);
    for t in 0..n {
        let state_id = |d: usize| id_of(t.checked_sub(d)?);
        let mut e = StressExtremes::default();
        // The generic order: arch segments (top layer first), then the column edges.
        if let Some(m) = arch_prefix[t] {
            for (x, d, segment) in [m.min, m.max] {
                e.add(
                    x,
                    ElementKind::ArchSegment {
                        layer: state_id(d)?,
                        segment,
                    },
                );
            }
        }
        let bed = |d: usize| -> Option<ElementKind> {
            Some(ElementKind::BedJoint {
                upper: state_id(d)?,
                lower: state_id(d + 1)?,
            })
        };
        let above_wall = t.checked_sub(1).and_then(|d| below_prefix[d]);
        if let Some(m) = above_wall {
            for (x, d, _) in [m.min, m.max] {
                e.add(x, bed(d)?);
            }
        }
        // The state's layer 0 stands on the wall.
        if let Some(w) = below_at[t] {
            let wall = ElementKind::WallJoint {
                layer: state_id(t)?,
            };
            for (x, _, _) in [w.min, w.max] {
                e.add(x, wall);
            }
        }
        e.abs_max = FamilyExtremes::abs_max(arch_prefix[t])
            .max(FamilyExtremes::abs_max(above_wall))
            .max(FamilyExtremes::abs_max(below_at[t]));
        out.push(e);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::form::states::build_state;

    /// Every state's extremes from the final state's force pass equal those of the state's own
    /// force pass (end-wall caps of 0.3 and 0.6 m, every state). Tolerance 1e-12 of the state's
    /// largest |σ|: the two differ only by the round-off of the translated coordinates in the
    /// unit vectors (1e-16 relative each, summed down at most a few hundred layers). Where the
    /// named element differs, the state's own pass gives it the same stress (a tie, e.g. the
    /// mirror column of a symmetric arch).
    #[test]
    fn extremes_by_depth_equal_every_states_own_force_pass() {
        for length in [0.3, 0.6] {
            let mut d = crate::Design::default();
            d.cap.length = length;
            d.cap.end = EndKind::EndWall;
            let cap = crate::design_cap(&d, crate::Context::default()).expect("cap");
            let phi = d.print.start_arch_fraction;
            let n = cap.sections.layers.len();
            let last = build_state(&cap.sections, &cap.frame, phi, n - 1).expect("state");
            let fast = extremes_by_depth(
                &cap.sections,
                &element_stresses(&last, cap.areas()).expect("stresses"),
            )
            .expect("an end-wall cap is depth-invariant");
            assert_eq!(fast.len(), n);
            for (top, f) in fast.iter().enumerate() {
                let state = build_state(&cap.sections, &cap.frame, phi, top).expect("state");
                let all = element_stresses(&state, cap.areas()).expect("stresses");
                let own = StressExtremes::of(&all);
                let tol = 1e-12 * own.abs_max.max(1.0);
                assert!((f.abs_max - own.abs_max).abs() <= tol, "state {top}");
                for (a, b) in [(f.min, own.min), (f.max, own.max)] {
                    let (Some(a), Some(b)) = (a, b) else {
                        panic!("state {top}: {a:?} vs {b:?}");
                    };
                    assert!((a.0 - b.0).abs() <= tol, "state {top}: {a:?} vs {b:?}");
                    if a.1 != b.1 {
                        let named = all.iter().find(|s| s.kind == a.1);
                        assert!(
                            named.is_some_and(|s| (s.stress - b.0).abs() <= tol),
                            "state {top}: {a:?} names an element the state does not have at {b:?}"
                        );
                    }
                }
            }
        }
        // A start section: the forces of its layers depend on the state, so no shortcut.
        let cap =
            crate::design_cap(&crate::Design::default(), crate::Context::default()).expect("cap");
        assert!(!depth_invariant(&cap.sections));
        assert!(extremes_by_depth(&cap.sections, &[]).is_none());
    }
}
