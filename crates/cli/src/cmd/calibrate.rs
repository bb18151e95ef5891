//! `kappe calibrate PROTOTYPES.toml`: derive BLF_min (and the equivalent effective E) from
//! printed prototypes that stood or failed (paper §3.3, `kappe::commands::calibrate_blf`).
//!
//! File format:
//! ```toml
//! [analysis]                 # optional, as for `kappe design` (states, row_stride, ageing, …)
//! states = "all"
//!
//! [[prototype]]
//! name = "P1"
//! design = "p1.toml"         # path relative to this file, or an inline [prototype.design] table
//! outcome = "stood"          # or "failed"
//!
//! [[prototype]]
//! name = "P2"
//! design = "p2.toml"
//! outcome = "failed"
//! failed_at_layer = 57       # layers printed when it collapsed, from 1 in print order
//! ```
//!
//! A file with a `[buildability]` table calibrates the green-state time model from buildability
//! prints instead (`kappe::commands::calibrate_print`):
//! ```toml
//! buildability = "cylinder.toml"   # a buildability spec (path relative to this file, or inline)
//! [fit]
//! parameter = "compressive_strength_rate"   # the one [material.time] field to fit
//! min = 0.0
//! max = 20.0
//! [[print]]
//! name = "C1"
//! failed_at_layer = 30             # or stood_to = n
//! # layer_time = 18.85             # s, if it differs from the spec's
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use kappe::commands::calibrate_blf::{PrototypeFile, calibrate};

use crate::output::{check_user_file, write_user_file};

#[derive(Args)]
pub struct CalibrateArgs {
    /// Prototype file (TOML).
    pub prototypes: PathBuf,
    /// Write the calibration as JSON to this file (atomically).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Print the calibration as JSON to stdout instead of the text report.
    #[arg(long)]
    pub json: bool,
    /// Replace an existing output file.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: CalibrateArgs) -> Result<ExitCode> {
    let path = &args.prototypes;
    // Refusals and unwritable locations fail before any analysis.
    if let Some(out) = &args.out {
        check_user_file(out, args.force)?;
    }
    let text = crate::input::read_text(path, "prototype file")?;
    if kappe::commands::calibrate_blf::is_prints_file(&text) {
        return run_prints(&args, &text);
    }
    let file = PrototypeFile::from_toml_str(&text)
        .with_context(|| format!("invalid prototype file {}", path.display()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let resolved = kappe::commands::calibrate_blf::resolve_prototypes(&file, base)?;
    let cal = calibrate(&resolved, &file.analysis).context("calibration failed")?;
    let doc = kappe::commands::calibrate_blf::document(&file, &cal);
    if let Some(out) = &args.out {
        write_user_file(out, &serde_json::to_vec_pretty(&doc)?, args.force)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(ExitCode::SUCCESS);
    }
    print!("{}", kappe::commands::calibrate_blf::text_report(&cal));
    Ok(if cal.separable {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}

/// `kappe calibrate` of a file with `[buildability]`: fit the time model to buildability prints.
fn run_prints(args: &CalibrateArgs, text: &str) -> Result<ExitCode> {
    use kappe::commands::calibrate_print::{PrintCalibrationFile, calibrate_prints};
    let path = &args.prototypes;
    let file = PrintCalibrationFile::from_toml_str(text)
        .with_context(|| format!("invalid calibration file {}", path.display()))?;
    let spec = kappe::commands::calibrate_print::resolve_spec(
        &file,
        path.parent().unwrap_or(Path::new(".")),
    )?;
    let cal = calibrate_prints(&spec, &file.fit, &file.prints).context("calibration failed")?;
    let doc = kappe::commands::calibrate_print::document(&file, &cal);
    if let Some(out) = &args.out {
        write_user_file(out, &serde_json::to_vec_pretty(&doc)?, args.force)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(ExitCode::SUCCESS);
    }
    print!("{}", kappe::commands::calibrate_print::text_report(&cal));
    Ok(ExitCode::SUCCESS)
}
