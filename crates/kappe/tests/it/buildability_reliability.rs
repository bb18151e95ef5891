//! The chance a buildability object stands (issue 24): the exact scalings the tables rest on,
//! the tables against re-solves, FORM against Monte Carlo, batches that merge bit for bit, and
//! the input checks of a buildability spec's `[uncertainty]`.

use kappe::commands::buildability::{BuildabilitySpec, Resolved, run};
use kappe::commands::buildability_reliability::{
    PARAMETERS, Surrogate, SurrogateTables, exact_state, example_scatter, example_spec,
    monte_carlo, monte_carlo_batch, monte_carlo_result, prepare, reliability, table_part_layers,
};
use kappe::input::DesignError;
use kappe_reliability::{Batch, SamplingOptions};

/// The Wolfs cylinder with 24 segments and 12 layers (quick), its strength lowered to
/// f₀ = 2300 Pa so that the 12-layer state is near its strength limit (u ≈ 0.9), and `extra`.
fn small(extra: &str) -> String {
    format!("{}\n{extra}", example_spec(12, Some(24), Some(2300.0)))
}

/// The `buildability_mc` example's scatter (the same fixture), seed 3.
fn scatter() -> String {
    example_scatter(3)
}

fn resolved(extra: &str) -> (Resolved, kappe::input::UncertaintyTable) {
    let mut spec = BuildabilitySpec::parse(&small(extra)).unwrap();
    let table = spec.uncertainty.take().unwrap_or_else(|| {
        let mut s = BuildabilitySpec::parse(&small(&scatter())).unwrap();
        s.uncertainty.take().unwrap()
    });
    (spec.resolve().unwrap(), table)
}

fn nominal(r: &Resolved) -> [f64; 6] {
    let p = prepare(r, &{
        let mut s = BuildabilitySpec::parse(&small(&scatter())).unwrap();
        s.uncertainty.take().unwrap()
    })
    .unwrap();
    p.nominal
}

#[test]
fn buckling_factor_and_stresses_scale_exactly_with_stiffness_and_weight() {
    // The reductions the tables rest on, checked by re-solves: E₀ and Ė × c and γ × g give
    // BLF × c/g and every stress × g (the load is linear in γ, a uniform factor on the
    // stiffness leaves the stresses), hence the strength utilisation × g. Tolerance 1e-8: the
    // eigenvalue's error is of the order of the Lanczos residual squared (1e-12), the static
    // solve's of round-off.
    let (r, _) = resolved("");
    let p0 = nominal(&r);
    let (c, g) = (1.7, 0.8);
    let mut p = p0;
    p[0] *= g;
    p[1] *= c;
    p[2] *= c;
    for n in [4, 12] {
        let a = exact_state(&r, n, &p0).unwrap();
        let b = exact_state(&r, n, &p).unwrap();
        let (ba, bb) = (a.0.unwrap(), b.0.unwrap());
        assert!(
            ((bb / ba) / (c / g) - 1.0).abs() < 1e-8,
            "n = {n}: {ba} → {bb}"
        );
        let (ua, ub) = (a.1.unwrap(), b.1.unwrap());
        assert!(((ub / ua) / g - 1.0).abs() < 1e-8, "n = {n}: {ua} → {ub}");
        let (sa, sb) = (a.2.unwrap(), b.2.unwrap());
        assert!(((sb / sa) / g - 1.0).abs() < 1e-8, "n = {n}: {sa} → {sb}");
    }
    // Without waits the layer time enters the moduli only through ρ = (Ė/E₀)(T/T₀): T × 1.3
    // with Ė / 1.3 leaves the buckling factor (the strength's ages do change).
    let mut q = p0;
    q[5] *= 1.3;
    q[2] /= 1.3;
    let a = exact_state(&r, 12, &p0).unwrap().0.unwrap();
    let b = exact_state(&r, 12, &q).unwrap().0.unwrap();
    assert!((b / a - 1.0).abs() < 1e-8, "{a} vs {b}");
}

#[test]
fn tables_match_resolves_at_random_points() {
    // Interpolation in ρ through 9 Chebyshev points against re-solves at 4 seeded points of the
    // model × every 3rd layer count. BLF: 1e-5 relative (a smooth function of ln ρ; measured
    // ≈ 1e-7 here). Strength and sliding: 1e-3 (the worst element of a layer can change with
    // ρ, a kink the polynomial rounds off; measured below 1e-4).
    let (r, table) = resolved(&scatter());
    let sur = Surrogate::build(&r, prepare(&r, &table).unwrap()).unwrap();
    assert!(sur.reducible);
    let e = sur.verify(&r, 4, 11, 3).unwrap();
    assert!(e[0] < 1e-5, "BLF {e:?}");
    assert!(e[1] < 1e-3 && e[2] < 1e-3, "utilisations {e:?}");
}

#[test]
fn form_of_the_strength_state_agrees_with_monte_carlo() {
    // The 12-layer state fails by strength near u = 1: FORM's P_f against 10⁴ crude Monte Carlo
    // samples of the same model (seeded), inside the Monte Carlo's 95 % (Wilson) interval.
    // Without the scatter of ḟ: the capacity f₀ + ḟ·a of two lognormals makes the strength
    // limit state curved in u-space, and FORM's first-order error then shows at 10⁴ samples
    // (FORM 0.0263 vs Monte Carlo 0.0229 [0.0201, 0.0260]; docs/reliability.md, Limits).
    let rate =
        "\"material.time.compressive_strength_rate\" = { dist = \"lognormal\", cov = 0.10 }\n";
    let without_rate = scatter().replace(rate, "");
    assert_ne!(without_rate, scatter(), "the fixture's ḟ line moved");
    let (r, table) = resolved(&without_rate);
    let sur = Surrogate::build(&r, prepare(&r, &table).unwrap()).unwrap();
    let values: Vec<_> = (1..=12)
        .map(|n| (n, sur.state(&r, n, &sur.prepared.nominal).unwrap()))
        .collect();
    let rel = reliability(&r, &sur, &values, &table).unwrap();
    let s12 = rel.states.iter().find(|s| s.index == 12).unwrap();
    let mc = monte_carlo(&r, &sur, 10_000, 5).unwrap();
    let m = mc.state_pf[11];
    assert!(m[0] > 0.01 && m[0] < 0.5, "an informative P_f: {m:?}");
    assert!(
        s12.pf >= m[1] && s12.pf <= m[2],
        "FORM {} vs MC {m:?}",
        s12.pf
    );
    // The print fails when some state does: at least as likely as its likeliest state.
    assert!(mc.pf >= m[0]);
}

/// The same state with the scatter of ḟ (cov 0.1), where FORM's P_f (0.0263) lay outside the
/// sampled interval (docs/reliability.md, Limits): the state's SORM P_f (its components'
/// Hohenbichler–Rackwitz P_f, the Hessian of the table-based g by second differences, in the
/// state's series system) against the same 10⁴ crude samples (seed 5), inside the 95 % (Wilson)
/// interval.
#[test]
fn sorm_of_the_strength_state_with_the_rate_agrees_with_monte_carlo() {
    let (r, table) = resolved(&scatter());
    let sur = Surrogate::build(&r, prepare(&r, &table).unwrap()).unwrap();
    let values: Vec<_> = (1..=12)
        .map(|n| (n, sur.state(&r, n, &sur.prepared.nominal).unwrap()))
        .collect();
    let rel = reliability(&r, &sur, &values, &table).unwrap();
    let s12 = rel.states.iter().find(|s| s.index == 12).unwrap();
    let mc = monte_carlo(&r, &sur, 10_000, 5).unwrap();
    let m = mc.state_pf[11];
    let sorm = s12.pf_sorm.unwrap();
    eprintln!("12 layers: FORM {}, SORM {sorm}, Monte Carlo {m:?}", s12.pf);
    assert!(m[0] > 0.01 && m[0] < 0.5, "an informative P_f: {m:?}");
    assert!(
        sorm >= m[1] && sorm <= m[2],
        "SORM {sorm} (FORM {}) vs MC {m:?}",
        s12.pf
    );
}

#[test]
fn monte_carlo_batches_merge_into_the_single_run_bit_for_bit() {
    let (r, table) = resolved(&scatter());
    let sur = Surrogate::build(&r, prepare(&r, &table).unwrap()).unwrap();
    let o = SamplingOptions::new(2500, 9);
    let one = monte_carlo_batch(&r, &sur, &o, Batch { index: 0, count: 1 }).unwrap();
    let parts: Vec<_> = (0..3)
        .rev()
        .map(|i| monte_carlo_batch(&r, &sur, &o, Batch { index: i, count: 3 }).unwrap())
        .collect();
    let a = monte_carlo_result(&[one], 0, [0.0; 2]).unwrap();
    let b = monte_carlo_result(&parts, 0, [0.0; 2]).unwrap();
    assert_eq!(a, b);
    assert!(a.failed_by.windows(2).all(|w| w[0] <= w[1]));
}

/// The table parts tile the layer counts for any number of parts, each about the same work.
#[test]
fn table_parts_tile_the_layer_counts() {
    for max in [1usize, 2, 12, 60] {
        for count in [1usize, 2, 3, 4, 7, 64] {
            let parts: Vec<_> = (0..count)
                .map(|i| table_part_layers(max, i, count))
                .collect();
            let all: Vec<usize> = parts.iter().flat_map(|p| p.clone()).collect();
            assert_eq!(
                all,
                (1..=max).collect::<Vec<_>>(),
                "{max} layers, {count} parts"
            );
            if count <= max {
                // Σ n per part within one layer count's share of the even split.
                let even = (max * (max + 1) / 2) as f64 / count as f64;
                for p in &parts {
                    let w: usize = p.clone().sum();
                    assert!(
                        (w as f64 - even).abs() <= max as f64,
                        "{max}/{count}: {p:?}"
                    );
                }
            }
        }
    }
}

/// Tables built once and shipped as JSON (what a Dask worker receives), whole or joined from
/// parts built apart, sample the same bits as the tables they were built from; tables of
/// another spec text, and parts with a gap, are refused by name.
#[test]
fn shipped_tables_sample_the_same_bits() {
    let text = small(&scatter());
    let (r, table) = resolved(&scatter());
    let sur = Surrogate::build(&r, prepare(&r, &table).unwrap()).unwrap();
    assert!(sur.reducible, "the test spec must use the tables");
    let json = serde_json::to_string(&sur.tables(&text)).unwrap();
    let shipped = |text: &str, json: &str| {
        let t = serde_json::from_str(json).unwrap();
        Surrogate::from_tables(&r, text, prepare(&r, &table).unwrap(), t)
    };
    let copy = shipped(&text, &json).unwrap();
    let part = |layers| {
        let s = Surrogate::build_layers(&r, prepare(&r, &table).unwrap(), layers).unwrap();
        serde_json::from_str(&serde_json::to_string(&s.tables(&text)).unwrap()).unwrap()
    };
    let joined = SurrogateTables::join(vec![part(1..=4), part(9..=12), part(5..=8)]).unwrap();
    let from_parts = shipped(&text, &serde_json::to_string(&joined).unwrap()).unwrap();
    // Every state's values at a point off the nominal one, to the bit (Debug prints the
    // shortest representation that reads back as the same f64).
    let mut p = nominal(&r);
    p.iter_mut().for_each(|v| *v *= 1.07);
    for n in 1..=r.spec.object.max_layers {
        let a = format!("{:?}", sur.state(&r, n, &p).unwrap());
        assert_eq!(
            a,
            format!("{:?}", copy.state(&r, n, &p).unwrap()),
            "state {n}"
        );
        assert_eq!(
            a,
            format!("{:?}", from_parts.state(&r, n, &p).unwrap()),
            "state {n}"
        );
    }
    let gap = SurrogateTables::join(vec![part(1..=4), part(6..=12)]).unwrap_err();
    assert!(gap.to_string().contains("5 was due"), "{gap}");
    let o = SamplingOptions::new(2500, 9);
    let b = Batch { index: 0, count: 1 };
    let a = monte_carlo_batch(&r, &sur, &o, b).unwrap();
    let c = monte_carlo_batch(&r, &from_parts, &o, b).unwrap();
    assert_eq!(
        monte_carlo_result(&[a], 0, [0.0; 2]).unwrap(),
        monte_carlo_result(&[c], 0, [0.0; 2]).unwrap()
    );
    let e = shipped(&format!("{text}\n# another spec\n"), &json).unwrap_err();
    assert!(e.to_string().contains("another spec"), "{e}");
}

#[test]
fn run_with_uncertainty_reports_beta_per_state_and_for_the_print() {
    let (r, _) = {
        let spec = BuildabilitySpec::from_toml_str(&small(&scatter())).unwrap();
        (spec, ())
    };
    let b = run(&r, &|_| {}).unwrap();
    let rel = b.reliability.as_ref().unwrap();
    assert!(b.states.iter().all(|s| s.beta.is_some() && s.pf.is_some()));
    // The series system fails at least as often as its likeliest state, up to the sampling
    // error of the two importance-sampling estimates (the state's 4000 samples and the print's
    // 20 000 have coefficients of variation of 1–3 % at P_f ≈ 0.02): 5 %.
    let worst = b.states.iter().filter_map(|s| s.pf).fold(0.0, f64::max);
    assert!(rel.pf >= 0.95 * worst, "{} vs {worst}", rel.pf);
    assert!(
        rel.design_point
            .contains_key("material.time.compressive_strength")
    );
    let doc = kappe::commands::buildability::document(&r, &b);
    assert!(doc["result"]["reliability"]["beta"].is_number());
    assert!(doc["result"]["states"][11]["beta_by_check"]["strength"].is_number());
}

#[test]
fn bad_uncertainty_in_a_buildability_spec_is_a_named_error() {
    let cases = [
        (
            "[uncertainty]\n\"material.youngs_modulus\" = { dist = \"lognormal\", cov = 0.1 }\n",
            "uncertainty.\"material.youngs_modulus\"",
            "allowed names",
        ),
        (
            "[uncertainty]\n\"process.layer_time\" = { dist = \"normal\", std = -1.0 }\n",
            "uncertainty.\"process.layer_time\"",
            "",
        ),
        (
            "[uncertainty]\n\"material.specific_weight\" = { dist = \"normal\", cov = 0.02 }\n\
             monte_carlo = 10\n",
            "uncertainty.monte_carlo",
            "at least 100",
        ),
    ];
    for (extra, field, words) in cases {
        match BuildabilitySpec::from_toml_str(&small(extra)) {
            Err(DesignError::Uncertainty { field: f, message }) => {
                assert_eq!(f, field, "{message}");
                assert!(message.contains(words), "{message}");
            }
            other => panic!("{extra}: {other:?}"),
        }
    }
    // A strength parameter needs the uniaxial strength model.
    let mohr = small(
        "[uncertainty]\n\"material.time.compressive_strength\" = { dist = \"lognormal\", cov = 0.1 }\n",
    )
    .replace(
        "compressive_strength = 2300.0",
        "cohesion = 1150.0\nfriction_angle_deg = 0.0",
    )
    .replace("compressive_strength_rate = 2.45", "cohesion_rate = 1.2");
    match BuildabilitySpec::from_toml_str(&mohr) {
        Err(DesignError::Uncertainty { field, message }) => {
            assert_eq!(field, "uncertainty.\"material.time.compressive_strength\"");
            assert!(message.contains("uniaxial"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(PARAMETERS.len(), 6);
}
