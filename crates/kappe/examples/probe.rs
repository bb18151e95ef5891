fn main() {
    let d = kappe::Design::default();
    let t = std::time::Instant::now();
    let cap = kappe::design_cap(&d, &|_| {}).unwrap();
    println!("design_cap in {:?}", t.elapsed());
    let worst = cap
        .states
        .iter()
        .map(|s| s.forces.max_residual / s.forces.residual_tolerance)
        .fold(0.0, f64::max);
    println!("worst residual/tol {worst:e}");
    let f = cap.states.last().unwrap();
    println!("{:#?}", f);
    let dmin = cap
        .states
        .iter()
        .map(|s| s.forces.factor_range[0])
        .fold(1.0, f64::min);
    println!(
        "dmin {dmin}; path len {} vol {} mass {} time {}",
        cap.path.print_length, cap.path.volume, cap.path.mass, cap.path.time
    );
}
