//! The caps the mesh-convergence examples measure: `KIND` (`smooth`, the default design, or
//! `corrugated`, `kappe init --kind corrugated`) at `LENGTH` m.

/// The form-found cap of `kind` with `[cap] length = length`.
pub fn cap_of(kind: &str, length: &str) -> Result<kappe::Cap, Box<dyn std::error::Error>> {
    let mut design = match kind {
        "smooth" => kappe::Design::default(),
        "corrugated" => kappe::Design::from_toml_str(kappe::commands::templates::CORRUGATED_TOML)?,
        other => return Err(format!("KIND {other}: smooth or corrugated").into()),
    };
    design.cap.length = length.parse()?;
    Ok(kappe::design_cap(&design, kappe::Context::default())?)
}
