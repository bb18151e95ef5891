//! Typed errors: each names the variable (or option), the field and what is allowed.

/// The error a caller's limit-state function may return (an FE solve that failed, ...).
pub type EvalError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Everything that can go wrong in this crate.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A distribution parameter outside its allowed range.
    #[error("variable `{variable}`: {field} = {value} is not allowed; {allowed}")]
    InvalidParameter {
        variable: String,
        field: &'static str,
        value: f64,
        allowed: &'static str,
    },
    /// An input-file spec with a missing, extra or conflicting field.
    #[error("uncertainty of `{variable}`: field `{field}`: {allowed}")]
    InvalidSpec {
        variable: String,
        field: &'static str,
        allowed: &'static str,
    },
    /// A quantity declared positive with a distribution that allows values ≤ 0.
    #[error(
        "variable `{variable}` is declared positive but its {distribution} distribution {reason}; \
         use a lognormal distribution (or uniform bounds > 0)"
    )]
    NotPositive {
        variable: String,
        distribution: &'static str,
        reason: String,
    },
    /// Two variables with the same name.
    #[error("variable `{variable}` is defined twice; names must be unique")]
    DuplicateVariable { variable: String },
    /// A name that is not one of the model's variables.
    #[error("unknown variable `{name}` in {context}; known variables: {known}")]
    UnknownVariable {
        name: String,
        context: &'static str,
        known: String,
    },
    /// A model without variables.
    #[error("the model has no random variables; at least one is needed")]
    NoVariables,
    /// The correlation matrix has the wrong size.
    #[error(
        "correlation matrix is {rows}×{cols}; it must be {expected}×{expected} (one row per variable)"
    )]
    CorrelationShape {
        rows: usize,
        cols: usize,
        expected: usize,
    },
    /// ρ_ij ≠ ρ_ji.
    #[error(
        "correlation between `{first}` and `{second}` is not symmetric: {upper} above the diagonal, \
         {lower} below; the matrix must be symmetric"
    )]
    CorrelationNotSymmetric {
        first: String,
        second: String,
        upper: f64,
        lower: f64,
    },
    /// A diagonal entry that is not 1.
    #[error("correlation of `{variable}` with itself is {value}; it must be 1")]
    CorrelationDiagonal { variable: String, value: f64 },
    /// |ρ_ij| > 1 (or NaN), or ±1 between two different variables.
    #[error(
        "correlation between `{first}` and `{second}` is {value}; allowed is -1 < ρ < 1 \
         (a perfect correlation means one variable, not two)"
    )]
    CorrelationOutOfRange {
        first: String,
        second: String,
        value: f64,
    },
    /// The Nataf model cannot reach this correlation for these two marginals.
    #[error(
        "correlation {value} between `{first}` and `{second}` cannot be reached with their marginal \
         distributions; allowed is {min:.6} < ρ < {max:.6}"
    )]
    CorrelationNotAttainable {
        first: String,
        second: String,
        value: f64,
        min: f64,
        max: f64,
    },
    /// The (Nataf-mapped) correlation matrix is not positive definite.
    #[error(
        "correlation matrix (in standard normal space) is not positive definite: `{variable}` is a \
         linear combination of the variables before it ({among}); reduce these correlations"
    )]
    CorrelationNotPositiveDefinite { variable: String, among: String },
    /// A vector of the wrong length.
    #[error("{what} has {got} entries; expected {expected}")]
    DimensionMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// An option outside its allowed range.
    #[error("option {field} = {value} is not allowed; {allowed}")]
    InvalidOption {
        field: &'static str,
        value: f64,
        allowed: &'static str,
    },
    /// A drift factor that makes a positive scale ≤ 0 (or not finite).
    #[error(
        "drift factor {factor} at t = {t_hours} h is not allowed; the factor must be finite and > 0 \
         (a linear drift of {percent_per_hour} %/h reaches zero at t = {zero_at_hours} h)"
    )]
    DriftFactorNotPositive {
        t_hours: f64,
        factor: f64,
        percent_per_hour: f64,
        zero_at_hours: f64,
    },
    /// The caller's limit-state function failed.
    #[error("limit-state function failed at x = {x:?}")]
    LimitState {
        x: Vec<f64>,
        #[source]
        source: EvalError,
    },
    /// The limit-state function returned NaN or ±∞ (value or gradient).
    #[error("limit-state function returned a non-finite {what} ({value}) at x = {x:?}")]
    NonFiniteLimitState {
        what: &'static str,
        value: f64,
        x: Vec<f64>,
    },
    /// ∇G = 0 in standard normal space: no search direction.
    #[error(
        "limit-state gradient is zero at x = {x:?}; FORM needs a limit state that depends on the variables there"
    )]
    ZeroGradient { x: Vec<f64> },
    /// HL-RF did not converge.
    #[error(
        "FORM did not converge in {iterations} iterations ({evaluations} limit-state evaluations): \
         last β = {beta}, |G|/|G0| = {g_residual:.3e} (tolerance {g_tolerance:.1e}), \
         ‖u − (αᵀu)α‖ = {u_residual:.3e} (tolerance {u_tolerance:.1e})"
    )]
    FormNotConverged {
        iterations: usize,
        evaluations: usize,
        beta: f64,
        g_residual: f64,
        g_tolerance: f64,
        u_residual: f64,
        u_tolerance: f64,
    },
    /// A principal curvature for which the second-order formula does not hold.
    #[error(
        "SORM: principal curvature κ{index} = {curvature} at β = {beta} gives the factor \
         1 + ψ(β)κ = {factor} ≤ 0; the formula needs κ > {bound} (the surface bends towards the \
         origin so strongly that its paraboloid encloses it); use sampling for this limit state"
    )]
    SormCurvature {
        index: usize,
        curvature: f64,
        beta: f64,
        factor: f64,
        bound: f64,
    },
    /// A series system without components.
    #[error("the series system has no components; at least one is needed")]
    NoComponents,
    /// A component whose α is not a unit vector (or has NaN).
    #[error("system component {index}: α has norm {norm}; it must be a unit vector")]
    ComponentAlpha { index: usize, norm: f64 },
    /// Sampling batches that do not belong to the same run, overlap or leave gaps.
    #[error("sampling batches cannot be merged: {reason}")]
    BatchMerge { reason: String },
}

/// This crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
