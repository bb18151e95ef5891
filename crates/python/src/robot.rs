//! UR10e kinematics from Python.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// UR10e inverse kinematics of a 4×4 TCP pose (row-major nested lists) with an optional
/// `flange_from_tcp`; returns every solution (6 joint angles, rad).
#[pyfunction]
#[pyo3(signature = (pose, flange_from_tcp=None))]
pub(crate) fn robot_ik(
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
