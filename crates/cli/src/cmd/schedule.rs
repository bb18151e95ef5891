//! `kappe schedule DESIGN.toml`: the least total print time for which every state passes the
//! green-state checks (`[material.time]`), by a wait after each layer (`kappe::commands::least_waits`).
//! Writes `DIR/schedule.csv` and `DIR/schedule.json` and prints the `[schedule] waits` line that
//! puts the waits into the design (so `kappe design` checks and plans the same schedule).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use crate::output::{prepare_dir, write_file_atomic};

#[derive(Args)]
pub struct ScheduleArgs {
    /// Design file (TOML) with a `[material.time]` table.
    pub design: PathBuf,
    /// Upper bound of each wait, s.
    #[arg(long, default_value_t = 600.0)]
    pub wait_max: f64,
    /// Output directory for schedule.csv and schedule.json.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print schedule.json to stdout instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Move a non-Kappe --out directory aside instead of refusing it.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: ScheduleArgs) -> Result<ExitCode> {
    let text = std::fs::read_to_string(&args.design)
        .with_context(|| format!("cannot read the design file {}", args.design.display()))?;
    let design = kappe::Design::from_toml_str(&text)
        .with_context(|| format!("invalid design file {}", args.design.display()))?;
    let prepared = match &args.out {
        Some(out) => Some(prepare_dir(out, args.force, "kappe schedule")?),
        None => None,
    };
    let cap = kappe::design_cap(&design, &|_| {})?;
    let plan =
        kappe::commands::least_waits::least_waits(&cap, &design.analysis, args.wait_max, &|_| {})?;
    let json = serde_json::to_string_pretty(&kappe::commands::least_waits::document(
        &design,
        args.wait_max,
        &plan,
    )?)? + "\n";
    if let Some(prepared) = prepared {
        let dir = prepared.path();
        write_file_atomic(&dir.join("schedule.csv"), plan.schedule.to_csv().as_bytes())?;
        write_file_atomic(&dir.join("schedule.json"), json.as_bytes())?;
        if let Some(notice) = prepared.commit()? {
            eprintln!("note: {notice}");
        }
    }
    if args.json {
        print!("{json}");
    } else {
        print!(
            "{}",
            kappe::commands::least_waits::text_report(&plan, args.wait_max)
        );
    }
    Ok(if plan.infeasible.is_empty() {
        ExitCode::SUCCESS
    } else {
        crate::exit::fails()
    })
}
