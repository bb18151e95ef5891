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
//! Above [`MODE_BUDGET_BYTES`] in total, every k-th analysed state keeps its mode (and always the
//! one with the lowest BLF): the viewer shows the last mode at or before the current state and
//! says whose it is.

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use serde_json::{Value, json};

use crate::error::ReportError;
use crate::input::{Quantity, QuantityPer, ReportInput};

/// Bytes of mode shapes (before base64) kept in a page: ~0.4 MB of its 3 MB budget.
pub const MODE_BUDGET_BYTES: usize = 300_000;

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

/// Pool of per-layer chunks: values and, per (state, printed layer), the chunk's offset and a
/// scale (value = pool[offset + i] · scale).
struct ChunkPool {
    pool: Vec<f32>,
    offsets: Vec<i64>,
    scales: Vec<f64>,
}

/// A chunk whose values are `c` times a stored chunk of the same layer, within 1e-7 of the
/// chunk's largest magnitude (the size of f32 rounding), is kept as (that chunk, c). Layer
/// stresses are F_i · d_q(state) / A: each state scales a layer's stresses by its layer factor,
/// so every layer is stored about once.
const PROPORTIONAL_TOLERANCE: f64 = 1e-7;

/// Builds the chunk pool of a per-segment (or per-layer) quantity. `chunk_len[q]` is the value
/// count of layer q; `states[s]` holds the values of the first `printed[s]` layers.
fn chunk_pool(chunk_len: &[usize], printed: &[usize], states: &[&[f64]]) -> ChunkPool {
    let mut out = ChunkPool {
        pool: Vec::new(),
        offsets: Vec::new(),
        scales: Vec::new(),
    };
    // Per layer, the stored chunk the others are scaled from (offset, f64 values).
    let mut base: Vec<Option<(usize, Vec<f64>)>> = vec![None; chunk_len.len()];
    for (s, values) in states.iter().enumerate() {
        let mut at = 0;
        for (q, &len) in chunk_len
            .iter()
            .enumerate()
            .take(printed.get(s).copied().unwrap_or(0))
        {
            let chunk = values.get(at..at + len).unwrap_or(&[]);
            at += len;
            let big = chunk.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let scaled = base[q].as_ref().and_then(|(o, b)| {
                let (j, bj) = b
                    .iter()
                    .enumerate()
                    .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))?;
                if *bj == 0.0 || b.len() != chunk.len() {
                    return None;
                }
                let c = chunk.get(j)? / bj;
                chunk
                    .iter()
                    .zip(b)
                    .all(|(v, w)| (v - c * w).abs() <= PROPORTIONAL_TOLERANCE * big)
                    .then_some((*o, c))
            });
            let (offset, scale) = scaled.unwrap_or_else(|| {
                let o = out.pool.len();
                out.pool.extend(chunk.iter().map(|&v| v as f32));
                if big > 0.0 || base[q].is_none() {
                    base[q] = Some((o, chunk.to_vec()));
                }
                (o, 1.0)
            });
            out.offsets.push(offset as i64);
            out.scales.push(scale);
        }
    }
    out
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
    for v in states.iter().flat_map(|s| s.iter()) {
        lo = lo.min(*v);
        hi = hi.max(*v);
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
        "scales": b64_f32(p.scales.iter().copied()),
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
            "base": b64_f32(r.base.iter().flatten().copied()),
        })
    });

    // Thin the modes to the budget: every k-th, the governing (lowest BLF) one and the last.
    let bytes: usize = input.modes.iter().map(|m| 3 * m.displacement.len()).sum();
    let stride = bytes.div_ceil(MODE_BUDGET_BYTES).max(1);
    let governing = input
        .modes
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.blf.total_cmp(&b.1.blf))
        .map(|(i, _)| i);
    let last = input.modes.len().saturating_sub(1);
    let modes: Vec<Value> = input
        .modes
        .iter()
        .enumerate()
        .filter(|(i, _)| i % stride == 0 || Some(*i) == governing || *i == last)
        .map(|(_, m)| m)
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
        "final_stress": b64_f32(finals.iter().copied()),
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
        "schedule": input.schedule,
        "robot_summary": input.robot_summary,
    })
}

fn decode<const N: usize>(v: &Value, field: &str) -> Result<Vec<[u8; N]>, ReportError> {
    let bad = || ReportError::Island {
        field: field.to_string(),
    };
    let bytes = STANDARD
        .decode(v.as_str().ok_or_else(bad)?)
        .map_err(|_| bad())?;
    if bytes.len() % N != 0 {
        return Err(bad());
    }
    Ok(bytes
        .chunks_exact(N)
        .map(|c| {
            let mut a = [0u8; N];
            a.copy_from_slice(c);
            a
        })
        .collect())
}

fn d_f32(v: &Value, field: &str) -> Result<Vec<f64>, ReportError> {
    Ok(decode::<4>(v, field)?
        .into_iter()
        .map(|b| f64::from(f32::from_le_bytes(b)))
        .collect())
}

fn d_i32(v: &Value, field: &str) -> Result<Vec<i64>, ReportError> {
    Ok(decode::<4>(v, field)?
        .into_iter()
        .map(|b| i64::from(i32::from_le_bytes(b)))
        .collect())
}

fn triples(v: Vec<f64>) -> Vec<[f64; 3]> {
    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Reads the scene island of a `report.html` back into a [`ReportInput`] (for tests and tools
/// that check a written page): every number as the page carries it (`f32` arrays, 7 significant
/// digits elsewhere). Mode shapes come back normalised (largest |u| = 1, 1/127 steps); plots
/// and the quantities other than the layer stress are not read back.
///
/// # Errors
/// [`ReportError::Json`] for text that is not JSON, [`ReportError::Island`] naming the first
/// field that is missing or malformed.
pub fn read_island(json: &str) -> Result<ReportInput, ReportError> {
    use crate::input::{BedJoint, Layer, ModeShape, PrintPath, PrintState, RobotAnimation};
    let v: Value = serde_json::from_str(json)?;
    let bad = |field: &str| ReportError::Island {
        field: field.to_string(),
    };
    let from = |field: &str| -> Result<Value, ReportError> {
        v.get(field).cloned().ok_or_else(|| bad(field))
    };
    let nodes = triples(d_f32(&from("nodes")?, "nodes")?);
    let finals = d_f32(&from("final_stress")?, "final_stress")?;
    let mut layers = Vec::new();
    let (mut at_node, mut at_seg) = (0usize, 0usize);
    for (k, l) in from("layers")?
        .as_array()
        .ok_or_else(|| bad("layers"))?
        .iter()
        .enumerate()
    {
        let field = format!("layers[{k}]");
        let n = l["n"].as_u64().ok_or_else(|| bad(&field))? as usize;
        let seg = n.saturating_sub(1);
        layers.push(Layer {
            id: i32::try_from(l["id"].as_i64().ok_or_else(|| bad(&field))?)
                .map_err(|_| bad(&field))?,
            nodes: nodes
                .get(at_node..at_node + n)
                .ok_or_else(|| bad("nodes"))?
                .to_vec(),
            segment_stress: finals
                .get(at_seg..at_seg + seg)
                .ok_or_else(|| bad("final_stress"))?
                .to_vec(),
            plane_normal: serde_json::from_value(l["plane_normal"].clone())?,
            bead_width: l["bead_width"].as_f64().ok_or_else(|| bad(&field))?,
            bead_height: l["bead_height"].as_f64().ok_or_else(|| bad(&field))?,
            overhang: l["overhang"].as_f64(),
        });
        at_node += n;
        at_seg += seg;
    }
    let bj = from("bed_joints")?;
    let bj_layer = d_i32(&bj["layer"], "bed_joints.layer")?;
    let bj_a = triples(d_f32(&bj["a"], "bed_joints.a")?);
    let bj_b = triples(d_f32(&bj["b"], "bed_joints.b")?);
    let bj_s = d_f32(&bj["stress"], "bed_joints.stress")?;
    let bed_joints = bj_layer
        .iter()
        .zip(bj_a.iter().zip(bj_b.iter().zip(&bj_s)))
        .map(|(l, (a, (b, s)))| BedJoint {
            layer: i32::try_from(*l).unwrap_or(i32::MAX),
            a: *a,
            b: *b,
            stress: *s,
        })
        .collect();
    let path = from("path")?;
    let print_path = PrintPath {
        points: triples(d_f32(&path["points"], "path.points")?),
        tool_axis: triples(d_f32(&path["axis"], "path.axis")?),
        layer: d_i32(&path["layer"], "path.layer")?
            .into_iter()
            .map(|l| i32::try_from(l).unwrap_or(i32::MAX))
            .collect(),
    };
    let point_time = d_f32(&path["time"], "path.time")?;
    // The end is written with 7 digits, the point times as f32: keep the end after the last.
    let total_time = from("total_time")?
        .as_f64()
        .ok_or_else(|| bad("total_time"))?
        .max(point_time.last().copied().unwrap_or(0.0));
    // Per-state layer stress from the chunk pool of the first quantity.
    let q = from("quantities")?
        .get(0)
        .cloned()
        .ok_or_else(|| bad("quantities"))?;
    let pool = d_f32(&q["pool"], "quantities[0].pool")?;
    let offsets = d_i32(&q["offsets"], "quantities[0].offsets")?;
    let scales = d_f32(&q["scales"], "quantities[0].scales")?;
    let mut states = Vec::new();
    let mut chunk = 0usize;
    for (si, s) in from("states")?
        .as_array()
        .ok_or_else(|| bad("states"))?
        .iter()
        .enumerate()
    {
        let field = format!("states[{si}]");
        let printed = s["layers_printed"].as_u64().ok_or_else(|| bad(&field))? as usize;
        let mut stress = Vec::new();
        for l in layers.iter().take(printed) {
            let o = offsets
                .get(chunk)
                .and_then(|o| usize::try_from(*o).ok())
                .ok_or_else(|| bad("quantities[0].offsets"))?;
            let len = l.segment_stress.len();
            let c = scales.get(chunk).copied().unwrap_or(1.0);
            stress.extend(
                pool.get(o..o + len)
                    .ok_or_else(|| bad("quantities[0].pool"))?
                    .iter()
                    .map(|v| v * c),
            );
            chunk += 1;
        }
        states.push(PrintState {
            index: s["index"].as_u64().ok_or_else(|| bad(&field))? as usize,
            progress: s["progress"].as_f64().ok_or_else(|| bad(&field))?,
            layers_printed: printed,
            blf: s["blf"].as_f64(),
            sigma_min: s["sigma_min"].as_f64().ok_or_else(|| bad(&field))?,
            sigma_max: s["sigma_max"].as_f64().ok_or_else(|| bad(&field))?,
            max_overhang: s["max_overhang"].as_f64().ok_or_else(|| bad(&field))?,
            ok: s["ok"].as_bool().ok_or_else(|| bad(&field))?,
            segment_stress: Some(stress),
        });
    }
    let robot = match v.get("robot") {
        Some(r) if !r.is_null() => {
            let joints: Vec<[f64; 6]> = d_f32(&r["joints"], "robot.joints")?
                .chunks_exact(6)
                .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
                .collect();
            let link_radii: Vec<f64> = serde_json::from_value(r["link_radii"].clone())?;
            let flat = triples(d_f32(&r["poses"], "robot.poses")?);
            let per = 2 * link_radii.len().max(1);
            let poses = flat
                .chunks_exact(per)
                .map(|c| c.chunks_exact(2).map(|p| [p[0], p[1]]).collect())
                .collect();
            Some(RobotAnimation {
                times: d_f32(&r["times"], "robot.times")?,
                joints,
                link_radii,
                poses,
                station: d_i32(&r["station"], "robot.station")?
                    .into_iter()
                    .map(|s| usize::try_from(s).unwrap_or(usize::MAX))
                    .collect(),
                // Pages written before the moving base have no `base`.
                base: match r.get("base") {
                    Some(b) if !b.is_null() => triples(d_f32(b, "robot.base")?),
                    _ => Vec::new(),
                },
            })
        }
        _ => None,
    };
    let mut modes = Vec::new();
    for (mi, m) in from("modes")?
        .as_array()
        .ok_or_else(|| bad("modes"))?
        .iter()
        .enumerate()
    {
        let field = format!("modes[{mi}]");
        let state = m["state"].as_u64().ok_or_else(|| bad(&field))? as usize;
        let first = m["first"].as_u64().ok_or_else(|| bad(&field))? as usize;
        let printed = states.get(state).map_or(0, |s| s.layers_printed);
        let total: usize = layers.iter().take(printed).map(|l| l.nodes.len()).sum();
        let u = decode::<1>(&m["u"], &field)?;
        let mut displacement = vec![[0.0; 3]; total];
        for (k, c) in u.chunks_exact(3).enumerate() {
            if let Some(d) = displacement.get_mut(first + k) {
                *d = [0, 1, 2].map(|i| f64::from(i8::from_le_bytes(c[i])) / 127.0);
            }
        }
        modes.push(ModeShape {
            state,
            blf: m["blf"].as_f64().ok_or_else(|| bad(&field))?,
            displacement,
        });
    }
    Ok(ReportInput {
        name: from("name")?
            .as_str()
            .ok_or_else(|| bad("name"))?
            .to_string(),
        parameters: Vec::new(),
        layers,
        bed_joints,
        print_path,
        states,
        constraints: serde_json::from_value(from("constraints")?)?,
        robot,
        plots: Vec::new(),
        timeline: Some(crate::input::Timeline {
            point_time,
            total_time,
        }),
        cell: serde_json::from_value(from("cell")?)?,
        modes,
        worst_places: serde_json::from_value(from("worst_places")?)?,
        quantities: Vec::new(),
        schedule: match v.get("schedule") {
            Some(v) if !v.is_null() => Some(serde_json::from_value(v.clone())?),
            _ => None,
        },
        robot_summary: match v.get("robot_summary") {
            Some(v) if !v.is_null() => Some(serde_json::from_value(v.clone())?),
            _ => None,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_proportional_to_a_stored_one_are_stored_once() {
        // Two layers of 2 and 1 values; state 0 prints layer 0, state 1 both, state 2 scales
        // layer 0 by 3, state 3 changes its shape, state 4 zeroes it.
        let s0 = [1.0, 2.0];
        let s1 = [1.0, 2.0, 5.0];
        let s2 = [3.0, 6.0, 5.0];
        let s3 = [1.5, 2.0, 5.0];
        let s4 = [0.0, 0.0, 5.0];
        let p = chunk_pool(&[2, 1], &[1, 2, 2, 2, 2], &[&s0, &s1, &s2, &s3, &s4]);
        assert_eq!(p.pool, vec![1.0, 2.0, 5.0, 1.5, 2.0]);
        assert_eq!(p.offsets, vec![0, 0, 2, 0, 2, 3, 2, 3, 2]);
        assert_eq!(p.scales, vec![1.0, 1.0, 1.0, 3.0, 1.0, 1.0, 1.0, 0.0, 1.0]);
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
