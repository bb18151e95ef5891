//! `kappe optimize` from Python: the same library loop, progress per evaluation.

use std::ops::ControlFlow;
use std::sync::atomic::Ordering;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::design::*;
use crate::errors::*;

/// `kappe optimize`: the design loop of an optimize file (or a design file with an
/// `[optimize]` table) given as TOML text; `directory` resolves `design = "FILE"`. Returns
/// `(design_toml, optimize_json, report, feasible)`: the files and the text the command
/// writes and prints. `progress(evaluation_json)` is called after every evaluation.
#[pyfunction]
#[pyo3(signature = (text, directory=".", max_evaluations=None, progress=None))]
pub(crate) fn optimize_design(
    py: Python<'_>,
    text: &str,
    directory: &str,
    max_evaluations: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<(String, String, String, bool)> {
    use kappe::commands::optimize;
    let (mut file, embedded) =
        optimize::OptimizeFile::from_any_toml_str(text).map_err(|e| design_error(&e))?;
    if let Some(n) = max_evaluations {
        if !(1..=10_000).contains(&n) {
            return Err(PyValueError::new_err(format!(
                "max_evaluations {n}: allowed 1 to 10000"
            )));
        }
        file.max_evaluations = n;
    }
    let start =
        optimize::start_design(&file, embedded, std::path::Path::new(directory)).map_err(|e| {
            let why = std::error::Error::source(&e).map_or(String::new(), |c| format!(": {c}"));
            DesignError::new_err((format!("{e}{why}"), "design", "", ""))
        })?;
    // Each evaluation goes to `progress(evaluation_json)` on this thread; Ctrl-C stops the
    // loop after the evaluation under way.
    let deliver = |cb: &Bound<'_, PyAny>, e: String| -> PyResult<()> { cb.call1((e,)).map(drop) };
    let result = run_with_progress(py, progress, deliver, |stop, tick| {
        optimize::optimize(&file, &start, &|e| {
            tick(serde_json::to_string(e).unwrap_or_default());
            if stop.load(Ordering::Relaxed) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
    })?;
    let doc = optimize::document(&file, &result).map_err(|e| design_error(&e))?;
    let json = serde_json::to_string_pretty(&doc).map_err(|e| json_err("optimize.json", e))?;
    Ok((
        result
            .design
            .to_toml_string()
            .map_err(|e| design_error(&e))?,
        json,
        result.report(),
        result.feasible,
    ))
}
