//! The Nataf ρ₀ (exact integral, solved numerically) against the pairs with closed forms
//! (Liu & Der Kiureghian 1986, Table 1 and its exact entries).

use crate::common::ln_params;
use kappe_reliability::{Correlation, Model, RandomVariable};

fn rho0(a: RandomVariable, b: RandomVariable, rho: f64) -> f64 {
    let (na, nb) = (a.name.clone(), b.name.clone());
    Model::new(vec![a, b], &Correlation::Pairs(vec![(na, nb, rho)]))
        .unwrap()
        .standard_correlation(1, 0)
}

// The tolerance 1e−10 for every pair: the 64-point Gauss–Hermite rule integrates these smooth
// (entire) integrands to ~1e−13 and the bisection stops at 1e−15; the margin covers the
// steeper lognormal integrand at δ = 0.5.

#[test]
fn lognormal_lognormal() {
    for (d1, d2, rho) in [(0.2, 0.3, 0.5), (0.5, 0.1, -0.4), (0.1, 0.1, 0.9)] {
        let (_, z1) = ln_params(1.0, d1);
        let (_, z2) = ln_params(1.0, d2);
        let exact = (1.0 + rho * d1 * d2).ln() / (z1 * z2);
        let got = rho0(
            RandomVariable::lognormal_cov("a", 3.0, d1).unwrap(),
            RandomVariable::lognormal_cov("b", 7.0, d2).unwrap(),
            rho,
        );
        assert!(
            (got - exact).abs() < 1e-10,
            "{d1} {d2} {rho}: {got} vs {exact}"
        );
    }
}

#[test]
fn normal_lognormal() {
    // ρ₀ = ρ δ/ζ, δ and ζ of the lognormal.
    for (d, rho) in [(0.2, 0.5), (0.5, -0.6)] {
        let (_, z) = ln_params(1.0, d);
        let got = rho0(
            RandomVariable::normal("a", 0.0, 2.0).unwrap(),
            RandomVariable::lognormal_cov("b", 4.0, d).unwrap(),
            rho,
        );
        assert!((got - rho * d / z).abs() < 1e-10, "{d} {rho}: {got}");
    }
}

#[test]
fn uniform_with_normal_and_uniform() {
    // Normal–uniform: ρ = ρ₀ √12 E[Z Φ(Z)] = ρ₀ √(3/π), so ρ₀ = ρ √(π/3).
    let got = rho0(
        RandomVariable::normal("a", 1.0, 1.0).unwrap(),
        RandomVariable::uniform("b", 2.0, 5.0).unwrap(),
        0.6,
    );
    assert!(
        (got - 0.6 * (std::f64::consts::PI / 3.0).sqrt()).abs() < 1e-10,
        "{got}"
    );
    // Uniform–uniform: ρ = (6/π) asin(ρ₀/2) (Pearson 1907), so ρ₀ = 2 sin(πρ/6).
    for rho in [-0.7, 0.3, 0.95] {
        let got = rho0(
            RandomVariable::uniform("a", 0.0, 1.0).unwrap(),
            RandomVariable::uniform("b", -3.0, 10.0).unwrap(),
            rho,
        );
        let exact = 2.0 * (std::f64::consts::PI * rho / 6.0).sin();
        assert!((got - exact).abs() < 1e-10, "{rho}: {got} vs {exact}");
    }
}

#[test]
fn sampled_physical_correlation_matches_the_target() {
    // End to end: x = T⁻¹(u) for 10⁵ seeded u ~ N(0, I); the Pearson correlation of the samples
    // must be the asked ρ = 0.6 (lognormal δ = 0.4 with uniform). The standard error of a sample
    // correlation is ≈ (1 − ρ²)/√N = 0.002; 4 standard errors = 0.008.
    use rand_chacha::ChaCha8Rng;
    use rand_chacha::rand_core::{Rng, SeedableRng};
    let model = Model::new(
        vec![
            RandomVariable::lognormal_cov("a", 5.0, 0.4).unwrap(),
            RandomVariable::uniform("b", 1.0, 2.0).unwrap(),
        ],
        &Correlation::Pairs(vec![("a".into(), "b".into(), 0.6)]),
    )
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut normal = || {
        let v = ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
        kappe_reliability::stdnormal::inv_cdf(v)
    };
    let n = 100_000;
    let xs: Vec<Vec<f64>> = (0..n)
        .map(|_| model.x_from_u(&[normal(), normal()]))
        .collect();
    let mean = |k: usize| xs.iter().map(|x| x[k]).sum::<f64>() / n as f64;
    let (m0, m1) = (mean(0), mean(1));
    let cov = |a: usize, b: usize, ma: f64, mb: f64| {
        xs.iter().map(|x| (x[a] - ma) * (x[b] - mb)).sum::<f64>() / n as f64
    };
    let rho = cov(0, 1, m0, m1) / (cov(0, 0, m0, m0) * cov(1, 1, m1, m1)).sqrt();
    assert!((rho - 0.6).abs() < 0.008, "sample ρ = {rho}");
    // The Nataf ρ₀ differs from ρ here (it is not a no-op).
    assert!((model.standard_correlation(1, 0) - 0.6).abs() > 0.01);
}
