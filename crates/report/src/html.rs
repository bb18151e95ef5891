//! The self-contained `report.html`.
//!
//! One file that opens offline from `file://`: CSS, the vendored three.js bundle
//! (`assets/three-vendor.min.js`, three 0.187 + OrbitControls as one IIFE, rebuilt by
//! `web/build.sh`), the hand-written `assets/viewer.js` and the scene data (a JSON island,
//! `<script type="application/json" id="kappe-data">`) are all inlined. Tables, the state panel
//! and the SVG plots are rendered here, so they read without JavaScript; the viewer adds the
//! 3D scene and the interactivity.
//!
//! Hand-written because it is a fixed page with a few tables: a template engine would add a
//! dependency for what `write!` does.

use std::fmt::Write as _;

use crate::error::ReportError;
use crate::input::ReportInput;
use crate::plots::{PlotSpec, fmt_num, render_svg, standard_plots};

/// The vendored three.js bundle (three 0.187.0 + OrbitControls, MIT; see `assets/three-LICENSE.txt`).
pub const THREE_BUNDLE: &str = include_str!("../assets/three-vendor.min.js");
/// three.js's MIT licence text, shipped in the page next to the bundle.
pub const THREE_LICENSE: &str = include_str!("../assets/three-LICENSE.txt");
/// The hand-written viewer.
pub const VIEWER_JS: &str = include_str!("../assets/viewer.js");
/// The page's style sheet.
pub const REPORT_CSS: &str = include_str!("../assets/report.css");

/// Escapes text for HTML element content and double-quoted attribute values.
#[must_use]
pub fn escape_html(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Makes JavaScript safe to inline in a classic `<script>` element: the HTML parser ends the
/// element at the first `</script` (any case), so every `</` becomes `<\/`, which JavaScript
/// reads as the same two characters inside strings, template literals and regular expressions
/// (the only places `</` can occur in valid code outside comments).
#[must_use]
pub fn escape_inline_script(js: &str) -> String {
    js.replace("</", "<\\/")
}

/// Significant digits kept for floats in the scene island: 0.1 µm on metre-sized coordinates
/// and 1 mPa on kPa stresses, far below what the viewer can show; it makes the page about
/// 2.5 times smaller than the 17-digit round-trip form.
pub const ISLAND_SIGNIFICANT_DIGITS: i32 = 7;

/// `v` rounded to `digits` significant decimal digits. The rounded integer and the power of
/// ten are exact doubles, so the one division (or product) gives the double nearest to the
/// short decimal, which serde_json then prints in that short form.
fn round_significant(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = v.abs().log10().floor() as i32;
    let k = digits - 1 - e;
    if k >= 0 {
        let s = 10f64.powi(k);
        (v * s).round() / s
    } else {
        let s = 10f64.powi(-k);
        (v / s).round() * s
    }
}

fn compact_numbers(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Number(n) if n.is_f64() => {
            if let Some(r) = n.as_f64().and_then(|x| {
                serde_json::Number::from_f64(round_significant(x, ISLAND_SIGNIFICANT_DIGITS))
            }) {
                *n = r;
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(compact_numbers),
        serde_json::Value::Object(o) => o.values_mut().for_each(compact_numbers),
        _ => {}
    }
}

/// Serialises the scene island: the [`ReportInput`] as JSON, floats rounded to
/// [`ISLAND_SIGNIFICANT_DIGITS`]. Every `<` is written as `\u003c` (valid JSON, same string), so
/// neither `</script` nor `<!--` can appear and end or confuse the `<script>` element; `<` can
/// only occur inside JSON strings.
///
/// # Errors
/// [`ReportError::Json`] if serialisation fails.
pub fn scene_json(input: &ReportInput) -> Result<String, ReportError> {
    let mut value = serde_json::to_value(input)?;
    compact_numbers(&mut value);
    Ok(serde_json::to_string(&value)?.replace('<', "\\u003c"))
}

/// Renders the complete report page.
///
/// # Errors
/// The first problem of [`ReportInput::validate`], or a plot that could not be drawn.
pub fn render_html(input: &ReportInput) -> Result<String, ReportError> {
    input.validate()?;
    let json = scene_json(input)?;
    let mut specs = standard_plots(input);
    specs.extend(input.plots.iter().map(|p| PlotSpec {
        plot: p.clone(),
        reference_lines: Vec::new(),
    }));
    let svgs = specs
        .iter()
        .map(|s| render_svg(s).map(|svg| (s.plot.title.clone(), svg)))
        .collect::<Result<Vec<_>, _>>()?;

    let name = escape_html(&input.name);
    let failed = input.constraints.iter().filter(|c| !c.pass).count();
    let total = input.constraints.len();
    let (verdict_class, verdict) = if failed == 0 {
        ("pass", format!("PASS: all {total} constraints met"))
    } else {
        (
            "fail",
            format!("FAIL: {failed} of {total} constraints violated"),
        )
    };
    let last = input.states.len().saturating_sub(1);

    // `write!` into a String cannot fail; the results are ignored on purpose.
    let mut h = String::with_capacity(THREE_BUNDLE.len() + json.len() + 64 * 1024);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"kappe-report {version}\">\n\
         <title>Kappe report: {name}</title>\n<style>\n{css}</style>\n</head>\n<body>\n\
         <header><h1>{name}</h1><span class=\"verdict {verdict_class}\">{verdict}</span></header>\n<main>\n",
        version = env!("CARGO_PKG_VERSION"),
        css = REPORT_CSS,
    );

    // 3D viewer and its controls.
    let _ = write!(
        h,
        "<section id=\"viewer-section\">\n<h2>Cap, print path and robot</h2>\n\
         <div id=\"viewer\"><canvas id=\"kappe-canvas\" aria-label=\"3D view of the cap\"></canvas>\
         <div id=\"viewer-message\"><noscript>The 3D view needs JavaScript.</noscript></div>\
         <div id=\"legend\">normal stress (blue: compression, red: tension)<div id=\"legend-bar\"></div>\
         <div class=\"ends\"><span id=\"legend-min\"></span><span>0</span><span id=\"legend-max\"></span></div></div></div>\n\
         <div class=\"controls\"><label for=\"state-slider\">Print state</label>\
         <input type=\"range\" id=\"state-slider\" min=\"0\" max=\"{last}\" step=\"1\" value=\"{last}\">\
         <output id=\"state-label\" for=\"state-slider\"></output></div>\n\
         <div class=\"controls\" id=\"robot-controls\"><button id=\"robot-play\" type=\"button\">▶ Play robot</button>\
         <input type=\"range\" id=\"robot-time\" min=\"0\" max=\"0\" step=\"1\" value=\"0\" aria-label=\"robot time step\">\
         <output id=\"robot-label\"></output></div>\n\
         <div class=\"controls\">\
         <label><input type=\"checkbox\" id=\"show-beads\" checked> beads</label>\
         <label><input type=\"checkbox\" id=\"show-top\" checked> top layer path + tool axes</label>\
         <label><input type=\"checkbox\" id=\"show-path\"> whole print path</label>\
         <label><input type=\"checkbox\" id=\"show-joints\"> bed joints</label>\
         <label><input type=\"checkbox\" id=\"show-robot\" checked> robot</label></div>\n</section>\n",
    );

    // State panel (filled for the last state; the viewer updates it on slider input).
    let _ = write!(
        h,
        "<aside id=\"state-panel\">\n<h2>Print state</h2>\n<dl class=\"state\">"
    );
    if let Some(st) = input.states.last() {
        let top = input
            .layers
            .get(st.layers_printed.saturating_sub(1))
            .map_or_else(|| "–".to_string(), |l| l.id.to_string());
        let blf = st
            .blf
            .map_or_else(|| "not computed".into(), |b| format!("{b:.2}"));
        let rows = [
            (
                "st-index",
                "state",
                format!("{} ({} of {})", st.index, last + 1, last + 1),
            ),
            (
                "st-progress",
                "progress",
                format!("{:.1} %", st.progress * 100.0),
            ),
            (
                "st-layers",
                "layers printed",
                format!("{} of {}", st.layers_printed, input.layers.len()),
            ),
            ("st-top", "top layer", top),
            ("st-blf", "BLF", blf),
            ("st-smin", "σ_min", format!("{:.2} kPa", st.sigma_min / 1e3)),
            ("st-smax", "σ_max", format!("{:.2} kPa", st.sigma_max / 1e3)),
            (
                "st-overhang",
                "max overhang",
                format!("{:.2} mm", st.max_overhang * 1e3),
            ),
        ];
        for (id, label, value) in rows {
            let _ = write!(
                h,
                "<dt>{label}</dt><dd id=\"{id}\">{}</dd>",
                escape_html(&value)
            );
        }
        let (class, text) = if st.ok {
            ("pass", "pass")
        } else {
            ("fail", "FAIL")
        };
        let _ = write!(
            h,
            "<dt>constraints</dt><dd id=\"st-ok\" class=\"{class}\">{text}</dd>"
        );
    }
    let _ = write!(
        h,
        "</dl>\n<h2>Parameters</h2>\n<table id=\"parameters\"><thead><tr><th>parameter</th><th>value</th><th>unit</th></tr></thead><tbody>"
    );
    for p in &input.parameters {
        let _ = write!(
            h,
            "<tr><td>{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
            escape_html(&p.key),
            escape_html(&p.value),
            escape_html(&p.unit)
        );
    }
    let _ = write!(h, "</tbody></table>\n</aside>\n");

    // Constraint table.
    let _ = write!(
        h,
        "<section id=\"constraints\" class=\"wide\">\n<h2>Constraints</h2>\n<table><thead><tr>\
         <th>constraint</th><th>limit</th><th>worst value</th><th>unit</th><th>state</th><th>element</th><th>result</th>\
         </tr></thead><tbody>"
    );
    for c in &input.constraints {
        let rel = c.bound.symbol();
        let _ = write!(
            h,
            "<tr class=\"{cls}\"><td>{name}</td><td class=\"num\">{rel} {limit}</td><td class=\"num\">{worst}</td>\
             <td>{unit}</td><td class=\"num\">{state}</td><td>{element}</td><td>{result}</td></tr>",
            cls = if c.pass { "pass-row" } else { "fail" },
            name = escape_html(&c.name),
            limit = fmt_num(c.limit),
            worst = fmt_num(c.worst),
            unit = escape_html(&c.unit),
            state = c.state.map_or_else(|| "–".to_string(), |s| s.to_string()),
            element = escape_html(c.element.as_deref().unwrap_or("–")),
            result = if c.pass { "pass" } else { "FAIL" },
        );
    }
    let _ = write!(h, "</tbody></table>\n</section>\n");

    // Plots.
    let _ = write!(
        h,
        "<section id=\"plots\" class=\"wide\">\n<h2>Plots</h2>\n<div class=\"grid\">\n"
    );
    for (title, svg) in &svgs {
        let _ = writeln!(
            h,
            "<figure aria-label=\"{}\">{}</figure>",
            escape_html(title),
            strip_xml_declaration(svg)
        );
    }
    let _ = write!(h, "</div>\n</section>\n</main>\n");
    let _ = writeln!(
        h,
        "<footer>Generated by kappe-report {}. 3D view: three.js r{} (MIT licence, included in this file).</footer>",
        env!("CARGO_PKG_VERSION"),
        crate::THREE_REVISION
    );

    // Data, then the libraries: the viewer runs synchronously at the end of the body.
    let _ = write!(
        h,
        "<script type=\"application/json\" id=\"kappe-data\">{json}</script>\n\
         <script>\n/*\nthree.js licence:\n{licence}*/\n{three}\n</script>\n<script>\n{viewer}\n</script>\n</body>\n</html>\n",
        licence = escape_inline_script(&THREE_LICENSE.replace("*/", "* /")),
        three = escape_inline_script(THREE_BUNDLE),
        viewer = escape_inline_script(VIEWER_JS),
    );
    Ok(h)
}

/// Inline SVG in HTML must not carry an XML declaration.
fn strip_xml_declaration(svg: &str) -> &str {
    let s = svg.trim_start();
    if s.starts_with("<?xml")
        && let Some(end) = s.find("?>")
    {
        return s.get(end + 2..).unwrap_or(s).trim_start();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::round_significant;

    #[test]
    fn rounding_keeps_seven_significant_digits() {
        assert_eq!(round_significant(0.123_456_789, 7), 0.123_456_8);
        assert_eq!(round_significant(-15_650.123_456, 7), -15_650.12);
        assert_eq!(round_significant(123_456_789.0, 7), 123_456_800.0);
        assert_eq!(round_significant(2.5e-9, 7), 2.5e-9);
        assert_eq!(round_significant(0.0, 7), 0.0);
        // The printed form is the short decimal.
        assert_eq!(
            serde_json::to_string(&round_significant(0.1 + 0.2, 7)).unwrap(),
            "0.3"
        );
    }
}
