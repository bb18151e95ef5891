//! The whole pipeline of one design: form-finding ([`crate::design_cap`]), then the robot plan
//! ([`crate::robot_plan::plan_robot`], when asked for), the analysis of every state
//! ([`crate::analysis::analyze`], when asked for; with a plan, the layers' ages come from the
//! plan's clock), the verdict ([`crate::verdict`]), the
//! summary (`summary.json`) and the report input ([`crate::output::report_input`]).
//!
//! [`run`] is what `kappe design`, every design of `kappe study` and the Python `kappe.design`
//! call, so their numbers and verdicts cannot disagree. [`evaluate`] is the part after
//! form-finding, for callers that already hold a [`Cap`].

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use crate::analysis::{Analysis, AnalysisOptions};
use crate::form::cap::Cap;
use crate::input::design::Design;
use crate::input::error::DesignError;
use crate::verdict::{RobotResults, Verdict};

/// What [`run`] does after form-finding.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Options {
    /// The analysis of every state (stresses, overhang, shell buckling); `None`: no analysis,
    /// the verdict then takes the preliminary checks ([`crate::verdict::preliminary_constraints`]).
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
    /// The robot plan, or why there is none; `None` when planning was not asked for (or the
    /// design disables the robot).
    pub robot: Option<Result<kappe_robot::Plan, kappe_robot::RobotError>>,
    /// The moving-base part of the plan (issue 27) when `[robot.base] mode = "moving"` and it
    /// planned: the base trajectory and the tracking simulation. `robot` then holds its arm
    /// plan (`MovingRun::plan.plan`), so the schedule, the summary and the verdict read it as
    /// any plan.
    pub moving: Option<MovingRun>,
    /// The base-pose tolerance check of the plan (`[robot.tolerance]`, issue 15); `None`
    /// without a plan or with `check = false`. For a moving plan it is
    /// `kappe_robot::check_moving_tolerance` (the base off its trajectory by the same errors).
    pub base_tolerance: Option<kappe_robot::tolerance::ToleranceReport>,
    /// The one schedule of the run (issue 11): every layer's start, end, wait and station
    /// change on the robot plan's clock when there is a plan, else from path length / print
    /// speed and the `[schedule]` waits. The analysis ages the layers on it; `schedule.csv`
    /// and the `schedule` block of `summary.json` are it.
    pub schedule: crate::schedule::Schedule,
    /// Stresses, overhang and buckling of every state, and the constraint report; `None` when
    /// not asked for.
    pub analysis: Option<Analysis>,
    /// β and P_f of every state and of the print under `[uncertainty]` (None without it).
    pub reliability: Option<crate::analysis::reliability::Reliability>,
    /// Pass or fail, and why ([`crate::verdict::verdict`]).
    pub verdict: Verdict,
    /// [`Options::allow_fail`] of the run.
    pub allow_fail: bool,
}

/// The moving-base results of a run (issue 27).
#[derive(Debug)]
pub struct MovingRun {
    /// The moving plan: the arm plan, the base trajectory, the lead and reach margin.
    pub plan: kappe_robot::MovingPlan,
    /// The controller's conveyor tracking simulated under the base's expected errors
    /// (`kappe_robot::simulate_tracking` with its documented default errors and tolerance), or
    /// why it could not run.
    pub tracking: Result<kappe_robot::TrackingReport, String>,
}

impl MovingRun {
    /// Whether the tracking simulation ran and kept the nozzle within its tolerance.
    pub fn tracking_ok(&self) -> bool {
        self.tracking.as_ref().is_ok_and(|r| r.problems.is_empty())
    }
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
    let cap = crate::form::cap::design_cap(
        design,
        crate::input::context::Context::new(&|total| states.tick(total), &stop),
    )?;
    check(&stop)?;
    after_form(cap, options, on_progress, &stop, None)
}

/// The pipeline after form-finding (see [`run`]): analysis, robot plan, verdict. `fe`: the
/// finite-element results of the analysed states computed elsewhere
/// ([`crate::analysis::check::state_fe`] over [`crate::analysis::check::fe_runs`]: the
/// designer's Web Workers), so the designer's verdict is the one `kappe design` reaches; states
/// missing from it count as not analysed. Plan no robot then (`options.robot = false`) when
/// `fe` was computed on the schedule without a plan ([`crate::schedule::cap_schedule`]).
/// `None`: solve every analysed state here.
///
/// # Errors
/// As [`run`], without the form-finding ones.
pub fn evaluate(
    cap: Cap,
    options: &Options,
    given: Option<Given>,
    on_progress: OnProgress<'_>,
) -> Result<Outcome, DesignError> {
    after_form(cap, options, on_progress, &AtomicBool::new(false), given)
}

/// The finite-element results [`evaluate`] is given, computed elsewhere (the designer's Web
/// Workers): the first pass of the analysed states and the mesh-error pass's solves so far
/// ([`crate::analysis::Request`]'s `fe` and `refined`).
#[derive(Clone, Debug, Default)]
pub struct Given {
    /// [`crate::analysis::check::state_fe`] of the states over
    /// [`crate::analysis::check::fe_runs`] (first pass, print-layer mesh).
    pub fe: Vec<crate::analysis::check::StateFe>,
    /// The mesh-error pass's solves ([`crate::analysis::check::RefineBatch`] asks for them).
    pub refined: crate::analysis::check::RefineSolves,
    /// The as-printed increments the first pass's buckling solves gave (by state; asked with
    /// [`crate::analysis::FeRequest::extra`]): the as-printed pass solves only the others.
    pub increments: std::collections::HashMap<usize, crate::analysis::Increment>,
}

fn after_form(
    cap: Cap,
    options: &Options,
    on_progress: OnProgress<'_>,
    stop: &AtomicBool,
    given: Option<Given>,
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
    // A moving plan hands its arm plan to the rest of the run and keeps the base's part.
    let (robot, moving) = match robot {
        Some(Planned::Moving(m)) => match m {
            Ok(mp) => {
                let tracking = kappe_robot::simulate_tracking(
                    &mp,
                    &kappe_robot::TrackingErrors::default(),
                    &kappe_robot::TrackingTolerance::default(),
                )
                .map_err(|e| e.to_string());
                (
                    Some(Ok(mp.plan.clone())),
                    Some(MovingRun { plan: mp, tracking }),
                )
            }
            Err(e) => (Some(Err(e)), None),
        },
        Some(Planned::Stations(p)) => (Some(p), None),
        None => (None, None),
    };
    check(stop)?;
    let schedule = run_schedule(&cap, robot.as_ref())?;
    let fe = Ticker::new(on_progress, stop, Stage::Analysis);
    let (given_fe, refined, increments) = match given {
        Some(g) => (Some(g.fe), Some(g.refined), g.increments),
        None => (None, None, Default::default()),
    };
    let analysis = match &options.analysis {
        Some(o) => Some(crate::analysis::analyze(
            &cap,
            o,
            crate::analysis::Request {
                schedule: Some(&schedule),
                fe: given_fe,
                refined,
                increments,
                context: crate::input::context::Context::new(&|total| fe.tick(total), stop),
            },
        )?),
        None => None,
    };
    check(stop)?;
    // Reliability under `[uncertainty]` (issue 24): None without the table, so nothing changes.
    let mut reliability = match &analysis {
        Some(a) => crate::analysis::reliability::reliability(&cap, a, &schedule)?,
        None => None,
    };
    // `[uncertainty] monte_carlo = N`: the print's governing states sampled (issue 24).
    if let (Some(r), Some(a)) = (reliability.as_mut(), &analysis) {
        r.monte_carlo =
            crate::analysis::design_monte_carlo::design_monte_carlo(&cap, a, &schedule, r)?;
    }
    check(stop)?;
    // A relocated base is never exactly where planned (issue 15): re-check the plan under the
    // base-pose errors of `[robot.tolerance]`; with `verdict = true` a failure fails the design.
    let tol = &cap.design.robot.tolerance;
    let base_tolerance = match (&robot, &moving) {
        (Some(Ok(_)), Some(m)) if tol.check => Some(kappe_robot::check_moving_tolerance(
            &m.plan,
            &tol.base_tolerance(),
        )),
        (Some(Ok(plan)), None) if tol.check => {
            let mut rep = kappe_robot::tolerance::check_base_tolerance(plan, &tol.base_tolerance());
            if tol.margins {
                rep.margins = kappe_robot::tolerance::station_margins(plan, &tol.base_tolerance());
            }
            Some(rep)
        }
        _ => None,
    };
    let mut verdict = crate::verdict::verdict(
        &cap,
        analysis.as_ref(),
        RobotResults {
            plan: robot.as_ref(),
            tolerance: base_tolerance.as_ref(),
            tracking: moving.as_ref().map(|m| &m.tracking),
        },
    );
    // SORM's β where there is one (`Reliability::verdict`): the better estimate of the print's
    // P_f; FORM's stays in the summary.
    if let Some(r) = &reliability
        && let (beta, gov_state, gov_check) = r.verdict()
        && beta < r.beta_min
    {
        // After the structural constraints, before the robot's failures.
        let at = verdict
            .failures
            .iter()
            .take_while(|f| matches!(f, crate::verdict::Failure::Constraint { .. }))
            .count();
        verdict.failures.insert(
            at,
            crate::verdict::Failure::Constraint {
                name: "beta_min".into(),
                worst: Some(beta),
                limit: r.beta_min,
                unit: "1".into(),
                state: Some(gov_state),
                element: gov_check.to_owned(),
            },
        );
        verdict.ok = false;
    }
    Ok(Outcome {
        cap,
        robot,
        reliability,
        moving,
        base_tolerance,
        schedule,
        analysis,
        verdict,
        allow_fail: options.allow_fail,
    })
}

impl Outcome {
    /// The print time, s, computed once for the table, the robot line, the summary and the
    /// study row: the robot plan's total time (printing, layer changes, station changes) when
    /// there is a plan, else the path length over the print speed plus the layer changes
    /// ([`crate::form::path::PrintPath::time`]).
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
            Some(Ok(_)) if !self.verdict.ok && !self.allow_fail => Err(
                "the design fails its checks; rerun with --allow-fail (Python: allow_fail=True) \
                 to write the programs anyway"
                    .into(),
            ),
            Some(Ok(plan)) => Ok(plan),
        }
    }

    /// The lowest buckling factor over the analysed states, if any.
    pub fn min_blf(&self) -> Option<f64> {
        self.analysis
            .iter()
            .flat_map(|a| &a.states)
            .filter_map(|s| s.blf)
            .fold(None, |m: Option<f64>, b| Some(m.map_or(b, |m| m.min(b))))
    }
}

/// The one schedule of a run: the timed robot plan's clock (print moves, layer changes, dwell,
/// station changes, waits) when there is a plan, else path length / print speed and the
/// `[schedule]` waits.
///
/// # Errors
/// A `[schedule]` that does not fit the print, or a plan whose layers are not the cap's
/// ([`DesignError::Invalid`], naming `schedule`).
fn run_schedule(
    cap: &Cap,
    robot: Option<&Result<kappe_robot::Plan, kappe_robot::RobotError>>,
) -> Result<crate::schedule::Schedule, DesignError> {
    let schedule = match robot {
        Some(Ok(plan)) => crate::schedule::from_robot(&crate::robot_plan::layer_schedule(plan))?,
        _ => crate::schedule::cap_schedule(cap)?,
    };
    let layers = cap.sections.layers.len();
    if schedule.layers.len() != layers {
        return Err(DesignError::Invalid {
            field: "schedule",
            value: format!("{} layers timed", schedule.layers.len()),
            allowed: format!("allowed: one time per printed layer ({layers})"),
        });
    }
    Ok(schedule)
}

/// A plan from stations or with the base moving.
// Both variants are large; the value lives only from planning to the next statement, so the
// size difference costs one move.
#[allow(clippy::large_enum_variant)]
enum Planned {
    Stations(Result<kappe_robot::Plan, kappe_robot::RobotError>),
    Moving(Result<kappe_robot::MovingPlan, kappe_robot::RobotError>),
}

/// Plan the robot with the design's `[schedule]` waits (so the printed schedule is the checked
/// one: the waits become pauses in the programs), or with the planner's own minimum layer time
/// when the design sets none; from stations or with the base moving (`[robot.base]`).
fn plan_with_schedule_waits(cap: &Cap) -> Result<Planned, DesignError> {
    let waits = cap.design.schedule.waits(cap.sections.layers.len())?;
    let moving = match &cap.design.robot.base {
        kappe_robot::BaseMode::Moving(m) => Some(m),
        kappe_robot::BaseMode::Stations => None,
    };
    if waits.iter().all(|w| *w == 0.0) {
        return Ok(match moving {
            Some(m) => Planned::Moving(crate::robot_plan::plan_robot_moving(cap, m, None)),
            None => Planned::Stations(crate::robot_plan::plan_robot(cap)),
        });
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
    Ok(match moving {
        Some(m) => Planned::Moving(crate::robot_plan::plan_robot_moving(cap, m, Some(&given))),
        None => Planned::Stations(crate::robot_plan::plan_robot_with_waits(cap, Some(&given))),
    })
}
