//! The collapse factor of print states (docs/collapse.md): the limit w0 → 0, the ordering in
//! w0 and in the base restraint, and the input checks of `[analysis.nonlinear]`.

use kappe::analysis::CollapseMode;
use kappe::analysis::FailureMode;
use kappe::commands::buildability::{BuildabilitySpec, EXAMPLE_TOML, Resolved, check_layers};
use kappe::input::DesignError;

/// The Wolfs cylinder (the `kappe init --kind buildability` example) with 24 segments instead
/// of 48, to keep the test quick, and the given `[analysis.nonlinear]` lines.
fn cylinder(nonlinear: &str) -> Resolved {
    let text = EXAMPLE_TOML.replace("# segments = 48", "segments = 24");
    BuildabilitySpec::from_toml_str(&format!("{text}\n[analysis.nonlinear]\n{nonlinear}\n"))
        .unwrap()
}

#[test]
fn collapse_tends_to_the_linear_buckling_factor_as_w0_vanishes() {
    // 12 layers on the example's own 48 segments, the material check off: the path ends at
    // the limit point only. The imperfect paths' load maxima converge to the perfect path's
    // critical point as w0 falls.
    let n = 12;
    let mut factors = Vec::new();
    let mut lba = 0.0;
    for w0 in [2e-3, 2e-4, 2e-5, 0.0] {
        let r = BuildabilitySpec::from_toml_str(&format!(
            "{EXAMPLE_TOML}\n[analysis.nonlinear]\nimperfection = {w0}\nmaterial = false\n"
        ))
        .unwrap();
        let s = check_layers(&r, n).unwrap();
        let c = s.collapse.clone().unwrap();
        assert_eq!(c.mode, CollapseMode::LimitPoint, "w0 = {w0}: {c:?}");
        lba = s.blf.unwrap();
        assert_eq!(c.lba, lba);
        factors.push(c.factor);
    }
    // Within 1 % at w0 = 0.02 mm (w0/t = 5e-4; Koiter's √w0 law leaves ~1 % there on the
    // frames of docs/nonlinear.md).
    let last = factors[factors.len() - 1];
    let near = factors[factors.len() - 2];
    assert!(
        (near / last - 1.0).abs() < 0.01,
        "w0 = 0.02 mm: {near} vs w0 = 0: {last}"
    );
    // The perfect path's critical point lies ABOVE the LBA factor: at buckling this fresh
    // wall is compressed by up to ~18 % at its base (σ ≈ 15 kPa on E ≈ 83 kPa at λ ≈ 6), and the shortened,
    // pre-deformed cylinder is stiffer than the undeformed one the LBA linearises about.
    // That is physics, not the element (docs/collapse.md §4): CalculiX NLGEOM on the identical
    // model (S6, 24 segments) finds its perfect path's critical point 7.0 % above its own
    // *BUCKLE factor, Kappe's 5.0 % on that mesh; on 48 segments Kappe's is 11.4 % above
    // (measured). Checked here: above, and by less than 20 % (a loose bound on the measured
    // 11.4 %: the size of the pre-buckling effect depends on the strain measure at such
    // strains, which differs between codes; this bound guards against a lost bifurcation).
    assert!(last > lba, "w0 = 0: {last} vs LBA {lba}");
    assert!(last < 1.20 * lba, "w0 = 0: {last} vs LBA {lba}");
    // The limit load rises monotonically as w0 falls (measured λ_c/λ_c(0) = 0.877, 0.990,
    // 0.9994 at w0 = 2, 0.2, 0.02 mm; CalculiX on 24 segments: 0.866 at 0.2 mm). Round-off
    // allowance 0.1 % between neighbours (the path brackets a limit to 10⁻³ in λ).
    for w in factors.windows(2) {
        assert!(w[0] <= w[1] * (1.0 + 1e-3), "{factors:?}");
    }
}

/// The part of λ_c → λ_LBA that is the element's (docs/collapse.md §4): on the identical
/// 12-layer state, the co-rotational model's own initial-stress stiffness (its tangent's
/// terms linear in the stresses of the linear solution) gives the LBA's critical factor
/// within the 1 % once the facets are fine enough for the O(h²) coupling term of the
/// rigid-facet split (measured on 48 segments: −1.57 %; split 2×2: −0.33 %; 96 segments:
/// −0.42 %; without the facets' local von Kármán terms +4.9 % on all three).
#[test]
fn the_co_rotational_initial_stress_stiffness_is_the_linear_buckling_one() {
    use kappe::analysis::{GreenOptions, check_state};
    use kappe::commands::buildability::object_shell;
    use kappe_fe::{BucklingOptions, Linearisation, buckling, linearised_critical_factor};
    let n = 12;
    let r = BuildabilitySpec::from_toml_str(EXAMPLE_TOML).unwrap();
    let (mut model, layers) = object_shell(&r, n);
    let ages = r.schedule.ages(n);
    check_state(
        &mut model,
        &layers,
        &ages,
        &r.time,
        &GreenOptions::default(),
        None,
    )
    .unwrap();
    let model = kappe_fe::refine::split(&model, 2).model;
    let lba = buckling(
        &model,
        &BucklingOptions {
            modes: 1,
            ..Default::default()
        },
    )
    .unwrap()
    .factors[0];
    let sigma = linearised_critical_factor(
        &model,
        lba,
        1e-4,
        Linearisation::InitialStress {
            local_geometric: true,
        },
    )
    .unwrap()
    .lambda;
    assert!((sigma / lba - 1.0).abs() < 0.01, "{sigma} vs LBA {lba}");
}

#[test]
fn a_pinned_base_collapses_before_a_clamped_one() {
    let n = 20;
    let clamped = check_layers(&cylinder("material = false"), n).unwrap();
    let pinned = check_layers(&cylinder("material = false\nbase = \"pinned\""), n).unwrap();
    let (c, p) = (
        clamped.collapse.unwrap().factor,
        pinned.collapse.unwrap().factor,
    );
    // Releasing the base rotation removes stiffness: both the LBA and the collapse factor fall.
    assert!(pinned.blf.unwrap() < clamped.blf.unwrap());
    assert!(p < c, "pinned {p} vs clamped {c}");
}

#[test]
fn the_material_along_the_path_can_only_lower_the_collapse_factor() {
    let n = 24;
    let with = check_layers(&cylinder(""), n).unwrap();
    let without = check_layers(&cylinder("material = false"), n).unwrap();
    let (a, b) = (with.collapse.unwrap(), without.collapse.unwrap());
    assert!(a.factor <= b.factor * (1.0 + 1e-9), "{a:?} vs {b:?}");
    // The face stresses include the membrane stress the linear check sees: the material
    // cannot fail later along the path than 1/u_lin of the perfect state's membrane check
    // allows, up to the path's first steps being nearly linear (5 %: the path's bending
    // from the 2 mm imperfection only adds to the face stresses; the margin covers the
    // linear interpolation between steps).
    let u = with.strength_utilisation.unwrap();
    if a.mode == CollapseMode::Strength {
        assert!(a.factor <= 1.05 / u, "{} vs 1/u = {}", a.factor, 1.0 / u);
    }
}

#[test]
fn the_default_rule_is_the_larger_of_t_over_20_and_h_ef_over_450() {
    let r = cylinder("material = false");
    let nl = r.spec.nonlinear().unwrap();
    // t = 40 mm: t/20 = 2 mm governs while 2H/450 < 2 mm, i.e. H < 0.45 m.
    assert_eq!(nl.amplitude(0.04, 0.3), 0.002);
    assert!((nl.amplitude(0.04, 0.9) - 0.004).abs() < 1e-15);
    let s = check_layers(&r, 5).unwrap();
    assert_eq!(s.collapse.unwrap().w0, 0.002);
}

#[test]
fn bad_nonlinear_input_is_a_named_error() {
    let text = |extra: &str| format!("{EXAMPLE_TOML}\n[analysis.nonlinear]\n{extra}\n");
    for (extra, field) in [
        ("imperfection = -0.001", "analysis.nonlinear.imperfection"),
        (
            "placement_tolerance = nan",
            "analysis.nonlinear.placement_tolerance",
        ),
        ("signs = 3", "analysis.nonlinear.signs"),
    ] {
        match BuildabilitySpec::from_toml_str(&text(extra)) {
            Err(DesignError::Invalid { field: f, .. }) => assert_eq!(f, field, "{extra}"),
            other => panic!("{extra}: {other:?}"),
        }
    }
    let e = BuildabilitySpec::from_toml_str(&text("imperfektion = 0.001")).unwrap_err();
    assert!(e.to_string().contains("imperfektion"), "{e}");
    let off = EXAMPLE_TOML.replace("buckling = true", "buckling = false");
    match BuildabilitySpec::from_toml_str(&format!("{off}\n[analysis.nonlinear]\n")) {
        Err(DesignError::Invalid { field, .. }) => assert_eq!(field, "checks.buckling"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_state_fails_by_collapse_below_collapse_min() {
    // collapse_min above every state's collapse factor: the first state fails by collapse.
    let text = EXAMPLE_TOML
        .replace("# segments = 48", "segments = 24")
        .replace(
            "stop_at_failure = true",
            "stop_at_failure = true\ncollapse_min = 1e9",
        );
    let r = BuildabilitySpec::from_toml_str(&format!(
        "{text}\n[analysis.nonlinear]\nmaterial = false\n"
    ))
    .unwrap();
    let s = check_layers(&r, 3).unwrap();
    assert_eq!(s.failure, Some(FailureMode::Collapse));
}
