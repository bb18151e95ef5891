//! study.html: failed cells and failed designs are highlighted, links stay relative.

use kappe_report::{ReportError, StudyCell, StudyColumn, StudyRow, StudyTable, render_study_html};

fn col(name: &str, unit: &str) -> StudyColumn {
    StudyColumn {
        name: name.into(),
        unit: unit.into(),
    }
}

fn table() -> StudyTable {
    let cell = |value, pass| Some(StudyCell { value, pass });
    StudyTable {
        title: "span × rise".into(),
        parameters: vec![col("span", "m"), col("rise", "m")],
        constraints: vec![col("sigma_min", "kPa"), col("blf", "")],
        rows: vec![
            StudyRow {
                name: "a".into(),
                parameters: vec!["0.8".into(), "0.2".into()],
                constraints: vec![cell(-15.6, true), cell(2.4, true)],
                error: None,
                report_href: Some("designs/a/report.html".into()),
            },
            StudyRow {
                name: "b".into(),
                parameters: vec!["1.2".into(), "0.1".into()],
                constraints: vec![cell(-31.0, false), cell(0.7, false)],
                error: None,
                report_href: Some("designs/b/report.html".into()),
            },
            StudyRow {
                name: "c<x>".into(),
                parameters: vec!["2.0".into(), "0.05".into()],
                constraints: vec![None, None],
                error: Some("form-finding did not converge".into()),
                report_href: None,
            },
        ],
    }
}

#[test]
fn failures_are_highlighted_and_counted() {
    let html = render_study_html(&table()).unwrap();
    assert_eq!(
        html.matches("cell-fail").count(),
        2 + 1,
        "two cells + the css rule"
    );
    assert_eq!(html.matches("<tr class=\"failed\">").count(), 1);
    assert_eq!(html.matches("<tr class=\"error\">").count(), 1);
    assert_eq!(html.matches("<tr class=\"ok\">").count(), 1);
    assert!(html.contains("3 designs: <span class=\"pass\">1 pass</span>"));
    assert!(html.contains("2 fail</span> (of which 1 could not be run)"));
    assert!(html.contains("form-finding did not converge"));
    assert!(html.contains("<a href=\"designs/a/report.html\">report</a>"));
    assert!(html.contains("c&lt;x&gt;"));
    // Self-contained: no scripts, no external links.
    assert!(!html.contains("<script"));
    assert!(!html.contains("http"));
}

#[test]
fn rows_must_match_columns() {
    let mut t = table();
    t.rows[1].constraints.pop();
    assert!(matches!(
        render_study_html(&t).unwrap_err(),
        ReportError::LengthMismatch { field, .. } if field == "rows[1].constraints"
    ));
}

#[test]
fn links_must_stay_in_the_study_directory() {
    for bad in [
        "https://x/report.html",
        "/etc/passwd",
        "../other/report.html",
        "javascript:alert(1)",
        "",
    ] {
        let mut t = table();
        t.rows[0].report_href = Some(bad.into());
        assert!(
            matches!(
                render_study_html(&t).unwrap_err(),
                ReportError::BadLink { .. }
            ),
            "{bad:?} accepted"
        );
    }
}
