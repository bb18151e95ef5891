#[path = "common/caps.rs"]
mod caps;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let d = caps::bay_half()?;
    let cap = kappe::design_cap(&d, kappe::Context::default())?;
    let a = kappe::analysis::analyze(&cap, &d.analysis, kappe::analysis::Request::default())?;
    println!("{:?}", a.timings);
    for s in &a.states {
        if s.blf_interpolated == Some(false) {
            print!(
                "{}:{:.4}:{:.2}% ",
                s.index,
                s.blf.unwrap_or(0.0),
                100.0 * s.blf_error.unwrap_or(0.0)
            );
        }
    }
    println!();
    let n_conv = a
        .states
        .iter()
        .filter(|s| s.blf_converged == Some(false))
        .count();
    println!("unconverged {n_conv}");
    Ok(())
}
