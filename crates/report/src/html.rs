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
use crate::markup::{escape_html, strip_xml_declaration};
use crate::plots::{PlotSpec, fmt_num, render_plot, standard_plots};

/// The vendored three.js bundle (three 0.187.0 + OrbitControls, MIT; see `assets/three-LICENSE.txt`).
pub const THREE_BUNDLE: &str = include_str!("../assets/three-vendor.min.js");
/// three.js's MIT licence text, shipped in the page next to the bundle.
pub const THREE_LICENSE: &str = include_str!("../assets/three-LICENSE.txt");
/// The hand-written viewer.
pub const VIEWER_JS: &str = include_str!("../assets/viewer.js");
/// The page's style sheet.
pub const REPORT_CSS: &str = include_str!("../assets/report.css");

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

/// Serialises the scene island: the [`ReportInput`] in the compact form of `island.rs` (long
/// arrays as base64 typed arrays), the remaining floats rounded to
/// [`ISLAND_SIGNIFICANT_DIGITS`]. Every `<` is written as `\u003c` (valid JSON, same string), so
/// neither `</script` nor `<!--` can appear and end or confuse the `<script>` element; `<` can
/// only occur inside JSON strings.
///
/// # Errors
/// [`ReportError::Json`] if serialisation fails.
pub fn scene_json(input: &ReportInput) -> Result<String, ReportError> {
    let mut value = crate::island::island(input);
    compact_numbers(&mut value);
    Ok(serde_json::to_string(&value)?.replace('<', "\\u003c"))
}

/// The UR10e meshes and kinematic chain (`assets/ur10e-meshes.json`, BSD-3-Clause, see
/// `assets/ur10e-LICENSE.txt`), inlined when the input has a robot cell.
pub const UR10E_MESHES: &str = include_str!("../assets/ur10e-meshes.json");
/// The licence of [`UR10E_MESHES`].
pub const UR10E_LICENSE: &str = include_str!("../assets/ur10e-LICENSE.txt");

/// A constraint's worst value as the table shows it: a stress whose magnitude is below 1e-9 of
/// the largest stress limit (round-off of the force pass, method.md §9) reads 0; a magnitude row
/// shows the signed value of its worst place when the input gives one.
fn worst_text(input: &ReportInput, c: &crate::input::ConstraintRow) -> String {
    let signed = input
        .worst_places
        .iter()
        .find(|w| w.constraint == c.name)
        .and_then(|w| w.signed_value);
    let v = signed.unwrap_or(c.worst);
    let stress_scale = input
        .constraints
        .iter()
        .filter(|r| r.unit == c.unit)
        .map(|r| {
            r.limit
                .abs()
                .max(r.worst.abs().min(r.limit.abs().max(1.0) * 1e3))
        })
        .fold(0.0, f64::max);
    if c.unit.ends_with("Pa") && v != 0.0 && v.abs() <= 1e-9 * stress_scale.max(1.0) {
        return "0 (round-off)".into();
    }
    fmt_num(v)
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
        ..PlotSpec::default()
    }));
    if let Some(schedule) = &input.schedule {
        specs.extend(crate::schedule::plots(schedule));
    }
    let plots = specs
        .iter()
        .map(|s| render_plot(s).map(|r| (s, r)))
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

    // `write!` into a String cannot fail; the results are ignored on purpose.
    let mut h = String::with_capacity(THREE_BUNDLE.len() + json.len() + 128 * 1024);
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

    // 3D viewer, its overlays and the one timeline.
    let _ = write!(
        h,
        "<section id=\"viewer-section\">\n<h2>Cap, print and robot</h2>\n\
         <div id=\"viewer\"><canvas id=\"kappe-canvas\" aria-label=\"3D view of the cap\"></canvas>\
         <div id=\"viewer-message\"><noscript>The 3D view needs JavaScript.</noscript></div>\
         <div id=\"toolbar\" class=\"overlay\">\
         <button type=\"button\" data-view=\"iso\">Iso</button><button type=\"button\" data-view=\"top\">Top</button>\
         <button type=\"button\" data-view=\"front\">Front</button><button type=\"button\" data-view=\"side\">Side</button>\
         <button type=\"button\" id=\"fit\">Fit</button>\
         <label><input type=\"checkbox\" id=\"follow\"> follow nozzle</label></div>\
         <div id=\"legend\" class=\"overlay\"><label for=\"colour-by\">colour</label> <select id=\"colour-by\"></select>\
         <div id=\"legend-scale\"></div><p id=\"legend-note\"></p></div>\
         <div id=\"scalebar\" class=\"overlay\"><div id=\"scalebar-bar\"></div><span id=\"scalebar-label\"></span></div>\
         <div id=\"mode-badge\" class=\"overlay\" hidden></div></div>\n\
         <div class=\"controls timeline\"><button id=\"play\" type=\"button\">▶ Play</button>\
         <input type=\"range\" id=\"timeline\" min=\"0\" max=\"10000\" step=\"1\" value=\"10000\" aria-label=\"print timeline\">\
         <output id=\"time-label\" for=\"timeline\"></output></div>\n\
         <div class=\"controls\">\
         <label><input type=\"checkbox\" id=\"show-mode\"> buckling mode</label>\
         <label>scale <input type=\"range\" id=\"mode-scale\" min=\"1\" max=\"100\" value=\"50\" aria-label=\"mode shape scale\"></label>\
         <label><input type=\"checkbox\" id=\"show-markers\" checked> worst places</label>\
         <label><input type=\"checkbox\" id=\"show-beads\" checked> beads</label>\
         <label><input type=\"checkbox\" id=\"show-top\" checked> current layer path</label>\
         <label><input type=\"checkbox\" id=\"show-joints\"> bed joints</label>\
         <label><input type=\"checkbox\" id=\"show-robot\" checked> robot</label>\
         <label><input type=\"checkbox\" id=\"show-cell\" checked> cell</label></div>\n</section>\n",
    );

    // State panel (the viewer fills it for the current moment).
    let _ = write!(
        h,
        "<aside id=\"state-panel\">\n<h2>At this moment</h2>\n<dl class=\"state\">"
    );
    let rows = [
        ("st-time", "time"),
        ("st-layers", "layers shown"),
        ("st-station", "robot station"),
        ("st-index", "print state"),
        ("st-progress", "progress"),
        ("st-top", "top complete layer"),
        ("st-blf", "BLF (this state)"),
        ("st-smin", "σ_min (this state)"),
        ("st-smax", "σ_max (this state)"),
        ("st-overhang", "max |overhang| so far"),
    ];
    for (id, label) in rows {
        let _ = write!(h, "<dt>{label}</dt><dd id=\"{id}\">–</dd>");
    }
    let _ = write!(
        h,
        "<dt>constraints</dt><dd id=\"st-ok\">–</dd></dl>\n<h2>Parameters</h2>\n\
         <table id=\"parameters\"><thead><tr><th>parameter</th><th>value</th><th>unit</th></tr></thead><tbody>"
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

    // Constraint table; a row with a worst place is a link to it in 3D.
    let _ = write!(
        h,
        "<section id=\"constraints\" class=\"wide\">\n<h2>Constraints</h2>\n\
         <p class=\"hint\">Click a row to go to its worst place in the 3D view.</p><table><thead><tr>\
         <th>constraint</th><th>limit</th><th>worst value</th><th>unit</th><th>state</th><th>where</th><th>result</th>\
         </tr></thead><tbody>"
    );
    for (ci, c) in input.constraints.iter().enumerate() {
        let rel = c.bound.symbol();
        let place = input.worst_places.iter().any(|w| w.constraint == c.name);
        let _ = write!(
            h,
            "<tr class=\"{cls}{link}\" data-row=\"{ci}\" data-constraint=\"{name}\"{tab}><td>{name}</td><td class=\"num\">{rel} {limit}</td><td class=\"num\">{worst}</td>\
             <td>{unit}</td><td class=\"num\">{state}</td><td>{element}</td><td class=\"result {rcls}\">{result}</td></tr>",
            cls = if c.pass { "pass-row" } else { "fail" },
            link = if place { " link" } else { "" },
            tab = if place { " tabindex=\"0\"" } else { "" },
            name = escape_html(&c.name),
            limit = fmt_num(c.limit),
            worst = escape_html(&worst_text(input, c)),
            unit = escape_html(&c.unit),
            state = c.state.map_or_else(|| "–".to_string(), |s| s.to_string()),
            element = escape_html(c.element.as_deref().unwrap_or("–")),
            rcls = if c.pass { "pass" } else { "fail" },
            result = if c.pass { "pass" } else { "FAIL" },
        );
    }
    let _ = write!(h, "</tbody></table>\n</section>\n");
    if let Some(schedule) = &input.schedule {
        h.push_str(&crate::schedule::section_html(schedule));
    }
    if let Some(r) = &input.robot_summary {
        h.push_str(&crate::robot_summary::section_html(r));
    }
    h.push_str(&crate::placement::section_html(input)?);

    // Plots, each with the data needed to draw the cursor of the current moment.
    let _ = write!(
        h,
        "<section id=\"plots\" class=\"wide\">\n<h2>Plots</h2>\n<div class=\"grid\">\n"
    );
    for (spec, r) in &plots {
        let f = &r.frame;
        let _ = writeln!(
            h,
            "<figure aria-label=\"{}\" data-cursor=\"{}\" data-x0=\"{}\" data-x1=\"{}\" data-px0=\"{}\" data-px1=\"{}\" data-py0=\"{}\" data-py1=\"{}\">{}</figure>",
            escape_html(&spec.plot.title),
            spec.cursor.as_str(),
            f.x0,
            f.x1,
            f.px0,
            f.px1,
            f.py0,
            f.py1,
            strip_xml_declaration(&r.svg)
        );
    }
    let _ = write!(h, "</div>\n</section>\n</main>\n");
    let robot_meshes = input.cell.is_some() && input.robot.is_some();
    let _ = writeln!(
        h,
        "<footer>Generated by kappe-report {}. 3D view: three.js r{} (MIT licence, included in this file){}.</footer>",
        env!("CARGO_PKG_VERSION"),
        crate::THREE_REVISION,
        if robot_meshes {
            "; UR10e meshes from ROS ur_description (BSD-3-Clause, licence included in this file)"
        } else {
            ""
        }
    );

    // Data, then the libraries: the viewer runs synchronously at the end of the body.
    let _ = writeln!(
        h,
        "<script type=\"application/json\" id=\"kappe-data\">{json}</script>"
    );
    if robot_meshes {
        let _ = write!(
            h,
            "<!-- UR10e meshes: {} -->\n<script type=\"application/json\" id=\"kappe-robot\">{}</script>\n",
            UR10E_LICENSE.replace("--", "- -").replace('>', ")"),
            UR10E_MESHES.trim().replace('<', "\\u003c"),
        );
    }
    let _ = write!(
        h,
        "<script>\n/*\nthree.js licence:\n{licence}*/\n{three}\n</script>\n<script>\n{viewer}\n</script>\n</body>\n</html>\n",
        licence = escape_inline_script(&THREE_LICENSE.replace("*/", "* /")),
        three = escape_inline_script(THREE_BUNDLE),
        viewer = escape_inline_script(VIEWER_JS),
    );
    Ok(h)
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
