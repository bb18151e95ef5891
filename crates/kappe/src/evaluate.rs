//! The whole pipeline of one design: form-finding ([`crate::design_cap`]), then the robot plan
//! ([`crate::robot_plan::plan_robot`], when asked for), the analysis of every state
//! ([`crate::analysis::analyze`], when asked for; with a plan, the layers' ages come from the
//! plan's clock), the verdict ([`crate::verdict`]), the
//! summary (`summary.json`) and the report input ([`crate::report_input`]).
//!
//! [`run`] is what `kappe design`, every design of `kappe study` and the Python `kappe.design`
//! call, so their numbers and verdicts cannot disagree. [`evaluate`] is the part after
//! form-finding, for callers that already hold a [`Cap`].

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use crate::analysis::{Analysis, AnalysisOptions};
use crate::error::DesignError;
use crate::pipeline::Cap;
use crate::report_input::{ReportExtras, add_robot, extras_from_analysis, report_input};
use crate::spec::Design;

/// What [`run`] does after form-finding.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Options {
    /// The analysis of every state (stresses, overhang, shell buckling); `None`: no analysis,
    /// the verdict is then the preliminary one of [`crate::verdict::design_ok`].
    pub analysis: Option<AnalysisOptions>,
    /// Plan the robot, for designs whose `robot.enabled` is set.
    pub robot: bool,
    /// Hand out the robot programs of a design that fails its checks too (`--allow-fail`);
    /// without it a failing design has a plan but no programs ([`Outcome::programs`]).
    pub allow_fail: bool,
}

impl Options {
    /// What `kappe design` does by default: the design's own `[analysis]` options (buckling on
    /// unless the file says otherwise) and the robot plan.
    pub fn of(design: &Design) -> Options {
        Options {
            analysis: Some(design.analysis.clone()),
            robot: true,
            allow_fail: false,
        }
    }
}

/// A stage of [`run`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Form-finding and the force pass of every print state.
    States,
    /// The buckling analysis of the selected states (one tick per finite-element solve).
    Analysis,
    /// Robot planning (one tick with `done = 0` when it starts, one with `done = 1` at the end).
    Robot,
}

/// One progress report of [`run`]: `done` of `total` steps of `stage` are finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// The stage.
    pub stage: Stage,
    /// Steps finished.
    pub done: usize,
    /// Steps of the stage.
    pub total: usize,
}

/// A progress callback: called from worker threads; [`ControlFlow::Break`] stops the run (it then
/// returns [`DesignError::Cancelled`]).
pub type OnProgress<'a> = &'a (dyn Fn(Progress) -> ControlFlow<()> + Sync);

/// A progress callback that reports nowhere and never stops.
pub fn no_progress(_: Progress) -> ControlFlow<()> {
    ControlFlow::Continue(())
}

/// Counts the ticks of one stage and remembers a request to stop.
struct Ticker<'a> {
    on_progress: OnProgress<'a>,
    stop: &'a AtomicBool,
    done: AtomicUsize,
    stage: Stage,
}

impl<'a> Ticker<'a> {
    fn new(on_progress: OnProgress<'a>, stop: &'a AtomicBool, stage: Stage) -> Self {
        Ticker {
            on_progress,
            stop,
            done: AtomicUsize::new(0),
            stage,
        }
    }

    fn tick(&self, total: usize) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        self.report(done, total);
    }

    fn report(&self, done: usize, total: usize) {
        let p = Progress {
            stage: self.stage,
            done,
            total,
        };
        if (self.on_progress)(p).is_break() {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
}

fn check(stop: &AtomicBool) -> Result<(), DesignError> {
    if stop.load(Ordering::Relaxed) {
        Err(DesignError::Cancelled)
    } else {
        Ok(())
    }
}

/// Everything [`run`] found for one design.
#[derive(Debug)]
pub struct Outcome {
    /// The designed cap: every state, the layers, the print path, the mesh.
    pub cap: Cap,
    /// Stresses, overhang and buckling of every state, and the constraint report; `None` when
    /// not asked for.
    pub analysis: Option<Analysis>,
    /// The robot plan, or why there is none; `None` when planning was not asked for (or the
    /// design disables the robot).
    pub robot: Option<Result<kappe_robot::Plan, kappe_robot::RobotError>>,
    /// The base-pose tolerance check of the plan (`[robot.tolerance]`, issue 15); `None`
    /// without a plan or with `check = false`.
    pub base_tolerance: Option<kappe_robot::tolerance::ToleranceReport>,
    /// The analysis and robot results in report form.
    pub extras: ReportExtras,
    /// The verdict of [`crate::verdict::design_ok`].
    pub ok: bool,
    /// [`Options::allow_fail`] of the run.
    pub allow_fail: bool,
}

/// Form-find `design`, then [`evaluate`] it. `on_progress` hears every state solved, every
/// buckling solve and the robot planning; it may stop the run.
///
/// # Errors
/// An invalid design or invalid analysis options ([`DesignError::Invalid`]), a design without an
/// equilibrium form, a state that cannot be built, or [`DesignError::Cancelled`].
pub fn run(
    design: &Design,
    options: &Options,
    on_progress: OnProgress<'_>,
) -> Result<Outcome, DesignError> {
    let stop = AtomicBool::new(false);
    let states = Ticker::new(on_progress, &stop, Stage::States);
    let cap = crate::pipeline::design_cap_until(design, &|total| states.tick(total), &stop)?;
    check(&stop)?;
    evaluate_until(cap, options, on_progress, &stop)
}

/// The pipeline after form-finding (see [`run`]): analysis, robot plan, verdict.
///
/// # Errors
/// As [`run`], without the form-finding ones.
pub fn evaluate(
    cap: Cap,
    options: &Options,
    on_progress: OnProgress<'_>,
) -> Result<Outcome, DesignError> {
    evaluate_until(cap, options, on_progress, &AtomicBool::new(false))
}

fn evaluate_until(
    cap: Cap,
    options: &Options,
    on_progress: OnProgress<'_>,
    stop: &AtomicBool,
) -> Result<Outcome, DesignError> {
    // The robot is planned first (planning does not depend on the analysis): with a plan, the
    // structural check takes every layer's age from the plan's clock (issue 11). Programs are
    // still handed out only when the design passes ([`Outcome::programs`]).
    let robot = if options.robot && cap.design.robot.enabled {
        let ticker = Ticker::new(on_progress, stop, Stage::Robot);
        ticker.report(0, 1);
        check(stop)?;
        let plan = plan_with_schedule_waits(&cap)?;
        ticker.report(1, 1);
        Some(plan)
    } else {
        None
    };
    check(stop)?;
    let schedule = plan_schedule(&cap, robot.as_ref())?;
    let fe = Ticker::new(on_progress, stop, Stage::Analysis);
    let analysis = match &options.analysis {
        Some(o) => Some(crate::analysis::check::analyze_scheduled(
            &cap,
            o,
            schedule.as_ref(),
            &|total| fe.tick(total),
            stop,
        )?),
        None => None,
    };
    check(stop)?;
    let mut extras = analysis
        .as_ref()
        .map(extras_from_analysis)
        .unwrap_or_default();
    if let Some(plan) = &robot {
        add_robot(&mut extras, plan);
    }
    // A relocated base is never exactly where planned (issue 15): re-check the plan under the
    // base-pose errors of `[robot.tolerance]`; with `verdict = true` a failure fails the design.
    let tol = &cap.design.robot.tolerance;
    let base_tolerance = match &robot {
        Some(Ok(plan)) if tol.check => Some(kappe_robot::tolerance::check_base_tolerance(
            plan,
            &tol.base_tolerance(),
        )),
        _ => None,
    };
    if tol.verdict
        && extras.robot_error.is_none()
        && let Some(r) = base_tolerance.as_ref().filter(|r| !r.ok())
    {
        extras.robot_error = Some(format!(
            "the plan does not survive a base placed up to ±{:.1} mm, ±{:.1}° off \
             ([robot.tolerance]): {}. Place the base more precisely and lower the tolerance to \
             match, or widen the base search ([robot.setup.base])",
            tol.position * 1e3,
            tol.yaw_deg,
            r.problems.first().cloned().unwrap_or_default()
        ));
    }
    // The report's constraint table says whether the plan survives its stated base error.
    if let Some(r) = &base_tolerance {
        extras.constraints.push(kappe_report::ConstraintRow {
            name: "base_tolerance".into(),
            bound: kappe_report::Bound::AtMost,
            limit: 0.0,
            worst: r.problems.len() as f64,
            unit: "problems".into(),
            state: None,
            element: Some(if r.ok() {
                format!(
                    "survives a base up to ±{:.1} mm, ±{:.1}° off (every station, {} points re-solved)",
                    tol.position * 1e3,
                    tol.yaw_deg,
                    r.waypoints_checked
                )
            } else {
                r.problems.first().cloned().unwrap_or_default()
            }),
            pass: r.ok(),
        });
    }
    extras.schedule = report_schedule(&cap, analysis.as_ref(), schedule);
    let ok = crate::verdict::design_ok(&cap, &extras);
    Ok(Outcome {
        cap,
        analysis,
        robot,
        base_tolerance,
        extras,
        ok,
        allow_fail: options.allow_fail,
    })
}

impl Outcome {
    /// `summary.json`: the cap's summary with the analysis merged in, the robot block
    /// (stations with `world_from_base`, `flange_from_tcp`, motion, time, clearance; or why it
    /// failed) and the verdict `ok`.
    pub fn summary(&self) -> serde_json::Value {
        let cap = &self.cap;
        let mut summary = crate::export::summary_json(cap);
        if let Some(analysis) = &self.analysis {
            crate::export::add_analysis(&mut summary, analysis);
        }
        let robot = match &self.robot {
            None => serde_json::json!({"planned": false, "reason": "disabled"}),
            Some(Ok(plan)) => {
                let mut v = plan_summary(plan);
                if let (Some(obj), Some(t)) = (v.as_object_mut(), &self.base_tolerance) {
                    obj.insert(
                        "base_tolerance".into(),
                        serde_json::json!({
                            "ok": t.ok(),
                            "position_m": t.tolerance.position,
                            "yaw_deg": t.tolerance.yaw_deg,
                            "stride": t.tolerance.stride,
                            "poses_per_station": t.poses_per_station,
                            "waypoints_checked": t.waypoints_checked,
                            "min_clearance_m": t.min_clearance,
                            "min_body_distance_m": t.min_body_distance,
                            "problems": t.problems,
                            "in_verdict": self.cap.design.robot.tolerance.verdict,
                        }),
                    );
                }
                v
            }
            Some(Err(e)) => {
                serde_json::json!({"planned": false, "ok": false, "failure": e.to_string()})
            }
        };
        let programs = self.programs();
        if let Some(obj) = summary.as_object_mut() {
            obj.insert("print_time_s".into(), serde_json::json!(self.print_time()));
            obj.insert("robot".into(), robot);
            obj.insert(
                "robot_programs_written".into(),
                serde_json::json!(programs.is_ok()),
            );
            obj.insert(
                "robot_programs_why".into(),
                serde_json::json!(programs.err()),
            );
            obj.insert("ok".into(), serde_json::json!(self.ok));
            if let Ok(schedule) = self.schedule() {
                obj.insert("schedule".into(), serde_json::json!(schedule));
            }
        }
        summary
    }

    /// The print schedule (issue 11): every layer's start, end, wait and station change, from
    /// the timed robot plan when there is one (the clock of `trajectory.csv` and the programs),
    /// else from path length / print speed and the `[schedule]` waits. `schedule.csv` and the
    /// `schedule` block of `summary.json` are this.
    ///
    /// # Errors
    /// A `[schedule]` that does not fit the print ([`DesignError::Invalid`]).
    pub fn schedule(&self) -> Result<crate::schedule::Schedule, DesignError> {
        match &self.robot {
            Some(Ok(plan)) => crate::schedule::from_robot(&crate::robot_plan::layer_schedule(plan)),
            _ => crate::schedule::cap_schedule(&self.cap),
        }
    }

    /// The print time, s, computed once for the table, the robot line, the summary and the
    /// study row: the robot plan's total time (printing, layer changes, station changes) when
    /// there is a plan, else the path length over the print speed plus the layer changes
    /// ([`crate::path::PrintPath::time`]).
    pub fn print_time(&self) -> f64 {
        match &self.robot {
            Some(Ok(plan)) => plan.total_time,
            _ => self.cap.path.time,
        }
    }

    /// The plan whose robot programs may be written: there is one and the design passes, or
    /// [`Options::allow_fail`] was given. Otherwise why not, in words (for the summary).
    ///
    /// # Errors
    /// The reason when no programs are to be written.
    pub fn programs(&self) -> Result<&kappe_robot::Plan, String> {
        match &self.robot {
            None => Err("robot planning was not run".into()),
            Some(Err(e)) => Err(format!("the robot cannot print this design: {e}")),
            Some(Ok(_)) if !self.ok && !self.allow_fail => Err(
                "the design fails its checks; rerun with --allow-fail (Python: allow_fail=True) \
                 to write the programs anyway"
                    .into(),
            ),
            Some(Ok(plan)) => Ok(plan),
        }
    }

    /// The input of the HTML report ([`crate::report_input::report_input`]).
    pub fn report_input(&self) -> kappe_report::ReportInput {
        report_input(&self.cap, &self.extras)
    }

    /// The HTML report.
    ///
    /// # Errors
    /// What [`kappe_report::render_html`] rejects (a report input that does not validate).
    pub fn report_html(&self) -> Result<String, kappe_report::ReportError> {
        kappe_report::render_html(&self.report_input())
    }

    /// The lowest buckling factor over the analysed states, if any.
    pub fn min_blf(&self) -> Option<f64> {
        self.extras
            .states
            .iter()
            .filter_map(|s| s.blf)
            .fold(None, |m: Option<f64>, b| Some(m.map_or(b, |m| m.min(b))))
    }
}

/// The plan in `summary.json`: stations with their base poses, the tool, motion, time, clearance.
fn plan_summary(plan: &kappe_robot::Plan) -> serde_json::Value {
    serde_json::json!({
        "planned": true,
        "ok": true,
        "stations": plan.stations.iter().map(|s| serde_json::json!({
            "world_from_base": s.world_from_base,
            "layers": s.layers.iter().map(|l| l.layer).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "flange_from_tcp": plan.flange_from_tcp,
        "joint_motion_rad": plan.joint_motion,
        "cost_rad2": plan.cost,
        "print_time_s": plan.print_time,
        "total_time_s": plan.total_time,
        "min_clearance_m": plan.min_clearance,
        "min_self_distance_m": plan.min_self_distance,
        "max_speed_ratio": plan.max_speed_ratio,
        "max_acceleration_ratio": plan.max_acceleration_ratio,
        "programs": plan.parts.len(),
        "slowdowns": plan.slowdowns,
        "layer_times": kappe_robot::layer_times(plan),
        "geometry": plan.meshes,
    })
}

/// The schedule of a successful robot plan (its clock: print moves, layer changes, dwell,
/// station changes, waits), which the structural check then uses for the layers' ages; `None`
/// without a plan (the check then uses path length / print speed and the waits).
fn plan_schedule(
    cap: &Cap,
    robot: Option<&Result<kappe_robot::Plan, kappe_robot::RobotError>>,
) -> Result<Option<crate::schedule::Schedule>, DesignError> {
    match robot {
        Some(Ok(plan)) => {
            let s = crate::schedule::from_robot(&crate::robot_plan::layer_schedule(plan))?;
            Ok((s.layers.len() == cap.sections.layers.len()).then_some(s))
        }
        _ => Ok(None),
    }
}

/// The report's schedule block: the plan's schedule (or path length / speed and the waits) with
/// the analysis' governing checks and ages; `None` when the `[schedule]` does not fit the print
/// (the summary then leaves the schedule out too).
fn report_schedule(
    cap: &Cap,
    analysis: Option<&Analysis>,
    schedule: Option<crate::schedule::Schedule>,
) -> Option<kappe_report::PrintSchedule> {
    let schedule = match schedule {
        Some(s) => s,
        None => crate::schedule::cap_schedule(cap).ok()?,
    };
    Some(crate::schedule::report_schedule(cap, analysis, &schedule))
}

/// Plan the robot with the design's `[schedule]` waits (so the printed schedule is the checked
/// one: the waits become pauses in the programs), or with the planner's own minimum layer time
/// when the design sets none.
fn plan_with_schedule_waits(
    cap: &Cap,
) -> Result<Result<kappe_robot::Plan, kappe_robot::RobotError>, DesignError> {
    let waits = cap.design.schedule.waits(cap.sections.layers.len())?;
    if waits.iter().all(|w| *w == 0.0) {
        return Ok(crate::robot_plan::plan_robot(cap));
    }
    let layers = crate::robot_plan::print_layers(&cap.path);
    let given: Vec<kappe_robot::LayerWait> = layers
        .iter()
        .zip(&waits)
        .map(|(l, w)| kappe_robot::LayerWait {
            layer: l.layer,
            wait: *w,
        })
        .collect();
    Ok(crate::robot_plan::plan_robot_with_waits(cap, Some(&given)))
}
