//! Robot programs and robot-independent exports of a [`Plan`] (robot.md §4): URScript, the joint
//! trajectory CSV and JSON. Hand-written writers over `impl Write` (a few lines each; no crate
//! writes URScript). Writers refuse a plan that fails [`check_plan`], so nothing unverified is
//! ever emitted.

use std::io::Write;

use crate::check::check_plan;
use crate::error::RobotError;
use crate::frames::Iso;
use crate::kinematics::UR10E;
use crate::plan::Plan;

fn verified(plan: &Plan) -> Result<(), RobotError> {
    let rep = check_plan(plan);
    if rep.problems.is_empty() {
        Ok(())
    } else {
        Err(RobotError::Verification(rep.problems))
    }
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

/// One subprogram body per part; parts split at layer boundaries after at most
/// `max_moves_per_program` moves (a single longer layer gets a part of its own).
fn parts(plan: &Plan) -> Vec<(String, usize)> {
    let o = &plan.options.program;
    let tool = Iso::from_mat4_unchecked(&plan.flange_from_tcp);
    let mut parts: Vec<(String, usize)> = Vec::new();
    let mut body = String::new();
    let mut moves = 0usize;
    for (si, st) in plan.stations.iter().enumerate() {
        let m = st.world_from_base;
        let station_note = format!("  # station {} world_from_base rows: {:?}\n", si + 1, m);
        if si > 0 {
            body += &station_note;
            body += &format!(
                "  popup(\"Move the mobile base to station {}, then continue\", \"Kappe\", blocking=True)\n",
                si + 1
            );
        } else {
            body += &station_note;
        }
        for l in &st.layers {
            let n = l.waypoints.len();
            if moves > 0 && moves + n > o.max_moves_per_program.max(1) {
                parts.push((std::mem::take(&mut body), moves));
                moves = 0;
            }
            body += &format!("  # layer {} ({} points)\n", l.layer, n);
            for (k, w) in l.waypoints.iter().enumerate() {
                if k == 0 {
                    body += &format!(
                        "  movej({}, a={}, v={})\n",
                        joints(&w.q),
                        o.joint_acceleration,
                        o.joint_speed
                    );
                    body += &format!("  set_standard_digital_out({}, True)\n", o.pump_output);
                    body += &format!("  sleep({})\n", o.pump_lead);
                } else {
                    let tcp = UR10E.fk(&w.q).mul(&tool);
                    let r = if k + 1 == n { 0.0 } else { o.blend_radius };
                    let cmd = if o.use_movel { "movel" } else { "movep" };
                    body += &format!(
                        "  {cmd}({}, a={}, v={}, r={})\n",
                        pose(&tcp),
                        o.tool_acceleration,
                        plan.options.print_speed,
                        r
                    );
                }
            }
            body += &format!("  set_standard_digital_out({}, False)\n", o.pump_output);
            moves += n;
        }
    }
    if moves > 0 || parts.is_empty() {
        parts.push((body, moves));
    }
    parts
}

fn header(plan: &Plan, w: &mut impl Write, part: Option<(usize, usize)>) -> Result<(), RobotError> {
    writeln!(
        w,
        "# Kappe print program for a UR10e (generated; verified by kappe-robot check)"
    )?;
    if let Some((i, n)) = part {
        writeln!(w, "# part {i} of {n}")?;
    }
    writeln!(
        w,
        "# stations {}, print waypoints {}, print time {:.1} s, min clearance {:.4} m",
        plan.stations.len(),
        plan.waypoint_count(),
        plan.print_time,
        plan.min_clearance
    )?;
    writeln!(w, "# flange_from_tcp rows: {:?}", plan.flange_from_tcp)?;
    writeln!(w, "# units: m, rad, s; poses in the robot base frame")?;
    Ok(())
}

/// Write the whole print as one URScript program: a `def kappe_print()` holding one subprogram
/// per part (robot.md §4: long programs split), called in order. One move per print waypoint:
/// `movej` (joint target) to each layer's first point, `movep` (or `movel`) through the rest; the
/// pump output is switched on before and off after every layer.
pub fn write_urscript(plan: &Plan, mut w: impl Write) -> Result<(), RobotError> {
    verified(plan)?;
    let parts = parts(plan);
    let tool = Iso::from_mat4_unchecked(&plan.flange_from_tcp);
    header(plan, &mut w, None)?;
    writeln!(w, "def kappe_print():")?;
    writeln!(w, "  set_tcp({})", pose(&tool))?;
    writeln!(
        w,
        "  set_standard_digital_out({}, False)",
        plan.options.program.pump_output
    )?;
    for (i, (body, _)) in parts.iter().enumerate() {
        writeln!(w, "  def kappe_part_{}():", i + 1)?;
        for line in body.lines() {
            writeln!(w, "  {line}")?;
        }
        writeln!(w, "  end")?;
    }
    for i in 0..parts.len() {
        writeln!(w, "  kappe_part_{}()", i + 1)?;
    }
    writeln!(w, "end")?;
    writeln!(w, "kappe_print()")?;
    Ok(())
}

/// The print as separate, self-contained programs (one per part), for controllers that fail on
/// long files.
pub fn urscript_programs(plan: &Plan) -> Result<Vec<String>, RobotError> {
    verified(plan)?;
    let parts = parts(plan);
    let tool = Iso::from_mat4_unchecked(&plan.flange_from_tcp);
    let n = parts.len();
    let mut out = Vec::new();
    for (i, (body, _)) in parts.into_iter().enumerate() {
        let mut w = Vec::new();
        header(plan, &mut w, Some((i + 1, n)))?;
        writeln!(w, "def kappe_print_part_{}():", i + 1)?;
        writeln!(w, "  set_tcp({})", pose(&tool))?;
        w.extend_from_slice(body.as_bytes());
        writeln!(w, "end")?;
        writeln!(w, "kappe_print_part_{}()", i + 1)?;
        out.push(String::from_utf8_lossy(&w).into_owned());
    }
    Ok(out)
}

/// Joint trajectory CSV `station,layer,index,t,q1..q6` (rad, s; one row per print waypoint,
/// `layer,index` as in `path.csv`). Numbers use Rust's shortest round-trip formatting, so the
/// file reads back to the same f64 values.
pub fn write_trajectory_csv(plan: &Plan, mut w: impl Write) -> Result<(), RobotError> {
    verified(plan)?;
    writeln!(w, "station,layer,index,t,q1,q2,q3,q4,q5,q6")?;
    for (si, st) in plan.stations.iter().enumerate() {
        for l in &st.layers {
            for p in &l.waypoints {
                write!(w, "{si},{},{},{}", l.layer, p.index, p.t)?;
                for q in p.q {
                    write!(w, ",{q}")?;
                }
                writeln!(w)?;
            }
        }
    }
    Ok(())
}

/// The plan as pretty JSON (stations with `world_from_base`, waypoints, summary, setup, options);
/// `kappe robot check` reads it back.
pub fn write_plan_json(plan: &Plan, w: impl Write) -> Result<(), RobotError> {
    verified(plan)?;
    serde_json::to_writer_pretty(w, plan).map_err(|e| RobotError::Io(std::io::Error::other(e)))
}
