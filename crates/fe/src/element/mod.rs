//! Shell elements behind one trait, so the membrane can be swapped without touching assembly
//! or the solvers: [`cst_dkt::CstDkt`] (the reference element of the fixtures) and
//! [`andes_dkt::AndesDkt`] (ANDES/OPT membrane with drilling freedoms, Felippa 2003).
//!
//! An element works on one flat triangle with 6 DOFs per node in the **global** frame, DOF
//! order per node `ux, uy, uz, rx, ry, rz`, node-major (18 DOFs). It returns global matrices.

pub mod andes_dkt;
pub mod cst_dkt;
pub mod dkmt;

use nalgebra::SMatrix;

use crate::model::Material;

/// 18×18 element matrix.
pub type Mat18 = SMatrix<f64, 18, 18>;

/// Local frame and 2-D coordinates of a flat triangle (buckling.md §2 item 1).
///
/// `e1 = (X2−X1)/|X2−X1|`, `e3 = (X2−X1)×(X3−X1)/|…|`, `e2 = e3×e1`; node 1 at the origin,
/// node 2 on the local x axis. `frame` holds the rows `[e1; e2; e3]` (= R, local = R·global).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleGeometry {
    /// Rows e1, e2, e3.
    pub frame: [[f64; 3]; 3],
    /// Local x of the three nodes.
    pub x: [f64; 3],
    /// Local y of the three nodes.
    pub y: [f64; 3],
    /// Area (m²).
    pub area: f64,
}

impl TriangleGeometry {
    /// Frame and local coordinates of the triangle `p` (assumed validated: positive area).
    pub fn new(p: &[[f64; 3]; 3]) -> Self {
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let unit = |a: [f64; 3]| {
            let l = dot(a, a).sqrt();
            [a[0] / l, a[1] / l, a[2] / l]
        };
        let d2 = sub(p[1], p[0]);
        let d3 = sub(p[2], p[0]);
        let e1 = unit(d2);
        let e3 = unit(cross(d2, d3));
        let e2 = cross(e3, e1);
        let x = [0.0, dot(d2, e1), dot(d3, e1)];
        let y = [0.0, 0.0, dot(d3, e2)];
        let area = 0.5 * x[1] * y[2];
        Self {
            frame: [e1, e2, e3],
            x,
            y,
            area,
        }
    }
}

/// Stress resultants of one element in its local frame (see [`TriangleGeometry`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Resultants {
    /// Membrane forces `[N_x, N_y, N_xy]` (N/m), tension positive (constant for CST).
    pub membrane: [f64; 3],
    /// Bending moments `[M_x, M_y, M_xy]` (N·m/m) at the centroid, `M = D_b κ`.
    pub moment: [f64; 3],
}

/// A 3-node flat shell element (6 DOF/node).
pub trait ShellElement: Send + Sync {
    /// Global elastic stiffness `Tᵀ K_local T`.
    fn stiffness(&self, g: &TriangleGeometry, t: f64, m: &Material, drilling_alpha: f64) -> Mat18;
    /// Resultants from the element's 18 global displacements.
    fn resultants(&self, g: &TriangleGeometry, t: f64, m: &Material, u: &[f64; 18]) -> Resultants;
    /// The membrane forces of [`Self::resultants`] alone, the same numbers: an element
    /// whose membrane part stands apart computes them without the plate's moments (the
    /// co-rotational facets take 18 of them each, nonlinear::corotational::LocalGeometric).
    fn membrane_resultants(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        u: &[f64; 18],
    ) -> [f64; 3] {
        self.resultants(g, t, m, u).membrane
    }
    /// Global geometric stiffness for constant membrane forces `n = [N_x, N_y, N_xy]`
    /// (tension positive), so that `(K + λ K_G) φ = 0` is the buckling pencil. Thickness and
    /// material are passed because a shear-deformable plate's deflection slopes depend on
    /// them (`∇w = γ − β`, see [`dkmt`]); Kirchhoff elements ignore them.
    fn geometric_stiffness(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        n: &[f64; 3],
    ) -> Mat18;
}

/// Rotate a local 18×18 matrix to the global frame: `Tᵀ K T`, T = blockdiag(R ×6).
pub(crate) fn to_global(k: &Mat18, frame: &[[f64; 3]; 3]) -> Mat18 {
    let mut out = Mat18::zeros();
    to_global_into(k, frame, &mut out);
    out
}

/// [`to_global`] written into `out` (every entry; a zero block of `k` gives a zero block).
pub(crate) fn to_global_into(k: &Mat18, frame: &[[f64; 3]; 3], out: &mut Mat18) {
    let r = nalgebra::Matrix3::from_fn(|i, j| frame[i][j]);
    let rt = r.transpose();
    for a in 0..6 {
        for b in 0..6 {
            let blk = k.fixed_view::<3, 3>(3 * a, 3 * b).into_owned();
            let mut dst = out.fixed_view_mut::<3, 3>(3 * a, 3 * b);
            if blk.iter().all(|v| *v == 0.0) {
                dst.fill(0.0);
                continue;
            }
            dst.copy_from(&(rt * blk * r));
        }
    }
}

/// Rotate global 18 displacements to local ones: `T u`.
pub(crate) fn to_local(u: &[f64; 18], frame: &[[f64; 3]; 3]) -> [f64; 18] {
    let mut out = [0.0; 18];
    for blk in 0..6 {
        for (i, row) in frame.iter().enumerate() {
            out[3 * blk + i] = (0..3).map(|j| row[j] * u[3 * blk + j]).sum();
        }
    }
    out
}

// Here, not in `model`, so the model (plain data) does not import the elements that read it.
impl crate::model::ElementKind {
    /// The element implementation.
    pub fn implementation(self) -> Box<dyn ShellElement> {
        match self {
            Self::CstDkt => Box::new(cst_dkt::CstDkt),
            Self::AndesDkt => Box::new(andes_dkt::AndesDkt),
            Self::AndesDkmt => Box::new(dkmt::AndesDkmt),
            Self::CstDkmt => Box::new(dkmt::CstDkmt),
        }
    }
}
