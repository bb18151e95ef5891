//! `kappe cem ...`: solve a CEM topology (`kappe.cem.topology` v1 JSON).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use kappe_cem::json::TopologyFile;
use kappe_cem::report;

use crate::exit::{self, Usage};
use crate::output::{check_user_file, write_user_file};

#[derive(Subcommand)]
pub enum CemCommand {
    /// Solve the equilibrium of a topology; writes a `kappe.cem.expected`-shaped result.
    Solve(SolveArgs),
    /// Constrained form-finding: optimize the parameters of the `optimization` block so the
    /// goals are met; writes the final equilibrium plus an `optimization` report.
    Optimize(OptimizeArgs),
}

#[derive(Args)]
pub struct OptimizeArgs {
    /// Input topology with an `optimization` block (`kappe.cem.topology` v1 JSON).
    input: PathBuf,
    /// Output file (written atomically); stdout when absent.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    /// Write the result and exit 0 even if the optimizer stopped short of convergence.
    #[arg(long)]
    allow_partial: bool,
}

#[derive(Args)]
pub struct SolveArgs {
    /// Input topology (`kappe.cem.topology` v1 JSON).
    #[arg(required_unless_present = "example")]
    input: Option<PathBuf>,
    /// Solve the built-in example arch instead of a file.
    #[arg(long, conflicts_with = "input")]
    example: bool,
    /// Output file (written atomically); stdout when absent.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    /// Print a short human-readable summary instead of the JSON on stdout.
    #[arg(long)]
    summary: bool,
    /// Add the per-node force polygons to the JSON result.
    #[arg(long)]
    force_polygons: bool,
}

pub fn run(cmd: CemCommand) -> Result<ExitCode> {
    match cmd {
        CemCommand::Solve(args) => solve(args),
        CemCommand::Optimize(args) => optimize(args),
    }
}

fn load(input: Option<&Path>, example: bool) -> Result<TopologyFile> {
    if example {
        return kappe_cem::example::example_arch().context("the built-in example is invalid");
    }
    let Some(path) = input else {
        return Err(Usage("give an INPUT.json or --example".into()).into());
    };
    // An unreadable or non-UTF-8 file is a bad input (exit 2), not an I/O failure of Kappe's.
    crate::input::read_text(path, "topology file")?;
    Ok(report::read_topology_file(path)?)
}

fn solve(args: SolveArgs) -> Result<ExitCode> {
    if let Some(out) = &args.output {
        check_user_file(out, args.force)?;
    }
    let file = load(args.input.as_deref(), args.example)?;
    let source = args.input.as_ref().map_or_else(
        || "built-in example".to_string(),
        |p| p.display().to_string(),
    );
    let eq = kappe_cem::solve(&file.topology, &file.solver)
        .with_context(|| format!("cannot solve {source}"))?;
    let text = report::solve_document(&eq, &file.solver, args.force_polygons)
        .context("cannot serialize the result")?;
    if let Some(out) = &args.output {
        write_user_file(out, text.as_bytes(), args.force)?;
    }
    if args.summary {
        print!("{}", report::summary(&eq, &file.solver, &source));
    } else if args.output.is_none() {
        print!("{text}");
    }
    Ok(ExitCode::SUCCESS)
}

fn optimize(args: OptimizeArgs) -> Result<ExitCode> {
    if let Some(out) = &args.output {
        check_user_file(out, args.force)?;
    }
    let file = load(Some(&args.input), false)?;
    let source = args.input.display().to_string();
    let Some((problem, options)) = report::optimization_problem(&file)
        .with_context(|| format!("invalid optimization block in {source}"))?
    else {
        return Err(Usage(format!(
            "{source} has no `optimization` block; nothing to optimize (use `kappe cem solve`)"
        ))
        .into());
    };
    let r = kappe_cem::optimize(&file.topology, &problem, &options)
        .with_context(|| format!("cannot optimize {source}"))?;
    eprint!("{}", report::optimization_report(&r));
    if !r.converged && !args.allow_partial {
        eprintln!(
            "error: the optimizer stopped short ({}, objective {:.3e}); no output written (use --allow-partial to keep it)",
            r.status.name(),
            r.objective_at_x_opt
        );
        return Ok(exit::fails());
    }
    let text =
        report::optimize_document(&r, &options.solver).context("cannot serialize the result")?;
    match &args.output {
        Some(out) => write_user_file(out, text.as_bytes(), args.force)?,
        None => print!("{text}"),
    }
    // Not converged here means --allow-partial was given: the user asked for status 0.
    Ok(ExitCode::SUCCESS)
}
