//! The collapse factor of a cap design as a limit state (issue 24,
//! `kappe::analysis::collapse_reliability`): the exact γ and E scalings by re-solves, the
//! imperfection accepted in a design only with the collapse check, and FORM/SORM of the
//! collapse component against the design's Monte Carlo of the same tables, with the tables
//! against direct paths at the design points.

use kappe::analysis::CollapseMode;
use kappe::analysis::collapse_reliability::{CapCollapseModel, DESIGN_POINT_BETA_TOLERANCE};
use kappe::analysis::design_monte_carlo::{McContext, McMethod, McPlan, plan};
use kappe::analysis::{AnalysisOptions, StateSelection, cap_state_collapse};
use kappe::{Design, Options, design_cap, no_progress, run};

/// A short default cap (0.2 m long, robot off) with `[analysis.nonlinear]` and `extra`.
fn short(extra: &str) -> Design {
    Design::from_toml_str(&format!(
        "name = \"c\"\n[cap]\nlength = 0.2\n[robot]\nenabled = false\n{extra}\n\
         [analysis.nonlinear]\n"
    ))
    .unwrap()
}

/// λ_c of state `q` of design `d` by its own collapse check (no stop).
fn collapse_of(d: &Design, q: usize) -> kappe::analysis::Collapse {
    let cap = design_cap(d, kappe::Context::default()).unwrap();
    let spec = d.analysis.nonlinear.unwrap();
    cap_state_collapse(&cap, &d.analysis, &spec, None, q, f64::INFINITY)
        .unwrap()
        .unwrap()
}

/// λ_c ∝ E/γ on the default cap's path (no time model: limit point only), the module docs'
/// proofs: a design with γ × 0.8 and one with E × 1.3, each form-found and solved anew,
/// against the design's own path on a middle state. Asserted to 1e-6 relative, as the
/// buildability objects' γ test: the paths visit the same displacements step for step, so
/// only round-off separates them (a scaling the code broke — an absolute tolerance, a control
/// not ∝ E/γ — would move the located limit point by the path's 10⁻³ location tolerance or
/// more).
#[test]
fn collapse_factor_scales_exactly_with_the_weight_and_the_modulus() {
    let d = short("");
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let q = cap.states.len() / 2;
    let base = collapse_of(&d, q);
    assert_eq!(base.mode, CollapseMode::LimitPoint, "{base:?}");
    let mut light = d.clone();
    light.material.specific_weight *= 0.8;
    let mut stiff = d.clone();
    stiff.material.youngs_modulus *= 1.3;
    let (l, s) = (collapse_of(&light, q), collapse_of(&stiff, q));
    println!(
        "state {q}: λ_c {:.9} ({}), γ × 0.8 → {:.9}, E × 1.3 → {:.9}",
        base.factor,
        base.mode.name(),
        l.factor,
        s.factor
    );
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    assert!(rel(l.factor, base.factor / 0.8) < 1e-6, "{l:?} vs {base:?}");
    assert!(rel(s.factor, base.factor * 1.3) < 1e-6, "{s:?} vs {base:?}");
    assert_eq!(l.mode, base.mode);
    assert_eq!(s.mode, base.mode);
}

/// `"analysis.nonlinear.imperfection"` in a design's `[uncertainty]`: accepted with
/// `[analysis.nonlinear]` (w0 in m when given, else a factor with mean 1); refused without the
/// check, as a normal, with `imperfection = 0`, and beyond two table axes.
#[test]
fn the_imperfection_is_uncertain_in_a_design_only_with_the_collapse_check() {
    let table = |extra: &str, dist: &str| {
        format!(
            "name = \"c\"\n{extra}\n[uncertainty]\n\
             \"analysis.nonlinear.imperfection\" = {dist}\n"
        )
    };
    let logn = "{ dist = \"lognormal\", cov = 0.5 }";
    // Accepted: the rule's factor (mean 1) and a given w0 (mean w0).
    for (extra, mean) in [
        ("[analysis.nonlinear]", 1.0),
        ("[analysis.nonlinear]\nimperfection = 0.002", 0.002),
    ] {
        let d = Design::from_toml_str(&table(extra, logn)).unwrap();
        let m = d.uncertainty.as_ref().unwrap().model(&d).unwrap();
        let v = &m.variables()[0];
        assert!(
            (v.distribution.mean() / mean - 1.0).abs() < 1e-12,
            "{extra}"
        );
    }
    let refused = [
        (table("", logn), "[analysis.nonlinear]"),
        (
            table("[analysis.nonlinear]\nenabled = false", logn),
            "[analysis.nonlinear]",
        ),
        (
            table("[analysis.nonlinear]", "{ dist = \"normal\", cov = 0.5 }"),
            "positive",
        ),
        (
            table("[analysis.nonlinear]\nimperfection = 0.0", logn),
            "perfect path",
        ),
    ];
    for (text, needle) in refused {
        let e = Design::from_toml_str(&text)
            .and_then(|d| d.uncertainty.as_ref().unwrap().model(&d).map(|_| ()))
            .unwrap_err();
        assert!(
            matches!(e, kappe::DesignError::Uncertainty { .. }) && e.to_string().contains(needle),
            "{text}: {e}"
        );
    }
    // Three table axes (ν, w0 and the time model's E₀): named, listing them.
    let mut d = short(
        "[material.time]\nmodel = \"linear\"\nyoungs_modulus = 1.3e6\nyoungs_modulus_rate = 400.0\n\
         [uncertainty]\n\"analysis.nonlinear.imperfection\" = { dist = \"lognormal\", cov = 0.5 }\n\
         \"material.poisson_ratio\" = { dist = \"lognormal\", cov = 0.05 }\n\
         \"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.15 }\n",
    );
    d.analysis.states = StateSelection::Every(usize::MAX);
    // The model of the collapse check on the cap and its schedule (no analysis needed).
    let options = Options {
        analysis: None,
        robot: false,
        allow_fail: true,
    };
    let out = run(&d, &options, &no_progress).unwrap();
    let model = d.uncertainty.as_ref().unwrap().model(&d).unwrap();
    let e = CapCollapseModel::new(&out.cap, &d.analysis, &out.schedule, &model)
        .err()
        .unwrap();
    let msg = e.to_string();
    assert!(
        msg.contains("at most 2") && msg.contains("material.poisson_ratio"),
        "{msg}"
    );
}

/// FORM and SORM of the collapse component against the design's crude Monte Carlo of the same
/// tables (10⁴ seeded samples), on a short cap's final state alone with a coarse mesh (8
/// layers per row, as `reliability::small`): ν lognormal (cov 0.05, the table axis; its ±5σ box stays below 0.5), E
/// lognormal (cov 0.15) and γ normal (cov 0.02) (both exact), w0 by the rule. collapse_min is
/// set to 0.75 × the state's own deterministic λ_c, which puts the state's β near 1.9 (σ of
/// ln λ_c ≈ 0.15) where 10⁴ samples resolve P_f to a few per cent; the expected value is the
/// sampled one, not ours. Asserted: FORM's and SORM's P_f inside the Wilson 95 % interval
/// (on this surface, nearly linear in ln E, both should be), the collapse governing the print,
/// the table within Δβ ≤ [`DESIGN_POINT_BETA_TOLERANCE`] of a direct path at the design point
/// (where γ, E and ν all differ from the design's: the exact scalings and the axis are
/// re-solved together), and the plan (with its tables) the same after a JSON round trip,
/// which is what the Dask workers get. The imperfection as the axis (cov 0.5) is the example's
/// (`cap_collapse_reliability`), whose table crosses a change of mode (docs/reliability.md).
#[test]
fn form_of_the_collapse_agrees_with_monte_carlo_on_the_table() {
    let coarse = |extra: &str| {
        let mut d = short(extra);
        d.cap.length = 0.15;
        d.print.path_sampling = 0.04;
        d.analysis = AnalysisOptions {
            states: StateSelection::Every(usize::MAX),
            row_stride: 8,
            nonlinear: d.analysis.nonlinear,
            ..d.analysis.clone()
        };
        d
    };
    let det = coarse("");
    let out = run(&det, &Options::of(&det), &no_progress).unwrap();
    let a = out.analysis.as_ref().unwrap();
    let (q, lc) = a
        .states
        .iter()
        .find_map(|s| s.collapse_factor.map(|f| (s.index, f)))
        .expect("a state with a collapse factor");
    let cmin = 0.75 * lc;
    let d = coarse(&format!(
        "[constraints]\ncollapse_min = {cmin}\n[uncertainty]\n\
         \"material.poisson_ratio\" = {{ dist = \"lognormal\", cov = 0.05 }}\n\
         \"material.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}\n\
         \"material.specific_weight\" = {{ dist = \"normal\", cov = 0.02 }}\n\
         monte_carlo = 10000\nmonte_carlo_method = \"crude\"\nseed = 7\n"
    ));
    let out = run(&d, &Options::of(&d), &no_progress).unwrap();
    let r = out.reliability.as_ref().unwrap();
    let c = r.collapse.as_ref().unwrap();
    let mc = r.monte_carlo.as_ref().unwrap();
    let s = r.states.iter().find(|s| s.index == q).unwrap();
    let beta = s.beta_by_check["collapse"];
    let form = kappe_reliability::stdnormal::cdf(-beta);
    let sorm = r.sorm.as_ref().unwrap().pf;
    println!(
        "state {q}: λ_c {lc:.5}, collapse_min {cmin:.5}; collapse β {beta:.4}, FORM P_f \
         {form:.5}, state SORM {:?}; print FORM {:.5} SORM {sorm:.5}; MC {:.5} {:?}",
        s.pf_sorm, r.pf, mc.pf, mc.pf_interval,
    );
    for g in &c.grids {
        for ((p, f), m) in g.points.iter().zip(&g.factors).zip(&g.modes) {
            println!("  state {} grid {p:?}: λ_c {f:.5} ({m})", g.state);
        }
    }
    println!("{:?}", c.design_points);
    assert_eq!(mc.method, McMethod::Crude);
    assert_eq!(c.parameters, ["material.poisson_ratio"]);
    assert_eq!(c.states, [q]);
    assert!(
        (0.005..0.2).contains(&form),
        "the case is meant for P_f ~ 0.03: {form}"
    );
    assert_eq!(r.governing_check, "collapse");
    for (name, p) in [("FORM", r.pf), ("SORM", sorm)] {
        assert!(
            p >= mc.pf_interval[0] && p <= mc.pf_interval[1],
            "{name} {p} outside the Monte Carlo interval {:?}",
            mc.pf_interval
        );
    }
    assert!(
        c.max_beta_error <= DESIGN_POINT_BETA_TOLERANCE,
        "{:?}",
        c.design_points
    );
    // The plan ships the tables bit for bit.
    let a = out.analysis.as_ref().unwrap();
    let ctx = McContext::new(&out.cap, &a.options, &out.schedule).unwrap();
    let p = plan(&ctx, a, r, 10_000, 7, McMethod::Crude).unwrap();
    assert!(p.collapse.is_some() && p.states.iter().any(|s| s.collapse));
    let back: McPlan = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
    assert_eq!(back, p);
}
