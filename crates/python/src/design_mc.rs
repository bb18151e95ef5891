//! The Monte Carlo of a design's governing states from Python, step by step (issue 24): the
//! library's `kappe::analysis::design_monte_carlo` functions — `plan` (after the design's run
//! with FORM), `build_tables` in parts, `setup` (tables joined, importance-sampling centres),
//! `sample_batch`, `merge` — each a function here, so a Dask client runs them as tasks and the
//! merged result equals `kappe design`'s `reliability.monte_carlo` with the same seed bit for bit
//! (every number shipped as its bit pattern).
//!
//! A worker needs the design's cap and schedule (form finding and the robot plan, no analysis);
//! they are built once per process and design text and kept.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use kappe::analysis::design_monte_carlo::{
    McBatch, McContext, McMethod, McPlan, McSetup, StateTable, build_tables, merge, plan,
    sample_batch, setup,
};
use kappe_reliability::Batch;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::errors::*;

/// A design's cap and schedule, and its analysis options.
type Built = Arc<(kappe::Design, kappe::Outcome)>;

fn cache() -> &'static Mutex<HashMap<String, Built>> {
    static CACHE: OnceLock<Mutex<HashMap<String, Built>>> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

/// The design of `text` with its `[uncertainty]` but no Monte Carlo of its own (the caller's
/// samples and seed are the run's).
fn design(text: &str) -> PyResult<kappe::Design> {
    let mut d = kappe::Design::from_toml_str(text).map_err(|e| design_error(&e))?;
    match d.uncertainty.as_mut() {
        Some(u) => {
            u.monte_carlo = None;
            u.monte_carlo_method = None;
        }
        None => {
            return Err(DesignError::new_err((
                "the design has no [uncertainty]: nothing to sample".to_owned(),
                "uncertainty".to_owned(),
                String::new(),
                "allowed: a design with an [uncertainty] table".to_owned(),
            )));
        }
    }
    Ok(d)
}

/// The cap and schedule of `text` (no analysis), built once per process.
fn built(text: &str) -> PyResult<Built> {
    let lock = |_| PyRuntimeError::new_err("the design Monte Carlo cache was poisoned");
    if let Some(b) = cache().lock().map_err(lock)?.get(text) {
        return Ok(b.clone());
    }
    let d = design(text)?;
    let options = kappe::Options {
        analysis: None,
        robot: true,
        allow_fail: true,
    };
    let out = kappe::run(&d, &options, &kappe::no_progress).map_err(|e| design_error(&e))?;
    let b = Arc::new((d, out));
    cache()
        .lock()
        .map_err(lock)?
        .insert(text.to_owned(), b.clone());
    Ok(b)
}

fn context<'a>(b: &'a Built) -> PyResult<McContext<'a>> {
    McContext::new(&b.1.cap, &b.0.analysis, &b.1.schedule).map_err(|e| design_error(&e))
}

fn method_of(m: &str) -> PyResult<McMethod> {
    match m {
        "auto" => Ok(McMethod::Auto),
        "crude" => Ok(McMethod::Crude),
        "importance" => Ok(McMethod::Importance),
        _ => Err(DesignError::new_err((
            format!("unknown Monte Carlo method `{m}`"),
            "method".to_owned(),
            m.to_owned(),
            "allowed: auto, crude, importance".to_owned(),
        ))),
    }
}

fn parse<T: serde::de::DeserializeOwned>(what: &str, json: &str) -> PyResult<T> {
    serde_json::from_str(json).map_err(|e| json_err(what, e))
}

fn to_json<T: serde::Serialize>(what: &str, v: &T) -> PyResult<String> {
    serde_json::to_string(v).map_err(|e| json_err(what, e))
}

/// The design `text` run with its analysis and FORM (`[uncertainty]`), and the plan of its
/// Monte Carlo: the governing states, `samples`, `seed`, `method` (`auto`, `crude`,
/// `importance`), as JSON.
#[pyfunction]
#[pyo3(signature = (text, samples, seed, method="auto"))]
pub(crate) fn design_mc_plan(
    py: Python<'_>,
    text: &str,
    samples: u64,
    seed: u64,
    method: &str,
) -> PyResult<String> {
    let method = method_of(method)?;
    let d = design(text)?;
    py.detach(move || -> PyResult<String> {
        let mut options = kappe::Options::of(&d);
        options.allow_fail = true;
        let out = kappe::run(&d, &options, &kappe::no_progress).map_err(|e| design_error(&e))?;
        let (Some(analysis), Some(r)) = (&out.analysis, &out.reliability) else {
            return Err(DesignError::new_err((
                "the design has no analysis or no random check: nothing to sample".to_owned(),
                "analysis".to_owned(),
                String::new(),
                "allowed: a design with [analysis] and [uncertainty]".to_owned(),
            )));
        };
        let ctx = McContext::new(&out.cap, &analysis.options, &out.schedule)
            .map_err(|e| design_error(&e))?;
        let p = plan(&ctx, analysis, r, samples, seed, method).map_err(|e| design_error(&e))?;
        to_json("Monte Carlo plan", &p)
    })
}

/// Part `index` of `count` of the plan's tables (consecutive governing states), as JSON.
#[pyfunction]
pub(crate) fn design_mc_table_part(
    py: Python<'_>,
    text: &str,
    plan_json: &str,
    index: usize,
    count: usize,
) -> PyResult<String> {
    if count == 0 || index >= count {
        return Err(DesignError::new_err((
            format!("table part {index} of {count}"),
            "index".to_owned(),
            index.to_string(),
            "allowed: 0 ≤ index < count".to_owned(),
        )));
    }
    let p: McPlan = parse("Monte Carlo plan", plan_json)?;
    let text = text.to_owned();
    py.detach(move || -> PyResult<String> {
        let b = built(&text)?;
        let ctx = context(&b)?;
        let n = p.states.len();
        let t = build_tables(&ctx, &p, index * n / count..(index + 1) * n / count)
            .map_err(|e| design_error(&e))?;
        to_json("Monte Carlo tables", &t)
    })
}

/// The setup every batch needs (the plan, its tables from all parts in any order, the
/// importance-sampling centres), as JSON.
#[pyfunction]
pub(crate) fn design_mc_setup(
    py: Python<'_>,
    text: &str,
    plan_json: &str,
    parts: Vec<String>,
) -> PyResult<String> {
    let p: McPlan = parse("Monte Carlo plan", plan_json)?;
    let mut tables: Vec<StateTable> = Vec::new();
    for part in &parts {
        tables.extend(parse::<Vec<StateTable>>("Monte Carlo tables", part)?);
    }
    let text = text.to_owned();
    py.detach(move || -> PyResult<String> {
        let b = built(&text)?;
        let ctx = context(&b)?;
        let s = setup(&ctx, p, tables, 0.0).map_err(|e| design_error(&e))?;
        to_json("Monte Carlo setup", &s)
    })
}

/// Batch `index` of `count` of the samples, as JSON.
#[pyfunction]
pub(crate) fn design_mc_batch(
    py: Python<'_>,
    text: &str,
    setup_json: &str,
    index: u64,
    count: u64,
) -> PyResult<String> {
    let s: McSetup = parse("Monte Carlo setup", setup_json)?;
    let text = text.to_owned();
    py.detach(move || -> PyResult<String> {
        let b = built(&text)?;
        let ctx = context(&b)?;
        let batch = sample_batch(&ctx, &s, Batch { index, count }).map_err(|e| design_error(&e))?;
        to_json("Monte Carlo batch", &batch)
    })
}

/// `reliability.monte_carlo` of summary.json from every batch of one run (any order), as JSON.
#[pyfunction]
pub(crate) fn design_mc_merge(setup_json: &str, batches: Vec<String>) -> PyResult<String> {
    let s: McSetup = parse("Monte Carlo setup", setup_json)?;
    let parsed = batches
        .iter()
        .map(|b| parse::<McBatch>("Monte Carlo batch", b))
        .collect::<PyResult<Vec<_>>>()?;
    let mc = merge(&s, &parsed).map_err(|e| design_error(&e))?;
    to_json("Monte Carlo", &mc)
}
