//! Timing comparison with CalculiX 2.20 on the same mesh: writes a `*BUCKLE` deck of the
//! barrel vault (S3 on the same triangles, and S4 on the quads of the same grid/nodes), runs
//! `ccx` (must be on PATH, e.g. `apt-get install calculix-ccx`), and prints a table with the
//! ccx wall time and factors next to kappe-fe's.
//!
//! `cargo run --release -p fe --example ccx_compare -- [N_ARC N_LEN [WORKDIR]]`
//! (default 130 76 → 10 087 nodes, workdir `target/ccx_compare`). OMP_NUM_THREADS=2.
//!
//! ccx expands S3/S4 shells to one layer of C3D6/C3D8I solids (3 nodes through the thickness
//! per shell node, 3 DOF each), SPOOLES factorisation + ARPACK shift-invert (buckling.md §8).

use std::path::PathBuf;
use std::time::Instant;

use kappe_fe::generate::barrel_vault;
use kappe_fe::{BucklingOptions, ShellModel, buckling, ccx};

fn deck(m: &ShellModel, n_arc: usize, n_len: usize, quads: bool, scale: f64) -> String {
    let mut s = String::from("*HEADING\nkappe-fe benchmark vault\n");
    ccx::write_nodes(&mut s, &m.nodes);
    if quads {
        let id = |i: usize, j: usize| j * (n_arc + 1) + i + 1;
        let quads = (0..n_len).flat_map(|j| {
            (0..n_arc).map(move |i| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
        });
        ccx::write_elements(&mut s, "S4", quads);
    } else {
        let tris = m
            .triangles
            .iter()
            .map(|t| t.iter().map(|n| n + 1).collect());
        ccx::write_elements(&mut s, "S3", tris);
    }
    let fixed = m.fixed_mask();
    ccx::write_supports(
        &mut s,
        (0..m.nodes.len()).filter(|&n| fixed[n][0]).map(|n| n + 1),
    );
    let step = ccx::BuckleStep::of(m, 3);
    ccx::write_buckle_step(&mut s, &step, scale);
    s
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n_arc: usize = args.first().map_or(Ok(130), |a| a.parse())?;
    let n_len: usize = args.get(1).map_or(Ok(76), |a| a.parse())?;
    let dir = args
        .get(2)
        .map_or_else(|| PathBuf::from("target/ccx_compare"), PathBuf::from);
    std::fs::create_dir_all(&dir)?;
    let m = barrel_vault(n_arc, n_len);

    let t0 = Instant::now();
    let r = buckling(&m, &BucklingOptions::default())?;
    let t_k = t0.elapsed().as_secs_f64();
    println!("| solver | element | shell nodes | wall s | λ₁, λ₂, λ₃ |");
    println!("|---|---|---|---|---|");
    println!(
        "| kappe-fe | CST+DKT facet (Sturm check on) | {} | {t_k:.2} | {:?} |",
        m.nodes.len(),
        r.factors
    );
    // ccx's ARPACK buckling mode finds the factors nearest its shift and silently skips lower
    // ones when they are far below 1 (buckling.md §8): run a scaled pass A (load × 0.01) to
    // locate λ₁, then pass B with the load scaled so that λ₁ ≈ 2, and unscale. Timed: pass B
    // (as the fixtures' `ccx_wall_time_s`) and A + B.
    for quads in [false, true] {
        let name = if quads { "vault_s4" } else { "vault_s3" };
        let elem = if quads {
            "S4 (→ C3D8I)"
        } else {
            "S3 (→ C3D6)"
        };
        let ((wall_a, _, ok_a), pass_b) =
            ccx::two_pass(&dir, name, |scale| deck(&m, n_arc, n_len, quads, scale))?;
        let Some((wall_b, fb, ok_b)) = pass_b else {
            println!(
                "| CalculiX 2.20 (pass A failed) | {elem} | {} | {wall_a:.2} | [] |",
                m.nodes.len()
            );
            continue;
        };
        println!(
            "| CalculiX 2.20 ({}) | {elem} | {} | {wall_b:.2} (A+B {:.2}) | {fb:?} |",
            if ok_a && ok_b { "ok" } else { "FAILED" },
            m.nodes.len(),
            wall_a + wall_b
        );
    }
    Ok(())
}
