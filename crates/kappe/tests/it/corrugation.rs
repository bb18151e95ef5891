//! Corrugated caps (issue 26, docs/corrugation.md): every centre layer is its own CEM arch in its
//! tilted plane; amplitude 0 is the prismatic cap byte for byte; the overhang is measured on the
//! real geometry; bad waves are named errors or failing constraints.

use kappe::form::V3;
use kappe::form::{layer_overhangs, measured_overhangs};
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
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
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
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
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
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
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
    // A crown above the span: rise 0.75 + a 0.1 = 850 mm > span 800 mm (rise/span > 1).
    match Design::from_toml_str(
        "[cap]\nrise = 0.75\n[cap.corrugation]\namplitude = 0.1\nwavelength = 0.3\n",
    ) {
        Err(DesignError::Invalid { field, allowed, .. }) => {
            assert_eq!(field, "cap.corrugation.amplitude");
            assert!(allowed.contains("850.0 mm"), "{allowed}");
        }
        other => panic!("expected an Invalid error, got {other:?}"),
    }
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
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let rows = kappe::verdict::preliminary_constraints(&cap);
    let o = rows.iter().find(|r| r.name == "overhang_max").unwrap();
    assert!(!o.pass);
    assert!(o.element.starts_with("layer "), "{}", o.element);
    assert!(o.worst.unwrap() > d.overhang_max());
}

/// A wide column of corrugated plate (one wave of λ across its width, crests along the load)
/// under in-plane compression, pinned ends, free long edges: buckling load against the
/// orthotropic (smeared) estimate `P_cr = π²·E·I_x / L²`, where `I_x` is the second moment of
/// the corrugated cross-section about its centroid (the stiffening a corrugated cap gets across
/// its waves, docs/corrugation.md). `kappe_fe` directly, its default element (CST + DKT).
fn corrugated_column(amplitude: f64, len: f64) -> (f64, f64) {
    // 100 × 48: elements 10 mm × 2.1 mm (aspect ≤ 5), 48 facets per wave (see the test).
    use kappe_fe::{BucklingOptions, Material, NodalLoad, ShellModel, Support, buckling};
    let (lambda, t, e) = (0.1, 0.004, 1.0e6);
    let (nx, ny) = (100usize, 48usize);
    // A cosine period: the section is symmetric about its mid-width, so its product of inertia
    // vanishes and y, z are principal axes (a sine period is a Z-like section that buckles
    // about an inclined minor axis instead).
    let z = |j: usize| amplitude * (2.0 * std::f64::consts::PI * j as f64 / ny as f64).cos();
    let y = |j: usize| lambda * j as f64 / ny as f64;
    let mut nodes = Vec::new();
    for i in 0..=nx {
        for j in 0..=ny {
            nodes.push([len * i as f64 / nx as f64, y(j), z(j)]);
        }
    }
    let id = |i: usize, j: usize| i * (ny + 1) + j;
    let mut tris = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    // ν = 0: the smeared I_x is then exact for the facets (no anticlastic coupling).
    let mut m = ShellModel::new(
        nodes,
        tris,
        t,
        Material {
            youngs_modulus: e,
            poisson_ratio: 0.0,
            unit_weight: 0.0,
        },
    );
    m.gravity = [0.0; 3];
    for i in [0, nx] {
        for j in 0..=ny {
            let mut fixed = [false, false, true, false, false, false];
            fixed[1] = j == 0;
            m.supports.push(Support {
                node: id(i, j),
                fixed,
            });
        }
    }
    m.supports.push(Support {
        node: id(nx / 2, 0),
        fixed: [true, false, false, false, false, false],
    });
    // Unit total load per end, spread by tributary chord length (uniform axial strain).
    let chord = |j: usize| ((y(j + 1) - y(j)).powi(2) + (z(j + 1) - z(j)).powi(2)).sqrt();
    let arc: f64 = (0..ny).map(chord).sum();
    for j in 0..=ny {
        let w =
            0.5 * (if j > 0 { chord(j - 1) } else { 0.0 } + if j < ny { chord(j) } else { 0.0 });
        for (i, sign) in [(0, 1.0), (nx, -1.0)] {
            m.nodal_loads.push(NodalLoad {
                node: id(i, j),
                force: [sign * w / arc, 0.0, 0.0],
                moment: [0.0; 3],
            });
        }
    }
    let r = buckling(
        &m,
        &BucklingOptions {
            modes: 1,
            ..Default::default()
        },
    )
    .unwrap();
    // I_x of the faceted section (the FE's own geometry): each chord of length c, inclined at θ,
    // contributes t·c·(z₁² + z₁z₂ + z₂²)/3 (z linear along it) + t³·c·cos²θ/12; the centroid is
    // at z = 0 (a full period).
    let ix: f64 = (0..ny)
        .map(|j| {
            let c = chord(j);
            let cos = (y(j + 1) - y(j)) / c;
            let (z1, z2) = (z(j), z(j + 1));
            t * c * (z1 * z1 + z1 * z2 + z2 * z2) / 3.0 + t.powi(3) * c * cos * cos / 12.0
        })
        .sum();
    let closed = std::f64::consts::PI.powi(2) * e * ix / (len * len);
    (r.factors[0], closed)
}

#[test]
fn a_corrugated_plate_buckles_at_its_orthotropic_estimate() {
    let (flat, flat_cf) = corrugated_column(0.0, 1.0);
    let (wavy, wavy_cf) = corrugated_column(0.005, 1.0);
    println!("flat: FE {flat:.5e} vs {flat_cf:.5e}; corrugated: FE {wavy:.5e} vs {wavy_cf:.5e}");
    // Flat: the Euler load of the strip; 40 elements over one half-wave put the FE within 1 %
    // (it converges from above).
    assert!(
        (flat / flat_cf - 1.0).abs() < 0.01,
        "flat {flat} vs {flat_cf}"
    );
    // Corrugated (a = 5 mm, t = 4 mm): the FE lies above the estimate because each CST facet
    // carries the section's bending stress, linear across the facet, as a constant (membrane
    // locking in in-plane bending): 24 → 48 facets per wave moved FE/estimate 1.082 → 1.055,
    // converging toward ≈ 1.03 (the smeared section ignores shear lag in the webs). 8 % bounds
    // this mesh; a lost stiffening (ratio ≈ 0.1) or a Z-like inclined-axis mode (≈ 0.55, what a
    // sine period gives) fails it by far.
    assert!(
        wavy >= wavy_cf && wavy / wavy_cf - 1.0 < 0.08,
        "corrugated {wavy} vs {wavy_cf}"
    );
    // The stiffening itself: 1 + 6a²/t² ≈ 10.4 in the small-slope limit.
    assert!(wavy / flat > 9.0, "stiffening only {}", wavy / flat);
}

/// Issue 26, verification: every corrugated print state is in equilibrium. The network carries
/// the funicular part of each state's loads exactly (its force pass residual ≤ 1e-9 N) and in
/// compression; the rest, the force a fixed wavy geometry cannot carry axially, is real (not
/// round-off) and is carried by the state's shell, whose statics balance it (|Σ loads +
/// Σ reactions| ≤ 1e-9 N) and whose stresses widen the element stresses on both sides.
#[test]
fn every_corrugated_state_is_in_equilibrium_network_plus_shell() {
    use kappe::analysis::corrugated_stresses;
    use kappe::analysis::{AnalysisOptions, element_stresses, state_material};
    use kappe::form::build_state;
    let d = small(WAVE);
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let mut handed: f64 = 0.0;
    for s in &cap.states {
        // 1e-9 N, the bound; forces are O(10 N), so this is ~1e5 ulp of the node sums.
        assert!(
            s.forces.max_residual <= 1e-9,
            "state {}: network residual {:.3e} N",
            s.index,
            s.forces.max_residual
        );
        // Compression, zero allowed: a near-zero edge may round to +1e-14 N, so the bound is
        // method.md §9's residual tolerance 1e-9·(1 + max|F|).
        assert!(
            s.forces.max_tension_force <= s.forces.residual_tolerance,
            "state {}: tension {} N",
            s.index,
            s.forces.max_tension_force
        );
        handed = handed.max(s.forces.out_of_funicular);
    }
    // The split is not vacuous: the wave's columns kink, and the shell takes a real load
    // (the default-scale cap hands over 0.5–1.4 N, docs/corrugation.md).
    assert!(handed > 0.05, "largest handed-over force {handed} N");

    let o = AnalysisOptions::default();
    let areas = cap.areas();
    let last = cap.states.len() - 1;
    for top in [cap.sections.n_start + 4, last] {
        let state = build_state(&cap.sections, &cap.frame, 0.0, top).unwrap();
        let mat = state_material(
            &cap,
            &o,
            top,
            Some(&kappe::analysis::CapGreen::new(&cap).unwrap()),
        );
        let (all, bending) = corrugated_stresses(&state, areas, &mat).unwrap();
        let b = bending.expect("a corrugated state has a bending part");
        assert!(b.load_sum_n > 0.0 && b.out_of_funicular_n > 0.0);
        // The shell's global equilibrium, 1e-9 N: its loads are O(1 N) and the solve is a
        // direct Cholesky factorization (relative residual ~1e-12 of K's scale).
        assert!(
            b.equilibrium_residual_n <= 1e-9,
            "state {top}: shell residual {:.3e} N",
            b.equilibrium_residual_n
        );
        // Both faces of every element are there, and the bending widens the network's range.
        let net = element_stresses(&state, areas).unwrap();
        assert_eq!(all.len(), 2 * net.len());
        let lo = |v: &[kappe::analysis::ElementStress]| {
            v.iter().map(|e| e.stress).fold(f64::INFINITY, f64::min)
        };
        let hi = |v: &[kappe::analysis::ElementStress]| {
            v.iter().map(|e| e.stress).fold(f64::NEG_INFINITY, f64::max)
        };
        // The start section's springing stays the most compressed element (its bending part
        // is ~0), so only "not above" there; every network stress here is ≤ 0, so the
        // bending's tension face must raise the highest.
        assert!(lo(&all) <= lo(&net) && hi(&all) > hi(&net));
        assert!(b.max_stress_pa > 0.0);
    }
}

/// `kappe optimize` takes the corrugation as free parameters (issue 26): from a smooth start
/// (no `[cap.corrugation]`), the amplitude step reaches the pipeline — the evaluated design is
/// corrugated (its volume differs from the smooth cap's, and its bending part shows in the
/// stress check) — and the result is what `kappe design` says of it.
#[test]
fn optimize_varies_the_corrugation() {
    use kappe::commands::optimize::{OptimizeFile, optimize};
    let d = Design::from_toml_str(
        "[cap]\nlength = 0.2\n[print]\nlayer_height = 0.015\n[constraints]\noverhang_max = 0.05\n\
         [robot]\nenabled = false\n",
    )
    .unwrap();
    let text = "max_evaluations = 3\n\
                [analysis]\nbuckling = false\n[verify]\nbuckling = false\n\
                [free]\n\"cap.corrugation.amplitude\" = { min = 0.0, max = 0.03 }\n\
                \"cap.corrugation.wavelength\" = { min = 0.15, max = 0.3 }\n";
    let f = OptimizeFile::from_toml_str(text).unwrap();
    let r = optimize(&f, &d, &|_| std::ops::ControlFlow::Continue(())).unwrap();
    let first = &r.evaluations[0];
    // The smooth start: amplitude 0, the default wavelength 0.3 m.
    assert_eq!(first.parameters["cap.corrugation.amplitude"], 0.0);
    assert_eq!(first.parameters["cap.corrugation.wavelength"], 0.3);
    let waved = r
        .evaluations
        .iter()
        .find(|e| e.parameters["cap.corrugation.amplitude"] > 0.0)
        .expect("the search never tried a wave");
    // The wave changes every centre layer's arch length, so the printed volume.
    let (v0, v1) = (first.volume_m3.unwrap(), waved.volume_m3.unwrap());
    assert!((v1 - v0).abs() > 1e-9 * v0, "{v0} vs {v1}");
    // The result is `kappe design`'s verdict on it.
    assert_eq!(r.feasible, r.verdict.as_ref().is_some_and(|v| v.ok));
}

/// The robot prints a corrugated cap (issue 26, item 2): the planned targets are the layers'
/// own (wavy) nozzle-tip points, every layer is one continuous bead at the print speed, and the
/// programs pass the URScript check.
#[test]
fn the_nozzle_follows_the_waves() {
    let d = Design::from_toml_str(&format!(
        "[cap]\nlength = 0.2\n[print]\nlayer_height = 0.015\n[constraints]\noverhang_max = 0.05\n{WAVE}"
    ))
    .unwrap();
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let plan = kappe::robot_plan::plan_robot(&cap).unwrap();
    let tips: std::collections::HashMap<(i64, usize), V3> = cap
        .path
        .points
        .iter()
        .map(|p| ((i64::from(p.layer), p.index), p.tip))
        .collect();
    // The wave is in the path: the crown tips of the centre layers do not lie on one line
    // (a prism's would, every layer being layer 0 translated).
    let crown_z: Vec<f64> = (0..cap.sections.n_centre as i64)
        .filter_map(|k| {
            cap.path
                .points
                .iter()
                .filter(|p| i64::from(p.layer) == k)
                .map(|p| p.tip.z)
                .reduce(f64::max)
        })
        .collect();
    let spread = crown_z.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - crown_z.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    assert!(spread > 0.02, "crown tips spread {spread} m");
    let mut visited = 0;
    for st in &plan.stations {
        for l in &st.layers {
            for (k, w) in l.waypoints.iter().enumerate() {
                let tip = tips[&(l.layer, w.index)];
                // The planner keeps the target it was given (copied, so exact; 1e-12 m allows
                // an f32-free round trip through the plan's own arrays).
                let err = (V3::from(w.position) - tip).norm();
                assert!(
                    err <= 1e-12,
                    "layer {} point {}: target off by {err} m",
                    l.layer,
                    w.index
                );
                // Continuous flow: inside a layer every move prints, at the print speed unless
                // the timing slowed it (then still > 0).
                if k > 0 {
                    if plan.slowdowns.is_empty() {
                        let v = d.print.print_speed;
                        assert!((w.speed - v).abs() <= 1e-9 * v, "speed {} m/s", w.speed);
                    } else {
                        assert!(w.speed > 0.0);
                    }
                }
                visited += 1;
            }
        }
    }
    assert_eq!(
        visited,
        cap.path.points.len(),
        "every path point is a target"
    );
    let files = kappe_robot::files::linted_programs(&plan, "corrugated").unwrap();
    assert!(!files.is_empty());
}

/// Issue 26, speed: the analysis solves a corrugated state's bending part as a second load case
/// of its buckling solve (`BucklingRequest::bending`), on the same factor of K. The stresses and
/// the summary are then exactly the stand-alone `corrugated_stresses` (the same K, ordering and
/// right-hand side: the same bits), and the buckling factors are those of the plain solve.
#[test]
fn the_bending_part_solved_in_the_buckling_solve_is_the_stand_alone_one() {
    use kappe::analysis::{
        AnalysisOptions, BucklingRequest, corrugated_stresses, state_buckling, state_material,
    };
    use kappe::form::build_state;
    let cap = design_cap(&small(WAVE), kappe::Context::default()).unwrap();
    let o = AnalysisOptions {
        blf_max_split: 1,
        ..AnalysisOptions::default()
    };
    let areas = cap.areas();
    let last = cap.states.len() - 1;
    for top in [cap.sections.n_start + 4, last] {
        let state = build_state(&cap.sections, &cap.frame, 0.0, top).unwrap();
        let mat = state_material(
            &cap,
            &o,
            top,
            Some(&kappe::analysis::CapGreen::new(&cap).unwrap()),
        );
        let alone = corrugated_stresses(&state, areas, &mat).unwrap();
        assert!(alone.1.is_some(), "state {top} has a bending part");
        for printed in [false, true] {
            let request = BucklingRequest {
                printed,
                bending: Some(areas),
                ..Default::default()
            };
            let r = state_buckling(&state, &mat, &o, &request).unwrap();
            assert_eq!(r.stresses.as_ref(), Some(&alone), "state {top}");
            assert_eq!(r.increment.is_some(), printed);
            assert_eq!(
                r.buckling.factors,
                state_buckling(&state, &mat, &o, &Default::default())
                    .unwrap()
                    .buckling
                    .factors
            );
        }
    }
}
