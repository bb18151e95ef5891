//! Marginals, the map to standard normal space, and drift.

use crate::common::{expect_normal, ln_params, simpson};
use kappe_reliability::{Distribution, Drift, Model, RandomVariable, stdnormal};

#[test]
fn lognormal_parameters_give_the_asked_mean_and_std() {
    let v = RandomVariable::lognormal_cov("E", 3.0e4, 0.2).unwrap();
    let Distribution::Lognormal { lambda, zeta, .. } = v.distribution else {
        panic!("not lognormal")
    };
    let (l, z) = ln_params(3.0e4, 0.2);
    // Same closed form, evaluated in another order: round-off only.
    assert!((lambda - l).abs() < 1e-13 && (zeta - z).abs() < 1e-15);
    // E[X] = exp(λ + ζ²/2), Var X = (exp(ζ²) − 1) exp(2λ + ζ²): the moments of the variable itself.
    let mean = (lambda + 0.5 * zeta * zeta).exp();
    let std = ((zeta * zeta).exp_m1()).sqrt() * mean;
    assert!((mean / 3.0e4 - 1.0).abs() < 1e-14);
    assert!((std / 6.0e3 - 1.0).abs() < 1e-13);
    assert!(v.positive, "a lognormal is positive by construction");
}

#[test]
fn cdf_pdf_inverse_and_standard_map_agree() {
    let vars = [
        RandomVariable::normal("a", 5.0, 2.0).unwrap(),
        RandomVariable::lognormal("b", 10.0, 3.0).unwrap(),
        RandomVariable::uniform("c", -1.0, 3.0).unwrap(),
    ];
    for v in &vars {
        let d = v.distribution;
        for p in [1e-9, 0.01, 0.3, 0.5, 0.8, 0.999, 1.0 - 1e-9] {
            let x = d.inv_cdf(p);
            // Round trip F(F⁻¹(p)) to 1e−12 relative plus 1e−15 absolute: Φ, Φ⁻¹ are accurate to
            // a few ulp; the uniform's x = a + (b − a)p carries an absolute round-off of ~ulp(b − a).
            let close = |a: f64| (a - p).abs() <= 1e-12 * p + 1e-15;
            assert!(close(d.cdf(x)), "{} p={p}", v.name);
            let z = d.to_standard(x);
            assert!(close(stdnormal::cdf(z)), "{} p={p}", v.name);
            assert!(
                (d.from_standard(z) - x).abs() < 1e-12 * (1.0 + x.abs()),
                "{} p={p}",
                v.name
            );
            // dx/dz = φ(z)/f(x) (the Jacobian FORM's chain rule uses).
            let jac = stdnormal::pdf(z) / d.pdf(x);
            assert!((d.dx_dz(z) / jac - 1.0).abs() < 1e-9, "{} p={p}", v.name);
        }
        // The pdf integrates to 1 and has the stated mean: ∫f = 1 and ∫x f = μ, Simpson in z
        // (x = x(z)), accurate to ~1e−12 for these smooth integrands.
        let total = expect_normal(|_| 1.0);
        let mean = expect_normal(|z| d.from_standard(z));
        assert!((total - 1.0).abs() < 1e-12);
        assert!(
            (mean - d.mean()).abs() < 1e-9 * d.mean().abs().max(1.0),
            "{}",
            v.name
        );
    }
    // Uniform density in x: ∫_a^b f = 1 (exact for a constant).
    let u = vars[2].distribution;
    assert!((simpson(|x| u.pdf(x), -1.0, 3.0, 100) - 1.0).abs() < 1e-14);
}

#[test]
fn drift_factor_formula_and_scaled_state_shares_u_space() {
    // −2 %/h, not compounded: 1 − 0.02·5 = 0.9 at 5 h.
    assert!((Drift::linear(-2.0).factor(5.0).unwrap() - 0.9).abs() < 1e-15);
    let both = Drift {
        percent_per_hour: 1.0,
        steps: vec![kappe_reliability::DriftStep {
            at_hours: 2.0,
            factor: 0.8,
        }],
    };
    assert!((both.factor(1.0).unwrap() - 1.01).abs() < 1e-15);
    assert!((both.factor(3.0).unwrap() - 1.03 * 0.8).abs() < 1e-15);
    assert_eq!(Drift::step(2.0, 0.5).factor(2.0).unwrap(), 0.5);
    assert_eq!(Drift::none().factor(100.0).unwrap(), 1.0);

    let base = Model::independent(vec![
        RandomVariable::lognormal_cov("E", 100.0, 0.2).unwrap(),
        RandomVariable::normal("q", 10.0, 1.0).unwrap(),
    ])
    .unwrap();
    let c = Drift::linear(-2.0).factor(5.0).unwrap();
    let state = base.scaled(&[c, 1.0]).unwrap();
    let e = &state.variables()[0].distribution;
    // c·X: mean and std both scaled, cov kept (closed form, round-off only).
    assert!((e.mean() - 90.0).abs() < 1e-12 && (e.std() - 18.0).abs() < 1e-12);
    // The same u maps to c·x: the states share one u-space.
    let u = [0.7, -1.3];
    let (xb, xs) = (base.x_from_u(&u), state.x_from_u(&u));
    assert!((xs[0] - c * xb[0]).abs() < 1e-12 * xb[0] && xs[1] == xb[1]);
}
