//! Design studies (issue 8; the paper's Table 2 is one): a grid or list of variations of a base
//! design, each run through [`crate::run`], their rows, and the merge of shards. `kappe study`
//! and the Python `kappe.study` are thin callers of this module; the I/O (writing
//! `designs/<name>/…` and the study files) is theirs.
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
//! [`crate::Design::from_toml_str`]: so an unknown field or a wrong type is rejected exactly as
//! in a design file (a study error, naming the entry), while a value outside its allowed range
//! makes only that design fail (a row marked failed with the reason).
//!
//! Every design is analysed as `kappe design` analyses it: with its own `[analysis]` options
//! (by default shell buckling in every state). An optional `[analysis]` table in the study file
//! (e.g. `states = "25%"`, `buckling = false`, `modes = 3`) replaces them in every design, and
//! is written into every `designs/<name>/design.toml`, so that `kappe design` on that file alone
//! reaches the same verdict. (`kappe study --no-robot` corresponds to `kappe design --no-robot`.)
//!
//! Grid axes are taken in the alphabetical order of their paths, the last varying fastest;
//! grid designs are named `<field>=<value>` joined by `_` (e.g. `rise=0.15_span=0.6`).
//!
//! # Output
//! `DIR/study.csv` (one row per design), `DIR/study.html` ([`kappe_report::render_study_html`]),
//! `DIR/study.json` (the same rows, machine-readable; what `merge` reads) and per design
//! `DIR/designs/<name>/{design.toml, summary.json, report.html}` (`design.toml` is the input
//! of that design, so `kappe design DIR/designs/<name>/design.toml` reruns it alone). Designs run
//! independently ([`run_one`]): a design that fails, or even panics, becomes a failed row. The verdict of each design is
//! [`crate::verdict::design_ok`], the same function `kappe design` uses.
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

mod file;
mod merge;
mod run;
mod table;

pub use file::{get_path, parse, parse_shard, show, slurm_shard};
pub use merge::{Merged, merge};
pub use run::{DesignRun, Step, collect, error_record, parameter_values, run_designs, run_one};

use kappe_report::ConstraintRow;
use serde::{Deserialize, Serialize};

/// A study file or a set of shards that cannot be run or merged; the message names the entry.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StudyError {
    /// The study file is wrong (syntax, unknown key, a design entry that does not match the
    /// design schema, duplicate names, …).
    #[error("{0}")]
    File(String),
    /// A `--shard i/n` that is not one.
    #[error("{0}")]
    Shard(String),
    /// `study.json` is not a study result, or shards that do not belong together.
    #[error("{0}")]
    Merge(String),
}

/// One design of the study: its position in the study order, name, and input table.
#[derive(Debug, Clone)]
pub struct Variation {
    /// Position in the study order (0-based).
    pub index: usize,
    /// The design's name (a directory name).
    pub name: String,
    /// The design's TOML input (base table with the overrides and `name`).
    pub table: toml::Table,
    /// The design parsed from `table`, or why it is out of range (a failed row).
    pub design: Result<crate::Design, String>,
}

impl Variation {
    /// `designs/<name>/design.toml`: the design's input, so that `kappe design` on it reruns
    /// the design alone.
    pub fn design_toml(&self) -> String {
        toml::to_string(&self.table).unwrap_or_default()
    }
}

/// A parsed and validated study.
#[derive(Debug, Clone)]
pub struct Study {
    /// The page title.
    pub title: String,
    /// Varied parameter paths: the table's parameter columns.
    pub parameters: Vec<String>,
    /// Every design, in study order.
    pub variations: Vec<Variation>,
    /// FNV-1a over the analysis options and every design's name and input: shards of one
    /// study share it.
    pub fingerprint: String,
    /// Options of the finite-element analysis, if the study asks for it.
    pub analysis: Option<crate::analysis::AnalysisOptions>,
}

impl Study {
    /// The designs of shard `i` of `n` (those whose index is ≡ i mod n), or all.
    pub fn select(&self, shard: Option<(usize, usize)>) -> Vec<&Variation> {
        self.variations
            .iter()
            .filter(|v| shard.is_none_or(|(i, n)| v.index % n == i))
            .collect()
    }
}

/// Verdict of one design.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Ran and meets every constraint.
    Pass,
    /// Ran and violates a constraint.
    Fail,
    /// Could not be run (out-of-range parameter, form-finding or state error).
    Error,
}

impl Verdict {
    /// `pass`, `fail` or `error`, as in `study.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::Error => "error",
        }
    }
}

/// One design's results, as stored in `study.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Position in the study (0-based).
    pub index: usize,
    /// The design's name.
    pub name: String,
    /// The value of each varied parameter, as text.
    pub parameters: Vec<String>,
    /// Pass, fail, or could not run.
    pub outcome: Verdict,
    /// Why it could not run.
    pub error: Option<String>,
    /// Most compressive stress over all states, Pa.
    pub max_compression_stress_pa: Option<f64>,
    /// Largest stress over all states, Pa.
    pub max_tension_stress_pa: Option<f64>,
    /// Largest layer overhang, m.
    pub max_overhang_m: Option<f64>,
    /// Lowest buckling factor over the analysed states.
    pub min_blf: Option<f64>,
    /// Printed mass, kg.
    pub mass_kg: Option<f64>,
    /// Print time, s.
    pub print_time_s: Option<f64>,
    /// Print states.
    pub states: Option<usize>,
    /// `ok` or `failed: <reason>` when the robot was planned.
    pub robot: Option<String>,
    /// The design's constraint table (the report's).
    pub constraints: Vec<ConstraintRow>,
    /// Relative link to the design's report.
    pub report: Option<String>,
}

/// `study.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyResult {
    /// Always `kappe.study`.
    pub format: String,
    /// Format version.
    pub version: u32,
    /// The study's title.
    pub title: String,
    /// Hash of the study file, so shards of different studies are not merged.
    pub fingerprint: String,
    /// Every design name of the study, in study order (also those of other shards).
    pub designs: Vec<String>,
    /// `[i, n]` for a shard, absent for a whole study.
    pub shard: Option<[usize; 2]>,
    /// The varied parameters (design file paths).
    pub parameters: Vec<String>,
    /// One row per design.
    pub rows: Vec<Record>,
}

/// `study.json`'s `format`.
pub const RESULT_FORMAT: &str = "kappe.study.result";

impl StudyResult {
    /// Reads `study.json`.
    ///
    /// # Errors
    /// Not JSON of a study result, or another format or version.
    pub fn from_json(bytes: &[u8]) -> Result<StudyResult, StudyError> {
        let r: StudyResult = serde_json::from_slice(bytes)
            .map_err(|e| StudyError::Merge(format!("not a study result: {e}")))?;
        if r.format != RESULT_FORMAT || r.version != 1 {
            return Err(StudyError::Merge(format!(
                "format {} version {}, expected {RESULT_FORMAT} version 1",
                r.format, r.version
            )));
        }
        Ok(r)
    }

    /// `study.json`, pretty-printed.
    pub fn to_json(&self) -> Vec<u8> {
        serde_json::to_vec_pretty(self).unwrap_or_default()
    }

    /// Whether every design of the rows ran and passes (`kappe study` exits 0, else 1).
    pub fn all_pass(&self) -> bool {
        self.rows.iter().all(|r| r.outcome == Verdict::Pass)
    }

    /// The study in a few lines: how many designs pass, fail or could not run, and why each
    /// of the last could not.
    pub fn overview(&self) -> String {
        use std::fmt::Write;
        let count = |o: Verdict| self.rows.iter().filter(|r| r.outcome == o).count();
        let mut s = format!(
            "study \"{}\": {} of {} designs{}: {} pass, {} fail, {} could not be run\n",
            self.title,
            self.rows.len(),
            self.designs.len(),
            self.shard
                .map(|[i, n]| format!(" (shard {i}/{n})"))
                .unwrap_or_default(),
            count(Verdict::Pass),
            count(Verdict::Fail),
            count(Verdict::Error),
        );
        for r in self.rows.iter().filter(|r| r.outcome == Verdict::Error) {
            let _ = writeln!(s, "  {}: {}", r.name, r.error.as_deref().unwrap_or(""));
        }
        s
    }
}
