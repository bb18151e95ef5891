//! Robot programs and robot-independent exports of a [`Plan`] (robot.md §4): URScript, the joint
//! trajectory CSV and JSON. Hand-written writers over `impl Write` (a few lines each; no crate
//! writes URScript). Writers refuse a plan that fails [`check_plan`], so nothing unverified is
//! ever emitted.

use std::io::Write;

use crate::check::check_plan;
use crate::error::RobotError;
use crate::plan::Plan;

fn verified(plan: &Plan) -> Result<(), RobotError> {
    let rep = check_plan(plan);
    if rep.problems.is_empty() {
        Ok(())
    } else {
        Err(RobotError::Verification(rep.problems))
    }
}

/// The program files of the plan (`program_partNN.script`), each a standalone program of at
/// most `max_moves_per_program` motion targets ([`crate::program`]).
pub fn urscript_programs(plan: &Plan) -> Result<Vec<String>, RobotError> {
    verified(plan)?;
    Ok(crate::program::program_files(plan, "program_part")?
        .into_iter()
        .map(|f| f.text)
        .collect())
}

/// Write the whole print as one program file when it fits in one (the plan has a single part).
/// A longer print is written as its program files one after the other, each a complete
/// program, under a header saying so: such a file exceeds the target limit and is only kept
/// until callers write [`urscript_programs`] instead (see [`fits_one_program`]).
pub fn write_urscript(plan: &Plan, mut w: impl Write) -> Result<(), RobotError> {
    verified(plan)?;
    let files = crate::program::program_files(plan, "program")?;
    if files.len() > 1 {
        writeln!(
            w,
            "# {} programs of at most {} targets each, concatenated: load program_partNN.script instead",
            files.len(),
            plan.options.program.max_moves_per_program
        )?;
    }
    for f in &files {
        w.write_all(f.text.as_bytes())?;
    }
    Ok(())
}

/// Whether the whole print fits in one program file of at most the target limit.
pub fn fits_one_program(plan: &Plan) -> bool {
    plan.parts.len() <= 1
}

/// Joint trajectory CSV `station,layer,index,t,q1..q6,v_tool,flow` (rad, s, m/s, output
/// ratio): one row per print waypoint at its arrival (`layer,index` as in `path.csv`), and a
/// second row at its departure where the robot holds (priming, waits, program changes).
/// `v_tool` is the planned tool speed of the move into the row (0 on a hold) and `flow` the
/// pump set-point during it (0 on the approach to a station, the first move's flow while
/// priming, the hold output or 0 during pauses). Numbers use Rust's shortest round-trip formatting, so the file
/// reads back to the same f64 values.
pub fn write_trajectory_csv(plan: &Plan, mut w: impl Write) -> Result<(), RobotError> {
    verified(plan)?;
    writeln!(w, "station,layer,index,t,q1,q2,q3,q4,q5,q6,v_tool,flow")?;
    let pump = &plan.options.pump;
    // Set-point while holding at a layer's end: primed, or stopped.
    let pause = match pump.pause {
        crate::setup::PauseMode::KeepPrimed => pump.hold(),
        crate::setup::PauseMode::Stop => 0.0,
    };
    for (si, st) in plan.stations.iter().enumerate() {
        let all: Vec<(i64, &crate::plan::Waypoint)> = st
            .layers
            .iter()
            .flat_map(|l| l.waypoints.iter().map(move |w| (l.layer, w)))
            .collect();
        for (k, &(layer, p)) in all.iter().enumerate() {
            // The flow during the move into this row: off on the approach to the station's
            // first target; during its hold (priming) the first move's flow.
            let (f_arrive, f_hold) = if k == 0 {
                let v1 = all.get(1).map_or(plan.options.print_speed, |w| w.1.speed);
                (0.0, crate::program::flow_output(plan, v1))
            } else {
                (crate::program::flow_output(plan, p.speed), pause)
            };
            write!(w, "{si},{layer},{},{}", p.index, p.t)?;
            for q in p.q {
                write!(w, ",{q}")?;
            }
            writeln!(w, ",{},{f_arrive}", p.speed)?;
            if p.hold > 0.0 {
                write!(w, "{si},{layer},{},{}", p.index, p.t + p.hold)?;
                for q in p.q {
                    write!(w, ",{q}")?;
                }
                writeln!(w, ",0,{f_hold}")?;
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
