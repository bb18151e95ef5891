//! Geometrically nonlinear statics: co-rotational flat shells, Newton–Raphson with path
//! following (load control or Crisfield's cylindrical arc length), limit-point detection,
//! imperfections from buckling modes, and stresses in the deformed state.
//!
//! * [`corotational`]: the element-independent co-rotational (EICR) wrapper of the linear
//!   facet elements of [`crate::element`] — small strains, large rotations. Internal force
//!   `f = Tᵀ Pᵀ Hᵀ K̄ d̄` and its consistent tangent (material + rotational, projector and
//!   moment-correction geometric terms), assembled symmetrised.
//! * [`nonlinear_path`] traces `f_int(u) = λ q` (q: the model's reference load, self-weight
//!   plus nodal loads, as in [`crate::buckling`]) with the arc-length constraint of Crisfield
//!   (1981), cylindrical form `‖Δu‖²_W = Δl²` (no load term, ψ = 0), `W` weighting rotations
//!   by a length ℓ² so that the norm has one unit (m²). Each iteration solves
//!   `K_T δu_r = r`, `K_T δu_t = q` with one LDLᵀ factor and takes
//!   `δu = δu_r + δλ δu_t`, δλ the root of `a δλ² + b δλ + c = 0`
//!   (`a = ‖δu_t‖²_W`, `b = 2⟨Δu + δu_r, δu_t⟩_W`, `c = ‖Δu + δu_r‖²_W − Δl²`) closest in
//!   direction to the step so far. The predictor's sign follows the previous step
//!   (`sign⟨δu_t, Δu_prev⟩_W`, Feng et al. 1996), which turns at limit points and snap-backs.
//!   Step length: `Δl ← Δl·clamp(√(n_target/n_iter), ½, 2)`, halved on failure.
//! * Limit points: a step whose λ drops after a rise is past a load maximum; the maximum is
//!   refined by a parabola through the three steps around it in the path's arc length. The
//!   LDLᵀ of every converged tangent also gives its inertia (number of negative pivots =
//!   negative eigenvalues, Sylvester): a rise in that count without a load maximum is a
//!   bifurcation (the perfect structure's path crosses a critical point).
//! * [`with_imperfection`] adds a scaled mode (e.g. of [`crate::buckling`]) to the nodes;
//!   [`deformed_resultants`] gives membrane forces, moments and stresses of a path state.
//!
//! Hand-written: no Rust crate provides co-rotational shells or arc-length continuation.
//! The sparse pattern, the symbolic factorization (AMD) and faer's numeric LDLᵀ are those of
//! the linear solvers; the symbolic step is done once per path.

pub mod corotational;
mod path;

pub use path::{
    LimitKind, LimitPoint, Path, PathControl, PathOptions, PathStats, PathStep, StopReason,
    nonlinear_path,
};

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use crate::assembly::{DofMap, Pattern, geometries, load_vector, scatter};
use crate::element::ShellElement;
use crate::error::FeError;
use crate::model::ShellModel;
use crate::solver::ElementResult;
use corotational::{CrElement, Vec18, rot_exp, rot_log};

/// Node positions and rotations of a configuration.
#[derive(Debug, Clone)]
pub(crate) struct State {
    pub(crate) x: Vec<Vector3<f64>>,
    pub(crate) r: Vec<Matrix3<f64>>,
}

impl State {
    fn initial(model: &ShellModel) -> Self {
        Self {
            x: model
                .nodes
                .iter()
                .map(|p| Vector3::new(p[0], p[1], p[2]))
                .collect(),
            r: vec![Matrix3::identity(); model.nodes.len()],
        }
    }

    fn from_displacements(model: &ShellModel, u: &[[f64; 6]]) -> Self {
        Self {
            x: model
                .nodes
                .iter()
                .zip(u)
                .map(|(p, d)| Vector3::new(p[0] + d[0], p[1] + d[1], p[2] + d[2]))
                .collect(),
            r: u.iter()
                .map(|d| rot_exp(&Vector3::new(d[3], d[4], d[5])))
                .collect(),
        }
    }

    /// Per node `[ux, uy, uz, rx, ry, rz]`, rotations as rotation vectors (|θ| ≤ π).
    fn displacements(&self, model: &ShellModel) -> Vec<[f64; 6]> {
        self.x
            .iter()
            .zip(&self.r)
            .zip(&model.nodes)
            .map(|((x, r), p)| {
                let th = rot_log(r);
                [x.x - p[0], x.y - p[1], x.z - p[2], th.x, th.y, th.z]
            })
            .collect()
    }
}

/// The discretised problem: DOF numbering, pattern, symbolic factorization, elements, load.
pub(crate) struct Problem<'m> {
    pub(crate) model: &'m ShellModel,
    pub(crate) dofs: DofMap,
    pub(crate) pattern: Pattern,
    pub(crate) symbolic: crate::factor::Symbolic,
    elements: Vec<CrElement>,
    /// Reference load on the free DOFs.
    pub(crate) q: Vec<f64>,
    /// Arc-length weight per free DOF (1 on translations, ℓ² on rotations).
    pub(crate) weight: Vec<f64>,
}

fn co_rotational_elements(model: &ShellModel) -> Vec<CrElement> {
    let geo = geometries(model);
    let el: Box<dyn ShellElement> = model.element.implementation();
    let alpha = model.drilling_alpha;
    (0..model.triangles.len())
        .into_par_iter()
        .map(|e| {
            let k = el.stiffness(&geo[e], model.thickness_of(e), &model.material_of(e), alpha);
            CrElement::new(&geo[e], &k)
        })
        .collect()
}

impl<'m> Problem<'m> {
    pub(crate) fn new(
        model: &'m ShellModel,
        rotation_length: Option<f64>,
    ) -> Result<Self, FeError> {
        model.validate()?;
        let dofs = DofMap::new(model);
        if dofs.n_free() == 0 {
            return Err(FeError::NoFreeDofs);
        }
        let pattern = Pattern::new(model, &dofs);
        let symbolic = crate::factor::Symbolic::new(&pattern)?;
        let geo = geometries(model);
        let f = load_vector(model, &geo);
        let q: Vec<f64> = dofs.free.iter().map(|&g| f[g]).collect();
        if q.iter().all(|v| *v == 0.0) {
            return Err(FeError::Empty {
                what: "reference load (self-weight and nodal loads on free DOFs are all zero)",
            });
        }
        let ell = match rotation_length {
            Some(l) => l,
            None => {
                let mut sum = 0.0;
                for t in &model.triangles {
                    for k in 0..3 {
                        let (a, b) = (model.nodes[t[k]], model.nodes[t[(k + 1) % 3]]);
                        sum +=
                            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2))
                                .sqrt();
                    }
                }
                sum / (3.0 * model.triangles.len() as f64)
            }
        };
        let weight = dofs
            .free
            .iter()
            .map(|&g| if g % 6 < 3 { 1.0 } else { ell * ell })
            .collect();
        Ok(Self {
            model,
            dofs,
            pattern,
            symbolic,
            elements: co_rotational_elements(model),
            q,
            weight,
        })
    }

    /// Internal force on the free DOFs and, if asked, the lower values of the symmetrised
    /// tangent.
    pub(crate) fn evaluate(
        &self,
        st: &State,
        tangent: bool,
    ) -> Result<(Vec<f64>, Option<Vec<f64>>), FeError> {
        let model = self.model;
        let mut fg = vec![0.0; 6 * model.nodes.len()];
        let mut kv = tangent.then(|| vec![0.0; self.pattern.nnz()]);
        const CHUNK: usize = 2048;
        let n_el = model.triangles.len();
        let mut start = 0;
        while start < n_el {
            let end = (start + CHUNK).min(n_el);
            let out: Vec<(Vec18, Option<crate::element::Mat18>)> = (start..end)
                .into_par_iter()
                .map(|e| {
                    let t = &model.triangles[e];
                    let x = [st.x[t[0]], st.x[t[1]], st.x[t[2]]];
                    let r = [&st.r[t[0]], &st.r[t[1]], &st.r[t[2]]];
                    let (f, k) = self.elements[e].force_tangent(&x, &r, tangent);
                    (f, k.map(|k| (k + k.transpose()) * 0.5))
                })
                .collect();
            for (e, (f, k)) in (start..end).zip(out) {
                let t = &model.triangles[e];
                for (a, &n) in t.iter().enumerate() {
                    for d in 0..6 {
                        fg[6 * n + d] += f[6 * a + d];
                    }
                }
                if let (Some(k), Some(vals)) = (k, kv.as_mut()) {
                    scatter(model, &self.dofs, &self.pattern, e, &k, vals)?;
                }
            }
            start = end;
        }
        let f = self.dofs.free.iter().map(|&g| fg[g]).collect();
        Ok((f, kv))
    }

    /// Apply a free-DOF increment: translations add, rotations `R ← exp(spin Δω) R`.
    pub(crate) fn apply(&self, st: &mut State, du: &[f64]) {
        let mut spins: Vec<(usize, Vector3<f64>)> = Vec::new();
        let mut last = usize::MAX;
        for (i, &g) in self.dofs.free.iter().enumerate() {
            let (n, d) = (g / 6, g % 6);
            if d < 3 {
                st.x[n][d] += du[i];
            } else {
                if last != n {
                    spins.push((n, Vector3::zeros()));
                    last = n;
                }
                if let Some(s) = spins.last_mut() {
                    s.1[d - 3] += du[i];
                }
            }
        }
        for (n, w) in spins {
            st.r[n] = rot_exp(&w) * st.r[n];
        }
    }
}

/// A copy of `model` with `shape` (per node `[ux, uy, uz, …]`, e.g. a mode of
/// [`crate::buckling`]) added to the node coordinates, scaled so that its largest
/// translation magnitude is `w0` (m; the sign of `w0` flips the shape). Rotations of
/// `shape` are ignored: a facet model's geometry is its node positions.
pub fn with_imperfection(
    model: &ShellModel,
    shape: &[[f64; 6]],
    w0: f64,
) -> Result<ShellModel, FeError> {
    if shape.len() != model.nodes.len() {
        return Err(FeError::OutOfRange {
            field: "imperfection shape length".into(),
            value: shape.len() as f64,
            allowed: "one entry per node",
        });
    }
    if !w0.is_finite() {
        return Err(FeError::NotFinite {
            field: "w0".into(),
            value: w0,
        });
    }
    let amax = shape
        .iter()
        .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
        .fold(0.0, f64::max);
    if !amax.is_finite() {
        return Err(FeError::NotFinite {
            field: "imperfection shape".into(),
            value: amax,
        });
    }
    let mut out = model.clone();
    if w0 == 0.0 {
        return Ok(out);
    }
    if amax == 0.0 {
        return Err(FeError::OutOfRange {
            field: "imperfection shape (largest translation)".into(),
            value: 0.0,
            allowed: "> 0 when w0 ≠ 0",
        });
    }
    let s = w0 / amax;
    for (p, d) in out.nodes.iter_mut().zip(shape) {
        for c in 0..3 {
            p[c] += s * d[c];
        }
    }
    Ok(out)
}

/// Element results in a deformed state given by `displacements` (e.g.
/// [`PathStep::displacements`]): membrane forces, moments and stresses from the
/// deformational displacements (small strains), each in the element's **current** frame
/// (rows e₁, e₂, e₃ of the deformed facet).
pub fn deformed_resultants(
    model: &ShellModel,
    displacements: &[[f64; 6]],
) -> Result<Vec<ElementResult>, FeError> {
    model.validate()?;
    if displacements.len() != model.nodes.len() {
        return Err(FeError::OutOfRange {
            field: "displacements length".into(),
            value: displacements.len() as f64,
            allowed: "one entry per node",
        });
    }
    let st = State::from_displacements(model, displacements);
    let geo = geometries(model);
    let el: Box<dyn ShellElement> = model.element.implementation();
    let alpha = model.drilling_alpha;
    Ok(model
        .triangles
        .par_iter()
        .enumerate()
        .map(|(e, t)| {
            let (th, mat) = (model.thickness_of(e), model.material_of(e));
            let k = el.stiffness(&geo[e], th, &mat, alpha);
            let cr = CrElement::new(&geo[e], &k);
            let x = [st.x[t[0]], st.x[t[1]], st.x[t[2]]];
            let r = [&st.r[t[0]], &st.r[t[1]], &st.r[t[2]]];
            let kin = cr.kinematics(&x, &r);
            let dg = cr.deformational_global(&kin);
            let tn = kin.tn;
            ElementResult {
                frame: std::array::from_fn(|i| [tn[(i, 0)], tn[(i, 1)], tn[(i, 2)]]),
                resultants: el.resultants(&geo[e], th, &mat, &dg),
                thickness: th,
            }
        })
        .collect())
}
