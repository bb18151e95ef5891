//! `kappe cem ...`: solve a CEM topology (`kappe.cem.topology` v1 JSON).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use kappe_cem::json::{TopologyFile, equilibrium_to_json, read_topology};
use kappe_cem::{Equilibrium, SolverOptions};

use crate::output::write_file_atomic;

#[derive(Subcommand)]
pub enum CemCommand {
    /// Solve the equilibrium of a topology; writes a `kappe.cem.expected`-shaped result.
    Solve(SolveArgs),
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
    }
}

fn load(input: Option<&Path>, example: bool) -> Result<TopologyFile> {
    if example {
        return kappe_cem::example::example_arch().context("the built-in example is invalid");
    }
    let Some(path) = input else {
        bail!("give an INPUT.json or --example");
    };
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    read_topology(&text).with_context(|| format!("invalid topology in {}", path.display()))
}

fn solve(args: SolveArgs) -> Result<ExitCode> {
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
        write_file_atomic(out, text.as_bytes())?;
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
