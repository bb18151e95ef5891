//! `kappe cem ...` (being built).

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Subcommand;

#[derive(Subcommand)]
pub enum CemCommand {
    /// Not available yet.
    Todo,
}

pub fn run(cmd: CemCommand) -> Result<ExitCode> {
    match cmd {
        CemCommand::Todo => bail!("`kappe cem` is not available yet"),
    }
}
