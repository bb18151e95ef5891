use kappe_reliability::stdnormal;

/// Composite Simpson rule of f on [a, b] with `n` (even) intervals.
pub fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for k in 1..n {
        let w = if k % 2 == 1 { 4.0 } else { 2.0 };
        s += w * f(a + k as f64 * h);
    }
    s * h / 3.0
}

/// E[f(Z)], Z ~ N(0, 1), by Simpson on [−12, 12] (the tails beyond carry < 1e−32).
pub fn expect_normal(f: impl Fn(f64) -> f64) -> f64 {
    simpson(|z| stdnormal::pdf(z) * f(z), -12.0, 12.0, 24_000)
}

/// λ, ζ of a lognormal with mean μ and coefficient of variation δ.
pub fn ln_params(mean: f64, cov: f64) -> (f64, f64) {
    let zeta2 = (1.0 + cov * cov).ln();
    (mean.ln() - 0.5 * zeta2, zeta2.sqrt())
}

/// Breitung's (1984) second-order factor 1/√(1 + βκ) of a 2-variable FORM result: κ = t̂ᵀHt̂/‖∇G‖
/// is the curvature of G(u) = 0 at u* (t̂ ⊥ α; κ > 0 when the surface bends away from the origin),
/// from central differences of G in u with step 10⁻³ (error ~10⁻⁶ in κ).
pub fn breitung_factor(
    model: &kappe_reliability::Model,
    g: impl Fn(&[f64]) -> f64,
    f: &kappe_reliability::FormResult,
) -> f64 {
    let h = 1e-3;
    let at = |dir: [f64; 2], s: f64| {
        let u = [f.u_star[0] + s * dir[0], f.u_star[1] + s * dir[1]];
        g(&model.x_from_u(&u))
    };
    let t = [f.alpha[1], -f.alpha[0]];
    let a = [f.alpha[0], f.alpha[1]];
    let second = (at(t, h) - 2.0 * at(t, 0.0) + at(t, -h)) / (h * h);
    let slope = -(at(a, h) - at(a, -h)) / (2.0 * h);
    1.0 / (1.0 + f.beta * second / slope).sqrt()
}
