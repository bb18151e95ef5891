//! Integration tests of kappe-fe: the acceptance checks A1–A12 of
//! `../shared/reference/buckling.md` §7 (one test binary, modules per topic).

// Index loops mirror the formulas (DOF d of node n).
#![allow(clippy::needless_range_loop)]

mod andes;
mod bad_input;
mod closed_form;
mod common;
mod element_patch;
mod fixtures;
mod mindlin;
mod nonlinear;
mod solver_checks;
mod twolevel;
