//! The print's Monte Carlo of a buildability spec with `[uncertainty]` from Python, one batch at
//! a time (issue 24): the library's `monte_carlo_batch` / `monte_carlo_result` (the CLI's
//! `kappe buildability` runs the same functions in one batch), so a Dask task per batch merges
//! bit for bit into the local run with the same seed.
//!
//! A batch needs the spec's interpolation tables (`Surrogate::build`, the costly part: one shell
//! solve per layer count and Chebyshev point). They are built once per process and spec text and
//! kept for the process's life (a Dask worker builds them for its first batch, then only
//! samples).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use kappe::commands::buildability::{BuildabilitySpec, Resolved};
use kappe::commands::buildability_reliability::{
    Surrogate, monte_carlo_batch, monte_carlo_result, prepare,
};
use kappe_reliability::{Batch, EventBatch, SamplingOptions};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::errors::*;

type Tables = Arc<(Resolved, Surrogate)>;

/// The tables of every spec text this process has sampled.
fn cache() -> &'static Mutex<HashMap<String, Tables>> {
    static CACHE: OnceLock<Mutex<HashMap<String, Tables>>> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

/// The checked spec and its tables (built on first use).
fn tables(text: &str) -> PyResult<Tables> {
    let lock = |_| PyRuntimeError::new_err("the buildability table cache was poisoned");
    if let Some(t) = cache().lock().map_err(lock)?.get(text) {
        return Ok(t.clone());
    }
    let mut spec = BuildabilitySpec::parse(text).map_err(|e| design_error(&e))?;
    let Some(table) = spec.uncertainty.take() else {
        return Err(DesignError::new_err((
            "the spec has no [uncertainty]: nothing to sample".to_owned(),
            "uncertainty".to_owned(),
            String::new(),
            "allowed: a buildability spec with an [uncertainty] table".to_owned(),
        )));
    };
    let r = spec.resolve().map_err(|e| design_error(&e))?;
    let sur = Surrogate::build(&r, prepare(&r, &table).map_err(|e| design_error(&e))?)
        .map_err(|e| design_error(&e))?;
    let t = Arc::new((r, sur));
    cache()
        .lock()
        .map_err(lock)?
        .insert(text.to_owned(), t.clone());
    Ok(t)
}

/// Batch `index` of `count` of the print's crude Monte Carlo (`samples` in all, `seed`) of the
/// buildability spec `text`, as the JSON of a `kappe_reliability::EventBatch`.
#[pyfunction]
pub(crate) fn buildability_mc_batch(
    py: Python<'_>,
    text: &str,
    samples: u64,
    seed: u64,
    index: u64,
    count: u64,
) -> PyResult<String> {
    if count == 0 || index >= count {
        return Err(PyValueError::new_err(format!(
            "batch {index} of {count}: allowed 0 ≤ index < count"
        )));
    }
    let text = text.to_owned();
    py.detach(move || -> PyResult<String> {
        let t = tables(&text)?;
        let (r, sur) = (&t.0, &t.1);
        let b = monte_carlo_batch(
            r,
            sur,
            &SamplingOptions::new(samples, seed),
            Batch { index, count },
        )
        .map_err(|e| design_error(&e))?;
        serde_json::to_string(&b).map_err(|e| json_err("event batch", e))
    })
}

/// The print's Monte Carlo from the JSON of every batch of one run (any order), as the JSON of
/// `buildability.json`'s `monte_carlo` block (`seconds` and `resolves` zero: they are the
/// workers').
#[pyfunction]
pub(crate) fn buildability_mc_merge(batches: Vec<String>) -> PyResult<String> {
    let parsed = batches
        .iter()
        .map(|b| serde_json::from_str::<EventBatch>(b).map_err(|e| json_err("event batch", e)))
        .collect::<PyResult<Vec<_>>>()?;
    let mc = monte_carlo_result(&parsed, 0, [0.0; 2]).map_err(|e| design_error(&e))?;
    serde_json::to_string(&mc).map_err(|e| json_err("monte carlo", e))
}
