//! The floor plan of `crates/kappe/src` (issue 22): every top-level module imports only the
//! modules on the floors below it, so the import graph between them has no cycle. A `crate::`
//! path in code (not in a comment, not in a `#[cfg(test)] mod tests` block) is an import; a
//! root re-export (`crate::Design`, `crate::run`, …) counts as the module that defines it.

use std::collections::{BTreeMap, BTreeSet};
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

/// Crates whose top-level modules still import each other in a cycle, and why it is not yet
/// broken. Empty is the aim; a crate leaves this list when its cycle is broken (the test below
/// fails for a listed crate that has none, so the list cannot go stale).
const CYCLIC_CRATES: [&str; 0] = [];

/// The top-level modules of a crate's `src` and the files of each.
fn modules(src: &Path) -> Vec<(String, Vec<PathBuf>)> {
    let mut out: Vec<(String, Vec<PathBuf>)> = std::fs::read_dir(src)
        .unwrap()
        .flatten()
        .filter_map(|e| {
            let p = e.path();
            let name = p.file_stem()?.to_str()?.to_string();
            if name == "lib" || name == "main" {
                return None;
            }
            if p.is_dir() {
                Some((name, sources(&p)))
            } else if p.extension().is_some_and(|x| x == "rs") {
                Some((name, vec![p]))
            } else {
                None
            }
        })
        .collect();
    out.sort();
    out
}

/// A cycle in the import graph between the modules, if there is one (depth-first search).
fn cycle(graph: &[(String, BTreeSet<String>)]) -> Option<Vec<String>> {
    fn visit(
        v: usize,
        graph: &[(String, BTreeSet<String>)],
        state: &mut [u8],
        stack: &mut Vec<usize>,
    ) -> Option<Vec<String>> {
        state[v] = 1;
        stack.push(v);
        for w in &graph[v].1 {
            let Some(j) = graph.iter().position(|(n, _)| n == w) else {
                continue;
            };
            if state[j] == 1 {
                let from = stack.iter().position(|&k| k == j).unwrap_or(0);
                return Some(stack[from..].iter().map(|&k| graph[k].0.clone()).collect());
            }
            if state[j] == 0
                && let Some(c) = visit(j, graph, state, stack)
            {
                return Some(c);
            }
        }
        stack.pop();
        state[v] = 2;
        None
    }
    let mut state = vec![0u8; graph.len()];
    for v in 0..graph.len() {
        if state[v] == 0
            && let Some(c) = visit(v, graph, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

/// A crate's code without comment lines and without its unit-test module.
fn code_of(text: &str) -> String {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    code.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The leading identifier of `s` (after spaces).
fn ident(s: &str) -> String {
    s.trim_start()
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The first path segments `code` names through `crate::`: `crate::m::x` gives `m`, a group
/// `crate::{a::x, b::{y, z}, C}` gives `a`, `b` and `C` (a group may span lines).
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (i, _) in code.match_indices("crate::") {
        let rest = &code[i + 7..];
        if let Some(group) = rest.strip_prefix('{') {
            let (mut depth, mut start) = (0usize, 0usize);
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        out.push(ident(&group[start..k]));
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        out.push(ident(&group[start..k]));
                        start = k + 1;
                    }
                    _ => {}
                }
            }
        } else {
            out.push(ident(rest));
        }
    }
    out.retain(|m| !m.is_empty());
    out
}

/// The crate root's re-exports: each name `pub use m::…` makes available at the root, mapped
/// to its module `m` (so `crate::Name` counts as an import of `m`).
fn root_reexports(src: &Path, names: &BTreeSet<String>) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for root in ["lib.rs", "main.rs"] {
        let Ok(text) = std::fs::read_to_string(src.join(root)) else {
            continue;
        };
        for stmt in code_of(&text).split(';') {
            let Some(path) = stmt.trim_start().strip_prefix("pub use ") else {
                continue;
            };
            let path = path.trim_start();
            let path = path
                .strip_prefix("crate::")
                .or_else(|| path.strip_prefix("self::"))
                .unwrap_or(path);
            let module = ident(path);
            if !names.contains(&module) {
                continue;
            }
            let items = &path[module.len()..];
            for word in items.split(|c: char| !(c.is_alphanumeric() || c == '_')) {
                if !word.is_empty() && word != "as" && word != "self" {
                    out.entry(word.to_string())
                        .or_insert_with(|| module.clone());
                }
            }
        }
    }
    out
}

/// The import graph of one crate's top-level modules: the `crate::` paths in code (groups
/// included), a root re-export followed to the module it comes from (a cycle closed only
/// through the root is still a cycle).
fn crate_graph(src: &Path) -> Vec<(String, BTreeSet<String>)> {
    let mods = modules(src);
    let names: BTreeSet<String> = mods.iter().map(|(n, _)| n.clone()).collect();
    let root = root_reexports(src, &names);
    mods.into_iter()
        .map(|(name, files)| {
            let mut deps = BTreeSet::new();
            for f in files {
                let text = std::fs::read_to_string(&f).unwrap();
                for m in crate_paths(&code_of(&text)) {
                    let m = if names.contains(&m) {
                        Some(m)
                    } else {
                        root.get(&m).cloned()
                    };
                    if let Some(m) = m
                        && m != name
                    {
                        deps.insert(m);
                    }
                }
            }
            (name, deps)
        })
        .collect()
}

#[test]
fn no_crate_of_the_workspace_has_an_import_cycle_between_its_modules() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut found = Vec::new();
    let mut names: Vec<PathBuf> = std::fs::read_dir(&crates)
        .unwrap()
        .flatten()
        .map(|e| e.path().join("src"))
        .filter(|p| p.is_dir())
        .collect();
    names.sort();
    assert!(names.len() >= 8, "the workspace's crates: {names:?}");
    for src in names {
        let name = src
            .parent()
            .and_then(|p| p.file_name())
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        let c = cycle(&crate_graph(&src));
        let listed = CYCLIC_CRATES.contains(&name.as_str());
        match (c, listed) {
            (Some(c), false) => found.push(format!("{name}: {}", c.join(" → "))),
            (None, true) => found.push(format!("{name} has no cycle: take it off CYCLIC_CRATES")),
            _ => {}
        }
    }
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn the_cycle_search_finds_a_cycle_and_only_a_cycle() {
    let g = |edges: &[(&str, &[&str])]| -> Vec<(String, BTreeSet<String>)> {
        edges
            .iter()
            .map(|(n, d)| (n.to_string(), d.iter().map(|s| s.to_string()).collect()))
            .collect()
    };
    let chain = g(&[("a", &["b"]), ("b", &["c"]), ("c", &[])]);
    assert_eq!(cycle(&chain), None);
    let diamond = g(&[("a", &["b", "c"]), ("b", &["d"]), ("c", &["d"]), ("d", &[])]);
    assert_eq!(cycle(&diamond), None);
    let ring = g(&[("a", &["b"]), ("b", &["c"]), ("c", &["a"])]);
    assert_eq!(cycle(&ring).map(|c| c.len()), Some(3));
}

#[test]
fn the_import_scan_follows_groups_and_root_reexports() {
    let code = "use crate::{a::x,\n    b::{y, z}, Root};\nfn f() { crate::c::g(); }";
    assert_eq!(crate_paths(code), ["a", "b", "Root", "c"]);
    let dir = std::env::temp_dir().join(format!("kappe-floors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("lib.rs"),
        "mod a;\npub use a::{Root, helper as h};\npub use crate::b::Other;\n",
    )
    .unwrap();
    let names: BTreeSet<String> = ["a", "b"].iter().map(|s| s.to_string()).collect();
    let root = root_reexports(&dir, &names);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(root.get("Root").map(String::as_str), Some("a"));
    assert_eq!(root.get("helper").map(String::as_str), Some("a"));
    assert_eq!(root.get("Other").map(String::as_str), Some("b"));
}
