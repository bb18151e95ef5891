//! Solver checks: A8 Sturm count, A9 residuals, A10 invariances, A11 scaling, A12 dense
//! cross-check, repeated eigenvalues, solver reuse.

use kappe_fe::oracle::dense_buckling_factors;
use kappe_fe::{BucklingOptions, BucklingSolver, NodalLoad, ShellModel, Support, buckling};
use nalgebra::{Rotation3, Vector3};

use crate::common::rel;

fn opts(modes: usize) -> BucklingOptions {
    BucklingOptions {
        modes,
        ..Default::default()
    }
}

/// Without the Sturm check, for tests whose subject is not the check (keeps the debug-build
/// test run short; the check is exercised in `a8_a9_*` and `repeated_*`).
fn fast(modes: usize) -> BucklingOptions {
    BucklingOptions {
        modes,
        sturm_check: false,
        ..Default::default()
    }
}

/// A8 + A9 on the coarse member of the vault fixture family: Sturm count at 1.0001·λ₁ is exactly 1 (nothing below λ₁
/// was missed), the solver's own check agrees, and every mode satisfies the pencil to
/// ‖(K + λK_G)φ‖/‖Kφ‖ ≤ 1e-6.
#[test]
fn a8_a9_sturm_and_residual() {
    let m = kappe_fe::generate::barrel_vault(10, 6);
    let solver = BucklingSolver::new(&m).unwrap();
    let r = solver.buckling(&m, &opts(3)).unwrap();
    let c = r.sturm.unwrap();
    assert_eq!(c.negative_pivots, c.found_below);
    assert_eq!(c.negative_pivots, 3);
    assert_eq!(
        solver
            .count_factors_below(&m, 1.0001 * r.factors[0])
            .unwrap(),
        1
    );
    assert_eq!(
        solver
            .count_factors_below(&m, 0.9999 * r.factors[0])
            .unwrap(),
        0
    );
    for (i, res) in r.residuals.iter().enumerate() {
        assert!(*res <= 1e-6, "mode {i}: residual {res}");
    }
    assert!(r.factors.windows(2).all(|w| w[0] <= w[1]));
}

/// A12: the sparse Lanczos path against the dense pencil (faer Cholesky + symmetric
/// eigensolver) on a coarse vault (≈ 500 DOF): 1e-8 relative on the three lowest factors.
#[test]
fn a12_dense_cross_check() {
    for m in [
        kappe_fe::generate::barrel_vault(10, 6),
        kappe_fe::generate::ss_plate(8),
    ] {
        let dense = dense_buckling_factors(&m).unwrap();
        let r = buckling(&m, &opts(3)).unwrap();
        for i in 0..3 {
            assert!(
                rel(r.factors[i], dense[i]) < 1e-8,
                "mode {i}: {} vs {}",
                r.factors[i],
                dense[i]
            );
        }
    }
}

/// Repeated eigenvalues: square SS plate under equal biaxial compression; the (1,2) and
/// (2,1) modes coincide (the mesh is symmetric under x ↔ y). When the requested count cuts
/// the pair, the Sturm check must detect the second copy and the deflated restart find it.
/// Checked against the dense pencil (1e-8).
#[test]
fn repeated_factors_found_via_sturm() {
    let mut m = kappe_fe::generate::ss_plate(8);
    // Add N_y = 1 N/m on y = 0 and y = a (same consistent nodal forces as N_x).
    let n = 8;
    let h = 1.0 / n as f64;
    for i in 0..=n {
        let w = if i == 0 || i == n { 0.5 * h } else { h };
        m.nodal_loads.push(NodalLoad {
            node: i,
            force: [0.0, w, 0.0],
            moment: [0.0; 3],
        });
        m.nodal_loads.push(NodalLoad {
            node: n * (n + 1) + i,
            force: [0.0, -w, 0.0],
            moment: [0.0; 3],
        });
    }
    // In-plane support: fix ux at (0, mid) too so the biaxial state is statically determinate.
    m.supports.push(Support {
        node: n / 2,
        fixed: [true, false, false, false, false, false],
    });
    let dense = dense_buckling_factors(&m).unwrap();
    assert!(
        rel(dense[1], dense[2]) < 1e-9,
        "expected a double factor: {dense:?}"
    );
    // Asking for 2 modes cuts the count inside the double factor: Lanczos returns one copy,
    // the Sturm count at 1.0001·λ₂ is 3, and the deflated restart must find the other copy.
    let two = buckling(&m, &opts(2)).unwrap();
    let c = two.sturm.unwrap();
    assert_eq!((c.negative_pivots, c.found_below), (3, 3));
    assert!(rel(two.factors[1], dense[1]) < 1e-8);
    let r = buckling(&m, &opts(3)).unwrap();
    for i in 0..3 {
        assert!(
            rel(r.factors[i], dense[i]) < 1e-8,
            "mode {i}: {:?} vs {:?}",
            r.factors,
            &dense[..3]
        );
    }
}

fn transformed(m: &ShellModel, rot: &Rotation3<f64>, shift: [f64; 3]) -> ShellModel {
    let mut t = m.clone();
    for p in &mut t.nodes {
        let v = rot * Vector3::from(*p);
        *p = [v[0] + shift[0], v[1] + shift[1], v[2] + shift[2]];
    }
    let g = rot * Vector3::from(m.gravity);
    t.gravity = [g[0], g[1], g[2]];
    t
}

/// A10: rigid rotation + translation (gravity rotated along), node renumbering and reversing
/// every triangle give the same λ₁…₃ to 1e-8 (only round-off and the 1e-10 eigen tolerance
/// differ); drilling α ∈ [1e-6, 1e-2] moves λ₁ by < 0.1 % (measured 0.03 % in the spec).
#[test]
fn a10_invariances() {
    // The coarse member of the fixture family keeps the debug-build test quick.
    let m = kappe_fe::generate::barrel_vault(10, 6);
    let base = buckling(&m, &fast(3)).unwrap().factors;
    let check = |other: &ShellModel, what: &str| {
        let f = buckling(other, &fast(3)).unwrap().factors;
        for i in 0..3 {
            assert!(
                rel(f[i], base[i]) < 1e-8,
                "{what} mode {i}: {} vs {}",
                f[i],
                base[i]
            );
        }
    };
    check(
        &transformed(
            &m,
            &Rotation3::from_euler_angles(0.4, -1.1, 2.3),
            [3.0, -7.0, 11.0],
        ),
        "rigid motion",
    );
    // Renumber nodes: reverse order.
    let nn = m.nodes.len();
    let mut r = m.clone();
    r.nodes = m.nodes.iter().rev().copied().collect();
    r.triangles = m.triangles.iter().map(|t| t.map(|i| nn - 1 - i)).collect();
    r.supports = m
        .supports
        .iter()
        .map(|s| Support {
            node: nn - 1 - s.node,
            fixed: s.fixed,
        })
        .collect();
    check(&r, "renumbering");
    // Reverse every triangle (consistent flip of all normals).
    let mut f = m.clone();
    f.triangles = m.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
    check(&f, "orientation flip");
    // Mixed orientation (every third triangle reversed) is rejected by default and, when
    // allowed, gives the same factors.
    let mut mixed = m.clone();
    for (e, t) in mixed.triangles.iter_mut().enumerate() {
        if e % 3 == 0 {
            *t = [t[0], t[2], t[1]];
        }
    }
    assert!(matches!(
        buckling(&mixed, &fast(1)),
        Err(kappe_fe::FeError::InvertedTriangle { .. })
    ));
    mixed.allow_mixed_orientation = true;
    check(&mixed, "mixed orientation");
    for alpha in [1e-6, 1e-2] {
        let mut a = m.clone();
        a.drilling_alpha = alpha;
        let l = buckling(&a, &fast(1)).unwrap().factors[0];
        assert!(rel(l, base[0]) < 1e-3, "alpha {alpha}: {l} vs {}", base[0]);
    }
}

/// A11: λ(2E) = 2λ(E) and λ(2γ) = λ(γ)/2 (K ∝ E, K_G independent of E; K_G ∝ γ), 1e-10.
#[test]
fn a11_scaling() {
    let m = kappe_fe::generate::barrel_vault(10, 6);
    let base = buckling(&m, &fast(2)).unwrap().factors;
    let mut e2 = m.clone();
    e2.materials[0].youngs_modulus *= 2.0;
    let mut g2 = m.clone();
    g2.materials[0].unit_weight *= 2.0;
    let fe = buckling(&e2, &fast(2)).unwrap().factors;
    let fg = buckling(&g2, &fast(2)).unwrap().factors;
    for i in 0..2 {
        assert!(rel(fe[i], 2.0 * base[i]) < 1e-10);
        assert!(rel(fg[i], 0.5 * base[i]) < 1e-10);
    }
}

/// A cached solver reused for another print state (other E and thickness, same mesh) gives
/// the same factors as a fresh solve, and refuses a model with other supports.
#[test]
fn solver_reuse_and_pattern_mismatch() {
    let m = kappe_fe::generate::barrel_vault(10, 6);
    let solver = BucklingSolver::new(&m).unwrap();
    let mut s2 = m.clone();
    s2.thickness = (0..m.triangles.len())
        .map(|e| 0.02 + 0.0001 * e as f64)
        .collect();
    s2.materials[0].youngs_modulus = 3.0e6;
    let a = solver.buckling(&s2, &opts(2)).unwrap().factors;
    let b = buckling(&s2, &opts(2)).unwrap().factors;
    assert!(rel(a[0], b[0]) < 1e-10 && rel(a[1], b[1]) < 1e-10);
    let mut s3 = m.clone();
    s3.supports.pop();
    assert!(matches!(
        solver.buckling(&s3, &opts(1)),
        Err(kappe_fe::FeError::PatternMismatch { .. })
    ));
}

/// A pure tension load has no positive factor: the result is empty, not an error or a
/// negative "factor".
#[test]
fn tension_only_gives_no_factor() {
    let mut m = kappe_fe::generate::ss_plate(6);
    for l in &mut m.nodal_loads {
        l.force[0] = -l.force[0];
    }
    let r = buckling(&m, &opts(2)).unwrap();
    assert!(r.factors.is_empty(), "{:?}", r.factors);
}

/// Restarted Lanczos (basis capped at 8 vectors, so several restarts with locking are
/// needed) gives the same factors as the dense pencil (1e-8): the path large models take.
#[test]
fn restarted_lanczos_matches_dense() {
    let m = kappe_fe::generate::barrel_vault(8, 5);
    let dense = dense_buckling_factors(&m).unwrap();
    let r = buckling(
        &m,
        &BucklingOptions {
            modes: 3,
            max_basis: 8,
            ..Default::default()
        },
    )
    .unwrap();
    for i in 0..3 {
        assert!(
            rel(r.factors[i], dense[i]) < 1e-8,
            "mode {i}: {:?} vs {:?}",
            r.factors,
            &dense[..3]
        );
    }
    assert!(r.stats.operator_applications > 8);
}

/// The analysis engineer runs print states in parallel: solver, model and results must be
/// shareable across threads.
#[test]
fn types_are_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<BucklingSolver>();
    check::<ShellModel>();
    check::<kappe_fe::BucklingResult>();
    check::<kappe_fe::FeError>();
}

/// The second load case of `buckling_with_weight_case` (the self-weight of some triangles
/// alone, solved with the buckling solve's factor of K) is the linear static solution of the
/// model with the other triangles' unit weight zeroed: the same K, pattern, ordering and
/// right-hand side, so the same bits. Its own buckling result is the plain solve's. A weight
/// mask of the wrong length is a named error.
#[test]
fn the_weight_case_is_the_static_solution_of_that_weight_alone() {
    let m = kappe_fe::generate::barrel_vault(10, 6);
    let n_el = m.triangles.len();
    // The half of the elements with the larger index: a load that is not a multiple of the
    // whole self-weight, so a solve of the wrong right-hand side cannot pass.
    let mask: Vec<bool> = (0..n_el).map(|e| e >= n_el / 2).collect();
    let solver = BucklingSolver::new(&m).unwrap();
    let (r, case) = solver
        .buckling_with_weight_case(&m, &fast(1), &mask)
        .unwrap();
    let mut only = m.clone();
    only.materials = (0..n_el)
        .map(|e| {
            let mut mat = m.material_of(e);
            if !mask[e] {
                mat.unit_weight = 0.0;
            }
            mat
        })
        .collect();
    let own = kappe_fe::linear_static(&only).unwrap();
    assert_eq!(case, own);
    let plain = solver.buckling(&m, &fast(1)).unwrap();
    assert_eq!(r.factors, plain.factors);
    assert_eq!(r.static_result, plain.static_result);
    // Not the whole weight's solution: about half the load.
    let ratio = case.load_sum[2] / r.static_result.load_sum[2];
    assert!(ratio > 0.3 && ratio < 0.7, "{ratio}");
    assert!(matches!(
        solver.buckling_with_weight_case(&m, &fast(1), &mask[1..]),
        Err(kappe_fe::FeError::BadOption { .. })
    ));
}

/// A nodal-load case of `buckling_with_cases` (the corrugation's bending load, issue 26) is the
/// linear static solution of the model without gravity under those nodal loads alone, bit for
/// bit (same K, ordering and right-hand side); two cases in one call are each their own
/// stand-alone solution; a load on a node the model does not have is a named error.
#[test]
fn a_nodal_load_case_is_the_static_solution_of_those_loads_alone() {
    use kappe_fe::{LoadCase, NodalLoad};
    let m = kappe_fe::generate::barrel_vault(10, 6);
    let n_el = m.triangles.len();
    let n = m.nodes.len();
    // Loads on a few interior nodes in three directions, with a moment: a right-hand side
    // unlike the self-weight's, so solving the wrong one cannot pass.
    let loads: Vec<NodalLoad> = [n / 3, n / 2, 2 * n / 3]
        .iter()
        .enumerate()
        .map(|(i, &node)| NodalLoad {
            node,
            force: [1.0 + i as f64, -2.0, 0.5 * i as f64],
            moment: [0.0, 0.01 * i as f64, 0.0],
        })
        .collect();
    let bending = LoadCase {
        weight: Vec::new(),
        nodal_loads: loads.clone(),
    };
    let mask: Vec<bool> = (0..n_el).map(|e| e % 3 == 0).collect();
    let weight = LoadCase {
        weight: mask.clone(),
        nodal_loads: Vec::new(),
    };
    let solver = BucklingSolver::new(&m).unwrap();
    let (r, cases) = solver
        .buckling_with_cases(&m, &fast(1), &[bending, weight])
        .unwrap();
    let mut alone = m.clone();
    alone.gravity = [0.0; 3];
    alone.nodal_loads = loads;
    assert_eq!(cases[0], kappe_fe::linear_static(&alone).unwrap());
    let mut part = m.clone();
    part.materials = (0..n_el)
        .map(|e| {
            let mut mat = m.material_of(e);
            if !mask[e] {
                mat.unit_weight = 0.0;
            }
            mat
        })
        .collect();
    assert_eq!(cases[1], kappe_fe::linear_static(&part).unwrap());
    assert_eq!(
        r,
        solver
            .buckling(&m, &fast(1))
            .map(|mut p| {
                // The solve's timings differ run to run; everything else is the same.
                p.stats = r.stats;
                p
            })
            .unwrap()
    );
    let bad = LoadCase {
        weight: Vec::new(),
        nodal_loads: vec![NodalLoad {
            node: n,
            force: [1.0, 0.0, 0.0],
            moment: [0.0; 3],
        }],
    };
    assert!(solver.buckling_with_cases(&m, &fast(1), &[bad]).is_err());
}

/// `buckling_with_derived_cases` (kappe's buckling sensitivities, issue 24): a case made from
/// the pre-buckling static solution — here a load proportional to its displacements, as the
/// sensitivity load −(∂K/∂p)·u is — is the linear static solution of the model without gravity
/// under that load alone, bit for bit (same K, ordering and right-hand side), and the buckling
/// result is the plain solve's.
#[test]
fn a_derived_case_is_the_static_solution_of_its_loads_alone() {
    use kappe_fe::{LoadCase, NodalLoad, StaticResult};
    let m = kappe_fe::generate::barrel_vault(10, 6);
    let solver = BucklingSolver::new(&m).unwrap();
    let make = |st: &StaticResult| -> Vec<NodalLoad> {
        st.displacements
            .iter()
            .enumerate()
            .filter(|(_, d)| d.iter().any(|v| *v != 0.0))
            .map(|(node, d)| NodalLoad {
                node,
                force: [1e3 * d[0], -2e3 * d[1], 1e3 * d[2]],
                moment: [0.0, 1e2 * d[4], 0.0],
            })
            .collect()
    };
    let cases = |st: &StaticResult| {
        vec![LoadCase {
            weight: Vec::new(),
            nodal_loads: make(st),
        }]
    };
    let (r, solved) = solver
        .buckling_with_derived_cases(&m, &fast(1), &cases)
        .unwrap();
    let loads = make(&r.static_result);
    assert!(!loads.is_empty(), "the static solution has no displacement");
    let mut alone = m.clone();
    alone.gravity = [0.0; 3];
    alone.nodal_loads = loads;
    assert_eq!(solved, vec![kappe_fe::linear_static(&alone).unwrap()]);
    let plain = solver.buckling(&m, &fast(1)).unwrap();
    assert_eq!(r.factors, plain.factors);
    assert_eq!(r.static_result, plain.static_result);
}
