//! `kappe robot ...`: UR10e IK, planning a print path CSV, re-checking a plan, linting and
//! resuming. Argument parsing and file writing only: the work is `kappe_robot::files`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::Subcommand;
use kappe_robot::{Plan, check_plan, files, lint_with_limits};

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
    /// their argument counts, finite numbers, joint targets within the joint limits, I/O
    /// numbers, and the motion target limit. Exit code 1 when any file fails.
    Lint {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Most motion targets (move commands) per file.
        #[arg(long, default_value_t = 1000)]
        max_targets: usize,
        /// A planning config JSON (as for `robot plan`) whose `options.limits.position_deg`
        /// replace the UR10e joint position limits.
        #[arg(long)]
        config: Option<PathBuf>,
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
        /// Write the programs even when the design fails its checks (they are marked as the
        /// programs of a failing design).
        #[arg(long)]
        allow_fail: bool,
    },
}

/// Write a plan's outputs ([`kappe_robot::files::plan_outputs`]) into `dir`.
pub fn write_plan_outputs(
    dir: &Path,
    plan: &Plan,
    files: &[kappe_robot::ProgramFile],
) -> Result<()> {
    for (name, bytes) in files::plan_outputs(plan, files)? {
        write_file_atomic(&dir.join(name), &bytes)?;
    }
    Ok(())
}

/// Whether DIR/summary.json (when there is one) says the design fails its checks.
fn summary_says_fails(dir: &Path) -> bool {
    std::fs::read(dir.join("summary.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .is_some_and(|v| v.get("ok") == Some(&serde_json::Value::Bool(false)))
}

/// The base tolerance `kappe design` checked the plan in `dir` with (`summary.json`'s
/// `robot.base_tolerance`) and whether it is in the verdict; `None` when no summary says.
fn summary_tolerance(dir: &Path) -> Option<(kappe_robot::tolerance::BaseTolerance, bool)> {
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).ok()?).ok()?;
    let t = v.get("robot")?.get("base_tolerance")?;
    Some((
        kappe_robot::tolerance::BaseTolerance {
            position: t.get("position_m")?.as_f64()?,
            yaw_deg: t.get("yaw_deg")?.as_f64()?,
            stride: usize::try_from(t.get("stride")?.as_u64()?).ok()?,
        },
        t.get("in_verdict")?.as_bool()?,
    ))
}

fn read(path: &Path) -> Result<String> {
    Ok(crate::input::read_text(path, "input file")?)
}

pub fn run(cmd: RobotCommand) -> Result<ExitCode> {
    match cmd {
        RobotCommand::Ik { poses } => {
            let out = files::ik_of_poses(&read(&poses)?, &poses.display().to_string())?;
            println!("{}", serde_json::to_string_pretty(&out)?);
            Ok(ExitCode::SUCCESS)
        }
        RobotCommand::Check { plan } => {
            let (json, waypoints, problems) =
                match files::parse_plan_file(&read(&plan)?, &plan.display().to_string())? {
                    files::PlanFile::Stations(p) => {
                        let rep = check_plan(&p);
                        (
                            serde_json::to_string_pretty(&rep)?,
                            rep.waypoints,
                            rep.problems,
                        )
                    }
                    // The moving base's own check: FK composed with the base trajectory,
                    // clearance certified with the base moving, base speed and acceleration.
                    files::PlanFile::Moving(mp) => {
                        let rep = kappe_robot::moving::check_moving(&mp);
                        (
                            serde_json::to_string_pretty(&rep)?,
                            rep.waypoints,
                            rep.problems,
                        )
                    }
                };
            println!("{json}");
            if problems.is_empty() {
                eprintln!("plan OK: {waypoints} waypoints verified");
                Ok(ExitCode::SUCCESS)
            } else {
                eprintln!("plan FAILED: {} problem(s)", problems.len());
                Ok(ExitCode::FAILURE)
            }
        }
        RobotCommand::Plan { path, out, config } => {
            let layers = files::parse_path_csv(&read(&path)?, &path.display().to_string())?;
            let cfg = match config {
                Some(c) => files::parse_plan_config(&read(&c)?, &c.display().to_string())?,
                None => files::PlanConfig::default(),
            };
            // Refusals and unwritable locations fail before the planning.
            let prepared = prepare_dir(&out, false, "robot plan")?;
            let (plan, programs) = files::plan_with_programs(&layers, &cfg, "program_part")?;
            write_plan_outputs(prepared.path(), &plan, &programs)?;
            prepared.commit()?;
            for note in files::plan_notes(&plan) {
                eprintln!("{note}");
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
                programs.len(),
                out.display()
            );
            Ok(ExitCode::SUCCESS)
        }
        RobotCommand::Lint {
            files: paths,
            max_targets,
            config,
        } => {
            let limits = match config {
                Some(c) => files::parse_plan_config(&read(&c)?, &c.display().to_string())?
                    .options
                    .limits
                    .position(),
                None => kappe_robot::setup::JointLimitOptions::default().position(),
            };
            let mut failed = 0;
            for f in &paths {
                let rep = lint_with_limits(&read(f)?, max_targets, &limits);
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
                eprintln!("{failed} of {} file(s) failed", paths.len());
                Ok(ExitCode::FAILURE)
            } else {
                Ok(ExitCode::SUCCESS)
            }
        }
        RobotCommand::Resume {
            dir,
            from_layer,
            out,
            allow_fail,
        } => {
            let plan_path = dir.join("plan.json");
            let mut file =
                files::parse_plan_file(&read(&plan_path)?, &plan_path.display().to_string())?;
            let mark = match &mut file {
                files::PlanFile::Stations(p) => &mut p.mark,
                files::PlanFile::Moving(mp) => &mut mp.plan.mark,
            };
            // A plan.json written before plans carried their mark: the summary beside it
            // still knows whether the design passed.
            if mark.failing_design.is_none() && summary_says_fails(&dir) {
                mark.failing_design = Some(format!(
                    "{} says the design fails its checks",
                    dir.join("summary.json").display()
                ));
            }
            if let Some(why) = &mark.failing_design {
                if !allow_fail {
                    eprintln!(
                        "error: the design of {} fails its checks ({why}); no resume programs written. \
                         Fix the design, or rerun with --allow-fail to write them anyway (marked as \
                         the programs of a failing design)",
                        plan_path.display()
                    );
                    return Ok(crate::exit::fails());
                }
                eprintln!(
                    "warning: the design fails its checks ({why}); the programs are marked FAILING DESIGN"
                );
            }
            let out = out.unwrap_or_else(|| dir.join(format!("resume_from_layer_{from_layer}")));
            let plan = match file {
                files::PlanFile::Stations(p) => *p,
                // A moving base resumes on the same base trajectory from the layer's travel
                // (`resume_moving`: the arm's resume plan, the base re-timed, the moving check),
                // written as `kappe design` writes a moving plan, with tracking programs.
                files::PlanFile::Moving(mp) => {
                    let resumed =
                        kappe_robot::moving::resume_moving(&mp, from_layer).map_err(|e| {
                            anyhow::Error::new(e)
                                .context(format!("resuming {} failed", plan_path.display()))
                        })?;
                    let written = kappe::output::moving_plan_files(&resumed, "resume_part", true)?;
                    let prepared = prepare_dir(&out, false, "robot resume")?;
                    for f in &written {
                        write_file_atomic(&prepared.path().join(&f.name), &f.bytes)?;
                    }
                    prepared.commit()?;
                    println!(
                        "resume from layer {from_layer} (moving base): {} waypoints, {} program(s), \
                         {:.1} s → {}",
                        resumed.plan.waypoint_count(),
                        resumed.plan.parts.len(),
                        resumed.plan.total_time,
                        out.display()
                    );
                    return Ok(ExitCode::SUCCESS);
                }
            };
            let (resumed, programs) =
                match files::resume_with_programs(&plan, from_layer, "resume_part") {
                    Err(e @ kappe_robot::RobotError::Verification(_)) => Err(anyhow::Error::new(e)
                        .context(format!("resuming {} failed its check", plan_path.display()))),
                    r => r.map_err(anyhow::Error::new),
                }?;
            // The resumed plan's approach and re-cut programs are new motions: re-check them
            // against the base tolerance the design was checked with (issue 28).
            match summary_tolerance(&dir) {
                Some((tol, in_verdict)) => {
                    let rep = kappe_robot::tolerance::check_base_tolerance(&resumed, &tol);
                    if rep.ok() {
                        eprintln!(
                            "base tolerance: the resumed plan survives a base up to ±{:.1} mm, ±{:.1}° off",
                            tol.position * 1e3,
                            tol.yaw_deg
                        );
                    } else if in_verdict && !allow_fail {
                        eprintln!(
                            "error: the resumed plan does not survive a base ±{:.1} mm, ±{:.1}° off ({} problem(s): {}); \
                             no resume programs written. Rerun with --allow-fail to write them anyway",
                            tol.position * 1e3,
                            tol.yaw_deg,
                            rep.problems.len(),
                            rep.problems.first().map_or("", String::as_str)
                        );
                        return Ok(crate::exit::fails());
                    } else {
                        eprintln!(
                            "warning: the resumed plan does not survive a base ±{:.1} mm, ±{:.1}° off ({} problem(s)); place the base precisely",
                            tol.position * 1e3,
                            tol.yaw_deg,
                            rep.problems.len()
                        );
                    }
                }
                None => eprintln!(
                    "base tolerance: not checked (no robot.base_tolerance in {})",
                    dir.join("summary.json").display()
                ),
            }
            let prepared = prepare_dir(&out, false, "robot resume")?;
            write_plan_outputs(prepared.path(), &resumed, &programs)?;
            prepared.commit()?;
            println!(
                "resume from layer {from_layer}: {} waypoints, {} program(s), {:.1} s → {}",
                resumed.waypoint_count(),
                programs.len(),
                resumed.total_time,
                out.display()
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}
