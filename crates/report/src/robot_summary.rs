//! The robot plan's checks on the page (issue 13): where the tool is slower than the design
//! speed, by how much and why (the flow follows the speed, so the bead stays the same), and the
//! clearances of the two geometric models the plan was checked with: the capsules the planner
//! uses and UR's convex collision meshes, to the environment and between the arm's own links,
//! at the waypoints and certified along the motion between them (a lower bound, not a sample).

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use crate::error::ReportError;
use crate::markup::escape_html;

/// What the robot section shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct RobotSummary {
    /// The design's tool speed, m/s.
    pub design_speed: f64,
    /// Largest joint speed / its usable limit, and acceleration / its limit, over the plan.
    pub max_speed_ratio: f64,
    pub max_acceleration_ratio: f64,
    /// Stretches of print moves slower than the design speed, in print order.
    pub slowdowns: Vec<SlowdownRow>,
    /// Clearances of the checked models.
    pub clearances: Vec<ClearanceRow>,
    /// The planner's clearance margin to the environment and between links, m.
    pub margin: f64,
    pub self_margin: f64,
}

/// A stretch of print moves where the tool is slower than the design speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SlowdownRow {
    /// Station (1-based).
    pub station: usize,
    /// Layer and point of the first and last waypoint reached slowly.
    pub from: (i64, usize),
    pub to: (i64, usize),
    /// Lowest tool speed / design speed in the stretch.
    pub min_speed_ratio: f64,
    /// Why (the joint speed or acceleration limit that binds).
    pub reason: String,
}

/// One clearance of one model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClearanceRow {
    /// The model, e.g. `arm capsules`, `arm meshes`, `nozzle (capsule)`.
    pub model: String,
    /// `environment` or `self`.
    pub to: String,
    /// Smallest distance over the waypoints, m, and where (link – object, station, layer).
    pub at_waypoints: f64,
    pub at: String,
    /// Certified lower bound along the motion between the waypoints, m, when checked.
    pub along_motion: Option<f64>,
}

impl RobotSummary {
    pub(crate) fn validate(&self) -> Result<(), ReportError> {
        let finite = |field: String, value: f64| {
            if value.is_finite() {
                Ok(())
            } else {
                Err(ReportError::NotFinite { field, value })
            }
        };
        finite("robot_summary.design_speed".into(), self.design_speed)?;
        finite("robot_summary.max_speed_ratio".into(), self.max_speed_ratio)?;
        finite(
            "robot_summary.max_acceleration_ratio".into(),
            self.max_acceleration_ratio,
        )?;
        finite("robot_summary.margin".into(), self.margin)?;
        finite("robot_summary.self_margin".into(), self.self_margin)?;
        for (i, s) in self.slowdowns.iter().enumerate() {
            finite(
                format!("robot_summary.slowdowns[{i}].min_speed_ratio"),
                s.min_speed_ratio,
            )?;
        }
        for (i, c) in self.clearances.iter().enumerate() {
            finite(
                format!("robot_summary.clearances[{i}].at_waypoints"),
                c.at_waypoints,
            )?;
            if let Some(v) = c.along_motion {
                finite(format!("robot_summary.clearances[{i}].along_motion"), v)?;
            }
        }
        Ok(())
    }
}

fn mm(v: f64) -> String {
    format!("{:.1} mm", v * 1e3)
}

/// The robot section: tool speed and slowdowns, then the clearance table.
pub(crate) fn section_html(r: &RobotSummary) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<section id=\"robot-check\" class=\"wide\">\n<h2>Robot: speed and clearances</h2>\n"
    );
    if r.slowdowns.is_empty() {
        let _ = writeln!(
            h,
            "<p id=\"robot-slowdowns\">The tool keeps the design speed of {:.0} mm/s (within 2 %) on every print move: \
             joints reach at most {:.0} % of their speed limit and {:.0} % of their acceleration limit.</p>",
            r.design_speed * 1e3,
            100.0 * r.max_speed_ratio,
            100.0 * r.max_acceleration_ratio
        );
    } else {
        let _ = writeln!(
            h,
            "<p id=\"robot-slowdowns\">The tool slows below the design speed of {:.0} mm/s in {} stretch{} \
             (the flow follows the speed, so the bead keeps its size; the print takes longer):</p>",
            r.design_speed * 1e3,
            r.slowdowns.len(),
            if r.slowdowns.len() == 1 { "" } else { "es" }
        );
        let _ = writeln!(
            h,
            "<table id=\"slowdown-table\"><thead><tr><th>station</th><th>from layer/point</th>\
             <th>to layer/point</th><th>lowest speed</th><th>why</th></tr></thead><tbody>"
        );
        for s in &r.slowdowns {
            let _ = writeln!(
                h,
                "<tr><td class=\"num\">{}</td><td class=\"num\">{} / {}</td><td class=\"num\">{} / {}</td>\
                 <td class=\"num\">{:.1} % ({:.1} mm/s)</td><td>{}</td></tr>",
                s.station,
                s.from.0,
                s.from.1,
                s.to.0,
                s.to.1,
                100.0 * s.min_speed_ratio,
                s.min_speed_ratio * r.design_speed * 1e3,
                escape_html(&s.reason)
            );
        }
        let _ = writeln!(h, "</tbody></table>");
    }
    if !r.clearances.is_empty() {
        let _ = writeln!(
            h,
            "<p class=\"hint\">Clearances of the capsule model the planner uses and of UR's convex collision meshes \
             (margins: {} to the environment, {} between links). “Along the motion” is a certified lower bound \
             between the waypoints (joint travel × lever arm, split where it falls below the margin, so a value \
             equal to the margin means the margin is proven, not that the arm is that close).</p>",
            mm(r.margin),
            mm(r.self_margin)
        );
        let _ = writeln!(
            h,
            "<table id=\"clearance-table\"><thead><tr><th>model</th><th>to</th><th>at waypoints</th>\
             <th>where</th><th>along the motion (≥)</th></tr></thead><tbody>"
        );
        for c in &r.clearances {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td class=\"num\">{}</td><td>{}</td><td class=\"num\">{}</td></tr>",
                escape_html(&c.model),
                escape_html(&c.to),
                mm(c.at_waypoints),
                escape_html(&c.at),
                c.along_motion
                    .map_or_else(|| "–".to_string(), |v| along_motion_text(c, v, r))
            );
        }
        let _ = writeln!(h, "</tbody></table>");
    }
    h.push_str("</section>\n");
    h
}

/// A certified bound is refined only until it clears the margin, so with a zero margin between
/// links it stops just above 0: shown as "0.0 mm" it reads as contact, when it proves the
/// opposite (a positive lower bound of the distance).
fn along_motion_text(c: &ClearanceRow, v: f64, r: &RobotSummary) -> String {
    let margin = if c.to == "self" {
        r.self_margin
    } else {
        r.margin
    };
    // Below half of the 0.1 mm the table shows, a positive bound would print as "0.0 mm".
    if margin == 0.0 && v > 0.0 && v < 0.05e-3 {
        "&gt; 0: no contact (certified)".to_string()
    } else {
        mm(v)
    }
}
