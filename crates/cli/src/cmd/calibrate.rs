//! `kappe calibrate PROTOTYPES.toml`: derive BLF_min (and the equivalent effective E) from
//! printed prototypes that stood or failed (paper §3.3, `kappe::calibrate`).
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

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use kappe::calibrate::{DesignSource, Outcome, PrototypeFile, Resolved, calibrate};

use crate::output::write_file_atomic;

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
}

fn resolve(file: &PrototypeFile, base: &Path) -> Result<Vec<Resolved>> {
    file.prototypes
        .iter()
        .map(|p| {
            let design = match &p.design {
                DesignSource::Inline(d) => {
                    d.validate()
                        .with_context(|| format!("prototype {:?}: invalid design", p.name))?;
                    (**d).clone()
                }
                DesignSource::Path(rel) => {
                    let path = base.join(rel);
                    let text = std::fs::read_to_string(&path).with_context(|| {
                        format!("prototype {:?}: cannot read {}", p.name, path.display())
                    })?;
                    kappe::Design::from_toml_str(&text).with_context(|| {
                        format!(
                            "prototype {:?}: invalid design file {}",
                            p.name,
                            path.display()
                        )
                    })?
                }
            };
            Ok(Resolved {
                prototype: p.clone(),
                design,
            })
        })
        .collect()
}

pub fn run(args: CalibrateArgs) -> Result<ExitCode> {
    let path = &args.prototypes;
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the prototype file {}", path.display()))?;
    let file = PrototypeFile::from_toml_str(&text)
        .with_context(|| format!("invalid prototype file {}", path.display()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let resolved = resolve(&file, base)?;
    let cal = calibrate(&resolved, &file.analysis).context("calibration failed")?;
    let doc = serde_json::json!({
        "format": "kappe.calibration",
        "version": 1,
        "analysis": file.analysis,
        "calibration": cal,
    });
    if let Some(out) = &args.out {
        write_file_atomic(out, &serde_json::to_vec_pretty(&doc)?)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!("Calibration from {} prototypes", cal.evidence.len());
    println!(
        "  {:<16} {:>7} {:>8} {:>14} {:>14}",
        "prototype", "outcome", "E [MPa]", "min BLF stood", "BLF at failure"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
    for e in &cal.evidence {
        println!(
            "  {:<16} {:>7} {:>8.3} {:>14} {:>14}",
            e.name,
            match e.outcome {
                Outcome::Stood => "stood",
                Outcome::Failed => "failed",
            },
            e.youngs_modulus / 1e6,
            f(e.min_blf_survived),
            f(e.blf_at_failure)
        );
    }
    println!("  BLF_min = {:.4}", cal.blf_min);
    if let Some(ee) = cal.effective_modulus {
        println!(
            "  (equivalently E_eff = {:.3} MPa with BLF_min = 1)",
            ee / 1e6
        );
    }
    println!();
    println!("{}", cal.explanation);
    Ok(if cal.separable {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}
