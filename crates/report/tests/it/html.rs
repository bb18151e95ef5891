//! The page is self-contained, its data island round-trips and nothing ends a script early.

use kappe_report::{Bound, ConstraintRow, demo_input, render_html};

use crate::island;

/// Every value of an attribute `name=` in the page (double or single quoted).
fn attribute_values<'a>(html: &'a str, name: &str) -> Vec<&'a str> {
    let mut out = Vec::new();
    for quote in ['"', '\''] {
        let pat = format!("{name}={quote}");
        let mut rest = html;
        while let Some(i) = rest.find(&pat) {
            let after = &rest[i + pat.len()..];
            let end = after.find(quote).unwrap_or(after.len());
            out.push(&after[..end]);
            rest = &after[end..];
        }
    }
    out
}

#[test]
fn page_is_self_contained() {
    let html = render_html(&demo_input()).unwrap();
    for attr in ["src", "href", "srcset", "action", "data"] {
        for v in attribute_values(&html, attr) {
            let v = v.trim().to_ascii_lowercase();
            assert!(
                !(v.starts_with("http:") || v.starts_with("https:") || v.starts_with("//")),
                "external {attr}={v:?}"
            );
        }
    }
    let lower = html.to_ascii_lowercase();
    // No external scripts, style sheets or CSS imports at all.
    assert!(!lower.contains("<script src"), "external script");
    assert!(!lower.contains("<link"), "linked resource");
    assert!(!lower.contains("@import"), "css import");
    assert!(!lower.contains("url(http"), "css url");
    // The vendored bundle and the viewer are inlined, with three's licence.
    assert!(html.contains("Three.js Authors"));
    assert!(html.contains("KAPPE_READY"));
    assert!(html.contains("The MIT License"));
}

/// Decodes a base64 little-endian f32 array of the island.
fn f32s(v: &serde_json::Value) -> Vec<f32> {
    use base64::Engine as _;
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(v.as_str().expect("a base64 string"))
        .unwrap();
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

#[test]
fn data_island_parses_back() {
    let input = demo_input();
    let html = render_html(&input).unwrap();
    let back: serde_json::Value = serde_json::from_str(island(&html)).unwrap();
    assert_eq!(back["name"], input.name.as_str());
    assert_eq!(back["layers"].as_array().unwrap().len(), input.layers.len());
    assert_eq!(back["states"].as_array().unwrap().len(), input.states.len());
    assert_eq!(
        back["constraints"].as_array().unwrap().len(),
        input.constraints.len()
    );
    // Coordinates travel as f32: relative error ≤ 2^-24 ≈ 6e-8 (round to nearest).
    let nodes = f32s(&back["nodes"]);
    let expected: Vec<f64> = input
        .layers
        .iter()
        .flat_map(|l| l.nodes.iter().flatten().copied())
        .collect();
    assert_eq!(nodes.len(), expected.len());
    for (a, b) in nodes.iter().zip(&expected) {
        assert!((f64::from(*a) - b).abs() <= 6e-8 * b.abs(), "{a} vs {b}");
    }
    // The timeline: one time per path point, non-decreasing, ending at the total time.
    let times = f32s(&back["path"]["time"]);
    assert_eq!(times.len(), input.print_path.points.len());
    assert!(times.windows(2).all(|w| w[0] <= w[1]));
    let total = back["total_time"].as_f64().unwrap();
    assert!(f64::from(*times.last().unwrap()) <= total * (1.0 + 1e-6));
    // Layer stress of every state from the chunk pool equals the input (f32).
    let q = &back["quantities"][0];
    assert_eq!(q["key"], "layer_stress");
    let pool = f32s(&q["pool"]);
    let offsets: Vec<i32> = {
        use base64::Engine as _;
        base64::engine::general_purpose::STANDARD
            .decode(q["offsets"].as_str().unwrap())
            .unwrap()
            .chunks_exact(4)
            .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    };
    let scales = f32s(&q["scales"]);
    let mut k = 0;
    for st in &input.states {
        let values = st.segment_stress.as_ref().unwrap();
        // Chunks proportional to a stored one: within 1e-7 of the largest value, plus f32
        // rounding of the value and of the scale (2e-7 of the largest covers both).
        let big = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut at = 0;
        for l in input.layers.iter().take(st.layers_printed) {
            let o = usize::try_from(offsets[k]).unwrap();
            let c = f64::from(scales[k]);
            for j in 0..l.segment_stress.len() {
                let want = values[at + j];
                assert!((f64::from(pool[o + j]) * c - want).abs() <= 2e-7 * big);
            }
            at += l.segment_stress.len();
            k += 1;
        }
    }
    assert_eq!(k, offsets.len());
    // Extra quantities follow the built-in ones.
    let keys: Vec<&str> = back["quantities"]
        .as_array()
        .unwrap()
        .iter()
        .map(|q| q["key"].as_str().unwrap())
        .collect();
    assert_eq!(keys, ["layer_stress", "bed_joint_stress", "layer_age"]);
}

#[test]
fn script_end_tags_in_data_are_escaped() {
    let mut input = demo_input();
    let evil = "</script><script>alert(1)</script><!-- </SCRIPT >";
    input.name = evil.into();
    input.parameters[0].value = evil.into();
    input.constraints[0].element = Some(evil.into());
    let html = render_html(&input).unwrap();
    // Exactly the page's own four scripts open and close (data, robot meshes, three, viewer).
    let lower = html.to_ascii_lowercase();
    assert_eq!(lower.matches("<script").count(), 4);
    assert_eq!(lower.matches("</script").count(), 4);
    assert!(!island(&html).contains('<'));
    let back: serde_json::Value = serde_json::from_str(island(&html)).unwrap();
    assert_eq!(back["name"], evil);
    // In element content the text is HTML-escaped.
    assert!(html.contains("&lt;/script&gt;&lt;script&gt;alert(1)"));
}

#[test]
fn failed_constraints_are_highlighted() {
    let mut input = demo_input();
    let html = render_html(&input).unwrap();
    assert_eq!(html.matches("<tr class=\"fail").count(), 0);
    assert!(html.contains("verdict pass"));
    input.constraints.push(ConstraintRow {
        name: "blf_final".into(),
        bound: Bound::AtLeast,
        limit: 3.0,
        worst: 2.4,
        unit: String::new(),
        state: Some(35),
        element: None,
        pass: false,
    });
    input.constraints[1].pass = false;
    let html = render_html(&input).unwrap();
    assert_eq!(html.matches("<tr class=\"fail").count(), 2);
    assert_eq!(html.matches("class=\"result fail\"").count(), 2);
    assert!(html.contains(&format!(
        "FAIL: 2 of {} constraints violated",
        input.constraints.len()
    )));
}

#[test]
fn plots_are_inline_svg_and_follow_the_data() {
    let mut input = demo_input();
    let html = render_html(&input).unwrap();
    // BLF, stress, overhang, joint angles, the demo's layer age, and the base placement.
    assert_eq!(html.matches("<figure").count(), 6);
    assert!(!html.contains("<?xml"));
    for title in [
        "Buckling load factor vs print progress",
        "Extreme normal stress vs print progress",
        "Overhang per layer",
        "Joint angles over time",
        "layer age vs print progress",
    ] {
        assert!(html.contains(title), "{title}");
    }
    input.robot = None;
    for s in &mut input.states {
        s.blf = None;
    }
    let html = render_html(&input).unwrap();
    // Stress, overhang, layer age and the base placement (the cell is still there).
    assert_eq!(html.matches("<figure").count(), 4);
}

#[test]
fn one_timeline_that_opens_at_the_end() {
    let html = render_html(&demo_input()).unwrap();
    assert!(html.contains("id=\"timeline\" min=\"0\" max=\"10000\" step=\"1\" value=\"10000\""));
    assert!(!html.contains("state-slider"));
    // The BLF plot has a log axis: its ticks are 1-2-5 values, and a cursor frame.
    assert!(html.contains("data-cursor=\"progress\""));
    assert!(html.contains("data-cursor=\"time\""));
}

#[test]
fn round_off_stress_reads_zero_and_rows_link_to_places() {
    let mut input = demo_input();
    input.constraints[1].worst = 2.798e-12;
    let html = render_html(&input).unwrap();
    let start = html.find("id=\"constraints\"").unwrap();
    let table = &html[start..start + html[start..].find("</table>").unwrap()];
    assert!(table.contains("0 (round-off)"));
    assert!(!table.contains("2.798e-12"));
    // The demo gives places for sigma_min and blf: those rows are links.
    assert_eq!(html.matches("class=\"pass-row link\"").count(), 2);
}

#[test]
fn island_reads_back_into_a_valid_input() {
    let input = demo_input();
    let html = render_html(&input).unwrap();
    let back = kappe_report::read_island(island(&html)).unwrap();
    back.validate().unwrap();
    assert_eq!(back.layers.len(), input.layers.len());
    assert_eq!(back.states.len(), input.states.len());
    assert_eq!(back.modes.len(), input.modes.len());
    // The cell is plain JSON: 7 significant digits.
    let (ca, cb) = (back.cell.unwrap(), input.cell.unwrap());
    assert_eq!(ca.stations.len(), cb.stations.len());
    assert_eq!(ca.stations[1].layers, cb.stations[1].layers);
    assert!(
        (ca.stations[1].world_from_base[1][3] - cb.stations[1].world_from_base[1][3]).abs() < 1e-6
    );
    // f32 storage: relative error ≤ 2^-24 ≈ 6e-8 per value; a stress chunk kept as a multiple
    // of another is within 1e-7 of its largest magnitude, plus the f32 rounding of both factors
    // (2e-7 of the state's largest stress covers it).
    let close = |a: f64, b: f64| (a - b).abs() <= 6e-8 * b.abs();
    for (a, b) in back.states.iter().zip(&input.states) {
        let (sa, sb) = (
            a.segment_stress.as_ref().unwrap(),
            b.segment_stress.as_ref().unwrap(),
        );
        assert_eq!(sa.len(), sb.len());
        let big = sb.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(sa.iter().zip(sb).all(|(x, y)| (x - y).abs() <= 2e-7 * big));
    }
    let (ra, rb) = (back.robot.unwrap(), input.robot.unwrap());
    assert_eq!(ra.station, rb.station);
    assert!(ra.times.iter().zip(&rb.times).all(|(x, y)| close(*x, *y)));
    // Mode shapes: normalised to max |u| = 1 and quantised in steps of 1/127.
    let m = &back.modes[5];
    let src = &input.modes[5].displacement;
    let max = src
        .iter()
        .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
        .fold(0.0, f64::max);
    for (a, b) in m.displacement.iter().zip(src) {
        for k in 0..3 {
            // Half a step of rounding, plus the 1 % cut-off outside the stored node range.
            assert!(
                (a[k] - b[k] / max).abs() <= 0.5 / 127.0 + 0.01,
                "{a:?} {b:?}"
            );
        }
    }
}

#[test]
fn robot_section_shows_slowdowns_and_both_models_clearances() {
    let mut input = demo_input();
    let html = render_html(&input).unwrap();
    let section = &html[html.find("id=\"robot-check\"").unwrap()..];
    let section = &section[..section.find("</section>").unwrap()];
    // The demo's slowdown: where (station, layers/points), by how much (ratio and speed), why.
    assert!(section.contains("id=\"slowdown-table\""), "{section}");
    assert!(section.contains("<td class=\"num\">3 / 10</td><td class=\"num\">3 / 14</td>"));
    assert!(section.contains("86.0 % (43.0 mm/s)"), "{section}");
    assert!(section.contains("joint acceleration"));
    // The clearance at the waypoints next to the certified bound along the motion.
    assert!(section.contains("55.5 mm"), "{section}");
    assert!(section.contains("31.0 mm"), "{section}");
    // A self pair certified just above the zero margin between links proves no contact; it must
    // not read as "0.0 mm". A larger bound is shown as a length.
    {
        let r = input.robot_summary.as_mut().unwrap();
        for along in [2e-6, 0.004] {
            r.clearances.push(kappe_report::ClearanceRow {
                model: "arm meshes (UR)".into(),
                to: "self".into(),
                at_waypoints: 0.0402,
                at: "upper_arm–wrist_3".into(),
                along_motion: Some(along),
            });
        }
    }
    let html = render_html(&input).unwrap();
    let rows = &html[html.find("id=\"clearance-table\"").unwrap()..];
    assert!(rows.contains("no contact (certified)"), "{rows}");
    assert!(rows.contains(">4.0 mm</td>"), "{rows}");
    assert!(!rows.contains(">0.0 mm</td>"), "{rows}");
    input.robot_summary.as_mut().unwrap().clearances.truncate(1);
    // No slowdown: one sentence with the design speed and the largest joint ratios.
    input.robot_summary.as_mut().unwrap().slowdowns.clear();
    let html = render_html(&input).unwrap();
    assert!(html.contains("keeps the design speed of 50 mm/s"));
    assert!(!html.contains("slowdown-table"));
    // A non-finite clearance is refused, naming the field.
    input.robot_summary.as_mut().unwrap().clearances[0].along_motion = Some(f64::NAN);
    let e = render_html(&input).unwrap_err().to_string();
    assert!(
        e.contains("robot_summary.clearances[0].along_motion"),
        "{e}"
    );
    // No robot summary: no section.
    input.robot_summary = None;
    assert!(!render_html(&input).unwrap().contains("robot-check"));
}
