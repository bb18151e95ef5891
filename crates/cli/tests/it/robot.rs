//! `kappe robot plan/check/lint/resume/ik` end to end on a small synthetic print: outputs, exit
//! codes (0 ok, 1 fails its check, 2 bad input) and nothing written on bad input.

use std::path::Path;

use crate::common::{kappe, text};
use kappe_robot::synthetic::cap_path;

/// 4 layers of 12 points of the synthetic cap and a config with the base fixed in front of it
/// (as the robot crate's own tests), ≤ 30 targets per program (so two files).
fn setup(dir: &Path) {
    let layers = cap_path(0.8, 0.2, 25.0, 0.008, 4, 12);
    let mut csv = String::from("layer,index,x,y,z,tx,ty,tz\n");
    for l in &layers {
        for p in &l.points {
            let [x, y, z] = p.position;
            let [tx, ty, tz] = p.axis;
            csv += &format!("{},{},{x},{y},{z},{tx},{ty},{tz}\n", l.layer, p.index);
        }
    }
    std::fs::write(dir.join("path.csv"), csv).unwrap();
    let setup = kappe_robot::synthetic::fixed_base_setup();
    let config = serde_json::json!({
        "setup": setup,
        "options": { "program": { "max_moves_per_program": 30 } }
    });
    std::fs::write(dir.join("config.json"), config.to_string()).unwrap();
}

#[test]
fn plan_check_lint_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    setup(d);
    let o = kappe(
        d,
        &[
            "robot",
            "plan",
            "path.csv",
            "--out",
            "r",
            "--config",
            "config.json",
        ],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.starts_with("planned 48 waypoints in 4 layers from 1 station(s): "),
        "{out}"
    );
    assert!(out.contains("2 program(s) → r"), "{out}");
    assert!(
        text(&o.stderr).starts_with("clearance to the environment: arm capsules "),
        "{}",
        text(&o.stderr)
    );
    let mut names: Vec<String> = std::fs::read_dir(d.join("r"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.'))
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "plan.json",
            "program_part01.script",
            "program_part02.script",
            "programs.json",
            "trajectory.csv"
        ]
    );

    let o = kappe(d, &["robot", "check", "r/plan.json"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert_eq!(text(&o.stderr), "plan OK: 48 waypoints verified\n");
    let rep: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(rep["problems"], serde_json::json!([]));

    let files = ["r/program_part01.script", "r/program_part02.script"];
    let o = kappe(d, &["robot", "lint", files[0], files[1]]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stdout));
    assert_eq!(text(&o.stdout).matches(": OK (").count(), 2);
    let o = kappe(d, &["robot", "lint", files[0], "--max-targets", "10"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stdout).contains("more than the limit 10"));
    // Joint limits from a config: a base joint held to ±1° rejects the programs' movej.
    let mut cfg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("config.json")).unwrap()).unwrap();
    cfg["options"]["limits"] = serde_json::json!({ "position_deg": [
        [-1.0, 1.0], [-360.0, 360.0], [-180.0, 180.0], [-360.0, 360.0], [-360.0, 360.0], [-360.0, 360.0]
    ]});
    std::fs::write(d.join("narrow.json"), cfg.to_string()).unwrap();
    let o = kappe(d, &["robot", "lint", files[0], "--config", "narrow.json"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stdout).contains("joint 1") && text(&o.stdout).contains("beyond its limits"),
        "{}",
        text(&o.stdout)
    );

    let o = kappe(d, &["robot", "resume", "r", "--from-layer", "2"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).starts_with("resume from layer 2: 24 waypoints, "),
        "{}",
        text(&o.stdout)
    );
    assert!(d.join("r/resume_from_layer_2/plan.json").exists());
    let o = kappe(
        d,
        &["robot", "resume", "r", "--from-layer", "99", "--out", "x"],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("layer 99 is not in the plan"));
    assert!(!d.join("x").exists());
}

#[test]
fn bad_input_is_named_exits_2_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    setup(d);
    let plan = |path: &str, config: &str| {
        kappe(
            d,
            &["robot", "plan", path, "--out", "o", "--config", config],
        )
    };
    std::fs::write(d.join("header.csv"), "layer,idx,x\n1,2,3\n").unwrap();
    std::fs::write(
        d.join("row.csv"),
        "layer,index,x,y,z,tx,ty,tz\n0,0,1,2,3,0,0,1\n0,x,1,2,3,0,0,1\n",
    )
    .unwrap();
    let mut cfg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("config.json")).unwrap()).unwrap();
    cfg["options"]["limits"] = serde_json::json!({ "position_deg": [
        [-360.0, 360.0], [-360.0, 360.0], [90.0, -90.0], [-360.0, 360.0], [-360.0, 360.0], [-360.0, 360.0]
    ]});
    std::fs::write(d.join("limits.json"), cfg.to_string()).unwrap();
    for (o, want) in [
        (
            plan("header.csv", "config.json"),
            "header is \"layer,idx,x\"",
        ),
        (
            plan("row.csv", "config.json"),
            "row.csv line 3: index \"x\"",
        ),
        (plan("path.csv", "path.csv"), "invalid config path.csv"),
        (
            plan("path.csv", "limits.json"),
            "invalid joint position limit of joint 3: [90, -90]°",
        ),
    ] {
        assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
        assert!(text(&o.stderr).contains(want), "{}", text(&o.stderr));
        assert!(!d.join("o").exists());
    }
    std::fs::write(d.join("poses.json"), "{\"nope\": 1}").unwrap();
    let o = kappe(d, &["robot", "ik", "poses.json"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
}
