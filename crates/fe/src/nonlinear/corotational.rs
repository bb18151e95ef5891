//! Element-independent co-rotational (EICR) kinematics of the flat 3-node facets.
//!
//! Rankin & Nour-Omid (1988, Comput. Struct. 30: 257–267); Felippa & Haugen (2005, CMAME 194:
//! 2285–2335, "A unified formulation of small-strain corotational finite elements"); Battini &
//! Pacoste (2002, CMAME 191: 1755–1789) for the derivative of `H`.
//!
//! **Frame.** The current element frame `Tₙ` (rows e₁, e₂, e₃) is built from the current node
//! positions exactly as [`crate::element::TriangleGeometry`] builds the initial one `T₀`
//! (e₁ along side 1→2, e₃ the facet normal), so a rigid motion leaves the local coordinates
//! unchanged.
//!
//! **Deformational DOFs** (local components, node a, centroid c):
//! `ū_a = Tₙ(x_a − x_c) − T₀(X_a − X_c)`, `θ̄_a = log(Tₙ R_a T₀ᵀ)`, where `R_a` is the node's
//! total rotation (updated multiplicatively, `R ← exp(spin Δω) R`, Δω a spatial spin). The
//! linear element stiffness `K̄` (the element's own matrix on the initial geometry, in its
//! local frame) acts on `d̄ = [ū_a; θ̄_a]`: `f̄ = K̄ d̄`.
//!
//! **Variations.** With `v̄ = T δv` the spatial variations (δx_a, δω_a) in local components:
//! `δd̄ = H P v̄`, where
//! * `P = I − A − S G` is the projector: A averages the translations, `S_a = [−spin(x̄_a); I]`,
//!   and `G` (3×18) gives the spin of the element frame, ω̄ = G v̄: ω̄₁ = ∂w/∂y,
//!   ω̄₂ = −∂w/∂x (linear w on the current facet), ω̄₃ = (v₂ − v₁)/l₁₂;
//! * `H = diag(I, H(θ̄_a))`, `H(θ) = I − ½ spin θ + η spin²θ`,
//!   `η = (1 − (θ/2) cot(θ/2))/θ²` (inverse of the differential of the exponential map).
//!
//! **Internal force** `f = Tᵀ Pᵀ Hᵀ f̄`.
//!
//! **Tangent** (consistent, Felippa & Haugen 2005 eq. (4.17) in our notation):
//! `K = Tᵀ (Pᵀ Hᵀ K̄ H P − F(y) G + Gᵀ F_n P + Pᵀ L H P) T` with `y = Pᵀ Hᵀ f̄`,
//! `F(y)` stacking `spin(y_blk)` of all six 3-blocks, `F_n` the 3×18 row of `spin(n_a)` on
//! the translations (n_a the translational blocks of `f̄`), and `L = diag(0, L_a)`,
//! `L_a = ∂(H(θ)ᵀ m̄_a)/∂θ = −½ spin m + η[(θ·m) I + θ mᵀ − 2 m θᵀ] + μ spin²θ m θᵀ`,
//! `μ = η'(θ)/θ`. One term is dropped: the variation of `G` times `Sᵀ Hᵀ f̄`, which is the
//! out-of-balance moment of the element forces about the centroid in the deformed
//! configuration and vanishes with the strains (small-strain theory). The tangent with
//! respect to spins is not symmetric away from equilibrium; the solver assembles its
//! symmetric part (the skew part vanishes at equilibrium under conservative loads, so
//! Newton's convergence stays quadratic near the solution; Felippa & Haugen §5).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::element::{Mat18, TriangleGeometry, to_global_into};

/// 18-vector.
pub(crate) type Vec18 = SVector<f64, 18>;

/// `spin(v) w = v × w`.
pub(crate) fn spin(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Rodrigues: `exp(spin w)`.
pub(crate) fn rot_exp(w: &Vector3<f64>) -> Matrix3<f64> {
    let th2 = w.norm_squared();
    let th = th2.sqrt();
    let (a, b) = if th < 1e-4 {
        (1.0 - th2 / 6.0, 0.5 - th2 / 24.0)
    } else {
        (th.sin() / th, (1.0 - th.cos()) / th2)
    };
    let s = spin(w);
    Matrix3::identity() + s * a + s * s * b
}

/// Rotation vector of a rotation matrix (|θ| ≤ π), through the quaternion (Shepperd's
/// branch choice, accurate near π).
pub(crate) fn rot_log(r: &Matrix3<f64>) -> Vector3<f64> {
    let tr = r.trace();
    let (r00, r11, r22) = (r[(0, 0)], r[(1, 1)], r[(2, 2)]);
    let (w, x, y, z);
    if tr >= r00 && tr >= r11 && tr >= r22 {
        let s = 0.5 * (1.0 + tr).max(0.0).sqrt();
        w = s;
        x = (r[(2, 1)] - r[(1, 2)]) / (4.0 * s);
        y = (r[(0, 2)] - r[(2, 0)]) / (4.0 * s);
        z = (r[(1, 0)] - r[(0, 1)]) / (4.0 * s);
    } else if r00 >= r11 && r00 >= r22 {
        let s = 0.5 * (1.0 + r00 - r11 - r22).max(0.0).sqrt();
        x = s;
        w = (r[(2, 1)] - r[(1, 2)]) / (4.0 * s);
        y = (r[(0, 1)] + r[(1, 0)]) / (4.0 * s);
        z = (r[(0, 2)] + r[(2, 0)]) / (4.0 * s);
    } else if r11 >= r22 {
        let s = 0.5 * (1.0 - r00 + r11 - r22).max(0.0).sqrt();
        y = s;
        w = (r[(0, 2)] - r[(2, 0)]) / (4.0 * s);
        x = (r[(0, 1)] + r[(1, 0)]) / (4.0 * s);
        z = (r[(1, 2)] + r[(2, 1)]) / (4.0 * s);
    } else {
        let s = 0.5 * (1.0 - r00 - r11 + r22).max(0.0).sqrt();
        z = s;
        w = (r[(1, 0)] - r[(0, 1)]) / (4.0 * s);
        x = (r[(0, 2)] + r[(2, 0)]) / (4.0 * s);
        y = (r[(1, 2)] + r[(2, 1)]) / (4.0 * s);
    }
    let (w, v) = if w < 0.0 {
        (-w, -Vector3::new(x, y, z))
    } else {
        (w, Vector3::new(x, y, z))
    };
    let sn = v.norm();
    if sn < 1e-12 {
        return v * (2.0 / w.max(1e-300));
    }
    v * (2.0 * sn.atan2(w) / sn)
}

/// `η(θ)` and `μ(θ) = η'(θ)/θ` of `H(θ)` (series below θ = 0.1, where the closed forms lose
/// digits to cancellation; the series' first omitted terms are < 1e-13 relative there).
fn eta_mu(th: f64) -> (f64, f64) {
    if th < 0.1 {
        let t2 = th * th;
        (
            1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0 + t2 * t2 * t2 / 1_209_600.0,
            1.0 / 360.0 + t2 / 7560.0 + t2 * t2 / 201_600.0,
        )
    } else {
        let h = 0.5 * th;
        let c = h.cos() / h.sin();
        let s2 = h.sin() * h.sin();
        let eta = (1.0 - h * c) / (th * th);
        let deta = -(0.5 * c - th / (4.0 * s2)) / (th * th) - 2.0 * (1.0 - h * c) / (th * th * th);
        (eta, deta / th)
    }
}

/// `H(θ) = I − ½ spin θ + η spin²θ`.
fn h_matrix(theta: &Vector3<f64>) -> Matrix3<f64> {
    let (eta, _) = eta_mu(theta.norm());
    let s = spin(theta);
    Matrix3::identity() - s * 0.5 + s * s * eta
}

/// `∂(H(θ)ᵀ m)/∂θ`.
fn l_matrix(theta: &Vector3<f64>, m: &Vector3<f64>) -> Matrix3<f64> {
    let (eta, mu) = eta_mu(theta.norm());
    let s = spin(theta);
    let tm = theta.dot(m);
    spin(m) * -0.5
        + (Matrix3::identity() * tm + theta * m.transpose() - m * theta.transpose() * 2.0) * eta
        + (s * s * m) * theta.transpose() * mu
}

/// `X P = X − X A − (X S) G` (A averages the three nodes' translations).
fn right_p<const R: usize>(
    x: &SMatrix<f64, R, 18>,
    s: &SMatrix<f64, 18, 3>,
    g: &SMatrix<f64, 3, 18>,
) -> SMatrix<f64, R, 18> {
    let mut out = x - (x * s) * g;
    for r in 0..R {
        for i in 0..3 {
            let m = (x[(r, i)] + x[(r, 6 + i)] + x[(r, 12 + i)]) / 3.0;
            for b in 0..3 {
                out[(r, 6 * b + i)] -= m;
            }
        }
    }
    out
}

/// `Pᵀ X = X − A X − Gᵀ (Sᵀ X)` (A is symmetric).
fn left_pt(x: &Mat18, s: &SMatrix<f64, 18, 3>, g: &SMatrix<f64, 3, 18>) -> Mat18 {
    let mut out = x - g.transpose() * (s.transpose() * x);
    for c in 0..18 {
        for i in 0..3 {
            let m = (x[(i, c)] + x[(6 + i, c)] + x[(12 + i, c)]) / 3.0;
            for b in 0..3 {
                out[(6 * b + i, c)] -= m;
            }
        }
    }
    out
}

/// `Pᵀ z` for a vector.
fn left_pt_vec(z: &Vec18, s: &SMatrix<f64, 18, 3>, g: &SMatrix<f64, 3, 18>) -> Vec18 {
    let mut out = z - g.transpose() * (s.transpose() * z);
    for i in 0..3 {
        let m = (z[i] + z[6 + i] + z[12 + i]) / 3.0;
        for b in 0..3 {
            out[6 * b + i] -= m;
        }
    }
    out
}

/// Frame rows (e₁, e₂, e₃) of the triangle `p`, as in [`TriangleGeometry::new`].
pub(crate) fn frame_of(p: &[Vector3<f64>; 3]) -> Matrix3<f64> {
    let d2 = p[1] - p[0];
    let d3 = p[2] - p[0];
    let e1 = d2.normalize();
    let e3 = d2.cross(&d3).normalize();
    let e2 = e3.cross(&e1);
    Matrix3::from_rows(&[e1.transpose(), e2.transpose(), e3.transpose()])
}

/// The facet's own initial-stress (von Kármán) terms in its local frame: membrane forces
/// `N = C d̄` and the linear element's geometric stiffness per unit membrane force,
/// `K̄_G(N) = Σ_k N_k G_k` (the same matrix the linear buckling solver assembles), kept as
/// its in-plane 3×3 block (acting on u and v alike) and its 9×9 block on the plate DOFs.
#[derive(Debug, Clone)]
pub(crate) struct LocalGeometric {
    c: SMatrix<f64, 3, 18>,
    /// `D_m / (2A)`: membrane force per unit `q = [d̄ᵀG_k d̄]` (the mean von Kármán strain is
    /// `q / 2A`).
    dq: Matrix3<f64>,
    kuu: [Matrix3<f64>; 3],
    kb: [SMatrix<f64, 9, 9>; 3],
}

/// Plate DOFs (w, θx, θy) of the 18 local ones.
const BEND: [usize; 9] = [2, 3, 4, 8, 9, 10, 14, 15, 16];

impl LocalGeometric {
    /// From the element's global geometric stiffness per unit `N_k` and its membrane forces
    /// per unit local DOF (both on the initial geometry, rotated into its frame).
    pub(crate) fn new(
        frame0: &[[f64; 3]; 3],
        area: f64,
        membrane_rigidity: Matrix3<f64>,
        geometric: impl Fn(&[f64; 3]) -> Mat18,
        membrane: impl Fn(&[f64; 18]) -> [f64; 3],
    ) -> Self {
        let t0 = Matrix3::from_fn(|i, j| frame0[i][j]);
        let mut c = SMatrix::<f64, 3, 18>::zeros();
        for j in 0..18 {
            let (blk, i) = (j / 3, j % 3);
            let mut ug = [0.0; 18];
            for r in 0..3 {
                ug[3 * blk + r] = t0[(i, r)];
            }
            let n = membrane(&ug);
            for k in 0..3 {
                c[(k, j)] = n[k];
            }
        }
        let mut kuu = [Matrix3::zeros(); 3];
        let mut kb = [SMatrix::<f64, 9, 9>::zeros(); 3];
        for k in 0..3 {
            let mut unit = [0.0; 3];
            unit[k] = 1.0;
            let kl = to_local18(&geometric(&unit), &t0);
            kuu[k] = Matrix3::from_fn(|a, b| kl[(6 * a, 6 * b)]);
            kb[k] = SMatrix::<f64, 9, 9>::from_fn(|a, b| kl[(BEND[a], BEND[b])]);
        }
        Self {
            c,
            dq: membrane_rigidity / (2.0 * area),
            kuu,
            kb,
        }
    }

    /// `K̄_G(n)` as a local 18×18 matrix.
    pub(crate) fn matrix(&self, n: &[f64; 3]) -> Mat18 {
        let mut out = Mat18::zeros();
        let kuu = self.kuu[0] * n[0] + self.kuu[1] * n[1] + self.kuu[2] * n[2];
        let kb = self.kb[0] * n[0] + self.kb[1] * n[1] + self.kb[2] * n[2];
        for a in 0..3 {
            for b in 0..3 {
                out[(6 * a, 6 * b)] = kuu[(a, b)];
                out[(6 * a + 1, 6 * b + 1)] = kuu[(a, b)];
            }
        }
        for (i, &gi) in BEND.iter().enumerate() {
            for (j, &gj) in BEND.iter().enumerate() {
                out[(gi, gj)] = kb[(i, j)];
            }
        }
        out
    }

    /// `ΔN = D_m q / 2A`: the membrane force of the mean von Kármán strain of the slopes.
    pub(crate) fn slope_membrane_force(&self, d: &Vec18) -> [f64; 3] {
        let gd = self.g_times(d);
        let q = Vector3::new(d.dot(&gd[0]), d.dot(&gd[1]), d.dot(&gd[2]));
        let dn = self.dq * q;
        [dn[0], dn[1], dn[2]]
    }

    /// `G_k d` for k = 0, 1, 2.
    fn g_times(&self, d: &Vec18) -> [Vec18; 3] {
        let db = SVector::<f64, 9>::from_fn(|i, _| d[BEND[i]]);
        std::array::from_fn(|k| {
            let mut out = Vec18::zeros();
            for a in 0..3 {
                for b in 0..3 {
                    out[6 * a] += self.kuu[k][(a, b)] * d[6 * b];
                    out[6 * a + 1] += self.kuu[k][(a, b)] * d[6 * b + 1];
                }
            }
            let kd = self.kb[k] * db;
            for (i, &gi) in BEND.iter().enumerate() {
                out[gi] += kd[i];
            }
            out
        })
    }

    /// Force and tangent of the facet's von Kármán energy beyond `½ d̄ᵀK̄d̄`, with the
    /// membrane strain of the slopes taken as its element mean `q / 2A`,
    /// `q_k = d̄ᵀ G_k d̄`, and `N = C d̄`, `ΔN = D_m q / 2A`:
    /// `Π = ½ Nᵀq + qᵀ D_m q / 8A`,
    /// `f = Σ (N_k + ΔN_k) G_k d̄ + ½ Σ c_k q_k`,
    /// `K = Σ (N_k + ΔN_k) G_k + Σ (G_k d̄ c_kᵀ + c_k d̄ᵀ G_k) + 2 Σ_kj (D_m/2A)_kj G_k d̄ d̄ᵀ G_j`.
    fn force_tangent(&self, d: &Vec18) -> (Vec18, Mat18) {
        let n = self.c * d;
        let gd = self.g_times(d);
        let q = Vector3::new(d.dot(&gd[0]), d.dot(&gd[1]), d.dot(&gd[2]));
        let nt = n + self.dq * q;
        let mut f = Vec18::zeros();
        let mut k = self.matrix(&[nt[0], nt[1], nt[2]]);
        for kk in 0..3 {
            let ck = self.c.row(kk).transpose();
            f += gd[kk] * nt[kk] + ck * (0.5 * q[kk]);
            // Σ_j 2 (D_m/2A)_kj G_k d̄ d̄ᵀ G_j = G_k d̄ hᵀ with h = Σ_j 2 (D_m/2A)_kj G_j d̄:
            // two rank-one updates per k instead of four.
            let mut h = ck;
            for j in 0..3 {
                h += gd[j] * (2.0 * self.dq[(kk, j)]);
            }
            // k += g hᵀ + c gᵀ entry by entry: the same sums as the matrix expression
            // (each entry `k + (g_i h_j + c_i g_j)`), without its three 18×18 temporaries.
            let g = &gd[kk];
            for j in 0..18 {
                for i in 0..18 {
                    k[(i, j)] += g[i] * h[j] + ck[i] * g[j];
                }
            }
        }
        (f, k)
    }

    /// The force of [`Self::force_tangent`] alone (a residual check needs no tangent).
    fn force(&self, d: &Vec18) -> Vec18 {
        let n = self.c * d;
        let gd = self.g_times(d);
        let q = Vector3::new(d.dot(&gd[0]), d.dot(&gd[1]), d.dot(&gd[2]));
        let nt = n + self.dq * q;
        let mut f = Vec18::zeros();
        for kk in 0..3 {
            f += gd[kk] * nt[kk] + self.c.row(kk).transpose() * (0.5 * q[kk]);
        }
        f
    }
}

/// `T₀ K T₀ᵀ` block by block (global → local).
fn to_local18(k: &Mat18, t0: &Matrix3<f64>) -> Mat18 {
    let mut out = Mat18::zeros();
    for a in 0..6 {
        for b in 0..6 {
            let blk = k.fixed_view::<3, 3>(3 * a, 3 * b).into_owned();
            out.fixed_view_mut::<3, 3>(3 * a, 3 * b)
                .copy_from(&(t0 * blk * t0.transpose()));
        }
    }
    out
}

/// The co-rotational wrapper of one element: its linear stiffness in the initial local frame
/// and the initial local node coordinates.
#[derive(Debug, Clone)]
pub(crate) struct CrElement {
    /// `K̄`: the linear element stiffness in its local frame.
    kbar: Mat18,
    /// Initial frame `T₀`.
    frame0: Matrix3<f64>,
    /// Initial local coordinates relative to the centroid.
    xbar0: [Vector3<f64>; 3],
    /// The facet's local initial-stress terms (`None`: the plain small-strain EICR facet).
    local: Option<LocalGeometric>,
}

/// Deformational state of one element.
pub(crate) struct Kinematics {
    /// Current frame `Tₙ`.
    pub(crate) tn: Matrix3<f64>,
    /// Current local coordinates relative to the centroid.
    xbar: [Vector3<f64>; 3],
    /// `d̄ = [ū_a; θ̄_a]`.
    pub(crate) d: Vec18,
}

impl CrElement {
    /// From the initial geometry and the element's global linear stiffness on it.
    pub(crate) fn new(
        geo: &TriangleGeometry,
        k_global: &Mat18,
        local: Option<LocalGeometric>,
    ) -> Self {
        let frame0 = Matrix3::from_fn(|i, j| geo.frame[i][j]);
        let kbar = to_local18(k_global, &frame0);
        let p: [Vector3<f64>; 3] = std::array::from_fn(|a| Vector3::new(geo.x[a], geo.y[a], 0.0));
        let c = (p[0] + p[1] + p[2]) / 3.0;
        Self {
            kbar,
            frame0,
            xbar0: p.map(|v| v - c),
            local,
        }
    }

    /// Deformational displacements from the current positions and nodal rotations.
    pub(crate) fn kinematics(&self, x: &[Vector3<f64>; 3], r: &[&Matrix3<f64>; 3]) -> Kinematics {
        let tn = frame_of(x);
        let c = (x[0] + x[1] + x[2]) / 3.0;
        let xbar: [Vector3<f64>; 3] = std::array::from_fn(|a| tn * (x[a] - c));
        let mut d = Vec18::zeros();
        for a in 0..3 {
            let u = xbar[a] - self.xbar0[a];
            let th = rot_log(&(tn * r[a] * self.frame0.transpose()));
            for i in 0..3 {
                d[6 * a + i] = u[i];
                d[6 * a + 3 + i] = th[i];
            }
        }
        Kinematics { tn, xbar, d }
    }

    /// The facet's local initial-stress terms, if it has them.
    pub(crate) fn local(&self) -> Option<&LocalGeometric> {
        self.local.as_ref()
    }

    /// Deformational displacements in the initial global axes (`T₀ᵀ d̄` per block), the input
    /// of [`crate::element::ShellElement::resultants`] on the initial geometry.
    pub(crate) fn deformational_global(&self, k: &Kinematics) -> [f64; 18] {
        let mut out = [0.0; 18];
        for blk in 0..6 {
            let v = Vector3::new(k.d[3 * blk], k.d[3 * blk + 1], k.d[3 * blk + 2]);
            let g = self.frame0.transpose() * v;
            for i in 0..3 {
                out[3 * blk + i] = g[i];
            }
        }
        out
    }

    /// Global internal force and (unsymmetrised, consistent) tangent.
    #[cfg(test)]
    pub(crate) fn force_tangent(
        &self,
        x: &[Vector3<f64>; 3],
        r: &[&Matrix3<f64>; 3],
        tangent: bool,
    ) -> (Vec18, Option<Mat18>) {
        let mut k = tangent.then(Mat18::zeros);
        let f = self.force_tangent_into(x, r, k.as_mut());
        (f, k)
    }

    /// [`Self::force_tangent`] with the tangent, when asked for, written into `k` (every
    /// entry): the assembly's buffer, instead of a 2.6 kB value moved out through the calls.
    pub(crate) fn force_tangent_into(
        &self,
        x: &[Vector3<f64>; 3],
        r: &[&Matrix3<f64>; 3],
        k: Option<&mut Mat18>,
    ) -> Vec18 {
        self.force_tangent_with(x, r, k, None)
    }

    /// The initial-stress stiffness of the facet on the current geometry (at the reference
    /// state: x = X, R = I) for the stresses of the local deformational DOFs `d_lin`: the
    /// tangent's terms linear in the element forces, without the material term `K̄`.
    pub(crate) fn initial_stress_stiffness(
        &self,
        x: &[Vector3<f64>; 3],
        r: &[&Matrix3<f64>; 3],
        d_lin: &Vec18,
    ) -> Mat18 {
        let mut k = Mat18::zeros();
        self.force_tangent_with(x, r, Some(&mut k), Some(d_lin));
        k
    }

    /// Local deformational DOFs of a small global displacement `u` (18, element order) on
    /// the initial geometry: `T₀ u` per block (the rigid part is annihilated by `K̄`, `C`).
    pub(crate) fn local_of(&self, u: &Vec18) -> Vec18 {
        let mut out = Vec18::zeros();
        for blk in 0..6 {
            let v = self.frame0 * Vector3::new(u[3 * blk], u[3 * blk + 1], u[3 * blk + 2]);
            for i in 0..3 {
                out[3 * blk + i] = v[i];
            }
        }
        out
    }

    /// [`Self::force_tangent_into`]; with `stress_of = Some(d)`, the stresses are those of
    /// `d` and the material term is left out ([`Self::initial_stress_stiffness`]).
    fn force_tangent_with(
        &self,
        x: &[Vector3<f64>; 3],
        r: &[&Matrix3<f64>; 3],
        out: Option<&mut Mat18>,
        stress_of: Option<&Vec18>,
    ) -> Vec18 {
        let tangent = out.is_some();
        let k = self.kinematics(x, r);
        let (fbar, ktan) = match (stress_of, &self.local) {
            (None, None) => (self.kbar * k.d, self.kbar),
            (None, Some(l)) if tangent => {
                let (fg, kg) = l.force_tangent(&k.d);
                (self.kbar * k.d + fg, self.kbar + kg)
            }
            // A force evaluation: the tangent is never used (`ktan` below).
            (None, Some(l)) => (self.kbar * k.d + l.force(&k.d), self.kbar),
            (Some(d), local) => {
                let kg = local.as_ref().map_or_else(Mat18::zeros, |l| {
                    let n = l.c * d;
                    l.matrix(&[n[0], n[1], n[2]])
                });
                (self.kbar * d, kg)
            }
        };
        let theta: [Vector3<f64>; 3] =
            std::array::from_fn(|a| Vector3::new(k.d[6 * a + 3], k.d[6 * a + 4], k.d[6 * a + 5]));
        let hs: [Matrix3<f64>; 3] = std::array::from_fn(|a| h_matrix(&theta[a]));
        // z = Hᵀ f̄
        let mut z = fbar;
        for a in 0..3 {
            let m = Vector3::new(fbar[6 * a + 3], fbar[6 * a + 4], fbar[6 * a + 5]);
            let hm = hs[a].transpose() * m;
            for i in 0..3 {
                z[6 * a + 3 + i] = hm[i];
            }
        }
        // G: spin of the element frame per unit local variation.
        let xb = &k.xbar;
        let two_a =
            (xb[1].x - xb[0].x) * (xb[2].y - xb[0].y) - (xb[2].x - xb[0].x) * (xb[1].y - xb[0].y);
        let l12 = xb[1].x - xb[0].x;
        let mut g = SMatrix::<f64, 3, 18>::zeros();
        for a in 0..3 {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let dndx = (xb[b].y - xb[c].y) / two_a;
            let dndy = (xb[c].x - xb[b].x) / two_a;
            g[(0, 6 * a + 2)] = dndy;
            g[(1, 6 * a + 2)] = -dndx;
        }
        g[(2, 1)] = -1.0 / l12;
        g[(2, 7)] = 1.0 / l12;
        // P = I − A − S G
        let mut s = SMatrix::<f64, 18, 3>::zeros();
        for a in 0..3 {
            s.fixed_view_mut::<3, 3>(6 * a, 0)
                .copy_from(&(-spin(&xb[a])));
            s.fixed_view_mut::<3, 3>(6 * a + 3, 0)
                .copy_from(&Matrix3::identity());
        }
        // P = I − A − S G is applied, never formed: A averages the translations (rank 3),
        // S G is rank 3 — about half the flops of dense 18×18 products.
        let y = left_pt_vec(&z, &s, &g);
        let mut f = Vec18::zeros();
        for blk in 0..6 {
            let v = Vector3::new(y[3 * blk], y[3 * blk + 1], y[3 * blk + 2]);
            let gv = k.tn.transpose() * v;
            for i in 0..3 {
                f[3 * blk + i] = gv[i];
            }
        }
        let Some(out) = out else {
            return f;
        };
        // K̄ H (H mixes the rotation columns), then C = K̄ H P.
        let mut kh = ktan;
        for a in 0..3 {
            let cols = ktan.fixed_view::<18, 3>(0, 6 * a + 3).into_owned();
            kh.fixed_view_mut::<18, 3>(0, 6 * a + 3)
                .copy_from(&(cols * hs[a]));
        }
        let c = right_p(&kh, &s, &g);
        // X = Hᵀ C + L H P (both only change or fill the rotation rows), K = Pᵀ X + …
        let mut x = c;
        for a in 0..3 {
            let rows = c.fixed_view::<3, 18>(6 * a + 3, 0).into_owned();
            let m = Vector3::new(fbar[6 * a + 3], fbar[6 * a + 4], fbar[6 * a + 5]);
            let la = l_matrix(&theta[a], &m);
            // Rotation rows of P: E_a − G (S's rotation blocks are I).
            let mut pa = -g;
            for i in 0..3 {
                pa[(i, 6 * a + 3 + i)] += 1.0;
            }
            x.fixed_view_mut::<3, 18>(6 * a + 3, 0)
                .copy_from(&(hs[a].transpose() * rows + la * hs[a] * pa));
        }
        let mut kl = left_pt(&x, &s, &g);
        // K_GR = −F(y) G
        let mut fy = SMatrix::<f64, 18, 3>::zeros();
        for blk in 0..6 {
            let v = Vector3::new(y[3 * blk], y[3 * blk + 1], y[3 * blk + 2]);
            fy.fixed_view_mut::<3, 3>(3 * blk, 0).copy_from(&spin(&v));
        }
        kl -= fy * g;
        // K_GP = Gᵀ F_n P
        let mut fnm = SMatrix::<f64, 3, 18>::zeros();
        for a in 0..3 {
            let n = Vector3::new(fbar[6 * a], fbar[6 * a + 1], fbar[6 * a + 2]);
            fnm.fixed_view_mut::<3, 3>(0, 6 * a).copy_from(&spin(&n));
        }
        kl += g.transpose() * right_p(&fnm, &s, &g);
        let frame: [[f64; 3]; 3] =
            std::array::from_fn(|i| [k.tn[(i, 0)], k.tn[(i, 1)], k.tn[(i, 2)]]);
        to_global_into(&kl, &frame, out);
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::ShellElement;
    use crate::element::cst_dkt::CstDkt;
    use crate::model::Material;

    fn element() -> (CrElement, [Vector3<f64>; 3]) {
        let p0 = [[0.0, 0.0, 0.0], [1.0, 0.1, 0.2], [0.3, 0.9, -0.1]];
        let geo = TriangleGeometry::new(&p0);
        let m = Material {
            youngs_modulus: 1e3,
            poisson_ratio: 0.3,
            unit_weight: 0.0,
        };
        let k = CstDkt.stiffness(&geo, 0.05, &m, 1e-3);
        (
            CrElement::new(&geo, &k, None),
            p0.map(|p| Vector3::new(p[0], p[1], p[2])),
        )
    }

    #[test]
    fn log_inverts_exp() {
        for w in [
            Vector3::new(0.3, -0.2, 0.1),
            Vector3::new(1e-9, 2e-9, 0.0),
            Vector3::new(0.0, 3.0, 0.1),
            Vector3::new(-2.0, 1.5, 0.9),
        ] {
            let back = rot_log(&rot_exp(&w));
            assert!((back - w).norm() < 1e-12 * (1.0 + w.norm()), "{w} → {back}");
        }
    }

    #[test]
    fn rigid_motion_gives_no_force() {
        let (el, x0) = element();
        let q = rot_exp(&Vector3::new(0.7, -1.1, 0.4));
        let t = Vector3::new(3.0, -2.0, 0.5);
        let x = x0.map(|p| q * p + t);
        let (f, _) = el.force_tangent(&x, &[&q, &q, &q], false);
        // f̄ is K̄ times round-off-sized deformational DOFs (|K̄| ~ 1e2 here).
        assert!(f.norm() < 1e-10, "{}", f.norm());
    }

    /// Largest entry error of the analytic tangent against central differences of the
    /// internal force (translations additive, rotations by left-multiplied exponentials, as
    /// in the solver's update), relative to the largest entry, at a deformed state (strains
    /// ~1 % × `sc`) under a large rigid rotation. Central differences with h = 1e-6 add
    /// ~1e-9.
    fn tangent_error(sc: f64) -> f64 {
        let (el, x0) = element();
        let q = rot_exp(&Vector3::new(0.4, 0.3, -0.5));
        let mut x = x0.map(|p| q * p);
        x[1] += Vector3::new(0.01, -0.004, 0.003) * sc;
        x[2] += Vector3::new(-0.002, 0.006, 0.01) * sc;
        let rs = [
            rot_exp(&(Vector3::new(0.02, -0.01, 0.015) * sc)) * q,
            rot_exp(&(Vector3::new(-0.03, 0.02, 0.01) * sc)) * q,
            rot_exp(&(Vector3::new(0.01, 0.025, -0.02) * sc)) * q,
        ];
        let (_, kt) = el.force_tangent(&x, &[&rs[0], &rs[1], &rs[2]], true);
        let kt = kt.unwrap();
        let h = 1e-6;
        let mut kfd = Mat18::zeros();
        for col in 0..18 {
            let (a, d) = (col / 6, col % 6);
            let eval = |s: f64| {
                let mut xx = x;
                let mut rr = rs;
                if d < 3 {
                    xx[a][d] += s;
                } else {
                    let mut w = Vector3::zeros();
                    w[d - 3] = s;
                    rr[a] = rot_exp(&w) * rr[a];
                }
                el.force_tangent(&xx, &[&rr[0], &rr[1], &rr[2]], false).0
            };
            let df = (eval(h) - eval(-h)) / (2.0 * h);
            kfd.set_column(col, &df);
        }
        let scale = kfd.abs().max();
        (kt - kfd).abs().max() / scale
    }

    #[test]
    fn tangent_matches_finite_differences() {
        let e: Vec<f64> = [1.0, 0.5, 0.25].iter().map(|s| tangent_error(*s)).collect();
        // Quadratic decay (ratio ≈ 4 per halving) shows the only mismatch is the dropped
        // O(strain · force) term; a wrong geometric term is linear in the forces and would
        // decay with ratio 2.
        assert!(e[0] < 1e-4, "tangent errors {e:?}");
        assert!(
            e[0] / e[1] > 3.5 && e[1] / e[2] > 3.5,
            "tangent errors {e:?}"
        );
    }
}
