//! `kappe study STUDY.toml --out DIR` and `kappe study merge DIR... --out DIR`: design studies.
//! The study engine (file format, expansion, per-design runs, merge, the CSV) is
//! [`kappe::study`]; this module parses arguments, shows progress and writes the files: per
//! design `DIR/designs/<name>/{design.toml, summary.json, report.html}`, and `DIR/study.csv`,
//! `DIR/study.html`, `DIR/study.json`, the whole directory atomically.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use kappe::study::{Record, StudyResult, Variation, Verdict};
use rayon::prelude::*;

use crate::exit::Usage;
use crate::output::prepare_dir;

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

/// The shard of this task of a Slurm job array (`--shard` without a value).
fn slurm_shard() -> Result<(usize, usize)> {
    let var = |k: &str| -> Result<Option<usize>> {
        match std::env::var(k) {
            Err(_) => Ok(None),
            Ok(v) => v.trim().parse().map(Some).map_err(|_| {
                crate::exit::Usage(format!("--shard: {k}={v:?} is not a whole number")).into()
            }),
        }
    };
    let (Some(id), Some(count)) = (var("SLURM_ARRAY_TASK_ID")?, var("SLURM_ARRAY_TASK_COUNT")?)
    else {
        return Err(crate::exit::Usage(
            "--shard without i/n needs SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT (a Slurm job \
             array); give --shard i/n otherwise"
                .into(),
        )
        .into());
    };
    let min = var("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
    let spec = format!("{}/{count}", id.saturating_sub(min));
    Ok(kappe::study::parse_shard(&spec)?)
}

/// Writes `study.json`, `study.csv` and `study.html` into `dir`.
fn write_study_files(dir: &Path, result: &StudyResult) -> Result<()> {
    let html = result.html().context("cannot render study.html")?;
    std::fs::write(dir.join("study.json"), result.to_json())?;
    std::fs::write(dir.join("study.csv"), result.csv())?;
    std::fs::write(dir.join("study.html"), html)?;
    Ok(())
}

/// Runs one design and writes `designs/<name>/` under `root`. Any failure becomes an error row.
fn run_one(v: &Variation, parameter_paths: &[String], no_robot: bool, root: &Path) -> Record {
    let parameters = kappe::study::parameter_values(v, parameter_paths);
    let dir = root.join("designs").join(&v.name);
    if let Err(e) = std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(dir.join("design.toml"), v.design_toml().as_bytes()))
    {
        return kappe::study::error_record(
            v,
            parameters,
            format!("cannot write {}: {e}", dir.display()),
        );
    }
    let run = kappe::study::run_one(v, parameters.clone(), no_robot);
    let write = || -> std::io::Result<()> {
        if let Some(summary) = &run.summary {
            std::fs::write(
                dir.join("summary.json"),
                serde_json::to_vec_pretty(summary)?,
            )?;
        }
        if let Some(html) = &run.report_html {
            std::fs::write(dir.join("report.html"), html)?;
        }
        Ok(())
    };
    match write() {
        Ok(()) => run.record,
        Err(e) => kappe::study::error_record(v, parameters, e.to_string()),
    }
}

fn print_summary(result: &StudyResult, out: &Path) {
    let count = |o: Verdict| result.rows.iter().filter(|r| r.outcome == o).count();
    println!(
        "study \"{}\": {} of {} designs{}: {} pass, {} fail, {} could not be run",
        result.title,
        result.rows.len(),
        result.designs.len(),
        result
            .shard
            .map(|[i, n]| format!(" (shard {i}/{n})"))
            .unwrap_or_default(),
        count(Verdict::Pass),
        count(Verdict::Fail),
        count(Verdict::Error),
    );
    for r in result.rows.iter().filter(|r| r.outcome == Verdict::Error) {
        println!("  {}: {}", r.name, r.error.as_deref().unwrap_or(""));
    }
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
        Some("slurm") => Some(slurm_shard()?),
        other => other.map(kappe::study::parse_shard).transpose()?,
    };
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read the study file {}", path.display()))?;
    let source = path.file_name().map_or_else(
        || path.display().to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    let study_dir = path.parent().unwrap_or(Path::new("."));
    let study = kappe::study::parse(&text, &source, study_dir)
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
    let pool = {
        let mut builder = rayon::ThreadPoolBuilder::new();
        if let Some(j) = args.jobs {
            if j == 0 {
                return Err(Usage("--jobs 0: give at least 1".into()).into());
            }
            builder = builder.num_threads(j);
        }
        builder.build().context("cannot start the worker threads")?
    };
    // Refusals and unwritable locations fail here, before any design runs.
    let prepared = prepare_dir(&out, args.force, "study")?;
    let dir = prepared.path();
    std::fs::create_dir_all(dir.join("designs"))?;
    let rows: Vec<Record> = pool.install(|| {
        selected
            .par_iter()
            .map(|v| {
                let r = run_one(v, &study.parameters, args.no_robot, dir);
                bar.inc(1);
                r
            })
            .collect()
    });
    let result = kappe::study::collect(&study, shard, args.no_robot, rows)?;
    write_study_files(dir, &result)?;
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    bar.finish_and_clear();
    if !args.quiet {
        print_summary(&result, &out);
    }
    // Status 1 when any design fails or could not run (the scheme of `kappe --help`).
    if result.rows.iter().any(|row| row.outcome != Verdict::Pass) {
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
    let merged = kappe::study::merge(&parts, args.allow_incomplete)?;
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
        write_study_files(dir, &merged.result)?;
    }
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    if !args.quiet {
        print_summary(&merged.result, &args.out);
    }
    if merged
        .result
        .rows
        .iter()
        .any(|row| row.outcome != Verdict::Pass)
    {
        return Ok(crate::exit::fails());
    }
    Ok(ExitCode::SUCCESS)
}
