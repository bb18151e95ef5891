//! Typed errors of the robot crate.

use serde::{Deserialize, Serialize};

/// Why a frame (or the step into it) could not be planned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// No IK solution: the target is out of reach (or inside the shoulder cylinder).
    Unreachable,
    /// Every IK solution is outside the joint limits.
    JointLimits,
    /// Every remaining solution is too close to a singularity.
    Singularity,
    /// Every remaining solution self-collides.
    SelfCollision,
    /// Every remaining solution is closer than the clearance margin to an object.
    Collision,
    /// Valid configurations exist, but none is compatible with the previous frame's
    /// (Σ Δq² > ε, a joint faster than allowed at the print speed, or a branch change).
    NoCompatibleNeighbour,
    /// A joint winds up beyond its range over the station.
    WindUp,
    /// The move between two layers collides.
    Transition,
    /// No base pose is usable (inside an obstacle, or nothing reachable).
    BasePlacement,
}

impl FailureKind {
    /// What failed, in the operator's words (messages never show the Rust name).
    pub fn words(&self) -> &'static str {
        match self {
            FailureKind::Unreachable => "out of reach",
            FailureKind::JointLimits => "outside the joint limits",
            FailureKind::Singularity => "too close to a singularity",
            FailureKind::SelfCollision => "the arm collides with itself",
            FailureKind::Collision => "too close to an obstacle",
            FailureKind::NoCompatibleNeighbour => "no configuration continues the previous one",
            FailureKind::WindUp => "a joint winds up beyond its range",
            FailureKind::Transition => "the move between two layers collides",
            FailureKind::BasePlacement => "no usable base pose",
        }
    }
}

/// The first failing frame of a plan and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanFailure {
    /// Station index (0-based).
    pub station: usize,
    /// Layer id (as in the path).
    pub layer: i64,
    /// Point index within the layer (as in the path).
    pub index: usize,
    pub kind: FailureKind,
    /// Human-readable detail: counts, the colliding link and object, the best Σ Δq², ….
    pub detail: String,
}

impl std::fmt::Display for PlanFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "station {}, layer {}, point {}: {}: {}",
            self.station + 1,
            self.layer,
            self.index,
            self.kind.words(),
            self.detail
        )
    }
}

/// Errors of `kappe-robot`.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// An input value is out of its allowed range.
    #[error("invalid {field}: {message}")]
    Invalid { field: String, message: String },
    /// The print cannot be planned; names the first failing frame.
    #[error("cannot plan the print: {0}")]
    Unplannable(Box<PlanFailure>),
    /// A joint position limit (`limits.position_deg`) is not a finite range inside the
    /// controller's ±360°.
    #[error(
        "invalid joint position limit of joint {joint}: [{min}, {max}]°: need finite values, min < max, both within ±360° (the UR10e controller's range)"
    )]
    JointPositionLimit { joint: usize, min: f64, max: f64 },
    /// A plan failed its independent re-check (never exported).
    #[error("plan verification failed: {}", .0.join("; "))]
    Verification(Vec<String>),
    /// Writing an export failed.
    #[error("cannot write the robot program: {0}")]
    Io(#[from] std::io::Error),
}

impl RobotError {
    /// Shorthand for [`RobotError::Invalid`].
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        RobotError::Invalid {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// A report's problem list cut to its first `keep` entries and a line counting the rest: a
/// plan that fails everywhere would otherwise print thousands of lines saying the same.
pub(crate) fn shorten(problems: &mut Vec<String>, keep: usize) {
    let n = problems.len();
    if n > keep {
        problems.truncate(keep);
        problems.push(format!("… and {} more", n - keep));
    }
}
