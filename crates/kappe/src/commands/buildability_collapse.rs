//! The collapse factor of a buildability object as a limit state (issue 24): the imperfection
//! amplitude w0 an uncertain input, and per layer count n the limit state
//!
//! g_n(x) = ln(λ_c,n(x) / collapse_min)
//!
//! (the surface λ_c = collapse_min in the logarithmic form of the other buildability checks),
//! with λ_c the collapse factor of docs/collapse.md: the smallest load factor at which the
//! imperfect, geometrically nonlinear path reaches a limit point or the aged material fails at
//! a face. It joins the state's checks (`beta_by_check["collapse"]`), the state's β, the print's
//! series system, its design point and sensitivities, and the print's Monte Carlo.
//!
//! # The imperfection as a random variable
//!
//! `"analysis.nonlinear.imperfection"` in `[uncertainty]`, only with `[analysis.nonlinear]`
//! (else a named error) and only for a positive distribution (lognormal, or a uniform with a
//! lower bound > 0; a normal is refused as E's is). With `imperfection = w0` given, the variable
//! is w0 itself, in m, mean w0 (w0 = 0, the perfect path, has no scatter to model and is
//! refused). With the rule w0 = max(t/20, 2H/450, δ_p), which gives each layer count its own
//! w0, the variable is a dimensionless **factor on the rule's w0, mean 1**, the same in every
//! layer count: the rule states a workmanship tolerance relative to the wall's thickness and
//! height, and its scatter is the printer's and the mix's, shared by every layer of one print
//! (a cov is then the cov of every state's w0; `std`, `lower`, `upper` are in units of the
//! rule's w0).
//!
//! # What λ_c depends on, and the one exact scaling
//!
//! λ_c depends on every parameter that sets the path or its material check: E₀, Ė (the layers'
//! moduli, hence the mode, the imperfect geometry and the path), T (the ages), f₀ and ḟ (the
//! capacity at the faces, when the path checks the material), w0, and γ. It is **not** E/γ-
//! scaled once the material can govern: the face stresses at a point of the path are E times
//! strains, the capacity is f_c(t), so E₀ and f₀ enter separately. Only γ scales exactly:
//!
//! λ_c(γ) = λ_c(γ₀)·γ₀/γ.
//!
//! *Proof.* The self-weight load is γ·f̂ (every element's unit weight is γ·t). The internal
//! force of the co-rotational shell depends on the displacements and the moduli only, so the
//! equilibria of the path under λ·γ·f̂ are those under μ·f̂ with μ = λγ, the same displacement
//! field u(μ); the face stresses are functions of u, so the material utilisation along the path
//! is a function of μ; a limit point and a material crossing are therefore at fixed μ_c, and
//! λ_c = μ_c/γ. The path's own controls scale the same way: the first increment
//! ½·min(λ_LBA, 1/u_lin) and λ_max = 1.5·λ_LBA are both ∝ 1/γ (λ_LBA ∝ 1/γ, u_lin ∝ γ), the
//! arc length is measured in displacements, the residual tolerance is relative to the load,
//! so the path visits the same μ at every step. Test
//! `buildability_collapse::collapse_factor_scales_exactly_with_the_weight` checks it by
//! re-solves.
//!
//! # Tables, FORM and sampling on them
//!
//! λ_c costs a path per evaluation, so, as buckling's Λ(ρ), it is tabulated: per layer count,
//! ln λ_c at γ₀ on the tensor grid of [`COLLAPSE_NODES`] Chebyshev points per uncertain
//! parameter it depends on (the axes: E₀, Ė, T; f₀, ḟ when the path checks the material; w0),
//! each axis in the logarithm of its variable over the box of ±[`Z_RANGE`] standard deviations
//! of every state's drifted model (the buckling tables' box); at most [`MAX_AXES`] axes (a
//! named error names the parameters otherwise: 5^d paths per state grow too fast). Each grid
//! point is one run of the deterministic check itself ([`check_layers`] with the parameters and
//! w0 set), so the tables are a speed-up of the same model. FORM evaluates the table (outside
//! the box: continued linearly in the logarithms from the edge, as the buckling tables) with
//! central-difference gradients; the Monte Carlo evaluates it and re-solves a sample outside
//! the box. Without an axis (γ alone uncertain) the table is the deterministic run's own
//! λ_c, exact by the scaling.
//!
//! # Which layer counts get a table
//!
//! A state can fail by collapse inside the selection box (±[`Z_SELECT`] = 4 standard
//! deviations per variable) only if its ln-margin G_n = ln(λ_c,n/collapse_min) at the means is
//! at most its own downward span D_n = G_n − min over that box of g_n. The state of least G_n
//! is tabulated first; D_n of a tabulated state is measured on its interpolant (9 points per
//! axis over the selection box, γ at the box's top). Every state with G_n ≤
//! [`SPAN_SAFETY`]·D_max (D_max the largest span measured so far) is then tabulated, and again
//! with the new spans, until no state is added. A skipped state could fail inside the
//! selection box only if its own span exceeded 1.5× every span measured on the same object — an
//! argument from the measured spans of neighbouring states (the same wall, material and
//! scatter), not a proof — and outside it only with P ≲ 10⁻⁴; its collapse then counts neither
//! in FORM nor in the Monte Carlo. (The first version used the whole ±5σ table box: with w0's
//! cov 0.5 that is w0 × [0.09, 11], and every layer count down to the first was admitted,
//! whose FORM then wandered to E₀ → 0 on a flat, extrapolated surface.) A state whose nominal λ_c is 0 (a
//! mechanism) fails in every sample. Without any axis every state gets its exact table.
//!
//! # Kinks
//!
//! λ_c = min(limit point, material crossing) is continuous but may have a kink where the two
//! swap inside the box; the grid's modes are reported per state (`mixed_modes` lists the states
//! whose nodes end by different modes). The Chebyshev interpolant rounds such a kink off, and
//! FORM's HL-RF linearises at the design point of the smoothed surface; both errors show in
//! the re-solve at every state's design point ([`CollapseTables::report`]: the table against a
//! direct path there, relative and as Δβ = |Δ ln λ_c|/‖∇ᵤg‖) and in FORM against the Monte
//! Carlo of the same table (tests).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use kappe_reliability::{EvalError, Fallible, FormResult, LimitState};

use crate::analysis::collapse::{Collapse, CollapseMode};
use crate::analysis::collapse_reliability::{
    LogAxis, admit, coefficients, design_point_error, grid_point, grid_size, interpolate, least_log,
};
use crate::analysis::design_monte_carlo::bits;
use crate::commands::buildability::{BuildState, Resolved, check_layers};
use crate::commands::buildability_reliability::{
    E0, F0, FRATE, GAMMA, PARAMETERS, Prepared, RATE, T, Z_RANGE, resolved_at, t_hours, uerr,
    variable_box,
};
use crate::input::error::DesignError;

pub use crate::input::uncertainty::IMPERFECTION;

pub use crate::analysis::collapse_reliability::{
    COLLAPSE_NODES, DESIGN_POINT_BETA_TOLERANCE, MAX_AXES, SPAN_SAFETY, Z_SELECT,
};

/// The nominal value of `analysis.nonlinear.imperfection` in `r` and that it is positive, or why
/// it cannot be uncertain (module docs).
///
/// # Errors
/// No collapse check, or `imperfection = 0`.
pub fn imperfection_nominal(r: &Resolved) -> Result<(f64, bool), String> {
    crate::input::uncertainty::imperfection_nominal(r.spec.nonlinear())
}

/// The uncertain parameters λ_c depends on (module docs): (index in [`PARAMETERS`] or None for
/// the imperfection, model index).
fn axes_of(r: &Resolved, p: &Prepared) -> Vec<(Option<usize>, usize)> {
    let Some(nl) = r.spec.nonlinear() else {
        return Vec::new();
    };
    let c = &r.spec.checks;
    let material = nl.material && (c.strength || c.sliding) && r.time.strength.is_some();
    let mut out: Vec<(Option<usize>, usize)> = [E0, RATE, F0, FRATE, T]
        .into_iter()
        .filter(|&k| material || (k != F0 && k != FRATE))
        .filter_map(|k| p.idx[k].map(|i| (Some(k), i)))
        .collect();
    if let Some(i) = p.imperfection {
        out.push((None, i));
    }
    out
}

fn axis_name(param: Option<usize>) -> &'static str {
    param
        .and_then(|k| PARAMETERS.get(k))
        .map_or(IMPERFECTION, |p| p.0)
}

/// A named error when λ_c would need a table over more than [`MAX_AXES`] parameters.
///
/// # Errors
/// [`DesignError::Uncertainty`] listing them.
pub fn check_collapse_axes(r: &Resolved, p: &Prepared) -> Result<(), DesignError> {
    let axes = axes_of(r, p);
    if axes.len() > MAX_AXES {
        let names: Vec<String> = axes
            .iter()
            .map(|a| format!("\"{}\"", axis_name(a.0)))
            .collect();
        return Err(uerr(
            "uncertainty",
            format!(
                "the collapse limit state ([analysis.nonlinear]) is tabulated over at most \
                 {MAX_AXES} of the uncertain parameters its path depends on; this table makes \
                 {} of them uncertain ({}): hold the others at fixed values (γ may be uncertain \
                 too: it scales λ_c exactly), or switch the collapse check off",
                axes.len(),
                names.join(", ")
            ),
        ));
    }
    Ok(())
}

/// The collapse of the state with `n` layers by a direct path at parameters `p`
/// ([`PARAMETERS`] order) and imperfection variable `m` (w0 in m with `imperfection` given,
/// else the factor on the rule's w0): the deterministic check itself ([`check_layers`]).
///
/// # Errors
/// No `[analysis.nonlinear]`, a refused parameter, a failed solve, or no collapse factor (no
/// positive buckling factor to take the imperfection's shape from).
pub fn direct(r: &Resolved, n: usize, p: &[f64; 6], m: f64) -> Result<Collapse, DesignError> {
    let mut at = resolved_at(r, p)?;
    let o = &r.spec.object;
    let Some(nl) = at
        .spec
        .analysis
        .as_mut()
        .and_then(|a| a.nonlinear.as_mut())
        .filter(|n| n.enabled)
    else {
        return Err(uerr(
            "analysis.nonlinear",
            "the collapse limit state needs [analysis.nonlinear]",
        ));
    };
    let w0 = match nl.imperfection {
        Some(_) => m,
        None => m * nl.amplitude(o.width, n as f64 * o.layer_height),
    };
    nl.imperfection = Some(w0);
    check_layers(&at, n)?.collapse.ok_or_else(|| {
        uerr(
            "uncertainty",
            format!("layer count {n}: no collapse factor (no positive buckling factor)"),
        )
    })
}

/// One axis of the tables: the parameter, its model index and its grid in the logarithm.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Axis {
    param: Option<usize>,
    var: usize,
}

/// One layer count's table: ln λ_c at γ₀ on the grid (the first axis slowest).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct StateTable {
    layers: usize,
    #[serde(with = "bits")]
    log: Vec<f64>,
    modes: Vec<CollapseMode>,
}

/// The collapse tables of a buildability print (module docs). Serializable with every number
/// as its bit pattern, so that the tables built once on a Dask worker
/// (`buildability_reliability::collapse_tables`) sample the same bits wherever they are
/// shipped (`SurrogateTables`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CollapseTables {
    axes: Vec<Axis>,
    grid: Vec<LogAxis>,
    states: Vec<StateTable>,
    /// Layer counts whose nominal λ_c is 0 (mechanisms): they fail in every sample.
    mechanisms: Vec<usize>,
    #[serde(with = "bits::one")]
    gamma0: f64,
    #[serde(with = "bits::one")]
    collapse_min: f64,
    /// Whether a random variable enters λ_c (else no FORM component: deterministic).
    random: bool,
    /// The largest downward span D measured (module docs).
    #[serde(with = "bits::one")]
    pub span: f64,
    /// Paths solved for the tables.
    pub solves: usize,
    /// Wall-clock seconds of the tables.
    pub seconds: f64,
}

impl CollapseTables {
    /// The tables of the layer counts the state rule keeps (module docs), from the
    /// deterministic run's `states` (their collapse factors).
    ///
    /// # Errors
    /// A drift factor that is not positive, a variable box that is not positive, a failed path,
    /// or a mechanism at a grid point.
    pub fn build(
        r: &Resolved,
        p: &Prepared,
        states: &[BuildState],
    ) -> Result<CollapseTables, DesignError> {
        let t0 = kappe_fe::clock::Instant::now();
        let boxes = variable_box(r, p)?;
        let axes: Vec<Axis> = axes_of(r, p)
            .into_iter()
            .map(|(param, var)| Axis { param, var })
            .collect();
        let grid = axes
            .iter()
            .map(|a| {
                let [lo, hi] = boxes.get(a.var).copied().unwrap_or([f64::NAN; 2]);
                LogAxis::new(lo, hi)
                    .map_err(|m| uerr(format!("uncertainty.\"{}\"", axis_name(a.param)), m))
            })
            .collect::<Result<Vec<_>, DesignError>>()?;
        let gamma0 = p.nominal[GAMMA];
        let gamma_hi = p.idx[GAMMA]
            .and_then(|i| boxes.get(i))
            .map_or(gamma0, |b| b[1]);
        // γ at the top of the selection box (a normal: linear in z).
        let gamma_select = (1.0 + Z_SELECT / Z_RANGE * (gamma_hi / gamma0 - 1.0)).ln();
        let collapse_min = r.spec.checks.collapse_min;
        let mut mechanisms = Vec::new();
        let mut order: Vec<(usize, f64)> = Vec::new();
        for s in states {
            match s.collapse_factor {
                Some(f) if f > 0.0 && f.is_finite() => {
                    order.push((s.layers, (f / collapse_min).ln()));
                }
                Some(f) if f <= 0.0 => mechanisms.push(s.layers),
                _ => {}
            }
        }
        order.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut out = CollapseTables {
            axes,
            grid,
            states: Vec::new(),
            mechanisms,
            gamma0,
            collapse_min,
            random: false,
            span: 0.0,
            solves: 0,
            seconds: 0.0,
        };
        out.random = !out.axes.is_empty() || p.idx[GAMMA].is_some();
        if out.axes.is_empty() {
            // The deterministic λ_c at γ₀, exact for every γ by the scaling.
            out.states = order
                .iter()
                .filter_map(|&(n, g)| {
                    let mode = states.iter().find(|s| s.layers == n)?.collapse_mode?;
                    Some(StateTable {
                        layers: n,
                        log: vec![g + collapse_min.ln()],
                        modes: vec![mode],
                    })
                })
                .collect();
            out.span = gamma_select;
        } else {
            // The selection box: ±Z_SELECT of the ±Z_RANGE box in each axis' logarithm
            // (exact for a lognormal without drift, whose logarithm is linear in z).
            let select: Vec<[f64; 2]> = out
                .grid
                .iter()
                .map(|a| {
                    let [lo, hi] = a.range();
                    let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo) * Z_SELECT / Z_RANGE);
                    [mid - half, mid + half]
                })
                .collect();
            let this = &out;
            let mut solves = 0;
            // γ's exact shift is taken into the spans (and so times SPAN_SAFETY), as this
            // rule was first written and measured (the cap's rule keeps it apart).
            let (tables, span) = admit(
                &order,
                0.0,
                |next| {
                    let t = this.tabulate(r, p, next)?;
                    solves += t.len() * grid_size(&this.grid);
                    Ok::<_, DesignError>(t.into_iter().map(|t| (t.layers, t)).collect())
                },
                |t: &StateTable| {
                    least_log(&this.grid, &t.log, &select) - collapse_min.ln() - gamma_select
                },
            )?;
            out.solves += solves;
            out.span = span;
            out.states = tables.into_iter().map(|t| t.1).collect();
        }
        out.states.sort_by_key(|s| s.layers);
        out.seconds = t0.elapsed().as_secs_f64();
        Ok(out)
    }

    /// The grids of the layer counts `layers`, every (state, point) path in parallel.
    fn tabulate(
        &self,
        r: &Resolved,
        p: &Prepared,
        layers: &[usize],
    ) -> Result<Vec<StateTable>, DesignError> {
        let total = grid_size(&self.grid);
        let m0 = imperfection_nominal(r).map_or(1.0, |v| v.0);
        let jobs: Vec<(usize, usize)> = layers
            .iter()
            .flat_map(|&n| (0..total).map(move |j| (n, j)))
            .collect();
        let (axes, grid) = (&self.axes, &self.grid);
        let solved = jobs
            .par_iter()
            .map(|&(n, j)| {
                let mut params = p.nominal;
                let mut m = m0;
                let point = grid_point(grid, j);
                for (a, &v) in axes.iter().zip(&point) {
                    match a.param {
                        Some(k) => params[k] = v,
                        None => m = v,
                    }
                }
                let c = direct(r, n, &params, m)?;
                if !(c.factor > 0.0 && c.factor.is_finite()) {
                    return Err(uerr(
                        "uncertainty",
                        format!(
                            "layer count {n}: collapse factor {} at a point of the collapse \
                             table ({}): the box of ±{Z_RANGE} standard deviations reaches a \
                             mechanism; narrow the scatter",
                            c.factor,
                            axes.iter()
                                .zip(&point)
                                .map(|(a, v)| format!("{} = {v:.4e}", axis_name(a.param)))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                }
                Ok((c.factor.ln(), c.mode))
            })
            .collect::<Result<Vec<_>, DesignError>>()?;
        Ok(layers
            .iter()
            .zip(solved.chunks(total.max(1)))
            .map(|(&n, c)| StateTable {
                layers: n,
                log: c.iter().map(|v| v.0).collect(),
                modes: c.iter().map(|v| v.1).collect(),
            })
            .collect())
    }

    fn has_table(&self, n: usize) -> bool {
        self.states.iter().any(|s| s.layers == n)
    }

    /// Whether layer count `n` has a collapse component in FORM (a table, and a random
    /// variable entering λ_c).
    pub fn has(&self, n: usize) -> bool {
        self.random && self.has_table(n)
    }

    /// The layer counts with a table.
    pub fn layers(&self) -> Vec<usize> {
        self.states.iter().map(|s| s.layers).collect()
    }

    /// The imperfection variable at the model point `x` (nominal where not uncertain).
    fn imperfection_at(r: &Resolved, p: &Prepared, x: &[f64]) -> f64 {
        p.imperfection
            .and_then(|i| x.get(i).copied())
            .unwrap_or_else(|| imperfection_nominal(r).map_or(1.0, |v| v.0))
    }

    /// λ_c of layer count `n` at the model point `x` by a direct path.
    ///
    /// # Errors
    /// See [`direct`].
    pub fn direct_at(
        r: &Resolved,
        p: &Prepared,
        n: usize,
        x: &[f64],
    ) -> Result<Collapse, DesignError> {
        direct(r, n, &p.params(x), Self::imperfection_at(r, p, x))
    }

    /// λ_c of layer count `n` at the model point `x` from its table (None: no table; 0 for a
    /// mechanism). Outside the box: continued from the edge with `clamp` (FORM), else a direct
    /// path, counted in `fallbacks` (sampling).
    ///
    /// # Errors
    /// A failed direct path.
    pub fn factor(
        &self,
        r: &Resolved,
        p: &Prepared,
        n: usize,
        x: &[f64],
        clamp: bool,
        fallbacks: &AtomicU64,
    ) -> Result<Option<f64>, DesignError> {
        if self.mechanisms.contains(&n) {
            return Ok(Some(0.0));
        }
        let Some(t) = self.states.iter().find(|s| s.layers == n) else {
            return Ok(None);
        };
        let s: Vec<f64> = self
            .axes
            .iter()
            .map(|a| x.get(a.var).copied().unwrap_or(f64::NAN).ln())
            .collect();
        let Some(coefs) = coefficients(&self.grid, &s, clamp) else {
            fallbacks.fetch_add(1, Ordering::Relaxed);
            return Self::direct_at(r, p, n, x).map(|c| Some(c.factor));
        };
        let log = interpolate(&self.grid, &t.log, &coefs);
        let gamma = p.params(x)[GAMMA];
        Ok(Some(log.exp() * self.gamma0 / gamma))
    }

    /// Whether layer count `n` collapses (λ_c < collapse_min) at the model point `x`.
    ///
    /// # Errors
    /// See [`CollapseTables::factor`].
    pub fn fails(
        &self,
        r: &Resolved,
        p: &Prepared,
        n: usize,
        x: &[f64],
        clamp: bool,
        fallbacks: &AtomicU64,
    ) -> Result<bool, DesignError> {
        Ok(self
            .factor(r, p, n, x, clamp, fallbacks)?
            .is_some_and(|f| f < self.collapse_min))
    }

    /// g(x) = ln(λ_c/collapse_min) of layer count `n` on its table (FORM: continued outside
    /// the box).
    ///
    /// # Errors
    /// No table, or no positive λ_c.
    pub fn g(&self, r: &Resolved, p: &Prepared, n: usize, x: &[f64]) -> Result<f64, EvalError> {
        let never = AtomicU64::new(0);
        match self.factor(r, p, n, x, true, &never) {
            Ok(Some(f)) if f > 0.0 => Ok((f / self.collapse_min).ln()),
            Ok(_) => Err(EvalError::from(format!(
                "layer count {n}: no positive collapse factor at x = {x:?}"
            ))),
            Err(e) => Err(EvalError::from(e.to_string())),
        }
    }

    /// The FORM limit state of layer count `n` ([`CollapseTables::g`]).
    pub fn limit_state<'a>(
        &'a self,
        r: &'a Resolved,
        p: &'a Prepared,
        n: usize,
    ) -> Box<dyn LimitState + 'a> {
        Box::new(Fallible(move |x: &[f64]| self.g(r, p, n, &p.floored(x))))
    }

    /// The tables' summary and the check of every state's collapse design point (`points`:
    /// layer count, FORM result) against a direct path there.
    ///
    /// # Errors
    /// A drift factor that is not positive, or a failed path.
    pub fn report(
        &self,
        r: &Resolved,
        p: &Prepared,
        points: &[(usize, FormResult)],
    ) -> Result<CollapseReliability, DesignError> {
        let checks = points
            .par_iter()
            .map(|(n, f)| self.check_point(r, p, *n, f))
            .collect::<Result<Vec<_>, DesignError>>()?;
        Ok(CollapseReliability {
            parameters: self
                .axes
                .iter()
                .map(|a| axis_name(a.param).to_owned())
                .collect(),
            nodes_per_parameter: COLLAPSE_NODES,
            imperfection_is_factor: r.spec.nonlinear().is_some_and(|n| n.imperfection.is_none()),
            states: self.layers(),
            mixed_modes: self
                .states
                .iter()
                .filter(|s| s.modes.iter().any(|m| Some(m) != s.modes.first()))
                .map(|s| s.layers)
                .collect(),
            span: self.span,
            solves: self.solves,
            seconds: self.seconds,
            max_relative_error: checks.iter().map(|c| c.relative_error).fold(0.0, f64::max),
            max_beta_error: checks.iter().map(|c| c.beta_error).fold(0.0, f64::max),
            design_points: checks,
        })
    }

    /// One state's design point: the table against a direct path, and the error as Δβ.
    fn check_point(
        &self,
        r: &Resolved,
        p: &Prepared,
        n: usize,
        f: &FormResult,
    ) -> Result<DesignPointCheck, DesignError> {
        let never = AtomicU64::new(0);
        let x = &f.x_star;
        let table = self.factor(r, p, n, x, true, &never)?.unwrap_or(f64::NAN);
        let path = Self::direct_at(r, p, n, x)?;
        let th = t_hours(r, n);
        let model = p
            .model
            .drifted(&p.drifts, th)
            .map_err(|e| uerr("uncertainty.drift", format!("state {n}: {e}")))?;
        let (relative_error, beta_error) =
            design_point_error(&f.u_star, table, path.factor, |u| {
                self.g(r, p, n, &model.x_from_u(u))
                    .map_err(|e| uerr("uncertainty", e.to_string()))
            })?;
        Ok(DesignPointCheck {
            layers: n,
            beta: f.beta,
            design_point: f.names.iter().cloned().zip(x.iter().copied()).collect(),
            table,
            path: path.factor,
            mode: path.mode,
            relative_error,
            beta_error,
        })
    }
}

/// A state's collapse design point checked by a direct path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignPointCheck {
    /// Layer count.
    pub layers: usize,
    /// FORM's β of the state's collapse component.
    pub beta: f64,
    /// The design point (every variable of the model).
    pub design_point: BTreeMap<String, f64>,
    /// λ_c there from the table.
    pub table: f64,
    /// λ_c there by a direct path.
    pub path: f64,
    /// What ends the direct path there.
    pub mode: CollapseMode,
    /// |table − path|/path.
    pub relative_error: f64,
    /// The error as Δβ = |ln table − ln path|/‖∇ᵤg‖.
    pub beta_error: f64,
}

/// The collapse limit state of a buildability print (`buildability.json`
/// `result.collapse_reliability`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CollapseReliability {
    /// The tables' axes (empty: γ alone, exact scaling).
    pub parameters: Vec<String>,
    /// Chebyshev points per axis.
    pub nodes_per_parameter: usize,
    /// Whether the imperfection variable is a factor on the rule's w0 (else w0 in m).
    pub imperfection_is_factor: bool,
    /// The layer counts with a table.
    pub states: Vec<usize>,
    /// Tabulated layer counts whose grid points end by different modes (a kink in the box).
    pub mixed_modes: Vec<usize>,
    /// The largest downward span of ln λ_c measured (the state rule's D).
    pub span: f64,
    /// Paths solved for the tables.
    pub solves: usize,
    /// Wall-clock seconds of the tables.
    pub seconds: f64,
    /// Every state's collapse design point against a direct path.
    pub design_points: Vec<DesignPointCheck>,
    /// The largest relative error there.
    pub max_relative_error: f64,
    /// The largest error there as Δβ.
    pub max_beta_error: f64,
}
