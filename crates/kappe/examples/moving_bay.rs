//! The 1.5 m × 4 m bay of `kappe init --kind moving` (issue 27) printed from stations and in one
//! take with the base moving, as a table:
//! `cargo run --release -p kappe --example moving_bay [-- default]`.
//!
//! The bay is the template itself (`kappe::commands::templates::MOVING_TOML`), form-found by
//! `kappe::design_cap`; both plans get the same layers, cell and options
//! (`kappe::robot_plan::robot_inputs`, what `kappe design` plans with) and the design's minimum
//! layer time (no extra waits). It prints, per plan: planning time (the planner call alone,
//! best of `KAPPE_REPS`, default 1), stations, print time (the plan's clock at the end of the
//! last layer), the layer age when the next layer starts (`start[k+1] − start[k]`: min, max and
//! spread over all layers) and the same at the station plan's seams (the layers after which the
//! base relocates), for both plans at those same layers. Targets (issue 27): moving planning ≤
//! 2 × the station plan's; with `default`, the default cap's moving planning ≤ 2 s.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

fn ages(times: &[kappe_robot::LayerTime]) -> Vec<f64> {
    times.windows(2).map(|w| w[1].start - w[0].start).collect()
}

fn span(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let reps: usize = std::env::var("KAPPE_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1)
        .max(1);
    let default = std::env::args().nth(1).as_deref() == Some("default");
    let mut design = kappe::Design::from_toml_str(kappe::commands::templates::MOVING_TOML)?;
    let base = match &design.robot.base {
        kappe_robot::BaseMode::Moving(m) => m.clone(),
        kappe_robot::BaseMode::Stations => return Err("the template's base is not moving".into()),
    };
    if default {
        let d = kappe::Design::default();
        design.cap = d.cap;
        design.robot.beams = d.robot.beams;
    }
    let load = load_average();
    let t = Instant::now();
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
    let t_form = t.elapsed().as_secs_f64();
    let (setup, opts) = kappe::robot_plan::robot_inputs(&cap);
    let layers = kappe::robot_plan::print_layers(&cap.path);
    let targets: usize = layers.iter().map(|l| l.points.len()).sum();
    println!(
        "{}: span {} m, length {} m, {} layers, {targets} targets; form-finding {t_form:.1} s; load {load}",
        design.name,
        design.cap.span,
        design.cap.length,
        layers.len()
    );

    let mut best = (f64::INFINITY, f64::INFINITY);
    // Process CPU seconds of the last repetition (the planners are parallel; on a shared
    // machine the wall time depends on the load, the CPU time less so).
    let mut cpu = (f64::NAN, f64::NAN);
    let cpu_now = || cpu_seconds().unwrap_or(f64::NAN);
    let mut st = None;
    let mut mv = None;
    for _ in 0..reps {
        let (t, c) = (Instant::now(), cpu_now());
        st = Some(kappe_robot::plan_print_with_waits(
            &layers, &setup, &opts, None,
        )?);
        best.0 = best.0.min(t.elapsed().as_secs_f64());
        cpu.0 = cpu_now() - c;
        let (t, c) = (Instant::now(), cpu_now());
        mv = Some(kappe_robot::plan_moving(
            &layers, &setup, &opts, &base, None,
        )?);
        best.1 = best.1.min(t.elapsed().as_secs_f64());
        cpu.1 = cpu_now() - c;
    }
    let (Some(st), Some(mv)) = (st, mv) else {
        return Err("no plan".into());
    };
    let ts = kappe_robot::layer_times(&st);
    let tm = kappe_robot::layer_times(&mv.plan);
    let (a_s, a_m) = (ages(&ts), ages(&tm));
    // The seams: layer k is the last of its station.
    let seams: Vec<usize> = ts
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0].station != w[1].station)
        .map(|(k, _)| k)
        .collect();
    let end = |t: &[kappe_robot::LayerTime]| t.last().map_or(0.0, |l| l.end);
    println!(
        "| plan | planning, wall (best of {reps}) / CPU | stations | print time | layer age min / max / spread | age at the {} station seams min / max |",
        seams.len()
    );
    println!("|---|---|---|---|---|---|");
    for (name, t_plan, c_plan, stations, times, a) in [
        ("stations", best.0, cpu.0, st.stations.len(), &ts, &a_s),
        ("moving", best.1, cpu.1, mv.plan.stations.len(), &tm, &a_m),
    ] {
        let (lo, hi) = span(a.iter().copied());
        let (slo, shi) = span(seams.iter().filter_map(|&k| a.get(k).copied()));
        println!(
            "| {name} | {t_plan:.2} s / {c_plan:.2} s | {stations} | {:.0} s ({:.1} min) | {lo:.1} / {hi:.1} / {:.1} s | {} |",
            end(times),
            end(times) / 60.0,
            hi - lo,
            if seams.is_empty() {
                "—".to_string()
            } else {
                format!("{slo:.1} / {shi:.1} s")
            }
        );
    }
    let ratio = best.1 / best.0;
    println!(
        "moving / stations planning time: {ratio:.2} (target ≤ 2){}; lead {:.2} m, reach margin {} mm",
        if default {
            format!(
                "; default cap moving planning {:.2} s (target ≤ 2 s)",
                best.1
            )
        } else {
            String::new()
        },
        mv.lead,
        mv.reach_margin
            .map_or("—".to_string(), |m| format!("{:.0}", m * 1e3))
    );
    Ok(())
}
