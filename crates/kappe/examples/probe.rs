fn main() {
    let d = kappe::Design::default();
    let t = std::time::Instant::now();
    let cap = kappe::design_cap(&d, &|_| {}).unwrap();
    println!("design_cap in {:?}", t.elapsed());
    let t = std::time::Instant::now();
    match kappe::robot_plan::plan_robot(&cap) {
        Ok(p) => println!(
            "plan in {:?}: stations {} motion {} time {} clearance {}",
            t.elapsed(),
            p.stations.len(),
            p.joint_motion,
            p.total_time,
            p.min_clearance
        ),
        Err(e) => println!("plan failed in {:?}: {e}", t.elapsed()),
    }
}
