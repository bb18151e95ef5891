//! The invariants of method.md §9 on the default design and on a sweep of designs, checked
//! independently of the pipeline's own bookkeeping (equilibrium is re-summed from the exported
//! network, geometry from the layer planes and translations).

use kappe::form::{Role, build_state};
use kappe::{Cap, Design, design_cap};
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Geometric tolerance of method.md §9 (1e-9 m); coordinates are O(1 m), so this is ~1e7 ulp
/// of slack for the sums of translations.
const GEO_TOL: f64 = 1e-9;

fn design(span: f64, rise: f64, tilt: f64, length: f64) -> Design {
    let mut d = Design::default();
    d.cap.span = span;
    d.cap.rise = rise;
    d.cap.tilt_deg = tilt;
    d.cap.length = length;
    d
}

/// Re-sum `q + Σ F·û + R` at every node of the exported final network.
fn network_residual(cap: &Cap) -> (f64, f64) {
    let doc = kappe::output::network_json(cap).unwrap();
    let nodes = doc["nodes"].as_array().unwrap();
    let xyz = |i: usize| -> V3 {
        let a = &nodes[i]["xyz"];
        V3::new(
            a[0].as_f64().unwrap(),
            a[1].as_f64().unwrap(),
            a[2].as_f64().unwrap(),
        )
    };
    let mut sum: Vec<V3> = nodes
        .iter()
        .map(|n| {
            let l = &n["load"];
            let mut v = V3::new(
                l[0].as_f64().unwrap(),
                l[1].as_f64().unwrap(),
                l[2].as_f64().unwrap(),
            );
            if let Some(r) = n.get("reaction") {
                v += V3::new(
                    r[0].as_f64().unwrap(),
                    r[1].as_f64().unwrap(),
                    r[2].as_f64().unwrap(),
                );
            }
            v
        })
        .collect();
    let mut max_f: f64 = 0.0;
    for key in ["trail_edges", "deviation_edges"] {
        for e in doc[key].as_array().unwrap() {
            let (u, v) = (
                e["u"].as_u64().unwrap() as usize,
                e["v"].as_u64().unwrap() as usize,
            );
            let f = e["force"].as_f64().unwrap();
            max_f = max_f.max(f.abs());
            let d = (xyz(v) - xyz(u)).normalize();
            // A tension edge pulls u toward v: force on u is F·û(v − u).
            sum[u] += d * f;
            sum[v] -= d * f;
        }
    }
    (sum.iter().map(|s| s.norm()).fold(0.0, f64::max), max_f)
}

fn check_invariants(d: &Design) {
    let cap = design_cap(d, kappe::Context::default()).unwrap_or_else(|e| panic!("{e}"));
    let frame = &cap.frame;
    let lh = d.print.layer_height;
    let span = d.cap.span;
    let tag = format!("span {} rise {} tilt {}", span, d.cap.rise, d.cap.tilt_deg);

    // Equilibrium of every node of every state (fixed-geometry force pass).
    for s in &cap.states {
        assert!(
            s.forces.max_residual <= s.forces.residual_tolerance,
            "{tag}: state {} residual {:e} > {:e}",
            s.index,
            s.forces.max_residual,
            s.forces.residual_tolerance
        );
        // All layer edges and all trail edges compressive (zero allowed, to rounding).
        assert!(
            s.forces.max_tension_force <= 1e-9 * (1.0 + s.forces.max_compression_force.abs()),
            "{tag}: tension {:e} in state {}",
            s.forces.max_tension_force,
            s.index
        );
        assert!(
            s.forces.factor_range[0] >= -1e-9 && s.forces.factor_range[1] <= 1.0 + 1e-9,
            "{tag}: factors {:?}",
            s.forces.factor_range
        );
    }
    // Independent re-summation of the exported final network.
    let (res, max_f) = network_residual(&cap);
    assert!(
        res <= 1e-9 * (1.0 + max_f),
        "{tag}: exported network residual {res:e}"
    );
    // Every trail edge of the final state, including the last edge to z = 0, compressive.
    assert!(
        cap.final_forces.trail_forces.iter().all(|&f| f < 0.0),
        "{tag}: a column edge is not compressive"
    );

    // Layer 0: feet on the springing lines, crown at the rise.
    let l0 = &cap.sections.layers[cap.sections.print_index(0).unwrap()];
    let first = l0.nodes.first().unwrap().xyz;
    let last = l0.nodes.last().unwrap().xyz;
    assert!(
        (first - V3::new(-span / 2.0, 0.0, 0.0)).norm() < GEO_TOL,
        "{tag}: left foot {first:?}"
    );
    assert!(
        (last - V3::new(span / 2.0, 0.0, 0.0)).norm() < GEO_TOL,
        "{tag}: right foot {last:?}"
    );
    let crown_z = l0.nodes.iter().map(|n| n.xyz.z).fold(f64::MIN, f64::max);
    assert!(
        (crown_z - d.cap.rise).abs() < GEO_TOL,
        "{tag}: crown at {crown_z}"
    );

    let step = V3::new(0.0, lh / frame.tilt.cos(), 0.0);
    for layer in &cap.sections.layers {
        // Every layer lies in its plane n·x = n·offset (layer 0's plane passes through the origin).
        let c = frame.n.dot(&layer.offset);
        for node in &layer.nodes {
            assert!(
                (frame.n.dot(&node.xyz) - c).abs() < GEO_TOL,
                "{tag}: layer {} off its plane",
                layer.id
            );
            assert!(
                node.xyz.z >= -GEO_TOL,
                "{tag}: layer {} below the base",
                layer.id
            );
        }
        if layer.id >= 0 {
            // Centre layer k = layer 0 + k·(lh/cos am)·e_y, node by node.
            assert_eq!(layer.nodes.len(), l0.nodes.len());
            for (a, b) in layer.nodes.iter().zip(&l0.nodes) {
                assert!(
                    (a.xyz - b.xyz - step * layer.id as f64).norm() < GEO_TOL,
                    "{tag}: layer {}",
                    layer.id
                );
            }
            // Its feet on x = ±Cs/2, z = 0.
            assert!(
                (layer.nodes[0].xyz.x + span / 2.0).abs() < GEO_TOL
                    && layer.nodes[0].xyz.z.abs() < GEO_TOL
            );
        } else {
            // Start layer −m: trimmed translate of layer 0 by T_m; feet on the base plane.
            let t = cap.sections.translations[(-layer.id) as usize];
            for node in &layer.nodes[1..layer.nodes.len() - 1] {
                let kappe::form::NodeKind::Column(i) = node.kind else {
                    panic!("interior foot")
                };
                assert!(
                    (node.xyz - (l0.nodes[i].xyz + t)).norm() < GEO_TOL,
                    "{tag}: layer {}",
                    layer.id
                );
            }
            assert!(
                layer.nodes[0].xyz.z.abs() < GEO_TOL
                    && layer.nodes.last().unwrap().xyz.z.abs() < GEO_TOL
            );
        }
    }
    // Consecutive layer planes are lh apart.
    for w in cap.sections.layers.windows(2) {
        let gap = frame.n.dot(&(w[1].offset - w[0].offset));
        assert!(
            (gap - lh).abs() < GEO_TOL,
            "{tag}: planes {} → {} are {gap} apart",
            w[0].id,
            w[1].id
        );
    }
    // Column ends on the base plane, in every state.
    for top in [
        0,
        cap.sections.layers.len() / 2,
        cap.sections.layers.len() - 1,
    ] {
        let st = build_state(&cap.sections, frame, d.print.start_arch_fraction, top).unwrap();
        for n in st
            .network
            .nodes
            .iter()
            .filter(|n| matches!(n.role, Role::ColumnEnd | Role::Foot))
        {
            assert!(
                n.xyz.z.abs() < GEO_TOL,
                "{tag}: support off the base in state {top}"
            );
        }
    }

    // T1: layer-0 crown stress within 0.5 % of γ·a/cos(am) (method.md §4).
    let nc = cap.arch.segments() / 2;
    let crown_stress = -cap.arch.segment_forces[nc] / (d.print.layer_width * lh);
    let rel = (crown_stress - cap.catenary.crown_stress).abs() / cap.catenary.crown_stress;
    assert!(
        rel < 5e-3,
        "{tag}: crown stress {crown_stress} vs catenary {} ({rel:e})",
        cap.catenary.crown_stress
    );

    // Print path: continuous, every node of every layer in order, tip lh/2 above along n.
    let mut k = 0;
    for layer in &cap.sections.layers {
        let pts: Vec<_> = cap.path.points[k..k + layer.nodes.len()].to_vec();
        k += layer.nodes.len();
        let fwd = pts[0].bead == layer.nodes[0].xyz;
        for (j, p) in pts.iter().enumerate() {
            let node = if fwd {
                &layer.nodes[j]
            } else {
                &layer.nodes[layer.nodes.len() - 1 - j]
            };
            assert_eq!(p.layer, layer.id);
            assert_eq!(p.index, j);
            assert!((p.bead - node.xyz).norm() == 0.0);
            assert!((p.tip - p.bead - frame.n * (lh / 2.0)).norm() < 1e-12);
            assert!((p.axis + frame.n).norm() < 1e-12);
        }
    }
    assert_eq!(k, cap.path.points.len());
}

#[test]
fn default_design_keeps_every_invariant() {
    check_invariants(&Design::default());
}

#[test]
fn default_design_matches_the_method_numbers() {
    let d = Design::default();
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    // method.md §5–6 and §9 give these for the defaults (3 significant digits there).
    assert_eq!(cap.sections.n_centre, 68);
    assert_eq!(cap.sections.n_start, 45);
    let f = &cap.states.last().unwrap().forces;
    assert!(
        (f.column_end_reaction[1] - 108.0).abs() < 0.5,
        "thrust {}",
        f.column_end_reaction[1]
    );
    assert!((f.column_end_hv_ratio - 0.92).abs() < 0.005);
    assert!(
        (f.min_column_hv_ratio - 0.70).abs() < 0.005
            && (f.max_column_hv_ratio - 3.17).abs() < 0.005
    );
    let arch_min = cap
        .arch
        .segment_forces
        .iter()
        .fold(0.0_f64, |m, &x| m.min(x))
        / (0.02 * 0.008);
    assert!(
        (arch_min / 1e3 + 15.45).abs() < 0.01,
        "arch stress {arch_min}"
    );
    assert!((f.max_compression_stress / 1e3 + 15.45).abs() < 0.01);
    let bed = cap
        .final_forces
        .trail_forces
        .iter()
        .fold(0.0_f64, |m, &x| m.min(x))
        / (0.02 * cap.arch.segment_length);
    // method.md quotes −10.2 kPa with l_trib = Δs = 20 mm; Kappe uses the node's actual tributary
    // length s = 20.09 mm, so the same force gives a stress smaller by Δs/s.
    let expected = -10.2e3 * 0.02 / cap.arch.segment_length;
    assert!(
        (bed - expected).abs() < 50.0,
        "bed joint stress {bed} vs {expected}"
    );
    // Overhang: lh·tan(am) = 3.73 mm in the centre, up to 4.5 mm in the start section.
    let max_o = cap.overhangs.iter().fold(0.0_f64, |m, o| m.max(o.abs()));
    assert!((max_o * 1e3 - 4.47).abs() < 0.05, "overhang {max_o}");
    // The discrete layer lies within 0.13 mm of the catenary (O(Δs²)); the sampled distance adds
    // at most 0.1 mm of sampling error.
    let worst = cap
        .arch
        .points
        .iter()
        .map(|p| cap.catenary.distance_to(p, d.cap.span, &cap.frame))
        .fold(0.0, f64::max);
    assert!(worst < 0.2e-3, "distance to catenary {worst}");
}

#[test]
fn a_sweep_of_designs_keeps_every_invariant() {
    // Span 0.5–1.2 m, rise/span 1/6–1/2, tilt 10°–40° (short centre sections keep it quick).
    for &(span, ratio, tilt) in &[
        (0.5, 1.0 / 6.0, 10.0),
        (0.5, 0.5, 40.0),
        (1.2, 1.0 / 6.0, 40.0),
        (1.2, 0.5, 10.0),
        (0.8, 0.3, 25.0),
    ] {
        check_invariants(&design(span, span * ratio, tilt, 0.15));
    }
}

#[test]
fn bad_fields_are_named_with_their_range() {
    let cases = [
        ("[cap]\ntilt_deg = 75.0\n", "cap.tilt_deg"),
        ("[cap]\ntilt_deg = 0.0\n", "cap.tilt_deg"),
        ("[cap]\nrise = -0.1\n", "cap.rise"),
        ("[cap]\nrise = 0.01\n", "cap.rise"),
        ("[print]\nlayer_height = 0.02\n", "print.layer_height"),
        ("[print]\nlayer_width = 0.05\n", "print.layer_width"),
        (
            "[material]\nspecific_weight = nan\n",
            "material.specific_weight",
        ),
        (
            "[print]\nstart_arch_fraction = 1.0\n",
            "print.start_arch_fraction",
        ),
    ];
    for (text, field) in cases {
        let err = Design::from_toml_str(text).unwrap_err().to_string();
        assert!(
            err.contains(field) && err.contains("allowed"),
            "{text:?} gave {err}"
        );
    }
    let err = Design::from_toml_str("[cap]\nspam = 1\n")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("spam") && err.contains("did you mean `span`"),
        "unknown field: {err}"
    );
    let err = Design::from_toml_str("[cap\nspan = 1")
        .unwrap_err()
        .to_string();
    // The parser's own words, without an empty path in front (issue 28: "design file: : …").
    assert!(err.starts_with("TOML parse error"), "{err}");
}

#[test]
fn the_example_file_is_the_default_design() {
    assert_eq!(
        Design::from_toml_str(kappe::input::EXAMPLE_TOML).unwrap(),
        Design::default()
    );
}

#[test]
fn meshes_are_valid_gltf_and_obj() {
    let mut d = Design::default();
    d.cap.length = 0.05;
    let cap = design_cap(&d, kappe::Context::default()).unwrap();
    let glb = cap.mesh.to_glb().unwrap();
    let gltf = gltf::Gltf::from_slice(&glb).expect("valid GLB");
    let mesh = gltf.meshes().next().unwrap();
    let prim = mesh.primitives().next().unwrap();
    assert_eq!(
        prim.indices().unwrap().count(),
        cap.mesh.triangles.len() * 3
    );
    assert_eq!(
        prim.get(&gltf::Semantic::Positions).unwrap().count(),
        cap.mesh.positions.len()
    );
    let obj = cap.mesh.to_obj("t");
    let v = obj.lines().filter(|l| l.starts_with("v ")).count();
    let f = obj.lines().filter(|l| l.starts_with("f ")).count();
    assert_eq!((v, f), (cap.mesh.positions.len(), cap.mesh.triangles.len()));
    // Closed beads: every edge shared by exactly two triangles.
    let mut edges = std::collections::HashMap::new();
    for t in &cap.mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    assert!(edges.values().all(|&c| c == 2), "bead mesh is not closed");
}

/// Every print state's force pass over the model built from its trails (`state_pass`, what
/// `design_cap` and the designer run on every change) equals, bit for bit, the pass over its CEM
/// topology validated and built by `kappe_cem::Model::new` (the general entry point), on the
/// default cap and on an end-wall cap (whose column ends lie on the wall face); and the cap's
/// summaries come from the same numbers. Exact equality: both build the same schedule and
/// adjacency (one implementation), so any difference in order would change the rounding.
#[test]
fn every_state_pass_equals_the_pass_over_its_topology() {
    let mut wall = Design::default();
    wall.cap.end = kappe::form::EndKind::EndWall;
    for d in [Design::default(), wall] {
        let cap = design_cap(&d, kappe::Context::default()).unwrap();
        let areas = cap.areas();
        for (top, summary) in cap.states.iter().enumerate() {
            let state = cap.state(top).unwrap();
            let (fast, forces) = kappe::form::state_pass(&state, areas).unwrap();
            let topo = state.network.to_topology("state");
            let general =
                kappe_cem::fixed_geometry::force_pass(&topo, &state.network.positions()).unwrap();
            assert_eq!(fast, general, "state {top}");
            assert_eq!(forces, summary.forces, "state {top}");
        }
    }
}
