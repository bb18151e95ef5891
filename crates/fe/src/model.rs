//! The shell model: nodes, triangles, per-element thickness and material, supports per DOF,
//! self-weight and nodal loads — plain data the rest of Kappe fills in — plus its validation.
//!
//! Units are SI throughout (m, N, Pa, N/m³). Each node carries six DOFs in the global frame,
//! in the order `ux, uy, uz, rx, ry, rz` (rotations are rotation-vector components, rad).

use std::collections::HashMap;

use crate::error::FeError;

/// Linear-elastic isotropic material with a unit weight for self-weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus E (Pa), > 0.
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, −1 < ν < 0.5.
    pub poisson_ratio: f64,
    /// Unit weight γ (N/m³), ≥ 0. Self-weight is γ·t per unit mid-surface area.
    pub unit_weight: f64,
}

/// Fixed DOFs of one node (`true` = displacement/rotation held at zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Support {
    /// Node index.
    pub node: usize,
    /// `[ux, uy, uz, rx, ry, rz]`.
    pub fixed: [bool; 6],
}

impl Support {
    /// A hinge: the three translations fixed, rotations free.
    pub fn pinned(node: usize) -> Self {
        Self {
            node,
            fixed: [true, true, true, false, false, false],
        }
    }
    /// All six DOFs fixed.
    pub fn clamped(node: usize) -> Self {
        Self {
            node,
            fixed: [true; 6],
        }
    }
}

/// A concentrated force and moment at a node, global frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodalLoad {
    /// Node index.
    pub node: usize,
    /// Force (N).
    pub force: [f64; 3],
    /// Moment (N·m).
    pub moment: [f64; 3],
}

/// A shell model made of flat 3-node facets.
///
/// `thickness` and `materials` hold either one entry (uniform) or one per triangle, so a
/// layer-age model can give every element its own E. The reference load is
/// `self-weight · gravity + nodal_loads`; buckling factors multiply this whole load.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellModel {
    /// Node coordinates (m).
    pub nodes: Vec<[f64; 3]>,
    /// Triangles as 0-based node indices. Orientation must be consistent across shared edges.
    pub triangles: Vec<[usize; 3]>,
    /// Thickness t (m): one value or one per triangle.
    pub thickness: Vec<f64>,
    /// Material: one or one per triangle.
    pub materials: Vec<Material>,
    /// Supported DOFs. Several entries for one node are combined.
    pub supports: Vec<Support>,
    /// Gravity direction and factor for self-weight: the body force per unit area is
    /// `γ·t·gravity`. Default `[0, 0, −1]`; `[0, 0, 0]` switches self-weight off.
    pub gravity: [f64; 3],
    /// Concentrated loads.
    pub nodal_loads: Vec<NodalLoad>,
    /// Drilling spring factor α: k = α·E·t·A on each node's local θz (default 1e-3,
    /// see buckling.md §2 item 5: α ∈ [1e-6, 1e-2] moves λ₁ by < 0.1 %).
    pub drilling_alpha: f64,
    /// Accept triangles whose orientation disagrees with their neighbours (default `false`:
    /// such a triangle is reported as inverted). The element is orientation-independent
    /// (acceptance check A10), so results do not change; only the local frames of the element
    /// results (top/bottom stresses) then follow each triangle's own normal.
    pub allow_mixed_orientation: bool,
    /// Element formulation (default [`ElementKind::CstDkt`], the reference element of the
    /// fixtures).
    pub element: ElementKind,
}

/// Which facet element [`crate::BucklingSolver::new`] uses. Serialised by its
/// [`ElementKind::name`] (`"cst_dkt"`, `"andes_dkt"`, `"andes_dkmt"`, `"cst_dkmt"`; the short
/// names of [`ElementKind::from_name`] are accepted too), e.g. in a design file's `[analysis]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// CST membrane + DKT plate + drilling spring α·E·t·A ([`crate::element::cst_dkt::CstDkt`]);
    /// the element of `facet_ref_results.json` (A2).
    #[default]
    #[serde(alias = "cst")]
    CstDkt,
    /// ANDES/OPT membrane with drilling freedoms + DKT plate
    /// ([`crate::element::andes_dkt::AndesDkt`]); `drilling_alpha` is not used.
    #[serde(alias = "andes")]
    AndesDkt,
    /// ANDES/OPT membrane + DKMT Reissner–Mindlin plate (transverse shear, κ = 5/6;
    /// [`crate::element::dkmt::AndesDkmt`]); `drilling_alpha` is not used.
    #[serde(alias = "dkmt", alias = "mindlin")]
    AndesDkmt,
    /// CST membrane + drilling spring + DKMT Reissner–Mindlin plate
    /// ([`crate::element::dkmt::CstDkmt`]).
    CstDkmt,
}

impl ElementKind {
    /// Parse the names used in mesh JSON and on the command line: `cst_dkt` / `cst`,
    /// `andes_dkt` / `andes`, `andes_dkmt` / `dkmt` / `mindlin`, `cst_dkmt`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "cst_dkt" | "cst" => Some(Self::CstDkt),
            "andes_dkt" | "andes" => Some(Self::AndesDkt),
            "andes_dkmt" | "dkmt" | "mindlin" => Some(Self::AndesDkmt),
            "cst_dkmt" => Some(Self::CstDkmt),
            _ => None,
        }
    }

    /// The mesh-JSON name.
    pub fn name(self) -> &'static str {
        match self {
            Self::CstDkt => "cst_dkt",
            Self::AndesDkt => "andes_dkt",
            Self::AndesDkmt => "andes_dkmt",
            Self::CstDkmt => "cst_dkmt",
        }
    }

    /// One-line description for reports.
    pub fn description(self) -> &'static str {
        match self {
            Self::CstDkt => "CST + DKT + drilling (alpha = model drilling_alpha)",
            Self::AndesDkt => "ANDES/OPT membrane with drilling freedoms + DKT (Felippa 2003)",
            Self::AndesDkmt => {
                "ANDES/OPT membrane + DKMT Reissner-Mindlin plate, shear factor 5/6 (Katili 1993)"
            }
            Self::CstDkmt => "CST + drilling + DKMT Reissner-Mindlin plate, shear factor 5/6",
        }
    }
}

/// Longest edge / smallest height above which a triangle is rejected as degenerate. Grid
/// triangles have 1.2–2; beyond ~1e3 the element matrices lose most significant digits.
pub const MAX_ASPECT: f64 = 1.0e3;

impl ShellModel {
    /// A model with uniform thickness and material, self-weight along −z, no supports/loads.
    pub fn new(
        nodes: Vec<[f64; 3]>,
        triangles: Vec<[usize; 3]>,
        thickness: f64,
        material: Material,
    ) -> Self {
        Self {
            nodes,
            triangles,
            thickness: vec![thickness],
            materials: vec![material],
            supports: Vec::new(),
            gravity: [0.0, 0.0, -1.0],
            nodal_loads: Vec::new(),
            drilling_alpha: 1.0e-3,
            allow_mixed_orientation: false,
            element: ElementKind::CstDkt,
        }
    }

    /// Thickness of element `e` (after validation, never out of range).
    pub fn thickness_of(&self, e: usize) -> f64 {
        let i = if self.thickness.len() == 1 { 0 } else { e };
        self.thickness.get(i).copied().unwrap_or(0.0)
    }

    /// Material of element `e`.
    pub fn material_of(&self, e: usize) -> Material {
        let i = if self.materials.len() == 1 { 0 } else { e };
        self.materials.get(i).copied().unwrap_or(Material {
            youngs_modulus: 0.0,
            poisson_ratio: 0.0,
            unit_weight: 0.0,
        })
    }

    /// Fixed-DOF mask per node (`n_nodes × 6`), combining all support entries.
    pub fn fixed_mask(&self) -> Vec<[bool; 6]> {
        let mut m = vec![[false; 6]; self.nodes.len()];
        for s in &self.supports {
            if let Some(f) = m.get_mut(s.node) {
                for d in 0..6 {
                    f[d] |= s.fixed[d];
                }
            }
        }
        m
    }

    /// Check the model and return a typed error naming the first problem found.
    ///
    /// Checks: finite numbers; node indices in range; every node used; thickness > 0,
    /// E > 0, −1 < ν < 0.5, γ ≥ 0; no degenerate triangle (repeated nodes, zero area, aspect
    /// ratio > [`MAX_ASPECT`]); unless `allow_mixed_orientation`, consistent orientation
    /// across shared edges (an inverted triangle traverses a shared edge in the same direction
    /// as its neighbour).
    pub fn validate(&self) -> Result<(), FeError> {
        let n_nodes = self.nodes.len();
        let n_el = self.triangles.len();
        if n_nodes == 0 {
            return Err(FeError::Empty { what: "no nodes" });
        }
        if n_el == 0 {
            return Err(FeError::Empty {
                what: "no triangles",
            });
        }
        for (i, p) in self.nodes.iter().enumerate() {
            for (c, v) in p.iter().enumerate() {
                if !v.is_finite() {
                    return Err(FeError::NotFinite {
                        field: format!("nodes[{i}].{}", ["x", "y", "z"][c]),
                        value: *v,
                    });
                }
            }
        }
        for (name, len) in [
            ("thickness", self.thickness.len()),
            ("materials", self.materials.len()),
        ] {
            if len != 1 && len != n_el {
                return Err(FeError::WrongLength {
                    field: name,
                    len,
                    n_elements: n_el,
                });
            }
        }
        for (i, &t) in self.thickness.iter().enumerate() {
            if !t.is_finite() {
                return Err(FeError::NotFinite {
                    field: format!("thickness[{i}]"),
                    value: t,
                });
            }
            if t <= 0.0 {
                return Err(FeError::OutOfRange {
                    field: format!("thickness[{i}]"),
                    value: t,
                    allowed: "> 0 m",
                });
            }
        }
        for (i, m) in self.materials.iter().enumerate() {
            for (name, v) in [
                ("E", m.youngs_modulus),
                ("nu", m.poisson_ratio),
                ("gamma", m.unit_weight),
            ] {
                if !v.is_finite() {
                    return Err(FeError::NotFinite {
                        field: format!("materials[{i}].{name}"),
                        value: v,
                    });
                }
            }
            if m.youngs_modulus <= 0.0 {
                return Err(FeError::OutOfRange {
                    field: format!("materials[{i}].E"),
                    value: m.youngs_modulus,
                    allowed: "> 0 Pa",
                });
            }
            if !(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
                return Err(FeError::OutOfRange {
                    field: format!("materials[{i}].nu"),
                    value: m.poisson_ratio,
                    allowed: "-1 < nu < 0.5",
                });
            }
            if m.unit_weight < 0.0 {
                return Err(FeError::OutOfRange {
                    field: format!("materials[{i}].gamma"),
                    value: m.unit_weight,
                    allowed: ">= 0 N/m³",
                });
            }
        }
        for (c, v) in self.gravity.iter().enumerate() {
            if !v.is_finite() {
                return Err(FeError::NotFinite {
                    field: format!("gravity[{c}]"),
                    value: *v,
                });
            }
        }
        if !(self.drilling_alpha.is_finite() && self.drilling_alpha > 0.0) {
            return Err(FeError::OutOfRange {
                field: "drilling_alpha".into(),
                value: self.drilling_alpha,
                allowed: "> 0 (typically 1e-3)",
            });
        }
        for (i, s) in self.supports.iter().enumerate() {
            if s.node >= n_nodes {
                return Err(FeError::ItemNodeOutOfRange {
                    field: format!("supports[{i}]"),
                    node: s.node,
                    n_nodes,
                });
            }
        }
        for (i, l) in self.nodal_loads.iter().enumerate() {
            if l.node >= n_nodes {
                return Err(FeError::ItemNodeOutOfRange {
                    field: format!("nodal_loads[{i}]"),
                    node: l.node,
                    n_nodes,
                });
            }
            for (c, v) in l.force.iter().chain(l.moment.iter()).enumerate() {
                if !v.is_finite() {
                    return Err(FeError::NotFinite {
                        field: format!(
                            "nodal_loads[{i}].{}",
                            ["fx", "fy", "fz", "mx", "my", "mz"][c]
                        ),
                        value: *v,
                    });
                }
            }
        }
        let mut used = vec![false; n_nodes];
        for (e, tri) in self.triangles.iter().enumerate() {
            for &n in tri {
                match used.get_mut(n) {
                    Some(u) => *u = true,
                    None => {
                        return Err(FeError::NodeOutOfRange {
                            element: e,
                            node: n,
                            n_nodes,
                        });
                    }
                }
            }
            let deg = |area: f64, aspect: f64| FeError::DegenerateTriangle {
                element: e,
                nodes: *tri,
                area,
                aspect,
                max_aspect: MAX_ASPECT,
            };
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return Err(deg(0.0, f64::INFINITY));
            }
            let p = [self.nodes[tri[0]], self.nodes[tri[1]], self.nodes[tri[2]]];
            let (area, aspect) = area_and_aspect(&p);
            if !(area > 0.0 && aspect <= MAX_ASPECT) {
                return Err(deg(area, aspect));
            }
        }
        if let Some(node) = used.iter().position(|u| !u) {
            return Err(FeError::UnreferencedNode { node });
        }
        if self.allow_mixed_orientation {
            return Ok(());
        }
        // Orientation: in a consistently oriented mesh every directed edge occurs at most once.
        let mut directed: HashMap<(usize, usize), usize> = HashMap::with_capacity(3 * n_el);
        for (e, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if let Some(&other) = directed.get(&(a, b)) {
                    return Err(FeError::InvertedTriangle {
                        element: e,
                        neighbour: other,
                        a,
                        b,
                    });
                }
                directed.insert((a, b), e);
            }
        }
        Ok(())
    }
}

/// Aspect ratio above which [`ShellModel::quality_warnings`] flags a triangle (buckling.md §2
/// "Pitfalls": very flat triangles, aspect > 20, lose accuracy but are still solved).
pub const WARN_ASPECT: f64 = 20.0;

impl ShellModel {
    /// Triangles with aspect ratio (longest edge / smallest height) above [`WARN_ASPECT`], as
    /// `(element, aspect)`. They are solved, but CST/DKT accuracy degrades; refine or re-mesh.
    pub fn quality_warnings(&self) -> Vec<(usize, f64)> {
        self.triangles
            .iter()
            .enumerate()
            .filter_map(|(e, t)| {
                let p = [
                    *self.nodes.get(t[0])?,
                    *self.nodes.get(t[1])?,
                    *self.nodes.get(t[2])?,
                ];
                let (_, aspect) = area_and_aspect(&p);
                (aspect > WARN_ASPECT).then_some((e, aspect))
            })
            .collect()
    }
}

/// Area and aspect ratio (longest edge / smallest height = longest edge² / (2·area)).
pub(crate) fn area_and_aspect(p: &[[f64; 3]; 3]) -> (f64, f64) {
    let d = |a: [f64; 3], b: [f64; 3]| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let e1 = d(p[0], p[1]);
    let e2 = d(p[0], p[2]);
    let e3 = d(p[1], p[2]);
    let c = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let area = 0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    let l2 = |v: [f64; 3]| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let lmax2 = l2(e1).max(l2(e2)).max(l2(e3));
    let aspect = if area > 0.0 {
        lmax2 / (2.0 * area)
    } else {
        f64::INFINITY
    };
    (area, aspect)
}
