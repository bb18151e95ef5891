//! Ceilings from Python (issue 15): one bay per call, so a cluster can run the bays of a room
//! as separate tasks, and the room assembled from the bays' rows on the client — the same
//! library functions `kappe design ROOM.toml` calls ([`kappe::commands::ceiling::run_bay`],
//! [`kappe::commands::ceiling::ceiling_summary`], [`kappe::commands::ceiling::index_html`]). Also the safe output
//! writer ([`kappe::output`]) for every `write()` of the Python package.

use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use kappe::commands::ceiling::CeilingDesign;
use kappe::output::{OutputError, OutputFile};

/// Files as Python gets them: `(relative name, bytes)`.
type PyFiles<'py> = Vec<(String, Bound<'py, PyBytes>)>;

fn parse(text: &str) -> PyResult<CeilingDesign> {
    CeilingDesign::from_toml_str(text).map_err(|e| crate::errors::design_error(&e))
}

fn output_error(e: &OutputError) -> PyErr {
    match e {
        OutputError::Refused(m) => PyValueError::new_err(python_terms(m)),
        OutputError::Io(m) => PyOSError::new_err(m.clone()),
        OutputError::Produce(m) => PyRuntimeError::new_err(m.clone()),
    }
}

/// The output library words its refusals for the command line (`--out DIR`, `--force`); a
/// Python user passes a directory and `force=True` (issue 28).
pub fn python_terms(message: &str) -> String {
    message
        .replace("pass --force", "pass force=True")
        .replace("(--force)", "(force=True)")
        .replace("without `--force`", "without force=True")
        .replace("Choose another --out", "Choose another directory")
        .replace("(give --out DIR)", "(give a directory)")
        .replace("(e.g. --out out)", "(e.g. \"out\")")
        .replace("--out ", "the directory ")
}

/// The number of bays of a ceiling file's text.
#[pyfunction]
pub fn ceiling_bays(text: &str) -> PyResult<usize> {
    let ceiling = parse(text)?;
    Ok(ceiling
        .bay_designs()
        .map_err(|e| crate::errors::design_error(&e))?
        .len())
}

/// Designs, analyses and plans bay `index` (0-based) of a ceiling as `kappe design` does
/// (every state, the robot unless `no_robot`). Returns the bay's row of `ceiling.json` (JSON
/// text) and the files of its `bay_N/` directory as `(name, bytes)` pairs.
#[pyfunction]
#[pyo3(signature = (text, index, no_robot=false, allow_fail=false))]
pub fn ceiling_run_bay<'py>(
    py: Python<'py>,
    text: &str,
    index: usize,
    no_robot: bool,
    allow_fail: bool,
) -> PyResult<(String, PyFiles<'py>)> {
    let ceiling = parse(text)?;
    let first = ceiling
        .bay_designs()
        .map_err(|e| crate::errors::design_error(&e))?
        .into_iter()
        .next()
        .unwrap_or_default();
    // The bays share the file's [analysis] and [robot], as in `kappe design`.
    let mut options = kappe::Options::of(&first);
    options.robot = !no_robot;
    options.allow_fail = allow_fail;
    let bay = py
        .detach(|| {
            kappe::commands::ceiling::run_bay(&ceiling, index, &options, &kappe::no_progress)
        })
        .map_err(|e| crate::errors::design_error(&e))?;
    let files = bay.files(allow_fail).map_err(|e| output_error(&e))?;
    Ok((
        bay.summary().to_string(),
        files
            .into_iter()
            .map(|f| (f.name, PyBytes::new(py, &f.bytes)))
            .collect(),
    ))
}

/// The room from its bays' rows (JSON texts, in bay order): `ceiling.json` as `kappe design`
/// writes it, and the room page `index.html`.
#[pyfunction]
pub fn ceiling_assemble(text: &str, bays: Vec<String>) -> PyResult<(String, String)> {
    let ceiling = parse(text)?;
    let rows = bays
        .iter()
        .map(|b| serde_json::from_str(b))
        .collect::<Result<Vec<serde_json::Value>, _>>()
        .map_err(|e| PyValueError::new_err(format!("bays: {e}")))?;
    let summary = kappe::commands::ceiling::ceiling_summary(&ceiling, rows);
    let json = serde_json::to_string_pretty(&summary)
        .map_err(|e| PyRuntimeError::new_err(format!("ceiling.json: {e}")))?;
    let html = kappe::commands::ceiling::index_html(&ceiling, &summary);
    Ok((json, html))
}

/// Writes `files` (`(relative name, bytes)` pairs) as the output directory `directory`, under
/// the rule of `kappe design --out`: a new directory, or one Kappe wrote, replaced atomically;
/// anything else refused (`ValueError`) unless `force`, which moves it aside (nothing is
/// deleted). Returns a notice when something was moved aside.
#[pyfunction]
#[pyo3(signature = (directory, files, force=false, command="python"))]
pub fn write_output(
    py: Python<'_>,
    directory: &str,
    files: Vec<(String, Bound<'_, PyBytes>)>,
    force: bool,
    command: &str,
) -> PyResult<Option<String>> {
    let files: Vec<OutputFile> = files
        .iter()
        .map(|(name, bytes)| OutputFile::new(name.clone(), bytes.as_bytes()))
        .collect();
    py.detach(|| {
        let prepared = kappe::output::prepare_dir(std::path::Path::new(directory), force, command)?;
        prepared.write(&files)?;
        prepared.commit()
    })
    .map(|notice| notice.map(|n| python_terms(&n)))
    .map_err(|e| output_error(&e))
}
