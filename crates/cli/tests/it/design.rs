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
        .replace("length = 0.6 ", "length = 0.15 ");
    std::fs::write(&toml, text).unwrap();
    let out = dir.path().join("out");
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        // Buckling of every 4th state keeps the debug-build test quick; all states are the default.
        .args(["--states", "every:4"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "summary.json",
        "network.json",
        "path.csv",
        "cap.obj",
        "cap.glb",
        "trajectory.csv",
        "plan.json",
        "programs.json",
        "program_part01.script",
        "report.html",
    ] {
        assert!(out.join(f).metadata().unwrap().len() > 0, "{f} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let layers = summary["counts"]["layers"].as_u64().unwrap();
    assert_eq!(summary["states"].as_array().unwrap().len() as u64, layers);
    assert_eq!(summary["design"]["cap"]["length"].as_f64(), Some(0.15));
    let csv = std::fs::read_to_string(out.join("path.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("layer,index,x,y,z,tx,ty,tz"));
    assert_eq!(
        csv.lines().count() as u64 - 1,
        summary["counts"]["path_points"].as_u64().unwrap()
    );
    check_trajectory_against_path(&out, &summary);
    // The verdict and the constraint report are in the summary.
    assert_eq!(summary["ok"], serde_json::json!(true));
    let names: Vec<&str> = summary["constraints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    for n in ["sigma_min", "sigma_max", "blf_min", "overhang_max"] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
    assert!(
        summary["states"]
            .as_array()
            .unwrap()
            .iter()
            .any(|s| s["blf"].as_f64().is_some_and(|b| b > 1.0))
    );
    // init refuses to overwrite.
    assert!(!kappe().arg("init").arg(&toml).status().unwrap().success());
}

/// Run `kappe design` on `text`; it must fail with every `needle` in its message and write nothing.
fn rejects(text: &str, needles: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("bad.toml");
    std::fs::write(&toml, text).unwrap();
    let out = dir.path().join("out");
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success(), "{text:?} was accepted");
    let err = String::from_utf8_lossy(&o.stderr);
    for n in needles {
        assert!(err.contains(n), "{text:?}: {n:?} not in {err}");
    }
    assert!(!out.exists(), "partial output left behind");
    // Nothing but the design file is left in the folder (no temp directories either).
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn bad_design_names_the_field_and_writes_nothing() {
    rejects("[cap]\ntilt_deg = 80\n", &["cap.tilt_deg", "60"]);
    rejects("[cap]\nspann = 1\n", &["spann", "did you mean `span`"]);
    rejects(
        "[print]\nlayer_height = 0.03\n",
        &["print.layer_height", "d_n"],
    );
    rejects("[cap]\nrise = 0.01\n", &["cap.rise", "rise/span"]);
}

type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn mat(v: &serde_json::Value) -> M4 {
    let mut m = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            m[i][j] = v[i][j].as_f64().unwrap();
        }
    }
    m
}

/// UR10e forward kinematics written here from the standard DH table (robot.md §1), independent
/// of kappe-robot: base → flange.
fn fk(q: &[f64; 6]) -> M4 {
    let d = [0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655];
    let a = [0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0];
    let alpha = [
        std::f64::consts::FRAC_PI_2,
        0.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_2,
        0.0,
    ];
    let mut t: M4 = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    for i in 0..6 {
        let (st, ct) = q[i].sin_cos();
        let (sa, ca) = alpha[i].sin_cos();
        let a_i: M4 = [
            [ct, -st * ca, st * sa, a[i] * ct],
            [st, ct * ca, -ct * sa, a[i] * st],
            [0.0, sa, ca, d[i]],
            [0.0, 0.0, 0.0, 1.0],
        ];
        t = mul(&t, &a_i);
    }
    t
}

/// Every print waypoint's TCP lies on its path.csv target (≤ 1e-6 m) with the tool z axis along
/// the target axis (≤ 1e-6 rad): the acceptance check of issue 7.
fn check_trajectory_against_path(out: &std::path::Path, summary: &serde_json::Value) {
    let robot = &summary["robot"];
    assert_eq!(
        robot["ok"],
        serde_json::json!(true),
        "robot not planned: {robot}"
    );
    let flange_from_tcp = mat(&robot["flange_from_tcp"]);
    let stations: Vec<M4> = robot["stations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| mat(&s["world_from_base"]))
        .collect();
    let path = std::fs::read_to_string(out.join("path.csv")).unwrap();
    let mut targets = std::collections::HashMap::new();
    for line in path.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let v: Vec<f64> = f[2..8].iter().map(|x| x.parse().unwrap()).collect();
        targets.insert((f[0].to_string(), f[1].to_string()), v);
    }
    let traj = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    // Rows where the robot holds (priming, pauses) repeat their waypoint at the departure time,
    // so distinct (layer, index) pairs are counted.
    let mut checked = std::collections::HashSet::new();
    for line in traj.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let Some(t) = targets.get(&(f[1].to_string(), f[2].to_string())) else {
            continue;
        };
        let station: usize = f[0].parse().unwrap();
        let q: Vec<f64> = f[4..10].iter().map(|x| x.parse().unwrap()).collect();
        let world_from_tcp = mul(
            &mul(
                &stations[station],
                &fk(&[q[0], q[1], q[2], q[3], q[4], q[5]]),
            ),
            &flange_from_tcp,
        );
        let pos_err = ((world_from_tcp[0][3] - t[0]).powi(2)
            + (world_from_tcp[1][3] - t[1]).powi(2)
            + (world_from_tcp[2][3] - t[2]).powi(2))
        .sqrt();
        let cos =
            world_from_tcp[0][2] * t[3] + world_from_tcp[1][2] * t[4] + world_from_tcp[2][2] * t[5];
        assert!(pos_err <= 1e-6, "TCP {pos_err:e} m off target at {line}");
        assert!(
            cos.clamp(-1.0, 1.0).acos() <= 1e-6,
            "tool axis off at {line}"
        );
        checked.insert((f[1].to_string(), f[2].to_string()));
    }
    assert_eq!(
        checked.len(),
        targets.len(),
        "not every path point has a waypoint"
    );
}

/// A cheap design (3 centre layers of 15 mm, 13 states) that fails by stress: σ_min = −12 kPa
/// against ~15.4 kPa of arch compression at the springing.
const FAILING: &str = "[cap]\nlength = 0.05\n[print]\nlayer_height = 0.015\n\
                       [constraints]\nsigma_min = -12e3\noverhang_max = 0.03\n[analysis]\nstates = \"every:1000\"\n";

fn scripts(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("program") && n.ends_with(".script"))
        .collect();
    v.sort();
    v
}

#[test]
fn a_failing_design_writes_its_report_but_no_robot_program_unless_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("fail.toml");
    std::fs::write(&toml, FAILING).unwrap();
    let out = dir.path().join("out");
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.join("report.html").is_file());
    assert!(scripts(&out).is_empty(), "{:?}", scripts(&out));
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["ok"], false);
    assert_eq!(
        s["robot"]["planned"], true,
        "the plan itself succeeds: {}",
        s["robot"]
    );
    assert_eq!(s["robot_programs_written"], false);
    assert!(
        s["robot_programs_why"]
            .as_str()
            .unwrap()
            .contains("--allow-fail"),
        "{}",
        s["robot_programs_why"]
    );
    // One print time: the plan's, in the summary and on the robot line.
    let plan_time = s["robot"]["total_time_s"].as_f64().unwrap();
    assert_eq!(s["print_time_s"].as_f64(), Some(plan_time));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let minutes = format!("{:.1}", plan_time / 60.0);
    let table_line = stdout
        .lines()
        .find(|l| l.contains("print time [min]"))
        .unwrap();
    assert!(table_line.ends_with(&minutes), "{table_line} vs {minutes}");
    assert!(stdout.contains(&format!(", {minutes} min,")), "{stdout}");

    // --allow-fail: status 0, the programs, and warnings rather than errors.
    let out2 = dir.path().join("out2");
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out2)
        .arg("--allow-fail")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("error:"), "{stderr}");
    assert!(
        stderr.contains("warning: constraint sigma_min fails"),
        "{stderr}"
    );
    assert!(!scripts(&out2).is_empty());
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out2.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["robot_programs_written"], true);
    assert!(s["robot_programs_why"].is_null());
}

/// `summary.json` of `kappe design` is the library's `Outcome::summary()` for the same design
/// and options, key for key and number for number (serialized the same way); only the
/// wall-clock `analysis_timings_s` differ between two runs.
#[test]
fn summary_json_is_the_library_outcome_summary() {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("d.toml");
    std::fs::write(&toml, FAILING).unwrap();
    let out = dir.path().join("out");
    let o = kappe()
        .arg("design")
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .arg("-q")
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let mut cli: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();

    let design = kappe::Design::from_toml_str(FAILING).unwrap();
    let outcome = kappe::run(&design, &kappe::Options::of(&design), &kappe::no_progress).unwrap();
    // Through the same bytes as the CLI writes them.
    let mut lib: serde_json::Value =
        serde_json::from_slice(&serde_json::to_vec_pretty(&outcome.summary()).unwrap()).unwrap();
    for v in [&mut cli, &mut lib] {
        v.as_object_mut().unwrap().remove("analysis_timings_s");
    }
    assert_eq!(cli, lib);
}
