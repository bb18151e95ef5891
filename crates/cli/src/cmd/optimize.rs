//! `kappe optimize FILE.toml`: the design loop (`kappe::commands::optimize`). FILE is either a design
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
use kappe::commands::optimize::{self, OptimizeFile};

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

pub fn run(args: OptimizeArgs) -> Result<ExitCode> {
    let path = &args.file;
    let text = crate::input::read_text(path, "optimize file")?;
    let (mut file, embedded) = OptimizeFile::from_any_toml_str(&text)
        .with_context(|| format!("invalid optimize file {}", path.display()))?;
    if let Some(n) = args.max_evaluations {
        if !(1..=10_000).contains(&n) {
            return Err(Usage(format!("--max-evaluations {n}: allowed 1 to 10000")).into());
        }
        file.max_evaluations = n;
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let start = optimize::start_design(&file, embedded, base)?;
    // Refusals and unwritable locations fail here, before the loop runs.
    let prepared = prepare_dir(&args.out, args.force, "optimize")?;
    let quiet = args.quiet;
    if !quiet {
        println!("{}", optimize::evaluation_header());
    }
    let result = optimize::optimize(&file, &start, &|e| {
        if !quiet {
            println!("{}", e.line());
        }
        std::ops::ControlFlow::Continue(())
    })
    .context("the design loop failed")?;

    let doc = optimize::document(&file, &result)?;
    let dir = prepared.path();
    std::fs::write(dir.join("design.toml"), result.design.to_toml_string()?)?;
    std::fs::write(dir.join("optimize.json"), serde_json::to_vec_pretty(&doc)?)?;
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    print!("{}", result.report());
    if result.feasible {
        println!("wrote {}", args.out.display());
        Ok(ExitCode::SUCCESS)
    } else {
        println!("wrote {} (the least-violating design)", args.out.display());
        Ok(exit::fails())
    }
}
