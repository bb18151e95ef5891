//! SORM against closed forms: a linear limit state (SORM = FORM), paraboloids against their
//! exact P_f by numerical integration, the curvatures of known quadrics, and the Hessian's chain
//! rule through lognormal, uniform and correlated (Nataf) marginals against finite differences.

use crate::common::simpson;
use kappe_reliability::sorm::{breitung, curvatures, hohenbichler_rackwitz, inverse_mills};
use kappe_reliability::{
    Correlation, Error, FormOptions, HessianSource, Model, RandomVariable, SormOptions,
    WithGradient, WithHessian, form, sorm, stdnormal,
};

fn standard(n: usize) -> Model {
    Model::independent(
        (0..n)
            .map(|i| RandomVariable::normal(format!("u{i}"), 0.0, 1.0).unwrap())
            .collect(),
    )
    .unwrap()
}

#[test]
fn sorm_equals_form_for_a_linear_limit_state() {
    // g = 10 + 3X₁ − 2X₂ with correlated normals: linear in u, every curvature 0.
    let model = Model::new(
        vec![
            RandomVariable::normal("X1", 5.0, 1.0).unwrap(),
            RandomVariable::normal("X2", 12.0, 2.0).unwrap(),
        ],
        &Correlation::Pairs(vec![("X1".into(), "X2".into(), 0.4)]),
    )
    .unwrap();
    let mut g = WithGradient(|x: &[f64], d: &mut [f64]| {
        d[0] = 3.0;
        d[1] = -2.0;
        10.0 + 3.0 * x[0] - 2.0 * x[1]
    });
    let f = form(&model, &mut g, &FormOptions::default()).unwrap();
    let s = sorm(&model, &mut g, &f, &SormOptions::default()).unwrap();
    assert_eq!(s.hessian, HessianSource::GradientDifferences);
    // A constant gradient differences to exactly 0, so every factor is exactly 1 and SORM's
    // P_f is FORM's to the bit.
    assert!(s.curvatures.iter().all(|k| *k == 0.0), "{:?}", s.curvatures);
    assert_eq!(s.pf, f.pf);
    assert_eq!(s.pf_breitung, Some(f.pf));
    // Without the gradient: second differences of g, whose round-off (4ε|G|/h² ≈ 10⁻⁸ here,
    // |G| ≲ 20) leaves curvatures of that order and P_f within 10⁻⁷ relative.
    let mut plain = |x: &[f64]| 10.0 + 3.0 * x[0] - 2.0 * x[1];
    let s = sorm(&model, &mut plain, &f, &SormOptions::default()).unwrap();
    assert_eq!(s.hessian, HessianSource::ValueDifferences);
    assert!(
        s.curvatures.iter().all(|k| k.abs() < 1e-7),
        "{:?}",
        s.curvatures
    );
    assert!((s.pf / f.pf - 1.0).abs() < 1e-7, "{} vs {}", s.pf, f.pf);
}

/// The leading relative error of Hohenbichler–Rackwitz against the exact P_f of the paraboloid
/// G = β − uₙ + ½Σκᵢuᵢ² (module docs of `sorm`): −(1/8)ψ(ψ − β)[2Σ(κᵢvᵢ)² + (Σκᵢvᵢ)²],
/// vᵢ = 1/(1 + ψκᵢ).
fn hr_leading_error(beta: f64, k: &[f64]) -> f64 {
    let psi = inverse_mills(beta);
    let kv: Vec<f64> = k.iter().map(|k| k / (1.0 + psi * k)).collect();
    let sq: f64 = kv.iter().map(|a| a * a).sum();
    let sum: f64 = kv.iter().sum();
    -psi * (psi - beta) * (2.0 * sq + sum * sum) / 8.0
}

#[test]
fn paraboloids_against_their_exact_pf() {
    // 2-D: P_f = ∫ φ(t) Φ(−β − ½κt²) dt, by Simpson on [−12, 12] with 24 000 intervals
    // (quadrature error far below 10⁻¹⁰ relative for this smooth, Gaussian-damped integrand).
    for beta in [1.0, 2.0, 3.0, 5.0] {
        for kappa in [-0.15, 0.1, 0.3, 1.0] {
            let model = standard(2);
            let mut g = |x: &[f64]| beta - x[1] + 0.5 * kappa * x[0] * x[0];
            let f = form(&model, &mut g, &FormOptions::default()).unwrap();
            let s = sorm(&model, &mut g, &f, &SormOptions::default()).unwrap();
            // The curvature of the paraboloid is κ; second differences with h = 10⁻³ of a
            // quadratic are exact up to round-off (4ε|G|/h² ≈ 5·10⁻⁹).
            assert!((s.curvatures[0] - kappa).abs() < 1e-6, "{:?}", s.curvatures);
            assert!((f.beta - beta).abs() < 1e-8);
            let exact = simpson(
                |t| stdnormal::pdf(t) * stdnormal::cdf(-beta - 0.5 * kappa * t * t),
                -12.0,
                12.0,
                24_000,
            );
            let err = s.pf / exact - 1.0;
            let lead = -hr_leading_error(beta, &[kappa]);
            // The formula's error is its leading term (the O(s²) term of ln Φ) up to the
            // higher orders: measured 0.66–1.0 of it over these cases (0.66 at βκ = −0.75,
            // near the formula's bound); asserted between 0.5 and 1.5 of it.
            assert!(
                err / lead > 0.5 && err / lead < 1.5,
                "β {beta}, κ {kappa}: SORM {} vs exact {exact}: error {err:.3e}, leading term \
                 {lead:.3e}",
                s.pf
            );
            // Surfaces bending away from the origin: Hohenbichler–Rackwitz is closer than
            // Breitung (its first-order term (ψ − β)κ/2(1 + βκ) is what it removes).
            if kappa > 0.0 {
                let b = s.pf_breitung.unwrap() / exact - 1.0;
                assert!(
                    err.abs() < b.abs(),
                    "β {beta}, κ {kappa}: {err} vs Breitung {b}"
                );
            }
        }
    }
    // 3-D, curvatures of both signs: P_f = ∫∫ φ(t₁)φ(t₂) Φ(−β − ½(κ₁t₁² + κ₂t₂²)), Simpson
    // 1 200 × 1 200 on [−10, 10]² (error far below 10⁻⁸ relative).
    let (beta, k) = (2.0, [0.3, -0.1]);
    let model = standard(3);
    let mut g = |x: &[f64]| beta - x[2] + 0.5 * (k[0] * x[0] * x[0] + k[1] * x[1] * x[1]);
    let f = form(&model, &mut g, &FormOptions::default()).unwrap();
    let s = sorm(&model, &mut g, &f, &SormOptions::default()).unwrap();
    assert!((s.curvatures[0] - k[1]).abs() < 1e-6 && (s.curvatures[1] - k[0]).abs() < 1e-6);
    let exact = simpson(
        |t1| {
            stdnormal::pdf(t1)
                * simpson(
                    |t2| {
                        stdnormal::pdf(t2)
                            * stdnormal::cdf(-beta - 0.5 * (k[0] * t1 * t1 + k[1] * t2 * t2))
                    },
                    -10.0,
                    10.0,
                    1_200,
                )
        },
        -10.0,
        10.0,
        1_200,
    );
    let err = s.pf / exact - 1.0;
    let lead = -hr_leading_error(beta, &k);
    assert!(
        err / lead > 0.5 && err / lead < 1.5,
        "SORM {} vs exact {exact}: error {err:.3e}, leading term {lead:.3e}",
        s.pf
    );
}

#[test]
fn curvatures_of_a_sphere_and_a_cylinder() {
    // The ball ‖u − c‖ ≤ r fails, c off every axis: the design point is on the line to c at
    // β = ‖c‖ − r, and every principal curvature is 1/r (the surface bends away from the
    // origin). A cylinder of radius r about the axis d ⊥ c: curvatures {0, 1/r}.
    let c = [1.5, -2.0, 2.5];
    let r = 1.2;
    let cn = c.iter().map(|v| v * v).sum::<f64>().sqrt();
    let u: Vec<f64> = c.iter().map(|v| v * (cn - r) / cn).collect();
    // G = ‖u − c‖² − r²: ∇G = 2(u − c), H = 2I.
    let grad: Vec<f64> = u.iter().zip(&c).map(|(a, b)| 2.0 * (a - b)).collect();
    let hess = [2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0];
    let k = curvatures(&grad, &hess).unwrap();
    // Exact up to round-off: 1e-12.
    assert!(
        k.iter().all(|k| (k - 1.0 / r).abs() < 1e-12),
        "sphere: {k:?}"
    );
    // Cylinder: G = (u − c)ᵀP(u − c) − r², P = I − ddᵀ, with the axis d = (4, 3, 0)/5 ⊥ c.
    let d = [0.8, 0.6, 0.0];
    assert!((d[0] * c[0] + d[1] * c[1] + d[2] * c[2]).abs() < 1e-15);
    let p = |i: usize, j: usize| f64::from(u8::from(i == j)) - d[i] * d[j];
    let hess: Vec<f64> = (0..9).map(|ij| 2.0 * p(ij / 3, ij % 3)).collect();
    let grad: Vec<f64> = (0..3)
        .map(|i| (0..3).map(|j| 2.0 * p(i, j) * (u[j] - c[j])).sum())
        .collect();
    let k = curvatures(&grad, &hess).unwrap();
    assert!(
        k[0].abs() < 1e-12 && (k[1] - 1.0 / r).abs() < 1e-12,
        "cylinder: {k:?}"
    );
    // The same sphere through FORM and SORM with second differences of g (a closure): the
    // design point and the curvatures (truncation 0 for a quadratic, round-off ≈ 10⁻⁸).
    let model = standard(3);
    let mut g = |x: &[f64]| {
        x.iter()
            .zip(&c)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            - r * r
    };
    let f = form(&model, &mut g, &FormOptions::default()).unwrap();
    assert!((f.beta - (cn - r)).abs() < 1e-6, "{}", f.beta);
    let s = sorm(&model, &mut g, &f, &SormOptions::default()).unwrap();
    assert!(
        s.curvatures.iter().all(|k| (k - 1.0 / r).abs() < 1e-5),
        "{:?}",
        s.curvatures
    );
}

/// g(x) = x₁²x₂ − 3x₃x₁ + x₂x₃² and its gradient and Hessian.
fn cubic(x: &[f64], d: &mut [f64], h: &mut [f64]) -> f64 {
    let (a, b, c) = (x[0], x[1], x[2]);
    d[0] = 2.0 * a * b - 3.0 * c;
    d[1] = a * a + c * c;
    d[2] = -3.0 * a + 2.0 * b * c;
    h.copy_from_slice(&[
        2.0 * b,
        2.0 * a,
        -3.0,
        2.0 * a,
        0.0,
        2.0 * c,
        -3.0,
        2.0 * c,
        2.0 * b,
    ]);
    a * a * b - 3.0 * c * a + b * c * c
}

#[test]
fn hessian_through_the_transform_matches_finite_differences() {
    // Lognormal, normal and uniform marginals, correlated through Nataf: the chain rule
    // Lᵀ(D H D + diag(x″∘∇g))L against second central differences of G(u) = g(x(u)), written
    // here independently of the library's (h = 10⁻³: truncation h²/12·|G⁗| and round-off
    // 4ε|G|/h² are both ≲ 10⁻⁶ of the entries' scale; asserted 10⁻⁵ of the largest entry).
    let model = Model::new(
        vec![
            RandomVariable::lognormal("A", 3.0, 0.9).unwrap(),
            RandomVariable::normal("B", 2.0, 0.5).unwrap(),
            RandomVariable::uniform("C", 1.0, 4.0).unwrap(),
        ],
        &Correlation::Pairs(vec![
            ("A".into(), "B".into(), 0.5),
            ("B".into(), "C".into(), -0.3),
        ]),
    )
    .unwrap();
    let n = 3;
    let g_u = |u: &[f64]| {
        let x = model.x_from_u(u);
        cubic(&x, &mut [0.0; 3], &mut [0.0; 9])
    };
    for u in [[0.3, -0.7, 1.1], [1.5, 0.8, -0.4], [-1.0, 2.0, 0.5]] {
        let x = model.x_from_u(&u);
        let (mut d, mut h) = ([0.0; 3], [0.0; 9]);
        cubic(&x, &mut d, &mut h);
        let analytic = model.hessian_to_standard(&u, &d, &h);
        let step = 1e-3;
        let at = |a: usize, da: f64, b: usize, db: f64| {
            let mut v = u;
            v[a] += da;
            v[b] += db;
            g_u(&v)
        };
        let scale = analytic.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for a in 0..n {
            for b in 0..n {
                let fd = (at(a, step, b, step) - at(a, step, b, -step) - at(a, -step, b, step)
                    + at(a, -step, b, -step))
                    / (4.0 * step * step);
                assert!(
                    (fd - analytic[a * n + b]).abs() < 1e-5 * scale,
                    "u {u:?}, H[{a}][{b}]: chain rule {} vs differences {fd}",
                    analytic[a * n + b]
                );
            }
        }
    }
    // SORM with the limit state's Hessian against SORM with second differences of g: the same
    // curvatures (the differences' error ≈ 10⁻⁶ of the entries, asserted 10⁻⁴ absolute on κ
    // of order 0.1–1) and P_f.
    let mut plain = |x: &[f64]| cubic(x, &mut [0.0; 3], &mut [0.0; 9]) - 2.0;
    let mut shifted = WithHessian(|x: &[f64], d: &mut [f64], h: &mut [f64]| cubic(x, d, h) - 2.0);
    let f = form(&model, &mut plain, &FormOptions::default()).unwrap();
    let a = sorm(&model, &mut shifted, &f, &SormOptions::default()).unwrap();
    let b = sorm(&model, &mut plain, &f, &SormOptions::default()).unwrap();
    assert_eq!(a.hessian, HessianSource::LimitState);
    assert_eq!(b.hessian, HessianSource::ValueDifferences);
    for (x, y) in a.curvatures.iter().zip(&b.curvatures) {
        assert!(
            (x - y).abs() < 1e-4,
            "{:?} vs {:?}",
            a.curvatures,
            b.curvatures
        );
    }
    assert!((a.pf / b.pf - 1.0).abs() < 1e-4, "{} vs {}", a.pf, b.pf);
}

#[test]
fn invalid_curvatures_are_named_errors() {
    // 1 + ψ(2)κ ≤ 0 for κ = −0.5 (ψ(2) = 2.37): refused, naming the curvature and the bound;
    // Breitung (1 + 2κ = 0) gives None.
    let err = hohenbichler_rackwitz(2.0, &[0.1, -0.5]).unwrap_err();
    match &err {
        Error::SormCurvature {
            index,
            curvature,
            bound,
            ..
        } => {
            assert_eq!(*index, 1);
            assert_eq!(*curvature, -0.5);
            assert!((bound + 1.0 / inverse_mills(2.0)).abs() < 1e-15);
        }
        e => panic!("{e}"),
    }
    assert!(err.to_string().contains("κ1 = -0.5"), "{err}");
    assert_eq!(breitung(2.0, &[-0.5]), None);
    assert!(matches!(
        hohenbichler_rackwitz(f64::NAN, &[0.1]),
        Err(Error::InvalidOption { field: "beta", .. })
    ));
    // β ≤ 0: the safe domain's formula, P_f = 1 − Φ(β)∏(1 − ψ(−β)κ)^(−1/2); with κ = 0 it is
    // Φ(−β) exactly, and it is continuous through β = 0 to first order in κ.
    assert_eq!(
        hohenbichler_rackwitz(-1.0, &[0.0]).unwrap(),
        stdnormal::cdf(1.0)
    );
    let (below, above) = (
        hohenbichler_rackwitz(-1e-9, &[0.01]).unwrap(),
        hohenbichler_rackwitz(1e-9, &[0.01]).unwrap(),
    );
    // The two branches differ at β = 0 by their second-order terms, (3/8)(ψ(0)κ)² = 2.4·10⁻⁵
    // (ψ(0) = 2φ(0) = 0.798); asserted below 3·10⁻⁵.
    assert!((below - above).abs() < 3e-5, "{below} vs {above}");
}
