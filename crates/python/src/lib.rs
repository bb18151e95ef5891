//! `kappe._kappe`: the native half of the Python package `kappe` (python/kappe). Inputs come
//! as JSON/TOML text (serde checks them and names the field in every error); results go back
//! as Python objects built here: NumPy arrays made from the Rust vectors (rust-numpy, moved
//! without a copy), and the larger documents (summary, network, report) as text only when the
//! Python side asks for them, so a run costs what the CLI's costs.
//!
//! Long work runs with the GIL released. A design runs on a worker thread while the calling
//! thread waits with the GIL released and, every 50 ms, takes it to deliver progress to the
//! Python callback and to check for signals: Ctrl-C (KeyboardInterrupt) stops the run through
//! `kappe::run`'s progress callback (`ControlFlow::Break` → `DesignError::Cancelled`).
//! Callbacks therefore run on the caller's thread, never on a worker.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

mod ceiling;

pyo3::create_exception!(
    _kappe,
    DesignError,
    PyValueError,
    "A design (or study, analysis option) outside what Kappe accepts; `field`, `value` and \
     `allowed` say which field and what is allowed."
);

/// A `kappe::DesignError` as a Python `DesignError(message, field, value, allowed)`.
fn design_error(e: &kappe::DesignError) -> PyErr {
    match e {
        kappe::DesignError::Invalid {
            field,
            value,
            allowed,
        } => DesignError::new_err((
            e.to_string(),
            (*field).to_string(),
            value.clone(),
            allowed.clone(),
        )),
        kappe::DesignError::Parse { path, .. } => {
            DesignError::new_err((e.to_string(), path.clone(), "", ""))
        }
        kappe::DesignError::Cancelled => PyKeyboardInterrupt::new_err("kappe run cancelled"),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

fn json_err(what: &str, e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{what}: {e}"))
}

/// The embedded default design as TOML.
#[pyfunction]
fn default_design_toml() -> PyResult<String> {
    kappe::Design::default()
        .to_toml_string()
        .map_err(|e| design_error(&e))
}

/// The commented example design file (`kappe init`).
#[pyfunction]
fn example_design_toml() -> &'static str {
    kappe::input::design::EXAMPLE_TOML
}

/// Parse and validate a design given as TOML text; returns its complete TOML (every field).
#[pyfunction]
fn design_from_toml(text: &str) -> PyResult<String> {
    let d = kappe::Design::from_toml_str(text).map_err(|e| design_error(&e))?;
    d.to_toml_string().map_err(|e| design_error(&e))
}

/// Parse and validate a design given as JSON text (a dict in the design file's schema);
/// returns its complete TOML.
#[pyfunction]
fn design_from_json(text: &str) -> PyResult<String> {
    let value: toml::Value =
        serde_json::from_str(text).map_err(|e| json_err("design dict is not valid", e))?;
    let toml_text = toml::to_string(&value).map_err(|e| {
        DesignError::new_err((
            format!("the design dict cannot be written as TOML: {e}"),
            "",
            "",
            "",
        ))
    })?;
    design_from_toml(&toml_text)
}

/// A design's TOML as JSON text (for the Python dict).
#[pyfunction]
fn design_to_json(text: &str) -> PyResult<String> {
    let d = kappe::Design::from_toml_str(text).map_err(|e| design_error(&e))?;
    let table: toml::Table = d
        .to_toml_string()
        .map_err(|e| design_error(&e))?
        .parse()
        .map_err(|e| json_err("design TOML", e))?;
    serde_json::to_string(&table).map_err(|e| json_err("design JSON", e))
}

/// Messages from the worker thread of a run.
enum Msg<T, P> {
    Progress(P),
    Done(Result<T, kappe::DesignError>),
}

fn stage_name(s: kappe::Stage) -> &'static str {
    match s {
        kappe::Stage::States => "states",
        kappe::Stage::Analysis => "analysis",
        kappe::Stage::Robot => "robot",
    }
}

/// Runs `work` (given the stop flag and a progress sender) on a worker thread; the caller
/// waits with the GIL released, delivers progress to `progress` and stops the work on Ctrl-C
/// or when `progress` raises.
fn run_with_progress<'py, T: Send, P: Send>(
    py: Python<'py>,
    progress: Option<Bound<'py, PyAny>>,
    deliver: impl Fn(&Bound<'py, PyAny>, P) -> PyResult<()>,
    work: impl FnOnce(&AtomicBool, &(dyn Fn(P) + Sync)) -> Result<T, kappe::DesignError> + Send,
) -> PyResult<T> {
    let stop = AtomicBool::new(false);
    let (tx, rx) = mpsc::channel::<Msg<T, P>>();
    std::thread::scope(|scope| {
        let stop = &stop;
        let tx_work = tx.clone();
        scope.spawn(move || {
            let sender = std::sync::Mutex::new(tx_work.clone());
            let on_progress = |p: P| {
                if let Ok(s) = sender.lock() {
                    let _ = s.send(Msg::Progress(p));
                }
            };
            let r = work(stop, &on_progress);
            let _ = tx_work.send(Msg::Done(r));
        });
        drop(tx);
        // `detach` needs a `Sync` capture; the receiver is only ever used from this thread.
        let rx = std::sync::Mutex::new(rx);
        let mut pending: Option<PyErr> = None;
        loop {
            let msg = py.detach(|| match rx.lock() {
                Ok(r) => r.recv_timeout(Duration::from_millis(50)),
                Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
            });
            match msg {
                Ok(Msg::Done(r)) => {
                    if let Some(e) = pending {
                        return Err(e);
                    }
                    return r.map_err(|e| design_error(&e));
                }
                Ok(Msg::Progress(p)) => {
                    if let (Some(cb), None) = (&progress, &pending)
                        && let Err(e) = deliver(cb, p)
                    {
                        stop.store(true, Ordering::Relaxed);
                        pending = Some(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "the kappe worker thread ended early",
                    ));
                }
            }
            if pending.is_none()
                && let Err(e) = py.check_signals()
            {
                stop.store(true, Ordering::Relaxed);
                pending = Some(e);
            }
        }
    })
}

/// An n×3 NumPy array of points (moves the flat vector into NumPy, no copy).
fn points<'py>(
    py: Python<'py>,
    it: impl ExactSizeIterator<Item = [f64; 3]>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let n = it.len();
    let flat: Vec<f64> = it.flatten().collect();
    PyArray1::from_vec(py, flat).reshape([n, 3])
}

/// One layer for Python: id, nodes (n×3), segment forces and stresses in the final state,
/// overhang.
type LayerArrays<'py> = (
    i32,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Option<f64>,
);

/// The print path for Python: tips (n×3), axes (n×3), layer ids, print length, time.
type PathArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<i32>>,
    f64,
    f64,
);

/// The robot trajectory for Python: the CSV header and the rows × columns array.
type Trajectory<'py> = (Vec<String>, Bound<'py, PyArray2<f64>>);

/// The result of `kappe::run` (`kappe.Result` wraps it). Nothing is converted until asked
/// for: arrays are built from the Rust vectors directly, the summary and the report only when
/// read.
#[pyclass(frozen, module = "kappe._kappe", name = "Outcome")]
struct PyOutcome {
    out: kappe::Outcome,
    report: bool,
}

#[pymethods]
impl PyOutcome {
    /// The verdict (`summary["ok"]`).
    #[getter]
    fn ok(&self) -> bool {
        self.out.verdict.ok
    }

    /// The print time, s (the robot plan's when planned).
    #[getter]
    fn print_time(&self) -> f64 {
        self.out.print_time()
    }

    /// summary.json as `kappe design` writes it (JSON text).
    fn summary_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.out.summary()).map_err(|e| json_err("summary", e))
    }

    /// The constraint report (JSON text of a list).
    fn constraints_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.out.report_input().constraints)
            .map_err(|e| json_err("constraints", e))
    }

    /// The final state's network (JSON text, network.json).
    fn network_json(&self) -> PyResult<String> {
        let v =
            kappe::output::network::network_json(&self.out.cap).map_err(|e| design_error(&e))?;
        serde_json::to_string(&v).map_err(|e| json_err("network", e))
    }

    /// The HTML report, or None when `report=False` was given.
    fn report_html(&self, py: Python<'_>) -> PyResult<Option<String>> {
        if !self.report {
            return Ok(None);
        }
        py.detach(|| self.out.report_html())
            .map(Some)
            .map_err(|e| PyRuntimeError::new_err(format!("report: {e}")))
    }

    /// Every file `kappe design --out` writes for this result, as `(name, bytes)` pairs
    /// (`kappe::Outcome::files`).
    fn files<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Vec<(String, Bound<'py, pyo3::types::PyBytes>)>> {
        let files = py
            .detach(|| self.out.files())
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok(files
            .into_iter()
            .map(|f| (f.name, pyo3::types::PyBytes::new(py, &f.bytes)))
            .collect())
    }

    /// Every layer: `(id, nodes n×3, segment_forces, segment_stress, overhang)`.
    fn layers<'py>(&self, py: Python<'py>) -> PyResult<Vec<LayerArrays<'py>>> {
        let cap = &self.out.cap;
        let area = cap.areas().along_layer;
        let factors = &cap.final_state.factors;
        cap.sections
            .layers
            .iter()
            .enumerate()
            .map(|(q, l)| {
                let d = factors.get(q).copied().unwrap_or(1.0);
                let forces: Vec<f64> = l.segment_forces.iter().map(|f| f * d).collect();
                let stress: Vec<f64> = forces.iter().map(|f| f / area).collect();
                Ok((
                    l.id,
                    points(py, l.nodes.iter().map(|n| [n.xyz.x, n.xyz.y, n.xyz.z]))?,
                    PyArray1::from_vec(py, forces),
                    PyArray1::from_vec(py, stress),
                    cap.overhangs.get(q).copied(),
                ))
            })
            .collect()
    }

    /// The print path: `(points n×3, axis n×3, layer, print_length_m, time_s)`.
    fn path<'py>(&self, py: Python<'py>) -> PyResult<PathArrays<'py>> {
        let p = &self.out.cap.path;
        Ok((
            points(py, p.points.iter().map(|p| [p.tip.x, p.tip.y, p.tip.z]))?,
            points(py, p.points.iter().map(|p| [p.axis.x, p.axis.y, p.axis.z]))?,
            PyArray1::from_vec(py, p.points.iter().map(|p| p.layer).collect()),
            p.print_length,
            p.time,
        ))
    }

    /// trajectory.csv of the robot plan (as `kappe design` writes it), or None.
    fn trajectory_csv(&self) -> PyResult<Option<String>> {
        let Some(Ok(plan)) = &self.out.robot else {
            return Ok(None);
        };
        let mut csv = Vec::new();
        kappe_robot::write_trajectory_csv(plan, &mut csv)
            .map_err(|e| PyRuntimeError::new_err(format!("trajectory: {e}")))?;
        String::from_utf8(csv)
            .map(Some)
            .map_err(|e| PyRuntimeError::new_err(format!("trajectory: {e}")))
    }

    /// The trajectory as `(header, rows×columns array)`: trajectory.csv's numbers, parsed
    /// here (Rust prints shortest round-trip floats, so the array equals the file).
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<Option<Trajectory<'py>>> {
        let Some(csv) = self.trajectory_csv()? else {
            return Ok(None);
        };
        let mut lines = csv.lines().filter(|l| !l.is_empty() && !l.starts_with('#'));
        let header: Vec<String> = lines
            .next()
            .map(|h| h.split(',').map(str::to_owned).collect())
            .unwrap_or_default();
        let mut flat = Vec::new();
        let mut rows = 0;
        for line in lines {
            for x in line.split(',') {
                flat.push(x.parse::<f64>().map_err(|e| {
                    PyRuntimeError::new_err(format!("trajectory row {rows}: {x:?}: {e}"))
                })?);
            }
            rows += 1;
        }
        let cols = header.len();
        if flat.len() != rows * cols {
            return Err(PyRuntimeError::new_err(
                "trajectory: rows of unequal length",
            ));
        }
        Ok(Some((
            header,
            PyArray1::from_vec(py, flat).reshape([rows, cols])?,
        )))
    }
}

/// Runs a design: `design_toml` (complete TOML), `analysis_json` (JSON of the `[analysis]`
/// options, `"null"` for none, absent for the design's own), whether to plan the robot,
/// `allow_fail`, a progress callable `progress(stage, done, total)`. Returns an `Outcome`.
#[pyfunction]
#[pyo3(signature = (design_toml, analysis_json=None, robot=true, allow_fail=false, progress=None, report=true))]
fn run_design(
    py: Python<'_>,
    design_toml: &str,
    analysis_json: Option<&str>,
    robot: bool,
    allow_fail: bool,
    progress: Option<Bound<'_, PyAny>>,
    report: bool,
) -> PyResult<PyOutcome> {
    let design = kappe::Design::from_toml_str(design_toml).map_err(|e| design_error(&e))?;
    let mut options = kappe::Options::of(&design);
    if let Some(a) = analysis_json {
        options.analysis = serde_json::from_str::<Option<kappe::analysis::AnalysisOptions>>(a)
            .map_err(|e| {
                DesignError::new_err((format!("analysis: {e}"), "analysis", a.to_string(), ""))
            })?;
        if let Some(o) = &options.analysis {
            o.validate().map_err(|e| design_error(&e))?;
        }
    }
    options.robot = robot;
    options.allow_fail = allow_fail;
    let deliver = |cb: &Bound<'_, PyAny>, p: kappe::Progress| -> PyResult<()> {
        cb.call1((stage_name(p.stage), p.done, p.total)).map(drop)
    };
    let out = run_with_progress(py, progress, deliver, move |stop, tick| {
        let on_progress = |p: kappe::Progress| {
            tick(p);
            if stop.load(Ordering::Relaxed) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        kappe::run(&design, &options, &on_progress)
    })?;
    Ok(PyOutcome { out, report })
}

/// Parses a study file's text (`source` names it; `base = "file"` is resolved in `directory`).
/// Returns JSON: title, parameters, fingerprint, and per design its name, `design.toml` and
/// parameter values (or the reason it cannot run).
#[pyfunction]
#[pyo3(signature = (text, source="study.toml", directory="."))]
fn study_parse(text: &str, source: &str, directory: &str) -> PyResult<String> {
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
fn run_json(
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
fn study_run_one(
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
fn study_run_local(
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
fn study_collect(
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

/// `kappe cem solve`: a topology as JSON text (the `kappe.cem.topology` format); returns the
/// equilibrium JSON exactly as the CLI writes it.
#[pyfunction]
#[pyo3(signature = (topology_json, force_polygons=false))]
fn cem_solve(py: Python<'_>, topology_json: &str, force_polygons: bool) -> PyResult<String> {
    let file = kappe_cem::json::read_topology(topology_json)
        .map_err(|e| PyValueError::new_err(format!("invalid topology: {e}")))?;
    let eq = py
        .detach(|| kappe_cem::solve(&file.topology, &file.solver))
        .map_err(|e| PyRuntimeError::new_err(format!("cannot solve: {e}")))?;
    kappe_cem::report::solve_document(&eq, &file.solver, force_polygons)
        .map_err(|e| json_err("the result", e))
}

/// A topology parsed once (`kappe.cem.Topology`), to solve many times without the JSON round
/// trip of [`cem_solve`]: the call then costs the solve plus moving the result vectors into
/// NumPy arrays (no copy, no Python lists).
#[pyclass(frozen, module = "kappe._kappe")]
struct Topology {
    file: kappe_cem::json::TopologyFile,
}

#[pymethods]
impl Topology {
    /// Parse and check a topology (JSON text in the `kappe.cem.topology` format).
    #[new]
    fn new(topology_json: &str) -> PyResult<Self> {
        let file = kappe_cem::json::read_topology(topology_json)
            .map_err(|e| PyValueError::new_err(format!("invalid topology: {e}")))?;
        Ok(Topology { file })
    }

    /// Solve; returns a dict of NumPy arrays: `xyz` (n×3, node order), `trail_forces`,
    /// `deviation_forces` (signed edge forces) and `reactions` (n×3, zero off supports).
    fn solve<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let eq = py
            .detach(|| kappe_cem::solve(&self.file.topology, &self.file.solver))
            .map_err(|e| PyRuntimeError::new_err(format!("cannot solve: {e}")))?;
        let d = PyDict::new(py);
        d.set_item("xyz", points(py, eq.nodes.iter().map(|n| n.xyz.into()))?)?;
        d.set_item(
            "trail_forces",
            PyArray1::from_vec(py, eq.trail_edges.iter().map(|e| e.force).collect()),
        )?;
        d.set_item(
            "deviation_forces",
            PyArray1::from_vec(py, eq.deviation_edges.iter().map(|e| e.force).collect()),
        )?;
        d.set_item(
            "reactions",
            points(py, eq.nodes.iter().map(|n| n.reaction.into()))?,
        )?;
        Ok(d)
    }
}

/// `kappe cem optimize`: a topology with an `optimization` block; returns JSON of
/// `{converged, status, objective, equilibrium}`.
#[pyfunction]
fn cem_optimize(py: Python<'_>, topology_json: &str) -> PyResult<String> {
    let file = kappe_cem::json::read_topology(topology_json)
        .map_err(|e| PyValueError::new_err(format!("invalid topology: {e}")))?;
    let Some((problem, options)) = kappe_cem::report::optimization_problem(&file)
        .map_err(|e| PyValueError::new_err(format!("invalid optimization block: {e}")))?
    else {
        return Err(PyValueError::new_err(
            "the topology has no `optimization` block; nothing to optimize (use kappe.cem.solve)",
        ));
    };
    let r = py
        .detach(|| kappe_cem::optimize(&file.topology, &problem, &options))
        .map_err(|e| PyRuntimeError::new_err(format!("cannot optimize: {e}")))?;
    Ok(serde_json::json!({
        "converged": r.converged,
        "status": r.status.name(),
        "objective": r.objective_at_x_opt,
        "equilibrium": kappe_cem::report::optimize_value(&r, &options.solver),
        "report": kappe_cem::report::optimization_report(&r),
    })
    .to_string())
}

/// `kappe fe buckle`'s result: its document (JSON text, without the modes), the factors and
/// the mode shapes (n×6 each) as NumPy arrays.
type Buckled<'py> = (
    String,
    Bound<'py, PyArray1<f64>>,
    Vec<Bound<'py, PyArray2<f64>>>,
);

/// `kappe fe buckle`: a shell mesh as JSON text (the fixture format, the command's element
/// default); returns the command's document with the factors and mode shapes as arrays.
#[pyfunction]
#[pyo3(signature = (mesh_json, modes=1, sturm_check=true))]
fn fe_buckle<'py>(
    py: Python<'py>,
    mesh_json: &str,
    modes: usize,
    sturm_check: bool,
) -> PyResult<Buckled<'py>> {
    let t0 = std::time::Instant::now();
    let model = kappe_fe::summary::mesh_from_str(mesh_json, false, None)
        .map_err(|e| PyValueError::new_err(format!("invalid mesh: {e}")))?;
    let options = kappe_fe::BucklingOptions {
        modes,
        sturm_check,
        ..kappe_fe::BucklingOptions::default()
    };
    let r = py
        .detach(|| {
            kappe_fe::BucklingSolver::new(&model)
                .and_then(|solver| solver.buckling(&model, &options))
        })
        .map_err(|e| PyRuntimeError::new_err(format!("buckling analysis failed: {e}")))?;
    if !kappe_fe::summary::has_load(&r.static_result) {
        return Err(PyValueError::new_err(
            "the mesh has no load (gamma = 0 and no nodal loads): there is nothing to buckle",
        ));
    }
    let doc = kappe_fe::summary::buckle_value(&model, &r, t0.elapsed().as_secs_f64(), false);
    let text = serde_json::to_string(&doc).map_err(|e| json_err("the result", e))?;
    let shapes = r
        .modes
        .iter()
        .map(|m| {
            let n = m.len();
            PyArray1::from_vec(py, m.iter().flatten().copied().collect()).reshape([n, 6])
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok((text, PyArray1::from_slice(py, &r.factors), shapes))
}

/// `kappe fe static`: linear statics of a shell mesh (JSON text, the command's element
/// default); returns the command's document (JSON text, without the displacements) and the
/// displacements (n×6: ux, uy, uz, rx, ry, rz) as a NumPy array.
#[pyfunction]
fn fe_static<'py>(
    py: Python<'py>,
    mesh_json: &str,
) -> PyResult<(String, Bound<'py, PyArray2<f64>>)> {
    let t0 = std::time::Instant::now();
    let model = kappe_fe::summary::mesh_from_str(mesh_json, false, None)
        .map_err(|e| PyValueError::new_err(format!("invalid mesh: {e}")))?;
    let r = py
        .detach(|| kappe_fe::linear_static(&model))
        .map_err(|e| PyRuntimeError::new_err(format!("static analysis failed: {e}")))?;
    let mut doc = kappe_fe::summary::static_value(&model, &r, t0.elapsed().as_secs_f64());
    if let serde_json::Value::Object(m) = &mut doc {
        m.remove("displacements");
    }
    let text = serde_json::to_string(&doc).map_err(|e| json_err("the result", e))?;
    let n = r.displacements.len();
    let u = PyArray1::from_vec(py, r.displacements.iter().flatten().copied().collect());
    Ok((text, u.reshape([n, 6])?))
}

/// `kappe optimize`: the design loop of an optimize file (or a design file with an
/// `[optimize]` table) given as TOML text; `directory` resolves `design = "FILE"`. Returns
/// `(design_toml, optimize_json, report, feasible)`: the files and the text the command
/// writes and prints. `progress(evaluation_json)` is called after every evaluation.
#[pyfunction]
#[pyo3(signature = (text, directory=".", max_evaluations=None, progress=None))]
fn optimize_design(
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
        optimize::optimize_until(&file, &start, &|e| {
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

/// UR10e inverse kinematics of a 4×4 TCP pose (row-major nested lists) with an optional
/// `flange_from_tcp`; returns every solution (6 joint angles, rad).
#[pyfunction]
#[pyo3(signature = (pose, flange_from_tcp=None))]
fn robot_ik(
    pose: [[f64; 4]; 4],
    flange_from_tcp: Option<[[f64; 4]; 4]>,
) -> PyResult<Vec<[f64; 6]>> {
    use kappe_robot::Iso;
    let tcp_from_flange = match flange_from_tcp {
        Some(m) => Iso::from_mat4(&m)
            .map_err(|e| PyValueError::new_err(format!("flange_from_tcp: {e}")))?
            .inverse(),
        None => Iso::IDENTITY,
    };
    let t = Iso::from_mat4(&pose).map_err(|e| PyValueError::new_err(format!("pose: {e}")))?;
    Ok(kappe_robot::UR10E
        .ik_tcp(&t, &tcp_from_flange)
        .as_slice()
        .to_vec())
}

#[pymodule]
fn _kappe(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("DesignError", m.py().get_type::<DesignError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(default_design_toml, m)?)?;
    m.add_function(wrap_pyfunction!(example_design_toml, m)?)?;
    m.add_function(wrap_pyfunction!(design_from_toml, m)?)?;
    m.add_function(wrap_pyfunction!(design_from_json, m)?)?;
    m.add_function(wrap_pyfunction!(design_to_json, m)?)?;
    m.add_function(wrap_pyfunction!(run_design, m)?)?;
    m.add_function(wrap_pyfunction!(study_parse, m)?)?;
    m.add_function(wrap_pyfunction!(study_run_one, m)?)?;
    m.add_function(wrap_pyfunction!(study_run_local, m)?)?;
    m.add_function(wrap_pyfunction!(study_collect, m)?)?;
    m.add_function(wrap_pyfunction!(cem_solve, m)?)?;
    m.add_function(wrap_pyfunction!(cem_optimize, m)?)?;
    m.add_class::<Topology>()?;
    m.add_class::<PyOutcome>()?;
    m.add_function(wrap_pyfunction!(fe_buckle, m)?)?;
    m.add_function(wrap_pyfunction!(fe_static, m)?)?;
    m.add_function(wrap_pyfunction!(robot_ik, m)?)?;
    m.add_function(wrap_pyfunction!(optimize_design, m)?)?;
    m.add_function(wrap_pyfunction!(ceiling::ceiling_bays, m)?)?;
    m.add_function(wrap_pyfunction!(ceiling::ceiling_run_bay, m)?)?;
    m.add_function(wrap_pyfunction!(ceiling::ceiling_assemble, m)?)?;
    m.add_function(wrap_pyfunction!(ceiling::write_output, m)?)?;
    Ok(())
}
