use std::path::PathBuf;

use kappe_robot::{Iso, Mat4};
use serde_json::Value;

pub fn fixture(name: &str) -> Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/fixtures/robot")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

pub fn mat4(v: &Value) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            m[i][j] = v[i][j].as_f64().unwrap();
        }
    }
    m
}

pub fn iso(v: &Value) -> Iso {
    Iso::from_mat4_unchecked(&mat4(v))
}

pub fn joints(v: &Value) -> [f64; 6] {
    let mut q = [0.0; 6];
    for j in 0..6 {
        q[j] = v[j].as_f64().unwrap();
    }
    q
}

pub fn joints_list(v: &Value) -> Vec<[f64; 6]> {
    v.as_array().unwrap().iter().map(joints).collect()
}

pub fn vec3(v: &Value) -> [f64; 3] {
    [
        v[0].as_f64().unwrap(),
        v[1].as_f64().unwrap(),
        v[2].as_f64().unwrap(),
    ]
}
