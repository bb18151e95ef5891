//! The cost of the reliability analysis against the deterministic analysis (issue 24: FORM of
//! every state ≤ 3× the deterministic analysis), on a cap whose time-model parameters are
//! uncertain, printed as a table:
//! `cargo run --release -p kappe --example form_cost [repeats]`.
//!
//! The cap is study No. 14's of the reliability tests (the small cap, 0.15 m long, printed at
//! 0.01 m/s: 44 states over 57 min; E(t) = 1.3 MPa + 400 Pa/s·t; every state analysed, every
//! 8th row in the shell, as the CLI test's `DRIFTING_CAP`) with E₀ (lognormal, cov 0.15),
//! Ė (lognormal, cov 0.3) and γ (normal, cov 0.05) uncertain and E₀ drifting −20 %/h, as stop
//! 31 measured it (5–8× by CPU time then). Its buckling components re-solve the state's shell
//! at every FORM iterate, with the exact eigenvalue sensitivity for the gradient. A second row
//! has the strength parameters and the print speed uncertain as well (a strength model
//! f(t) = 30 kPa + 3 Pa/s·t, φ = 0).
//!
//! Per row: the deterministic analysis (`analysis_timings_s.total`, wall) and the CPU time of
//! the whole nominal run, then the reliability of every state and of the print (the function
//! the run calls), wall and CPU, and the ratios; runs alternate (deterministic, reliability)
//! `repeats` times (default 2) and the medians are printed, with the load average (the machine
//! is shared).

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::{Design, Options, design_cap, no_progress, run};

fn cap(strength: bool) -> Result<Design, Box<dyn std::error::Error>> {
    let strength_model = if strength {
        "compressive_strength = 3.0e4\ncompressive_strength_rate = 3.0\n"
    } else {
        ""
    };
    let strength_vars = if strength {
        "\"material.time.compressive_strength\" = { dist = \"lognormal\", cov = 0.15 }\n\
         \"material.time.compressive_strength_rate\" = { dist = \"lognormal\", cov = 0.2 }\n\
         \"print.print_speed\" = { dist = \"lognormal\", cov = 0.1 }\n"
    } else {
        ""
    };
    let text = format!(
        "name = \"study14\"\n[cap]\nlength = 0.15\n[print]\npath_sampling = 0.04\n\
         print_speed = 0.01\n[robot]\nenabled = false\n[analysis]\nrow_stride = 8\n\
         [material.time]\nmodel = \"linear\"\nyoungs_modulus = 1.3e6\n\
         youngs_modulus_rate = 400.0\n{strength_model}\
         [uncertainty]\n\"material.time.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}\n\
         \"material.time.youngs_modulus_rate\" = {{ dist = \"lognormal\", cov = 0.3 }}\n\
         \"material.specific_weight\" = {{ dist = \"normal\", cov = 0.05 }}\n{strength_vars}\
         [uncertainty.drift]\n\"material.time.youngs_modulus\" = {{ percent_per_hour = -20.0 }}\n"
    );
    Ok(Design::from_toml_str(&text)?)
}

/// The default cap (`kappe init`'s design) with a linear time model E(t) = 10 MPa + 1 kPa/s·t
/// (the default E at age 0, stiffening by 3.6 MPa an hour) and the kind of input: E₀
/// (lognormal, cov 0.2), Ė (lognormal, cov 0.3), γ (normal, cov 0.05), E₀ drifting −20 %/h.
fn default_cap() -> Result<Design, Box<dyn std::error::Error>> {
    let text = "name = \"default\"\n[material.time]\nmodel = \"linear\"\n\
                youngs_modulus = 1.0e7\nyoungs_modulus_rate = 1000.0\n\
                [uncertainty]\n\
                \"material.time.youngs_modulus\" = { dist = \"lognormal\", cov = 0.2 }\n\
                \"material.time.youngs_modulus_rate\" = { dist = \"lognormal\", cov = 0.3 }\n\
                \"material.specific_weight\" = { dist = \"normal\", cov = 0.05 }\n\
                [uncertainty.drift]\n\
                \"material.time.youngs_modulus\" = { percent_per_hour = -20.0 }\n";
    Ok(Design::from_toml_str(text)?)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2);
    println!(
        "row | det. analysis wall s | nominal run CPU s | reliability wall s | CPU s | \
         ratio wall | ratio CPU | components | screened states | print β | print P_f | \
         SORM β / P_f | SORM thread-s | FORM-only components | load"
    );
    // `form_cost [repeats] [rows]`: rows a list of 1 (study No. 14, time parameters), 2 (+
    // strength, speed), 3 (the default cap, time parameters); default all.
    let rows = std::env::args().nth(2).unwrap_or_else(|| "123".into());
    // a, b, c: rows 1, 2, 3 with the screening off (`[uncertainty] screening = false`).
    let all = [
        ("study 14, time parameters", '1'),
        ("study 14, + strength, speed", '2'),
        ("default cap, time parameters", '3'),
        ("study 14, time parameters, unscreened", 'a'),
        ("study 14, + strength, speed, unscreened", 'b'),
        ("default cap, time parameters, unscreened", 'c'),
    ];
    // `form_cost 0 13 delta`: per state, the buckling component's first-order β₁ against FORM's
    // β (screening off), and the largest |β − β₁| (the screening rule's δ).
    let delta = std::env::args().nth(3).is_some_and(|a| a == "delta");
    // `form_cost 0 13 reduced`: per state, the time buckling component by the 1-D reduction
    // (`time_buckling_form`) against FORM on the re-solves: β and the re-solves of each.
    let reduced = std::env::args().nth(3).is_some_and(|a| a == "reduced");
    for (name, row) in all.into_iter().filter(|(_, r)| rows.contains(*r)) {
        let mut d = match row {
            '1' | 'a' => cap(false)?,
            '2' | 'b' => cap(true)?,
            _ => default_cap()?,
        };
        if row.is_ascii_lowercase()
            && let Some(u) = d.uncertainty.as_mut()
        {
            u.screening = Some(false);
        }
        if reduced {
            let mut nominal = d.clone();
            nominal.uncertainty = None;
            let out = run(&nominal, &Options::of(&nominal), &no_progress)?;
            let analysis = out.analysis.as_ref().ok_or("no analysis")?;
            let cap = design_cap(&d, kappe::Context::default())?;
            let rows = kappe::analysis::reduced_against_form(&cap, analysis, &out.schedule)?;
            println!(
                "{name}: state | beta_reduced | beta_FORM | difference | re-solves reduced | FORM"
            );
            let (mut worst, mut rel) = (0.0_f64, 0.0_f64);
            let (mut sr, mut sf) = (0, 0);
            for r in &rows {
                let diff = r.beta_reduced - r.beta_form;
                println!(
                    "  {} | {:.7} | {:.7} | {diff:+.2e} | {} | {}",
                    r.index, r.beta_reduced, r.beta_form, r.solves_reduced, r.solves_form
                );
                worst = worst.max(diff.abs());
                rel = rel.max(diff.abs() / r.beta_form.abs().max(1.0));
                sr += r.solves_reduced;
                sf += r.solves_form;
            }
            println!(
                "{name}: {} states, largest |beta_reduced - beta_FORM| = {worst:.2e} \
                 ({rel:.2e} of max(1, beta)); re-solves {sr} reduced vs {sf} FORM \
                 ({:.2} vs {:.2} per state)",
                rows.len(),
                sr as f64 / rows.len().max(1) as f64,
                sf as f64 / rows.len().max(1) as f64
            );
            continue;
        }
        if delta {
            let mut nominal = d.clone();
            nominal.uncertainty = None;
            let out = run(&nominal, &Options::of(&nominal), &no_progress)?;
            let analysis = out.analysis.as_ref().ok_or("no analysis")?;
            let cap = design_cap(&d, kappe::Context::default())?;
            let pairs = kappe::analysis::first_order_against_form(&cap, analysis, &out.schedule)?;
            println!("{name}: state | beta_1 | beta_FORM | beta_FORM - beta_1");
            let (mut worst, mut ratio) = ((0.0_f64, 0), (0.0_f64, 0));
            for (i, b1, b) in &pairs {
                println!("  {i} | {b1:.4} | {b:.4} | {:+.4}", b - b1);
                if (b - b1).abs() > worst.0 {
                    worst = ((b - b1).abs(), *i);
                }
                // The measurement behind δ(β₁) (`SCREEN_DELTA_RATIO`).
                let r = (b - b1).abs() / b1.max(1.0);
                if r > ratio.0 {
                    ratio = (r, *i);
                }
            }
            println!(
                "{name}: {} states, largest |beta_FORM - beta_1| = {:.4} (state {}), largest \
                 |beta_FORM - beta_1|/max(1, beta_1) = {:.4} (state {})",
                pairs.len(),
                worst.0,
                worst.1,
                ratio.0,
                ratio.1
            );
            continue;
        }
        let mut nominal = d.clone();
        nominal.uncertainty = None;
        let cap = design_cap(&d, kappe::Context::default())?;
        let (mut dw, mut dc, mut rw, mut rc) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..repeats {
            let c0 = cpu_seconds().unwrap_or(f64::NAN);
            let out = run(&nominal, &Options::of(&nominal), &no_progress)?;
            dc.push(cpu_seconds().unwrap_or(f64::NAN) - c0);
            let analysis = out.analysis.as_ref().ok_or("no analysis")?;
            dw.push(analysis.timings.total);
            let (t0, c0) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
            let r = kappe::analysis::reliability(&cap, analysis, &out.schedule)?
                .ok_or("no reliability")?;
            rw.push(t0.elapsed().as_secs_f64());
            rc.push(cpu_seconds().unwrap_or(f64::NAN) - c0);
            last = Some(r);
        }
        let r = last.ok_or("no run")?;
        let (dw, dc, rw, rc) = (
            median(&mut dw),
            median(&mut dc),
            median(&mut rw),
            median(&mut rc),
        );
        println!(
            "{name} | {dw:.2} | {dc:.2} | {rw:.2} | {rc:.2} | {:.2} | {:.2} | {} | {} of {} | {:.4} | \
             {:.4e} | {} | {:.3} | {:?} | {}",
            rw / dw,
            rc / dc,
            r.components,
            r.states.iter().filter(|s| s.beta_first_order).count(),
            r.states.len(),
            r.beta,
            r.pf,
            r.sorm
                .as_ref()
                .map_or(String::new(), |s| format!("{:.4} / {:.4e}", s.beta, s.pf)),
            r.sorm.as_ref().map_or(f64::NAN, |s| s.seconds),
            r.sorm.as_ref().map(|s| &s.form_only),
            load_average()
        );
    }
    Ok(())
}
