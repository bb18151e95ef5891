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

/// The overhang of every layer over the one printed before it, measured on the real geometry
/// (used for a corrugated cap, whose successive layers are not translates of each other).
///
/// Every interior node p of the layer is projected into the preceding layer's bed plane
/// (`p' = p − ((p − q₀)·n) n`, q₀ a node of that layer); the offset is the component of
/// `p' − a` along `n × t` for the preceding layer's segment (a, t̂) nearest to p'. The largest
/// magnitude over the layer is reported, signed as in [`layer_overhangs`]. For translates this is
/// `Δ·(n × t)` of [`layer_overhangs`] evaluated at the matching point of the path.
pub fn measured_overhangs(sections: &Sections, frame: &LayerFrame) -> Vec<f64> {
    let n = frame.n;
    let mut out = Vec::with_capacity(sections.layers.len());
    for (q, layer) in sections.layers.iter().enumerate() {
        let Some(prev) = q.checked_sub(1).and_then(|p| sections.layers.get(p)) else {
            out.push(0.0);
            continue;
        };
        let Some(q0) = prev.nodes.first().map(|nd| nd.xyz) else {
            out.push(0.0);
            continue;
        };
        let pts: Vec<V3> = prev.nodes.iter().map(|nd| nd.xyz).collect();
        let mut worst: f64 = 0.0;
        let inner = layer.nodes.len().saturating_sub(1);
        for node in layer.nodes.iter().take(inner).skip(1) {
            let p = node.xyz - n * (node.xyz - q0).dot(&n);
            let mut best = (f64::INFINITY, 0.0);
            for w in pts.windows(2) {
                let t = w[1] - w[0];
                let len2 = t.norm_squared();
                if len2 <= 0.0 {
                    continue;
                }
                let s = ((p - w[0]).dot(&t) / len2).clamp(0.0, 1.0);
                let d = (p - (w[0] + t * s)).norm();
                if d < best.0 {
                    let lo = (p - w[0]).dot(&n.cross(&(t / len2.sqrt())));
                    best = (d, lo);
                }
            }
            if best.0.is_finite() && best.1.abs() > worst.abs() {
                worst = best.1;
            }
        }
        out.push(worst);
    }
    out
}
