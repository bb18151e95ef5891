//! Issue 16: Kappe never loses a user's files, fails early and clearly, and uses one exit-status
//! scheme (0 success, 1 fails its checks, 2 usage or input error, 3 internal or I/O failure).

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn kappe() -> Command {
    Command::new(env!("CARGO_BIN_EXE_kappe"))
}

/// A small design that runs in about a second in a debug build.
const SMALL: &str = "[cap]\nlength = 0.15\n";

fn small_design(dir: &Path) -> PathBuf {
    let p = dir.join("small.toml");
    std::fs::write(&p, SMALL).unwrap();
    p
}

fn design(cwd: &Path, file: &Path, out: &str, extra: &[&str]) -> Output {
    kappe()
        .current_dir(cwd)
        .arg("design")
        .arg(file)
        .args(["--out", out, "--quiet", "--no-robot", "--no-buckling"])
        .args(extra)
        .output()
        .unwrap()
}

fn code(o: &Output) -> i32 {
    o.status.code().unwrap_or(-1)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Every file below `dir` with its bytes, to compare a tree before and after.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let e = e.unwrap();
            if e.file_type().unwrap().is_dir() {
                out.push((e.path(), Vec::new()));
                stack.push(e.path());
            } else {
                out.push((e.path(), std::fs::read(e.path()).unwrap()));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn out_dot_is_refused_and_nothing_is_touched() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    std::fs::write(work.join("notes.txt"), "mine").unwrap();
    let file = small_design(&work);
    let before = snapshot(tmp.path());
    let o = design(&work, &file, ".", &[]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("working directory"), "{}", stderr(&o));
    assert_eq!(snapshot(tmp.path()), before);
    // --force does not change that: the working directory is never replaced.
    let o = design(&work, &file, ".", &["--force"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(snapshot(tmp.path()), before);
}

#[test]
fn out_parent_is_refused_and_nothing_is_touched() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    std::fs::write(tmp.path().join("other.txt"), "mine").unwrap();
    let file = small_design(&work);
    let before = snapshot(tmp.path());
    for out in ["..", "../work/..", "/"] {
        let o = design(&work, &file, out, &[]);
        assert_eq!(code(&o), 2, "--out {out}: {}", stderr(&o));
        assert_eq!(snapshot(tmp.path()), before, "--out {out}");
    }
}

#[test]
fn unrelated_non_empty_directory_is_refused_then_moved_aside_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let file = small_design(tmp.path());
    let target = tmp.path().join("mine");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("thesis.tex"), "years of work").unwrap();
    let before = snapshot(tmp.path());
    let o = design(tmp.path(), &file, "mine", &[]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("thesis.tex"),
        "names the foreign file: {}",
        stderr(&o)
    );
    assert_eq!(snapshot(tmp.path()), before);

    let o = design(tmp.path(), &file, "mine", &["--force"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let aside = tmp.path().join("mine.old-1");
    assert_eq!(
        std::fs::read(aside.join("thesis.tex")).unwrap(),
        b"years of work"
    );
    assert!(target.join("summary.json").is_file());
}

#[test]
fn own_output_is_replaced_but_not_when_the_user_added_files() {
    let tmp = tempfile::tempdir().unwrap();
    let file = small_design(tmp.path());
    let o = design(tmp.path(), &file, "out", &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = tmp.path().join("out");
    assert!(out.join(".kappe-output.json").is_file());
    // Kappe's own output: replaced without --force.
    std::fs::write(out.join("summary.json"), "stale").unwrap();
    let o = design(tmp.path(), &file, "out", &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert_ne!(std::fs::read(out.join("summary.json")).unwrap(), b"stale");
    // A file the user put into it makes it theirs: refused, file kept.
    std::fs::write(out.join("my-notes.md"), "keep me").unwrap();
    let before = snapshot(tmp.path());
    let o = design(tmp.path(), &file, "out", &[]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("my-notes.md"), "{}", stderr(&o));
    assert_eq!(snapshot(tmp.path()), before);
    // No staging directory is left behind.
    let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(".kappe"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn killed_while_writing_leaves_the_old_output_intact() {
    let tmp = tempfile::tempdir().unwrap();
    let file = small_design(tmp.path());
    let o = design(tmp.path(), &file, "out", &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let out = tmp.path().join("out");
    let before = snapshot(&out);

    // 300 ms after every file: the run is killed after it has written a few files of the new
    // output into its staging directory.
    let mut child = kappe()
        .current_dir(tmp.path())
        .env("KAPPE_TEST_WRITE_DELAY_MS", "300")
        .arg("design")
        .arg(&file)
        .args(["--out", "out", "--quiet", "--no-robot", "--no-buckling"])
        .spawn()
        .unwrap();
    let start = Instant::now();
    let staged = loop {
        let staging: Vec<PathBuf> = std::fs::read_dir(tmp.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with(".kappe-out-"))
            })
            .collect();
        let written = staging
            .iter()
            .flat_map(|d| std::fs::read_dir(d).into_iter().flatten())
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".json"))
            .count();
        if written >= 1 {
            break true;
        }
        if start.elapsed() > Duration::from_secs(120) || child.try_wait().unwrap().is_some() {
            break false;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(staged, "the run never started writing");
    assert_eq!(snapshot(&out), before, "the old output changed");

    // The next run removes the dead run's staging directory and replaces the output.
    let o = design(tmp.path(), &file, "out", &[]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.starts_with(".kappe-out-")),
        "{names:?}"
    );
}

#[test]
fn unwritable_output_fails_before_any_computing() {
    let tmp = tempfile::tempdir().unwrap();
    // The full default design with buckling of every state takes many seconds; the refusal must
    // come first. /proc cannot take a new directory, even for root (a chmod-555 directory does
    // not stop root, who runs CI).
    for out in ["/proc/kappe-out", "/proc/self/status"] {
        let start = Instant::now();
        let o = kappe()
            .current_dir(tmp.path())
            .args(["design", "--quiet", "--out", out])
            .output()
            .unwrap();
        let took = start.elapsed();
        assert!(matches!(code(&o), 2 | 3), "--out {out}: {}", stderr(&o));
        // Generous bound (the analysis alone takes > 10 s in a debug build): this checks the
        // order of work, not speed.
        assert!(took < Duration::from_secs(5), "--out {out} took {took:?}");
    }
    // A regular file as --out is a usage error.
    std::fs::write(tmp.path().join("afile"), "x").unwrap();
    let o = kappe()
        .current_dir(tmp.path())
        .args(["design", "--quiet", "--out", "afile"])
        .output()
        .unwrap();
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(std::fs::read(tmp.path().join("afile")).unwrap(), b"x");
}

#[test]
fn outputs_respect_the_umask() {
    let tmp = tempfile::tempdir().unwrap();
    let file = small_design(tmp.path());
    let bin = env!("CARGO_BIN_EXE_kappe");
    for (umask, file_mode, dir_mode) in [("022", 0o644, 0o755), ("027", 0o640, 0o750)] {
        let out = tmp.path().join(format!("out{umask}"));
        let st = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "umask {umask} && exec \"$0\" design \"$1\" --out \"$2\" --quiet --no-robot --no-buckling && umask {umask} && exec true"
            ))
            .arg(bin)
            .arg(&file)
            .arg(&out)
            .status()
            .unwrap();
        assert!(st.success());
        let mode = |p: &Path| p.metadata().unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&out.join("summary.json")), file_mode, "umask {umask}");
        assert_eq!(mode(&out), dir_mode, "umask {umask}");
        let init = tmp.path().join(format!("init{umask}.toml"));
        let st = Command::new("sh")
            .arg("-c")
            .arg(format!("umask {umask} && exec \"$0\" init \"$1\""))
            .arg(bin)
            .arg(&init)
            .status()
            .unwrap();
        assert!(st.success());
        assert_eq!(mode(&init), file_mode, "init, umask {umask}");
    }
}

#[test]
fn single_output_files_are_not_overwritten_without_force() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("result.json");
    std::fs::write(&out, "user data").unwrap();
    let o = kappe()
        .args(["cem", "solve", "--example", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(std::fs::read(&out).unwrap(), b"user data");
    let o = kappe()
        .args(["cem", "solve", "--example", "--force", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert!(v.is_object());
    // init refuses too.
    let o = kappe().arg("init").arg(&out).output().unwrap();
    assert_eq!(code(&o), 2, "{}", stderr(&o));
}

#[test]
fn exit_status_scheme() {
    let tmp = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| kappe().current_dir(tmp.path()).args(args).output().unwrap();
    // 2: usage (clap) and input errors; nothing written.
    assert_eq!(code(&run(&["design", "--no-such-flag"])), 2);
    std::fs::write(tmp.path().join("bad.toml"), "[cap]\nspan = -1.0\n").unwrap();
    let o = run(&["design", "bad.toml", "--out", "o1"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("cap.span"), "{}", stderr(&o));
    assert!(!tmp.path().join("o1").exists());
    std::fs::write(tmp.path().join("empty.toml"), "# nothing here\n").unwrap();
    let o = run(&["design", "empty.toml", "--out", "o2"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("empty"), "{}", stderr(&o));
    assert!(!tmp.path().join("o2").exists());
    let o = run(&["design", "missing.toml", "--out", "o3"]);
    // A missing input is a bad input the user fixes (README: 2), not an I/O failure of
    // Kappe's (issue 28).
    assert_eq!(
        code(&o),
        2,
        "a missing input file is an input error: {}",
        stderr(&o)
    );
    assert!(!tmp.path().join("o3").exists());
    // 1: the design fails its checks (a too-flat long span crushes, issue 6's failing case);
    // the summary and report are written so the user sees why, the robot program is not.
    std::fs::write(
        tmp.path().join("fails.toml"),
        "[cap]\nspan = 1.4\nrise = 0.12\nlength = 0.15\n",
    )
    .unwrap();
    let o = run(&[
        "design",
        "fails.toml",
        "--out",
        "o4",
        "--quiet",
        "--no-buckling",
    ]);
    assert_eq!(code(&o), 1, "{}", stderr(&o));
    assert!(tmp.path().join("o4/summary.json").is_file());
    assert!(tmp.path().join("o4/report.html").is_file());
    assert!(!tmp.path().join("o4/program.script").exists());
    // --allow-fail: status 0, and what is reported is not an `error:`.
    let o = run(&[
        "design",
        "fails.toml",
        "--out",
        "o5",
        "--quiet",
        "--no-buckling",
        "--allow-fail",
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(!stderr(&o).contains("error:"), "{}", stderr(&o));
}

#[test]
fn fe_buckle_of_an_unloaded_mesh_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    // The plate fixture with its edge loads removed (and gamma = 0 already): nothing loads it.
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/fixtures/fe/plate_ss_s3_n16.mesh.json");
    let mut mesh: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fixture).unwrap()).unwrap();
    assert_eq!(mesh["gamma"], serde_json::json!(0.0));
    mesh["load"]["forces"] = serde_json::json!([]);
    let p = tmp.path().join("m.json");
    std::fs::write(&p, mesh.to_string()).unwrap();
    let o = kappe().args(["fe", "buckle"]).arg(&p).output().unwrap();
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("no load"), "{}", stderr(&o));
}

#[test]
fn optimize_on_a_design_file_without_its_table_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("d.toml"), "[cap]\nspan = 0.9\n").unwrap();
    let o = kappe()
        .current_dir(tmp.path())
        .args(["optimize", "d.toml", "--out", "o"])
        .output()
        .unwrap();
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("[optimize]"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("unknown field"), "{}", stderr(&o));
    assert!(!tmp.path().join("o").exists());
}

/// Issue 22: `kappe optimize` confirms its optimum with `kappe design`'s run and verdict, so
/// `kappe design` of the design it writes passes whenever it reports a feasible optimum.
#[test]
fn kappe_design_passes_the_optimum_kappe_optimize_writes() {
    let tmp = tempfile::tempdir().unwrap();
    let o = kappe()
        .current_dir(tmp.path())
        .args(["init", "opt.toml", "--kind", "optimize"])
        .output()
        .unwrap();
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let o = kappe()
        .current_dir(tmp.path())
        .args([
            "optimize",
            "opt.toml",
            "--out",
            "o",
            "--max-evaluations",
            "4",
            "-q",
        ])
        .output()
        .unwrap();
    // The example is feasible from its start design; a budget of 4 evaluations keeps it quick.
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let o = kappe()
        .current_dir(tmp.path())
        .args(["design", "o/design.toml", "--out", "d", "--quiet"])
        .output()
        .unwrap();
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("d/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ok"], true);
    assert_eq!(summary["failures"], serde_json::json!([]));
}

/// Issue 22: a `[schedule]` that does not fit the print is a named error and nothing is
/// written (it used to vanish from `summary.json`).
#[test]
fn a_schedule_that_does_not_fit_the_print_is_a_named_error() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("d.toml"),
        "[schedule]\nwaits = [1.0, 2.0, 3.0]\n",
    )
    .unwrap();
    let o = kappe()
        .current_dir(tmp.path())
        .args(["design", "d.toml", "--out", "o", "--no-robot"])
        .output()
        .unwrap();
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("schedule.waits"), "{}", stderr(&o));
    assert!(!tmp.path().join("o").exists());
}

/// Issue 22: an invalid time model is a named error before anything runs, nothing written.
#[test]
fn an_invalid_time_model_is_a_named_error() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("d.toml"),
        "[material.time]\nmodel = \"linear\"\nyoungs_modulus_rate = -5.0\n",
    )
    .unwrap();
    let o = kappe()
        .current_dir(tmp.path())
        .args(["design", "d.toml", "--out", "o", "--no-robot"])
        .output()
        .unwrap();
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("material.time"), "{}", stderr(&o));
    assert!(!tmp.path().join("o").exists());
}
