//! The page is self-contained, its data island round-trips and nothing ends a script early.

use kappe_report::{Bound, ConstraintRow, ReportInput, demo_input, render_html};

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

#[test]
fn data_island_parses_back() {
    let input = demo_input();
    let html = render_html(&input).unwrap();
    let back: ReportInput = serde_json::from_str(island(&html)).unwrap();
    assert_eq!(back.name, input.name);
    assert_eq!(back.layers.len(), input.layers.len());
    assert_eq!(back.states.len(), input.states.len());
    assert_eq!(back.constraints.len(), input.constraints.len());
    assert_eq!(back.parameters, input.parameters);
    // Floats are rounded to 7 significant digits in the island (ISLAND_SIGNIFICANT_DIGITS):
    // relative error ≤ 0.5e-6.
    for (a, b) in back.layers.iter().zip(&input.layers) {
        assert_eq!(a.id, b.id);
        for (p, q) in a.nodes.iter().zip(&b.nodes) {
            for k in 0..3 {
                assert!((p[k] - q[k]).abs() <= 5e-7 * q[k].abs().max(1e-300));
            }
        }
        for (s, t) in a.segment_stress.iter().zip(&b.segment_stress) {
            assert!((s - t).abs() <= 5e-7 * t.abs());
        }
    }
    let (ra, rb) = (back.robot.unwrap(), input.robot.unwrap());
    assert_eq!(ra.poses.len(), rb.poses.len());
    assert_eq!(ra.link_radii, rb.link_radii);
}

#[test]
fn script_end_tags_in_data_are_escaped() {
    let mut input = demo_input();
    let evil = "</script><script>alert(1)</script><!-- </SCRIPT >";
    input.name = evil.into();
    input.parameters[0].value = evil.into();
    input.constraints[0].element = Some(evil.into());
    let html = render_html(&input).unwrap();
    // Exactly the page's own three scripts open and close.
    let lower = html.to_ascii_lowercase();
    assert_eq!(lower.matches("<script").count(), 3);
    assert_eq!(lower.matches("</script").count(), 3);
    assert!(!island(&html).contains('<'));
    let back: ReportInput = serde_json::from_str(island(&html)).unwrap();
    assert_eq!(back.name, evil);
    // In element content the text is HTML-escaped.
    assert!(html.contains("&lt;/script&gt;&lt;script&gt;alert(1)"));
}

#[test]
fn failed_constraints_are_highlighted() {
    let mut input = demo_input();
    let html = render_html(&input).unwrap();
    assert_eq!(html.matches("<tr class=\"fail\">").count(), 0);
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
    assert_eq!(html.matches("<tr class=\"fail\">").count(), 2);
    assert!(html.contains(&format!(
        "FAIL: 2 of {} constraints violated",
        input.constraints.len()
    )));
}

#[test]
fn plots_are_inline_svg_and_follow_the_data() {
    let mut input = demo_input();
    let html = render_html(&input).unwrap();
    // BLF, stress, overhang, joint angles.
    assert_eq!(html.matches("<svg").count(), 4);
    assert!(!html.contains("<?xml"));
    for title in [
        "Buckling load factor vs print progress",
        "Extreme normal stress vs print progress",
        "Overhang per layer",
        "Joint angles over time",
    ] {
        assert!(html.contains(title), "{title}");
    }
    input.robot = None;
    for s in &mut input.states {
        s.blf = None;
    }
    let html = render_html(&input).unwrap();
    assert_eq!(html.matches("<svg").count(), 2);
}

#[test]
fn state_slider_spans_all_states_and_starts_at_the_last() {
    let input = demo_input();
    let html = render_html(&input).unwrap();
    let last = input.states.len() - 1;
    assert!(html.contains(&format!(
        "id=\"state-slider\" min=\"0\" max=\"{last}\" step=\"1\" value=\"{last}\""
    )));
}
