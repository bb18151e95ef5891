//! Bad input gives distinct typed errors (issue 2, "Bad input"), and the reaction-node
//! extension works.

use kappe_cem::json::read_topology;
use kappe_cem::{CemError, SolverOptions, Topology, solve};
use nalgebra::Vector3;

fn kind(topo: Result<Topology, CemError>) -> &'static str {
    match topo.and_then(|t| solve(&t, &SolverOptions::default())) {
        Ok(_) => "ok",
        Err(e) => {
            // Every message names something concrete; at least it is not empty.
            assert!(!e.to_string().is_empty());
            e.kind()
        }
    }
}

fn chain() -> kappe_cem::TopologyBuilder {
    Topology::builder()
        .node(0, [0.0, 0.0, 2.0])
        .load(0, [0.0, 0.0, -1.0])
        .node(1, [0.0, 0.0, 1.0])
        .node(2, [0.0, 0.0, 0.0])
        .trail_edge(0, 1, -1.0)
        .trail_edge(1, 2, -1.0)
}

#[test]
fn valid_chain_solves() {
    assert_eq!(kind(chain().support(2).build()), "ok");
}

#[test]
fn each_bad_input_has_its_own_kind() {
    assert_eq!(kind(chain().build()), "no_support");
    assert_eq!(
        kind(chain().support(2).support(0).build()),
        "trail_with_two_supports"
    );
    assert_eq!(kind(chain().support(1).build()), "support_inside_trail");
    assert_eq!(
        kind(chain().support(2).node(3, [1.0, 0.0, 0.0]).build()),
        "unassigned_node"
    );
    assert_eq!(
        kind(
            chain()
                .support(2)
                .node(3, [1.0, 0.0, 0.0])
                .trail_edge(1, 3, -1.0)
                .build()
        ),
        "node_on_two_trails"
    );
    // A triangle of trail edges that touches no support.
    let cyc = chain()
        .support(2)
        .node(5, [0.0; 3])
        .node(6, [0.0; 3])
        .node(7, [0.0; 3])
        .trail_edge(5, 6, 1.0)
        .trail_edge(6, 7, 1.0)
        .trail_edge(7, 5, 1.0)
        .build();
    assert_eq!(kind(cyc), "trail_cycle");
    let open = chain()
        .support(2)
        .node(5, [0.0; 3])
        .node(6, [0.0; 3])
        .trail_edge(5, 6, 1.0)
        .build();
    assert_eq!(kind(open), "trail_without_support");
    assert_eq!(
        kind(chain().support(2).trail_edge(0, 9, -1.0).build()),
        "unknown_node"
    );
    assert_eq!(kind(chain().support(9).build()), "unknown_node");
    assert_eq!(
        kind(chain().support(2).node(1, [0.0; 3]).build()),
        "duplicate_node"
    );
    assert_eq!(
        kind(chain().support(2).deviation_edge(0, 1, 1.0).build()),
        "duplicate_edge"
    );
    assert_eq!(
        kind(chain().support(2).deviation_edge(0, 0, 1.0).build()),
        "self_loop"
    );
    assert_eq!(
        kind(chain().support(2).load(1, [f64::NAN, 0.0, 0.0]).build()),
        "non_finite"
    );
    let mut t = chain().support(2).build().unwrap();
    t.nodes[1].origin = Some(true);
    assert_eq!(kind(Ok(t)), "origin_mismatch");
    assert_eq!(
        kind(chain().support(2).shift_trail(1, 3).build()),
        "shift_not_origin"
    );
}

#[test]
fn json_errors_name_the_place() {
    let err = read_topology("{\"format\": \"kappe.cem.topology\", \"version\": 1, \"nodes\": [{\"id\": -1, \"xyz\": [0,0,0]}]}")
        .unwrap_err();
    assert_eq!(err.kind(), "malformed_json");
    assert!(err.to_string().contains("nodes[0].id"), "{err}");
    let err = read_topology("{\"format\": \"other\", \"version\": 1, \"nodes\": []}").unwrap_err();
    assert_eq!(err.kind(), "unsupported_format");
    let err = read_topology("{ not json").unwrap_err();
    assert_eq!(err.kind(), "malformed_json");
}

#[test]
fn not_converged_is_reported() {
    // Braced tower of compas_cem with an impossible eta after 3 sweeps (cf. err_no_convergence).
    let text =
        std::fs::read_to_string(crate::common::fixture_dir().join("braced_tower_2d.input.json"))
            .unwrap();
    let file = read_topology(&text).unwrap();
    let err = solve(
        &file.topology,
        &SolverOptions {
            tmax: 3,
            eta: 1e-12,
        },
    )
    .unwrap_err();
    assert_eq!(err.kind(), "not_converged");
}

/// Reaction node: a support without trail edge, held by one deviation edge. Closed form:
/// its reaction is −q − μ·û(x_m − x_s), and it is processed at its neighbour's sequence.
#[test]
fn reaction_node_balances_load_and_deviation_forces() {
    let mu = -2.5;
    let q5 = Vector3::new(0.1, 0.0, -0.7);
    let topo = chain()
        .support(2)
        .node(5, [3.0, 0.0, 1.5])
        .support(5)
        .load(5, q5.into())
        .deviation_edge(1, 5, mu)
        .build()
        .unwrap();
    let eq = solve(&topo, &SolverOptions::default()).unwrap();
    let n5 = eq.node(5).unwrap();
    assert!(n5.origin && n5.support);
    assert_eq!(n5.sequence, eq.node(1).unwrap().sequence);
    assert!(eq.deviation_edge(5, 1).unwrap().direct);
    // Its position is prescribed.
    assert_eq!(n5.xyz, Vector3::new(3.0, 0.0, 1.5));
    let x1 = eq.position(1).unwrap();
    let expect = -q5 - (x1 - n5.xyz).normalize() * mu;
    // 1e-12: a handful of floating-point operations on O(1) numbers.
    assert!(
        (n5.reaction - expect).amax() < 1e-12,
        "{:?} vs {expect:?}",
        n5.reaction
    );
    assert!(eq.checks.max_node_residual < 1e-12);
    assert!((eq.checks.sum_loads + eq.checks.sum_reactions).amax() < 1e-12);
}

/// threebar funicular closed form (cem.md fixture table): supports at (1 − 1/√2, −1/√2),
/// trail forces −√2, reactions (1, 1, 0).
#[test]
fn threebar_closed_form() {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let topo = Topology::builder()
        .node(0, [0.0, 0.0, 0.0])
        .support(0)
        .node(1, [1.0, 0.0, 0.0])
        .load(1, [0.0, -1.0, 0.0])
        .node(2, [2.5, 0.0, 0.0])
        .load(2, [0.0, -1.0, 0.0])
        .node(3, [3.5, 0.0, 0.0])
        .support(3)
        .trail_edge(0, 1, -1.0)
        .trail_edge(2, 3, -1.0)
        .deviation_edge(1, 2, -1.0)
        .build()
        .unwrap();
    let eq = solve(&topo, &SolverOptions::default()).unwrap();
    assert!((eq.position(0).unwrap() - Vector3::new(1.0 - s, -s, 0.0)).amax() < 1e-14);
    assert!((eq.position(3).unwrap() - Vector3::new(2.5 + s, -s, 0.0)).amax() < 1e-14);
    assert!((eq.trail_edge(1, 0).unwrap().force + 2f64.sqrt()).abs() < 1e-14);
    assert!((eq.reaction(3).unwrap() - Vector3::new(-1.0, 1.0, 0.0)).amax() < 1e-14);
    // Force polygons close.
    for p in eq.force_polygons() {
        assert!(p.closure().amax() < 1e-14, "{p:?}");
    }
}
