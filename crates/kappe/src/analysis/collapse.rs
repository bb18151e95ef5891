//! The collapse factor of a print state (docs/collapse.md): the geometrically nonlinear path of
//! the imperfect state under λ × its self-weight (`kappe_fe::nonlinear_path`: co-rotational
//! shells, arc length), with the aged material checked at every converged step in the deformed,
//! bent state. The collapse factor is the smallest λ at which the path reaches a limit point
//! (load maximum or bifurcation) or the material fails.
//!
//! **Imperfection.** The state's lowest linear buckling mode (the one the LBA check computed on
//! the same model with the same aged moduli) scaled to the amplitude w0
//! ([`crate::input::nonlinear::NonlinearSpec::amplitude`]), with one or both signs.
//!
//! **Material along the path.** Per element, the stresses at both faces z = ±t/2,
//! σ = N/t ± 6M/t² from the deformational part of the facet's motion
//! (`kappe_fe::deformed_resultants`), against the Mohr–Coulomb criterion and the bed-joint
//! sliding check of [`crate::analysis::green`] at the age of the element's younger layer. The
//! linear checks use the mid-surface (membrane) stress of the undeformed state; here the bending
//! that the imperfection and its growth cause is what matters, so the faces are checked. The
//! utilisation u(λ) is interpolated linearly between the last step with u ≤ 1 and the first
//! with u > 1 (from u(0) = 0): the λ where it crosses 1 is the material's collapse factor.
//!
//! **Path options.** First load increment λ₁ = ½·min(λ_LBA, 1/u_lin) (u_lin: the linear
//! strength utilisation at λ = 1, when known) so that the first step lands before either
//! bound; the path ends at λ_max = 1.5·λ_LBA (an imperfect state's limit point lies below
//! λ_LBA up to the co-rotational mesh's 1–3 % stiffer critical load, docs/nonlinear.md): a
//! path that gets there without a limit point is reported as `not_reached` with that λ.

use std::ops::ControlFlow;

use kappe_fe::{PathOptions, ShellModel, StopReason};
use serde::Serialize;

use crate::analysis::green::{ElementLayers, bed_traction, principal};
use crate::input::error::DesignError;
use crate::input::material::TimeModel;

/// What ended a state's path at its collapse factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CollapseMode {
    /// The path reached a limit point (load maximum or bifurcation): buckling.
    LimitPoint,
    /// Mohr–Coulomb strength failed at a face of the deformed shell.
    Strength,
    /// A bed joint slid in the deformed shell.
    Sliding,
    /// The state is a mechanism (collapse factor 0).
    Mechanism,
    /// The path reached λ_max = 1.5·λ_LBA without collapse: the factor is a lower bound.
    NotReached,
    /// The path stopped converging before any limit point: the factor is the last converged
    /// λ (a lower bound).
    NoConvergence,
}

impl CollapseMode {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            CollapseMode::LimitPoint => "limit_point",
            CollapseMode::Strength => "strength",
            CollapseMode::Sliding => "sliding",
            CollapseMode::Mechanism => "mechanism",
            CollapseMode::NotReached => "not_reached",
            CollapseMode::NoConvergence => "no_convergence",
        }
    }
}

/// Options of [`collapse_factor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollapseOptions {
    /// Imperfection amplitude w0, m (0: the perfect path).
    pub w0: f64,
    /// 1: the mode as given; 2: both signs, the lower factor kept.
    pub signs: usize,
    /// Check Mohr–Coulomb strength at the faces along the path.
    pub strength: bool,
    /// Check bed-joint sliding at the faces along the path.
    pub sliding: bool,
    /// Modified Newton and the secant predictor (docs/collapse.md §6): half the factorizations
    /// on a cap state's long path to its limit point; on a buildability object's short path,
    /// which a face failure ends within a few steps, they cost more iterations than they save
    /// (the 60-layer Wolfs cylinder: 28.0 → 32.6 s CPU with them), so the objects run full
    /// Newton.
    pub fast_path: bool,
    /// Stop a path at its first converged step at or above this load factor when it has met
    /// no limit point and no material failure there (`f64::INFINITY`: off). The state rule
    /// passes the least collapse factor found so far (docs/collapse.md §3): a state that gets
    /// past it cannot govern, and its collapse factor is reported as a lower bound
    /// (`not_reached`, the λ of that step).
    pub stop_above: f64,
}

/// The collapse of one state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Collapse {
    /// Collapse factor λ_c (multiplies the state's self-weight).
    pub factor: f64,
    /// What ended the path there.
    pub mode: CollapseMode,
    /// The linear buckling factor of the same model (the imperfection's source).
    pub lba: f64,
    /// Imperfection amplitude used, m.
    pub w0: f64,
    /// Sign of the mode that governs (+1 or −1).
    pub sign: f64,
    /// Largest translation relative to the imperfect geometry at the last converged step with
    /// λ ≤ 1 (m; 0 if the first step is beyond 1): the state's sag under its own weight.
    pub deflection_at_1: f64,
    /// Converged steps of the governing path.
    pub steps: usize,
    /// The governing path's load–deflection curve up to the collapse factor: (λ, largest
    /// translation relative to the imperfect geometry, m) per converged step, at most
    /// [`CURVE_POINTS`] points (the report's plot; not in `summary.json`).
    pub curve: Vec<[f64; 2]>,
    /// Tangent assemblies over all paths run.
    pub assemblies: usize,
    /// Numeric LDLᵀ factorizations of the tangent over all paths run (the benchmark's count;
    /// not in the outputs).
    #[serde(skip)]
    pub factorizations: usize,
}

/// Most points of [`Collapse::curve`]: enough to draw a smooth curve, few enough for the
/// report input.
pub const CURVE_POINTS: usize = 64;

/// The stop reason of a path that passed the other sign's collapse factor.
const ABOVE_OTHER_SIGN: &str = "above the other sign's collapse factor";

/// Every k-th point of `v` so at most `n` remain, always keeping the last.
fn thin(v: Vec<[f64; 2]>, n: usize) -> Vec<[f64; 2]> {
    if v.len() <= n || n < 2 {
        return v;
    }
    let step = v.len().div_ceil(n - 1);
    let last = v[v.len() - 1];
    let mut out: Vec<[f64; 2]> = v.into_iter().step_by(step).collect();
    if out.last() != Some(&last) {
        out.push(last);
    }
    out
}

/// The collapse factor of a state (module docs). `model` carries the aged moduli, supports and
/// load of the state (as its LBA check used them); `mode` is its lowest buckling mode per node
/// and `lba` its factor; `elements`/`ages`/`time` give each element's layer ages and strength.
#[allow(clippy::too_many_arguments)]
pub fn collapse_factor(
    model: &ShellModel,
    mode: &[[f64; 6]],
    lba: f64,
    linear_strength: Option<f64>,
    elements: &[ElementLayers],
    ages: &[f64],
    time: &TimeModel,
    options: &CollapseOptions,
) -> Result<Collapse, DesignError> {
    if !(lba.is_finite() && lba > 0.0) {
        return Ok(Collapse {
            factor: 0.0,
            mode: CollapseMode::Mechanism,
            lba,
            w0: options.w0,
            sign: 1.0,
            deflection_at_1: 0.0,
            steps: 0,
            curve: Vec::new(),
            assemblies: 0,
            factorizations: 0,
        });
    }
    let signs: &[f64] = if options.signs >= 2
        && options.w0 != 0.0
        && !mirror_antisymmetric(model, mode, options.w0, elements, ages)
    {
        &[1.0, -1.0]
    } else {
        &[1.0]
    };
    let mut best: Option<Collapse> = None;
    let mut assemblies = 0;
    let mut factorizations = 0;
    for &sign in signs {
        let c = one_path(
            model,
            mode,
            lba,
            linear_strength,
            elements,
            ages,
            time,
            options,
            sign,
            best.as_ref()
                .map_or(options.stop_above, |b| b.factor.min(options.stop_above)),
        )?;
        assemblies += c.assemblies;
        factorizations += c.factorizations;
        if best.as_ref().is_none_or(|b| c.factor < b.factor) {
            best = Some(c);
        }
        // A perfect path has no sign.
        if options.w0 == 0.0 {
            break;
        }
    }
    let mut best = best.ok_or_else(|| DesignError::FormFinding("collapse: no path run".into()))?;
    best.assemblies = assemblies;
    best.factorizations = factorizations;
    Ok(best)
}

/// Whether the state is its own mirror image and its mode antisymmetric about the mirror
/// (`kappe_fe::nonlinear::mirror_symmetry`): then the imperfect states X ± w0·φ are mirror
/// images of each other, so are their paths and material checks, and one sign gives the
/// collapse factor of both (docs/collapse.md §1). Nodes must mirror onto nodes within
/// 1e-3·w0 and the mode be antisymmetric within 1e-3 of its largest translation: the two
/// imperfect geometries then differ from exact mirror images by at most ~2e-3·w0, whose effect
/// on λ is far below the path's 1e-3 location tolerance (λ changes by well under 10 % over the
/// whole range 0…w0, §4). With the material check, mirrored elements must also have the same
/// younger layer age and mirrored bed normals.
fn mirror_antisymmetric(
    model: &ShellModel,
    mode: &[[f64; 6]],
    w0: f64,
    elements: &[ElementLayers],
    ages: &[f64],
) -> bool {
    let age = |e: &ElementLayers| ages.get(e.younger).copied();
    kappe_fe::nonlinear::mirror_symmetries(model, 1e-3 * w0.abs())
        .iter()
        .any(|m| {
            m.is_antisymmetric(mode, 1e-3)
                && elements.iter().enumerate().all(|(e, info)| {
                    let Some(other) = m.element_map.get(e).and_then(|&f| elements.get(f)) else {
                        return false;
                    };
                    let r = m.reflect(info.bed_normal);
                    let o = other.bed_normal;
                    let d = (r[0] * o[0] + r[1] * o[1] + r[2] * o[2]).abs();
                    age(info) == age(other) && (d - 1.0).abs() <= 1e-9
                })
        })
}

#[allow(clippy::too_many_arguments)]
fn one_path(
    model: &ShellModel,
    mode: &[[f64; 6]],
    lba: f64,
    linear_strength: Option<f64>,
    elements: &[ElementLayers],
    ages: &[f64],
    time: &TimeModel,
    options: &CollapseOptions,
    sign: f64,
    above: f64,
) -> Result<Collapse, DesignError> {
    let fe = |e: kappe_fe::FeError| DesignError::FormFinding(format!("collapse path: {e}"));
    let imperfect = kappe_fe::with_imperfection(model, mode, sign * options.w0).map_err(fe)?;
    let lam_mat = linear_strength
        .filter(|u| u.is_finite() && *u > 0.0)
        .map_or(f64::INFINITY, |u| 1.0 / u);
    let bound = lba.min(lam_mat);
    // A path that only has to pass `above` (the other sign's collapse factor, or the least
    // one of the state rule, docs/collapse.md §3) aims its first step 10 % past it, if that is
    // below 0.8 of the linear bound: far from its limit a path is nearly linear and lands
    // within a few per cent of the aimed λ, so one step often decides it. A step that crosses
    // a limit point on the way is cut as any other.
    let mut first = 0.5 * bound;
    if options.fast_path && above.is_finite() {
        first = first.max((1.1 * above).min(0.8 * bound));
    }
    let opt = PathOptions {
        initial_increment: first,
        lambda_max: 1.5 * lba,
        // docs/collapse.md §6: the same path at a fraction of the factorizations.
        modified_newton: options.fast_path,
        secant_predictor: options.fast_path,
        locate_by_eigenvalue: options.fast_path,
        reuse_iteration_factor: options.fast_path,
        ..Default::default()
    };
    let check_material = (options.strength || options.sliding) && time.strength.is_some();
    let age = |k: usize| ages.get(k).copied().unwrap_or(0.0);
    // (λ, utilisation, mode) of the last step at or below u = 1.
    let mut last = (0.0, 0.0);
    let mut material: Option<(f64, CollapseMode)> = None;
    let mut deflection_at_1 = 0.0;
    let mut material_error: Option<DesignError> = None;
    // Once a path has passed `above` (the other sign's collapse factor) before its own limit
    // point or material failure, its own collapse factor is higher: every later limit or
    // failure lies at a λ at least that of a step already passed (a load maximum's vertex is
    // at or above the steps around it, a bifurcation or a failure lies between a step and the
    // next higher one). It cannot govern, so it stops there.
    let beyond = |step: &kappe_fe::PathStep| {
        if step.lambda > above && !step.limit_passed {
            ControlFlow::Break(StopReason::Caller(ABOVE_OTHER_SIGN.into()))
        } else {
            ControlFlow::Continue(())
        }
    };
    let path = kappe_fe::nonlinear_path(&imperfect, &opt, &mut |step| {
        if step.lambda <= 1.0 {
            deflection_at_1 = step
                .displacements
                .iter()
                .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
                .fold(0.0, f64::max);
        }
        if !check_material {
            return beyond(step);
        }
        let res = match kappe_fe::deformed_resultants(&imperfect, &step.displacements) {
            Ok(r) => r,
            Err(e) => {
                material_error = Some(fe(e));
                return ControlFlow::Break(StopReason::Caller("resultants".into()));
            }
        };
        let (mut us, mut ul) = (0.0f64, 0.0f64);
        for (r, info) in res.iter().zip(elements) {
            let Some(mc) = time.mohr_coulomb(age(info.younger)) else {
                continue;
            };
            for top in [true, false] {
                let s = r.surface_stress(top);
                if options.strength {
                    let (s1, s2) = principal(s[0], s[1], s[2]);
                    us = us.max(mc.utilisation(s1, s2));
                }
                if options.sliding {
                    let (sn, tau) = bed_traction(&r.frame, s, info.bed_normal);
                    ul = ul.max(mc.sliding_utilisation(tau, sn));
                }
            }
        }
        let (u, m) = if us >= ul {
            (us, CollapseMode::Strength)
        } else {
            (ul, CollapseMode::Sliding)
        };
        // A step with λ below the last one lies past a load maximum, which the path reports
        // as its limit point (it comes first along the path).
        if u > 1.0 && step.lambda > last.0 {
            let (l0, u0) = last;
            let lam = l0 + (1.0 - u0) / (u - u0) * (step.lambda - l0);
            material = Some((lam.clamp(l0, step.lambda), m));
            ControlFlow::Break(StopReason::Caller(m.name().into()))
        } else if step.lambda > last.0 {
            last = (step.lambda, u);
            beyond(step)
        } else {
            beyond(step)
        }
    })
    .map_err(fe)?;
    if let Some(e) = material_error {
        return Err(e);
    }
    let last_lambda = path.steps.last().map_or(0.0, |s| s.lambda);
    let limit = path.limit.map(|l| l.lambda);
    let (factor, cmode) = match (limit, material) {
        (Some(l), Some((m, mm))) => {
            if m < l {
                (m, mm)
            } else {
                (l, CollapseMode::LimitPoint)
            }
        }
        (Some(l), None) => (l, CollapseMode::LimitPoint),
        (None, Some((m, mm))) => (m, mm),
        (None, None) => match path.stop {
            StopReason::LambdaMax => (last_lambda, CollapseMode::NotReached),
            StopReason::Caller(ref r) if r == ABOVE_OTHER_SIGN => {
                (last_lambda, CollapseMode::NotReached)
            }
            _ => (last_lambda, CollapseMode::NoConvergence),
        },
    };
    // The curve ends at the first step at or past the collapse factor (a path that turns back
    // at a limit point is drawn up to the step after it).
    let mut curve: Vec<[f64; 2]> = Vec::new();
    for st in &path.steps {
        let u = st
            .displacements
            .iter()
            .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
            .fold(0.0, f64::max);
        curve.push([st.lambda, u]);
        if st.lambda >= factor || st.limit_passed {
            break;
        }
    }
    Ok(Collapse {
        factor,
        mode: cmode,
        lba,
        w0: options.w0,
        sign,
        deflection_at_1,
        steps: path.steps.len(),
        curve: thin(curve, CURVE_POINTS),
        assemblies: path.stats.assemblies,
        factorizations: path.stats.factorizations,
    })
}

/// A state's linear upper bound on its collapse factor, for [`cap_states_to_run`]: its LBA
/// factor and the load factors 1/u at which its linear strength and sliding checks reach 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearBound {
    /// State index.
    pub state: usize,
    /// min(BLF, 1/u_strength, 1/u_sliding).
    pub bound: f64,
}

/// The knockdown floor of the state rule: the rule keeps running states while the next one's
/// linear bound times this floor lies below the least collapse factor found
/// (docs/collapse.md §3).
pub const KNOCKDOWN_FLOOR: f64 = 0.5;

/// The collapse factors of a cap's states (docs/collapse.md §3): the states in ascending order
/// of their linear bound, in batches of the worker count, until the next state's bound times
/// min(½, 0.8 × the least knockdown λ_c/bound seen) exceeds the least collapse factor found
/// (`all`: every state with a bound). `run(state)` computes one state's collapse.
pub fn cap_states_to_run(
    bounds: &[LinearBound],
    all: bool,
    run: &(dyn Fn(usize, f64) -> Result<Option<Collapse>, DesignError> + Sync),
) -> Result<Vec<(usize, Collapse)>, DesignError> {
    use rayon::prelude::*;
    let mut order: Vec<LinearBound> = bounds
        .iter()
        .copied()
        .filter(|b| b.bound.is_finite())
        .collect();
    order.sort_by(|a, b| a.bound.total_cmp(&b.bound));
    let batch = rayon::current_num_threads().max(1);
    let mut done: Vec<(usize, Collapse)> = Vec::new();
    let mut least = f64::INFINITY;
    let mut knockdown = 1.0f64;
    let mut next = 0;
    while next < order.len() {
        let floor = KNOCKDOWN_FLOOR.min(0.8 * knockdown);
        if !all && !done.is_empty() && order[next].bound * floor > least {
            break;
        }
        let hi = (next + batch).min(order.len());
        let part: Vec<(LinearBound, Option<Collapse>)> = order[next..hi]
            .par_iter()
            .map(|b| run(b.state, if all { f64::INFINITY } else { least }).map(|c| (*b, c)))
            .collect::<Result<_, DesignError>>()?;
        for (b, c) in part {
            if let Some(c) = c {
                least = least.min(c.factor);
                // A path stopped at `least` (or at λ_max) measured no knockdown, only a
                // lower bound on it: it must not lower the floor.
                if b.bound > 0.0 && c.mode != CollapseMode::NotReached {
                    knockdown = knockdown.min(c.factor / b.bound);
                }
                done.push((b.state, c));
            }
        }
        next = hi;
    }
    done.sort_by_key(|d| d.0);
    Ok(done)
}

/// A cap state's model and its linear buckling solve, as the collapse check starts from them
/// ([`cap_state_lba`]).
pub struct StateLba {
    /// The print state.
    pub state: crate::form::states::State,
    /// The state's shell (full print-layer mesh with the aged moduli).
    pub shell: crate::analysis::shell::StateShell,
    /// The LBA: factor and lowest mode; `None` when the state is a mechanism.
    pub lba: Option<(f64, Vec<[f64; 6]>)>,
    /// The LBA's own linear static solution of the same model under its weight (its
    /// prebuckling state); `None` with `lba`.
    pub linear: Option<kappe_fe::StaticResult>,
}

/// The analysis's own first-pass linear buckling solve of a state (`analysis::check`'s
/// `first_modes`): its lowest factor on the print-layer mesh and its mode 1 by (layer, index
/// in the layer). The collapse check takes them instead of solving the same model again where
/// the model is the same: no graded mesh, no green-state model (docs/collapse.md §3).
#[derive(Debug, Clone, Copy)]
pub struct FirstPass<'a> {
    /// The lowest factor of the print-layer mesh (not the mesh-converged estimate: the path
    /// runs on this mesh).
    pub factor: f64,
    /// Mode 1 ([`crate::analysis::buckling::ModeGuess`]).
    pub mode: &'a crate::analysis::buckling::ModeGuess,
}

/// The model of cap state `top` and its linear buckling solve (the first half of
/// [`cap_state_collapse`]; public so the benchmark can time the LBA alone). `None`: no shell
/// (one layer).
pub fn cap_state_lba(
    cap: &crate::form::cap::Cap,
    options: &crate::input::analysis::AnalysisOptions,
    green: Option<&crate::analysis::green::CapGreen>,
    top: usize,
) -> Result<Option<StateLba>, DesignError> {
    cap_state_lba_from(cap, options, green, top, None)
}

/// [`cap_state_lba`], taking the factor and mode from `first` instead of solving when they
/// were solved on the same model: no graded mesh, no green-state model (whose moduli and
/// solve the analysis does not keep), and the kept mode covers exactly this shell's nodes
/// ([`crate::analysis::buckling::mode_on_shell`]). Otherwise it solves, as
/// [`cap_state_lba`]. With `first` taken, [`StateLba::linear`] is `None` (the collapse check
/// needs it only with a green-state model).
pub fn cap_state_lba_from(
    cap: &crate::form::cap::Cap,
    options: &crate::input::analysis::AnalysisOptions,
    green: Option<&crate::analysis::green::CapGreen>,
    top: usize,
    first: Option<FirstPass<'_>>,
) -> Result<Option<StateLba>, DesignError> {
    let state = cap.state(top)?;
    let mat = crate::analysis::buckling::state_material(cap, options, top, green);
    let Ok(shell) = crate::analysis::shell::state_shell(&state, &mat, options.row_stride) else {
        return Ok(None);
    };
    let same_model = green.is_none() && options.grading.is_none();
    if let Some(first) = first.filter(|f| same_model && f.factor.is_finite() && f.factor > 0.0)
        && let Some(mode) = crate::analysis::buckling::mode_on_shell(&state, &shell, first.mode)
    {
        return Ok(Some(StateLba {
            state,
            shell,
            lba: Some((first.factor, mode)),
            linear: None,
        }));
    }
    let lba = match kappe_fe::buckling(
        &shell.model,
        &kappe_fe::BucklingOptions {
            modes: 1,
            // Far below any modelling error; a mode this converged is the imperfection's
            // shape to ~1e-8 of w0.
            tolerance: 1e-8,
            // As the LBA check (buckling.rs): the Sturm count that no lower factor was
            // missed only when the analysis asks for it. It costs one more LDLᵀ, about 40 %
            // of this solve (docs/collapse.md §6).
            sturm_check: options.sturm_check,
            ..Default::default()
        },
    ) {
        Ok(r) => r,
        Err(kappe_fe::FeError::Mechanism { .. }) => {
            return Ok(Some(StateLba {
                state,
                shell,
                lba: None,
                linear: None,
            }));
        }
        Err(e) => {
            return Err(DesignError::State {
                state: top,
                message: format!("buckling solve for the collapse check failed: {e}"),
            });
        }
    };
    let linear = Some(lba.static_result);
    let lba = lba
        .factors
        .first()
        .copied()
        .zip(lba.modes.into_iter().next());
    if lba.is_none() {
        return Ok(None);
    }
    Ok(Some(StateLba {
        state,
        shell,
        lba,
        linear,
    }))
}

/// The collapse of one cap state (top print index `top`) on its full shell mesh: its LBA
/// (mode 1 on the shell's nodes), the imperfection rule with the shell's thickness and the
/// state's height above its lowest node, and the path with the aged material (`green`: the
/// time model and ages; without one, the limit point only). `None`: no shell (one layer).
pub fn cap_state_collapse(
    cap: &crate::form::cap::Cap,
    options: &crate::input::analysis::AnalysisOptions,
    spec: &crate::input::nonlinear::NonlinearSpec,
    green: Option<&crate::analysis::green::CapGreen>,
    top: usize,
    above: f64,
) -> Result<Option<Collapse>, DesignError> {
    cap_state_collapse_from(cap, options, spec, green, top, above, None)
}

/// [`cap_state_collapse`] from the analysis's own first-pass LBA of the state where it is the
/// same model ([`cap_state_lba_from`]): no second linear buckling solve.
pub fn cap_state_collapse_from(
    cap: &crate::form::cap::Cap,
    options: &crate::input::analysis::AnalysisOptions,
    spec: &crate::input::nonlinear::NonlinearSpec,
    green: Option<&crate::analysis::green::CapGreen>,
    top: usize,
    above: f64,
    first: Option<FirstPass<'_>>,
) -> Result<Option<Collapse>, DesignError> {
    let Some(StateLba {
        state,
        shell,
        lba,
        linear,
    }) = cap_state_lba_from(cap, options, green, top, first)?
    else {
        return Ok(None);
    };
    let model = &shell.model;
    let Some((blf, mode)) = lba else {
        return Ok(Some(Collapse {
            factor: 0.0,
            mode: CollapseMode::Mechanism,
            lba: 0.0,
            w0: 0.0,
            sign: 1.0,
            deflection_at_1: 0.0,
            steps: 0,
            curve: Vec::new(),
            assemblies: 0,
            factorizations: 0,
        }));
    };
    let mode = &mode;
    let w0 = state_amplitude(spec, model);
    let start;
    // From the design, the path's model is the LBA's, and so is its linear static solution
    // (one factorization of K fewer per state).
    let (model, linear) = match spec.start {
        crate::input::nonlinear::PathStart::Design => (model, linear),
        crate::input::nonlinear::PathStart::AsPrinted => {
            let shift = cap_as_printed_shift(cap, options, green, top, &state, &shell)?;
            start = shifted(model, &shift);
            (&start, None)
        }
    };
    let (elements, ages, time) = match green {
        Some(g) => (
            g.element_layers(&shell),
            g.schedule.ages(top + 1),
            g.time.clone(),
        ),
        None => (Vec::new(), Vec::new(), cap.design.time_model()?),
    };
    let linear_strength = green
        .and_then(|g| {
            g.time
                .strength
                .is_some()
                .then(|| linear.or_else(|| kappe_fe::linear_static(model).ok()))
                .flatten()
                .map(|st| {
                    crate::analysis::green::stress_checks(
                        &st,
                        &elements,
                        &ages,
                        &g.time,
                        &Default::default(),
                    )
                })
        })
        .and_then(|(s, _)| s.map(|w| w.utilisation));
    collapse_factor(
        model,
        mode,
        blf,
        linear_strength,
        &elements,
        &ages,
        &time,
        &CollapseOptions {
            w0,
            signs: spec.signs.unwrap_or(2),
            strength: spec.material,
            sliding: spec.material,
            fast_path: true,
            stop_above: above,
        },
    )
    .map(Some)
}

/// The imperfection amplitude w0 of a cap state's path on its shell `model`: `spec`'s
/// `imperfection`, else the rule with the shell's thickness and the state's height above its
/// lowest node ([`crate::input::nonlinear::NonlinearSpec::amplitude`]). The collapse limit
/// state's factor on the rule's w0 multiplies this (`analysis::collapse_reliability`).
pub fn state_amplitude(spec: &crate::input::nonlinear::NonlinearSpec, model: &ShellModel) -> f64 {
    let (zmin, zmax) = model
        .nodes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[2]), b.max(p[2]))
        });
    spec.amplitude(model.thickness_of(0), (zmax - zmin).max(0.0))
}

/// `model` with every node moved by `shift` (m).
pub fn shifted(model: &ShellModel, shift: &[[f64; 3]]) -> ShellModel {
    let mut out = model.clone();
    for (p, d) in out.nodes.iter_mut().zip(shift) {
        (0..3).for_each(|k| p[k] += d[k]);
    }
    out
}

/// The deviation cap state `top`'s print has locked into its geometry (docs/collapse.md §8):
/// per shell node, its as-printed displacement (the sum of the increments of the states from
/// the one it was laid in up to `top`, `crate::analysis::asprinted`) minus the state's own
/// linear displacement under its whole weight. The path then starts stress-free from the
/// design moved by this and reaches, at λ = 1 in the linear range, the as-printed shape.
/// Nodes the as-printed pass does not track (column ends) stay at the design.
///
/// # Errors
/// An increment or the static solve fails.
pub fn cap_as_printed_shift(
    cap: &crate::form::cap::Cap,
    options: &crate::input::analysis::AnalysisOptions,
    green: Option<&crate::analysis::green::CapGreen>,
    top: usize,
    state: &crate::form::states::State,
    shell: &crate::analysis::shell::StateShell,
) -> Result<Vec<[f64; 3]>, DesignError> {
    use rayon::prelude::*;
    let increments = (0..=top)
        .into_par_iter()
        .map(|k| crate::analysis::asprinted::cap_increment(cap, options, green, k))
        .collect::<Result<Vec<_>, DesignError>>()?;
    let mut printed: std::collections::HashMap<crate::analysis::asprinted::NodeKey, [f64; 3]> =
        std::collections::HashMap::new();
    for inc in &increments {
        for (key, _, du) in &inc.nodes {
            let e = printed.entry(*key).or_insert([0.0; 3]);
            (0..3).for_each(|k| e[k] += du[k]);
        }
    }
    let keys = crate::analysis::asprinted::node_keys(state, shell);
    let own = kappe_fe::linear_static(&shell.model).map_err(|e| DesignError::State {
        state: top,
        message: format!("static solve for the as-printed start failed: {e}"),
    })?;
    Ok(as_printed_shift(
        keys.iter()
            .map(|k| k.and_then(|k| printed.get(&k).copied())),
        &own.displacements,
    ))
}

/// Per node: the as-printed displacement (None: not tracked, no shift) minus the node's own
/// linear displacement `own`.
pub fn as_printed_shift(
    printed: impl Iterator<Item = Option<[f64; 3]>>,
    own: &[[f64; 6]],
) -> Vec<[f64; 3]> {
    printed
        .zip(own)
        .map(|(p, d)| p.map_or([0.0; 3], |p| [p[0] - d[0], p[1] - d[1], p[2] - d[2]]))
        .collect()
}

/// The as-printed increments of a buildability object's layer counts, kept across the
/// object's layer counts within one run: increment k (the weight of the k-layer object's top
/// strip on that object, with the moduli at its ages) is the same for every n ≥ k, so a run
/// over n = 1…N solves N increments instead of N(N+1)/2.
#[derive(Debug, Default)]
pub struct ObjectIncrements(std::sync::Mutex<std::collections::HashMap<usize, Vec<[f64; 6]>>>);

/// The deviation an `n`-layer buildability object's print locks into its geometry, as
/// [`cap_as_printed_shift`]: `shell(k)` is the k-layer object (its nodes numbered row by row
/// from the bed, the same in every k), `ages(k)` its layers' ages, `own` the n-layer model
/// with its aged moduli. Layer count k adds the weight of its top strip (elements whose
/// younger layer is k − 1) on the k-layer object with the moduli at its ages; a node's
/// as-printed displacement is the sum over the counts it exists in.
///
/// # Errors
/// A static solve fails.
pub fn object_as_printed_shift(
    n: usize,
    shell: &(dyn Fn(usize) -> (ShellModel, Vec<ElementLayers>) + Sync),
    ages: &(dyn Fn(usize) -> Vec<f64> + Sync),
    time: &TimeModel,
    own: &ShellModel,
) -> Result<Vec<[f64; 3]>, DesignError> {
    object_as_printed_shift_cached(n, shell, ages, time, own, &ObjectIncrements::default())
}

/// [`object_as_printed_shift`] with the increments taken from, and added to, `cache` (which
/// must belong to the same object, schedule and time model).
///
/// # Errors
/// A static solve fails.
pub fn object_as_printed_shift_cached(
    n: usize,
    shell: &(dyn Fn(usize) -> (ShellModel, Vec<ElementLayers>) + Sync),
    ages: &(dyn Fn(usize) -> Vec<f64> + Sync),
    time: &TimeModel,
    own: &ShellModel,
    cache: &ObjectIncrements,
) -> Result<Vec<[f64; 3]>, DesignError> {
    use rayon::prelude::*;
    let fe = |e: kappe_fe::FeError| DesignError::FormFinding(format!("as-printed start: {e}"));
    let known = |k: usize| cache.0.lock().ok().and_then(|m| m.get(&k).cloned());
    let increments = (1..=n)
        .into_par_iter()
        .map(|k| {
            if let Some(du) = known(k) {
                return Ok(du);
            }
            let (mut m, layers) = shell(k);
            crate::analysis::green::set_aged_moduli(&mut m, &layers, &ages(k), time);
            m.materials = (0..m.triangles.len())
                .map(|e| {
                    let mut mat = m.material_of(e);
                    if layers.get(e).is_none_or(|l| l.younger + 1 != k) {
                        mat.unit_weight = 0.0;
                    }
                    mat
                })
                .collect();
            let du = kappe_fe::linear_static(&m)
                .map(|r| r.displacements)
                .map_err(fe)?;
            if let Ok(mut c) = cache.0.lock() {
                c.insert(k, du.clone());
            }
            Ok(du)
        })
        .collect::<Result<Vec<_>, DesignError>>()?;
    let mut printed = vec![[0.0; 3]; own.nodes.len()];
    for du in &increments {
        for (p, d) in printed.iter_mut().zip(du) {
            (0..3).for_each(|c| p[c] += d[c]);
        }
    }
    let own = kappe_fe::linear_static(own).map_err(fe)?;
    Ok(as_printed_shift(
        printed.into_iter().map(Some),
        &own.displacements,
    ))
}
