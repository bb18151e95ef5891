//! Helpers shared by the integration tests.

use std::path::PathBuf;

use serde_json::Value;

/// The shared CEM fixtures (compas_cem 0.8.6 reference outputs).
pub fn fixture_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/fixtures/cem")
}

/// Names of all fixtures (`NAME.input.json` present).
pub fn fixture_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(fixture_dir())
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().into_string().unwrap();
            name.strip_suffix(".input.json").map(str::to_string)
        })
        .collect();
    names.sort();
    names
}

pub fn read_input(name: &str) -> String {
    std::fs::read_to_string(fixture_dir().join(format!("{name}.input.json"))).unwrap()
}

pub fn read_expected(name: &str) -> Value {
    let text =
        std::fs::read_to_string(fixture_dir().join(format!("{name}.expected.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

pub fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

pub fn v3(v: &Value) -> nalgebra::Vector3<f64> {
    let a = v.as_array().unwrap();
    nalgebra::Vector3::new(f(&a[0]), f(&a[1]), f(&a[2]))
}

/// `|a − b| ≤ t·(1 + |b|)` (cem.md §10 "rel+abs").
pub fn close_rel(a: f64, b: f64, t: f64) -> bool {
    (a - b).abs() <= t * (1.0 + b.abs())
}
