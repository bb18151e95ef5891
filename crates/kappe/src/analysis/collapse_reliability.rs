//! The collapse factor as a limit state (issue 24): the tables of ln λ_c over the uncertain
//! parameters a path depends on, shared by the buildability objects
//! (`commands::buildability_collapse`) and the cap's states ([`CapCollapseTables`]), and the
//! cap's collapse component of each state's reliability.
//!
//! Per state q, g_q(x) = ln(λ_c,q(x)/collapse_min), λ_c the collapse factor of
//! docs/collapse.md (limit point, or the material failing at a face of the imperfect,
//! geometrically nonlinear path).
//!
//! # What λ_c of a cap state depends on, and what scales exactly
//!
//! **γ exactly**, λ_c(γ) = λ_c(γ₀)·γ₀/γ: the proof of `commands::buildability_collapse` holds
//! for the cap's path word for word (the load is γ·f̂, the co-rotational internal force depends
//! on the displacements and moduli only, the face stresses on the displacements, the path's
//! controls λ₁ = ½·min(λ_LBA, 1/u_lin) and λ_max = 1.5·λ_LBA are ∝ 1/γ).
//!
//! **The uniform E exactly**, λ_c(E) = λ_c(E₀)·E/E₀, when the modulus is one number (no time
//! model; a design with a time model takes the time model's own E₀, Ė instead, and without a
//! time model there is no strength model, so the path checks the limit point only). *Proof.*
//! The shell's internal force is linear in E at fixed displacements, f_int(u; E) =
//! (E/E₀)·f_int(u; E₀) (every membrane, bending and shear stiffness is E times a function of
//! the geometry and ν; the co-rotational frames depend on the displacements only). The
//! equilibria of the path under λγf̂ at E are those at E₀ under μγf̂ with μ = λE₀/E, with the
//! same displacements; a limit point (det K_T = 0, K_T = (E/E₀)·K_T(u; E₀)) is at the same u,
//! so λ_c(E) = (E/E₀)·λ_c(E₀). The imperfection's shape is the LBA mode, the same vector at
//! every E (K and K_G scale by E and by 1), and its amplitude w0 does not involve E. The path's
//! controls scale with it: λ_LBA ∝ E, u_lin ∝ 1/E, so λ₁ and λ_max are ∝ E; the arc length is
//! measured in displacements and the residual tolerance is relative to the load. So the path
//! at E visits the displacements of the path at E₀, step for step. With a strength model
//! (which needs the time model) the face stresses are E × strains against a capacity that does
//! not scale with E, and the time model's E₀, Ė, f₀, ḟ are table axes instead. Both scalings
//! are checked by re-solves (`collapse_reliability::collapse_factor_scales_exactly_with_the_weight_and_the_modulus`).
//!
//! **Table axes**: ν (the stiffnesses' shape), the imperfection variable
//! (`"analysis.nonlinear.imperfection"`: w0 in m with `imperfection = w0`, else a factor,
//! mean 1, on every state's rule w0), the time model's E₀ and Ė, and — when the path checks
//! the material (`material = true` and a strength model) — f₀, ḟ and φ. At most [`MAX_AXES`];
//! the print speed (it moves the ages through the schedule) and `start = "as_printed"` (whose
//! start geometry moves with γ/E, so neither scaling holds) are named errors.
//!
//! # Tables and the state rule
//!
//! Per state, ln λ_c at γ₀, E₀ on the tensor grid of [`COLLAPSE_NODES`] Chebyshev points in
//! the logarithm of each axis over the box of ±[`super::design_monte_carlo::Z_BOX`] standard
//! deviations of every analysed state's drifted model; each point one run of the state's own
//! collapse check ([`super::collapse::cap_state_collapse_from`] with the parameters set, no
//! stop: `above = ∞`), so a table is a speed-up of the same model. Which states get one: only
//! those the deterministic check ran (they have a collapse factor); a state reported
//! `not_reached` holds a lower bound there, which as its nominal λ_c in the rule below makes
//! its margin smaller than it is and so admits more states (the safe side); a tabulated
//! `not_reached` state gets real paths (`above = ∞`). Then the buildability rule
//! ([`admit`]): the least-margin state first, its downward span D measured on its interpolant
//! over the ±[`Z_SELECT`] box, every state with G_q ≤ S + [`SPAN_SAFETY`]·D_max added,
//! repeated. S is the downward shift of ln λ_c by the exactly scaled variables at their worst
//! over the box (ln(γ_hi/γ₀) + ln(E₀/E_lo)): they shift every state's ln λ_c by the same
//! amount, so that part of every span is the same and known exactly, and takes no safety
//! factor; only the table axes' span D differs between states, and that is the part the rule
//! measures on neighbours rather than proves. A state q can fail inside the box only if
//! G_q ≤ S + D_q; a skipped state has G_q > S + 1.5·D_max, so it could only if its own table
//! span exceeded 1.5× every span measured on the same cap. Without a table axis the rule is exact: every g_q is
//! G_q + the same shift, the least-G state fails first in every sample, and every state with a
//! collapse factor gets its (exact, free) table.

use std::sync::atomic::{AtomicU64, Ordering};

use kappe_reliability::{EvalError, Fallible, FormResult, LimitState, Model};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::collapse::{Collapse, CollapseMode};
use super::design_monte_carlo::{Z_BOX, bary_into, bits, cheb, table_coefficients};
use super::reliability::Vars;
use crate::form::cap::Cap;
use crate::input::error::DesignError;
use crate::input::nonlinear::{NonlinearSpec, PathStart};
use crate::input::uncertainty::{IMPERFECTION, SPEED};

/// Chebyshev points per axis of a collapse table. λ_c is smooth in each parameter away from a
/// kink (a switch between limit point and material failure); 5 points per axis keep a table at
/// ≤ 25 paths per state. Their error is measured at every design point, not assumed.
pub const COLLAPSE_NODES: usize = 5;

/// Most uncertain parameters a collapse table spans (5² = 25 paths per state; three would be
/// 125).
pub const MAX_AXES: usize = 2;

/// The margin on the measured spans of the state rule ([`admit`]).
pub const SPAN_SAFETY: f64 = 1.5;

/// Half-width of the state rule's box, in standard deviations: a state that cannot fail inside
/// it has P_f ≤ P(some |zᵢ| > 4) ≈ d·6.3·10⁻⁵ (d variables), negligible against any print P_f
/// the β target admits (Φ(−2.3) ≈ 10⁻²).
pub const Z_SELECT: f64 = 4.0;

/// Points per axis on which the state rule evaluates a table's interpolant.
pub const SELECT_POINTS: usize = 9;

/// The table's error at a design point, as Δβ = |ln λ_table − ln λ_path|/‖∇ᵤg‖, that the tests
/// accept: below FORM's own first-order error measured on these objects (Δβ ≈ 0.07 on study
/// No. 14's last state, docs/reliability.md), so the table adds no error FORM does not have.
pub const DESIGN_POINT_BETA_TOLERANCE: f64 = 0.05;

/// One axis of a collapse table: [`COLLAPSE_NODES`] Chebyshev points in the logarithm of its
/// variable over [lo, hi] (logarithms).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogAxis {
    /// The points (logarithms).
    #[serde(with = "bits")]
    pub nodes: Vec<f64>,
    /// Their barycentric weights.
    #[serde(with = "bits")]
    pub weights: Vec<f64>,
    /// ln of the box's lower end.
    #[serde(with = "bits::one")]
    pub lo: f64,
    /// ln of its upper end.
    #[serde(with = "bits::one")]
    pub hi: f64,
}

impl LogAxis {
    /// The axis over the variable's box [lo, hi] (values, not logarithms).
    ///
    /// # Errors
    /// A box that is not positive and finite (the message says so).
    pub fn new(lo: f64, hi: f64) -> Result<LogAxis, String> {
        if !(lo > 0.0 && hi > lo && hi.is_finite()) {
            return Err(format!(
                "the collapse table needs a positive range, got [{lo}, {hi}]"
            ));
        }
        let (lo, hi) = (lo.ln(), hi.ln());
        let (nodes, weights) = cheb(lo, hi, COLLAPSE_NODES);
        Ok(LogAxis {
            nodes,
            weights,
            lo,
            hi,
        })
    }

    /// [lo, hi] in logarithms.
    pub fn range(&self) -> [f64; 2] {
        [self.lo, self.hi]
    }
}

/// Points of the tensor grid of `axes`.
pub fn grid_size(axes: &[LogAxis]) -> usize {
    axes.iter().map(|a| a.nodes.len().max(1)).product()
}

/// The grid indices of flat index `flat` (the last axis fastest).
pub fn grid_index(axes: &[LogAxis], mut flat: usize) -> Vec<usize> {
    let mut out = vec![0; axes.len()];
    for (o, a) in out.iter_mut().zip(axes).rev() {
        let k = a.nodes.len().max(1);
        *o = flat % k;
        flat /= k;
    }
    out
}

/// The variables' values (not logarithms) at grid point `flat`.
pub fn grid_point(axes: &[LogAxis], flat: usize) -> Vec<f64> {
    axes.iter()
        .zip(grid_index(axes, flat))
        .map(|(a, i)| a.nodes.get(i).copied().unwrap_or(f64::NAN).exp())
        .collect()
}

/// The interpolant of grid values `log` from per-axis barycentric coefficients.
pub fn interpolate(axes: &[LogAxis], log: &[f64], coefs: &[Vec<f64>]) -> f64 {
    log.iter()
        .enumerate()
        .map(|(j, v)| {
            let w: f64 = grid_index(axes, j)
                .iter()
                .zip(coefs)
                .map(|(&i, c)| c.get(i).copied().unwrap_or(0.0))
                .product();
            w * v
        })
        .sum()
}

/// Per axis, the coefficients at the logarithms `s` ([`table_coefficients`]: outside the box
/// the straight continuation with `clamp`, else None: the caller re-solves).
pub fn coefficients(axes: &[LogAxis], s: &[f64], clamp: bool) -> Option<Vec<Vec<f64>>> {
    axes.iter()
        .zip(s)
        .map(|(a, &s)| {
            let mut c = vec![0.0; a.nodes.len()];
            table_coefficients(&a.nodes, &a.weights, a.range(), s, clamp, &mut c).then_some(c)
        })
        .collect()
}

/// The least of the interpolant of `log` over the box `select` (per axis [lo, hi] in
/// logarithms), on [`SELECT_POINTS`] points per axis (edges included).
pub fn least_log(axes: &[LogAxis], log: &[f64], select: &[[f64; 2]]) -> f64 {
    let k = SELECT_POINTS;
    let total = k.pow(axes.len() as u32);
    (0..total)
        .map(|j| {
            let mut rest = j;
            let mut coefs = Vec::with_capacity(axes.len());
            for (a, [lo, hi]) in axes.iter().zip(select).rev() {
                let i = rest % k;
                rest /= k;
                let s = lo + (hi - lo) * i as f64 / (k - 1) as f64;
                let mut c = vec![0.0; a.nodes.len()];
                bary_into(&a.nodes, &a.weights, s, &mut c);
                coefs.push(c);
            }
            coefs.reverse();
            interpolate(axes, log, &coefs)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The state rule (module docs): `order` = (state, G) ascending in G, the nominal ln-margins;
/// `tabulate` the tables of some states; `least_g` the least g of a table over the selection
/// box with the exactly scaled variables at their means; `exact` the downward shift S ≥ 0 of
/// every state's ln λ_c by the exactly scaled variables at their worst over the box (the same
/// for every state, known exactly). The least-G state first, then every state with
/// G ≤ S + [`SPAN_SAFETY`]·D_max (D = G − least g, the tables' own span, the largest measured:
/// the safety factor covers only what is measured on neighbours), repeated until none is
/// added. Returns the tables (tabulation order) and D_max.
///
/// # Errors
/// `tabulate`'s.
pub fn admit<T, E>(
    order: &[(usize, f64)],
    exact: f64,
    mut tabulate: impl FnMut(&[usize]) -> Result<Vec<(usize, T)>, E>,
    least_g: impl Fn(&T) -> f64,
) -> Result<(Vec<(usize, T)>, f64), E> {
    let mut out: Vec<(usize, T)> = Vec::new();
    let mut span = 0.0_f64;
    let mut next: Vec<usize> = order.first().map(|s| s.0).into_iter().collect();
    while !next.is_empty() {
        for (n, t) in tabulate(&next)? {
            let g = order.iter().find(|s| s.0 == n).map_or(f64::NAN, |s| s.1);
            span = span.max(g - least_g(&t));
            out.push((n, t));
        }
        let bound = exact + SPAN_SAFETY * span;
        next = order
            .iter()
            .filter(|&&(n, g)| g <= bound && !out.iter().any(|t| t.0 == n))
            .map(|s| s.0)
            .collect();
    }
    Ok((out, span))
}

/// One table axis of a cap's collapse tables: the model variable and its grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CapAxis {
    /// The variable's name (`[uncertainty]`'s).
    pub name: String,
    /// Its index in the model.
    pub var: usize,
    /// The grid.
    pub grid: LogAxis,
}

/// One cap state's table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CapStateTable {
    /// State index.
    pub index: usize,
    /// ln λ_c at γ₀, E₀ on the grid (the first axis slowest; one value without axes).
    #[serde(with = "bits")]
    pub log: Vec<f64>,
    /// Whether the grid's paths end by different modes (a kink in the box).
    pub mixed: bool,
    /// Whether a grid path reached λ_max or stopped converging without a limit point (its
    /// value a lower bound).
    pub bounded: bool,
    /// What ended each grid path (`CollapseMode::name`; the deterministic λ_c's mode without
    /// axes).
    pub modes: Vec<String>,
}

/// A cap's collapse tables (module docs): plain data, shipped to the design Monte Carlo's
/// workers with its plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CapCollapseTables {
    /// The table axes.
    pub axes: Vec<CapAxis>,
    /// Model index of γ (exact scaling), if uncertain.
    pub gamma: Option<usize>,
    /// γ₀, the design's.
    #[serde(with = "bits::one")]
    pub gamma0: f64,
    /// Model index of the uniform E (exact scaling), if uncertain.
    pub e: Option<usize>,
    /// E₀, the design's.
    #[serde(with = "bits::one")]
    pub e0: f64,
    /// collapse_min.
    #[serde(with = "bits::one")]
    pub collapse_min: f64,
    /// The tabulated states, in state order.
    pub states: Vec<CapStateTable>,
    /// The largest downward span D of a table measured (the state rule's; without axes the
    /// exact shift).
    #[serde(with = "bits::one")]
    pub span: f64,
    /// The downward shift S of every state's ln λ_c by the exactly scaled variables at their
    /// worst over the selection box.
    #[serde(with = "bits::one")]
    pub exact_shift: f64,
    /// Paths solved for the tables.
    pub solves: usize,
    /// Wall-clock seconds of the tables.
    #[serde(with = "bits::one")]
    pub seconds: f64,
}

/// What a cap state's collapse path needs beyond the tables: the cap, its analysis options and
/// schedule, the `[analysis.nonlinear]` spec, the green-state model, and where the variables
/// sit in the design's uncertain model.
pub struct CapCollapseModel<'a> {
    cap: &'a Cap,
    options: &'a super::AnalysisOptions,
    spec: NonlinearSpec,
    green: Option<super::green::CapGreen>,
    vars: Vars,
    /// Model index of the imperfection variable.
    imperfection: Option<usize>,
    /// The imperfection variable is w0 in m (`imperfection` given), else a factor on the rule.
    given: bool,
    /// Every model variable's nominal value (the design's; the imperfection's m0).
    nominal: Vec<f64>,
    names: Vec<String>,
}

fn uerr(field: impl Into<String>, message: impl Into<String>) -> DesignError {
    DesignError::Uncertainty {
        field: field.into(),
        message: message.into(),
    }
}

impl<'a> CapCollapseModel<'a> {
    /// The collapse model of `cap` under the design's uncertain `model`; None when the design
    /// has no enabled `[analysis.nonlinear]` (or no buckling analysis, which the check needs).
    ///
    /// # Errors
    /// The print speed uncertain, `start = "as_printed"`, or more than [`MAX_AXES`] table axes
    /// (named errors), or an invalid time model or schedule.
    pub fn new(
        cap: &'a Cap,
        options: &'a super::AnalysisOptions,
        schedule: &crate::schedule::Schedule,
        model: &Model,
    ) -> Result<Option<Self>, DesignError> {
        let Some(spec) = options.nonlinear.filter(|n| n.enabled) else {
            return Ok(None);
        };
        if !options.buckling {
            return Ok(None);
        }
        let names: Vec<String> = model.variables().iter().map(|v| v.name.clone()).collect();
        let find = |n: &str| names.iter().position(|v| v == n);
        if find(SPEED).is_some() {
            return Err(uerr(
                format!("uncertainty.\"{SPEED}\""),
                "the collapse limit state ([analysis.nonlinear]) does not follow an uncertain \
                 print speed (it moves every layer's age through the schedule of each path): \
                 hold the speed fixed, or switch the collapse check off",
            ));
        }
        if spec.start == PathStart::AsPrinted {
            return Err(uerr(
                "analysis.nonlinear.start",
                "the collapse limit state ([uncertainty] with [analysis.nonlinear]) needs the \
                 path to start from the design (start = \"design\"): the as-printed start moves \
                 with γ/E, so neither the exact scaling nor the tables hold",
            ));
        }
        let d = &cap.design;
        let w0 = spec.imperfection;
        let nominal: Vec<f64> = names
            .iter()
            .map(|n| {
                if n == IMPERFECTION {
                    w0.unwrap_or(1.0)
                } else {
                    crate::input::uncertainty::nominal(d, n).unwrap_or(f64::NAN)
                }
            })
            .collect();
        let out = CapCollapseModel {
            cap,
            options,
            spec,
            green: super::check::analysis_green(cap, Some(schedule))?,
            vars: Vars::of(model, cap),
            imperfection: find(IMPERFECTION),
            given: w0.is_some(),
            nominal,
            names,
        };
        let axes = out.axis_vars();
        if axes.len() > MAX_AXES {
            let list: Vec<String> = axes
                .iter()
                .filter_map(|&i| out.names.get(i))
                .map(|n| format!("\"{n}\""))
                .collect();
            return Err(uerr(
                "uncertainty",
                format!(
                    "the collapse limit state ([analysis.nonlinear]) is tabulated over at most \
                     {MAX_AXES} of the uncertain parameters its path depends on; this table \
                     makes {} of them uncertain ({}): hold the others at fixed values (γ and \
                     the uniform E may be uncertain too: they scale λ_c exactly), or switch the \
                     collapse check off",
                    axes.len(),
                    list.join(", ")
                ),
            ));
        }
        Ok(Some(out))
    }

    /// The model indices of the table axes (module docs), in model order.
    fn axis_vars(&self) -> Vec<usize> {
        let v = &self.vars;
        let material = self.spec.material
            && self
                .green
                .as_ref()
                .is_some_and(|g| g.time.strength.is_some());
        let mut out: Vec<usize> = [v.nu, v.e0t, v.rate]
            .into_iter()
            .chain([v.f0, v.frate, v.phi].into_iter().filter(|_| material))
            .flatten()
            .chain(self.imperfection)
            .collect();
        out.sort_unstable();
        out
    }

    /// Whether a random variable enters λ_c (else the collapse is deterministic).
    fn random(&self) -> bool {
        !self.axis_vars().is_empty() || self.vars.gamma.is_some() || self.vars.e.is_some()
    }

    /// The collapse of state `top` by a direct path at the model point `x` (every variable;
    /// no stop): the deterministic check itself with the parameters set.
    ///
    /// # Errors
    /// A state that cannot be built, a failed path, or no collapse factor (one layer).
    pub fn direct(&self, top: usize, x: &[f64]) -> Result<Collapse, DesignError> {
        let v = &self.vars;
        let at = |i: Option<usize>| i.and_then(|i| x.get(i).copied());
        let mut cap = self.cap.clone();
        let m = &mut cap.design.material;
        m.specific_weight = at(v.gamma).unwrap_or(m.specific_weight);
        m.youngs_modulus = at(v.e).unwrap_or(m.youngs_modulus);
        m.poisson_ratio = at(v.nu).unwrap_or(m.poisson_ratio);
        let green = self.green.clone().map(|mut g| {
            g.time = v.time_at(&g.time, x);
            g
        });
        let mut spec = self.spec;
        if let Some(w) = at(self.imperfection) {
            spec.imperfection = Some(if self.given {
                w
            } else {
                w * self.rule_w0(&cap, green.as_ref(), top)?
            });
        }
        super::collapse::cap_state_collapse_from(
            &cap,
            self.options,
            &spec,
            green.as_ref(),
            top,
            f64::INFINITY,
            None,
        )?
        .ok_or_else(|| {
            uerr(
                "uncertainty",
                format!("state {top}: no shell, no collapse factor"),
            )
        })
    }

    /// The rule's w0 of state `top` on its shell (what the path would use without
    /// `imperfection`).
    fn rule_w0(
        &self,
        cap: &Cap,
        green: Option<&super::green::CapGreen>,
        top: usize,
    ) -> Result<f64, DesignError> {
        let state = cap.state(top)?;
        let mat = super::buckling::state_material(cap, self.options, top, green);
        let shell =
            super::shell::state_shell(&state, &mat, self.options.row_stride).map_err(|e| {
                DesignError::State {
                    state: top,
                    message: format!("the collapse limit state's shell: {e:?}"),
                }
            })?;
        let mut rule = self.spec;
        rule.imperfection = None;
        Ok(super::collapse::state_amplitude(&rule, &shell.model))
    }

    /// The tables of the states the rule admits (module docs) from the deterministic
    /// `collapse` factors (state index, λ_c), over the box of the drifted models at the
    /// analysed states' print times `t_hours`.
    ///
    /// # Errors
    /// A drift factor that is not positive, a box that is not positive, a failed path, or a
    /// grid point that is a mechanism.
    pub fn build(
        &self,
        model: &Model,
        drifts: &[(String, kappe_reliability::Drift)],
        t_hours: &[f64],
        collapse: &[(usize, f64)],
    ) -> Result<Option<CapCollapseTables>, DesignError> {
        if !self.random() {
            return Ok(None);
        }
        let t0 = kappe_fe::clock::Instant::now();
        let boxes = |z: f64| -> Result<Vec<[f64; 2]>, DesignError> {
            let mut out = vec![[f64::INFINITY, f64::NEG_INFINITY]; model.len()];
            for &t in t_hours {
                let m = model
                    .drifted(drifts, t)
                    .map_err(|e| uerr("uncertainty.drift", format!("at {t:.3} h: {e}")))?;
                for (b, v) in out.iter_mut().zip(m.variables()) {
                    b[0] = b[0].min(v.distribution.from_standard(-z));
                    b[1] = b[1].max(v.distribution.from_standard(z));
                }
            }
            Ok(out)
        };
        let table_box = boxes(Z_BOX)?;
        let select_box = boxes(Z_SELECT)?;
        let axes = self
            .axis_vars()
            .into_iter()
            .map(|var| {
                let name = self.names.get(var).cloned().unwrap_or_default();
                let [lo, hi] = table_box.get(var).copied().unwrap_or([f64::NAN; 2]);
                let grid =
                    LogAxis::new(lo, hi).map_err(|m| uerr(format!("uncertainty.\"{name}\""), m))?;
                Ok(CapAxis { name, var, grid })
            })
            .collect::<Result<Vec<_>, DesignError>>()?;
        let v = &self.vars;
        let collapse_min = self.cap.design.constraints.collapse_min();
        // The exactly scaled variables at their worst over the selection box: every state's
        // ln λ_c moves by this same amount.
        let sel = |i: Option<usize>| i.and_then(|i| select_box.get(i).copied());
        let exact_shift = sel(v.gamma).map_or(0.0, |b| (b[1] / v.gamma0).ln())
            + sel(v.e).map_or(0.0, |b| (v.e0 / b[0]).ln());
        let select: Vec<[f64; 2]> = axes
            .iter()
            .map(|a| {
                let b = select_box.get(a.var).copied().unwrap_or([f64::NAN; 2]);
                [b[0].ln().max(a.grid.lo), b[1].ln().min(a.grid.hi)]
            })
            .collect();
        let mut order: Vec<(usize, f64)> = collapse
            .iter()
            .filter(|c| c.1 > 0.0 && c.1.is_finite())
            .map(|&(q, f)| (q, (f / collapse_min).ln()))
            .collect();
        order.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        let mut solves = 0;
        let grids: Vec<LogAxis> = axes.iter().map(|a| a.grid.clone()).collect();
        let (states, span) = if axes.is_empty() {
            // Exact: the deterministic λ_c at γ₀, E₀ of every state (a `not_reached` one's
            // lower bound: on the safe side).
            let states = order
                .iter()
                .map(|&(q, g)| {
                    (
                        q,
                        CapStateTable {
                            index: q,
                            log: vec![g + collapse_min.ln()],
                            mixed: false,
                            bounded: false,
                            modes: Vec::new(),
                        },
                    )
                })
                .collect();
            (states, exact_shift)
        } else {
            admit(
                &order,
                exact_shift,
                |states| {
                    let t = self.tabulate(&axes, states)?;
                    solves += t.len() * grid_size(&grids);
                    Ok::<_, DesignError>(t)
                },
                |t: &CapStateTable| least_log(&grids, &t.log, &select) - collapse_min.ln(),
            )?
        };
        let mut states: Vec<CapStateTable> = states.into_iter().map(|s| s.1).collect();
        states.sort_by_key(|s| s.index);
        Ok(Some(CapCollapseTables {
            axes,
            gamma: v.gamma,
            gamma0: v.gamma0,
            e: v.e,
            e0: v.e0,
            collapse_min,
            states,
            span,
            exact_shift,
            solves,
            seconds: t0.elapsed().as_secs_f64(),
        }))
    }

    /// The grids of states `states`, every (state, point) path in parallel.
    fn tabulate(
        &self,
        axes: &[CapAxis],
        states: &[usize],
    ) -> Result<Vec<(usize, CapStateTable)>, DesignError> {
        let grids: Vec<LogAxis> = axes.iter().map(|a| a.grid.clone()).collect();
        let total = grid_size(&grids);
        let jobs: Vec<(usize, usize)> = states
            .iter()
            .flat_map(|&q| (0..total).map(move |j| (q, j)))
            .collect();
        let solved = jobs
            .par_iter()
            .map(|&(q, j)| {
                let mut x = self.nominal.clone();
                let point = grid_point(&grids, j);
                for (a, &val) in axes.iter().zip(&point) {
                    if let Some(xi) = x.get_mut(a.var) {
                        *xi = val;
                    }
                }
                let c = self.direct(q, &x)?;
                if !(c.factor > 0.0 && c.factor.is_finite()) {
                    let at: Vec<String> = axes
                        .iter()
                        .zip(&point)
                        .map(|(a, v)| format!("{} = {v:.4e}", a.name))
                        .collect();
                    return Err(uerr(
                        "uncertainty",
                        format!(
                            "state {q}: collapse factor {} at a point of the collapse table \
                             ({}): the box of ±{Z_BOX} standard deviations reaches a \
                             mechanism; narrow the scatter",
                            c.factor,
                            at.join(", ")
                        ),
                    ));
                }
                Ok((c.factor.ln(), c.mode))
            })
            .collect::<Result<Vec<_>, DesignError>>()?;
        Ok(states
            .iter()
            .zip(solved.chunks(total.max(1)))
            .map(|(&q, c)| {
                let first = c.first().map(|v| v.1);
                (
                    q,
                    CapStateTable {
                        index: q,
                        log: c.iter().map(|v| v.0).collect(),
                        mixed: c.iter().any(|v| Some(v.1) != first),
                        bounded: c.iter().any(|v| {
                            matches!(v.1, CollapseMode::NotReached | CollapseMode::NoConvergence)
                        }),
                        modes: c.iter().map(|v| v.1.name().to_owned()).collect(),
                    },
                )
            })
            .collect())
    }

    /// The check of a state's collapse design point (FORM result `f` in the drifted `model`)
    /// against a direct path there.
    ///
    /// # Errors
    /// A failed path.
    pub fn check_point(
        &self,
        tables: &CapCollapseTables,
        model: &Model,
        index: usize,
        f: &FormResult,
    ) -> Result<DesignPointCheck, DesignError> {
        let x = &f.x_star;
        let never = AtomicU64::new(0);
        let table = tables
            .factor(self, index, x, true, &never)?
            .unwrap_or(f64::NAN);
        let path = self.direct(index, x)?;
        let (relative_error, beta_error) =
            design_point_error(&f.u_star, table, path.factor, |u| {
                tables
                    .g(self, index, &model.x_from_u(u))
                    .map_err(|e| uerr("uncertainty", e.to_string()))
            })?;
        Ok(DesignPointCheck {
            state: index,
            beta: f.beta,
            design_point: f.names.iter().cloned().zip(x.iter().copied()).collect(),
            table,
            path: path.factor,
            mode: path.mode.name().to_owned(),
            relative_error,
            beta_error,
        })
    }

    /// The state's FORM limit state on its table (None: no table).
    pub fn limit_state<'b>(
        &'b self,
        tables: &'b CapCollapseTables,
        index: usize,
    ) -> Option<Box<dyn LimitState + 'b>> {
        tables.has(index).then(|| {
            Box::new(Fallible(move |x: &[f64]| tables.g(self, index, x)))
                as Box<dyn LimitState + 'b>
        })
    }
}

impl CapCollapseTables {
    /// Whether state `index` has a table.
    pub fn has(&self, index: usize) -> bool {
        self.states.iter().any(|s| s.index == index)
    }

    /// λ_c of state `index` at the model point `x` from its table (None: no table). Outside the
    /// box: continued from the edge with `clamp` (FORM), else a direct path, counted in
    /// `fallbacks` (sampling).
    ///
    /// # Errors
    /// A failed direct path.
    pub fn factor(
        &self,
        m: &CapCollapseModel<'_>,
        index: usize,
        x: &[f64],
        clamp: bool,
        fallbacks: &AtomicU64,
    ) -> Result<Option<f64>, DesignError> {
        let Some(t) = self.states.iter().find(|s| s.index == index) else {
            return Ok(None);
        };
        let s: Vec<f64> = self
            .axes
            .iter()
            .map(|a| x.get(a.var).copied().unwrap_or(f64::NAN).ln())
            .collect();
        let grids: Vec<LogAxis> = self.axes.iter().map(|a| a.grid.clone()).collect();
        let Some(coefs) = coefficients(&grids, &s, clamp) else {
            fallbacks.fetch_add(1, Ordering::Relaxed);
            return m.direct(index, x).map(|c| Some(c.factor));
        };
        let at =
            |i: Option<usize>, nominal: f64| i.and_then(|i| x.get(i).copied()).unwrap_or(nominal);
        let scale = at(self.e, self.e0) / self.e0 * self.gamma0 / at(self.gamma, self.gamma0);
        Ok(Some(interpolate(&grids, &t.log, &coefs).exp() * scale))
    }

    /// g(x) = ln(λ_c/collapse_min) of state `index` on its table (continued outside the box).
    ///
    /// # Errors
    /// No table, or no positive λ_c (γ ≤ 0 far out in FORM's iterates).
    pub fn g(&self, m: &CapCollapseModel<'_>, index: usize, x: &[f64]) -> Result<f64, EvalError> {
        let never = AtomicU64::new(0);
        match self.factor(m, index, x, true, &never) {
            Ok(Some(f)) if f > 0.0 && f.is_finite() => Ok((f / self.collapse_min).ln()),
            Ok(_) => Err(EvalError::from(format!(
                "state {index}: no positive collapse factor at x = {x:?}"
            ))),
            Err(e) => Err(EvalError::from(e.to_string())),
        }
    }

    /// g of state `index` for sampling: the table inside its box, a direct path outside
    /// (counted in `fallbacks`).
    ///
    /// # Errors
    /// A failed direct path.
    pub fn sample_g(
        &self,
        m: &CapCollapseModel<'_>,
        index: usize,
        x: &[f64],
        fallbacks: &AtomicU64,
    ) -> Result<f64, DesignError> {
        match self.factor(m, index, x, false, fallbacks)? {
            Some(f) if f > 0.0 => Ok((f / self.collapse_min).ln()),
            Some(_) => Ok(f64::NEG_INFINITY),
            None => Err(uerr(
                "uncertainty",
                format!("state {index}: no collapse table"),
            )),
        }
    }
}

/// A table's error at a design point u* against a direct path there (the cap's and the
/// buildability objects' design-point checks): |table − path|/path, and as
/// Δβ = |ln table − ln path|/‖∇ᵤg‖ with ‖∇ᵤg‖ by central differences of the table's `g` in u
/// (step 10⁻³: truncation O(10⁻⁶) relative for a surface this smooth between nodes); Δβ is
/// infinite where the gradient vanishes.
///
/// # Errors
/// `g`'s.
pub fn design_point_error<E>(
    u_star: &[f64],
    table: f64,
    path: f64,
    g: impl Fn(&[f64]) -> Result<f64, E>,
) -> Result<(f64, f64), E> {
    let h = 1e-3;
    let mut norm2 = 0.0;
    for i in 0..u_star.len() {
        let mut up = u_star.to_vec();
        let mut dn = u_star.to_vec();
        up[i] += h;
        dn[i] -= h;
        norm2 += ((g(&up)? - g(&dn)?) / (2.0 * h)).powi(2);
    }
    let dlog = (table.ln() - path.ln()).abs();
    let beta_error = if norm2 > 0.0 {
        dlog / norm2.sqrt()
    } else {
        f64::INFINITY
    };
    Ok((((table - path) / path).abs(), beta_error))
}

/// A state's collapse design point checked by a direct path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DesignPointCheck {
    /// State index.
    pub state: usize,
    /// FORM's β of the state's collapse component.
    pub beta: f64,
    /// The design point (every variable of the model).
    pub design_point: std::collections::BTreeMap<String, f64>,
    /// λ_c there from the table.
    pub table: f64,
    /// λ_c there by a direct path.
    pub path: f64,
    /// What ends the direct path there.
    pub mode: String,
    /// |table − path|/path.
    pub relative_error: f64,
    /// The error as Δβ = |ln table − ln path|/‖∇ᵤg‖.
    pub beta_error: f64,
}

/// The collapse limit state of a cap design (`summary.json` `reliability.collapse`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CapCollapseReliability {
    /// The tables' axes (empty: γ and/or E alone, exact scalings).
    pub parameters: Vec<String>,
    /// The variables that scale λ_c exactly (γ, the uniform E).
    pub exact: Vec<String>,
    /// Chebyshev points per axis.
    pub nodes_per_parameter: usize,
    /// Whether the imperfection variable is a factor on the rule's w0 (else w0 in m).
    pub imperfection_is_factor: bool,
    /// The states with a table.
    pub states: Vec<usize>,
    /// Tabulated states whose grid points end by different modes (a kink in the box).
    pub mixed_modes: Vec<usize>,
    /// Tabulated states with a grid path that ended without collapse (λ_max reached or no
    /// convergence: a lower bound there).
    pub bounded: Vec<usize>,
    /// The largest downward span of a table's ln λ_c measured (the state rule's D).
    pub span: f64,
    /// The downward shift S of every state's ln λ_c by γ and E at their worst over the
    /// selection box (exact; the rule admits states with G ≤ S + 1.5·D).
    pub exact_shift: f64,
    /// Paths solved for the tables.
    pub solves: usize,
    /// Wall-clock seconds of the tables.
    pub seconds: f64,
    /// Every tabulated state's grid: λ_c at γ₀, E₀ per point and what ended its path.
    pub grids: Vec<CollapseGrid>,
    /// Every state's collapse design point against a direct path.
    pub design_points: Vec<DesignPointCheck>,
    /// The largest relative error there.
    pub max_relative_error: f64,
    /// The largest error there as Δβ.
    pub max_beta_error: f64,
}

/// One tabulated state's grid (the first axis slowest).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CollapseGrid {
    /// State index.
    pub state: usize,
    /// The axes' values per point.
    pub points: Vec<Vec<f64>>,
    /// λ_c per point (at γ₀, E₀).
    pub factors: Vec<f64>,
    /// What ended each path.
    pub modes: Vec<String>,
}

impl CapCollapseReliability {
    /// The report of `tables` with the design points checked.
    pub fn of(
        m: &CapCollapseModel<'_>,
        tables: &CapCollapseTables,
        checks: Vec<DesignPointCheck>,
    ) -> Self {
        let exact = [tables.gamma, tables.e]
            .into_iter()
            .flatten()
            .filter_map(|i| m.names.get(i).cloned())
            .collect();
        CapCollapseReliability {
            parameters: tables.axes.iter().map(|a| a.name.clone()).collect(),
            exact,
            nodes_per_parameter: COLLAPSE_NODES,
            imperfection_is_factor: !m.given,
            states: tables.states.iter().map(|s| s.index).collect(),
            mixed_modes: tables
                .states
                .iter()
                .filter(|s| s.mixed)
                .map(|s| s.index)
                .collect(),
            bounded: tables
                .states
                .iter()
                .filter(|s| s.bounded)
                .map(|s| s.index)
                .collect(),
            span: tables.span,
            exact_shift: tables.exact_shift,
            solves: tables.solves,
            seconds: tables.seconds,
            grids: tables
                .states
                .iter()
                .filter(|s| !s.modes.is_empty())
                .map(|s| {
                    let grids: Vec<LogAxis> = tables.axes.iter().map(|a| a.grid.clone()).collect();
                    CollapseGrid {
                        state: s.index,
                        points: (0..s.log.len()).map(|j| grid_point(&grids, j)).collect(),
                        factors: s.log.iter().map(|l| l.exp()).collect(),
                        modes: s.modes.clone(),
                    }
                })
                .collect(),
            max_relative_error: checks.iter().map(|c| c.relative_error).fold(0.0, f64::max),
            max_beta_error: checks.iter().map(|c| c.beta_error).fold(0.0, f64::max),
            design_points: checks,
        }
    }
}
