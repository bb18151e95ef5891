//! `kappe study STUDY.toml --out DIR` and `kappe study merge DIR... --out DIR`: design studies.
//! The study engine (file format, expansion, per-design runs, merge, the CSV) is
//! [`kappe::commands::study`]; this module parses arguments, shows progress and writes the files: per
//! design `DIR/designs/<name>/{design.toml, summary.json, report.html}`, and `DIR/study.csv`,
//! `DIR/study.html`, `DIR/study.json`, the whole directory atomically.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use kappe::commands::study::{Step, StudyResult, Variation};

use crate::exit::Usage;
use crate::output::{PreparedDir, prepare_dir};

/// `kappe study`: run a study file, or merge shards.
#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct StudyCommand {
    #[command(subcommand)]
    action: Option<StudyAction>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Subcommand)]
enum StudyAction {
    /// Merge the partial results of `--shard` runs into one study.
    Merge(MergeArgs),
}

#[derive(Args)]
struct RunArgs {
    /// Study file (TOML): a base design and a `[grid]` or a `[[design]]` list.
    #[arg(required = true)]
    study: Option<PathBuf>,
    /// Output directory (replaced atomically: nothing is written on error).
    #[arg(long, short, required = true)]
    out: Option<PathBuf>,
    /// Run only the designs i, i+n, i+2n, … of the study order (0 ≤ i < n) and write a partial
    /// result for `kappe study merge`. `--shard` alone (or `--shard slurm`) takes i and n from a
    /// Slurm job array: i = SLURM_ARRAY_TASK_ID − SLURM_ARRAY_TASK_MIN, n =
    /// SLURM_ARRAY_TASK_COUNT (docs/python.md has a job script).
    #[arg(long, value_name = "i/n", num_args = 0..=1, default_missing_value = "slurm")]
    shard: Option<String>,
    /// Number of designs run at the same time (default: one per core).
    #[arg(long, short)]
    jobs: Option<usize>,
    /// Skip robot motion planning (as `kappe design --no-robot`): designs are then judged
    /// without it.
    #[arg(long)]
    no_robot: bool,
    /// No progress bar and no summary.
    #[arg(long, short)]
    quiet: bool,
    /// Also replace a non-empty directory that is not a Kappe output, by moving it aside.
    #[arg(long)]
    force: bool,
}

#[derive(Args)]
struct MergeArgs {
    /// Output directories of the shards of one study.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output directory of the merged study (replaced atomically).
    #[arg(long, short)]
    out: PathBuf,
    /// Merge even if designs of the study are missing from the shards given.
    #[arg(long)]
    allow_incomplete: bool,
    /// No summary.
    #[arg(long, short)]
    quiet: bool,
    /// Also replace a non-empty directory that is not a Kappe output, by moving it aside.
    #[arg(long)]
    force: bool,
}

pub fn run(cmd: StudyCommand) -> Result<ExitCode> {
    match cmd.action {
        Some(StudyAction::Merge(args)) => merge(args),
        None => run_study(cmd.run),
    }
}

/// Writes `designs/<name>/`: `design.toml` before the run, `summary.json` and `report.html`
/// after it.
fn store(prepared: &PreparedDir, v: &Variation, step: Step<'_>) -> Result<(), String> {
    let files = match step {
        Step::Start => Ok(v.files_before()),
        Step::Done(run) => run.files(v),
    };
    files
        .and_then(|f| prepared.write(&f))
        .map_err(|e| e.to_string())
}

fn print_summary(result: &StudyResult, out: &Path) {
    print!("{}", result.overview());
    print!("{}", result_table(result));
    println!(
        "  wrote {}/{{study.csv, study.html, study.json, designs/}}",
        out.display()
    );
}

fn run_study(args: RunArgs) -> Result<ExitCode> {
    let (Some(path), Some(out)) = (args.study, args.out) else {
        return Err(Usage("give a STUDY.toml and --out DIR".into()).into());
    };
    let shard = match args.shard.as_deref() {
        Some("slurm") => Some(kappe::commands::study::slurm_shard(|k| {
            std::env::var(k).ok()
        })?),
        other => other.map(kappe::commands::study::parse_shard).transpose()?,
    };
    let text = crate::input::read_text(&path, "study file")?;
    let source = path.file_name().map_or_else(
        || path.display().to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    let study_dir = path.parent().unwrap_or(Path::new("."));
    let study = kappe::commands::study::parse(&text, &source, study_dir)
        .with_context(|| format!("invalid study file {}", path.display()))?;

    let selected: Vec<&Variation> = study.select(shard);
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(selected.len() as u64);
        b.set_style(
            ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} designs ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        b.set_message("study");
        b
    };
    if args.jobs == Some(0) {
        return Err(Usage("--jobs 0: give at least 1".into()).into());
    }
    // Refusals and unwritable locations fail here, before any design runs.
    let prepared = prepare_dir(&out, args.force, "study")?;
    std::fs::create_dir_all(prepared.path().join("designs"))?;
    let rows = kappe::commands::study::run_designs(
        &selected,
        &study.parameters,
        args.no_robot,
        args.jobs,
        &|v, step| {
            let done = matches!(step, Step::Done(_));
            let r = store(&prepared, v, step);
            if done {
                bar.inc(1);
            }
            r
        },
    )
    .context("cannot start the worker threads")?;
    let result = kappe::commands::study::collect(&study, shard, args.no_robot, rows)?;
    prepared.write(&result.files()?)?;
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    bar.finish_and_clear();
    if !args.quiet {
        print_summary(&result, &out);
    }
    // Status 1 when any design fails or could not run (the scheme of `kappe --help`).
    if !result.all_pass() {
        return Ok(crate::exit::fails());
    }
    Ok(ExitCode::SUCCESS)
}

// ---------------------------------------------------------------------------------------------
// Merging shards.

fn read_result(dir: &Path) -> Result<StudyResult> {
    let path = dir.join("study.json");
    let text = std::fs::read(&path).with_context(|| {
        format!(
            "cannot read {} (is {} the output of `kappe study`?)",
            path.display(),
            dir.display()
        )
    })?;
    StudyResult::from_json(&text).with_context(|| format!("{}", path.display()))
}

fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("cannot create {}", to.display()))?;
    for entry in
        std::fs::read_dir(from).with_context(|| format!("cannot read {}", from.display()))?
    {
        let entry = entry?;
        let target = to.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            copy_dir(&entry.path(), &target)?;
        } else {
            std::fs::copy(entry.path(), &target).with_context(|| {
                format!(
                    "cannot copy {} to {}",
                    entry.path().display(),
                    target.display()
                )
            })?;
        }
    }
    Ok(())
}

fn merge(args: MergeArgs) -> Result<ExitCode> {
    let out_abs = std::path::absolute(&args.out).unwrap_or_else(|_| args.out.clone());
    let mut parts = Vec::with_capacity(args.dirs.len());
    for dir in &args.dirs {
        if std::path::absolute(dir).is_ok_and(|d| d == out_abs) {
            return Err(Usage(format!(
                "--out {} is also an input; merge into a new directory",
                args.out.display()
            ))
            .into());
        }
        parts.push((dir.display().to_string(), read_result(dir)?));
    }
    let merged = kappe::commands::study::merge(&parts, args.allow_incomplete)?;
    let prepared = prepare_dir(&args.out, args.force, "study merge")?;
    {
        let dir = prepared.path();
        for (row, &k) in merged.result.rows.iter().zip(&merged.sources) {
            let from = args.dirs[k].join("designs").join(&row.name);
            if from.is_dir() {
                copy_dir(&from, &dir.join("designs").join(&row.name))?;
            }
        }
        std::fs::create_dir_all(dir.join("designs"))?;
        prepared.write(&merged.result.files()?)?;
    }
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    if !args.quiet {
        print_summary(&merged.result, &args.out);
    }
    if !merged.result.all_pass() {
        return Ok(crate::exit::fails());
    }
    Ok(ExitCode::SUCCESS)
}

/// The small result table (issue 28): per design its verdict, the governing check (the one
/// nearest its limit, or the first that fails), the lowest BLF, mass and print time, so the
/// terminal answers "which design, and why" without opening study.html.
fn result_table(result: &StudyResult) -> String {
    use std::fmt::Write as _;
    let mut t = format!(
        "  {:<24} {:<13} {:<16} {:>9} {:>10} {:>10}\n",
        "design", "verdict", "governing check", "min BLF", "mass [kg]", "time [min]"
    );
    let opt = |v: Option<f64>, scale: f64, digits: usize| {
        v.map_or("-".to_string(), |x| format!("{:.*}", digits, x * scale))
    };
    for r in &result.rows {
        let _ = writeln!(
            t,
            "  {:<24} {:<13} {:<16} {:>9} {:>10} {:>10}",
            r.name,
            match r.outcome {
                kappe::commands::study::Verdict::Pass => "passes",
                kappe::commands::study::Verdict::Fail => "FAILS",
                kappe::commands::study::Verdict::Error => "could not run",
            },
            governing(&r.constraints),
            opt(r.min_blf, 1.0, 2),
            opt(r.mass_kg, 1.0, 1),
            opt(r.print_time_s, 1.0 / 60.0, 1),
        );
    }
    t
}

/// The first failing check, else the one nearest its limit (utilisation worst/limit, or
/// limit/worst for a lower bound on a positive factor such as the BLF); "-" without checks.
fn governing(rows: &[kappe_report::ConstraintRow]) -> String {
    if let Some(c) = rows.iter().find(|c| !c.pass) {
        return c.name.clone();
    }
    let use_of = |c: &kappe_report::ConstraintRow| match c.bound {
        kappe_report::Bound::AtLeast if c.limit > 0.0 && c.worst > 0.0 => c.limit / c.worst,
        _ if c.limit != 0.0 => c.worst / c.limit,
        _ => 0.0,
    };
    rows.iter()
        .map(|c| (use_of(c), c))
        .filter(|(u, _)| u.is_finite())
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map_or("-".to_string(), |(_, c)| c.name.clone())
}
