//! The fixed-geometry force pass reproduces the solver on solved geometry.

use kappe_cem::json::read_topology;
use kappe_cem::{Topology, fixed_geometry::force_pass, solve};
use nalgebra::Vector3;

use crate::common::read_input;

fn check(name: &str, tol_scale: f64) {
    let file = read_topology(&read_input(name)).unwrap();
    let eq = solve(&file.topology, &file.solver).unwrap();
    let positions: Vec<Vector3<f64>> = file
        .topology
        .nodes
        .iter()
        .map(|n| eq.position(n.id).unwrap())
        .collect();
    let fp = force_pass(&file.topology, &positions).unwrap();
    let tol = tol_scale * (1.0 + fp.max_abs_force);
    assert!(
        fp.max_node_residual <= tol,
        "{name}: residual {}",
        fp.max_node_residual
    );
    for (e, f) in file.topology.trail_edges.iter().zip(&fp.trail_forces) {
        let want = eq.trail_edge(e.u, e.v).unwrap().force;
        assert!(
            (f - want).abs() <= tol,
            "{name}: ({},{}) {f} vs {want}",
            e.u,
            e.v
        );
    }
    for (n, r) in file.topology.nodes.iter().zip(&fp.reactions) {
        assert!(
            (r - eq.reaction(n.id).unwrap()).amax() <= tol,
            "{name}: reaction {}",
            n.id
        );
    }
}

#[test]
fn force_pass_reproduces_solver_forces() {
    // Direct-only networks: the solved geometry is exact to rounding (1e-10 scaled, as the
    // per-node check of cem.md §10).
    // (edge_cases is left out: its zero-length edges have no direction to carry a force.)
    for name in ["threebar_funicular", "arch2d_crown", "vault_grid500"] {
        check(name, 1e-10);
    }
    // Indirect edges: the geometry is converged only to eta = 1e-6 (cem.md §10).
    check("braced_tower_2d", 1e-6);
}

#[test]
fn force_pass_finds_out_of_balance_geometry() {
    // A straight two-edge column, loaded at the top, with the middle node pushed sideways
    // by 0.1: the trail edges cannot carry the vertical load without a residual.
    let topo = Topology::builder()
        .node(0, [0.0, 0.0, 2.0])
        .load(0, [0.0, 0.0, -1.0])
        .node(1, [0.0, 0.0, 1.0])
        .node(2, [0.0, 0.0, 0.0])
        .support(2)
        .trail_edge(0, 1, -1.0)
        .trail_edge(1, 2, -1.0)
        .build()
        .unwrap();
    let straight = [
        Vector3::new(0.0, 0.0, 2.0),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::zeros(),
    ];
    let fp = force_pass(&topo, &straight).unwrap();
    assert!(fp.max_node_residual < 1e-15);
    assert!((fp.trail_forces[0] + 1.0).abs() < 1e-15 && (fp.trail_forces[1] + 1.0).abs() < 1e-15);
    assert!((fp.reactions[2] - Vector3::new(0.0, 0.0, 1.0)).amax() < 1e-15);
    let bent = [
        Vector3::new(0.0, 0.0, 2.0),
        Vector3::new(0.1, 0.0, 1.0),
        Vector3::zeros(),
    ];
    let fp = force_pass(&topo, &bent).unwrap();
    // At node 0: r = (0,0,1), ê = (0.1,0,−1)/√1.01: F = −1/√1.01, residual = 0.1/√1.01.
    let s = 1.01f64.sqrt();
    assert!((fp.trail_forces[0] + 1.0 / s).abs() < 1e-14);
    assert!((fp.node_residuals[0] - 0.1 / s).abs() < 1e-14);
    // Node 1 turns the load path by the kink angle (sin ≈ 0.2), more than node 0 (≈ 0.1).
    assert_eq!(fp.max_residual_node, Some(1));
    assert!(force_pass(&topo, &bent[..2]).is_err());
}
