//! `kappe robot ...` (being built).

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Subcommand;

#[derive(Subcommand)]
pub enum RobotCommand {
    /// Not available yet.
    Todo,
}

pub fn run(cmd: RobotCommand) -> Result<ExitCode> {
    match cmd {
        RobotCommand::Todo => bail!("`kappe robot` is not available yet"),
    }
}
