//! Helpers shared by the CLI integration tests.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Every file under `dir`, relative path → bytes.
pub fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Two Kappe output directories hold the same files, byte-identical except Kappe's manifest
/// (`.kappe-output.json`, which names the command that wrote it) and the wall-clock
/// `analysis_timings_s` in each summary.json (it differs between two runs of one design).
pub fn assert_same_outputs(a: &Path, b: &Path) {
    let outputs = |dir: &Path| {
        let mut t = tree(dir);
        t.remove(Path::new(".kappe-output.json"));
        t
    };
    let (a, b) = (outputs(a), outputs(b));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "same files"
    );
    let without_timings = |bytes: &[u8]| {
        let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
        v.as_object_mut().unwrap().remove("analysis_timings_s");
        v
    };
    for (path, bytes) in &a {
        if path.ends_with("summary.json") {
            assert_eq!(
                without_timings(&b[path]),
                without_timings(bytes),
                "{} differs",
                path.display()
            );
        } else {
            assert!(b[path] == *bytes, "{} differs", path.display());
        }
    }
}

/// Runs the `kappe` binary in `dir` with `args`.
pub fn kappe(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kappe"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// A process's output bytes as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}
