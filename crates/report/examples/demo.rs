//! Writes the report of the synthetic demo cap: `cargo run -p kappe-report --example demo -- OUT.html`.
//! Prints the page size and the time to render, so it doubles as a rough benchmark.

use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let Some(out) = std::env::args().nth(1) else {
        eprintln!("usage: demo OUT.html");
        return ExitCode::FAILURE;
    };
    let t0 = Instant::now();
    let input = kappe_report::demo_input();
    let t1 = Instant::now();
    let html = match kappe_report::render_html(&input) {
        Ok(h) => h,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let t2 = Instant::now();
    if let Err(e) = std::fs::write(&out, &html) {
        eprintln!("error: cannot write {out}: {e}");
        return ExitCode::FAILURE;
    }
    let segments: usize = input.layers.iter().map(|l| l.segment_stress.len()).sum();
    println!(
        "wrote {out}: {} bytes; {} layers, {segments} segments, {} states, {} robot steps; \
         demo input {:.1} ms, render_html {:.1} ms",
        html.len(),
        input.layers.len(),
        input.states.len(),
        input.robot.as_ref().map_or(0, |r| r.times.len()),
        (t1 - t0).as_secs_f64() * 1e3,
        (t2 - t1).as_secs_f64() * 1e3,
    );
    ExitCode::SUCCESS
}
