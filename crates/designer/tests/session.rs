//! The designer's session and workers (natively; the same code runs in the browser) reach the
//! numbers of `kappe::run` (what `kappe design --no-robot` runs): every state's BLF, the
//! verdict and the constraint table, exactly (one library, one code path, same machine).
//! And a bad value keeps the last good design and names its field.

use kappe_designer::{SessionCore, WorkerCore, set_field};
use serde_json::{Value, json};

/// A short cap with buckling every 6th state: quick, and still a real analysis.
const SHORT: &str = "[cap]\nlength = 0.15\n[analysis]\nstates = \"every:6\"\n";

/// The mesh-error solves by the worker that solved the states' first pass (from its modes, as
/// `kappe design` solves them).
#[test]
fn session_with_worker_results_equals_run() {
    session_equals_run(true);
}

/// The mesh-error solves by a worker that did not solve their first pass (from a cold start,
/// as when the page's other worker takes them).
#[test]
fn session_with_cold_mesh_error_solves_equals_run() {
    session_equals_run(false);
}

fn session_equals_run(owner_refines: bool) {
    let mut session = SessionCore::new();
    let loaded = session.load(SHORT).expect("design loads");
    assert_eq!(loaded["report"]["states_done"], json!(0));
    assert_eq!(
        loaded["report"]["ok"],
        Value::Null,
        "no verdict before buckling"
    );
    let runs: Vec<Vec<usize>> = serde_json::from_value(loaded["runs"].clone()).expect("runs");
    let generation = loaded["generation"].as_u64().expect("generation");
    let mut workers = [WorkerCore::new(), WorkerCore::new()];
    let mut report = Value::Null;
    let mut solve = |run: &[usize], max_split: usize, report: &mut Value| {
        let mut results: Vec<String> = Vec::new();
        let k = usize::from(max_split > 1 && !owner_refines);
        workers[k]
            .run(
                session.text().to_string().as_str(),
                run,
                max_split,
                &mut |s| results.push(s),
            )
            .expect("worker run");
        for r in results {
            // A first-pass result carries its state's as-printed increment (solved on the
            // buckling solve's factor of K; the bed layer alone has none), so the page's last
            // evaluation does not solve it again.
            if max_split == 1 {
                let wire: Value = serde_json::from_str(&r).expect("wire");
                for w in wire.as_array().expect("list") {
                    assert!(
                        w["state"] == json!(0) || w["printed"]["du"].is_array(),
                        "state {} without its increment",
                        w["state"]
                    );
                }
            }
            *report = session.add_fe(generation, &r).expect("results taken");
        }
    };
    for run in &runs {
        solve(run, 1, &mut report);
    }
    // The page's part of the mesh-error pass: every batch the pass asks for, solved by a worker
    // (in the page: one state per worker message, both workers), until it asks for none.
    let mut batches = 0;
    while let Some(batch) = report["refine"].as_object().cloned() {
        assert_eq!(
            report["complete"],
            json!(false),
            "a pass still asking is not complete"
        );
        let states: Vec<usize> = serde_json::from_value(batch["states"].clone()).expect("states");
        let split = batch["max_split"].as_u64().expect("max_split") as usize;
        assert!(!states.is_empty() && split >= 2, "{batch:?}");
        solve(&states, split, &mut report);
        batches += 1;
        assert!(batches <= 64, "the pass keeps asking");
    }
    assert!(
        batches >= 1,
        "the converged BLF (the default) needs the 2×2 split somewhere"
    );
    assert_eq!(report["complete"], json!(true));

    let design = kappe::Design::from_toml_str(SHORT).expect("design");
    let options = kappe::Options {
        robot: false,
        ..kappe::Options::of(&design)
    };
    let outcome = kappe::run(&design, &options, &kappe::no_progress).expect("run");
    let analysis = outcome.analysis.as_ref().expect("analysis");
    assert_eq!(report["ok"], json!(outcome.verdict.ok));
    let (page_min, native_min) = (report["min_blf"].as_f64(), outcome.min_blf());
    match (page_min, native_min) {
        (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-9 * b.abs(), "{a} vs {b}"),
        (a, b) => assert_eq!(a, b),
    }
    let states = report["states"].as_array().expect("states");
    assert_eq!(states.len(), analysis.states.len());
    // Every BLF within 1e-9 relative: the mesh-error pass solves its states on the calling
    // thread here (faer may fork there) and inside rayon workers natively (faer sequential), so
    // the factorizations sum in a different order (~1e-14 observed); the bound is 1e-6.
    for (page, native) in states.iter().zip(&analysis.states) {
        match (page["blf"].as_f64(), native.blf) {
            (Some(a), Some(b)) => assert!(
                (a - b).abs() <= 1e-9 * b.abs(),
                "state {}: {a} vs {b}",
                native.index
            ),
            (a, b) => assert_eq!(a, b, "state {}", native.index),
        }
        assert_eq!(
            page["compression_pa"],
            json!(native.max_compression_stress_pa)
        );
    }
    // The constraint table: the same rows, verdicts and governing states; the worst values to
    // the BLFs' 1e-9 (above).
    let rows = report["constraints"].as_array().expect("constraints");
    assert_eq!(rows.len(), analysis.constraints.len());
    for (page, native) in rows.iter().zip(&analysis.constraints) {
        assert_eq!(page["name"], json!(native.name));
        assert_eq!(page["pass"], json!(native.pass), "{}", native.name);
        assert_eq!(page["state"], json!(native.state), "{}", native.name);
        match (page["worst"].as_f64(), native.worst) {
            (Some(a), Some(b)) => assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1e-300),
                "{}: {a} vs {b}",
                native.name
            ),
            (a, b) => assert_eq!(a, b, "{}", native.name),
        }
    }
}

#[test]
fn a_bad_value_names_its_field_and_keeps_the_design() {
    let mut session = SessionCore::new();
    session.load(SHORT).expect("design loads");
    let before = session.text().to_string();
    let e = session
        .set("cap.rise", &json!(-0.1))
        .expect_err("negative rise");
    assert_eq!(e.field, "cap.rise");
    assert!(e.message.contains("cap.rise"), "{}", e.message);
    assert_eq!(session.text(), before);
    let e = session
        .set("print.layer_width", &json!("wide"))
        .expect_err("text width");
    assert_eq!(e.field, "print.layer_width", "{}", e.message);
    assert_eq!(session.text(), before);
    let e = session.load("[cap\nspan = 1").expect_err("not TOML");
    assert!(
        e.message.contains("TOML") || e.message.contains("expected"),
        "{}",
        e.message
    );
    assert_eq!(session.text(), before);
}

#[test]
fn set_field_writes_dotted_fields() {
    let t = set_field("[cap]\nrise = 0.2\n", "cap.rise", &json!(0.22)).expect("set");
    assert!(t.contains("rise = 0.22"), "{t}");
    let t = set_field(&t, "material.time.preset", &json!("earth")).expect("set");
    assert!(t.contains("preset = \"earth\""), "{t}");
    assert!(set_field(&t, "cap.rise.x", &json!(1)).is_err());
    assert!(set_field(&t, "cap..rise", &json!(1)).is_err());
    let t = set_field(&t, "material.time.preset", &Value::Null).expect("remove");
    assert!(!t.contains("preset"), "{t}");
}
