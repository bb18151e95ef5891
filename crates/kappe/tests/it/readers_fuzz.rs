//! Issue 16: the readers of user files never panic. Random bytes and random structurally-valid
//! files (real files with values, types and keys replaced) go into the design reader, the
//! optimize and prototype readers, the CEM topology reader and the FE mesh reader; each must
//! return a named error or a valid result. Seeds are fixed (determinism); 256 cases per reader
//! keep the whole file under a few seconds.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use serde_json::Value;

fn config() -> Config {
    Config {
        cases: 256,
        rng_seed: RngSeed::Fixed(0x006b_6170_7065),
        failure_persistence: None,
        ..Config::default()
    }
}

/// Nasty TOML values: wrong types, non-finite, zero, negative, huge.
fn toml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("0.0".to_string()),
        Just("-1.0".to_string()),
        Just("1e308".to_string()),
        Just("-1e-308".to_string()),
        Just("9223372036854775807".to_string()),
        Just("\"text\"".to_string()),
        Just("true".to_string()),
        Just("[1.0, 2.0]".to_string()),
        Just("{ a = 1 }".to_string()),
        any::<f64>().prop_map(|v| format!("{v:?}")),
        (-5i64..1000).prop_map(|v| v.to_string()),
    ]
}

/// A JSON value to put somewhere in a valid document.
fn json_value() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Null),
        Just(serde_json::json!(-1)),
        Just(serde_json::json!(0)),
        Just(serde_json::json!(1e308)),
        Just(serde_json::json!(usize::MAX)),
        Just(serde_json::json!("text")),
        Just(serde_json::json!([])),
        Just(serde_json::json!({})),
        Just(serde_json::json!([[1.0, 2.0]])),
        any::<f64>()
            .prop_filter("JSON numbers are finite", |v| v.is_finite())
            .prop_map(|v| serde_json::json!(v)),
        (0u64..10_000).prop_map(|v| serde_json::json!(v)),
    ]
}

/// Replace the value at the `pick`-th position (depth-first) of `doc` by `new`; also used to
/// delete (`None`).
fn mutate(doc: &mut Value, pick: usize, new: Option<Value>) {
    fn walk(v: &mut Value, pick: &mut usize, new: &mut Option<Option<Value>>) {
        if new.is_none() {
            return;
        }
        if *pick == 0 {
            match new.take() {
                Some(Some(n)) => *v = n,
                Some(None) => *v = Value::Null,
                None => {}
            }
            return;
        }
        *pick -= 1;
        match v {
            Value::Array(a) => a.iter_mut().for_each(|x| walk(x, pick, new)),
            Value::Object(o) => o.values_mut().for_each(|x| walk(x, pick, new)),
            _ => {}
        }
    }
    let mut pick = pick;
    let mut new = Some(new);
    walk(doc, &mut pick, &mut new);
}

/// The design file's dotted keys, from the resolved default.
fn design_keys() -> Vec<(String, String)> {
    let table: toml::Table =
        toml::from_str(&kappe::Design::default().to_toml_string().unwrap()).unwrap();
    let mut keys = Vec::new();
    for (section, v) in &table {
        if let toml::Value::Table(t) = v {
            for (k, _) in t {
                keys.push((section.clone(), k.clone()));
            }
        }
    }
    keys
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn design_reader_survives_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = kappe::Design::from_toml_str(&text);
        let _ = kappe::commands::optimize::OptimizeFile::from_any_toml_str(&text);
        let _ = kappe::commands::calibrate_blf::PrototypeFile::from_toml_str(&text);
    }

    #[test]
    fn design_reader_names_the_field_or_accepts(
        picks in proptest::collection::vec((any::<prop::sample::Index>(), toml_value()), 1..4),
        unknown in any::<bool>(),
    ) {
        let keys = design_keys();
        let mut text = String::new();
        let mut fields = Vec::new();
        for (idx, value) in &picks {
            let (section, key) = idx.get(&keys);
            text.push_str(&format!("[{section}]\n{key} = {value}\n"));
            fields.push(format!("{section}.{key}"));
        }
        if unknown {
            text.push_str("[cap]\nspann = 1.0\n");
        }
        match kappe::Design::from_toml_str(&text) {
            Ok(design) => {
                // A valid result: it round-trips through the writer.
                prop_assert!(!unknown);
                let again = kappe::Design::from_toml_str(&design.to_toml_string().unwrap());
                prop_assert!(again.is_ok(), "{:?}", again.err());
            }
            Err(err) => {
                // A named error: a parse error (duplicate table, wrong type…) or the field.
                let msg = err.to_string();
                prop_assert!(!msg.is_empty());
                prop_assert!(
                    msg.contains("TOML parse error") || fields.iter().any(|f| msg.contains(f.as_str()))
                        || msg.contains('.'),
                    "{msg}"
                );
            }
        }
    }

    #[test]
    fn cem_reader_survives_mutated_topologies(pick in 0usize..400, value in json_value(), delete in any::<bool>()) {
        let mut doc: Value = serde_json::from_str(kappe_cem::example::EXAMPLE_ARCH_JSON).unwrap();
        mutate(&mut doc, pick, if delete { None } else { Some(value) });
        if let Ok(parsed) = kappe_cem::json::read_topology(&doc.to_string()) {
            // A topology the reader accepts is solved or rejected with a named error.
            let _ = kappe_cem::solve(&parsed.topology, &parsed.solver);
        }
    }

    #[test]
    fn fe_reader_survives_mutated_meshes(pick in 0usize..1200, value in json_value(), delete in any::<bool>()) {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/fixtures/fe/plate_ss_s3_n16.mesh.json"
        ))
        .unwrap();
        let mut doc: Value = serde_json::from_str(&text).unwrap();
        mutate(&mut doc, pick, if delete { None } else { Some(value) });
        let _ = kappe_fe::mesh_json::parse_mesh(&doc.to_string());
    }

    #[test]
    fn json_readers_survive_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = kappe_cem::json::read_topology(&text);
        let _ = kappe_fe::mesh_json::parse_mesh(&text);
    }
}
