//! The base placement drawing (issue 28): a plan view of the robot cell for the operator — the
//! beams, the cap's footprint, and at each station the mobile base's outline, the robot base
//! origin and its heading, numbered in print order with x, y and yaw in the world frame of
//! `docs/operator.md` — and the same numbers as a table beneath it.
//!
//! The geometry ([`placement_shapes`]) is a pure function of the report input so it can be
//! checked against hand-computed corners; the drawing is `plotters` on an SVG string like the
//! other plots, with equal scales on both axes (a plan must not distort angles).

use std::fmt::Write as _;

use plotters::prelude::*;

use crate::error::ReportError;
use crate::input::{BoxBody, ReportInput};
use crate::markup::escape_html;

/// One station in plan view, world frame, m.
#[derive(Debug, Clone, PartialEq)]
pub struct StationShape {
    /// Station number, 1-based in print order.
    pub number: usize,
    /// Robot base origin (x, y), m.
    pub origin: [f64; 2],
    /// Yaw of the base's x axis from world x, degrees, counter-clockwise seen from above.
    pub yaw_deg: f64,
    /// The mobile base's boxes as closed outlines (4 corners each, counter-clockwise).
    pub outlines: Vec<[[f64; 2]; 4]>,
    /// First and last layer printed from here.
    pub layers: Option<(i32, i32)>,
}

/// What the plan view draws, world frame, m.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlacementShapes {
    /// Static obstacles (the beams) as outlines, with their names.
    pub obstacles: Vec<(String, [[f64; 2]; 4])>,
    /// The cap's layers projected on the floor (one polyline per layer).
    pub footprint: Vec<Vec<[f64; 2]>>,
    /// The stations in print order.
    pub stations: Vec<StationShape>,
    /// A base that moves while printing: the path of the robot base origin (empty otherwise).
    pub base_path: Vec<[f64; 2]>,
}

/// The outline of `b` seen from above: its centre and half extents rotated by its yaw, then
/// mapped by the rigid transform `(c, s, t)` (rotation cos/sin about z and translation).
fn outline(b: &BoxBody, c: f64, s: f64, t: [f64; 2]) -> [[f64; 2]; 4] {
    let (bc, bs) = (b.yaw.cos(), b.yaw.sin());
    let [hx, hy, _] = b.half_extents;
    let mut out = [[0.0; 2]; 4];
    for (k, (sx, sy)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .into_iter()
        .enumerate()
    {
        let (lx, ly) = (sx * hx, sy * hy);
        let px = b.center[0] + bc * lx - bs * ly;
        let py = b.center[1] + bs * lx + bc * ly;
        out[k] = [t[0] + c * px - s * py, t[1] + s * px + c * py];
    }
    out
}

/// The plan view's geometry; `None` without a robot cell.
#[must_use]
pub fn placement_shapes(input: &ReportInput) -> Option<PlacementShapes> {
    let cell = input.cell.as_ref()?;
    let obstacles = cell
        .obstacles
        .iter()
        .map(|o| (o.name.clone(), outline(o, 1.0, 0.0, [0.0, 0.0])))
        .collect();
    let footprint = input
        .layers
        .iter()
        .map(|l| l.nodes.iter().map(|p| [p[0], p[1]]).collect())
        .collect();
    let stations = cell
        .stations
        .iter()
        .enumerate()
        .map(|(i, st)| {
            let m = &st.world_from_base;
            // The base stands on the floor: its rotation is about z, read from the first
            // column of the rotation block.
            let (c, s) = (m[0][0], m[1][0]);
            let norm = c.hypot(s).max(f64::MIN_POSITIVE);
            let (c, s) = (c / norm, s / norm);
            let origin = [m[0][3], m[1][3]];
            StationShape {
                number: i + 1,
                origin,
                yaw_deg: s.atan2(c).to_degrees(),
                outlines: cell
                    .mobile_base
                    .iter()
                    .map(|b| outline(b, c, s, origin))
                    .collect(),
                layers: st
                    .layers
                    .iter()
                    .min()
                    .zip(st.layers.iter().max())
                    .map(|(a, b)| (*a, *b)),
            }
        })
        .collect();
    let base_path = input
        .robot
        .as_ref()
        .map(|r| r.base.iter().map(|b| [b[0], b[1]]).collect())
        .unwrap_or_default();
    Some(PlacementShapes {
        obstacles,
        footprint,
        stations,
        base_path,
    })
}

/// Station colours, in print order (cycled).
const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// Length of the heading arrow, m.
const ARROW: f64 = 0.3;

/// The plan view as SVG, 560 px wide, the height following the drawing's aspect (equal scales).
///
/// # Errors
/// [`ReportError::Plot`] when plotters fails.
pub fn placement_svg(shapes: &PlacementShapes) -> Result<String, ReportError> {
    let err = |e: &dyn std::fmt::Display| ReportError::Plot {
        plot: "base placement".into(),
        message: e.to_string(),
    };
    let pts = shapes
        .obstacles
        .iter()
        .flat_map(|(_, o)| o.iter().copied())
        .chain(shapes.footprint.iter().flatten().copied())
        .chain(
            shapes
                .stations
                .iter()
                .flat_map(|s| s.outlines.iter().flatten().copied().chain([s.origin])),
        )
        .chain(shapes.base_path.iter().copied());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for [x, y] in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (-1.0, 1.0, -1.0, 1.0);
    }
    let pad = 0.06 * (x1 - x0).max(y1 - y0).max(0.1);
    (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
    // Equal scales: the plotting area is (W − 80) × (H − 60) px; choose H from the aspect,
    // within 260–760 px, and widen the shorter range when clamped.
    let width = 560u32;
    let (area_w, extra_h) = (f64::from(width - 80), 60.0);
    let scale = area_w / (x1 - x0);
    let want_h = (y1 - y0) * scale + extra_h;
    let height = want_h.clamp(260.0, 760.0);
    let area_h = height - extra_h;
    let span_y = area_h / scale;
    if span_y > y1 - y0 {
        let grow = 0.5 * (span_y - (y1 - y0));
        (y0, y1) = (y0 - grow, y1 + grow);
    } else {
        let span_x = (x1 - x0) * (y1 - y0) / span_y;
        let grow = 0.5 * (span_x - (x1 - x0));
        (x0, x1) = (x0 - grow, x1 + grow);
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height as u32)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("x [m] (across the span)")
            .y_desc("y [m] (along the beams)")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(|e| err(&e))?;
        let grey = RGBColor(150, 150, 150);
        for (_, o) in &shapes.obstacles {
            let poly: Vec<(f64, f64)> = o.iter().map(|p| (p[0], p[1])).collect();
            chart
                .draw_series(std::iter::once(Polygon::new(poly, grey.mix(0.35).filled())))
                .map_err(|e| err(&e))?;
        }
        let brown = RGBColor(150, 100, 60);
        chart
            .draw_series(shapes.footprint.iter().map(|l| {
                PathElement::new(
                    l.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>(),
                    brown.mix(0.5).stroke_width(1),
                )
            }))
            .map_err(|e| err(&e))?;
        if let (Some(first), Some(last)) = (shapes.base_path.first(), shapes.base_path.last()) {
            let black = RGBColor(40, 40, 40);
            chart
                .draw_series([PathElement::new(
                    shapes
                        .base_path
                        .iter()
                        .map(|p| (p[0], p[1]))
                        .collect::<Vec<_>>(),
                    black.stroke_width(2),
                )])
                .map_err(|e| err(&e))?;
            chart
                .draw_series([Circle::new((last[0], last[1]), 5, black.filled())])
                .map_err(|e| err(&e))?;
            chart
                .draw_series([Text::new(
                    format!(
                        "base at the end: x {:.3}, y {:.3} ({:.2} m travelled)",
                        last[0],
                        last[1],
                        (last[0] - first[0]).hypot(last[1] - first[1])
                    ),
                    (last[0], last[1]),
                    ("sans-serif", 14).into_font().color(&black),
                )])
                .map_err(|e| err(&e))?;
        }
        for st in &shapes.stations {
            let colour = COLOURS[(st.number - 1) % COLOURS.len()];
            for o in &st.outlines {
                let mut poly: Vec<(f64, f64)> = o.iter().map(|p| (p[0], p[1])).collect();
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        poly.clone(),
                        colour.mix(0.15).filled(),
                    )))
                    .map_err(|e| err(&e))?;
                poly.push(poly[0]);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        poly,
                        colour.stroke_width(2),
                    )))
                    .map_err(|e| err(&e))?;
            }
            let (ox, oy) = (st.origin[0], st.origin[1]);
            let a = st.yaw_deg.to_radians();
            let tip = (ox + ARROW * a.cos(), oy + ARROW * a.sin());
            chart
                .draw_series([PathElement::new(
                    vec![(ox, oy), tip],
                    colour.stroke_width(3),
                )])
                .map_err(|e| err(&e))?;
            chart
                .draw_series([Circle::new((ox, oy), 5, colour.filled())])
                .map_err(|e| err(&e))?;
            // Stations at the same pose (the base returns to an earlier place) share one label.
            let same: Vec<String> = shapes
                .stations
                .iter()
                .filter(|o| {
                    (o.origin[0] - ox).hypot(o.origin[1] - oy) < 1e-3
                        && (o.yaw_deg - st.yaw_deg).abs() < 0.1
                })
                .map(|o| o.number.to_string())
                .collect();
            if same.first() != Some(&st.number.to_string()) {
                continue;
            }
            chart
                .draw_series([Text::new(
                    format!(
                        "{}: x {:.3}, y {:.3}, yaw {:.1}°",
                        same.join(", "),
                        ox,
                        oy,
                        st.yaw_deg
                    ),
                    (ox, oy),
                    ("sans-serif", 14).into_font().color(&colour),
                )])
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    Ok(svg)
}

/// The report section: the drawing and the table of base poses. Empty without a robot cell.
///
/// # Errors
/// [`ReportError::Plot`] when the drawing fails.
pub fn section_html(input: &ReportInput) -> Result<String, ReportError> {
    let Some(shapes) = placement_shapes(input) else {
        return Ok(String::new());
    };
    if shapes.stations.is_empty() {
        return Ok(String::new());
    }
    let svg = placement_svg(&shapes)?;
    let mut h = String::new();
    let _ = write!(
        h,
        "<section id=\"placement\" class=\"wide\">\n<h2>Base placement</h2>\n\
         <p>Plan view of the cell, world frame (docs/operator.md: origin on the beams' top face \
         midway between their inner faces where layer 0 meets them; x across the span, y along \
         the beams). Each station: the mobile base's outline, the robot base origin (dot) and the \
         direction of its x axis (line, {ARROW} m); a base that moves while printing starts at \
         station 1 and follows the black line. The station sheet (<code>stations.md</code>) \
         gives the tolerance each must be placed to.</p>\n<figure aria-label=\"base placement\">{}</figure>\n\
         <table><thead><tr><th>station</th><th>base x [m]</th><th>base y [m]</th>\
         <th>base yaw [°]</th><th>layers</th></tr></thead><tbody>\n",
        crate::markup::strip_xml_declaration(&svg)
    );
    for st in &shapes.stations {
        let layers = st
            .layers
            .map_or_else(|| "–".to_string(), |(a, b)| format!("{a} to {b}"));
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{}</td></tr>",
            st.number,
            st.origin[0],
            st.origin[1],
            st.yaw_deg,
            escape_html(&layers)
        );
    }
    h.push_str("</tbody></table>\n</section>\n");
    Ok(h)
}
