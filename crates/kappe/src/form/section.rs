//! Centre section (paper T2, method.md §5) and start section (paper T3, method.md §6): the layers
//! of the cap as translates of layer 0, in print order.
//!
//! Centre layer k is layer 0 translated by `k·(lh / cos am)·e_y`. Start layer −m is layer 0
//! translated by `T_m` and trimmed by the base plane, where the translations follow the
//! final-state thrust line (per unit node weight):
//!
//! ```text
//! r_0 = N tan(am) e_y,   T_0 = 0,
//! T_m = T_{m−1} − lh · r_{m−1} / (n · r_{m−1}),
//! r_m = r_{m−1} + (1 − φ) e_z + φ tan(am) e_y,
//! ```
//!
//! and K is the last m whose crown stays above the base plane, `Cr + T_m·e_z > 0`.
//!
//! With an end wall ([`EndKind::EndWall`], [`crate::form::ends`]) there are no start layers: K = 0 and
//! `T_1 = −(lh / cos am)·e_y` is the wall face (the plane of layer −1) that layer 0 leans on.

use crate::form::arch::Arch;
use crate::form::ends::EndKind;
use crate::form::frame::{LayerFrame, V3};
use crate::input::error::DesignError;

/// Where a layer node comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeKind {
    /// An interior node of column `i` (the index of its layer-0 node).
    Column(usize),
    /// A foot on the base plane (a reaction node; no trail edge).
    Foot,
}

/// A node of a layer.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerNode {
    /// Position, m.
    pub xyz: V3,
    /// Column or foot.
    pub kind: NodeKind,
    /// Gravity load magnitude, N.
    pub weight: f64,
}

/// One print layer: a polyline from foot to foot lying in its tilted plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// −K..−1 for start layers, 0..N−1 for centre layers.
    pub id: i32,
    /// Translation from layer 0, m.
    pub offset: V3,
    /// Nodes from the left foot to the right foot.
    pub nodes: Vec<LayerNode>,
    /// Layer-0 force of each segment (between nodes `i` and `i + 1`), N, before the layer factor.
    pub segment_forces: Vec<f64>,
}

impl Layer {
    /// Length of the bead centre line, m.
    pub fn length(&self) -> f64 {
        self.nodes
            .windows(2)
            .map(|w| (w[1].xyz - w[0].xyz).norm())
            .sum()
    }
}

/// All layers of the cap and the start-section translations.
#[derive(Debug, Clone, PartialEq)]
pub struct Sections {
    /// Number of centre layers N = round(Cl·cos(am) / lh).
    pub n_centre: usize,
    /// Number of start layers K.
    pub n_start: usize,
    /// `T_0 ..= T_{K+1}` (T_0 = 0); `T_{K+1}` continues the final-state thrust line below the base
    /// (with an end wall, K = 0 and `T_1` is the wall face).
    pub translations: Vec<V3>,
    /// What layer 0 leans on.
    pub end: EndKind,
    /// Every layer in print order: −K, …, −1, 0, …, N−1.
    pub layers: Vec<Layer>,
}

impl Sections {
    /// Index in print order of layer `id`.
    pub fn print_index(&self, id: i32) -> Option<usize> {
        let i = id + self.n_start as i32;
        (i >= 0 && (i as usize) < self.layers.len()).then_some(i as usize)
    }
}

/// N = round(Cl·cos(am) / lh), at least 1.
pub fn centre_layer_count(length: f64, frame: &LayerFrame, layer_height: f64) -> usize {
    ((length * frame.tilt.cos() / layer_height).round() as usize).max(1)
}

/// Build the sections for the given end: the start section of method.md §6, or none against an
/// end wall.
pub fn build_sections_with_end(
    arch: &Arch,
    frame: &LayerFrame,
    length: f64,
    layer_height: f64,
    phi: f64,
    half_chord_weight: impl Fn(f64) -> f64,
    end: EndKind,
) -> Result<Sections, DesignError> {
    let n_centre = centre_layer_count(length, frame, layer_height);
    if end == EndKind::EndWall {
        return Ok(Sections {
            n_centre,
            n_start: 0,
            translations: vec![V3::zeros(), -frame.layer_step(layer_height)],
            end,
            layers: centre_layers(arch, frame, layer_height, n_centre),
        });
    }
    let crown_z = arch
        .points
        .iter()
        .map(|p| p.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let lean = frame.lean();
    let ez = V3::z();

    // Final-state thrust line through the start section.
    let mut r = lean * n_centre as f64;
    let mut translations = vec![V3::zeros()];
    let mut n_start = 0usize;
    // A start section longer than this many layers means the thrust never turns down.
    let cap = 100_000usize;
    loop {
        let t_prev = translations[translations.len() - 1];
        let nr = frame.n.dot(&r);
        if nr <= 0.0 {
            return Err(DesignError::FormFinding(format!(
                "start layer −{}: the thrust line runs parallel to the layer planes",
                translations.len()
            )));
        }
        let t_next = t_prev - r * (layer_height / nr);
        r += ez * (1.0 - phi) + lean * phi;
        translations.push(t_next);
        if crown_z + t_next.z > 0.0 {
            n_start = translations.len() - 1;
        } else {
            break;
        }
        if translations.len() > cap {
            return Err(DesignError::FormFinding(
                "the start section does not reach the base plane (thrust never turns down)".into(),
            ));
        }
    }

    let mut layers = Vec::with_capacity(n_start + n_centre);
    for m in (1..=n_start).rev() {
        layers.push(trimmed_layer(
            arch,
            -(m as i32),
            translations[m],
            &half_chord_weight,
        )?);
    }
    layers.extend(centre_layers(arch, frame, layer_height, n_centre));
    Ok(Sections {
        n_centre,
        n_start,
        translations,
        end,
        layers,
    })
}

/// The sections of a corrugated cap (`[cap.corrugation]`, docs/corrugation.md): those of
/// [`build_sections_with_end`], then centre layer k takes its own form-found arch `centre[k]`
/// (in the plane of layer k: its points translated by `k·(lh / cos am)·e_y`). Layer 0's arch is
/// `arch` itself (the wave is zero there), so the start section and an end wall are unchanged.
#[allow(clippy::too_many_arguments)]
pub fn build_corrugated_sections(
    arch: &Arch,
    centre: &[Arch],
    frame: &LayerFrame,
    length: f64,
    layer_height: f64,
    phi: f64,
    half_chord_weight: impl Fn(f64) -> f64,
    end: EndKind,
) -> Result<Sections, DesignError> {
    let mut sections = build_sections_with_end(
        arch,
        frame,
        length,
        layer_height,
        phi,
        half_chord_weight,
        end,
    )?;
    if centre.len() != sections.n_centre {
        return Err(DesignError::FormFinding(format!(
            "{} corrugated centre arches for {} centre layers",
            centre.len(),
            sections.n_centre
        )));
    }
    let first = sections.n_start;
    for (k, a) in centre.iter().enumerate() {
        if a.points.len() != arch.points.len() {
            return Err(DesignError::FormFinding(format!(
                "corrugated centre layer {k} has {} nodes, layer 0 has {}: the columns must \
                 run through every layer",
                a.points.len(),
                arch.points.len()
            )));
        }
        let layer = &mut sections.layers[first + k];
        let offset = layer.offset;
        for ((node, p), w) in layer.nodes.iter_mut().zip(&a.points).zip(&a.weights) {
            node.xyz = p + offset;
            node.weight = *w;
        }
        layer.segment_forces.clone_from(&a.segment_forces);
    }
    Ok(sections)
}

/// Centre layers 0..N−1: layer 0 translated by `k·(lh / cos am)·e_y`.
fn centre_layers(
    arch: &Arch,
    frame: &LayerFrame,
    layer_height: f64,
    n_centre: usize,
) -> Vec<Layer> {
    let step = frame.layer_step(layer_height);
    let mut layers = Vec::with_capacity(n_centre);
    for k in 0..n_centre {
        let offset = step * k as f64;
        let nodes = arch
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| LayerNode {
                xyz: p + offset,
                kind: if i == 0 || i + 1 == arch.points.len() {
                    NodeKind::Foot
                } else {
                    NodeKind::Column(i)
                },
                weight: arch.weights[i],
            })
            .collect();
        layers.push(Layer {
            id: k as i32,
            offset,
            nodes,
            segment_forces: arch.segment_forces.clone(),
        });
    }
    layers
}

/// Layer 0 translated by `t` and trimmed by z = 0: the interior nodes above the base are kept and
/// the feet are placed where the cut chords cross the base plane, each chord keeping the force of
/// the segment it cuts.
fn trimmed_layer(
    arch: &Arch,
    id: i32,
    t: V3,
    half_chord_weight: &impl Fn(f64) -> f64,
) -> Result<Layer, DesignError> {
    let pts: Vec<V3> = arch.points.iter().map(|p| p + t).collect();
    let kept: Vec<usize> = arch.columns().filter(|&i| pts[i].z > 0.0).collect();
    let (Some(&first), Some(&last)) = (kept.first(), kept.last()) else {
        return Err(DesignError::FormFinding(format!(
            "start layer {id} has no node above the base plane"
        )));
    };
    if last - first + 1 != kept.len() {
        return Err(DesignError::FormFinding(format!(
            "start layer {id}: the arch dips below the base plane between its feet"
        )));
    }
    let cut = |a: usize, b: usize| -> V3 {
        // a above the base, b on or below it.
        let (za, zb) = (pts[a].z, pts[b].z);
        let s = za / (za - zb);
        let mut p = pts[a] + (pts[b] - pts[a]) * s;
        p.z = 0.0;
        p
    };
    let left = cut(first, first - 1);
    let right = cut(last, last + 1);
    let mut nodes = Vec::with_capacity(kept.len() + 2);
    nodes.push(LayerNode {
        xyz: left,
        kind: NodeKind::Foot,
        weight: half_chord_weight((pts[first] - left).norm()),
    });
    for &i in &kept {
        nodes.push(LayerNode {
            xyz: pts[i],
            kind: NodeKind::Column(i),
            weight: arch.weights[i],
        });
    }
    nodes.push(LayerNode {
        xyz: right,
        kind: NodeKind::Foot,
        weight: half_chord_weight((right - pts[last]).norm()),
    });
    // Segment first-1 → first is cut; segments between kept nodes keep their index.
    let segment_forces = arch.segment_forces[first - 1..=last].to_vec();
    Ok(Layer {
        id,
        offset: t,
        nodes,
        segment_forces,
    })
}
