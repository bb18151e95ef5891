//! The collapse check on the Wolfs 2018 cylinder (docs/collapse.md §4), printed as tables:
//! `cargo run --release -p kappe --example collapse [-- default|matrix|speed]`.
//!
//! * `default`: the failure layer with the default imperfection rule and the clamped base,
//!   next to the five observed failures (25, 27, 30, 31, 31).
//! * `matrix`: w0 = rule, 0, 1, 2, 5 mm, each with the clamped and the pinned base, and the
//!   as-printed start (`asprinted` alone: only those, docs/collapse.md §8).
//! * `speed`: per layer count 10, 20, 30, 40: one LBA solve against one collapse path (best of
//!   three), and `kappe buildability` of the 60-layer cylinder with the collapse check at every
//!   layer (wall-clock, CPU); then the same from the as-printed start, with the increments
//!   kept across counts (`run`) and with every count from scratch.
//! * `diag`: the 12-layer state (material check off, w0 = 0) on 24, 48, 96 segments and on
//!   48 segments split 2×2: λ_LBA, the critical factor of the co-rotational tangent linearised
//!   at the reference state (`kappe_fe::linearised_critical_factor`) and the perfect path's
//!   bifurcation (docs/collapse.md §4, the λ_c → λ_LBA check).
//! * `ccx [SEGMENTS] [LAYERS]`: the same state (default 48 segments, 12 layers) in CalculiX
//!   (needs `ccx` on PATH; checking only): S6 triangles on our facets (mid-side nodes on the
//!   straight edges), per-layer aged moduli, the base nodes' translations held; `*BUCKLE`, and
//!   `*STATIC, NLGEOM` (load control with automatic increments: the last converged load is
//!   the limit point, to the increment) on the perfect model and with our first mode as
//!   imperfection, w0 = 0.2 and 2 mm; next to Kappe's λ_LBA and collapse factors.

use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{cpu_seconds, load_average};

use kappe::commands::buildability::{BuildabilitySpec, EXAMPLE_TOML, Resolved, run};

fn spec(extra_checks: &str, nonlinear: &str) -> Result<Resolved, Box<dyn std::error::Error>> {
    let text = format!("{EXAMPLE_TOML}{extra_checks}\n[analysis.nonlinear]\n{nonlinear}\n");
    Ok(BuildabilitySpec::from_toml_str(&text)?)
}

fn failure(r: &Resolved) -> Result<String, Box<dyn std::error::Error>> {
    let t0 = Instant::now();
    let b = run(r, &|_| {})?;
    let secs = t0.elapsed().as_secs_f64();
    let at = |n: usize| {
        b.states
            .iter()
            .find(|s| s.layers == n)
            .and_then(|s| s.collapse.as_ref())
            .map_or("-".to_string(), |c| {
                format!("{:.3} {} (LBA {:.3})", c.factor, c.mode.name(), c.lba)
            })
    };
    let last = b.states.last();
    Ok(format!(
        "fails at {:?} by {:?}{}; n=25: {}; n=28: {}; ({secs:.1} s)",
        b.failure_layer,
        b.failure_mode.map(|m| m.name()),
        last.and_then(|s| s.collapse.as_ref())
            .map_or(String::new(), |c| format!(
                " [collapse {:.3} {} w0 {:.2} mm]",
                c.factor,
                c.mode.name(),
                c.w0 * 1e3
            )),
        at(25),
        at(28)
    ))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let what = std::env::args().nth(1).unwrap_or_else(|| "default".into());
    println!("Wolfs 2018 cylinder: observed failures 25, 27, 30, 31, 31 layers (mean 28.8)");
    if what == "default" || what == "matrix" {
        println!("  rule, clamped: {}", failure(&spec("", "")?)?);
    }
    if what == "matrix" {
        println!(
            "  rule, pinned: {}",
            failure(&spec("", "base = \"pinned\"")?)?
        );
        for w in [0.0, 1.0, 2.0, 5.0] {
            for base in ["clamped", "pinned"] {
                let r = spec(
                    "",
                    &format!("imperfection = {}\nbase = \"{base}\"", w * 1e-3),
                )?;
                println!("  w0 = {w} mm, {base}: {}", failure(&r)?);
            }
        }
        let r = spec("", "material = false")?;
        println!(
            "  rule, clamped, no material check along the path: {}",
            failure(&r)?
        );
    }
    if what == "matrix" || what == "asprinted" {
        // docs/collapse.md §8: the path from the as-printed shape (rule w0 on top), next to
        // the design start.
        for base in ["clamped", "pinned"] {
            let r = spec("", &format!("base = \"{base}\"\nstart = \"as_printed\""))?;
            println!("  rule, {base}, as-printed start: {}", failure(&r)?);
        }
        let r = spec("", "imperfection = 0.0\nstart = \"as_printed\"")?;
        println!("  w0 = 0, clamped, as-printed start: {}", failure(&r)?);
    }
    if what == "diag" {
        diag()?;
    }
    if what == "ccx" {
        let arg = |i: usize, d: usize| {
            std::env::args()
                .nth(i)
                .and_then(|v| v.parse().ok())
                .unwrap_or(d)
        };
        ccx_compare(arg(2, 48), arg(3, 12))?;
    }
    if what == "speed" {
        let r = spec("", "")?;
        println!(
            "  {:>4} {:>8} {:>10} {:>10} {:>8} {:>10} {:>10} {:>8} {:>6} {:>5} {:>9}",
            "n",
            "DOFs",
            "t_LBA [s]",
            "t_path [s]",
            "ratio",
            "CPU LBA",
            "CPU path",
            "CPU ×",
            "steps",
            "LDLt",
            "collapse"
        );
        let cpu = || cpu_seconds().unwrap_or(f64::NAN);
        for n in [10, 20, 30, 40] {
            let (mut t_lba, mut t_all) = (f64::INFINITY, f64::INFINITY);
            let (mut c_lba, mut c_all) = (f64::INFINITY, f64::INFINITY);
            let mut last = None;
            for _ in 0..3 {
                let (t0, c0) = (Instant::now(), cpu());
                let mut plain = r.clone();
                plain.spec.analysis = None;
                let _ = kappe::commands::buildability::check_layers(&plain, n)?;
                t_lba = t_lba.min(t0.elapsed().as_secs_f64());
                c_lba = c_lba.min(cpu() - c0);
                let (t1, c1) = (Instant::now(), cpu());
                let s = kappe::commands::buildability::check_layers(&r, n)?;
                t_all = t_all.min(t1.elapsed().as_secs_f64());
                c_all = c_all.min(cpu() - c1);
                last = s.collapse;
            }
            let dofs = 6 * r.segments * n;
            let (steps, ldlt, factor) =
                last.map_or((0, 0, f64::NAN), |c| (c.steps, c.factorizations, c.factor));
            println!(
                "  {n:>4} {dofs:>8} {t_lba:>10.3} {:>10.3} {:>8.1} {c_lba:>10.2} {:>10.2} {:>8.1} {steps:>6} {ldlt:>5} {factor:>9.5}",
                t_all - t_lba,
                (t_all - t_lba) / t_lba,
                c_all - c_lba,
                (c_all - c_lba) / c_lba
            );
        }
        let mut every = r.clone();
        every.spec.checks.stop_at_failure = false;
        let (c0, t0) = (cpu_seconds(), Instant::now());
        let b = run(&every, &|_| {})?;
        println!(
            "  60 layers, collapse at every layer: {:.1} s wall, {:.1} s CPU (load {}); fails first at {:?}",
            t0.elapsed().as_secs_f64(),
            cpu_seconds().zip(c0).map_or(f64::NAN, |(a, b)| a - b),
            load_average(),
            b.failure_layer
        );
        // The as-printed start: `run` keeps each count's increments for the next counts;
        // before session 8 every count solved its own k = 1…n again, as this loop does.
        let mut printed = spec("", "start = \"as_printed\"")?;
        printed.spec.checks.stop_at_failure = false;
        let (c0, t0) = (cpu_seconds(), Instant::now());
        let b = run(&printed, &|_| {})?;
        println!(
            "  60 layers, as-printed start, increments kept: {:.1} s wall, {:.1} s CPU (load {}); fails first at {:?}",
            t0.elapsed().as_secs_f64(),
            cpu_seconds().zip(c0).map_or(f64::NAN, |(a, b)| a - b),
            load_average(),
            b.failure_layer
        );
        let (c0, t0) = (cpu_seconds(), Instant::now());
        let mut prev = None;
        for n in 1..=printed.spec.object.max_layers {
            let (_, mode) =
                kappe::commands::buildability::check_layers_warm(&printed, n, prev.as_deref())?;
            if mode.is_some() {
                prev = mode;
            }
        }
        println!(
            "  60 layers, as-printed start, every count from scratch (one chain): {:.1} s wall, {:.1} s CPU (load {})",
            t0.elapsed().as_secs_f64(),
            cpu_seconds().zip(c0).map_or(f64::NAN, |(a, b)| a - b),
            load_average()
        );
    }
    Ok(())
}

/// The `diag` table (module docs).
fn diag() -> Result<(), Box<dyn std::error::Error>> {
    use kappe::commands::buildability::aged_object_shell;
    use kappe_fe::{BucklingOptions, Linearisation, PathOptions, buckling, nonlinear_path};
    let n = 12;
    println!(
        "  {:>4} {:>5} {:>7} {:>6} {:>9} {:>9} {:>9} {:>9} {:>8} {:>6}",
        "segs",
        "split",
        "DOFs",
        "local",
        "λ_LBA",
        "K_σ/LBA",
        "dK/LBA",
        "λ_path",
        "path/LBA",
        "LDLᵀ"
    );
    for (segs, split) in [(24, 1), (48, 1), (96, 1), (48, 2)] {
        let text = EXAMPLE_TOML.replace("# segments = 48", &format!("segments = {segs}"));
        let r = BuildabilitySpec::from_toml_str(&text)?;
        let (model, _, _) = aged_object_shell(&r, n);
        let model = kappe_fe::refine::split(&model, split).model;
        let lba = buckling(
            &model,
            &BucklingOptions {
                modes: 1,
                ..Default::default()
            },
        )?;
        let l = lba.factors[0];
        for local_geometric in [false, true] {
            let lin = |which| -> Result<f64, Box<dyn std::error::Error>> {
                Ok(kappe_fe::linearised_critical_factor(&model, l, 1e-5, which)?.lambda)
            };
            let sigma = lin(Linearisation::InitialStress { local_geometric })?;
            let deriv = lin(Linearisation::Derivative { local_geometric })?;
            let opt = PathOptions {
                initial_increment: 0.5 * l,
                lambda_max: 1.5 * l,
                local_geometric,
                ..Default::default()
            };
            let path = nonlinear_path(&model, &opt, &mut |_| std::ops::ControlFlow::Continue(()))?;
            let lp = path.limit.map_or(f64::NAN, |x| x.lambda);
            println!(
                "  {segs:>4} {split:>5} {:>7} {:>6} {l:>9.4} {:>9.4} {:>9.4} {lp:>9.4} {:>8.4} {:>6}",
                6 * model.nodes.len(),
                if local_geometric { "yes" } else { "no" },
                sigma / l,
                deriv / l,
                lp / l,
                path.stats.factorizations,
            );
        }
    }
    Ok(())
}

/// A ccx deck of `m` as S6 (mid-side nodes on the straight facet edges), one material and
/// shell section per distinct modulus, base translations held, self-weight along
/// `m.gravity` times `scale`, and `step` (the keyword lines of the step).
fn ccx_deck(m: &kappe_fe::ShellModel, scale: f64, step: &str) -> String {
    use kappe_fe::ccx;
    use std::collections::HashMap;
    use std::fmt::Write as _;
    let mut s = String::from("*HEADING\nstate\n");
    let mut nodes = m.nodes.clone();
    let fixed = m.fixed_mask();
    let mut held: Vec<bool> = fixed.iter().map(|f| f[0] && f[1] && f[2]).collect();
    // A clamped base holds the rotations too (ccx's shell node rotations: 4–6, a knot).
    let clamped = fixed.iter().any(|f| f[3] && f[4] && f[5]);
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut elems = Vec::new();
    for t in &m.triangles {
        let mut e = vec![t[0], t[1], t[2]];
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let id = *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (nodes[a], nodes[b]);
                nodes.push([
                    0.5 * (p[0] + q[0]),
                    0.5 * (p[1] + q[1]),
                    0.5 * (p[2] + q[2]),
                ]);
                held.push(held[a] && held[b]);
                nodes.len() - 1
            });
            e.push(id);
        }
        elems.push(e);
    }
    ccx::write_nodes(&mut s, &nodes);
    ccx::write_elements(
        &mut s,
        "S6",
        elems.iter().map(|e| e.iter().map(|n| n + 1).collect()),
    );
    let mut groups: Vec<(kappe_fe::Material, Vec<usize>)> = Vec::new();
    for e in 0..m.triangles.len() {
        let mat = m.material_of(e);
        match groups.iter_mut().find(|g| g.0 == mat) {
            Some(g) => g.1.push(e + 1),
            None => groups.push((mat, vec![e + 1])),
        }
    }
    ccx::write_supports(&mut s, (0..nodes.len()).filter(|&n| held[n]).map(|n| n + 1));
    s.push_str(if clamped {
        "*BOUNDARY\nSUP, 1, 6\n"
    } else {
        "*BOUNDARY\nSUP, 1, 3\n"
    });
    let t = m.thickness_of(0);
    for (k, (mat, ids)) in groups.iter().enumerate() {
        let _ = writeln!(s, "*ELSET, ELSET=E{k}");
        for c in ids.chunks(10) {
            let v: Vec<String> = c.iter().map(usize::to_string).collect();
            let _ = writeln!(s, "{}", v.join(", "));
        }
        let _ = write!(
            s,
            "*MATERIAL, NAME=M{k}\n*ELASTIC\n{:e}, {}\n*DENSITY\n{:e}\n\
             *SHELL SECTION, ELSET=E{k}, MATERIAL=M{k}\n{t}\n",
            mat.youngs_modulus,
            mat.poisson_ratio,
            mat.unit_weight / ccx::GRAVITY
        );
    }
    let g = m.gravity;
    let gn = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let _ = write!(
        s,
        "{step}*DLOAD\nEALL, GRAV, {:.8e}, {}, {}, {}\n*END STEP\n",
        ccx::GRAVITY * gn * scale,
        g[0] / gn,
        g[1] / gn,
        g[2] / gn
    );
    s
}

/// The limit load factor of a ccx NLGEOM run under `lam_max` × self-weight: the total time
/// of the last converged increment in the `.sta` file times `lam_max`, and the wall time.
fn ccx_limit(
    dir: &std::path::Path,
    job: &str,
    m: &kappe_fe::ShellModel,
    lam_max: f64,
) -> Result<(f64, f64, usize), Box<dyn std::error::Error>> {
    let step = "*STEP, NLGEOM, INC=2000\n*STATIC\n0.05, 1.0, 1e-7, 0.05\n";
    std::fs::write(dir.join(format!("{job}.inp")), ccx_deck(m, lam_max, step))?;
    let t0 = Instant::now();
    std::process::Command::new("ccx")
        .arg(job)
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "1")
        .stdout(std::process::Stdio::null())
        .status()?;
    let wall = t0.elapsed().as_secs_f64();
    let sta = std::fs::read_to_string(dir.join(format!("{job}.sta")))?;
    let mut last = 0.0;
    let mut incs = 0;
    for line in sta.lines() {
        let v: Vec<f64> = line
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
        if v.len() >= 7 {
            last = v[4];
            incs += 1;
        }
    }
    Ok((last * lam_max, wall, incs))
}

/// The `ccx` table (module docs).
fn ccx_compare(segs: usize, n: usize) -> Result<(), Box<dyn std::error::Error>> {
    use kappe::commands::buildability::aged_object_shell;
    use kappe_fe::{BucklingOptions, PathOptions, buckling, nonlinear_path, with_imperfection};
    let text = EXAMPLE_TOML.replace("# segments = 48", &format!("segments = {segs}"));
    let r = BuildabilitySpec::from_toml_str(&text)?;
    let (model, _, _) = aged_object_shell(&r, n);
    let dir = std::path::Path::new("target/ccx_collapse");
    std::fs::create_dir_all(dir)?;
    let lba = buckling(
        &model,
        &BucklingOptions {
            modes: 1,
            ..Default::default()
        },
    )?;
    let l = lba.factors[0];
    let (a, b) = kappe_fe::ccx::two_pass(dir, "buckle", |scale| {
        ccx_deck(&model, scale, "*STEP\n*BUCKLE\n2, 1e-6\n")
    })?;
    let ccx_l = b
        .or(Some(a))
        .and_then(|x| x.1.first().copied())
        .unwrap_or(f64::NAN);
    println!(
        "  {segs} segments, {n} layers: λ_LBA Kappe {l:.4}, ccx S6 *BUCKLE {ccx_l:.4} ({:+.2} %)",
        100.0 * (ccx_l / l - 1.0)
    );
    println!(
        "  {:>8} {:>10} {:>10} {:>8} {:>10} {:>6}",
        "w0 [mm]", "Kappe λ_c", "ccx λ_c", "ccx/K", "ccx [s]", "incs"
    );
    for w0 in [0.0, 0.2e-3, 2e-3] {
        let imp = with_imperfection(&model, &lba.modes[0], w0)?;
        let opt = PathOptions {
            initial_increment: 0.5 * l,
            lambda_max: 1.5 * l,
            ..Default::default()
        };
        let path = nonlinear_path(&imp, &opt, &mut |_| std::ops::ControlFlow::Continue(()))?;
        let lk = path.limit.map_or(f64::NAN, |x| x.lambda);
        let (lc, wall, incs) = ccx_limit(dir, "nlgeom", &imp, 1.5 * l)?;
        println!(
            "  {:>8.2} {lk:>10.4} {lc:>10.4} {:>8.4} {wall:>10.1} {incs:>6}",
            w0 * 1e3,
            lc / lk
        );
    }
    Ok(())
}
