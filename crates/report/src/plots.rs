//! The report's line plots, drawn with `plotters` into SVG strings that are inlined in the page.
//!
//! SVG needs no font at generation time (the browser draws the `<text>` elements), so plotters
//! is built without its font features and nothing here depends on the machine's fonts.
//!
//! [`standard_plots`] derives the four plots of issue 8 from the report input:
//! BLF vs print progress, extreme normal stress vs progress, overhang per layer and joint angles
//! over time. Limits from the constraint table are drawn as dashed reference lines.

use plotters::prelude::*;
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

/// A plot with its reference lines, ready to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotSpec {
    /// The data.
    pub plot: Plot,
    /// Dashed horizontal lines.
    pub reference_lines: Vec<ReferenceLine>,
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
            reference_lines: Vec::new(),
        });
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

/// Draws `spec` as an SVG document string of size [`PLOT_SIZE`].
///
/// # Errors
/// [`ReportError::Plot`] when plotters fails (it only fails on backend errors, which for the
/// in-memory SVG backend do not occur in practice).
pub fn render_svg(spec: &PlotSpec) -> Result<String, ReportError> {
    let plot = &spec.plot;
    let err = |e: &dyn std::fmt::Display| ReportError::Plot {
        plot: plot.title.clone(),
        message: e.to_string(),
    };
    let all = || plot.series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = padded_range(all().map(|p| p[0]));
    let (y0, y1) = padded_range(
        all()
            .map(|p| p[1])
            .chain(spec.reference_lines.iter().map(|r| r.y)),
    );

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&plot.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(plot.x_label.as_str())
            .y_desc(plot.y_label.as_str())
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(|e| err(&e))?;

        for (i, s) in plot.series.iter().enumerate() {
            let colour = series_colour(i);
            let style = ShapeStyle::from(&colour).stroke_width(2);
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().map(|p| (p[0], p[1])),
                    style,
                ))
                .map_err(|e| err(&e))?
                .label(s.name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            // Markers only for short series, where they show the sampling (the states).
            if s.points.len() <= 60 {
                chart
                    .draw_series(
                        s.points
                            .iter()
                            .map(|p| Circle::new((p[0], p[1]), 2, colour.filled())),
                    )
                    .map_err(|e| err(&e))?;
            }
        }
        for r in &spec.reference_lines {
            let style = ShapeStyle::from(&RED).stroke_width(1);
            // plotters has no dash style for series; draw the limit as short pieces.
            let n = 40;
            let pieces = (0..n).step_by(2).map(|k| {
                let a = x0 + (x1 - x0) * f64::from(k) / f64::from(n);
                let b = x0 + (x1 - x0) * f64::from(k + 1) / f64::from(n);
                PathElement::new(vec![(a, r.y), (b, r.y)], style)
            });
            chart
                .draw_series(pieces)
                .map_err(|e| err(&e))?
                .label(format!("limit {} = {}", r.name, fmt_num(r.y)))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .label_font(("sans-serif", 12))
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    Ok(svg)
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
