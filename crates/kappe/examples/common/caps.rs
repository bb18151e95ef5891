//! The caps the mesh-convergence examples measure: `KIND` (`smooth`, the default design, or
//! `corrugated`, `kappe init --kind corrugated`) at `LENGTH` m.

/// The form-found cap of `kind` with `[cap] length = length`.
#[allow(dead_code)]
pub fn cap_of(kind: &str, length: &str) -> Result<kappe::Cap, Box<dyn std::error::Error>> {
    let mut design = match kind {
        "smooth" => kappe::Design::default(),
        "corrugated" => kappe::Design::from_toml_str(kappe::commands::templates::CORRUGATED_TOML)?,
        other => return Err(format!("KIND {other}: smooth or corrugated").into()),
    };
    design.cap.length = length.parse()?;
    Ok(kappe::design_cap(&design, kappe::Context::default())?)
}

/// The bay of `examples/scaling.rs -- bay 1.5 4.0` that the speed tables measure: one half of a
/// 1.5 m span between walls 4 m apart, graded mesh.
#[allow(dead_code)]
pub fn bay_half() -> Result<kappe::Design, Box<dyn std::error::Error>> {
    let text = "name = \"bench bay\"\n[ceiling]\nlength = 4.0\nends = \"both_walls\"\n\
                rise_ratio = 0.25\ntilt_deg = 25.0\n[[bay]]\nname = \"bay\"\nspan = 1.5\n\
                [analysis.grading]\n";
    let c = kappe::commands::ceiling::CeilingDesign::from_toml_str(text)?;
    Ok(c.bay_designs()?.into_iter().next().ok_or("no bay")?)
}
