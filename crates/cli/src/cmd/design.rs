//! `kappe design` and `kappe init` (being built).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

#[derive(Args)]
pub struct DesignArgs {
    /// Design file (TOML); the embedded default design when omitted.
    pub design: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct InitArgs {
    /// Where to write the example design.
    #[arg(default_value = "kappe.toml")]
    pub path: PathBuf,
}

pub fn run(_args: DesignArgs) -> Result<ExitCode> {
    bail!("`kappe design` is not available yet")
}

pub fn init(_args: InitArgs) -> Result<ExitCode> {
    bail!("`kappe init` is not available yet")
}
