//! `kappe buildability SPEC.toml --out DIR`: print a standard test object (straight wall or
//! cylinder) layer by layer and check every layer count with the green-state time model, the
//! shell FE and the strength checks of the cap (`kappe::commands::buildability`). Writes
//! `DIR/buildability.json` (failure layer, failure mode, per layer count BLF and utilisations)
//! and `DIR/schedule.csv`. `kappe init --kind buildability` writes a commented example spec.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::output::{prepare_dir, write_file_atomic};

#[derive(Args)]
pub struct BuildabilityArgs {
    /// Buildability spec (TOML; `kappe init --kind buildability` writes an example).
    pub spec: PathBuf,
    /// Output directory for buildability.json and schedule.csv.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print buildability.json to stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// Move a non-Kappe --out directory aside instead of refusing it.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: BuildabilityArgs) -> Result<ExitCode> {
    let text = crate::input::read_text(&args.spec, "buildability spec")?;
    let resolved = kappe::commands::buildability::BuildabilitySpec::from_toml_str(&text)
        .with_context(|| format!("invalid buildability spec {}", args.spec.display()))?;
    // The output location is checked before any computing (nothing is written on bad input).
    let prepared = match &args.out {
        Some(out) => Some(prepare_dir(out, args.force, "kappe buildability")?),
        None => None,
    };
    let max = resolved.spec.object.max_layers;
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(max as u64);
        b.set_style(
            ProgressStyle::with_template(
                "{msg:>14} [{bar:40}] {pos}/{len} layer counts ({elapsed})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        b.set_message("buildability");
        b
    };
    let result = kappe::commands::buildability::run(&resolved, &|_| bar.inc(1))?;
    bar.finish_and_clear();
    let json =
        serde_json::to_string_pretty(&kappe::commands::buildability::document(&resolved, &result))?
            + "\n";
    if let Some(prepared) = prepared {
        let dir = prepared.path();
        let schedule = kappe::commands::buildability::checked_schedule(&resolved, &result);
        write_file_atomic(&dir.join("buildability.json"), json.as_bytes())?;
        write_file_atomic(&dir.join("schedule.csv"), schedule.to_csv().as_bytes())?;
        if let Some(notice) = prepared.commit()? {
            eprintln!("note: {notice}");
        }
    }
    if args.json {
        print!("{json}");
    } else {
        print!(
            "{}",
            kappe::commands::buildability::text_report(&resolved, &result, args.out.as_deref())
        );
    }
    Ok(ExitCode::SUCCESS)
}
