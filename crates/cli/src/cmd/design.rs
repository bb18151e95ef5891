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
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(0);
        b.set_style(
            ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} states ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        b.set_message("print states");
        b
    };
    // The number of states is known only after form-finding; the bar learns it on the first tick.
    let cap = {
        let bar_ref = &bar;
        kappe::design_cap(&design, &|total| {
            bar_ref.set_length(total as u64);
            bar_ref.inc(1);
        })?
    };
    bar.finish_and_clear();

    let summary = kappe::export::summary_json(&cap);
    let network = kappe::export::network_json(&cap)?;
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
        Ok(())
    })?;

    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else if !args.quiet {
        print_table(&cap, &args.out);
    }
    Ok(ExitCode::SUCCESS)
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
        "  wrote {}/{{summary.json, network.json, path.csv, cap.obj, cap.glb}}",
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
