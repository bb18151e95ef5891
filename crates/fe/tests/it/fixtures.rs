//! A2 (executable spec: exact CST+DKT reference factors) and A6 (vault vs CalculiX).

use kappe_fe::{BucklingOptions, ElementKind, buckling};

use crate::common::{load_json, load_mesh, rel};

/// A2: every triangle fixture with a reference entry, λ₁…₃ to 1e-6 relative. The reference
/// is the same element and K_G (Python/scipy, eigsh tol 1e-10), so only round-off and the
/// eigen tolerance separate the two: 1e-6 catches any formula or sign slip.
#[test]
fn a2_reference_factors() {
    let refs = load_json("facet_ref_results.json");
    for name in ["plate_ss_s3_n16", "vault_s3_20x12"] {
        let model = load_mesh(name);
        // Sturm check off: it is exercised in solver_checks; here only the factors matter.
        let r = buckling(
            &model,
            &BucklingOptions {
                sturm_check: false,
                ..Default::default()
            },
        )
        .unwrap();
        let exp = refs["results"][name]["lambda"].as_array().unwrap();
        let ndof = refs["results"][name]["n_free_dof"].as_u64().unwrap() as usize;
        assert_eq!(r.stats.n_free_dofs, ndof, "{name}: free DOFs");
        for (i, e) in exp.iter().enumerate() {
            let e = e.as_f64().unwrap();
            println!("{name} mode {i}: {} vs {e}", r.factors[i]);
            assert!(
                rel(r.factors[i], e) < 1e-6,
                "{name} mode {i}: {} vs {e}",
                r.factors[i]
            );
        }
    }
}

/// The generators reproduce the fixture meshes (same nodes, triangles, supports, loads), so
/// refined meshes built with them are the fixtures' family.
#[test]
fn generators_match_fixtures() {
    let f = load_mesh("vault_s3_20x12");
    let g = kappe_fe::generate::barrel_vault(20, 12);
    assert_eq!(f.triangles, g.triangles);
    assert_eq!(f.fixed_mask(), g.fixed_mask());
    for (a, b) in f.nodes.iter().zip(&g.nodes) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-11, "{a:?} vs {b:?}");
        }
    }
    let f = load_mesh("plate_ss_s3_n16");
    let g = kappe_fe::generate::ss_plate(16);
    assert_eq!(f.triangles, g.triangles);
    assert_eq!(f.fixed_mask(), g.fixed_mask());
    let sum = |m: &kappe_fe::ShellModel| {
        let mut s = vec![[0.0; 3]; m.nodes.len()];
        for l in &m.nodal_loads {
            for c in 0..3 {
                s[l.node][c] += l.force[c];
            }
        }
        s
    };
    assert_eq!(sum(&f), sum(&g));
}

/// A6: vault 20×12 against the converged CalculiX S8R reference (0.068970, 0.16562,
/// 0.26760). Kirchhoff facets vs 3-D solids differ by O(t/L) ≈ 0.5 %; the spec's tolerances
/// at this mesh are 2 % (mode 1), 2.5 % (mode 2), 5 % (mode 3); the finer meshes run in
/// `examples/convergence.rs`.
#[test]
fn a6_vault_vs_calculix() {
    a6_vault(ElementKind::CstDkt);
}

/// A6 with ANDES/OPT+DKT: same reference and tolerances (measured +0.81 / +1.56 / +2.66 % at
/// 20×12; the softer membrane takes 0.3 % off CST+DKT's mode-1 error).
#[test]
fn a6_vault_vs_calculix_andes() {
    a6_vault(ElementKind::AndesDkt);
}

fn a6_vault(element: ElementKind) {
    let exp = load_json("vault_s3_20x12.expected.json");
    let refs: Vec<f64> = exp["reference"]["factors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let mut model = load_mesh("vault_s3_20x12");
    model.element = element;
    let r = buckling(
        &model,
        &BucklingOptions {
            sturm_check: false,
            ..Default::default()
        },
    )
    .unwrap();
    for (i, tol) in [0.02, 0.025, 0.05].into_iter().enumerate() {
        let e = rel(r.factors[i], refs[i]);
        println!(
            "{element:?} mode {i}: {} vs {} ({e})",
            r.factors[i], refs[i]
        );
        assert!(e < tol, "mode {i}: {} vs {} ({e})", r.factors[i], refs[i]);
        // Facets are stiffer than the solid reference: convergence from above.
        assert!(r.factors[i] > refs[i]);
    }
}
