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

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use kappe_fe::generate::barrel_vault;
use kappe_fe::{BucklingOptions, ShellModel, buckling};

fn deck(m: &ShellModel, n_arc: usize, n_len: usize, quads: bool, scale: f64) -> String {
    let mut s = String::from("*HEADING\nkappe-fe benchmark vault\n*NODE\n");
    for (i, p) in m.nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {:.12e}, {:.12e}, {:.12e}", i + 1, p[0], p[1], p[2]);
    }
    if quads {
        s.push_str("*ELEMENT, TYPE=S4, ELSET=EALL\n");
        let id = |i: usize, j: usize| j * (n_arc + 1) + i + 1;
        let mut e = 1;
        for j in 0..n_len {
            for i in 0..n_arc {
                let _ = writeln!(
                    s,
                    "{e}, {}, {}, {}, {}",
                    id(i, j),
                    id(i + 1, j),
                    id(i + 1, j + 1),
                    id(i, j + 1)
                );
                e += 1;
            }
        }
    } else {
        s.push_str("*ELEMENT, TYPE=S3, ELSET=EALL\n");
        for (e, t) in m.triangles.iter().enumerate() {
            let _ = writeln!(s, "{}, {}, {}, {}", e + 1, t[0] + 1, t[1] + 1, t[2] + 1);
        }
    }
    s.push_str("*NSET, NSET=SUP\n");
    let fixed = m.fixed_mask();
    let sup: Vec<String> = (0..m.nodes.len())
        .filter(|&n| fixed[n][0])
        .map(|n| (n + 1).to_string())
        .collect();
    for chunk in sup.chunks(10) {
        let _ = writeln!(s, "{}", chunk.join(", "));
    }
    let mat = m.materials[0];
    let g = 9.81;
    let _ = write!(
        s,
        "*BOUNDARY\nSUP, 1, 3\n*MATERIAL, NAME=CLAY\n*ELASTIC\n{:e}, {}\n*DENSITY\n{:e}\n\
         *SHELL SECTION, ELSET=EALL, MATERIAL=CLAY\n{}\n*STEP\n*BUCKLE\n3, 1e-6\n\
         *DLOAD\nEALL, GRAV, {:.8e}, 0., 0., -1.\n*END STEP\n",
        mat.youngs_modulus,
        mat.poisson_ratio,
        mat.unit_weight / g,
        m.thickness[0],
        g * scale
    );
    s
}

/// Buckling factors from the ccx `.dat` file.
fn factors(dat: &Path) -> Vec<f64> {
    let Ok(text) = std::fs::read_to_string(dat) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut on = false;
    for line in text.lines() {
        if line.contains("B U C K L I N G") {
            on = true;
            continue;
        }
        if on {
            let w: Vec<&str> = line.split_whitespace().collect();
            if let [a, b] = w.as_slice()
                && let (Ok(_), Ok(f)) = (a.parse::<usize>(), b.parse::<f64>())
            {
                out.push(f);
            }
        }
    }
    out
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
        let run = |scale: f64| -> Result<(f64, Vec<f64>, bool), Box<dyn std::error::Error>> {
            std::fs::write(
                dir.join(format!("{name}.inp")),
                deck(&m, n_arc, n_len, quads, scale),
            )?;
            let t = Instant::now();
            let status = Command::new("ccx")
                .arg(name)
                .current_dir(&dir)
                .env("OMP_NUM_THREADS", "2")
                .env("CCX_NPROC_EQUATION_SOLVER", "2")
                .stdout(std::process::Stdio::null())
                .status()?;
            let wall = t.elapsed().as_secs_f64();
            let f = factors(&dir.join(format!("{name}.dat")))
                .into_iter()
                .map(|x| x * scale)
                .collect();
            Ok((wall, f, status.success()))
        };
        let (wall_a, fa, ok_a) = run(0.01)?;
        let Some(&l1) = fa.first() else {
            println!(
                "| CalculiX 2.20 (pass A failed) | {elem} | {} | {wall_a:.2} | [] |",
                m.nodes.len()
            );
            continue;
        };
        let (wall_b, fb, ok_b) = run(l1 / 2.0)?;
        println!(
            "| CalculiX 2.20 ({}) | {elem} | {} | {wall_b:.2} (A+B {:.2}) | {fb:?} |",
            if ok_a && ok_b { "ok" } else { "FAILED" },
            m.nodes.len(),
            wall_a + wall_b
        );
    }
    Ok(())
}
