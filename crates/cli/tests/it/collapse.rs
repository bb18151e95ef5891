//! `kappe buildability` with `[analysis.nonlinear]` (docs/collapse.md).

use std::process::Command;

fn kappe() -> Command {
    Command::new(env!("CARGO_BIN_EXE_kappe"))
}

/// The Wolfs cylinder of `kappe init --kind buildability`, coarsened (24 segments, 6 layers) to
/// keep the test quick, with `[analysis.nonlinear]`.
fn spec(dir: &std::path::Path, checks: &str, nonlinear: &str) -> std::path::PathBuf {
    let init = dir.join("init.toml");
    let o = kappe()
        .args(["init", "--force", "--kind", "buildability"])
        .arg(&init)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&init)
        .unwrap()
        .replace("# segments = 48", "segments = 24")
        .replace("max_layers = 60", "max_layers = 6")
        .replace(
            "stop_at_failure = true",
            &format!("stop_at_failure = true\n{checks}"),
        );
    let path = dir.join("spec.toml");
    std::fs::write(
        &path,
        format!("{text}\n[analysis.nonlinear]\n{nonlinear}\n"),
    )
    .unwrap();
    path
}

#[test]
fn buildability_reports_the_collapse_factor_of_every_layer_count() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "", "");
    let out = dir.path().join("out");
    let o = kappe()
        .arg("buildability")
        .arg(&s)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("collapse"), "{text}");
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("buildability.json")).unwrap()).unwrap();
    let states = doc["result"]["states"].as_array().unwrap();
    assert_eq!(states.len(), 6);
    for st in states {
        let c = st["collapse_factor"].as_f64().unwrap();
        // Six 10 mm layers of the Wolfs mix stand (the linear checks: BLF and 1/u ≫ 1).
        assert!(c > 1.0, "{st}");
        assert!(st["collapse_mode"].is_string(), "{st}");
        // The rule: w0 = t/20 = 2 mm for a 40 mm wall this low.
        assert_eq!(st["collapse"]["w0"].as_f64(), Some(0.002));
    }
    assert!(doc["failure_layer"].is_null());
}

#[test]
fn collapse_below_collapse_min_is_the_failure_mode() {
    let dir = tempfile::tempdir().unwrap();
    let s = spec(dir.path(), "collapse_min = 1e6", "material = false");
    let out = dir.path().join("out");
    let o = kappe()
        .args(["buildability", "--quiet"])
        .arg(&s)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("buildability.json")).unwrap()).unwrap();
    assert_eq!(doc["failure_layer"].as_u64(), Some(1));
    assert_eq!(doc["failure_mode"].as_str(), Some("collapse"));
}

#[test]
fn bad_nonlinear_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for (nonlinear, field) in [
        ("imperfection = -0.001", "analysis.nonlinear.imperfection"),
        ("base = \"hinged\"", "base"),
    ] {
        let s = spec(dir.path(), "", nonlinear);
        let out = dir.path().join("out");
        let o = kappe()
            .args(["buildability", "--quiet"])
            .arg(&s)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{nonlinear}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(field), "{nonlinear}: {err}");
        assert!(!out.exists());
    }
}
