//! `kappe study`: a 3×3×3 grid against `kappe design` run on each design alone, shards merged
//! against the unsharded study, and bad study files.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

const KAPPE: &str = env!("CARGO_BIN_EXE_kappe");

fn kappe(args: &[&str], cwd: &Path) -> Output {
    Command::new(KAPPE)
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

/// A cheap base (3 centre layers of 15 mm, 13 states) and three axes chosen so that the grid
/// holds designs that pass, that fail by stress (σ_min = −12 or −16 kPa against 15.4–17 kPa of
/// arch compression), that fail by overhang (l_o,max = 10 mm against 20–25 mm in the start
/// section) and that cannot run (l_o,max < 0 is out of range).
const BASE: &str = "cap.length = 0.05\nprint.layer_height = 0.015\n";
const OVERHANGS: [f64; 3] = [-0.005, 0.01, 0.03];
const RISES: [f64; 3] = [0.15, 0.2, 0.3];
const SIGMA_MINS: [f64; 3] = [-12e3, -16e3, -40e3];

fn grid_study() -> String {
    format!(
        "title = \"grid\"\n[base]\n{BASE}[grid]\n\"constraints.overhang_max\" = {OVERHANGS:?}\n\
         \"cap.rise\" = {RISES:?}\n\"constraints.sigma_min\" = {SIGMA_MINS:?}\n"
    )
}

/// One CSV line split into fields (RFC 4180 quoting: `"a, ""b"""` is `a, "b"`).
fn csv_fields(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(String::new()),
            (c, _) => out.last_mut().unwrap().push(c),
        }
    }
    out
}

/// `study.csv` as rows of header → value.
fn read_csv(path: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = csv_fields(lines.next().unwrap());
    lines
        .map(|l| {
            let fields = csv_fields(l);
            assert_eq!(fields.len(), header.len(), "{l}");
            header.iter().cloned().zip(fields).collect()
        })
        .collect()
}

/// `kappe design` alone: `(ran, ok)`. It ran if it wrote its outputs; it passes if it exits 0
/// and its `summary.json` meets the design's own limits (method.md §3): σ_min ≤ σ ≤ σ_max in
/// every state, max |l_o| ≤ l_o,max (default lw/2), and the robot was planned if it was tried.
/// (Today `kappe design` exits non-zero only for a robot failure; when it also does so for a
/// failed constraint, the exit status alone will carry the verdict and the checks below agree.)
/// Stress limits get 1e-9 of the largest stress as slack: the force pass is exact to ~1e-14
/// relative, and an all-compression arch shows ~1e-11 Pa of roundoff tension.
fn design_alone_passes(toml: &str, work: &Path, tag: &str) -> (bool, bool) {
    let file = work.join(format!("{tag}.toml"));
    std::fs::write(&file, toml).unwrap();
    let out = work.join(tag);
    let run = kappe(
        &[
            "design",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
        work,
    );
    let Ok(bytes) = std::fs::read(out.join("summary.json")) else {
        assert!(!run.status.success(), "exit 0 without outputs");
        return (false, false);
    };
    let s: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    let k = &s["design"]["constraints"];
    let sigma_min = k["sigma_min"].as_f64().unwrap();
    let sigma_max = k["sigma_max"].as_f64().unwrap();
    let lo_max = k["overhang_max"]
        .as_f64()
        .unwrap_or(0.5 * s["design"]["print"]["layer_width"].as_f64().unwrap());
    let states = s["states"].as_array().unwrap();
    let comp = states
        .iter()
        .map(|x| x["max_compression_stress_pa"].as_f64().unwrap())
        .fold(0.0, f64::min);
    let tens = states
        .iter()
        .map(|x| x["max_tension_stress_pa"].as_f64().unwrap())
        .fold(0.0, f64::max);
    let tol = 1e-9 * comp.abs().max(tens.abs());
    let ok = run.status.success()
        && comp >= sigma_min - tol
        && tens <= sigma_max + tol
        && s["max_overhang_m"].as_f64().unwrap() <= lo_max
        && s["robot"]["ok"].as_bool() != Some(false);
    (true, ok)
}

#[test]
fn grid_reproduces_kappe_design_row_by_row() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    std::fs::write(work.join("grid.toml"), grid_study()).unwrap();
    // The grid holds failing designs, so the study exits 1 (`kappe --help`).
    let run = kappe(&["study", "grid.toml", "--out", "s", "--quiet"], work);
    assert_eq!(
        run.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let rows = read_csv(&work.join("s/study.csv"));
    assert_eq!(rows.len(), 27);

    // Every combination as its own design file, in the test's own words.
    let mut combos = Vec::new();
    for o in OVERHANGS {
        for r in RISES {
            for sm in SIGMA_MINS {
                let toml = format!(
                    "[cap]\nlength = 0.05\nrise = {r:?}\n[print]\nlayer_height = 0.015\n\
                     [constraints]\nsigma_min = {sm:?}\noverhang_max = {o:?}\n"
                );
                combos.push(((o, r, sm), toml));
            }
        }
    }
    // `kappe design` on each alone, two processes at a time (the machine has 2 cores).
    let alone: Vec<(bool, bool)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..2)
            .map(|w| {
                let combos = &combos;
                scope.spawn(move || {
                    (w..combos.len())
                        .step_by(2)
                        .map(|k| (k, design_alone_passes(&combos[k].1, work, &format!("d{k}"))))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        let mut all: Vec<(usize, (bool, bool))> = workers
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect();
        all.sort_by_key(|(k, _)| *k);
        all.into_iter().map(|(_, v)| v).collect()
    });

    let mut seen = [0usize; 3]; // pass, fail, error
    for (((o, r, sm), _), (ran, ok)) in combos.iter().zip(alone) {
        // Find the row by its parameter values, not by the study's naming scheme.
        let num = |row: &BTreeMap<String, String>, key: &str| -> f64 { row[key].parse().unwrap() };
        let matching: Vec<&BTreeMap<String, String>> = rows
            .iter()
            .filter(|row| {
                num(row, "constraints.overhang_max") == *o
                    && num(row, "cap.rise") == *r
                    && num(row, "constraints.sigma_min") == *sm
            })
            .collect();
        assert_eq!(matching.len(), 1, "l_o,max {o} rise {r} σ_min {sm}");
        let row = matching[0];
        let result = row["result"].as_str();
        assert_eq!(
            result == "pass",
            ok,
            "row {} says {result}, kappe design alone says ok = {ok}",
            row["name"]
        );
        // A design that cannot run is an error row, with its reason, and vice versa.
        assert_eq!(result == "error", !ran, "row {}", row["name"]);
        let report = work
            .join("s/designs")
            .join(&row["name"])
            .join("report.html");
        if ran {
            assert!(report.is_file(), "{}", report.display());
        } else {
            assert!(
                row["error"].contains("constraints.overhang_max"),
                "{}",
                row["error"]
            );
            assert!(!report.exists());
        }
        seen[match result {
            "pass" => 0,
            "fail" => 1,
            _ => 2,
        }] += 1;
    }
    // The grid was chosen to hold all three outcomes; if it stops doing so, this test would
    // compare nothing interesting.
    assert!(
        seen.iter().all(|&n| n > 0),
        "pass/fail/error counts {seen:?}"
    );

    // study.html: one row per design, a link to every report that exists.
    let html = std::fs::read_to_string(work.join("s/study.html")).unwrap();
    assert_eq!(html.matches("<tr class=").count(), 27);
    assert_eq!(html.matches(">report</a>").count(), seen[0] + seen[1]);
    assert!(html.contains("cell-fail"));
}

#[test]
fn shards_merged_equal_the_unsharded_study() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    std::fs::write(work.join("grid.toml"), grid_study()).unwrap();
    // The grid holds failing designs: its runs and merges exit 1 ("some designs failed"), and
    // would exit 2 or 3 for a usage or I/O error.
    let ok = |o: Output| {
        assert_eq!(
            o.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        o
    };
    // The robot is not what shards are about: skip planning to keep the test quick.
    ok(kappe(
        &["study", "grid.toml", "--out", "all", "-q", "--no-robot"],
        work,
    ));
    // 27 designs in 4 shards: 7, 7, 7, 6; one shard on one thread.
    for i in 0..4 {
        let spec = format!("{i}/4");
        let out = format!("part{i}");
        let mut args = vec![
            "study",
            "grid.toml",
            "--shard",
            &spec,
            "--out",
            &out,
            "-q",
            "--no-robot",
        ];
        if i == 2 {
            args.extend(["--jobs", "1"]);
        }
        ok(kappe(&args, work));
        let n = read_csv(&work.join(&out).join("study.csv")).len();
        assert_eq!(n, if i < 3 { 7 } else { 6 }, "shard {i}");
    }
    // Shards given in any order.
    ok(kappe(
        &[
            "study", "merge", "part3", "part1", "part0", "part2", "--out", "merged", "-q",
        ],
        work,
    ));
    // Every file byte-identical but the manifest and the analysis wall-clock timings.
    crate::common::assert_same_outputs(&work.join("all"), &work.join("merged"));

    // A missing shard is an error naming the gap; --allow-incomplete merges what is there.
    let missing = kappe(
        &["study", "merge", "part0", "part1", "part2", "--out", "m2"],
        work,
    );
    assert!(!missing.status.success());
    let err = String::from_utf8_lossy(&missing.stderr);
    assert!(err.contains("6 of 27 designs are missing"), "{err}");
    assert!(!work.join("m2").exists());
    ok(kappe(
        &[
            "study",
            "merge",
            "part0",
            "part1",
            "--out",
            "m3",
            "--allow-incomplete",
            "-q",
        ],
        work,
    ));
    assert_eq!(read_csv(&work.join("m3/study.csv")).len(), 14);
    // The same shard twice, and a shard of another study.
    let twice = kappe(&["study", "merge", "part0", "part0", "--out", "m4"], work);
    assert!(String::from_utf8_lossy(&twice.stderr).contains("is in both"));
    std::fs::write(
        work.join("other.toml"),
        grid_study().replace("0.15, 0.2", "0.16, 0.2"),
    )
    .unwrap();
    ok(kappe(
        &[
            "study",
            "other.toml",
            "--shard",
            "1/4",
            "--out",
            "other1",
            "-q",
            "--no-robot",
        ],
        work,
    ));
    let mixed = kappe(&["study", "merge", "part0", "other1", "--out", "m5"], work);
    assert!(String::from_utf8_lossy(&mixed.stderr).contains("different studies"));
    // The same study with the robot planned is another study too.
    ok(kappe(
        &[
            "study",
            "grid.toml",
            "--shard",
            "1/4",
            "--out",
            "robot1",
            "-q",
        ],
        work,
    ));
    let mixed = kappe(&["study", "merge", "part0", "robot1", "--out", "m6"], work);
    assert!(String::from_utf8_lossy(&mixed.stderr).contains("different studies"));
}

#[test]
fn bad_study_files_are_clear_errors_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    let cases: [(&str, &str, &[&str]); 7] = [
        (
            "bad analysis options",
            "[analysis]\nstate = \"all\"\n[[design]]\nname = \"a\"\n",
            &["[analysis]", "unknown field `state`"],
        ),
        ("empty grid", "[grid]\n", &["[grid] table is empty"]),
        (
            "duplicate names",
            "[[design]]\nname = \"a\"\n[[design]]\nname = \"b\"\n[[design]]\nname = \"a\"\n",
            &["duplicate design name `a`", "#1", "#3"],
        ),
        (
            "unknown parameter in a grid",
            "[grid]\n\"cap.spam\" = [0.6, 0.8]\n",
            &["grid entry `cap.spam`", "unknown field `spam`"],
        ),
        (
            "unknown parameter in a list",
            "[[design]]\nname = \"wide\"\ncap.span = 1.0\n[[design]]\nname = \"x\"\nprint.nozle = 0.02\n",
            &["[[design]] #2 (`x`)", "`print.nozle`"],
        ),
        (
            "wrong type",
            "[grid]\n\"cap.rise\" = [\"high\"]\n",
            &["grid entry `cap.rise`", "expected f64"],
        ),
        (
            "empty list",
            "[grid]\n\"cap.rise\" = []\n\"cap.span\" = [1.0]\n",
            &["grid entry `cap.rise` is an empty list"],
        ),
    ];
    for (what, text, needles) in cases {
        std::fs::write(work.join("bad.toml"), text).unwrap();
        let o = kappe(&["study", "bad.toml", "--out", "out"], work);
        assert!(!o.status.success(), "{what}");
        let err = String::from_utf8_lossy(&o.stderr);
        for n in needles {
            assert!(err.contains(n), "{what}: {err}");
        }
        assert!(!work.join("out").exists(), "{what}: wrote output");
    }
    std::fs::write(work.join("ok.toml"), "[grid]\n\"cap.rise\" = [0.2]\n").unwrap();
    for spec in ["4/4", "x", "1/0"] {
        let o = kappe(&["study", "ok.toml", "--shard", spec, "--out", "out"], work);
        assert!(!o.status.success(), "{spec}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(&format!("--shard `{spec}`")),
            "{spec}"
        );
    }
}

#[test]
fn an_analysis_table_adds_the_buckling_factor() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    // "every:1000" analyses state 0 (one layer on the bed: no shell, no factor) and the final
    // state: one finite-element solve, so the test stays quick.
    std::fs::write(
        work.join("a.toml"),
        "[analysis]\nstates = \"every:1000\"\n[[design]]\nname = \"a\"\n\
         cap.length = 0.05\nprint.layer_height = 0.015\nconstraints.overhang_max = 0.03\n",
    )
    .unwrap();
    let run = kappe(&["study", "a.toml", "--out", "s", "-q", "--no-robot"], work);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let rows = read_csv(&work.join("s/study.csv"));
    let blf: f64 = rows[0]["min_blf"].parse().unwrap();
    assert!(blf > 0.0);
    // The report's table has the BLF row, at the final state, with the design's BLF_min = 1.
    let html = std::fs::read_to_string(work.join("s/designs/a/report.html")).unwrap();
    let start = html.find("id=\"kappe-data\">").unwrap() + "id=\"kappe-data\">".len();
    let len = html[start..].find("</script>").unwrap();
    let input: serde_json::Value = serde_json::from_str(&html[start..start + len]).unwrap();
    let rows = input["constraints"].as_array().unwrap();
    let row = rows.iter().find(|r| r["name"] == "blf_min").unwrap();
    let states = input["states"].as_array().unwrap();
    assert_eq!(row["limit"], 1.0);
    assert_eq!(row["state"], states.len() - 1);
    assert_eq!(row["pass"], blf >= 1.0);
    // The island keeps 7 significant digits.
    assert!((row["worst"].as_f64().unwrap() - blf).abs() <= 1e-6 * blf);
    let with_blf: Vec<usize> = states
        .iter()
        .enumerate()
        .filter(|(_, s)| !s["blf"].is_null())
        .map(|(i, _)| i)
        .collect();
    assert_eq!(with_blf, [states.len() - 1]);
}

#[test]
fn a_study_analyses_as_kappe_design_and_its_design_files_reproduce_the_verdict() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    // Two cheap designs (13 states). Without [analysis] the study must check buckling as
    // `kappe design` does by default. BLF_min = 1e9 cannot be met by any shell (the factors are
    // O(10–100) for these caps), so "b" fails by buckling alone; "a" keeps BLF_min = 1.
    std::fs::write(
        work.join("no-table.toml"),
        "[base]
cap.length = 0.05
print.layer_height = 0.015
constraints.overhang_max = 0.03
         [grid]
\"constraints.blf_min\" = [1.0, 1e9]
",
    )
    .unwrap();
    let run = kappe(
        &["study", "no-table.toml", "--out", "s", "-q", "--no-robot"],
        work,
    );
    assert_eq!(
        run.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let rows = read_csv(&work.join("s/study.csv"));
    assert_eq!(rows.len(), 2);
    for row in &rows {
        let blf: f64 = row["min_blf"].parse().unwrap();
        assert!(blf > 1.0, "{}: BLF {blf}", row["name"]);
    }
    let result = |name: &str| {
        rows.iter()
            .find(|r| r["constraints.blf_min"] == name)
            .unwrap()["result"]
            .clone()
    };
    assert_eq!(result("1.0"), "pass");
    assert_eq!(result("1000000000.0"), "fail");

    // With an [analysis] table (buckling off) that table goes into every design.toml, so the
    // design run alone reaches the study's verdict: "b" passes without buckling.
    std::fs::write(
        work.join("table.toml"),
        std::fs::read_to_string(work.join("no-table.toml"))
            .unwrap()
            .replace("[grid]", "[analysis]\nbuckling = false\n[grid]"),
    )
    .unwrap();
    let run = kappe(
        &["study", "table.toml", "--out", "t", "-q", "--no-robot"],
        work,
    );
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for (dir, expect_blf) in [("s", true), ("t", false)] {
        for row in read_csv(&work.join(dir).join("study.csv")) {
            let design = work
                .join(dir)
                .join("designs")
                .join(&row["name"])
                .join("design.toml");
            let text = std::fs::read_to_string(&design).unwrap();
            assert_eq!(text.contains("buckling = false"), !expect_blf, "{text}");
            let out = work.join(format!("alone-{dir}-{}", row["name"]));
            let alone = kappe(
                &[
                    "design",
                    design.to_str().unwrap(),
                    "--out",
                    out.to_str().unwrap(),
                    "-q",
                    "--no-robot",
                ],
                work,
            );
            let code = alone.status.code();
            assert_eq!(
                code == Some(0),
                row["result"] == "pass",
                "{dir}/{}: kappe design exits {code:?}, the study says {}",
                row["name"],
                row["result"]
            );
            let s: serde_json::Value =
                serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
            assert_eq!(s["ok"].as_bool(), Some(row["result"] == "pass"));
        }
    }
}
