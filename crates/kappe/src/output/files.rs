//! The files of a run, as names and bytes: what `kappe design` writes into its output
//! directory, produced once for the CLI and the Python package.

use kappe_robot::Plan;

use super::{OutputError, Result};
use crate::Outcome;

/// One file of an output directory: its `/`-separated path relative to the directory, and its
/// contents.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputFile {
    /// Relative path, e.g. `summary.json` or `bay_1/report.html`.
    pub name: String,
    /// The contents.
    pub bytes: Vec<u8>,
}

impl OutputFile {
    /// A file named `name` holding `bytes`.
    pub fn new(name: impl Into<String>, bytes: impl Into<Vec<u8>>) -> Self {
        Self {
            name: name.into(),
            bytes: bytes.into(),
        }
    }

    /// The same file one directory down, under `dir/`.
    #[must_use]
    pub fn under(mut self, dir: &str) -> Self {
        self.name = format!("{dir}/{}", self.name);
        self
    }
}

fn json(name: &str, value: &impl serde::Serialize) -> Result<OutputFile> {
    serde_json::to_vec_pretty(value)
        .map(|b| OutputFile::new(name, b))
        .map_err(|e| OutputError::Produce(format!("cannot write {name}: {e}")))
}

/// The outputs of a timed robot plan: `trajectory.csv`, `plan.json` (what `kappe robot resume`
/// reads), and when `programs` the controller-sized program files, each passing the independent
/// URScript check against the plan's target limit, their index `programs.json`, and one combined
/// `program.script` only when the whole print fits in one file.
///
/// # Errors
/// [`OutputError::Produce`] when a program fails the URScript check or a writer fails (a bug in
/// Kappe, not in the input).
pub fn plan_files(plan: &Plan, prefix: &str, programs: bool) -> Result<Vec<OutputFile>> {
    let produce = |e: kappe_robot::RobotError| OutputError::Produce(format!("robot outputs: {e}"));
    let files = if programs {
        kappe_robot::files::linted_programs(plan, prefix).map_err(produce)?
    } else {
        Vec::new()
    };
    let out = kappe_robot::files::plan_outputs(plan, &files).map_err(produce)?;
    Ok(out
        .into_iter()
        // No index without programs.
        .filter(|(name, _)| !files.is_empty() || name != "programs.json")
        .map(|(name, bytes)| OutputFile::new(name, bytes))
        .collect())
}

/// The outputs of a moving-base plan (issue 27): `trajectory.csv` with the base pose
/// (`base_x, base_y, base_yaw`, world, m and rad) on every row, `plan.json`,
/// `base_trajectory.csv` and `base_trajectory.json` (what the base follows), and when `programs`
/// the conveyor-tracking program files, each passing `kappe_robot::lint_tracking` against the
/// plan's target limit, and their index `programs.json` (`kappe_robot::tracking_index_json`).
///
/// # Errors
/// [`OutputError::Produce`] when a program fails the tracking lint or a writer fails.
pub fn moving_plan_files(
    mp: &kappe_robot::MovingPlan,
    prefix: &str,
    programs: bool,
) -> Result<Vec<OutputFile>> {
    let produce = |e: kappe_robot::RobotError| OutputError::Produce(format!("robot outputs: {e}"));
    // plan.json is the whole moving plan (arm plan, base trajectory, lead): the station writer
    // verifies its plan from fixed stations, which a moving plan is not.
    let mut out = vec![
        OutputFile::new("trajectory.csv", mp.trajectory_csv()),
        json("plan.json", mp)?,
    ];
    out.push(OutputFile::new(
        "base_trajectory.csv",
        mp.trajectory.to_csv(),
    ));
    out.push(OutputFile::new(
        "base_trajectory.json",
        mp.trajectory.to_json(),
    ));
    if programs {
        let files = kappe_robot::tracking_program_files(
            mp,
            &kappe_robot::ConveyorOptions::default(),
            prefix,
        )
        .map_err(produce)?;
        let max = mp.plan.options.program.max_moves_per_program;
        let limits = mp.plan.options.limits.position();
        for (f, _) in &files {
            let rep = kappe_robot::lint_tracking(&f.text, max, &limits);
            if !rep.ok() {
                return Err(OutputError::Produce(format!(
                    "{} fails the URScript check: {}",
                    f.name,
                    rep.problems.join("; ")
                )));
            }
            out.push(OutputFile::new(f.name.clone(), f.text.clone()));
        }
        out.push(OutputFile::new(
            "programs.json",
            kappe_robot::tracking_index_json(&files),
        ));
    }
    Ok(out)
}

impl Outcome {
    /// Every file `kappe design` writes for this outcome: `summary.json`, `network.json`,
    /// `path.csv`, `cap.obj`, `cap.glb`, `report.html`, `schedule.csv`, and with a robot plan
    /// its [`plan_files`] (programs only when [`Outcome::programs`] allows them).
    ///
    /// # Errors
    /// [`OutputError::Produce`] when a file cannot be produced (see [`plan_files`]).
    pub fn files(&self) -> Result<Vec<OutputFile>> {
        let cap = &self.cap;
        let network = crate::output::network::network_json(cap)
            .map_err(|e| OutputError::Produce(format!("cannot write network.json: {e}")))?;
        let report = self
            .report_html()
            .map_err(|e| OutputError::Produce(format!("cannot write report.html: {e}")))?;
        let mut out = vec![
            json("summary.json", &self.summary())?,
            json("network.json", &network)?,
            OutputFile::new("path.csv", cap.path.to_csv()),
            OutputFile::new("cap.obj", cap.mesh.to_obj(&cap.design.name)),
            OutputFile::new(
                "cap.glb",
                cap.mesh
                    .to_glb()
                    .map_err(|e| OutputError::Produce(e.to_string()))?,
            ),
            OutputFile::new("report.html", report),
        ];
        // The layer times the structural check and the robot share (issue 11).
        out.push(OutputFile::new("schedule.csv", self.schedule.to_csv()));
        match (&self.robot, &self.moving) {
            (Some(Ok(_)), Some(m)) => out.extend(moving_plan_files(
                &self.marked_moving(&m.plan),
                "program_part",
                self.programs().is_ok(),
            )?),
            (Some(Ok(plan)), None) => {
                let plan = self.marked_plan(plan);
                let programs = self.programs();
                out.extend(plan_files(&plan, "program_part", programs.is_ok())?);
                // The operator's station sheet (issue 28): base pose, tolerance, layers,
                // programs and time per station.
                let sheet = kappe_robot::stations::station_sheet(
                    &plan,
                    self.base_tolerance.as_ref(),
                    programs
                        .as_ref()
                        .map(|_| "program_part")
                        .map_err(String::as_str),
                );
                out.push(OutputFile::new("stations.md", sheet));
            }
            _ => {}
        }
        Ok(out)
    }

    /// `plan` as its files carry it: marked as the plan of a failing design when the design
    /// fails, so that its programs (with `--allow-fail`) and `plan.json` (which
    /// `kappe robot resume` reads) say so (issue 28).
    pub fn marked_plan(&self, plan: &Plan) -> Plan {
        let mut plan = plan.clone();
        if !self.verdict.ok {
            let mut why: Vec<String> = self
                .analysis
                .iter()
                .flat_map(|a| a.failing())
                .map(|c| format!("{} fails", c.name))
                .collect();
            if let Some(t) = self.base_tolerance.as_ref().filter(|t| !t.ok()) {
                why.push(format!(
                    "the plan does not survive a base ±{:.1} mm, ±{:.1}° off",
                    t.tolerance.position * 1e3,
                    t.tolerance.yaw_deg
                ));
            }
            plan.mark.failing_design = Some(if why.is_empty() {
                "the design fails its checks".into()
            } else {
                why.join("; ")
            });
        }
        plan
    }

    /// [`Outcome::marked_plan`] for a moving plan: its arm plan marked, so the tracking
    /// programs and `plan.json` of a failing design say so as the station programs do.
    pub fn marked_moving(&self, mp: &kappe_robot::MovingPlan) -> kappe_robot::MovingPlan {
        let mut mp = mp.clone();
        mp.plan = self.marked_plan(&mp.plan);
        mp
    }

    /// The table `kappe design` prints: the design, the layer arch, the states, the worst
    /// stresses, overhang, thrust, path, material and print time, the analysis report and the
    /// robot line; `out` is the output directory it names, `programs` the number of program
    /// files written.
    pub fn table(&self, out: &std::path::Path, programs: usize) -> String {
        use std::fmt::Write;
        let cap = &self.cap;
        let d = &cap.design;
        let fold = |f: fn(&crate::StateSummary) -> f64, init: f64, pick: fn(f64, f64) -> f64| {
            cap.states.iter().map(f).fold(init, pick)
        };
        let worst_c = fold(|s| s.forces.max_compression_stress, 0.0, f64::min);
        let worst_t = fold(|s| s.forces.max_tension_stress, 0.0, f64::max);
        let worst_res = fold(|s| s.forces.max_residual, 0.0, f64::max);
        let overhang = cap.overhangs.iter().fold(0.0_f64, |m, o| m.max(o.abs()));
        let mut t = String::new();
        let row = |t: &mut String, name: &str, value: String| {
            let _ = writeln!(t, "  {name:<34} {value:>14}");
        };
        let _ = writeln!(t, "Kappe design \"{}\"", d.name);
        let _ = writeln!(
            t,
            "  span {:.3} m, rise {:.3} m, length {:.3} m, tilt {:.1}°, lh {:.1} mm, lw {:.1} mm",
            d.cap.span,
            d.cap.rise,
            d.cap.length,
            d.cap.tilt_deg,
            d.print.layer_height * 1e3,
            d.print.layer_width * 1e3
        );
        let _ = writeln!(
            t,
            "  layer arch: {} segments of {:.2} mm, crown thrust {:.3} N (catenary a = {:.4} m)",
            cap.arch.segments(),
            cap.arch.segment_length * 1e3,
            -cap.arch.crown_force,
            cap.catenary.a
        );
        let _ = writeln!(
            t,
            "  layers: {} start + {} centre = {} states; final network {} nodes",
            cap.sections.n_start,
            cap.sections.n_centre,
            cap.states.len(),
            cap.final_state.network.nodes.len()
        );
        row(&mut t, "quantity", "value".into());
        row(
            &mut t,
            "max compression stress [kPa]",
            format!("{:.2}", worst_c / 1e3),
        );
        // kPa like the compression: the all-compression arch's roundoff tension (~1e-9 Pa)
        // reads 0.00, not as a tension in scientific notation (issue 28).
        row(
            &mut t,
            "max tension stress [kPa]",
            crate::analysis::check::readable(worst_t, "Pa").replace(" kPa", ""),
        );
        row(&mut t, "max node residual [N]", format!("{worst_res:.3e}"));
        row(
            &mut t,
            "max layer overhang [mm]",
            format!("{:.2}", overhang * 1e3),
        );
        if let Some(s) = cap.states.last() {
            row(
                &mut t,
                "start-section thrust on base [N]",
                format!("{:.1}", s.forces.column_end_reaction[1]),
            );
            row(
                &mut t,
                "start-section H/V",
                format!("{:.3}", s.forces.column_end_hv_ratio),
            );
        }
        row(
            &mut t,
            "path length [m]",
            format!("{:.2}", cap.path.print_length),
        );
        row(
            &mut t,
            "volume [l]",
            format!("{:.2}", cap.path.volume * 1e3),
        );
        row(&mut t, "mass [kg]", format!("{:.1}", cap.path.mass));
        row(
            &mut t,
            "print time [min]",
            format!("{:.1}", self.print_time() / 60.0),
        );
        if let Some(r) = &self.reliability {
            // One line (issue 24): the print's β against its target, and P_f (FORM's, then
            // SORM's, which the verdict judges).
            row(
                &mut t,
                &format!("reliability β (min {:.2}) / P_f", r.beta_min),
                format!("{:.2} / {:.2e}", r.beta, r.pf)
                    + &r.sorm.as_ref().map_or(String::new(), |s| {
                        format!(", SORM {:.2} / {:.2e}", s.beta, s.pf)
                    }),
            );
            if let Some(mc) = &r.monte_carlo {
                // FORM's P_f against the sampled one, with its 95 % interval.
                row(
                    &mut t,
                    &format!(
                        "Monte Carlo P_f ({}, N = {})",
                        match mc.method {
                            crate::input::uncertainty::McMethod::Importance => "importance",
                            _ => "crude",
                        },
                        mc.samples
                    ),
                    format!(
                        "{:.3e} [{:.3e}, {:.3e}], FORM {:.3e} {}",
                        mc.pf,
                        mc.pf_interval[0],
                        mc.pf_interval[1],
                        mc.form_pf,
                        if mc.form_in_interval {
                            "inside"
                        } else {
                            "outside"
                        }
                    ) + &mc.sorm_pf.map_or(String::new(), |p| {
                        format!(
                            ", SORM {p:.3e} {}",
                            if mc.sorm_in_interval == Some(true) {
                                "inside"
                            } else {
                                "outside"
                            }
                        )
                    }),
                );
            }
        }
        let _ = writeln!(
            t,
            "  wrote {}/{{summary.json, network.json, path.csv, cap.obj, cap.glb, report.html}}",
            out.display()
        );
        if let Some(analysis) = &self.analysis {
            for line in analysis.constraint_lines().lines() {
                let _ = writeln!(t, "  {line}");
            }
            // The one verdict (issue 22): the constraints, the print's reliability (issue 24)
            // and the robot's checks, not the analysis' constraints alone.
            if let Some(r) = self.reliability.as_ref().filter(|r| r.beta < r.beta_min) {
                let _ = writeln!(
                    t,
                    "  {:<13} FAIL limit {:.2}, worst {:.2} at state {}, {}\n  {:<18} to fix: {}",
                    "beta_min",
                    r.beta_min,
                    r.beta,
                    r.governing_state,
                    r.governing_check,
                    "",
                    crate::analysis::check::levers("beta_min")
                );
            }
            let _ = writeln!(
                t,
                "  {}",
                if self.verdict.ok {
                    "design passes every constraint"
                } else {
                    "design FAILS"
                }
            );
        }
        let _ = match &self.robot {
            Some(Ok(plan)) => writeln!(
                t,
                "  robot: {} station(s), joint motion {:.1} rad, {:.1} min, min clearance {:.1} mm, \
                 {} slowdown(s); wrote trajectory.csv, plan.json{}",
                plan.stations.len(),
                plan.joint_motion,
                self.print_time() / 60.0,
                plan.min_clearance * 1e3,
                plan.slowdowns.len(),
                match self.programs() {
                    Ok(_) => format!(", {programs} program(s) listed in programs.json"),
                    Err(why) => format!("; no programs: {why}"),
                }
            ),
            Some(Err(e)) => writeln!(t, "  robot: NOT PLANNED: {e}"),
            None => writeln!(t, "  robot: planning skipped"),
        };
        // Whether the plan survives the stated base error, never only in summary.json.
        if let Some(r) = &self.base_tolerance {
            let tol = &r.tolerance;
            let _ = if r.ok() {
                writeln!(
                    t,
                    "  base tolerance: the plan survives a base up to ±{:.1} mm, ±{:.1}° off at every station",
                    tol.position * 1e3,
                    tol.yaw_deg
                )
            } else {
                writeln!(
                    t,
                    "  base tolerance: FAILS at ±{:.1} mm, ±{:.1}° ({} problem(s){}): {}",
                    tol.position * 1e3,
                    tol.yaw_deg,
                    r.problems.len(),
                    if d.robot.tolerance.verdict {
                        ""
                    } else {
                        "; not in the verdict: [robot.tolerance] verdict = false"
                    },
                    r.problems.first().map_or("", String::as_str)
                )
            };
        }
        t
    }

    /// Why the design fails, one line each (the robot, then every failing constraint), each
    /// starting with `level` (`error`, or `warning` when failing is allowed).
    pub fn failure_lines(&self, level: &str) -> Vec<String> {
        let mut lines = Vec::new();
        if let Some(Err(e)) = &self.robot {
            lines.push(format!("{level}: the robot cannot print this design: {e}"));
        } else {
            // A plan that exists but fails the design, e.g. one that does not survive the
            // stated base error ([robot.tolerance]).
            for f in &self.verdict.failures {
                if let crate::verdict::Failure::BaseTolerance { .. } = f {
                    lines.push(format!("{level}: {f}"));
                }
            }
        }
        if !self.verdict.ok {
            use crate::analysis::check::{levers, readable};
            for c in self.analysis.iter().flat_map(|a| a.failing()) {
                lines.push(format!(
                    "{level}: constraint {} fails: worst {} against the limit {}{}",
                    c.name,
                    c.worst.map_or("n/a".into(), |w| readable(w, c.unit)),
                    readable(c.limit, c.unit),
                    c.state
                        .map_or(String::new(), |s| format!(" (state {s}, {})", c.element))
                ));
                lines.push(format!("  to fix: {}", levers(c.name)));
            }
        }
        lines
    }
}
