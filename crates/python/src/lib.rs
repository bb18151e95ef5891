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

//!
//! One module per area, as the package's Python modules: [`design`], [`study`], [`ceiling`],
//! [`cem`], [`fe`], [`optimize`], [`robot`], [`buildability`] (the Monte Carlo batches of a
//! buildability print), [`design_mc`] (the steps of a design's Monte Carlo); [`errors`] maps library errors to Python exceptions.

use pyo3::prelude::*;

mod buildability;
mod ceiling;
mod cem;
mod design;
mod design_mc;
mod errors;
mod fe;
mod optimize;
mod robot;
mod study;

use cem::*;
use design::*;
use errors::DesignError;
use fe::*;
use optimize::*;
use robot::*;
use study::*;

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
    m.add_function(wrap_pyfunction!(
        buildability::buildability_mc_table_part,
        m
    )?)?;
    m.add_function(wrap_pyfunction!(
        buildability::buildability_mc_tables_join,
        m
    )?)?;
    m.add_function(wrap_pyfunction!(
        buildability::buildability_mc_collapse_tables,
        m
    )?)?;
    m.add_function(wrap_pyfunction!(buildability::buildability_mc_batch, m)?)?;
    m.add_function(wrap_pyfunction!(buildability::buildability_mc_merge, m)?)?;
    m.add_function(wrap_pyfunction!(design_mc::design_mc_plan, m)?)?;
    m.add_function(wrap_pyfunction!(design_mc::design_mc_table_part, m)?)?;
    m.add_function(wrap_pyfunction!(design_mc::design_mc_setup, m)?)?;
    m.add_function(wrap_pyfunction!(design_mc::design_mc_batch, m)?)?;
    m.add_function(wrap_pyfunction!(design_mc::design_mc_merge, m)?)?;
    Ok(())
}
