//! `summary.json` is a typed struct with a published JSON Schema (issue 22).

use kappe::output::{Summary, summary_schema};

fn published_path() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/formats/summary.schema.json")
}

#[test]
fn the_published_schema_is_the_generated_one() {
    let generated = format!(
        "{}\n",
        serde_json::to_string_pretty(&summary_schema()).unwrap()
    );
    // `KAPPE_BLESS=1 cargo test -p kappe --test it summary_schema` rewrites the file after a
    // deliberate change of the summary's fields.
    if std::env::var_os("KAPPE_BLESS").is_some() {
        std::fs::write(published_path(), &generated).unwrap();
    }
    let published = std::fs::read_to_string(published_path()).unwrap();
    assert!(
        published == generated,
        "docs/formats/summary.schema.json is not the schema of kappe::output::Summary; \
         rerun this test with KAPPE_BLESS=1 and commit the file"
    );
}

#[test]
fn a_summary_reads_back_as_the_same_summary() {
    // A small cap, analysed (stresses, overhang and buckling every 2nd state), no robot: every
    // field the type declares survives JSON, and the JSON names no field the type lacks.
    let design = kappe::Design::from_toml_str(
        "[cap]\nlength = 0.05\n[print]\nlayer_height = 0.015\n[constraints]\noverhang_max = 0.05\n\
         [analysis]\nstates = \"every:2\"\n",
    )
    .unwrap();
    let options = kappe::Options {
        robot: false,
        ..kappe::Options::of(&design)
    };
    let out = kappe::run(&design, &options, &kappe::no_progress).unwrap();
    let summary = out.summary();
    let text = serde_json::to_string(&summary).unwrap();
    let back: Summary = serde_json::from_str(&text).unwrap();
    assert_eq!(back, summary);
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let again = serde_json::to_value(&back).unwrap();
    assert_eq!(value, again);
    assert_eq!(summary.ok, out.verdict.ok);
    assert_eq!(summary.states.len(), out.cap.states.len());
}
