//! Bad input: every case gives a typed error naming the node/element/field, never a panic.

use kappe_fe::mesh_json::parse_mesh;
use kappe_fe::{BucklingOptions, FeError, ShellModel, Support, buckling, linear_static};

use crate::common::material;

fn square() -> ShellModel {
    let nodes = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut m = ShellModel::new(
        nodes,
        vec![[0, 1, 2], [0, 2, 3]],
        0.01,
        material(1e6, 0.3, 2e4),
    );
    m.supports = vec![Support::clamped(0), Support::clamped(1)];
    m
}

#[test]
fn valid_square_solves() {
    assert!(linear_static(&square()).is_ok());
}

#[test]
fn degenerate_triangle() {
    let mut m = square();
    m.nodes[2] = [0.5, 0.5, 0.0]; // collinear with 0 and the diagonal → [0,2,3] ok, [0,1,2]?
    m.nodes[2] = [2.0, 0.0, 0.0]; // 0, 1, 2 collinear
    let e = m.validate().unwrap_err();
    assert!(
        matches!(e, FeError::DegenerateTriangle { element: 0, .. }),
        "{e}"
    );
    let mut m = square();
    m.triangles[1] = [0, 2, 2];
    assert!(matches!(
        m.validate().unwrap_err(),
        FeError::DegenerateTriangle { element: 1, .. }
    ));
}

#[test]
fn inverted_triangle() {
    let mut m = square();
    m.triangles[1] = [0, 3, 2];
    let e = m.validate().unwrap_err();
    assert!(
        matches!(
            e,
            FeError::InvertedTriangle {
                element: 1,
                neighbour: 0,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn unreferenced_node() {
    let mut m = square();
    m.nodes.push([5.0, 5.0, 5.0]);
    assert!(matches!(
        m.validate().unwrap_err(),
        FeError::UnreferencedNode { node: 4 }
    ));
}

#[test]
fn out_of_range_properties_and_nan() {
    let mut m = square();
    m.thickness = vec![0.01, -0.01];
    let e = m.validate().unwrap_err();
    assert!(e.to_string().contains("thickness[1]"), "{e}");
    let mut m = square();
    m.materials[0].youngs_modulus = 0.0;
    assert!(
        m.validate()
            .unwrap_err()
            .to_string()
            .contains("materials[0].E")
    );
    let mut m = square();
    m.nodes[3][1] = f64::NAN;
    assert!(m.validate().unwrap_err().to_string().contains("nodes[3].y"));
    let mut m = square();
    m.thickness = vec![0.01; 3];
    assert!(matches!(
        m.validate().unwrap_err(),
        FeError::WrongLength {
            field: "thickness",
            ..
        }
    ));
    let mut m = square();
    m.triangles[0][2] = 9;
    assert!(matches!(
        m.validate().unwrap_err(),
        FeError::NodeOutOfRange {
            element: 0,
            node: 9,
            ..
        }
    ));
}

/// No supports at all: a mechanism, reported with free DOFs, never a panic.
#[test]
fn mechanism_unsupported() {
    let mut m = square();
    m.supports.clear();
    let e = linear_static(&m).unwrap_err();
    match &e {
        FeError::Mechanism { free_dofs } => assert!(!free_dofs.is_empty()),
        other => panic!("expected a mechanism, got {other}"),
    }
    assert!(e.to_string().contains("structure is a mechanism"), "{e}");
}

/// Only node 0 pinned: the plate can rotate about it — still a mechanism.
#[test]
fn mechanism_single_hinge() {
    let mut m = square();
    m.supports = vec![Support::pinned(0)];
    let e = buckling(&m, &BucklingOptions::default()).unwrap_err();
    assert!(matches!(e, FeError::Mechanism { .. }), "{e}");
}

#[test]
fn json_errors_name_the_field() {
    let e = parse_mesh(
        "{\"nodes\": [[0,0,0]], \"triangles\": [[0,1]], \"thickness\": 1, \"E\": 1, \"nu\": 0}",
    )
    .unwrap_err();
    assert!(e.to_string().contains("triangles[0]"), "{e}");
    let e = parse_mesh("{\"nodes\": [[0,0,0]], \"triangles\": [], \"thickness\": 1, \"E\": 1, \"nu\": 0, \"supports\": {\"uq\": [0]}}")
        .unwrap_err();
    assert!(e.to_string().contains("supports.uq"), "{e}");
    let e = parse_mesh("{\"nodes\": [[0,0,\"a\"]]}").unwrap_err();
    assert!(e.to_string().contains("nodes[0][2]"), "{e}");
    assert!(parse_mesh("not json").is_err());
}

/// γ given only inside the self_weight load is used; conflicting values are rejected.
#[test]
fn gamma_in_load() {
    let base = "\"nodes\": [[0,0,0],[1,0,0],[0,1,0]], \"triangles\": [[0,1,2]], \"thickness\": 0.1, \"E\": 1e6, \"nu\": 0.3";
    let m = parse_mesh(&format!(
        "{{{base}, \"load\": {{\"type\": \"self_weight\", \"gamma\": 5.0}}}}"
    ))
    .unwrap();
    assert_eq!(m.materials[0].unit_weight, 5.0);
    let e = parse_mesh(&format!(
        "{{{base}, \"gamma\": 4.0, \"load\": {{\"type\": \"self_weight\", \"gamma\": 5.0}}}}"
    ))
    .unwrap_err();
    assert!(e.to_string().contains("load.gamma"), "{e}");
}

/// A flat but valid triangle (longest edge 1 m, height 0.01 m: aspect 100) is accepted and
/// flagged; a regular grid has no warnings.
#[test]
fn flat_triangles_are_flagged() {
    assert!(square().quality_warnings().is_empty());
    let nodes = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.01, 0.0]];
    let m = ShellModel::new(nodes, vec![[0, 1, 2]], 0.01, material(1e6, 0.3, 0.0));
    let w = m.quality_warnings();
    assert_eq!(w.len(), 1);
    assert!((w[0].1 - 100.0).abs() < 1e-9, "{w:?}");
    assert!(m.validate().is_ok());
}
