//! `kappe design` and `kappe init`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::output::{write_dir_atomic, write_file_atomic};

#[derive(Args)]
pub struct DesignArgs {
    /// Design file (TOML); the embedded default design when omitted (`kappe init` writes it).
    pub design: Option<PathBuf>,
    /// Output directory (replaced atomically: nothing is written on error).
    #[arg(long, short, default_value = "out")]
    pub out: PathBuf,
    /// No progress bar and no table.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON to stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Skip robot motion planning (no trajectory.csv / program.script).
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

#[derive(Args)]
pub struct InitArgs {
    /// Where to write the example design.
    #[arg(default_value = "kappe.toml")]
    pub path: PathBuf,
    /// Overwrite an existing file.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: DesignArgs) -> Result<ExitCode> {
    let design = match &args.design {
        None => kappe::Design::default(),
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read the design file {}", path.display()))?;
            kappe::Design::from_toml_str(&text)
                .with_context(|| format!("invalid design file {}", path.display()))?
        }
    };
    // Analysis of every state: stresses, overhang, shell buckling (method.md §3).
    let mut options = kappe::Options::of(&design);
    if let Some(analysis) = options.analysis.as_mut() {
        if let Some(states) = &args.states {
            analysis.states = states
                .parse()
                .map_err(|e| anyhow::anyhow!("--states: {e}"))?;
        }
        if args.no_buckling {
            analysis.buckling = false;
        }
    }
    // Robot: planned (and verified inside the planner) unless disabled.
    options.robot = !args.no_robot;
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
    let mut programs: Vec<String> = Vec::new();
    let mut trajectory: Vec<u8> = Vec::new();
    let mut program: Vec<u8> = Vec::new();
    if let Some(Ok(plan)) = robot {
        kappe_robot::write_trajectory_csv(plan, &mut trajectory)?;
        kappe_robot::write_urscript(plan, &mut program)?;
        programs = kappe_robot::urscript_programs(plan)?;
    }
    let report = eval.report_html()?;
    let summary = eval.summary();
    let network = kappe::export::network_json(cap)?;
    write_dir_atomic(&args.out, |dir| {
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
        if !trajectory.is_empty() {
            std::fs::write(dir.join("trajectory.csv"), &trajectory)?;
        }
        if !program.is_empty() {
            std::fs::write(dir.join("program.script"), &program)?;
        }
        // Long programs also come as numbered parts that fit the controller, run in order.
        if programs.len() > 1 {
            for (i, p) in programs.iter().enumerate() {
                std::fs::write(dir.join(format!("program_part{:02}.script", i + 1)), p)?;
            }
        }
        Ok(())
    })?;

    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else if !args.quiet {
        print_table(cap, &args.out);
        if let Some(analysis) = analysis {
            print!("{}", indent(&analysis.report()));
        }
        match &robot {
            Some(Ok(plan)) => println!(
                "  robot: {} station(s), joint motion {:.1} rad, {:.1} min, min clearance {:.1} mm; \
                 wrote trajectory.csv, program.script ({} part(s))",
                plan.stations.len(),
                plan.joint_motion,
                plan.total_time / 60.0,
                plan.min_clearance * 1e3,
                programs.len()
            ),
            Some(Err(e)) => println!("  robot: NOT PLANNED: {e}"),
            None => println!("  robot: planning skipped"),
        }
    }
    if let Some(Err(e)) = &robot {
        eprintln!("error: the robot cannot print this design: {e}");
    }
    if !ok {
        for c in analysis.iter().flat_map(|a| a.failing()) {
            eprintln!(
                "error: constraint {} fails: worst {} {} against the limit {} {}{}",
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
            return Ok(ExitCode::FAILURE);
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

fn print_table(cap: &kappe::Cap, out: &std::path::Path) {
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
    println!(
        "  {:<34} {:>14.1}",
        "print time [min]",
        cap.path.time / 60.0
    );
    println!(
        "  wrote {}/{{summary.json, network.json, path.csv, cap.obj, cap.glb, report.html}}",
        out.display()
    );
}

pub fn init(args: InitArgs) -> Result<ExitCode> {
    if args.path.exists() && !args.force {
        bail!(
            "{} exists; pass --force to overwrite it",
            args.path.display()
        );
    }
    write_file_atomic(&args.path, kappe::spec::EXAMPLE_TOML.as_bytes())?;
    println!("wrote {}", args.path.display());
    Ok(ExitCode::SUCCESS)
}
