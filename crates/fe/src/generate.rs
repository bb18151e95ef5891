//! Structured meshes of the benchmark cases (buckling.md §5 and the `fixtures/fe` vaults), for
//! tests, benchmarks and examples at any refinement.

use crate::model::{Material, ShellModel, Support};

/// Node index of grid point (i, j) with `nx + 1` points per row.
fn id(nx: usize, i: usize, j: usize) -> usize {
    j * (nx + 1) + i
}

/// Triangles of an `nx × ny` structured grid, diagonals alternating with (i + j) parity
/// (the pattern of `fixtures/fe/vault_s3_*`), consistently oriented.
pub fn alternating_triangles(nx: usize, ny: usize) -> Vec<[usize; 3]> {
    let mut t = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (
                id(nx, i, j),
                id(nx, i + 1, j),
                id(nx, i + 1, j + 1),
                id(nx, i, j + 1),
            );
            if (i + j) % 2 == 0 {
                t.push([a, b, c]);
                t.push([a, c, d]);
            } else {
                t.push([a, b, d]);
                t.push([b, c, d]);
            }
        }
    }
    t
}

/// The barrel vault of `fixtures/fe/vault_s3_*`: span 1 m, rise 0.25 m (R = 0.625 m,
/// half-angle 0.9273 rad), length 0.6 m along y, t = 0.02 m, E = 1 MPa, ν = 0.3,
/// γ = 23 044 N/m³ self-weight; both springing lines pinned (translations fixed).
/// `n_arc` elements around the arc, `n_len` along the length.
pub fn barrel_vault(n_arc: usize, n_len: usize) -> ShellModel {
    let r: f64 = 0.625;
    let rise = 0.25;
    let half = (0.5_f64 / r).asin();
    let length = 0.6;
    let mut nodes = Vec::with_capacity((n_arc + 1) * (n_len + 1));
    for j in 0..=n_len {
        let y = length * j as f64 / n_len as f64;
        for i in 0..=n_arc {
            let phi = -half + 2.0 * half * i as f64 / n_arc as f64;
            nodes.push([r * phi.sin(), y, r * phi.cos() - (r - rise)]);
        }
    }
    let mut m = ShellModel::new(
        nodes,
        alternating_triangles(n_arc, n_len),
        0.02,
        Material {
            youngs_modulus: 1.0e6,
            poisson_ratio: 0.3,
            unit_weight: 23_044.0,
        },
    );
    for j in 0..=n_len {
        m.supports.push(Support::pinned(id(n_arc, 0, j)));
        m.supports.push(Support::pinned(id(n_arc, n_arc, j)));
    }
    m
}

/// Simply supported square plate `a × a` (t = 0.01 m, E = 1 MPa, ν = 0.3, no self-weight) under
/// a uniform compressive edge traction N_x = 1 N/m on x = 0 and x = a (consistent nodal
/// forces), as `fixtures/fe/plate_ss_s3_*`: w = 0 on all edges, in-plane rigid-body motion
/// removed at mid-edge nodes. The buckling factor equals N_cr in N/m (closed form 3.61524).
pub fn ss_plate(n: usize) -> ShellModel {
    let a = 1.0;
    let mut nodes = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            nodes.push([a * i as f64 / n as f64, a * j as f64 / n as f64, 0.0]);
        }
    }
    let tris = alternating_triangles(n, n);
    let mut m = ShellModel::new(
        nodes,
        tris,
        0.01,
        Material {
            youngs_modulus: 1.0e6,
            poisson_ratio: 0.3,
            unit_weight: 0.0,
        },
    );
    m.gravity = [0.0; 3];
    let mut fixed = vec![[false; 6]; (n + 1) * (n + 1)];
    for j in 0..=n {
        for i in 0..=n {
            if i == 0 || j == 0 || i == n || j == n {
                fixed[id(n, i, j)][2] = true;
            }
        }
    }
    let mid = n / 2;
    fixed[id(n, mid, mid)][0] = true;
    fixed[id(n, 0, mid)][1] = true;
    fixed[id(n, n, mid)][1] = true;
    for (node, f) in fixed.into_iter().enumerate() {
        if f.iter().any(|b| *b) {
            m.supports.push(Support { node, fixed: f });
        }
    }
    let h = a / n as f64;
    for j in 0..=n {
        let w = if j == 0 || j == n { 0.5 * h } else { h };
        m.nodal_loads.push(crate::model::NodalLoad {
            node: id(n, 0, j),
            force: [w, 0.0, 0.0],
            moment: [0.0; 3],
        });
        m.nodal_loads.push(crate::model::NodalLoad {
            node: id(n, n, j),
            force: [-w, 0.0, 0.0],
            moment: [0.0; 3],
        });
    }
    m
}

/// [`ss_plate`] with thickness `thickness` and **hard** simple supports for a
/// Reissner–Mindlin plate: on x = 0, a also θx (the rotation whose Kirchhoff value is ∂w/∂y,
/// the tangential slope of the edge) is fixed, on y = 0, a also θy. This is the support of
/// the Navier (double-sine) solution of the Mindlin plate; with the rotations free ("soft"
/// support) a shear-deformable plate has an edge boundary layer and buckles lower.
/// For a Kirchhoff element both give the same limit.
pub fn ss_plate_hard(n: usize, thickness: f64) -> ShellModel {
    let mut m = ss_plate(n);
    m.thickness = vec![thickness];
    let mut fixed = vec![[false; 6]; m.nodes.len()];
    for s in &m.supports {
        if let Some(f) = fixed.get_mut(s.node) {
            *f = s.fixed;
        }
    }
    for j in 0..=n {
        for i in 0..=n {
            let f = &mut fixed[id(n, i, j)];
            if i == 0 || i == n {
                f[3] = true;
            }
            if j == 0 || j == n {
                f[4] = true;
            }
        }
    }
    m.supports = fixed
        .into_iter()
        .enumerate()
        .filter(|(_, f)| f.iter().any(|b| *b))
        .map(|(node, fixed)| Support { node, fixed })
        .collect();
    m
}
