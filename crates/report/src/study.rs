//! The design-study table `study.html` of `kappe study` (issue 8; like Table 2 of the paper):
//! one row per design, columns for its parameters and for each constraint's worst value,
//! failed cells highlighted, a design that could not be run shown as a failed row with its
//! reason, and a link to each design's `report.html`.
//!
//! Plain HTML and CSS, no script: the page is a table and must open anywhere.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use crate::error::ReportError;
use crate::markup::escape_html;
use crate::plots::fmt_num;

/// A column header: key and unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyColumn {
    /// Parameter key or constraint name.
    pub name: String,
    /// Unit, empty when dimensionless.
    pub unit: String,
}

/// One constraint result of one design.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StudyCell {
    /// Worst value, in the column's unit.
    pub value: f64,
    /// Whether the constraint holds.
    pub pass: bool,
}

/// One design of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyRow {
    /// Design name (unique within the study).
    pub name: String,
    /// Parameter values as text, one per [`StudyTable::parameters`] column.
    pub parameters: Vec<String>,
    /// Constraint results, one per [`StudyTable::constraints`] column; `None` where not computed.
    pub constraints: Vec<Option<StudyCell>>,
    /// Why the design could not be run, if it failed before producing results.
    pub error: Option<String>,
    /// Relative link to the design's report, e.g. `designs/span-0.8/report.html`.
    pub report_href: Option<String>,
}

impl StudyRow {
    /// A design passes when it ran and every computed constraint holds.
    #[must_use]
    pub fn passed(&self) -> bool {
        self.error.is_none() && self.constraints.iter().flatten().all(|c| c.pass)
    }
}

/// The study table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyTable {
    /// Page title, e.g. the study file name.
    pub title: String,
    /// Parameter columns.
    pub parameters: Vec<StudyColumn>,
    /// Constraint columns.
    pub constraints: Vec<StudyColumn>,
    /// One row per design, in the order to show.
    pub rows: Vec<StudyRow>,
}

/// A link must stay inside the study directory: relative, no scheme, no `..`, so that the
/// page works when the directory is moved or copied.
fn check_href(row: usize, href: &str) -> Result<(), ReportError> {
    let bad = href.is_empty()
        || href.contains(':')
        || href.starts_with('/')
        || href.starts_with('\\')
        || href.split(['/', '\\']).any(|part| part == "..");
    if bad {
        return Err(ReportError::BadLink {
            field: format!("rows[{row}].report_href"),
            href: href.to_string(),
        });
    }
    Ok(())
}

impl StudyTable {
    /// Checks row shapes, finite values and relative links.
    ///
    /// # Errors
    /// The first violation, naming the row and field.
    pub fn validate(&self) -> Result<(), ReportError> {
        for (i, row) in self.rows.iter().enumerate() {
            if row.parameters.len() != self.parameters.len() {
                return Err(ReportError::LengthMismatch {
                    field: format!("rows[{i}].parameters"),
                    len: row.parameters.len(),
                    expected: self.parameters.len(),
                });
            }
            if row.constraints.len() != self.constraints.len() {
                return Err(ReportError::LengthMismatch {
                    field: format!("rows[{i}].constraints"),
                    len: row.constraints.len(),
                    expected: self.constraints.len(),
                });
            }
            for (j, cell) in row.constraints.iter().enumerate() {
                if let Some(c) = cell
                    && !c.value.is_finite()
                {
                    return Err(ReportError::NotFinite {
                        field: format!("rows[{i}].constraints[{j}].value"),
                        value: c.value,
                    });
                }
            }
            if let Some(href) = &row.report_href {
                check_href(i, href)?;
            }
        }
        Ok(())
    }
}

/// Renders `study.html`.
///
/// # Errors
/// The first problem found by [`StudyTable::validate`].
pub fn render_study_html(table: &StudyTable) -> Result<String, ReportError> {
    table.validate()?;
    let title = escape_html(&table.title);
    let total = table.rows.len();
    let passed = table.rows.iter().filter(|r| r.passed()).count();
    let errors = table.rows.iter().filter(|r| r.error.is_some()).count();
    let mut h = String::with_capacity(4096 + 512 * total);
    // `write!` into a String cannot fail; the results are ignored on purpose.
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>Kappe study: {title}</title>\n<style>\n{STUDY_CSS}</style>\n</head>\n<body>\n\
         <h1>{title}</h1>\n<p class=\"summary\">{total} designs: <span class=\"pass\">{passed} pass</span>, \
         <span class=\"fail\">{} fail</span> (of which {errors} could not be run).</p>\n\
         <table id=\"study\">\n<thead><tr><th>design</th><th>result</th>",
        total - passed
    );
    let header = |h: &mut String, c: &StudyColumn, class: &str| {
        let unit = if c.unit.is_empty() {
            String::new()
        } else {
            format!(" <span class=\"unit\">[{}]</span>", escape_html(&c.unit))
        };
        let _ = write!(
            h,
            "<th class=\"{class}\">{}{unit}</th>",
            escape_html(&c.name)
        );
    };
    for c in &table.parameters {
        header(&mut h, c, "param");
    }
    for c in &table.constraints {
        header(&mut h, c, "constraint");
    }
    let _ = write!(h, "<th>report</th></tr></thead>\n<tbody>\n");
    for row in &table.rows {
        let ok = row.passed();
        let _ = write!(
            h,
            "<tr class=\"{}\"><td class=\"name\">{}</td><td class=\"{}\">{}</td>",
            if row.error.is_some() {
                "error"
            } else if ok {
                "ok"
            } else {
                "failed"
            },
            escape_html(&row.name),
            if ok { "pass" } else { "fail" },
            if ok { "pass" } else { "FAIL" }
        );
        for v in &row.parameters {
            let _ = write!(h, "<td class=\"num\">{}</td>", escape_html(v));
        }
        if let Some(reason) = &row.error {
            let _ = write!(
                h,
                "<td class=\"reason\" colspan=\"{}\">{}</td>",
                table.constraints.len().max(1),
                escape_html(reason)
            );
        } else {
            for cell in &row.constraints {
                match cell {
                    Some(c) if c.pass => {
                        let _ = write!(h, "<td class=\"num\">{}</td>", fmt_num(c.value));
                    }
                    Some(c) => {
                        let _ = write!(h, "<td class=\"num cell-fail\">{}</td>", fmt_num(c.value));
                    }
                    None => h.push_str("<td class=\"num\">–</td>"),
                }
            }
            if table.constraints.is_empty() {
                h.push_str("<td></td>");
            }
        }
        match &row.report_href {
            Some(href) => {
                let _ = write!(h, "<td><a href=\"{}\">report</a></td>", escape_html(href));
            }
            None => h.push_str("<td>–</td>"),
        }
        h.push_str("</tr>\n");
    }
    let _ = write!(
        h,
        "</tbody>\n</table>\n<p class=\"note\">Constraint columns show the worst value over all print states; \
         highlighted cells violate their limit.</p>\n</body>\n</html>\n"
    );
    Ok(h)
}

const STUDY_CSS: &str =
    "body { margin: 20px; font: 14px/1.45 system-ui, \"DejaVu Sans\", sans-serif; color: #1f2328; }
h1 { font-size: 20px; margin: 0 0 6px; }
table { border-collapse: collapse; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #d0d7de; padding: 3px 8px; }
th { background: #f6f8fa; text-align: left; }
th.constraint { background: #eef3f8; }
td.num { text-align: right; }
.unit { color: #57606a; font-weight: normal; }
.pass { color: #1a7f37; font-weight: 600; }
.fail { color: #b2182b; font-weight: 600; }
td.cell-fail { background: #fbe3e0; color: #b2182b; font-weight: 600; }
tr.error td { background: #fff4e5; }
td.reason { color: #9a3412; }
tbody tr:hover td { outline: 1px solid #afb8c1; }
.note { color: #57606a; font-size: 12px; }
";
