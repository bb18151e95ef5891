//! `kappe design` / `kappe init` end to end through the binary.

use std::process::Command;

fn kappe() -> Command {
    Command::new(env!("CARGO_BIN_EXE_kappe"))
}

#[test]
fn design_writes_every_output_and_init_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("d.toml");
    let st = kappe().arg("init").arg(&toml).status().unwrap();
    assert!(st.success());
    // A short cap keeps the test quick.
    let text = std::fs::read_to_string(&toml)
        .unwrap()
        .replace("length = 0.6 ", "length = 0.1 ");
    std::fs::write(&toml, text).unwrap();
    let out = dir.path().join("out");
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "summary.json",
        "network.json",
        "path.csv",
        "cap.obj",
        "cap.glb",
    ] {
        assert!(out.join(f).metadata().unwrap().len() > 0, "{f} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let layers = summary["counts"]["layers"].as_u64().unwrap();
    assert_eq!(summary["states"].as_array().unwrap().len() as u64, layers);
    assert_eq!(summary["design"]["cap"]["length"].as_f64(), Some(0.1));
    let csv = std::fs::read_to_string(out.join("path.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("layer,index,x,y,z,tx,ty,tz"));
    assert_eq!(
        csv.lines().count() as u64 - 1,
        summary["counts"]["path_points"].as_u64().unwrap()
    );
    // init refuses to overwrite.
    assert!(!kappe().arg("init").arg(&toml).status().unwrap().success());
}

#[test]
fn bad_design_names_the_field_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("bad.toml");
    std::fs::write(&toml, "[cap]\ntilt_deg = 80\n").unwrap();
    let out = dir.path().join("out");
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("cap.tilt_deg") && err.contains("60"), "{err}");
    assert!(!out.exists(), "partial output left behind");
    // Unknown field.
    std::fs::write(&toml, "[cap]\nspann = 1\n").unwrap();
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("spann"));
    assert!(!out.exists());
    // Only the temp-dir prefix could be left; nothing else appears next to `out`.
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "{leftovers:?}");
}
