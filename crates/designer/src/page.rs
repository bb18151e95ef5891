//! The designer page (`kappe designer --out DIR` writes it as `designer.html`): one
//! self-contained HTML file holding the three.js bundle of the report
//! ([`kappe_report::THREE_BUNDLE`]), the wasm-bindgen glue and the designer's wasm (base64),
//! the worker script and [`DESIGNER_JS`]. Opens offline from a file; makes no network request.

use std::fmt::Write as _;

/// The page script.
pub const DESIGNER_JS: &str = include_str!("../assets/designer.js");
/// The Web Worker script (appended to the glue in a Blob URL).
pub const WORKER_JS: &str = include_str!("../assets/worker.js");
/// The page's style.
pub const PAGE_CSS: &str = include_str!("../assets/page.css");

/// Base64 (standard alphabet, padded) of `bytes`.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= c.len() {
                out.push(char::from(A[((n >> (18 - 6 * k)) & 63) as usize]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The page, from the wasm-bindgen glue (`--target no-modules`) and the gzip-compressed wasm
/// (the page unpacks it with the browser's `DecompressionStream`).
pub fn page(glue: &str, wasm_gz: &[u8]) -> String {
    let esc = kappe_report::escape_inline_script;
    let mut h = String::with_capacity(wasm_gz.len() * 4 / 3 + 1_000_000);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
<meta name=\"generator\" content=\"kappe-designer {version}\">\n\
<title>Kappe designer</title>\n<style>\n{css}</style>\n</head>\n<body>\n\
<header><h1>Kappe designer</h1><span id=\"verdict\" class=\"verdict pending\">loading…</span>\
<span>lowest BLF <b id=\"min-blf\">–</b></span>\
<progress id=\"progress\" max=\"1\" value=\"0\"></progress>\
<span class=\"small\">geometry and stresses <span id=\"latency\">–</span>, all buckling factors <span id=\"full\">–</span></span>\
<button type=\"button\" id=\"download\">Download design.toml</button>\
<label>Open design.toml <input type=\"file\" id=\"open\" accept=\".toml,text/plain\"></label>\
<span class=\"small\">(or drop it on the page)</span></header>\n\
<main>\n<section id=\"fields\" aria-label=\"design parameters\"><div id=\"error-design\" class=\"error\"></div></section>\n\
<section>\n<canvas id=\"kappe-canvas\" aria-label=\"3D view of the cap\"></canvas>\
<div id=\"viewer-message\" class=\"error\"></div><p class=\"small\"><label>colour by \
<select id=\"colour-by\"><option value=\"stress\">member stress</option>\
<option value=\"overhang\">layer overhang</option></select></label> <span id=\"legend\"></span></p>\n\
<h2>Constraints</h2>\n<table id=\"constraints\"><thead><tr><th>constraint</th><th></th><th>limit</th>\
<th>worst</th><th>state</th><th>where</th></tr></thead><tbody></tbody></table>\n<p id=\"failures\"></p>\n\
<h2>Every print state</h2><div id=\"plot\"></div>\n\
<p class=\"small\">The numbers of <code>kappe design</code> on the downloaded design.toml: the same library \
compiled to WebAssembly. The designer plans no robot (as <code>kappe design --no-robot</code>): with a \
time model the layers' ages are those of path length / print speed and the waits.</p>\n\
</section>\n</main>\n",
        version = env!("CARGO_PKG_VERSION"),
        css = PAGE_CSS,
    );
    let _ = write!(
        h,
        "<script>\n{three}\n</script>\n\
<script type=\"text/plain\" id=\"kappe-glue\">{glue_text}</script>\n\
<script type=\"text/plain\" id=\"kappe-worker\">{worker}</script>\n\
<script type=\"text/plain\" id=\"kappe-wasm\">{wasm}</script>\n\
<script>\n{glue}\n</script>\n<script>\n{js}\n</script>\n</body>\n</html>\n",
        three = esc(kappe_report::THREE_BUNDLE),
        glue_text = esc(glue),
        worker = esc(WORKER_JS),
        wasm = base64(wasm_gz),
        glue = esc(glue),
        js = esc(DESIGNER_JS),
    );
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_the_standard_alphabet() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }
}
