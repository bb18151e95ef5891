//! Constrained form-finding against `opt_arch_span_rise` (cem.md §10 tolerances), gradient
//! checks against central differences, and restarts.

use kappe_cem::json::read_topology;
use kappe_cem::optimize::Evaluator;
use kappe_cem::{Bounds, Goal, OptimizeOptions, ParameterKind, Problem, Topology, optimize};
use nalgebra::Vector3;

use crate::common::{close_rel, f, read_expected, read_input, v3};

fn fixture(name: &str) -> (Topology, Problem, OptimizeOptions) {
    let file = read_topology(&read_input(name)).unwrap();
    let (p, o) = Problem::from_json(file.optimization.as_ref().unwrap()).unwrap();
    (file.topology, p, o)
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(f).collect()
}

#[test]
fn objective_and_gradient_at_x0_match_reference() {
    let (t, p, o) = fixture("opt_arch_span_rise");
    let exp = read_expected("opt_arch_span_rise")["optimization"].clone();
    let ev = Evaluator::new(&t, &p, &o).unwrap();
    assert_eq!(ev.x0(), floats(&exp["x0"]).as_slice());
    let (lo, hi) = ev.bounds();
    assert_eq!(lo, floats(&exp["bounds_low"]).as_slice());
    assert_eq!(hi, floats(&exp["bounds_up"]).as_slice());
    let (f0, g0) = ev.objective_and_gradient(ev.x0()).unwrap();
    // Objective at x0: rel 1e-9 (deterministic, no optimizer involved).
    let fe = f(&exp["objective_at_x0"]);
    assert!(((f0 - fe) / fe).abs() <= 1e-9, "{f0} vs {fe}");
    // Gradient: rel+abs 1e-6 against autograd (autograd ≈ central differences to ~1e-9).
    for (g, ge) in g0.iter().zip(floats(&exp["gradient_at_x0"])) {
        assert!(close_rel(*g, ge, 1e-6), "{g} vs {ge}");
    }
}

/// Forward-mode gradient vs central differences h = 1e-6 at a few points: the truncation
/// error is O(h²·f''') ≈ 1e-12 and the rounding error O(ε·f/h) ≈ 1e-9, so 1e-6 rel+abs.
#[test]
fn dual_gradient_matches_central_differences() {
    let (t, p, o) = fixture("opt_arch_span_rise");
    let ev = Evaluator::new(&t, &p, &o).unwrap();
    for scale in [1.0, 0.8, 1.2] {
        let x: Vec<f64> = ev.x0().iter().map(|v| v * scale).collect();
        let (_, g) = ev.objective_and_gradient(&x).unwrap();
        for j in 0..x.len() {
            let h = 1e-6;
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[j] += h;
            xm[j] -= h;
            let fd = (ev.objective(&xp).unwrap() - ev.objective(&xm).unwrap()) / (2.0 * h);
            assert!(
                close_rel(g[j], fd, 1e-6),
                "scale {scale} j {j}: {} vs {fd}",
                g[j]
            );
        }
    }
}

#[test]
fn opt_arch_span_rise_reaches_reference_optimum() {
    let (t, p, o) = fixture("opt_arch_span_rise");
    let exp = read_expected("opt_arch_span_rise");
    let r = optimize(&t, &p, &o).unwrap();
    assert!(r.converged, "{:?}", r.status);
    // Own final objective ≤ 1e-12 (targets met to ~1e-6 length units).
    assert!(r.objective_at_x_opt <= 1e-12, "{}", r.objective_at_x_opt);
    // x_opt rel+abs 1e-6 (unique optimum).
    for (x, xe) in r.x_opt.iter().zip(floats(&exp["optimization"]["x_opt"])) {
        assert!(close_rel(*x, xe, 1e-6), "{x} vs {xe}");
    }
    // Final positions abs 1e-6.
    for n in exp["nodes"].as_array().unwrap() {
        let id = n["id"].as_u64().unwrap();
        let d = (r.equilibrium.position(id).unwrap() - v3(&n["xyz"])).amax();
        assert!(d <= 1e-6, "node {id}: {d}");
    }
    assert_eq!(r.goals.len(), 2);
    assert!(r.goals.iter().all(|g| g.error.abs() <= 1e-6));
}

#[test]
fn perturbed_starts_converge_to_the_same_optimum() {
    let (t, p, o) = fixture("opt_arch_span_rise");
    let reference = optimize(&t, &p, &o).unwrap();
    for factor in [0.6, 1.4] {
        let ev = Evaluator::new(&t, &p, &o).unwrap();
        let x: Vec<f64> = ev.x0().iter().map(|v| v * factor).collect();
        let t2 = ev.topology_at(&t, &x);
        let r = optimize(&t2, &p, &o).unwrap();
        assert!(
            r.objective_at_x_opt <= 1e-12,
            "×{factor}: {}",
            r.objective_at_x_opt
        );
        for (a, b) in r.x_opt.iter().zip(&reference.x_opt) {
            assert!(close_rel(*a, *b, 1e-6), "×{factor}: {a} vs {b}");
        }
    }
}

#[test]
fn shared_length_tilted_arch_hits_span_and_rise() {
    let (t, p) = kappe_cem::example::tilted_arch(20);
    let r = optimize(&t, &p, &OptimizeOptions::default()).unwrap();
    assert!(
        r.converged && r.objective_at_x_opt <= 1e-12,
        "{:?} {}",
        r.status,
        r.objective_at_x_opt
    );
    // All trail edges got the same length, and the realized lengths equal it.
    let s = r.x_opt[1];
    for e in &r.equilibrium.trail_edges {
        assert!((e.length - s).abs() <= 1e-9, "{} vs {s}", e.length);
    }
    // The feet lie on the targets to 1e-6 (√1e-12).
    assert!((r.equilibrium.position(19).unwrap() - Vector3::new(-0.4, 0.0, 0.0)).amax() <= 1e-6);
}

#[test]
fn bad_problems_are_typed_errors() {
    let (t, p, o) = fixture("opt_arch_span_rise");
    let with = |f: &dyn Fn(&mut Problem)| {
        let mut q = p.clone();
        f(&mut q);
        Evaluator::new(&t, &q, &o).map(|_| ()).unwrap_err()
    };
    assert_eq!(with(&|q| q.parameters.clear()).kind(), "invalid_problem");
    assert_eq!(
        with(&|q| q.parameters[0].kind = ParameterKind::DeviationForce(0, 99)).kind(),
        "unknown_edge"
    );
    assert_eq!(
        with(&|q| q.parameters[1].kind = ParameterKind::TrailLength(0, 8)).kind(),
        "unknown_edge"
    );
    assert_eq!(
        with(&|q| q.parameters[0].bounds = Bounds::Absolute {
            lower: 1.0,
            upper: 0.0
        })
        .kind(),
        "invalid_problem"
    );
    assert_eq!(with(&|q| q.goals[0].weight = 0.0).kind(), "invalid_problem");
    assert_eq!(
        with(&|q| q.goals[0].weight = -1.0).kind(),
        "invalid_problem"
    );
    assert_eq!(
        with(&|q| q.goals[0].goal = Goal::Point {
            node: 99,
            target: Vector3::zeros()
        })
        .kind(),
        "unknown_node"
    );
    assert_eq!(
        with(&|q| q.goals[0].goal = Goal::Point {
            node: 7,
            target: Vector3::new(f64::NAN, 0.0, 0.0)
        })
        .kind(),
        "non_finite"
    );
    assert_eq!(
        with(&|q| q.parameters[0].kind = ParameterKind::OriginZ(3)).kind(),
        "invalid_problem"
    );
}
