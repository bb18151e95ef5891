//! Structural reliability for Kappe: the chance that a print stands (issue 24).
//!
//! A general engine, independent of the rest of Kappe:
//!
//! * [`variable`]: normal, lognormal and uniform random variables (cdf, inverse cdf, pdf, the map
//!   to standard normal space), validated with named errors.
//! * [`model`]: a set of variables with a physical correlation matrix, mapped to standard normal
//!   space by the Nataf model (exact integral, solved numerically) and a Cholesky factor.
//! * [`spec`]: the input-file form of an uncertain parameter (`{ dist = "normal", std = … }`).
//! * [`drift`]: a parameter whose mean drifts with print time (linear %/h, steps).
//! * [`mod@form`]: FORM with the improved HL-RF algorithm: β, P_f = Φ(−β), the design point, α, γ,
//!   importance factors and dβ/dμ, dβ/dσ.
//! * [`system`]: a series system of many FORM components (every state × every check), with
//!   ρᵢⱼ = αᵢᵀαⱼ: P_f,sys by seeded importance sampling of the union, and Ditlevsen bounds.
//! * [`mod@sorm`]: SORM at FORM's design point: the principal curvatures of the limit-state
//!   surface and P_f by Hohenbichler–Rackwitz (Breitung's formula alongside).
//! * [`sampling`]: crude Monte Carlo and importance sampling around the design point, seeded,
//!   splittable into batches that merge bit for bit into the single run.
//!
//! Conventions: the limit state g(x) is given in physical space and failure is g ≤ 0; β is
//! positive when the means are safe.
//!
//! ```
//! use kappe_reliability::{form, FormOptions, Model, RandomVariable};
//! // g = R − S, R ~ N(200, 20), S ~ N(150, 10): β = 50/√500.
//! let model = Model::independent(vec![
//!     RandomVariable::normal("R", 200.0, 20.0)?,
//!     RandomVariable::normal("S", 150.0, 10.0)?,
//! ])?;
//! let r = form(&model, &mut |x: &[f64]| x[0] - x[1], &FormOptions::default())?;
//! assert!((r.beta - 50.0 / 500f64.sqrt()).abs() < 1e-9);
//! # Ok::<(), kappe_reliability::Error>(())
//! ```

pub mod drift;
pub mod error;
pub mod form;
pub mod limit_state;
pub mod model;
mod rng;
pub mod sampling;
pub mod sorm;
pub mod spec;
pub mod stdnormal;
pub mod system;
pub mod variable;

pub use drift::{Drift, DriftStep};
pub use error::{Error, EvalError, Result};
pub use form::{FormOptions, FormResult, form, form_at};
pub use limit_state::{Fallible, LimitState, WithGradient, WithHessian};
pub use model::{Correlation, Model};
pub use sampling::{
    Batch, BlockSums, EventBatch, EventBlock, SamplingBatch, SamplingMethod, SamplingOptions,
    SamplingResult, importance_sampling, merge, merge_events, monte_carlo, sample_batch,
    sample_batch_parallel, sample_events,
};
pub use sorm::{HessianSource, SormOptions, SormResult, sorm};
pub use spec::{DistKind, UncertaintySpec};
pub use system::{Component, SystemOptions, SystemResult, series_system};
pub use variable::{Distribution, RandomVariable};
