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
use crate::analysis::design_monte_carlo::{bary_into, bits, cheb};
use crate::commands::buildability::{BuildState, Resolved, check_layers};
use crate::commands::buildability_reliability::{
    E0, F0, FRATE, GAMMA, PARAMETERS, Prepared, RATE, T, Z_RANGE, resolved_at, t_hours,
    table_coefficients, uerr, variable_box,
};
use crate::input::error::DesignError;

pub use crate::input::uncertainty::IMPERFECTION;

/// Chebyshev points per axis of a collapse table. λ_c is smooth in each parameter away from a
/// kink (see the module docs); 5 points per axis (25 paths per state with two axes) keep a
/// table at ~25 paths per state. Their error is measured at every design point, not assumed.
pub const COLLAPSE_NODES: usize = 5;

/// Most uncertain parameters a collapse table spans (5² = 25 paths per state; three would be
/// 125).
pub const MAX_AXES: usize = 2;

/// The margin on the measured spans of the state rule (module docs).
pub const SPAN_SAFETY: f64 = 1.5;

/// Half-width of the state rule's box, in standard deviations: a state that cannot fail inside
/// it has P_f ≤ P(some |zᵢ| > 4) ≈ d·6.3·10⁻⁵ (d ≤ 2 axes, and γ), negligible against any print
/// P_f the β target admits (Φ(−2.3) ≈ 10⁻²).
pub const Z_SELECT: f64 = 4.0;

/// Points per axis on which the state rule evaluates a table's interpolant.
const SELECT_POINTS: usize = 9;

/// The table's error at a design point, as Δβ = |ln λ_table − ln λ_path|/‖∇ᵤg‖, that the tests
/// accept: below FORM's own first-order error measured on these objects (Δβ ≈ 0.07 on study
/// No. 14's last state, docs/reliability.md), so the table adds no error FORM does not have.
pub const DESIGN_POINT_BETA_TOLERANCE: f64 = 0.05;

/// The nominal value of `analysis.nonlinear.imperfection` in `r` and that it is positive, or why
/// it cannot be uncertain (module docs).
///
/// # Errors
/// No collapse check, or `imperfection = 0`.
pub fn imperfection_nominal(r: &Resolved) -> Result<(f64, bool), String> {
    match r.spec.nonlinear() {
        None => Err(
            "the imperfection amplitude is an input of the nonlinear collapse check \
             only: give [analysis.nonlinear] (enabled) or remove it"
                .to_owned(),
        ),
        Some(nl) => match nl.imperfection {
            Some(w) if w <= 0.0 => Err(format!(
                "[analysis.nonlinear] imperfection = {w} is the perfect path, which has no \
                 scatter to model; give w0 > 0 m, or leave it to the rule, whose w0 the \
                 variable then multiplies (mean 1)"
            )),
            Some(w) => Ok((w, true)),
            None => Ok((1.0, true)),
        },
    }
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

/// One axis of the tables: ln of its variable over the box. Numbers travel as their bit
/// patterns when shipped (`SurrogateTables`).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Axis {
    param: Option<usize>,
    var: usize,
    #[serde(with = "bits")]
    nodes: Vec<f64>,
    #[serde(with = "bits")]
    weights: Vec<f64>,
    #[serde(with = "bits::pair")]
    range: [f64; 2],
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

/// The grid indices of flat index `flat` (the last axis fastest).
fn grid_index(axes: &[Axis], mut flat: usize) -> Vec<usize> {
    let mut out = vec![0; axes.len()];
    for (o, a) in out.iter_mut().zip(axes).rev() {
        let k = a.nodes.len().max(1);
        *o = flat % k;
        flat /= k;
    }
    out
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
        let axes = axes_of(r, p)
            .into_iter()
            .map(|(param, var)| {
                let [lo, hi] = boxes.get(var).copied().unwrap_or([f64::NAN; 2]);
                if !(lo > 0.0 && hi > lo && hi.is_finite()) {
                    return Err(uerr(
                        format!("uncertainty.\"{}\"", axis_name(param)),
                        format!("the collapse table needs a positive range, got [{lo}, {hi}]"),
                    ));
                }
                let range = [lo.ln(), hi.ln()];
                let (nodes, weights) = cheb(range[0], range[1], COLLAPSE_NODES);
                Ok(Axis {
                    param,
                    var,
                    nodes,
                    weights,
                    range,
                })
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
            let mut next: Vec<usize> = order.first().map(|s| s.0).into_iter().collect();
            while !next.is_empty() {
                let new = out.tabulate(r, p, &next)?;
                for t in new {
                    let g = order
                        .iter()
                        .find(|s| s.0 == t.layers)
                        .map_or(f64::NAN, |s| s.1);
                    let least = out.least_log(&t) - collapse_min.ln() - gamma_select;
                    out.span = out.span.max(g - least);
                    out.states.push(t);
                }
                let bound = SPAN_SAFETY * out.span;
                next = order
                    .iter()
                    .filter(|&&(n, g)| g <= bound && !out.has_table(n))
                    .map(|s| s.0)
                    .collect();
            }
        }
        out.states.sort_by_key(|s| s.layers);
        out.seconds = t0.elapsed().as_secs_f64();
        Ok(out)
    }

    /// The grids of the layer counts `layers`, every (state, point) path in parallel.
    fn tabulate(
        &mut self,
        r: &Resolved,
        p: &Prepared,
        layers: &[usize],
    ) -> Result<Vec<StateTable>, DesignError> {
        let total: usize = self.axes.iter().map(|a| a.nodes.len()).product();
        let m0 = imperfection_nominal(r).map_or(1.0, |v| v.0);
        let jobs: Vec<(usize, usize)> = layers
            .iter()
            .flat_map(|&n| (0..total).map(move |j| (n, j)))
            .collect();
        let axes = &self.axes;
        let solved = jobs
            .par_iter()
            .map(|&(n, j)| {
                let mut params = p.nominal;
                let mut m = m0;
                for (a, i) in axes.iter().zip(grid_index(axes, j)) {
                    let v = a.nodes.get(i).copied().unwrap_or(f64::NAN).exp();
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
                                .zip(grid_index(axes, j))
                                .map(|(a, i)| format!(
                                    "{} = {:.4e}",
                                    axis_name(a.param),
                                    a.nodes.get(i).copied().unwrap_or(f64::NAN).exp()
                                ))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                }
                Ok((c.factor.ln(), c.mode))
            })
            .collect::<Result<Vec<_>, DesignError>>()?;
        self.solves += solved.len();
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

    /// The least ln λ_c (at γ₀) of table `t` over the selection box: ±[`Z_SELECT`] of the
    /// ±[`Z_RANGE`] box in each axis' logarithm (exact for a lognormal without drift, whose
    /// logarithm is linear in z), on [`SELECT_POINTS`] points per axis of the interpolant
    /// (nodes and edges included).
    fn least_log(&self, t: &StateTable) -> f64 {
        let k = SELECT_POINTS;
        let total = k.pow(self.axes.len() as u32);
        (0..total)
            .map(|j| {
                let mut rest = j;
                let mut coefs = Vec::with_capacity(self.axes.len());
                for a in self.axes.iter().rev() {
                    let i = rest % k;
                    rest /= k;
                    let [lo, hi] = a.range;
                    let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo) * Z_SELECT / Z_RANGE);
                    let s = mid - half + 2.0 * half * i as f64 / (k - 1) as f64;
                    let mut c = vec![0.0; a.nodes.len()];
                    bary_into(&a.nodes, &a.weights, s, &mut c);
                    coefs.push(c);
                }
                coefs.reverse();
                self.interpolate(t, &coefs)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The table's interpolant from per-axis barycentric coefficients.
    fn interpolate(&self, t: &StateTable, coefs: &[Vec<f64>]) -> f64 {
        t.log
            .iter()
            .enumerate()
            .map(|(j, v)| {
                let w: f64 = grid_index(&self.axes, j)
                    .iter()
                    .zip(coefs)
                    .map(|(&i, c)| c.get(i).copied().unwrap_or(0.0))
                    .product();
                w * v
            })
            .sum()
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
        let mut coefs = Vec::with_capacity(self.axes.len());
        for a in &self.axes {
            let s = x.get(a.var).copied().unwrap_or(f64::NAN).ln();
            let mut c = vec![0.0; a.nodes.len()];
            if !table_coefficients(&a.nodes, &a.weights, a.range, s, clamp, &mut c) {
                fallbacks.fetch_add(1, Ordering::Relaxed);
                return Self::direct_at(r, p, n, x).map(|c| Some(c.factor));
            }
            coefs.push(c);
        }
        let log = self.interpolate(t, &coefs);
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
        // ‖∇ᵤg‖ at u* by central differences of the table (closed-form cost; step 10⁻³ in
        // u: truncation O(10⁻⁶) relative for a surface this smooth between nodes).
        let h = 1e-3;
        let mut norm2 = 0.0;
        for i in 0..f.u_star.len() {
            let mut up = f.u_star.clone();
            let mut dn = f.u_star.clone();
            up[i] += h;
            dn[i] -= h;
            let gu = self
                .g(r, p, n, &model.x_from_u(&up))
                .map_err(|e| uerr("uncertainty", e.to_string()))?;
            let gd = self
                .g(r, p, n, &model.x_from_u(&dn))
                .map_err(|e| uerr("uncertainty", e.to_string()))?;
            norm2 += ((gu - gd) / (2.0 * h)).powi(2);
        }
        let dlog = (table.ln() - path.factor.ln()).abs();
        Ok(DesignPointCheck {
            layers: n,
            beta: f.beta,
            design_point: f.names.iter().cloned().zip(x.iter().copied()).collect(),
            table,
            path: path.factor,
            mode: path.mode,
            relative_error: ((table - path.factor) / path.factor).abs(),
            beta_error: if norm2 > 0.0 {
                dlog / norm2.sqrt()
            } else {
                f64::INFINITY
            },
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
