//! ANDES/OPT membrane with drilling freedoms + DKT plate: the second facet element.
//!
//! Hand-written because no Rust crate provides shell elements. The membrane is Felippa's
//! optimal 3-node membrane triangle (OPT), an instance of the ANDES template (Felippa, CMAME 192
//! (2003) 2125–2168; Alvin, de la Fuente, Haugen & Felippa, FEAD 12 (1992) 163–187; Felippa &
//! Militello, FEAD 12 (1992) 189–201). Local membrane DOFs per node `(u, v, θz)`, θz the
//! counter-clockwise rotation about the facet normal, `K_m = K_b + K_h`:
//!
//! * **Basic stiffness** (free formulation, Bergan & Felippa 1985): `K_b = L C Lᵀ / V`, V = A t,
//!   C the plane-stress stress–strain matrix and L (9×3) the force-lumping matrix of a constant
//!   boundary traction with the edge displacement made quadratic by the corner rotations
//!   (weight α_b): node 1 rows `t/2·[y23, 0, x32]`, `t/2·[0, x32, y23]`,
//!   `t/2·α_b/6·[y23(y13−y21), x32(x31−x12), 2(x31 y13 − x12 y21)]`, nodes 2, 3 cyclically
//!   (x_ij = x_i − x_j). Its mean strain `ε̄ = Lᵀu/V` is the element's membrane strain (used for
//!   N and hence for K_G).
//! * **Higher-order stiffness** (ANDES): hierarchical rotations `θ̃ = T_θu u`,
//!   `θ̃_i = θ_i − θ_0` with `θ_0 = (v,x − u,y)/2` the CST rotation; corner natural strains
//!   (along the sides 12, 23, 31) `ε_n,i = Q_i θ̃` with `Q_1 = (2A/3)[β1 β2 β3; β4 β5 β6; β7 β8 β9]`
//!   (row k divided by the squared length of side k), Q_2, Q_3 by cyclic permutation of the β's;
//!   Cartesian strains `ε = T_e ε_n`. `K_h = (3/4) β0 V T_θuᵀ (Σ_{k=4,5,6} Q_kᵀ T_eᵀ C T_e Q_k) T_θu`
//!   with Q_4..6 the mid-side averages. The 3/4 normalisation is the one for which the bending
//!   test below is exact (Felippa's optimality criterion: exact in-plane pure bending of
//!   rectangular mesh units of any aspect ratio; tested in `tests/it/andes.rs`).
//! * **OPT signature**: α_b = 3/2, β0 = max(½(1 − 4ν²), 0.01), (β1…β9) = (1, 2, 1, 0, 1, −1,
//!   −1, −1, −2). The β's sum to zero over each natural-strain row at the centroid, so the
//!   higher-order strain vanishes there (energy orthogonality: the patch test is passed by
//!   K_b alone, and rigid motions — θ_i = θ_0 — cost no energy).
//!
//! Bending is DKT exactly as in [`super::cst_dkt`]; the geometric stiffness is the same
//! (membrane forces + DKT rotation field), evaluated with the ANDES mean membrane forces.
//! No drilling spring: θz is a true rotation here, so `drilling_alpha` is ignored.

use nalgebra::{Matrix3, SMatrix};

use super::cst_dkt::{CstDkt, add_dkt_bending, dkt_centroid_moment, plane_stress};
use super::{Mat18, Resultants, ShellElement, TriangleGeometry, to_global, to_local};
use crate::model::Material;

/// ANDES/OPT membrane + DKT plate (drilling DOF with real stiffness, no spring).
#[derive(Debug, Clone, Copy, Default)]
pub struct AndesDkt;

type Mat9 = SMatrix<f64, 9, 9>;
type L9x3 = SMatrix<f64, 9, 3>;

/// Local 18-DOF index of the membrane DOFs (u, v, θz) of the three nodes.
const MEMB: [usize; 9] = [0, 1, 5, 6, 7, 11, 12, 13, 17];

/// α_b of the OPT element.
const ALPHA_B: f64 = 1.5;
/// β1…β9 of the OPT element (Felippa 2003).
const BETA: [f64; 9] = [1.0, 2.0, 1.0, 0.0, 1.0, -1.0, -1.0, -1.0, -2.0];

/// β0 of the OPT element for an isotropic material: max(½(1 − 4ν²), 0.01).
pub fn opt_beta0(nu: f64) -> f64 {
    (0.5 * (1.0 - 4.0 * nu * nu)).max(0.01)
}

/// Triangle differences in the ANDES notation (x_ij = x_i − x_j, 1-based names).
struct Diff {
    x12: f64,
    x21: f64,
    x13: f64,
    x31: f64,
    x23: f64,
    x32: f64,
    y12: f64,
    y21: f64,
    y13: f64,
    y31: f64,
    y23: f64,
    y32: f64,
}

impl Diff {
    fn new(g: &TriangleGeometry) -> Self {
        let (x, y) = (g.x, g.y);
        Self {
            x12: x[0] - x[1],
            x21: x[1] - x[0],
            x13: x[0] - x[2],
            x31: x[2] - x[0],
            x23: x[1] - x[2],
            x32: x[2] - x[1],
            y12: y[0] - y[1],
            y21: y[1] - y[0],
            y13: y[0] - y[2],
            y31: y[2] - y[0],
            y23: y[1] - y[2],
            y32: y[2] - y[1],
        }
    }
}

/// Force-lumping matrix L (9×3) with the thickness factor t/2.
fn lumping(g: &TriangleGeometry, t: f64) -> L9x3 {
    let d = Diff::new(g);
    let ab = ALPHA_B;
    let rows: [[f64; 3]; 9] = [
        [d.y23, 0.0, d.x32],
        [0.0, d.x32, d.y23],
        [
            ab / 6.0 * d.y23 * (d.y13 - d.y21),
            ab / 6.0 * d.x32 * (d.x31 - d.x12),
            ab / 3.0 * (d.x31 * d.y13 - d.x12 * d.y21),
        ],
        [d.y31, 0.0, d.x13],
        [0.0, d.x13, d.y31],
        [
            ab / 6.0 * d.y31 * (d.y21 - d.y32),
            ab / 6.0 * d.x13 * (d.x12 - d.x23),
            ab / 3.0 * (d.x12 * d.y21 - d.x23 * d.y32),
        ],
        [d.y12, 0.0, d.x21],
        [0.0, d.x21, d.y12],
        [
            ab / 6.0 * d.y12 * (d.y32 - d.y13),
            ab / 6.0 * d.x21 * (d.x23 - d.x31),
            ab / 3.0 * (d.x23 * d.y32 - d.x31 * d.y13),
        ],
    ];
    L9x3::from_fn(|i, j| rows[i][j] * t / 2.0)
}

/// Higher-order stiffness K_h (9×9) of the OPT element.
fn higher_order(g: &TriangleGeometry, t: f64, c: &Matrix3<f64>, beta0: f64) -> Mat9 {
    let d = Diff::new(g);
    let a = g.area;
    let l21 = d.x21 * d.x21 + d.y21 * d.y21;
    let l32 = d.x32 * d.x32 + d.y32 * d.y32;
    let l13 = d.x13 * d.x13 + d.y13 * d.y13;
    // Hierarchical rotations θ̃ = T_θu u.
    let mut tth = SMatrix::<f64, 3, 9>::zeros();
    for i in 0..3 {
        let row = [d.x32, d.y32, 0.0, d.x13, d.y13, 0.0, d.x21, d.y21, 0.0];
        for j in 0..9 {
            tth[(i, j)] = row[j] / (4.0 * a);
        }
        tth[(i, 3 * i + 2)] += 1.0;
    }
    // Natural strains (sides 12, 23, 31) → Cartesian strains.
    let te = Matrix3::new(
        d.y23 * d.y13 * l21,
        d.y31 * d.y21 * l32,
        d.y12 * d.y32 * l13,
        d.x23 * d.x13 * l21,
        d.x31 * d.x21 * l32,
        d.x12 * d.x32 * l13,
        (d.y23 * d.x31 + d.x32 * d.y13) * l21,
        (d.y31 * d.x12 + d.x13 * d.y21) * l32,
        (d.y12 * d.x23 + d.x21 * d.y32) * l13,
    ) / (4.0 * a * a);
    let b = BETA;
    let q = |p: [usize; 9]| {
        let f = 2.0 * a / 3.0;
        Matrix3::new(
            f * b[p[0]] / l21,
            f * b[p[1]] / l21,
            f * b[p[2]] / l21,
            f * b[p[3]] / l32,
            f * b[p[4]] / l32,
            f * b[p[5]] / l32,
            f * b[p[6]] / l13,
            f * b[p[7]] / l13,
            f * b[p[8]] / l13,
        )
    };
    // Corner matrices: β indices (0-based) in Felippa's cyclic arrangement.
    let q1 = q([0, 1, 2, 3, 4, 5, 6, 7, 8]);
    let q2 = q([8, 6, 7, 2, 0, 1, 5, 3, 4]);
    let q3 = q([4, 5, 3, 7, 8, 6, 1, 2, 0]);
    let enat = te.transpose() * c * te;
    let mut kth = Matrix3::zeros();
    for qk in [(q1 + q2) * 0.5, (q2 + q3) * 0.5, (q3 + q1) * 0.5] {
        kth += qk.transpose() * enat * qk;
    }
    tth.transpose() * kth * tth * (0.75 * beta0 * a * t)
}

impl AndesDkt {
    /// Local ANDES/OPT membrane stiffness (9×9) on `(u1, v1, θz1, …, θz3)`.
    pub fn membrane_stiffness(g: &TriangleGeometry, t: f64, m: &Material) -> Mat9 {
        let c = plane_stress(m.poisson_ratio, m.youngs_modulus);
        let l = lumping(g, t);
        let kb = l * c * l.transpose() / (g.area * t);
        kb + higher_order(g, t, &c, opt_beta0(m.poisson_ratio))
    }

    /// Local 18×18 matrix with only the ANDES membrane block (u, v, θz) filled.
    pub(crate) fn local_membrane(g: &TriangleGeometry, t: f64, m: &Material) -> Mat18 {
        let km = Self::membrane_stiffness(g, t, m);
        let mut k = Mat18::zeros();
        for (i, &gi) in MEMB.iter().enumerate() {
            for (j, &gj) in MEMB.iter().enumerate() {
                k[(gi, gj)] = km[(i, j)];
            }
        }
        k
    }

    /// Local (element-frame) elastic stiffness, 18×18, node-major (u, v, w, θx, θy, θz).
    pub fn local_stiffness(g: &TriangleGeometry, t: f64, m: &Material) -> Mat18 {
        let mut k = Self::local_membrane(g, t, m);
        add_dkt_bending(&mut k, g, t, m);
        k
    }

    /// Membrane forces `N = t C ε̄` from the mean strain (= the centroid strain).
    pub(crate) fn membrane_forces(
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        ul: &[f64; 18],
    ) -> [f64; 3] {
        let n = plane_stress(m.poisson_ratio, m.youngs_modulus * t) * Self::mean_strain(g, ul);
        [n[0], n[1], n[2]]
    }

    /// Mean membrane strain `ε̄ = Lᵀ u_m / V` = `[ε_x, ε_y, γ_xy]` from local displacements.
    fn mean_strain(g: &TriangleGeometry, ul: &[f64; 18]) -> SMatrix<f64, 3, 1> {
        // L is proportional to t, V = A t: use t = 1.
        let l = lumping(g, 1.0);
        let um = SMatrix::<f64, 9, 1>::from_fn(|i, _| ul[MEMB[i]]);
        l.transpose() * um / g.area
    }
}

impl ShellElement for AndesDkt {
    /// `drilling_alpha` is ignored: the ANDES membrane gives θz its own stiffness.
    fn stiffness(&self, g: &TriangleGeometry, t: f64, m: &Material, _drilling_alpha: f64) -> Mat18 {
        to_global(&Self::local_stiffness(g, t, m), &g.frame)
    }

    /// Membrane forces from the mean strain `N = t C ε̄` (equal to the strain at the
    /// centroid: the OPT higher-order strain vanishes there); DKT moments at the centroid.
    fn resultants(&self, g: &TriangleGeometry, t: f64, m: &Material, u: &[f64; 18]) -> Resultants {
        let ul = to_local(u, &g.frame);
        Resultants {
            membrane: Self::membrane_forces(g, t, m, &ul),
            moment: dkt_centroid_moment(g, t, m, &ul),
        }
    }

    fn membrane_resultants(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        u: &[f64; 18],
    ) -> [f64; 3] {
        Self::membrane_forces(g, t, m, &to_local(u, &g.frame))
    }

    fn geometric_stiffness(
        &self,
        g: &TriangleGeometry,
        _t: f64,
        _m: &Material,
        n: &[f64; 3],
    ) -> Mat18 {
        to_global(&CstDkt::local_geometric_stiffness(g, n), &g.frame)
    }
}
