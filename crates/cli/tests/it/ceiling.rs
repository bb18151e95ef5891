//! Issue 15: `kappe design` runs a ceiling file (three bays at a small size) end to end: every
//! bay designed, analysed and planned, a room summary, one page for the room, every bay's report.

use std::process::Output;

use crate::common::{kappe, text};

/// The three-bay room shared with the other ceiling tests.
const SMALL: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../kappe/tests/data/small_room.toml"
));

/// `kappe design room.toml --out room --quiet` and `extra` on the ceiling file `room`, in a fresh
/// temporary directory (kept alive by the returned handle).
fn design_room(room: &str, extra: &[&str]) -> (tempfile::TempDir, Output) {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("room.toml"), room).unwrap();
    let mut args = vec!["design", "room.toml", "--out", "room", "--quiet"];
    args.extend_from_slice(extra);
    let o = kappe(tmp.path(), &args);
    (tmp, o)
}

#[test]
fn design_runs_a_three_bay_ceiling() {
    let (tmp, o) = design_room(SMALL, &["--states", "every:4"]);
    let code = o.status.code().unwrap_or(-1);
    assert!(code == 0 || code == 1, "{}", text(&o.stderr));
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

/// Issue 27: a ceiling with `[robot.base] mode = "moving"` prints each half of a bay in one take
/// with the base moving: both halves get the moving plan's files, and the mirrored half's base
/// creeps toward −y (its front advances that way) while the first half's creeps toward +y.
#[test]
fn moving_base_ceiling_plans_each_half_moving() {
    // One default-size bay (0.8 m span, as the moving default cap) between walls 1 m apart.
    let room = "name = \"moving room\"\n[ceiling]\nlength = 1.0\nends = \"both_walls\"\n\
                rise_ratio = 0.25\n[[bay]]\nspan = 0.8\n[robot.base]\nmode = \"moving\"\n";
    let (tmp, o) = design_room(room, &["--no-buckling", "--allow-fail"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let bay = tmp.path().join("room/bay_1");
    let base_y = |p: &std::path::Path| -> Vec<f64> {
        let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let mut lines = text.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let c = head.iter().position(|h| *h == "base_y").unwrap();
        lines
            .map(|l| l.split(',').nth(c).unwrap().parse().unwrap())
            .collect()
    };
    let first = base_y(&bay.join("base_trajectory.csv"));
    let mirror = base_y(&bay.join("mirror/base_trajectory.csv"));
    // The base travels a few centimetres at least (the centre sections are ≈ 0.36 m long); 1 cm
    // separates a creeping base from one standing still.
    let travel = |v: &[f64]| v.last().unwrap() - v.first().unwrap();
    assert!(travel(&first) > 0.01, "first half: {}", travel(&first));
    assert!(travel(&mirror) < -0.01, "mirror: {}", travel(&mirror));
    for half in ["", "mirror/"] {
        let head = std::fs::read_to_string(bay.join(format!("{half}trajectory.csv"))).unwrap();
        assert!(
            head.lines()
                .next()
                .unwrap()
                .ends_with("base_x,base_y,base_yaw"),
            "{half}trajectory.csv"
        );
        let prog = std::fs::read_to_string(bay.join(format!("{half}program_part01.script")))
            .unwrap_or_else(|e| panic!("{half}program_part01.script: {e}"));
        assert!(prog.contains("track_conveyor_linear"), "{half}");
        // The tracking form passes `kappe robot lint` (issue 27 verification).
        let lint = kappe(
            &bay,
            &["robot", "lint", &format!("{half}program_part01.script")],
        );
        assert!(lint.status.success(), "{}", text(&lint.stdout));
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("room/ceiling.json")).unwrap())
            .unwrap();
    // One take per half: one "station" each, no relocation.
    assert_eq!(summary["bays"][0]["robot"]["stations"], 2);
}
