//! Reader for the mesh format of `../shared/fixtures/fe/*.mesh.json` (see `../shared/README.md`).
//!
//! ```json
//! { "nodes": [[x, y, z], ...],            // m
//!   "triangles": [[i, j, k], ...],         // 0-based
//!   "thickness": 0.02,                     // or one per triangle
//!   "E": 1e6, "nu": 0.3, "gamma": 23044,   // each a number or one per triangle
//!   "supports": {"ux": [0, 5], "uy": [...], "uz": [...], "rx": [...], "ry": [...], "rz": [...]},
//!   "load": {"type": "self_weight", "direction": [0, 0, -1]}
//!        |  {"type": "nodal_forces", "forces": [[node, [fx, fy, fz]], [node, [fx, fy, fz, mx, my, mz]]]}
//!        |  [ ...several of these... ],
//!   "drilling_alpha": 1e-3,                // optional (CST membranes only)
//!   "element": "cst_dkt",                  // optional: "cst_dkt" (default) | "andes_dkt"
//!                                          //   | "andes_dkmt" | "cst_dkmt" (Reissner–Mindlin)
//!   "allow_mixed_orientation": false }     // optional
//! ```
//! Self-weight γ·t per unit area acts whenever γ > 0, along `direction` of a `self_weight`
//! load (default −z); γ may also be given inside the `self_weight` load (as the fixtures do). Other keys (`name`, `units`, `description`, `geometry`, `note`) are
//! ignored.
//!
//! Without `"element"` the mesh gets the fixtures' reference element CST+DKT (the
//! `kappe fe` end-to-end tests compare with its exact reference factors); the
//! shear-deformable `"andes_dkmt"` (issue 17: DKT in the thin limit, transverse shear for
//! thick shells) is selected by name.

use serde_json::Value;

use crate::error::FeError;
use crate::model::{ElementKind, Material, NodalLoad, ShellModel, Support};

fn fmt_err(field: impl Into<String>, detail: impl Into<String>) -> FeError {
    FeError::MeshFormat {
        field: field.into(),
        detail: detail.into(),
    }
}

fn num(v: &Value, field: &str) -> Result<f64, FeError> {
    v.as_f64()
        .ok_or_else(|| fmt_err(field, format!("expected a number, found {v}")))
}

fn index(v: &Value, field: &str) -> Result<usize, FeError> {
    v.as_u64()
        .and_then(|u| usize::try_from(u).ok())
        .ok_or_else(|| fmt_err(field, format!("expected a non-negative integer, found {v}")))
}

fn array<'a>(v: &'a Value, field: &str) -> Result<&'a Vec<Value>, FeError> {
    v.as_array()
        .ok_or_else(|| fmt_err(field, "expected an array"))
}

/// A number or an array of numbers.
fn scalar_or_list(v: &Value, field: &str) -> Result<Vec<f64>, FeError> {
    match v {
        Value::Array(a) => a
            .iter()
            .enumerate()
            .map(|(i, x)| num(x, &format!("{field}[{i}]")))
            .collect(),
        _ => Ok(vec![num(v, field)?]),
    }
}

fn triple(v: &Value, field: &str) -> Result<[f64; 3], FeError> {
    let a = array(v, field)?;
    if a.len() != 3 {
        return Err(fmt_err(
            field,
            format!("expected 3 numbers, found {}", a.len()),
        ));
    }
    Ok([
        num(&a[0], &format!("{field}[0]"))?,
        num(&a[1], &format!("{field}[1]"))?,
        num(&a[2], &format!("{field}[2]"))?,
    ])
}

/// Parse the fixture mesh JSON into a [`ShellModel`] (not yet validated: call
/// [`ShellModel::validate`] or let the solver do it).
pub fn parse_mesh(text: &str) -> Result<ShellModel, FeError> {
    let root: Value = serde_json::from_str(text)?;
    let obj = root
        .as_object()
        .ok_or_else(|| fmt_err("(root)", "expected a JSON object"))?;
    let get = |k: &str| {
        obj.get(k)
            .ok_or_else(|| fmt_err(k, "missing (required field)"))
    };
    let nodes = array(get("nodes")?, "nodes")?
        .iter()
        .enumerate()
        .map(|(i, p)| triple(p, &format!("nodes[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let triangles = array(get("triangles")?, "triangles")?
        .iter()
        .enumerate()
        .map(|(e, t)| {
            let f = format!("triangles[{e}]");
            let a = array(t, &f)?;
            if a.len() != 3 {
                return Err(fmt_err(
                    &f,
                    format!("expected 3 node indices, found {}", a.len()),
                ));
            }
            Ok([index(&a[0], &f)?, index(&a[1], &f)?, index(&a[2], &f)?])
        })
        .collect::<Result<Vec<_>, _>>()?;
    let thickness = scalar_or_list(get("thickness")?, "thickness")?;
    let e = scalar_or_list(get("E")?, "E")?;
    let nu = scalar_or_list(get("nu")?, "nu")?;
    // γ at the top level, or (fixture style) inside a self_weight load.
    let load_gamma = obj.get("load").and_then(|l| match l {
        Value::Array(a) => a
            .iter()
            .find(|x| x.get("type").and_then(Value::as_str) == Some("self_weight"))
            .and_then(|x| x.get("gamma")),
        _ => l.get("gamma"),
    });
    let gamma = match (obj.get("gamma"), load_gamma) {
        (Some(v), _) => scalar_or_list(v, "gamma")?,
        (None, Some(v)) => scalar_or_list(v, "load.gamma")?,
        (None, None) => vec![0.0],
    };
    if let (Some(top), Some(inner)) = (obj.get("gamma"), load_gamma)
        && top != inner
    {
        return Err(fmt_err(
            "load.gamma",
            format!("{inner} differs from the top-level gamma {top}; give one of them"),
        ));
    }
    let n_el = triangles.len();
    let n_mat = [e.len(), nu.len(), gamma.len()]
        .into_iter()
        .max()
        .unwrap_or(1);
    for (name, len) in [("E", e.len()), ("nu", nu.len()), ("gamma", gamma.len())] {
        if len == 0 || (len != 1 && len != n_mat) {
            return Err(fmt_err(
                name,
                format!(
                    "has {len} entries; allowed: 1 or the same count as the other material arrays ({n_mat}) = one per triangle ({n_el})"
                ),
            ));
        }
    }
    let pick = |v: &Vec<f64>, i: usize| if v.len() == 1 { v[0] } else { v[i] };
    let materials: Vec<Material> = (0..n_mat)
        .map(|i| Material {
            youngs_modulus: pick(&e, i),
            poisson_ratio: pick(&nu, i),
            unit_weight: pick(&gamma, i),
        })
        .collect();

    let mut supports = Vec::new();
    if let Some(s) = obj.get("supports") {
        let so = s
            .as_object()
            .ok_or_else(|| fmt_err("supports", "expected an object {\"ux\": [...], ...}"))?;
        for (key, list) in so {
            let dof = match key.as_str() {
                "ux" => 0,
                "uy" => 1,
                "uz" => 2,
                "rx" => 3,
                "ry" => 4,
                "rz" => 5,
                "note" => continue,
                other => {
                    return Err(fmt_err(
                        format!("supports.{other}"),
                        "unknown DOF; allowed: ux, uy, uz, rx, ry, rz (and note)",
                    ));
                }
            };
            for (i, n) in array(list, &format!("supports.{key}"))?.iter().enumerate() {
                let node = index(n, &format!("supports.{key}[{i}]"))?;
                let mut fixed = [false; 6];
                fixed[dof] = true;
                supports.push(Support { node, fixed });
            }
        }
    }

    let mut gravity = [0.0, 0.0, -1.0];
    let mut nodal_loads = Vec::new();
    if let Some(l) = obj.get("load") {
        let loads: Vec<&Value> = match l {
            Value::Array(a) => a.iter().collect(),
            _ => vec![l],
        };
        for (k, load) in loads.iter().enumerate() {
            let f = if loads.len() == 1 {
                "load".to_string()
            } else {
                format!("load[{k}]")
            };
            let ty = load.get("type").and_then(Value::as_str).ok_or_else(|| {
                fmt_err(
                    format!("{f}.type"),
                    "missing; allowed: \"self_weight\", \"nodal_forces\"",
                )
            })?;
            match ty {
                "self_weight" => {
                    if let Some(d) = load.get("direction") {
                        gravity = triple(d, &format!("{f}.direction"))?;
                    }
                }
                "nodal_forces" => {
                    let forces = load
                        .get("forces")
                        .ok_or_else(|| fmt_err(format!("{f}.forces"), "missing"))?;
                    for (i, item) in array(forces, &format!("{f}.forces"))?.iter().enumerate() {
                        let fi = format!("{f}.forces[{i}]");
                        let pair = array(item, &fi)?;
                        let (Some(nv), Some(vv), 2) = (pair.first(), pair.get(1), pair.len())
                        else {
                            return Err(fmt_err(
                                &fi,
                                "expected [node, [fx, fy, fz(, mx, my, mz)]]",
                            ));
                        };
                        let node = index(nv, &format!("{fi}[0]"))?;
                        let comps = array(vv, &format!("{fi}[1]"))?
                            .iter()
                            .enumerate()
                            .map(|(c, x)| num(x, &format!("{fi}[1][{c}]")))
                            .collect::<Result<Vec<_>, _>>()?;
                        if comps.len() != 3 && comps.len() != 6 {
                            return Err(fmt_err(
                                format!("{fi}[1]"),
                                format!("expected 3 or 6 components, found {}", comps.len()),
                            ));
                        }
                        let g = |c: usize| comps.get(c).copied().unwrap_or(0.0);
                        nodal_loads.push(NodalLoad {
                            node,
                            force: [g(0), g(1), g(2)],
                            moment: [g(3), g(4), g(5)],
                        });
                    }
                }
                other => {
                    return Err(fmt_err(
                        format!("{f}.type"),
                        format!(
                            "unknown load type {other:?}; allowed: \"self_weight\", \"nodal_forces\""
                        ),
                    ));
                }
            }
        }
    }
    let mut model = ShellModel::new(nodes, triangles, 0.0, materials[0]);
    model.thickness = thickness;
    model.materials = materials;
    model.supports = supports;
    model.gravity = gravity;
    model.nodal_loads = nodal_loads;
    if let Some(a) = obj.get("drilling_alpha") {
        model.drilling_alpha = num(a, "drilling_alpha")?;
    }
    if let Some(a) = obj.get("element") {
        model.element = a.as_str().and_then(ElementKind::from_name).ok_or_else(|| {
            fmt_err(
                "element",
                format!(
                    "unknown element {a}; allowed: \"cst_dkt\", \"andes_dkt\", \"andes_dkmt\", \"cst_dkmt\""
                ),
            )
        })?;
    }
    if let Some(a) = obj.get("allow_mixed_orientation") {
        model.allow_mixed_orientation = a
            .as_bool()
            .ok_or_else(|| fmt_err("allow_mixed_orientation", "expected true or false"))?;
    }
    Ok(model)
}
