//! `kappe designer --out DIR`: writes `DIR/designer.html`, the designer in the browser
//! (issue 25; crates/designer): the design's parameters as sliders and fields, the cap in 3D and
//! its checks, recomputed on every change by the kappe library compiled to WebAssembly. One
//! self-contained file that opens offline. The WebAssembly is built by
//! scripts/build-designer.sh before the CLI (the CLI embeds it when it exists at build time).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use crate::output::prepare_dir;

#[derive(Args)]
pub struct DesignerArgs {
    /// Output directory (created, or replaced if it is a previous Kappe output).
    #[arg(long, short, default_value = "out-designer")]
    pub out: PathBuf,
    /// Also replace a non-empty directory that is not a Kappe output, by moving it aside.
    #[arg(long)]
    pub force: bool,
}

/// The page, if this build embeds the designer's WebAssembly.
#[cfg(kappe_designer_bundle)]
fn page() -> Result<String> {
    Ok(kappe_designer::page::page(
        include_str!(env!("KAPPE_DESIGNER_GLUE")),
        include_bytes!(env!("KAPPE_DESIGNER_WASM")),
    ))
}

#[cfg(not(kappe_designer_bundle))]
fn page() -> Result<String> {
    Err(crate::exit::Usage(
        "this kappe was built without the designer's WebAssembly: run scripts/build-designer.sh \
         (it needs the wasm32 toolchain, see its header), then rebuild kappe"
            .into(),
    )
    .into())
}

pub fn run(args: DesignerArgs) -> Result<ExitCode> {
    // The page first: without the bundle nothing is touched.
    let html = page()?;
    let prepared = prepare_dir(&args.out, args.force, "kappe designer")?;
    std::fs::write(prepared.path().join("designer.html"), html)?;
    if let Some(notice) = prepared.commit()? {
        eprintln!("note: {notice}");
    }
    println!("wrote {}", args.out.join("designer.html").display());
    Ok(ExitCode::SUCCESS)
}
