//! Shell finite elements from Python: `kappe fe buckle` / `static` on a mesh.

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::errors::*;

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
pub(crate) fn fe_buckle<'py>(
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
pub(crate) fn fe_static<'py>(
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
