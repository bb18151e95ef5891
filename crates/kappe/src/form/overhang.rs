//! Per-state analysis that needs no finite elements: element normal stresses (method.md §3) and
//! layer overhang.
//!
//! Stress = N / A with A = lw·lh for arch segments (along a layer) and A = lw·l_trib for the bed
//! joints between layers, where l_trib is the tributary length of the column node along its layer.

use crate::form::frame::{LayerFrame, V3};
use crate::form::section::Sections;

/// The overhang of every layer over the one printed before it, in print order (first layer: 0).
///
/// l_o is the offset of the bead centre line from the preceding layer's, measured in the
/// preceding layer's bed plane perpendicular to the path: for a node with unit tangent t,
/// `l_o = Δ · (n × t)` with Δ the translation between the layers. Its largest magnitude over the
/// layer is reported (at the crown, where it equals `−Δ·u`; `lh·tan(am)` in the centre section).
pub fn layer_overhangs(sections: &Sections, frame: &LayerFrame) -> Vec<f64> {
    let mut out = Vec::with_capacity(sections.layers.len());
    for (q, layer) in sections.layers.iter().enumerate() {
        let Some(prev) = q.checked_sub(1).and_then(|p| sections.layers.get(p)) else {
            out.push(0.0);
            continue;
        };
        let delta: V3 = layer.offset - prev.offset;
        let pts: Vec<V3> = prev.nodes.iter().map(|n| n.xyz).collect();
        let mut worst: f64 = 0.0;
        for w in pts.windows(2) {
            let t = w[1] - w[0];
            let len = t.norm();
            if len <= 0.0 {
                continue;
            }
            let p = frame.n.cross(&(t / len));
            let lo = delta.dot(&p);
            if lo.abs() > worst.abs() {
                worst = lo;
            }
        }
        out.push(worst);
    }
    out
}
