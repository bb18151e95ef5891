//! Page size and render time of `render_html` as the design grows, up to ten times the default
//! design's states: the demo cap repeated along y (every copy's layers, path, bed joints and
//! robot frames; one state per layer with its own stresses, layer ages and mode shape), so the
//! page carries everything a real report of that size would. The copies reuse the demo's robot
//! frames and stations unshifted, so the pages are for size and opening time, not for the e2e
//! nozzle check. Prints a table; with OUT_DIR it also writes the pages:
//! `cargo run --release -p kappe-report --example size_table -- [OUT_DIR]`.

use std::time::Instant;

use kappe_report::{ModeShape, ReportInput, demo_input, render_html};

/// The demo with its layers repeated `copies` times, each copy shifted 0.5 m along y.
fn scaled(copies: usize) -> ReportInput {
    let base = demo_input();
    let mut input = base.clone();
    let dy = 0.5;
    let per_copy = base.layers.len();
    let t_copy = base.timeline.as_ref().map_or(0.0, |t| t.total_time);
    let shift = |p: &[f64; 3], c: usize| [p[0], p[1] + dy * c as f64, p[2]];
    let id = |l: i32, c: usize| l + i32::try_from(c * 1000).unwrap_or(i32::MAX);
    for c in 1..copies {
        for l in &base.layers {
            let mut l = l.clone();
            l.id = id(l.id, c);
            l.nodes = l.nodes.iter().map(|p| shift(p, c)).collect();
            input.layers.push(l);
        }
        for j in &base.bed_joints {
            let mut j = j.clone();
            j.layer = id(j.layer, c);
            j.a = shift(&j.a, c);
            j.b = shift(&j.b, c);
            input.bed_joints.push(j);
        }
        let p = &base.print_path;
        input
            .print_path
            .points
            .extend(p.points.iter().map(|q| shift(q, c)));
        input
            .print_path
            .tool_axis
            .extend(p.tool_axis.iter().copied());
        input
            .print_path
            .layer
            .extend(p.layer.iter().map(|&l| id(l, c)));
        if let (Some(t), Some(b)) = (input.timeline.as_mut(), base.timeline.as_ref()) {
            t.point_time
                .extend(b.point_time.iter().map(|x| x + t_copy * c as f64));
            t.total_time = t_copy * (c + 1) as f64;
        }
        if let (Some(r), Some(b)) = (input.robot.as_mut(), base.robot.as_ref()) {
            r.times
                .extend(b.times.iter().map(|x| x + t_copy * c as f64));
            r.joints.extend(b.joints.iter().copied());
            r.station.extend(b.station.iter().copied());
        }
    }
    // One state per layer: each layer's demo stresses scaled by how much is printed above it
    // (as the demo does), a layer age, and a mode shape bulging at the top layers.
    let n = input.layers.len();
    input.states = (1..=n)
        .map(|printed| {
            let mut s = base.states[(printed - 1) % per_copy].clone();
            s.index = printed - 1;
            s.progress = printed as f64 / n as f64;
            s.layers_printed = printed;
            s.segment_stress = Some(
                input.layers[..printed]
                    .iter()
                    .enumerate()
                    .flat_map(|(k, l)| {
                        let above = (printed - 1 - k) as f64 / n as f64;
                        l.segment_stress
                            .iter()
                            .map(move |x| x * (0.8 + 0.4 * above))
                    })
                    .collect(),
            );
            s
        })
        .collect();
    if let Some(q) = input.quantities.first_mut() {
        q.states = (1..=n)
            .map(|printed| {
                (0..printed)
                    .map(|k| 60.0 * (printed - 1 - k) as f64)
                    .collect()
            })
            .collect();
    }
    input.modes = (1..n)
        .map(|s| {
            let printed = s + 1;
            let displacement = input.layers[..printed]
                .iter()
                .enumerate()
                .flat_map(|(k, l)| {
                    let decay = (-((printed - 1 - k) as f64) / 3.0).exp();
                    let m = l.nodes.len().max(2) - 1;
                    (0..l.nodes.len()).map(move |j| {
                        [
                            0.0,
                            0.0,
                            decay * (std::f64::consts::PI * j as f64 / m as f64).sin(),
                        ]
                    })
                })
                .collect();
            ModeShape {
                state: s,
                blf: 2.0 + 50.0 / printed as f64,
                displacement,
            }
        })
        .collect();
    input.worst_places.clear();
    input
}

fn main() {
    let dir = std::env::args().nth(1);
    println!("| layers = states | segments | robot frames | html bytes | render_html ms |");
    println!("|---|---|---|---|---|");
    for copies in [1, 3, 10, 28] {
        let input = scaled(copies);
        let t0 = Instant::now();
        let html = match render_html(&input) {
            Ok(h) => h,
            Err(e) => {
                eprintln!("error: {e}");
                return;
            }
        };
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let segments: usize = input.layers.iter().map(|l| l.segment_stress.len()).sum();
        println!(
            "| {} | {segments} | {} | {} | {ms:.0} |",
            input.states.len(),
            input.robot.as_ref().map_or(0, |r| r.times.len()),
            html.len()
        );
        if let Some(d) = &dir {
            let path = format!("{d}/report_{}.html", input.layers.len());
            if let Err(e) = std::fs::write(&path, html) {
                eprintln!("cannot write {path}: {e}");
            }
        }
    }
}
