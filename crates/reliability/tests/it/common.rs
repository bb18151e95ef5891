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
