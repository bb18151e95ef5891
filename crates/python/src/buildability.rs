//! The print's Monte Carlo of a buildability spec with `[uncertainty]` from Python, one batch at
//! a time (issue 24): the library's `monte_carlo_batch` / `monte_carlo_result` (the CLI's
//! `kappe buildability` runs the same functions in one batch), so a Dask task per batch merges
//! bit for bit into the local run with the same seed.
//!
//! A batch needs the spec's interpolation tables (`Surrogate::build`, the costly part: one shell
//! solve per layer count and Chebyshev point). They are built once per process and spec text and
//! kept for the process's life. On Dask they are built in parts over the workers
//! (`buildability_mc_table_part`), joined (`buildability_mc_tables_join`) and shipped to every
//! batch (`tables=`): no worker solves them again, and the samples are the same bits
//! (`SurrogateTables` carries every number's bit pattern).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use kappe::commands::buildability::{BuildabilitySpec, Resolved};
use kappe::commands::buildability_reliability::{
    Surrogate, SurrogateTables, collapse_tables, monte_carlo_batch, monte_carlo_result, prepare,
    table_part_layers,
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

/// The checked spec and its tables (built on first use, or made from `shipped` tables).
fn tables(text: &str, shipped: Option<&str>) -> PyResult<Tables> {
    let lock = |_| PyRuntimeError::new_err("the buildability table cache was poisoned");
    if let Some(t) = cache().lock().map_err(lock)?.get(text) {
        return Ok(t.clone());
    }
    let (r, table) = resolved(text)?;
    let prepared = prepare(&r, &table).map_err(|e| design_error(&e))?;
    let sur = match shipped {
        Some(json) => {
            let t: SurrogateTables =
                serde_json::from_str(json).map_err(|e| json_err("Monte Carlo tables", e))?;
            Surrogate::from_tables(&r, text, prepared, t)
        }
        // Built here: the linear tables and, with [analysis.nonlinear], the collapse tables
        // from the deterministic states, as `kappe buildability` builds them.
        None => Surrogate::build(&r, prepared).and_then(|mut sur| {
            sur.collapse = collapse_tables(&r, &sur.prepared)?;
            Ok(sur)
        }),
    }
    .map_err(|e| design_error(&e))?;
    let t = Arc::new((r, sur));
    cache()
        .lock()
        .map_err(lock)?
        .insert(text.to_owned(), t.clone());
    Ok(t)
}

/// The spec `text` checked and resolved, with its `[uncertainty]` table.
fn resolved(text: &str) -> PyResult<(Resolved, kappe::input::UncertaintyTable)> {
    let mut spec = BuildabilitySpec::parse(text).map_err(|e| design_error(&e))?;
    let Some(table) = spec.uncertainty.take() else {
        return Err(DesignError::new_err((
            "the spec has no [uncertainty]: nothing to sample".to_owned(),
            "uncertainty".to_owned(),
            String::new(),
            "allowed: a buildability spec with an [uncertainty] table".to_owned(),
        )));
    };
    Ok((spec.resolve().map_err(|e| design_error(&e))?, table))
}

/// That `index` names one of `count` parts of a run (`what`: "batch", "table part").
fn check_part(what: &str, index: u64, count: u64) -> PyResult<()> {
    if count == 0 || index >= count {
        return Err(PyValueError::new_err(format!(
            "{what} {index} of {count}: allowed 0 ≤ index < count"
        )));
    }
    Ok(())
}

/// Part `index` of `count` of the interpolation tables of the buildability spec `text`
/// (`table_part_layers`: consecutive layer counts, about equal work), as JSON: built on one
/// worker; `buildability_mc_tables_join` makes the tables of the print from all parts.
#[pyfunction]
pub(crate) fn buildability_mc_table_part(
    py: Python<'_>,
    text: &str,
    index: usize,
    count: usize,
) -> PyResult<String> {
    // usize → u64 is lossless on every target PyO3 builds for.
    check_part("table part", index as u64, count as u64)?;
    let text = text.to_owned();
    py.detach(move || -> PyResult<String> {
        let (r, table) = resolved(&text)?;
        let prepared = prepare(&r, &table).map_err(|e| design_error(&e))?;
        let layers = table_part_layers(r.spec.object.max_layers, index, count);
        let part = Surrogate::build_layers(&r, prepared, layers).map_err(|e| design_error(&e))?;
        serde_json::to_string(&part.tables(&text)).map_err(|e| json_err("Monte Carlo tables", e))
    })
}

/// The collapse tables of the buildability spec `text` (`collapse_tables`: the deterministic
/// states, then the tables of the layer counts the state rule keeps), as JSON (`null` without
/// `[analysis.nonlinear]`): one worker's task beside the table parts, joined by
/// `buildability_mc_tables_join`.
#[pyfunction]
pub(crate) fn buildability_mc_collapse_tables(py: Python<'_>, text: &str) -> PyResult<String> {
    let text = text.to_owned();
    py.detach(move || -> PyResult<String> {
        let (r, table) = resolved(&text)?;
        let prepared = prepare(&r, &table).map_err(|e| design_error(&e))?;
        let c = collapse_tables(&r, &prepared).map_err(|e| design_error(&e))?;
        serde_json::to_string(&c).map_err(|e| json_err("collapse tables", e))
    })
}

/// The tables of the print from the JSON of its parts (`buildability_mc_table_part`, any
/// order) and of its collapse tables (`buildability_mc_collapse_tables`; required with
/// `[analysis.nonlinear]`, where the batches refuse tables without them), as JSON to ship to
/// the processes that sample (`buildability_mc_batch`'s `tables`).
#[pyfunction]
#[pyo3(signature = (parts, collapse=None))]
pub(crate) fn buildability_mc_tables_join(
    parts: Vec<String>,
    collapse: Option<String>,
) -> PyResult<String> {
    let parsed = parts
        .iter()
        .map(|p| serde_json::from_str::<SurrogateTables>(p).map_err(|e| json_err("table part", e)))
        .collect::<PyResult<Vec<_>>>()?;
    let collapse = match collapse {
        Some(c) => serde_json::from_str(&c).map_err(|e| json_err("collapse tables", e))?,
        None => None,
    };
    let all = SurrogateTables::join(parsed)
        .map_err(|e| design_error(&e))?
        .with_collapse(collapse);
    serde_json::to_string(&all).map_err(|e| json_err("Monte Carlo tables", e))
}

/// Batch `index` of `count` of the print's crude Monte Carlo (`samples` in all, `seed`) of the
/// buildability spec `text`, as the JSON of a `kappe_reliability::EventBatch`; `tables`: the
/// spec's tables from `buildability_mc_tables_join` (used when this process has none yet), else
/// they are built here.
#[pyfunction]
#[pyo3(signature = (text, samples, seed, index, count, tables=None))]
pub(crate) fn buildability_mc_batch(
    py: Python<'_>,
    text: &str,
    samples: u64,
    seed: u64,
    index: u64,
    count: u64,
    tables: Option<String>,
) -> PyResult<String> {
    check_part("batch", index, count)?;
    let text = text.to_owned();
    py.detach(move || -> PyResult<String> {
        let t = self::tables(&text, tables.as_deref())?;
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
