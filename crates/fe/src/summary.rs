//! What `kappe fe buckle` and `kappe fe static` read and write, as library functions so the
//! command line and the Python package (`kappe.fe`) share one implementation: reading a mesh
//! file with the command's element default, and the result documents (JSON) of a buckling and
//! a static run.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::mesh_json::parse_mesh;
use crate::{BucklingResult, ElementKind, FeError, ShellModel, StaticResult};

/// A mesh file that could not be read or is not a valid mesh.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is not a valid mesh (fixture mesh format).
    #[error("invalid mesh in {}", path.display())]
    Invalid {
        path: PathBuf,
        #[source]
        source: FeError,
    },
}

/// A mesh from its JSON text, as the commands take it. `element` overrides the mesh's
/// `"element"`; without either, the element is ANDES + DKMT. (A mesh file's own default is the
/// fixtures' reference element, CST + DKT, so old files keep their meaning inside the library;
/// the commands' default is the shear-deformable element, which is at least as accurate on
/// thin shells and right on thick ones, issue 17.)
pub fn mesh_from_str(
    text: &str,
    allow_mixed_orientation: bool,
    element: Option<ElementKind>,
) -> Result<ShellModel, FeError> {
    let mut model = parse_mesh(text)?;
    model.allow_mixed_orientation |= allow_mixed_orientation;
    let names_element = serde_json::from_str::<Value>(text)
        .ok()
        .is_some_and(|v| v.get("element").is_some());
    match element {
        Some(e) => model.element = e,
        None if !names_element => model.element = ElementKind::AndesDkmt,
        None => {}
    }
    Ok(model)
}

/// [`mesh_from_str`] of a file.
pub fn read_mesh_file(
    path: &Path,
    allow_mixed_orientation: bool,
    element: Option<ElementKind>,
) -> Result<ShellModel, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|source| LoadError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    mesh_from_str(&text, allow_mixed_orientation, element).map_err(|source| LoadError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}

/// Whether the static solution carries any load (a mesh with γ = 0 and no nodal loads has
/// nothing to buckle).
pub fn has_load(s: &StaticResult) -> bool {
    !(s.load_sum.iter().all(|v| *v == 0.0) && s.max_displacement == 0.0)
}

/// Flat triangles (aspect > [`crate::model::WARN_ASPECT`]) are solved but flagged, with the
/// worst ten named.
pub fn quality(model: &ShellModel) -> Value {
    let mut w = model.quality_warnings();
    w.sort_by(|a, b| b.1.total_cmp(&a.1));
    json!({
        "flat_triangles": w.len(),
        "aspect_limit": crate::model::WARN_ASPECT,
        "worst": w.iter().take(10).map(|(e, a)| json!({"element": e, "aspect": a})).collect::<Vec<_>>(),
    })
}

/// The `static` block: the largest displacement and the load/reaction sums (equilibrium).
pub fn static_summary(s: &StaticResult) -> Value {
    json!({
        "max_displacement": s.max_displacement,
        "reactions_sum": s.reactions_sum,
        "load_sum": s.load_sum,
    })
}

/// The document of `kappe fe buckle`; `time_s` is the command's wall time, `mode_shapes`
/// adds the modes.
pub fn buckle_value(
    model: &ShellModel,
    r: &BucklingResult,
    time_s: f64,
    mode_shapes: bool,
) -> Value {
    let s = &r.stats;
    let mut doc = json!({
        "factors": r.factors,
        "static": static_summary(&r.static_result),
        "dofs": s.n_free_dofs,
        "time_s": time_s,
        "residuals": r.residuals,
        "mesh_quality": quality(model),
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
    if mode_shapes {
        doc["modes"] = json!(r.modes);
    }
    doc
}

/// The document of `kappe fe static`; `time_s` is the command's wall time.
pub fn static_value(model: &ShellModel, r: &StaticResult, time_s: f64) -> Value {
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
    json!({
        "static": static_summary(r),
        "dofs": r.n_free_dofs,
        "element": model.element.name(),
        "mesh_quality": quality(model),
        "time_s": time_s,
        "displacements": r.displacements,
        "reactions": reactions,
        "elements": elements,
        "element_note": "per element, local frame rows [e1, e2, e3]; membrane_force [Nx, Ny, Nxy] N/m (tension +); moment [Mx, My, Mxy] N·m/m at the centroid; stresses Pa, top = +e3 side",
    })
}

/// A document as the commands write it: pretty JSON with a final newline.
pub fn document(doc: &Value) -> Result<String, serde_json::Error> {
    let mut text = serde_json::to_string_pretty(doc)?;
    text.push('\n');
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plate() -> String {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/fixtures/fe/plate_ss_s3_n16.mesh.json"
        );
        std::fs::read_to_string(path).expect("the plate fixture")
    }

    #[test]
    fn the_commands_default_element_unless_the_mesh_or_caller_names_one() {
        let text = plate();
        // The fixture names no element: the library's own default is CST + DKT, the
        // commands' is ANDES + DKMT.
        assert_eq!(
            parse_mesh(&text).map(|m| m.element).ok(),
            Some(ElementKind::CstDkt)
        );
        let m = mesh_from_str(&text, false, None).expect("valid mesh");
        assert_eq!(m.element, ElementKind::AndesDkmt);
        let m = mesh_from_str(&text, false, Some(ElementKind::AndesDkt)).expect("valid mesh");
        assert_eq!(m.element, ElementKind::AndesDkt);
        // A mesh that names its element keeps it.
        let mut v: Value = serde_json::from_str(&text).expect("JSON");
        v["element"] = json!(ElementKind::CstDkmt.name());
        let m = mesh_from_str(&v.to_string(), false, None).expect("valid mesh");
        assert_eq!(m.element, ElementKind::CstDkmt);
    }

    #[test]
    fn an_unreadable_or_invalid_file_names_the_path() {
        let missing = Path::new("/nonexistent/kappe-mesh.json");
        let e = read_mesh_file(missing, false, None).expect_err("missing file");
        assert!(matches!(e, LoadError::Read { .. }));
        assert_eq!(e.to_string(), "cannot read /nonexistent/kappe-mesh.json");
        let dir = std::env::temp_dir().join(format!("kappe-fe-summary-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let bad = dir.join("bad.json");
        std::fs::write(&bad, "{\"nodes\": 3}").expect("write");
        let e = read_mesh_file(&bad, false, None).expect_err("invalid mesh");
        assert!(matches!(e, LoadError::Invalid { .. }));
        assert!(e.to_string().starts_with("invalid mesh in "));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
