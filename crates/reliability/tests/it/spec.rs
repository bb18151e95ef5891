//! The input-file form of uncertain parameters (issue 24's `[uncertainty]` syntax).

use kappe_reliability::{Distribution, Drift, Error, Model, UncertaintySpec};
use std::collections::BTreeMap;

fn parse(text: &str) -> BTreeMap<String, UncertaintySpec> {
    #[derive(serde::Deserialize)]
    struct File {
        uncertainty: BTreeMap<String, UncertaintySpec>,
    }
    toml::from_str::<File>(text).unwrap().uncertainty
}

#[test]
fn issue_24_examples() {
    let specs = parse(
        r#"
        [uncertainty]
        "material.specific_weight" = { dist = "normal", std = 1015.0 }
        "material.time.youngs_modulus" = { dist = "lognormal", cov = 0.2 }
        "print.layer_time" = { dist = "uniform", lower = 50.0, upper = 70.0 }
        "material.poisson" = { dist = "uniform", mean = 0.3, std = 0.02 }
        "#,
    );
    let w = specs["material.specific_weight"]
        .to_variable("material.specific_weight", 2.0e4, false)
        .unwrap();
    assert_eq!(
        w.distribution,
        Distribution::Normal {
            mean: 2.0e4,
            std: 1015.0
        }
    );
    let e = specs["material.time.youngs_modulus"]
        .to_variable("E", 3.0e4, true)
        .unwrap();
    // Mean from the design, cov 0.2 of the variable itself (round-off only).
    assert!(
        (e.distribution.mean() - 3.0e4).abs() < 1e-9 && (e.distribution.std() - 6.0e3).abs() < 1e-9
    );
    let t = specs["print.layer_time"]
        .to_variable("t", 60.0, true)
        .unwrap();
    assert_eq!(
        t.distribution,
        Distribution::Uniform {
            lower: 50.0,
            upper: 70.0
        }
    );
    let nu = specs["material.poisson"]
        .to_variable("nu", 0.25, false)
        .unwrap();
    // Given mean 0.3 overrides the design's 0.25; std 0.02 ↔ half-width √3·0.02.
    assert!(
        (nu.distribution.mean() - 0.3).abs() < 1e-15
            && (nu.distribution.std() - 0.02).abs() < 1e-15
    );
    // A positive quantity with a normal spec: the model refuses it, naming it.
    let bad = specs["material.specific_weight"]
        .to_variable("material.specific_weight", 2.0e4, true)
        .unwrap();
    assert!(matches!(
        Model::independent(vec![bad]).unwrap_err(),
        Error::NotPositive { .. }
    ));
    let drift: Drift =
        toml::from_str("percent_per_hour = -2.0\nsteps = [{ at_hours = 3.0, factor = 0.9 }]")
            .unwrap();
    assert!((drift.factor(4.0).unwrap() - 0.92 * 0.9).abs() < 1e-15);
}

#[test]
fn bad_specs_are_named() {
    let one = |text: &str| parse(&format!("[uncertainty]\nx = {text}"))["x"].clone();
    let cases = [
        ("{ dist = \"normal\" }", "std"),
        ("{ dist = \"normal\", std = 1.0, cov = 0.1 }", "cov"),
        ("{ dist = \"lognormal\", cov = 0.1, lower = 1.0 }", "lower"),
        ("{ dist = \"uniform\", lower = 1.0 }", "upper"),
        (
            "{ dist = \"uniform\", lower = 1.0, upper = 2.0, std = 0.1 }",
            "lower",
        ),
        ("{ dist = \"uniform\" }", "std"),
    ];
    for (text, field) in cases {
        let e = one(text).to_variable("x", 10.0, false).unwrap_err();
        assert!(
            matches!(&e, Error::InvalidSpec { variable, field: f, .. } if variable == "x" && *f == field),
            "{text}: {e}"
        );
    }
    let e = one("{ dist = \"normal\", std = -1.0 }")
        .to_variable("x", 10.0, false)
        .unwrap_err();
    assert!(matches!(e, Error::InvalidParameter { field: "std", .. }));
    // Unknown fields and families are refused by the parser (deny_unknown_fields).
    #[derive(serde::Deserialize, Debug)]
    #[allow(dead_code)]
    struct File {
        uncertainty: BTreeMap<String, UncertaintySpec>,
    }
    assert!(toml::from_str::<File>("[uncertainty]\nx = { dist = \"normal\", sd = 1.0 }").is_err());
    assert!(toml::from_str::<File>("[uncertainty]\nx = { dist = \"gamma\", std = 1.0 }").is_err());
}
