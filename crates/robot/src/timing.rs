//! One clock for the whole print: every motion of a plan (print moves, the printed layer
//! changes, priming, waits, program changes, station moves) is timed here, and the times go to
//! the waypoints, `trajectory.csv`, the programs (`movep` speeds, `sleep`s) and the schedule
//! ([`layer_times`]).
//!
//! The trajectory is the sequence of *rows* of `trajectory.csv`: each waypoint at its arrival,
//! plus a second row at its departure when the robot holds there. Between consecutive rows a
//! segment either moves (duration `d`, joint velocity `v = Δq/d`) or holds (`v = 0`, fixed
//! duration). The limits are the ones an independent check recomputes from those rows:
//!
//! ```text
//! |v_j|                          ≤ s · v_j,max                (every move segment)
//! |v_{k+1,j} − v_{k,j}| / τ_k    ≤ a_j,max,  τ_k = (d_k + d_{k+1}) / 2   (every row)
//! ```
//!
//! with the robot at rest before a station's first row and after its last (a zero-length rest
//! segment). Each move starts at its design duration `L/v_print`, lengthened to meet the speed
//! limit; then rows that break the acceleration limit stretch their neighbouring moves
//! (both by √r, or the only movable one by r, where r is the excess ratio; either removes the
//! excess at that row) in alternating forward and backward sweeps until every row holds. Slower
//! moves never raise a joint speed, so the first step's speed limits still hold. Hand-written: a
//! time-optimal parameterisation (TOTG, Ruckig) would need a continuous path, while the
//! controller and the check see exactly these rows.
//!
//! Where a move ends up slower than 98 % of the design speed the flow follows it
//! (`Waypoint::speed`) and the plan lists the range in [`Plan::slowdowns`].

use serde::{Deserialize, Serialize};

use crate::error::RobotError;
use crate::plan::Plan;
pub use crate::plan::Slowdown;

/// A move slower than 98 % of the design speed is reported.
pub const SLOWDOWN_REPORT: f64 = 0.98;

/// When one layer is printed, on the plan's clock.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LayerTime {
    pub station: usize,
    pub layer: i64,
    /// Arrival at the layer's first target (s).
    pub start: f64,
    /// Arrival at its last target (s).
    pub end: f64,
    /// Scheduled wait after the layer (s).
    pub wait: f64,
    /// The whole pause after the layer (wait, program change, re-priming) (s).
    pub pause: f64,
}

/// A wait after a layer, e.g. from the time-dependent schedule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LayerWait {
    pub layer: i64,
    /// Seconds.
    pub wait: f64,
}

/// Per-layer start and end times of a timed plan (the schedule's input).
pub fn layer_times(plan: &Plan) -> Vec<LayerTime> {
    let mut out = Vec::new();
    for (si, st) in plan.stations.iter().enumerate() {
        for l in &st.layers {
            let (Some(a), Some(b)) = (l.waypoints.first(), l.waypoints.last()) else {
                continue;
            };
            out.push(LayerTime {
                station: si,
                layer: l.layer,
                start: a.t,
                end: b.t,
                wait: l.wait,
                pause: b.hold,
            });
        }
    }
    out
}

/// The same plan re-timed with per-layer `waits` (e.g. from the time-dependent schedule, which
/// needs [`layer_times`] first): the joint path and programs' cuts are kept, every time and
/// speed follows the new pauses, and the result is re-checked.
pub fn retime(plan: &Plan, waits: &[LayerWait]) -> Result<Plan, RobotError> {
    let mut p = plan.clone();
    apply_timing(&mut p, Some(waits))?;
    let rep = crate::check::check_plan(&p);
    if !rep.problems.is_empty() {
        return Err(RobotError::Verification(rep.problems));
    }
    p.certified = Some(crate::plan::CertifiedClearance::of(&rep));
    Ok(p)
}

/// Duration of a straight move of `dist` at cruise speed `v` with acceleration `a` from rest to
/// rest (trapezoidal, or triangular when too short to reach `v`).
pub fn trapezoid_time(dist: f64, v: f64, a: f64) -> f64 {
    if dist <= 0.0 {
        return 0.0;
    }
    if dist >= v * v / a {
        dist / v + v / a
    } else {
        2.0 * (dist / a).sqrt()
    }
}

#[derive(Clone, Copy, Debug)]
struct Seg {
    /// Duration (s).
    d: f64,
    /// Shortest allowed duration (design speed and joint speed limits).
    d_min: f64,
    /// Duration at the design speed.
    d_design: f64,
    /// Holds (and rests) are fixed; moves stretch.
    fixed: bool,
    dq: [f64; 6],
    /// Joint whose speed limit set `d_min`, if any.
    speed_joint: Option<usize>,
    /// (layer slot, waypoint slot) reached by this move.
    to: Option<(usize, usize)>,
}

impl Seg {
    fn v(&self, j: usize) -> f64 {
        if self.fixed || self.d <= 0.0 {
            0.0
        } else {
            self.dq[j] / self.d
        }
    }
}

fn accel_ratio(a: &Seg, b: &Seg, amax: &[f64; 6]) -> f64 {
    let tau = 0.5 * (a.d + b.d);
    if tau <= 0.0 {
        return 0.0;
    }
    (0..6)
        .map(|j| (b.v(j) - a.v(j)).abs() / (tau * amax[j]))
        .fold(0.0, f64::max)
}

/// Stretch moves until every row meets the acceleration limits.
fn fix_accelerations(segs: &mut [Seg], amax: &[f64; 6]) -> Result<(), RobotError> {
    let n = segs.len();
    if n < 2 {
        return Ok(());
    }
    // 1e-9: relative margin so that round-off never leaves a row a hair above its limit.
    let grow = 1.0 + 1e-9;
    let fix = |segs: &mut [Seg], k: usize| -> bool {
        let r = accel_ratio(&segs[k], &segs[k + 1], amax);
        if r <= 1.0 {
            return false;
        }
        match (segs[k].fixed, segs[k + 1].fixed) {
            (false, false) => {
                let f = r.sqrt() * grow;
                segs[k].d *= f;
                segs[k + 1].d *= f;
            }
            (true, false) => segs[k + 1].d *= r * grow,
            (false, true) => segs[k].d *= r * grow,
            (true, true) => return false,
        }
        true
    };
    for _ in 0..10_000 {
        let mut changed = false;
        for k in 0..n - 1 {
            changed |= fix(segs, k);
        }
        for k in (0..n - 1).rev() {
            changed |= fix(segs, k);
        }
        if !changed {
            return Ok(());
        }
    }
    Err(RobotError::Verification(vec![
        "timing: the acceleration limits could not be met after 10 000 sweeps".into(),
    ]))
}

/// Time the whole plan: holds at the waypoints (priming, waits, program changes), move
/// durations, arrival times, speeds, slowdowns and the summary times. `waits` (per layer id)
/// override the minimum layer time of the options.
pub fn apply_timing(plan: &mut Plan, waits: Option<&[LayerWait]>) -> Result<(), RobotError> {
    let opts = plan.options.clone();
    let vmax = opts.limits.max_speed();
    let amax = opts.limits.max_acceleration;
    for j in 0..6 {
        if !(vmax[j].is_finite() && vmax[j] > 0.0 && amax[j].is_finite() && amax[j] > 0.0) {
            return Err(RobotError::invalid(
                "limits",
                format!(
                    "joint {}: speed {} °/s, acceleration {} rad/s²: must be finite and > 0",
                    j + 1,
                    opts.limits.max_speed_deg_s[j],
                    amax[j]
                ),
            ));
        }
    }
    let given: Option<std::collections::HashMap<i64, f64>> = match waits {
        Some(w) => {
            let mut m = std::collections::HashMap::new();
            for lw in w {
                if !(lw.wait.is_finite() && lw.wait >= 0.0) {
                    return Err(RobotError::invalid(
                        format!("wait of layer {}", lw.layer),
                        format!("{} s: must be finite and ≥ 0", lw.wait),
                    ));
                }
                if !plan
                    .stations
                    .iter()
                    .flat_map(|s| &s.layers)
                    .any(|l| l.layer == lw.layer)
                {
                    return Err(RobotError::invalid(
                        "waits",
                        format!("layer {} is not in the plan", lw.layer),
                    ));
                }
                m.insert(lw.layer, lw.wait);
            }
            Some(m)
        }
        None => None,
    };
    let min_layer = opts.waits.min_layer_time;
    if !(min_layer.is_finite() && min_layer >= 0.0) {
        return Err(RobotError::invalid(
            "waits.min_layer_time",
            format!("{min_layer} s: must be finite and ≥ 0"),
        ));
    }
    // Scheduled waits: given, or from the minimum layer time (iterated, because a pause relaxes
    // the deceleration before it and so shortens the layer; waits only grow, so it settles).
    for l in plan.stations.iter_mut().flat_map(|s| &mut s.layers) {
        l.wait = given
            .as_ref()
            .map_or(0.0, |m| m.get(&l.layer).copied().unwrap_or(0.0));
    }
    for _ in 0..20 {
        time_all(plan, &vmax, &amax)?;
        if given.is_some() || min_layer <= 0.0 {
            return Ok(());
        }
        let mut grew = false;
        for st in &mut plan.stations {
            let n = st.layers.len();
            for i in 0..n {
                if i + 1 == n {
                    continue; // nothing follows the station's last layer on this station
                }
                let start = st.layers[i].waypoints.first().map_or(0.0, |w| w.t);
                let next = st.layers[i + 1].waypoints.first().map_or(0.0, |w| w.t);
                let short = min_layer - (next - start);
                // 1e-9 s: round-off of the sums of durations.
                if short > 1e-9 {
                    st.layers[i].wait += short;
                    grew = true;
                }
            }
        }
        if !grew {
            return Ok(());
        }
    }
    time_all(plan, &vmax, &amax)
}

fn time_all(plan: &mut Plan, vmax: &[f64; 6], amax: &[f64; 6]) -> Result<(), RobotError> {
    let opts = plan.options.clone();
    let prog = &opts.program;
    let pump = &opts.pump;
    let v_design = opts.print_speed;
    let approach = trapezoid_time(
        prog.approach_distance,
        prog.approach_speed,
        prog.tool_acceleration,
    );
    // Pauses: scheduled waits and program changes inside a station.
    let part_ends: std::collections::HashSet<(usize, usize)> = plan
        .parts
        .iter()
        .filter(|p| !p.ends_station)
        .map(|p| (p.station, p.last))
        .collect();
    let mut t = 0.0;
    let mut slowdowns = Vec::new();
    let (mut print_time, mut max_v, mut max_a) = (0.0, 0.0f64, 0.0f64);
    let n_st = plan.stations.len();
    for si in 0..n_st {
        if si > 0 {
            t += opts.station_change_time;
        }
        t += approach;
        let st = &mut plan.stations[si];
        // Holds.
        let n_l = st.layers.len();
        for (li, l) in st.layers.iter_mut().enumerate() {
            for w in &mut l.waypoints {
                w.hold = 0.0;
            }
            let mut pause = l.wait;
            if part_ends.contains(&(si, li)) {
                pause += prog.program_switch_time;
            }
            if li + 1 < n_l && pause > 0.0 && pump.pause == crate::setup::PauseMode::Stop {
                pause += pump.prime_dwell;
            }
            if li + 1 < n_l
                && let Some(w) = l.waypoints.last_mut()
            {
                w.hold = pause;
            }
        }
        if let Some(w) = st.layers.first_mut().and_then(|l| l.waypoints.first_mut()) {
            w.hold += pump.prime_dwell;
        }
        // Segments: rest, then per waypoint (move into it, hold at it), then rest.
        let rest = Seg {
            d: 0.0,
            d_min: 0.0,
            d_design: 0.0,
            fixed: true,
            dq: [0.0; 6],
            speed_joint: None,
            to: None,
        };
        let mut segs = vec![rest];
        let mut prev: Option<([f64; 6], [f64; 3])> = None;
        for (li, l) in st.layers.iter().enumerate() {
            for (wi, w) in l.waypoints.iter().enumerate() {
                if let Some((q0, p0)) = prev {
                    let len = ((w.position[0] - p0[0]).powi(2)
                        + (w.position[1] - p0[1]).powi(2)
                        + (w.position[2] - p0[2]).powi(2))
                    .sqrt();
                    let dq: [f64; 6] = std::array::from_fn(|j| w.q[j] - q0[j]);
                    let d_design = len / v_design;
                    let mut d_min = d_design.max(1e-3);
                    let mut speed_joint = None;
                    for j in 0..6 {
                        let dj = dq[j].abs() / (opts.speed_fraction * vmax[j]);
                        if dj > d_min {
                            d_min = dj;
                            speed_joint = Some(j);
                        }
                    }
                    segs.push(Seg {
                        d: d_min,
                        d_min,
                        d_design,
                        fixed: false,
                        dq,
                        speed_joint,
                        to: Some((li, wi)),
                    });
                }
                if w.hold > 0.0 {
                    segs.push(Seg {
                        d: w.hold,
                        d_min: w.hold,
                        d_design: w.hold,
                        ..rest
                    });
                }
                prev = Some((w.q, w.position));
            }
        }
        segs.push(rest);
        fix_accelerations(&mut segs, amax)?;
        for k in 0..segs.len() - 1 {
            max_a = max_a.max(accel_ratio(&segs[k], &segs[k + 1], amax));
        }
        // Times, speeds, slowdowns.
        let first = st.layers.first().and_then(|l| l.waypoints.first());
        let hold0 = first.map_or(0.0, |w| w.hold);
        if let Some(l) = st.layers.first_mut()
            && let Some(w) = l.waypoints.first_mut()
        {
            w.t = t;
            w.speed = 0.0;
        }
        t += hold0;
        let mut open: Option<Slowdown> = None;
        for s in &segs[1..segs.len() - 1] {
            let Some((li, wi)) = s.to else {
                continue; // holds are added with their waypoint
            };
            t += s.d;
            print_time += s.d;
            let speed = if s.d_design > 0.0 {
                s.d_design / s.d
            } else {
                1.0
            };
            for j in 0..6 {
                max_v = max_v.max((s.dq[j] / s.d).abs() / vmax[j]);
            }
            let l = &mut st.layers[li];
            let layer_id = l.layer;
            let w = &mut l.waypoints[wi];
            w.t = t;
            w.speed = speed * v_design;
            let at = (layer_id, w.index);
            t += w.hold;
            if speed < SLOWDOWN_REPORT {
                let reason = match s.speed_joint {
                    Some(j) if s.d <= s.d_min * (1.0 + 1e-6) => {
                        format!("joint speed (joint {})", j + 1)
                    }
                    _ => "joint acceleration".to_string(),
                };
                match &mut open {
                    Some(o) if o.reason == reason => {
                        o.to = at;
                        o.min_speed_ratio = o.min_speed_ratio.min(speed);
                    }
                    _ => {
                        if let Some(o) = open.take() {
                            slowdowns.push(o);
                        }
                        open = Some(Slowdown {
                            station: si,
                            from: at,
                            to: at,
                            min_speed_ratio: speed,
                            reason,
                        });
                    }
                }
            } else if let Some(o) = open.take() {
                slowdowns.push(o);
            }
        }
        if let Some(o) = open.take() {
            slowdowns.push(o);
        }
    }
    plan.slowdowns = slowdowns;
    plan.print_time = print_time;
    plan.max_speed_ratio = max_v;
    plan.max_acceleration_ratio = max_a;
    // One clock: 0 is the start of the first program (its approach from the safe pose), so the
    // total is the arrival at the last target, which is also the end of the last layer in
    // `layer_times` and the last row of trajectory.csv (the final retract comes after it).
    let last = plan
        .stations
        .last()
        .and_then(|s| s.layers.last())
        .and_then(|l| l.waypoints.last())
        .map_or(0.0, |w| w.t);
    plan.total_time = last;
    for st in &mut plan.stations {
        for l in &mut st.layers {
            let mut m = 0.0f64;
            for k in 1..l.waypoints.len() {
                let (a, b) = (&l.waypoints[k - 1], &l.waypoints[k]);
                let dt = b.t - a.t - a.hold;
                if dt > 0.0 {
                    for j in 0..6 {
                        m = m.max((b.q[j] - a.q[j]).abs() / dt / vmax[j]);
                    }
                }
            }
            l.max_speed_ratio = m;
        }
    }
    Ok(())
}
