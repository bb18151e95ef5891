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
//!
//! A file with a `[buildability]` table calibrates the green-state time model from buildability
//! prints instead (`kappe::print_calibration`):
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
use kappe::calibrate::{DesignSource, Outcome, PrototypeFile, Resolved, calibrate};

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
    // Refusals and unwritable locations fail before any analysis.
    if let Some(out) = &args.out {
        check_user_file(out, args.force)?;
    }
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the prototype file {}", path.display()))?;
    if text
        .parse::<toml::Table>()
        .is_ok_and(|t| t.contains_key("buildability"))
    {
        return run_prints(&args, &text);
    }
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
        write_user_file(out, &serde_json::to_vec_pretty(&doc)?, args.force)?;
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

/// `kappe calibrate` of a file with `[buildability]`: fit the time model to buildability prints.
fn run_prints(args: &CalibrateArgs, text: &str) -> Result<ExitCode> {
    use kappe::print_calibration::{PrintCalibrationFile, SpecSource, calibrate_prints};
    let path = &args.prototypes;
    let file = PrintCalibrationFile::from_toml_str(text)
        .with_context(|| format!("invalid calibration file {}", path.display()))?;
    let spec = match &file.buildability {
        SpecSource::Inline(s) => (**s).clone(),
        SpecSource::Path(rel) => {
            let p = path.parent().unwrap_or(Path::new(".")).join(rel);
            let t = std::fs::read_to_string(&p)
                .with_context(|| format!("cannot read the buildability spec {}", p.display()))?;
            kappe::buildability::BuildabilitySpec::parse(&t)
                .with_context(|| format!("invalid buildability spec {}", p.display()))?
        }
    };
    let cal = calibrate_prints(&spec, &file.fit, &file.prints).context("calibration failed")?;
    let doc = serde_json::json!({
        "format": "kappe.calibration.prints",
        "version": 1,
        "fit": file.fit,
        "calibration": cal,
    });
    if let Some(out) = &args.out {
        write_user_file(out, &serde_json::to_vec_pretty(&doc)?, args.force)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(ExitCode::SUCCESS);
    }
    let name = cal.parameter.name();
    println!("Calibration of {name} from {} prints", cal.prints.len());
    println!(
        "  {:<12} {:>9} {:>14} {:>14} {:>10} {:>9}",
        "print", "observed", "lower", "upper", "predicted", "mode"
    );
    let f = |v: Option<usize>| v.map_or("stood".to_string(), |x| x.to_string());
    for e in &cal.prints {
        println!(
            "  {:<12} {:>9} {:>14.6e} {:>14.6e} {:>10} {:>9}",
            e.name,
            f(e.observed_failure_layer),
            e.lower,
            e.upper,
            f(e.predicted_failure_layer),
            e.predicted_mode.map_or("-", |m| m.name())
        );
    }
    println!(
        "  {name} = {:.6e} ± {:.3e}  (allowed by the data: [{:.6e}, {:.6e}])",
        cal.value, cal.uncertainty, cal.interval[0], cal.interval[1]
    );
    println!();
    println!("{}", cal.explanation);
    Ok(ExitCode::SUCCESS)
}
