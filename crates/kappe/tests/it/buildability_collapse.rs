//! The collapse factor as a limit state of a buildability object (issue 24;
//! `kappe::commands::buildability_collapse`): the imperfection amplitude as an uncertain input
//! and its named errors, the exact γ scaling, λ_c against w0 (decreasing, and the perfect path's
//! factor as w0 → 0), FORM of the collapse component against Monte Carlo on the same table, and
//! the table against direct paths at the design points.

use std::sync::atomic::AtomicU64;

use kappe::commands::buildability::{BuildabilitySpec, Resolved, check_layers, run};
use kappe::commands::buildability_collapse::{
    CollapseTables, DESIGN_POINT_BETA_TOLERANCE, IMPERFECTION, direct,
};
use kappe::commands::buildability_reliability::{
    Surrogate, collapse_tables, example_spec, monte_carlo, prepare, reliability_with_points,
};
use kappe::input::DesignError;
use kappe_reliability::{Batch, SamplingOptions, sample_events};

/// The Wolfs cylinder with 24 segments and 12 layers (quick), its strength lowered to
/// f₀ = 2300 Pa (the fixture of `buildability_reliability`'s tests) so that the collapse by
/// strength at a face falls within the 12 layers, the collapse check on (the rule's w0,
/// clamped) with `nonlinear` lines, and `extra`.
fn small(nonlinear: &str, extra: &str) -> String {
    format!(
        "{}\n[analysis.nonlinear]\n{nonlinear}\n{extra}",
        example_spec(12, Some(24), Some(2300.0))
    )
}

/// w0 (a factor on the rule's w0, lognormal, cov 0.5), E₀ (lognormal, cov 0.15) and γ
/// (normal, cov 0.02): the scatter of the example `buildability_collapse` (docs/reliability.md,
/// "Collapse as a limit state").
fn scatter(seed: u64, monte_carlo: bool) -> String {
    format!(
        "[uncertainty]\n\"{IMPERFECTION}\" = {{ dist = \"lognormal\", cov = 0.5 }}\n\
         \"material.time.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}\n\
         \"material.specific_weight\" = {{ dist = \"normal\", cov = 0.02 }}\n\
         seed = {seed}\n{}",
        if monte_carlo {
            "monte_carlo = 2000\n"
        } else {
            ""
        }
    )
}

fn nominal(r: &Resolved) -> [f64; 6] {
    let mut spec = BuildabilitySpec::parse(&small("", &scatter(1, false))).unwrap();
    let table = spec.uncertainty.take().unwrap();
    prepare(r, &table).unwrap().nominal
}

#[test]
fn collapse_factor_scales_exactly_with_the_weight() {
    // λ_c(γ) = λ_c(γ₀)·γ₀/γ (proof in the module docs): γ × 0.8 gives λ_c × 1.25. Tolerance
    // 1e-6 relative: the path visits the same μ = λγ at every step, so only round-off and
    // the Newton iterations' convergence to their relative tolerance separate the two; 1e-6 is
    // far below the path's own location tolerance (1e-3), so a pass shows the scaling and not
    // that tolerance.
    let r = BuildabilitySpec::from_toml_str(&small("", "")).unwrap();
    let p0 = nominal(&r);
    let mut p = p0;
    p[0] *= 0.8;
    for n in [6, 10] {
        let a = direct(&r, n, &p0, 1.0).unwrap();
        let b = direct(&r, n, &p, 1.0).unwrap();
        eprintln!("n = {n}: {a:?}\n {b:?}");
        assert_eq!(a.mode, b.mode);
        assert!(
            ((b.factor / a.factor) / 1.25 - 1.0).abs() < 1e-6,
            "n = {n}: {} → {}",
            a.factor,
            b.factor
        );
    }
}

#[test]
fn collapse_factor_falls_with_the_imperfection_and_tends_to_the_perfect_path() {
    // λ_c of the 8-layer state against the factor m on the rule's w0 (2 mm): a larger
    // imperfection bends the wall more under the same load, so the face stress reaches the
    // strength (or the path its limit) earlier: λ_c strictly decreasing in m over 4, 2, 1,
    // 0.5, 0.25. And as m → 0 the imperfect path tends to the perfect one: at m = 10⁻³
    // (w0 = 2 µm) λ_c lies within 1 % of the perfect path's (`imperfection = 0`) — the bending
    // a 2 µm bow adds is ~10⁻³ of the 2 mm one, whose whole effect (m = 1 against the perfect
    // path) is measured here too and must be larger than that 1 %.
    let r = BuildabilitySpec::from_toml_str(&small("", "")).unwrap();
    let p0 = nominal(&r);
    let n = 8;
    let f: Vec<f64> = [4.0, 2.0, 1.0, 0.5, 0.25]
        .iter()
        .map(|&m| direct(&r, n, &p0, m).unwrap().factor)
        .collect();
    eprintln!("λ_c(m = 4, 2, 1, 0.5, 0.25) = {f:?}");
    assert!(f.windows(2).all(|w| w[0] < w[1]), "{f:?}");
    let perfect = BuildabilitySpec::from_toml_str(&small("imperfection = 0.0", "")).unwrap();
    let c0 = check_layers(&perfect, n).unwrap().collapse.unwrap();
    let tiny = direct(&r, n, &p0, 1e-3).unwrap().factor;
    eprintln!("perfect {c0:?}, m = 1e-3: {tiny}");
    assert!(
        (tiny / c0.factor - 1.0).abs() < 0.01,
        "{tiny} vs {}",
        c0.factor
    );
    assert!(
        (f[2] / c0.factor - 1.0).abs() > 0.01,
        "{} vs {}",
        f[2],
        c0.factor
    );
}

#[test]
fn form_of_the_collapse_agrees_with_monte_carlo_on_the_table() {
    // The print with w0 and E₀ uncertain: every tabulated layer count gets a `collapse`
    // component; the state whose collapse β is nearest 1 (P_f ≈ 0.16, informative at 10⁴
    // samples: the Wilson interval is ±5 % of it) is checked against crude Monte Carlo of the
    // same table (10⁴ seeded samples, a sample fails when λ_c < collapse_min): FORM's P_f
    // inside the 95 % interval. And the table against a direct path at every state's design
    // point: Δβ ≤ DESIGN_POINT_BETA_TOLERANCE (0.05, below FORM's own first-order error).
    let r = BuildabilitySpec::from_toml_str(&small("", "")).unwrap();
    let b = run(&r, &|_| {}).unwrap();
    let mut spec = BuildabilitySpec::parse(&small("", &scatter(4, false))).unwrap();
    let table = spec.uncertainty.take().unwrap();
    let mut sur = Surrogate::build(&r, prepare(&r, &table).unwrap()).unwrap();
    sur.collapse = Some(CollapseTables::build(&r, &sur.prepared, &b.states).unwrap());
    let values: Vec<_> = b
        .states
        .iter()
        .map(|s| {
            (
                s.layers,
                (s.blf, s.strength_utilisation, s.sliding_utilisation),
            )
        })
        .collect();
    eprintln!("{:?}", sur.collapse);
    let (rel, points) = reliability_with_points(&r, &sur, &values, &table).unwrap();
    let col = sur.collapse.as_ref().unwrap();
    eprintln!(
        "tabulated {:?}, span {}, solves {}; nominal λ_c {:?}",
        col.layers(),
        col.span,
        col.solves,
        b.states
            .iter()
            .map(|s| s.collapse_factor)
            .collect::<Vec<_>>()
    );
    for s in &rel.states {
        eprintln!("state {}: {:?}", s.index, s.beta_by_check);
    }
    assert!(!points.is_empty());
    let (n, f) = points
        .iter()
        .min_by(|a, b| (a.1.beta - 1.0).abs().total_cmp(&(b.1.beta - 1.0).abs()))
        .unwrap();
    let p = &sur.prepared;
    let counter = AtomicU64::new(0);
    let mc = sample_events(
        &p.model,
        1,
        &|_u: &[f64], x: &[f64], hits: &mut [bool]| {
            hits[0] = col
                .fails(&r, p, *n, x, false, &counter)
                .map_err(|e| kappe_reliability::EvalError::from(e.to_string()))?;
            Ok(())
        },
        &SamplingOptions::new(10_000, 17),
        Batch { index: 0, count: 1 },
    )
    .unwrap();
    let m = kappe_reliability::merge_events(&[mc]).unwrap();
    let s = &m[0];
    eprintln!(
        "state {n}: FORM β {} P_f {} vs MC {} {:?}",
        f.beta, f.pf, s.pf, s.interval
    );
    assert!(s.pf > 0.01 && s.pf < 0.5, "an informative P_f: {}", s.pf);
    assert!(
        f.pf >= s.interval[0] && f.pf <= s.interval[1],
        "FORM {} vs MC {} {:?}",
        f.pf,
        s.pf,
        s.interval
    );
    let report = col.report(&r, p, &points).unwrap();
    eprintln!("{report:#?}");
    assert!(
        report.max_beta_error <= DESIGN_POINT_BETA_TOLERANCE,
        "{report:?}"
    );
    // The collapse components are in the print's system.
    assert!(
        rel.states
            .iter()
            .any(|s| s.beta_by_check.contains_key("collapse"))
    );
}

#[test]
fn run_with_an_uncertain_imperfection_reports_the_collapse_limit_state() {
    // Through `run` (what `kappe buildability` calls): per state a `collapse` β, the design
    // points checked, and the Monte Carlo counting collapses (the nominal print fails by
    // collapse within 12 layers, so its Monte Carlo fails too).
    let r = BuildabilitySpec::from_toml_str(&small("", &scatter(2, true))).unwrap();
    let b = run(&r, &|_| {}).unwrap();
    let c = b.collapse_reliability.as_ref().unwrap();
    assert_eq!(c.parameters.len(), 2);
    assert!(c.imperfection_is_factor);
    assert_eq!(c.design_points.len(), c.states.len());
    assert!(b.states.iter().any(|s| {
        s.beta_by_check
            .as_ref()
            .is_some_and(|m| m.contains_key("collapse"))
    }));
    let mc = b.monte_carlo.as_ref().unwrap();
    assert!(mc.pf > 0.5, "{mc:?}");
    let doc = kappe::commands::buildability::document(&r, &b);
    assert!(doc["result"]["collapse_reliability"]["max_beta_error"].is_number());

    // The Monte Carlo outside `run` (Python, Dask): the collapse tables built by
    // `collapse_tables` from the same deterministic states and shipped as JSON with the linear
    // tables give `run`'s Monte Carlo bit for bit (every field but the timings and the
    // re-solve count, which belong to the process); tables shipped without them are refused
    // for this nonlinear spec, never sampled without the collapse.
    let text = small("", &scatter(2, true));
    let mut spec = BuildabilitySpec::parse(&text).unwrap();
    let table = spec.uncertainty.take().unwrap();
    let mut sur = Surrogate::build(&r, prepare(&r, &table).unwrap()).unwrap();
    let linear_only = serde_json::to_string(&sur.tables(&text)).unwrap();
    let refused = Surrogate::from_tables(
        &r,
        &text,
        prepare(&r, &table).unwrap(),
        serde_json::from_str(&linear_only).unwrap(),
    )
    .err()
    .unwrap();
    assert!(refused.to_string().contains("collapse"), "{refused}");
    let collapse = collapse_tables(&r, &sur.prepared).unwrap();
    assert_eq!(
        collapse.as_ref().map(CollapseTables::layers),
        Some(c.states.clone()),
        "the same layer counts tabulated as in run"
    );
    let json = serde_json::to_string(&sur.tables(&text).with_collapse(collapse.clone())).unwrap();
    sur.collapse = collapse;
    let shipped = Surrogate::from_tables(
        &r,
        &text,
        prepare(&r, &table).unwrap(),
        serde_json::from_str(&json).unwrap(),
    )
    .unwrap();
    for s in [&sur, &shipped] {
        let m = monte_carlo(&r, s, mc.samples, mc.seed).unwrap();
        assert_eq!(
            (&m.state_pf, &m.failed_by, m.pf, m.pf_interval),
            (&mc.state_pf, &mc.failed_by, mc.pf, mc.pf_interval)
        );
    }
}

#[test]
fn the_imperfection_is_uncertain_only_with_the_collapse_check() {
    let named =
        |text: String, field: &str, words: &str| match BuildabilitySpec::from_toml_str(&text) {
            Err(DesignError::Uncertainty { field: f, message }) => {
                assert_eq!(f, field, "{message}");
                assert!(message.contains(words), "{message}");
            }
            other => panic!("{text}: {other:?}"),
        };
    let var = format!("uncertainty.\"{IMPERFECTION}\"");
    let lognormal =
        format!("[uncertainty]\n\"{IMPERFECTION}\" = {{ dist = \"lognormal\", cov = 0.3 }}\n");
    // Without [analysis.nonlinear].
    named(
        format!("{}\n{lognormal}", example_spec(12, Some(24), None)),
        &var,
        "[analysis.nonlinear]",
    );
    // A normal for a positive amplitude.
    named(
        small(
            "",
            &format!("[uncertainty]\n\"{IMPERFECTION}\" = {{ dist = \"normal\", cov = 0.3 }}\n"),
        ),
        &var,
        "",
    );
    // The perfect path has nothing to scatter.
    named(
        small("imperfection = 0.0", &lognormal),
        &var,
        "perfect path",
    );
    // Three axes (E₀, Ė and w0) are more than a table spans.
    named(
        small(
            "",
            &format!(
                "{lognormal}\"material.time.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.1 }}\n\
                 \"material.time.youngs_modulus_rate\" = {{ dist = \"lognormal\", cov = 0.1 }}\n"
            ),
        ),
        "uncertainty",
        "at most 2",
    );
    // Given w0 in metres, and the rule's factor: both accepted.
    for nl in ["imperfection = 0.002", ""] {
        assert!(BuildabilitySpec::from_toml_str(&small(nl, &lognormal)).is_ok());
    }
}
