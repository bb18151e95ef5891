//! `kappe robot ...`: UR10e IK, planning a print path CSV, re-checking a plan.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use kappe_robot::{
    Iso, Mat4, PathPoint, Plan, PlanOptions, PrintLayer, RobotSetup, UR10E, check_plan, index_json,
    lint, plan_print, program_files, resume_plan, write_plan_json, write_trajectory_csv,
};
use serde::Deserialize;

use crate::output::{prepare_dir, write_file_atomic};

#[derive(Subcommand)]
pub enum RobotCommand {
    /// Flange poses → all closed-form IK solutions (JSON to stdout). POSES.json is a list of
    /// row-major 4×4 matrices, or {"poses": [...], "flange_from_tcp": 4×4} for TCP poses.
    Ik { poses: PathBuf },
    /// Re-verify a plan JSON independently (FK vs targets, limits, collisions, continuity,
    /// speeds); exit code 1 when it fails.
    Check { plan: PathBuf },
    /// Plan a print path CSV (`layer,index,x,y,z,tx,ty,tz`, world frame) and write
    /// DIR/plan.json, DIR/trajectory.csv, the programs DIR/program_partNN.script (each ≤ the
    /// target limit, linted), their index DIR/programs.json, and DIR/program.script when the
    /// whole print fits in one program.
    Plan {
        path: PathBuf,
        /// Output directory (replaced atomically).
        #[arg(long, default_value = "robot-out")]
        out: PathBuf,
        /// JSON with optional "setup" (RobotSetup) and "options" (PlanOptions).
        #[arg(long)]
        config: Option<PathBuf>,
    },
    /// Check URScript program files independently: syntax and blocks, known functions and
    /// their argument counts, finite numbers, joint targets within the UR10e limits, I/O
    /// numbers, and the motion target limit. Exit code 1 when any file fails.
    Lint {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Most motion targets (move commands) per file.
        #[arg(long, default_value_t = 1000)]
        max_targets: usize,
    },
    /// Write the programs that continue a planned print from layer K (approach from the safe
    /// pose, prime the pump, print on), from DIR/plan.json (written by `kappe design` or
    /// `kappe robot plan`), checked and linted like the rest.
    Resume {
        /// Directory holding plan.json.
        dir: PathBuf,
        /// The first layer to print.
        #[arg(long, allow_hyphen_values = true)]
        from_layer: i64,
        /// Output directory (default DIR/resume_from_layer_K; replaced atomically).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

/// The program files of a timed plan, each linted against the plan's target limit.
pub fn linted_programs(plan: &Plan, prefix: &str) -> Result<Vec<kappe_robot::ProgramFile>> {
    let files = program_files(plan, prefix)?;
    let max = plan.options.program.max_moves_per_program;
    for f in &files {
        let rep = lint(&f.text, max);
        if !rep.ok() {
            bail!(
                "{} fails the URScript check: {}",
                f.name,
                rep.problems.join("; ")
            );
        }
    }
    Ok(files)
}

/// Write a plan's outputs into `dir`: plan.json, trajectory.csv, the programs and their index.
pub fn write_plan_outputs(
    dir: &Path,
    plan: &Plan,
    files: &[kappe_robot::ProgramFile],
) -> Result<()> {
    let mut csv = Vec::new();
    write_trajectory_csv(plan, &mut csv)?;
    let mut json = Vec::new();
    write_plan_json(plan, &mut json)?;
    write_file_atomic(&dir.join("trajectory.csv"), &csv)?;
    write_file_atomic(&dir.join("plan.json"), &json)?;
    for f in files {
        write_file_atomic(&dir.join(&f.name), f.text.as_bytes())?;
    }
    write_file_atomic(&dir.join("programs.json"), index_json(files).as_bytes())?;
    if let [one] = files {
        write_file_atomic(&dir.join("program.script"), one.text.as_bytes())?;
    }
    Ok(())
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

#[derive(Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
struct Config {
    setup: RobotSetup,
    options: PlanOptions,
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// Parse `layer,index,x,y,z,tx,ty,tz` rows into layers (in order of first appearance).
fn read_path_csv(path: &Path) -> Result<Vec<PrintLayer>> {
    let text = read(path)?;
    let mut lines = text.lines().enumerate();
    let header = lines.next().map(|(_, l)| l.trim()).unwrap_or("");
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let want = ["layer", "index", "x", "y", "z", "tx", "ty", "tz"];
    if cols.len() < 8 || cols[..8] != want {
        bail!(
            "{}: header is {header:?}, expected \"layer,index,x,y,z,tx,ty,tz\"",
            path.display()
        );
    }
    let mut layers: Vec<PrintLayer> = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() < 8 {
            bail!(
                "{} line {}: {} fields, expected 8",
                path.display(),
                i + 1,
                f.len()
            );
        }
        let layer: i64 = f[0]
            .parse()
            .with_context(|| format!("{} line {}: layer {:?}", path.display(), i + 1, f[0]))?;
        let index: usize = f[1]
            .parse()
            .with_context(|| format!("{} line {}: index {:?}", path.display(), i + 1, f[1]))?;
        let mut v = [0.0; 6];
        for (k, slot) in v.iter_mut().enumerate() {
            *slot = f[2 + k].parse().with_context(|| {
                format!(
                    "{} line {}: {} {:?}",
                    path.display(),
                    i + 1,
                    want[2 + k],
                    f[2 + k]
                )
            })?;
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
                    bail!(
                        "{} line {}: layer {layer} appears again after another layer",
                        path.display(),
                        i + 1
                    );
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

pub fn run(cmd: RobotCommand) -> Result<ExitCode> {
    match cmd {
        RobotCommand::Ik { poses } => {
            let file: PosesFile = serde_json::from_str(&read(&poses)?).with_context(|| {
                format!(
                    "{}: expected a list of 4×4 matrices or {{\"poses\", \"flange_from_tcp\"}}",
                    poses.display()
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
                    .map_err(|e| anyhow::anyhow!("flange_from_tcp: {e}"))?
                    .inverse(),
                None => Iso::IDENTITY,
            };
            let mut out = Vec::new();
            for (i, m) in list.iter().enumerate() {
                let t = Iso::from_mat4(m).map_err(|e| anyhow::anyhow!("poses[{i}]: {e}"))?;
                let sols = UR10E.ik_tcp(&t, &tcp_from_flange);
                out.push(
                    serde_json::json!({ "n_solutions": sols.len(), "solutions": sols.as_slice() }),
                );
            }
            println!("{}", serde_json::to_string_pretty(&out)?);
            Ok(ExitCode::SUCCESS)
        }
        RobotCommand::Check { plan } => {
            let p: kappe_robot::Plan = serde_json::from_str(&read(&plan)?)
                .with_context(|| format!("{} is not a kappe plan JSON", plan.display()))?;
            let rep = check_plan(&p);
            println!("{}", serde_json::to_string_pretty(&rep)?);
            if rep.problems.is_empty() {
                eprintln!("plan OK: {} waypoints verified", rep.waypoints);
                Ok(ExitCode::SUCCESS)
            } else {
                eprintln!("plan FAILED: {} problem(s)", rep.problems.len());
                Ok(ExitCode::FAILURE)
            }
        }
        RobotCommand::Plan { path, out, config } => {
            let layers = read_path_csv(&path)?;
            let cfg: Config = match config {
                Some(c) => serde_json::from_str(&read(&c)?)
                    .with_context(|| format!("invalid config {}", c.display()))?,
                None => Config::default(),
            };
            // Refusals and unwritable locations fail before the planning.
            let prepared = prepare_dir(&out, false, "robot plan")?;
            let mut plan = plan_print(&layers, &cfg.setup, &cfg.options)?;
            kappe_robot::meshes::attach_mesh_report(&mut plan, 1)?;
            let files = linted_programs(&plan, "program_part")?;
            write_plan_outputs(prepared.path(), &plan, &files)?;
            prepared.commit()?;
            for s in &plan.slowdowns {
                eprintln!(
                    "note: station {} layer {} point {} to layer {} point {}: tool slowed to {:.1} % of the design speed ({}), the flow with it",
                    s.station + 1,
                    s.from.0,
                    s.from.1,
                    s.to.0,
                    s.to.1,
                    100.0 * s.min_speed_ratio,
                    s.reason
                );
            }
            if let Some(m) = &plan.meshes {
                eprintln!(
                    "clearance to the environment: arm capsules {:.4} m, arm meshes {:.4} m, nozzle {:.4} m; self: capsules {:.4} m, meshes {:.4} m",
                    m.capsules.environment.distance,
                    m.meshes.environment.distance,
                    m.nozzle.distance,
                    m.capsules.self_distance.distance,
                    m.meshes.self_distance.distance
                );
            }
            println!(
                "planned {} waypoints in {} layers from {} station(s): joint motion {:.3} rad, print time {:.1} s, total {:.1} s, min clearance {:.4} m, {} program(s) → {}",
                plan.waypoint_count(),
                layers.len(),
                plan.stations.len(),
                plan.joint_motion,
                plan.print_time,
                plan.total_time,
                plan.min_clearance,
                files.len(),
                out.display()
            );
            Ok(ExitCode::SUCCESS)
        }
        RobotCommand::Lint { files, max_targets } => {
            let mut failed = 0;
            for f in &files {
                let text = read(f)?;
                let rep = lint(&text, max_targets);
                if rep.ok() {
                    println!(
                        "{}: OK ({} motion targets, {} calls)",
                        f.display(),
                        rep.targets,
                        rep.calls
                    );
                } else {
                    failed += 1;
                    println!("{}: FAILED", f.display());
                    for p in &rep.problems {
                        println!("  {p}");
                    }
                }
            }
            if failed > 0 {
                eprintln!("{failed} of {} file(s) failed", files.len());
                Ok(ExitCode::FAILURE)
            } else {
                Ok(ExitCode::SUCCESS)
            }
        }
        RobotCommand::Resume {
            dir,
            from_layer,
            out,
        } => {
            let plan_path = dir.join("plan.json");
            let plan: Plan = serde_json::from_str(&read(&plan_path)?)
                .with_context(|| format!("{} is not a kappe plan JSON", plan_path.display()))?;
            let rep = check_plan(&plan);
            if !rep.problems.is_empty() {
                bail!(
                    "{} fails its check: {}",
                    plan_path.display(),
                    rep.problems.join("; ")
                );
            }
            let mut resumed = resume_plan(&plan, from_layer)?;
            kappe_robot::meshes::attach_mesh_report(&mut resumed, 1)?;
            let rep = check_plan(&resumed);
            if !rep.problems.is_empty() {
                bail!(
                    "the resumed plan fails its check: {}",
                    rep.problems.join("; ")
                );
            }
            let files = linted_programs(&resumed, "resume_part")?;
            let out = out.unwrap_or_else(|| dir.join(format!("resume_from_layer_{from_layer}")));
            let prepared = prepare_dir(&out, false, "robot resume")?;
            write_plan_outputs(prepared.path(), &resumed, &files)?;
            prepared.commit()?;
            println!(
                "resume from layer {from_layer}: {} waypoints, {} program(s), {:.1} s → {}",
                resumed.waypoint_count(),
                files.len(),
                resumed.total_time,
                out.display()
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}
