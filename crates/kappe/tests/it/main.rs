//! The kappe crate's integration tests: one binary, one module per area (issue 22).

mod analysis;
mod analysis_loop;
mod analysis_props;
mod asprinted;
mod blf_convergence;
mod buildability_collapse;
mod buildability_reliability;
mod cap;
mod ceiling;
mod collapse;
mod collapse_reliability;
mod common;
mod corrugation;
mod design_monte_carlo;
mod ends;
mod floors;
mod green_state;
mod moving;
mod readers_fuzz;
mod reliability;
mod scale;
mod shell_element;
mod summary_schema;
