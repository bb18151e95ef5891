//! Errors as Python sees them: `DesignError(message, field, value, allowed)` for what the user
//! got wrong, `ValueError` for malformed JSON.

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
pub(crate) fn design_error(e: &kappe::DesignError) -> PyErr {
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

pub(crate) fn json_err(what: &str, e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{what}: {e}"))
}
