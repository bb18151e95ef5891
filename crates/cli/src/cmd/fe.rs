//! `kappe fe ...`: linear buckling and linear statics of a shell mesh (the fixture mesh format
//! of `../shared/fixtures/fe/`, see `kappe_fe::mesh_json`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use kappe_fe::summary;
use kappe_fe::{BucklingOptions, BucklingSolver, ElementKind, ShellModel};
use serde_json::Value;

use crate::exit::Usage;
use crate::output::{check_user_file, write_user_file};

#[derive(Subcommand)]
pub enum FeCommand {
    /// Linear buckling: lowest positive load factors of (K + λ K_G) φ = 0 under the mesh's load.
    Buckle(BuckleArgs),
    /// Linear statics: displacements, reactions, membrane forces, moments and stresses.
    Static(StaticArgs),
}

#[derive(Args)]
pub struct BuckleArgs {
    /// Input mesh (JSON, fixture mesh format).
    mesh: PathBuf,
    /// Output file (written atomically); stdout when absent.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    /// Number of buckling factors (lowest positive).
    #[arg(long, default_value_t = 3)]
    modes: usize,
    /// Include the mode shapes (per node [ux, uy, uz, rx, ry, rz], max |·| = 1).
    #[arg(long)]
    mode_shapes: bool,
    /// Skip the Sturm-count check (saves one factorization).
    #[arg(long)]
    no_sturm: bool,
    /// Accept triangles oriented against their neighbours (results are orientation-independent).
    #[arg(long)]
    allow_mixed_orientation: bool,
    /// Element formulation; overrides the mesh's "element". Default: the mesh's "element", else
    /// ANDES + DKMT (shear-deformable, exact Kirchhoff limit; `kappe_fe::element::dkmt`).
    #[arg(long, value_enum)]
    element: Option<ElementArg>,
}

/// `--element`: the facet element of `kappe_fe::ElementKind`.
#[derive(Clone, Copy, ValueEnum)]
enum ElementArg {
    /// ANDES/OPT membrane + DKMT Reissner–Mindlin plate: transverse shear for thick shells,
    /// DKT in the thin limit (the default).
    Dkmt,
    /// CST membrane + DKMT plate.
    CstDkmt,
    /// CST membrane + DKT plate + drilling spring (the reference element of the fixtures).
    Cst,
    /// ANDES/OPT membrane with drilling freedoms + DKT plate (better membrane on coarse meshes).
    Andes,
}

impl From<ElementArg> for ElementKind {
    fn from(e: ElementArg) -> Self {
        match e {
            ElementArg::Dkmt => ElementKind::AndesDkmt,
            ElementArg::CstDkmt => ElementKind::CstDkmt,
            ElementArg::Cst => ElementKind::CstDkt,
            ElementArg::Andes => ElementKind::AndesDkt,
        }
    }
}

#[derive(Args)]
pub struct StaticArgs {
    /// Input mesh (JSON, fixture mesh format).
    mesh: PathBuf,
    /// Output file (written atomically); stdout when absent.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    /// Accept triangles oriented against their neighbours (results are orientation-independent;
    /// element frames then follow each triangle's own normal).
    #[arg(long)]
    allow_mixed_orientation: bool,
    /// Element formulation; overrides the mesh's "element". Default: the mesh's "element", else
    /// ANDES + DKMT (shear-deformable, exact Kirchhoff limit; `kappe_fe::element::dkmt`).
    #[arg(long, value_enum)]
    element: Option<ElementArg>,
}

pub fn run(cmd: FeCommand) -> Result<ExitCode> {
    match cmd {
        FeCommand::Buckle(a) => buckle(a),
        FeCommand::Static(a) => statics(a),
    }
}

fn load(
    path: &Path,
    allow_mixed_orientation: bool,
    element: Option<ElementArg>,
) -> Result<ShellModel> {
    // An unreadable or non-UTF-8 file is a bad input (exit 2), not an I/O failure of Kappe's.
    crate::input::read_text(path, "mesh file")?;
    Ok(summary::read_mesh_file(
        path,
        allow_mixed_orientation,
        element.map(Into::into),
    )?)
}

fn emit(output: Option<&Path>, force: bool, doc: &Value) -> Result<()> {
    let text = summary::document(doc).context("cannot serialize the result")?;
    match output {
        Some(out) => Ok(write_user_file(out, text.as_bytes(), force)?),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

fn buckle(args: BuckleArgs) -> Result<ExitCode> {
    let t0 = Instant::now();
    if let Some(out) = &args.output {
        check_user_file(out, args.force)?;
    }
    let model = load(&args.mesh, args.allow_mixed_orientation, args.element)?;
    let source = args.mesh.display().to_string();
    let options = BucklingOptions {
        modes: args.modes,
        sturm_check: !args.no_sturm,
        ..BucklingOptions::default()
    };
    let solver = BucklingSolver::new(&model).with_context(|| format!("invalid model {source}"))?;
    let r = solver
        .buckling(&model, &options)
        .with_context(|| format!("buckling analysis of {source} failed"))?;
    let time_s = t0.elapsed().as_secs_f64();
    if !summary::has_load(&r.static_result) {
        return Err(Usage(format!(
            "{source} has no load (gamma = 0 and no nodal loads): there is nothing to buckle"
        ))
        .into());
    }
    if r.factors.is_empty() {
        eprintln!(
            "note: no positive buckling factor: under this load the shell is nowhere in \
             compression (reversing the load may buckle it)"
        );
    }
    let doc = summary::buckle_value(&model, &r, time_s, args.mode_shapes);
    emit(args.output.as_deref(), args.force, &doc)?;
    Ok(ExitCode::SUCCESS)
}

fn statics(args: StaticArgs) -> Result<ExitCode> {
    let t0 = Instant::now();
    if let Some(out) = &args.output {
        check_user_file(out, args.force)?;
    }
    let model = load(&args.mesh, args.allow_mixed_orientation, args.element)?;
    let source = args.mesh.display().to_string();
    let r = kappe_fe::linear_static(&model)
        .with_context(|| format!("static analysis of {source} failed"))?;
    let doc = summary::static_value(&model, &r, t0.elapsed().as_secs_f64());
    emit(args.output.as_deref(), args.force, &doc)?;
    Ok(ExitCode::SUCCESS)
}
