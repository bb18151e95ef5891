//! Issue 28: the robot operator's day. Each test covers one defect of the issue and failed
//! before the fix: resume of a failing design (1), the base tolerance in the verdict (2), the
//! cost guard (3), resume outputs kept (4), marked programs (5), `kappe schedule` (6), exit
//! statuses and messages (8), wording (9). Defect 7 (Python) is in python/tests/test_operator.py.

use crate::common::{kappe, text};
use std::path::Path;
use std::process::Command;

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// A short cap (0.1 m: about 56 print states) whose compressive limit of 5 kPa the start
/// sections exceed (about 15 kPa): it fails sigma_min, and plans quickly.
const FAILING: &str = "[cap]\nlength = 0.1\n[constraints]\nsigma_min = -5000.0\n";
/// A cap of 0.15 m with the default limits: it passes (at 0.1 m its start layers overhang
/// 10.2 mm, over the 10 mm limit).
const PASSING: &str = "[cap]\nlength = 0.15\n";

fn scripts(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".script"))
        .collect();
    v.sort();
    v
}

fn first_layer(plan: &Path) -> i64 {
    json(plan)["stations"][0]["layers"][0]["layer"]
        .as_i64()
        .unwrap()
}

#[test]
fn resume_refuses_a_failing_design_and_marks_its_programs() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("f.toml"), FAILING).unwrap();
    let o = kappe(
        d,
        &["design", "f.toml", "--out", "o", "--quiet", "--no-buckling"],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(
        scripts(&d.join("o")).is_empty(),
        "no programs for a failing design"
    );
    let k = first_layer(&d.join("o/plan.json"));
    let from = k.to_string();

    // Defect 1: no programs through the back door, and nothing written.
    let o = kappe(d, &["robot", "resume", "o", "--from-layer", &from]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("fails its checks") && err.contains("--allow-fail"),
        "{err}"
    );
    assert!(!d.join(format!("o/resume_from_layer_{k}")).exists());

    // Defect 9: a layer outside the plan gives the range in words, not Rust's `a..=b`.
    let o = kappe(
        d,
        &[
            "robot",
            "resume",
            "o",
            "--from-layer",
            "9999",
            "--allow-fail",
        ],
    );
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!err.contains("..=") && err.contains(" to "), "{err}");

    // With --allow-fail they are written, and every one says what it is (defect 5).
    let o = kappe(
        d,
        &[
            "robot",
            "resume",
            "o",
            "--from-layer",
            &from,
            "--allow-fail",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let rdir = d.join(format!("o/resume_from_layer_{k}"));
    let names = scripts(&rdir);
    assert!(!names.is_empty());
    for n in &names {
        let t = std::fs::read_to_string(rdir.join(n)).unwrap();
        let title = t.lines().next().unwrap();
        assert!(
            title.contains(&format!("RESUME FROM LAYER {k}")),
            "{n}: {title}"
        );
        assert!(title.contains("FAILING DESIGN"), "{n}: {title}");
        assert!(t.contains("# WARNING: the design FAILS its checks"), "{n}");
        assert!(t.contains("docs/operator.md"), "{n}: no link to the guide");
        let def = t.lines().find(|l| l.starts_with("def ")).unwrap();
        assert!(
            def.contains("_resume_") && def.contains("_failing"),
            "{n}: {def}"
        );
    }
    let index = json(&rdir.join("programs.json"));
    for p in index["programs"].as_array().unwrap() {
        assert!(
            p["failing_design"].as_str().unwrap().contains("sigma_min"),
            "{p}"
        );
        assert_eq!(p["resumed_from_layer"], k);
        assert!(p["title"].as_str().unwrap().contains("FAILING DESIGN"));
        assert!(p["station"].as_u64().unwrap() >= 1, "stations count from 1");
    }

    // Defect 5: `kappe design --allow-fail` marks its programs the same way.
    let o = kappe(
        d,
        &[
            "design",
            "f.toml",
            "--out",
            "a",
            "--quiet",
            "--no-buckling",
            "--allow-fail",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let names = scripts(&d.join("a"));
    assert!(!names.is_empty());
    for n in &names {
        let t = std::fs::read_to_string(d.join("a").join(n)).unwrap();
        let title = t.lines().next().unwrap();
        assert!(
            title.contains("FAILING DESIGN") && !title.contains("RESUME"),
            "{n}: {title}"
        );
        let def = t.lines().find(|l| l.starts_with("def ")).unwrap();
        assert!(def.ends_with("_failing():"), "{n}: {def}");
    }
    let index = json(&d.join("a/programs.json"));
    assert!(index["programs"][0]["failing_design"].is_string());
}

#[test]
fn the_default_design_survives_its_base_tolerance_and_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let o = kappe(d, &["design", "--out", "o", "--no-buckling"]);
    let out = text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}\n{}", text(&o.stderr));
    // Defect 2: the terminal, the summary and the report say it.
    assert!(
        out.contains("base tolerance: the plan survives a base up to ±10.0 mm, ±1.0° off"),
        "{out}"
    );
    let s = json(&d.join("o/summary.json"));
    let t = &s["robot"]["base_tolerance"];
    assert_eq!(t["ok"], true, "{t}");
    assert_eq!(
        t["in_verdict"], true,
        "a failing check must fail the design"
    );
    let report = std::fs::read_to_string(d.join("o/report.html")).unwrap();
    assert!(report.contains("base_tolerance"));
    // Stations count from 1 in programs.json.
    let index = json(&d.join("o/programs.json"));
    let stations: Vec<u64> = index["programs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["station"].as_u64().unwrap())
        .collect();
    assert_eq!(stations.first(), Some(&1), "{stations:?}");
    // Defect 9: the constraint rows in the user's units; an all-compression arch shows no
    // tension (roundoff of ~1e-9 Pa printed as 0.00 kPa).
    assert!(out.contains("limit -20.00 kPa"), "{out}");
    assert!(!out.contains("e4 Pa"), "{out}");
    let sigma_max = out.lines().find(|l| l.contains("sigma_max")).unwrap();
    assert!(sigma_max.contains("worst 0.00 kPa"), "{sigma_max}");
    let tension = out
        .lines()
        .find(|l| l.contains("max tension stress"))
        .unwrap();
    assert!(
        tension.contains("[kPa]") && tension.trim_end().ends_with(" 0.00"),
        "{tension}"
    );
}

#[test]
fn a_plan_that_does_not_survive_its_tolerance_fails_with_the_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // 0.4 m and 20°: far more than any base placement between these beams can absorb (at
    // 0.15 m this short cap is still reachable).
    std::fs::write(
        d.join("t.toml"),
        format!("{PASSING}[robot.tolerance]\nposition = 0.4\nyaw_deg = 20.0\n"),
    )
    .unwrap();
    let o = kappe(d, &["design", "t.toml", "--out", "o", "--no-buckling"]);
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    assert!(
        out.contains("base tolerance: FAILS at ±400.0 mm, ±20.0°"),
        "{out}"
    );
    assert!(
        err.contains("does not survive a base placed up to ±400.0 mm"),
        "{err}"
    );
    assert!(scripts(&d.join("o")).is_empty(), "no programs");
    let s = json(&d.join("o/summary.json"));
    let problems = s["robot"]["base_tolerance"]["problems"].as_array().unwrap();
    assert!(!problems.is_empty());
    for p in problems {
        let p = p.as_str().unwrap();
        assert!(!p.starts_with("station 0"), "stations count from 1: {p}");
    }
}

#[test]
fn costly_or_impossible_settings_are_refused_up_front() {
    for (toml, field, allowed) in [
        (
            "[print]\npath_sampling = 1e-7\n",
            "print.path_sampling",
            "10.0 mm",
        ),
        (
            "[print]\npath_sampling = 0.001\n",
            "print.path_sampling",
            "10.0 mm",
        ),
        (
            "[robot.plan.program]\nmax_moves_per_program = 0\n",
            "robot.plan.program.max_moves_per_program",
            "at least 4",
        ),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("c.toml"), toml).unwrap();
        let o = kappe(d, &["design", "c.toml", "--out", "o", "--quiet"]);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{toml}: {err}");
        assert!(
            err.contains(field) && err.contains(allowed),
            "{toml}: {err}"
        );
        assert!(!d.join("o").exists(), "nothing written");
    }
}

#[test]
fn a_new_design_run_keeps_the_resume_programs_of_the_previous_one() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("p.toml"), PASSING).unwrap();
    let run = || {
        kappe(
            d,
            &["design", "p.toml", "--out", "o", "--quiet", "--no-buckling"],
        )
    };
    let o = run();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let k = first_layer(&d.join("o/plan.json")) + 1;
    let o = kappe(d, &["robot", "resume", "o", "--from-layer", &k.to_string()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let name = format!("resume_from_layer_{k}");
    let before = crate::common::tree(&d.join("o").join(&name));
    assert!(!before.is_empty());
    // Defect 4: the rerun replaced the output but moved the resume programs aside, with a word.
    let o = run();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains(&name) && err.contains("aside"), "{err}");
    let kept = d.join("o.old-1").join(&name);
    assert_eq!(
        crate::common::tree(&kept),
        before,
        "every file kept, byte for byte"
    );
    assert!(!d.join("o").join(&name).exists());
}

/// A resumed plan's new motions (the approach, the re-cut programs) are re-checked against the
/// base tolerance the design was checked with (`summary.json`): the passing design's resume
/// survives ±10 mm, ±1°; with the summary's tolerance raised to ±300 mm (the base would stand
/// in the beams) the resume is refused with the reason and nothing is written, unless
/// `--allow-fail`.
#[test]
fn resume_rechecks_the_base_tolerance() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("p.toml"), PASSING).unwrap();
    let o = kappe(
        d,
        &["design", "p.toml", "--out", "o", "--quiet", "--no-buckling"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let k = (first_layer(&d.join("o/plan.json")) + 1).to_string();
    let resume = |out: &str, extra: &[&str]| {
        let mut args = vec!["robot", "resume", "o", "--from-layer", &k, "--out", out];
        args.extend_from_slice(extra);
        kappe(d, &args)
    };
    let o = resume("r1", &[]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("resumed plan survives a base up to ±10.0 mm"),
        "{err}"
    );

    let path = d.join("o/summary.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    v["robot"]["base_tolerance"]["position_m"] = serde_json::json!(0.3);
    std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
    let o = resume("r2", &[]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("does not survive a base ±300.0 mm") && err.contains("--allow-fail"),
        "{err}"
    );
    assert!(!d.join("r2").exists(), "nothing written");
    let o = resume("r3", &["--allow-fail"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("warning: the resumed plan does not survive"),
        "{err}"
    );
    assert!(!scripts(&d.join("r3")).is_empty());
}

/// `[robot.tolerance] margins = true`: every station's largest base error is in the summary
/// and on the station sheet, and since the plan survives the stated box, each is at least 1×
/// that box (a station that did not would fail the design).
#[test]
fn station_margins_reach_the_summary_and_the_sheet() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let design = format!("{PASSING}[robot.tolerance]\nmargins = true\n");
    std::fs::write(d.join("p.toml"), design).unwrap();
    let o = kappe(
        d,
        &["design", "p.toml", "--out", "o", "--quiet", "--no-buckling"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("o/summary.json")).unwrap()).unwrap();
    let stations = v["robot"]["stations"].as_array().unwrap().len();
    let m = v["robot"]["base_tolerance"]["margins"].as_array().unwrap();
    assert_eq!(m.len(), stations);
    let sheet = std::fs::read_to_string(d.join("o/stations.md")).unwrap();
    for (i, s) in m.iter().enumerate() {
        assert_eq!(s["station"], i + 1);
        let scale = s["scale"].as_f64().unwrap();
        assert!((1.0..=4.0).contains(&scale), "{s}");
        assert!((s["position_m"].as_f64().unwrap() - 0.01 * scale).abs() < 1e-12);
    }
    assert_eq!(sheet.matches("takes up to").count(), stations, "{sheet}");
}

/// The small cap of the green-state tests (34 states) with a Mohr–Coulomb cohesion of
/// `cohesion` Pa growing by 20 Pa/s.
fn cap_design(cohesion: f64) -> String {
    format!(
        "[cap]\nlength = 0.1\nspan = 0.3\n[analysis]\nrow_stride = 2\n[material.time]\n\
         model = \"linear\"\nyoungs_modulus = 5.0e6\nyoungs_modulus_rate = 2000.0\n\
         cohesion = {cohesion:.1}\ncohesion_rate = 20.0\nfriction_angle_deg = 20.0\n"
    )
}

#[test]
fn schedule_says_infeasible_plainly_and_needs_a_time_model() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // Defect 6: no time model, no search (it used to print one zero wait per layer).
    std::fs::write(d.join("plain.toml"), PASSING).unwrap();
    let o = kappe(d, &["schedule", "plain.toml", "--out", "s"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("[material.time]"), "{err}");
    assert!(!d.join("s").exists());

    // c₀ = 0.4 kPa: the youngest layers (age 0, which no wait ages) already fail.
    std::fs::write(d.join("weak.toml"), cap_design(400.0)).unwrap();
    let o = kappe(d, &["schedule", "weak.toml"]);
    let out = text(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("INFEASIBLE:"), "{out}");
    assert!(!out.contains("Some("), "no Rust debug values: {out}");
    assert!(
        !out.contains("waits = ["),
        "no waits recommended when none helps: {out}"
    );
    // One line per state that needed a wait, plus a fixed summary: not one line per failing
    // state (the small cap has 34).
    let json_o = kappe(d, &["schedule", "weak.toml", "--json"]);
    let plan: serde_json::Value = serde_json::from_slice(&json_o.stdout).unwrap();
    let binding = plan["plan"]["binding"].as_array().unwrap().len();
    assert!(out.lines().count() <= binding + 8, "{out}");
}

#[test]
fn unreadable_inputs_exit_2_and_say_why() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("bin.toml"), [0xff_u8, 0xfe, 0x00, 0x81]).unwrap();
    for (args, why) in [
        (vec!["design", "bin.toml", "--out", "o"], "not UTF-8"),
        (vec!["design", "missing.toml", "--out", "o"], "no such file"),
        (vec!["schedule", "missing.toml"], "no such file"),
        (vec!["study", "bin.toml", "--out", "o"], "not UTF-8"),
        (vec!["cem", "solve", "bin.toml"], "not UTF-8"),
        (vec!["robot", "check", "missing.json"], "no such file"),
    ] {
        let o = kappe(d, &args);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(why), "{args:?}: {err}");
        assert!(!d.join("o").exists());
    }
}

#[test]
fn ctrl_c_says_what_happened() {
    let tmp = tempfile::tempdir().unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_kappe"))
        .current_dir(tmp.path())
        .args(["design", "--out", "o", "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Long enough for the handler to be installed (the first thing main does); the default
    // design runs for many seconds, so the signal arrives mid-run.
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let k = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let o = child.wait_with_output().unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(!tmp.path().join("o").exists(), "nothing put in place");
}

#[test]
fn a_lost_race_on_one_output_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("o");
    let prepared = kappe::output::prepare_dir(&target, false, "test").unwrap();
    prepared
        .write(&[kappe::output::OutputFile::new("a.txt", "mine")])
        .unwrap();
    // Another run puts its output in place first.
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("theirs.txt"), "theirs").unwrap();
    let err = prepared.commit().unwrap_err().to_string();
    assert!(err.contains("another run"), "{err}");
    assert_eq!(
        std::fs::read_to_string(target.join("theirs.txt")).unwrap(),
        "theirs"
    );
    assert!(!target.join("a.txt").exists());
}

#[test]
fn messages_speak_toml_not_rust() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for (toml, bad) in [("cap = 1\n", "struct"), ("[cap\nspan = 1\n", ": :")] {
        std::fs::write(d.join("w.toml"), toml).unwrap();
        let o = kappe(d, &["design", "w.toml", "--out", "o"]);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{toml}: {err}");
        assert!(!err.contains(bad), "{toml}: {err}");
    }
    std::fs::write(d.join("w.toml"), "cap = 1\n").unwrap();
    let o = kappe(d, &["design", "w.toml", "--out", "o"]);
    assert!(text(&o.stderr).contains("a table"), "{}", text(&o.stderr));
}

#[test]
fn the_operators_guide_commands_run() {
    let guide = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/operator.md"
    ))
    .unwrap();
    let mut commands = Vec::new();
    let mut in_sh = false;
    for line in guide.lines().map(str::trim) {
        if line.starts_with("```") {
            in_sh = line == "```sh";
        } else if in_sh && line.starts_with("kappe ") {
            commands.push(line.to_string());
        }
    }
    assert!(commands.len() >= 3, "{commands:?}");
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // The designer's output the guide starts from (a short passing cap, quick to plan).
    std::fs::write(d.join("p.toml"), PASSING).unwrap();
    let o = kappe(
        d,
        &[
            "design",
            "p.toml",
            "--out",
            "out",
            "--quiet",
            "--no-buckling",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_kappe")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for c in &commands {
        let o = Command::new("sh")
            .current_dir(d)
            .env("PATH", &path)
            .args(["-c", c])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{c}: {}", text(&o.stderr));
    }
    // The resume the guide shows wrote where the guide says.
    assert!(
        d.join("out/resume_from_layer_12/resume_part01.script")
            .is_file()
    );
}
