//! A robot that moves along the work: stations along the beams (print, drive, print).
//!
//! **Fewest stations.** Every station prints a contiguous range of layers in print order. Let
//! `reach(s)` be the largest `e` such that one base pose covers layers `s..e`. Reach is monotone
//! (`s ≤ s'` ⇒ `reach(s) ≤ reach(s')`: a pose that covers `s..e` covers `s'..e`), so the greedy
//! rule "from the first unprinted layer, take the pose that covers the most layers" gives the
//! fewest stations: by induction the greedy k-th station ends at or after the k-th station of any
//! cover (interval-cover exchange argument; e.g. Kleinberg & Tardos, *Algorithm Design* §4.1).
//! [`fewest_stations`] is that rule on an abstract `reach`; [`crate::base`]'s search applies it
//! with the reach of the candidate base poses (and shrinks a range if the full plan of a station
//! fails, which can only add stations where the reach estimate was optimistic).
//!
//! **Schedule.** [`station_schedule`] reads a plan's stations back as an ordered schedule: per
//! station its layer range, base pose, print window, and the relocation to the next station
//! (drive distance / speed + a fixed settle time for localisation and levelling). It checks that
//! the ranges are contiguous and ordered (every layer printed once, in print order).

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::frames::Iso;
use crate::plan::Plan;

/// The greedy cover of layers `0..n` by contiguous ranges (see the module docs). `reach(s)` is
/// the end (exclusive) of the longest range one station can print from layer `s`; a value
/// `≤ s` means no station reaches layer `s`, which is returned as the error.
pub fn fewest_stations(
    n: usize,
    mut reach: impl FnMut(usize) -> usize,
) -> Result<Vec<Range<usize>>, usize> {
    let mut out = Vec::new();
    let mut s = 0;
    while s < n {
        let e = reach(s).min(n);
        if e <= s {
            return Err(s);
        }
        out.push(s..e);
        s = e;
    }
    Ok(out)
}

/// How the mobile base relocates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DriveSpec {
    /// Driving speed along the beams, m/s (default 0.1: a slow, guided move beside fresh work).
    pub speed: f64,
    /// Fixed time per relocation for stopping, localising and levelling the base, s (default 60).
    pub settle_time: f64,
}

impl Default for DriveSpec {
    fn default() -> Self {
        DriveSpec {
            speed: 0.1,
            settle_time: 60.0,
        }
    }
}

/// One station of a schedule.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StationEntry {
    /// Station index (print order).
    pub index: usize,
    /// Print-order range of its layers (`start..end`, over the plan's layers).
    pub range: [usize; 2],
    /// Ids of its first and last layer.
    pub layers: [i64; 2],
    /// Base position x, y (m) and yaw (deg) in the world.
    pub base: [f64; 3],
    /// Time of its first and last waypoint in the plan, s.
    pub print_window: [f64; 2],
    /// Distance to drive to the next station, m (0 for the last).
    pub relocation_distance: f64,
    /// Time of that relocation, s (distance / speed + settle time; 0 for the last).
    pub relocation_time: f64,
}

/// The stations of a plan as an ordered schedule.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StationSchedule {
    /// Stations in print order.
    pub stations: Vec<StationEntry>,
    /// Σ time from the first to the last waypoint of each station, s.
    pub station_time: f64,
    /// Σ relocation time, s.
    pub relocation_time: f64,
    /// Total: station time + relocation time, s.
    pub total_time: f64,
}

/// The schedule of `plan`'s stations with relocations timed by `drive`. Errors name a station
/// whose range is empty or whose pose is not rigid, or an invalid drive.
pub fn station_schedule(plan: &Plan, drive: &DriveSpec) -> Result<StationSchedule, String> {
    let speed_ok = drive.speed.is_finite() && drive.speed > 0.0;
    let settle_ok = drive.settle_time.is_finite() && drive.settle_time >= 0.0;
    if !speed_ok || !settle_ok {
        return Err(format!(
            "drive speed {} m/s, settle time {} s: need speed > 0 and settle time ≥ 0",
            drive.speed, drive.settle_time
        ));
    }
    let mut out: Vec<StationEntry> = Vec::with_capacity(plan.stations.len());
    let mut start = 0usize;
    let mut poses: Vec<Iso> = Vec::new();
    for (i, st) in plan.stations.iter().enumerate() {
        let pose = Iso::from_mat4(&st.world_from_base)
            .map_err(|e| format!("station {i}: world_from_base: {e}"))?;
        let (Some(first), Some(last)) = (st.layers.first(), st.layers.last()) else {
            return Err(format!("station {i} prints no layer"));
        };
        let t0 = first.waypoints.first().map_or(0.0, |w| w.t);
        let t1 = last.waypoints.last().map_or(t0, |w| w.t);
        let x = pose.r.x_axis;
        out.push(StationEntry {
            index: i,
            range: [start, start + st.layers.len()],
            layers: [first.layer, last.layer],
            base: [pose.t.x, pose.t.y, x.y.atan2(x.x).to_degrees()],
            print_window: [t0, t1],
            relocation_distance: 0.0,
            relocation_time: 0.0,
        });
        poses.push(pose);
        start += st.layers.len();
    }
    for i in 1..out.len() {
        let d = (poses[i].t - poses[i - 1].t).truncate().length();
        out[i - 1].relocation_distance = d;
        out[i - 1].relocation_time = d / drive.speed + drive.settle_time;
        // Print order: a station starts after the previous one ends.
        if out[i].print_window[0] < out[i - 1].print_window[1] {
            return Err(format!(
                "station {i} starts at {:.1} s, before station {} ends at {:.1} s",
                out[i].print_window[0],
                i - 1,
                out[i - 1].print_window[1]
            ));
        }
    }
    let station_time: f64 = out
        .iter()
        .map(|s| s.print_window[1] - s.print_window[0])
        .sum();
    let relocation_time: f64 = out.iter().map(|s| s.relocation_time).sum();
    Ok(StationSchedule {
        stations: out,
        station_time,
        relocation_time,
        total_time: station_time + relocation_time,
    })
}

/// The station sheet (`stations.md`, issue 28): what the operator needs at each station, in
/// print order: where the base stands (x, y, yaw in the world frame of docs/operator.md), how
/// precisely it must stand (the base tolerance the plan was checked against, and whether this
/// station survives it), the layers it prints, its program files and its time. `programs` is
/// the file prefix of the written programs, or `None` with the reason none were written.
pub fn station_sheet(
    plan: &Plan,
    tolerance: Option<&crate::tolerance::ToleranceReport>,
    programs: Result<&str, &str>,
) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    let _ = writeln!(t, "# Station sheet\n");
    let _ = writeln!(
        t,
        "Where the mobile base stands for each part of the print, in print order. World frame \
         (docs/operator.md in the Kappe repository): origin on the top face of the beams, midway \
         between their inner faces, where the first centre layer (layer 0) meets the beams; x \
         across the span, y along the beams toward the printing front (the start layers, with \
         negative numbers, lie at y < 0), z up. Base x, y: the robot base frame's origin; yaw: \
         the angle of its x axis from world x, counter-clockwise seen from above.\n"
    );
    let offset = plan.mark.station_offset;
    if let Some(why) = &plan.mark.failing_design {
        let _ = writeln!(
            t,
            "**WARNING: the design fails its checks ({why}).** Print only for a test.\n"
        );
    }
    if let Some(k) = plan.mark.resumed_from_layer {
        let _ = writeln!(
            t,
            "**Resumed print** from layer {k}: the layers before it must already stand.\n"
        );
    }
    match tolerance {
        Some(r) => {
            let tol = &r.tolerance;
            let _ = writeln!(
                t,
                "Base placement tolerance checked: ±{:.1} mm in x and y, ±{:.1}° in yaw \
                 ({} poses per station, every {} point(s) re-solved). {}\n",
                tol.position * 1e3,
                tol.yaw_deg,
                r.poses_per_station,
                tol.stride,
                if r.ok() {
                    "Every station survives it: place each base at least this precisely."
                } else {
                    "**The plan does NOT survive it** (see the stations marked FAILS)."
                }
            );
        }
        None => {
            let _ = writeln!(
                t,
                "The base placement tolerance was not checked ([robot.tolerance] check = false): \
                 place the base as precisely as you can.\n"
            );
        }
    }
    let sched = match station_schedule(plan, &DriveSpec::default()) {
        Ok(s) => s,
        Err(e) => {
            let _ = writeln!(t, "The stations cannot be listed: {e}");
            return t;
        }
    };
    let _ = writeln!(
        t,
        "| station | base x [m] | base y [m] | base yaw [°] | tolerance | layers | programs | print time [min] | then drive |"
    );
    let _ = writeln!(t, "|---|---|---|---|---|---|---|---|---|");
    for s in &sched.stations {
        let n = s.index + 1 + offset;
        let tol = match tolerance {
            None => "not checked".to_string(),
            Some(r) => {
                let prefix = format!("station {n},");
                let bad = r.problems.iter().filter(|p| p.starts_with(&prefix)).count();
                let (p, y) = (r.tolerance.position * 1e3, r.tolerance.yaw_deg);
                let verdict = if bad == 0 {
                    format!("±{p:.1} mm, ±{y:.1}°: survives")
                } else {
                    format!("±{p:.1} mm, ±{y:.1}°: FAILS ({bad} problem(s))")
                };
                match r.margins.iter().find(|m| m.station == n) {
                    Some(m) => format!(
                        "{verdict}; takes up to {}±{:.1} mm, ±{:.2}°",
                        if m.at_least { "at least " } else { "" },
                        m.position_m * 1e3,
                        m.yaw_deg
                    ),
                    None => verdict,
                }
            }
        };
        let files = match programs {
            Ok(prefix) => {
                let list: Vec<String> = plan
                    .parts
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.station == s.index)
                    .map(|(i, _)| format!("{prefix}{:02}.script", i + 1))
                    .collect();
                list.join(", ")
            }
            Err(_) => "none written".to_string(),
        };
        let drive = if s.relocation_distance > 0.0 {
            format!(
                "{:.2} m ({:.0} s with settling)",
                s.relocation_distance, s.relocation_time
            )
        } else {
            "done".to_string()
        };
        let _ = writeln!(
            t,
            "| {n} | {:.3} | {:.3} | {:.1} | {tol} | {} to {} | {files} | {:.1} | {drive} |",
            s.base[0],
            s.base[1],
            s.base[2],
            s.layers[0],
            s.layers[1],
            (s.print_window[1] - s.print_window[0]) / 60.0
        );
    }
    if let Err(why) = programs {
        let _ = writeln!(t, "\nNo programs were written: {why}.");
    }
    let _ = writeln!(
        t,
        "\nTotal: {:.1} min at the stations, {:.1} min driving and settling between them.",
        sched.station_time / 60.0,
        sched.relocation_time / 60.0
    );
    t
}
