//! `kappe study STUDY.toml --out DIR` and `kappe study merge DIR... --out DIR`: design studies
//! (issue 8; the paper's Table 2 is one).
//!
//! # The study file
//! ```toml
//! title = "span and rise"          # optional, the page title (default: the file name)
//! base = "base.toml"               # a design file, relative to the study file; or an inline
//!                                  # [base] table in the design schema; or nothing (defaults)
//! [grid]                           # full factorial: every combination of the lists
//! "cap.span" = [0.6, 0.8, 1.0]
//! "cap.rise" = [0.15, 0.2]
//! ```
//! or a list of named variations instead of `[grid]`:
//! ```toml
//! [[design]]
//! name = "wide"
//! "cap.span" = 1.0                 # dotted keys or nested tables (`cap.span = 1.0`) both work
//! ```
//! Parameter paths are the design file's fields. Every variation is the base design's TOML
//! table with the overrides applied and `name` set to the variation's name, parsed by
//! [`kappe::Design::from_toml_str`]: so an unknown field or a wrong type is rejected exactly as
//! in a design file (a study error, naming the entry), while a value outside its allowed range
//! makes only that design fail (a row marked failed with the reason).
//!
//! An optional `[analysis]` table (the options of `kappe::constraints::analyze`, e.g.
//! `states = "25%"`, `buckling = false`, `modes = 3`) runs the finite-element analysis on every
//! design, adding the BLF and its verdict; without it designs are judged on stresses and
//! overhang only (the preliminary checks of [`crate::report_input::preliminary_constraints`]).
//!
//! Grid axes are taken in the alphabetical order of their paths, the last varying fastest;
//! grid designs are named `<field>=<value>` joined by `_` (e.g. `rise=0.15_span=0.6`).
//!
//! # Output
//! `DIR/study.csv` (one row per design), `DIR/study.html` ([`kappe_report::render_study_html`]),
//! `DIR/study.json` (the same rows, machine-readable; what `merge` reads) and per design
//! `DIR/designs/<name>/{design.toml, summary.json, report.html}` (`design.toml` is the input
//! of that design, so `kappe design DIR/designs/<name>/design.toml` reruns it alone). The whole
//! directory is written atomically. Designs run in parallel (rayon), each independently: a design
//! that fails, or even panics, becomes a failed row. The verdict of each design is
//! [`crate::report_input::design_ok`], the same function `kappe design` uses.
//!
//! # Shards
//! `--shard i/n` (0 ≤ i < n) runs the designs whose index in the study order is ≡ i (mod n) and
//! writes a partial study; `kappe study merge DIR0 DIR1 ... --out DIR` joins the shards (they must
//! come from the same study file: checked by a fingerprint of every design's input) into one
//! study whose files equal those of an unsharded run. With a Slurm job array:
//! `kappe study s.toml --shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT --out part-$SLURM_ARRAY_TASK_ID`.
//!
//! The CSV is written by hand (one quoting rule of RFC 4180 for text fields), and the
//! fingerprint is a hand-written FNV-1a: both are a few lines, and std's hasher is not
//! guaranteed stable across builds, which shards run on different machines would need.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use kappe_report::{ConstraintRow, StudyCell, StudyColumn, StudyRow, StudyTable};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::output::write_dir_atomic;
use crate::report_input::{evaluate, report_input};

/// `kappe study`: run a study file, or merge shards.
#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct StudyCommand {
    #[command(subcommand)]
    action: Option<StudyAction>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Subcommand)]
enum StudyAction {
    /// Merge the partial results of `--shard` runs into one study.
    Merge(MergeArgs),
}

#[derive(Args)]
struct RunArgs {
    /// Study file (TOML): a base design and a `[grid]` or a `[[design]]` list.
    #[arg(required = true)]
    study: Option<PathBuf>,
    /// Output directory (replaced atomically: nothing is written on error).
    #[arg(long, short, required = true)]
    out: Option<PathBuf>,
    /// Run only the designs i, i+n, i+2n, … of the study order (0 ≤ i < n) and write a partial
    /// result for `kappe study merge`.
    #[arg(long, value_name = "i/n")]
    shard: Option<String>,
    /// Number of designs run at the same time (default: one per core).
    #[arg(long, short)]
    jobs: Option<usize>,
    /// Skip robot motion planning (as `kappe design --no-robot`): designs are then judged
    /// without it.
    #[arg(long)]
    no_robot: bool,
    /// No progress bar and no summary.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args)]
struct MergeArgs {
    /// Output directories of the shards of one study.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output directory of the merged study (replaced atomically).
    #[arg(long, short)]
    out: PathBuf,
    /// Merge even if designs of the study are missing from the shards given.
    #[arg(long)]
    allow_incomplete: bool,
    /// No summary.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(cmd: StudyCommand) -> Result<ExitCode> {
    match cmd.action {
        Some(StudyAction::Merge(args)) => merge(args),
        None => run_study(cmd.run),
    }
}

// ---------------------------------------------------------------------------------------------
// The study file.

/// One design of the study: its position in the study order, name, and input table.
#[derive(Debug, Clone)]
struct Variation {
    index: usize,
    name: String,
    /// The design's TOML input (base table with the overrides and `name`).
    table: toml::Table,
    /// The design parsed from `table`, or why it is out of range (a failed row).
    design: std::result::Result<kappe::Design, String>,
}

/// A parsed and validated study.
#[derive(Debug, Clone)]
struct Study {
    title: String,
    /// Varied parameter paths: the table's parameter columns.
    parameters: Vec<String>,
    variations: Vec<Variation>,
    /// FNV-1a over the analysis options and every design's name and input: shards of one
    /// study share it.
    fingerprint: String,
    /// Options of the finite-element analysis, if the study asks for it.
    analysis: Option<kappe::constraints::AnalysisOptions>,
}

/// Flattens nested tables into dotted paths, so that `"cap.span" = 1` and `cap.span = 1` (or
/// `[cap] span = 1`) are the same override.
fn flatten(prefix: &str, table: &toml::Table, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in table {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(t) => flatten(&path, t, out),
            other => out.push((path, other.clone())),
        }
    }
}

/// Sets `path` (dotted; a key containing a dot is split) in `table`.
fn set_path(table: &mut toml::Table, path: &str, value: toml::Value) -> Result<()> {
    let parts: Vec<&str> = path.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        bail!("`{path}` is not a parameter path (expected e.g. `cap.span`)");
    }
    let Some((leaf, parents)) = parts.split_last() else {
        bail!("empty parameter path");
    };
    let mut cur = table;
    for (i, part) in parents.iter().enumerate() {
        let entry = cur
            .entry((*part).to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => bail!(
                "`{path}`: `{}` is a value, not a section of the design file",
                parts[..=i].join(".")
            ),
        };
    }
    cur.insert((*leaf).to_string(), value);
    Ok(())
}

/// Looks a dotted path up in a table.
fn get_path<'a>(table: &'a toml::Table, path: &str) -> Option<&'a toml::Value> {
    let mut parts = path.split('.');
    let mut cur = table.get(parts.next()?)?;
    for part in parts {
        cur = cur.as_table()?.get(part)?;
    }
    Some(cur)
}

/// A value as the user reads it: strings without quotes.
fn show(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Design names become directory names and links: keep them to a portable character set.
fn check_name(name: &str) -> std::result::Result<(), String> {
    let ok_char = |c: char| c.is_ascii_alphanumeric() || "._+=-".contains(c);
    if name.is_empty() {
        return Err("the name is empty".into());
    }
    if name.len() > 120 {
        return Err(format!(
            "the name has {} characters; at most 120",
            name.len()
        ));
    }
    if name.starts_with('.') || !name.chars().all(ok_char) {
        return Err(format!(
            "`{name}` is not a portable directory name: use letters, digits and . _ + = - \
             (not starting with a dot)"
        ));
    }
    Ok(())
}

/// The part of a grid value that goes into a design name.
fn name_part(value: &toml::Value) -> String {
    show(value)
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._+-".contains(c) {
                c
            } else {
                '-'
            }
        })
        .collect()
}

/// FNV-1a, 64 bit (see the module docs for why not std's hasher).
fn fnv1a(bytes: &[u8], mut hash: u64) -> u64 {
    for b in bytes {
        hash ^= u64::from(*b);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

/// Parses a design table: `Ok(Ok(design))`, `Ok(Err(reason))` for a value out of range (the
/// design fails, the study goes on), `Err` for a schema error (unknown field, wrong type: the
/// study file is wrong).
fn parse_design(table: &toml::Table) -> Result<std::result::Result<kappe::Design, String>> {
    let text = toml::to_string(table).context("cannot write the design as TOML")?;
    match kappe::Design::from_toml_str(&text) {
        Ok(d) => Ok(Ok(d)),
        Err(e @ kappe::DesignError::Parse { .. }) => Err(anyhow!(e)),
        Err(e) => Ok(Err(e.to_string())),
    }
}

/// Reads the base design table.
fn base_table(doc: &toml::Table, study_dir: &Path) -> Result<toml::Table> {
    let table = match doc.get("base") {
        None => toml::Table::new(),
        Some(toml::Value::Table(t)) => t.clone(),
        Some(toml::Value::String(file)) => {
            let path = study_dir.join(file);
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("cannot read the base design {}", path.display()))?;
            text.parse::<toml::Table>()
                .with_context(|| format!("the base design {} is not valid TOML", path.display()))?
        }
        Some(other) => bail!(
            "`base` must be a design file name or a [base] table, not a {}",
            other.type_str()
        ),
    };
    // Only schema errors matter here: a base out of range may be made valid by the overrides.
    let _range_checked_per_design =
        parse_design(&table).context("the base design does not match the design file schema")?;
    Ok(table)
}

/// Parses and validates a study file's text (`source` names it in messages and is the default
/// title; `study_dir` resolves `base = "file"`).
fn parse_study(text: &str, source: &str, study_dir: &Path) -> Result<Study> {
    let doc: toml::Table = text.parse().context("the study file is not valid TOML")?;
    for key in doc.keys() {
        if !["title", "base", "grid", "design", "analysis"].contains(&key.as_str()) {
            bail!(
                "unknown key `{key}` in the study file; allowed: title, base, grid (a table), \
                 design (a [[design]] list), analysis (a table)"
            );
        }
    }
    let title = match doc.get("title") {
        None => source.to_string(),
        Some(toml::Value::String(s)) => s.clone(),
        Some(other) => bail!("`title` must be a string, not a {}", other.type_str()),
    };
    let base = base_table(&doc, study_dir)?;
    let analysis = match doc.get("analysis") {
        None => None,
        Some(v) => {
            let o: kappe::constraints::AnalysisOptions = v
                .clone()
                .try_into()
                .map_err(|e: toml::de::Error| anyhow!("[analysis]: {}", e.message()))?;
            o.validate().context("[analysis]")?;
            Some(o)
        }
    };

    // (name, overrides) in study order, and the parameter columns.
    let (parameters, entries): Entries = match (doc.get("grid"), doc.get("design")) {
        (Some(_), Some(_)) => {
            bail!("the study file has both [grid] and [[design]]; give one of them")
        }
        (None, None) => {
            bail!("the study file has neither a [grid] table nor a [[design]] list: nothing to run")
        }
        (Some(grid), None) => grid_entries(grid, &base)?,
        (None, Some(list)) => list_entries(list, &base)?,
    };

    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (i, (name, _)) in entries.iter().enumerate() {
        check_name(name).map_err(|e| anyhow!("design #{} (`{name}`): {e}", i + 1))?;
        if let Some(first) = seen.insert(name.as_str(), i) {
            bail!(
                "duplicate design name `{name}` (designs #{} and #{}); design names must be unique",
                first + 1,
                i + 1
            );
        }
    }

    let mut hash = 0xcbf2_9ce4_8422_2325_u64;
    let options = serde_json::to_string(&analysis).unwrap_or_default();
    hash = fnv1a(options.as_bytes(), hash);
    let mut variations = Vec::with_capacity(entries.len());
    for (index, (name, overrides)) in entries.into_iter().enumerate() {
        let mut table = base.clone();
        for (path, value) in overrides {
            set_path(&mut table, &path, value)
                .with_context(|| format!("design `{name}`: cannot apply `{path}`"))?;
        }
        table.insert("name".into(), toml::Value::String(name.clone()));
        let design = parse_design(&table)
            .with_context(|| format!("design `{name}`: unknown parameter or wrong type"))?;
        let text = toml::to_string(&table).unwrap_or_default();
        hash = fnv1a(text.as_bytes(), fnv1a(name.as_bytes(), hash));
        variations.push(Variation {
            index,
            name,
            table,
            design,
        });
    }
    Ok(Study {
        title,
        parameters,
        variations,
        fingerprint: format!("{hash:016x}"),
        analysis,
    })
}

/// Checks one override path against the design schema: applied alone to the base, it must
/// parse (a range error is fine here: other overrides may make the design valid).
fn check_override(base: &toml::Table, path: &str, value: &toml::Value) -> Result<()> {
    if path == "name" || path == "base" {
        bail!("`{path}` is set by the study, not a design parameter");
    }
    let mut table = base.clone();
    set_path(&mut table, path, value.clone())?;
    parse_design(&table).map(|_| ())
}

type Entries = (Vec<String>, Vec<(String, Vec<(String, toml::Value)>)>);

fn grid_entries(grid: &toml::Value, base: &toml::Table) -> Result<Entries> {
    let toml::Value::Table(grid) = grid else {
        bail!("`grid` must be a table of parameter = [values]");
    };
    let mut axes = Vec::new();
    flatten("", grid, &mut axes);
    if axes.is_empty() {
        bail!(
            "the [grid] table is empty: give at least one parameter with a list of values, e.g. \"cap.span\" = [0.6, 0.8]"
        );
    }
    // Alphabetical by path, whatever the TOML map's order, so the study order is defined.
    axes.sort_by(|a, b| a.0.cmp(&b.0));
    let mut lists: Vec<(String, Vec<toml::Value>)> = Vec::new();
    for (path, value) in axes {
        let toml::Value::Array(values) = value else {
            bail!(
                "grid entry `{path}`: expected a list of values, e.g. [0.6, 0.8], got a {}",
                value.type_str()
            );
        };
        if values.is_empty() {
            bail!("grid entry `{path}` is an empty list: give at least one value");
        }
        let mut shown = HashSet::new();
        for v in &values {
            if !shown.insert(name_part(v)) {
                bail!("grid entry `{path}` lists the value {} twice", show(v));
            }
            check_override(base, &path, v)
                .with_context(|| format!("grid entry `{path}` = {}", show(v)))?;
        }
        lists.push((path, values));
    }
    // Name parts: the last path segment, unless two axes share it.
    let last = |p: &str| p.rsplit('.').next().unwrap_or(p).to_string();
    let lasts: Vec<String> = lists.iter().map(|(p, _)| last(p)).collect();
    let labels: Vec<String> = lists
        .iter()
        .map(|(p, _)| {
            if lasts.iter().filter(|l| **l == last(p)).count() > 1 {
                p.clone()
            } else {
                last(p)
            }
        })
        .collect();
    let total: usize = lists.iter().map(|(_, v)| v.len()).product();
    const MAX_DESIGNS: usize = 1_000_000;
    if total > MAX_DESIGNS {
        bail!(
            "the grid has {total} designs; at most {MAX_DESIGNS} (split it into several studies)"
        );
    }
    let mut entries = Vec::with_capacity(total);
    for k in 0..total {
        // Mixed radix, last axis fastest.
        let mut rest = k;
        let mut picks = vec![0usize; lists.len()];
        for (a, (_, values)) in lists.iter().enumerate().rev() {
            picks[a] = rest % values.len();
            rest /= values.len();
        }
        let mut overrides = Vec::with_capacity(lists.len());
        let mut name_parts = Vec::with_capacity(lists.len());
        for (a, (path, values)) in lists.iter().enumerate() {
            let v = &values[picks[a]];
            name_parts.push(format!("{}={}", labels[a], name_part(v)));
            overrides.push((path.clone(), v.clone()));
        }
        entries.push((name_parts.join("_"), overrides));
    }
    Ok((lists.into_iter().map(|(p, _)| p).collect(), entries))
}

fn list_entries(list: &toml::Value, base: &toml::Table) -> Result<Entries> {
    let toml::Value::Array(list) = list else {
        bail!("`design` must be a [[design]] list of tables");
    };
    if list.is_empty() {
        bail!("the [[design]] list is empty: nothing to run");
    }
    let mut parameters: Vec<String> = Vec::new();
    let mut entries = Vec::with_capacity(list.len());
    for (i, item) in list.iter().enumerate() {
        let toml::Value::Table(t) = item else {
            bail!("[[design]] #{}: expected a table", i + 1);
        };
        let name = match t.get("name") {
            Some(toml::Value::String(s)) => s.clone(),
            Some(other) => bail!(
                "[[design]] #{}: `name` must be a string, not a {}",
                i + 1,
                other.type_str()
            ),
            None => bail!("[[design]] #{}: every design needs a `name`", i + 1),
        };
        let mut rest = t.clone();
        rest.remove("name");
        let mut overrides = Vec::new();
        flatten("", &rest, &mut overrides);
        for (path, value) in &overrides {
            check_override(base, path, value)
                .with_context(|| format!("[[design]] #{} (`{name}`): `{path}`", i + 1))?;
            if !parameters.contains(path) {
                parameters.push(path.clone());
            }
        }
        entries.push((name, overrides));
    }
    Ok((parameters, entries))
}

/// `i/n` with 0 ≤ i < n.
fn parse_shard(spec: &str) -> Result<(usize, usize)> {
    let bad = || {
        anyhow!(
            "--shard `{spec}`: expected i/n with whole numbers 0 ≤ i < n (0-based shard i of n), \
             e.g. 0/4"
        )
    };
    let (i, n) = spec.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if n == 0 {
        bail!("--shard `{spec}`: the shard count n must be at least 1");
    }
    if i >= n {
        bail!(
            "--shard `{spec}`: the shard index must be below the count (0-based: 0..={})",
            n - 1
        );
    }
    Ok((i, n))
}

// ---------------------------------------------------------------------------------------------
// Running designs.

/// Verdict of one design.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Outcome {
    /// Ran and meets every constraint.
    Pass,
    /// Ran and violates a constraint.
    Fail,
    /// Could not be run (out-of-range parameter, form-finding or state error).
    Error,
}

impl Outcome {
    fn as_str(self) -> &'static str {
        match self {
            Outcome::Pass => "pass",
            Outcome::Fail => "fail",
            Outcome::Error => "error",
        }
    }
}

/// One design's results, as stored in `study.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Record {
    index: usize,
    name: String,
    /// The value of each varied parameter, as text.
    parameters: Vec<String>,
    outcome: Outcome,
    error: Option<String>,
    max_compression_stress_pa: Option<f64>,
    max_tension_stress_pa: Option<f64>,
    max_overhang_m: Option<f64>,
    min_blf: Option<f64>,
    mass_kg: Option<f64>,
    print_time_s: Option<f64>,
    states: Option<usize>,
    /// `ok` or `failed: <reason>` when the robot was planned.
    robot: Option<String>,
    /// The design's constraint table (the report's).
    constraints: Vec<ConstraintRow>,
    /// Relative link to the design's report.
    report: Option<String>,
}

/// `study.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct StudyResult {
    format: String,
    version: u32,
    title: String,
    fingerprint: String,
    /// Every design name of the study, in study order (also those of other shards).
    designs: Vec<String>,
    /// `[i, n]` for a shard, absent for a whole study.
    shard: Option<[usize; 2]>,
    parameters: Vec<String>,
    rows: Vec<Record>,
}

const RESULT_FORMAT: &str = "kappe.study.result";

fn failed_record(v: &Variation, parameters: Vec<String>, reason: String) -> Record {
    Record {
        index: v.index,
        name: v.name.clone(),
        parameters,
        outcome: Outcome::Error,
        error: Some(reason),
        max_compression_stress_pa: None,
        max_tension_stress_pa: None,
        max_overhang_m: None,
        min_blf: None,
        mass_kg: None,
        print_time_s: None,
        states: None,
        robot: None,
        constraints: Vec::new(),
        report: None,
    }
}

/// What is run for every design besides `design_cap`.
#[derive(Debug, Clone, Copy)]
struct Steps<'a> {
    /// The finite-element analysis, if the study asks for it.
    analysis: Option<&'a kappe::constraints::AnalysisOptions>,
    /// Plan the robot (for designs with `robot.enabled`), as `kappe design` does.
    robot: bool,
}

/// Runs one design and writes `designs/<name>/` under `root`. Any failure becomes an error row.
fn run_one(v: &Variation, parameter_paths: &[String], steps: Steps, root: &Path) -> Record {
    let parameters: Vec<String> = parameter_paths
        .iter()
        .map(|p| {
            // The effective value: the override, else the resolved design's own.
            get_path(&v.table, p)
                .map(show)
                .or_else(|| {
                    v.design.as_ref().ok().and_then(|d| {
                        d.to_toml_string()
                            .parse::<toml::Table>()
                            .ok()
                            .and_then(|t| get_path(&t, p).map(show))
                    })
                })
                .unwrap_or_default()
        })
        .collect();
    let dir = root.join("designs").join(&v.name);
    let input = toml::to_string(&v.table).unwrap_or_default();
    if let Err(e) = std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(dir.join("design.toml"), input.as_bytes()))
    {
        return failed_record(
            v,
            parameters,
            format!("cannot write {}: {e}", dir.display()),
        );
    }
    let design = match &v.design {
        Ok(d) => d,
        Err(reason) => return failed_record(v, parameters, reason.clone()),
    };
    let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| -> Result<Record> {
        let cap = kappe::design_cap(design, &|_| {})?;
        let plan = steps.robot && cap.design.robot.enabled;
        let eval = evaluate(&cap, steps.analysis, plan, &|_| {}, &|| {})?;
        let extras = &eval.extras;
        let robot = eval
            .robot
            .as_ref()
            .map(|r| r.as_ref().err().map(ToString::to_string));
        let ok = eval.ok;
        let input = report_input(&cap, extras);
        let html = kappe_report::render_html(&input).context("cannot render the report")?;
        let summary = eval.summary(&cap);
        std::fs::write(
            dir.join("summary.json"),
            serde_json::to_vec_pretty(&summary)?,
        )?;
        std::fs::write(dir.join("report.html"), html)?;
        let fold = |f: fn(&kappe::StateSummary) -> f64, init: f64, pick: fn(f64, f64) -> f64| {
            cap.states.iter().map(f).fold(init, pick)
        };
        let min_blf = extras
            .states
            .iter()
            .filter_map(|s| s.blf)
            .fold(None, |m: Option<f64>, b| Some(m.map_or(b, |m| m.min(b))));
        Ok(Record {
            index: v.index,
            name: v.name.clone(),
            parameters: parameters.clone(),
            outcome: if ok { Outcome::Pass } else { Outcome::Fail },
            error: None,
            max_compression_stress_pa: Some(fold(
                |s| s.forces.max_compression_stress,
                0.0,
                f64::min,
            )),
            max_tension_stress_pa: Some(fold(|s| s.forces.max_tension_stress, 0.0, f64::max)),
            max_overhang_m: Some(cap.overhangs.iter().fold(0.0, |m, o| m.max(o.abs()))),
            min_blf,
            mass_kg: Some(cap.path.mass),
            print_time_s: Some(cap.path.time),
            states: Some(cap.states.len()),
            robot: robot.map(|e| e.map_or_else(|| "ok".into(), |e| format!("failed: {e}"))),
            constraints: input.constraints,
            report: Some(format!("designs/{}/report.html", v.name)),
        })
    }));
    match outcome {
        Ok(Ok(record)) => record,
        Ok(Err(e)) => failed_record(v, parameters, format!("{e:#}")),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            failed_record(v, parameters, format!("internal error (panic): {what}"))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Writing the study files.

/// A CSV field: quoted (RFC 4180) when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number in its shortest round-trip form; scientific notation outside [1e-3, 1e15), where the
/// plain form would be long (Rust's `{}` never switches to an exponent by itself).
fn csv_num(v: Option<f64>) -> String {
    v.map(|x| {
        if x == 0.0 || (1e-3..1e15).contains(&x.abs()) {
            format!("{x}")
        } else {
            format!("{x:e}")
        }
    })
    .unwrap_or_default()
}

fn study_csv(result: &StudyResult) -> String {
    let mut s = String::new();
    let mut header: Vec<String> = vec!["name".into()];
    header.extend(result.parameters.iter().map(|p| csv_field(p)));
    header.extend(
        [
            "result",
            "max_compression_stress_pa",
            "max_tension_stress_pa",
            "max_overhang_m",
            "min_blf",
            "mass_kg",
            "print_time_s",
            "states",
            "robot",
            "error",
        ]
        .map(String::from),
    );
    s.push_str(&header.join(","));
    s.push('\n');
    for r in &result.rows {
        let mut f: Vec<String> = vec![csv_field(&r.name)];
        f.extend(r.parameters.iter().map(|p| csv_field(p)));
        f.push(r.outcome.as_str().into());
        f.push(csv_num(r.max_compression_stress_pa));
        f.push(csv_num(r.max_tension_stress_pa));
        f.push(csv_num(r.max_overhang_m));
        f.push(csv_num(r.min_blf));
        f.push(csv_num(r.mass_kg));
        f.push(csv_num(r.print_time_s));
        f.push(r.states.map(|n| n.to_string()).unwrap_or_default());
        f.push(csv_field(r.robot.as_deref().unwrap_or("")));
        f.push(csv_field(r.error.as_deref().unwrap_or("")));
        s.push_str(&f.join(","));
        s.push('\n');
    }
    s
}

/// Unit of a design parameter, for the table header.
fn unit_of(path: &str) -> &'static str {
    match path {
        "cap.span"
        | "cap.rise"
        | "cap.length"
        | "print.layer_height"
        | "print.layer_width"
        | "print.nozzle_diameter"
        | "print.path_sampling"
        | "constraints.overhang_max"
        | "robot.tool_length" => "m",
        "cap.tilt_deg" | "robot.rotation_step_deg" => "deg",
        "material.specific_weight" => "N/m³",
        "material.youngs_modulus" | "constraints.sigma_min" | "constraints.sigma_max" => "Pa",
        "print.print_speed" => "m/s",
        "robot.epsilon" => "rad²",
        _ => "",
    }
}

fn study_table(result: &StudyResult) -> StudyTable {
    let mut parameters: Vec<StudyColumn> = result
        .parameters
        .iter()
        .map(|p| StudyColumn {
            name: p.clone(),
            unit: unit_of(p).into(),
        })
        .collect();
    // Figures that are results, not constraints, shown next to the parameters.
    parameters.push(StudyColumn {
        name: "mass".into(),
        unit: "kg".into(),
    });
    parameters.push(StudyColumn {
        name: "print time".into(),
        unit: "min".into(),
    });
    // Constraint columns: every constraint any design reports, in first-seen order.
    let mut constraints: Vec<StudyColumn> = Vec::new();
    for r in &result.rows {
        for c in &r.constraints {
            if !constraints.iter().any(|k| k.name == c.name) {
                constraints.push(StudyColumn {
                    name: c.name.clone(),
                    unit: c.unit.clone(),
                });
            }
        }
    }
    let keys: Vec<String> = constraints.iter().map(|c| c.name.clone()).collect();
    let rows = result
        .rows
        .iter()
        .map(|r| {
            let mut values = r.parameters.clone();
            values.push(r.mass_kg.map(|m| format!("{m:.2}")).unwrap_or_default());
            values.push(
                r.print_time_s
                    .map(|t| format!("{:.1}", t / 60.0))
                    .unwrap_or_default(),
            );
            StudyRow {
                name: r.name.clone(),
                parameters: values,
                constraints: keys
                    .iter()
                    .map(|k| {
                        r.constraints
                            .iter()
                            .find(|c| &c.name == k)
                            .map(|c| StudyCell {
                                value: c.worst,
                                pass: c.pass,
                            })
                    })
                    .collect(),
                error: r.error.clone(),
                report_href: r.report.clone(),
            }
        })
        .collect();
    StudyTable {
        title: result.title.clone(),
        parameters,
        constraints,
        rows,
    }
}

/// Writes `study.json`, `study.csv` and `study.html` into `dir`.
fn write_study_files(dir: &Path, result: &StudyResult) -> Result<()> {
    let html = kappe_report::render_study_html(&study_table(result))
        .context("cannot render study.html")?;
    std::fs::write(dir.join("study.json"), serde_json::to_vec_pretty(result)?)?;
    std::fs::write(dir.join("study.csv"), study_csv(result))?;
    std::fs::write(dir.join("study.html"), html)?;
    Ok(())
}

fn print_summary(result: &StudyResult, out: &Path) {
    let count = |o: Outcome| result.rows.iter().filter(|r| r.outcome == o).count();
    println!(
        "study \"{}\": {} of {} designs{}: {} pass, {} fail, {} could not be run",
        result.title,
        result.rows.len(),
        result.designs.len(),
        result
            .shard
            .map(|[i, n]| format!(" (shard {i}/{n})"))
            .unwrap_or_default(),
        count(Outcome::Pass),
        count(Outcome::Fail),
        count(Outcome::Error),
    );
    for r in result.rows.iter().filter(|r| r.outcome == Outcome::Error) {
        println!("  {}: {}", r.name, r.error.as_deref().unwrap_or(""));
    }
    println!(
        "  wrote {}/{{study.csv, study.html, study.json, designs/}}",
        out.display()
    );
}

fn run_study(args: RunArgs) -> Result<ExitCode> {
    let (Some(path), Some(out)) = (args.study, args.out) else {
        bail!("give a STUDY.toml and --out DIR");
    };
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read the study file {}", path.display()))?;
    let source = path.file_name().map_or_else(
        || path.display().to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    let study_dir = path.parent().unwrap_or(Path::new("."));
    let study = parse_study(&text, &source, study_dir)
        .with_context(|| format!("invalid study file {}", path.display()))?;

    let selected: Vec<&Variation> = study
        .variations
        .iter()
        .filter(|v| shard.is_none_or(|(i, n)| v.index % n == i))
        .collect();
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(selected.len() as u64);
        b.set_style(
            ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} designs ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        b.set_message("study");
        b
    };
    let pool = {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(j) = args.jobs {
            if j == 0 {
                bail!("--jobs 0: give at least 1");
            }
            builder = builder.num_threads(j);
        }
        builder.build().context("cannot start the worker threads")?
    };
    let steps = Steps {
        analysis: study.analysis.as_ref(),
        robot: !args.no_robot,
    };
    let mut result = None;
    write_dir_atomic(&out, |dir| {
        std::fs::create_dir_all(dir.join("designs"))?;
        let rows: Vec<Record> = pool.install(|| {
            selected
                .par_iter()
                .map(|v| {
                    let r = run_one(v, &study.parameters, steps, dir);
                    bar.inc(1);
                    r
                })
                .collect()
        });
        let r = StudyResult {
            format: RESULT_FORMAT.into(),
            version: 1,
            title: study.title.clone(),
            // Shards run with and without the robot must not be merged.
            fingerprint: if args.no_robot {
                format!("{}-no-robot", study.fingerprint)
            } else {
                study.fingerprint.clone()
            },
            designs: study.variations.iter().map(|v| v.name.clone()).collect(),
            shard: shard.map(|(i, n)| [i, n]),
            parameters: study.parameters.clone(),
            rows,
        };
        // The files are rendered from the rows as `study.json` stores them, so that a merge of
        // shards (which reads them back from JSON) writes exactly the same bytes.
        let r: StudyResult = serde_json::from_slice(&serde_json::to_vec(&r)?)?;
        write_study_files(dir, &r)?;
        result = Some(r);
        Ok(())
    })?;
    bar.finish_and_clear();
    if let (Some(r), false) = (&result, args.quiet) {
        print_summary(r, &out);
    }
    Ok(ExitCode::SUCCESS)
}

// ---------------------------------------------------------------------------------------------
// Merging shards.

fn read_result(dir: &Path) -> Result<StudyResult> {
    let path = dir.join("study.json");
    let text = std::fs::read(&path).with_context(|| {
        format!(
            "cannot read {} (is {} the output of `kappe study`?)",
            path.display(),
            dir.display()
        )
    })?;
    let r: StudyResult = serde_json::from_slice(&text)
        .with_context(|| format!("{} is not a study result", path.display()))?;
    if r.format != RESULT_FORMAT || r.version != 1 {
        bail!(
            "{}: format {} version {}, expected {RESULT_FORMAT} version 1",
            path.display(),
            r.format,
            r.version
        );
    }
    Ok(r)
}

fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("cannot create {}", to.display()))?;
    for entry in
        std::fs::read_dir(from).with_context(|| format!("cannot read {}", from.display()))?
    {
        let entry = entry?;
        let target = to.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            copy_dir(&entry.path(), &target)?;
        } else {
            std::fs::copy(entry.path(), &target).with_context(|| {
                format!(
                    "cannot copy {} to {}",
                    entry.path().display(),
                    target.display()
                )
            })?;
        }
    }
    Ok(())
}

fn merge(args: MergeArgs) -> Result<ExitCode> {
    let out_abs = std::path::absolute(&args.out).unwrap_or_else(|_| args.out.clone());
    let mut parts = Vec::with_capacity(args.dirs.len());
    for dir in &args.dirs {
        if std::path::absolute(dir).is_ok_and(|d| d == out_abs) {
            bail!(
                "--out {} is also an input; merge into a new directory",
                args.out.display()
            );
        }
        parts.push((dir.clone(), read_result(dir)?));
    }
    let Some((first_dir, first)) = parts.first() else {
        bail!("give at least one shard directory");
    };
    let mut rows: BTreeMap<usize, (Record, &Path)> = BTreeMap::new();
    for (dir, r) in &parts {
        if r.fingerprint != first.fingerprint || r.designs != first.designs {
            bail!(
                "{} and {} are results of different studies (fingerprints {} and {})",
                first_dir.display(),
                dir.display(),
                first.fingerprint,
                r.fingerprint
            );
        }
        for row in &r.rows {
            if first.designs.get(row.index) != Some(&row.name) {
                bail!(
                    "{}: design `{}` has index {}, which the study gives to another design",
                    dir.display(),
                    row.name,
                    row.index
                );
            }
            if let Some((_, other)) = rows.insert(row.index, (row.clone(), dir)) {
                bail!(
                    "design `{}` is in both {} and {}; give every shard once",
                    row.name,
                    other.display(),
                    dir.display()
                );
            }
        }
    }
    let missing: Vec<&str> = first
        .designs
        .iter()
        .enumerate()
        .filter(|(i, _)| !rows.contains_key(i))
        .map(|(_, n)| n.as_str())
        .collect();
    if !missing.is_empty() && !args.allow_incomplete {
        let shown: Vec<&str> = missing.iter().take(10).copied().collect();
        bail!(
            "{} of {} designs are missing from the shards given (e.g. {}); pass every shard, \
             or --allow-incomplete",
            missing.len(),
            first.designs.len(),
            shown.join(", ")
        );
    }
    let result = StudyResult {
        format: RESULT_FORMAT.into(),
        version: 1,
        title: first.title.clone(),
        fingerprint: first.fingerprint.clone(),
        designs: first.designs.clone(),
        shard: None,
        parameters: first.parameters.clone(),
        rows: rows.values().map(|(r, _)| r.clone()).collect(),
    };
    write_dir_atomic(&args.out, |dir| {
        for (row, src) in rows.values() {
            let from = src.join("designs").join(&row.name);
            if from.is_dir() {
                copy_dir(&from, &dir.join("designs").join(&row.name))?;
            }
        }
        std::fs::create_dir_all(dir.join("designs"))?;
        write_study_files(dir, &result)
    })?;
    if !args.quiet {
        print_summary(&result, &args.out);
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Study> {
        parse_study(text, "test.toml", Path::new("."))
    }

    #[test]
    fn grid_is_full_factorial_in_alphabetical_axis_order() {
        let s = parse("[grid]\n\"cap.span\" = [0.6, 0.8]\ncap.rise = [0.15, 0.2, 0.25]\n").unwrap();
        assert_eq!(s.parameters, ["cap.rise", "cap.span"]);
        let names: Vec<&str> = s.variations.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(names[0], "rise=0.15_span=0.6");
        assert_eq!(names[1], "rise=0.15_span=0.8");
        assert_eq!(names[5], "rise=0.25_span=0.8");
        assert_eq!(names.len(), 6);
        let d = s.variations[5].design.as_ref().unwrap();
        assert_eq!(
            (d.cap.rise, d.cap.span, d.name.as_str()),
            (0.25, 0.8, names[5])
        );
    }

    #[test]
    fn bad_studies_are_rejected_with_the_entry_named() {
        let err = |t: &str| format!("{:#}", parse(t).unwrap_err());
        assert!(err("[grid]\n").contains("[grid] table is empty"));
        assert!(err("[grid]\n\"cap.span\" = []\n").contains("`cap.span` is an empty list"));
        assert!(err("[grid]\n\"cap.spam\" = [1.0]\n").contains("grid entry `cap.spam`"));
        assert!(err("[grid]\n\"cap.span\" = [\"wide\"]\n").contains("grid entry `cap.span`"));
        assert!(err("[grid]\n\"cap.span.x\" = [1.0]\n").contains("grid entry `cap.span.x`"));
        assert!(
            err("[[design]]\nname = \"a\"\n[[design]]\nname = \"a\"\n")
                .contains("duplicate design name `a`")
        );
        assert!(err("[[design]]\nname = \"a b\"\n").contains("not a portable directory name"));
        assert!(
            err("[[design]]\nname = \"a\"\nprint.layer_hieght = 0.01\n")
                .contains("`print.layer_hieght`")
        );
        assert!(err("grid = 1\n[[design]]\nname = \"a\"\n").contains("both"));
        assert!(err("title = \"x\"\n").contains("neither"));
        assert!(err("[gird]\n").contains("unknown key `gird`"));
        assert!(
            err("[base]\ncap.spn = 1.0\n[grid]\n\"cap.span\" = [1.0]\n").contains("base design")
        );
    }

    #[test]
    fn out_of_range_values_fail_only_their_design() {
        let s = parse("[grid]\n\"print.layer_height\" = [0.01, 0.5]\n").unwrap();
        assert!(s.variations[0].design.is_ok());
        let reason = s.variations[1].design.as_ref().unwrap_err();
        assert!(reason.contains("print.layer_height"), "{reason}");
    }

    #[test]
    fn shard_specs() {
        assert_eq!(parse_shard("1/3").unwrap(), (1, 3));
        for bad in ["3/3", "1/0", "a/2", "1", "-1/2", "1/2/3"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn csv_quotes_only_what_needs_it() {
        assert_eq!(csv_field("plain"), "plain");
        assert_eq!(csv_field("a, \"b\""), "\"a, \"\"b\"\"\"");
    }
}
