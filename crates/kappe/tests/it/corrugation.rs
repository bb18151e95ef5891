//! Corrugated caps (issue 26, docs/corrugation.md): every centre layer is its own CEM arch in its
//! tilted plane; amplitude 0 is the prismatic cap byte for byte; the overhang is measured on the
//! real geometry; bad waves are named errors or failing constraints.

use kappe::form::frame::V3;
use kappe::form::overhang::{layer_overhangs, measured_overhangs};
use kappe::{Design, DesignError, design_cap};

/// A small cap (12 centre layers of 15 mm) so the tests stay quick; the wave's wavelength is
/// 8 layer steps (the shortest allowed is 8 steps, 132 mm).
fn small(corrugation: &str) -> Design {
    Design::from_toml_str(&format!(
        "[cap]\nlength = 0.2\n[print]\nlayer_height = 0.015\n[constraints]\noverhang_max = 0.05\n\
         [analysis]\nstates = \"every:4\"\n{corrugation}"
    ))
    .unwrap()
}

const WAVE: &str = "[cap.corrugation]\namplitude = 0.03\nwavelength = 0.15\n";

#[test]
fn every_corrugated_layer_is_a_compression_arch_in_equilibrium_in_its_plane() {
    let d = small(WAVE);
    let cap = design_cap(&d, &|_| {}).unwrap();
    let n_centre = cap.sections.n_centre;
    assert_eq!(cap.centre_arches.len(), n_centre);
    let frame = cap.frame;
    let tan = frame.tilt.tan();
    let step = d.print.layer_height / frame.tilt.cos();
    let wave = d.cap.corrugation.clone().unwrap();
    let mut rises = Vec::new();
    for (k, arch) in cap.centre_arches.iter().enumerate() {
        let p = &arch.points;
        assert_eq!(p.len(), cap.arch.points.len(), "layer {k}: node count");
        // In-plane load of a node: W·(tan(am) e_y − e_z) (method.md §4), W its own bead weight.
        let mut worst: f64 = 0.0;
        for i in 1..p.len() - 1 {
            let mut r = V3::new(0.0, arch.weights[i] * tan, -arch.weights[i]);
            let (fl, fr) = (arch.segment_forces[i - 1], arch.segment_forces[i]);
            r += (p[i - 1] - p[i]).normalize() * fl;
            r += (p[i + 1] - p[i]).normalize() * fr;
            worst = worst.max(r.norm());
        }
        // 1e-9 N (the bound): forces are O(1 N), so this is ~1e6 ulp of the sums.
        assert!(worst <= 1e-9, "layer {k}: node residual {worst:.3e} N");
        assert!(
            arch.segment_forces.iter().all(|&f| f < 0.0),
            "layer {k}: not in compression"
        );
        // In its plane through the feet on the springing lines: n·p = 0 for layer-0 coordinates.
        for q in p {
            assert!(frame.n.dot(q).abs() <= 1e-9, "layer {k}: off its plane");
        }
        // Its own self-weight: W = γ·lw·lh·s with its own segment length s (relative 1e-12).
        let w = d.material.specific_weight
            * d.print.layer_width
            * d.print.layer_height
            * arch.segment_length;
        assert!(
            (arch.weights[1] - w).abs() <= 1e-12 * w,
            "layer {k}: weight"
        );
        // The crown (the middle segment is horizontal by symmetry) at the rise target, 1e-9 m.
        let crown = p[p.len() / 2].z;
        let target = wave.layer_rise(d.cap.rise, step, k);
        assert!(
            (crown - target).abs() <= 1e-9,
            "layer {k}: crown {crown} m, target {target} m"
        );
        rises.push(crown);
    }
    // The wave is there: some layer lies within half a step of each peak, so the sampled sine
    // reaches at least a·cos(π·step/λ) on both sides.
    let (lo, hi) = rises
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &r| {
            (a.min(r), b.max(r))
        });
    let reach = 0.03 * (std::f64::consts::PI * step / wave.wavelength).cos();
    assert!(hi - d.cap.rise >= reach - 1e-9 && d.cap.rise - lo >= reach - 1e-9);
    // The sections carry these arches: centre layer k's nodes are arch k translated by k·step.
    for (k, arch) in cap.centre_arches.iter().enumerate() {
        let layer = &cap.sections.layers[cap.sections.n_start + k];
        for (node, p) in layer.nodes.iter().zip(&arch.points) {
            let want = p + V3::new(0.0, step * k as f64, 0.0);
            assert!((node.xyz - want).norm() <= 1e-12);
        }
    }
}

#[test]
fn amplitude_zero_is_the_prismatic_cap_byte_for_byte() {
    let options = |d: &Design| kappe::Options {
        robot: false,
        ..kappe::Options::of(d)
    };
    let smooth = small("");
    let flat = small("[cap.corrugation]\namplitude = 0.0\nwavelength = 0.3\n");
    assert!(flat.cap.corrugation.is_some() && flat.corrugation().is_none());
    let a = kappe::run(&smooth, &options(&smooth), &kappe::no_progress).unwrap();
    let b = kappe::run(&flat, &options(&flat), &kappe::no_progress).unwrap();
    // Every byte but the wall-clock timings of the analysis, which differ run to run.
    let text = |o: &kappe::Outcome| {
        let mut v = serde_json::to_value(o.summary()).unwrap();
        assert!(v["analysis_timings_s"].is_object());
        v["analysis_timings_s"] = serde_json::Value::Null;
        serde_json::to_string_pretty(&v).unwrap()
    };
    let (ja, jb) = (text(&a), text(&b));
    if ja != jb {
        let _ = std::fs::write(std::env::temp_dir().join("kappe-corr-a.json"), &ja);
        let _ = std::fs::write(std::env::temp_dir().join("kappe-corr-b.json"), &jb);
    }
    assert!(
        ja == jb,
        "summary.json differs with amplitude 0 (both in the temp dir)"
    );
    assert!(b.cap.centre_arches.is_empty());
}

#[test]
fn the_measured_overhang_is_the_closed_form_one() {
    // Prismatic cap: the real offset at the crown is lh·tan(am) (method.md §3). Measured
    // offsets take the nearest segment of the layer below, whose tangent turns by at most
    // s/a_cat ≈ 0.05 rad near the crown: 1 % covers 1 − cos of that with room.
    let d = small("");
    let cap = design_cap(&d, &|_| {}).unwrap();
    let lh_tan = d.print.layer_height * cap.frame.tilt.tan();
    let measured = measured_overhangs(&cap.sections, &cap.frame);
    let formula = layer_overhangs(&cap.sections, &cap.frame);
    let first = cap.sections.n_start + 1;
    for q in first..measured.len() {
        assert!((formula[q] - lh_tan).abs() <= 1e-12);
        assert!(
            (measured[q] - lh_tan).abs() <= 0.01 * lh_tan,
            "layer {q}: measured {} m, lh·tan(am) {lh_tan} m",
            measured[q]
        );
    }
    // Corrugated: at the crown the layer moves along the in-plane up u by ΔCr/cos(am) on top of
    // the step, so l_o(crown) = lh·tan(am) − ΔCr/cos(am); the layer's largest |l_o| is at least
    // that (the crown is one of the nodes measured), within the same 1 %.
    let d = small(WAVE);
    let cap = design_cap(&d, &|_| {}).unwrap();
    let cos = cap.frame.tilt.cos();
    let mut beyond_smooth = false;
    for k in 1..cap.sections.n_centre {
        let q = cap.sections.n_start + k;
        let rise = |k: usize| {
            let p = &cap.centre_arches[k].points;
            p[p.len() / 2].z
        };
        let crown = lh_tan - (rise(k) - rise(k - 1)) / cos;
        let lo = cap.overhangs[q];
        assert!(
            lo.abs() >= crown.abs() * 0.99,
            "layer {k}: overhang {lo} m below the crown's {crown} m"
        );
        beyond_smooth |= lo.abs() > 1.5 * lh_tan;
    }
    assert!(beyond_smooth, "the wave never increased the overhang");
}

#[test]
fn a_wave_too_short_or_too_deep_is_a_named_error() {
    let err = |toml: &str| match Design::from_toml_str(&format!(
        "[cap]\nlength = 0.2\n[print]\nlayer_height = 0.015\n{toml}"
    )) {
        Err(DesignError::Invalid { field, allowed, .. }) => (field, allowed),
        other => panic!("expected an Invalid error, got {other:?}"),
    };
    // 8 layer steps of 16.55 mm = 132 mm is the shortest wavelength.
    let (field, allowed) = err("[cap.corrugation]\namplitude = 0.01\nwavelength = 0.12\n");
    assert_eq!(field, "cap.corrugation.wavelength");
    assert!(allowed.contains("132.4 mm"), "{allowed}");
    // rise − a must keep rise/span ≥ 0.05 (40 mm): 0.2 − 0.17 = 30 mm is too flat.
    let (field, allowed) = err("[cap.corrugation]\namplitude = 0.17\nwavelength = 0.3\n");
    assert_eq!(field, "cap.corrugation.amplitude");
    assert!(allowed.contains("30.0 mm"), "{allowed}");
    let (field, _) = err("[cap.corrugation]\namplitude = -0.01\nwavelength = 0.3\n");
    assert_eq!(field, "cap.corrugation.amplitude");
    assert!(
        Design::from_toml_str("[cap.corrugation]\namplitude = 0.01\nwave = 0.3\n").is_err(),
        "an unknown field must be rejected"
    );
}

#[test]
fn an_overhang_beyond_the_limit_fails_naming_the_layer() {
    // a·2π/λ·step/cos(am) = 0.03·2π/0.15·16.55 mm/0.906 ≈ 23 mm of crown shift per layer:
    // far beyond the default l_o,max = lw/2 = 10 mm.
    let d = Design::from_toml_str(&format!(
        "[cap]\nlength = 0.2\n[print]\nlayer_height = 0.015\n{WAVE}"
    ))
    .unwrap();
    let cap = design_cap(&d, &|_| {}).unwrap();
    let rows = kappe::verdict::preliminary_constraints(&cap);
    let o = rows.iter().find(|r| r.name == "overhang_max").unwrap();
    assert!(!o.pass);
    assert!(o.element.starts_with("layer "), "{}", o.element);
    assert!(o.worst.unwrap() > d.overhang_max());
}
