//! Controller-sized URScript programs (robot.md §4; issue 13): the print is cut, at layer
//! boundaries, into standalone programs of at most `max_moves_per_program` motion targets. Each
//! is a complete program (`def … end` and the call, TCP, payload, I/O set-up, an approach move)
//! and an index lists them in order with the station (base pose) each needs.
//!
//! The bead is continuous within a station: the pump is enabled once, at the station's first
//! target, primed for `prime_dwell`, and switched off after the station's last target. The flow
//! set-point (an analog output, proportional to lw·lh·v) is set wherever the planned speed
//! changes. Pauses (layer waits, the change to the next program file inside a station) keep the
//! pump primed at the hold output, or stop it and prime again, as configured.
//!
//! Hand-written: no crate writes URScript.

use serde::Serialize;

use crate::error::RobotError;
use crate::frames::Iso;
use crate::kinematics::{UR10E, approach_config};
use crate::plan::Plan;
pub use crate::plan::ProgramPart;
use crate::setup::{AnalogDomain, PauseMode};

/// Targets of a part: approach `movej` + `movel` and the other points (starting a station), or
/// a `movej` to where the previous part stopped and every point (continuing); + the retract.
fn part_targets(points: usize, starts: bool, ends: bool) -> usize {
    let body = if starts { 2 + points - 1 } else { 1 + points };
    body + usize::from(ends)
}

/// Layer ranges `first..end` of a station's files filled greedily up to `cap` targets each;
/// `Err(slot)` names a layer that does not fit in one file.
fn fill(sizes: &[usize], cap: usize) -> Result<Vec<(usize, usize)>, usize> {
    let n = sizes.len();
    let mut out = Vec::new();
    let mut first = 0usize;
    while first < n {
        let starts = first == 0;
        let (mut end, mut points) = (first, 0usize);
        while end < n {
            let p = points + sizes[end];
            if part_targets(p, starts, end + 1 == n) > cap {
                break;
            }
            points = p;
            end += 1;
        }
        if end == first {
            return Err(first);
        }
        out.push((first, end));
        first = end;
    }
    Ok(out)
}

/// Among the cuts of `sizes` into exactly `k` files of at most `cap` targets, one whose
/// smallest file is largest (DP over the cut points, O(k·n²)); None if there is none.
fn widest_smallest(sizes: &[usize], k: usize, cap: usize) -> Option<Vec<(usize, usize)>> {
    let n = sizes.len();
    let mut pre = vec![0usize; n + 1];
    for (i, s) in sizes.iter().enumerate() {
        pre[i + 1] = pre[i] + s;
    }
    let cost = |a: usize, b: usize| part_targets(pre[b] - pre[a], a == 0, b == n);
    // best[j][b]: the largest smallest file cutting layers 0..b into j files; from[j][b] the
    // start of the last of them.
    let mut best = vec![vec![None::<usize>; n + 1]; k + 1];
    let mut from = vec![vec![0usize; n + 1]; k + 1];
    best[0][0] = Some(usize::MAX);
    for j in 1..=k {
        for b in j..=n {
            for a in (j - 1)..b {
                let Some(prev) = best[j - 1][a] else { continue };
                let c = cost(a, b);
                if c > cap {
                    continue;
                }
                let v = prev.min(c);
                if best[j][b].is_none_or(|x| v > x) {
                    best[j][b] = Some(v);
                    from[j][b] = a;
                }
            }
        }
    }
    best[k][n]?;
    let mut cut = Vec::with_capacity(k);
    let mut b = n;
    for j in (1..=k).rev() {
        let a = from[j][b];
        cut.push((a, b));
        b = a;
    }
    cut.reverse();
    Some(cut)
}

/// Cut the plan into program parts: whole layers, at most `max_moves_per_program` targets each,
/// in the fewest files per station, balanced (linear partition): among the cuts into that many
/// files, the largest file is as small as possible, and then the smallest as large as possible
/// (so no station ends with a small file when an even cut exists). Greedy filling up to a cap
/// C gives the fewest files for C, and that count only falls as C grows, so the smallest C that
/// needs no more files than the limit does is found by bisection; a DP then picks, among the
/// cuts within C, the one with the largest smallest file.
pub fn split_parts(plan: &Plan) -> Result<Vec<ProgramPart>, RobotError> {
    let max = plan.options.program.max_moves_per_program;
    let mut parts = Vec::new();
    for (si, st) in plan.stations.iter().enumerate() {
        let sizes: Vec<usize> = st.layers.iter().map(|l| l.waypoints.len()).collect();
        let fewest = fill(&sizes, max).map_err(|slot| {
            let l = &st.layers[slot];
            let need = part_targets(l.waypoints.len(), true, true);
            RobotError::invalid(
                "program.max_moves_per_program",
                format!(
                    "{max} targets per program is below what layer {} needs ({} points + {} approach/retract moves); raise it to at least {need}",
                    l.layer,
                    l.waypoints.len(),
                    need - l.waypoints.len(),
                ),
            )
        })?;
        // fill(max) succeeded, so the smallest feasible cap lies in (lo, hi].
        let (mut lo, mut hi) = (0usize, max);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            match fill(&sizes, mid) {
                Ok(c) if c.len() <= fewest.len() => hi = mid,
                _ => lo = mid,
            }
        }
        let cut = widest_smallest(&sizes, fewest.len(), hi).unwrap_or(fewest);
        let n = sizes.len();
        for (first, end) in cut {
            let points: usize = sizes[first..end].iter().sum();
            parts.push(ProgramPart {
                station: si,
                first,
                last: end - 1,
                first_layer: st.layers[first].layer,
                last_layer: st.layers[end - 1].layer,
                targets: part_targets(points, first == 0, end == n),
                starts_station: first == 0,
                ends_station: end == n,
            });
        }
    }
    Ok(parts)
}

fn joints(q: &[f64; 6]) -> String {
    let v: Vec<String> = q.iter().map(|x| format!("{x:.9}")).collect();
    format!("[{}]", v.join(", "))
}

fn pose(t: &Iso) -> String {
    let r = t.rotation_vector();
    format!(
        "p[{:.9}, {:.9}, {:.9}, {:.9}, {:.9}, {:.9}]",
        t.t.x, t.t.y, t.t.z, r.x, r.y, r.z
    )
}

fn num(x: f64) -> String {
    // Six decimals: 1 µm, 1 µs, 1e-6 of the output range.
    let s = format!("{x:.6}");
    if s == "-0.000000" {
        "0.000000".into()
    } else {
        s
    }
}

/// One program file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProgramFile {
    /// File name (`<prefix>NN.script`).
    pub name: String,
    pub part: ProgramPart,
    /// `world_from_base` of the station, row-major.
    pub world_from_base: crate::frames::Mat4,
    /// Plan times (s): arrival at the first and last target.
    pub start: f64,
    pub end: f64,
    /// The plan's mark (failing design, resumed print), repeated in the file's title.
    pub mark: crate::plan::PlanMark,
    #[serde(skip)]
    pub text: String,
}

/// The flow set-point (output ratio) for tool speed `v` (m/s).
pub fn flow_output(plan: &Plan, v: f64) -> f64 {
    let o = &plan.options;
    let q = 4.0 * o.bead_radius * o.bead_offset.abs() * v;
    o.pump.output_for_flow(q)
}

/// All program files of a timed plan, named `<prefix>01.script`, … in order.
pub fn program_files(plan: &Plan, prefix: &str) -> Result<Vec<ProgramFile>, RobotError> {
    let o = &plan.options;
    let pr = &o.program;
    let pump = &o.pump;
    let tool = Iso::from_mat4(&plan.flange_from_tcp)
        .map_err(|e| RobotError::invalid("flange_from_tcp", e))?;
    let n_parts = plan.parts.len();
    let mut files = Vec::new();
    let aout = |v: f64| format!("set_standard_analog_out({}, {})", pump.flow_output, num(v));
    let enable = |on: bool| pump.enable_output.map(|e| e.call(on));
    for (pi, part) in plan.parts.iter().enumerate() {
        let st = plan
            .stations
            .get(part.station)
            .ok_or_else(|| RobotError::invalid("parts", "names a station the plan lacks"))?;
        let layers = st
            .layers
            .get(part.first..=part.last)
            .ok_or_else(|| RobotError::invalid("parts", "names layers the station lacks"))?;
        let fname = format!("{prefix}{:02}.script", pi + 1);
        let func = format!("kappe_part_{:02}{}", pi + 1, plan.mark.function_suffix());
        let mut w = String::new();
        let mut line = |s: &str| {
            w.push_str("  ");
            w.push_str(s);
            w.push('\n');
        };
        let b = &st.world_from_base;
        let mut targets = 0usize;
        let first_wp = layers
            .first()
            .and_then(|l| l.waypoints.first())
            .ok_or_else(|| RobotError::invalid("parts", "an empty layer"))?;
        let last_wp = layers
            .last()
            .and_then(|l| l.waypoints.last())
            .ok_or_else(|| RobotError::invalid("parts", "an empty layer"))?;
        line(&format!("set_tcp({})", pose(&tool)));
        line(&format!(
            "set_payload({}, [{}, {}, {}])",
            num(pr.payload_mass),
            num(pr.payload_cog[0]),
            num(pr.payload_cog[1]),
            num(pr.payload_cog[2])
        ));
        let domain = match pump.flow_domain {
            AnalogDomain::Current => 0,
            AnalogDomain::Voltage => 1,
        };
        line(&format!(
            "set_analog_outputdomain({}, {domain})",
            pump.flow_output
        ));
        let mut flow_now: f64;
        if part.starts_station {
            line(&aout(0.0));
            if let Some(s) = enable(false) {
                line(&s);
            }
            let qa = approach_config(
                &first_wp.q,
                &tool,
                pr.approach_distance,
                &plan.options.limits.position(),
            )?;
            line(&format!(
                "# approach: safe pose {} m behind the first target, then down to it",
                num(pr.approach_distance)
            ));
            line(&format!(
                "movej({}, a={}, v={})",
                joints(&qa),
                num(pr.joint_acceleration),
                num(pr.joint_speed)
            ));
            line(&format!(
                "movel({}, a={}, v={})",
                pose(&UR10E.fk(&first_wp.q).mul(&tool)),
                num(pr.tool_acceleration),
                num(pr.approach_speed)
            ));
            targets += 2;
            let v1 = layers
                .iter()
                .flat_map(|l| &l.waypoints)
                .nth(1)
                .map_or(o.print_speed, |w| w.speed);
            flow_now = flow_output(plan, v1);
            line(&format!(
                "# prime: pump on, {} s at the first move's flow",
                num(pump.prime_dwell)
            ));
            line(&aout(flow_now));
            if let Some(s) = enable(true) {
                line(&s);
            }
            line(&format!("sleep({})", num(pump.prime_dwell)));
        } else {
            // The previous part stopped at the end of the previous layer, pump primed.
            let prev = part
                .first
                .checked_sub(1)
                .and_then(|i| st.layers.get(i))
                .and_then(|l| l.waypoints.last())
                .ok_or_else(|| {
                    RobotError::invalid("parts", "a continuing part without a previous layer")
                })?;
            line("# continue the bead where the previous program stopped (pump primed)");
            line(&format!(
                "movej({}, a={}, v={})",
                joints(&prev.q),
                num(pr.joint_acceleration),
                num(pr.joint_speed)
            ));
            targets += 1;
            if pump.pause == PauseMode::Stop {
                line(&aout(flow_output(plan, first_wp.speed)));
                if let Some(s) = enable(true) {
                    line(&s);
                }
                line(&format!("sleep({})", num(pump.prime_dwell)));
            }
            flow_now = f64::NAN;
        }
        let cmd = if pr.use_movel { "movel" } else { "movep" };
        let n_layers = layers.len();
        for (li, l) in layers.iter().enumerate() {
            line(&format!(
                "# layer {} ({} points)",
                l.layer,
                l.waypoints.len()
            ));
            for (k, wp) in l.waypoints.iter().enumerate() {
                if part.starts_station && li == 0 && k == 0 {
                    continue;
                }
                let f = flow_output(plan, wp.speed);
                // 1e-4 of the range: below any analog output's resolution.
                if flow_now.is_nan() || (f - flow_now).abs() > 1e-4 {
                    line(&aout(f));
                    flow_now = f;
                }
                let is_last = k + 1 == l.waypoints.len();
                let stop = is_last && (wp.hold > 0.0 || li + 1 == n_layers);
                let r = if stop { 0.0 } else { pr.blend_radius };
                line(&format!(
                    "{cmd}({}, a={}, v={}, r={})",
                    pose(&UR10E.fk(&wp.q).mul(&tool)),
                    num(pr.tool_acceleration),
                    num(wp.speed),
                    num(r)
                ));
                targets += 1;
            }
            let last_of_part = li + 1 == n_layers;
            if last_of_part {
                break;
            }
            if l.wait > 0.0 || l.waypoints.last().is_some_and(|w| w.hold > 0.0) {
                let hold = l.waypoints.last().map_or(0.0, |w| w.hold);
                match pump.pause {
                    PauseMode::KeepPrimed => {
                        line(&format!("# pause {} s, pump primed", num(hold)));
                        line(&aout(pump.hold()));
                        line(&format!("sleep({})", num(hold)));
                    }
                    PauseMode::Stop => {
                        line(&format!(
                            "# pause {} s, pump stopped, then primed again",
                            num(hold)
                        ));
                        line(&aout(0.0));
                        if let Some(s) = enable(false) {
                            line(&s);
                        }
                        line(&format!("sleep({})", num(hold - pump.prime_dwell)));
                        line(&aout(flow_output(plan, o.print_speed)));
                        if let Some(s) = enable(true) {
                            line(&s);
                        }
                        line(&format!("sleep({})", num(pump.prime_dwell)));
                    }
                }
                flow_now = f64::NAN;
            }
        }
        if part.ends_station {
            line("# station done: pump off, retract");
            line(&aout(0.0));
            if let Some(s) = enable(false) {
                line(&s);
            }
            let back = UR10E.fk(&last_wp.q).mul(&tool).mul(&Iso::translation(
                0.0,
                0.0,
                -pr.approach_distance,
            ));
            line(&format!(
                "movel({}, a={}, v={})",
                pose(&back),
                num(pr.tool_acceleration),
                num(pr.approach_speed)
            ));
            targets += 1;
        } else {
            let last_layer = layers.last().map(|l| (l.wait, l.waypoints.last()));
            let wait = last_layer.map_or(0.0, |x| x.0);
            match pump.pause {
                PauseMode::KeepPrimed => {
                    line("# the next program continues this station's bead: pump stays primed");
                    line(&aout(pump.hold()));
                    if wait > 0.0 {
                        line(&format!("sleep({})", num(wait)));
                    }
                }
                PauseMode::Stop => {
                    line(
                        "# the next program continues this station: pump stopped, primed again there",
                    );
                    line(&aout(0.0));
                    if let Some(s) = enable(false) {
                        line(&s);
                    }
                    if wait > 0.0 {
                        line(&format!("sleep({})", num(wait)));
                    }
                }
            }
        }
        let mut text = program_head(
            (&fname, targets, part.targets),
            (pi, n_parts),
            ("a UR10e", "generated; verified by kappe-robot check"),
            &plan.mark,
        )?;
        text.push_str(&format!(
            "# station {}: base at x {:.3} m, y {:.3} m, yaw {:.1}° (stations.md); layers {} to {}, {} motion targets\n",
            part.station + 1 + plan.mark.station_offset,
            b[0][3],
            b[1][3],
            b[1][0].atan2(b[0][0]).to_degrees(),
            part.first_layer,
            part.last_layer,
            targets
        ));
        text.push_str(&format!("# world_from_base rows {b:?}\n"));
        text.push_str(&format!(
            "# plan time {:.3} s to {:.3} s; units m, rad, s; poses in the robot base frame\n",
            first_wp.t, last_wp.t
        ));
        text.push_str(&format!("def {func}():\n"));
        text.push_str(&w);
        text.push_str("end\n");
        text.push_str(&format!("{func}()\n"));
        files.push(ProgramFile {
            name: fname,
            part: part.clone(),
            world_from_base: *b,
            start: first_wp.t,
            end: last_wp.t,
            mark: plan.mark.clone(),
            text,
        });
    }
    Ok(files)
}

/// A reason on one comment line (a newline would end the URScript comment).
/// The title of program `i` of `n`, as its first line says it.
fn program_title(f: &ProgramFile, i: usize, n: usize) -> String {
    let mark = f.mark.title();
    if mark.is_empty() {
        format!("Kappe print program {}/{n}", i + 1)
    } else {
        format!("Kappe print program {}/{n} -- {mark}", i + 1)
    }
}

/// The index of the program files (JSON): in order, each with its station, base pose, layers,
/// targets and plan times.
pub fn index_json(files: &[ProgramFile]) -> String {
    let list: Vec<serde_json::Value> = files
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let m = &f.world_from_base;
            serde_json::json!({
                "order": i + 1,
                "file": f.name,
                "station": f.part.station + 1 + f.mark.station_offset,
                "title": program_title(f, i, files.len()),
                "failing_design": f.mark.failing_design,
                "resumed_from_layer": f.mark.resumed_from_layer,
                "base_x_m": m[0][3],
                "base_y_m": m[1][3],
                "base_z_m": m[2][3],
                "base_yaw_deg": m[1][0].atan2(m[0][0]).to_degrees(),
                "world_from_base": m,
                "first_layer": f.part.first_layer,
                "last_layer": f.part.last_layer,
                "targets": f.part.targets,
                "starts_station": f.part.starts_station,
                "ends_station": f.part.ends_station,
                "start_s": f.start,
                "end_s": f.end,
            })
        })
        .collect();
    serde_json::to_string_pretty(&serde_json::json!({ "programs": list }))
        .unwrap_or_else(|_| "{}".into())
}

/// The plan that continues the print from layer `layer` (its first target first): the layers
/// before it are dropped, the station holding it starts there (approach from the safe pose,
/// prime), the programs are cut again and everything is re-timed from 0.
pub fn resume_plan(plan: &Plan, layer: i64) -> Result<Plan, RobotError> {
    let mut found = None;
    for (si, st) in plan.stations.iter().enumerate() {
        if let Some(li) = st.layers.iter().position(|l| l.layer == layer) {
            found = Some((si, li));
            break;
        }
    }
    let Some((si, li)) = found else {
        let ids: Vec<i64> = plan
            .stations
            .iter()
            .flat_map(|s| &s.layers)
            .map(|l| l.layer)
            .collect();
        return Err(RobotError::invalid(
            "--from-layer",
            format!(
                "layer {layer} is not in the plan (its layers are {} to {})",
                ids.first().copied().unwrap_or(0),
                ids.last().copied().unwrap_or(0)
            ),
        ));
    };
    let mut out = plan.clone();
    // The mesh clearances were measured on the whole print.
    out.meshes = None;
    out.mark.resumed_from_layer = Some(layer);
    out.mark.station_offset += si;
    out.stations.drain(..si);
    if let Some(st) = out.stations.first_mut() {
        st.layers.drain(..li);
    }
    let waits: Vec<crate::timing::LayerWait> = out
        .stations
        .iter()
        .flat_map(|s| &s.layers)
        .map(|l| crate::timing::LayerWait {
            layer: l.layer,
            wait: l.wait,
        })
        .collect();
    out.parts = split_parts(&out)?;
    crate::timing::apply_timing(&mut out, Some(&waits))?;
    Ok(out)
}

/// The first lines of program `pi + 1` of `n_parts` (`part`: its file, the motion targets
/// written and those it was sized for, which must agree): the title naming the `robot` and
/// `how` it was made, and the plan's mark.
pub(crate) fn program_head(
    (fname, wrote, sized): (&str, usize, usize),
    (pi, n_parts): (usize, usize),
    (robot, how): (&str, &str),
    mark: &crate::plan::PlanMark,
) -> Result<String, RobotError> {
    if wrote != sized {
        return Err(RobotError::Verification(vec![format!(
            "{fname}: wrote {wrote} motion targets, the part was sized for {sized}"
        )]));
    }
    let title = mark.title();
    let title = if title.is_empty() {
        String::new()
    } else {
        format!(" -- {title}")
    };
    Ok(format!(
        "# Kappe print program {}/{n_parts} for {robot}{title} ({how})\n{}",
        pi + 1,
        mark.header_lines()
    ))
}
