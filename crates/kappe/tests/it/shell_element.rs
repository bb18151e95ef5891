//! The shell element of the cap analysis (issue 17): the shear-deformable ANDES+DKMT by
//! default, the Kirchhoff CST+DKT selectable in the design file's `[analysis]`.

use crate::common::single_state_buckling;
use kappe::analysis::AnalysisOptions;
use kappe::form::build_state;
use kappe_fe::ElementKind;

/// `[analysis] element` parses by name; the default is ANDES+DKMT; unknown names are errors
/// that name the field.
#[test]
fn element_option_parses() {
    assert_eq!(AnalysisOptions::default().element, ElementKind::AndesDkmt);
    let d = kappe::Design::from_toml_str("[analysis]\nelement = \"cst_dkt\"\n").unwrap();
    assert_eq!(d.analysis.element, ElementKind::CstDkt);
    let d = kappe::Design::from_toml_str("[analysis]\nelement = \"dkmt\"\n").unwrap();
    assert_eq!(d.analysis.element, ElementKind::AndesDkmt);
    let e = kappe::Design::from_toml_str("[analysis]\nelement = \"mitc9\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("element") && e.contains("mitc9"), "{e}");
}

/// The final state of the default cap (4 layers per mesh row, as the analysis tests): the
/// Mindlin BLF is below the Kirchhoff one by the transverse-shear share. Expected band 0.5–5 %:
/// span/t ≈ 40 gives a shear correction of order π²D/(κGt ℓ²) ≈ 2 % for mode wavelengths ℓ of
/// a few tenths of the span (measured −1.55 % here, −1.8 % at stride 1; issue 17 measured DKT +2.5 % above
/// CalculiX S8R on this state); outside the band the element or its selection is wrong.
#[test]
fn final_state_blf_drops_by_the_shear_share() {
    let design = kappe::Design::default();
    let cap = kappe::design_cap(&design, kappe::Context::default()).unwrap();
    let last = cap.states.len() - 1;
    let state = build_state(
        &cap.sections,
        &cap.frame,
        design.print.start_arch_fraction,
        last,
    )
    .unwrap();
    let blf = |element: ElementKind| {
        let o = AnalysisOptions {
            row_stride: 4,
            element,
            ..AnalysisOptions::default()
        };
        single_state_buckling(&cap, &state, &o, last).factors[0]
    };
    let (dkt, dkmt) = (blf(ElementKind::CstDkt), blf(ElementKind::AndesDkmt));
    let change = dkmt / dkt - 1.0;
    println!(
        "final state: CST+DKT {dkt}, ANDES+DKMT {dkmt} ({:+.2} %)",
        100.0 * change
    );
    assert!((-0.05..-0.005).contains(&change), "{change}");
}
