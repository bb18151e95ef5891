//! `kappe-robot`: UR10e kinematics, capsule collision, print-path motion planning and robot
//! programs for printing vaulted cap ceilings (paper §3.4; spec in `shared/reference/robot.md`).
//!
//! Frames follow the rerun naming `a_from_b` ([`frames`]). The base frame is the UR DH base
//! (controller Base), the flange is DH frame 6, a TCP pose is `base_from_flange · flange_from_tcp`.

// Joint loops `for j in 0..6` index several parallel arrays (q, limits, speeds); iterator
// zips would hide which joint is meant.
#![allow(clippy::needless_range_loop)]

pub mod base;
pub mod base_trajectory;
pub mod check;
pub mod collision;
pub mod conveyor;
pub mod error;
pub mod export;
pub mod files;
pub mod frames;
pub mod kinematics;
pub mod ladder;
pub mod lint;
pub mod meshes;
pub mod moving;
pub mod plan;
pub mod program;
pub mod setup;
pub mod stations;
pub mod sweep;
pub mod synthetic;
pub mod timing;
pub mod tolerance;
pub mod tracking;

pub use base_trajectory::{BaseSample, BaseSummary, BaseTrajectory};
pub use check::{CheckReport, check_plan};
pub use conveyor::{ConveyorOptions, lint_tracking, tracking_index_json, tracking_program_files};
pub use error::{FailureKind, PlanFailure, RobotError};
pub use export::{urscript_programs, write_plan_json, write_trajectory_csv, write_urscript};
pub use frames::{Iso, Mat4};
pub use kinematics::{Dh, IkSolutions, Joints, UR10E};
pub use lint::{LintReport, lint, lint_with_limits};
pub use moving::{
    BaseMode, MovingBase, MovingCheck, MovingPlan, check_moving, check_moving_tolerance,
    plan_moving, resume_moving,
};
pub use plan::{
    CertifiedClearance, LayerPlan, Plan, Station, Waypoint, plan_print, plan_print_with_waits,
};
pub use program::{ProgramFile, ProgramPart, index_json, program_files, resume_plan};
pub use setup::{
    BasePlacement, BaseSearch, PathPoint, PlanOptions, PlannerKind, PrintLayer, ProgramOptions,
    RobotSetup, Tool, ToolCapsule,
};
pub use timing::{LayerTime, LayerWait, Slowdown, apply_timing, layer_times, retime};
pub use tracking::{TrackingErrors, TrackingReport, TrackingTolerance, simulate_tracking};
