//! Issue 26: `kappe init --kind corrugated`, `kappe corrugation`, and a bad wave refused with
//! nothing written.

use std::path::Path;
use std::process::{Command, Output};

fn kappe(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kappe"))
        .current_dir(cwd)
        .args(args)
        .output()
        .unwrap()
}

/// 12 centre layers of 15 mm (step 16.55 mm, shortest wavelength 8 steps = 132 mm), buckling in
/// every 4th state: quick.
const SMALL: &str = "[cap]\nlength = 0.2\n[print]\nlayer_height = 0.015\n[constraints]\n\
                     overhang_max = 0.05\n[analysis]\nstates = \"every:4\"\n[robot]\nenabled = false\n";

#[test]
fn init_writes_the_documented_corrugated_example() {
    let tmp = tempfile::tempdir().unwrap();
    let o = kappe(tmp.path(), &["init", "--kind", "corrugated"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(tmp.path().join("corrugated.toml")).unwrap();
    assert!(text.contains("[cap.corrugation]"));
    let doc = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/corrugation.md");
    let doc = std::fs::read_to_string(&doc).unwrap();
    assert!(
        doc.contains(&text),
        "docs/corrugation.md does not hold the example `kappe init --kind corrugated` writes"
    );
}

#[test]
fn the_study_writes_a_row_per_wave_and_names_an_impossible_one() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("small.toml"), SMALL).unwrap();
    let o = kappe(
        tmp.path(),
        &[
            "corrugation",
            "small.toml",
            "--amplitudes",
            "0.02",
            "--wavelengths",
            "0.15,0.1",
            "--out",
            "study",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(tmp.path().join("study/corrugation.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 4, "{csv}");
    assert!(lines[0].starts_with("amplitude_m,wavelength_m,min_blf"));
    // The smooth reference has a BLF ratio of exactly 1 against itself.
    let cols: Vec<&str> = lines[1].split(',').collect();
    assert_eq!(cols[8], "1.000000", "{}", lines[1]);
    assert!(lines[2].starts_with("0.02,0.15,"), "{}", lines[2]);
    assert!(!lines[2].contains("error"), "{}", lines[2]);
    // λ = 0.1 m is shorter than 8 layer steps: the row names the field, the study goes on.
    assert!(
        lines[3].contains("cap.corrugation.wavelength"),
        "{}",
        lines[3]
    );
}

#[test]
fn a_wave_too_short_is_an_input_error_and_nothing_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let text = format!("{SMALL}[cap.corrugation]\namplitude = 0.02\nwavelength = 0.05\n");
    std::fs::write(tmp.path().join("bad.toml"), text).unwrap();
    let o = kappe(tmp.path(), &["design", "bad.toml", "-q", "--out", "out"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("cap.corrugation.wavelength"), "{err}");
    assert!(!tmp.path().join("out").exists());
}
