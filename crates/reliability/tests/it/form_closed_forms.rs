//! FORM against closed forms: linear limit states in normal variables (FORM is exact), the
//! lognormal R, S case, and sensitivities.

use crate::common::{expect_normal, ln_params};
use kappe_reliability::{
    Correlation, FormOptions, Model, RandomVariable, WithGradient, form, stdnormal,
};

fn r_s() -> Model {
    Model::independent(vec![
        RandomVariable::normal("R", 200.0, 20.0).unwrap(),
        RandomVariable::normal("S", 150.0, 10.0).unwrap(),
    ])
    .unwrap()
}

#[test]
fn linear_normal_r_minus_s() {
    let model = r_s();
    let s = (20.0f64 * 20.0 + 10.0 * 10.0).sqrt();
    let beta = 50.0 / s;
    for analytic in [false, true] {
        let r = if analytic {
            form(
                &model,
                &mut WithGradient(|x: &[f64], g: &mut [f64]| {
                    g[0] = 1.0;
                    g[1] = -1.0;
                    x[0] - x[1]
                }),
                &FormOptions::default(),
            )
            .unwrap()
        } else {
            form(
                &model,
                &mut |x: &[f64]| x[0] - x[1],
                &FormOptions::default(),
            )
            .unwrap()
        };
        // Linear in normal variables: FORM is exact; 1e−9 leaves room for the finite-difference
        // gradient (relative error ~1e−11, see the form module docs) and round-off.
        assert!(
            (r.beta - beta).abs() < 1e-9,
            "analytic {analytic}: {}",
            r.beta
        );
        assert!((r.pf / stdnormal::cdf(-beta) - 1.0).abs() < 1e-8);
        // Design point x* = μ − β σ α-scaled: R* = S* = 200 − 2·20 = 160; u* = (−2, 1).
        for (got, want) in r.x_star.iter().zip([160.0, 160.0]) {
            assert!((got - want).abs() < 1e-7, "x* {got}");
        }
        for (got, want) in r.u_star.iter().zip([-2.0, 1.0]) {
            assert!((got - want).abs() < 1e-9, "u* {got}");
        }
        // α = (−σR, σS)/s; importance factors α² = (0.8, 0.2).
        assert!((r.alpha[0] + 20.0 / s).abs() < 1e-9 && (r.alpha[1] - 10.0 / s).abs() < 1e-9);
        assert!((r.importance[0] - 0.8).abs() < 1e-9);
        // dβ/dμR = 1/s, dβ/dμS = −1/s, dβ/dσR = −(μR − μS)σR/s³, dβ/dσS = −(μR − μS)σS/s³;
        // 1e−7 relative covers the 1e−6σ central difference of z (exact for a normal up to round-off).
        let rel = |a: f64, b: f64| ((a - b) / b).abs() < 1e-7;
        assert!(rel(r.dbeta_dmean[0], 1.0 / s) && rel(r.dbeta_dmean[1], -1.0 / s));
        assert!(rel(r.dbeta_dstd[0], -50.0 * 20.0 / s.powi(3)));
        assert!(rel(r.dbeta_dstd[1], -50.0 * 10.0 / s.powi(3)));
        if analytic {
            assert!(r.gradient_evaluations >= 1);
        } else {
            // Mean point: 1 + 4 (central differences), 1 line-search step, then 4 at u*.
            assert_eq!(r.evaluations, 10);
            assert_eq!(r.iterations, 2);
        }
    }
}

#[test]
fn correlated_linear_normal() {
    // g = 10 + 3X₁ − 2X₂ + X₃ with correlated normals: β = (a₀ + aᵀμ)/√(aᵀΣa).
    let mu = [5.0, 12.0, 3.0];
    let sd = [1.0, 2.0, 1.5];
    let rho = [[1.0, 0.5, -0.3], [0.5, 1.0, 0.2], [-0.3, 0.2, 1.0]];
    let a = [3.0, -2.0, 1.0];
    let model = Model::new(
        (0..3)
            .map(|i| RandomVariable::normal(format!("x{i}"), mu[i], sd[i]).unwrap())
            .collect(),
        &Correlation::Matrix(rho.iter().map(|r| r.to_vec()).collect()),
    )
    .unwrap();
    let mean_g = 10.0 + (0..3).map(|i| a[i] * mu[i]).sum::<f64>();
    let var_g: f64 = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .map(|(i, j)| a[i] * a[j] * sd[i] * sd[j] * rho[i][j])
        .sum();
    let beta = mean_g / var_g.sqrt();
    let r = form(
        &model,
        &mut |x: &[f64]| 10.0 + 3.0 * x[0] - 2.0 * x[1] + x[2],
        &FormOptions::default(),
    )
    .unwrap();
    // FORM exact for a linear g in jointly normal x; tolerance as in the independent case.
    assert!((r.beta - beta).abs() < 1e-9, "{} vs {beta}", r.beta);
    // The importance factors γᵢ² sum to 1 (γ is normalised; round-off only).
    assert!((r.importance.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    // dβ/dμᵢ = aᵢ/√(aᵀΣa) (μ enters g linearly); 1e−7 relative as above.
    for (i, (got, ai)) in r.dbeta_dmean.iter().zip(a).enumerate() {
        let want = ai / var_g.sqrt();
        assert!(((got - want) / want).abs() < 1e-7, "i {i}");
    }
}

#[test]
fn lognormal_ln_r_minus_ln_s_with_and_without_correlation() {
    let (mr, dr, ms, ds) = (200.0, 0.15, 100.0, 0.25);
    let (lr, zr) = ln_params(mr, dr);
    let (ls, zs) = ln_params(ms, ds);
    for rho in [0.0, 0.4] {
        let model = Model::new(
            vec![
                RandomVariable::lognormal_cov("R", mr, dr).unwrap(),
                RandomVariable::lognormal_cov("S", ms, ds).unwrap(),
            ],
            &Correlation::Pairs(vec![("R".into(), "S".into(), rho)]),
        )
        .unwrap();
        // Nataf for two lognormals in closed form: ρ₀ = ln(1 + ρδRδS)/(ζRζS).
        let rho0 = (1.0 + rho * dr * ds).ln() / (zr * zs);
        let beta = (lr - ls) / (zr * zr + zs * zs - 2.0 * rho0 * zr * zs).sqrt();
        let r = form(
            &model,
            &mut |x: &[f64]| x[0].ln() - x[1].ln(),
            &FormOptions::default(),
        )
        .unwrap();
        // Linear in u (ln x is linear in z): FORM exact. 1e−9 as above, plus the numerically
        // solved Nataf ρ₀ (bisection to 1e−15 on a 64-point Gauss–Hermite rule, exact to
        // ~1e−13 for these smooth integrands; see the nataf tests).
        assert!(
            (r.beta - beta).abs() < 1e-9,
            "rho {rho}: {} vs {beta}",
            r.beta
        );
    }
}

#[test]
fn lognormal_r_minus_s_against_numerical_integration() {
    // g = R − S with lognormal R, S. P_f = P(R ≤ S) = ∫ φ(z) F_R(S(z)) dz, integrated by Simpson.
    // The failure set R ≤ S is ln R ≤ ln S, so it is a half-space in u and FORM is exact here too:
    // this checks the FORM pipeline on a g that is nonlinear in u-space's coordinates of x.
    let (mr, dr, ms, ds) = (200.0, 0.15, 100.0, 0.25);
    let (lr, zr) = ln_params(mr, dr);
    let (ls, zs) = ln_params(ms, ds);
    let reference = expect_normal(|z| stdnormal::cdf((ls + zs * z - lr) / zr));
    let model = Model::independent(vec![
        RandomVariable::lognormal_cov("R", mr, dr).unwrap(),
        RandomVariable::lognormal_cov("S", ms, ds).unwrap(),
    ])
    .unwrap();
    // Tight tolerances: the β error of a converged iterate is of the order of its distance from
    // the surface, ε_G·|G₀|/‖∇G‖.
    let options = FormOptions {
        g_tolerance: 1e-12,
        u_tolerance: 1e-10,
        ..FormOptions::default()
    };
    let r = form(&model, &mut |x: &[f64]| x[0] - x[1], &options).unwrap();
    // β agrees with −Φ⁻¹(reference) to 1e−8: Simpson (h = 1e−3) is accurate to ~1e−13 in P_f
    // (relative ~1e−10 at P_f ≈ 1e−3, i.e. ~3e−11 in β); FORM stops at ~1e−10 in u.
    let beta_ref = -stdnormal::inv_cdf(reference);
    assert!((r.beta - beta_ref).abs() < 1e-8, "{} vs {beta_ref}", r.beta);
}

#[test]
fn lognormal_sensitivities_against_the_differentiated_closed_form() {
    // β(μR, σR, μS, σS) = (λR − λS)/√(ζR² + ζS²) for g = ln R − ln S; its derivatives by central
    // differences of the closed form itself (step 1e−5 of each parameter, truncation ~1e−10).
    let beta = |p: [f64; 4]| {
        let (zr2, zs2) = ((p[1] / p[0]).powi(2).ln_1p(), (p[3] / p[2]).powi(2).ln_1p());
        let (lr, ls) = (p[0].ln() - 0.5 * zr2, p[2].ln() - 0.5 * zs2);
        (lr - ls) / (zr2 + zs2).sqrt()
    };
    let p0 = [200.0, 30.0, 100.0, 25.0];
    let model = Model::independent(vec![
        RandomVariable::lognormal("R", p0[0], p0[1]).unwrap(),
        RandomVariable::lognormal("S", p0[2], p0[3]).unwrap(),
    ])
    .unwrap();
    let r = form(
        &model,
        &mut |x: &[f64]| x[0].ln() - x[1].ln(),
        &FormOptions::default(),
    )
    .unwrap();
    let got = [
        r.dbeta_dmean[0],
        r.dbeta_dstd[0],
        r.dbeta_dmean[1],
        r.dbeta_dstd[1],
    ];
    for k in 0..4 {
        let h = 1e-5 * p0[k];
        let (mut up, mut dn) = (p0, p0);
        up[k] += h;
        dn[k] -= h;
        let want = (beta(up) - beta(dn)) / (2.0 * h);
        // 1e−6 relative: both sides are central differences with errors ≤ 1e−9 relative, and
        // FORM's design point is exact here (g linear in u).
        assert!(
            ((got[k] - want) / want).abs() < 1e-6,
            "k {k}: {} vs {want}",
            got[k]
        );
    }
}

#[test]
fn failing_means_give_a_negative_beta() {
    // g = S − R fails at the means: β = −50/√500, P_f = Φ(50/√500) > ½.
    let r = form(
        &r_s(),
        &mut |x: &[f64]| x[1] - x[0],
        &FormOptions::default(),
    )
    .unwrap();
    assert!((r.beta + 50.0 / 500f64.sqrt()).abs() < 1e-9);
    assert!(r.pf > 0.5);
}

#[test]
fn uniform_variable_threshold() {
    // g = X − 3, X ~ U(2, 10): P_f = (3 − 2)/8 exactly, and g(x(u)) = 0 at one u, a half-line in
    // u, so FORM is exact: β = −Φ⁻¹(1/8). g is nonlinear in u, so the iterate stops within
    // ε_G·|G₀|/‖∇G‖ of the root: ε_G = 1e−12 makes that ~1e−12, and 1e−9 covers Φ, Φ⁻¹ round-off.
    let model = Model::independent(vec![RandomVariable::uniform("X", 2.0, 10.0).unwrap()]).unwrap();
    let options = FormOptions {
        g_tolerance: 1e-12,
        ..FormOptions::default()
    };
    let r = form(&model, &mut |x: &[f64]| x[0] - 3.0, &options).unwrap();
    assert!(
        (r.beta + stdnormal::inv_cdf(0.125)).abs() < 1e-9,
        "{}",
        r.beta
    );
    assert!((r.x_star[0] - 3.0).abs() < 1e-9);
}

/// `form_at` judges a proposed point with FORM's own tolerances: on a curved limit state
/// (lognormal R over S, g = R − S: not linear in u) FORM's design point is accepted, with
/// FORM's β and design point (the same evaluation, so to round-off: 1e-12), and a point off
/// the surface (the means) or on it but not where u ∥ ∇G is refused; a g_scale that is not
/// positive and a point of the wrong length are named errors.
#[test]
fn form_at_accepts_the_design_point_and_refuses_others() {
    use kappe_reliability::{Error, form_at};
    let model = Model::independent(vec![
        RandomVariable::lognormal_cov("R", 200.0, 0.1).unwrap(),
        RandomVariable::lognormal_cov("S", 150.0, 0.2).unwrap(),
    ])
    .unwrap();
    let mut g = |x: &[f64]| x[0] - x[1];
    let o = FormOptions::default();
    let r = form(&model, &mut g, &o).unwrap();
    let u0 = model.u_from_x(&model.means());
    let g0 = (g(&model.x_from_u(&u0))).abs();
    let at = form_at(&model, &mut g, &r.u_star, g0, &o).unwrap().unwrap();
    assert!(
        (at.beta - r.beta).abs() < 1e-12,
        "{} vs {}",
        at.beta,
        r.beta
    );
    for (a, b) in at.x_star.iter().zip(&r.x_star) {
        assert!((a / b - 1.0).abs() < 1e-12);
    }
    assert!(form_at(&model, &mut g, &u0, g0, &o).unwrap().is_none());
    // On the surface R = S but away from the design point: u not parallel to ∇G.
    let off = model.u_from_x(&[170.0, 170.0]);
    assert!(form_at(&model, &mut g, &off, g0, &o).unwrap().is_none());
    assert!(matches!(
        form_at(&model, &mut g, &r.u_star, 0.0, &o),
        Err(Error::InvalidOption {
            field: "g_scale",
            ..
        })
    ));
    assert!(matches!(
        form_at(&model, &mut g, &[0.0], g0, &o),
        Err(Error::DimensionMismatch { .. })
    ));
}
