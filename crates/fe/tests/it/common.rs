//! Shared helpers: fixture loading and small generated meshes.
#![allow(dead_code)] // helpers are shared by the test modules; not every module uses all

use std::path::PathBuf;

use kappe_fe::mesh_json::parse_mesh;
use kappe_fe::{Material, ShellModel};

pub fn fixture_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/fixtures/fe")
}

/// A fixture mesh with the fixtures' reference element CST+DKT, set explicitly so the
/// Kirchhoff A-checks do not follow a change of the mesh-JSON default. Tests of other
/// elements set `element` after loading.
pub fn load_mesh(name: &str) -> ShellModel {
    let p = fixture_dir().join(format!("{name}.mesh.json"));
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let mut m = parse_mesh(&text).unwrap();
    m.element = kappe_fe::ElementKind::CstDkt;
    m
}

pub fn load_json(file: &str) -> serde_json::Value {
    let p = fixture_dir().join(file);
    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()
}

pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Rectangular grid in the x-y plane, `nx × ny` cells, each split into two triangles
/// (consistent counter-clockwise orientation). Node (i, j) has index j·(nx+1)+i.
pub fn grid(a: f64, b: f64, nx: usize, ny: usize) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let mut nodes = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([a * i as f64 / nx as f64, b * j as f64 / ny as f64, 0.0]);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut tris = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (nodes, tris)
}

pub fn material(e: f64, nu: f64, gamma: f64) -> Material {
    Material {
        youngs_modulus: e,
        poisson_ratio: nu,
        unit_weight: gamma,
    }
}
