//! Errors of the report crate.

/// What went wrong while checking the input or rendering the report.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A list the report needs is empty.
    #[error("{field} is empty; the report needs at least one entry")]
    Empty {
        /// Path of the field, e.g. `layers`.
        field: String,
    },
    /// A number is NaN or infinite (JSON cannot carry it and the viewer cannot draw it).
    #[error("{field} = {value} is not finite; only finite numbers are allowed")]
    NotFinite {
        /// Path of the field, e.g. `layers[3].nodes[7][2]`.
        field: String,
        /// The offending value.
        value: f64,
    },
    /// Two arrays that must correspond have different lengths.
    #[error("{field} has {len} entries, expected {expected}")]
    LengthMismatch {
        /// Path of the field.
        field: String,
        /// Its length.
        len: usize,
        /// The length it must have.
        expected: usize,
    },
    /// A layer polyline has fewer than two nodes.
    #[error("layer {layer} has {len} nodes; a layer needs at least 2")]
    TooFewNodes {
        /// Layer id.
        layer: i32,
        /// Its node count.
        len: usize,
    },
    /// A reference to a layer id that is not in `layers`.
    #[error("{field} = {id} refers to no layer in `layers`")]
    UnknownLayer {
        /// Path of the field.
        field: String,
        /// The unknown id.
        id: i32,
    },
    /// A value outside its allowed range.
    #[error("{field} = {value} is out of range; allowed: {allowed}")]
    OutOfRange {
        /// Path of the field.
        field: String,
        /// The offending value.
        value: f64,
        /// What is allowed.
        allowed: &'static str,
    },
    /// A link that would leave the study directory or needs the network.
    #[error(
        "{field} = {href:?} is not allowed; use a relative path inside the study directory (no scheme, no leading /, no ..)"
    )]
    BadLink {
        /// Path of the field.
        field: String,
        /// The link.
        href: String,
    },
    /// plotters failed to draw a plot.
    #[error("plot {plot:?} could not be drawn: {message}")]
    Plot {
        /// Plot title.
        plot: String,
        /// The backend's message.
        message: String,
    },
    /// A page's scene island lacks a field or holds a malformed one.
    #[error("the report's scene island has no valid {field}")]
    Island {
        /// Path of the field.
        field: String,
    },
    /// The scene data could not be serialised.
    #[error("scene data could not be serialised to JSON: {0}")]
    Json(#[from] serde_json::Error),
}
