//! Series systems against closed forms.

use kappe_reliability::{
    Component, FormOptions, Model, RandomVariable, SystemOptions, form, series_system, stdnormal,
};

#[test]
fn two_independent_components() {
    // α₁ ⊥ α₂: P_f,sys = 1 − (1 − p₁)(1 − p₂).
    let comps = [
        Component {
            beta: 2.0,
            alpha: vec![1.0, 0.0],
        },
        Component {
            beta: 2.5,
            alpha: vec![0.0, 1.0],
        },
    ];
    let (p1, p2) = (stdnormal::cdf(-2.0), stdnormal::cdf(-2.5));
    let exact = 1.0 - (1.0 - p1) * (1.0 - p2);
    let r = series_system(&comps, &SystemOptions::default()).unwrap();
    // The exact value lies in the 95 % interval of the seeded estimate, and the estimator's
    // scores lie in [P̄/2, P̄] so its CoV is tiny (< 1e−3 with 2·10⁴ samples here).
    assert!(
        r.interval[0] <= exact && exact <= r.interval[1],
        "{:?} vs {exact}",
        r.interval
    );
    assert!(r.cov < 1e-3, "{}", r.cov);
    assert!((r.beta + stdnormal::inv_cdf(r.pf)).abs() < 1e-12);
    // Ditlevsen bounds of two components are both exact (p₁ + p₂ − p₁₂, with p₁₂ = p₁p₂ at
    // ρ = 0; Φ₂ quadrature round-off only).
    let [lo, hi] = r.ditlevsen_bounds.unwrap();
    assert!(
        (lo - exact).abs() < 1e-15 && (hi - exact).abs() < 1e-15,
        "{lo} {hi} {exact}"
    );
    assert_eq!(r.governing, 0);
}

#[test]
fn identical_components_are_one() {
    // Two identical components fail together: P_f,sys = p₁ (every score is 2p₁/2 = p₁); 1e−11
    // relative is the round-off of summing 2·10⁴ scores (~N·ε_mach).
    let c = Component {
        beta: 3.0,
        alpha: vec![0.6, 0.8],
    };
    let r = series_system(&[c.clone(), c], &SystemOptions::default()).unwrap();
    assert!(
        (r.pf / stdnormal::cdf(-3.0) - 1.0).abs() < 1e-11,
        "{:e}",
        r.pf / stdnormal::cdf(-3.0) - 1.0
    );
}

#[test]
fn correlated_components_from_form() {
    // g₁ = R₁ − S, g₂ = R₂ − S share S: ρ₁₂ = α₁ᵀα₂, and for two linear components
    // P_f,sys = p₁ + p₂ − Φ₂(−β₁, −β₂; ρ₁₂) exactly (Φ₂ checked against closed forms in stdnormal).
    let model = Model::independent(vec![
        RandomVariable::normal("R1", 200.0, 20.0).unwrap(),
        RandomVariable::normal("R2", 210.0, 15.0).unwrap(),
        RandomVariable::normal("S", 150.0, 15.0).unwrap(),
    ])
    .unwrap();
    let o = FormOptions::default();
    let f1 = form(&model, &mut |x: &[f64]| x[0] - x[2], &o).unwrap();
    let f2 = form(&model, &mut |x: &[f64]| x[1] - x[2], &o).unwrap();
    let rho: f64 = f1.alpha.iter().zip(&f2.alpha).map(|(a, b)| a * b).sum();
    // ρ₁₂ = σS²/(s₁s₂), s₁ = √(20² + 15²), s₂ = √(15² + 15²).
    assert!((rho - 225.0 / (25.0 * 450f64.sqrt())).abs() < 1e-9);
    let exact = f1.pf + f2.pf - stdnormal::bivariate_cdf(-f1.beta, -f2.beta, rho);
    let r = series_system(&[(&f1).into(), (&f2).into()], &SystemOptions::default()).unwrap();
    assert!(
        r.interval[0] <= exact && exact <= r.interval[1],
        "{:?} vs {exact}",
        r.interval
    );
    // Uni-modal bounds hold: max pᵢ ≤ P_f,sys ≤ Σpᵢ.
    assert!(r.unimodal_bounds[0] <= exact && exact <= r.unimodal_bounds[1]);
    let [lo, hi] = r.ditlevsen_bounds.unwrap();
    assert!((lo - exact).abs() < 1e-14 && (hi - exact).abs() < 1e-14);
}

#[test]
fn more_components_than_variables() {
    // 50 half-planes {e(tₖ)ᵀu ≥ 3} in 2-D, tₖ = (π/2)k/49 (R is singular: rank 2). Reference in
    // polar coordinates: a ray at angle θ fails from r(θ) = 3/maxₖ cos(θ − tₖ) on (when that max
    // is > 0), and P(‖u‖ ≥ r) = exp(−r²/2) in 2-D, so P_f,sys = (1/2π)∫ exp(−r(θ)²/2) dθ.
    let t: Vec<f64> = (0..50)
        .map(|k| std::f64::consts::FRAC_PI_2 * k as f64 / 49.0)
        .collect();
    let comps: Vec<Component> = t
        .iter()
        .map(|t| Component {
            beta: 3.0,
            alpha: vec![t.cos(), t.sin()],
        })
        .collect();
    let ray = |theta: f64| {
        let c = t
            .iter()
            .map(|tk| (theta - tk).cos())
            .fold(f64::MIN, f64::max);
        if c > 0.0 { (-4.5 / (c * c)).exp() } else { 0.0 }
    };
    // Midpoint rule with 10⁶ points: the integrand is continuous with kinks, error ~1e−12·P.
    let n = 1_000_000;
    let h = 2.0 * std::f64::consts::PI / n as f64;
    let reference =
        (0..n).map(|k| ray((k as f64 + 0.5) * h)).sum::<f64>() * h / (2.0 * std::f64::consts::PI);
    let r = series_system(&comps, &SystemOptions::default()).unwrap();
    assert!(
        r.interval[0] <= reference && reference <= r.interval[1],
        "{:?} vs {reference}",
        r.interval
    );
    // For half-planes taken in angle order the events form a chain (each overlaps only its
    // neighbours' new parts), so Ditlevsen's upper bound Σpᵢ − Σpᵢ,ᵢ₋₁ is exact: 1e−12
    // relative covers the Φ₂ quadrature and the reference's midpoint rule.
    let [lo, hi] = r.ditlevsen_bounds.unwrap();
    assert!(
        lo <= reference && (hi / reference - 1.0).abs() < 1e-12,
        "{lo} {reference} {hi}"
    );
}
