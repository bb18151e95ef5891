//! Every bad input gives its named error, and the message names the variable and field.

use kappe_reliability::{
    Batch, Component, Correlation, Drift, Error, EvalError, Fallible, FormOptions, Model,
    RandomVariable, SamplingMethod, SamplingOptions, SystemOptions, form, merge, sample_batch,
    series_system,
};

fn n(name: &str) -> RandomVariable {
    RandomVariable::normal(name, 10.0, 1.0).unwrap()
}

fn msg(e: &Error, parts: &[&str]) {
    let s = e.to_string();
    for p in parts {
        assert!(s.contains(p), "`{s}` lacks `{p}`");
    }
}

#[test]
fn bad_distribution_parameters() {
    let e = RandomVariable::normal("E", 10.0, -1.0).unwrap_err();
    assert!(matches!(&e, Error::InvalidParameter { field: "std", .. }));
    msg(&e, &["`E`", "std = -1", "> 0"]);
    let e = RandomVariable::normal("E", 10.0, 0.0).unwrap_err();
    assert!(matches!(&e, Error::InvalidParameter { field: "std", .. }));
    let e = RandomVariable::lognormal_cov("E", 10.0, 0.0).unwrap_err();
    assert!(matches!(&e, Error::InvalidParameter { field: "cov", .. }));
    msg(&e, &["`E`", "cov"]);
    let e = RandomVariable::lognormal("E", -5.0, 1.0).unwrap_err();
    assert!(matches!(&e, Error::InvalidParameter { field: "mean", .. }));
    let e = RandomVariable::normal_cov("q", 0.0, 0.1).unwrap_err();
    assert!(matches!(&e, Error::InvalidParameter { field: "mean", .. }));
    let e = RandomVariable::uniform("t", 3.0, 3.0).unwrap_err();
    assert!(matches!(&e, Error::InvalidParameter { field: "upper", .. }));
    msg(&e, &["`t`", "upper", "lower"]);
    let e = RandomVariable::normal("E", f64::NAN, 1.0).unwrap_err();
    assert!(matches!(&e, Error::InvalidParameter { field: "mean", .. }));
    let e = n("E").scaled(0.0).unwrap_err();
    assert!(matches!(
        &e,
        Error::InvalidParameter {
            field: "scale factor",
            ..
        }
    ));
}

#[test]
fn unbounded_distribution_for_a_positive_quantity() {
    let e = Model::independent(vec![n("material.specific_weight").positive()]).unwrap_err();
    assert!(matches!(
        &e,
        Error::NotPositive {
            distribution: "normal",
            ..
        }
    ));
    msg(&e, &["`material.specific_weight`", "positive", "unbounded"]);
    let e = Model::independent(vec![
        RandomVariable::uniform("t", -1.0, 2.0).unwrap().positive(),
    ])
    .unwrap_err();
    assert!(matches!(
        &e,
        Error::NotPositive {
            distribution: "uniform",
            ..
        }
    ));
    // Lognormal and uniform with lower > 0 are fine.
    Model::independent(vec![
        RandomVariable::lognormal_cov("E", 1.0, 0.2)
            .unwrap()
            .positive(),
        RandomVariable::uniform("t", 1.0, 2.0).unwrap().positive(),
    ])
    .unwrap();
}

#[test]
fn bad_models() {
    assert!(matches!(
        Model::independent(vec![]).unwrap_err(),
        Error::NoVariables
    ));
    let e = Model::independent(vec![n("a"), n("a")]).unwrap_err();
    assert!(matches!(&e, Error::DuplicateVariable { variable } if variable == "a"));
    let pairs = |v: Vec<(&str, &str, f64)>| {
        Correlation::Pairs(
            v.into_iter()
                .map(|(a, b, r)| (a.to_owned(), b.to_owned(), r))
                .collect(),
        )
    };
    let e = Model::new(vec![n("a"), n("b")], &pairs(vec![("a", "c", 0.3)])).unwrap_err();
    assert!(matches!(&e, Error::UnknownVariable { name, .. } if name == "c"));
    msg(&e, &["`c`", "a, b"]);
    let e = Model::new(vec![n("a"), n("b")], &pairs(vec![("a", "b", 1.2)])).unwrap_err();
    assert!(matches!(&e, Error::CorrelationOutOfRange { .. }));
    msg(&e, &["`a`", "`b`", "1.2"]);
    let e = Model::new(
        vec![n("a"), n("b")],
        &pairs(vec![("a", "b", 0.3), ("b", "a", 0.4)]),
    )
    .unwrap_err();
    assert!(matches!(&e, Error::CorrelationNotSymmetric { .. }));
    let m = |rows: Vec<Vec<f64>>| Model::new(vec![n("a"), n("b")], &Correlation::Matrix(rows));
    let e = m(vec![vec![1.0, 0.3], vec![0.2, 1.0]]).unwrap_err();
    assert!(matches!(&e, Error::CorrelationNotSymmetric { .. }));
    msg(&e, &["`a`", "`b`", "symmetric"]);
    let e = m(vec![vec![1.0, -1.0], vec![-1.0, 1.0]]).unwrap_err();
    assert!(matches!(&e, Error::CorrelationOutOfRange { .. }));
    let e = m(vec![vec![0.9, 0.0], vec![0.0, 1.0]]).unwrap_err();
    assert!(matches!(&e, Error::CorrelationDiagonal { variable, .. } if variable == "a"));
    let e = m(vec![vec![1.0, 0.0, 0.0], vec![0.0, 1.0, 0.0]]).unwrap_err();
    assert!(matches!(
        &e,
        Error::CorrelationShape {
            rows: 2,
            cols: 3,
            expected: 2
        }
    ));
    // ρab = ρac = 0.9 force b and c to correlate ≥ 0.62; −0.9 is impossible (not positive definite).
    let e = Model::new(
        vec![n("a"), n("b"), n("c")],
        &pairs(vec![("a", "b", 0.9), ("a", "c", 0.9), ("b", "c", -0.9)]),
    )
    .unwrap_err();
    assert!(
        matches!(&e, Error::CorrelationNotPositiveDefinite { variable, .. } if variable == "c")
    );
    msg(&e, &["`c`", "a, b", "positive definite"]);
    // Two strongly skewed lognormals cannot reach ρ = −0.9 (the Nataf bound is about −0.6 at δ = 1).
    let e = Model::new(
        vec![
            RandomVariable::lognormal_cov("a", 1.0, 1.0).unwrap(),
            RandomVariable::lognormal_cov("b", 1.0, 1.0).unwrap(),
        ],
        &pairs(vec![("a", "b", -0.9)]),
    )
    .unwrap_err();
    assert!(matches!(&e, Error::CorrelationNotAttainable { .. }));
    msg(&e, &["`a`", "`b`", "-0.9"]);
    let base = Model::independent(vec![n("a")]).unwrap();
    assert!(matches!(
        base.scaled(&[1.0, 2.0]).unwrap_err(),
        Error::DimensionMismatch { .. }
    ));
    assert!(matches!(
        base.index_of("zz").unwrap_err(),
        Error::UnknownVariable { .. }
    ));
}

#[test]
fn drift_reaching_zero() {
    let e = Drift::linear(-10.0).factor(12.0).unwrap_err();
    assert!(matches!(&e, Error::DriftFactorNotPositive { .. }));
    msg(&e, &["t = 12 h", "10 h"]);
}

#[test]
fn bad_limit_states_and_options() {
    let model = Model::independent(vec![n("a"), n("b")]).unwrap();
    let o = FormOptions::default();
    let e = form(&model, &mut |_: &[f64]| 1.0, &o).unwrap_err();
    assert!(matches!(&e, Error::ZeroGradient { .. }));
    let e = form(
        &model,
        &mut |x: &[f64]| if x[0] < 9.99 { f64::NAN } else { x[0] - 9.0 },
        &o,
    )
    .unwrap_err();
    assert!(matches!(&e, Error::NonFiniteLimitState { .. }), "{e}");
    let e = form(
        &model,
        &mut Fallible(|_: &[f64]| -> Result<f64, EvalError> { Err("FE solve failed".into()) }),
        &o,
    )
    .unwrap_err();
    assert!(matches!(&e, Error::LimitState { .. }));
    assert_eq!(
        std::error::Error::source(&e).unwrap().to_string(),
        "FE solve failed"
    );
    let bad = FormOptions {
        fd_step: 0.0,
        ..FormOptions::default()
    };
    let e = form(&model, &mut |x: &[f64]| x[0] - x[1], &bad).unwrap_err();
    assert!(matches!(
        &e,
        Error::InvalidOption {
            field: "fd_step",
            ..
        }
    ));
    let start = FormOptions {
        start: Some(vec![1.0]),
        ..FormOptions::default()
    };
    let e = form(&model, &mut |x: &[f64]| x[0] - x[1], &start).unwrap_err();
    assert!(matches!(&e, Error::DimensionMismatch { .. }));
}

#[test]
fn bad_sampling_and_systems() {
    let model = Model::independent(vec![n("a"), n("b")]).unwrap();
    let g = &mut |x: &[f64]| x[0] - x[1];
    let mc = SamplingMethod::MonteCarlo;
    let opts = SamplingOptions::new(3000, 1);
    let e = sample_batch(&model, g, &mc, &opts, Batch { index: 2, count: 2 }).unwrap_err();
    assert!(matches!(
        &e,
        Error::InvalidOption {
            field: "batch.index",
            ..
        }
    ));
    let e = sample_batch(
        &model,
        g,
        &SamplingMethod::ImportanceSampling { center: vec![1.0] },
        &opts,
        Batch { index: 0, count: 1 },
    )
    .unwrap_err();
    assert!(matches!(&e, Error::DimensionMismatch { .. }));
    let b0 = sample_batch(&model, g, &mc, &opts, Batch { index: 0, count: 3 }).unwrap();
    let b1 = sample_batch(&model, g, &mc, &opts, Batch { index: 1, count: 3 }).unwrap();
    // Missing block, duplicate block, batches of another seed: all refused.
    assert!(matches!(
        merge(&[b0.clone(), b1.clone()]).unwrap_err(),
        Error::BatchMerge { .. }
    ));
    assert!(matches!(
        merge(&[b0.clone(), b0.clone(), b1.clone()]).unwrap_err(),
        Error::BatchMerge { .. }
    ));
    let other = sample_batch(
        &model,
        g,
        &mc,
        &SamplingOptions::new(3000, 2),
        Batch { index: 2, count: 3 },
    )
    .unwrap();
    assert!(matches!(
        merge(&[b0, b1, other]).unwrap_err(),
        Error::BatchMerge { .. }
    ));
    assert!(matches!(merge(&[]).unwrap_err(), Error::BatchMerge { .. }));

    let so = SystemOptions::default();
    assert!(matches!(
        series_system(&[], &so).unwrap_err(),
        Error::NoComponents
    ));
    let c = |alpha: Vec<f64>| Component { beta: 2.0, alpha };
    let e = series_system(&[c(vec![1.0, 0.0]), c(vec![0.5, 0.5])], &so).unwrap_err();
    assert!(matches!(&e, Error::ComponentAlpha { index: 1, .. }));
    let e = series_system(&[c(vec![1.0, 0.0]), c(vec![1.0])], &so).unwrap_err();
    assert!(matches!(&e, Error::DimensionMismatch { .. }));
}

#[test]
fn hand_built_variables_are_checked_and_drift_names_must_exist() {
    let mut v = n("E");
    v.distribution = kappe_reliability::Distribution::Normal {
        mean: 1.0,
        std: -2.0,
    };
    let e = Model::independent(vec![v]).unwrap_err();
    assert!(
        matches!(&e, Error::InvalidParameter { variable, field: "std", .. } if variable == "E")
    );
    let model = Model::independent(vec![n("E"), n("q")]).unwrap();
    let e = model
        .drifted(&[("G".to_owned(), Drift::linear(-1.0))], 2.0)
        .unwrap_err();
    assert!(
        matches!(&e, Error::UnknownVariable { name, context: "the drifts", .. } if name == "G")
    );
    let state = model
        .drifted(&[("E".to_owned(), Drift::linear(-1.0))], 2.0)
        .unwrap();
    // c(2 h) = 0.98 on E only (closed form, round-off only).
    assert!((state.variables()[0].distribution.mean() - 9.8).abs() < 1e-12);
    assert_eq!(state.variables()[1].distribution.mean(), 10.0);
}
