//! `kappe buildability SPEC.toml --out DIR`: print a standard test object (straight wall or
//! cylinder) layer by layer and check every layer count with the green-state time model, the
//! shell FE and the strength checks of the cap (`kappe::buildability`). Writes
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
    let text = std::fs::read_to_string(&args.spec)
        .with_context(|| format!("cannot read the buildability spec {}", args.spec.display()))?;
    let resolved = kappe::buildability::BuildabilitySpec::from_toml_str(&text)
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
    let result = kappe::buildability::run(&resolved, &|_| bar.inc(1))?;
    bar.finish_and_clear();
    let doc = serde_json::json!({
        "format": "kappe.buildability",
        "version": 1,
        "spec": resolved.spec,
        "failure_layer": result.failure_layer,
        "failure_mode": result.failure_mode,
        "result": result,
    });
    let json = serde_json::to_string_pretty(&doc)? + "\n";
    if let Some(prepared) = prepared {
        let dir = prepared.path();
        let mut schedule = resolved.schedule.clone();
        schedule.layers.truncate(result.states.len());
        write_file_atomic(&dir.join("buildability.json"), json.as_bytes())?;
        write_file_atomic(&dir.join("schedule.csv"), schedule.to_csv().as_bytes())?;
        if let Some(notice) = prepared.commit()? {
            eprintln!("note: {notice}");
        }
    }
    if args.json {
        print!("{json}");
        return Ok(ExitCode::SUCCESS);
    }
    let o = &resolved.spec.object;
    println!(
        "{} {:?}: {} layers of {:.1} mm, {:.2} s per layer, {} elements along the centre line",
        if resolved.spec.name.is_empty() {
            "buildability"
        } else {
            &resolved.spec.name
        },
        o.kind,
        result.states.len(),
        o.layer_height * 1e3,
        result.layer_time_s,
        result.segments
    );
    println!(
        "  {:>5} {:>8} {:>9} {:>10} {:>9} {:>9}  governs",
        "n", "H [m]", "age0 [s]", "BLF", "strength", "sliding"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
    let step = (result.states.len() / 20).max(1);
    for s in &result.states {
        if s.layers % step == 0 || s.failure.is_some() || s.layers == 1 {
            println!(
                "  {:>5} {:>8.3} {:>9.1} {:>10} {:>9} {:>9}  {}",
                s.layers,
                s.height_m,
                s.bottom_age_s,
                f(s.blf),
                f(s.strength_utilisation),
                f(s.sliding_utilisation),
                s.governing.map_or("-", |m| m.name())
            );
        }
    }
    match (result.failure_layer, result.failure_mode) {
        (Some(n), Some(m)) => println!("fails at layer {n} by {}", m.name()),
        _ => println!("stands to {max} layers"),
    }
    if let Some(n) = result.plastic_collapse_estimate {
        println!("  (closed-form uniaxial plastic collapse at the base: layer {n})");
    }
    if let Some(out) = &args.out {
        println!("wrote {}", out.display());
    }
    Ok(ExitCode::SUCCESS)
}
