//! `kappe cem ...`: solve a CEM topology (`kappe.cem.topology` v1 JSON).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use kappe_cem::json::{TopologyFile, equilibrium_to_json, read_topology};
use kappe_cem::{Equilibrium, OptimizeResult, Problem, SolverOptions};
use serde_json::json;

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
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    read_topology(&text).with_context(|| format!("invalid topology in {}", path.display()))
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
    let doc = equilibrium_to_json(&eq, &file.solver, args.force_polygons);
    let mut text = serde_json::to_string_pretty(&doc).context("cannot serialize the result")?;
    text.push('\n');
    if let Some(out) = &args.output {
        write_user_file(out, text.as_bytes(), args.force)?;
    }
    if args.summary {
        print!("{}", summary(&eq, &file.solver, &source));
    } else if args.output.is_none() {
        print!("{text}");
    }
    Ok(ExitCode::SUCCESS)
}

fn summary(eq: &Equilibrium, solver: &SolverOptions, source: &str) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let indirect = eq.deviation_edges.iter().filter(|e| !e.direct).count();
    let _ = writeln!(s, "CEM equilibrium of {source} ({})", eq.name);
    let _ = writeln!(
        s,
        "  nodes {}  trails {}  trail edges {}  deviation edges {} ({indirect} indirect)  auxiliary trails {}",
        eq.nodes.len(),
        eq.trails.len(),
        eq.trail_edges.len(),
        eq.deviation_edges.len(),
        eq.auxiliary_trails.len()
    );
    let _ = writeln!(
        s,
        "  sweeps {} (tmax {}, eta {:e}, residual distance {:.3e})",
        eq.iterations.sweeps, solver.tmax, solver.eta, eq.iterations.residual_distance
    );
    let (fmin, fmax) = eq
        .trail_edges
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), e| {
            (a.min(e.force), b.max(e.force))
        });
    if fmin.is_finite() {
        let _ = writeln!(s, "  trail forces  min {fmin:.6}  max {fmax:.6}");
    }
    let _ = writeln!(
        s,
        "  max node residual {:.3e}  |Σq + ΣR| {:.3e}",
        eq.checks.max_node_residual,
        (eq.checks.sum_loads + eq.checks.sum_reactions).norm()
    );
    let _ = writeln!(
        s,
        "  {:>8}  {:>14} {:>14} {:>14}",
        "support", "Rx", "Ry", "Rz"
    );
    for n in eq.nodes.iter().filter(|n| n.support) {
        let r = n.reaction;
        let _ = writeln!(
            s,
            "  {:>8}  {:>14.6} {:>14.6} {:>14.6}",
            n.id, r.x, r.y, r.z
        );
    }
    s
}

fn optimize(args: OptimizeArgs) -> Result<ExitCode> {
    if let Some(out) = &args.output {
        check_user_file(out, args.force)?;
    }
    let file = load(Some(&args.input), false)?;
    let source = args.input.display().to_string();
    let Some(block) = &file.optimization else {
        return Err(Usage(format!(
            "{source} has no `optimization` block; nothing to optimize (use `kappe cem solve`)"
        ))
        .into());
    };
    let (problem, options) = Problem::from_json(block)
        .with_context(|| format!("invalid optimization block in {source}"))?;
    let r = kappe_cem::optimize(&file.topology, &problem, &options)
        .with_context(|| format!("cannot optimize {source}"))?;
    let report = optimization_report(&r);
    eprint!("{report}");
    if !r.converged && !args.allow_partial {
        eprintln!(
            "error: the optimizer stopped short ({}, objective {:.3e}); no output written (use --allow-partial to keep it)",
            r.status.name(),
            r.objective_at_x_opt
        );
        return Ok(exit::fails());
    }
    let mut doc = equilibrium_to_json(&r.equilibrium, &options.solver, false);
    if let serde_json::Value::Object(m) = &mut doc {
        m.insert(
            "optimization".into(),
            json!({
                "x0": r.x0,
                "bounds_low": r.bounds_low,
                "bounds_up": r.bounds_up,
                "objective_at_x0": r.objective_at_x0,
                "gradient_at_x0": r.gradient_at_x0,
                "x_opt": r.x_opt,
                "objective_at_x_opt": r.objective_at_x_opt,
                "gradient_at_x_opt": r.gradient_at_x_opt,
                "status": r.status.name(),
                "converged": r.converged,
                "iterations": r.iterations,
                "evaluations": r.evaluations,
                "goals": r.goals.iter().map(|g| json!({
                    "goal": g.goal,
                    "weight": g.weight,
                    "error": g.error,
                    "weighted_squared_error": g.weighted_squared_error,
                })).collect::<Vec<_>>(),
            }),
        );
    }
    let mut text = serde_json::to_string_pretty(&doc).context("cannot serialize the result")?;
    text.push('\n');
    match &args.output {
        Some(out) => write_user_file(out, text.as_bytes(), args.force)?,
        None => print!("{text}"),
    }
    // Not converged here means --allow-partial was given: the user asked for status 0.
    Ok(ExitCode::SUCCESS)
}

fn optimization_report(r: &OptimizeResult) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "status {} ({}), {} iterations, {} evaluations, objective {:.3e} -> {:.3e}",
        r.status.name(),
        if r.converged {
            "converged"
        } else {
            "NOT converged"
        },
        r.iterations,
        r.evaluations,
        r.objective_at_x0,
        r.objective_at_x_opt
    );
    let _ = writeln!(s, "  x0    {:?}", r.x0);
    let _ = writeln!(s, "  x_opt {:?}", r.x_opt);
    let _ = writeln!(
        s,
        "  {:<32} {:>8} {:>14} {:>14}",
        "goal", "weight", "error", "w*e^2"
    );
    for g in &r.goals {
        let _ = writeln!(
            s,
            "  {:<32} {:>8.3} {:>14.3e} {:>14.3e}",
            g.goal, g.weight, g.error, g.weighted_squared_error
        );
    }
    s
}
