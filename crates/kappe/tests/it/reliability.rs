//! Reliability of the print states under `[uncertainty]` (issue 24): named errors for bad input,
//! the exact scalings against a re-solve, FORM against Monte Carlo, and no change without the
//! table.

use kappe::analysis::{AnalysisOptions, StateSelection, state_buckling, state_material};
use kappe::analysis::{Check, GreenField, Vars, check_form, limit_state, prepare, scaled_ages};
use kappe::form::build_state;
use kappe::{Design, Options, design_cap, no_progress, run};
use kappe_reliability::{SamplingOptions, WithGradient, monte_carlo};

/// Final state only, 8 layers per mesh row (as `analysis.rs`'s `final_coarse`).
fn small() -> Design {
    let mut d = Design::default();
    d.cap.length = 0.15;
    d.print.path_sampling = 0.04;
    d.robot.enabled = false;
    d.analysis = AnalysisOptions {
        states: StateSelection::Every(usize::MAX),
        row_stride: 8,
        ..AnalysisOptions::default()
    };
    d
}

fn with_uncertainty(extra: &str) -> Result<Design, kappe::DesignError> {
    Design::from_toml_str(&format!("name = \"u\"\n{extra}"))
}

#[test]
fn bad_uncertainty_is_a_named_error() {
    let cases = [
        (
            "[uncertainty]\n\"material.youngs_modulus\" = { dist = \"lognormal\", std = -5.0 }\n",
            "material.youngs_modulus",
        ),
        (
            "[uncertainty]\n\"material.colour\" = { dist = \"normal\", std = 1.0 }\n",
            "material.specific_weight",
        ),
        (
            "[uncertainty]\n\"material.youngs_modulus\" = { dist = \"normal\", cov = 0.1 }\n",
            "positive",
        ),
        (
            "[uncertainty]\n\"material.youngs_modulus\" = { dist = \"lognormal\", cov = 0.1 }\n\
             \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n\
             \"material.poisson_ratio\" = { dist = \"lognormal\", cov = 0.05 }\n\
             [uncertainty.correlation]\n\
             \"material.youngs_modulus\" = { \"material.specific_weight\" = 0.9, \"material.poisson_ratio\" = 0.9 }\n\
             \"material.specific_weight\" = { \"material.poisson_ratio\" = -0.9 }\n",
            "uncertainty.correlation",
        ),
        (
            // The imperfection is an input of the collapse check only: without
            // [analysis.nonlinear] it is refused with the reason, not as an unknown name.
            "[uncertainty]\n\
             \"analysis.nonlinear.imperfection\" = { dist = \"lognormal\", cov = 0.5 }\n",
            "[analysis.nonlinear]",
        ),
    ];
    for (text, needle) in cases {
        let e = with_uncertainty(text).unwrap_err();
        let msg = e.to_string();
        assert!(
            matches!(
                e,
                kappe::DesignError::Uncertainty { .. } | kappe::DesignError::Parse { .. }
            ),
            "{msg}"
        );
        assert!(msg.contains(needle), "`{needle}` not in: {msg}");
        assert!(msg.contains("uncertainty"), "no field named: {msg}");
    }
}

/// BLF ∝ E/γ with a uniform E: the shortcut against a re-solve of the shell with E×1.3, γ×0.8.
#[test]
fn buckling_scaling_matches_a_resolve() {
    let d = small();
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let o = d.analysis.clone();
    let last = cap.states.len() - 1;
    let state = build_state(&cap.sections, &cap.frame, 0.0, last).unwrap();
    let mut mat = state_material(
        &cap,
        &o,
        last,
        Some(&kappe::analysis::CapGreen::new(&cap).unwrap()),
    );
    let blf0 = state_buckling(&state, &mat, &o.with_split_at_most(2), &Default::default())
        .unwrap()
        .buckling
        .factors[0];
    mat.youngs_modulus *= 1.3;
    mat.unit_weight *= 0.8;
    let blf1 = state_buckling(&state, &mat, &o.with_split_at_most(2), &Default::default())
        .unwrap()
        .buckling
        .factors[0];
    let table = with_uncertainty(
        "[uncertainty]\n\"material.youngs_modulus\" = { dist = \"lognormal\", cov = 0.2 }\n\
         \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n",
    )
    .unwrap()
    .uncertainty
    .unwrap();
    let model = table.model(&d).unwrap();
    let v = Vars::of(&model, &cap);
    // Variables are in name order: specific_weight, youngs_modulus.
    let x = [
        d.material.specific_weight * 0.8,
        d.material.youngs_modulus * 1.3,
    ];
    let mut grad = [0.0; 2];
    let g = limit_state(
        Check::Buckling {
            blf: blf0,
            s_nu: 0.0,
        },
        v,
        (-1.0, 0.0, 1.0),
        &x,
        &mut grad,
    );
    // 1e-6 relative: the eigensolver converges each factor to a relative residual ≪ 1e-6, and
    // the scaling is exact (K ∝ E, K_G ∝ γ), so only solver round-off separates the two.
    assert!(
        ((g + 1.0) / blf1 - 1.0).abs() < 1e-6,
        "scaled {} vs re-solved {blf1}",
        g + 1.0
    );
}

/// FORM of a buckling limit state with the exact scalings against crude Monte Carlo of the same
/// g, 2·10⁴ seeded samples: the FORM P_f must lie in the 95 % (Wilson) interval.
#[test]
fn form_agrees_with_monte_carlo() {
    let d = small();
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let table = with_uncertainty(
        "[uncertainty]\n\"material.youngs_modulus\" = { dist = \"lognormal\", cov = 0.35 }\n\
         \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n",
    )
    .unwrap()
    .uncertainty
    .unwrap();
    let model = table.model(&d).unwrap();
    let v = Vars::of(&model, &cap);
    // BLF₀ = 1.6 against BLF_min = 1: P_f ≈ 9 %, where 2·10⁴ samples resolve it to ±5 %.
    let check = Check::Buckling {
        blf: 1.6,
        s_nu: 0.0,
    };
    let limits = (-2.0e4, 0.0, 1.0);
    let r = check_form(&model, check, v, limits).unwrap();
    let mut g = WithGradient(|x: &[f64], grad: &mut [f64]| limit_state(check, v, limits, x, grad));
    let mc = monte_carlo(&model, &mut g, &SamplingOptions::new(20_000, 7)).unwrap();
    assert!(
        mc.interval[0] <= r.pf && r.pf <= mc.interval[1],
        "FORM P_f {} outside the MC interval {:?} (MC P_f {})",
        r.pf,
        mc.interval,
        mc.pf
    );
}

/// Without `[uncertainty]` nothing changes: no reliability, no new keys in summary.json; with
/// it the print gets a finite β and the analysed state its β per check.
#[test]
fn reliability_only_with_the_table() {
    let d = small();
    let out = run(&d, &Options::of(&d), &no_progress).unwrap();
    assert!(out.reliability.is_none());
    let json = serde_json::to_string(&out.summary()).unwrap();
    for key in ["\"reliability\"", "\"beta\"", "\"pf\"", "\"beta_by_check\""] {
        assert!(
            !json.contains(key),
            "{key} in the summary without [uncertainty]"
        );
    }
    let mut du = d.clone();
    du.uncertainty = with_uncertainty(
        "[uncertainty]\n\"material.youngs_modulus\" = { dist = \"lognormal\", cov = 0.3 }\n\
         \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n",
    )
    .unwrap()
    .uncertainty;
    let out_u = run(&du, &Options::of(&du), &no_progress).unwrap();
    let r = out_u.reliability.as_ref().unwrap();
    assert!(r.beta.is_finite() && r.pf > 0.0 && r.pf < 1.0, "{r:?}");
    let last = r
        .states
        .iter()
        .find(|s| s.beta_by_check.contains_key("buckling"));
    assert!(last.is_some(), "no buckling check in {:?}", r.states);
    // The report plots β over the print only when there is a reliability (issue 24).
    let title = "Reliability index β per state";
    assert!(out_u.report_html().unwrap().contains(title));
    assert!(!out.report_html().unwrap().contains(title));
    // The deterministic results are the same run's.
    assert_eq!(
        out.analysis.as_ref().map(|a| a.constraints.clone()),
        out_u.analysis.as_ref().map(|a| a.constraints.clone())
    );
}

/// A 0.6 m × 0.8 m wall, 2 cm thick, clamped at its base under its own weight, whose element rows
/// have the moduli of printed layers of different ages: E(row j) = E₀ + Ė·age_j, age_j = 60 s
/// per row below the top. Returns the model and each element's age.
fn aged_wall(e0: f64, rate: f64) -> (kappe_fe::ShellModel, Vec<f64>) {
    let (nx, ny, w, h) = (6, 8, 0.6, 0.8);
    let mut nodes = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([w * i as f64 / nx as f64, 0.0, h * j as f64 / ny as f64]);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let (mut tris, mut ages) = (Vec::new(), Vec::new());
    for j in 0..ny {
        let age = 60.0 * (ny - 1 - j) as f64;
        for i in 0..nx {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            ages.extend([age, age]);
        }
    }
    let base = kappe_fe::Material {
        youngs_modulus: e0,
        poisson_ratio: 0.3,
        unit_weight: 2.0e4,
    };
    let mut m = kappe_fe::ShellModel::new(nodes, tris, 0.02, base);
    m.materials = ages
        .iter()
        .map(|a| kappe_fe::Material {
            youngs_modulus: e0 + rate * a,
            ..base
        })
        .collect();
    m.supports = (0..=nx).map(kappe_fe::Support::clamped).collect();
    (m, ages)
}

/// Tight Lanczos residual for the finite differences: the factor's error is of the order of its
/// square, so the difference quotient's round-off stays near 1e-12/step ≪ 1e-5.
fn tight_blf(m: &kappe_fe::ShellModel) -> kappe_fe::BucklingResult {
    kappe_fe::buckling(
        m,
        &kappe_fe::BucklingOptions {
            modes: 1,
            tolerance: 1e-12,
            ..Default::default()
        },
    )
    .unwrap()
}

/// dλ/dE₀ and dλ/dĖ of the aged wall (eigenvalue sensitivity with ∂K_G/∂p from the force
/// redistribution) against central finite differences of re-solves, relative 1e-5 (issue 24's
/// verification). Step 1e-4 of each parameter: the central difference's truncation error is
/// O(step²) ≈ 1e-8 relative, its round-off ≈ 1e-12/1e-4 = 1e-8. Also Euler's identity for a
/// modulus linear in (E₀, Ė): E₀·∂λ/∂E₀ + Ė·∂λ/∂Ė = λ (λ is homogeneous of degree 1 in them).
#[test]
fn blf_sensitivity_of_an_aged_wall_matches_finite_differences() {
    let (e0, rate) = (1.0e5, 150.0);
    let (m, ages) = aged_wall(e0, rate);
    let r = tight_blf(&m);
    let lambda = r.factors[0];
    let de = vec![vec![1.0; ages.len()], ages.clone()];
    let d =
        kappe::analysis::blf_derivatives(&m, lambda, &r.modes[0], &r.static_result, &de).unwrap();
    for (k, (p, name)) in [(e0, "E0"), (rate, "rate")].into_iter().enumerate() {
        let h = 1e-4 * p;
        let at = |s: f64| {
            let (e, ra) = if k == 0 {
                (e0 + s * h, rate)
            } else {
                (e0, rate + s * h)
            };
            tight_blf(&aged_wall(e, ra).0).factors[0]
        };
        let fd = (at(1.0) - at(-1.0)) / (2.0 * h);
        assert!(
            (d[k] / fd - 1.0).abs() < 1e-5,
            "dλ/d{name}: sensitivity {} vs central difference {fd}",
            d[k]
        );
    }
    let euler = e0 * d[0] + rate * d[1];
    assert!(
        (euler / lambda - 1.0).abs() < 1e-6,
        "E0·dλ/dE0 + Ė·dλ/dĖ = {euler} vs λ = {lambda}"
    );
}

/// A cap state with a linear time model: dλ/dE₀ and dλ/dĖ of the analysis' shell (the function
/// the reliability analysis calls) against central differences of the same function's λ,
/// relative 1e-5 (steps and tolerance as for the wall).
#[test]
fn blf_sensitivity_of_a_cap_state_matches_finite_differences() {
    let mut d = small();
    d.material.time = Some(kappe::input::TimeModelSpec {
        model: Some(kappe::input::TimeLaw::Linear),
        youngs_modulus: Some(2.0e6),
        youngs_modulus_rate: Some(2.0e4),
        ..Default::default()
    });
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    let last = cap.states.len() - 1;
    let time = d.time_model().unwrap();
    let solve = |t: &kappe::input::TimeModel| {
        kappe::analysis::time_state_blf(&cap, &d.analysis, &green.schedule, t, last, 1e-12)
            .unwrap()
            .unwrap()
    };
    let (lambda, dl) = solve(&time);
    let ages = green.schedule.ages(last + 1);
    assert!(
        ages[0] > 60.0,
        "the bottom layer's age {} s makes the moduli non-uniform",
        ages[0]
    );
    for (k, dk) in dl.into_iter().enumerate() {
        let p = if k == 0 {
            time.youngs_modulus.initial
        } else {
            time.youngs_modulus.rate
        };
        let h = 1e-4 * p;
        let at = |s: f64| {
            let mut t = time.clone();
            if k == 0 {
                t.youngs_modulus.initial += s * h;
            } else {
                t.youngs_modulus.rate += s * h;
            }
            solve(&t).0
        };
        let fd = (at(1.0) - at(-1.0)) / (2.0 * h);
        assert!(
            (dk / fd - 1.0).abs() < 1e-5,
            "state {last}, parameter {k}: sensitivity {dk} vs central difference {fd} (λ {lambda})"
        );
    }
}

/// The small cap printed slowly (44 states, 57 min) from a mix whose modulus grows with age,
/// E(t) = 1.3 MPa + 400 Pa/s·t, with E₀ lognormal (coefficient of variation 0.15) and, when
/// `percent_per_hour` is given, drifting at that rate.
fn study14(percent_per_hour: Option<f64>) -> Design {
    let mut d = small();
    d.print.print_speed = 0.01;
    let drift = percent_per_hour.map_or(String::new(), |r| {
        format!(
            "[uncertainty.drift]\n\"material.time.youngs_modulus\" = {{ percent_per_hour = {r:?} }}\n"
        )
    });
    let u = with_uncertainty(&format!(
        "[material.time]\nmodel = \"linear\"\nyoungs_modulus = 1.3e6\nyoungs_modulus_rate = 400.0\n\
         [uncertainty]\n\"material.time.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}\n{drift}"
    ))
    .unwrap();
    d.material.time = u.material.time;
    d.uncertainty = u.uncertainty;
    d
}

/// FORM's time-parameter buckling components take the ratio's denominator, λ of the state's
/// shell at the design's values, from the deterministic analysis (its print-layer mesh factor
/// `blf_mesh`) instead of a re-solve: the two are the same shell (grading, row stride, element,
/// the moduli at the schedule's ages). Every analysed state of study No. 14's cap: the re-solve
/// (Lanczos residual 1e-10) equals `blf_mesh` within 1e-5 relative, the analysis' own Lanczos
/// residual with the mesh error controlled (a Ritz value lies within its relative residual of
/// an eigenvalue); a different mesh or moduli would differ by far more (a row stride of 8
/// against 4 moves λ by percents).
#[test]
fn analysis_factor_is_the_resolve_at_the_mean() {
    let mut d = study14(Some(-20.0));
    d.analysis.states = StateSelection::All;
    d.uncertainty = None;
    let out = run(&d, &Options::of(&d), &no_progress).unwrap();
    let analysis = out.analysis.as_ref().unwrap();
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let time = d.time_model().unwrap();
    let (mut checked, mut worst) = (0, 0.0_f64);
    for s in &analysis.states {
        let Some(mesh) = s.blf_mesh else { continue };
        let (l, _) = kappe::analysis::time_state_blf(
            &cap,
            &analysis.options,
            &out.schedule,
            &time,
            s.index,
            1e-10,
        )
        .unwrap()
        .unwrap();
        assert!(
            (l / mesh - 1.0).abs() < 1e-5,
            "state {}: re-solve {l} vs the analysis' blf_mesh {mesh}",
            s.index
        );
        worst = worst.max((l / mesh - 1.0).abs());
        checked += 1;
    }
    eprintln!("{checked} states: largest relative difference {worst:.2e}");
    assert!(checked > 30, "only {checked} states had a mesh factor");
}

/// Study No. 14's story (the paper: a cap that met every constraint collapsed as the mix dried
/// over the testing period). The cap passes on nominal values and keeps β ≥ β_min = 2.3 with a
/// steady mix; a mix drying at −20 %/h (E₀ falls 19 % over the print) pulls the last states'
/// β below the target; `kappe schedule`'s least waits with the same drift bring every state
/// back to β ≥ β_min (each state re-checked on the final schedule).
#[test]
fn study14_drying_mix_and_the_waits_that_keep_beta() {
    use kappe::commands::least_waits::{check_state_on, least_waits};
    let beta_min = kappe::input::BETA_MIN_DEFAULT;
    // Nominal values: every state passes without a wait.
    let mut nominal = study14(None);
    nominal.uncertainty = None;
    let cap = design_cap(&nominal, kappe::Context::default()).unwrap();
    let plan = least_waits(&cap, &nominal.analysis, 0.0, &|_| {}).unwrap();
    assert!(
        plan.infeasible.is_empty() && plan.states.iter().all(|c| c.pass),
        "nominal fails: {:?}",
        plan.infeasible
    );
    // The last states govern (the cap's BLF falls towards its completion, BLF₀ of the last
    // state 1.39); the earlier ones have β > 4 either way.
    let last_betas = |d: &Design| -> Vec<f64> {
        let cap = design_cap(d, kappe::Context::default()).unwrap();
        let green = kappe::analysis::CapGreen::new(&cap).unwrap();
        let n = cap.states.len();
        (n - 4..n)
            .map(|q| {
                check_state_on(&cap, &green, &d.analysis, &green.schedule, q)
                    .unwrap()
                    .beta
                    .unwrap()
            })
            .collect()
    };
    let steady = last_betas(&study14(None));
    assert!(
        steady.iter().all(|b| *b >= beta_min),
        "steady mix: β {steady:?} below {beta_min}"
    );
    let drying = study14(Some(-20.0));
    let dried = last_betas(&drying);
    let low = dried.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(low < beta_min, "drying mix: β {dried:?} all ≥ {beta_min}");
    // The least waits with the same drift.
    let cap = design_cap(&drying, kappe::Context::default()).unwrap();
    let plan = least_waits(&cap, &drying.analysis, 600.0, &|_| {}).unwrap();
    assert!(plan.infeasible.is_empty(), "{:?}", plan.infeasible);
    assert!(plan.schedule.total_wait_s() > 0.0, "no wait was needed");
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    for q in 0..cap.states.len() {
        let c = check_state_on(&cap, &green, &drying.analysis, &plan.schedule, q).unwrap();
        assert!(c.pass, "state {q} on the final schedule: {c:?}");
        assert!(
            c.beta.is_none_or(|b| b >= beta_min),
            "state {q}: β {:?} < {beta_min}",
            c.beta
        );
    }
}

/// FORM of a time-parameter limit state against crude Monte Carlo (issue 24): the last state of
/// study No. 14's cap with the mix drying at −20 %/h and E₀ lognormal (cov 0.15). With E₀ alone
/// FORM is exact for this monotone g, so the test checks the chain (the drifted state model,
/// the re-solves, the BLF₀ ratio) against an independent sampler; with Ė lognormal (cov 0.3)
/// too, FORM's first-order error shows (P_f 0.128 vs Monte Carlo 0.113 [0.107, 0.119], 10⁴
/// samples: docs/reliability.md, Limits) and SORM's test below takes over. FORM re-solves the
/// shell at every iterate (exact g and gradient); the 10⁴ Monte Carlo samples (seeded) use the
/// exact reduction λ(E₀, Ė) = (E₀/E₀⁰)·Λ(Ė/E₀) (the moduli E₀ + Ė·a are E₀ times a shape in
/// Ė/E₀), with Λ interpolated in ln(Ė/E₀) through 15 Chebyshev points over the ±5σ box and
/// checked against re-solves at 3 points (relative 1e-6; 9 points left 7e-6). FORM's P_f lies
/// in the Monte Carlo's 95 % (Wilson) interval.
#[test]
fn form_of_a_time_parameter_state_agrees_with_monte_carlo() {
    let (state, results, mc) = time_state_against_monte_carlo(false);
    let form_pf = results[0].1.pf;
    assert!(
        mc.pf > 0.005 && mc.pf < 0.5,
        "an informative P_f: MC {mc:?}, FORM {form_pf} (state β {})",
        state.beta
    );
    assert!(
        form_pf >= mc.interval[0] && form_pf <= mc.interval[1],
        "FORM P_f {form_pf} (β {}) vs Monte Carlo {} {:?}",
        results[0].1.beta,
        mc.pf,
        mc.interval
    );
    // One variable: no tangent direction, so SORM is FORM to the bit.
    assert_eq!(results[0].2.pf, form_pf);
}

/// SORM of the same state with E₀ (cov 0.15) and Ė (cov 0.3) lognormal, where FORM's P_f lay
/// outside the sampled interval (docs/reliability.md, Limits), against the same 10⁴ seeded
/// Monte Carlo samples of the same reduction: SORM's P_f (Hohenbichler–Rackwitz, L″ from the
/// 1-D reduction's Hermite cubic, no extra eigensolve) lies in the 95 % (Wilson) interval.
/// Also its curvature against SORM with the Hessian by central differences of the exact
/// gradient (four more re-solves, h = 10⁻³ in u): relative 10⁻³ on P_f (the cubic's L″
/// error h_y²L⁗/12 for re-solves h_y apart, and the differences' eigen-residual noise
/// 10⁻⁸/10⁻³ = 10⁻⁵, are both far below that; a wrong chain-rule term would move P_f by
/// percents).
#[test]
fn sorm_of_a_time_parameter_state_agrees_with_monte_carlo() {
    let (state, results, mc) = time_state_against_monte_carlo(true);
    let (_, form, sorm) = &results[0];
    eprintln!(
        "FORM P_f {} (β {}), SORM {} (β {}; {:?}), Monte Carlo {} {:?}; state SORM {:?}",
        form.pf, form.beta, sorm.pf, sorm.beta, sorm.form_only, mc.pf, mc.interval, state.pf_sorm
    );
    assert_eq!(sorm.form_only, None, "SORM through the reduction");
    assert!(
        sorm.pf >= mc.interval[0] && sorm.pf <= mc.interval[1],
        "SORM P_f {} (FORM {}) vs Monte Carlo {} {:?}",
        sorm.pf,
        form.pf,
        mc.pf,
        mc.interval
    );
    // The independent Hessian: differences of the re-solves' exact gradient at the design point.
    let d = study14_with_rate(true);
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    let (model, drifts, v) = prepare(&cap).unwrap().unwrap();
    let q = cap.states.len() - 1;
    let t_hours = green.schedule.layers[q].end_s / 3600.0;
    let dm = model.drifted(&drifts, t_hours).unwrap();
    let time = d.time_model().unwrap();
    let blf0 = kappe::analysis::time_state_blf(&cap, &d.analysis, &green.schedule, &time, q, 1e-10)
        .unwrap()
        .unwrap()
        .0;
    let mut g = kappe::analysis::TimeBuckling::new(
        (&cap, &d.analysis, &green.schedule),
        time,
        v,
        (blf0, 0.0, q),
        d.constraints.blf_min,
        None,
    );
    let r = kappe::analysis::time_buckling_form(&dm, &mut g).unwrap();
    let reduced = kappe::analysis::time_buckling_sorm(&dm, &mut g, &r);
    let fd = kappe_reliability::sorm(&dm, &mut g, &r, &Default::default()).unwrap();
    assert_eq!(
        fd.hessian,
        kappe_reliability::HessianSource::GradientDifferences
    );
    eprintln!(
        "curvatures by differences {:?}: P_f {} against the reduction's {}",
        fd.curvatures, fd.pf, reduced.pf
    );
    assert!(
        (reduced.pf / fd.pf - 1.0).abs() < 1e-3,
        "SORM by the reduction {} vs by differences {}",
        reduced.pf,
        fd.pf
    );
}

/// Study No. 14 with the mix drying at −20 %/h and E₀ lognormal (cov 0.15); with `rate`, Ė
/// lognormal (cov 0.3) too.
fn study14_with_rate(rate: bool) -> Design {
    let mut d = study14(None);
    let extra = if rate {
        "\"material.time.youngs_modulus_rate\" = { dist = \"lognormal\", cov = 0.3 }\n"
    } else {
        ""
    };
    let u = with_uncertainty(&format!(
        "[material.time]\nmodel = \"linear\"\nyoungs_modulus = 1.3e6\nyoungs_modulus_rate = 400.0\n\
         [uncertainty]\n\"material.time.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}\n\
         {extra}[uncertainty.drift]\n\"material.time.youngs_modulus\" = {{ percent_per_hour = -20.0 }}\n",
    ))
    .unwrap();
    d.uncertainty = u.uncertainty;
    d
}

/// The last state of [`study14_with_rate`]: its FORM (and SORM) by `state_form`, and 10⁴ crude
/// Monte Carlo samples (seed 21) of the exact reduction λ(E₀, Ė) = (E₀/E₀⁰)·λ(E₀⁰, E₀⁰·Ė/E₀)
/// with λ(E₀⁰, ·) interpolated in ln(Ė/E₀) (see the FORM test's docs).
fn time_state_against_monte_carlo(
    rate: bool,
) -> (
    kappe::analysis::StateReliability,
    Vec<(
        &'static str,
        kappe_reliability::FormResult,
        kappe::analysis::ComponentSorm,
    )>,
    kappe_reliability::SamplingResult,
) {
    use kappe::analysis::state_form;
    use kappe::analysis::time_state_blf;
    let d = study14_with_rate(rate);
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    let (model, drifts, v) = prepare(&cap).unwrap().unwrap();
    let q = cap.states.len() - 1;
    let t_hours = green.schedule.layers[q].end_s / 3600.0;
    let time = d.time_model().unwrap();
    let lambda = |e0: f64, rate: f64| {
        let mut t = time.clone();
        t.youngs_modulus.initial = e0;
        t.youngs_modulus.rate = rate;
        time_state_blf(&cap, &d.analysis, &green.schedule, &t, q, 1e-10)
            .unwrap()
            .unwrap()
            .0
    };
    let (e00, r00) = (time.youngs_modulus.initial, time.youngs_modulus.rate);
    let blf0 = lambda(e00, r00);
    let blf_min = d.constraints.blf_min;
    let check = Check::BucklingTime {
        blf: blf0,
        s_nu: 0.0,
        top: q,
        shell0: None,
    };
    let (state, results) = state_form(
        &cap,
        &d.analysis,
        &green.schedule,
        (&model, &drifts, v),
        q,
        t_hours,
        &[check],
    )
    .unwrap()
    .unwrap();
    // Λ(ρ) through Chebyshev points of ln ρ over the drifted model's ±5σ box.
    let dm = model.drifted(&drifts, t_hours).unwrap();
    let var = |name: &str| {
        let i = dm.index_of(name).ok()?;
        Some((i, dm.variables()[i].distribution))
    };
    let (ie, de) = var("material.time.youngs_modulus").unwrap();
    let ir = var("material.time.youngs_modulus_rate");
    let rate_at = |z: f64| ir.map_or(r00, |(_, dr)| dr.from_standard(z));
    let lo = (rate_at(-5.0) / de.from_standard(5.0)).ln();
    let hi = (rate_at(5.0) / de.from_standard(-5.0)).ln();
    let k = 15;
    let pi = std::f64::consts::PI;
    let th: Vec<f64> = (0..k)
        .map(|j| (2 * j + 1) as f64 * pi / (2 * k) as f64)
        .collect();
    let nodes: Vec<f64> = th
        .iter()
        .map(|t| 0.5 * (lo + hi) + 0.5 * (hi - lo) * t.cos())
        .collect();
    let w: Vec<f64> = th
        .iter()
        .enumerate()
        .map(|(j, t)| if j % 2 == 0 { t.sin() } else { -t.sin() })
        .collect();
    let vals: Vec<f64> = nodes
        .iter()
        .map(|s| lambda(e00, e00 * s.exp()).ln())
        .collect();
    let interp = |s: f64| {
        let (mut num, mut den) = (0.0, 0.0);
        for j in 0..k {
            let c = w[j] / (s - nodes[j]);
            num += c * vals[j];
            den += c;
        }
        (num / den).exp()
    };
    for (e0, rate) in [
        (0.8 * e00, 1.5 * r00),
        (1.2 * e00, 0.6 * r00),
        (e00, 2.5 * r00),
    ] {
        let exact = lambda(e0, rate);
        let approx = (e0 / e00) * interp((rate / e0).ln());
        assert!(
            (approx / exact - 1.0).abs() < 1e-6,
            "Λ interpolation {approx} vs re-solve {exact}"
        );
    }
    let mut g = |x: &[f64]| {
        let rate = ir.map_or(r00, |(i, _)| x[i]);
        let rho = (rate / x[ie]).ln().clamp(lo, hi);
        (x[ie] / e00) * interp(rho) - blf_min
    };
    let mc = monte_carlo(&dm, &mut g, &SamplingOptions::new(10_000, 21)).unwrap();
    (state, results, mc)
}

/// The small cap with a strength model: E constant in time unless `e_rate` > 0 (linear law),
/// uniaxial strength f(t) = `f0` + `f_rate`·t with friction angle `phi` (degrees).
fn green_cap(e_rate: f64, f0: f64, f_rate: f64, phi: f64) -> Design {
    let mut d = small();
    d.material.time = Some(kappe::input::TimeModelSpec {
        model: Some(kappe::input::TimeLaw::Linear),
        youngs_modulus: Some(d.material.youngs_modulus),
        youngs_modulus_rate: Some(e_rate),
        compressive_strength: Some(f0),
        compressive_strength_rate: Some(f_rate),
        friction_angle_deg: Some(phi),
        ..Default::default()
    });
    d
}

/// The `[uncertainty]` table `table` (its entries), parsed alone: a design file's parse checks
/// it against that file's own material, which here is set in code.
fn table_of(table: &str) -> kappe::input::UncertaintyTable {
    toml::from_str(table).unwrap()
}

fn uncertain(d: &Design, table: &str) -> Design {
    let mut d = d.clone();
    let t = table_of(table);
    t.model(&d).unwrap();
    d.uncertainty = Some(t);
    d
}

/// A strength parameter without a strength model, one of the other strength form, and the
/// print speed without a time model: named errors that say what is allowed.
#[test]
fn strength_parameters_and_the_speed_are_named_errors() {
    let lognormal = "{ dist = \"lognormal\", cov = 0.1 }";
    let cases = [
        (
            small(),
            format!("\"material.time.compressive_strength\" = {lognormal}\n"),
            "strength model",
        ),
        (
            green_cap(0.0, 5.0e3, 0.0, 0.0),
            format!("\"material.time.cohesion\" = {lognormal}\n"),
            "compressive_strength (uniaxial)",
        ),
        (
            small(),
            format!("\"print.print_speed\" = {lognormal}\n"),
            "time model",
        ),
        (
            green_cap(0.0, 5.0e3, 0.0, 0.0),
            "\"print.print_speed\" = { dist = \"normal\", cov = 0.1 }\n".to_owned(),
            "positive",
        ),
    ];
    for (d, table, needle) in cases {
        let e = table_of(&table).model(&d).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, kappe::DesignError::Uncertainty { .. }), "{msg}");
        assert!(msg.contains(needle), "`{needle}` not in: {msg}");
        assert!(msg.contains("uncertainty."), "no field named: {msg}");
    }
}

/// Closed form: with a strength constant in time (rate 0, φ = 0) and f₀ lognormal alone, every
/// layer's utilisation is u₀·f₀⁰/f₀, so the state's strength β is exactly
/// (−ln u₀ − ζ²/2)/ζ, ζ² = ln(1 + cov²), u₀ the deterministic verdict's utilisation. FORM of a
/// limit state linear in ln f₀ converges in one step; 1e-6 absolute covers its convergence
/// test (|G| ≤ 1e-6 relative) and the static solves' round-off (≤ 1e-10 relative in u₀).
#[test]
fn strength_beta_of_a_constant_strength_is_the_closed_form() {
    // f₀ = 10 kPa first, then scaled so the worst state's u₀ is 0.7 (u ∝ 1/f₀ exactly).
    let probe = green_cap(0.0, 1.0e4, 0.0, 0.0);
    let out = run(&probe, &Options::of(&probe), &no_progress).unwrap();
    let u = out
        .analysis
        .as_ref()
        .unwrap()
        .states
        .iter()
        .filter_map(|s| s.strength_utilisation)
        .fold(0.0, f64::max);
    assert!(u > 0.0, "no strength check in the probe run");
    let d = green_cap(0.0, 1.0e4 * u / 0.7, 0.0, 0.0);
    let cov: f64 = 0.1;
    let d = uncertain(
        &d,
        &format!(
            "\"material.time.compressive_strength\" = {{ dist = \"lognormal\", cov = {cov} }}\n"
        ),
    );
    let out = run(&d, &Options::of(&d), &no_progress).unwrap();
    let r = out.reliability.as_ref().unwrap();
    let zeta = (1.0 + cov * cov).ln().sqrt();
    let mut checked = 0;
    for s in &out.analysis.as_ref().unwrap().states {
        let Some(u0) = s.strength_utilisation else {
            continue;
        };
        let state = r.states.iter().find(|x| x.index == s.index).unwrap();
        let beta = state.beta_by_check["strength"];
        let exact = (-u0.ln() - 0.5 * zeta * zeta) / zeta;
        assert!(
            (beta - exact).abs() < 1e-6,
            "state {}: FORM β {beta} vs closed form {exact} (u₀ {u0})",
            s.index
        );
        checked += 1;
    }
    assert!(checked > 0, "no state with a strength β");
}

/// The layer-by-layer strength and sliding utilisations at a trial point of γ, f₀, ḟ, φ and the
/// print speed against the deterministic verdict re-run with those values (E constant in time,
/// so the stresses do not depend on the ages and the reduction is exact: the stresses scale
/// with γ, each layer's age with v₀/v). 1e-8 relative: two static solves of load vectors that
/// differ by a factor, and ages summed in a different order, round-off only. Then the whole
/// run with the five uncertain: a finite β with strength and sliding components.
#[test]
fn strength_and_speed_limit_states_match_a_rerun() {
    // f₀ = 30 kPa: the last state passes (u₀ ≈ 0.65) with a finite β.
    let f0 = 3.0e4;
    let d = green_cap(0.0, f0, 3.0, 20.0);
    let table = "\"material.specific_weight\" = { dist = \"normal\", cov = 0.03 }\n\
                 \"material.time.compressive_strength\" = { dist = \"lognormal\", cov = 0.15 }\n\
                 \"material.time.compressive_strength_rate\" = { dist = \"lognormal\", cov = 0.2 }\n\
                 \"material.time.friction_angle_deg\" = { dist = \"lognormal\", cov = 0.1 }\n\
                 \"print.print_speed\" = { dist = \"lognormal\", cov = 0.1 }\n";
    let du = uncertain(&d, table);
    let cap = design_cap(&du, kappe::Context::default()).unwrap();
    let (model, _, v) = prepare(&cap).unwrap().unwrap();
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    let time = du.time_model().unwrap();
    let last = cap.states.len() - 1;
    let field = GreenField::solve(&cap, &du.analysis, &green.schedule, last)
        .unwrap()
        .unwrap();
    // Variables in name order.
    let names: Vec<&str> = model.variables().iter().map(|v| v.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "material.specific_weight",
            "material.time.compressive_strength",
            "material.time.compressive_strength_rate",
            "material.time.friction_angle_deg",
            "print.print_speed"
        ]
    );
    let m = &d.material;
    let trial = [
        m.specific_weight * 1.04,
        f0 * 0.9,
        3.0 * 1.2,
        23.0,
        d.print.print_speed * 1.3,
    ];
    let verdict = |x: &[f64]| {
        let mut e = green_cap(0.0, x[1], x[2], x[3]);
        e.material.specific_weight = x[0];
        e.print.print_speed = x[4];
        let out = run(&e, &Options::of(&e), &no_progress).unwrap();
        let s = out.analysis.unwrap().states.last().cloned().unwrap();
        (
            s.strength_utilisation.unwrap(),
            s.sliding_utilisation.unwrap(),
        )
    };
    let nominal = [m.specific_weight, f0, 3.0, 20.0, d.print.print_speed];
    for x in [nominal, trial] {
        let (st, sl) = verdict(&x);
        let ours = (
            field.utilisation(v, &time, &x, None, false),
            field.utilisation(v, &time, &x, None, true),
        );
        assert!(
            (ours.0 / st - 1.0).abs() < 1e-8 && (ours.1 / sl - 1.0).abs() < 1e-8,
            "at {x:?}: strength {} vs re-run {st}, sliding {} vs {sl}",
            ours.0,
            ours.1
        );
    }
    let out = run(&du, &Options::of(&du), &no_progress).unwrap();
    let r = out.reliability.as_ref().unwrap();
    let s = r.states.iter().find(|s| s.index == last).unwrap();
    assert!(r.beta.is_finite() && s.beta.is_finite(), "{r:?}");
    for k in ["strength", "sliding", "buckling"] {
        assert!(s.beta_by_check.contains_key(k), "no {k} in {s:?}");
    }
}

/// The print speed in the buckling check: ∂λ/∂s (s = v₀/v scales every print duration) from
/// the eigenvalue sensitivity against central differences of re-solves (step 1e-4 of s, the
/// tolerance 1e-5 as for E₀ and Ė), and the scaled ages against the schedule of the design
/// printed at v = 1.25 v₀ (relative 1e-9 on λ: the same shell, ages summed in another order).
#[test]
fn print_speed_sensitivity_of_a_cap_state() {
    use kappe::analysis::time_state_blf_ages;
    let mut d = small();
    d.material.time = Some(kappe::input::TimeModelSpec {
        model: Some(kappe::input::TimeLaw::Linear),
        youngs_modulus: Some(2.0e6),
        youngs_modulus_rate: Some(2.0e4),
        ..Default::default()
    });
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    let time = d.time_model().unwrap();
    let last = cap.states.len() - 1;
    let at = |s: f64| {
        let (ages, print) = scaled_ages(&green.schedule, last, s);
        time_state_blf_ages(&cap, &d.analysis, &ages, &print, &time, last, 1e-12)
            .unwrap()
            .unwrap()
    };
    let (lambda, dl) = at(1.0);
    let h = 1e-4;
    let fd = (at(1.0 + h).0 - at(1.0 - h).0) / (2.0 * h);
    assert!(
        (dl[2] / fd - 1.0).abs() < 1e-5,
        "∂λ/∂s {} vs central difference {fd} (λ {lambda})",
        dl[2]
    );
    let mut fast = d.clone();
    fast.print.print_speed *= 1.25;
    let cap2 = design_cap(&fast, kappe::Context::default()).unwrap();
    let sched = kappe::analysis::CapGreen::new(&cap2).unwrap().schedule;
    let direct = kappe::analysis::time_state_blf(&cap2, &d.analysis, &sched, &time, last, 1e-12)
        .unwrap()
        .unwrap()
        .0;
    let scaled = at(1.0 / 1.25).0;
    assert!(
        (scaled / direct - 1.0).abs() < 1e-9,
        "scaled ages λ {scaled} vs the faster print's schedule {direct}"
    );
}

/// FORM of a cap state's strength and sliding components (one per layer and check, g = −ln u_k)
/// against crude Monte Carlo of the same limit states (issue 24's check by sampling), the last
/// state of the small cap with γ (normal, cov 0.05), f₀ (lognormal, 0.15), φ (lognormal, 0.1)
/// and the print speed (lognormal, 0.1) uncertain and f(t) = 24 kPa + 3 Pa/s·t, φ = 20°. The
/// state's FORM P_f is the series system of its components (importance sampling around their
/// design points, 4 000 samples); the Monte Carlo fails a sample when any component's g ≤ 0
/// (10⁴ seeded samples, Wilson 95 % interval). The FORM P_f lies in the interval. (ḟ is held:
/// with it the capacity f₀ + ḟ·a of two lognormals is curved in u-space and FORM's
/// first-order error shows, as on the buildability cylinder: docs/reliability.md, Limits.)
#[test]
fn form_of_the_strength_components_agrees_with_monte_carlo() {
    let d = green_cap(0.0, 2.4e4, 3.0, 20.0);
    let table = "\"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n\
                 \"material.time.compressive_strength\" = { dist = \"lognormal\", cov = 0.15 }\n\
                 \"material.time.friction_angle_deg\" = { dist = \"lognormal\", cov = 0.1 }\n\
                 \"print.print_speed\" = { dist = \"lognormal\", cov = 0.1 }\n";
    let du = uncertain(&d, table);
    let cap = design_cap(&du, kappe::Context::default()).unwrap();
    let (model, drifts, v) = prepare(&cap).unwrap().unwrap();
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    let time = du.time_model().unwrap();
    let last = cap.states.len() - 1;
    let (state, results) = kappe::analysis::state_form(
        &cap,
        &du.analysis,
        &green.schedule,
        (&model, &drifts, v),
        last,
        0.0,
        &[Check::GreenLayers(1.0)],
    )
    .unwrap()
    .unwrap();
    assert!(
        results.iter().any(|(n, _, _)| *n == "strength") && results.len() > 2,
        "components: {:?}",
        results
            .iter()
            .map(|(n, r, _)| (n, r.beta))
            .collect::<Vec<_>>()
    );
    let field = GreenField::solve(&cap, &du.analysis, &green.schedule, last)
        .unwrap()
        .unwrap();
    let mut comps = field.components(v, &time);
    let mut g = |x: &[f64]| {
        comps
            .iter_mut()
            .map(|(_, c)| c.value(x).unwrap())
            .fold(f64::INFINITY, f64::min)
    };
    let mc = monte_carlo(&model, &mut g, &SamplingOptions::new(10_000, 33)).unwrap();
    eprintln!(
        "state {last}: {} components, FORM P_f {} (β {}), Monte Carlo {} {:?}",
        results.len(),
        state.pf,
        state.beta,
        mc.pf,
        mc.interval
    );
    assert!(
        mc.pf > 0.005 && mc.pf < 0.5,
        "an informative P_f: MC {mc:?}, FORM {} (β {})",
        state.pf,
        state.beta
    );
    assert!(
        state.pf >= mc.interval[0] && state.pf <= mc.interval[1],
        "FORM P_f {} (β {}) vs Monte Carlo {} {:?}",
        state.pf,
        state.beta,
        mc.pf,
        mc.interval
    );
}

/// The screening rule (docs/reliability.md, "Screening") against the unscreened run, on study
/// No. 14's cap with E₀, Ė and γ uncertain (form_cost's row 1, every third state analysed to
/// keep the test quick): some states are screened (else the test proves nothing); each screened
/// state's first-order β₁ lies within the rule's δ of its FORM β; the component count and the
/// governing component are the same; and the print's P_f moves by at most 2·SCREEN_SHARE of
/// itself: SCREEN_SHARE is the rule's bound (the screened components together hold less than
/// that share), and the other SCREEN_SHARE allows the seeded system sampler's change (it draws
/// the same random numbers in both runs; only the screened components' slightly different
/// P_f moves its picks of a component).
#[test]
fn screening_moves_the_print_pf_within_its_bound() {
    use kappe::analysis::{SCREEN_SHARE, screen_delta};
    let mut d = study14(Some(-20.0));
    d.analysis.states = StateSelection::Every(3);
    if let Some(u) = d.uncertainty.as_mut() {
        *u = table_of(
            "\"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.15 }\n\
             \"material.time.youngs_modulus_rate\" = { dist = \"lognormal\", cov = 0.3 }\n\
             \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n\
             [drift]\n\"material.time.youngs_modulus\" = { percent_per_hour = -20.0 }\n",
        );
    }
    let mut nominal = d.clone();
    nominal.uncertainty = None;
    let out = run(&nominal, &Options::of(&nominal), &no_progress).unwrap();
    let analysis = out.analysis.as_ref().unwrap();
    let reliability = |screening: bool| {
        let mut d = d.clone();
        if let Some(u) = d.uncertainty.as_mut() {
            u.screening = Some(screening);
        }
        let cap = design_cap(&d, kappe::Context::default()).unwrap();
        kappe::analysis::reliability(&cap, analysis, &out.schedule)
            .unwrap()
            .unwrap()
    };
    let full = reliability(false);
    let screened = reliability(true);
    let flagged: Vec<_> = screened
        .states
        .iter()
        .filter(|s| s.beta_first_order)
        .collect();
    assert!(
        flagged.len() >= 3,
        "{} of {} states screened",
        flagged.len(),
        screened.states.len()
    );
    assert!(full.states.iter().all(|s| !s.beta_first_order));
    for s in &flagged {
        let f = full.states.iter().find(|f| f.index == s.index).unwrap();
        let (b1, b) = (s.beta_by_check["buckling"], f.beta_by_check["buckling"]);
        assert!(
            (b - b1).abs() <= screen_delta(b1),
            "state {}: β₁ {b1} vs FORM {b} (δ {})",
            s.index,
            screen_delta(b1)
        );
    }
    assert_eq!(full.components, screened.components);
    assert_eq!(
        (full.governing_state, &full.governing_check),
        (screened.governing_state, &screened.governing_check)
    );
    let moved = (screened.pf - full.pf).abs() / full.pf;
    eprintln!(
        "{} of {} states screened; print P_f {:.6e} (β {:.4}) vs unscreened {:.6e} (β {:.4}): \
         relative change {moved:.2e}",
        flagged.len(),
        screened.states.len(),
        screened.pf,
        screened.beta,
        full.pf,
        full.beta
    );
    assert!(
        moved <= 2.0 * SCREEN_SHARE,
        "print P_f moved by {moved:.2e} of itself"
    );
}

/// The 1-D reduction of the time buckling components (docs/reliability.md, "Cost":
/// λ = E₀·Λ(Ė/E₀), FORM on a Hermite model of ln Λ, the true limit state re-solved only at the
/// proposed design points) against FORM on the re-solves, on study No. 14's cap with E₀, Ė and
/// γ uncertain and the mix drying (form_cost's row 1, every third state): every state's β is
/// FORM's within 10⁻⁵·max(1, β). Both results meet FORM's tolerances (|G| ≤ 10⁻⁶|G₀| and
/// ‖u − βα‖ ≤ 10⁻⁶‖u‖), so each β lies within about 10⁻⁶(|G₀|/‖∇G‖ + β) ≈ 2·10⁻⁶β of the exact
/// design point's (|G₀|/‖∇G‖ ≈ β₁ < 1.1β, "Screening"); twice that for the two, with a margin
/// of 2.5 (measured: 2.5·10⁻⁷ over all 43 states). And the reduction takes fewer re-solves:
/// at most 5 per state (measured 3–5 with the solve at the means) and less than a third of
/// FORM's in all (measured 3.7 against 25.7 per state).
#[test]
fn reduced_form_of_the_time_buckling_equals_form_on_the_re_solves() {
    let mut d = study14(Some(-20.0));
    d.analysis.states = StateSelection::Every(3);
    if let Some(u) = d.uncertainty.as_mut() {
        *u = table_of(
            "\"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.15 }\n\
             \"material.time.youngs_modulus_rate\" = { dist = \"lognormal\", cov = 0.3 }\n\
             \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n\
             [drift]\n\"material.time.youngs_modulus\" = { percent_per_hour = -20.0 }\n",
        );
    }
    let mut nominal = d.clone();
    nominal.uncertainty = None;
    let out = run(&nominal, &Options::of(&nominal), &no_progress).unwrap();
    let analysis = out.analysis.as_ref().unwrap();
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let rows = kappe::analysis::reduced_against_form(&cap, analysis, &out.schedule).unwrap();
    assert!(rows.len() >= 10, "only {} states compared", rows.len());
    let (mut reduced, mut full, mut worst) = (0, 0, 0.0_f64);
    for r in &rows {
        let diff = (r.beta_reduced - r.beta_form).abs() / r.beta_form.abs().max(1.0);
        assert!(
            diff <= 1e-5,
            "state {}: β {} by the reduction vs {} by FORM",
            r.index,
            r.beta_reduced,
            r.beta_form
        );
        assert!(
            r.solves_reduced <= 5,
            "state {}: {} re-solves",
            r.index,
            r.solves_reduced
        );
        worst = worst.max(diff);
        reduced += r.solves_reduced;
        full += r.solves_form;
    }
    eprintln!(
        "{} states: largest relative β difference {worst:.2e}; re-solves {reduced} reduced vs \
         {full} FORM",
        rows.len()
    );
    assert!(3 * reduced < full, "{reduced} re-solves vs FORM's {full}");
}

/// The same comparison on a subset of the default cap's states (`kappe init`'s design with
/// form_cost's time model and scatter: E(t) = 10 MPa + 1 kPa/s·t, E₀ lognormal cov 0.2, Ė
/// lognormal cov 0.3, γ normal cov 0.05, E₀ drifting −20 %/h; the states at 50 % of the print
/// and the last): β within 10⁻⁵·max(1, β) of FORM's on the re-solves, for the reason above
/// (measured over all 111 states by `form_cost -- 0 3 reduced`: 2.0·10⁻⁸), with fewer re-solves.
/// Ignored in the quick suite: the default cap's nominal run and FORM on its re-solves take
/// about 40 s on the shared machine (`cargo test --release -p kappe --test it -- --ignored
/// reduced_form_equals`).
#[test]
#[ignore = "about 40 s: the default cap's run and FORM on its re-solves"]
fn reduced_form_equals_form_on_default_cap_states() {
    let d = Design::from_toml_str(
        "name = \"default\"\n[analysis]\nstates = \"50%\"\n[material.time]\nmodel = \"linear\"\n\
         youngs_modulus = 1.0e7\nyoungs_modulus_rate = 1000.0\n[uncertainty]\n\
         \"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.2 }\n\
         \"material.time.youngs_modulus_rate\" = { dist = \"lognormal\", cov = 0.3 }\n\
         \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n\
         [uncertainty.drift]\n\"material.time.youngs_modulus\" = { percent_per_hour = -20.0 }\n",
    )
    .unwrap();
    let mut nominal = d.clone();
    nominal.uncertainty = None;
    let out = run(&nominal, &Options::of(&nominal), &no_progress).unwrap();
    let analysis = out.analysis.as_ref().unwrap();
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let rows = kappe::analysis::reduced_against_form(&cap, analysis, &out.schedule).unwrap();
    assert!(rows.len() >= 2, "only {} states compared", rows.len());
    let (mut reduced, mut full) = (0, 0);
    for r in &rows {
        let diff = (r.beta_reduced - r.beta_form).abs() / r.beta_form.abs().max(1.0);
        eprintln!(
            "state {}: β {} reduced ({} re-solves) vs {} FORM ({}): {diff:.1e}",
            r.index, r.beta_reduced, r.solves_reduced, r.beta_form, r.solves_form
        );
        assert!(diff <= 1e-5, "state {}: {r:?}", r.index);
        reduced += r.solves_reduced;
        full += r.solves_form;
    }
    assert!(reduced < full, "{reduced} re-solves vs FORM's {full}");
}

/// Every time buckling component of study No. 14's cap with E₀, Ė and γ uncertain and E₀
/// drifting −20 %/h (form_cost's first row, screening off): SORM through the 1-D reduction
/// against SORM with the Hessian by differences of the re-solves' exact gradient (2n more
/// re-solves), printed per state with the reason where FORM's P_f is kept. A measurement for
/// docs/reliability.md ("SORM"), not a check: `cargo test --release -p kappe --test it
/// sorm_of_every_time_buckling_component -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement: about a minute of re-solves"]
fn sorm_of_every_time_buckling_component() {
    let mut d = study14(Some(-20.0));
    let u = with_uncertainty(
        "[material.time]\nmodel = \"linear\"\nyoungs_modulus = 1.3e6\nyoungs_modulus_rate = 400.0\n\
         [uncertainty]\n\"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.15 }\n\
         \"material.time.youngs_modulus_rate\" = { dist = \"lognormal\", cov = 0.3 }\n\
         \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n\
         [uncertainty.drift]\n\"material.time.youngs_modulus\" = { percent_per_hour = -20.0 }\n",
    )
    .unwrap();
    d.uncertainty = u.uncertainty;
    d.analysis.row_stride = 8;
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let green = kappe::analysis::CapGreen::new(&cap).unwrap();
    let (model, drifts, v) = prepare(&cap).unwrap().unwrap();
    let time = d.time_model().unwrap();
    eprintln!(
        "state | FORM β | SORM β (reduction) | reason | SORM β (differences) | κ (differences)"
    );
    for q in (0..cap.states.len()).rev().take(12) {
        let t_hours = green.schedule.layers[q].end_s / 3600.0;
        let dm = model.drifted(&drifts, t_hours).unwrap();
        let Some((blf0, _)) =
            kappe::analysis::time_state_blf(&cap, &d.analysis, &green.schedule, &time, q, 1e-10)
                .unwrap()
        else {
            continue;
        };
        let mut g = kappe::analysis::TimeBuckling::new(
            (&cap, &d.analysis, &green.schedule),
            time.clone(),
            v,
            (blf0, 0.0, q),
            d.constraints.blf_min,
            None,
        );
        let Ok(r) = kappe::analysis::time_buckling_form(&dm, &mut g) else {
            continue;
        };
        let reduced = kappe::analysis::time_buckling_sorm(&dm, &mut g, &r);
        let fd = kappe_reliability::sorm(&dm, &mut g, &r, &Default::default());
        eprintln!(
            "{q} | {:.4} | {:.4} | {:?} | {:?} | {:?}",
            r.beta,
            reduced.beta,
            reduced.form_only,
            fd.as_ref().map(|s| s.beta).ok(),
            fd.as_ref()
                .map(|s| s.curvatures.clone())
                .map_err(|e| e.to_string())
        );
    }
}
