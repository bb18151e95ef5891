//! The inverse problem of the print schedule (issue 11 §4): the least total print time for which
//! every state of a cap passes the green-state checks, by choosing a wait after each layer.
//!
//! **Why waits only.** A state's ages are sums of layer times and pauses (the top layer always has
//! age 0), so a slower print speed ages the lower layers exactly like a wait of the same total
//! length, but spread over every layer whether it helps or not. At the fastest allowed speed
//! (the design's `print_speed`) with waits placed where they are needed, the print is never
//! longer than at a slower speed for the same ages; so only waits are searched.
//!
//! **Greedy forward search.** States are checked in print order with the waits found so far.
//! When the state with top layer q fails, the wait after layer q − 1 (just before the top) is
//! raised by bisection to the least value that makes it pass: a wait there ages *every* layer
//! below the top, so it buys the most age per second, and it also helps every later state. If
//! even `wait_max` does not help (the top layer itself, at age 0, fails; or the wait is bounded),
//! the state is reported as infeasible with its binding check. Every check only improves with
//! age in the time models of [`crate::input::material`] (non-negative rates), which the bisection needs.
//!
//! **β target (issue 24).** With `[uncertainty]` a state passes only when, besides the
//! deterministic checks, its reliability index β (SORM of its random checks as a series system,
//! FORM where SORM does not apply; [`crate::analysis::reliability::state_form`], the function
//! the run's reliability uses, and the β its `beta_min` verdict judges) reaches
//! `constraints.beta_min` (default [`crate::input::uncertainty::BETA_MIN_DEFAULT`]). The state's
//! variables are drifted to its print time on the schedule being tried, so a drying mix is
//! followed exactly: a wait ages the layers below (stiffer) but prints the top later (drifted).
//! β then need not grow with the wait when the drift outpaces the ageing; the bisection assumes
//! it does, and the final plan's states are re-checked (`states`) so a miss shows there. The
//! stress checks of the force pass are left out here: no wait changes them.

use serde::Serialize;

use crate::analysis::buckling::state_material;
use crate::analysis::green::{CapGreen, FailureMode};
use crate::analysis::{AnalysisOptions, BucklingStatus, state_buckling};
use crate::form::cap::Cap;
use crate::input::error::DesignError;
use crate::schedule::Schedule;

/// Result of one state's check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StateCheck {
    /// State index (top print index).
    pub state: usize,
    /// BLF (None: no shell).
    pub blf: Option<f64>,
    /// Worst strength utilisation.
    pub strength: Option<f64>,
    /// Worst sliding utilisation.
    pub sliding: Option<f64>,
    /// The check with the largest utilisation (BLF_min/BLF for buckling).
    pub governing: Option<FailureMode>,
    /// β of the state under `[uncertainty]` (None: no table, or no random check).
    pub beta: Option<f64>,
    /// All pass (and β ≥ β_min with `[uncertainty]`).
    pub pass: bool,
}

/// A wait the search had to add.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Binding {
    /// The state that needed it.
    pub state: usize,
    /// Wait after layer `state − 1`, s.
    pub wait_s: f64,
    /// The check that failed without it (the governing one when only β fell short).
    pub check: Option<FailureMode>,
    /// β without the wait (with `[uncertainty]`).
    pub beta_before: Option<f64>,
}

/// The least-time schedule.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WaitPlan {
    /// The schedule with the waits.
    pub schedule: Schedule,
    /// Print time with the waits (end of the last layer), s.
    pub total_s: f64,
    /// Print time without waits, s.
    pub total_without_waits_s: f64,
    /// Where waits were needed and what bound them.
    pub binding: Vec<Binding>,
    /// States that fail even with `wait_max` before their top layer.
    pub infeasible: Vec<StateCheck>,
    /// Every state's check with the final waits.
    pub states: Vec<StateCheck>,
    /// The β target (None without `[uncertainty]`).
    pub beta_min: Option<f64>,
}

/// Check the state with top print index `top` on `schedule`.
pub fn check_state_on(
    cap: &Cap,
    green: &CapGreen,
    options: &AnalysisOptions,
    schedule: &Schedule,
    top: usize,
) -> Result<StateCheck, DesignError> {
    let state = cap.state(top)?;
    let mut g = green.clone();
    g.schedule = schedule.clone();
    let mut material = state_material(cap, options, top, Some(&g));
    if !g.time.is_constant() {
        material.layer_modulus = g.layer_moduli(cap, top);
    }
    // One solve gives the BLF and the stresses (graded mesh when `options.grading` is set);
    // without a strength model (or a shell) the plain buckling check.
    let (b, checks) = match g.state_checks(&state, &material, options, top)? {
        Some((b, _, worst)) => (b, worst),
        None => (
            state_buckling(
                &state,
                &material,
                &options.with_split_at_most(2),
                &Default::default(),
            )?
            .buckling,
            None,
        ),
    };
    let blf = match b.status {
        BucklingStatus::Analysed => b.factors.first().copied(),
        BucklingStatus::Mechanism => Some(0.0),
        _ => None,
    };
    let (st, sl) = checks.unwrap_or((None, None));
    let blf_min = cap.design.constraints.blf_min;
    let candidates = [
        (FailureMode::Buckling, blf.map(|f| blf_min / f)),
        (FailureMode::Strength, st.map(|w| w.utilisation)),
        (FailureMode::Sliding, sl.map(|w| w.utilisation)),
    ];
    let governing = candidates
        .iter()
        .filter_map(|(m, u)| u.map(|u| (*m, u)))
        .max_by(|a, b| a.1.total_cmp(&b.1));
    let beta = match crate::analysis::reliability::prepare(cap)? {
        Some((model, drifts, v)) => {
            use crate::analysis::reliability::{StateValues, checks_of, state_form};
            let values = StateValues {
                index: top,
                blf,
                stresses: None,
                strength: st.map(|w| w.utilisation),
            };
            let checks = checks_of(cap, options, schedule, v, values)?;
            let t_hours = schedule.layers.get(top).map_or(0.0, |l| l.end_s) / 3600.0;
            state_form(
                cap,
                options,
                schedule,
                (&model, &drifts, v),
                top,
                t_hours,
                &checks,
            )?
            // The state's SORM β where it has one, as the run's `beta_min` verdict judges.
            .map(|(r, _)| r.beta_sorm.unwrap_or(r.beta))
        }
        None => None,
    };
    let beta_ok = beta.is_none_or(|b| b >= beta_min(cap));
    Ok(StateCheck {
        state: top,
        blf,
        strength: st.map(|w| w.utilisation),
        sliding: sl.map(|w| w.utilisation),
        governing: governing.map(|g| g.0),
        beta,
        pass: governing.is_none_or(|g| g.1 <= 1.0) && beta_ok,
    })
}

/// The β target of a design: `constraints.beta_min` or the default.
fn beta_min(cap: &Cap) -> f64 {
    cap.design
        .constraints
        .beta_min
        .unwrap_or(crate::input::uncertainty::BETA_MIN_DEFAULT)
}

/// Find the least waits (see the module docs). `wait_max` bounds each wait, s.
pub fn least_waits(
    cap: &Cap,
    options: &AnalysisOptions,
    wait_max: f64,
    on_state: &(dyn Fn(usize) + Sync),
) -> Result<WaitPlan, DesignError> {
    if !(wait_max.is_finite() && wait_max >= 0.0) {
        return Err(DesignError::Invalid {
            field: "wait_max",
            value: wait_max.to_string(),
            allowed: "allowed: a finite bound ≥ 0 s".into(),
        });
    }
    let green = CapGreen::new(cap)?;
    let base = green.schedule.clone();
    let n = cap.states.len();
    let mut waits: Vec<f64> = base.layers.iter().map(|l| l.wait_s).collect();
    let mut schedule = base.clone();
    let mut binding = Vec::new();
    let mut infeasible = Vec::new();
    let mut states = Vec::with_capacity(n);
    for top in 0..n {
        let mut c = check_state_on(cap, &green, options, &schedule, top)?;
        if !c.pass && top > 0 {
            let before = waits[top - 1];
            let with =
                |w: f64, waits: &mut Vec<f64>| -> Result<(Schedule, StateCheck), DesignError> {
                    waits[top - 1] = w;
                    let s = base.with_waits(waits)?;
                    let c = check_state_on(cap, &green, options, &s, top)?;
                    Ok((s, c))
                };
            let (s_max, c_max) = with(wait_max.max(before), &mut waits)?;
            if c_max.pass {
                // Bisection to 0.5 s (a robot `sleep` resolution well below a layer time).
                let (mut lo, mut hi) = (before, wait_max.max(before));
                let mut best = (s_max, c_max);
                while hi - lo > 0.5 {
                    let mid = 0.5 * (lo + hi);
                    let (s, cm) = with(mid, &mut waits)?;
                    if cm.pass {
                        hi = mid;
                        best = (s, cm);
                    } else {
                        lo = mid;
                    }
                }
                waits[top - 1] = hi;
                binding.push(Binding {
                    state: top,
                    wait_s: hi - before,
                    check: c.governing,
                    beta_before: c.beta,
                });
                schedule = best.0;
                c = best.1;
            } else {
                waits[top - 1] = before;
                schedule = base.with_waits(&waits)?;
                infeasible.push(c);
            }
        } else if !c.pass {
            infeasible.push(c);
        }
        on_state(n);
        states.push(c);
    }
    Ok(WaitPlan {
        total_s: schedule.total_s(),
        total_without_waits_s: base.with_waits(&[])?.total_s(),
        schedule,
        binding,
        infeasible,
        states,
        beta_min: cap.design.uncertainty.as_ref().map(|_| beta_min(cap)),
    })
}

/// `schedule.json` of `kappe schedule`: the time model, the bound on each wait and the plan.
///
/// # Errors
/// An invalid `[material.time]`.
pub fn document(
    design: &crate::input::design::Design,
    wait_max: f64,
    plan: &WaitPlan,
) -> Result<serde_json::Value, DesignError> {
    Ok(serde_json::json!({
        "format": "kappe.schedule",
        "version": 1,
        "time_model": design.time_model()?,
        "wait_max_s": wait_max,
        "plan": plan,
    }))
}

/// The text `kappe schedule` prints: print times, each binding wait, the states that fail
/// even at `wait_max`, and the `[schedule] waits = [...]` lines for the design.
pub fn text_report(plan: &WaitPlan, wait_max: f64) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "{} states; print time {:.1} s without waits, {:.1} s with the least waits ({:.1} s of waits)",
        plan.states.len(),
        plan.total_without_waits_s,
        plan.total_s,
        plan.schedule.total_wait_s()
    );
    for b in &plan.binding {
        let beta = b
            .beta_before
            .map_or(String::new(), |v| format!("; β {v:.2} without it"));
        let _ = writeln!(
            t,
            "  state {:>4}: wait {:.1} s before its top layer ({} binds{beta})",
            b.state,
            b.wait_s,
            b.check.map_or("-", |m| m.name())
        );
    }
    for c in &plan.infeasible {
        let _ = writeln!(
            t,
            "  state {:>4}: FAILS even with {:.0} s of wait ({} governs; BLF {:?}, strength {:?}, sliding {:?}, β {:?})",
            c.state,
            wait_max,
            c.governing.map_or("-", |m| m.name()),
            c.blf,
            c.strength,
            c.sliding,
            c.beta
        );
    }
    let list: Vec<String> = plan
        .schedule
        .layers
        .iter()
        .map(|l| format!("{:.1}", l.wait_s))
        .collect();
    if let Some(bm) = plan.beta_min {
        let low = plan
            .states
            .iter()
            .filter_map(|c| c.beta)
            .fold(f64::INFINITY, f64::min);
        let _ = writeln!(
            t,
            "β target {bm:.2}: lowest state β with these waits {low:.2} (drift included)"
        );
    }
    let _ = writeln!(t, "add to the design to print and check this schedule:");
    let _ = writeln!(t, "[schedule]\nwaits = [{}]", list.join(", "));
    t
}
