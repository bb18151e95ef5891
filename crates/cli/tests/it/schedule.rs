//! Issue 11: the print schedule of `kappe design` — the `[schedule]` waits become pauses in the
//! robot programs, and `schedule.csv` / `summary.json` carry the plan's layer times.

use std::process::Command;

#[test]
fn design_waits_reach_the_programs_and_the_schedule() {
    let tmp = tempfile::tempdir().unwrap();
    let wait = 7.0;
    std::fs::write(
        tmp.path().join("w.toml"),
        format!("[cap]\nlength = 0.15\n[schedule]\nwait = {wait}\n"),
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_kappe"))
        .current_dir(tmp.path())
        .args(["design", "w.toml", "--out", "o", "--quiet", "--no-buckling"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = tmp.path().join("o");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let layers = summary["counts"]["layers"].as_u64().unwrap() as usize;
    assert_eq!(summary["schedule"]["source"], "robot_plan");

    let csv = std::fs::read_to_string(out.join("schedule.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("layer,start_s,end_s,wait_s,relocation_s")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), layers);
    for (k, w) in rows.windows(2).enumerate() {
        // Every layer waits the scheduled time (CSV has 3 decimals), and the next layer starts
        // no earlier than the end of this one plus its wait.
        assert!((w[0][3] - wait).abs() < 1e-3, "layer {k}: wait {}", w[0][3]);
        assert!(
            w[1][1] >= w[0][2] + wait - 1e-3,
            "layer {k}: {:?} → {:?}",
            w[0],
            w[1]
        );
    }
    // The same waits are pauses in the programs the operator runs.
    let mut sleeps = 0;
    for e in std::fs::read_dir(&out).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "script") {
            let text = std::fs::read_to_string(&p).unwrap();
            sleeps += text.matches(&format!("sleep({wait:.6})")).count();
        }
    }
    assert!(
        sleeps >= layers - 1,
        "{sleeps} pauses of {wait} s for {layers} layers"
    );
    // One clock: the summary's print time spans the layers' times (first start to last end) on
    // the plan's clock (3-decimal CSV; the approach before the first layer is not counted).
    let total = summary["print_time_s"].as_f64().unwrap();
    assert!(total >= rows[layers - 1][2] - rows[0][1] - 1e-3, "{total}");
}
