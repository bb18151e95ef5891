//! `kappe corrugation [DESIGN]`: the corrugation study (issue 26, `kappe::commands::corrugation`):
//! the smooth cap and every (amplitude, wavelength) of the grid, with the governing buckling
//! factor per kg and per print minute against the smooth cap. Prints the table and, with
//! `--out`, writes `DIR/corrugation.csv`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use crate::exit::Usage;
use crate::output::{prepare_dir, write_file_atomic};

#[derive(Args)]
pub struct CorrugationArgs {
    /// Design file (TOML); the embedded default design when omitted. Its own
    /// `[cap.corrugation]` is replaced by each grid point.
    pub design: Option<PathBuf>,
    /// Amplitudes a, m, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.01,0.02,0.03")]
    pub amplitudes: Vec<f64>,
    /// Wavelengths λ, m, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.2,0.3,0.6")]
    pub wavelengths: Vec<f64>,
    /// Print states that get a shell buckling analysis ("all", "every:N", "P%"); overrides
    /// `[analysis] states`.
    #[arg(long)]
    pub states: Option<String>,
    /// Skip robot planning (print time from the path at print speed).
    #[arg(long)]
    pub no_robot: bool,
    /// The most extra material a variant may use to be picked as the best, as a fraction.
    #[arg(long, default_value_t = 0.05)]
    pub max_material: f64,
    /// Output directory for corrugation.csv.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Move a non-Kappe --out directory aside instead of refusing it.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: CorrugationArgs) -> Result<ExitCode> {
    let design = match &args.design {
        Some(path) => {
            let text = crate::input::read_text(path, "design file")?;
            kappe::Design::from_toml_str(&text)
                .with_context(|| format!("invalid design file {}", path.display()))?
        }
        None => kappe::Design::default(),
    };
    if !(args.max_material.is_finite() && args.max_material >= 0.0) {
        return Err(Usage(format!(
            "--max-material {}: allowed a fraction ≥ 0",
            args.max_material
        ))
        .into());
    }
    let mut options = kappe::Options::of(&design);
    if let (Some(analysis), Some(states)) = (options.analysis.as_mut(), &args.states) {
        analysis.states = states
            .parse()
            .map_err(|e| Usage(format!("--states: {e}")))?;
    }
    options.robot = !args.no_robot;
    options.allow_fail = true;
    let prepared = match &args.out {
        Some(out) => Some(prepare_dir(out, args.force, "kappe corrugation")?),
        None => None,
    };
    let study = kappe::commands::corrugation::study(
        &design,
        &args.amplitudes,
        &args.wavelengths,
        &options,
        &|done, total| eprintln!("design {done}/{total} done"),
    )?;
    let csv = study.to_csv();
    if let Some(prepared) = prepared {
        write_file_atomic(&prepared.path().join("corrugation.csv"), csv.as_bytes())?;
        if let Some(notice) = prepared.commit()? {
            eprintln!("note: {notice}");
        }
    }
    print!("{csv}");
    let r0 = &study.reference;
    match study.best(args.max_material) {
        Some(best) => println!(
            "best within +{:.0} % material: amplitude {} m, wavelength {} m: min BLF {:.3} \
             ({:.2}× the smooth cap's {:.3}), mass {:+.2} %",
            args.max_material * 100.0,
            best.amplitude,
            best.wavelength,
            best.min_blf.unwrap_or(f64::NAN),
            best.min_blf.unwrap_or(f64::NAN) / r0.min_blf.unwrap_or(f64::NAN),
            r0.min_blf.unwrap_or(f64::NAN),
            (best.mass_kg / r0.mass_kg - 1.0) * 100.0
        ),
        None => println!(
            "no variant passes every check within +{:.0} % material",
            args.max_material * 100.0
        ),
    }
    Ok(ExitCode::SUCCESS)
}
