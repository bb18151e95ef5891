//! `kappe init [PATH] [--kind K]`: write a commented example file of any input format
//! (`kappe::commands::templates`; formats documented in `docs/formats/`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use crate::exit::Usage;
use crate::output::write_user_file;

#[derive(Args)]
pub struct InitArgs {
    /// Where to write the example (default: `kappe.toml`, or `<kind>.toml` for other kinds).
    pub path: Option<PathBuf>,
    /// Which example: design, study, prototypes, optimize, buildability, ceiling, moving, corrugated.
    #[arg(long, default_value = "design")]
    pub kind: String,
    /// Overwrite an existing file.
    #[arg(long)]
    pub force: bool,
}

pub fn init(args: InitArgs) -> Result<ExitCode> {
    let Some(text) = kappe::commands::templates::example(&args.kind) else {
        let kinds: Vec<&str> = kappe::commands::templates::KINDS
            .iter()
            .map(|(k, _)| *k)
            .collect();
        return Err(Usage(format!(
            "--kind {}: unknown; allowed: {}",
            args.kind,
            kinds.join(", ")
        ))
        .into());
    };
    let path = args.path.unwrap_or_else(|| match args.kind.as_str() {
        "design" => PathBuf::from("kappe.toml"),
        k => PathBuf::from(format!("{k}.toml")),
    });
    write_user_file(&path, text.as_bytes(), args.force)?;
    println!("wrote {} ({} example)", path.display(), args.kind);
    Ok(ExitCode::SUCCESS)
}
