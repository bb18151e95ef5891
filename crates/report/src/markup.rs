//! Text to HTML, on the floor below every section that writes HTML (the page, the schedule,
//! the robot summary, the placement drawing, the study table).

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

/// Inline SVG in HTML must not carry an XML declaration.
pub(crate) fn strip_xml_declaration(svg: &str) -> &str {
    let s = svg.trim_start();
    if s.starts_with("<?xml")
        && let Some(end) = s.find("?>")
    {
        return s.get(end + 2..).unwrap_or(s).trim_start();
    }
    s
}
