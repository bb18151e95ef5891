//! Floor 0, **the input**: the design and its option tables as plain data, parsed and validated
//! ([`Design`]), the material's time model ([`material`]), the analysis options
//! ([`analysis`]), the schedule's waits ([`schedule`]), and the one error type of the pipeline
//! ([`DesignError`]). Nothing here knows about any later stage.

pub mod ageing;
pub mod analysis;
pub mod context;
pub mod design;
pub mod error;
pub mod material;
pub mod nonlinear;
pub mod resolve;
pub mod schedule;
pub mod uncertainty;

pub use context::Context;
pub use design::Design;
pub use error::DesignError;
