//! `kappe schedule DESIGN.toml`: the least total print time for which every state passes the
//! green-state checks (`[material.time]`), by a wait after each layer (`kappe::commands::least_waits`).
//! Writes `DIR/schedule.csv` and `DIR/schedule.json` and prints the `[schedule] waits` line that
//! puts the waits into the design (so `kappe design` checks and plans the same schedule).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use crate::exit::Usage;
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
    let text = crate::input::read_text(&args.design, "design file")?;
    let design = kappe::Design::from_toml_str(&text)
        .with_context(|| format!("invalid design file {}", args.design.display()))?;
    // Without a time model every layer is equally stiff at any age, so waiting never helps:
    // the search would print one zero wait per layer and look like an answer.
    if design.material.time.is_none() {
        return Err(Usage(format!(
            "{} has no [material.time] table: kappe schedule finds the waits that let the \
             layers gain stiffness and strength with age, and without a time model waiting never \
             helps. Add [material.time] (docs/green-state.md; `kappe init --kind buildability` \
             shows one), or use `kappe design` to check the design as it is",
            args.design.display()
        ))
        .into());
    }
    let prepared = match &args.out {
        Some(out) => Some(prepare_dir(out, args.force, "kappe schedule")?),
        None => None,
    };
    let cap = kappe::design_cap(&design, kappe::Context::default())?;
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
        print!("{}", text_report(&design, &plan, args.wait_max));
    }
    Ok(if plan.infeasible.is_empty() {
        ExitCode::SUCCESS
    } else {
        crate::exit::fails()
    })
}

/// What `kappe schedule` prints: the print times, one line per state that needed a wait (its
/// wait and the check that bound it), and either the `[schedule] waits` to add to the design or,
/// when some state fails even at `--wait-max`, a clear infeasible verdict (no waits to add:
/// they would not make the design pass) with what to change instead.
fn text_report(
    design: &kappe::Design,
    plan: &kappe::commands::least_waits::WaitPlan,
    wait_max: f64,
) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "{} print states; print time {:.1} min without waits, {:.1} min with the least waits \
         ({:.1} min of waits)",
        plan.states.len(),
        plan.total_without_waits_s / 60.0,
        plan.total_s / 60.0,
        plan.schedule.total_wait_s() / 60.0
    );
    if !plan.binding.is_empty() {
        let _ = writeln!(t, "waits needed ({}):", plan.binding.len());
    }
    for b in &plan.binding {
        let beta = b
            .beta_before
            .map_or(String::new(), |v| format!("; β {v:.2} without it"));
        let _ = writeln!(
            t,
            "  state {:>4}: wait {:.1} s before its top layer ({} binds{beta})",
            b.state,
            b.wait_s,
            b.check.map_or("-", |m| m.name())
        );
    }
    if let Some(bm) = plan.beta_min {
        // [uncertainty]: the target is β ≥ beta_min in every state, drift included (issue 24).
        let low = plan
            .states
            .iter()
            .filter_map(|c| c.beta)
            .fold(f64::INFINITY, f64::min);
        let _ = writeln!(
            t,
            "reliability target β ≥ {bm:.2} (constraints.beta_min): lowest state β {low:.2} \
             with these waits, drift included"
        );
    }
    if plan.infeasible.is_empty() {
        let list: Vec<String> = plan
            .schedule
            .layers
            .iter()
            .map(|l| format!("{:.1}", l.wait_s))
            .collect();
        let _ = writeln!(t, "FEASIBLE: every state passes with these waits.");
        let _ = writeln!(t, "add to the design to print and check this schedule:");
        let _ = writeln!(t, "[schedule]\nwaits = [{}]", list.join(", "));
        return t;
    }
    let blf_min = design.constraints.blf_min;
    let mut by_check: std::collections::BTreeMap<&str, usize> = Default::default();
    for c in &plan.infeasible {
        *by_check
            .entry(c.governing.map_or("-", |m| m.name()))
            .or_default() += 1;
    }
    let counts: Vec<String> = by_check
        .iter()
        .map(|(k, n)| format!("{k} in {n}"))
        .collect();
    let _ = writeln!(
        t,
        "INFEASIBLE: {} of {} states fail even with {:.0} s of wait before their top layer \
         (governing: {}); no schedule of waits makes this design pass.",
        plan.infeasible.len(),
        plan.states.len(),
        wait_max,
        counts.join(", ")
    );
    let show = |c: &kappe::commands::least_waits::StateCheck| {
        let mut parts = Vec::new();
        if let Some(b) = c.blf {
            parts.push(format!("BLF {b:.2} (needs {blf_min:.2})"));
        }
        if let Some(u) = c.strength {
            parts.push(format!("strength used {:.0} %", 100.0 * u));
        }
        if let Some(u) = c.sliding {
            parts.push(format!("sliding used {:.0} %", 100.0 * u));
        }
        if let (Some(b), Some(bm)) = (c.beta, plan.beta_min) {
            parts.push(format!("β {b:.2} (needs {bm:.2})"));
        }
        parts.join(", ")
    };
    if let Some(c) = plan.infeasible.first() {
        let _ = writeln!(t, "  first failing state {:>4}: {}", c.state, show(c));
    }
    if let Some(c) = plan.infeasible.iter().max_by(|a, b| {
        let worst = |c: &kappe::commands::least_waits::StateCheck| {
            c.blf
                .map_or(0.0, |b| if b > 0.0 { blf_min / b } else { f64::INFINITY })
                .max(c.strength.unwrap_or(0.0))
                .max(c.sliding.unwrap_or(0.0))
        };
        worst(a).total_cmp(&worst(b))
    }) {
        let _ = writeln!(t, "  worst state          {:>4}: {}", c.state, show(c));
    }
    let _ = writeln!(
        t,
        "to fix: change the design, not the waits: for buckling raise cap.rise or widen \
         print.layer_width; for strength or sliding a stiffer, faster-setting mix \
         ([material.time]); a larger --wait-max only if the print may pause that long"
    );
    t
}
