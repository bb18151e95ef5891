//! Integration tests of kappe-report (one binary, modules per topic).

mod demo;
mod html;
mod placement;
mod study;
mod validate;

/// The text between `<script type="application/json" id="kappe-data">` and its `</script>`.
pub fn island(html: &str) -> &str {
    let open = "<script type=\"application/json\" id=\"kappe-data\">";
    let start = html.find(open).expect("island present") + open.len();
    let len = html[start..].find("</script>").expect("island closed");
    &html[start..start + len]
}
