//! Shear-deformable (Reissner–Mindlin) facet shells: the **DKMT** plate (Discrete
//! Kirchhoff–Mindlin Triangle) with the ANDES/OPT or the CST membrane.
//!
//! Hand-written because no Rust crate provides shell elements.
//!
//! # Why DKMT
//! The printed shells are thick (span/t ≈ 40), so transverse shear matters (≈ 0.5–3 % on the
//! buckling factor), but the meshes are triangles and the thin cases must stay as accurate as
//! DKT. DKMT (Katili, IJNME 36 (1993) 1859–1883, "A new discrete Kirchhoff–Mindlin element
//! based on Mindlin–Reissner plate theory and assumed shear strain fields, part I"; Batoz &
//! Katili 1992) is the Mindlin generalisation of DKT:
//! * it has the DOFs, the cost and the sparsity of DKT (3 nodes × (w, θx, θy));
//! * it **is** DKT when t → 0 (φ_k → 0 below), so it cannot lock and keeps DKT's fast
//!   convergence on thin shells — the A-checks of buckling.md §7 are unchanged in practice;
//! * it converges to the Mindlin solution for thick plates.
//!
//! The alternatives considered: MITC3 locks mildly and converges slowly on coarse meshes;
//! MITC3+ (Lee, Lee & Bathe, C&S 138 (2014)) needs a condensed cubic bubble and is still
//! stiffer than DKT on the coarse thin meshes the cap uses; DSG3/CS-DSG3 (Bletzinger 2000,
//! Nguyen-Thoi 2012) needs a stabilisation parameter (α h²/t²) that trades thin accuracy;
//! MITC4/quadratic elements would need quad/6-node meshes of the print states. DKMT gives the
//! Mindlin physics at exactly the cost of the present element, which is what "accuracy per
//! second" on the cap meshes asks for.
//!
//! # Formulation (local frame of the facet, sign convention of [`super::cst_dkt`])
//! Nodal bending DOFs `U_b = (w_i, θx_i, θy_i)`, θx = ∂w/∂y, θy = −∂w/∂x in the Kirchhoff
//! limit; the normal rotations `β = (β_x, β_y) = (θy, −θx)`; Mindlin shear `γ = ∇w + β`.
//! * **Rotations**: `β = Σ_i λ_i β_i + Σ_k 4 λ_i λ_j s_k Δβ_k`, λ the area coordinates, edge
//!   k = (i, j) with unit tangent `s_k`, length `L_k`, `Δβ_k` the mid-side tangential rotation
//!   increment (quadratic along the edge, normal rotation linear: as DKT).
//! * **Edge shear** (kinematics, exact integral of `γ_s = w,s + β_s` along the edge):
//!   `γ_k = (w_j − w_i)/L_k + (β_si + β_sj)/2 + (2/3) Δβ_k`.
//! * **Discrete equilibrium** along the edge (cylindrical bending, `T_s = D ∂²β_s/∂s²` and
//!   `∂²β_s/∂s² = −8 Δβ_k / L_k²`): `γ_k = T_s/D_s = −(2/3) φ_k Δβ_k` with
//!   `φ_k = 12 D / (D_s L_k²) = 2/(κ(1−ν)) (t/L_k)²`, `D = E t³/(12(1−ν²))`,
//!   `D_s = κ G t`, κ = 5/6. Eliminating γ_k:
//!   `Δβ_k = −(3/2)/(1+φ_k) · [(w_j − w_i)/L_k + (β_si + β_sj)/2]` (DKT for φ_k = 0).
//! * **Assumed shear field** inside the element: the lowest-order Nédélec (rotated
//!   Raviart–Thomas) field `γ = a + c (−(y − y_c), x − x_c)` whose tangential component on
//!   each edge is the constant γ_k — the same space as the MITC3 tying.
//! * Stiffness `K = ∫ B_bᵀ D_b B_b dA + ∫ B_sᵀ D_s B_s dA` (3 mid-side points, exact: both B
//!   linear), `κ = [β_x,x; β_y,y; β_x,y + β_y,x]`.
//! * **Geometric stiffness** (shear-consistent): the slopes that the membrane forces act on
//!   are those of the deflection, `∇w = γ − β`, not the rotations alone:
//!   `K_G,w = ∫ (B_s − H_β)ᵀ N̂ (B_s − H_β) dA` (6-point degree-4 rule, exact), plus the
//!   in-plane `u, v` terms as in [`super::cst_dkt`]. With `∇w ≈ −β` (DKT's choice) the
//!   thick-plate factor misses the Mindlin closed form (test
//!   `mindlin::geometric_stiffness_needs_shear_slope`).
//!
//! The membrane is either Felippa's ANDES/OPT triangle with drilling freedoms
//! ([`super::andes_dkt::AndesDkt::membrane_stiffness`], [`AndesDkmt`], the default element)
//! or the CST with the weak drilling spring ([`CstDkmt`]); membrane and plate are uncoupled
//! on the flat facet.

use nalgebra::{Matrix2, SMatrix};

use super::andes_dkt::AndesDkt;
use super::cst_dkt::{BEND, CstDkt, GAUSS6, MIDSIDE, add_cst_membrane, plane_stress};
use super::{Mat18, Resultants, ShellElement, TriangleGeometry, to_global, to_local};
use crate::model::Material;

/// Shear correction factor κ of the Reissner–Mindlin plate (5/6, Reissner 1945).
pub const SHEAR_CORRECTION: f64 = 5.0 / 6.0;

type Mat9 = SMatrix<f64, 9, 9>;
type Row9 = SMatrix<f64, 1, 9>;
type B2x9 = SMatrix<f64, 2, 9>;
type B3x9 = SMatrix<f64, 3, 9>;

/// Edges k = 0, 1, 2 ↔ node pairs (2,3), (3,1), (1,2) (DKT's sides 4, 5, 6).
const SIDES: [(usize, usize); 3] = [(1, 2), (2, 0), (0, 1)];

/// The DKMT plate of one triangle: everything that depends on the geometry and φ_k.
pub struct Dkmt {
    /// Gradients of λ_i: (∂λ_i/∂x, ∂λ_i/∂y).
    b: [f64; 3],
    c: [f64; 3],
    /// Unit tangents s_k of the edges.
    s: [[f64; 2]; 3],
    /// Rows Δβ_k = dbeta[k] · U_b.
    dbeta: [Row9; 3],
    /// Assumed shear coefficients (a_x, a_y, c) = `shear_coef · U_b`.
    shear_coef: SMatrix<f64, 3, 9>,
    /// Local coordinates and centroid.
    x: [f64; 3],
    y: [f64; 3],
    xc: f64,
    yc: f64,
    area: f64,
}

impl Dkmt {
    /// The plate of `g` with bending stiffness `d` and shear stiffness `ds` (φ_k = 12 d /
    /// (ds L_k²)); `ds = ∞` (or `d = 0`) gives DKT.
    pub fn new(g: &TriangleGeometry, d: f64, ds: f64) -> Self {
        let (x, y) = (g.x, g.y);
        let two_a = 2.0 * g.area;
        let b = [
            (y[1] - y[2]) / two_a,
            (y[2] - y[0]) / two_a,
            (y[0] - y[1]) / two_a,
        ];
        let c = [
            (x[2] - x[1]) / two_a,
            (x[0] - x[2]) / two_a,
            (x[1] - x[0]) / two_a,
        ];
        let xc = (x[0] + x[1] + x[2]) / 3.0;
        let yc = (y[0] + y[1] + y[2]) / 3.0;
        let mut s = [[0.0; 2]; 3];
        let mut dbeta = [Row9::zeros(); 3];
        let mut gamma = SMatrix::<f64, 3, 9>::zeros();
        let mut m = nalgebra::Matrix3::zeros();
        for (k, &(i, j)) in SIDES.iter().enumerate() {
            let (dx, dy) = (x[j] - x[i], y[j] - y[i]);
            let l = (dx * dx + dy * dy).sqrt();
            let (sx, sy) = (dx / l, dy / l);
            s[k] = [sx, sy];
            let phi = if ds.is_finite() {
                12.0 * d / (ds * l * l)
            } else {
                0.0
            };
            // Δβ_k = −(3/2)/(1+φ)·[(w_j − w_i)/L + (β_si + β_sj)/2], β_s = s_x θy − s_y θx.
            let f = -1.5 / (1.0 + phi);
            let mut row = Row9::zeros();
            row[3 * i] = -f / l;
            row[3 * j] = f / l;
            for n in [i, j] {
                row[3 * n + 1] += f * (-sy) / 2.0;
                row[3 * n + 2] += f * sx / 2.0;
            }
            dbeta[k] = row;
            // γ_k = −(2/3) φ Δβ_k.
            let grow = row * (-2.0 / 3.0 * phi);
            for q in 0..9 {
                gamma[(k, q)] = grow[q];
            }
            // Tangential component of a + c(−(y−yc), x−xc) on edge k (constant along it).
            m[(k, 0)] = sx;
            m[(k, 1)] = sy;
            m[(k, 2)] = (x[i] - xc) * sy - (y[i] - yc) * sx;
        }
        // M is invertible for any non-degenerate triangle (validated upstream); the fallback
        // keeps the element finite (no shear) instead of panicking.
        let shear_coef = m
            .try_inverse()
            .map_or_else(SMatrix::<f64, 3, 9>::zeros, |mi| mi * gamma);
        Self {
            b,
            c,
            s,
            dbeta,
            shear_coef,
            x,
            y,
            xc,
            yc,
            area: g.area,
        }
    }

    /// Area coordinates of the point (ξ, η): λ = (1 − ξ − η, ξ, η).
    fn lambda(xi: f64, eta: f64) -> [f64; 3] {
        [1.0 - xi - eta, xi, eta]
    }

    /// Rotations `β = H_β U_b` (2×9) at (ξ, η).
    pub fn h_beta(&self, xi: f64, eta: f64) -> B2x9 {
        let l = Self::lambda(xi, eta);
        let mut h = B2x9::zeros();
        for i in 0..3 {
            h[(0, 3 * i + 2)] += l[i];
            h[(1, 3 * i + 1)] -= l[i];
        }
        for (k, &(i, j)) in SIDES.iter().enumerate() {
            let p = 4.0 * l[i] * l[j];
            for q in 0..9 {
                h[(0, q)] += p * self.s[k][0] * self.dbeta[k][q];
                h[(1, q)] += p * self.s[k][1] * self.dbeta[k][q];
            }
        }
        h
    }

    /// Curvatures `κ = B_b U_b` (3×9) at (ξ, η).
    pub fn b_bending(&self, xi: f64, eta: f64) -> B3x9 {
        let l = Self::lambda(xi, eta);
        // ∂β_x/∂x, ∂β_x/∂y, ∂β_y/∂x, ∂β_y/∂y as rows.
        let mut d = SMatrix::<f64, 4, 9>::zeros();
        for i in 0..3 {
            d[(0, 3 * i + 2)] += self.b[i];
            d[(1, 3 * i + 2)] += self.c[i];
            d[(2, 3 * i + 1)] -= self.b[i];
            d[(3, 3 * i + 1)] -= self.c[i];
        }
        for (k, &(i, j)) in SIDES.iter().enumerate() {
            let px = 4.0 * (self.b[i] * l[j] + l[i] * self.b[j]);
            let py = 4.0 * (self.c[i] * l[j] + l[i] * self.c[j]);
            let [sx, sy] = self.s[k];
            for q in 0..9 {
                let v = self.dbeta[k][q];
                d[(0, q)] += px * sx * v;
                d[(1, q)] += py * sx * v;
                d[(2, q)] += px * sy * v;
                d[(3, q)] += py * sy * v;
            }
        }
        let mut bb = B3x9::zeros();
        for q in 0..9 {
            bb[(0, q)] = d[(0, q)];
            bb[(1, q)] = d[(3, q)];
            bb[(2, q)] = d[(1, q)] + d[(2, q)];
        }
        bb
    }

    /// Assumed transverse shear `γ = B_s U_b` (2×9) at (ξ, η).
    pub fn b_shear(&self, xi: f64, eta: f64) -> B2x9 {
        let l = Self::lambda(xi, eta);
        let px = l[0] * self.x[0] + l[1] * self.x[1] + l[2] * self.x[2];
        let py = l[0] * self.y[0] + l[1] * self.y[1] + l[2] * self.y[2];
        let p = SMatrix::<f64, 2, 3>::new(1.0, 0.0, -(py - self.yc), 0.0, 1.0, px - self.xc);
        p * self.shear_coef
    }

    /// Bending + shear stiffness (9×9) on `U_b`.
    pub fn stiffness(&self, db: &nalgebra::Matrix3<f64>, ds: f64) -> Mat9 {
        let mut k = Mat9::zeros();
        for &(xi, eta) in &MIDSIDE {
            let bb = self.b_bending(xi, eta);
            let bs = self.b_shear(xi, eta);
            k += (bb.transpose() * db * bb + bs.transpose() * bs * ds) * (self.area / 3.0);
        }
        k
    }

    /// Geometric stiffness (9×9) on `U_b` for membrane forces `nh`, slopes `∇w = γ − β`.
    pub fn geometric(&self, nh: &Matrix2<f64>) -> Mat9 {
        let mut k = Mat9::zeros();
        for &(xi, eta, w) in &GAUSS6 {
            let gw = self.b_shear(xi, eta) - self.h_beta(xi, eta);
            k += gw.transpose() * nh * gw * (w * self.area);
        }
        k
    }
}

impl Dkmt {
    /// The w-part of K_G with the slopes taken as the rotations alone (`∇w ≈ −β`, DKT's
    /// choice), for comparison only: it ignores the shear part of the slope.
    pub fn geometric_rotations_only(&self, nh: &Matrix2<f64>) -> Mat9 {
        let mut k = Mat9::zeros();
        for &(xi, eta, w) in &GAUSS6 {
            let h = self.h_beta(xi, eta);
            k += h.transpose() * nh * h * (w * self.area);
        }
        k
    }
}

/// Plate stiffnesses of a material: `(D_b matrix, D, D_s = κ G t)`.
fn plate_constants(t: f64, m: &Material) -> (nalgebra::Matrix3<f64>, f64, f64) {
    let e = m.youngs_modulus;
    let nu = m.poisson_ratio;
    let d = e * t * t * t / (12.0 * (1.0 - nu * nu));
    let ds = SHEAR_CORRECTION * e / (2.0 * (1.0 + nu)) * t;
    (plane_stress(nu, e * t * t * t / 12.0), d, ds)
}

fn scatter_bending(k: &mut Mat18, kb: &Mat9) {
    for (i, &gi) in BEND.iter().enumerate() {
        for (j, &gj) in BEND.iter().enumerate() {
            k[(gi, gj)] += kb[(i, j)];
        }
    }
}

/// Add the DKMT bending + transverse shear stiffness to the bending DOFs of a local matrix.
pub(crate) fn add_dkmt_plate(k: &mut Mat18, g: &TriangleGeometry, t: f64, m: &Material) {
    let (db, d, ds) = plate_constants(t, m);
    scatter_bending(k, &Dkmt::new(g, d, ds).stiffness(&db, ds));
}

/// DKMT moments `M = D_b B_b(centroid) U_b`.
fn dkmt_centroid_moment(g: &TriangleGeometry, t: f64, m: &Material, ul: &[f64; 18]) -> [f64; 3] {
    let (db, d, ds) = plate_constants(t, m);
    let ub = SMatrix::<f64, 9, 1>::from_fn(|i, _| ul[BEND[i]]);
    let mm = db * Dkmt::new(g, d, ds).b_bending(1.0 / 3.0, 1.0 / 3.0) * ub;
    [mm[0], mm[1], mm[2]]
}

/// Local geometric stiffness: in-plane `u, v` terms (linear shape functions) + the DKMT
/// shear-consistent deflection slopes.
pub fn local_geometric_stiffness(
    g: &TriangleGeometry,
    t: f64,
    m: &Material,
    n: &[f64; 3],
) -> Mat18 {
    // The in-plane part is CST+DKT's; replace its w part by DKMT's.
    let mut k = CstDkt::local_geometric_stiffness_in_plane(g, n);
    let (_, d, ds) = plate_constants(t, m);
    let nh = Matrix2::new(n[0], n[2], n[2], n[1]);
    scatter_bending(&mut k, &Dkmt::new(g, d, ds).geometric(&nh));
    k
}

/// ANDES/OPT membrane (drilling freedoms) + DKMT Mindlin plate: the default element.
#[derive(Debug, Clone, Copy, Default)]
pub struct AndesDkmt;

/// CST membrane + drilling spring + DKMT Mindlin plate.
#[derive(Debug, Clone, Copy, Default)]
pub struct CstDkmt;

impl AndesDkmt {
    /// Local elastic stiffness (18×18).
    pub fn local_stiffness(g: &TriangleGeometry, t: f64, m: &Material) -> Mat18 {
        let mut k = AndesDkt::local_membrane(g, t, m);
        add_dkmt_plate(&mut k, g, t, m);
        k
    }
}

impl CstDkmt {
    /// Local elastic stiffness (18×18).
    pub fn local_stiffness(g: &TriangleGeometry, t: f64, m: &Material, alpha: f64) -> Mat18 {
        let mut k = Mat18::zeros();
        add_cst_membrane(&mut k, g, t, m, alpha);
        add_dkmt_plate(&mut k, g, t, m);
        k
    }
}

impl ShellElement for AndesDkmt {
    /// `drilling_alpha` is ignored (ANDES has a true drilling stiffness).
    fn stiffness(&self, g: &TriangleGeometry, t: f64, m: &Material, _drilling_alpha: f64) -> Mat18 {
        to_global(&Self::local_stiffness(g, t, m), &g.frame)
    }

    fn resultants(&self, g: &TriangleGeometry, t: f64, m: &Material, u: &[f64; 18]) -> Resultants {
        let ul = to_local(u, &g.frame);
        Resultants {
            membrane: AndesDkt::membrane_forces(g, t, m, &ul),
            moment: dkmt_centroid_moment(g, t, m, &ul),
        }
    }

    fn membrane_resultants(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        u: &[f64; 18],
    ) -> [f64; 3] {
        AndesDkt::membrane_forces(g, t, m, &to_local(u, &g.frame))
    }

    fn geometric_stiffness(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        n: &[f64; 3],
    ) -> Mat18 {
        to_global(&local_geometric_stiffness(g, t, m, n), &g.frame)
    }
}

impl ShellElement for CstDkmt {
    fn stiffness(&self, g: &TriangleGeometry, t: f64, m: &Material, drilling_alpha: f64) -> Mat18 {
        to_global(&Self::local_stiffness(g, t, m, drilling_alpha), &g.frame)
    }

    fn resultants(&self, g: &TriangleGeometry, t: f64, m: &Material, u: &[f64; 18]) -> Resultants {
        let ul = to_local(u, &g.frame);
        Resultants {
            membrane: CstDkt::membrane_forces(g, t, m, &ul),
            moment: dkmt_centroid_moment(g, t, m, &ul),
        }
    }

    fn membrane_resultants(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        u: &[f64; 18],
    ) -> [f64; 3] {
        CstDkt::membrane_forces(g, t, m, &to_local(u, &g.frame))
    }

    fn geometric_stiffness(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        n: &[f64; 3],
    ) -> Mat18 {
        to_global(&local_geometric_stiffness(g, t, m, n), &g.frame)
    }
}
