//! The report's line plots, drawn with `plotters` into SVG strings that are inlined in the page.
//!
//! SVG needs no font at generation time (the browser draws the `<text>` elements), so plotters
//! is built without its font features and nothing here depends on the machine's fonts.
//!
//! [`standard_plots`] derives the four plots of issue 8 from the report input:
//! BLF vs print progress, extreme normal stress vs progress, overhang per layer and joint angles
//! over time. Limits from the constraint table are drawn as dashed reference lines.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::{Deserialize, Serialize};

use crate::error::ReportError;
use crate::input::{Plot, ReportInput, Series};

/// Width and height of every plot, px (the page scales them down to fit).
pub const PLOT_SIZE: (u32, u32) = (560, 340);

/// A horizontal reference line, e.g. a constraint limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceLine {
    /// Legend name, e.g. `BLF_min`.
    pub name: String,
    /// Height in plot units.
    pub y: f64,
}

/// A vertical marker, e.g. a robot station change.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VerticalMarker {
    /// Legend name, e.g. `station 2`.
    pub name: String,
    /// Position in plot x units.
    pub x: f64,
}

/// What the x axis of a plot follows, so the page can draw the cursor of the current moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CursorAxis {
    /// No cursor.
    #[default]
    None,
    /// Print progress in percent.
    Progress,
    /// Robot time in seconds.
    Time,
    /// Layer id.
    Layer,
}

impl CursorAxis {
    /// The name the page uses (`data-cursor`).
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            CursorAxis::None => "none",
            CursorAxis::Progress => "progress",
            CursorAxis::Time => "time",
            CursorAxis::Layer => "layer",
        }
    }
}

/// A plot with its reference lines, ready to draw.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlotSpec {
    /// The data.
    pub plot: Plot,
    /// Dashed horizontal lines.
    pub reference_lines: Vec<ReferenceLine>,
    /// Dotted vertical lines (station changes).
    pub markers: Vec<VerticalMarker>,
    /// Logarithmic y axis (the BLF, whose governing values are small beside its early values).
    pub log_y: bool,
    /// What the cursor follows.
    pub cursor: CursorAxis,
}

/// Where the data lie in the SVG: data x range and its pixel range, and the pixel y range of
/// the plotting area (for the page's cursor).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlotFrame {
    /// Data x at the left edge of the plotting area.
    pub x0: f64,
    /// Data x at the right edge.
    pub x1: f64,
    /// Pixel x of the left edge.
    pub px0: i32,
    /// Pixel x of the right edge.
    pub px1: i32,
    /// Pixel y of the top edge.
    pub py0: i32,
    /// Pixel y of the bottom edge.
    pub py1: i32,
}

/// A drawn plot.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RenderedPlot {
    /// The SVG document.
    pub svg: String,
    /// Where the data lie in it.
    pub frame: PlotFrame,
}

/// Limit of the first constraint whose name contains `key` (case-insensitive), scaled.
fn constraint_limit(input: &ReportInput, key: &str) -> Option<(String, f64)> {
    input
        .constraints
        .iter()
        .find(|c| c.name.to_lowercase().contains(key))
        .map(|c| (c.name.clone(), c.limit))
}

/// The standard plots of the report, in display order; plots without data are left out
/// (no BLF computed, no overhangs given, no robot).
///
/// Constraint limits are taken from rows whose name contains `blf`, `sigma_min`, `sigma_max`
/// or `overhang`; their `limit` is assumed to be in the row's `unit` and is converted when the
/// unit is `Pa`/`kPa` or `m`/`mm`.
#[must_use]
pub fn standard_plots(input: &ReportInput) -> Vec<PlotSpec> {
    let mut out = Vec::new();
    let pct = |p: f64| 100.0 * p;

    let blf: Vec<[f64; 2]> = input
        .states
        .iter()
        .filter_map(|s| s.blf.map(|b| [pct(s.progress), b]))
        .collect();
    if !blf.is_empty() {
        let reference_lines = constraint_limit(input, "blf")
            .map(|(name, y)| vec![ReferenceLine { name, y }])
            .unwrap_or_default();
        out.push(PlotSpec {
            plot: Plot {
                title: "Buckling load factor vs print progress".into(),
                x_label: "print progress [%]".into(),
                y_label: "BLF [-]".into(),
                series: vec![Series {
                    name: "BLF".into(),
                    points: blf,
                }],
            },
            reference_lines,
            markers: station_markers_progress(input),
            log_y: true,
            cursor: CursorAxis::Progress,
        });
    }

    let kpa = |pa: f64| pa / 1e3;
    let unit_to_kpa = |name: &str| {
        input
            .constraints
            .iter()
            .find(|c| c.name.to_lowercase().contains(name))
            .map(|c| {
                let y = match c.unit.as_str() {
                    "Pa" => c.limit / 1e3,
                    "MPa" => c.limit * 1e3,
                    _ => c.limit,
                };
                ReferenceLine {
                    name: c.name.clone(),
                    y,
                }
            })
    };
    out.push(PlotSpec {
        plot: Plot {
            title: "Extreme normal stress vs print progress".into(),
            x_label: "print progress [%]".into(),
            y_label: "normal stress [kPa] (compression < 0)".into(),
            series: vec![
                Series {
                    name: "σ_min (compression)".into(),
                    points: input
                        .states
                        .iter()
                        .map(|s| [pct(s.progress), kpa(s.sigma_min)])
                        .collect(),
                },
                Series {
                    name: "σ_max".into(),
                    points: input
                        .states
                        .iter()
                        .map(|s| [pct(s.progress), kpa(s.sigma_max)])
                        .collect(),
                },
            ],
        },
        reference_lines: ["sigma_min", "sigma_max"]
            .iter()
            .filter_map(|k| unit_to_kpa(k))
            .collect(),
        markers: station_markers_progress(input),
        log_y: false,
        cursor: CursorAxis::Progress,
    });

    let overhang: Vec<[f64; 2]> = input
        .layers
        .iter()
        .filter_map(|l| l.overhang.map(|o| [f64::from(l.id), o * 1e3]))
        .collect();
    if !overhang.is_empty() {
        let reference_lines = input
            .constraints
            .iter()
            .find(|c| c.name.to_lowercase().contains("overhang"))
            .map(|c| {
                let y = if c.unit == "m" {
                    c.limit * 1e3
                } else {
                    c.limit
                };
                vec![
                    ReferenceLine {
                        name: format!("{} (+)", c.name),
                        y,
                    },
                    ReferenceLine {
                        name: format!("{} (−)", c.name),
                        y: -y,
                    },
                ]
            })
            .unwrap_or_default();
        out.push(PlotSpec {
            plot: Plot {
                title: "Overhang per layer".into(),
                x_label: "layer id (negative: start layers)".into(),
                y_label: "overhang [mm]".into(),
                series: vec![Series {
                    name: "overhang".into(),
                    points: overhang,
                }],
            },
            reference_lines,
            cursor: CursorAxis::Layer,
            ..PlotSpec::default()
        });
    }

    if let Some(robot) = &input.robot
        && !robot.times.is_empty()
    {
        let series = (0..6)
            .map(|j| Series {
                name: format!("q{}", j + 1),
                points: robot
                    .times
                    .iter()
                    .zip(&robot.joints)
                    .map(|(t, q)| [*t, q.get(j).copied().unwrap_or(0.0).to_degrees()])
                    .collect(),
            })
            .collect();
        out.push(PlotSpec {
            plot: Plot {
                title: "Joint angles over time".into(),
                x_label: "time [s]".into(),
                y_label: "joint angle [deg]".into(),
                series,
            },
            markers: station_markers_time(input),
            cursor: CursorAxis::Time,
            ..PlotSpec::default()
        });
    }
    // Every extra colour quantity (layer age, stiffness, …): its range over the printed
    // elements of each state.
    for q in &input.quantities {
        if q.states.len() != input.states.len() || input.states.len() < 2 {
            continue;
        }
        let (mut lo, mut hi) = (Vec::new(), Vec::new());
        for (s, values) in input.states.iter().zip(&q.states) {
            let (a, b) = values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(*v), b.max(*v))
                });
            if a.is_finite() {
                lo.push([pct(s.progress), a * q.to_unit]);
                hi.push([pct(s.progress), b * q.to_unit]);
            }
        }
        out.push(PlotSpec {
            plot: Plot {
                title: format!("{} vs print progress", q.label),
                x_label: "print progress [%]".into(),
                y_label: format!("{} [{}]", q.label, q.unit),
                series: vec![
                    Series {
                        name: "min over printed".into(),
                        points: lo,
                    },
                    Series {
                        name: "max over printed".into(),
                        points: hi,
                    },
                ],
            },
            markers: station_markers_progress(input),
            cursor: CursorAxis::Progress,
            ..PlotSpec::default()
        });
    }
    out
}

/// Print progress (%) at which each robot station after the first starts: the progress of the
/// first state that shows the station's first layer.
fn station_markers_progress(input: &ReportInput) -> Vec<VerticalMarker> {
    let Some(cell) = &input.cell else {
        return Vec::new();
    };
    cell.stations
        .iter()
        .enumerate()
        .skip(1)
        .filter_map(|(k, st)| {
            let first = st.layers.first()?;
            let q = input.layers.iter().position(|l| l.id == *first)?;
            let s = input.states.iter().find(|s| s.layers_printed > q)?;
            Some(VerticalMarker {
                name: format!("station {}", k + 1),
                x: 100.0 * s.progress,
            })
        })
        .collect()
}

/// Robot time at which each station after the first starts.
fn station_markers_time(input: &ReportInput) -> Vec<VerticalMarker> {
    let Some(robot) = &input.robot else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (i, w) in robot.station.windows(2).enumerate() {
        if let ([a, b], Some(t)) = (w, robot.times.get(i + 1))
            && a != b
        {
            out.push(VerticalMarker {
                name: format!("station {}", b + 1),
                x: *t,
            });
        }
    }
    out
}

/// Range `[lo, hi]` of the values with 5 % padding; widened when all values are equal so that
/// plotters gets a non-empty axis.
fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo <= f64::EPSILON * (lo.abs() + hi.abs()) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        lo -= d;
        hi += d;
    } else {
        let d = 0.05 * (hi - lo);
        lo -= d;
        hi += d;
    }
    (lo, hi)
}

/// A colour per series from plotters' 99-colour palette (distinct for the first few).
fn series_colour(i: usize) -> RGBColor {
    let c = Palette99::pick(i).to_rgba();
    RGBColor(c.0, c.1, c.2)
}

/// Tick values in plot coordinates: multiples of 1, 2 or 5 × 10^k, about five over the range;
/// on a log axis (coordinates are log10 of the values) the values 1, 2, 5 × 10^k inside it.
fn ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    if log {
        let mut out = Vec::new();
        let (k0, k1) = (lo.floor() as i32, hi.ceil() as i32);
        let decades = k1 - k0;
        for k in k0..=k1 {
            let mantissas: &[f64] = if decades > 3 {
                &[1.0]
            } else {
                &[1.0, 2.0, 5.0]
            };
            for m in mantissas {
                let v = (m * 10f64.powi(k)).log10();
                if v >= lo - 1e-12 && v <= hi + 1e-12 {
                    out.push(v);
                }
            }
        }
        return out;
    }
    let raw = (hi - lo) / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// Draws `spec` as an SVG document string of size [`PLOT_SIZE`].
///
/// # Errors
/// As [`render_plot`].
pub fn render_svg(spec: &PlotSpec) -> Result<String, ReportError> {
    render_plot(spec).map(|r| r.svg)
}

/// Draws `spec` as an SVG of size [`PLOT_SIZE`]: 14 px tick labels, the legend in a strip below
/// the plotting area (never on the data), limits dashed red under the series, station changes
/// dotted grey; on a log axis values ≤ 0 are left out.
///
/// # Errors
/// [`ReportError::Plot`] when plotters fails (it only fails on backend errors, which for the
/// in-memory SVG backend do not occur in practice).
pub fn render_plot(spec: &PlotSpec) -> Result<RenderedPlot, ReportError> {
    let plot = &spec.plot;
    let err = |e: &dyn std::fmt::Display| ReportError::Plot {
        plot: plot.title.clone(),
        message: e.to_string(),
    };
    let log = spec.log_y;
    let fy = |y: f64| if log { y.log10() } else { y };
    let keep = |y: f64| !log || y > 0.0;
    let all = || plot.series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = padded_range(all().map(|p| p[0]).chain(spec.markers.iter().map(|m| m.x)));
    let (y0, y1) = padded_range(
        all()
            .map(|p| p[1])
            .chain(spec.reference_lines.iter().map(|r| r.y))
            .filter(|y| keep(*y))
            .map(fy),
    );
    let key_points = ticks(y0, y1, log);

    // Legend entries: (kind, colour, text); kind 0 solid, 1 dashed, 2 dotted.
    let mut entries: Vec<(u8, RGBColor, String)> = plot
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| (0, series_colour(i), s.name.clone()))
        .collect();
    entries.extend(
        spec.reference_lines
            .iter()
            .map(|r| (1, RED, format!("limit {} = {}", r.name, fmt_num(r.y)))),
    );
    entries.extend(spec.markers.iter().map(|m| {
        (
            2,
            RGBColor(90, 90, 90),
            format!("{} at {}", m.name, fmt_num(m.x)),
        )
    }));
    // Rows of entries, ~7.2 px per character at 13 px.
    let width = i32::try_from(PLOT_SIZE.0).unwrap_or(560);
    let mut rows: Vec<Vec<(i32, usize)>> = vec![Vec::new()];
    let mut x = 12;
    for (k, e) in entries.iter().enumerate() {
        let w = 30 + (e.2.chars().count() as f64 * 7.2) as i32 + 16;
        if x + w > width - 8 && rows.last().is_some_and(|r| !r.is_empty()) {
            rows.push(Vec::new());
            x = 12;
        }
        if let Some(r) = rows.last_mut() {
            r.push((x, k));
        }
        x += w;
    }
    let legend_h = 8 + 20 * rows.len() as u32;

    let mut svg = String::new();
    let mut frame = PlotFrame {
        x0,
        x1,
        ..PlotFrame::default()
    };
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let (upper, lower) = root.split_vertically(PLOT_SIZE.1.saturating_sub(legend_h));
        let mut chart = ChartBuilder::on(&upper)
            .caption(&plot.title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(46)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        // y ticks are ours (1-2-5 steps, also on the log axis): plotters' labels are off.
        chart
            .configure_mesh()
            .x_desc(plot.x_label.as_str())
            .y_desc(plot.y_label.as_str())
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .x_label_formatter(&|v| fmt_num(*v))
            .y_labels(0)
            .disable_y_mesh()
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(BLACK.mix(0.08))
            .draw()
            .map_err(|e| err(&e))?;
        let grid = ShapeStyle::from(&BLACK.mix(0.08)).stroke_width(1);
        chart
            .draw_series(
                key_points
                    .iter()
                    .map(|&v| PathElement::new(vec![(x0, v), (x1, v)], grid)),
            )
            .map_err(|e| err(&e))?;
        let tick_font = ("sans-serif", 14)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Right, VPos::Center));
        for &v in &key_points {
            let (px, py) = chart.backend_coord(&(x0, v));
            let label = if log {
                fmt_num(10f64.powf(v))
            } else {
                fmt_num(v)
            };
            upper
                .draw(&PathElement::new(vec![(px - 5, py), (px, py)], BLACK))
                .map_err(|e| err(&e))?;
            upper
                .draw(&Text::new(label, (px - 8, py), tick_font.clone()))
                .map_err(|e| err(&e))?;
        }

        // Limits and station changes first, so the series lie on top of them.
        let red = ShapeStyle::from(&RED).stroke_width(1);
        for r in spec.reference_lines.iter().filter(|r| keep(r.y)) {
            let y = fy(r.y);
            let n = 60;
            let pieces = (0..n).step_by(2).map(|k| {
                let a = x0 + (x1 - x0) * f64::from(k) / f64::from(n);
                let b = x0 + (x1 - x0) * f64::from(k + 1) / f64::from(n);
                PathElement::new(vec![(a, y), (b, y)], red)
            });
            chart.draw_series(pieces).map_err(|e| err(&e))?;
        }
        let grey = ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(1);
        for m in &spec.markers {
            let n = 40;
            let pieces = (0..n).step_by(2).map(|k| {
                let a = y0 + (y1 - y0) * f64::from(k) / f64::from(n);
                let b = y0 + (y1 - y0) * (f64::from(k) + 0.6) / f64::from(n);
                PathElement::new(vec![(m.x, a), (m.x, b)], grey)
            });
            chart.draw_series(pieces).map_err(|e| err(&e))?;
        }
        for (i, s) in plot.series.iter().enumerate() {
            let colour = series_colour(i);
            let style = ShapeStyle::from(&colour).stroke_width(2);
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|p| keep(p[1]))
                .map(|p| (p[0], fy(p[1])))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), style))
                .map_err(|e| err(&e))?;
            // Markers only for short series, where they show the sampling (the states).
            if pts.len() <= 60 {
                chart
                    .draw_series(pts.iter().map(|p| Circle::new(*p, 2, colour.filled())))
                    .map_err(|e| err(&e))?;
            }
        }
        let (xr, yr) = chart.plotting_area().get_pixel_range();
        frame.px0 = xr.start;
        frame.px1 = xr.end;
        frame.py0 = yr.start;
        frame.py1 = yr.end;

        // The legend strip.
        for (row, items) in rows.iter().enumerate() {
            let y = 12 + 20 * row as i32;
            for &(x, k) in items {
                let Some((kind, colour, text)) = entries.get(k) else {
                    continue;
                };
                let style = ShapeStyle::from(colour).stroke_width(if *kind == 0 { 2 } else { 1 });
                let segs: Vec<(i32, i32)> = match kind {
                    0 => vec![(0, 24)],
                    1 => vec![(0, 6), (9, 15), (18, 24)],
                    _ => vec![(0, 3), (6, 9), (12, 15), (18, 21)],
                };
                for (a, b) in segs {
                    lower
                        .draw(&PathElement::new(vec![(x + a, y), (x + b, y)], style))
                        .map_err(|e| err(&e))?;
                }
                lower
                    .draw(&Text::new(
                        text.clone(),
                        (x + 30, y - 7),
                        ("sans-serif", 13).into_font().color(&BLACK),
                    ))
                    .map_err(|e| err(&e))?;
            }
        }
        root.present().map_err(|e| err(&e))?;
    }
    Ok(RenderedPlot { svg, frame })
}

/// Short human number: 4 significant digits, no exponent for everyday magnitudes.
#[must_use]
pub fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        // Digits after the point so that 4 significant digits remain.
        let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fmt_num_keeps_four_significant_digits() {
        assert_eq!(fmt_num(15_650.3), "15650");
        assert_eq!(fmt_num(-10.034), "-10.03");
        assert_eq!(fmt_num(0.0037), "0.0037");
        assert_eq!(fmt_num(1.0), "1");
        assert_eq!(fmt_num(2.5e-7), "2.500e-7");
    }

    #[test]
    fn padded_range_never_empty() {
        let (lo, hi) = padded_range([3.0, 3.0].into_iter());
        assert!(lo < 3.0 && hi > 3.0);
        let (lo, hi) = padded_range(std::iter::empty());
        assert!(lo < hi);
        // 5 % padding each side of [0, 10].
        let (lo, hi) = padded_range([0.0, 10.0].into_iter());
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
    }
}
