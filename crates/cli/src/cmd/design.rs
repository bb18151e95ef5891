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
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read the design file {}", path.display()))?;
            if kappe::ceiling::is_ceiling_toml(&text) {
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
            kappe::Stage::Analysis => {
                bar.finish_and_clear();
                tick(&fe_bar, p);
            }
            kappe::Stage::Robot if p.done == 0 => {
                bar.finish_and_clear();
                fe_bar.finish_and_clear();
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
    let cap = &eval.cap;
    let (analysis, robot, ok) = (&eval.analysis, &eval.robot, eval.ok);
    // Robot programs: standalone files of at most the target limit, each passing the
    // independent URScript check, their index, the trajectory and the plan (for resume).
    let mut programs: Vec<kappe_robot::ProgramFile> = Vec::new();
    let mut trajectory: Vec<u8> = Vec::new();
    let mut plan_json: Vec<u8> = Vec::new();
    if let Some(Ok(plan)) = robot {
        kappe_robot::write_trajectory_csv(plan, &mut trajectory)?;
        kappe_robot::write_plan_json(plan, &mut plan_json)?;
    }
    // No programs for a design that fails its checks, unless --allow-fail (issue 16).
    if let Ok(plan) = eval.programs() {
        programs = crate::cmd::robot::linted_programs(plan, "program_part")?;
    }
    let report = eval.report_html()?;
    let summary = eval.summary();
    let network = kappe::export::network_json(cap)?;
    {
        let dir = prepared.path();
        std::fs::write(
            dir.join("summary.json"),
            serde_json::to_vec_pretty(&summary)?,
        )?;
        std::fs::write(
            dir.join("network.json"),
            serde_json::to_vec_pretty(&network)?,
        )?;
        std::fs::write(dir.join("path.csv"), cap.path.to_csv())?;
        std::fs::write(dir.join("cap.obj"), cap.mesh.to_obj(&cap.design.name))?;
        std::fs::write(dir.join("cap.glb"), cap.mesh.to_glb())?;
        std::fs::write(dir.join("report.html"), &report)?;
        // The layer times the structural check and the robot share (issue 11).
        if let Ok(schedule) = eval.schedule() {
            std::fs::write(dir.join("schedule.csv"), schedule.to_csv())?;
        }
        if !trajectory.is_empty() {
            std::fs::write(dir.join("trajectory.csv"), &trajectory)?;
            std::fs::write(dir.join("plan.json"), &plan_json)?;
        }
        // Programs that fit the controller, run in the order of programs.json; one combined
        // program.script only when the whole print fits in one.
        for p in &programs {
            std::fs::write(dir.join(&p.name), &p.text)?;
        }
        if !programs.is_empty() {
            std::fs::write(
                dir.join("programs.json"),
                kappe_robot::index_json(&programs),
            )?;
        }
        if let [one] = programs.as_slice() {
            std::fs::write(dir.join("program.script"), &one.text)?;
        }
    }
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }

    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else if !args.quiet {
        print_table(cap, eval.print_time(), &args.out);
        if let Some(analysis) = analysis {
            print!("{}", indent(&analysis.report()));
        }
        match &robot {
            Some(Ok(plan)) => println!(
                "  robot: {} station(s), joint motion {:.1} rad, {:.1} min, min clearance {:.1} mm, \
                 {} slowdown(s); wrote trajectory.csv, plan.json{}",
                plan.stations.len(),
                plan.joint_motion,
                eval.print_time() / 60.0,
                plan.min_clearance * 1e3,
                plan.slowdowns.len(),
                match eval.programs() {
                    Ok(_) => format!(", {} program(s) listed in programs.json", programs.len()),
                    Err(why) => format!("; no programs: {why}"),
                }
            ),
            Some(Err(e)) => println!("  robot: NOT PLANNED: {e}"),
            None => println!("  robot: planning skipped"),
        }
    }
    // With --allow-fail a failing design is not an error: its reasons are warnings.
    let level = if args.allow_fail { "warning" } else { "error" };
    if let Some(Err(e)) = &robot {
        eprintln!("{level}: the robot cannot print this design: {e}");
    }
    if !ok {
        for c in analysis.iter().flat_map(|a| a.failing()) {
            eprintln!(
                "{level}: constraint {} fails: worst {} {} against the limit {} {}{}",
                c.name,
                c.worst.map_or("n/a".into(), |w| format!("{w:.4e}")),
                c.unit,
                c.limit,
                c.unit,
                c.state
                    .map_or(String::new(), |s| format!(" (state {s}, {})", c.element))
            );
        }
        if !args.allow_fail {
            return Ok(crate::exit::fails());
        }
    }
    Ok(ExitCode::SUCCESS)
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

fn indent(text: &str) -> String {
    text.lines().map(|l| format!("  {l}\n")).collect()
}

fn print_table(cap: &kappe::Cap, print_time: f64, out: &std::path::Path) {
    let d = &cap.design;
    let last = cap.states.last();
    let worst_c = cap
        .states
        .iter()
        .map(|s| s.forces.max_compression_stress)
        .fold(0.0, f64::min);
    let worst_t = cap
        .states
        .iter()
        .map(|s| s.forces.max_tension_stress)
        .fold(0.0, f64::max);
    let worst_res = cap
        .states
        .iter()
        .map(|s| s.forces.max_residual)
        .fold(0.0, f64::max);
    let overhang = cap.overhangs.iter().fold(0.0_f64, |m, o| m.max(o.abs()));
    println!("Kappe design \"{}\"", d.name);
    println!(
        "  span {:.3} m, rise {:.3} m, length {:.3} m, tilt {:.1}°, lh {:.1} mm, lw {:.1} mm",
        d.cap.span,
        d.cap.rise,
        d.cap.length,
        d.cap.tilt_deg,
        d.print.layer_height * 1e3,
        d.print.layer_width * 1e3
    );
    println!(
        "  layer arch: {} segments of {:.2} mm, crown thrust {:.3} N (catenary a = {:.4} m)",
        cap.arch.segments(),
        cap.arch.segment_length * 1e3,
        -cap.arch.crown_force,
        cap.catenary.a
    );
    println!(
        "  layers: {} start + {} centre = {} states; final network {} nodes",
        cap.sections.n_start,
        cap.sections.n_centre,
        cap.states.len(),
        cap.final_state.network.nodes.len()
    );
    println!("  {:<34} {:>14}", "quantity", "value");
    println!(
        "  {:<34} {:>14.2}",
        "max compression stress [kPa]",
        worst_c / 1e3
    );
    println!("  {:<34} {:>14.3e}", "max tension stress [Pa]", worst_t);
    println!("  {:<34} {:>14.3e}", "max node residual [N]", worst_res);
    println!(
        "  {:<34} {:>14.2}",
        "max layer overhang [mm]",
        overhang * 1e3
    );
    if let Some(s) = last {
        println!(
            "  {:<34} {:>14.1}",
            "start-section thrust on base [N]", s.forces.column_end_reaction[1]
        );
        println!(
            "  {:<34} {:>14.3}",
            "start-section H/V", s.forces.column_end_hv_ratio
        );
    }
    println!(
        "  {:<34} {:>14.2}",
        "path length [m]", cap.path.print_length
    );
    println!("  {:<34} {:>14.2}", "volume [l]", cap.path.volume * 1e3);
    println!("  {:<34} {:>14.1}", "mass [kg]", cap.path.mass);
    println!("  {:<34} {:>14.1}", "print time [min]", print_time / 60.0);
    println!(
        "  wrote {}/{{summary.json, network.json, path.csv, cap.obj, cap.glb, report.html}}",
        out.display()
    );
}

/// A ceiling file (`[ceiling]` + `[[bay]]`, issue 15): every bay designed, analysed and planned
/// (`kappe::ceiling::run_ceiling`); writes `ceiling.json` (the room summary), `index.html` (the
/// room page) and per bay `bay_N/{summary.json, report.html, path.csv}` plus, when the bay passes
/// (or `--allow-fail`), its robot programs (`bay_N/program_partNN.script`, `programs.json`,
/// `trajectory.csv`, `plan.json`; the mirrored second half of a `both_walls` bay under
/// `bay_N/mirror/`).
fn run_ceiling(args: &DesignArgs, text: &str, path: &std::path::Path) -> Result<ExitCode> {
    let ceiling = kappe::ceiling::CeilingDesign::from_toml_str(text)
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
    let out = kappe::ceiling::run_ceiling(&ceiling, &options, &on_progress)?;
    spinner.finish_and_clear();
    let dir = prepared.path();
    let summary = out.summary();
    std::fs::write(
        dir.join("ceiling.json"),
        serde_json::to_vec_pretty(&summary)?,
    )?;
    std::fs::write(dir.join("index.html"), out.index_html())?;
    for (i, bay) in out.bays.iter().enumerate() {
        let bay_dir = dir.join(format!("bay_{}", i + 1));
        std::fs::create_dir_all(&bay_dir)?;
        let eval = &bay.outcome;
        std::fs::write(
            bay_dir.join("summary.json"),
            serde_json::to_vec_pretty(&eval.summary())?,
        )?;
        std::fs::write(bay_dir.join("report.html"), eval.report_html()?)?;
        std::fs::write(bay_dir.join("path.csv"), eval.cap.path.to_csv())?;
        if eval.ok || args.allow_fail {
            if let Some(Ok(plan)) = &eval.robot {
                let files = crate::cmd::robot::linted_programs(plan, "program_part")?;
                crate::cmd::robot::write_plan_outputs(&bay_dir, plan, &files)?;
            }
            if let Some(Ok(plan)) = &bay.mirror_plan {
                let mirror = bay_dir.join("mirror");
                std::fs::create_dir_all(&mirror)?;
                let files = crate::cmd::robot::linted_programs(plan, "program_part")?;
                crate::cmd::robot::write_plan_outputs(&mirror, plan, &files)?;
            }
        }
    }
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else if !args.quiet {
        println!(
            "Kappe ceiling: {} bay(s); wrote {}/{{ceiling.json, index.html, bay_N/}}",
            out.bays.len(),
            args.out.display()
        );
        for (i, bay) in out.bays.iter().enumerate() {
            println!(
                "  bay {}: span {:.3} m, {} half/halves, {}",
                i + 1,
                bay.design.cap.span,
                bay.halves,
                if bay.outcome.ok { "passes" } else { "FAILS" }
            );
        }
    }
    if !out.ok {
        let level = if args.allow_fail { "warning" } else { "error" };
        for (i, b) in out.bays.iter().enumerate() {
            if !b.outcome.ok {
                eprintln!(
                    "{level}: bay {} fails its checks (see bay_{}/report.html)",
                    i + 1,
                    i + 1
                );
            }
        }
        if !args.allow_fail {
            return Ok(crate::exit::fails());
        }
    }
    Ok(ExitCode::SUCCESS)
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
