//! The as-printed shape (docs/as-printed.md): a column built in stages under its own weight
//! against its closed forms (staged, all at once, infinitely stiffening), the equilibrium of
//! every increment, and the cap's as-printed pass.

use kappe::analysis::{Increment, NodeKey, accumulate, increment};
use kappe_fe::{Material, NodalLoad, ShellModel, Support};

const H: f64 = 0.01; // layer height, m
const W: f64 = 0.04; // column width, m
const T: f64 = 0.02; // wall thickness, m
const E: f64 = 1.0e6; // Pa
const GAMMA: f64 = 2.0e4; // N/m³

/// A vertical wall strip of `k` layers on a clamped base row (rows z = 0, h, …, k·h, two nodes
/// each), strip i between rows i−1 and i with modulus `e(i)`; `loads[j]` is the downward force
/// on row j, split equally between its two nodes. ν = 0, so the strip is a bar: a uniform
/// axial stress in every strip is the exact solution, which the constant-strain membrane
/// represents exactly (its consistent nodal forces are equal on the two nodes of a row).
fn column(k: usize, e: &dyn Fn(usize) -> f64, loads: &[f64]) -> (ShellModel, Vec<Option<NodeKey>>) {
    let mut nodes = Vec::new();
    let mut keys = Vec::new();
    for j in 0..=k {
        for (c, x) in [0.0, W].into_iter().enumerate() {
            nodes.push([x, 0.0, j as f64 * H]);
            keys.push(Some((j as i32, c)));
        }
    }
    let mut triangles = Vec::new();
    let mut materials = Vec::new();
    for i in 1..=k {
        let (a0, a1, b0, b1) = (2 * i - 2, 2 * i - 1, 2 * i, 2 * i + 1);
        triangles.push([a0, a1, b0]);
        triangles.push([a1, b1, b0]);
        for _ in 0..2 {
            materials.push(Material {
                youngs_modulus: e(i),
                poisson_ratio: 0.0,
                unit_weight: 0.0,
            });
        }
    }
    let mut model = ShellModel::new(nodes, triangles, T, materials[0]);
    model.materials = materials;
    model.supports = vec![Support::clamped(0), Support::clamped(1)];
    model.nodal_loads = loads
        .iter()
        .enumerate()
        .flat_map(|(j, f)| {
            (0..2).map(move |c| NodalLoad {
                node: 2 * j + c,
                force: [0.0, 0.0, -0.5 * f],
                moment: [0.0; 3],
            })
        })
        .collect();
    (model, keys)
}

/// Weight of one layer (one strip), N.
fn layer_weight() -> f64 {
    GAMMA * T * W * H
}

/// The stages of an `n`-layer column: stage k adds strip k, its weight lumped half on row k−1
/// and half on row k (the lumping of the shell's self-weight), strip i at stage k with
/// modulus `e(i, k)`.
fn staged(n: usize, e: &dyn Fn(usize, usize) -> f64) -> Vec<Increment> {
    (1..=n)
        .map(|k| {
            let mut loads = vec![0.0; k + 1];
            loads[k - 1] = 0.5 * layer_weight();
            loads[k] = 0.5 * layer_weight();
            let (m, keys) = column(k, &|i| e(i, k), &loads);
            increment(&m, &keys).expect("stage solve")
        })
        .collect()
}

/// Downward deviation of row j after the last state (mean of its two nodes).
fn row_sag(inc: &[Increment], j: usize) -> f64 {
    let mut u = 0.0;
    for s in inc {
        for (key, _, du) in &s.nodes {
            if key.0 == j as i32 {
                u -= 0.5 * du[2];
            }
        }
    }
    u
}

#[test]
fn staged_column_matches_its_closed_form() {
    // Row j (height z_j = j·h, laid in stage j) of an N-layer column, constant E: stage j
    // sinks it by W(z_j − h/2)/EA (the new strip's weight through the column below, half of
    // it through the new strip), every later stage by W z_j/EA. With W/EA = γh/E:
    //   δ_j = γ/E · [(H − z_j) z_j + h (z_j − h/2)],  H = N h  (docs/as-printed.md §3),
    // the continuous γ(H − z)z/E plus the lumping's O(h) term. The all-at-once deflection
    // γ/E (Hz − z²/2) (+ lumping) is larger by γz²/2E: the sag under its own layers below
    // happened before a row was laid.
    let n = 12;
    let inc = staged(n, &|_, _| E);
    let total_h = n as f64 * H;
    let mut worst: f64 = 0.0;
    for j in 1..=n {
        let z = j as f64 * H;
        let exact = GAMMA / E * ((total_h - z) * z + H * (z - 0.5 * H));
        let got = row_sag(&inc, j);
        worst = worst.max((got - exact).abs() / exact);
    }
    // The discrete model is exact for this field; 1e-9 leaves room for the Cholesky solve's
    // round-off on ~80 DOFs (condition ~1e6 from the drilling springs).
    assert!(worst < 1e-9, "largest relative error {worst:e}");
    // The staged shape differs from the all-at-once shape: the top row sinks only by the
    // column's shortening under the top layer's weight, γh(H − h/2)/E, the all-at-once top
    // by γH²/2E, about 6 times more here; 0.25 bounds the ratio 2h/H − h²/H² ≈ 0.16.
    let all_at_once_top = GAMMA / E * 0.5 * total_h * total_h;
    assert!(row_sag(&inc, n) < 0.25 * all_at_once_top);
    // accumulate() finds the largest deviation where the closed form peaks: between H/2 and
    // H/2 + h (δ_j is a parabola in z_j with its vertex at (H + h)/2).
    let a = accumulate(&inc);
    let layer = a.layer.expect("a deviation");
    assert!(
        (6..=7).contains(&layer),
        "largest deviation in row {layer}: {a:?}"
    );
    assert_eq!(a.state, Some(n - 1));
    // Every stage's increment is in equilibrium: Σ reactions = −Σ loads to round-off.
    assert!(a.max_residual < 1e-10, "residual {}", a.max_residual);
}

#[test]
fn one_stage_is_the_linear_static_deflection() {
    // The whole column in one stage: the sum of one increment is the linear static solution,
    // whose closed form is the bar under its lumped weights: the strip between rows i−1 and i
    // carries W(N − i) + W/2.
    let n = 8;
    let mut loads = vec![layer_weight(); n + 1];
    loads[0] = 0.5 * layer_weight();
    loads[n] = 0.5 * layer_weight();
    let (m, keys) = column(n, &|_| E, &loads);
    let inc = vec![increment(&m, &keys).expect("solve")];
    let ea = E * T * W;
    let mut exact = 0.0;
    for j in 1..=n {
        exact += layer_weight() * ((n - j) as f64 + 0.5) * H / ea;
        let got = row_sag(&inc, j);
        // Same round-off bound as the staged test.
        assert!(
            (got / exact - 1.0).abs() < 1e-9,
            "row {j}: {got} vs {exact}"
        );
    }
    let a = accumulate(&inc);
    assert!((a.deviation_m / exact - 1.0).abs() < 1e-9);
    assert_eq!(a.layer, Some(n as i32));
}

#[test]
fn an_infinitely_stiffening_material_freezes_the_earlier_layers() {
    // Each strip is soft (E) in the stage it is laid and 10⁹ E afterwards: a row only moves
    // in its own stage, by the new strip's shortening under half its weight, W h / 2EA, and
    // never again; the rows below it no longer move at all.
    let n = 10;
    let inc = staged(n, &|i, k| if i == k { E } else { 1e9 * E });
    let own = layer_weight() * H / (2.0 * E * T * W);
    for j in 1..=n {
        let got = row_sag(&inc, j);
        // The stiff strips still shorten by 1e-9 of their soft value per later stage (≤ n of
        // them): 1e-7 relative bounds that and the round-off.
        assert!((got / own - 1.0).abs() < 1e-7, "row {j}: {got} vs {own}");
    }
    // For contrast, the constant material keeps sinking the lower rows (the test can fail).
    let soft = staged(n, &|_, _| E);
    assert!(row_sag(&soft, 1) > 5.0 * own);
}

#[test]
fn the_cap_as_printed_pass_reports_every_state() {
    // A short cap keeps the test quick (every state is solved: the deviation accumulates).
    let design = kappe::Design::from_toml_str("[cap]\nlength = 0.2\n").expect("design");
    let cap = kappe::design_cap(&design, kappe::Context::default()).expect("cap");
    // The buckling check of the final state only: the as-printed pass runs every state anyway.
    let mut options = design.analysis.clone();
    options.states = "every:1000".parse().expect("selection");
    options.converged_blf = false;
    let a = kappe::analysis::analyze(&cap, &options, kappe::analysis::Request::default())
        .expect("analysis");
    let p = a.as_printed.as_ref().expect("as-printed pass");
    assert_eq!(p.states.len(), cap.states.len());
    // Equilibrium of every increment (Σ R = −Σ f): 1e-9 relative, the sparse solve's
    // round-off on ~10⁴ DOFs.
    assert!(p.max_residual < 1e-9, "residual {}", p.max_residual);
    // The largest deviation over the print is the largest per-state value, and the
    // constraint row reports it with its state.
    let top = p.states.iter().map(|s| s.deviation_m).fold(0.0, f64::max);
    assert_eq!(p.deviation_m, top);
    assert!(top > 0.0 && top.is_finite());
    let row = a
        .constraints
        .iter()
        .find(|c| c.name == "deviation_max")
        .expect("deviation_max row");
    assert_eq!(row.worst, Some(top));
    assert_eq!(row.state, p.state);
    assert_eq!(row.limit, design.deviation_max());
    // Deterministic: a second pass (new hash maps, other thread timing) gives the same bits.
    let again = kappe::analysis::cap_as_printed(&cap, &options, None, &|| Ok(())).expect("again");
    assert_eq!(&again, p);
    // A crown never sinks by more than the largest deviation.
    for s in &p.states {
        assert!(s.crown_sag_m <= s.deviation_m + 1e-15, "{s:?}");
    }
    // A stiffer material (every layer 4× stiffer) deviates 4× less: linear per increment.
    let stiff = kappe::Design::from_toml_str(&format!(
        "[cap]\nlength = 0.2\n[material]\nyoungs_modulus = {}\n",
        4.0 * design.material.youngs_modulus
    ))
    .expect("design");
    let cap4 = kappe::design_cap(&stiff, kappe::Context::default()).expect("cap");
    let p4 =
        kappe::analysis::cap_as_printed(&cap4, &options, None, &|| Ok(())).expect("as-printed");
    // Same geometry, K scaled by 4: the deviation scales by 1/4 to round-off (1e-9).
    assert!(
        (4.0 * p4.deviation_m / top - 1.0).abs() < 1e-9,
        "{} vs {top}",
        p4.deviation_m
    );
}

/// The analysis solves each buckled state's as-printed increment inside its buckling solve's
/// factorization of K (`BucklingRequest::printed`) instead of factorizing K again; the pass must
/// be exactly the stand-alone one (`cap_as_printed`: every increment its own linear static
/// solve), bit for bit, on the full print-layer mesh and on a graded one (whose states the pass
/// still solves itself).
#[test]
fn the_buckling_solves_give_the_as_printed_increments_exactly() {
    let design = kappe::Design::from_toml_str("[cap]\nlength = 0.2\n").expect("design");
    let cap = kappe::design_cap(&design, kappe::Context::default()).expect("cap");
    let mut options = design.analysis.clone();
    // The first pass only: the mesh-error pass does not touch the increments.
    options.converged_blf = false;
    assert!(kappe::analysis::shares_mesh(&options));
    let alone =
        kappe::analysis::cap_as_printed(&cap, &options, None, &|| Ok(())).expect("as-printed");
    let a = kappe::analysis::analyze(&cap, &options, kappe::analysis::Request::default())
        .expect("analysis");
    assert_eq!(a.as_printed.as_ref(), Some(&alone));
    // Every state was buckled, so every increment but the bed layer's came from a buckling
    // solve (the test would pass vacuously if none did).
    let buckled = a
        .states
        .iter()
        .filter(|s| s.buckling == kappe::analysis::BucklingStatus::Analysed)
        .count();
    assert!(buckled + 1 >= cap.states.len(), "{buckled} buckled");
    // A row stride thins the buckling mesh alone: the pass keeps its own mesh and solves
    // every state.
    let mut strided = options.clone();
    strided.row_stride = 2;
    assert!(!kappe::analysis::shares_mesh(&strided));
    let g = kappe::analysis::analyze(&cap, &strided, kappe::analysis::Request::default())
        .expect("strided analysis");
    assert_eq!(g.as_printed.as_ref(), Some(&alone));
    // A graded mesh is shared: the buckling solves give the pass's graded increments (filled
    // in over the dropped nodes) bit for bit.
    let mut graded = options.clone();
    graded.grading = Some(short_grading());
    assert!(kappe::analysis::shares_mesh(&graded));
    let alone_graded =
        kappe::analysis::cap_as_printed(&cap, &graded, None, &|| Ok(())).expect("as-printed");
    let g = kappe::analysis::analyze(&cap, &graded, kappe::analysis::Request::default())
        .expect("graded analysis");
    assert_eq!(g.as_printed.as_ref(), Some(&alone_graded));
}

/// A grading that thins this file's short caps (the default keeps the newest 32 layers whole,
/// all of a 0.2 m cap's centre section).
fn short_grading() -> kappe::analysis::Grading {
    kappe::analysis::Grading {
        fine: 8,
        zone_rows: 2,
        max_stride: 8,
        ..Default::default()
    }
}

/// On a graded mesh the increments are solved on the kept rows and filled in
/// (`asprinted::fill_graded`); the shape must stay the full mesh's. Per state, the largest
/// deviation and the crown sag with the default grading against the full print-layer mesh
/// within 0.5 %, the tolerance Kappe holds every mesh-dependent factor to (`blf_tolerance`):
/// measured 3e-5 on this 0.4 m cap and at most 0.34 % on the default cap, the 1.2 m cap and a
/// 1.5 m × 4 m bay (docs/as-printed.md §5). The filling itself is checked exactly in
/// `asprinted::tests` (a linear field is reproduced at every dropped node).
#[test]
fn a_graded_mesh_keeps_the_as_printed_shape_of_the_full_mesh() {
    let design = kappe::Design::from_toml_str("[cap]\nlength = 0.4\n").expect("design");
    let cap = kappe::design_cap(&design, kappe::Context::default()).expect("cap");
    let full = design.analysis.clone();
    let mut graded = full.clone();
    graded.grading = Some(kappe::analysis::Grading::default());
    let f = kappe::analysis::cap_as_printed(&cap, &full, None, &|| Ok(())).expect("full");
    let g = kappe::analysis::cap_as_printed(&cap, &graded, None, &|| Ok(())).expect("graded");
    let dropped = (0..cap.states.len())
        .filter(|&k| {
            let s = cap.state(k).expect("state");
            kappe::analysis::graded_state(&s, &kappe::analysis::Grading::default())
                .network
                .nodes
                .len()
                < s.network.nodes.len()
        })
        .count();
    assert!(dropped > 10, "the grading thins only {dropped} states");
    let mut worst = 0.0f64;
    for (a, b) in g.states.iter().zip(&f.states) {
        for (x, y) in [
            (a.deviation_m, b.deviation_m),
            (a.crown_sag_m, b.crown_sag_m),
        ] {
            if y > 1e-7 {
                worst = worst.max((x / y - 1.0).abs());
            }
        }
    }
    assert!(worst < 0.005, "{worst}");
    assert!(f.deviation_m > 1e-4, "a sag to compare: {}", f.deviation_m);
}

#[test]
fn a_deviation_above_deviation_max_fails_the_design_with_its_levers() {
    // 1 µm is far below the short cap's sag (≈ 1 mm on the default cap): the row must fail,
    // every state past the first sag fails, and the verdict names the constraint.
    let design =
        kappe::Design::from_toml_str("[cap]\nlength = 0.2\n[constraints]\ndeviation_max = 1e-6\n")
            .expect("design");
    assert_eq!(design.deviation_max(), 1e-6);
    let cap = kappe::design_cap(&design, kappe::Context::default()).expect("cap");
    let mut options = design.analysis.clone();
    options.states = "every:1000".parse().expect("selection");
    options.converged_blf = false;
    let a = kappe::analysis::analyze(&cap, &options, kappe::analysis::Request::default())
        .expect("analysis");
    assert!(!a.ok);
    let row = a
        .constraints
        .iter()
        .find(|c| c.name == "deviation_max")
        .expect("row");
    assert!(!row.pass && row.element.starts_with("layer "), "{row:?}");
    let report = a.report();
    assert!(report.contains("deviation_max FAIL"), "{report}");
    assert!(report.contains(kappe::analysis::levers("deviation_max")));
    assert!(a.states.iter().any(|s| !s.ok));
    let v = kappe::verdict::verdict(&cap, Some(&a), Default::default());
    assert!(v.failures.iter().any(|f| matches!(
        f,
        kappe::verdict::Failure::Constraint { name, .. } if name == "deviation_max"
    )));
    // A limit that is not a positive length is rejected, naming the field.
    let e = kappe::Design::from_toml_str("[constraints]\ndeviation_max = -0.001\n")
        .expect_err("negative limit");
    assert!(e.to_string().contains("constraints.deviation_max"), "{e}");
}

#[test]
fn the_collapse_curve_runs_up_to_the_collapse_factor() {
    // The report's load–deflection curve (docs/collapse.md): the Wolfs cylinder example at 20
    // layers on 24 segments (quick), the material check off (the path ends at its limit point).
    use kappe::commands::buildability::{BuildabilitySpec, EXAMPLE_TOML, check_layers};
    let text = EXAMPLE_TOML.replace("# segments = 48", "segments = 24");
    let r = BuildabilitySpec::from_toml_str(&format!(
        "{text}\n[analysis.nonlinear]\nmaterial = false\n"
    ))
    .expect("spec");
    let c = check_layers(&r, 20)
        .expect("layers")
        .collapse
        .expect("collapse");
    let curve = &c.curve;
    assert!(!curve.is_empty() && curve.len() <= kappe::analysis::CURVE_POINTS);
    // Every point but the last lies below the collapse factor: the curve stops at the first
    // step at or past it.
    for p in &curve[..curve.len() - 1] {
        assert!(p[0] < c.factor && p[1] >= 0.0, "{p:?} vs {}", c.factor);
    }
    // The curve's deflection at the last step with λ ≤ 1 is the path's own sag at λ ≤ 1
    // (`deflection_at_1`, computed separately along the path), when the curve is not thinned.
    if c.steps <= kappe::analysis::CURVE_POINTS
        && let Some(p) = curve.iter().rev().find(|p| p[0] <= 1.0)
    {
        assert_eq!(p[1], c.deflection_at_1);
    }
}
