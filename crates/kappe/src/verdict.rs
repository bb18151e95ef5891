//! The verdict of a design: the one place where pass or fail is decided, so that `kappe design`
//! (its exit status), `kappe study` (the result column) and the Python `kappe.design` cannot
//! disagree.
//!
//! With an analysis ([`crate::analysis::analyze`]) its verdict counts; without one, the
//! preliminary checks that need no finite elements ([`preliminary_constraints`]: σ_min ≤ σ ≤
//! σ_max in every state from the form-finding force pass, max |l_o| ≤ l_o,max). A design whose
//! robot plan was tried and failed fails too.

use kappe_report::{Bound, ConstraintRow};

use crate::form::cap::{Cap, StateSummary};
use crate::output::report_input::ReportExtras;

/// Relative tolerance on stress limits. The fixed-geometry force pass balances every node to
/// ~1e-14 relative (method.md §9), so an arch whose forces are all compressive in exact
/// arithmetic shows tensile stresses of ~1e-11 Pa from roundoff (observed 3e-11 Pa against
/// 15 kPa of compression); without a tolerance σ_max = 0 would fail every design. 1e-9 of the
/// largest stress magnitude is far above roundoff and far below any physical meaning (the same
/// value as [`crate::analysis::STRESS_REL_TOL`]).
const STRESS_RELATIVE_TOLERANCE: f64 = crate::analysis::STRESS_REL_TOL;

/// Whether the design passes: the analysis verdict when there is one, else every
/// [`preliminary_constraints`] row holds (σ_min ≤ σ ≤ σ_max in every state and
/// max |l_o| ≤ l_o,max); and the robot could be planned, if planning was tried
/// ([`add_robot`]). `kappe design`, `kappe study` and the Python package all decide with this function.
pub fn design_ok(cap: &Cap, extras: &ReportExtras) -> bool {
    extras.robot_error.is_none()
        && extras
            .ok
            .unwrap_or_else(|| preliminary_constraints(cap).iter().all(|c| c.pass))
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

/// The constraints checkable without the finite-element analysis, worst value over all states:
/// `sigma_min` (most compressive stress ≥ σ_min), `sigma_max` (largest stress ≤ σ_max), both
/// in kPa, and `overhang_max` (max |l_o| ≤ l_o,max, mm). The names are those of
/// [`crate::analysis::analyze`], so its rows replace these.
pub fn preliminary_constraints(cap: &Cap) -> Vec<ConstraintRow> {
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
    vec![
        ConstraintRow {
            name: "sigma_min".into(),
            bound: Bound::AtLeast,
            limit: k.sigma_min / 1e3,
            worst: worst_c.0 / 1e3,
            unit: "kPa".into(),
            state: worst_c.1,
            element: None,
            pass: worst_c.0 >= k.sigma_min - tol,
        },
        ConstraintRow {
            name: "sigma_max".into(),
            bound: Bound::AtMost,
            limit: k.sigma_max / 1e3,
            worst: worst_t.0 / 1e3,
            unit: "kPa".into(),
            state: worst_t.1,
            element: None,
            pass: worst_t.0 <= k.sigma_max + tol,
        },
        ConstraintRow {
            name: "overhang_max".into(),
            bound: Bound::AtMost,
            limit: lo_max * 1e3,
            worst: worst_o.0 * 1e3,
            unit: "mm".into(),
            state: worst_o.1,
            element: worst_o.1.and_then(layer_name),
            pass: worst_o.0 <= lo_max,
        },
    ]
}
