//! Second-order reliability method (SORM): P_f from FORM's design point and the principal
//! curvatures of the limit-state surface there.
//!
//! # Curvatures
//!
//! At the design point u* (from [`crate::form`]) with ∇G = ∇_u G(u*) and α = −∇G/‖∇G‖, let R
//! be an orthogonal matrix whose last row is ±α (a Householder reflection that maps α to the
//! last axis). The first n − 1 rows span the tangent plane of G = 0 at u*, and the principal
//! curvatures κ₁ … κₙ₋₁ are the eigenvalues of the (n−1)×(n−1) block
//!
//! A = [R H Rᵀ]ₙ₋₁ / ‖∇G‖,  H = ∂²G/∂u∂uᵀ(u*),
//!
//! (Der Kiureghian, *Structural and System Reliability*, 2022, §6.3; Breitung 1984). κ > 0 means
//! the surface bends away from the origin (the failure domain is smaller than FORM's half space,
//! P_f < Φ(−β)). For the paraboloid G = β − uₙ + ½Σκᵢuᵢ² these are exactly the κᵢ. The
//! curvatures do not depend on how g is written: g̃ = f(g) with f(0) = 0, f′ > 0 adds
//! f″∇g∇gᵀ to the Hessian, which the tangent plane does not see, and scales H and ‖∇G‖ alike.
//!
//! H comes from the limit state when it can give it ([`LimitState::value_gradient_hessian`],
//! through the Nataf map by [`Model::hessian_to_standard`]), else from central differences in
//! u-space with step h = [`SormOptions::hessian_step`] (default 10⁻³): of ∇_u G when the limit
//! state gives its gradient (2n gradient evaluations; truncation error h²/6·|G⁗| ≈ 2·10⁻⁷
//! relative to a curvature of order one, and an evaluation noise ε of the gradient enters as
//! ε/h), else second differences of G (1 + 2n² evaluations; truncation h²/12, round-off
//! 4ε_mach|G|/h² ≈ 10⁻⁹ relative). Differences in u rather than x keep every point inside the
//! variables' supports.
//!
//! # The P_f formula: Hohenbichler–Rackwitz
//!
//! P_f ≈ Φ(−β) ∏ᵢ (1 + ψ(β) κᵢ)^(−1/2),  ψ(β) = φ(β)/Φ(−β)
//!
//! (Hohenbichler, Gollwitzer, Kruse & Rackwitz 1987, Struct. Safety 4; Hohenbichler & Rackwitz
//! 1988, J. Eng. Mech. 114). It is Breitung's (1984, J. Eng. Mech. 110) asymptotic formula
//! Φ(−β)∏(1 + βκᵢ)^(−1/2) with β replaced by ψ(β) = β + 1/β − … : for the paraboloid,
//! P_f = E[Φ(−β − s)], s = ½Σκᵢuᵢ² over the tangent coordinates, and ln Φ(−β − s) equals
//! ln Φ(−β) − ψ(β)s to first order in s, where Breitung's β is only ψ's large-β limit. Both
//! tend to the exact P_f of the paraboloid as β → ∞ with βκ fixed. At the moderate β of a
//! print (1–6) Breitung's keeps a first-order relative error of about −Σ(ψ − β)κᵢ/(2(1 + βκᵢ));
//! Hohenbichler–Rackwitz's leading error is the O(s²) term of ln Φ, −½ψ(ψ − β)s², averaged
//! under the weight (uᵢ ~ N(0, vᵢ), vᵢ = 1/(1 + ψκᵢ)):
//!
//! P_f,HR/P_f − 1 ≈ (1/8)ψ(ψ − β)[2Σ(κᵢvᵢ)² + (Σκᵢvᵢ)²].
//!
//! The tests check that against the exact paraboloid P_f (measured 0.66–1.0 of it for
//! β = 1…5, κ = −0.15…1). For κ > 0 (the surface bends away from the origin, FORM
//! conservative: the print's measured cases) it is 2.7–11 times closer than Breitung's; for
//! κ < 0 near the bound Breitung's can be closer. Tvedt's exact paraboloid integral would
//! remove the last term too, at the price of a complex contour integral; the paraboloid's own
//! error against the true surface (the third derivatives of G) is of the same order, so we
//! stop here. Breitung's value is reported next to it ([`SormResult::pf_breitung`]).
//!
//! **Validity.** The formula needs 1 + ψ(β)κᵢ > 0 for every i: a surface that bends towards
//! the origin with κ ≤ −1/ψ has a paraboloid that encloses the origin's neighbourhood, and the
//! asymptotic integral diverges. That is an error ([`Error::SormCurvature`], naming the
//! curvature and the bound), never a silent FORM value; the caller decides (Kappe keeps FORM's
//! P_f for such a component and counts it). β ≤ 0 (the means fail): the formula is applied to
//! the safe domain, whose surface has the curvatures −κᵢ seen from it, P_f = 1 − Φ(β)∏(1 −
//! ψ(−β)κᵢ)^(−1/2).

use crate::error::{Error, Result};
use crate::form::FormResult;
use crate::limit_state::LimitState;
use crate::model::Model;
use crate::stdnormal;
use serde::{Deserialize, Serialize};

/// SORM settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SormOptions {
    /// Central-difference step in u of the Hessian when the limit state does not give it
    /// (default 10⁻³; see the module docs).
    pub hessian_step: f64,
}

impl Default for SormOptions {
    fn default() -> Self {
        Self { hessian_step: 1e-3 }
    }
}

/// Where the Hessian came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HessianSource {
    /// The limit state's own ([`LimitState::value_gradient_hessian`]).
    LimitState,
    /// Central differences of the limit state's gradient in u.
    GradientDifferences,
    /// Second central differences of g in u.
    ValueDifferences,
}

/// The result of SORM at a FORM design point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SormResult {
    /// FORM's β (the design point's distance).
    pub beta_form: f64,
    /// FORM's P_f = Φ(−β).
    pub pf_form: f64,
    /// Principal curvatures κᵢ of G = 0 at u* (ascending; > 0 bends away from the origin).
    pub curvatures: Vec<f64>,
    /// P_f by Hohenbichler–Rackwitz (module docs).
    pub pf: f64,
    /// The equivalent index −Φ⁻¹(P_f).
    pub beta: f64,
    /// Breitung's asymptotic P_f; None where some 1 + βκᵢ ≤ 0.
    pub pf_breitung: Option<f64>,
    /// ‖∇_u G‖ at u*.
    pub gradient_norm: f64,
    /// Where H came from.
    pub hessian: HessianSource,
    /// Limit-state evaluations SORM made (with or without gradient).
    pub evaluations: usize,
}

/// ψ(β) = φ(β)/Φ(−β), the inverse Mills ratio; for β > 30 (Φ(−β) near underflow) its asymptotic
/// series 1/ψ = (1/β)(1 − 1/β² + 3/β⁴ − 15/β⁶), whose next term is below 10⁻¹⁰ of it there.
pub fn inverse_mills(beta: f64) -> f64 {
    if beta > 30.0 {
        let b2 = beta * beta;
        let r = (1.0 - 1.0 / b2 + 3.0 / (b2 * b2) - 15.0 / (b2 * b2 * b2)) / beta;
        1.0 / r
    } else {
        stdnormal::pdf(beta) / stdnormal::cdf(-beta)
    }
}

/// P_f by Hohenbichler–Rackwitz from β and the principal curvatures (module docs).
///
/// # Errors
/// [`Error::SormCurvature`] where a factor 1 + ψκᵢ (β ≤ 0: 1 − ψ(−β)κᵢ) is ≤ 0; a non-finite
/// β or curvature is [`Error::InvalidOption`].
pub fn hohenbichler_rackwitz(beta: f64, curvatures: &[f64]) -> Result<f64> {
    check_inputs(beta, curvatures)?;
    let (b, sign) = if beta > 0.0 {
        (beta, 1.0)
    } else {
        (-beta, -1.0)
    };
    let psi = inverse_mills(b);
    let mut product = 1.0;
    for (index, &k) in curvatures.iter().enumerate() {
        let factor = 1.0 + psi * sign * k;
        if factor <= 0.0 {
            return Err(Error::SormCurvature {
                index,
                curvature: k,
                beta,
                factor,
                bound: -sign / psi,
            });
        }
        product /= factor.sqrt();
    }
    let tail = stdnormal::cdf(-b) * product;
    Ok(if beta > 0.0 { tail } else { 1.0 - tail }.clamp(0.0, 1.0))
}

/// Breitung's asymptotic P_f = Φ(−β)∏(1 + βκᵢ)^(−1/2) (β > 0; β ≤ 0 on the safe domain as in
/// [`hohenbichler_rackwitz`]); None where a factor is ≤ 0 or β, κ are not finite.
pub fn breitung(beta: f64, curvatures: &[f64]) -> Option<f64> {
    check_inputs(beta, curvatures).ok()?;
    let (b, sign) = if beta > 0.0 {
        (beta, 1.0)
    } else {
        (-beta, -1.0)
    };
    let mut product = 1.0;
    for &k in curvatures {
        let factor = 1.0 + b * sign * k;
        if factor <= 0.0 {
            return None;
        }
        product /= factor.sqrt();
    }
    let tail = stdnormal::cdf(-b) * product;
    Some(if beta > 0.0 { tail } else { 1.0 - tail }.clamp(0.0, 1.0))
}

fn check_inputs(beta: f64, curvatures: &[f64]) -> Result<()> {
    if !beta.is_finite() {
        return Err(Error::InvalidOption {
            field: "beta",
            value: beta,
            allowed: "finite",
        });
    }
    if let Some(&k) = curvatures.iter().find(|k| !k.is_finite()) {
        return Err(Error::InvalidOption {
            field: "curvature",
            value: k,
            allowed: "finite",
        });
    }
    Ok(())
}

/// The principal curvatures (ascending) of G = 0 at a point where ∇_u G = `grad_u` and
/// ∂²G/∂u∂uᵀ = `hess_u` (n×n, row-major): the eigenvalues of the tangent block of R H Rᵀ/‖∇G‖
/// (module docs). Empty for n = 1.
///
/// # Errors
/// Mismatched lengths, a zero or non-finite gradient, a non-finite Hessian.
pub fn curvatures(grad_u: &[f64], hess_u: &[f64]) -> Result<Vec<f64>> {
    let n = grad_u.len();
    if hess_u.len() != n * n {
        return Err(Error::DimensionMismatch {
            what: "SORM Hessian",
            expected: n * n,
            got: hess_u.len(),
        });
    }
    let norm = grad_u.iter().map(|d| d * d).sum::<f64>().sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(Error::ZeroGradient { x: grad_u.to_vec() });
    }
    if let Some(&h) = hess_u.iter().find(|h| !h.is_finite()) {
        return Err(Error::NonFiniteLimitState {
            what: "Hessian",
            value: h,
            x: grad_u.to_vec(),
        });
    }
    if n == 1 {
        return Ok(Vec::new());
    }
    // Householder reflection Q = I − 2wwᵀ/‖w‖², w = α + s·eₙ, s = sign(αₙ): Qα = −s·eₙ, so
    // rows 0..n−1 of the symmetric orthogonal Q are orthonormal and orthogonal to α (no
    // cancellation in w: |wₙ| ≥ 1).
    let alpha: Vec<f64> = grad_u.iter().map(|d| -d / norm).collect();
    let s = if alpha[n - 1] >= 0.0 { 1.0 } else { -1.0 };
    let mut w = alpha.clone();
    w[n - 1] += s;
    let ww: f64 = w.iter().map(|v| v * v).sum();
    let q = |i: usize, j: usize| f64::from(u8::from(i == j)) - 2.0 * w[i] * w[j] / ww;
    let m = n - 1;
    let h = nalgebra::DMatrix::from_row_slice(n, n, hess_u);
    let r = nalgebra::DMatrix::from_fn(m, n, q);
    let mut a = &r * h * r.transpose() / norm;
    // The Hessian of differences is symmetric to round-off only.
    a = (&a + a.transpose()) * 0.5;
    let mut k: Vec<f64> = nalgebra::SymmetricEigen::new(a)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    k.sort_by(f64::total_cmp);
    Ok(k)
}

/// SORM at the design point of `form` (FORM of the same `limit_state` in the same `model`):
/// the principal curvatures there and P_f by Hohenbichler–Rackwitz; see the module docs.
///
/// # Errors
/// A failed or non-finite evaluation, a zero gradient at u*, a bad step, or
/// [`Error::SormCurvature`] when the formula does not hold.
pub fn sorm<L: LimitState + ?Sized>(
    model: &Model,
    limit_state: &mut L,
    form: &FormResult,
    options: &SormOptions,
) -> Result<SormResult> {
    let h = options.hessian_step;
    if !(h > 0.0 && h < 1.0) {
        return Err(Error::InvalidOption {
            field: "hessian_step",
            value: h,
            allowed: "0 < hessian_step < 1 (standard normal units)",
        });
    }
    let n = model.len();
    if form.u_star.len() != n {
        return Err(Error::DimensionMismatch {
            what: "FORM design point",
            expected: n,
            got: form.u_star.len(),
        });
    }
    let (grad_u, hess_u, hessian, evaluations) = hessian_at(model, limit_state, &form.u_star, h)?;
    let kappa = curvatures(&grad_u, &hess_u)?;
    let pf = hohenbichler_rackwitz(form.beta, &kappa)?;
    Ok(SormResult {
        beta_form: form.beta,
        pf_form: stdnormal::cdf(-form.beta),
        pf_breitung: breitung(form.beta, &kappa),
        beta: stdnormal::beta_of(pf),
        pf,
        curvatures: kappa,
        gradient_norm: grad_u.iter().map(|d| d * d).sum::<f64>().sqrt(),
        hessian,
        evaluations,
    })
}

/// ∇_u G and ∂²G/∂u∂uᵀ at `u`, where from, and the evaluations it took.
#[allow(clippy::type_complexity)]
fn hessian_at<L: LimitState + ?Sized>(
    model: &Model,
    ls: &mut L,
    u: &[f64],
    h: f64,
) -> Result<(Vec<f64>, Vec<f64>, HessianSource, usize)> {
    let n = model.len();
    let wrap = |x: &[f64]| {
        let x = x.to_vec();
        move |source| Error::LimitState { x, source }
    };
    let check = |what: &'static str, v: &[f64], x: &[f64]| -> Result<()> {
        match v.iter().find(|d| !d.is_finite()) {
            Some(&value) => Err(Error::NonFiniteLimitState {
                what,
                value,
                x: x.to_vec(),
            }),
            None => Ok(()),
        }
    };
    let x = model.x_from_u(u);
    let mut grad_x = vec![0.0; n];
    let mut hess_x = vec![0.0; n * n];
    if let Some(g) = ls
        .value_gradient_hessian(&x, &mut grad_x, &mut hess_x)
        .map_err(wrap(&x))?
    {
        check("value", &[g], &x)?;
        check("gradient", &grad_x, &x)?;
        check("Hessian", &hess_x, &x)?;
        let grad_u = model.gradient_to_standard(u, &grad_x);
        let hess_u = model.hessian_to_standard(u, &grad_x, &hess_x);
        return Ok((grad_u, hess_u, HessianSource::LimitState, 1));
    }
    let mut evaluations = 0;
    let shifted = |a: usize, da: f64, b: usize, db: f64| {
        let mut v = u.to_vec();
        v[a] += da;
        v[b] += db;
        v
    };
    // Central differences of ∇_u G when the limit state gives its gradient.
    let gradient = |ls: &mut L, v: &[f64]| -> Result<Option<Vec<f64>>> {
        let x = model.x_from_u(v);
        let mut gx = vec![0.0; n];
        match ls.value_and_gradient(&x, &mut gx).map_err(wrap(&x))? {
            Some(g) => {
                check("value", &[g], &x)?;
                check("gradient", &gx, &x)?;
                Ok(Some(model.gradient_to_standard(v, &gx)))
            }
            None => Ok(None),
        }
    };
    if let Some(grad_u) = gradient(ls, u)? {
        evaluations += 1;
        let mut hess = vec![0.0; n * n];
        let mut complete = true;
        for b in 0..n {
            let (Some(p), Some(m)) = (
                gradient(ls, &shifted(b, h, b, 0.0))?,
                gradient(ls, &shifted(b, -h, b, 0.0))?,
            ) else {
                // A limit state that gives its gradient at some points only: differences of g.
                complete = false;
                break;
            };
            evaluations += 2;
            for a in 0..n {
                hess[a * n + b] = (p[a] - m[a]) / (2.0 * h);
            }
        }
        if complete {
            symmetrise(&mut hess, n);
            return Ok((
                grad_u,
                hess,
                HessianSource::GradientDifferences,
                evaluations,
            ));
        }
    }
    // Second differences of G.
    let mut value = |v: Vec<f64>| -> Result<f64> {
        let x = model.x_from_u(&v);
        let g = ls.value(&x).map_err(wrap(&x))?;
        check("value", &[g], &x)?;
        evaluations += 1;
        Ok(g)
    };
    let g0 = value(u.to_vec())?;
    let mut plus = vec![0.0; n];
    let mut minus = vec![0.0; n];
    for a in 0..n {
        plus[a] = value(shifted(a, h, a, 0.0))?;
        minus[a] = value(shifted(a, -h, a, 0.0))?;
    }
    let mut hess = vec![0.0; n * n];
    for a in 0..n {
        hess[a * n + a] = (plus[a] - 2.0 * g0 + minus[a]) / (h * h);
        for b in 0..a {
            let pp = value(shifted(a, h, b, h))?;
            let pm = value(shifted(a, h, b, -h))?;
            let mp = value(shifted(a, -h, b, h))?;
            let mm = value(shifted(a, -h, b, -h))?;
            let d = (pp - pm - mp + mm) / (4.0 * h * h);
            hess[a * n + b] = d;
            hess[b * n + a] = d;
        }
    }
    let grad_u = (0..n).map(|a| (plus[a] - minus[a]) / (2.0 * h)).collect();
    Ok((grad_u, hess, HessianSource::ValueDifferences, evaluations))
}

fn symmetrise(h: &mut [f64], n: usize) {
    for a in 0..n {
        for b in 0..a {
            let m = 0.5 * (h[a * n + b] + h[b * n + a]);
            h[a * n + b] = m;
            h[b * n + a] = m;
        }
    }
}
