//! The robot's input files and whole workflows, for any front end (the `kappe robot` commands,
//! the Python package): reading a print path CSV, a planning config, poses and a plan; planning
//! with the mesh check and the program lint; resuming; the files a plan writes and the notes it
//! prints. Nothing here touches the file system: callers read the text and write the bytes.

use serde::Deserialize;

use crate::error::RobotError;
use crate::frames::{Iso, Mat4};
use crate::kinematics::UR10E;
use crate::plan::Plan;
use crate::program::{ProgramFile, index_json, program_files, resume_plan};
use crate::setup::{PathPoint, PlanOptions, PrintLayer, RobotSetup};

/// A planning config: the robot cell and the planner options (both optional, defaults).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlanConfig {
    pub setup: RobotSetup,
    pub options: PlanOptions,
}

/// Parse a planning config JSON (`{"setup": …, "options": …}`); `source` names it in errors.
pub fn parse_plan_config(text: &str, source: &str) -> Result<PlanConfig, RobotError> {
    serde_json::from_str(text)
        .map_err(|e| RobotError::invalid(format!("config {source}"), e.to_string()))
}

/// Parse a plan JSON (as `kappe design` and `kappe robot plan` write it).
pub fn parse_plan(text: &str, source: &str) -> Result<Plan, RobotError> {
    serde_json::from_str(text)
        .map_err(|e| RobotError::invalid(source.to_string(), format!("not a kappe plan JSON: {e}")))
}

/// A plan file as `kappe design` writes it: stations (a fixed base per station) or one moving
/// base ([`crate::moving::MovingPlan`], `[robot.base] mode = "moving"`).
#[derive(Clone, Debug)]
pub enum PlanFile {
    /// A plan of stations.
    Stations(Box<Plan>),
    /// A plan whose base moves while the arm prints.
    Moving(Box<crate::moving::MovingPlan>),
}

/// Parse a plan JSON of either kind: a moving plan is an object with `plan`, `travel` and
/// `trajectory`; anything else is read as a plan of stations, so its errors are the ones
/// [`parse_plan`] names. A moving plan's shape is validated ([`crate::moving::MovingPlan::validate_shape`]).
pub fn parse_plan_file(text: &str, source: &str) -> Result<PlanFile, RobotError> {
    let value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| RobotError::invalid(source.to_string(), format!("not JSON: {e}")))?;
    let moving = ["plan", "travel", "trajectory"]
        .iter()
        .all(|k| value.get(k).is_some());
    if !moving {
        return parse_plan(text, source).map(|p| PlanFile::Stations(Box::new(p)));
    }
    let mp: crate::moving::MovingPlan = serde_json::from_value(value).map_err(|e| {
        RobotError::invalid(
            source.to_string(),
            format!("not a kappe moving-base plan JSON: {e}"),
        )
    })?;
    mp.validate_shape()?;
    Ok(PlanFile::Moving(Box::new(mp)))
}

/// Parse a print path CSV `layer,index,x,y,z,tx,ty,tz` (world frame; extra columns ignored)
/// into layers in order of first appearance. A layer that appears again after another one, a
/// wrong header, a short row or a field that is not a number is an error naming the line.
pub fn parse_path_csv(text: &str, source: &str) -> Result<Vec<PrintLayer>, RobotError> {
    let mut lines = text.lines().enumerate();
    let header = lines.next().map(|(_, l)| l.trim()).unwrap_or("");
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let want = ["layer", "index", "x", "y", "z", "tx", "ty", "tz"];
    if cols.len() < 8 || cols[..8] != want {
        return Err(RobotError::invalid(
            source.to_string(),
            format!("header is {header:?}, expected \"layer,index,x,y,z,tx,ty,tz\""),
        ));
    }
    let mut layers: Vec<PrintLayer> = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let at = || format!("{source} line {}", i + 1);
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() < 8 {
            return Err(RobotError::invalid(
                at(),
                format!("{} fields, expected 8", f.len()),
            ));
        }
        let bad = |name: &str, v: &str, e: &dyn std::fmt::Display| {
            RobotError::invalid(at(), format!("{name} {v:?}: {e}"))
        };
        let layer: i64 = f[0].parse().map_err(|e| bad("layer", f[0], &e))?;
        let index: usize = f[1].parse().map_err(|e| bad("index", f[1], &e))?;
        let mut v = [0.0; 6];
        for (k, slot) in v.iter_mut().enumerate() {
            *slot = f[2 + k]
                .parse()
                .map_err(|e| bad(want[2 + k], f[2 + k], &e))?;
        }
        let p = PathPoint {
            index,
            position: [v[0], v[1], v[2]],
            axis: [v[3], v[4], v[5]],
        };
        match layers.last_mut() {
            Some(l) if l.layer == layer => l.points.push(p),
            _ => {
                if layers.iter().any(|l| l.layer == layer) {
                    return Err(RobotError::invalid(
                        at(),
                        format!("layer {layer} appears again after another layer"),
                    ));
                }
                layers.push(PrintLayer {
                    layer,
                    points: vec![p],
                });
            }
        }
    }
    Ok(layers)
}

#[derive(Deserialize)]
#[serde(untagged)]
enum PosesFile {
    List(Vec<Mat4>),
    Tool {
        poses: Vec<Mat4>,
        flange_from_tcp: Option<Mat4>,
    },
}

/// All closed-form IK solutions of the poses in a poses JSON: a list of row-major 4×4 flange
/// poses, or `{"poses": [...], "flange_from_tcp": 4×4}` for TCP poses. Returns the JSON list
/// `[{"n_solutions", "solutions"}, …]`.
pub fn ik_of_poses(text: &str, source: &str) -> Result<serde_json::Value, RobotError> {
    let file: PosesFile = serde_json::from_str(text).map_err(|e| {
        RobotError::invalid(
            source.to_string(),
            format!("expected a list of 4×4 matrices or {{\"poses\", \"flange_from_tcp\"}}: {e}"),
        )
    })?;
    let (list, tool) = match file {
        PosesFile::List(l) => (l, None),
        PosesFile::Tool {
            poses,
            flange_from_tcp,
        } => (poses, flange_from_tcp),
    };
    let tcp_from_flange = match tool {
        Some(m) => Iso::from_mat4(&m)
            .map_err(|e| RobotError::invalid("flange_from_tcp", e))?
            .inverse(),
        None => Iso::IDENTITY,
    };
    let mut out = Vec::new();
    for (i, m) in list.iter().enumerate() {
        let t = Iso::from_mat4(m).map_err(|e| RobotError::invalid(format!("poses[{i}]"), e))?;
        let sols = UR10E.ik_tcp(&t, &tcp_from_flange);
        out.push(serde_json::json!({ "n_solutions": sols.len(), "solutions": sols.as_slice() }));
    }
    Ok(serde_json::Value::Array(out))
}

/// The program files of a timed plan, each linted against the plan's target limit and joint
/// position limits; a file that fails is an error naming it and its problems.
pub fn linted_programs(plan: &Plan, prefix: &str) -> Result<Vec<ProgramFile>, RobotError> {
    let files = program_files(plan, prefix)?;
    let max = plan.options.program.max_moves_per_program;
    let limits = plan.options.limits.position();
    for f in &files {
        let rep = crate::lint::lint_with_limits(&f.text, max, &limits);
        if !rep.ok() {
            return Err(RobotError::Verification(vec![format!(
                "{} fails the URScript check: {}",
                f.name,
                rep.problems.join("; ")
            )]));
        }
    }
    Ok(files)
}

/// Plan, time and check a print ([`crate::plan_print`]), check it against UR's collision
/// meshes ([`crate::meshes::attach_mesh_report`]) and write and lint its programs.
pub fn plan_with_programs(
    layers: &[PrintLayer],
    config: &PlanConfig,
    prefix: &str,
) -> Result<(Plan, Vec<ProgramFile>), RobotError> {
    let mut plan = crate::plan_print(layers, &config.setup, &config.options)?;
    crate::meshes::attach_mesh_report(&mut plan, 1)?;
    let files = linted_programs(&plan, prefix)?;
    Ok((plan, files))
}

/// The plan that continues `plan` from layer `from_layer` ([`resume_plan`]), after checking the
/// given plan; the result is checked against the capsules and the meshes, and its programs
/// are linted. `Err(Verification)` when either check fails.
pub fn resume_with_programs(
    plan: &Plan,
    from_layer: i64,
    prefix: &str,
) -> Result<(Plan, Vec<ProgramFile>), RobotError> {
    let rep = crate::check_plan(plan);
    if !rep.problems.is_empty() {
        return Err(RobotError::Verification(rep.problems));
    }
    let mut resumed = resume_plan(plan, from_layer)?;
    crate::meshes::attach_mesh_report(&mut resumed, 1)?;
    let rep = crate::check_plan(&resumed);
    if !rep.problems.is_empty() {
        return Err(RobotError::Verification(
            std::iter::once("the resumed plan fails its check".to_string())
                .chain(rep.problems)
                .collect(),
        ));
    }
    resumed.certified = Some(crate::plan::CertifiedClearance::of(&rep));
    let files = linted_programs(&resumed, prefix)?;
    Ok((resumed, files))
}

/// The files a plan writes, in order, as (name, bytes): trajectory.csv, plan.json, the
/// programs, programs.json, and program.script when the whole print fits in one program.
pub fn plan_outputs(
    plan: &Plan,
    files: &[ProgramFile],
) -> Result<Vec<(String, Vec<u8>)>, RobotError> {
    let mut csv = Vec::new();
    crate::export::write_trajectory_csv(plan, &mut csv)?;
    let mut json = Vec::new();
    crate::export::write_plan_json(plan, &mut json)?;
    let mut out = vec![
        ("trajectory.csv".to_string(), csv),
        ("plan.json".to_string(), json),
    ];
    for f in files {
        out.push((f.name.clone(), f.text.as_bytes().to_vec()));
    }
    out.push(("programs.json".to_string(), index_json(files).into_bytes()));
    if let [one] = files {
        out.push(("program.script".to_string(), one.text.as_bytes().to_vec()));
    }
    Ok(out)
}

/// Notes on a plan for its user: where the tool slows down (and the flow with it) and the
/// clearances of both geometric models.
pub fn plan_notes(plan: &Plan) -> Vec<String> {
    let mut out = Vec::new();
    for s in &plan.slowdowns {
        out.push(format!(
            "note: station {} layer {} point {} to layer {} point {}: tool slowed to {:.1} % of the design speed ({}), the flow with it",
            s.station + 1,
            s.from.0,
            s.from.1,
            s.to.0,
            s.to.1,
            100.0 * s.min_speed_ratio,
            s.reason
        ));
    }
    if let Some(m) = &plan.meshes {
        out.push(format!(
            "clearance to the environment: arm capsules {:.4} m, arm meshes {:.4} m, nozzle {:.4} m; self: capsules {:.4} m, meshes {:.4} m",
            m.capsules.environment.distance,
            m.meshes.environment.distance,
            m.nozzle.distance,
            m.capsules.self_distance.distance,
            m.meshes.self_distance.distance
        ));
    }
    out
}
