//! `kappe fe ...` (being built).

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Subcommand;

#[derive(Subcommand)]
pub enum FeCommand {
    /// Not available yet.
    Todo,
}

pub fn run(cmd: FeCommand) -> Result<ExitCode> {
    match cmd {
        FeCommand::Todo => bail!("`kappe fe` is not available yet"),
    }
}
