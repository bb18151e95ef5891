//! Floor 0, **the input**: the design and its option tables as plain data, parsed and validated
//! ([`Design`]), the material's time model ([`material`]), the analysis options
//! ([`analysis`]), the schedule's waits ([`schedule`]), and the one error type of the pipeline
//! ([`DesignError`]). Nothing here knows about any later stage.

pub(crate) mod ageing;
pub(crate) mod analysis;
pub(crate) mod context;
pub(crate) mod design;
pub(crate) mod error;
pub(crate) mod material;
pub(crate) mod nonlinear;
pub(crate) mod resolve;
pub(crate) mod schedule;
pub(crate) mod uncertainty;

pub use context::Context;
pub use design::Design;
pub use error::DesignError;

// The items users outside the crate need (the CLI, Python, the designer, the tests).
pub use analysis::AnalysisOptions;
pub use design::EXAMPLE_TOML;
pub use material::{TimeLaw, TimeModel, TimeModelSpec};
pub use nonlinear::{NonlinearSpec, PathStart};
pub use uncertainty::{BETA_MIN_DEFAULT, IMPERFECTION, UncertaintyTable};
