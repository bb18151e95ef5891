//! Designs from Python: the design file (TOML/JSON) and one run of `kappe::run` with progress, its `Outcome` as NumPy arrays and lazily built documents.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::errors::*;

/// The embedded default design as TOML.
#[pyfunction]
pub(crate) fn default_design_toml() -> PyResult<String> {
    kappe::Design::default()
        .to_toml_string()
        .map_err(|e| design_error(&e))
}

/// The commented example design file (`kappe init`).
#[pyfunction]
pub(crate) fn example_design_toml() -> &'static str {
    kappe::input::EXAMPLE_TOML
}

/// Parse and validate a design given as TOML text; returns its complete TOML (every field).
#[pyfunction]
pub(crate) fn design_from_toml(text: &str) -> PyResult<String> {
    let d = kappe::Design::from_toml_str(text).map_err(|e| design_error(&e))?;
    d.to_toml_string().map_err(|e| design_error(&e))
}

/// Parse and validate a design given as JSON text (a dict in the design file's schema);
/// returns its complete TOML.
#[pyfunction]
pub(crate) fn design_from_json(text: &str) -> PyResult<String> {
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
pub(crate) fn design_to_json(text: &str) -> PyResult<String> {
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

pub(crate) fn stage_name(s: kappe::Stage) -> &'static str {
    match s {
        kappe::Stage::States => "states",
        kappe::Stage::Analysis => "analysis",
        kappe::Stage::Robot => "robot",
    }
}

/// Runs `work` (given the stop flag and a progress sender) on a worker thread; the caller
/// waits with the GIL released, delivers progress to `progress` and stops the work on Ctrl-C
/// or when `progress` raises.
pub(crate) fn run_with_progress<'py, T: Send, P: Send>(
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
pub(crate) fn points<'py>(
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
pub(crate) struct PyOutcome {
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
        let v = kappe::output::network_json(&self.out.cap).map_err(|e| design_error(&e))?;
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
pub(crate) fn run_design(
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
