//! Embeds the designer's WebAssembly bundle (issue 25) when it has been built: scripts/build-designer.sh
//! writes `crates/designer/pkg/kappe_designer.js` (wasm-bindgen glue) and
//! `crates/designer/pkg/kappe_designer_bg.wasm.gz` (gzip). Without them the CLI still builds, and
//! `kappe designer` fails with an error naming that script.
use std::path::Path;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(kappe_designer_bundle)");
    let pkg = Path::new(env!("CARGO_MANIFEST_DIR")).join("../designer/pkg");
    let glue = pkg.join("kappe_designer.js");
    let wasm = pkg.join("kappe_designer_bg.wasm.gz");
    println!("cargo::rerun-if-changed={}", pkg.display());
    println!("cargo::rerun-if-changed={}", glue.display());
    println!("cargo::rerun-if-changed={}", wasm.display());
    if glue.is_file() && wasm.is_file() {
        println!("cargo::rustc-cfg=kappe_designer_bundle");
        println!("cargo::rustc-env=KAPPE_DESIGNER_GLUE={}", glue.display());
        println!("cargo::rustc-env=KAPPE_DESIGNER_WASM={}", wasm.display());
    }
}
