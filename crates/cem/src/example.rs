//! A built-in example topology, embedded in the binary so that `kappe cem solve --example`
//! runs on a fresh machine without any file.

use crate::error::CemError;
use crate::json::{TopologyFile, read_topology};

/// `kappe.cem.topology` text of a 16-node compression arch in the XZ plane: two 7-edge
/// trails (λ = −0.5) from a crown deviation edge (μ = −3), unit loads along −Z on every
/// node except the two supports.
pub const EXAMPLE_ARCH_JSON: &str = include_str!("example_arch.json");

/// The parsed example arch.
pub fn example_arch() -> Result<TopologyFile, CemError> {
    read_topology(EXAMPLE_ARCH_JSON)
}

/// A vault grid like the `vault_grid*` fixtures (cem.md §9): `arches` parallel arches along
/// Y (spacing 0.5), each two compression trails of `nodes_per_trail` nodes (λ = −0.3) from
/// crown origins at (±0.3, y, 5) joined by a crown edge μ = −8; longitudinal direct
/// deviation edges (μ = +0.2) join neighbouring arches at every sequence; gravity
/// (0, 0, −0.1) on every non-support node. Node `j` of side `s` of arch `a` has id
/// `2·n·a + n·s + j` with `n = nodes_per_trail`.
///
/// With `braced`, indirect diagonals (μ = +0.1) join node `j` of one arch to node `j + 1`
/// of the next, on both sides, so the solve iterates.
pub fn vault_grid(arches: usize, nodes_per_trail: usize, braced: bool) -> crate::Topology {
    use crate::topology::{DeviationEdge, Node, Topology, TrailEdge};
    use nalgebra::Vector3;
    let n = nodes_per_trail;
    let id = |a: usize, s: usize, j: usize| (2 * n * a + n * s + j) as u64;
    let mut t = Topology {
        name: format!(
            "vault_grid{}{}",
            2 * n * arches,
            if braced { "_braced" } else { "" }
        ),
        ..Topology::default()
    };
    for a in 0..arches {
        for s in 0..2 {
            let dir = if s == 0 { -1.0 } else { 1.0 };
            for j in 0..n {
                let last = j + 1 == n;
                t.nodes.push(Node {
                    id: id(a, s, j),
                    xyz: Vector3::new(
                        dir * (0.3 + 0.25 * j as f64),
                        0.5 * a as f64,
                        5.0 - 0.2 * j as f64,
                    ),
                    load: if last {
                        Vector3::zeros()
                    } else {
                        Vector3::new(0.0, 0.0, -0.1)
                    },
                    support: last,
                    origin: None,
                });
                if j > 0 {
                    t.trail_edges.push(TrailEdge {
                        u: id(a, s, j - 1),
                        v: id(a, s, j),
                        length: -0.3,
                        plane: None,
                    });
                }
            }
        }
    }
    for a in 0..arches {
        t.deviation_edges.push(DeviationEdge {
            u: id(a, 0, 0),
            v: id(a, 1, 0),
            force: -8.0,
        });
    }
    for a in 0..arches.saturating_sub(1) {
        for s in 0..2 {
            for j in 0..n {
                t.deviation_edges.push(DeviationEdge {
                    u: id(a, s, j),
                    v: id(a + 1, s, j),
                    force: 0.2,
                });
            }
        }
    }
    if braced {
        for a in 0..arches.saturating_sub(1) {
            for s in 0..2 {
                for j in 0..n - 1 {
                    t.deviation_edges.push(DeviationEdge {
                        u: id(a, s, j),
                        v: id(a + 1, s, j + 1),
                        force: 0.1,
                    });
                }
            }
        }
    }
    t
}

/// A tilted arch (method.md §4 shape): two trails of `n` nodes from crown origins at height
/// 0.5, loads (0, w·tan 20°, −w); one crown force and ONE length shared by all trail edges;
/// goals: the feet at (∓0.4, 0, 0). `n ≥ 2` nodes per trail (2·n in all). The crown sits at y = −0.5·tan 20°, so the plane spanned
/// by the x axis and the load direction passes through the feet line: the goals are reachable.
pub fn tilted_arch(n: usize) -> (crate::Topology, crate::Problem) {
    use crate::optimize::{Bounds, Goal, Parameter, ParameterKind, WeightedGoal};
    use nalgebra::Vector3;
    let w = 0.1;
    let tan = 20f64.to_radians().tan();
    let mut b = crate::Topology::builder();
    let id = |s: usize, j: usize| (s * n + j) as u64;
    for s in 0..2 {
        let dir = if s == 0 { -1.0 } else { 1.0 };
        for j in 0..n {
            b = b.node(
                id(s, j),
                [
                    dir * (0.05 + 0.1 * j as f64),
                    -0.5 * tan,
                    0.5 - 0.05 * j as f64,
                ],
            );
            if j + 1 < n {
                b = b.load(id(s, j), [0.0, w * tan, -w]);
                b = b.trail_edge(id(s, j), id(s, j + 1), -0.06);
            } else {
                b = b.support(id(s, j));
            }
        }
    }
    let t = b
        .deviation_edge(id(0, 0), id(1, 0), -1.0)
        .build()
        .expect("the example arch is valid");
    let edges: Vec<(u64, u64)> = t.trail_edges.iter().map(|e| (e.u, e.v)).collect();
    let problem = crate::Problem {
        parameters: vec![
            Parameter::new(
                ParameterKind::DeviationForce(id(0, 0), id(1, 0)),
                Bounds::Absolute {
                    lower: -50.0,
                    upper: -1e-3,
                },
            ),
            Parameter::new(
                ParameterKind::TrailLengths(edges),
                Bounds::Absolute {
                    lower: -0.5,
                    upper: -1e-3,
                },
            ),
        ],
        goals: vec![
            WeightedGoal {
                goal: Goal::Point {
                    node: id(0, n - 1),
                    target: Vector3::new(-0.4, 0.0, 0.0),
                },
                weight: 1.0,
            },
            WeightedGoal {
                goal: Goal::Point {
                    node: id(1, n - 1),
                    target: Vector3::new(0.4, 0.0, 0.0),
                },
                weight: 1.0,
            },
        ],
    };
    (t, problem)
}
