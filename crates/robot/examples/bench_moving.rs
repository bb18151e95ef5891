//! Moving base against stations (issue 27) as a table: `cargo run --release -p kappe-robot
//! --example bench_moving`. For two synthetic cap paths (`kappe_robot::synthetic::cap_path`):
//!
//! - the default cap: 0.8 m span, 0.2 m rise, 25° tilt, 8 mm layers, 120 layers × 30 points
//!   (the `bench_table` cap);
//! - a 4 m bay: 1.5 m span, 0.375 m rise (the same rise/span), 25°, 8 mm layers, 453 layers
//!   (4 m of bay: 453 · 0.008 / cos 25°) × `KAPPE_BAY_POINTS` points (default 45, Δs ≈ 4 cm),
//!
//! each on two beams under the print (0.12 × 0.24 m, 5 cm overrun, as `kappe design`), it
//! plans the station plan (`plan_print`, base search) and the moving plan (`plan_moving`) and
//! prints planning time, print time (the plan's clock at the last target), the layer ages (time
//! from a layer's start to the next layer's start: min, max, and the spread max − min, which the
//! station seams set), the tracking simulation's largest deviation (default errors) and the lint
//! of the tracking programs, and whether every 5th target stays reachable with the base off by
//! ±10 mm and ±1° (`check_moving_tolerance`). Targets: moving ≤ 2 × stations; the default cap ≤ 2 s.

use std::time::Instant;

use kappe_robot::setup::beams;
use kappe_robot::synthetic::cap_path;
use kappe_robot::*;

struct Case {
    name: &'static str,
    span: f64,
    rise: f64,
    layers: usize,
    points: usize,
}

fn ages(times: &[LayerTime]) -> (f64, f64) {
    let a: Vec<f64> = times.windows(2).map(|w| w[1].start - w[0].start).collect();
    let lo = a.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = a.iter().copied().fold(0.0, f64::max);
    (lo, hi)
}

fn main() {
    let bay_points: usize = std::env::var("KAPPE_BAY_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(45);
    let cases = [
        Case {
            name: "default cap (0.8 m span, 120 layers × 30 points)",
            span: 0.8,
            rise: 0.2,
            layers: 120,
            points: 30,
        },
        Case {
            name: "4 m bay (1.5 m span, 453 layers)",
            span: 1.5,
            rise: 0.375,
            layers: 453,
            points: bay_points,
        },
    ];
    println!(
        "| path | plan | planning time | print time | layer age min / max / spread | stations | tracking: max deviation (where) | lint | base ±10 mm, ±1° |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for c in &cases {
        let layers = cap_path(c.span, c.rise, 25.0, 0.008, c.layers, c.points);
        let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in layers.iter().flat_map(|l| &l.points) {
            y0 = y0.min(p.position[1]);
            y1 = y1.max(p.position[1]);
        }
        let setup = RobotSetup {
            obstacles: beams(c.span, 0.12, 0.24, y0 - 0.05, y1 + 0.05),
            ..RobotSetup::default()
        };
        let opts = PlanOptions::default();
        let t = Instant::now();
        let st = plan_print(&layers, &setup, &opts);
        let t_st = t.elapsed().as_secs_f64();
        match &st {
            Ok(p) => {
                let (lo, hi) = ages(&layer_times(p));
                println!(
                    "| {} | stations | {t_st:.2} s | {:.0} s | {lo:.1} / {hi:.1} / {:.1} s | {} | — | — |",
                    c.name,
                    p.total_time,
                    hi - lo,
                    p.stations.len()
                );
            }
            Err(e) => println!(
                "| {} | stations | {t_st:.2} s | failed: {e} | | | | |",
                c.name
            ),
        }
        let t = Instant::now();
        let mv = plan_moving(&layers, &setup, &opts, &MovingBase::default(), None);
        let t_mv = t.elapsed().as_secs_f64();
        match &mv {
            Ok(m) => {
                let (lo, hi) = ages(&layer_times(&m.plan));
                let sim =
                    simulate_tracking(m, &TrackingErrors::default(), &TrackingTolerance::default());
                let sim = match sim {
                    Ok(r) => format!(
                        "{:.1} mm (layer {}, point {}, t = {:.0} s); rel. across {:.2} mm, axial {:.2} mm; base off ≤ {:.1} mm, margin {:.0} mm; {}",
                        r.max_deviation * 1e3,
                        r.at.0,
                        r.at.1,
                        r.at.2,
                        r.max_relative_across * 1e3,
                        r.max_relative_axial * 1e3,
                        r.max_base_offset * 1e3,
                        r.reach_margin.unwrap_or(0.0) * 1e3,
                        if r.problems.is_empty() {
                            "within tolerance".to_string()
                        } else {
                            r.problems.join("; ")
                        }
                    ),
                    Err(e) => e.to_string(),
                };
                let t = Instant::now();
                let tol = check_moving_tolerance(
                    m,
                    &kappe_robot::tolerance::BaseTolerance {
                        stride: 5,
                        ..Default::default()
                    },
                );
                let tol = format!(
                    "{} ({} waypoints × 9 poses, {:.1} s)",
                    if tol.ok() {
                        "holds".to_string()
                    } else {
                        tol.problems.join("; ")
                    },
                    tol.waypoints_checked / 9,
                    t.elapsed().as_secs_f64()
                );
                let lint = match tracking_program_files(m, &ConveyorOptions::default(), "part_") {
                    Ok(files) => {
                        let bad = files
                            .iter()
                            .filter(|(f, _)| {
                                !lint_tracking(
                                    &f.text,
                                    opts.program.max_moves_per_program,
                                    &opts.limits.position(),
                                )
                                .ok()
                            })
                            .count();
                        format!("{} files, {bad} rejected", files.len())
                    }
                    Err(e) => e.to_string(),
                };
                println!(
                    "| {} | moving (lead {:.2} m, base ≤ {:.2} mm/s) | {t_mv:.2} s ({:.2} × stations) | {:.0} s | {lo:.1} / {hi:.1} / {:.1} s | 0 | {sim} | {lint} | {tol} |",
                    c.name,
                    m.lead,
                    m.check.max_base_speed * 1e3,
                    t_mv / t_st,
                    m.plan.total_time,
                    hi - lo,
                );
            }
            Err(e) => println!(
                "| {} | moving | {t_mv:.2} s | failed: {e} | | | | |",
                c.name
            ),
        }
    }
}
