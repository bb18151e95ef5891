//! The print schedule on the page (issue 11): when every layer starts and ends and how long the
//! printer waits after it, which check governs each analysed state (the largest utilisation of
//! buckling, strength, sliding, stress and overhang), and the age of every layer at the
//! governing state(s) as a plot.
//!
//! Utilisation is demand / capacity, so 1 is the limit for every check: BLF_min / BLF for
//! buckling, the Mohr–Coulomb and bed-joint sliding utilisations for strength and sliding,
//! σ / σ_limit (the larger of compression and tension) for stress, |l_o| / l_o,max for overhang.

use std::fmt::Write as _;

use crate::error::ReportError;
use crate::markup::escape_html;
use crate::plots::{CursorAxis, PlotSpec, ReferenceLine, fmt_num};
use crate::series::{Plot, Series};

pub use crate::input::{PrintSchedule, ScheduleRow, StateAges, StateGoverning};

impl PrintSchedule {
    /// Every number finite, times non-negative, every layer's end after its start.
    ///
    /// # Errors
    /// [`ReportError::NotFinite`] / [`ReportError::OutOfRange`] naming the first bad field.
    pub fn validate(&self) -> Result<(), ReportError> {
        let finite = |field: String, value: f64| {
            if value.is_finite() {
                Ok(())
            } else {
                Err(ReportError::NotFinite { field, value })
            }
        };
        for (i, r) in self.layers.iter().enumerate() {
            for (name, v) in [
                ("start", r.start),
                ("end", r.end),
                ("wait", r.wait),
                ("pause", r.pause),
            ] {
                finite(format!("schedule.layers[{i}].{name}"), v)?;
                if v < 0.0 {
                    return Err(ReportError::OutOfRange {
                        field: format!("schedule.layers[{i}].{name}"),
                        value: v,
                        allowed: "a time ≥ 0 s",
                    });
                }
            }
            if r.end < r.start {
                return Err(ReportError::OutOfRange {
                    field: format!("schedule.layers[{i}].end"),
                    value: r.end,
                    allowed: "not before the layer's start",
                });
            }
        }
        for (i, s) in self.states.iter().enumerate() {
            for (k, (_, u)) in s.checks.iter().enumerate() {
                if !u.is_finite() {
                    return Err(ReportError::NotFinite {
                        field: format!("schedule.states[{i}].checks[{k}]"),
                        value: *u,
                    });
                }
            }
        }
        for (i, a) in self.ages.iter().enumerate() {
            for (k, (_, t)) in a.ages.iter().enumerate() {
                finite(format!("schedule.ages[{i}].ages[{k}]"), *t)?;
            }
        }
        Ok(())
    }
}

fn util_text(u: f64) -> String {
    // A mechanism (BLF 0) comes as the largest finite f64 (JSON carries no infinity).
    if u < 1e300 { fmt_num(u) } else { "∞".into() }
}

/// The page section: which check governs (counts, then a table per state), the schedule table.
pub(crate) fn section_html(s: &PrintSchedule) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<section id=\"schedule\" class=\"wide\">\n<h2>Schedule and governing checks</h2>\n\
         <p class=\"hint\">Times from the {}. Utilisation = demand / capacity (1 is the limit): \
         BLF_min/BLF, Mohr–Coulomb strength, bed-joint sliding, σ/σ_limit, |l_o|/l_o,max.</p>\n",
        escape_html(&s.source)
    );
    // Counts of the governing check over the states.
    let mut counts: Vec<(String, usize)> = Vec::new();
    for st in &s.states {
        if let Some((c, _)) = st.governing() {
            match counts.iter_mut().find(|(n, _)| n == c) {
                Some(e) => e.1 += 1,
                None => counts.push((c.to_string(), 1)),
            }
        }
    }
    if !counts.is_empty() {
        let text: Vec<String> = counts
            .iter()
            .map(|(c, n)| {
                format!(
                    "{} in {n} state{}",
                    escape_html(c),
                    if *n == 1 { "" } else { "s" }
                )
            })
            .collect();
        let _ = writeln!(
            h,
            "<p id=\"governing-summary\">Governs: {}.</p>",
            text.join(", ")
        );
    }
    let mut names: Vec<&str> = Vec::new();
    for st in &s.states {
        for (c, _) in &st.checks {
            if !names.contains(&c.as_str()) {
                names.push(c);
            }
        }
    }
    let _ = write!(
        h,
        "<details id=\"governing\"><summary>Governing check of every state ({} states)</summary>\
         <table><thead><tr><th>state</th><th>governs</th>",
        s.states.len()
    );
    for n in &names {
        let _ = write!(h, "<th>{}</th>", escape_html(n));
    }
    let _ = write!(h, "</tr></thead><tbody>");
    for st in &s.states {
        let g = st.governing();
        let fail = g.is_some_and(|(_, u)| u > 1.0);
        let _ = write!(
            h,
            "<tr{}><td class=\"num\">{}</td><td>{}</td>",
            if fail { " class=\"fail\"" } else { "" },
            st.state,
            escape_html(g.map_or("–", |g| g.0))
        );
        for n in &names {
            let v = st.checks.iter().find(|(c, _)| c == n).map(|(_, u)| *u);
            let _ = write!(
                h,
                "<td class=\"num\">{}</td>",
                v.map_or_else(|| "–".to_string(), util_text)
            );
        }
        let _ = write!(h, "</tr>");
    }
    let _ = writeln!(h, "</tbody></table></details>");
    let total = s.layers.last().map_or(0.0, |l| l.end);
    let waits: f64 = s.layers.iter().map(|l| l.wait).sum();
    let _ = write!(
        h,
        "<details id=\"schedule-table\"><summary>Schedule: {} layers, {} s to the end of the last \
         layer, {} s of waits</summary><table><thead><tr><th>layer</th><th>start [s]</th>\
         <th>end [s]</th><th>wait [s]</th><th>other pause [s]</th></tr></thead><tbody>",
        s.layers.len(),
        fmt_num(total),
        fmt_num(waits)
    );
    for r in &s.layers {
        let _ = write!(
            h,
            "<tr><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>\
             <td class=\"num\">{}</td><td class=\"num\">{}</td></tr>",
            r.layer,
            fmt_num(r.start),
            fmt_num(r.end),
            fmt_num(r.wait),
            fmt_num(r.pause)
        );
    }
    let _ = write!(h, "</tbody></table></details>\n</section>\n");
    h
}

/// The plots: each check's utilisation over the states (limit 1), and the layer ages at the
/// governing state(s) over the layer id.
pub(crate) fn plots(s: &PrintSchedule) -> Vec<PlotSpec> {
    let mut out = Vec::new();
    let mut names: Vec<&str> = Vec::new();
    for st in &s.states {
        for (c, _) in &st.checks {
            if !names.contains(&c.as_str()) {
                names.push(c);
            }
        }
    }
    if !s.states.is_empty() {
        let series = names
            .iter()
            .map(|n| Series {
                name: (*n).to_string(),
                points: s
                    .states
                    .iter()
                    .filter_map(|st| {
                        let u = st.checks.iter().find(|(c, _)| c == n)?.1;
                        (u < 1e300).then_some([st.state as f64, u])
                    })
                    .collect(),
            })
            .collect();
        out.push(PlotSpec {
            plot: Plot {
                title: "Utilisation of each check per state".into(),
                x_label: "print state".into(),
                y_label: "utilisation (1 = limit)".into(),
                series,
            },
            reference_lines: vec![ReferenceLine {
                name: "limit".into(),
                y: 1.0,
            }],
            cursor: CursorAxis::None,
            ..PlotSpec::default()
        });
    }
    if !s.ages.is_empty() {
        out.push(PlotSpec {
            plot: Plot {
                title: "Layer age at the governing state(s)".into(),
                x_label: "layer id".into(),
                y_label: "age [s]".into(),
                series: s
                    .ages
                    .iter()
                    .map(|a| Series {
                        name: format!("state {} ({})", a.state, a.why),
                        points: a.ages.iter().map(|&(l, t)| [f64::from(l), t]).collect(),
                    })
                    .collect(),
            },
            cursor: CursorAxis::None,
            ..PlotSpec::default()
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> PrintSchedule {
        PrintSchedule {
            source: "robot plan".into(),
            layers: vec![
                ScheduleRow {
                    layer: 0,
                    start: 0.0,
                    end: 10.0,
                    wait: 5.0,
                    pause: 0.0,
                },
                ScheduleRow {
                    layer: 1,
                    start: 15.0,
                    end: 25.0,
                    wait: 0.0,
                    pause: 0.0,
                },
            ],
            states: vec![
                StateGoverning {
                    state: 0,
                    checks: vec![("stress".into(), 0.2), ("overhang".into(), 0.1)],
                },
                StateGoverning {
                    state: 1,
                    checks: vec![
                        ("buckling".into(), 1.25),
                        ("stress".into(), 0.3),
                        ("strength".into(), 0.9),
                    ],
                },
            ],
            ages: vec![StateAges {
                state: 1,
                why: "lowest BLF".into(),
                ages: vec![(0, 15.0), (1, 0.0)],
            }],
        }
    }

    #[test]
    fn governing_is_the_largest_utilisation_and_the_page_says_so() {
        let s = sample();
        assert_eq!(s.states[1].governing(), Some(("buckling", 1.25)));
        let h = section_html(&s);
        assert!(
            h.contains("Governs: stress in 1 state, buckling in 1 state."),
            "{h}"
        );
        // The failing state (utilisation > 1) is marked.
        assert!(h.contains("<tr class=\"fail\"><td class=\"num\">1</td><td>buckling</td>"));
        assert!(h.contains("Schedule: 2 layers, 25 s to the end of the last layer, 5 s of waits"));
        assert_eq!(plots(&s).len(), 2);
    }

    #[test]
    fn bad_times_are_named() {
        let mut s = sample();
        s.layers[1].end = 12.0;
        s.layers[1].start = 13.0;
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("schedule.layers[1].end"), "{e}");
        let mut s = sample();
        s.ages[0].ages[0].1 = f64::NAN;
        assert!(
            s.validate()
                .unwrap_err()
                .to_string()
                .contains("schedule.ages[0].ages[0]")
        );
    }
}
