//! `kappe._kappe`: the native half of the Python package `kappe` (python/kappe). It exchanges
//! JSON text and plain numbers with the Python half, which builds the user-facing classes
//! (`Design`, `Result`, NumPy arrays, the COMPAS data conventions): JSON keeps this layer small
//! and its types checked in one place (serde, with the field named in every error).
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

use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

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
fn default_design_toml() -> String {
    kappe::Design::default().to_toml_string()
}

/// The commented example design file (`kappe init`).
#[pyfunction]
fn example_design_toml() -> &'static str {
    kappe::spec::EXAMPLE_TOML
}

/// Parse and validate a design given as TOML text; returns its complete TOML (every field).
#[pyfunction]
fn design_from_toml(text: &str) -> PyResult<String> {
    let d = kappe::Design::from_toml_str(text).map_err(|e| design_error(&e))?;
    Ok(d.to_toml_string())
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
        .parse()
        .map_err(|e| json_err("design TOML", e))?;
    serde_json::to_string(&table).map_err(|e| json_err("design JSON", e))
}

/// Messages from the worker thread of a run.
enum Msg {
    Progress(kappe::Progress),
    Done(Result<String, kappe::DesignError>),
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
fn run_with_progress(
    py: Python<'_>,
    progress: Option<Bound<'_, PyAny>>,
    work: impl FnOnce(
        &AtomicBool,
        &(dyn Fn(kappe::Progress) + Sync),
    ) -> Result<String, kappe::DesignError>
    + Send,
) -> PyResult<String> {
    let stop = AtomicBool::new(false);
    let (tx, rx) = mpsc::channel::<Msg>();
    std::thread::scope(|scope| {
        let stop = &stop;
        let tx_work = tx.clone();
        scope.spawn(move || {
            let sender = std::sync::Mutex::new(tx_work.clone());
            let on_progress = |p: kappe::Progress| {
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
                        && let Err(e) = cb.call1((stage_name(p.stage), p.done, p.total))
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

/// The result of `kappe::run` as JSON: everything the Python `Result` needs.
fn outcome_json(out: &kappe::Outcome, with_report: bool) -> Result<String, kappe::DesignError> {
    let cap = &out.cap;
    let areas = cap.areas();
    let factors = &cap.final_state.factors;
    let layers: Vec<serde_json::Value> = cap
        .sections
        .layers
        .iter()
        .enumerate()
        .map(|(q, l)| {
            let d = factors.get(q).copied().unwrap_or(1.0);
            serde_json::json!({
                "id": l.id,
                "nodes": l.nodes.iter().map(|n| [n.xyz.x, n.xyz.y, n.xyz.z]).collect::<Vec<_>>(),
                "segment_forces": l.segment_forces.iter().map(|f| f * d).collect::<Vec<_>>(),
                "segment_stress": l.segment_forces.iter().map(|f| f * d / areas.along_layer).collect::<Vec<_>>(),
                "overhang": cap.overhangs.get(q).copied(),
            })
        })
        .collect();
    let path = serde_json::json!({
        "points": cap.path.points.iter().map(|p| [p.tip.x, p.tip.y, p.tip.z]).collect::<Vec<_>>(),
        "axis": cap.path.points.iter().map(|p| [p.axis.x, p.axis.y, p.axis.z]).collect::<Vec<_>>(),
        "layer": cap.path.points.iter().map(|p| p.layer).collect::<Vec<_>>(),
        "print_length_m": cap.path.print_length,
        "time_s": cap.path.time,
    });
    let trajectory = match &out.robot {
        Some(Ok(plan)) => {
            let mut csv = Vec::new();
            kappe_robot::write_trajectory_csv(plan, &mut csv).map_err(|e| {
                kappe::DesignError::State {
                    state: 0,
                    message: format!("trajectory: {e}"),
                }
            })?;
            serde_json::Value::String(String::from_utf8_lossy(&csv).into_owned())
        }
        _ => serde_json::Value::Null,
    };
    let network = kappe::export::network_json(cap)?;
    let report = if with_report {
        serde_json::json!(out.report_html().map_err(|e| kappe::DesignError::State {
            state: 0,
            message: format!("report: {e}"),
        })?)
    } else {
        serde_json::Value::Null
    };
    let doc = serde_json::json!({
        "summary": out.summary(),
        "ok": out.ok,
        "print_time_s": out.print_time(),
        "constraints": out.report_input().constraints,
        "layers": layers,
        "path": path,
        "trajectory_csv": trajectory,
        "network": network,
        "report_html": report,
    });
    Ok(doc.to_string())
}

/// Runs a design: `design_toml` (complete TOML), `analysis_json` (JSON of the `[analysis]`
/// options, `"null"` for none, absent for the design's own), whether to plan the robot,
/// `allow_fail`, a progress callable `progress(stage, done, total)`. Returns JSON text.
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
) -> PyResult<String> {
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
    run_with_progress(py, progress, move |stop, tick| {
        let on_progress = |p: kappe::Progress| {
            tick(p);
            if stop.load(Ordering::Relaxed) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        let out = kappe::run(&design, &options, &on_progress)?;
        outcome_json(&out, report)
    })
}

/// Parses a study file's text (`source` names it; `base = "file"` is resolved in `directory`).
/// Returns JSON: title, parameters, fingerprint, and per design its name, `design.toml` and
/// parameter values (or the reason it cannot run).
#[pyfunction]
#[pyo3(signature = (text, source="study.toml", directory="."))]
fn study_parse(text: &str, source: &str, directory: &str) -> PyResult<String> {
    let study = kappe::study::parse(text, source, std::path::Path::new(directory))
        .map_err(|e| DesignError::new_err((e.to_string(), "study", "", "")))?;
    let designs: Vec<serde_json::Value> = study
        .variations
        .iter()
        .map(|v| {
            serde_json::json!({
                "index": v.index,
                "name": v.name,
                "design_toml": v.design_toml(),
                "parameters": kappe::study::parameter_values(v, &study.parameters),
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
    let study = kappe::study::parse(text, source, std::path::Path::new(directory))
        .map_err(|e| DesignError::new_err((e.to_string(), "study", "", "")))?;
    let Some(v) = study.variations.get(index) else {
        return Err(PyValueError::new_err(format!(
            "index {index}: the study has {} designs",
            study.variations.len()
        )));
    };
    let params = kappe::study::parameter_values(v, &study.parameters);
    let run = py.detach(|| kappe::study::run_one(v, params, no_robot));
    Ok(serde_json::json!({
        "record": run.record,
        "summary": run.summary,
        "report_html": run.report_html,
    })
    .to_string())
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
    let study = kappe::study::parse(text, source, std::path::Path::new(directory))
        .map_err(|e| DesignError::new_err((e.to_string(), "study", "", "")))?;
    let mut rows: Vec<kappe::study::Record> =
        serde_json::from_str(records_json).map_err(|e| json_err("records", e))?;
    rows.sort_by_key(|r| r.index);
    let result = kappe::study::collect(&study, None, no_robot, rows)
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
    let doc = kappe_cem::json::equilibrium_to_json(&eq, &file.solver, force_polygons);
    let mut text = serde_json::to_string_pretty(&doc).map_err(|e| json_err("the result", e))?;
    text.push('\n');
    Ok(text)
}

/// `(xyz, trail_forces, deviation_forces, reactions)` of [`Topology::solve`], flat.
type SolvedArrays = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

/// A topology parsed once (`kappe.cem.Topology`), to solve many times without the JSON round
/// trip of [`cem_solve`]: the call then costs the solve plus copying the results.
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

    /// Solve; returns `(xyz, trail_forces, deviation_forces, reactions)`: node coordinates
    /// (n×3, in node order), the signed edge forces, and the support reactions (n×3, zero off
    /// supports), as flat lists for NumPy.
    fn solve(&self, py: Python<'_>) -> PyResult<SolvedArrays> {
        let eq = py
            .detach(|| kappe_cem::solve(&self.file.topology, &self.file.solver))
            .map_err(|e| PyRuntimeError::new_err(format!("cannot solve: {e}")))?;
        let xyz = eq
            .nodes
            .iter()
            .flat_map(|n| [n.xyz.x, n.xyz.y, n.xyz.z])
            .collect();
        let reactions = eq
            .nodes
            .iter()
            .flat_map(|n| [n.reaction.x, n.reaction.y, n.reaction.z])
            .collect();
        let trail = eq.trail_edges.iter().map(|e| e.force).collect();
        let deviation = eq.deviation_edges.iter().map(|e| e.force).collect();
        Ok((xyz, trail, deviation, reactions))
    }
}

/// `kappe cem optimize`: a topology with an `optimization` block; returns JSON of
/// `{converged, status, objective, equilibrium}`.
#[pyfunction]
fn cem_optimize(py: Python<'_>, topology_json: &str) -> PyResult<String> {
    let file = kappe_cem::json::read_topology(topology_json)
        .map_err(|e| PyValueError::new_err(format!("invalid topology: {e}")))?;
    let Some(block) = &file.optimization else {
        return Err(PyValueError::new_err(
            "the topology has no `optimization` block; nothing to optimize (use kappe.cem.solve)",
        ));
    };
    let (problem, options) = kappe_cem::Problem::from_json(block)
        .map_err(|e| PyValueError::new_err(format!("invalid optimization block: {e}")))?;
    let r = py
        .detach(|| kappe_cem::optimize(&file.topology, &problem, &options))
        .map_err(|e| PyRuntimeError::new_err(format!("cannot optimize: {e}")))?;
    let eq = kappe_cem::json::equilibrium_to_json(&r.equilibrium, &file.solver, false);
    Ok(serde_json::json!({
        "converged": r.converged,
        "status": r.status.name(),
        "objective": r.objective_at_x_opt,
        "equilibrium": eq,
    })
    .to_string())
}

/// `kappe fe buckle`: a shell mesh as JSON text (the fixture format); returns
/// `{factors, modes}`.
#[pyfunction]
#[pyo3(signature = (mesh_json, modes=1, sturm_check=true))]
fn fe_buckle(py: Python<'_>, mesh_json: &str, modes: usize, sturm_check: bool) -> PyResult<String> {
    let model = kappe_fe::mesh_json::parse_mesh(mesh_json)
        .map_err(|e| PyValueError::new_err(format!("invalid mesh: {e}")))?;
    let options = kappe_fe::BucklingOptions {
        modes,
        sturm_check,
        ..kappe_fe::BucklingOptions::default()
    };
    let r = py
        .detach(|| kappe_fe::buckling(&model, &options))
        .map_err(|e| PyRuntimeError::new_err(format!("buckling analysis failed: {e}")))?;
    Ok(serde_json::json!({"factors": r.factors, "modes": r.modes}).to_string())
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
    m.add_function(wrap_pyfunction!(study_collect, m)?)?;
    m.add_function(wrap_pyfunction!(cem_solve, m)?)?;
    m.add_function(wrap_pyfunction!(cem_optimize, m)?)?;
    m.add_class::<Topology>()?;
    m.add_function(wrap_pyfunction!(fe_buckle, m)?)?;
    m.add_function(wrap_pyfunction!(robot_ik, m)?)?;
    Ok(())
}
