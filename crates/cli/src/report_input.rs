//! Moved to the library: `kappe::report_input` (the mapping), `kappe::verdict` (pass or fail)
//! and `kappe::evaluate` (the pipeline after form-finding). This file stays until `main.rs`
//! drops its `mod report_input;`.
