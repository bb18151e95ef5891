//! The study files: `study.csv` (written by hand: one quoting rule of RFC 4180 for text fields)
//! and the table of `study.html` ([`kappe_report::render_study_html`]).

use kappe_report::{StudyCell, StudyColumn, StudyRow, StudyTable};

use super::StudyResult;

/// A CSV field: quoted (RFC 4180) when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number in its shortest round-trip form; scientific notation outside [1e-3, 1e15), where the
/// plain form would be long (Rust's `{}` never switches to an exponent by itself).
fn csv_num(v: Option<f64>) -> String {
    v.map(|x| {
        if x == 0.0 || (1e-3..1e15).contains(&x.abs()) {
            format!("{x}")
        } else {
            format!("{x:e}")
        }
    })
    .unwrap_or_default()
}

/// `study.csv`: one row per design.
pub fn study_csv(result: &StudyResult) -> String {
    let mut s = String::new();
    let mut header: Vec<String> = vec!["name".into()];
    header.extend(result.parameters.iter().map(|p| csv_field(p)));
    header.extend(
        [
            "result",
            "max_compression_stress_pa",
            "max_tension_stress_pa",
            "max_overhang_m",
            "min_blf",
            "mass_kg",
            "print_time_s",
            "states",
            "robot",
            "error",
        ]
        .map(String::from),
    );
    s.push_str(&header.join(","));
    s.push('\n');
    for r in &result.rows {
        let mut f: Vec<String> = vec![csv_field(&r.name)];
        f.extend(r.parameters.iter().map(|p| csv_field(p)));
        f.push(r.outcome.as_str().into());
        f.push(csv_num(r.max_compression_stress_pa));
        f.push(csv_num(r.max_tension_stress_pa));
        f.push(csv_num(r.max_overhang_m));
        f.push(csv_num(r.min_blf));
        f.push(csv_num(r.mass_kg));
        f.push(csv_num(r.print_time_s));
        f.push(r.states.map(|n| n.to_string()).unwrap_or_default());
        f.push(csv_field(r.robot.as_deref().unwrap_or("")));
        f.push(csv_field(r.error.as_deref().unwrap_or("")));
        s.push_str(&f.join(","));
        s.push('\n');
    }
    s
}

/// Unit of a design parameter, for the table header.
fn unit_of(path: &str) -> &'static str {
    match path {
        "cap.span"
        | "cap.rise"
        | "cap.length"
        | "print.layer_height"
        | "print.layer_width"
        | "print.nozzle_diameter"
        | "print.path_sampling"
        | "constraints.overhang_max"
        | "robot.tool_length" => "m",
        "cap.tilt_deg" | "robot.rotation_step_deg" => "deg",
        "material.specific_weight" => "N/m³",
        "material.youngs_modulus" | "constraints.sigma_min" | "constraints.sigma_max" => "Pa",
        "print.print_speed" => "m/s",
        "robot.epsilon" => "rad²",
        _ => "",
    }
}

/// The table of `study.html`.
pub fn study_table(result: &StudyResult) -> StudyTable {
    let mut parameters: Vec<StudyColumn> = result
        .parameters
        .iter()
        .map(|p| StudyColumn {
            name: p.clone(),
            unit: unit_of(p).into(),
        })
        .collect();
    // Figures that are results, not constraints, shown next to the parameters.
    parameters.push(StudyColumn {
        name: "mass".into(),
        unit: "kg".into(),
    });
    parameters.push(StudyColumn {
        name: "print time".into(),
        unit: "min".into(),
    });
    // Constraint columns: every constraint any design reports, in first-seen order.
    let mut constraints: Vec<StudyColumn> = Vec::new();
    for r in &result.rows {
        for c in &r.constraints {
            if !constraints.iter().any(|k| k.name == c.name) {
                constraints.push(StudyColumn {
                    name: c.name.clone(),
                    unit: c.unit.clone(),
                });
            }
        }
    }
    let keys: Vec<String> = constraints.iter().map(|c| c.name.clone()).collect();
    let rows = result
        .rows
        .iter()
        .map(|r| {
            let mut values = r.parameters.clone();
            values.push(r.mass_kg.map(|m| format!("{m:.2}")).unwrap_or_default());
            values.push(
                r.print_time_s
                    .map(|t| format!("{:.1}", t / 60.0))
                    .unwrap_or_default(),
            );
            StudyRow {
                name: r.name.clone(),
                parameters: values,
                constraints: keys
                    .iter()
                    .map(|k| {
                        r.constraints
                            .iter()
                            .find(|c| &c.name == k)
                            .map(|c| StudyCell {
                                value: c.worst,
                                pass: c.pass,
                            })
                    })
                    .collect(),
                error: r.error.clone(),
                report_href: r.report.clone(),
            }
        })
        .collect();
    StudyTable {
        title: result.title.clone(),
        parameters,
        constraints,
        rows,
    }
}

impl StudyResult {
    /// `study.csv`.
    pub fn csv(&self) -> String {
        study_csv(self)
    }

    /// `study.html`.
    ///
    /// # Errors
    /// What [`kappe_report::render_study_html`] rejects.
    pub fn html(&self) -> Result<String, kappe_report::ReportError> {
        kappe_report::render_study_html(&study_table(self))
    }
}
