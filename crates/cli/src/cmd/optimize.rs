//! `kappe optimize FILE.toml`: the design loop (`kappe::design_loop`). FILE is either a design
//! file with an `[optimize]` table, or an optimize file with `design = "kappe.toml"` (or an inline
//! `[design]` table) next to `[free]`:
//!
//! ```toml
//! [cap]
//! rise = 0.2
//!
//! [optimize]
//! max_evaluations = 60
//! [optimize.free]
//! "cap.rise" = { min = 0.15, max = 0.30 }
//! "print.layer_width" = { min = 0.015, max = 0.030 }
//! [optimize.analysis]        # inside the loop (default: buckling every 25 % of progress)
//! states = "25%"
//! [optimize.verify]          # the final check (default: every state)
//! states = "all"
//! ```
//!
//! Writes `design.toml` (the result) and `optimize.json` (every evaluation, the path taken, the
//! verification) atomically into `--out`. Exit status 0 if the result satisfies every
//! constraint, 1 if no design within the bounds does (the binding constraints are named).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use kappe::calibrate::DesignSource;
use kappe::design_loop::{OptimizeFile, optimize};

use crate::exit::{self, Usage};
use crate::output::prepare_dir;

#[derive(Args)]
pub struct OptimizeArgs {
    /// Design file with an [optimize] table, or an optimize file.
    pub file: PathBuf,
    /// Output directory (created, or replaced if it is a previous Kappe output).
    #[arg(long, short, default_value = "out-optimize")]
    pub out: PathBuf,
    /// Also replace a non-empty directory that is not a Kappe output, by moving it aside.
    #[arg(long)]
    pub force: bool,
    /// Override the evaluation budget.
    #[arg(long)]
    pub max_evaluations: Option<usize>,
    /// No per-evaluation lines.
    #[arg(long, short)]
    pub quiet: bool,
}

fn start_design(
    file: &OptimizeFile,
    embedded: Option<kappe::Design>,
    base: &Path,
) -> Result<kappe::Design> {
    if let Some(d) = embedded {
        return Ok(d);
    }
    Ok(match &file.design {
        None => kappe::Design::default(),
        Some(DesignSource::Inline(d)) => {
            d.validate().context("invalid inline design")?;
            (**d).clone()
        }
        Some(DesignSource::Path(rel)) => {
            let path = base.join(rel);
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("cannot read the design file {}", path.display()))?;
            kappe::Design::from_toml_str(&text)
                .with_context(|| format!("invalid design file {}", path.display()))?
        }
    })
}

pub fn run(args: OptimizeArgs) -> Result<ExitCode> {
    let path = &args.file;
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let (mut file, embedded) = OptimizeFile::from_any_toml_str(&text)
        .with_context(|| format!("invalid optimize file {}", path.display()))?;
    if let Some(n) = args.max_evaluations {
        if !(1..=10_000).contains(&n) {
            return Err(Usage(format!("--max-evaluations {n}: allowed 1 to 10000")).into());
        }
        file.max_evaluations = n;
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let start = start_design(&file, embedded, base)?;
    // Refusals and unwritable locations fail here, before the loop runs.
    let prepared = prepare_dir(&args.out, args.force, "optimize")?;
    let quiet = args.quiet;
    if !quiet {
        println!(
            "{:>5} {:>10} {:>10}  {:<40} failing",
            "eval", "volume dm³", "violation", "parameters"
        );
    }
    let result = optimize(&file, &start, &|e| {
        if quiet {
            return;
        }
        let params: Vec<String> = e
            .parameters
            .iter()
            .map(|(k, v)| format!("{}={v:.4}", k.rsplit('.').next().unwrap_or(k)))
            .collect();
        println!(
            "{:>5} {:>10} {:>10.4}  {:<40} {}",
            e.evaluation,
            e.volume_m3
                .map_or("-".into(), |v| format!("{:.4}", v * 1e3)),
            e.violation,
            params.join(" "),
            e.failing.join(", ")
        );
    })
    .context("the design loop failed")?;

    let doc = serde_json::json!({
        "format": "kappe.optimize",
        "version": 1,
        "free": file.parameters()?,
        "result": &result,
    });
    let design_toml = result.design.to_toml_string();
    let dir = prepared.path();
    std::fs::write(dir.join("design.toml"), &design_toml)?;
    std::fs::write(dir.join("optimize.json"), serde_json::to_vec_pretty(&doc)?)?;
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }

    println!();
    println!("path taken (accepted moves):");
    for e in result.evaluations.iter().filter(|e| e.accepted) {
        let params: Vec<String> = e
            .parameters
            .iter()
            .map(|(k, v)| format!("{k} = {v:.5}"))
            .collect();
        println!(
            "  #{:<4} {}  volume {}",
            e.evaluation,
            params.join(", "),
            e.volume_m3
                .map_or("-".into(), |v| format!("{:.4} dm³", v * 1e3))
        );
    }
    println!(
        "{} evaluations; volume {} → {}",
        result.evaluations.len(),
        result
            .start_volume_m3
            .map_or("-".into(), |v| format!("{:.4} dm³", v * 1e3)),
        result
            .volume_m3
            .map_or("-".into(), |v| format!("{:.4} dm³", v * 1e3)),
    );
    if let Some(a) = &result.verification {
        print!("{}", a.report());
    }
    if !result.at_bounds.is_empty() {
        println!("at bounds: {}", result.at_bounds.join(", "));
    }
    if result.feasible {
        if !result.binding.is_empty() {
            println!(
                "binding constraints (within 5 % of their limit): {}",
                result.binding.join(", ")
            );
        }
        println!("wrote {}", args.out.display());
        Ok(ExitCode::SUCCESS)
    } else {
        println!(
            "INFEASIBLE within the bounds; binding constraints: {}",
            result.binding.join(", ")
        );
        println!("wrote {} (the least-violating design)", args.out.display());
        Ok(exit::fails())
    }
}
