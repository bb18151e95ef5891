//! # kappe: the 3D-printed cap ceiling
//!
//! The method of the paper (`cap-ceiling-paper.txt`) made precise in `method.md`. The modules
//! are the floors of the data flow; each imports only the floors before it:
//!
//! | floor | module | holds |
//! |---|---|---|
//! | 0 | [`input`] | the design and its option tables (plain data, parse, validate), the errors |
//! | 1 | [`form`] | layer arch (CEM), sections, ends, print states and forces, overhang, path, beads |
//! | 2 | [`robot_plan`] | the UR10e plan of the print path (stations, timing, programs' input) |
//! | 3 | [`schedule`] | the one clock: every layer's start and end, so its age in every state |
//! | 4 | [`analysis`] | every state's stresses, shell buckling and green-state checks |
//! | 5 | [`verdict`] | pass or fail, from the domain results |
//! | 6 | [`run`] | the pipeline of one design: form → plan → schedule → analysis → verdict |
//! | 7 | [`output`] | `summary.json`, `network.json`, the report input, the files, the safe writer |
//! | 8 | [`commands`] | study, ceiling, optimize, least waits, calibrations, buildability |
//!
//! [`class`] sorts every crate's errors for whoever reports them (exit status, exception).

#![warn(missing_docs)]

pub mod analysis;
pub mod class;
pub mod commands;
pub mod form;
pub mod input;
pub mod output;
pub mod robot_plan;
pub mod run;
pub mod schedule;
pub mod verdict;

pub use form::{Cap, StateSummary, design_cap};
pub use input::{Context, Design, DesignError};
pub use run::{Given, Options, Outcome, Progress, Stage, evaluate, no_progress, run};
