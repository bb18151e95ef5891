//! Integration tests of `kappe-robot` against the fixtures in `shared/fixtures/robot/`
//! (robot.md §7 acceptance checks).

mod collision;
mod common;
mod kinematics;
mod ladder;
mod moving;
mod plan;
mod program;
mod stations;
mod sweep;
