//! [`analyze`]: every print state of a cap against every constraint (σ_min, σ_max, BLF_min,
//! l_o,max), and the constraint report (see the [module docs](super)).

use kappe_fe::clock::Instant;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use super::asprinted::Increment;
use super::bending::BendingSummary;
use super::buckling::{
    BucklingRequest, BucklingStatus, ModeGuess, NetworkMode, StateBuckling, state_buckling,
    state_material,
};
use crate::form::cap::Cap;
use crate::form::stresses::{STRESS_REL_TOL, StressExtremes};
use crate::input::analysis::AnalysisOptions;
use crate::input::context::Context;
use crate::input::error::DesignError;

/// Consecutive states per warm-started run: each run's first state starts cold, so longer runs
/// save more Lanczos steps; shorter ones balance the cores better. 16: the default cap's 113
/// states in 8 runs instead of 4, so the last run no longer finishes alone (four more cold
/// starts, about five Lanczos steps each).
const WARM_RUN: usize = 16;

/// The analysis of one print state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StateAnalysis {
    /// State index (0 = first layer printed).
    pub index: usize,
    /// Id of the top layer.
    pub top_layer: i32,
    /// Lowest positive buckling factor (None: not analysed, no shell or mechanism): the
    /// converged estimate when `AnalysisOptions::converged_blf` (the safe end of its bracket,
    /// docs/convergence.md), else the shell mesh's own factor.
    pub blf: Option<f64>,
    /// The print-layer shell mesh's own factor (the `blf` of Kappe before issue 23), when the
    /// mesh error is controlled.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blf_mesh: Option<f64>,
    /// Relative error estimate of `blf`: the converged factor lies in
    /// [blf, blf·(1 + blf_error)] (docs/convergence.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blf_error: Option<f64>,
    /// `blf_error ≤ AnalysisOptions::blf_tolerance`. A state left unconverged cannot govern:
    /// its safe-side factor is above the governing state's converged bracket.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blf_converged: Option<bool>,
    /// Splits per edge of the finest mesh solved (2: the print-layer mesh and its 2×2 split).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blf_split: Option<usize>,
    /// The split mesh was not solved in this state: its correction is interpolated between
    /// solved neighbours (`crate::analysis::convergence`; such a state cannot govern).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blf_interpolated: Option<bool>,
    /// All factors found (ascending).
    pub blf_modes: Vec<f64>,
    /// What the buckling analysis did.
    pub buckling: BucklingStatus,
    /// Most negative element normal stress, Pa (0 if none).
    pub max_compression_stress_pa: f64,
    /// Largest element normal stress, Pa (0 if none).
    pub max_tension_stress_pa: f64,
    /// Largest |l_o| over the printed layers, m.
    pub max_overhang_m: f64,
    /// Every checked constraint holds in this state.
    pub ok: bool,
    /// If the shell model is a mechanism: where.
    pub mechanism: Option<String>,
    /// Shell nodes (0 if none).
    pub shell_nodes: usize,
    /// Seconds spent on the FE model of this state (build + solve).
    pub fe_seconds: f64,
    /// Worst Mohr–Coulomb utilisation of the shell's membrane stresses (only with a strength
    /// model in `[material.time]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strength_utilisation: Option<f64>,
    /// Worst bed-joint sliding utilisation (only with a strength model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sliding_utilisation: Option<f64>,
    /// Age of the oldest printed layer at this state, s (only with a time model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bottom_age_s: Option<f64>,
    /// Collapse factor of the imperfect state (`[analysis.nonlinear]`; only the states the
    /// state rule ran, docs/collapse.md §3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collapse_factor: Option<f64>,
    /// What ends its path there: `limit_point` or the material check that failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collapse_mode: Option<crate::analysis::collapse::CollapseMode>,
    /// The collapse path's load–deflection curve ([`crate::analysis::collapse::Collapse::curve`];
    /// empty when the state's collapse was not run). Not in `summary.json`.
    #[serde(skip)]
    pub collapse_curve: Vec<[f64; 2]>,
    /// Mode 1 per shell node (network node index, translation), for the report's 3D view;
    /// empty when not analysed. Not in `summary.json`.
    #[serde(skip)]
    pub mode: super::buckling::NetworkMode,
    /// A corrugated state: what its shell carries by bending (`crate::analysis::bending`);
    /// `None` for a network in exact equilibrium under its own loads.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bending: Option<crate::analysis::bending::BendingSummary>,
}

/// One constraint of the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstraintResult {
    /// `sigma_min`, `sigma_max`, `blf_min` or `overhang_max`.
    pub name: &'static str,
    /// In words.
    pub description: &'static str,
    /// The limit.
    pub limit: f64,
    /// The worst value over all checked states (None if nothing was checked).
    pub worst: Option<f64>,
    /// State where the worst value occurs.
    pub state: Option<usize>,
    /// Element, layer or mode where it occurs.
    pub element: String,
    /// Whether the constraint holds in every checked state.
    pub pass: bool,
    /// Unit of `limit` and `worst`.
    pub unit: &'static str,
    /// States checked.
    pub states_checked: usize,
}

/// Wall-clock split of [`analyze`], seconds (states run in parallel, so the per-state sums
/// exceed the wall-clock phases on several cores).
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Timings {
    /// Phase 1, wall clock: rebuilding every state, its force pass and element stresses.
    pub stresses: f64,
    /// Sum over states of phase 1.
    pub stresses_sum: f64,
    /// Phase 2, wall clock: shell models and buckling solves.
    pub fe: f64,
    /// Sum over states of their FE time.
    pub fe_sum: f64,
    /// Whole analysis.
    pub total: f64,
    /// The as-printed pass (docs/as-printed.md), wall clock.
    #[serde(default)]
    pub as_printed: f64,
}

/// The analysis of a cap: per state, the constraint report and the verdict.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Analysis {
    /// One entry per state, in print order.
    pub states: Vec<StateAnalysis>,
    /// The constraint report.
    pub constraints: Vec<ConstraintResult>,
    /// All constraints hold.
    pub ok: bool,
    /// The options used.
    pub options: AnalysisOptions,
    /// Timings.
    pub timings: Timings,
    /// The as-printed shape (docs/as-printed.md; None when the buckling analysis is off).
    pub as_printed: Option<crate::analysis::asprinted::AsPrinted>,
    /// The mesh-error pass's next batch, when its solves are made elsewhere
    /// ([`Request::refined`]) and this one is not among them yet: the factors are then the
    /// first pass's and the verdict is partial. Always `None` when the analysis solves itself.
    pub refine_pending: Option<RefineBatch>,
}

/// The mesh-error pass's single-state solves made elsewhere (the designer's Web Workers, issue
/// 25), by state and the `blf_max_split` they were solved with ([`state_fe`] from a cold start,
/// as [`solve_states`] does): [`converge_fe`] asks for batches of both kinds.
pub type RefineSolves = std::collections::BTreeMap<(usize, usize), StateFe>;

/// A batch of the mesh-error pass that [`Request::refined`] does not hold yet: solve `states`
/// with `blf_max_split = max_split` and analyse again with the results added. The pass is
/// deterministic given the first-pass factors and these solves, so replaying it costs only its
/// bookkeeping, and the batches come out as [`analyze`] would solve them itself.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RefineBatch {
    /// The states to solve, in print order.
    pub states: Vec<usize>,
    /// The `blf_max_split` to solve them with (2: the 2×2 split; more: the states that could
    /// govern, refined until converged).
    pub max_split: usize,
}

impl Analysis {
    /// The constraints that fail.
    pub fn failing(&self) -> impl Iterator<Item = &ConstraintResult> {
        self.constraints.iter().filter(|c| !c.pass)
    }

    /// The report as plain text, one line per constraint, numbers in the user's units (kPa,
    /// mm, plain factors: [`readable`]) and, for a failing constraint, what to change
    /// ([`levers`]).
    pub fn report(&self) -> String {
        let mut s = self.constraint_lines();
        s.push_str(if self.ok {
            "design passes every constraint\n"
        } else {
            "design FAILS\n"
        });
        s
    }

    /// [`Analysis::report`] without its last line (the analysis' own pass or fail): for a
    /// caller whose verdict also weighs other checks (`kappe design`: reliability, the robot).
    pub fn constraint_lines(&self) -> String {
        let mut s = String::new();
        for c in &self.constraints {
            let worst = c
                .worst
                .map_or("not checked".to_string(), |w| readable(w, c.unit));
            let at = c
                .state
                .map_or(String::new(), |st| format!(" at state {st}, {}", c.element));
            s.push_str(&format!(
                "{:<13} {:<4} limit {}, worst {worst}{at}\n",
                c.name,
                if c.pass { "PASS" } else { "FAIL" },
                readable(c.limit, c.unit),
            ));
            if !c.pass {
                s.push_str(&format!("{:<18} to fix: {}\n", "", levers(c.name)));
            }
        }
        s
    }
}

/// A value of a constraint in the user's units: stresses in kPa, lengths in mm, factors plain
/// (no unit). Stresses below 0.005 kPa print as 0.00 kPa: the force pass leaves roundoff of
/// ~1e-9 Pa in an all-compression arch, which must not read as a tension.
pub fn readable(value: f64, unit: &str) -> String {
    match unit {
        "Pa" => {
            let kpa = value / 1e3;
            format!("{:.2} kPa", if kpa.abs() < 0.005 { 0.0 } else { kpa })
        }
        "m" => format!("{:.1} mm", value * 1e3),
        "1" => format!("{value:.3}"),
        other => format!("{value} {other}"),
    }
}

/// What would make a failing constraint pass, in the design file's terms (issue 28).
pub fn levers(name: &str) -> &'static str {
    match name {
        "sigma_min" => {
            "the compression is too high: raise cap.rise or shorten cap.span (less thrust per \
             layer), or use a stronger mix (constraints.sigma_min, [material.time]); \
             `kappe optimize` searches the free parameters for you"
        }
        "sigma_max" => {
            "the arch is in tension: raise cap.rise or shorten cap.span so the layer arch stays \
             in compression, or use a mix with tensile strength (constraints.sigma_max); \
             `kappe optimize` searches the free parameters for you"
        }
        "blf_min" => {
            "the shell buckles: raise cap.rise, widen the layers (print.layer_width: a thicker \
             shell), or wait between layers so they stiffen (`kappe schedule` finds the least \
             waits)"
        }
        "overhang_max" => "the layers overhang too far: lower cap.tilt_deg or print.layer_height",
        "deviation_max" => {
            "the print sags out of its design shape as it is built (docs/as-printed.md): raise \
             cap.rise, widen the layers (print.layer_width), or wait between layers so the lower \
             layers stiffen before they carry the next (`kappe schedule`)"
        }
        "collapse_min" => {
            "the imperfect state collapses (docs/collapse.md): raise cap.rise, widen the layers \
             (print.layer_width), wait between layers so they stiffen and strengthen (`kappe \
             schedule`), or measure your placement tolerance and imperfection"
        }
        "beta_min" => {
            "the print stands with too little certainty for the stated scatter (docs/reliability.md): \
             the sensitivities in summary.json's reliability block name the parameter that matters; \
             measure it more tightly, or add margin (cap.rise, print.layer_width, waits from \
             `kappe schedule`, which targets β)"
        }
        _ => "see the report (report.html) for the governing state",
    }
}

#[derive(Debug, Clone)]
struct Worst {
    value: f64,
    state: usize,
    element: String,
}

fn keep_min(w: &mut Option<Worst>, value: f64, state: usize, element: impl FnOnce() -> String) {
    if w.as_ref().is_none_or(|c| value < c.value) {
        *w = Some(Worst {
            value,
            state,
            element: element(),
        });
    }
}

fn keep_max(w: &mut Option<Worst>, value: f64, state: usize, element: impl FnOnce() -> String) {
    if w.as_ref().is_none_or(|c| value > c.value) {
        *w = Some(Worst {
            value,
            state,
            element: element(),
        });
    }
}

/// The green-state checks of one state: the worst strength and the worst bed-joint sliding
/// element (each `None` when not checked).
pub type GreenChecks = (
    Option<crate::analysis::green::WorstElement>,
    Option<crate::analysis::green::WorstElement>,
);

/// The finite-element part of one state's analysis ([`state_fe`]): what [`analyze`] computes per
/// selected state in parallel, and what the designer in the browser computes in its Web
/// Workers and hands to [`analyze`] in [`Request::fe`].
#[derive(Debug, Clone, PartialEq)]
pub struct StateFe {
    /// State index (top print index).
    pub state: usize,
    /// The buckling analysis.
    pub buckling: StateBuckling,
    /// Mode 1 per shell node (empty when none).
    pub mode: NetworkMode,
    /// The green-state checks (only with a strength model).
    pub green: Option<GreenChecks>,
    /// Seconds spent (build + solve).
    pub seconds: f64,
}

/// The green-state model of the analysis (issue 11): the layers' ages on `schedule`, `None`
/// when the time model is constant and has no strength (then nothing depends on the ages).
///
/// # Errors
/// An invalid time model or a `[schedule]` that does not fit the print.
pub fn analysis_green(
    cap: &Cap,
    schedule: Option<&crate::schedule::Schedule>,
) -> Result<Option<crate::analysis::green::CapGreen>, DesignError> {
    let green = crate::analysis::green::CapGreen::with_schedule(cap, schedule)?;
    Ok((green.time.strength.is_some() || !green.time.is_constant()).then_some(green))
}

/// The selected states of the buckling analysis in the runs [`analyze`] solves them in: with a
/// graded mesh, contiguous runs of consecutive states (each state warm-started from the one
/// before it in its run), else one state per run; largest first.
pub fn fe_runs(options: &AnalysisOptions, total: usize) -> Vec<Vec<usize>> {
    let mut selected = vec![false; total];
    if options.buckling {
        for i in options.states.indices(total) {
            if let Some(x) = selected.get_mut(i) {
                *x = true;
            }
        }
    }
    let order: Vec<usize> = (0..total).filter(|&i| selected[i]).collect();
    // Each state's eigensolve starts from the previous state's mode (graded or full mesh: the
    // mode guess is keyed by layer and position in the layer).
    order
        .chunks(WARM_RUN)
        .rev()
        .map(<[usize]>::to_vec)
        .collect()
}

/// What [`state_fe`] is asked beyond the state; the default: no green-state model, nothing more.
#[derive(Debug, Clone, Copy, Default)]
pub struct FeRequest<'a> {
    /// The green-state model: [`analysis_green`] of the run's schedule.
    pub green: Option<&'a crate::analysis::green::CapGreen>,
    /// Also what the buckling solve's factor of K gives beyond the factors: the state's
    /// as-printed increment and a corrugated state's bending part ([`StateFeSolve`]).
    pub extra: bool,
}

/// What [`state_fe`] gives.
#[derive(Debug, Clone)]
pub struct StateFeSolve {
    /// The state's finite-element results.
    pub fe: StateFe,
    /// With [`FeRequest::extra`]: the as-printed increment, solved inside the buckling solve
    /// (`None` where that solve cannot give it).
    pub increment: Option<Increment>,
    /// With [`FeRequest::extra`]: a corrugated state's stress extremes with its bending part,
    /// solved inside the buckling solve (`None` where that solve cannot give them: phase 1 of
    /// [`analyze`] solves them).
    pub(crate) stresses: Option<(StressExtremes, Option<BendingSummary>)>,
}

/// The finite-element analysis of state `top` (shell buckling, and the green-state strength
/// checks with a strength model) with `options` as given: the first pass of [`analyze`] (one
/// step of a run of [`fe_runs`]) passes `blf_max_split` 1
/// ([`AnalysisOptions::with_split_at_most`]), the print-layer mesh alone, and estimates the mesh
/// error over all states afterwards ([`converge_fe`]); more solves the split meshes too.
/// `guess` carries the warm start from the run's previous state (start each run with `None`).
///
/// # Errors
/// A state that cannot be built or solved.
pub fn state_fe(
    cap: &Cap,
    options: &AnalysisOptions,
    top: usize,
    guess: &mut Option<ModeGuess>,
    request: &FeRequest<'_>,
) -> Result<StateFeSolve, DesignError> {
    let t0 = Instant::now();
    let state = cap.state(top)?;
    let green = request.green;
    let mat = state_material(cap, options, top, green);
    // With a strength model the buckling solve's own static solution gives the membrane
    // stresses (one factorization per state, not two).
    let checked = match green {
        Some(g) => g.state_checks(&state, &mat, options, top)?,
        None => None,
    };
    let (buckling, mode, green, increment, stresses) = match checked {
        Some((b, mode, green)) => (b, mode, green, None, None),
        _ => {
            let request = BucklingRequest {
                guess: guess.as_ref(),
                printed: request.extra,
                // Phase 1 of `assemble` adds the bending part to a corrugated cap's stresses.
                bending: (request.extra && !cap.centre_arches.is_empty()).then(|| cap.areas()),
            };
            let r = state_buckling(&state, &mat, options, &request)?;
            *guess = Some(r.next);
            let stresses = r
                .stresses
                .map(|(all, bending)| (StressExtremes::of(&all), bending));
            (r.buckling, r.mode, None, r.increment, stresses)
        }
    };
    Ok(StateFeSolve {
        fe: StateFe {
            state: top,
            buckling,
            mode,
            green,
            seconds: t0.elapsed().as_secs_f64(),
        },
        increment,
        stresses,
    })
}

/// The mesh-error levels of state `top` from its first-pass factor `coarse` and mode `mode`
/// ([`state_fe`] without a green-state model; `mode` is the `guess` it leaves) with `options`,
/// without solving the print-layer mesh again. Only `buckling.convergence` and `seconds` are
/// meant to be read ([`converge_fe`]'s solver: [`analyze`]'s, and the designer's workers for
/// the states whose first pass they solved).
///
/// # Errors
/// A state that cannot be built or solved.
pub fn state_fe_refine(
    cap: &Cap,
    options: &AnalysisOptions,
    top: usize,
    coarse: f64,
    mode: &ModeGuess,
) -> Result<StateFe, DesignError> {
    let t0 = Instant::now();
    let state = cap.state(top)?;
    let mat = state_material(cap, options, top, None);
    let convergence = super::buckling::state_refine(&state, &mat, options, coarse, mode)?;
    Ok(StateFe {
        state: top,
        buckling: StateBuckling {
            status: BucklingStatus::Analysed,
            factors: vec![coarse],
            location: None,
            mechanism: None,
            shell_nodes: 0,
            convergence,
        },
        mode: Vec::new(),
        green: None,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// A solver of single states with given options (see [`converge_fe`]).
pub type SolveStates<'a> =
    dyn FnMut(&[usize], &AnalysisOptions) -> Result<Vec<StateFe>, DesignError> + 'a;

/// The mesh error of the buckling factors (issue 23, docs/convergence.md): the first-pass
/// results `fe` ([`state_fe`]) gain each state's converged estimate — the 2×2 split solved on
/// an adaptive sample of the states and the correction interpolated for the others
/// ([`super::convergence::sample`]); the states that could govern are always solved, and
/// refined further up to `blf_max_split` until within `blf_tolerance`. `solve(states, options)`
/// solves single states (in parallel natively, in turn in the browser). Returns the states whose
/// correction is interpolated. Nothing is done without `converged_blf`.
///
/// # Errors
/// A state that cannot be built or solved.
pub fn converge_fe(
    options: &AnalysisOptions,
    fe: &mut [StateFe],
    solve: &mut SolveStates<'_>,
) -> Result<Vec<usize>, DesignError> {
    let mut interpolated: Vec<usize> = Vec::new();
    if !options.converged_blf {
        return Ok(interpolated);
    }
    let split_opts = AnalysisOptions {
        blf_max_split: 2,
        ..options.clone()
    };
    let mut coarse: Vec<(usize, f64)> = fe
        .iter()
        .filter(|f| f.buckling.status == BucklingStatus::Analysed)
        .filter_map(|f| Some((f.state, *f.buckling.factors.first()?)))
        .collect();
    // In print order: the runs come back largest first.
    coarse.sort_unstable_by_key(|c| c.0);
    let mut extra_secs: std::collections::HashMap<usize, f64> = Default::default();
    let mut solve_conv = |batch: &[usize], opts: &AnalysisOptions| {
        let r = solve(batch, opts)?;
        Ok::<_, DesignError>(
            r.into_iter()
                .filter_map(|f| {
                    *extra_secs.entry(f.state).or_default() += f.seconds;
                    Some((f.state, f.buckling.convergence?))
                })
                .collect::<Vec<_>>(),
        )
    };
    let sampled = super::convergence::sample(
        &coarse,
        options.blf_tolerance,
        options.blf_sampling,
        &mut |b| solve_conv(b, &split_opts),
    )?;
    let mut est: std::collections::BTreeMap<usize, (kappe_fe::ConvergedFactor, bool)> =
        sampled.into_iter().map(|(i, c, s)| (i, (c, s))).collect();
    // The states that could govern: solved, and converged to the tolerance.
    for _ in 0..4 {
        let upper = est
            .values()
            .map(|(c, _)| c.upper)
            .fold(f64::INFINITY, f64::min);
        let interp: Vec<usize> = est
            .iter()
            .filter(|(_, (c, s))| !*s && c.extrapolated <= upper)
            .map(|(i, _)| *i)
            .collect();
        let coarse_only: Vec<usize> = est
            .iter()
            .filter(|(_, (c, s))| {
                *s && !c.converged
                    && c.extrapolated <= upper
                    && options.blf_max_split > 2
                    && c.levels
                        .last()
                        .is_some_and(|l| l.split < options.blf_max_split)
            })
            .map(|(i, _)| *i)
            .collect();
        if interp.is_empty() && coarse_only.is_empty() {
            break;
        }
        for (i, c) in solve_conv(&interp, &split_opts)? {
            est.insert(i, (c, true));
        }
        for (i, c) in solve_conv(&coarse_only, options)? {
            est.insert(i, (c, true));
        }
    }
    for f in fe.iter_mut() {
        if let Some((c, solved)) = est.remove(&f.state) {
            if !solved {
                interpolated.push(f.state);
            }
            f.buckling.convergence = Some(c);
        }
        f.seconds += extra_secs.get(&f.state).copied().unwrap_or(0.0);
    }
    Ok(interpolated)
}

/// Single states solved with `options` in turn, each from a cold start: the mesh-error pass's
/// solver when [`analyze`] is given first-pass results without [`Request::refined`]. (Solving
/// every state itself, [`analyze`] runs the pass in parallel from the first pass's modes
/// ([`state_fe_refine`]); so do the designer's workers for a [`RefineBatch`]'s states whose first
/// pass they solved, and these cold-start solves for the others.)
///
/// # Errors
/// A state that cannot be built or solved.
pub fn solve_states(
    cap: &Cap,
    options: &AnalysisOptions,
    green: Option<&crate::analysis::green::CapGreen>,
    states: &[usize],
) -> Result<Vec<StateFe>, DesignError> {
    states
        .iter()
        .map(|&top| {
            let request = FeRequest {
                green,
                extra: false,
            };
            state_fe(cap, options, top, &mut None, &request).map(|r| r.fe)
        })
        .collect()
}

/// What [`analyze`] is asked beyond the cap and its options.
#[derive(Default)]
pub struct Request<'a> {
    /// The layers' ages from this schedule (the run's, on the robot plan's clock, issue 11);
    /// `None`: path length / print speed and the `[schedule]` waits.
    pub schedule: Option<&'a crate::schedule::Schedule>,
    /// The finite-element results of the selected states computed elsewhere ([`state_fe`] over
    /// [`fe_runs`], e.g. in the designer's Web Workers): the stresses, the overhangs, the
    /// constraint report and the verdict are made from them exactly as from the states
    /// [`analyze`] solves itself. A selected state missing here counts as not analysed (the
    /// designer's partial verdict while its workers run). `None`: solve every selected state.
    pub fe: Option<Vec<StateFe>>,
    /// With [`Self::fe`]: the mesh-error pass's solves made elsewhere so far. The pass then
    /// solves nothing itself: it stops at the first batch this lacks and names it in
    /// [`Analysis::refine_pending`]. `None`: the pass solves its states here, in turn.
    pub refined: Option<RefineSolves>,
    /// With [`Self::fe`]: the as-printed increments the buckling solves made elsewhere gave
    /// (by state, [`FeRequest::extra`]); the as-printed pass solves only the other states.
    pub increments: std::collections::HashMap<usize, Increment>,
    /// Progress (one step per buckling analysis finished) and cancellation (checked before every
    /// state's rebuild and buckling solve).
    pub context: Context<'a>,
}

/// Analyse every state of `cap` (see the module docs) as `request` asks.
///
/// # Errors
/// Invalid options, a state that cannot be built or solved, a `[schedule]` that does not fit
/// the print, or [`DesignError::Cancelled`].
pub fn analyze(
    cap: &Cap,
    options: &AnalysisOptions,
    request: Request<'_>,
) -> Result<Analysis, DesignError> {
    match request.fe {
        Some(fe) => analyze_from_fe(
            cap,
            options,
            request.schedule,
            fe,
            request.refined.as_ref(),
            request.increments,
            request.context,
        ),
        None => analyze_all(cap, options, request.schedule, request.context),
    }
}

/// [`analyze`] with the finite-element results given ([`Request::fe`]).
fn analyze_from_fe(
    cap: &Cap,
    options: &AnalysisOptions,
    schedule: Option<&crate::schedule::Schedule>,
    fe: Vec<StateFe>,
    refined: Option<&RefineSolves>,
    increments: std::collections::HashMap<usize, Increment>,
    context: Context<'_>,
) -> Result<Analysis, DesignError> {
    options.validate()?;
    let green = analysis_green(cap, schedule)?;
    let t_all = Instant::now();
    let mut fe = fe;
    // The mesh error is estimated over all states together, so only once every selected state
    // is in: a partial verdict (the designer's, while its workers run) carries the first-pass
    // factors.
    let selected: usize = fe_runs(options, cap.states.len())
        .iter()
        .map(Vec::len)
        .sum();
    let mut complete = fe.len() >= selected;
    let mut pending = None;
    let interpolated = match (complete, refined) {
        (false, _) => Vec::new(),
        (true, None) => converge_fe(options, &mut fe, &mut |states, opts| {
            solve_states(cap, opts, green.as_ref(), states)
        })?,
        (true, Some(refined)) => {
            // On a clone, so a pass stopped at a missing batch leaves the first-pass factors.
            let mut tried = fe.clone();
            let outcome = converge_fe(options, &mut tried, &mut |states, opts| {
                let split = opts.blf_max_split;
                let missing: Vec<usize> = states
                    .iter()
                    .copied()
                    .filter(|&s| !refined.contains_key(&(s, split)))
                    .collect();
                if missing.is_empty() {
                    Ok(states
                        .iter()
                        .filter_map(|&s| refined.get(&(s, split)).cloned())
                        .collect())
                } else {
                    pending = Some(RefineBatch {
                        states: missing,
                        max_split: split,
                    });
                    // Stops the pass: not an error once `pending` names what it lacks.
                    Err(DesignError::Cancelled)
                }
            });
            match outcome {
                Ok(interpolated) => {
                    fe = tried;
                    interpolated
                }
                Err(DesignError::Cancelled) if pending.is_some() => {
                    complete = false;
                    Vec::new()
                }
                Err(e) => return Err(e),
            }
        }
    };
    let mut analysis = assemble(
        cap,
        options,
        green,
        fe,
        &interpolated,
        (t_all, 0.0),
        complete,
        increments,
        Default::default(),
        &Default::default(),
        context.stop_flag(),
    )?;
    analysis.refine_pending = pending;
    Ok(analysis)
}

/// [`analyze`] solving every selected state itself.
fn analyze_all(
    cap: &Cap,
    options: &AnalysisOptions,
    schedule: Option<&crate::schedule::Schedule>,
    context: Context<'_>,
) -> Result<Analysis, DesignError> {
    let on_state = |n| context.step(n);
    let stop = context.stop_flag();
    options.validate()?;
    let t_all = Instant::now();
    let cancelled = || {
        if stop.load(Ordering::Relaxed) {
            Err(DesignError::Cancelled)
        } else {
            Ok(())
        }
    };
    // Green state (issue 11): strength and bed-joint sliding with the layers' ages, only when
    // `[material.time]` gives a strength model (otherwise nothing changes).
    let green = analysis_green(cap, schedule)?;
    // The buckling analysis of the selected states, largest first so the two cores finish
    // together. With a graded mesh (issue 15) consecutive states share most of their mesh, so
    // each state's eigensolve starts from the previous state's mode: the selected states run in
    // contiguous runs, one after another within a run, the runs in parallel (largest first).
    // The start changes the Lanczos steps, not the converged result (`BucklingRequest::guess`).
    // The green-state strength path (`CapGreen::state_checks`) starts cold.
    let t_phase = Instant::now();
    let runs = fe_runs(options, cap.states.len());
    let n_fe = runs.iter().map(Vec::len).sum();
    // Each state's first-pass mode is kept (about 50 bytes a shell node) so the mesh-error pass
    // continues from it instead of solving the print-layer mesh again (`state_refine`), and so
    // the collapse check takes it as its imperfection's shape where its model is the same
    // (`collapse::cap_state_lba_from`).
    let first_modes = std::sync::Mutex::new(std::collections::HashMap::new());
    // The first pass is the print-layer mesh alone; the mesh error is estimated afterwards over
    // all states together (`converge_fe`).
    let first = options.with_split_at_most(1);
    // Each state's as-printed increment, solved inside its buckling solve's factorization of K
    // (the as-printed pass then factorizes only the states this pass did not solve).
    let increments = std::sync::Mutex::new(std::collections::HashMap::new());
    // A corrugated state's stresses with its bending part, likewise (phase 1 of `assemble`
    // then solves only the states this pass did not).
    let bending = std::sync::Mutex::new(std::collections::HashMap::new());
    let fe: Vec<StateFe> = runs
        .into_par_iter()
        .map(|run| {
            let mut guess: Option<ModeGuess> = None;
            let mut out = Vec::with_capacity(run.len());
            for top in run {
                cancelled()?;
                let request = FeRequest {
                    green: green.as_ref(),
                    extra: true,
                };
                let StateFeSolve {
                    fe: f,
                    increment,
                    stresses,
                } = state_fe(cap, &first, top, &mut guess, &request)?;
                if let Some(i) = increment
                    && let Ok(mut m) = increments.lock()
                {
                    m.insert(top, i);
                }
                if let Some(x) = stresses
                    && let Ok(mut m) = bending.lock()
                {
                    m.insert(top, x);
                }
                if let (None, Some(g), Some(&f1)) = (&green, &guess, f.buckling.factors.first())
                    && let Ok(mut m) = first_modes.lock()
                {
                    m.insert(top, (f1, g.clone()));
                }
                out.push(f);
                on_state(n_fe);
            }
            Ok(out)
        })
        .collect::<Result<Vec<_>, DesignError>>()?
        .into_iter()
        .flatten()
        .collect();
    let first_modes = first_modes.into_inner().unwrap_or_default();
    let mut fe = fe;
    let interpolated = converge_fe(options, &mut fe, &mut |states, opts| {
        // Largest state first, each core taking the next state as it finishes (longest
        // processing time first): a batch of a few split meshes of very different sizes left a
        // core idle behind the largest one under rayon's halving of the slice.
        let mut order = states.to_vec();
        order.sort_unstable_by(|a, b| b.cmp(a));
        let next = std::sync::atomic::AtomicUsize::new(0);
        let workers = rayon::current_num_threads().clamp(1, order.len().max(1));
        let parts = (0..workers)
            .into_par_iter()
            .map(|_| {
                let mut out = Vec::new();
                while let Some(&top) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
                    cancelled()?;
                    out.push(match first_modes.get(&top) {
                        Some((f1, mode)) => state_fe_refine(cap, opts, top, *f1, mode),
                        None => {
                            let request = FeRequest {
                                green: green.as_ref(),
                                extra: false,
                            };
                            state_fe(cap, opts, top, &mut None, &request).map(|r| r.fe)
                        }
                    }?);
                }
                Ok(out)
            })
            .collect::<Result<Vec<_>, DesignError>>()?;
        Ok(parts.into_iter().flatten().collect())
    })?;
    let wall_fe = t_phase.elapsed().as_secs_f64();
    assemble(
        cap,
        options,
        green,
        fe,
        &interpolated,
        (t_all, wall_fe),
        true,
        increments.into_inner().unwrap_or_default(),
        bending.into_inner().unwrap_or_default(),
        &first_modes,
        stop,
    )
}

/// Phase 1 (every state's force pass and element stresses) and the report of [`analyze`], with
/// the finite-element results `fe`; `clock`: when the analysis started and the wall-clock
/// seconds of the finite-element phase. `complete`: every selected state is in `fe`, so the
/// whole-print passes run (the as-printed shape; a partial verdict, the designer's while its
/// workers run, leaves them out rather than pay for them at every result). `increments`: the
/// as-printed increments the buckling solves already gave (by state; the pass solves the rest);
/// `solved_bending`: likewise a corrugated cap's stresses with their bending part;
/// `first_modes`: the first pass's factor and mode 1 by state, for the collapse check.
#[allow(clippy::too_many_arguments)]
fn assemble(
    cap: &Cap,
    options: &AnalysisOptions,
    green: Option<crate::analysis::green::CapGreen>,
    fe: Vec<StateFe>,
    interpolated: &[usize],
    (t_all, wall_fe): (Instant, f64),
    complete: bool,
    increments: std::collections::HashMap<usize, Increment>,
    solved_bending: std::collections::HashMap<usize, (StressExtremes, Option<BendingSummary>)>,
    first_modes: &std::collections::HashMap<usize, (f64, ModeGuess)>,
    stop: &AtomicBool,
) -> Result<Analysis, DesignError> {
    let cancelled = || {
        if stop.load(Ordering::Relaxed) {
            Err(DesignError::Cancelled)
        } else {
            Ok(())
        }
    };
    let design = &cap.design;
    let total = cap.states.len();
    let areas = cap.areas();

    struct PerState {
        bending: Option<BendingSummary>,
        stresses: StressExtremes,
        stress_seconds: f64,
        buckling: Option<StateBuckling>,
        mode: NetworkMode,
        fe_seconds: f64,
        top_layer: i32,
        green: Option<GreenChecks>,
    }
    // Phase 1: every state's element stresses. A prismatic cap's come with its form
    // (`StateSummary::stresses`, from the force pass `design_cap` ran anyway); a corrugated
    // cap's add the shell's bending (`crate::analysis::bending`).
    let t_phase = Instant::now();
    let mut per: Vec<PerState> = (0..total)
        .into_par_iter()
        .map(|top| {
            cancelled()?;
            let t0 = Instant::now();
            let summary = cap.states.get(top);
            // A corrugated state's bending may have been solved as a load case of its buckling
            // solve already.
            let known = summary
                .and_then(|s| s.stresses)
                .map(|s| (s, None))
                .or_else(|| solved_bending.get(&top).copied());
            let (stresses, bending) = match known {
                Some(known) => known,
                None => {
                    let state = cap.state(top)?;
                    // The bending part of the corrugation (`crate::analysis::bending`).
                    let mat = crate::analysis::buckling::state_material(
                        cap,
                        options,
                        top,
                        green.as_ref(),
                    );
                    let (all, bending) =
                        crate::analysis::bending::corrugated_stresses(&state, areas, &mat)?;
                    (StressExtremes::of(&all), bending)
                }
            };
            Ok(PerState {
                bending,
                stresses,
                stress_seconds: t0.elapsed().as_secs_f64(),
                buckling: None,
                mode: Vec::new(),
                fe_seconds: 0.0,
                top_layer: summary.map_or(0, |s| s.top_layer),
                green: None,
            })
        })
        .collect::<Result<_, DesignError>>()?;
    let wall_stresses = t_phase.elapsed().as_secs_f64();
    for f in fe {
        if let Some(p) = per.get_mut(f.state) {
            p.buckling = Some(f.buckling);
            p.green = f.green;
            p.mode = f.mode;
            p.fe_seconds = f.seconds;
        }
    }

    // Overhangs: |l_o| of each layer, in print order.
    let overhang_of = |q: usize| cap.overhangs.get(q).map_or(0.0, |o| o.abs());
    let lo_max = design.overhang_max();
    let (sigma_min, sigma_max, blf_min) = (
        design.constraints.sigma_min,
        design.constraints.sigma_max,
        design.constraints.blf_min,
    );
    let stress_scale = per.iter().fold(0.0_f64, |m, p| m.max(p.stresses.abs_max));
    let stol = STRESS_REL_TOL * stress_scale;

    let mut w_comp: Option<Worst> = None;
    let mut w_tens: Option<Worst> = None;
    let mut w_blf: Option<Worst> = None;
    let mut w_lo: Option<Worst> = None;
    let mut w_strength: Option<Worst> = None;
    let mut w_sliding: Option<Worst> = None;
    let mut green_checked = 0;
    let layer_name = |k: usize| cap.sections.layers.get(k).map_or(0, |l| l.id);
    let mut blf_checked = 0;
    let mut states = Vec::with_capacity(total);
    let mut running_lo: f64 = 0.0;
    let (mut t_stress, mut t_fe) = (0.0, 0.0);
    for (q, p) in per.iter().enumerate() {
        t_stress += p.stress_seconds;
        t_fe += p.fe_seconds;
        let (smin, smax) = (
            p.stresses.min.map_or(0.0, |m| m.0.min(0.0)),
            p.stresses.max.map_or(0.0, |m| m.0.max(0.0)),
        );
        if let Some((v, kind)) = p.stresses.min {
            keep_min(&mut w_comp, v, q, || kind.to_string());
        }
        if let Some((v, kind)) = p.stresses.max {
            keep_max(&mut w_tens, v, q, || kind.to_string());
        }
        let lo = overhang_of(q);
        let layer_id = cap.sections.layers.get(q).map_or(0, |l| l.id);
        keep_max(&mut w_lo, lo, q, || format!("layer {layer_id}"));
        running_lo = running_lo.max(lo);
        let mut ok = smin >= sigma_min - stol && smax <= sigma_max + stol && running_lo <= lo_max;
        let (mut blf, mut modes, mut status, mut mechanism, mut nodes) =
            (None, Vec::new(), BucklingStatus::Skipped, None, 0);
        let (mut blf_mesh, mut blf_error, mut blf_converged, mut blf_split) =
            (None, None, None, None);
        let mut blf_interpolated = None;
        if let Some(b) = &p.buckling {
            status = b.status;
            modes = b.factors.clone();
            blf = b.blf();
            if let Some(c) = &b.convergence {
                blf_interpolated = Some(interpolated.contains(&q));
                blf_mesh = b.factors.first().copied();
                blf_error = Some(c.error);
                blf_converged = Some(c.converged);
                blf_split = c.levels.last().map(|l| l.split);
            }
            mechanism = b.mechanism.clone();
            nodes = b.shell_nodes;
            let place = || match b.location {
                Some((layer, x)) => format!(
                    "mode 1 peaks in layer {layer} at ({:.3}, {:.3}, {:.3}) m",
                    x[0], x[1], x[2]
                ),
                None => "mode 1".to_string(),
            };
            match b.status {
                BucklingStatus::Analysed => {
                    blf_checked += 1;
                    if let Some(f) = blf {
                        ok &= f >= blf_min;
                        keep_min(&mut w_blf, f, q, place);
                    }
                }
                BucklingStatus::Mechanism => {
                    blf_checked += 1;
                    ok = false;
                    let m = mechanism.clone().unwrap_or_default();
                    keep_min(&mut w_blf, 0.0, q, || m);
                }
                _ => {}
            }
        }
        let (mut strength_u, mut sliding_u) = (None, None);
        if let Some((st, sl)) = &p.green {
            green_checked += 1;
            for (w, slot, out) in [
                (st, &mut w_strength, &mut strength_u),
                (sl, &mut w_sliding, &mut sliding_u),
            ] {
                if let Some(w) = w {
                    *out = Some(w.utilisation);
                    ok &= w.utilisation <= 1.0;
                    keep_max(slot, w.utilisation, q, || {
                        format!(
                            "shell element {} in layer {} (age {:.1} s; σ = {:.1}, {:.1} Pa)",
                            w.element,
                            layer_name(w.layer),
                            w.age_s,
                            w.stresses[0],
                            w.stresses[1]
                        )
                    });
                }
            }
        }
        let bottom_age_s = green
            .as_ref()
            .and_then(|g| g.schedule.ages(q + 1).first().copied());
        states.push(StateAnalysis {
            strength_utilisation: strength_u,
            sliding_utilisation: sliding_u,
            bottom_age_s,
            index: q,
            top_layer: p.top_layer,
            blf,
            blf_mesh,
            blf_error,
            blf_converged,
            blf_split,
            blf_interpolated,
            blf_modes: modes,
            buckling: status,
            max_compression_stress_pa: smin,
            max_tension_stress_pa: smax,
            max_overhang_m: running_lo,
            ok,
            mechanism,
            shell_nodes: nodes,
            fe_seconds: p.fe_seconds,
            collapse_factor: None,
            collapse_mode: None,
            collapse_curve: Vec::new(),
            mode: p.mode.clone(),
            bending: p.bending,
        });
    }

    // The collapse check (docs/collapse.md): the states the state rule picks from the linear
    // bounds just found.
    let nonlinear = options
        .nonlinear
        .unwrap_or(crate::input::nonlinear::NonlinearSpec {
            // Opt-in for caps: the default design with the check costs ~5× the analysis
            // (docs/collapse.md §6), against the 1.5×.
            enabled: false,
            ..Default::default()
        });
    let collapse_min = design.constraints.collapse_min();
    let mut w_collapse: Option<Worst> = None;
    let mut collapse_checked = 0;
    let t_collapse = Instant::now();
    if options.buckling && nonlinear.enabled {
        let bounds: Vec<crate::analysis::collapse::LinearBound> = states
            .iter()
            .filter_map(|s| {
                let b = s.blf.filter(|b| *b > 0.0)?;
                let inv =
                    |u: Option<f64>| u.filter(|u| *u > 0.0).map_or(f64::INFINITY, |u| 1.0 / u);
                Some(crate::analysis::collapse::LinearBound {
                    state: s.index,
                    bound: b
                        .min(inv(s.strength_utilisation))
                        .min(inv(s.sliding_utilisation)),
                })
            })
            .collect();
        let found = crate::analysis::collapse::cap_states_to_run(&bounds, false, &|top, above| {
            cancelled()?;
            // The first pass's own LBA of the state: no second solve where the model is the
            // same (docs/collapse.md §3).
            let first =
                first_modes
                    .get(&top)
                    .map(|(factor, mode)| crate::analysis::collapse::FirstPass {
                        factor: *factor,
                        mode,
                    });
            crate::analysis::collapse::cap_state_collapse_from(
                cap,
                options,
                &nonlinear,
                green.as_ref(),
                top,
                above,
                first,
            )
        })?;
        for (q, c) in found {
            if let Some(s) = states.get_mut(q) {
                collapse_checked += 1;
                s.collapse_factor = Some(c.factor);
                s.collapse_mode = Some(c.mode);
                s.collapse_curve = c.curve.clone();
                s.ok &= c.factor >= collapse_min;
                keep_min(&mut w_collapse, c.factor, q, || {
                    format!(
                        "{} (LBA {:.3}, w0 = {:.2} mm)",
                        c.mode.name(),
                        c.lba,
                        c.w0 * 1e3
                    )
                });
            }
        }
    }
    let wall_collapse = t_collapse.elapsed().as_secs_f64();

    // The as-printed shape (docs/as-printed.md): every state's increment under its new weight.
    let t_printed = Instant::now();
    let deviation_max = design.deviation_max();
    let as_printed = if options.buckling && total > 0 && complete {
        let a = crate::analysis::asprinted::cap_as_printed_given(
            cap,
            options,
            green.as_ref(),
            increments,
            &cancelled,
        )?;
        for (s, d) in states.iter_mut().zip(&a.states) {
            s.ok &= d.deviation_m <= deviation_max;
        }
        Some(a)
    } else {
        None
    };
    let wall_printed = t_printed.elapsed().as_secs_f64();

    let result = |name: &'static str,
                  description: &'static str,
                  unit: &'static str,
                  limit: f64,
                  w: Option<Worst>,
                  checked: usize,
                  pass: &dyn Fn(f64) -> bool| {
        let pass_v = w.as_ref().is_none_or(|w| pass(w.value));
        ConstraintResult {
            name,
            description,
            limit,
            worst: w.as_ref().map(|w| w.value),
            state: w.as_ref().map(|w| w.state),
            element: w.map(|w| w.element).unwrap_or_default(),
            pass: pass_v,
            unit,
            states_checked: checked,
        }
    };
    let mut constraints = vec![
        result(
            "sigma_min",
            "compressive stress: σ ≥ σ_min in every element",
            "Pa",
            sigma_min,
            w_comp,
            total,
            &|v| v >= sigma_min - stol,
        ),
        result(
            "sigma_max",
            "tensile stress: σ ≤ σ_max in every element",
            "Pa",
            sigma_max,
            w_tens,
            total,
            &|v| v <= sigma_max + stol,
        ),
        result(
            "blf_min",
            "buckling: BLF ≥ BLF_min in every analysed state",
            "1",
            blf_min,
            w_blf,
            blf_checked,
            &|v| v >= blf_min,
        ),
        result(
            "overhang_max",
            "layer overhang: |l_o| ≤ l_o,max for every layer",
            "m",
            lo_max,
            w_lo,
            total,
            &|v| v <= lo_max,
        ),
    ];
    if collapse_checked > 0 {
        constraints.push(result(
            "collapse_min",
            "collapse: factor of the imperfect state's nonlinear path (limit point or the aged material at the faces) ≥ collapse_min",
            "1",
            collapse_min,
            w_collapse,
            collapse_checked,
            &|v| v >= collapse_min,
        ));
    }
    if let Some(a) = &as_printed {
        let w = a.state.map(|state| Worst {
            value: a.deviation_m,
            state,
            element: match (a.layer, a.at_m) {
                (Some(l), Some(x)) => {
                    format!("layer {l} at ({:.3}, {:.3}, {:.3}) m", x[0], x[1], x[2])
                }
                _ => String::new(),
            },
        });
        constraints.push(result(
            "deviation_max",
            "as-printed shape: deviation from the design ≤ deviation_max at every node in every state",
            "m",
            deviation_max,
            w,
            a.states.len(),
            &|v| v <= deviation_max,
        ));
    }
    if green.as_ref().is_some_and(|g| g.time.strength.is_some()) {
        constraints.push(result(
            "strength",
            "green strength: Mohr–Coulomb utilisation ≤ 1 on the shell's membrane stresses, c(t), φ(t) at the younger layer's age",
            "1",
            1.0,
            w_strength,
            green_checked,
            &|v| v <= 1.0,
        ));
        constraints.push(result(
            "sliding",
            "bed-joint sliding: |τ| ≤ c(t) + σ_n·tan φ(t) on the bed plane, younger layer's age",
            "1",
            1.0,
            w_sliding,
            green_checked,
            &|v| v <= 1.0,
        ));
    }
    let ok = constraints.iter().all(|c| c.pass);
    Ok(Analysis {
        states,
        constraints,
        ok,
        options: options.clone(),
        timings: Timings {
            stresses: wall_stresses,
            stresses_sum: t_stress,
            fe: wall_fe + wall_collapse,
            fe_sum: t_fe,
            total: t_all.elapsed().as_secs_f64(),
            as_printed: wall_printed,
        },
        as_printed,
        refine_pending: None,
    })
}
