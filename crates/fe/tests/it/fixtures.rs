//! A2 (executable spec: exact CST+DKT reference factors) and A6 (vault vs CalculiX).

use kappe_fe::{BucklingOptions, buckling};

use crate::common::{load_json, load_mesh, rel};

/// A2: every triangle fixture with a reference entry, λ₁…₃ to 1e-6 relative. The reference
/// is the same element and K_G (Python/scipy, eigsh tol 1e-10), so only round-off and the
/// eigen tolerance separate the two: 1e-6 catches any formula or sign slip.
#[test]
fn a2_reference_factors() {
    let refs = load_json("facet_ref_results.json");
    for name in ["plate_ss_s3_n16", "vault_s3_20x12"] {
        let model = load_mesh(name);
        let r = buckling(&model, &BucklingOptions::default()).unwrap();
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
