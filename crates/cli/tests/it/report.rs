//! The report input that `kappe study` (and `kappe design`) write into each design's
//! `report.html`, read back from the page's JSON island and checked against the closed forms of
//! method.md and against the same design's `summary.json`.

use std::path::Path;
use std::process::{Command, Output};

use kappe_report::ReportInput;

const KAPPE: &str = env!("CARGO_BIN_EXE_kappe");

fn kappe(args: &[&str], cwd: &Path) -> Output {
    Command::new(KAPPE)
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

/// The page's scene data: `<script type="application/json" id="kappe-data">…</script>`, read
/// back with `kappe_report::read_island`.
fn island(html: &str) -> ReportInput {
    let start = html.find("id=\"kappe-data\">").unwrap() + "id=\"kappe-data\">".len();
    let len = html[start..].find("</script>").unwrap();
    kappe_report::read_island(&html[start..start + len]).unwrap()
}

/// Catenary parameter a of method.md §4: a(cosh(Cs/2a) − 1) = R, by bisection (the left side
/// falls monotonically in a).
fn catenary_a(span: f64, r: f64) -> f64 {
    let (mut lo, mut hi) = (1e-3, 1e3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid * ((span / (2.0 * mid)).cosh() - 1.0) > r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The island keeps its long arrays as f32 (relative error ≤ 2^-24 ≈ 6e-8) and rounds the other
/// numbers to 7 significant digits (`ISLAND_SIGNIFICANT_DIGITS`, ≤ 5e-7 relative); 1e-6 covers
/// both with a margin.
const ISLAND_REL: f64 = 1e-6;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[test]
fn report_input_matches_closed_forms_and_the_summary() {
    assert_eq!(kappe_report::ISLAND_SIGNIFICANT_DIGITS, 7);
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    // 8 centre layers (round(0.1·cos 25°/0.012)), lw = 30 mm so that l_o,max = 15 mm holds.
    let (span, rise, tilt_deg, lh, lw, gamma) = (0.8, 0.2, 25.0_f64, 0.012, 0.03, 23044.0);
    std::fs::write(
        work.join("one.toml"),
        "[[design]]\nname = \"cheap\"\ncap.length = 0.1\nprint.layer_height = 0.012\n\
         print.layer_width = 0.03\nrobot.plan.pump.flow_factor = 0.5\n\
         [analysis]\nbuckling = false\n",
    )
    .unwrap();
    // Without buckling (a study analyses as `kappe design` does, buckling on, unless its
    // [analysis] says otherwise): this test checks the stress and overhang rows in closed form.
    let run = kappe(&["study", "one.toml", "--out", "s", "-q"], work);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let dir = work.join("s/designs/cheap");
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let input = island(&html);
    input.validate().unwrap();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let counts = &summary["counts"];
    let count = |k: &str| counts[k].as_u64().unwrap() as usize;

    assert_eq!(input.name, "cheap");
    assert_eq!(input.layers.len(), count("layers"));
    assert_eq!(input.states.len(), count("states"));
    assert_eq!(input.print_path.points.len(), count("path_points"));
    assert_eq!(input.bed_joints.len(), count("trail_edges"));
    let n_centre = count("centre_layers");
    assert_eq!(n_centre, 8);
    let am = tilt_deg.to_radians();

    // T1 (method.md §4, §9): the crown segment of every centre layer (d = 1) carries
    // σ = −γ·a/cos(am) within 0.5 % at Δs = 0.02 (the discrete layer agrees to 0.05 %).
    let a = catenary_a(span, rise / am.cos());
    let crown = -gamma * a / am.cos();
    for layer in input.layers.iter().filter(|l| l.id >= 0) {
        let nc = layer.segment_stress.len() / 2;
        let s = layer.segment_stress[nc];
        assert!(close(s, crown, 5e-3), "layer {}: {s} vs {crown}", layer.id);
    }

    // Bed joints between centre layers j−1 and j (method.md §5, final state t = N−1): trail force
    // −(N − j)·W·tan(am) with W = γ·lw·lh·l_trib on the area lw·l_trib, so
    // σ = −(N − j)·γ·lh·tan(am), independent of the node.
    let mut checked = 0;
    for joint in input.bed_joints.iter().filter(|j| j.layer >= 1) {
        let expected = -((n_centre as i32 - joint.layer) as f64) * gamma * lh * am.tan();
        assert!(
            close(joint.stress, expected, ISLAND_REL),
            "joint under layer {}: {} vs {expected}",
            joint.layer,
            joint.stress
        );
        // Horizontal and lh/cos(am) long (method.md §5).
        let d = [
            joint.b[0] - joint.a[0],
            joint.b[1] - joint.a[1],
            joint.b[2] - joint.a[2],
        ];
        assert!(d[0].abs() < 1e-6 && d[2].abs() < 1e-6, "{d:?}");
        // A difference of two f32 coordinates of magnitude < 1 m: ≤ 2 · 2^-24 m ≈ 1.2e-7 m.
        assert!((d[1] - lh / am.cos()).abs() < 2e-7, "{d:?}");
        checked += 1;
    }
    assert!(checked > 0);

    // Overhang of centre layers over the layer before: lh·tan(am) (method.md §3); the first
    // layer printed has none.
    assert_eq!(input.layers[0].overhang, None);
    for layer in input.layers.iter().filter(|l| l.id >= 1) {
        let o = layer.overhang.unwrap();
        assert!(
            close(o.abs(), lh * am.tan(), ISLAND_REL),
            "layer {}: {o}",
            layer.id
        );
    }
    // Bead size and layer normal n = (0, cos am, sin am) (method.md §4).
    for layer in &input.layers {
        assert_eq!((layer.bead_width, layer.bead_height), (lw, lh));
        assert!(close(layer.plane_normal[1], am.cos(), ISLAND_REL));
        assert!(close(layer.plane_normal[2], am.sin(), ISLAND_REL));
    }
    // Tool axis along −n (method.md §7).
    for axis in &input.print_path.tool_axis {
        assert!(axis[0].abs() < 1e-9 && close(axis[1], -am.cos(), ISLAND_REL));
    }

    // States: the extremes are those of summary.json, state by state; every state carries its
    // own segment stresses, and the last one is the final state shown on the layers.
    let states = summary["states"].as_array().unwrap();
    for (s, j) in input.states.iter().zip(states) {
        assert_eq!(
            s.layers_printed,
            j["layers_printed"].as_u64().unwrap() as usize
        );
        let c = j["max_compression_stress_pa"].as_f64().unwrap();
        assert!(close(s.sigma_min, c, ISLAND_REL), "{} vs {c}", s.sigma_min);
        assert!(s.segment_stress.is_some());
    }
    let last = input.states.last().unwrap().segment_stress.clone().unwrap();
    let from_layers: Vec<f64> = input
        .layers
        .iter()
        .flat_map(|l| l.segment_stress.iter().copied())
        .collect();
    // Both read back from f32 arrays, the state's as a multiple of a stored layer chunk: equal
    // within 2e-7 of the largest stress (f32 rounding of value and scale).
    assert_eq!(last.len(), from_layers.len());
    let big = from_layers.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!(
        last.iter()
            .zip(&from_layers)
            .all(|(a, b)| (a - b).abs() <= 2e-7 * big)
    );

    // Constraint table: σ_min, σ_max, overhang with the design's limits; their verdict is the
    // study's.
    let names: Vec<&str> = input.constraints.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "sigma_min",
            "sigma_max",
            "overhang_max",
            "robot_plan",
            "base_tolerance"
        ]
    );
    assert_eq!(input.constraints[0].limit, -20.0);
    assert_eq!(input.constraints[2].limit, 15.0);
    let all_pass = input.constraints.iter().all(|c| c.pass);
    assert!(all_pass, "{:?}", input.constraints);
    let csv = std::fs::read_to_string(work.join("s/study.csv")).unwrap();
    assert!(csv.lines().nth(1).unwrap().contains(",pass,"), "{csv}");
    assert!(html.contains("PASS: all 5 constraints met"));
    // The robot was planned (the design's default) and is animated from the plan's waypoints
    // (the page draws the UR10e meshes at the cell's stations): a station per frame, and the
    // timeline's point times are the waypoints' times.
    let robot = input.robot.as_ref().unwrap();
    assert!(robot.times.len() >= input.print_path.points.len());
    assert_eq!(robot.station.len(), robot.times.len());
    let cell = input.cell.as_ref().unwrap();
    assert!(!cell.stations.is_empty());
    let timeline = input.timeline.as_ref().unwrap();
    assert_eq!(timeline.point_time.len(), input.print_path.points.len());
    // The robot section: the tool speed and the clearances of both models, the meshes' next to
    // the capsules', with the certified bound along the motion never above the waypoints' value.
    let summary = input.robot_summary.as_ref().unwrap();
    assert!(html.contains("id=\"robot-check\""));
    let models: Vec<&str> = summary
        .clearances
        .iter()
        .map(|c| c.model.as_str())
        .collect();
    assert!(models.contains(&"arm meshes (UR)") && models.contains(&"arm capsules"));
    for c in &summary.clearances {
        if let Some(along) = c.along_motion {
            assert!(along <= c.at_waypoints + 1e-12, "{c:?}");
        }
    }
}

#[test]
fn failed_constraints_are_marked_in_the_report() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path();
    // σ_min = −12 kPa is below the ~15.4 kPa springing stress; lw = 20 mm gives l_o,max = 10 mm
    // against ~15 mm of start-section overhang at lh = 12 mm.
    std::fs::write(
        work.join("one.toml"),
        "[[design]]\nname = \"weak\"\ncap.length = 0.1\nprint.layer_height = 0.012\n\
         constraints.sigma_min = -12e3\n",
    )
    .unwrap();
    // A study whose designs fail exits 1 (the exit-status scheme of `kappe --help`).
    let run = kappe(&["study", "one.toml", "--out", "s", "-q"], work);
    assert_eq!(
        run.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let html = std::fs::read_to_string(work.join("s/designs/weak/report.html")).unwrap();
    let input = island(&html);
    // Without an [analysis] table the study analyses as `kappe design` does (buckling on), so
    // the BLF and as-printed rows follow the three preliminary ones, then the robot's.
    let names: Vec<&str> = input.constraints.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "sigma_min",
            "sigma_max",
            "overhang_max",
            "blf_min",
            "deviation_max",
            "robot_plan",
            "base_tolerance"
        ]
    );
    let row = |name: &str| input.constraints.iter().find(|c| c.name == name).unwrap();
    assert!(!row("sigma_min").pass);
    assert!(row("sigma_max").pass);
    assert!(!row("overhang_max").pass);
    assert!(row("robot_plan").pass);
    // The BLF row agrees with its own numbers (the island keeps 7 significant digits).
    let blf = row("blf_min");
    assert_eq!(blf.pass, blf.worst >= blf.limit);
    // The worst overhang is in the start section: a layer with a negative id.
    let element = row("overhang_max").element.clone().unwrap();
    assert!(element.starts_with("layer -"), "{element}");
    assert!(input.states.iter().any(|s| !s.ok));
    let failing = input.constraints.iter().filter(|c| !c.pass).count();
    assert!(html.contains(&format!("FAIL: {failing} of 7 constraints violated")));
}
