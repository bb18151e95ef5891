//! Speed of the CEM solver against the compas_cem anchors of cem.md §9
//! (`cargo bench -p cem`). Targets (100× compas_cem 0.8.6): vault_grid500 ≤ 0.2 ms,
//! vault_grid500_braced ≤ 1.5 ms, vault_grid5000 ≤ 4.7 ms.

use kappe_cem::example::vault_grid;
use kappe_cem::json::read_topology;
use kappe_cem::{Model, SolverOptions, Topology, solve};

fn main() {
    divan::main();
}

fn fixture_grid500() -> (Topology, SolverOptions) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fixtures/cem/vault_grid500.input.json"
    );
    let text = std::fs::read_to_string(path).expect("vault_grid500 fixture");
    let file = read_topology(&text).expect("valid fixture");
    (file.topology, file.solver)
}

/// Braced grids converge to eta = 1e-9 like the reference `vault_grid500_braced`.
const BRACED: SolverOptions = SolverOptions {
    tmax: 100,
    eta: 1e-9,
};

/// Full solve: validation, trail building and the equilibrium (what `kappe cem solve` does
/// apart from I/O).
mod solve_full {
    use super::*;

    #[divan::bench]
    fn vault_grid500(b: divan::Bencher) {
        let (t, o) = fixture_grid500();
        b.bench(|| solve(divan::black_box(&t), &o).expect("solves"));
    }

    #[divan::bench]
    fn vault_grid500_braced(b: divan::Bencher) {
        let t = vault_grid(10, 25, true);
        b.bench(|| solve(divan::black_box(&t), &BRACED).expect("solves"));
    }

    #[divan::bench]
    fn vault_grid5000(b: divan::Bencher) {
        let t = vault_grid(50, 50, false);
        b.bench(|| solve(divan::black_box(&t), &SolverOptions::default()).expect("solves"));
    }
}

/// Equilibrium only, on a prebuilt [`Model`] (repeated solves of one topology).
mod solve_model {
    use super::*;

    #[divan::bench]
    fn vault_grid500(b: divan::Bencher) {
        let (t, o) = fixture_grid500();
        let m = Model::new(&t).expect("valid");
        b.bench(|| divan::black_box(&m).solve(&o).expect("solves"));
    }

    #[divan::bench]
    fn vault_grid500_braced(b: divan::Bencher) {
        let m = Model::new(&vault_grid(10, 25, true)).expect("valid");
        b.bench(|| divan::black_box(&m).solve(&BRACED).expect("solves"));
    }

    #[divan::bench]
    fn vault_grid5000(b: divan::Bencher) {
        let m = Model::new(&vault_grid(50, 50, false)).expect("valid");
        b.bench(|| {
            divan::black_box(&m)
                .solve(&SolverOptions::default())
                .expect("solves")
        });
    }
}

/// Fixed-geometry force pass on the solved 5000-node grid (the cap runs ~100 of these).
#[divan::bench]
fn force_pass_grid5000(b: divan::Bencher) {
    let t = vault_grid(50, 50, false);
    let eq = solve(&t, &SolverOptions::default()).expect("solves");
    let pos: Vec<_> = t
        .nodes
        .iter()
        .map(|n| eq.position(n.id).expect("node"))
        .collect();
    b.bench(|| kappe_cem::force_pass(divan::black_box(&t), &pos).expect("passes"));
}

/// Constrained form-finding (targets ≤ 10 ms each).
mod optimize {
    use kappe_cem::{OptimizeOptions, Problem, optimize};

    use super::*;

    #[divan::bench]
    fn opt_arch_span_rise(b: divan::Bencher) {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/fixtures/cem/opt_arch_span_rise.input.json"
        );
        let file = read_topology(&std::fs::read_to_string(path).expect("fixture")).expect("valid");
        let (p, o) = Problem::from_json(file.optimization.as_ref().expect("block")).expect("valid");
        b.bench(|| optimize(divan::black_box(&file.topology), &p, &o).expect("optimizes"));
    }

    /// 40-node tilted arch (2 × 20 nodes), crown force + one shared trail length, feet goals.
    #[divan::bench]
    fn tilted_arch40_span_rise(b: divan::Bencher) {
        let (t, p) = kappe_cem::example::tilted_arch(20);
        let o = OptimizeOptions::default();
        b.bench(|| optimize(divan::black_box(&t), &p, &o).expect("optimizes"));
    }
}
