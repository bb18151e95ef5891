//! First-order reliability method (FORM): the design point by the improved HL-RF algorithm.
//!
//! In the standard normal space u (see [`crate::model`]) the limit state is G(u) = g(T⁻¹(u)),
//! failure G ≤ 0. The design point u* is the point of G = 0 nearest the origin; β = αᵀu*, with
//! α = −∇G(u*)/‖∇G(u*)‖ (pointing towards failure), and P_f ≈ Φ(−β) (exact for G linear in u).
//!
//! # iHL-RF (Zhang & Der Kiureghian 1995)
//!
//! From uₖ, the HL-RF direction is
//!
//! dₖ = [(∇Gₖᵀuₖ − Gₖ)/‖∇Gₖ‖²] ∇Gₖ − uₖ,
//!
//! and the step uₖ₊₁ = uₖ + λₖdₖ takes λₖ = ½ʲ, the first j = 0, 1, … with the Armijo decrease
//! m(uₖ + λdₖ) ≤ m(uₖ) + a λ ∇m(uₖ)ᵀdₖ (a = 10⁻⁴) of the merit function
//!
//! m(u) = ½‖u‖² + c |G(u)|,  c = 2 max(‖uₖ‖, ‖uₖ + dₖ‖)/‖∇Gₖ‖ > ‖uₖ‖/‖∇Gₖ‖,
//!
//! for which dₖ is a descent direction (Zhang & Der Kiureghian 1995, Struct. Safety; also Der
//! Kiureghian, *Structural and System Reliability*, 2022, §5.4). The term ‖uₖ + dₖ‖ keeps c > 0 at
//! the origin and makes the full step acceptable whenever G is linear (then m(uₖ + dₖ) ≤ m(uₖ)
//! for any start), so a linear limit state converges in one step as with plain HL-RF. Convergence: |G(uₖ)|/|G(u₀)| ≤ ε_G and ‖uₖ − (αₖᵀuₖ)αₖ‖ ≤ ε_u (the point is on
//! the surface and u is parallel to the gradient; ε_u is scaled by max(1, ‖uₖ‖), an angle rather
//! than a distance far out). The start is the mean point.
//!
//! # Gradients
//!
//! ∇_u G = Lᵀ (dx/dz ∘ ∇_x g) by the chain rule through the Nataf map. ∇_x g comes from the caller
//! ([`crate::WithGradient`]) or from central differences ∂g/∂xᵢ ≈ (g(x + hᵢeᵢ) − g(x − hᵢeᵢ))/(2hᵢ),
//! hᵢ = `fd_step`·σᵢ (default 10⁻⁵σᵢ: a step of 10⁻⁵ in u, truncation error O(10⁻¹⁰) relative and
//! round-off O(ε_mach·10⁵) ≈ 10⁻¹¹ relative for a limit state whose value changes by O(|g|) over one σ).
//!
//! # Sensitivities
//!
//! At a fixed design point x*, β = αᵀT(x*, θ), so dβ/dθ = αᵀ ∂u*/∂θ = (L⁻ᵀα)ᵢ ∂zᵢ/∂θ for a
//! parameter θ of variable i (Hohenbichler & Rackwitz 1986; Der Kiureghian 2022, §5.7). ∂zᵢ/∂μᵢ and
//! ∂zᵢ/∂σᵢ are central differences of zᵢ = Φ⁻¹(Fᵢ(xᵢ*; μᵢ, σᵢ)) with steps 10⁻⁶σᵢ (no limit-state
//! evaluation). R₀ is held fixed; for normal variables this is exact, for others it neglects
//! the (small) change of the Nataf ρ₀ with μ, σ.
//!
//! The importance vector γ = L⁻ᵀα/‖L⁻ᵀα‖ (Der Kiureghian 2022, §5.6) equals α for independent
//! variables and attributes correlated u's back to the physical variables; the importance factors
//! are γᵢ² (they sum to 1). γᵢ < 0: variable i acts as a resistance (lower values fail),
//! γᵢ > 0: as a load.

use crate::error::{Error, Result};
use crate::limit_state::LimitState;
use crate::model::Model;
use crate::stdnormal;
use serde::{Deserialize, Serialize};

/// FORM settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FormOptions {
    /// Maximum HL-RF iterations (default 100).
    pub max_iterations: usize,
    /// ε_G: |G|/|G(start)| at convergence (default 10⁻⁶; |G| itself when G(start) = 0).
    pub g_tolerance: f64,
    /// ε_u: ‖u − (αᵀu)α‖ / max(1, ‖u‖) at convergence (default 10⁻⁶).
    pub u_tolerance: f64,
    /// Central-difference step in standard deviations (default 10⁻⁵).
    pub fd_step: f64,
    /// Maximum step halvings of the line search (default 30).
    pub max_line_search: usize,
    /// Start point in physical space (default: the means).
    pub start: Option<Vec<f64>>,
}

impl Default for FormOptions {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            g_tolerance: 1e-6,
            u_tolerance: 1e-6,
            fd_step: 1e-5,
            max_line_search: 30,
            start: None,
        }
    }
}

/// The result of a FORM analysis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FormResult {
    /// Variable names, in model order (the order of every vector below).
    pub names: Vec<String>,
    /// Reliability index β = αᵀu* (negative when the means fail).
    pub beta: f64,
    /// P_f = Φ(−β).
    pub pf: f64,
    /// Design point in physical space (the most probable failing values).
    pub x_star: Vec<f64>,
    /// Design point in standard normal space, u* ≈ βα.
    pub u_star: Vec<f64>,
    /// α = −∇G/‖∇G‖ at u* (in u-space).
    pub alpha: Vec<f64>,
    /// Importance vector γ = L⁻ᵀα/‖L⁻ᵀα‖ (= α without correlation).
    pub gamma: Vec<f64>,
    /// Importance factors γᵢ² (sum 1).
    pub importance: Vec<f64>,
    /// dβ/dμᵢ (mean of each variable, its std held).
    pub dbeta_dmean: Vec<f64>,
    /// dβ/dσᵢ (std of each variable, its mean held).
    pub dbeta_dstd: Vec<f64>,
    /// g(x*).
    pub g_at_design_point: f64,
    /// |G|/|G(start)| at the last iterate.
    pub g_residual: f64,
    /// ‖u − (αᵀu)α‖ at the last iterate.
    pub u_residual: f64,
    /// HL-RF iterations.
    pub iterations: usize,
    /// Limit-state value evaluations (including those of finite differences and line searches).
    pub evaluations: usize,
    /// Evaluations with a caller-supplied gradient.
    pub gradient_evaluations: usize,
}

struct Evaluator<'a, L: ?Sized> {
    model: &'a Model,
    ls: &'a mut L,
    fd_step: f64,
    evaluations: usize,
    gradient_evaluations: usize,
}

fn finite(what: &'static str, value: f64, x: &[f64]) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NonFiniteLimitState {
            what,
            value,
            x: x.to_vec(),
        })
    }
}

impl<L: LimitState + ?Sized> Evaluator<'_, L> {
    fn value(&mut self, x: &[f64]) -> Result<f64> {
        self.evaluations += 1;
        let g = self.ls.value(x).map_err(|source| Error::LimitState {
            x: x.to_vec(),
            source,
        })?;
        finite("value", g, x)
    }

    fn value_and_gradient(&mut self, x: &[f64], known: Option<f64>) -> Result<(f64, Vec<f64>)> {
        let n = x.len();
        let mut grad = vec![0.0; n];
        let supplied =
            self.ls
                .value_and_gradient(x, &mut grad)
                .map_err(|source| Error::LimitState {
                    x: x.to_vec(),
                    source,
                })?;
        if let Some(g) = supplied {
            self.gradient_evaluations += 1;
            for &d in &grad {
                finite("gradient", d, x)?;
            }
            return Ok((finite("value", g, x)?, grad));
        }
        let g = match known {
            Some(g) => g,
            None => self.value(x)?,
        };
        let stds = self.model.stds();
        let mut xp = x.to_vec();
        for i in 0..n {
            let h = self.fd_step * stds[i];
            xp[i] = x[i] + h;
            let gp = self.value(&xp)?;
            xp[i] = x[i] - h;
            let gm = self.value(&xp)?;
            xp[i] = x[i];
            grad[i] = (gp - gm) / (2.0 * h);
        }
        Ok((g, grad))
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

fn check_options(o: &FormOptions) -> Result<()> {
    let bad = |field, value: f64, allowed| {
        Err(Error::InvalidOption {
            field,
            value,
            allowed,
        })
    };
    if o.max_iterations == 0 {
        return bad("max_iterations", 0.0, "at least 1");
    }
    if !(o.g_tolerance > 0.0 && o.g_tolerance.is_finite()) {
        return bad("g_tolerance", o.g_tolerance, "finite and > 0");
    }
    if !(o.u_tolerance > 0.0 && o.u_tolerance.is_finite()) {
        return bad("u_tolerance", o.u_tolerance, "finite and > 0");
    }
    if !(o.fd_step > 0.0 && o.fd_step < 1.0) {
        return bad(
            "fd_step",
            o.fd_step,
            "0 < fd_step < 1 (standard deviations)",
        );
    }
    Ok(())
}

/// FORM by iHL-RF; see the module docs. `limit_state` is g(x) in physical space, failure g ≤ 0.
pub fn form<L: LimitState + ?Sized>(
    model: &Model,
    limit_state: &mut L,
    options: &FormOptions,
) -> Result<FormResult> {
    check_options(options)?;
    let n = model.len();
    let start = match &options.start {
        Some(x) if x.len() != n => {
            return Err(Error::DimensionMismatch {
                what: "FORM start point",
                expected: n,
                got: x.len(),
            });
        }
        Some(x) => x.clone(),
        None => model.means(),
    };
    let mut u = model.u_from_x(&start);
    if let Some(i) = u.iter().position(|v| !v.is_finite()) {
        return Err(Error::InvalidOption {
            field: "start",
            value: start[i],
            allowed: "a point inside every variable's support",
        });
    }
    let mut ev = Evaluator {
        model,
        ls: limit_state,
        fd_step: options.fd_step,
        evaluations: 0,
        gradient_evaluations: 0,
    };
    let mut known_g = None;
    let mut scale = 1.0;
    let (mut beta, mut g_res, mut u_res) = (f64::NAN, f64::NAN, f64::NAN);
    for iteration in 1..=options.max_iterations {
        let x = model.x_from_u(&u);
        let (g, grad_x) = ev.value_and_gradient(&x, known_g)?;
        if iteration == 1 && g != 0.0 {
            scale = g.abs();
        }
        let grad_u = model.gradient_to_standard(&u, &grad_x);
        let gnorm = norm(&grad_u);
        if !(gnorm > 0.0 && gnorm.is_finite()) {
            return Err(Error::ZeroGradient { x });
        }
        let alpha: Vec<f64> = grad_u.iter().map(|d| -d / gnorm).collect();
        beta = dot(&alpha, &u);
        g_res = g.abs() / scale;
        u_res = norm(
            &u.iter()
                .zip(&alpha)
                .map(|(ui, ai)| ui - beta * ai)
                .collect::<Vec<_>>(),
        );
        // ε_u is relative to ‖u‖ beyond 1: the direction's angle, not an absolute distance,
        // which central-difference gradients cannot resolve below ~1e-8·‖u‖ far out (β ≫ 10).
        if g_res <= options.g_tolerance && u_res <= options.u_tolerance * norm(&u).max(1.0) {
            return Ok(finish(
                model, u, x, g, alpha, beta, g_res, u_res, iteration, &ev,
            ));
        }
        let coef = (dot(&grad_u, &u) - g) / (gnorm * gnorm);
        let d: Vec<f64> = grad_u
            .iter()
            .zip(&u)
            .map(|(gi, ui)| coef * gi - ui)
            .collect();
        let unorm = norm(&u);
        let full: Vec<f64> = u.iter().zip(&d).map(|(ui, di)| ui + di).collect();
        let c = 2.0 * unorm.max(norm(&full)) / gnorm;
        let merit0 = 0.5 * unorm * unorm + c * g.abs();
        let slope = dot(&u, &d) + c * g.signum() * dot(&grad_u, &d);
        let mut lambda = 1.0;
        let mut next = None;
        for _ in 0..=options.max_line_search {
            let un: Vec<f64> = u.iter().zip(&d).map(|(ui, di)| ui + lambda * di).collect();
            let gn = ev.value(&model.x_from_u(&un))?;
            let merit = 0.5 * dot(&un, &un) + c * gn.abs();
            let accept = merit <= merit0 + 1e-4 * lambda * slope;
            next = Some((un, gn));
            if accept {
                break;
            }
            lambda *= 0.5;
        }
        // If no step decreased the merit (round-off near the solution), the smallest step is
        // taken; the iteration limit still bounds the loop.
        if let Some((un, gn)) = next {
            u = un;
            known_g = Some(gn);
        }
    }
    Err(Error::FormNotConverged {
        iterations: options.max_iterations,
        evaluations: ev.evaluations,
        beta,
        g_residual: g_res,
        g_tolerance: options.g_tolerance,
        u_residual: u_res,
        u_tolerance: options.u_tolerance,
    })
}

/// Whether `u` is a design point of `limit_state` within `options`' tolerances, judged as
/// [`form`] judges its iterates but with ε_G relative to `g_scale` (|G| at the start of the
/// search that proposed `u`): one evaluation with gradient at x = T⁻¹(u). `Some` holds the
/// result as [`form`] returns it (sensitivities included), `None` says the tolerances are not
/// met there. For searches that propose the design point from a cheaper model of the limit
/// state and need the true one only to confirm it.
///
/// # Errors
/// A `u` of the wrong length, bad options, a failed or non-finite evaluation, a zero gradient.
pub fn form_at<L: LimitState + ?Sized>(
    model: &Model,
    limit_state: &mut L,
    u: &[f64],
    g_scale: f64,
    options: &FormOptions,
) -> Result<Option<FormResult>> {
    check_options(options)?;
    if u.len() != model.len() {
        return Err(Error::DimensionMismatch {
            what: "FORM point",
            expected: model.len(),
            got: u.len(),
        });
    }
    if !(g_scale > 0.0 && g_scale.is_finite()) {
        return Err(Error::InvalidOption {
            field: "g_scale",
            value: g_scale,
            allowed: "finite and > 0",
        });
    }
    let mut ev = Evaluator {
        model,
        ls: limit_state,
        fd_step: options.fd_step,
        evaluations: 0,
        gradient_evaluations: 0,
    };
    let x = model.x_from_u(u);
    let (g, grad_x) = ev.value_and_gradient(&x, None)?;
    let grad_u = model.gradient_to_standard(u, &grad_x);
    let gnorm = norm(&grad_u);
    if !(gnorm > 0.0 && gnorm.is_finite()) {
        return Err(Error::ZeroGradient { x });
    }
    let alpha: Vec<f64> = grad_u.iter().map(|d| -d / gnorm).collect();
    let beta = dot(&alpha, u);
    let g_res = g.abs() / g_scale;
    let u_res = norm(
        &u.iter()
            .zip(&alpha)
            .map(|(ui, ai)| ui - beta * ai)
            .collect::<Vec<_>>(),
    );
    // The tolerances exactly as `form` applies them.
    Ok(
        (g_res <= options.g_tolerance && u_res <= options.u_tolerance * norm(u).max(1.0))
            .then(|| finish(model, u.to_vec(), x, g, alpha, beta, g_res, u_res, 1, &ev)),
    )
}

#[allow(clippy::too_many_arguments)]
fn finish<L: ?Sized>(
    model: &Model,
    u: Vec<f64>,
    x: Vec<f64>,
    g: f64,
    alpha: Vec<f64>,
    beta: f64,
    g_residual: f64,
    u_residual: f64,
    iterations: usize,
    ev: &Evaluator<'_, L>,
) -> FormResult {
    let n = model.len();
    let v = model.solve_lt(&alpha);
    let vnorm = norm(&v);
    let gamma: Vec<f64> = v.iter().map(|vi| vi / vnorm).collect();
    let importance = gamma.iter().map(|gi| gi * gi).collect();
    let mut dbeta_dmean = vec![0.0; n];
    let mut dbeta_dstd = vec![0.0; n];
    for i in 0..n {
        let d = model.distribution(i);
        let (mu, sigma) = (d.mean(), d.std());
        let h = 1e-6 * sigma;
        let z = |m: f64, s: f64| d.with_mean_std(m, s).to_standard(x[i]);
        dbeta_dmean[i] = v[i] * (z(mu + h, sigma) - z(mu - h, sigma)) / (2.0 * h);
        dbeta_dstd[i] = v[i] * (z(mu, sigma + h) - z(mu, sigma - h)) / (2.0 * h);
    }
    FormResult {
        names: model.variables().iter().map(|v| v.name.clone()).collect(),
        beta,
        pf: stdnormal::cdf(-beta),
        x_star: x,
        u_star: u,
        alpha,
        gamma,
        importance,
        dbeta_dmean,
        dbeta_dstd,
        g_at_design_point: g,
        g_residual,
        u_residual,
        iterations,
        evaluations: ev.evaluations,
        gradient_evaluations: ev.gradient_evaluations,
    }
}
