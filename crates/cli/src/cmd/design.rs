//! `kappe design`: parse, call `kappe::run`, show progress, write the output directory.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::exit::Usage;
use crate::output::prepare_dir;

#[derive(Args)]
pub struct DesignArgs {
    /// Design file (TOML); the embedded default design when omitted (`kappe init` writes it).
    pub design: Option<PathBuf>,
    /// Output directory: created, or replaced if it is a previous Kappe output (swapped in
    /// atomically when complete; nothing is written on error). Never the working directory.
    #[arg(long, short, default_value = "out")]
    pub out: PathBuf,
    /// Also replace a non-empty directory that is not a Kappe output, by moving it aside to
    /// `DIR.old-N` (nothing is deleted).
    #[arg(long)]
    pub force: bool,
    /// No progress bar and no table.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON to stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Skip robot motion planning (no trajectory.csv, plan.json or programs).
    #[arg(long)]
    pub no_robot: bool,
    /// Print states that get a shell buckling analysis: "all", "every:N" or "P%" (stresses and
    /// overhang are always checked in every state); overrides `[analysis] states`.
    #[arg(long)]
    pub states: Option<String>,
    /// Skip the finite-element buckling analysis (stresses and overhang only).
    #[arg(long)]
    pub no_buckling: bool,
    /// Exit with status 0 even when the design fails a constraint or cannot be planned.
    #[arg(long)]
    pub allow_fail: bool,
}

pub fn run(args: DesignArgs) -> Result<ExitCode> {
    let design = match &args.design {
        None => kappe::Design::default(),
        Some(path) => {
            let text = crate::input::read_text(path, "design file")?;
            if kappe::commands::ceiling::is_ceiling_toml(&text) {
                return run_ceiling(&args, &text, path);
            }
            kappe::Design::from_toml_str(&text)
                .with_context(|| format!("invalid design file {}", path.display()))?
        }
    };
    let options = run_options(&args, &design)?;
    // Refusals and unwritable locations fail here, before any computing.
    let prepared = prepare_dir(&args.out, args.force, "design")?;
    let silent = args.quiet || args.json;
    let bar = state_bar("print states", silent);
    let fe_bar = state_bar("analysis", silent);
    let spinner = if silent {
        ProgressBar::hidden()
    } else {
        ProgressBar::new_spinner()
    };
    let on_progress = |p: kappe::Progress| {
        match p.stage {
            kappe::Stage::States => tick(&bar, p),
            // The robot is planned before the analysis (its clock gives the layers' ages).
            kappe::Stage::Analysis => {
                bar.finish_and_clear();
                spinner.finish_and_clear();
                tick(&fe_bar, p);
            }
            kappe::Stage::Robot if p.done == 0 => {
                bar.finish_and_clear();
                spinner.set_message("planning the UR10e trajectory");
                spinner.enable_steady_tick(std::time::Duration::from_millis(120));
            }
            kappe::Stage::Robot => {}
        }
        std::ops::ControlFlow::Continue(())
    };
    let eval = kappe::run(&design, &options, &on_progress)?;
    bar.finish_and_clear();
    fe_bar.finish_and_clear();
    spinner.finish_and_clear();
    let files = eval.files()?;
    let programs = files
        .iter()
        .filter(|f| f.name.starts_with("program_part"))
        .count();
    let summary = eval.summary();
    let table = || eval.table(&args.out, programs);
    let failures = |level: &str| eval.failure_lines(level);
    finish(
        &args,
        prepared,
        &files,
        &summary,
        table,
        failures,
        eval.verdict.ok,
    )
}

/// The end of every design run: write the output, print the summary (JSON or the table), the
/// reasons it fails (warnings with `--allow-fail`), and the exit status.
fn finish(
    args: &DesignArgs,
    prepared: crate::output::PreparedDir,
    files: &[kappe::output::OutputFile],
    summary: &impl serde::Serialize,
    table: impl FnOnce() -> String,
    failure_lines: impl FnOnce(&str) -> Vec<String>,
    ok: bool,
) -> Result<ExitCode> {
    prepared.write(files)?;
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(summary)?);
    } else if !args.quiet {
        print!("{}", table());
    }
    let level = if args.allow_fail { "warning" } else { "error" };
    for line in failure_lines(level) {
        eprintln!("{line}");
    }
    if ok || args.allow_fail {
        Ok(ExitCode::SUCCESS)
    } else {
        Ok(crate::exit::fails())
    }
}

/// A bar over print states (hidden when quiet); its length is learnt on the first tick, since
/// the number of states is known only after form-finding.
fn state_bar(message: &'static str, hidden: bool) -> ProgressBar {
    if hidden {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(0);
    b.set_style(
        ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} states ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    b.set_message(message);
    b
}

fn tick(bar: &ProgressBar, p: kappe::Progress) {
    bar.set_length(p.total as u64);
    bar.set_position(p.done as u64);
}

/// A ceiling file (`[ceiling]` + `[[bay]]`, issue 15): every bay designed, analysed and planned
/// (`kappe::commands::ceiling::run_ceiling`); writes `ceiling.json` (the room summary), `index.html` (the
/// room page) and per bay `bay_N/{summary.json, report.html, path.csv}` plus, when the bay passes
/// (or `--allow-fail`), its robot programs (`bay_N/program_partNN.script`, `programs.json`,
/// `trajectory.csv`, `plan.json`; the mirrored second half of a `both_walls` bay under
/// `bay_N/mirror/`).
fn run_ceiling(args: &DesignArgs, text: &str, path: &std::path::Path) -> Result<ExitCode> {
    let ceiling = kappe::commands::ceiling::CeilingDesign::from_toml_str(text)
        .with_context(|| format!("invalid ceiling file {}", path.display()))?;
    // The bays share the file's [analysis] and [robot]: the first bay's design carries them.
    let first = ceiling
        .bay_designs()?
        .into_iter()
        .next()
        .unwrap_or_default();
    let options = run_options(args, &first)?;
    let prepared = prepare_dir(&args.out, args.force, "design (ceiling)")?;
    let silent = args.quiet || args.json;
    let spinner = if silent {
        ProgressBar::hidden()
    } else {
        ProgressBar::new_spinner()
    };
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let on_progress = |bay: usize, p: kappe::Progress| {
        spinner.set_message(format!(
            "bay {}: {:?} {}/{}",
            bay + 1,
            p.stage,
            p.done,
            p.total
        ));
        std::ops::ControlFlow::Continue(())
    };
    let out = kappe::commands::ceiling::run_ceiling(&ceiling, &options, &on_progress)?;
    spinner.finish_and_clear();
    let files = out.files(args.allow_fail)?;
    let table = || out.table(&args.out);
    let failures = |level: &str| out.failure_lines(level);
    finish(
        args,
        prepared,
        &files,
        &out.summary(),
        table,
        failures,
        out.ok,
    )
}

/// What `kappe design` runs for `design`: the analysis of every state (stresses, overhang, shell
/// buckling, method.md §3) from its `[analysis]` with the command-line overrides, the robot plan
/// unless `--no-robot`, and robot programs for a failing design only with `--allow-fail`.
fn run_options(args: &DesignArgs, design: &kappe::Design) -> Result<kappe::Options> {
    let mut options = kappe::Options::of(design);
    if let Some(analysis) = options.analysis.as_mut() {
        if let Some(states) = &args.states {
            analysis.states = states
                .parse()
                .map_err(|e| Usage(format!("--states: {e}")))?;
        }
        if args.no_buckling {
            analysis.buckling = false;
        }
    }
    options.robot = !args.no_robot;
    options.allow_fail = args.allow_fail;
    Ok(options)
}
