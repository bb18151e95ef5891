//! Running the designs of a study: one design at a time ([`run_one`], no I/O: the caller writes
//! the files it returns), and the rows collected into a [`StudyResult`] ([`collect`]).

use std::panic::AssertUnwindSafe;

use super::file::{get_path, show};
use super::{RESULT_FORMAT, Record, Study, StudyError, StudyResult, Variation, Verdict};
use crate::run::{Options, no_progress};

/// What one design of a study produced: its row and, if it ran, its files.
#[derive(Debug, Clone)]
pub struct DesignRun {
    /// The row of `study.csv` / `study.json`.
    pub record: Record,
    /// `designs/<name>/summary.json` (the same as `kappe design` writes), if the design ran.
    pub summary: Option<crate::output::summary::Summary>,
    /// `designs/<name>/report.html`, if the design ran.
    pub report_html: Option<String>,
}

/// The value of each varied parameter of `v`, as text: the override, else the resolved
/// design's own value.
pub fn parameter_values(v: &Variation, parameter_paths: &[String]) -> Vec<String> {
    parameter_paths
        .iter()
        .map(|p| {
            get_path(&v.table, p)
                .map(show)
                .or_else(|| {
                    v.design.as_ref().ok().and_then(|d| {
                        d.to_toml_string()
                            .ok()
                            .and_then(|s| s.parse::<toml::Table>().ok())
                            .and_then(|t| get_path(&t, p).map(show))
                    })
                })
                .unwrap_or_default()
        })
        .collect()
}

/// The row of a design that could not be run, with the reason.
pub fn error_record(v: &Variation, parameters: Vec<String>, reason: String) -> Record {
    Record {
        index: v.index,
        name: v.name.clone(),
        parameters,
        outcome: Verdict::Error,
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

/// Runs one design through [`crate::run`] as `kappe design` would ([`Options::of`]: the
/// design's own `[analysis]`, which carries the study's; the robot unless `no_robot`). Never
/// fails: a design out of range, one that cannot be form-found, or even a panic becomes an error
/// row.
pub fn run_one(v: &Variation, parameters: Vec<String>, no_robot: bool) -> DesignRun {
    let failed = |reason: String| DesignRun {
        record: error_record(v, parameters.clone(), reason),
        summary: None,
        report_html: None,
    };
    let design = match &v.design {
        Ok(d) => d,
        Err(reason) => return failed(reason.clone()),
    };
    let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| -> Result<DesignRun, String> {
        let options = Options {
            robot: !no_robot,
            ..Options::of(design)
        };
        let out = crate::run(design, &options, &no_progress).map_err(|e| e.to_string())?;
        let cap = &out.cap;
        let robot = out
            .robot
            .as_ref()
            .map(|r| r.as_ref().err().map(ToString::to_string));
        let input = out.report_input();
        let html = kappe_report::render_html(&input)
            .map_err(|e| format!("cannot render the report: {e}"))?;
        let summary = out.summary();
        let fold = |f: fn(&crate::StateSummary) -> f64, init: f64, pick: fn(f64, f64) -> f64| {
            cap.states.iter().map(f).fold(init, pick)
        };
        let record = Record {
            index: v.index,
            name: v.name.clone(),
            parameters: parameters.clone(),
            outcome: if out.verdict.ok {
                Verdict::Pass
            } else {
                Verdict::Fail
            },
            error: None,
            max_compression_stress_pa: Some(fold(
                |s| s.forces.max_compression_stress,
                0.0,
                f64::min,
            )),
            max_tension_stress_pa: Some(fold(|s| s.forces.max_tension_stress, 0.0, f64::max)),
            max_overhang_m: Some(cap.overhangs.iter().fold(0.0, |m, o| m.max(o.abs()))),
            min_blf: out.min_blf(),
            mass_kg: Some(cap.path.mass),
            print_time_s: Some(out.print_time()),
            states: Some(cap.states.len()),
            robot: robot.map(|e| e.map_or_else(|| "ok".into(), |e| format!("failed: {e}"))),
            constraints: input.constraints,
            report: Some(format!("designs/{}/report.html", v.name)),
        };
        Ok(DesignRun {
            record,
            summary: Some(summary),
            report_html: Some(html),
        })
    }));
    match outcome {
        Ok(Ok(run)) => run,
        Ok(Err(e)) => failed(e),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            failed(format!("internal error (panic): {what}"))
        }
    }
}

/// The study result of `rows` (in study order) of `study`, run with the robot unless
/// `no_robot`, as shard `shard` or whole.
///
/// # Errors
/// None in practice: the result is round-tripped through JSON (see below), which cannot fail
/// for these types; the error is kept rather than unwrapped.
pub fn collect(
    study: &Study,
    shard: Option<(usize, usize)>,
    no_robot: bool,
    rows: Vec<Record>,
) -> Result<StudyResult, StudyError> {
    let r = StudyResult {
        format: RESULT_FORMAT.into(),
        version: 1,
        title: study.title.clone(),
        // Shards run with and without the robot must not be merged.
        fingerprint: if no_robot {
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
    let bytes = serde_json::to_vec(&r).map_err(|e| StudyError::Merge(e.to_string()))?;
    serde_json::from_slice(&bytes).map_err(|e| StudyError::Merge(e.to_string()))
}

/// Where [`run_designs`] is with a design: about to run it, or done with it.
pub enum Step<'a> {
    /// Before the run (the command writes `designs/<name>/design.toml` here).
    Start,
    /// After the run (the command writes `summary.json` and `report.html` here).
    Done(&'a DesignRun),
}

/// Runs `designs` in parallel on `jobs` threads (default: one per core) with [`run_one`],
/// calling `store(v, step)` on the worker thread before and after each design; an `Err` from
/// `store` (say, a file that cannot be written) makes the design an error row with that
/// reason. Returns the rows in the order of `designs`.
///
/// # Errors
/// The worker threads cannot be started.
pub fn run_designs(
    designs: &[&Variation],
    parameter_paths: &[String],
    no_robot: bool,
    jobs: Option<usize>,
    store: &(dyn Fn(&Variation, Step<'_>) -> Result<(), String> + Sync),
) -> Result<Vec<Record>, rayon::ThreadPoolBuildError> {
    use rayon::prelude::*;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(j) = jobs {
        builder = builder.num_threads(j);
    }
    let pool = builder.build()?;
    Ok(pool.install(|| {
        designs
            .par_iter()
            .map(|v| {
                let parameters = parameter_values(v, parameter_paths);
                if let Err(reason) = store(v, Step::Start) {
                    return error_record(v, parameters, reason);
                }
                let run = run_one(v, parameters.clone(), no_robot);
                match store(v, Step::Done(&run)) {
                    Ok(()) => run.record,
                    Err(reason) => error_record(v, parameters, reason),
                }
            })
            .collect()
    }))
}

impl Variation {
    /// `designs/<name>/design.toml`: what a design directory holds before the design runs.
    pub fn files_before(&self) -> Vec<crate::output::OutputFile> {
        vec![crate::output::OutputFile::new(
            format!("designs/{}/design.toml", self.name),
            self.design_toml(),
        )]
    }
}

impl DesignRun {
    /// `designs/<name>/summary.json` and `report.html` of `v` after its run (none for a design
    /// that could not run).
    ///
    /// # Errors
    /// [`crate::output::OutputError::Produce`] when the summary cannot be serialized.
    pub fn files(
        &self,
        v: &Variation,
    ) -> Result<Vec<crate::output::OutputFile>, crate::output::OutputError> {
        use crate::output::{OutputError, OutputFile};
        let mut out = Vec::new();
        if let Some(summary) = &self.summary {
            let bytes = serde_json::to_vec_pretty(summary)
                .map_err(|e| OutputError::Produce(format!("cannot write summary.json: {e}")))?;
            out.push(OutputFile::new(
                format!("designs/{}/summary.json", v.name),
                bytes,
            ));
        }
        if let Some(html) = &self.report_html {
            out.push(OutputFile::new(
                format!("designs/{}/report.html", v.name),
                html.as_bytes(),
            ));
        }
        Ok(out)
    }
}

impl StudyResult {
    /// `study.json`, `study.csv` and `study.html`.
    ///
    /// # Errors
    /// [`crate::output::OutputError::Produce`] when the table page cannot be rendered.
    pub fn files(&self) -> Result<Vec<crate::output::OutputFile>, crate::output::OutputError> {
        use crate::output::{OutputError, OutputFile};
        let html = self
            .html()
            .map_err(|e| OutputError::Produce(format!("cannot render study.html: {e}")))?;
        Ok(vec![
            OutputFile::new("study.json", self.to_json()),
            OutputFile::new("study.csv", self.csv()),
            OutputFile::new("study.html", html),
        ])
    }
}
