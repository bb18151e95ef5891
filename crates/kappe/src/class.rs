//! What kind of failure an error is, for whoever reports it (the CLI's exit status, the Python
//! package's exception): one classification of every crate's errors, on the top floor because it
//! knows them all.

use crate::input::DesignError;

/// What kind of failure an error is, for whoever reports it: the CLI's exit status (0/1/2/3 in
/// the README), the Python package's exception. One classification for every crate's errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    /// The input is wrong (bad arguments, a bad file, a refused output location): nothing ran.
    Input,
    /// The design is valid but fails (no equilibrium form, the robot cannot print it, a CEM
    /// optimization that does not converge).
    Fails,
    /// A bug or the environment (I/O, a solver breakdown): not the user's input.
    Internal,
}

/// The class of one error of Kappe's crates (or of TOML/JSON parsing, or I/O); `None` for an
/// error type Kappe does not know (its caller looks further down the error chain).
pub fn class_of(cause: &(dyn std::error::Error + 'static)) -> Option<Class> {
    use kappe_cem::CemError;
    use kappe_fe::FeError;
    use kappe_robot::RobotError;

    let cem = |e: &CemError| match e {
        CemError::NotConverged { .. } => Class::Fails,
        CemError::NumericalBreakdown { .. } => Class::Internal,
        _ => Class::Input,
    };
    if let Some(e) = cause.downcast_ref::<crate::output::OutputError>() {
        return Some(match e {
            crate::output::OutputError::Refused(_) => Class::Input,
            _ => Class::Internal,
        });
    }
    if cause.is::<std::io::Error>() {
        return Some(Class::Internal);
    }
    if cause.is::<toml::de::Error>() || cause.is::<serde_json::Error>() {
        return Some(Class::Input);
    }
    if let Some(e) = cause.downcast_ref::<DesignError>() {
        return Some(match e {
            DesignError::Parse { .. }
            | DesignError::Invalid { .. }
            | DesignError::Uncertainty { .. } => Class::Input,
            // The design as given has no equilibrium form within its bounds: it fails.
            DesignError::FormFinding(_) => Class::Fails,
            DesignError::Cem(inner) => cem(inner),
            _ => Class::Internal,
        });
    }
    if let Some(e) = cause.downcast_ref::<CemError>() {
        return Some(cem(e));
    }
    if let Some(e) = cause.downcast_ref::<FeError>() {
        return Some(match e {
            FeError::SturmMismatch { .. }
            | FeError::NoConvergence { .. }
            | FeError::Numerical { .. }
            | FeError::PatternMismatch { .. } => Class::Internal,
            _ => Class::Input,
        });
    }
    if let Some(e) = cause.downcast_ref::<RobotError>() {
        return Some(match e {
            RobotError::Invalid { .. } | RobotError::JointPositionLimit { .. } => Class::Input,
            RobotError::Io(_) => Class::Internal,
            // The robot cannot print it, or the plan fails its independent check.
            _ => Class::Fails,
        });
    }
    if cause.is::<crate::commands::study::StudyError>() {
        return Some(Class::Input);
    }
    if cause.is::<kappe_report::ReportError>() {
        return Some(Class::Internal);
    }
    None
}
