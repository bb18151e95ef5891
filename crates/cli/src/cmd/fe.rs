//! `kappe fe ...`: linear buckling and linear statics of a shell mesh (the fixture mesh format
//! of `../shared/fixtures/fe/`, see `kappe_fe::mesh_json`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use kappe_fe::mesh_json::parse_mesh;
use kappe_fe::{BucklingOptions, BucklingSolver, ElementKind, ShellModel, StaticResult};
use serde_json::{Value, json};

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
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut model =
        parse_mesh(&text).with_context(|| format!("invalid mesh in {}", path.display()))?;
    model.allow_mixed_orientation |= allow_mixed_orientation;
    // The mesh file's own default is the fixtures' reference element (CST+DKT), so old files
    // keep their meaning inside the library; the command's default is the shear-deformable
    // element, which is at least as accurate on thin shells and right on thick ones (issue 17).
    let names_element = serde_json::from_str::<Value>(&text)
        .ok()
        .is_some_and(|v| v.get("element").is_some());
    match element {
        Some(e) => model.element = e.into(),
        None if !names_element => model.element = ElementKind::AndesDkmt,
        None => {}
    }
    Ok(model)
}

fn emit(output: Option<&Path>, force: bool, doc: &Value) -> Result<()> {
    let mut text = serde_json::to_string_pretty(doc).context("cannot serialize the result")?;
    text.push('\n');
    match output {
        Some(out) => write_user_file(out, text.as_bytes(), force),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// Flat triangles (aspect > 20) are solved but flagged, with the worst few named.
fn quality(model: &ShellModel) -> Value {
    let mut w = model.quality_warnings();
    w.sort_by(|a, b| b.1.total_cmp(&a.1));
    json!({
        "flat_triangles": w.len(),
        "aspect_limit": kappe_fe::model::WARN_ASPECT,
        "worst": w.iter().take(10).map(|(e, a)| json!({"element": e, "aspect": a})).collect::<Vec<_>>(),
    })
}

fn static_summary(s: &StaticResult) -> Value {
    json!({
        "max_displacement": s.max_displacement,
        "reactions_sum": s.reactions_sum,
        "load_sum": s.load_sum,
    })
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
    if r.static_result.load_sum.iter().all(|v| *v == 0.0) && r.static_result.max_displacement == 0.0
    {
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
    let s = &r.stats;
    let mut doc = json!({
        "factors": r.factors,
        "static": static_summary(&r.static_result),
        "dofs": s.n_free_dofs,
        "time_s": time_s,
        "residuals": r.residuals,
        "mesh_quality": quality(&model),
        "sturm": r.sturm.map(|c| json!({
            "sigma": c.sigma,
            "negative_pivots": c.negative_pivots,
            "factors_below_sigma": c.found_below,
        })),
        "solver": {
            "element": model.element.description(),
            "element_kind": model.element.name(),
            "nnz_k": s.nnz_k,
            "nnz_l": s.nnz_l,
            "operator_applications": s.operator_applications,
            "t_symbolic_s": s.t_symbolic,
            "t_assembly_s": s.t_assembly,
            "t_factor_s": s.t_factor,
            "t_geometric_s": s.t_geometric,
            "t_eigen_s": s.t_eigen,
            "t_sturm_s": s.t_sturm,
        },
    });
    if args.mode_shapes {
        doc["modes"] = json!(r.modes);
    }
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
    let elements: Vec<Value> = r
        .elements
        .iter()
        .map(|e| {
            json!({
                "frame": e.frame,
                "membrane_force": e.resultants.membrane,
                "moment": e.resultants.moment,
                "membrane_stress": e.membrane_stress(),
                "stress_top": e.surface_stress(true),
                "stress_bottom": e.surface_stress(false),
            })
        })
        .collect();
    let reactions: Vec<Value> = r
        .reactions
        .iter()
        .enumerate()
        .filter(|(_, f)| f.iter().any(|v| *v != 0.0))
        .map(|(n, f)| json!({"node": n, "reaction": f}))
        .collect();
    let doc = json!({
        "static": static_summary(&r),
        "dofs": r.n_free_dofs,
        "element": model.element.name(),
        "mesh_quality": quality(&model),
        "time_s": t0.elapsed().as_secs_f64(),
        "displacements": r.displacements,
        "reactions": reactions,
        "elements": elements,
        "element_note": "per element, local frame rows [e1, e2, e3]; membrane_force [Nx, Ny, Nxy] N/m (tension +); moment [Mx, My, Mxy] N·m/m at the centroid; stresses Pa, top = +e3 side",
    });
    emit(args.output.as_deref(), args.force, &doc)?;
    Ok(ExitCode::SUCCESS)
}
