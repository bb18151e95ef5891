//! Native per-change latency of the designer's synchronous part (issue 25): `Session::set` of the
//! rise on the default design, the median of 10 moves, and its stages. The browser adds the
//! WASM slowdown and the 3D redraw (web/designer/bench.mjs measures those).
//!   cargo run --release -p kappe-designer --example latency
use std::time::Instant;

fn main() {
    let mut s = kappe_designer::SessionCore::new();
    if let Err(e) = s.load(&kappe_designer::default_toml()) {
        eprintln!("default design: {}", e.message);
        std::process::exit(1);
    }
    let mut ms = Vec::new();
    for k in 0..10 {
        let rise = 0.2 + 0.004 * f64::from(k + 1) * if k % 2 == 1 { -1.0 } else { 1.0 };
        let t = Instant::now();
        let out = s.set("cap.rise", &serde_json::json!(rise));
        let text = out.map(|v| v.to_string());
        let dt = t.elapsed().as_secs_f64() * 1e3;
        ms.push(dt);
        println!(
            "move {:>2}  rise {rise:.3}  {dt:8.1} ms  {} bytes",
            k + 1,
            text.map(|t| t.len()).unwrap_or(0)
        );
    }
    ms.sort_by(f64::total_cmp);
    println!("median {:.1} ms", (ms[4] + ms[5]) / 2.0);
}
