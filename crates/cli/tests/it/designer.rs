//! `kappe designer --out DIR` (issue 25): with the designer's WebAssembly built
//! (scripts/build-designer.sh, before the CLI) it writes one self-contained designer.html of at
//! most 5 MB; without it, it fails with an error naming the build script and writes nothing.

use std::process::Command;

#[test]
fn designer_writes_one_page_or_names_the_build_script() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let out = tmp.path().join("designer");
    let run = Command::new(env!("CARGO_BIN_EXE_kappe"))
        .args(["designer", "--out"])
        .arg(&out)
        .output()
        .expect("kappe runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    if run.status.success() {
        let html = std::fs::read_to_string(out.join("designer.html")).expect("designer.html");
        assert!(html.len() <= 5_000_000, "page is {} bytes", html.len());
        for part in [
            "id=\"kappe-wasm\"",
            "id=\"kappe-glue\"",
            "kappeDesigner",
            "OrbitControls",
        ] {
            assert!(html.contains(part), "page lacks {part}");
        }
        assert!(
            !html.contains("http://") || !html.contains("src=\"http"),
            "no remote scripts"
        );
    } else {
        assert_eq!(run.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("scripts/build-designer.sh"), "{stderr}");
        assert!(!out.exists(), "nothing written");
    }
}

#[test]
fn designer_refuses_a_directory_it_did_not_write() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).expect("dir");
    std::fs::write(out.join("notes.txt"), "mine").expect("file");
    let run = Command::new(env!("CARGO_BIN_EXE_kappe"))
        .args(["designer", "--out"])
        .arg(&out)
        .output()
        .expect("kappe runs");
    assert!(!run.status.success());
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).expect("kept"),
        "mine"
    );
    assert!(!out.join("designer.html").exists());
}
