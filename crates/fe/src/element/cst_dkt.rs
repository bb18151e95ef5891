//! The reference facet element: CST membrane + DKT plate + weak drilling spring
//! (buckling.md §2 "Element formulation", items 1–7).
//!
//! Hand-written because no Rust crate provides shell elements.
//!
//! * **CST** (constant strain triangle): `B_m` constant, with `b_i = y_j − y_k`,
//!   `c_i = x_k − x_j` over 2A; `D_m = E t/(1−ν²)[[1,ν,0],[ν,1,0],[0,0,(1−ν)/2]]`;
//!   `K_m = A B_mᵀ D_m B_m`.
//! * **DKT** (discrete Kirchhoff triangle, Batoz, Bathe & Ho, IJNME 15 (1980) 1771–1812):
//!   rotations of the normal `β_x = H_x·U_b`, `β_y = H_y·U_b` with
//!   `U_b = (w1, θx1, θy1, w2, …, θy3)` and quadratic `H_x, H_y` (coefficients a_k…e_k on the
//!   sides k = 4, 5, 6 ↔ 23, 31, 12). Convention `θx = ∂w/∂y`, `θy = −∂w/∂x`, so
//!   `β_x = −w,x`, `β_y = −w,y`. Curvatures `κ = [β_x,x; β_y,y; β_x,y + β_y,x]`, moments
//!   `M = D_b κ` with `D_b = E t³/(12(1−ν²))[…]`. `K_b` uses the 3 mid-side points (exact:
//!   `B_b` is linear). The derivatives of H are taken from the derivatives of the six
//!   quadratic shape functions (equivalent to Batoz' explicit P_k, q_k, r_k, t_k form).
//! * **Drilling**: `k_d = α E t A` on each node's local θz (no coupling).
//! * **Geometric stiffness** for constant `N̂ = [[N_x, N_xy],[N_xy, N_y]]`:
//!   `A G_mᵀ N̂ G_m` for u and for v (linear shape functions), plus
//!   `Σ_g w_g A [H_x;H_y]ᵀ N̂ [H_x;H_y]` on the bending DOFs (∇w ≈ −β, 6-point degree-4 rule).

use nalgebra::{Matrix3, SMatrix};

use super::{Mat18, Resultants, ShellElement, TriangleGeometry, to_global, to_local};
use crate::model::Material;

/// CST + DKT + drilling spring (the reference element of `facet_ref_results.json`).
#[derive(Debug, Clone, Copy, Default)]
pub struct CstDkt;

type Mat9 = SMatrix<f64, 9, 9>;
type B3x9 = SMatrix<f64, 3, 9>;
type H9 = SMatrix<f64, 2, 9>;

/// Local DOF index of the bending DOFs (w, θx, θy) of node i, in `U_b` order.
pub(crate) const BEND: [usize; 9] = [2, 3, 4, 8, 9, 10, 14, 15, 16];

/// Constitutive matrix of plane stress times a factor `f`.
pub(crate) fn plane_stress(nu: f64, f: f64) -> Matrix3<f64> {
    let c = f / (1.0 - nu * nu);
    Matrix3::new(
        c,
        c * nu,
        0.0,
        c * nu,
        c,
        0.0,
        0.0,
        0.0,
        c * (1.0 - nu) / 2.0,
    )
}

/// Gradients of the linear shape functions: `(dN_i/dx, dN_i/dy) = (b_i, c_i)/2A`.
fn linear_gradients(g: &TriangleGeometry) -> ([f64; 3], [f64; 3]) {
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
    (b, c)
}

/// CST strain-displacement matrix on (u1, v1, u2, v2, u3, v3).
fn b_membrane(g: &TriangleGeometry) -> SMatrix<f64, 3, 6> {
    let (b, c) = linear_gradients(g);
    let mut m = SMatrix::<f64, 3, 6>::zeros();
    for i in 0..3 {
        m[(0, 2 * i)] = b[i];
        m[(1, 2 * i + 1)] = c[i];
        m[(2, 2 * i)] = c[i];
        m[(2, 2 * i + 1)] = b[i];
    }
    m
}

/// DKT: coefficients of H_x and H_y (9 rows each) on the six quadratic shape functions.
struct Dkt {
    cx: SMatrix<f64, 9, 6>,
    cy: SMatrix<f64, 9, 6>,
    x12: f64,
    x31: f64,
    y12: f64,
    y31: f64,
    two_a: f64,
}

impl Dkt {
    fn new(g: &TriangleGeometry) -> Self {
        let (x, y) = (g.x, g.y);
        // Sides k = 4, 5, 6 ↔ (i, j) = (2,3), (3,1), (1,2); x_ij = x_i − x_j.
        let sides = [(1usize, 2usize), (2, 0), (0, 1)];
        let mut a = [0.0; 3];
        let mut b = [0.0; 3];
        let mut c = [0.0; 3];
        let mut d = [0.0; 3];
        let mut e = [0.0; 3];
        for (k, &(i, j)) in sides.iter().enumerate() {
            let xij = x[i] - x[j];
            let yij = y[i] - y[j];
            let l2 = xij * xij + yij * yij;
            a[k] = -xij / l2;
            b[k] = 0.75 * xij * yij / l2;
            c[k] = (0.25 * xij * xij - 0.5 * yij * yij) / l2;
            d[k] = -yij / l2;
            e[k] = (0.25 * yij * yij - 0.5 * xij * xij) / l2;
        }
        let mut cx = SMatrix::<f64, 9, 6>::zeros();
        let mut cy = SMatrix::<f64, 9, 6>::zeros();
        // Node n (0,1,2) with corner shape function N_n and its two adjacent sides:
        // node 1: sides 6 (12) and 5 (31); node 2: 4 (23) and 6; node 3: 5 and 4.
        // Pattern (Batoz 1980): for node n with "next" side p and "previous" side q
        //   Hx_w  = 1.5(a_p N_p − a_q N_q), Hx_θx = b_q N_q + b_p N_p,
        //   Hx_θy = N_n − c_q N_q − c_p N_p, Hy_w = 1.5(d_p N_p − d_q N_q),
        //   Hy_θx = −N_n + e_q N_q + e_p N_p, Hy_θy = −Hx_θx.
        // Side index in a..e: 0 ↔ k=4, 1 ↔ k=5, 2 ↔ k=6; shape function index 3 + that.
        let adj = [(2usize, 1usize), (0, 2), (1, 0)]; // (p, q) per node
        for (n, &(p, q)) in adj.iter().enumerate() {
            let (np, nq) = (3 + p, 3 + q);
            let r = 3 * n;
            cx[(r, np)] = 1.5 * a[p];
            cx[(r, nq)] = -1.5 * a[q];
            cx[(r + 1, nq)] = b[q];
            cx[(r + 1, np)] = b[p];
            cx[(r + 2, n)] = 1.0;
            cx[(r + 2, nq)] = -c[q];
            cx[(r + 2, np)] = -c[p];
            cy[(r, np)] = 1.5 * d[p];
            cy[(r, nq)] = -1.5 * d[q];
            cy[(r + 1, n)] = -1.0;
            cy[(r + 1, nq)] = e[q];
            cy[(r + 1, np)] = e[p];
            cy[(r + 2, nq)] = -b[q];
            cy[(r + 2, np)] = -b[p];
        }
        Self {
            cx,
            cy,
            x12: x[0] - x[1],
            x31: x[2] - x[0],
            y12: y[0] - y[1],
            y31: y[2] - y[0],
            two_a: 2.0 * g.area,
        }
    }

    /// Quadratic shape functions N1..N6 at (ξ, η): corners 1,2,3 then mid-sides 23, 31, 12.
    fn n(xi: f64, eta: f64) -> SMatrix<f64, 6, 1> {
        let z = 1.0 - xi - eta;
        SMatrix::<f64, 6, 1>::from([
            z * (2.0 * z - 1.0),
            xi * (2.0 * xi - 1.0),
            eta * (2.0 * eta - 1.0),
            4.0 * xi * eta,
            4.0 * eta * z,
            4.0 * xi * z,
        ])
    }

    /// (∂N/∂ξ, ∂N/∂η).
    fn dn(xi: f64, eta: f64) -> (SMatrix<f64, 6, 1>, SMatrix<f64, 6, 1>) {
        let z = 1.0 - xi - eta;
        (
            SMatrix::<f64, 6, 1>::from([
                1.0 - 4.0 * z,
                4.0 * xi - 1.0,
                0.0,
                4.0 * eta,
                -4.0 * eta,
                4.0 * (z - xi),
            ]),
            SMatrix::<f64, 6, 1>::from([
                1.0 - 4.0 * z,
                0.0,
                4.0 * eta - 1.0,
                4.0 * xi,
                4.0 * (z - eta),
                -4.0 * xi,
            ]),
        )
    }

    /// `[H_x; H_y]` (2×9) at (ξ, η).
    fn h(&self, xi: f64, eta: f64) -> H9 {
        let n = Self::n(xi, eta);
        let hx = self.cx * n;
        let hy = self.cy * n;
        let mut m = H9::zeros();
        for j in 0..9 {
            m[(0, j)] = hx[j];
            m[(1, j)] = hy[j];
        }
        m
    }

    /// Curvature matrix `B_b` (3×9) at (ξ, η).
    fn b(&self, xi: f64, eta: f64) -> B3x9 {
        let (dxi, deta) = Self::dn(xi, eta);
        let hx_xi = self.cx * dxi;
        let hx_eta = self.cx * deta;
        let hy_xi = self.cy * dxi;
        let hy_eta = self.cy * deta;
        let mut m = B3x9::zeros();
        for j in 0..9 {
            m[(0, j)] = (self.y31 * hx_xi[j] + self.y12 * hx_eta[j]) / self.two_a;
            m[(1, j)] = (-self.x31 * hy_xi[j] - self.x12 * hy_eta[j]) / self.two_a;
            m[(2, j)] = (-self.x31 * hx_xi[j] - self.x12 * hx_eta[j]
                + self.y31 * hy_xi[j]
                + self.y12 * hy_eta[j])
                / self.two_a;
        }
        m
    }
}

/// Mid-side points (exact for the quadratic integrand `B_bᵀ D_b B_b`, B_b linear).
pub(crate) const MIDSIDE: [(f64, f64); 3] = [(0.5, 0.0), (0.5, 0.5), (0.0, 0.5)];

/// Strang–Fix/Dunavant 6-point rule, degree 4 (weights sum to 1, multiply by A).
pub(crate) const GAUSS6: [(f64, f64, f64); 6] = [
    (
        0.445_948_490_915_965,
        0.445_948_490_915_965,
        0.223_381_589_678_011,
    ),
    (
        0.108_103_018_168_070,
        0.445_948_490_915_965,
        0.223_381_589_678_011,
    ),
    (
        0.445_948_490_915_965,
        0.108_103_018_168_070,
        0.223_381_589_678_011,
    ),
    (
        0.091_576_213_509_771,
        0.091_576_213_509_771,
        0.109_951_743_655_322,
    ),
    (
        0.816_847_572_980_459,
        0.091_576_213_509_771,
        0.109_951_743_655_322,
    ),
    (
        0.091_576_213_509_771,
        0.816_847_572_980_459,
        0.109_951_743_655_322,
    ),
];

/// Add the DKT bending stiffness `Σ_{mid-sides} (A/3) B_bᵀ D_b B_b` to the bending DOFs of a
/// local 18×18 matrix (shared by every membrane variant).
pub(crate) fn add_dkt_bending(k: &mut Mat18, g: &TriangleGeometry, t: f64, m: &Material) {
    let dkt = Dkt::new(g);
    let db = plane_stress(m.poisson_ratio, m.youngs_modulus * t * t * t / 12.0);
    let mut kb = Mat9::zeros();
    for &(xi, eta) in &MIDSIDE {
        let b = dkt.b(xi, eta);
        kb += b.transpose() * db * b * (g.area / 3.0);
    }
    for (i, &gi) in BEND.iter().enumerate() {
        for (j, &gj) in BEND.iter().enumerate() {
            k[(gi, gj)] += kb[(i, j)];
        }
    }
}

/// DKT moments `M = D_b B_b(centroid) U_b` from the 18 local displacements.
pub(crate) fn dkt_centroid_moment(
    g: &TriangleGeometry,
    t: f64,
    m: &Material,
    ul: &[f64; 18],
) -> [f64; 3] {
    let ub = SMatrix::<f64, 9, 1>::from_fn(|i, _| ul[BEND[i]]);
    let db = plane_stress(m.poisson_ratio, m.youngs_modulus * t * t * t / 12.0);
    let mm = db * Dkt::new(g).b(1.0 / 3.0, 1.0 / 3.0) * ub;
    [mm[0], mm[1], mm[2]]
}

/// Add the CST membrane and the drilling spring `α E t A` to a local 18×18 matrix.
pub(crate) fn add_cst_membrane(
    k: &mut Mat18,
    g: &TriangleGeometry,
    t: f64,
    m: &Material,
    alpha: f64,
) {
    let e = m.youngs_modulus;
    let bm = b_membrane(g);
    let km = bm.transpose() * plane_stress(m.poisson_ratio, e * t) * bm * g.area;
    for i in 0..3 {
        for j in 0..3 {
            for a in 0..2 {
                for b in 0..2 {
                    k[(6 * i + a, 6 * j + b)] += km[(2 * i + a, 2 * j + b)];
                }
            }
        }
    }
    let kd = alpha * e * t * g.area;
    for n in 0..3 {
        k[(6 * n + 5, 6 * n + 5)] += kd;
    }
}

impl CstDkt {
    /// Local (element-frame) elastic stiffness, 18×18, node-major (u, v, w, θx, θy, θz).
    pub fn local_stiffness(g: &TriangleGeometry, t: f64, m: &Material, alpha: f64) -> Mat18 {
        let mut k = Mat18::zeros();
        add_cst_membrane(&mut k, g, t, m, alpha);
        add_dkt_bending(&mut k, g, t, m);
        k
    }

    /// CST membrane forces `N = D_m B_m u_m` from the 18 local displacements.
    pub(crate) fn membrane_forces(
        g: &TriangleGeometry,
        t: f64,
        m: &Material,
        ul: &[f64; 18],
    ) -> [f64; 3] {
        let um = SMatrix::<f64, 6, 1>::from([ul[0], ul[1], ul[6], ul[7], ul[12], ul[13]]);
        let nm = plane_stress(m.poisson_ratio, m.youngs_modulus * t) * b_membrane(g) * um;
        [nm[0], nm[1], nm[2]]
    }

    /// In-plane part of the geometric stiffness (`u`, `v` rows only, linear shape functions).
    pub(crate) fn local_geometric_stiffness_in_plane(g: &TriangleGeometry, n: &[f64; 3]) -> Mat18 {
        let nh = nalgebra::Matrix2::new(n[0], n[2], n[2], n[1]);
        let (b, c) = linear_gradients(g);
        let gm = SMatrix::<f64, 2, 3>::new(b[0], b[1], b[2], c[0], c[1], c[2]);
        let kuu = gm.transpose() * nh * gm * g.area;
        let mut k = Mat18::zeros();
        for i in 0..3 {
            for j in 0..3 {
                k[(6 * i, 6 * j)] += kuu[(i, j)];
                k[(6 * i + 1, 6 * j + 1)] += kuu[(i, j)];
            }
        }
        k
    }

    /// Local geometric stiffness for membrane forces `n = [N_x, N_y, N_xy]`.
    pub fn local_geometric_stiffness(g: &TriangleGeometry, n: &[f64; 3]) -> Mat18 {
        let nh = nalgebra::Matrix2::new(n[0], n[2], n[2], n[1]);
        let mut k = Self::local_geometric_stiffness_in_plane(g, n);
        let dkt = Dkt::new(g);
        let mut kw = Mat9::zeros();
        for &(xi, eta, w) in &GAUSS6 {
            let h = dkt.h(xi, eta);
            kw += h.transpose() * nh * h * (w * g.area);
        }
        for (i, &gi) in BEND.iter().enumerate() {
            for (j, &gj) in BEND.iter().enumerate() {
                k[(gi, gj)] += kw[(i, j)];
            }
        }
        k
    }

    /// Curvature matrix at (ξ, η), exposed for the patch tests.
    pub fn curvature_matrix(g: &TriangleGeometry, xi: f64, eta: f64) -> SMatrix<f64, 3, 9> {
        Dkt::new(g).b(xi, eta)
    }
}

impl ShellElement for CstDkt {
    fn stiffness(&self, g: &TriangleGeometry, t: f64, m: &Material, drilling_alpha: f64) -> Mat18 {
        to_global(&Self::local_stiffness(g, t, m, drilling_alpha), &g.frame)
    }

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
        to_global(&Self::local_geometric_stiffness(g, n), &g.frame)
    }
}
