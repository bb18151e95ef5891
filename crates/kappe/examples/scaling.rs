//! How the cost of checking every print state grows with the bay length (issue 15 benchmark).
//!
//! `cargo run --release -p kappe --example scaling [-- LENGTH ...]` (default 0.6 1.2 2.4 4.8):
//! for each centre length, the default design with an end wall (`[cap] end = "end_wall"`, so
//! long caps do not crush their start; `KAPPE_END=start_section` for the default start section,
//! the configuration of issue 15's baseline table) and the graded shell mesh (`[analysis.grading]` with
//! its defaults), form-finding and the analysis of **every** state (stresses, overhang, shell
//! buckling), each length in its own process so its peak memory (`VmHWM`) is its own. Prints the
//! table and the least-squares exponent p of `analysis time ∝ length^p`, overall and over the
//! last doubling.
//!
//! `-- bay SPAN LENGTH`: one bay of a room `LENGTH` long between end walls (`both_walls`: two
//! mirrored halves, one analysis serves both), span `SPAN`, rise span/4, as `kappe design` runs a
//! ceiling with the graded mesh: form-finding, every state analysed, both halves planned and
//! their base-pose tolerance checked. Issue 15's target is the 1.5 m × 4 m bay.
//!
//! CPU time and the load average are printed next to the wall times so figures taken on a
//! shared machine can be read. `KAPPE_REPEAT=N` runs every length N times (in rounds over the
//! lengths) and reports the median, with the spread: single runs on this machine scatter by
//! ±10 %.

use std::process::Command;
use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;

/// Peak resident memory of this process, MB (`/proc/self/status` `VmHWM`).
fn peak_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// One length, in this process: prints one machine-readable line `ROW length states nodes
/// design_s analysis_s cpu_s peak_mb ok`.
fn one(length: f64) -> Result<(), Box<dyn std::error::Error>> {
    let mut d = kappe::Design::default();
    d.cap.length = length;
    if std::env::var("KAPPE_END").is_ok_and(|e| e == "start_section") {
        d.cap.end = kappe::form::EndKind::StartSection;
    } else {
        d.cap.end = kappe::form::EndKind::EndWall;
    }
    d.analysis.grading = Some(kappe::analysis::Grading::default());
    let cpu0 = measure::cpu_seconds().unwrap_or(0.0);
    let t = Instant::now();
    let cap = kappe::design_cap(&d, kappe::Context::default())?;
    let t_design = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let a = kappe::analysis::analyze(&cap, &d.analysis, kappe::analysis::Request::default())?;
    let t_analysis = t.elapsed().as_secs_f64();
    let cpu = measure::cpu_seconds().unwrap_or(0.0) - cpu0;
    let nodes = cap.states.last().map_or(0, |s| s.nodes);
    println!(
        "ROW {length} {} {nodes} {t_design:.3} {t_analysis:.3} {cpu:.3} {:.0} {} {:.3} {:.3}",
        cap.states.len(),
        peak_mb().unwrap_or(f64::NAN),
        a.ok,
        a.timings.stresses,
        a.timings.fe
    );
    Ok(())
}

/// Least-squares slope of log(y) against log(x).
fn exponent(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

fn bay(span: f64, length: f64) -> Result<(), Box<dyn std::error::Error>> {
    let text = format!(
        "name = \"scaling bay\"\n[ceiling]\nlength = {length}\nends = \"both_walls\"\n\
         rise_ratio = 0.25\ntilt_deg = 25.0\n[[bay]]\nname = \"bay\"\nspan = {span}\n\
         [analysis.grading]\n"
    );
    let c = kappe::commands::ceiling::CeilingDesign::from_toml_str(&text)?;
    let designs = c.bay_designs()?;
    let first = designs.first().ok_or("no bay")?;
    let options = kappe::Options::of(first);
    let cpu0 = measure::cpu_seconds().unwrap_or(0.0);
    let t = Instant::now();
    let b = kappe::commands::ceiling::run_bay(&c, 0, &options, &|_| {
        std::ops::ControlFlow::Continue(())
    })?;
    let total = t.elapsed().as_secs_f64();
    let cpu = measure::cpu_seconds().unwrap_or(0.0) - cpu0;
    let analysis = b.outcome.analysis.as_ref();
    println!(
        "| span m | room length m | halves | states per half | final nodes | analysis s | whole bay s (design, analysis, 2 plans, tolerance) | CPU s | peak MB | load | verdict |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    println!(
        "| {span} | {length} | {} | {} | {} | {:.1} | {total:.1} | {cpu:.1} | {:.0} | {} | {} |",
        b.halves,
        b.outcome.cap.states.len(),
        b.outcome.cap.states.last().map_or(0, |s| s.nodes),
        analysis.map_or(0.0, |a| a.timings.total),
        peak_mb().unwrap_or(f64::NAN),
        measure::load_average(),
        if b.outcome.verdict.ok { "pass" } else { "fail" }
    );
    if let Some(a) = analysis {
        for c in a.constraints.iter().filter(|c| !c.pass) {
            println!(
                "  fails {}: worst {:?} at state {:?} ({}), limit {}",
                c.name, c.worst, c.state, c.element, c.limit
            );
        }
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("one") => {
            let l: f64 = args.get(1).ok_or("one LENGTH")?.parse()?;
            return one(l);
        }
        Some("bay") => {
            let span: f64 = args.get(1).map_or(Ok(1.5), |a| a.parse())?;
            let length: f64 = args.get(2).map_or(Ok(4.0), |a| a.parse())?;
            return bay(span, length);
        }
        _ => {}
    }
    let lengths: Vec<f64> = if args.is_empty() {
        vec![0.6, 1.2, 2.4, 4.8]
    } else {
        args.iter().map(|a| a.parse()).collect::<Result<_, _>>()?
    };
    let exe = std::env::current_exe()?;
    // Repeats run in rounds over all lengths (so a slow spell of the machine spreads over the
    // lengths); each length reports its median run.
    let repeat: usize = std::env::var("KAPPE_REPEAT")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(1)
        .max(1);
    let mut runs: Vec<Vec<(f64, Vec<String>, String)>> = vec![Vec::new(); lengths.len()];
    for _ in 0..repeat {
        for (k, l) in lengths.iter().enumerate() {
            let out = Command::new(&exe).arg("one").arg(l.to_string()).output()?;
            let text = String::from_utf8_lossy(&out.stdout);
            let Some(row) = text.lines().find_map(|r| r.strip_prefix("ROW ")) else {
                println!(
                    "| {l} | error: {} |",
                    String::from_utf8_lossy(&out.stderr).trim()
                );
                continue;
            };
            let f: Vec<String> = row.split_whitespace().map(str::to_string).collect();
            if f.len() < 10 {
                continue;
            }
            let analysis: f64 = f[4].parse()?;
            runs[k].push((analysis, f, measure::load_average()));
        }
    }
    println!(
        "| centre length m | states | final nodes | form-finding s | analysis s (every state; median of {repeat}, min–max) | of which force passes + stresses s | of which shell buckling s | CPU s | peak MB | load | verdict |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let (mut xs, mut ts) = (Vec::new(), Vec::new());
    for (l, r) in lengths.iter().zip(&mut runs) {
        r.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (Some(lo), Some(hi)) = (r.first(), r.last()) else {
            continue;
        };
        let (lo, hi) = (lo.0, hi.0);
        let Some((analysis, f, load)) = r.get(r.len() / 2) else {
            continue;
        };
        println!(
            "| {} | {} | {} | {} | {analysis:.2} ({lo:.2}–{hi:.2}) | {} | {} | {} | {} | {load} | {} |",
            f[0],
            f[1],
            f[2],
            f[3],
            f[8],
            f[9],
            f[5],
            f[6],
            if f[7] == "true" { "pass" } else { "fail" }
        );
        xs.push(*l);
        ts.push(*analysis);
    }
    if xs.len() >= 2 {
        let n = xs.len();
        println!(
            "exponent of analysis time vs length: {:.2} overall (least squares), {:.2} over the last doubling",
            exponent(&xs, &ts),
            exponent(&xs[n - 2..], &ts[n - 2..])
        );
        // Issue 15's range, when the run covers it and more.
        let k = xs.iter().position(|&x| x > 4.8 + 1e-9).unwrap_or(n);
        if k >= 2 && k < n {
            println!(
                "exponent over {}–{} m: {:.2}",
                xs[0],
                xs[k - 1],
                exponent(&xs[..k], &ts[..k])
            );
        }
    }
    Ok(())
}
