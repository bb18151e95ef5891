//! Typed errors of the cap pipeline.

use thiserror::Error;

/// The text of [`DesignError::Parse`]: the entry when there is one. Every TOML file Kappe
/// reads goes through the same parser, so the message does not claim it is a design file (the
/// command names the file).
fn parse_message(path: &str, message: &str) -> String {
    if path.is_empty() {
        message.to_string()
    } else {
        format!("`{path}`: {message}")
    }
}

/// Everything that can go wrong between a design file and a finished cap.
#[derive(Debug, Error)]
pub enum DesignError {
    /// The design file is not valid TOML or does not match the schema (unknown field, wrong type).
    #[error("{}", parse_message(.path, .message))]
    Parse {
        /// Dotted path of the offending entry (empty for a syntax error).
        path: String,
        /// What the parser said.
        message: String,
    },
    /// A parameter or constraint is outside its allowed range.
    #[error("design field `{field}` = {value}: {allowed}")]
    Invalid {
        /// Dotted field name, e.g. `cap.tilt_deg`.
        field: &'static str,
        /// The value given.
        value: String,
        /// What is allowed, in words.
        allowed: String,
    },
    /// The layer arch could not be form-found for these parameters.
    #[error("layer form-finding failed: {0}")]
    FormFinding(String),
    /// A print state violates an equilibrium invariant of the method (method.md §9).
    #[error("print state {state}: {message}")]
    State {
        /// State index (0 = first layer printed).
        state: usize,
        /// What is wrong.
        message: String,
    },
    /// The design cannot be written back as TOML (a value TOML cannot hold, e.g. a NaN set
    /// from code).
    #[error("cannot write the design as TOML: {0}")]
    ToToml(String),
    /// An `[uncertainty]` entry that is not allowed (issue 24): unknown name, bad distribution,
    /// correlation or drift.
    #[error("design field `{field}`: {message}")]
    Uncertainty {
        /// Dotted field, e.g. `uncertainty."material.youngs_modulus".std`.
        field: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// The caller's progress callback asked the run to stop (e.g. Ctrl-C in Python).
    #[error("cancelled")]
    Cancelled,
    /// The CEM engine rejected a network we built (a bug in Kappe if it happens).
    #[error("CEM: {0}")]
    Cem(#[from] kappe_cem::CemError),
}
