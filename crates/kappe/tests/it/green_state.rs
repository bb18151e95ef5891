//! Verification of the green-state check (issue 11, green-state.md §4): closed forms for the
//! straight wall (Greenhill, linear curing, plastic collapse), the time model and the bad-input
//! errors. Every tolerance is stated and justified where it is used.

use kappe::analysis::FailureMode;
use kappe::commands::buildability::{BuildabilitySpec, Resolved, check_layers, run};
use kappe::input::TimeModelSpec;

/// A wall spec: length 0.2 m, thickness t, layer height h, `n` layers, ν = 0, γ = 20 kN/m³.
fn wall(t: f64, h: f64, n: usize, time: &str, extra: &str) -> String {
    format!(
        "[object]\nkind = \"wall\"\nlength = 0.2\nwidth = {t}\nlayer_height = {h}\nmax_layers = {n}\nsegments = 4\n\
         [process]\nlayer_time = 10.0\n\
         [material]\nspecific_weight = 20000.0\npoisson_ratio = 0.0\n\
         [material.time]\n{time}\n{extra}"
    )
}

fn resolved(text: &str) -> Resolved {
    match BuildabilitySpec::from_toml_str(text) {
        Ok(r) => r,
        Err(e) => panic!("spec rejected: {e}\n{text}"),
    }
}

/// q·H³/(E·I) at the buckling load of an n-layer wall, E = `e_ref` (per unit length: q = γ·t,
/// I = t³/12; ν = 0 so the wall bends like a beam).
fn greenhill_constant(r: &Resolved, n: usize, e_ref: f64) -> f64 {
    let s = check_layers(r, n).expect("check");
    let blf = s.blf.expect("a buckling factor");
    let o = &r.spec.object;
    let q = r.spec.material.specific_weight * o.width;
    let i = o.width.powi(3) / 12.0;
    let h = n as f64 * o.layer_height;
    blf * q * h.powi(3) / (e_ref * i)
}

#[test]
fn greenhill_wall_uniform_e() {
    // Uniform E: q·H³/(E·I) = 7.837347 (Greenhill). 60 layers of 10 mm on a 40 mm wall: the
    // DKT column converges as O(h²) (buckling.md §5: 7.8373 with 200 frame elements); at 60
    // rows the discretisation error is well below the 1 % the issue asks for.
    let r = resolved(&wall(
        0.04,
        0.01,
        60,
        "model = \"constant\"\nyoungs_modulus = 1.0e6",
        "[checks]\nstrength = false\nsliding = false",
    ));
    let c = greenhill_constant(&r, 60, 1.0e6);
    println!("Greenhill constant at 60 layers: {c:.6}");
    assert!((c / 7.837347 - 1.0).abs() < 0.01, "C = {c}");
    // Converged: 30 layers is farther from the closed form than 60.
    let c30 = greenhill_constant(&r, 30, 1.0e6);
    println!("Greenhill constant at 30 layers: {c30:.6}");
    assert!((c - 7.837347).abs() <= (c30 - 7.837347).abs() + 1e-9);
}

#[test]
fn linear_curing_tends_to_bessel_limit() {
    // E = E₀ + Ė·t with the layer time T; with E₀ = Ė·T/2 every layer has the continuous
    // E(depth) = Ė·depth/v at its centroid, so as layers get thin the constant with
    // E_base = Ė·H/v tends to 2.404826² = 5.783186 (E₀ → 0 in the continuous limit).
    let edot = 1000.0;
    let t_layer = 10.0;
    let mut prev = f64::INFINITY;
    for n in [15usize, 30, 60] {
        let h = 0.6 / n as f64;
        let r = resolved(&wall(
            0.04,
            h,
            n,
            &format!(
                "model = \"linear\"\nyoungs_modulus = {}\nyoungs_modulus_rate = {edot}",
                edot * t_layer / 2.0
            ),
            "[checks]\nstrength = false\nsliding = false",
        ));
        let e_base = edot * t_layer * n as f64;
        let c = greenhill_constant(&r, n, e_base);
        println!("linear curing, {n} layers: C = {c:.6}");
        // Approaches the limit monotonically as the layers get thinner.
        assert!(
            (c - 5.783186).abs() < (prev - 5.783186).abs(),
            "C = {c}, before {prev}"
        );
        prev = c;
    }
    // 60 layers: within 1 % of the Bessel limit (same O(h²) convergence as Greenhill).
    assert!((prev / 5.783186 - 1.0).abs() < 0.01, "C = {prev}");
    // A stiffer top (E₀ large) lies between the two limits: 5.783 < C < 7.837.
    let n = 30;
    let r = resolved(&wall(
        0.04,
        0.02,
        n,
        &format!(
            "model = \"linear\"\nyoungs_modulus = {}\nyoungs_modulus_rate = {edot}",
            edot * 50.0
        ),
        "[checks]\nstrength = false\nsliding = false",
    ));
    let e_base = r.time.modulus(t_layer * (n - 1) as f64);
    let c = greenhill_constant(&r, n, e_base);
    println!(
        "E_top/E_base = {:.3}: C = {c:.6}",
        r.time.modulus(0.0) / e_base
    );
    assert!(c > 5.783186 && c < 7.837347, "C = {c}");
}

/// Strength-only wall (E huge so buckling never governs; checks off but strength).
fn plastic_wall(h: f64, n: usize, s0: f64, sdot: f64) -> Resolved {
    resolved(&wall(
        0.04,
        h,
        n,
        &format!(
            "model = \"linear\"\nyoungs_modulus = 1.0e9\ncompressive_strength = {s0}\n\
             compressive_strength_rate = {sdot}"
        ),
        "[checks]\nbuckling = false\nsliding = false",
    ))
}

#[test]
fn plastic_collapse_of_the_bottom_layer() {
    // σ(t) = σ₀ + σ̇·t, layer time T, vertical speed v = h/T. The FE samples the stress at the
    // element centroid: with ν = 0 the bottom layer carries the weight above its centroid,
    // γ·(n − ½)·h on average over the strip (lumped CST loads put half of each layer's weight on
    // each of its rows). The lumped loads are not uniform along a row (union-jack triangles give
    // nodes of 4 and 8 triangles, and the free ends have fewer), so the element stresses scatter
    // around that mean: the largest lies 0.5–1.05 % above it in these meshes, and we allow 2 %.
    // So the FE fails at the first n whose closed-form utilisation
    // u_n = γ(n − ½)h / (σ₀ + σ̇(n − 1)T) exceeds 1/1.02, and not after the first with u_n > 1.
    let (g, t_layer, s0) = (20000.0, 10.0, 3033.0);
    let u_closed = |n: usize, h: f64, sdot: f64| {
        g * (n as f64 - 0.5) * h / (s0 + sdot * (n - 1) as f64 * t_layer)
    };
    for (h, sdot) in [(0.01, 10.0), (0.005, 5.0), (0.0025, 2.5)] {
        let r = plastic_wall(h, 400, s0, sdot);
        let b = run(&r, &|_| {}).expect("run");
        let expected = (1..=400)
            .find(|&n| u_closed(n, h, sdot) > 1.0)
            .expect("collapses");
        let n_fail = b.failure_layer.expect("collapses");
        assert_eq!(b.failure_mode, Some(FailureMode::Strength));
        assert!(
            n_fail <= expected && u_closed(n_fail, h, sdot) * 1.02 > 1.0,
            "{n_fail} vs {expected}"
        );
        // The worst element is in the bottom layer, within [1, 1.02] of the closed form.
        let last = b.states.last().expect("a state");
        let w = last.strength_worst.expect("strength checked");
        assert_eq!(w.layer, 0);
        let ratio = w.utilisation / u_closed(n_fail, h, sdot);
        assert!(
            (1.0 - 1e-9..1.02).contains(&ratio),
            "FE/closed form = {ratio}"
        );
        // The continuous limit H_p = σ₀/(γ − σ̇/v): the layered height differs by less than
        // two layers (half a layer from the centroid sampling, one from rounding up to a
        // whole layer, and the (n − 1)·T lag of the bottom layer's age, all O(h)).
        let v = h / t_layer;
        let hp = s0 / (g - sdot / v);
        let hn = n_fail as f64 * h;
        println!("h = {h}: H_p = {hp:.4} m, first failing height {hn:.4} m (n = {n_fail})");
        assert!((hn - hp).abs() < 2.0 * h, "{hn} vs {hp}");
    }
}

#[test]
fn no_plastic_collapse_when_strength_grows_fast_enough() {
    // σ̇ ≥ γ·v: the stress of the bottom layer never catches up with its strength.
    let (h, t_layer) = (0.01, 10.0);
    let sdot = 20000.0 * h / t_layer;
    let r = plastic_wall(h, 300, 3000.0, sdot);
    let b = run(&r, &|_| {}).expect("run");
    assert_eq!(b.failure_layer, None);
    assert_eq!(b.states.len(), 300);
    // Just below the threshold it collapses.
    let r = plastic_wall(h, 2000, 3000.0, 0.9 * sdot);
    let b = run(&r, &|_| {}).expect("run");
    assert!(b.failure_layer.is_some());
}

#[test]
fn wolfs_cylinder_plastic_estimate() {
    // green-state.md §5: bottom-layer plastic collapse with the linear f_c gives about 38 layers
    // for the Wolfs 2018 cylinder (γ·n·h ≥ f₀ + ḟ·(n − 1)·T, T = π·0.5 m / (5 m/min)).
    let r = BuildabilitySpec::from_toml_str(kappe::commands::buildability::EXAMPLE_TOML)
        .expect("example");
    assert!((r.layer_time - 18.85).abs() < 0.01, "T = {}", r.layer_time);
    assert_eq!(
        kappe::commands::buildability::plastic_collapse_estimate(&r),
        Some(38)
    );
}

#[test]
fn time_model_laws_and_mohr_coulomb() {
    let lin = TimeModelSpec {
        model: Some(kappe::input::TimeLaw::Linear),
        youngs_modulus: Some(100.0),
        youngs_modulus_rate: Some(2.0),
        cohesion: Some(1000.0),
        friction_angle_deg: Some(30.0),
        ..Default::default()
    }
    .resolve(1.0)
    .expect("valid");
    assert_eq!(lin.modulus(10.0), 120.0);
    // f_c = 2c·cos φ/(1 − sin φ) = 2·1000·cos30°/(1 − 0.5) = 3464.10 (exact up to round-off).
    let mc = lin.mohr_coulomb(0.0).expect("strength");
    assert!((mc.compressive_strength() - 4000.0 * 30f64.to_radians().cos()).abs() < 1e-9);
    // Uniaxial compression at f_c has utilisation 1; pure shear τ = c·cos φ also (plane stress
    // σ₁ = τ, σ₂ = −τ: (σ₁ − σ₂)/2 = τ, mean 0).
    assert!((mc.utilisation(0.0, -mc.compressive_strength()) - 1.0).abs() < 1e-12);
    let tau = 1000.0 * 30f64.to_radians().cos();
    assert!((mc.utilisation(tau, -tau) - 1.0).abs() < 1e-12);
    // Sliding: τ = c + σ·tan φ under compression σ.
    assert!(
        (mc.sliding_utilisation(1000.0 + 500.0 * 30f64.to_radians().tan(), -500.0) - 1.0).abs()
            < 1e-12
    );
    // The exponential law starts with the same rate and accelerates; t_c → ∞ is linear.
    let exp = TimeModelSpec {
        model: Some(kappe::input::TimeLaw::Exponential),
        youngs_modulus: Some(100.0),
        youngs_modulus_rate: Some(2.0),
        time_constant: Some(60.0),
        ..Default::default()
    }
    .resolve(1.0)
    .expect("valid");
    assert!((exp.modulus(60.0) - (100.0 + 2.0 * 60.0 * (1f64.exp() - 1.0))).abs() < 1e-9);
    assert!(exp.modulus(60.0) > lin.modulus(60.0));
    // Constant model: the value at age 0 forever.
    let c = TimeModelSpec::default().resolve(7.0).expect("valid");
    assert!(c.is_constant() && c.modulus(1e6) == 7.0 && c.strength.is_none());
}

/// The error of a spec, as text (panics if it is accepted).
fn rejected(text: &str) -> String {
    match BuildabilitySpec::from_toml_str(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_input_names_the_field() {
    let ok_time = "model = \"linear\"\nyoungs_modulus = 1e5\ncompressive_strength = 5000.0";
    let cases: [(String, &str); 9] = [
        (
            wall(
                0.04,
                0.01,
                10,
                "model = \"linear\"\nyoungs_modulus = 1e5\nyoungs_modulus_rate = -1.0\ncompressive_strength = 5000.0",
                "",
            ),
            "material.time.youngs_modulus_rate",
        ),
        (
            wall(
                0.04,
                0.01,
                10,
                "model = \"linear\"\nyoungs_modulus = 1e5\ncompressive_strength = 5000.0\ncompressive_strength_rate = nan",
                "",
            ),
            "material.time.compressive_strength_rate",
        ),
        (
            wall(
                0.04,
                0.01,
                10,
                "model = \"linear\"\nyoungs_modulus = 1e5\ncompressive_strength = 5000.0\ncompressive_strength_rate = inf",
                "",
            ),
            "material.time.compressive_strength_rate",
        ),
        (
            wall(
                0.04,
                0.01,
                10,
                "model = \"linear\"\nyoungs_modulus = 1e5\ncohesion = 2000.0",
                "",
            ),
            "material.time.friction_angle_deg",
        ),
        (
            wall(
                0.04,
                0.01,
                10,
                "model = \"linear\"\nyoungs_modulus = 1e5",
                "",
            ),
            "material.time.compressive_strength",
        ),
        (
            wall(
                0.04,
                0.01,
                10,
                "model = \"exponential\"\nyoungs_modulus = 1e5\ncompressive_strength = 5000.0",
                "",
            ),
            "material.time.time_constant",
        ),
        (
            wall(0.04, 0.01, 10, ok_time, "")
                .replace("layer_time = 10.0", "layer_time = 10.0\nwait = -1.0"),
            "process.wait",
        ),
        (
            wall(0.04, 0.01, 10, ok_time, "")
                .replace("layer_time = 10.0", "layer_time = 10.0\nwaits = [1.0, 2.0]"),
            "process.waits",
        ),
        (
            wall(0.04, 0.01, 10, ok_time, "").replace(
                "layer_time = 10.0",
                "layer_time = 10.0\nwaits = [1.0, 2.0, -3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
            ),
            "process.waits",
        ),
    ];
    for (text, field) in cases {
        let e = rejected(&text);
        assert!(e.contains(field), "error {e:?} does not name {field}");
    }
}

#[test]
fn waits_age_the_layers_below() {
    // A wait after layer 0 adds to the age of layer 0 in every later state (green-state.md §3).
    let s = kappe::schedule::Schedule::uniform(4, 10.0, &[5.0, 0.0, 0.0, 0.0]).expect("valid");
    assert_eq!(s.ages(1), vec![0.0]);
    // Layer 0: 0–10 s, wait 5 s, layer 1: 15–25 s, layer 2: 25–35 s.
    assert_eq!(s.ages(3), vec![25.0, 10.0, 0.0]);
    assert_eq!(s.total_s(), 45.0);
    assert!(s.to_csv().starts_with("layer,start_s,end_s,wait_s"));
}

/// The analysis of a design as comparable data: every state's BLF and stresses, the constraint
/// report (timings left out: wall clock).
type Fingerprint = (Vec<(Option<f64>, f64, f64)>, String);

fn analysis_fingerprint(design_toml: &str) -> Fingerprint {
    let design = kappe::Design::from_toml_str(design_toml).expect("design");
    let cap = kappe::design_cap(&design, kappe::Context::default()).expect("cap");
    let mut options = design.analysis.clone();
    options.states = "every:10".parse().expect("selection");
    let a = kappe::analysis::analyze(&cap, &options, kappe::analysis::Request::default())
        .expect("analysis");
    let states = a
        .states
        .iter()
        .map(|s| (s.blf, s.max_compression_stress_pa, s.max_tension_stress_pa))
        .collect();
    (states, serde_json::to_string(&a.constraints).expect("json"))
}

#[test]
fn constant_time_model_is_bit_for_bit_the_analysis_without_one() {
    // A short cap keeps the test quick; every:10 still analyses a dozen states.
    let base = "[cap]\nlength = 0.2\n";
    let plain = analysis_fingerprint(base);
    let constant = analysis_fingerprint(&format!("{base}[material.time]\nmodel = \"constant\"\n"));
    // Exact equality (f64 ==): the constant model must not touch a single bit.
    assert_eq!(plain, constant);
    // A linear E(t) does change the BLFs (older layers stiffer): the test can fail.
    let ageing = analysis_fingerprint(&format!(
        "{base}[material.time]\nmodel = \"linear\"\nyoungs_modulus_rate = 1.0e5\n"
    ));
    assert_ne!(plain.0, ageing.0);
}

#[test]
fn old_ageing_table_is_the_linear_time_model() {
    // [analysis.ageing] is read as [material.time] linear E (one model, not two): same BLFs.
    let base = "[cap]\nlength = 0.2\n";
    let old = analysis_fingerprint(&format!(
        "{base}[analysis.ageing]\ninitial_modulus = 5.0e6\nrate = 2.0e4\n"
    ));
    let new = analysis_fingerprint(&format!(
        "{base}[material.time]\nmodel = \"linear\"\nyoungs_modulus = 5.0e6\nyoungs_modulus_rate = 2.0e4\n"
    ));
    let blfs = |f: &Fingerprint| -> Vec<f64> { f.0.iter().filter_map(|s| s.0).collect() };
    // Same layer ages (path length / speed, summed the same way) and the same E(t): equal to
    // the solver's tolerance (1e-8 relative Lanczos residual; 1e-7 leaves room for the
    // different order in which the two paths fill the per-layer moduli).
    for (a, b) in blfs(&old).iter().zip(blfs(&new)) {
        assert!((a / b - 1.0).abs() < 1e-7, "{a} vs {b}");
    }
    // Both at once: an error pointing to the new table.
    let e = kappe::Design::from_toml_str(&format!(
        "{base}[analysis.ageing]\ninitial_modulus = 5.0e6\nrate = 2.0e4\n[material.time]\nmodel = \"linear\"\n"
    ))
    .expect_err("two time models");
    assert!(e.to_string().contains("analysis.ageing") && e.to_string().contains("[material.time]"));
}

#[test]
fn cap_reports_strength_and_sliding_with_ages() {
    // The earth preset: today's constant E and f_c = 20 kPa (Tresca). The cap's analysis then
    // reports the two green checks with the state, element, layer and age of the worst value.
    let design = kappe::Design::from_toml_str(
        "[cap]\nlength = 0.2\n[material.time]\npreset = \"earth\"\nyoungs_modulus = 10.0e6\n",
    )
    .expect("design");
    let cap = kappe::design_cap(&design, kappe::Context::default()).expect("cap");
    let mut options = design.analysis.clone();
    options.states = "every:10".parse().expect("selection");
    let a = kappe::analysis::analyze(&cap, &options, kappe::analysis::Request::default())
        .expect("analysis");
    let strength = a
        .constraints
        .iter()
        .find(|c| c.name == "strength")
        .expect("strength");
    let sliding = a
        .constraints
        .iter()
        .find(|c| c.name == "sliding")
        .expect("sliding");
    for c in [strength, sliding] {
        let w = c.worst.expect("checked");
        assert!(
            w.is_finite() && w >= 0.0 && c.element.contains("age"),
            "{c:?}"
        );
    }
    // Sliding in the centre section: the leaning layer gives τ/σ_n ≈ tan(am) on the bed plane
    // (method.md §5), so the sliding utilisation is not zero.
    assert!(sliding.worst.unwrap_or(0.0) > 0.0);
}

/// Per analysed state: (BLF, strength utilisation, sliding utilisation).
type GreenRow = (Option<f64>, Option<f64>, Option<f64>);

fn green_rows(design: &kappe::Design, grading: Option<kappe::analysis::Grading>) -> Vec<GreenRow> {
    let cap = kappe::design_cap(design, kappe::Context::default()).expect("cap");
    let mut options = design.analysis.clone();
    options.states = "every:4".parse().expect("selection");
    options.grading = grading;
    let a = kappe::analysis::analyze(&cap, &options, kappe::analysis::Request::default())
        .expect("analysis");
    a.states
        .iter()
        .filter(|s| s.blf.is_some())
        .map(|s| (s.blf, s.strength_utilisation, s.sliding_utilisation))
        .collect()
}

#[test]
fn graded_mesh_with_the_strength_model_matches_the_full_mesh() {
    // Issue 11 + 15: `[analysis.grading]` goes through the green-state path (one solve per state
    // gives BLF, strength and sliding). A 0.6 m cap with linear E(t) and Mohr–Coulomb strength;
    // the default grading, whose stress zones (strides 2 and 4 below the 32 fine rows) the
    // centre section's 68 layers reach, so the mesh really is graded.
    let design = kappe::Design::from_toml_str(
        "[cap]\nlength = 0.6\n[material.time]\nmodel = \"linear\"\nyoungs_modulus = 5.0e6\n\
         youngs_modulus_rate = 2000.0\ncohesion = 10000.0\nfriction_angle_deg = 20.0\n",
    )
    .expect("design");
    let g = kappe::analysis::Grading::default();
    let full = green_rows(&design, None);
    let graded = green_rows(&design, Some(g));
    assert_eq!(full.len(), graded.len());
    assert!(full.len() >= 5, "{} states analysed", full.len());
    let rel = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => (b - a).abs() / a.abs().max(1e-12),
        _ => f64::INFINITY,
    };
    let (mut wb, mut ws) = (0.0_f64, 0.0_f64);
    let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
    for (f, g) in full.iter().zip(&graded) {
        wb = wb.max(rel(f.0, g.0));
        ws = ws.max(rel(f.1, g.1));
        let (Some(a), Some(b)) = (f.2, g.2) else {
            panic!("sliding not checked: {f:?} {g:?}");
        };
        lo = lo.min(b / a);
        hi = hi.max(b / a);
    }
    eprintln!(
        "graded vs full: BLF within {:.3} %, strength within {:.3} %, sliding ratio graded/full in [{lo:.3}, {hi:.3}]",
        100.0 * wb,
        100.0 * ws
    );
    // BLF: 1 % (issue 15's bound for the graded mesh; measured 0.009 %). Strength: 2 % (measured
    // 0.006 % with the stress grading's 12 zone rows, `Grading::for_stresses`; 24 % over with 4):
    // the Mohr–Coulomb peak sits in the fine rows or at the bed, where both meshes agree.
    assert!(wb <= 0.01, "BLF {wb}");
    assert!(ws <= 0.02, "strength {ws}");
    // Sliding is the bed-plane shear, which constant-strain triangles spanning up to
    // `max_stride` layers (tall, thin facets) overestimate: the graded mesh is conservative
    // (measured ratio 1.00–1.23). Bound: never more than 1 % below the full mesh, at most 50 %
    // above it. Use the full mesh when sliding governs a design.
    assert!(lo >= 0.99, "graded sliding below the full mesh: {lo}");
    assert!(hi <= 1.5, "graded sliding far above the full mesh: {hi}");
}
