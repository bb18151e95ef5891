//! Dump the default cap's robot inputs (layers, setup, options) as JSON for robot-crate work:
//! `cargo run --release -p kappe --example robot_inputs_dump -- OUT.json`.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "robot_inputs.json".into());
    let cap = kappe::design_cap(&kappe::Design::default(), &|_| {})?;
    let (setup, options) = kappe::robot_plan::robot_inputs(&cap);
    let layers = kappe::robot_plan::print_layers(&cap.path);
    let v = serde_json::json!({ "layers": layers, "setup": setup, "options": options });
    std::fs::write(&out, serde_json::to_string(&v)?)?;
    Ok(())
}
