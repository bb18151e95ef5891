//! A1: element patch tests — constant membrane strain and constant curvature reproduced
//! exactly on an irregular 5-triangle patch (in a tilted plane, so the local frames are
//! exercised); the 6 rigid-body modes of a curved patch carry zero energy. Run for both
//! elements: the reference CST+DKT and ANDES/OPT+DKT.

use kappe_fe::element::andes_dkt::AndesDkt;
use kappe_fe::element::cst_dkt::CstDkt;
use kappe_fe::element::dkmt::AndesDkmt;
use kappe_fe::element::{ShellElement, TriangleGeometry};
use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::common::material;

/// Irregular patch: interior node 0 and five boundary nodes, in local plane coordinates.
fn patch_2d() -> (Vec<[f64; 2]>, Vec<[usize; 3]>) {
    let pts = vec![
        [0.42, 0.37],
        [0.0, 0.0],
        [1.1, -0.1],
        [1.3, 0.8],
        [0.5, 1.2],
        [-0.2, 0.7],
    ];
    let tris = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5], [0, 5, 1]];
    (pts, tris)
}

fn tilt() -> Matrix3<f64> {
    *Rotation3::from_euler_angles(0.3, -0.5, 1.1).matrix()
}

/// Internal nodal forces Σ K_e u_e of the patch (global 6 per node).
fn internal_forces(
    el: &dyn ShellElement,
    x: &[[f64; 3]],
    tris: &[[usize; 3]],
    u: &[[f64; 6]],
    alpha: f64,
) -> Vec<[f64; 6]> {
    let mat = material(2.0e9, 0.25, 0.0);
    let mut f = vec![[0.0; 6]; x.len()];
    for t in tris {
        let g = TriangleGeometry::new(&[x[t[0]], x[t[1]], x[t[2]]]);
        let k = el.stiffness(&g, 0.05, &mat, alpha);
        let ue = nalgebra::SVector::<f64, 18>::from_fn(|i, _| u[t[i / 6]][i % 6]);
        let fe = k * ue;
        for (a, &n) in t.iter().enumerate() {
            for d in 0..6 {
                f[n][d] += fe[6 * a + d];
            }
        }
    }
    f
}

fn to_global(r: &Matrix3<f64>, local: [f64; 3]) -> [f64; 3] {
    let v = r.transpose() * Vector3::from(local);
    [v[0], v[1], v[2]]
}

/// Constant strain (membrane) and constant curvature (bending) fields are equilibrated at
/// the interior node (zero internal force) and give the exact constant resultants in every
/// element. Tolerance 1e-10 relative to the force/resultant scale: the fields are reproduced
/// exactly by CST and DKT, so only round-off remains.
#[test]
fn a1_constant_strain_and_curvature() {
    // CST: drilling DOFs at 0 (the spring acts on the absolute θz and is not part of the
    // linear field).
    constant_strain_and_curvature(&CstDkt, false);
}

/// A1 for ANDES/OPT+DKT: the same patch test, with the drilling DOFs set to the field's
/// true rotation ω = (v,x − u,y)/2 — the state the ANDES membrane represents exactly (its
/// basic stiffness passes the patch test, the higher-order strain vanishes for θ_i = ω).
#[test]
fn a1_andes_constant_strain_and_curvature() {
    constant_strain_and_curvature(&AndesDkt, true);
}

fn constant_strain_and_curvature(el: &dyn ShellElement, drill_rotation: bool) {
    let (p2, tris) = patch_2d();
    let r = tilt(); // local = r · global
    let x: Vec<[f64; 3]> = p2
        .iter()
        .map(|p| to_global(&r, [p[0], p[1], 0.0]))
        .collect();
    let mat = material(2.0e9, 0.25, 0.0);
    let t = 0.05;
    // Membrane: u = 1e-3(2x + 0.5y), v = 1e-3(−0.7x + 1.5y) → ε = 1e-3(2, 1.5, −0.2).
    // Bending: w = 1e-3(0.8x² − 0.6xy + 0.3y²); θx = w,y, θy = −w,x, drilling 0.
    let (a, b, c) = (0.8e-3, -0.6e-3, 0.3e-3);
    let omega = if drill_rotation {
        0.5e-3 * (-0.7 - 0.5)
    } else {
        0.0
    };
    let u: Vec<[f64; 6]> = p2
        .iter()
        .map(|&[px, py]| {
            let ul = [
                1e-3 * (2.0 * px + 0.5 * py),
                1e-3 * (-0.7 * px + 1.5 * py),
                a * px * px + b * px * py + c * py * py,
            ];
            let th = [b * px + 2.0 * c * py, -(2.0 * a * px + b * py), omega];
            let ug = to_global(&r, ul);
            let tg = to_global(&r, th);
            [ug[0], ug[1], ug[2], tg[0], tg[1], tg[2]]
        })
        .collect();
    let f = internal_forces(el, &x, &tris, &u, 1e-3);
    let scale = f
        .iter()
        .flat_map(|v| v.iter())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    for d in 0..6 {
        assert!(
            f[0][d].abs() < 1e-10 * scale,
            "interior dof {d}: {} (scale {scale})",
            f[0][d]
        );
    }
    // Exact resultants: N = D_m ε, M = D_b κ with κ = (−2a, −2c, −2b) (β = −∇w).
    let dm = 2.0e9 * t / (1.0 - 0.0625);
    let eps = [2e-3, 1.5e-3, -0.7e-3 + 0.5e-3];
    let n_exact = [
        dm * (eps[0] + 0.25 * eps[1]),
        dm * (0.25 * eps[0] + eps[1]),
        dm * 0.375 * eps[2],
    ];
    let db = 2.0e9 * t * t * t / 12.0 / (1.0 - 0.0625);
    let kap = [-2.0 * a, -2.0 * c, -2.0 * b];
    let m_exact = [
        db * (kap[0] + 0.25 * kap[1]),
        db * (0.25 * kap[0] + kap[1]),
        db * 0.375 * kap[2],
    ];
    for tri in &tris {
        let g = TriangleGeometry::new(&[x[tri[0]], x[tri[1]], x[tri[2]]]);
        let ue: [f64; 18] = std::array::from_fn(|i| u[tri[i / 6]][i % 6]);
        let res = el.resultants(&g, t, &mat, &ue);
        // Resultants are in the element frame; rotate the plane tensors from the patch frame.
        let e1 = Vector3::from(g.frame[0]);
        let e1p = r * e1; // element x axis in patch-local coordinates
        let (cs, sn) = (e1p[0], e1p[1]);
        let rot = |v: [f64; 3]| {
            let (xx, yy, xy) = (v[0], v[1], v[2]);
            [
                xx * cs * cs + yy * sn * sn + 2.0 * xy * sn * cs,
                xx * sn * sn + yy * cs * cs - 2.0 * xy * sn * cs,
                (yy - xx) * sn * cs + xy * (cs * cs - sn * sn),
            ]
        };
        let ne = rot(n_exact);
        let me = rot(m_exact);
        // The element normal may be ±e3 of the patch; with it flipped, y flips, so Nxy/Mxy
        // change sign and M changes sign (curvature seen from the other side).
        let flip = (r * Vector3::from(g.frame[2]))[2] < 0.0;
        let sgn = if flip { -1.0 } else { 1.0 };
        let nscale = n_exact.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mscale = m_exact.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for k in 0..3 {
            let nxy = if k == 2 { sgn } else { 1.0 };
            assert!(
                (res.membrane[k] - nxy * ne[k]).abs() < 1e-10 * nscale,
                "N{k}: {:?} vs {ne:?}",
                res.membrane
            );
            let mk = if k == 2 { 1.0 } else { sgn };
            assert!(
                (res.moment[k] - mk * me[k]).abs() < 1e-9 * mscale,
                "M{k}: {:?} vs {me:?}",
                res.moment
            );
        }
    }
}

/// Six rigid-body modes of a curved (non-coplanar) patch: u = a + ω × x, θ = ω gives zero
/// internal forces. Tolerance 1e-10 of ‖K‖·‖u‖ (round-off only). The spec's drilling spring
/// acts on the absolute local θz (buckling.md §2 item 5, as in the reference fixtures), so it
/// resists a rigid rotation about the facet normal by design: the exact check is made with
/// α = 0, and with α = 1e-3 the spurious force must stay at the α·E·t·A level.
#[test]
fn a1_rigid_body_modes_curved_patch() {
    rigid_body_modes(&CstDkt, true);
}

/// A1 for ANDES/OPT+DKT: rigid-body modes of the curved patch give zero internal forces at
/// 1e-10 of ‖K‖·‖u‖ with the model's default `drilling_alpha` = 1e-3 passed in — the ANDES
/// drilling DOF is the true rotation, so there is no spring to switch off.
#[test]
fn a1_andes_rigid_body_modes_curved_patch() {
    rigid_body_modes(&AndesDkt, false);
}

fn rigid_body_modes(el: &dyn ShellElement, absolute_spring: bool) {
    let (p2, tris) = patch_2d();
    let x: Vec<[f64; 3]> = p2
        .iter()
        .map(|p| {
            [
                p[0],
                p[1],
                0.3 * p[0] * p[0] - 0.2 * p[1] * p[1] + 0.1 * p[0] * p[1],
            ]
        })
        .collect();
    let mat = material(2.0e9, 0.25, 0.0);
    let kscale = 2.0e9 * 0.05; // membrane stiffness scale E t
    for mode in 0..6 {
        let u: Vec<[f64; 6]> = x
            .iter()
            .map(|xi| {
                let mut v = [0.0; 6];
                if mode < 3 {
                    v[mode] = 1.0;
                } else {
                    let mut w = [0.0; 3];
                    w[mode - 3] = 1.0;
                    let c = [
                        w[1] * xi[2] - w[2] * xi[1],
                        w[2] * xi[0] - w[0] * xi[2],
                        w[0] * xi[1] - w[1] * xi[0],
                    ];
                    v = [c[0], c[1], c[2], w[0], w[1], w[2]];
                }
                v
            })
            .collect();
        let alpha = if absolute_spring { 0.0 } else { 1e-3 };
        let f = internal_forces(el, &x, &tris, &u, alpha);
        let _ = mat;
        for (n, fn_) in f.iter().enumerate() {
            for d in 0..6 {
                assert!(
                    fn_[d].abs() < 1e-10 * kscale,
                    "mode {mode} node {n} dof {d}: {}",
                    fn_[d]
                );
            }
        }
        if !absolute_spring {
            continue;
        }
        // Patch area ≈ 1.5 m² → α E t A ≈ 1.5e-3·kscale per unit rotation, spread over nodes.
        let f = internal_forces(el, &x, &tris, &u, 1e-3);
        for fn_ in &f {
            for v in fn_ {
                assert!(v.abs() < 2e-3 * kscale, "alpha-level bound: {v}");
            }
        }
    }
}

/// Orientation independence (part of A10): reversing a triangle's node order gives the same
/// global stiffness and geometric stiffness (after permuting the node blocks back), for both
/// elements.
#[test]
fn a10_element_orientation_independent() {
    let x = [[0.1, 0.0, 0.2], [1.0, 0.3, 0.1], [0.4, 0.9, -0.3]];
    let mat = material(3.0e7, 0.3, 0.0);
    let g1 = TriangleGeometry::new(&x);
    let g2 = TriangleGeometry::new(&[x[0], x[2], x[1]]);
    let perm = [0usize, 2, 1];
    let nf = [120.0, -40.0, 15.0];
    // The membrane forces are a tensor in the element plane; express them in frame 2.
    let e1a = Vector3::from(g1.frame[0]);
    let (cs, sn) = (
        e1a.dot(&Vector3::from(g2.frame[0])),
        e1a.dot(&Vector3::from(g2.frame[1])),
    );
    let nt = nalgebra::Matrix2::new(nf[0], nf[2], nf[2], nf[1]);
    // Frame-1 tensor components → frame 2: T' = Q T Qᵀ, Q rows = frame-2 axes in frame 1.
    let e1b = Vector3::from(g2.frame[0]);
    let e2b = Vector3::from(g2.frame[1]);
    let q = nalgebra::Matrix2::new(
        e1b.dot(&Vector3::from(g1.frame[0])),
        e1b.dot(&Vector3::from(g1.frame[1])),
        e2b.dot(&Vector3::from(g1.frame[0])),
        e2b.dot(&Vector3::from(g1.frame[1])),
    );
    let _ = (cs, sn);
    let n2 = q * nt * q.transpose();
    let nf2 = [n2[(0, 0)], n2[(1, 1)], n2[(0, 1)]];
    for (k1, k2, what) in [
        (
            CstDkt.stiffness(&g1, 0.02, &mat, 1e-3),
            CstDkt.stiffness(&g2, 0.02, &mat, 1e-3),
            "K",
        ),
        (
            CstDkt.geometric_stiffness(&g1, 0.02, &mat, &nf),
            CstDkt.geometric_stiffness(&g2, 0.02, &mat, &nf2),
            "K_G",
        ),
        (
            AndesDkt.stiffness(&g1, 0.02, &mat, 1e-3),
            AndesDkt.stiffness(&g2, 0.02, &mat, 1e-3),
            "ANDES K",
        ),
        (
            AndesDkt.geometric_stiffness(&g1, 0.02, &mat, &nf),
            AndesDkt.geometric_stiffness(&g2, 0.02, &mat, &nf2),
            "ANDES K_G",
        ),
        (
            AndesDkmt.stiffness(&g1, 0.02, &mat, 1e-3),
            AndesDkmt.stiffness(&g2, 0.02, &mat, 1e-3),
            "ANDES+DKMT K",
        ),
        (
            AndesDkmt.geometric_stiffness(&g1, 0.02, &mat, &nf),
            AndesDkmt.geometric_stiffness(&g2, 0.02, &mat, &nf2),
            "ANDES+DKMT K_G",
        ),
    ] {
        let scale = k1.abs().max();
        for a in 0..3 {
            for b in 0..3 {
                for i in 0..6 {
                    for j in 0..6 {
                        let v1 = k1[(6 * a + i, 6 * b + j)];
                        let v2 = k2[(6 * perm[a] + i, 6 * perm[b] + j)];
                        assert!(
                            (v1 - v2).abs() < 1e-10 * scale,
                            "{what} ({a},{b},{i},{j}): {v1} vs {v2}"
                        );
                    }
                }
            }
        }
    }
}
