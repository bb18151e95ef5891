//! Benchmark: symbolic analysis + assembly + static + K_G + 3 buckling modes on barrel-vault
//! meshes of the fixture family (`generate::barrel_vault`), ~10⁴ and ~10⁵ nodes. Prints a
//! markdown table (wall times per phase, nnz, operator applications, peak RSS).
//!
//! `cargo run --release -p fe --example bench_buckling [-- all|small|large|small-sturm|large-nosturm|… [cst|andes]]`
//! (second argument: the element, default the reference CST+DKT).
//! Targets (buckling.md §4): 10⁴ nodes ≤ 2 s, 10⁵ nodes ≤ 30 s and ≤ 2 GB, on 2 cores.

use std::time::Instant;

use kappe_fe::generate::barrel_vault;
use kappe_fe::{BucklingOptions, BucklingSolver, ElementKind, FeError};

/// Peak resident set size of this process (MB) from /proc (Linux); `None` elsewhere.
fn peak_rss_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn run(n_arc: usize, n_len: usize, sturm: bool, element: ElementKind) -> Result<(), FeError> {
    let mut model = barrel_vault(n_arc, n_len);
    model.element = element;
    let t0 = Instant::now();
    let solver = BucklingSolver::new(&model)?;
    let r = solver.buckling(
        &model,
        &BucklingOptions {
            modes: 3,
            sturm_check: sturm,
            ..Default::default()
        },
    )?;
    let total = t0.elapsed().as_secs_f64();
    let s = r.stats;
    println!(
        "| {} | {} | {} | {:.2e} | {:.2e} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {} | **{:.2}** | {:.0} | {:.6}, {:.6}, {:.6} |",
        model.nodes.len(),
        s.n_free_dofs,
        if sturm { "yes" } else { "no" },
        s.nnz_k as f64,
        s.nnz_l as f64,
        s.t_symbolic,
        s.t_assembly,
        s.t_factor,
        s.t_geometric,
        s.t_eigen,
        s.t_sturm,
        s.operator_applications,
        total,
        peak_rss_mb().unwrap_or(f64::NAN),
        r.factors.first().copied().unwrap_or(f64::NAN),
        r.factors.get(1).copied().unwrap_or(f64::NAN),
        r.factors.get(2).copied().unwrap_or(f64::NAN),
    );
    Ok(())
}

fn main() -> Result<(), FeError> {
    let which = std::env::args().nth(1).unwrap_or_else(|| "all".into());
    let element = std::env::args()
        .nth(2)
        .and_then(|e| ElementKind::from_name(&e))
        .unwrap_or_default();
    println!("element: {}\n", element.description());
    println!(
        "| nodes | free DOFs | Sturm | nnz(K) | nnz(L) | symbolic s | assembly s | factor+static s | stresses+K_G s | Lanczos s | Sturm s | K⁻¹K_G applications | total s | peak RSS MB | λ₁, λ₂, λ₃ |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    // Each configuration can run in its own process (`small-sturm`, `large-nosturm`, …) so
    // the peak RSS column is not the high-water mark of an earlier run.
    let cases = [
        ("small", 130, 76),  // 131 × 77 = 10 087 nodes
        ("large", 410, 243), // 411 × 244 = 100 284 nodes
    ];
    for (name, na, nl) in cases {
        for sturm in [false, true] {
            let tag = format!("{name}-{}", if sturm { "sturm" } else { "nosturm" });
            if which == "all" || which == name || which == tag {
                run(na, nl, sturm, element)?;
            }
        }
    }
    Ok(())
}
