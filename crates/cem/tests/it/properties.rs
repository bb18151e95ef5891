//! Property tests on random valid topologies (proptest; its RNG is seeded deterministically
//! per test by proptest's default config, and failures are reproducible from the printed seed).

use kappe_cem::{Equilibrium, SolverOptions, Topology, TopologyBuilder, solve};
use nalgebra::Vector3;
use proptest::prelude::*;

/// A random network: `trails` trails of `len` nodes (ids `100·t + j`, origin j = 0, support
/// j = len−1), random origins, loads, signed lengths, and deviation edges between random
/// nodes. Indirect edges get small forces so the iteration contracts.
#[derive(Debug, Clone)]
struct Net {
    origins: Vec<[f64; 3]>,
    len: usize,
    loads: Vec<[f64; 3]>,
    lengths: Vec<f64>,
    devs: Vec<(usize, usize, usize, usize, f64)>,
}

fn net() -> impl Strategy<Value = Net> {
    (2usize..5, 2usize..7).prop_flat_map(|(trails, len)| {
        let n = trails * len;
        (
            prop::collection::vec(prop::array::uniform3(-5.0..5.0f64), trails),
            prop::collection::vec(prop::array::uniform3(-1.0..1.0f64), n),
            prop::collection::vec(
                (0.2..2.0f64, any::<bool>()).prop_map(|(l, s)| if s { l } else { -l }),
                n,
            ),
            prop::collection::vec(
                (0..trails, 0..len, 0..trails, 0..len, -1.0..1.0f64),
                0..2 * n,
            ),
        )
            .prop_map(move |(origins, loads, lengths, devs)| Net {
                origins,
                len,
                loads,
                lengths,
                devs,
            })
    })
}

fn build(net: &Net, shift: Vector3<f64>, flip: Option<usize>) -> Topology {
    let id = |t: usize, j: usize| (100 * t + j) as u64;
    let mut b: TopologyBuilder = Topology::builder();
    let mut k = 0;
    for (t, o) in net.origins.iter().enumerate() {
        for j in 0..net.len {
            let p = Vector3::from(*o) + shift + Vector3::new(0.0, 0.0, -(j as f64));
            b = b.node(id(t, j), p.into()).load(id(t, j), net.loads[k]);
            k += 1;
        }
        b = b.support(id(t, net.len - 1));
    }
    let mut e = 0;
    for t in 0..net.origins.len() {
        for j in 0..net.len - 1 {
            let (u, v) = if flip == Some(e) {
                (id(t, j + 1), id(t, j))
            } else {
                (id(t, j), id(t, j + 1))
            };
            b = b.trail_edge(u, v, net.lengths[t * net.len + j]);
            e += 1;
        }
    }
    let mut seen = std::collections::HashSet::new();
    for &(t1, j1, t2, j2, f) in &net.devs {
        let (a, c) = (id(t1, j1), id(t2, j2));
        // Skip self loops, pairs already joined, and trail neighbours (they share a trail edge).
        if a == c || (t1 == t2 && j1.abs_diff(j2) == 1) || !seen.insert((a.min(c), a.max(c))) {
            continue;
        }
        let indirect = j1 != j2;
        let force = if indirect { 0.05 * f } else { 2.0 * f };
        let (u, v) = if flip == Some(e) { (c, a) } else { (a, c) };
        b = b.deviation_edge(u, v, force);
        e += 1;
    }
    b.build().unwrap()
}

const OPTS: SolverOptions = SolverOptions {
    tmax: 2000,
    eta: 1e-12,
};

fn solved(t: &Topology) -> Option<Equilibrium> {
    // Random indirect edges may still fail to contract; those cases are not equilibria to test.
    solve(t, &OPTS).ok()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Every node is in equilibrium: direct-only to rounding (1e-10·scale), with indirect
    /// edges to the convergence level (Σ‖Δx‖ < 1e-12 ⇒ force error ≲ 1e-12·|μ|/ℓ, allow 1e-9·scale).
    #[test]
    fn random_networks_are_in_equilibrium(n in net()) {
        let topo = build(&n, Vector3::zeros(), None);
        let Some(eq) = solved(&topo) else { return Ok(()) };
        let scale = 1.0 + eq.checks.max_abs_force;
        let indirect = eq.deviation_edges.iter().any(|e| !e.direct);
        let tol = if indirect { 1e-9 * scale } else { 1e-10 * scale };
        prop_assert!(eq.checks.max_node_residual <= tol, "residual {}", eq.checks.max_node_residual);
        prop_assert!((eq.checks.sum_loads + eq.checks.sum_reactions).amax() <= tol * eq.nodes.len() as f64);
        for p in eq.force_polygons() {
            prop_assert!(p.closure().amax() <= tol);
        }
    }

    /// Translating every origin by d translates every node by d; forces do not change.
    #[test]
    fn translating_origins_translates_result(n in net(), d in prop::array::uniform3(-10.0..10.0f64)) {
        let d = Vector3::from(d);
        let Some(a) = solved(&build(&n, Vector3::zeros(), None)) else { return Ok(()) };
        let b = solve(&build(&n, d, None), &OPTS).unwrap();
        // Positions are O(10): 1e-9 leaves room for the rounding of x + d along long trails.
        for (x, y) in a.nodes.iter().zip(&b.nodes) {
            prop_assert!((y.xyz - x.xyz - d).amax() <= 1e-9, "{} {:?} {:?}", x.id, x.xyz, y.xyz);
            prop_assert!((y.reaction - x.reaction).amax() <= 1e-9 * (1.0 + x.reaction.amax()));
        }
        for (x, y) in a.trail_edges.iter().zip(&b.trail_edges) {
            prop_assert!((x.force - y.force).abs() <= 1e-9 * (1.0 + x.force.abs()));
        }
    }

    /// Reversing the u/v orientation of any one edge changes nothing.
    #[test]
    fn reversing_an_edge_changes_nothing(n in net(), which in 0usize..64) {
        let a_topo = build(&n, Vector3::zeros(), None);
        let count = a_topo.trail_edges.len() + a_topo.deviation_edges.len();
        let flipped = build(&n, Vector3::zeros(), Some(which % count));
        let Some(a) = solved(&a_topo) else { return Ok(()) };
        let b = solve(&flipped, &OPTS).unwrap();
        for (x, y) in a.nodes.iter().zip(&b.nodes) {
            prop_assert!((x.xyz - y.xyz).amax() <= 1e-12);
            prop_assert!((x.reaction - y.reaction).amax() <= 1e-12 * (1.0 + x.reaction.amax()));
        }
        for (x, y) in a.trail_edges.iter().zip(&b.trail_edges) {
            let other = b.trail_edge(x.u, x.v).unwrap();
            prop_assert!((x.force - other.force).abs() <= 1e-12 * (1.0 + x.force.abs()));
            prop_assert!((x.length.abs() - y.length.abs()).abs() <= 1e-12);
        }
    }
}
