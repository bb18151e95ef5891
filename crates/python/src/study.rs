//! Studies from Python: parse a study, run one design or all locally, collect the results; the same library calls as `kappe study`.

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::errors::*;

/// Parses a study file's text (`source` names it; `base = "file"` is resolved in `directory`).
/// Returns JSON: title, parameters, fingerprint, and per design its name, `design.toml` and
/// parameter values (or the reason it cannot run).
#[pyfunction]
#[pyo3(signature = (text, source="study.toml", directory="."))]
pub(crate) fn study_parse(text: &str, source: &str, directory: &str) -> PyResult<String> {
    let study = kappe::commands::study::parse(text, source, std::path::Path::new(directory))
        .map_err(|e| DesignError::new_err((e.to_string(), "study", "", "")))?;
    let designs: Vec<serde_json::Value> = study
        .variations
        .iter()
        .map(|v| {
            serde_json::json!({
                "index": v.index,
                "name": v.name,
                "design_toml": v.design_toml(),
                "parameters": kappe::commands::study::parameter_values(v, &study.parameters),
                "error": v.design.as_ref().err(),
            })
        })
        .collect();
    Ok(serde_json::json!({
        "title": study.title,
        "parameters": study.parameters,
        "fingerprint": study.fingerprint,
        "designs": designs,
    })
    .to_string())
}

/// One design of a study for Python: its row, summary and report, and the files `kappe study`
/// writes for it (`designs/<name>/design.toml`, `summary.json`, `report.html`, from the
/// library's `Variation::files_before` and `DesignRun::files`, so `StudyResult.write` writes
/// the same bytes).
pub(crate) fn run_json(
    v: &kappe::commands::study::Variation,
    run: &kappe::commands::study::DesignRun,
) -> Result<serde_json::Value, String> {
    let mut files = v.files_before();
    files.extend(run.files(v).map_err(|e| e.to_string())?);
    let files: Vec<(String, String)> = files
        .into_iter()
        .map(|f| (f.name, String::from_utf8_lossy(&f.bytes).into_owned()))
        .collect();
    Ok(serde_json::json!({
        "record": run.record,
        "summary": run.summary,
        "report_html": run.report_html,
        "files": files,
    }))
}

/// Runs design `index` of a study (as `kappe study` does) and returns the JSON of
/// `{record, summary, report_html}` (summary/report null if it could not run).
#[pyfunction]
#[pyo3(signature = (text, index, no_robot=false, source="study.toml", directory="."))]
pub(crate) fn study_run_one(
    py: Python<'_>,
    text: &str,
    index: usize,
    no_robot: bool,
    source: &str,
    directory: &str,
) -> PyResult<String> {
    let study = kappe::commands::study::parse(text, source, std::path::Path::new(directory))
        .map_err(|e| DesignError::new_err((e.to_string(), "study", "", "")))?;
    let Some(v) = study.variations.get(index) else {
        return Err(PyValueError::new_err(format!(
            "index {index}: the study has {} designs",
            study.variations.len()
        )));
    };
    let params = kappe::commands::study::parameter_values(v, &study.parameters);
    let run = py.detach(|| kappe::commands::study::run_one(v, params, no_robot));
    Ok(run_json(v, &run)
        .map_err(PyRuntimeError::new_err)?
        .to_string())
}

/// Runs every design of a study here, in parallel on `jobs` threads (default: one per core),
/// as `kappe study` does; returns the JSON list of `{record, summary, report_html, files}` in
/// study order.
#[pyfunction]
#[pyo3(signature = (text, no_robot=false, jobs=None, source="study.toml", directory="."))]
pub(crate) fn study_run_local(
    py: Python<'_>,
    text: &str,
    no_robot: bool,
    jobs: Option<usize>,
    source: &str,
    directory: &str,
) -> PyResult<String> {
    if jobs == Some(0) {
        return Err(PyValueError::new_err("jobs: give at least 1"));
    }
    let study = kappe::commands::study::parse(text, source, std::path::Path::new(directory))
        .map_err(|e| DesignError::new_err((e.to_string(), "study", "", "")))?;
    let selected = study.select(None);
    let runs = std::sync::Mutex::new(std::collections::BTreeMap::new());
    let rows = py
        .detach(|| {
            kappe::commands::study::run_designs(
                &selected,
                &study.parameters,
                no_robot,
                jobs,
                &|v, step| {
                    if let kappe::commands::study::Step::Done(run) = step {
                        let json = run_json(v, run)?;
                        if let Ok(mut r) = runs.lock() {
                            r.insert(v.index, json);
                        }
                    }
                    Ok(())
                },
            )
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start the worker threads: {e}")))?;
    let mut runs = runs
        .into_inner()
        .map_err(|_| PyRuntimeError::new_err("a study worker panicked"))?;
    let runs: Vec<serde_json::Value> = rows
        .into_iter()
        .map(|record| {
            runs.remove(&record.index).unwrap_or_else(
                || serde_json::json!({"record": record, "summary": null, "report_html": null, "files": []}),
            )
        })
        .collect();
    serde_json::to_string(&runs).map_err(|e| json_err("the study", e))
}

/// Collects the record JSONs of a study (`records_json`: a JSON list, any order) into the
/// study result; returns `[study_json, study_csv, study_html]`.
#[pyfunction]
#[pyo3(signature = (text, records_json, no_robot=false, source="study.toml", directory="."))]
pub(crate) fn study_collect(
    text: &str,
    records_json: &str,
    no_robot: bool,
    source: &str,
    directory: &str,
) -> PyResult<(String, String, String)> {
    let study = kappe::commands::study::parse(text, source, std::path::Path::new(directory))
        .map_err(|e| DesignError::new_err((e.to_string(), "study", "", "")))?;
    let mut rows: Vec<kappe::commands::study::Record> =
        serde_json::from_str(records_json).map_err(|e| json_err("records", e))?;
    rows.sort_by_key(|r| r.index);
    let result = kappe::commands::study::collect(&study, None, no_robot, rows)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let html = result
        .html()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok((
        String::from_utf8_lossy(&result.to_json()).into_owned(),
        result.csv(),
        html,
    ))
}
