//! The floor plan of `crates/kappe/src` (issue 22): every top-level module imports only the
//! modules on the floors below it, so the import graph between them has no cycle. A `crate::`
//! path in code (not in a comment, not in a `#[cfg(test)] mod tests` block) is an import; a
//! root re-export (`crate::Design`, `crate::run`, …) counts as the module that defines it.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The floors, bottom first (the order of `lib.rs`'s table).
const FLOORS: [&str; 10] = [
    "input",
    "form",
    "robot_plan",
    "schedule",
    "analysis",
    "verdict",
    "run",
    "output",
    "commands",
    "class",
];

/// The root re-exports of `lib.rs` and the module each comes from.
const ROOT_ITEMS: [(&str, &str); 12] = [
    ("Context", "input"),
    ("Design", "input"),
    ("DesignError", "input"),
    ("Cap", "form"),
    ("StateSummary", "form"),
    ("design_cap", "form"),
    ("Options", "run"),
    ("Outcome", "run"),
    ("Progress", "run"),
    ("Stage", "run"),
    ("evaluate", "run"),
    ("no_progress", "run"),
];

fn sources(path: &Path) -> Vec<PathBuf> {
    if path.is_dir() {
        let mut out = Vec::new();
        for entry in std::fs::read_dir(path).unwrap().flatten() {
            out.extend(sources(&entry.path()));
        }
        out
    } else if path.extension().is_some_and(|e| e == "rs") {
        vec![path.to_path_buf()]
    } else {
        Vec::new()
    }
}

/// The top-level modules a source file's code names through `crate::`.
fn imports(text: &str) -> BTreeSet<String> {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    let mut out = BTreeSet::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        for (i, _) in line.match_indices("crate::") {
            let name: String = line[i + 7..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            let module = ROOT_ITEMS
                .iter()
                .find(|(item, _)| *item == name)
                .map_or(name.as_str(), |(_, m)| m);
            out.insert(module.to_string());
        }
    }
    out
}

#[test]
fn every_module_imports_only_the_floors_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut violations = Vec::new();
    for (floor, module) in FLOORS.iter().enumerate() {
        let dir = src.join(module);
        let file = src.join(format!("{module}.rs"));
        let files = if dir.is_dir() {
            sources(&dir)
        } else {
            vec![file]
        };
        assert!(!files.is_empty(), "module {module} has no source");
        for f in files {
            let text = std::fs::read_to_string(&f).unwrap();
            for m in imports(&text) {
                if m != *module && !FLOORS[..floor].contains(&m.as_str()) {
                    violations.push(format!("{} imports crate::{m}", f.display()));
                }
            }
        }
    }
    assert!(violations.is_empty(), "{violations:#?}");
}

#[test]
fn every_top_level_module_is_on_a_floor() {
    // A new top-level module must be given its floor here (and in lib.rs's table).
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut modules: Vec<String> = std::fs::read_dir(&src)
        .unwrap()
        .flatten()
        .filter_map(|e| {
            let p = e.path();
            let name = p.file_stem()?.to_str()?.to_string();
            (p.is_dir() || p.extension().is_some_and(|x| x == "rs")).then_some(name)
        })
        .filter(|n| n != "lib")
        .collect();
    modules.sort();
    modules.dedup();
    let mut floors: Vec<String> = FLOORS.iter().map(|s| s.to_string()).collect();
    floors.sort();
    assert_eq!(modules, floors);
}

#[test]
fn the_rule_sees_an_upward_import() {
    // The detector itself: an import in code is seen, one in a comment or a test module is not.
    let text = "use crate::output::x;\n// crate::commands\nfn f() { crate::Design::default(); }\n\
                #[cfg(test)]\nmod tests { use crate::class; }\n";
    let found: Vec<String> = imports(text).into_iter().collect();
    assert_eq!(found, ["input", "output"]);
}
