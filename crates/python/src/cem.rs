//! General CEM from Python: `kappe cem solve` / `optimize` on a topology, results as NumPy arrays.

use numpy::PyArray1;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::design::*;
use crate::errors::*;

/// `kappe cem solve`: a topology as JSON text (the `kappe.cem.topology` format); returns the
/// equilibrium JSON exactly as the CLI writes it.
#[pyfunction]
#[pyo3(signature = (topology_json, force_polygons=false))]
pub(crate) fn cem_solve(
    py: Python<'_>,
    topology_json: &str,
    force_polygons: bool,
) -> PyResult<String> {
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
pub(crate) struct Topology {
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
pub(crate) fn cem_optimize(py: Python<'_>, topology_json: &str) -> PyResult<String> {
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
