//! Floor 5, **the verdict**: the one place where pass or fail is decided, from the domain
//! results of a run (the form, the analysis, the robot plan and its base-pose tolerance check),
//! never from the report's rows. `kappe design` (its exit status), every design of
//! `kappe study`, `kappe optimize`'s confirmation of its optimum, ceilings and the Python
//! package all take [`Verdict`] from [`verdict`], so they cannot disagree.
//!
//! The constraints come from the analysis when there is one; without one from the checks that
//! need no finite elements ([`preliminary_constraints`]: σ_min ≤ σ ≤ σ_max in every state from
//! the form-finding force pass, max |l_o| ≤ l_o,max). A robot plan that was tried and failed
//! fails the design; a plan that does not survive the base-pose errors of `[robot.tolerance]`
//! fails it when `[robot.tolerance] verdict = true`.

use serde::Serialize;

use crate::analysis::{Analysis, ConstraintResult};
use crate::form::{Cap, StateSummary};

/// Relative tolerance on stress limits. The fixed-geometry force pass balances every node to
/// ~1e-14 relative (method.md §9), so an arch whose forces are all compressive in exact
/// arithmetic shows tensile stresses of ~1e-11 Pa from roundoff (observed 3e-11 Pa against
/// 15 kPa of compression); without a tolerance σ_max = 0 would fail every design. 1e-9 of the
/// largest stress magnitude is far above roundoff and far below any physical meaning (the same
/// value as [`crate::analysis::STRESS_REL_TOL`]).
const STRESS_RELATIVE_TOLERANCE: f64 = crate::analysis::STRESS_REL_TOL;

/// Pass or fail, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// Every check holds.
    pub ok: bool,
    /// The checks that fail (empty when `ok`), constraints first, then the robot.
    pub failures: Vec<Failure>,
}

/// One failing check.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(tag = "check", rename_all = "snake_case")]
pub enum Failure {
    /// A structural constraint (`sigma_min`, `sigma_max`, `overhang_max`, `blf_min`, `strength`,
    /// `sliding`, …) fails; values in the constraint's SI unit.
    Constraint {
        /// The constraint's name in the design file.
        name: String,
        /// The worst value over the checked states (None: nothing was checked).
        worst: Option<f64>,
        /// The limit.
        limit: f64,
        /// Unit of `worst` and `limit` (`Pa`, `m`, `1`).
        unit: String,
        /// State where the worst value occurs.
        state: Option<usize>,
        /// Element, layer or mode where it occurs.
        element: String,
    },
    /// The robot cannot print the design.
    RobotPlan {
        /// The planner's reason.
        reason: String,
    },
    /// The plan does not tolerate the base-pose errors of `[robot.tolerance]`.
    BaseTolerance {
        /// Position error tolerated, m.
        position_m: f64,
        /// Yaw error tolerated, degrees.
        yaw_deg: f64,
        /// The first problem found.
        problem: String,
    },
    /// The moving base's conveyor-tracking simulation (issue 27) keeps the nozzle outside its
    /// tolerance, or could not run.
    BaseTracking {
        /// Largest nozzle-to-path deviation found, m (None when the simulation did not run).
        max_deviation_m: Option<f64>,
        /// Largest deviation allowed, m (None when the simulation did not run).
        allowed_m: Option<f64>,
        /// The first problem found.
        problem: String,
    },
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Constraint {
                name,
                state,
                element,
                ..
            } => {
                write!(f, "{name} fails")?;
                if let Some(s) = state {
                    write!(f, " at state {s}")?;
                }
                if !element.is_empty() {
                    write!(f, " ({element})")?;
                }
                Ok(())
            }
            Failure::RobotPlan { reason } => write!(f, "the robot cannot print it: {reason}"),
            Failure::BaseTolerance {
                position_m,
                yaw_deg,
                problem,
            } => write!(
                f,
                "the plan does not survive a base placed up to ±{:.1} mm, ±{yaw_deg:.1}° off \
                 ([robot.tolerance]): {problem}. Place the base more precisely and lower the \
                 tolerance to match, or widen the base search ([robot.setup.base])",
                position_m * 1e3
            ),
            Failure::BaseTracking { problem, .. } => write!(
                f,
                "the arm does not track the moving base within tolerance: {problem}"
            ),
        }
    }
}

/// The robot results the verdict looks at.
#[derive(Debug, Clone, Copy, Default)]
pub struct RobotResults<'a> {
    /// The plan, or why there is none; `None` when planning was not run.
    pub plan: Option<&'a Result<kappe_robot::Plan, kappe_robot::RobotError>>,
    /// The base-pose tolerance check of the plan, when run.
    pub tolerance: Option<&'a kappe_robot::tolerance::ToleranceReport>,
    /// The moving base's tracking simulation, when the base moves (issue 27).
    pub tracking: Option<&'a Result<kappe_robot::TrackingReport, String>>,
}

/// The verdict of a run: the analysis' constraints (or the [`preliminary_constraints`] without
/// one), the robot plan, and the base-pose tolerance check when the design puts it in the
/// verdict (`[robot.tolerance] verdict = true`).
pub fn verdict(cap: &Cap, analysis: Option<&Analysis>, robot: RobotResults<'_>) -> Verdict {
    let preliminary;
    let constraints: &[ConstraintResult] = match analysis {
        Some(a) => &a.constraints,
        None => {
            preliminary = preliminary_constraints(cap);
            &preliminary
        }
    };
    let mut failures: Vec<Failure> = constraints
        .iter()
        .filter(|c| !c.pass)
        .map(|c| Failure::Constraint {
            name: c.name.to_string(),
            worst: c.worst,
            limit: c.limit,
            unit: c.unit.to_string(),
            state: c.state,
            element: c.element.clone(),
        })
        .collect();
    match robot.plan {
        Some(Err(e)) => failures.push(Failure::RobotPlan {
            reason: e.to_string(),
        }),
        Some(Ok(_)) => {
            let tol = &cap.design.robot.tolerance;
            if tol.verdict
                && let Some(r) = robot.tolerance.filter(|r| !r.ok())
            {
                failures.push(Failure::BaseTolerance {
                    position_m: tol.position,
                    yaw_deg: tol.yaw_deg,
                    problem: r.problems.first().cloned().unwrap_or_default(),
                });
            }
            // The tracking simulation is a tolerance check too: in the verdict on the same
            // switch as the base-pose check.
            let tracking_failure = match robot.tracking {
                Some(Err(why)) => Some(Failure::BaseTracking {
                    max_deviation_m: None,
                    allowed_m: None,
                    problem: why.clone(),
                }),
                Some(Ok(r)) if !r.problems.is_empty() => Some(Failure::BaseTracking {
                    max_deviation_m: Some(r.max_deviation),
                    allowed_m: Some(r.max_deviation_allowed),
                    problem: r.problems[0].clone(),
                }),
                _ => None,
            };
            if tol.verdict
                && let Some(f) = tracking_failure
            {
                failures.push(f);
            }
        }
        None => {}
    }
    Verdict {
        ok: failures.is_empty(),
        failures,
    }
}

/// Stress tolerance in Pa (see [`STRESS_RELATIVE_TOLERANCE`]).
pub(crate) fn stress_tolerance(cap: &Cap) -> f64 {
    let scale = cap
        .states
        .iter()
        .map(|s| {
            s.forces
                .max_compression_stress
                .abs()
                .max(s.forces.max_tension_stress.abs())
        })
        .fold(0.0, f64::max);
    STRESS_RELATIVE_TOLERANCE * scale
}

/// Largest |l_o| among the first `printed` layers (print order), m.
pub(crate) fn max_overhang(cap: &Cap, printed: usize) -> f64 {
    cap.overhangs
        .iter()
        .take(printed)
        .fold(0.0, |m, o| m.max(o.abs()))
}

/// Preliminary per-state verdict: stresses within the limits and every printed layer's
/// overhang within l_o,max.
pub(crate) fn state_ok_preliminary(cap: &Cap, state: &StateSummary, tol: f64) -> bool {
    let k = &cap.design.constraints;
    state.forces.max_compression_stress >= k.sigma_min - tol
        && state.forces.max_tension_stress <= k.sigma_max + tol
        && max_overhang(cap, state.layers_printed) <= cap.design.overhang_max()
}

/// The constraints checkable without the finite-element analysis, worst value over all states,
/// in SI units: `sigma_min` (most compressive stress ≥ σ_min, Pa), `sigma_max` (largest stress
/// ≤ σ_max, Pa) and `overhang_max` (max |l_o| ≤ l_o,max, m). The names are those of
/// [`crate::analysis::analyze`], whose rows replace these.
pub fn preliminary_constraints(cap: &Cap) -> Vec<ConstraintResult> {
    let k = &cap.design.constraints;
    let tol = stress_tolerance(cap);
    let mut worst_c: (f64, Option<usize>) = (0.0, None);
    let mut worst_t: (f64, Option<usize>) = (f64::NEG_INFINITY, None);
    for s in &cap.states {
        if worst_c.1.is_none() || s.forces.max_compression_stress < worst_c.0 {
            worst_c = (s.forces.max_compression_stress, Some(s.index));
        }
        if worst_t.1.is_none() || s.forces.max_tension_stress > worst_t.0 {
            worst_t = (s.forces.max_tension_stress, Some(s.index));
        }
    }
    let worst_t = if worst_t.1.is_none() {
        (0.0, None)
    } else {
        worst_t
    };
    // The worst overhang is reached when its layer is printed: that state index is the layer's
    // print index (state q = layers 0..=q printed).
    let mut worst_o: (f64, Option<usize>) = (0.0, None);
    for (q, o) in cap.overhangs.iter().enumerate() {
        if worst_o.1.is_none() || o.abs() > worst_o.0 {
            worst_o = (o.abs(), Some(q));
        }
    }
    let layer_name = |q: usize| {
        cap.sections
            .layers
            .get(q)
            .map(|l| format!("layer {} over the layer before it", l.id))
    };
    let lo_max = cap.design.overhang_max();
    let states = cap.states.len();
    vec![
        ConstraintResult {
            name: "sigma_min",
            description: "most compressive stress ≥ σ_min (form-finding force pass)",
            limit: k.sigma_min,
            worst: Some(worst_c.0),
            state: worst_c.1,
            element: String::new(),
            pass: worst_c.0 >= k.sigma_min - tol,
            unit: "Pa",
            states_checked: states,
        },
        ConstraintResult {
            name: "sigma_max",
            description: "largest stress ≤ σ_max (form-finding force pass)",
            limit: k.sigma_max,
            worst: Some(worst_t.0),
            state: worst_t.1,
            element: String::new(),
            pass: worst_t.0 <= k.sigma_max + tol,
            unit: "Pa",
            states_checked: states,
        },
        ConstraintResult {
            name: "overhang_max",
            description: "largest layer overhang |l_o| ≤ l_o,max",
            limit: lo_max,
            worst: Some(worst_o.0),
            state: worst_o.1,
            element: worst_o.1.and_then(layer_name).unwrap_or_default(),
            pass: worst_o.0 <= lo_max,
            unit: "m",
            states_checked: states,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `constraints`: lines of the `[constraints]` table.
    fn cheap_cap(constraints: &str) -> Cap {
        // 3 centre layers and lh = 15 mm: a few start layers, a fast design; its 22 mm start
        // overhang is allowed here (these tests are about stresses and the robot).
        let design = crate::Design::from_toml_str(&format!(
            "[cap]\nlength = 0.05\n[print]\nlayer_height = 0.015\n\
             [constraints]\noverhang_max = 0.05\n{constraints}"
        ))
        .unwrap();
        crate::design_cap(&design, crate::Context::default()).unwrap()
    }

    #[test]
    fn preliminary_verdict_follows_the_stress_limit() {
        // The default cheap cap passes; the same cap with σ_min above its most compressive
        // stress (a limit it must fail) fails on sigma_min only.
        let cap = cheap_cap("");
        let v = verdict(&cap, None, RobotResults::default());
        assert!(v.ok, "{:?}", v.failures);
        let worst = cap
            .states
            .iter()
            .map(|s| s.forces.max_compression_stress)
            .fold(0.0, f64::min);
        let strict = cheap_cap(&format!("sigma_min = {}\n", worst / 2.0));
        let v = verdict(&strict, None, RobotResults::default());
        assert!(!v.ok);
        assert_eq!(v.failures.len(), 1);
        assert!(
            matches!(&v.failures[0], Failure::Constraint { name, .. } if name == "sigma_min"),
            "{:?}",
            v.failures
        );
    }

    #[test]
    fn the_analysis_decides_when_present_and_agrees_with_the_preliminary_checks() {
        let cap = cheap_cap("");
        let options = crate::analysis::AnalysisOptions {
            // Stresses and overhang only: the FE buckling solve is tested elsewhere.
            buckling: false,
            ..Default::default()
        };
        let analysis =
            crate::analysis::analyze(&cap, &options, crate::analysis::Request::default()).unwrap();
        let with = verdict(&cap, Some(&analysis), RobotResults::default());
        let without = verdict(&cap, None, RobotResults::default());
        assert_eq!(with.ok, without.ok);
        // An analysis that fails a constraint fails the design, whatever the preliminary
        // checks say.
        let mut failing = analysis.clone();
        if let Some(c) = failing.constraints.first_mut() {
            c.pass = false;
        }
        let v = verdict(&cap, Some(&failing), RobotResults::default());
        assert!(!v.ok);
        assert_eq!(v.failures.len(), 1);
    }

    #[test]
    fn a_failed_robot_plan_fails_the_design() {
        let cap = cheap_cap("");
        let plan = Err(kappe_robot::RobotError::Verification(vec!["test".into()]));
        let v = verdict(
            &cap,
            None,
            RobotResults {
                plan: Some(&plan),
                tolerance: None,
                tracking: None,
            },
        );
        assert!(!v.ok);
        assert!(matches!(v.failures[0], Failure::RobotPlan { .. }));
    }
}
