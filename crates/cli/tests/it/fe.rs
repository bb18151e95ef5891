//! `kappe fe buckle` / `kappe fe static` end to end on the shared fixtures: output fields,
//! factors against the exact CST+DKT reference, and bad input (non-zero exit, message, no
//! output file).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const KAPPE: &str = env!("CARGO_BIN_EXE_kappe");

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/fixtures/fe")
        .join(name)
}

fn kappe(args: &[&str]) -> Output {
    Command::new(KAPPE).args(args).output().unwrap()
}

fn read_json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// Factors equal the exact reference of this element (facet_ref_results.json) to 1e-6, the
/// static block balances (reactions = −load to round-off), the Sturm count agrees.
#[test]
fn buckle_vault_fixture() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("vault.json");
    let mesh = fixture("vault_s3_20x12.mesh.json");
    let o = kappe(&[
        "fe",
        "buckle",
        mesh.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--modes",
        "3",
        "--mode-shapes",
        // The exact reference factors are CST+DKT's; the command's default is ANDES+DKMT.
        "--element",
        "cst",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = read_json(&out);
    let refs = read_json(&fixture("facet_ref_results.json"));
    let exp = refs["results"]["vault_s3_20x12"]["lambda"]
        .as_array()
        .unwrap();
    let got = r["factors"].as_array().unwrap();
    assert_eq!(got.len(), 3);
    for (g, e) in got.iter().zip(exp) {
        let (g, e) = (g.as_f64().unwrap(), e.as_f64().unwrap());
        assert!((g - e).abs() < 1e-6 * e, "{g} vs {e}");
    }
    assert_eq!(r["dofs"].as_u64(), Some(1560));
    let rz = r["static"]["reactions_sum"][2].as_f64().unwrap();
    let lz = r["static"]["load_sum"][2].as_f64().unwrap();
    assert!((rz + lz).abs() < 1e-9 * lz.abs());
    assert!(r["static"]["max_displacement"].as_f64().unwrap() > 0.0);
    assert!(r["time_s"].as_f64().unwrap() >= 0.0);
    assert_eq!(r["sturm"]["negative_pivots"].as_u64(), Some(3));
    let modes = r["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 3);
    assert_eq!(modes[0].as_array().unwrap().len(), 273);
}

#[test]
fn static_plate_fixture() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plate.json");
    let mesh = fixture("plate_ss_s3_n16.mesh.json");
    let o = kappe(&[
        "fe",
        "static",
        mesh.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        // CST's membrane reproduces N_x = −1 exactly; that is what this test checks.
        "--element",
        "cst",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = read_json(&out);
    assert_eq!(r["displacements"].as_array().unwrap().len(), 289);
    let els = r["elements"].as_array().unwrap();
    assert_eq!(els.len(), 512);
    // Uniform edge compression N_x = −1 N/m: every element carries N_x ≈ −1 in its frame
    // when its first edge is along x (CST is exact for this constant state up to the
    // point supports' round-off).
    let nx: Vec<f64> = els
        .iter()
        .filter(|e| e["frame"][0][0].as_f64().unwrap() > 0.999)
        .map(|e| e["membrane_force"][0].as_f64().unwrap())
        .collect();
    assert!(!nx.is_empty());
    for n in nx {
        assert!((n + 1.0).abs() < 1e-6, "N_x = {n}");
    }
}

/// A mechanism: non-zero exit, the message names the failure, no output file is left.
#[test]
fn mechanism_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("mech.json");
    std::fs::write(
        &mesh,
        r#"{"nodes": [[0,0,0],[1,0,0],[1,1,0],[0,1,0]], "triangles": [[0,1,2],[0,2,3]],
            "thickness": 0.01, "E": 1e6, "nu": 0.3, "gamma": 2e4,
            "supports": {"ux": [0], "uy": [0], "uz": [0]}}"#,
    )
    .unwrap();
    let out = dir.path().join("out.json");
    let o = kappe(&[
        "fe",
        "buckle",
        mesh.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("structure is a mechanism"), "{err}");
    assert!(!out.exists());
}

/// Invalid input names the element (inverted triangle) and the field (negative thickness).
#[test]
fn bad_mesh_messages() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("bad.json");
    std::fs::write(
        &mesh,
        r#"{"nodes": [[0,0,0],[1,0,0],[1,1,0],[0,1,0]], "triangles": [[0,1,2],[0,3,2]],
            "thickness": 0.01, "E": 1e6, "nu": 0.3, "supports": {"ux": [0,1], "uy": [0,1], "uz": [0,1]}}"#,
    )
    .unwrap();
    let o = kappe(&["fe", "static", mesh.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("triangle 1 is inverted"));
    std::fs::write(
        &mesh,
        r#"{"nodes": [[0,0,0],[1,0,0],[1,1,0]], "triangles": [[0,1,2]],
            "thickness": -0.01, "E": 1e6, "nu": 0.3}"#,
    )
    .unwrap();
    let o = kappe(&["fe", "buckle", mesh.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("thickness[0] = -0.01"));
}

/// The default element of `kappe fe` is ANDES+DKMT (issue 17): on the vault fixture it is
/// closer to CalculiX's converged S8R factor 0.068970 than CST+DKT (+0.48 % against +1.14 % at
/// this 20×12 mesh, crates/fe README); checked as "below CST+DKT's exact factor, within 1 % of
/// S8R".
#[test]
fn buckle_defaults_to_the_shear_deformable_element() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("vault.json");
    let mesh = fixture("vault_s3_20x12.mesh.json");
    let o = kappe(&[
        "fe",
        "buckle",
        mesh.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = read_json(&out);
    assert_eq!(r["solver"]["element_kind"].as_str(), Some("andes_dkmt"));
    let got = r["factors"][0].as_f64().unwrap();
    let refs = read_json(&fixture("facet_ref_results.json"));
    let cst = refs["results"]["vault_s3_20x12"]["lambda"][0]
        .as_f64()
        .unwrap();
    assert!(got < cst, "{got} vs CST+DKT {cst}");
    assert!((got / 0.068970 - 1.0).abs() < 0.01, "{got}");
}
