//! `kappe buildability` end to end through the binary (issue 11): a short wall is written with
//! its failure layer and schedule; bad input names the field, exits 2 and writes nothing.

use std::process::Command;

fn kappe() -> Command {
    Command::new(env!("CARGO_BIN_EXE_kappe"))
}

const WALL: &str = "[object]\nkind = \"wall\"\nlength = 0.2\nwidth = 0.04\nlayer_height = 0.01\n\
    max_layers = 40\nsegments = 4\n[process]\nlayer_time = 10.0\n[material]\n\
    specific_weight = 20000.0\npoisson_ratio = 0.0\n[material.time]\nmodel = \"linear\"\n\
    youngs_modulus = 1.0e9\ncompressive_strength = 3033.0\ncompressive_strength_rate = 10.0\n";

#[test]
fn buildability_writes_failure_and_schedule() {
    let dir = tempfile::tempdir().unwrap();
    let spec = dir.path().join("wall.toml");
    std::fs::write(&spec, WALL).unwrap();
    let out = dir.path().join("out");
    let o = kappe()
        .args(["buildability", "--quiet"])
        .arg(&spec)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("buildability.json")).unwrap()).unwrap();
    // The plastic-collapse closed form (green_state.rs) puts the failure at layer 30 or 31
    // (centroid stress within 2 % of γ(n − ½)h); the mode is strength (E is huge).
    let n = json["failure_layer"].as_u64().unwrap();
    assert!((30..=31).contains(&n), "failure layer {n}");
    assert_eq!(json["failure_mode"], "strength");
    let states = json["result"]["states"].as_array().unwrap();
    assert_eq!(states.len() as u64, n);
    assert!(states[0]["blf"].is_number() && states[0]["strength_utilisation"].is_number());
    let csv = std::fs::read_to_string(out.join("schedule.csv")).unwrap();
    assert!(csv.starts_with("layer,start_s,end_s,wait_s"));
    assert_eq!(csv.lines().count() as u64, n + 1);
}

#[test]
fn buildability_bad_input_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for (bad, field) in [
        (
            WALL.replace(
                "compressive_strength_rate = 10.0",
                "compressive_strength_rate = -1.0",
            ),
            "material.time.compressive_strength_rate",
        ),
        (
            WALL.replace("layer_time = 10.0", "layer_time = 10.0\nwait = -5.0"),
            "process.wait",
        ),
    ] {
        let spec = dir.path().join("bad.toml");
        std::fs::write(&spec, bad).unwrap();
        let out = dir.path().join("out");
        let o = kappe()
            .args(["buildability", "--quiet"])
            .arg(&spec)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&o.stderr).contains(field));
        assert!(!out.exists());
    }
}
