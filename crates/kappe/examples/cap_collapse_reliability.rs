//! The collapse factor of the default cap as a limit state (issue 24), printed as a table:
//! `cargo run --release -p kappe --example cap_collapse_reliability -- [LENGTH] [SAMPLES] [METHOD]`
//! (defaults: the default cap's own length (0 keeps it), 10⁴ samples, `crude`; LENGTH in m for a
//! shorter cap; METHOD `importance` samples each state's table (continued linearly outside its
//! box, FORM's surface) around its design point, for P_f far below 1/N; the design's own Monte
//! Carlo stays crude).
//!
//! The default design (`kappe init`; robot planning off, which the reliability does not use)
//! with `[analysis.nonlinear]` (no time model: the limit point only, w0 by the rule) and three
//! uncertain inputs, chosen before this example was first run (docs/reliability.md, "Collapse
//! of a cap design"):
//! - the imperfection, a factor on the rule's w0, lognormal with mean 1 and **cov 0.5**: the
//!   order of the scatter of measured imperfection amplitudes of nominally equal shells (the
//!   imperfection data banks, e.g. Arbocz's, and reliability studies of imperfection-sensitive
//!   shells commonly use 0.3–0.5); no measurement of printed caps exists, and the rule's w0 is a
//!   code design value taken as the mean — the buildability example's choice;
//! - E lognormal, **cov 0.15**, and γ normal, **cov 0.02** (the project's illustrative
//!   `example_scatter`, not calibrated); both scale λ_c exactly and add no table axis.
//!
//! 1. `kappe design`'s run without and with the uncertainty: wall and CPU time.
//! 2. Per tabulated state: nominal λ_c, the collapse component's β (FORM), its P_f by FORM and
//!    SORM, and a crude Monte Carlo of the same table (SAMPLES, seed 1) with its Wilson 95 %
//!    interval; the print's P_f by FORM, SORM and the design's Monte Carlo.
//! 3. The grids and the tables against direct paths at every design point.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::analysis::collapse_reliability::CapCollapseModel;
use kappe::input::IMPERFECTION;
use kappe::{Design, Options, no_progress, run};
use kappe_reliability::{
    EvalError, Fallible, FormOptions, SamplingOptions, SormOptions, form, importance_sampling,
    monte_carlo, sorm,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let length: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.0);
    let samples: u64 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let method = std::env::args()
        .nth(3)
        .unwrap_or_else(|| "crude".to_owned());
    let mut base = Design::default();
    if length > 0.0 {
        base.cap.length = length;
    }
    base.robot.enabled = false;
    base.analysis.nonlinear = Some(kappe::input::NonlinearSpec {
        enabled: true,
        ..Default::default()
    });
    println!(
        "default cap (length {} m), [analysis.nonlinear] (limit point, w0 by the rule); {} \
         threads, load average {}",
        base.cap.length,
        rayon::current_num_threads(),
        load_average()
    );
    let (t0, c0) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
    let det = run(&base, &Options::of(&base), &no_progress)?;
    let (w0, cpu0) = (
        t0.elapsed().as_secs_f64(),
        cpu_seconds().unwrap_or(f64::NAN) - c0,
    );
    let checked: Vec<String> = det
        .analysis
        .as_ref()
        .map(|a| {
            a.states
                .iter()
                .filter_map(|s| {
                    s.collapse_factor.map(|f| {
                        format!(
                            "{} {f:.4} ({})",
                            s.index,
                            s.collapse_mode.map_or("?", |m| m.name())
                        )
                    })
                })
                .collect()
        })
        .unwrap_or_default();
    println!(
        "without [uncertainty]: {w0:.1} s wall, {cpu0:.1} s CPU; collapse checked: {checked:?}"
    );
    let mut d = base.clone();
    let text = format!(
        "[uncertainty]\n\"{IMPERFECTION}\" = {{ dist = \"lognormal\", cov = 0.5 }}\n\
         \"material.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}\n\
         \"material.specific_weight\" = {{ dist = \"normal\", cov = 0.02 }}\n\
         monte_carlo = {samples}\nmonte_carlo_method = \"crude\"\nseed = 1\n"
    );
    #[derive(serde::Deserialize)]
    struct U {
        uncertainty: kappe::input::UncertaintyTable,
    }
    d.uncertainty = Some(toml::from_str::<U>(&text)?.uncertainty);
    let (t1, c1) = (Instant::now(), cpu_seconds().unwrap_or(f64::NAN));
    let out = run(&d, &Options::of(&d), &no_progress)?;
    let (w1, cpu1) = (
        t1.elapsed().as_secs_f64(),
        cpu_seconds().unwrap_or(f64::NAN) - c1,
    );
    println!(
        "with [uncertainty]: {w1:.1} s wall, {cpu1:.1} s CPU ({:.1}× the CPU without); load \
         average {}",
        cpu1 / cpu0,
        load_average()
    );
    let (Some(a), Some(r)) = (&out.analysis, &out.reliability) else {
        return Err("no analysis or reliability".into());
    };
    let (Some(c), Some(tables)) = (&r.collapse, &r.collapse_tables) else {
        return Err("no collapse limit state".into());
    };
    println!(
        "tables: axes {:?}, exact {:?}, states {:?}, {} paths, {:.1} s wall; span D {:.4}; \
         mixed modes {:?}; bounded {:?}",
        c.parameters, c.exact, c.states, c.solves, c.seconds, c.span, c.mixed_modes, c.bounded
    );
    let table = d.uncertainty.as_ref().ok_or("no table")?;
    let model = table.model(&d)?;
    let m = CapCollapseModel::new(&out.cap, &a.options, &out.schedule, &model)?
        .ok_or("no collapse model")?;
    println!(
        "\n| state | nominal λ_c | β FORM | P_f FORM | P_f SORM | P_f Monte Carlo ({method}, N = {samples}) [95 %] |"
    );
    println!("|---|---|---|---|---|---|");
    for s in &tables.states {
        let Some(st) = r.states.iter().find(|x| x.index == s.index) else {
            continue;
        };
        let nominal = a
            .states
            .iter()
            .find(|x| x.index == s.index)
            .and_then(|x| x.collapse_factor)
            .unwrap_or(f64::NAN);
        let sm = model.drifted(&table.drifts(), st.t_hours)?;
        let mut g = Fallible(|x: &[f64]| tables.g(&m, s.index, x));
        let f = form(&sm, &mut g, &FormOptions::default())?;
        let so = sorm(&sm, &mut g, &f, &SormOptions::default())?;
        let fallbacks = std::sync::atomic::AtomicU64::new(0);
        let mut gs = Fallible(|x: &[f64]| {
            tables
                .sample_g(&m, s.index, x, &fallbacks)
                .map_err(|e| EvalError::from(e.to_string()))
        });
        let options = SamplingOptions::new(samples, 1);
        // Importance sampling evaluates the table continued linearly outside its box (FORM's
        // surface): samples around a design point near the box's edge would otherwise each
        // re-solve a path.
        let mut gc = Fallible(|x: &[f64]| tables.g(&m, s.index, x));
        let mc = if method == "importance" {
            importance_sampling(&sm, &mut gc, &f.u_star, &options)?
        } else {
            monte_carlo(&sm, &mut gs, &options)?
        };
        println!(
            "| {} | {nominal:.4} | {:.3} | {:.4e} | {:.4e} | {:.4e} [{:.4e}, {:.4e}] ({} re-solved) |",
            s.index,
            f.beta,
            f.pf,
            so.pf,
            mc.pf,
            mc.interval[0],
            mc.interval[1],
            fallbacks.load(std::sync::atomic::Ordering::Relaxed)
        );
    }
    if let Some(mc) = &r.monte_carlo {
        println!(
            "\nprint: FORM P_f {:.4e} (β {:.3}, governing {} {}), SORM {:?}; design Monte Carlo \
             (crude) {:.4e} [{:.4e}, {:.4e}] over states {:?}, {} re-solved",
            r.pf,
            r.beta,
            r.governing_state,
            r.governing_check,
            r.sorm.as_ref().map(|s| s.pf),
            mc.pf,
            mc.pf_interval[0],
            mc.pf_interval[1],
            mc.states,
            mc.resolved_samples
        );
    }
    for g in &c.grids {
        for ((p, f), mode) in g.points.iter().zip(&g.factors).zip(&g.modes) {
            println!("grid: state {} at {p:?}: λ_c {f:.4} ({mode})", g.state);
        }
    }
    for p in &c.design_points {
        println!(
            "design point: state {} β {:.3} at {:?}: table {:.5}, path {:.5} ({}), relative \
             {:.2e}, Δβ {:.3}",
            p.state,
            p.beta,
            p.design_point,
            p.table,
            p.path,
            p.mode,
            p.relative_error,
            p.beta_error
        );
    }
    Ok(())
}
