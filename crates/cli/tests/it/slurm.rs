//! `kappe study --shard` in a Slurm job array: the shard index and count come from
//! `SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN` and `SLURM_ARRAY_TASK_COUNT`, and give the
//! same partial result as the explicit `--shard i/n`; bad values are usage errors (status 2)
//! that write nothing.

use std::path::Path;
use std::process::{Command, Output};

const KAPPE: &str = env!("CARGO_BIN_EXE_kappe");

const SLURM_VARS: [&str; 3] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_COUNT",
];

/// Runs kappe with exactly the Slurm variables given (the test process's own are removed, in
/// case the tests themselves run inside a job array).
fn kappe(args: &[&str], cwd: &Path, slurm: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(KAPPE);
    cmd.args(args).current_dir(cwd);
    for k in SLURM_VARS {
        cmd.env_remove(k);
    }
    cmd.envs(slurm.iter().copied());
    cmd.output().unwrap()
}

/// Five cheap designs (3 centre layers of 15 mm, 13 states; buckling of the last state only)
/// that all pass (the start section overhangs 20–25 mm, so l_o,max = 30 mm): a 2-task array
/// splits them 3 + 2, so the two shards differ.
const STUDY: &str = r#"title = "slurm"
[base]
cap.length = 0.05
print.layer_height = 0.015
constraints.overhang_max = 0.03
[analysis]
states = "every:1000"
[grid]
"cap.rise" = [0.15, 0.18, 0.2, 0.22, 0.25]
"#;

fn rows(dir: &Path) -> usize {
    let csv = std::fs::read_to_string(dir.join("study.csv")).unwrap();
    csv.lines().filter(|l| !l.is_empty()).count() - 1
}

#[test]
fn the_slurm_array_task_takes_the_shard_of_its_index() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    std::fs::write(work.join("s.toml"), STUDY).unwrap();
    let run = |args: &[&str], slurm: &[(&str, &str)]| {
        let o = kappe(args, work, slurm);
        // Every design of the grid passes: a status other than 0 is a failure of the test.
        assert_eq!(
            o.status.code(),
            Some(0),
            "{args:?} {slurm:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    let common = ["study", "s.toml", "-q", "--no-robot", "--jobs", "1"];
    // `#SBATCH --array=1-2`: Slurm numbers the tasks 1 and 2 (SLURM_ARRAY_TASK_MIN = 1), and
    // task 2 is the second shard, 1/2.
    run(
        &[&common[..], &["--shard", "--out", "env"]].concat(),
        &[
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ],
    );
    run(
        &[&common[..], &["--shard", "1/2", "--out", "explicit"]].concat(),
        &[],
    );
    assert_eq!(rows(&work.join("env")), 2, "designs 1 and 3 of 0..5");
    crate::common::assert_same_outputs(&work.join("env"), &work.join("explicit"));
    // `--array=0-1` without SLURM_ARRAY_TASK_MIN (0 is taken), and `--shard slurm`: task 0 is
    // shard 0/2.
    run(
        &[&common[..], &["--shard", "slurm", "--out", "env0"]].concat(),
        &[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ],
    );
    run(
        &[&common[..], &["--shard", "0/2", "--out", "explicit0"]].concat(),
        &[],
    );
    assert_eq!(rows(&work.join("env0")), 3, "designs 0, 2 and 4 of 0..5");
    crate::common::assert_same_outputs(&work.join("env0"), &work.join("explicit0"));
}

/// What is wrong, the Slurm variables, and what the error must say.
type Case<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a [&'a str]);

#[test]
fn bad_slurm_variables_are_usage_errors_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    std::fs::write(work.join("s.toml"), STUDY).unwrap();
    let cases: [Case; 5] = [
        (
            "ID beyond the count",
            &[
                ("SLURM_ARRAY_TASK_ID", "2"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            &["SLURM_ARRAY_TASK_ID=2", "SLURM_ARRAY_TASK_COUNT=2", "0..=1"],
        ),
        (
            "ID below the minimum",
            &[
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            &["SLURM_ARRAY_TASK_ID=0 is below SLURM_ARRAY_TASK_MIN=1"],
        ),
        (
            "not a number",
            &[
                ("SLURM_ARRAY_TASK_ID", "x1"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            &["SLURM_ARRAY_TASK_ID=\"x1\" is not a whole number"],
        ),
        (
            "a zero count",
            &[
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "0"),
            ],
            &["the shard count n must be at least 1"],
        ),
        (
            "not in a job array",
            &[("SLURM_ARRAY_TASK_ID", "0")],
            &["needs SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT"],
        ),
    ];
    for (what, slurm, needles) in cases {
        let o = kappe(
            &["study", "s.toml", "--shard", "--out", "out", "--no-robot"],
            work,
            slurm,
        );
        assert_eq!(o.status.code(), Some(2), "{what}: status 2 (usage error)");
        let err = String::from_utf8_lossy(&o.stderr);
        for n in needles {
            assert!(err.contains(n), "{what}: {err}");
        }
        assert!(!work.join("out").exists(), "{what}: wrote output");
    }
}
