//! The shear-deformable element (ANDES/CST membrane + DKMT Reissner–Mindlin plate,
//! `element::dkmt`): thin limit = DKT, no shear locking, thick plates against the Mindlin
//! closed form, the vault against CalculiX S8R (issue 17).
//!
//! Closed form used throughout (simply supported a × b plate, uniaxial N_x, "hard" simple
//! support, i.e. w = 0 and the tangential rotation fixed on every edge, so that the
//! double-sine (Navier) mode is exact): with `α = mπ/a`, `k² = (mπ/a)² + (nπ/b)²`,
//! `D = E t³/(12(1−ν²))`, `D_s = κ G t`, κ = 5/6:
//!
//! `N_cr,Mindlin = (D k⁴/α²) / (1 + D k²/D_s)`,
//!
//! the Kirchhoff value `D k⁴/α²` (Bryan 1891; Timoshenko & Gere 1961 §9.2) divided by the
//! shear factor. Derivation (Mindlin 1951 plate equations): taking the divergence of the
//! moment equilibrium `M_αβ,β = Q_α` with `M = D(…ψ…)` gives `D ∇²(∇·ψ) = ∇·Q`;
//! `∇·Q = D_s(∇²w + ∇·ψ)` and the transverse equilibrium `∇·Q = N_x w,xx` (the membrane
//! force acting on the slope of the deflection w). For `w, ∇·ψ ∝ sin(αx) sin(nπy/b)`:
//! `∇·ψ = N_x α² w/(D k²)` and `D_s(−k² + N_x α²/(D k²)) = −N_x α²`, i.e. the formula above.
//! It is the uniaxial form of the Kirchhoff–Mindlin relation of Wang, Reddy & Lee,
//! *Shear Deformable Beams and Plates* (Elsevier 2000), ch. 10 (`N_M = N_K/(1 + N_K/(κ G h))`
//! for isotropic in-plane load, where `N_K = D k²`). For a = b = 1 the lowest mode is
//! m = n = 1: `k² = 2π²`, `N_K = 4π²D`.

use kappe_fe::element::ShellElement;
use kappe_fe::element::TriangleGeometry;
use kappe_fe::element::cst_dkt::CstDkt;
use kappe_fe::element::dkmt::{AndesDkmt, Dkmt, SHEAR_CORRECTION};
use kappe_fe::generate::{barrel_vault, ss_plate, ss_plate_hard};
use kappe_fe::{BucklingOptions, ElementKind, ShellModel, buckling};
use nalgebra::SMatrix;

use crate::common::{load_json, load_mesh, material, rel};

const PI2: f64 = std::f64::consts::PI * std::f64::consts::PI;

/// (Kirchhoff, Mindlin) closed-form N_cr of the unit square plate, E = 1 MPa, ν = 0.3.
fn plate_closed_form(t: f64) -> (f64, f64) {
    let (e, nu) = (1.0e6, 0.3);
    let d = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
    let ds = SHEAR_CORRECTION * e / (2.0 * (1.0 + nu)) * t;
    let nk = 4.0 * PI2 * d;
    (nk, nk / (1.0 + 2.0 * PI2 * d / ds))
}

fn lambda1(model: &ShellModel) -> f64 {
    let r = buckling(
        model,
        &BucklingOptions {
            modes: 1,
            ..Default::default()
        },
    )
    .unwrap();
    r.factors[0]
}

fn plate(n: usize, t: f64, element: ElementKind) -> f64 {
    let mut m = ss_plate_hard(n, t);
    m.element = element;
    lambda1(&m)
}

/// An irregular triangle in its own plane.
fn triangle() -> TriangleGeometry {
    TriangleGeometry::new(&[[0.0, 0.0, 0.0], [0.31, 0.04, 0.0], [0.12, 0.27, 0.0]])
}

/// With φ_k = 0 (no shear flexibility, `D = 0` passed to the φ formula) the DKMT bending
/// stiffness and the w-part of K_G are DKT's exactly: the element cannot lock, and its thin
/// limit is the Kirchhoff element of the fixtures. 1e-12 relative: two different codings of
/// the same polynomials, only round-off separates them.
#[test]
fn dkmt_with_zero_phi_is_dkt() {
    let g = triangle();
    let m = material(1.0e6, 0.3, 0.0);
    let t = 0.02;
    let kdkt = CstDkt::local_stiffness(&g, t, &m, 0.0);
    let db = nalgebra::Matrix3::new(1.0, 0.3, 0.0, 0.3, 1.0, 0.0, 0.0, 0.0, 0.35)
        * (1.0e6 * t.powi(3) / (12.0 * (1.0 - 0.09)));
    let plate = Dkmt::new(&g, 0.0, 1.0);
    let kb = plate.stiffness(&db, 1.0);
    let nf = [-1.3, 0.4, 0.7];
    let kg_dkt = CstDkt::local_geometric_stiffness(&g, &nf);
    let nh = nalgebra::Matrix2::new(nf[0], nf[2], nf[2], nf[1]);
    let kg = plate.geometric(&nh);
    const BEND: [usize; 9] = [2, 3, 4, 8, 9, 10, 14, 15, 16];
    let (sk, sg) = (kdkt.abs().max(), kg_dkt.abs().max());
    for (i, &gi) in BEND.iter().enumerate() {
        for (j, &gj) in BEND.iter().enumerate() {
            assert!(
                (kb[(i, j)] - kdkt[(gi, gj)]).abs() < 1e-12 * sk,
                "K ({i},{j}): {} vs {}",
                kb[(i, j)],
                kdkt[(gi, gj)]
            );
            assert!(
                (kg[(i, j)] - kg_dkt[(gi, gj)]).abs() < 1e-12 * sg,
                "K_G ({i},{j})"
            );
        }
    }
}

/// Patch: a quadratic deflection with the Kirchhoff rotations (`β = −∇w`) is a constant-
/// curvature, zero-shear state at any thickness (the edge kinematics vanish, so Δβ_k = 0
/// and γ_k = 0): curvatures exact and γ = 0 at several points, 1e-10 relative.
#[test]
fn dkmt_constant_curvature_zero_shear() {
    let g = triangle();
    // w = a x² + b x y + c y² + d x + e y + f.
    let (a, b, c, d, e, f) = (0.7, -0.4, 1.1, 0.2, -0.3, 0.05);
    let mut ub = SMatrix::<f64, 9, 1>::zeros();
    for i in 0..3 {
        let (x, y) = (g.x[i], g.y[i]);
        let wx = 2.0 * a * x + b * y + d;
        let wy = b * x + 2.0 * c * y + e;
        ub[3 * i] = a * x * x + b * x * y + c * y * y + d * x + e * y + f;
        ub[3 * i + 1] = wy; // θx = ∂w/∂y
        ub[3 * i + 2] = -wx; // θy = −∂w/∂x
    }
    // κ = [β_x,x, β_y,y, β_x,y + β_y,x] with β = −∇w.
    let exact = [-2.0 * a, -2.0 * c, -2.0 * b];
    // A thick plate: φ_k = O(1) (t comparable to the sides).
    let plate = Dkmt::new(&g, 1.0, 3.0);
    for (xi, eta) in [(0.2, 0.3), (1.0 / 3.0, 1.0 / 3.0), (0.0, 0.9), (0.6, 0.1)] {
        let k = plate.b_bending(xi, eta) * ub;
        let s = plate.b_shear(xi, eta) * ub;
        for r in 0..3 {
            assert!(
                (k[r] - exact[r]).abs() < 1e-10 * 2.2,
                "κ{r}: {} vs {}",
                k[r],
                exact[r]
            );
        }
        assert!(s.norm() < 1e-10, "γ = {s:?}");
    }
}

/// The global element K (curved orientation, thick) has exactly the 6 rigid-body zero
/// eigenvalues and no spurious mode: the 7th eigenvalue is far from round-off (> 1e-8 of
/// the largest; round-off level is 1e-16).
#[test]
fn andes_dkmt_six_zero_energy_modes() {
    let g = TriangleGeometry::new(&[[0.1, 0.2, 0.3], [0.35, 0.1, 0.4], [0.2, 0.45, 0.2]]);
    let k = AndesDkmt.stiffness(&g, 0.05, &material(1.0e6, 0.3, 0.0), 0.0);
    let mut ev: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    let max = ev[17];
    for v in &ev[..6] {
        assert!(v.abs() < 1e-12 * max, "{ev:?}");
    }
    assert!(ev[6] > 1e-8 * max, "{ev:?}");
}

/// No shear locking: t/L = 1/1000, 16 × 16 mesh, within 1 % of the closed form (issue 17's
/// tolerance; the Mindlin and Kirchhoff values differ by 5.6e-6 here). It is in fact as
/// accurate as DKT on the same mesh: measured +0.043 % for both, so the test also requires
/// agreement with CST+DKT to 0.01 % (a locking element is off by tens of %).
#[test]
fn thin_plate_no_shear_locking() {
    let t = 1.0e-3;
    let (nk, nm) = plate_closed_form(t);
    assert!(rel(nk, nm) < 1e-5);
    let l = plate(16, t, ElementKind::AndesDkmt);
    let l_dkt = plate(16, t, ElementKind::CstDkt);
    println!("t/L = 1/1000: DKMT {l:e}, DKT {l_dkt:e}, closed form {nk:e}");
    assert!(rel(l, nk) < 0.01, "{l} vs {nk}");
    assert!(rel(l, l_dkt) < 1e-4, "{l} vs DKT {l_dkt}");
}

/// The A3 plate (t/L = 1/100) with the new element: within A3's tolerances of the Kirchhoff
/// closed form 3.615240 (0.2 % at n = 16, 0.05 % at n = 32) — the Mindlin value is only
/// 0.056 % below it — and converging monotonically from above to the Mindlin closed form
/// (measured +0.056 % / +0.020 %).
#[test]
fn a3_plate_with_dkmt() {
    let (nk, nm) = plate_closed_form(0.01);
    assert!(rel(nk, 3.615240) < 1e-6);
    let l16 = plate(16, 0.01, ElementKind::AndesDkmt);
    let l32 = plate(32, 0.01, ElementKind::AndesDkmt);
    println!("t/L = 1/100: {l16} {l32}, Kirchhoff {nk}, Mindlin {nm}");
    assert!(rel(l16, nk) < 0.002 && rel(l32, nk) < 0.0005);
    assert!(
        l16 > l32 && l32 > nm,
        "monotone from above: {l16} {l32} {nm}"
    );
}

/// Thick plates, t/b = 1/10 and 1/20, against the Mindlin closed form (module docs), within
/// 1 % (issue 17) at n = 16 (measured +0.21 % and +0.16 %), and converging from above
/// (n = 8 is farther). The Kirchhoff element misses the shear: CST+DKT is +5.7 % / +1.5 %
/// off at t/b = 1/10 / 1/20, so the test can fail.
#[test]
fn thick_plate_mindlin_closed_form() {
    for t in [0.1, 0.05] {
        let (nk, nm) = plate_closed_form(t);
        let l8 = plate(8, t, ElementKind::AndesDkmt);
        let l16 = plate(16, t, ElementKind::AndesDkmt);
        let dkt = plate(16, t, ElementKind::CstDkt);
        println!(
            "t/b = {t}: DKMT n8 {l8:.3} n16 {l16:.3}, DKT {dkt:.3}; Mindlin {nm:.3}, Kirchhoff {nk:.3}"
        );
        assert!(rel(l16, nm) < 0.01, "t = {t}: {l16} vs {nm}");
        assert!(l8 > l16 && l16 > nm, "from above: {l8} {l16} {nm}");
        assert!(
            rel(dkt, nm) > 0.01,
            "DKT should miss the shear: {dkt} vs {nm}"
        );
    }
}

/// A soft simple support (tangential rotation free, the fixture's conditions) has the
/// Mindlin edge boundary layer, so a shear-deformable plate buckles below the hard-support
/// value; a Kirchhoff element cannot tell the two apart. Checks the sign of the physics at
/// t/b = 1/10 (measured: soft −5 % below hard at n = 16).
#[test]
fn soft_support_is_softer() {
    let t = 0.1;
    let mut soft = ss_plate(16);
    soft.thickness = vec![t];
    soft.element = ElementKind::AndesDkmt;
    let hard = plate(16, t, ElementKind::AndesDkmt);
    let s = lambda1(&soft);
    assert!(s < hard * 0.99, "soft {s} vs hard {hard}");
}

/// A6 with the new element: the vault 20×12 fixture vs CalculiX S8R converged (0.068970):
/// measured +0.48 % (CST+DKT +1.14 %). Tolerance A6's 2.0 %, plus: closer than CST+DKT.
/// The 0.2 % convergence is shown on finer meshes in `vault_converges_below_0_2_percent`.
#[test]
fn a6_vault_with_dkmt() {
    let s8r = load_json("vault_s3_20x12.expected.json");
    println!("{s8r}");
    let mut m = load_mesh("vault_s3_20x12");
    m.element = ElementKind::AndesDkmt;
    let l = lambda1(&m);
    m.element = ElementKind::CstDkt;
    let l_dkt = lambda1(&m);
    println!("vault 20x12: DKMT {l}, DKT {l_dkt}");
    assert!(rel(l, 0.068970) < 0.02);
    assert!(rel(l, 0.068970) < rel(l_dkt, 0.068970));
}

/// The vault converges to within 0.2 % of S8R's converged 0.068970 (issue 17): 48 × 28
/// (1 421 nodes) is the first fixture-family mesh of the bench sequence under 0.2 %
/// (measured +0.17 %), and the next refinement moves towards it (64 × 38: +0.13 %). The
/// Kirchhoff element's limit is +0.45 % (buckling.md A6), so this fails without shear.
#[test]
fn vault_converges_below_0_2_percent() {
    let mut prev = f64::INFINITY;
    for (na, nl) in [(48, 28), (64, 38)] {
        let mut m = barrel_vault(na, nl);
        m.element = ElementKind::AndesDkmt;
        let l = lambda1(&m);
        let e = rel(l, 0.068970);
        println!(
            "vault {na}x{nl}: {l} ({:+.3} %)",
            100.0 * (l / 0.068970 - 1.0)
        );
        assert!(e < 0.002, "{na}x{nl}: {l}");
        assert!(l < prev, "decreasing towards the limit");
        prev = l;
    }
}

/// ANDES+DKMT with the w-part of K_G on the rotations alone (`∇w ≈ −β`), to show that the
/// shear part of the slope is needed.
struct RotationSlopes;

impl ShellElement for RotationSlopes {
    fn stiffness(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &kappe_fe::Material,
        a: f64,
    ) -> kappe_fe::element::Mat18 {
        AndesDkmt.stiffness(g, t, m, a)
    }
    fn resultants(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &kappe_fe::Material,
        u: &[f64; 18],
    ) -> kappe_fe::element::Resultants {
        AndesDkmt.resultants(g, t, m, u)
    }
    fn geometric_stiffness(
        &self,
        g: &TriangleGeometry,
        t: f64,
        m: &kappe_fe::Material,
        n: &[f64; 3],
    ) -> kappe_fe::element::Mat18 {
        let (e, nu) = (m.youngs_modulus, m.poisson_ratio);
        let d = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
        let ds = SHEAR_CORRECTION * e / (2.0 * (1.0 + nu)) * t;
        let nh = nalgebra::Matrix2::new(n[0], n[2], n[2], n[1]);
        let plate = Dkmt::new(g, d, ds);
        let delta = plate.geometric_rotations_only(&nh) - plate.geometric(&nh);
        const BEND: [usize; 9] = [2, 3, 4, 8, 9, 10, 14, 15, 16];
        let mut local = kappe_fe::element::Mat18::zeros();
        for (i, &gi) in BEND.iter().enumerate() {
            for (j, &gj) in BEND.iter().enumerate() {
                local[(gi, gj)] = delta[(i, j)];
            }
        }
        // Tᵀ (local) T with T = blockdiag(R) (R rows = the frame).
        let r = nalgebra::Matrix3::from_fn(|i, j| g.frame[i][j]);
        let mut out = AndesDkmt.geometric_stiffness(g, t, m, n);
        for a in 0..6 {
            for b in 0..6 {
                let blk = local.fixed_view::<3, 3>(3 * a, 3 * b).into_owned();
                let add = r.transpose() * blk * r;
                let mut v = out.fixed_view_mut::<3, 3>(3 * a, 3 * b);
                v += add;
            }
        }
        out
    }
}

/// The transverse-shear-consistent geometric stiffness matters for thick plates: with the
/// slopes `∇w = γ − β` the t/b = 1/10 plate is within 1 % of the Mindlin closed form (see
/// `thick_plate_mindlin_closed_form`); with the rotations alone (`∇w ≈ −β`) the same mesh
/// and stiffness give +1.12 % (shear-consistent: +0.21 %), so the
/// closed-form check would fail without the shear part.
#[test]
fn geometric_stiffness_needs_shear_slope() {
    let t = 0.1;
    let (_, nm) = plate_closed_form(t);
    let mut m = ss_plate_hard(16, t);
    m.element = ElementKind::AndesDkmt;
    let solver = kappe_fe::BucklingSolver::with_element(&m, Box::new(RotationSlopes)).unwrap();
    let opts = BucklingOptions {
        modes: 1,
        ..Default::default()
    };
    let rot = solver.buckling(&m, &opts).unwrap().factors[0];
    let full = lambda1(&m);
    println!(
        "t/b = 1/10: shear-consistent {full:.3} ({:+.2} %), rotations only {rot:.3} ({:+.2} %), Mindlin {nm:.3}",
        100.0 * (full / nm - 1.0),
        100.0 * (rot / nm - 1.0)
    );
    assert!(rel(full, nm) < 0.01);
    assert!(rel(rot, nm) > 0.01 && rot > 1.005 * full, "{rot} vs {nm}");
}
