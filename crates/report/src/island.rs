//! The scene island of `report.html`: the [`ReportInput`] in the compact form the viewer reads.
//!
//! Small, structured parts (names, parameters, constraints, per-state scalars, the cell) stay
//! plain JSON. Every long numeric array is a typed array in base64 (little-endian; `f32` for
//! coordinates, times, stresses and joint angles: 7 significant digits, far below what the page
//! can show; `i32`/`u32` for ids and offsets): 4 bytes of binary are 5.3 characters, against
//! 8–12 for the same number as JSON text, and the browser decodes them without parsing.
//!
//! Per-segment quantities of every state (the stress of every printed segment in every state)
//! dominate the size: they grow with the square of the layer count. They are stored as a pool of
//! per-layer chunks with an offset per (state, printed layer): a chunk equal to the same layer's
//! chunk in the previous state (bit for bit, as `f32`) is not stored again. In a cap most layers
//! keep their stresses from one state to the next (only the layer factors of the start section
//! change), so the pool stays near the size of one state (see `examples/size_table.rs`).
//!
//! Mode shapes are normalised (largest |u| = 1) and stored as `i8` per component for the nodes
//! between the first and the last one whose |u| exceeds 1 % (a mode is local to the top layers).

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use serde_json::{Value, json};

use crate::input::{Quantity, QuantityPer, ReportInput};

/// Little-endian `f32` array in base64.
pub(crate) fn b64_f32(values: impl IntoIterator<Item = f64>) -> String {
    let bytes: Vec<u8> = values
        .into_iter()
        .flat_map(|v| (v as f32).to_le_bytes())
        .collect();
    STANDARD.encode(bytes)
}

fn b64_i32(values: impl IntoIterator<Item = i64>) -> String {
    let bytes: Vec<u8> = values
        .into_iter()
        .flat_map(|v| (v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32).to_le_bytes())
        .collect();
    STANDARD.encode(bytes)
}

fn b64_i8(values: impl IntoIterator<Item = i8>) -> String {
    let bytes: Vec<u8> = values.into_iter().map(|v| v.to_le_bytes()[0]).collect();
    STANDARD.encode(bytes)
}

/// Pool of per-layer chunks: values and, per (state, printed layer), the chunk's offset.
struct ChunkPool {
    pool: Vec<f32>,
    offsets: Vec<i64>,
}

/// Builds the chunk pool of a per-segment (or per-layer) quantity. `chunk_len[q]` is the value
/// count of layer q; `states[s]` holds the values of the first `printed[s]` layers.
fn chunk_pool(chunk_len: &[usize], printed: &[usize], states: &[&[f64]]) -> ChunkPool {
    let mut pool: Vec<f32> = Vec::new();
    let mut offsets = Vec::new();
    // Offset of each layer's chunk in the previous state, to reuse an identical chunk.
    let mut last: Vec<Option<usize>> = vec![None; chunk_len.len()];
    for (s, values) in states.iter().enumerate() {
        let mut at = 0;
        for (q, &len) in chunk_len
            .iter()
            .enumerate()
            .take(printed.get(s).copied().unwrap_or(0))
        {
            let chunk: Vec<f32> = values
                .get(at..at + len)
                .unwrap_or(&[])
                .iter()
                .map(|&v| v as f32)
                .collect();
            at += len;
            let reuse = last[q].filter(|&o| {
                pool.get(o..o + len).is_some_and(|p| {
                    p.iter()
                        .zip(&chunk)
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                })
            });
            let offset = reuse.unwrap_or_else(|| {
                let o = pool.len();
                pool.extend(&chunk);
                o
            });
            last[q] = Some(offset);
            offsets.push(offset as i64);
        }
    }
    ChunkPool { pool, offsets }
}

/// A quantity's island entry; `meta` gives everything but the values (its `states` unused).
fn quantity_json(input: &ReportInput, meta: &Quantity, states: &[&[f64]]) -> Value {
    let per = meta.per;
    let chunk_len: Vec<usize> = input
        .layers
        .iter()
        .map(|l| match per {
            QuantityPer::Segment => l.segment_stress.len(),
            QuantityPer::Layer => 1,
        })
        .collect();
    let printed: Vec<usize> = if states.len() == 1 && input.states.len() != 1 {
        vec![input.layers.len()]
    } else {
        input.states.iter().map(|s| s.layers_printed).collect()
    };
    let p = chunk_pool(&chunk_len, &printed, states);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in &p.pool {
        lo = lo.min(f64::from(*v));
        hi = hi.max(f64::from(*v));
    }
    if !lo.is_finite() {
        (lo, hi) = (0.0, 0.0);
    }
    json!({
        "key": meta.key,
        "label": meta.label,
        "unit": meta.unit,
        "to_unit": meta.to_unit,
        "per": match per { QuantityPer::Segment => "segment", QuantityPer::Layer => "layer" },
        "diverging": meta.diverging,
        "shared": states.len() == 1 && input.states.len() != 1,
        "note": meta.note,
        "min": lo,
        "max": hi,
        "pool": b64_f32(p.pool.iter().map(|&v| f64::from(v))),
        "offsets": b64_i32(p.offsets),
    })
}

/// Bed-joint stress spread onto the bead segments: each joint's stress goes to the node of its
/// upper layer nearest to its upper end, a segment shows the mean of its two nodes (0 where no
/// joint ends, e.g. the first layer on the bed).
fn bed_joint_segment_stress(input: &ReportInput) -> Vec<f64> {
    let mut out = Vec::new();
    for layer in &input.layers {
        let mut at_node = vec![(0.0, 0usize); layer.nodes.len()];
        for j in input.bed_joints.iter().filter(|j| j.layer == layer.id) {
            let nearest = layer
                .nodes
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let d = (0..3).map(|k| (p[k] - j.b[k]).powi(2)).sum::<f64>();
                    (i, d)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((i, _)) = nearest
                && let Some(slot) = at_node.get_mut(i)
            {
                slot.0 += j.stress;
                slot.1 += 1;
            }
        }
        let node = |i: usize| {
            at_node
                .get(i)
                .map_or(0.0, |&(s, n)| if n > 0 { s / n as f64 } else { 0.0 })
        };
        out.extend((0..layer.segment_stress.len()).map(|i| 0.5 * (node(i) + node(i + 1))));
    }
    out
}

/// The island as a JSON value (see the module docs).
pub(crate) fn island(input: &ReportInput) -> Value {
    let layers: Vec<Value> = input
        .layers
        .iter()
        .map(|l| {
            json!({
                "id": l.id,
                "n": l.nodes.len(),
                "plane_normal": l.plane_normal,
                "bead_width": l.bead_width,
                "bead_height": l.bead_height,
                "overhang": l.overhang,
            })
        })
        .collect();
    let nodes = b64_f32(
        input
            .layers
            .iter()
            .flat_map(|l| l.nodes.iter().flatten().copied()),
    );
    let path = &input.print_path;

    // The timeline: the given point times, or the arc length (1 m per time unit).
    let point_time: Vec<f64> = match &input.timeline {
        Some(t) => t.point_time.clone(),
        None => {
            let mut s = 0.0;
            let mut prev: Option<&[f64; 3]> = None;
            path.points
                .iter()
                .map(|p| {
                    if let Some(q) = prev {
                        s += (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
                    }
                    prev = Some(p);
                    s
                })
                .collect()
        }
    };
    let robot_end = input
        .robot
        .as_ref()
        .and_then(|r| r.times.last().copied())
        .unwrap_or(0.0);
    let total_time = input
        .timeline
        .as_ref()
        .map_or_else(
            || point_time.last().copied().unwrap_or(0.0),
            |t| t.total_time,
        )
        .max(robot_end);

    let states: Vec<Value> = input
        .states
        .iter()
        .map(|s| {
            json!({
                "index": s.index,
                "progress": s.progress,
                "layers_printed": s.layers_printed,
                "blf": s.blf,
                "sigma_min": s.sigma_min,
                "sigma_max": s.sigma_max,
                "max_overhang": s.max_overhang,
                "ok": s.ok,
            })
        })
        .collect();

    // Colour quantities: layer stress (per state when given), bed-joint stress (final state),
    // then the caller's.
    let finals: Vec<f64> = input
        .layers
        .iter()
        .flat_map(|l| l.segment_stress.iter().copied())
        .collect();
    let per_state: Vec<Vec<f64>> = input
        .states
        .iter()
        .map(|s| match &s.segment_stress {
            Some(v) => v.clone(),
            None => finals
                .get(..input.printed_segments(s.layers_printed))
                .unwrap_or(&[])
                .to_vec(),
        })
        .collect();
    let per_state_refs: Vec<&[f64]> = per_state.iter().map(Vec::as_slice).collect();
    // A start layer whose final arch stress is zero next to stressed centre layers (relative
    // 1e-9, the force pass's round-off): the legend explains the white beads.
    let scale = finals.iter().fold(0.0_f64, |m, s| m.max(s.abs()));
    let zero_start = scale > 0.0
        && input
            .layers
            .iter()
            .any(|l| l.id < 0 && l.segment_stress.iter().all(|s| s.abs() <= 1e-9 * scale));
    let stress = |key: &str, label: &str, note: Option<&str>| Quantity {
        key: key.into(),
        label: label.into(),
        unit: "kPa".into(),
        to_unit: 1e-3,
        per: QuantityPer::Segment,
        diverging: true,
        states: Vec::new(),
        note: note.map(str::to_string),
    };
    let mut quantities = vec![quantity_json(
        input,
        &stress(
            "layer_stress",
            "layer stress σ (along the bead)",
            zero_start.then_some(
                "White start layers at the end of the print carry no arch force: with φ = 0 the \
                 chosen equilibrium lets the centre layers' weight go down the bed joints (their \
                 stress shows under \u{201c}bed-joint stress\u{201d}).",
            ),
        ),
        &per_state_refs,
    )];
    if !input.bed_joints.is_empty() {
        let bj = bed_joint_segment_stress(input);
        quantities.push(quantity_json(
            input,
            &stress(
                "bed_joint_stress",
                "bed-joint stress σ (final state, joint under each bead node)",
                None,
            ),
            &[bj.as_slice()],
        ));
    }
    for q in &input.quantities {
        let refs: Vec<&[f64]> = q.states.iter().map(Vec::as_slice).collect();
        quantities.push(quantity_json(input, q, &refs));
    }

    let robot = input.robot.as_ref().map(|r| {
        json!({
            "times": b64_f32(r.times.iter().copied()),
            "joints": b64_f32(r.joints.iter().flatten().copied()),
            "station": b64_i32(r.station.iter().map(|&s| s as i64)),
            "link_radii": r.link_radii,
            "poses": b64_f32(r.poses.iter().flatten().flatten().flatten().copied()),
        })
    });

    let modes: Vec<Value> = input
        .modes
        .iter()
        .filter_map(|m| {
            let mag = |d: &[f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let max = m.displacement.iter().map(mag).fold(0.0, f64::max);
            if max <= 0.0 {
                return None;
            }
            let big = |d: &&[f64; 3]| mag(d) > 0.01 * max;
            let first = m.displacement.iter().position(|d| big(&d))?;
            let last = m.displacement.iter().rposition(|d| big(&d))?;
            let q = m
                .displacement
                .get(first..=last)?
                .iter()
                .flat_map(|d| d.map(|c| (c / max * 127.0).round().clamp(-127.0, 127.0) as i8));
            Some(json!({
                "state": m.state,
                "blf": m.blf,
                "first": first,
                "count": last + 1 - first,
                "u": b64_i8(q),
            }))
        })
        .collect();

    json!({
        "format": 2,
        "name": input.name,
        "layers": layers,
        "nodes": nodes,
        "bed_joints": {
            "layer": b64_i32(input.bed_joints.iter().map(|j| i64::from(j.layer))),
            "a": b64_f32(input.bed_joints.iter().flat_map(|j| j.a)),
            "b": b64_f32(input.bed_joints.iter().flat_map(|j| j.b)),
            "stress": b64_f32(input.bed_joints.iter().map(|j| j.stress)),
        },
        "path": {
            "points": b64_f32(path.points.iter().flatten().copied()),
            "axis": b64_f32(path.tool_axis.iter().flatten().copied()),
            "layer": b64_i32(path.layer.iter().map(|&l| i64::from(l))),
            "time": b64_f32(point_time.iter().copied()),
            "timed": input.timeline.is_some(),
        },
        "total_time": total_time,
        "states": states,
        "constraints": input.constraints,
        "quantities": quantities,
        "robot": robot,
        "cell": input.cell,
        "modes": modes,
        "worst_places": input.worst_places,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_equal_to_the_previous_state_are_stored_once() {
        // Two layers of 2 and 1 values; state 0 prints layer 0, state 1 both, state 2 changes
        // layer 0 only.
        let s0 = [1.0, 2.0];
        let s1 = [1.0, 2.0, 5.0];
        let s2 = [1.5, 2.0, 5.0];
        let p = chunk_pool(&[2, 1], &[1, 2, 2], &[&s0, &s1, &s2]);
        assert_eq!(p.pool, vec![1.0, 2.0, 5.0, 1.5, 2.0]);
        assert_eq!(p.offsets, vec![0, 0, 2, 3, 2]);
    }

    #[test]
    fn f32_base64_round_trips() {
        let s = b64_f32([1.5, -2.25]);
        let bytes = STANDARD.decode(s).unwrap();
        let back: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(back, vec![1.5, -2.25]);
    }
}
