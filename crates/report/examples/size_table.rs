//! Page size and render time of `render_html` as the scene grows, up to the default design's
//! size (113 layers of ~50 segments, every state with per-state stresses, thousands of robot
//! steps). Prints a table; the e2e test can be pointed at the written pages:
//! `cargo run --release -p kappe-report --example size_table -- OUT_DIR`.

use std::time::Instant;

use kappe_report::{ReportInput, demo_input, render_html};

/// The demo with its layer list repeated `copies` times (shifted along y) and the robot
/// trajectory repeated `robot_copies` times: more of the same geometry, as in a longer cap.
fn scaled(copies: usize, robot_copies: usize) -> ReportInput {
    let base = demo_input();
    let mut input = base.clone();
    let dy = 0.5;
    for c in 1..copies {
        for l in &base.layers {
            let mut l = l.clone();
            l.id += i32::try_from(c * 1000).unwrap_or(i32::MAX);
            for p in &mut l.nodes {
                p[1] += dy * c as f64;
            }
            input.layers.push(l);
        }
    }
    input.bed_joints.clear();
    input.print_path = Default::default();
    let n = input.layers.len();
    input.states = (1..=n)
        .map(|printed| {
            let mut s = base.states[(printed - 1) % base.states.len()].clone();
            s.index = printed - 1;
            s.progress = printed as f64 / n as f64;
            s.layers_printed = printed;
            s.segment_stress = Some(
                input.layers[..printed]
                    .iter()
                    .flat_map(|l| l.segment_stress.clone())
                    .collect(),
            );
            s
        })
        .collect();
    if let Some(robot) = input.robot.as_mut() {
        let (t_end, r0) = (robot.times.last().copied().unwrap_or(0.0), robot.clone());
        for c in 1..robot_copies {
            for (i, t) in r0.times.iter().enumerate() {
                robot.times.push(t + t_end * c as f64);
                robot.joints.push(r0.joints[i]);
                robot.poses.push(r0.poses[i].clone());
            }
        }
    }
    input
}

fn main() {
    let dir = std::env::args().nth(1);
    println!("| layers | segments | states | robot steps | html bytes | render_html ms |");
    println!("|---|---|---|---|---|---|");
    for (copies, robot_copies) in [(1, 1), (2, 3), (3, 7)] {
        let input = scaled(copies, robot_copies);
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
            "| {} | {segments} | {} | {} | {} | {ms:.1} |",
            input.layers.len(),
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
