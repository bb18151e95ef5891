//! `kappe-robot`: UR10e kinematics, capsule collision, print-path motion planning and robot
//! programs for printing vaulted cap ceilings (paper §3.4; spec in `shared/reference/robot.md`).
//!
//! Frames follow the rerun naming `a_from_b` ([`frames`]). The base frame is the UR DH base
//! (controller Base), the flange is DH frame 6, a TCP pose is `base_from_flange · flange_from_tcp`.
//!
//! # Module map
//!
//! The modules stand in the order data moves, and each imports only modules on the rows above
//! it (no import cycle; `crates/kappe/tests/it/floors.rs` checks every crate of the workspace):
//!
//! | floor | modules | what they hold |
//! |---|---|---|
//! | ground | [`error`], [`frames`], [`ladder`] | typed errors, rigid transforms, the ladder-graph search |
//! | arm | [`kinematics`], [`collision`], [`sweep`], [`base_trajectory`] | UR10e FK/IK, limits and the approach pose; the capsule model and scenes; certified clearance along a motion; the moving base's time-stamped path |
//! | input | [`setup`], [`synthetic`] | the robot setup, plan and program options, the base tolerance; a synthetic test path |
//! | data | [`plan`] | the plan: stations, layers, waypoints and what it carries (program parts, slowdowns, mesh report, certified clearance) |
//! | planning | [`planner`], [`base`] | IK vertices and the ladder search of one station; the base-pose search |
//! | checks | [`tolerance`], [`check`] | the plan under base-pose errors; the independent re-verification |
//! | clock, programs | [`timing`], [`program`] | the one clock; program parts and URScript files |
//! | entries | [`stationary`], [`meshes`], [`lint`](mod@lint) | [`plan_print`]; UR's collision meshes against a plan; the independent URScript checker |
//! | moving base | [`moving`], [`tracking`], [`conveyor`] | planning and checking with a moving base; its tracking simulation; its conveyor-tracking programs |
//! | outputs | [`export`], [`stations`], [`files`] | `plan.json`, `trajectory.csv`, URScript; the station sheet; a plan's output files |
//!
//! What users call is re-exported here (`kappe_robot::Plan`, [`plan_print`], …). A type that
//! moved down to a lower floor is re-exported from the module that held it before
//! (`meshes::MeshReport`, `program::ProgramPart`, `timing::Slowdown`, `tolerance::BaseTolerance`,
//! `conveyor::lint_tracking`).

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
pub mod planner;
pub mod program;
pub mod setup;
pub mod stationary;
pub mod stations;
pub mod sweep;
pub mod synthetic;
pub mod timing;
pub mod tolerance;
pub mod tracking;

pub use base_trajectory::{BaseSample, BaseSummary, BaseTrajectory};
pub use check::{CheckReport, check_plan};
pub use conveyor::{ConveyorOptions, tracking_index_json, tracking_program_files};
pub use error::{FailureKind, PlanFailure, RobotError};
pub use export::{urscript_programs, write_plan_json, write_trajectory_csv, write_urscript};
pub use frames::{Iso, Mat4};
pub use kinematics::{Dh, IkSolutions, Joints, UR10E};
pub use lint::{LintReport, lint, lint_tracking, lint_with_limits};
pub use moving::{
    BaseMode, MovingBase, MovingCheck, MovingPlan, check_moving, check_moving_tolerance,
    plan_moving, resume_moving,
};
pub use plan::{CertifiedClearance, LayerPlan, Plan, Station, Waypoint};
pub use program::{ProgramFile, ProgramPart, index_json, program_files, resume_plan};
pub use setup::{
    BasePlacement, BaseSearch, PathPoint, PlanOptions, PlannerKind, PrintLayer, ProgramOptions,
    RobotSetup, Tool, ToolCapsule,
};
pub use stationary::{plan_print, plan_print_with_waits};
pub use timing::{LayerTime, LayerWait, Slowdown, apply_timing, layer_times, retime};
pub use tracking::{TrackingErrors, TrackingReport, TrackingTolerance, simulate_tracking};
