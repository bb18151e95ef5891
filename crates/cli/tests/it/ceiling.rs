//! Issue 15: `kappe design` runs a ceiling file (three bays at a small size) end to end: every
//! bay designed, analysed and planned, a room summary, one page for the room, every bay's report.

use std::process::Command;

/// The three-bay room shared with the other ceiling tests.
const SMALL: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../kappe/tests/data/small_room.toml"
));

#[test]
fn design_runs_a_three_bay_ceiling() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("room.toml"), SMALL).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_kappe"))
        .current_dir(tmp.path())
        .args([
            "design",
            "room.toml",
            "--out",
            "room",
            "--quiet",
            "--states",
            "every:4",
        ])
        .output()
        .unwrap();
    let code = o.status.code().unwrap_or(-1);
    assert!(
        code == 0 || code == 1,
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = tmp.path().join("room");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("ceiling.json")).unwrap()).unwrap();
    let bays = summary["bays"].as_array().unwrap();
    assert_eq!(bays.len(), 3);
    let index = std::fs::read_to_string(out.join("index.html")).unwrap();
    for n in 1..=3 {
        let bay = out.join(format!("bay_{n}"));
        assert!(index.contains(&format!("bay_{n}/report.html")));
        assert!(bay.join("report.html").is_file());
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(bay.join("summary.json")).unwrap()).unwrap();
        // Every state analysed, and the verdict the room summary shows is the bay's own.
        assert_eq!(
            s["states"].as_array().unwrap().len() as u64,
            s["counts"]["layers"].as_u64().unwrap()
        );
        assert_eq!(bays[n - 1]["ok"].as_bool(), s["ok"].as_bool());
        // A passing bay gets its robot programs, for both halves.
        if s["ok"] == serde_json::json!(true) {
            assert!(bay.join("programs.json").is_file(), "bay {n}");
            assert!(bay.join("mirror/programs.json").is_file(), "bay {n} mirror");
        }
    }
    assert_eq!(
        code == 0,
        bays.iter().all(|b| b["ok"] == serde_json::json!(true))
    );
}
