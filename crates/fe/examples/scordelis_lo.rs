//! Scordelis–Lo roof convergence study (MacNeal & Harder 1985): mid free-edge vertical
//! displacement vs the reference 0.3024, for quarter models n×n and two diagonal patterns.
//!
//! with the reference CST+DKT element (α = 1e-3) and the ANDES/OPT+DKT element.
//!
//! `cargo run --release -p fe --example scordelis_lo`

use kappe_fe::{ElementKind, Material, ShellModel, Support, linear_static};

fn model(n: usize, alpha: f64, pattern: &str, element: ElementKind) -> (ShellModel, usize) {
    let (r0, half_l, ang) = (25.0_f64, 25.0, 40.0_f64.to_radians());
    let mut nodes = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let x = half_l * i as f64 / n as f64;
            let phi = ang * j as f64 / n as f64;
            nodes.push([x, r0 * phi.sin(), r0 * phi.cos()]);
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let tris = match pattern {
        "alternating" => kappe_fe::generate::alternating_triangles(n, n),
        _ => {
            let mut t = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
            t
        }
    };
    let t = 0.25;
    let mut m = ShellModel::new(
        nodes,
        tris,
        t,
        Material {
            youngs_modulus: 4.32e8,
            poisson_ratio: 0.0,
            unit_weight: 90.0 / t,
        },
    );
    m.drilling_alpha = alpha;
    m.element = element;
    for j in 0..=n {
        for i in 0..=n {
            let mut f = [false; 6];
            if i == 0 {
                f[0] = true;
                f[4] = true;
                f[5] = true;
            }
            if i == n {
                f[1] = true;
                f[2] = true;
            }
            if j == 0 {
                f[1] = true;
                f[3] = true;
                f[5] = true;
            }
            if f.iter().any(|b| *b) {
                m.supports.push(Support {
                    node: id(i, j),
                    fixed: f,
                });
            }
        }
    }
    (m, id(0, n))
}

fn main() -> Result<(), kappe_fe::FeError> {
    println!("| element | n | pattern | w (mid free edge) | / 0.3024 |");
    println!("|---|---|---|---|---|");
    for element in [ElementKind::CstDkt, ElementKind::AndesDkt] {
        for pattern in ["alternating", "uniform"] {
            for n in [4, 8, 16, 32, 64] {
                let (m, node) = model(n, 1e-3, pattern, element);
                let s = linear_static(&m)?;
                let w = -s.displacements[node][2];
                println!(
                    "| {element:?} | {n} | {pattern} | {w:.5} | {:.4} |",
                    w / 0.3024
                );
            }
        }
    }
    Ok(())
}
