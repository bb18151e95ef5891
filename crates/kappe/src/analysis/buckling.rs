//! The linear buckling run of one print state: its shell model ([`crate::analysis::shell`]) under
//! self-weight, solved by `kappe_fe::buckling`; the lowest positive factor is the state's BLF.
//! A shell model that is a mechanism is reported with the layers of its free motion.

use std::collections::{HashMap, HashSet};

use serde::Serialize;

use crate::analysis::asprinted::Increment;
use crate::analysis::bending::BendingSummary;
use crate::analysis::shell::{NoShell, ShellMaterial, StateShell, state_shell};
use crate::form::cap::Cap;
use crate::form::forces::Sections2D;
use crate::form::states::State;
use crate::form::stresses::ElementStress;
use crate::input::analysis::AnalysisOptions;
use crate::input::error::DesignError;

/// What the buckling analysis of a state did.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum BucklingStatus {
    /// Analysed; `blf` holds the factor.
    Analysed,
    /// Not in the state selection (or buckling switched off).
    Skipped,
    /// A single layer on the bed: no shell surface.
    SingleLayer,
    /// The shell model is a mechanism (see `mechanism`).
    Mechanism,
    /// The load produces no compressive buckling mode (no positive factor).
    NoPositiveFactor,
}

/// The shell material of the state with top print index `top`: the design's material, every
/// layer's modulus from its age on `green`'s schedule (the run's one clock, e.g. the robot
/// plan's; [`crate::analysis::green::CapGreen::new`]: the cap's own) when the time model varies
/// with age; `None`: the material without a time model.
pub fn state_material(
    cap: &Cap,
    options: &AnalysisOptions,
    top: usize,
    green: Option<&crate::analysis::green::CapGreen>,
) -> ShellMaterial {
    let d = &cap.design;
    // E per layer from its age on the schedule (`[material.time]`, or the older
    // `[analysis.ageing]` read as the linear time model); empty for the constant model, so the
    // shell is exactly the one without a time model.
    let layer_modulus = green.map_or_else(HashMap::new, |g| g.layer_moduli(cap, top));
    ShellMaterial {
        thickness: d.print.layer_width,
        poisson_ratio: d.material.poisson_ratio,
        unit_weight: d.material.specific_weight,
        layer_modulus,
        youngs_modulus: d.material.youngs_modulus,
        element: options.element,
    }
}

/// Result of the buckling analysis of one state.
#[derive(Debug, Clone, PartialEq)]
pub struct StateBuckling {
    /// What happened.
    pub status: BucklingStatus,
    /// Factors found, ascending.
    pub factors: Vec<f64>,
    /// Where mode 1 peaks (layer id, position), or where the mechanism is.
    pub location: Option<(i32, [f64; 3])>,
    /// Mechanism description.
    pub mechanism: Option<String>,
    /// Shell nodes.
    pub shell_nodes: usize,
    /// The mesh-error control of the lowest factor (`AnalysisOptions::converged_blf`):
    /// `factors` are the shell mesh's own, this is the converged estimate
    /// (`kappe_fe::convergence`, docs/convergence.md).
    pub convergence: Option<kappe_fe::ConvergedFactor>,
}

impl StateBuckling {
    /// The factor the verdict uses: the converged estimate when the mesh error is controlled,
    /// else the mesh's lowest factor.
    pub fn blf(&self) -> Option<f64> {
        match &self.convergence {
            Some(c) => Some(c.extrapolated),
            None => self.factors.first().copied(),
        }
    }
}

/// Mode 1 of a state as the translations (ux, uy, uz, scaled to max |·| = 1 over all six
/// freedoms, as `kappe_fe` returns it) of each shell node, keyed by its network node index: what
/// the report draws. Empty when the state has no mode.
pub type NetworkMode = Vec<(usize, [f64; 3])>;

/// Mode 1 of a state per shell node, keyed by (layer id, index of the node in its layer): keys
/// that mean the same material point in every state, so one state's mode can start the
/// eigensolver of the next ([`BucklingRequest::guess`]).
pub type ModeGuess = HashMap<(i32, usize), [f64; 6]>;

/// How far below a layer missing from a [`ModeGuess`] (a new top layer, or a row the previous
/// mesh did not keep) its guess is looked up: the largest stride of a graded mesh is far less.
const GUESS_REACH: i32 = 256;

/// What a state's buckling solve ([`state_buckling`]) is asked beyond its factors; the
/// default: a cold start, nothing more.
#[derive(Debug, Clone, Copy, Default)]
pub struct BucklingRequest<'a> {
    /// Start the eigensolver from this mode of a nearby state (`None`: a random start). It only
    /// saves Lanczos steps: the result meets the same residual bound either way.
    pub guess: Option<&'a ModeGuess>,
    /// Also the state's as-printed increment (the weight of its new strip alone), on a mesh the
    /// as-printed pass shares ([`crate::analysis::asprinted::shares_mesh`]).
    pub printed: bool,
    /// Also the element stresses with a corrugated state's bending part, for these section
    /// areas ([`crate::analysis::bending`]), on a mesh the bending part shares (the state's
    /// own, row stride 1, no grading).
    pub bending: Option<Sections2D>,
}

/// What [`state_buckling`] gives.
#[derive(Debug, Clone)]
pub struct StateSolve {
    /// The buckling analysis.
    pub buckling: StateBuckling,
    /// Mode 1 per network node.
    pub mode: NetworkMode,
    /// Mode 1 as a [`ModeGuess`] for the next state (empty when none).
    pub next: ModeGuess,
    /// With [`BucklingRequest::printed`]: the as-printed increment, solved with the buckling
    /// solve's own factor of K (exactly [`crate::analysis::asprinted::cap_increment`]'s, for one
    /// triangular solve instead of a second factorization). `None` on a mesh the pass does not
    /// share, for a single layer or a mechanism.
    pub increment: Option<Increment>,
    /// With [`BucklingRequest::bending`]: the element stresses and the bending summary,
    /// exactly [`crate::analysis::bending::corrugated_stresses`]'s (its shell statics solved as
    /// a load case on the buckling solve's factor). `None` where that solve cannot give them
    /// (another mesh, a single layer, a mechanism) or the state has no unbalanced forces.
    pub stresses: Option<(Vec<ElementStress>, Option<BendingSummary>)>,
}

/// Buckling analysis of one state (its shell model, [`state_shell`], under self-weight, solved by
/// `kappe_fe`), and what `request` asks beyond it. With `converged_blf` the converged estimate
/// ([`StateBuckling::blf`]) is refined up to `options.blf_max_split`: a single state solved
/// outside [`crate::analysis::analyze`] stops at the 2×2 split
/// ([`AnalysisOptions::with_split_at_most`]), [`crate::analysis::analyze`] refines further only
/// the states that could govern (docs/convergence.md).
pub fn state_buckling(
    state: &State,
    material: &ShellMaterial,
    options: &AnalysisOptions,
    request: &BucklingRequest<'_>,
) -> Result<StateSolve, DesignError> {
    // A graded mesh (issue 15, `crate::analysis::graded`) analyses the state reduced to its kept rows; the
    // mode is mapped back to the state's own network nodes.
    let analysed = crate::analysis::graded::AnalysedState::new(state, options.grading.as_ref());
    let shell = match state_shell(analysed.state(), material, options.row_stride) {
        Ok(s) => s,
        Err(NoShell::SingleLayer) => {
            return Ok(StateSolve {
                buckling: StateBuckling {
                    status: BucklingStatus::SingleLayer,
                    factors: Vec::new(),
                    location: None,
                    mechanism: None,
                    shell_nodes: 0,
                    convergence: None,
                },
                mode: Vec::new(),
                next: ModeGuess::new(),
                increment: None,
                stresses: None,
            });
        }
    };
    let keys = crate::analysis::asprinted::node_keys_of(state, &analysed, &shell);
    let start = request
        .guess
        .filter(|g| !g.is_empty())
        .map(|g| guess_start(&keys, g));
    // The as-printed increment's load: the strip that ends in the new top layer
    // (`asprinted::cap_increment`, on this mesh, graded or not).
    let printed = request.printed && crate::analysis::asprinted::shares_mesh(options);
    // The bending part's stresses are per element of the state's own mesh.
    let own_mesh = options.row_stride <= 1 && options.grading.is_none();
    let mut cases = Vec::new();
    if printed {
        cases.push(kappe_fe::LoadCase {
            weight: shell
                .element_layers
                .iter()
                .map(|l| l.1 == state.top_layer)
                .collect(),
            nodal_loads: shell.model.nodal_loads.clone(),
        });
    }
    // The corrugation's bending part: the unbalanced forces on the same shell.
    let unbalanced = match request.bending {
        Some(areas) if own_mesh => {
            let u = crate::analysis::bending::Unbalanced::of(state, areas)?;
            u.any().then_some(u)
        }
        _ => None,
    };
    let bending_case = unbalanced.as_ref().map(|u| u.load_case(&shell));
    cases.extend(bending_case.iter().cloned());
    let Run {
        buckling: b,
        mode,
        full,
        cases: solved,
        ..
    } = shell_buckling_run(&shell, state.index, options, start, &cases)?;
    let mut solved = solved.into_iter();
    let increment = printed.then(|| solved.next()).flatten().map(|r| {
        let inc = crate::analysis::asprinted::increment_of(&shell.model.nodes, &keys, &r);
        crate::analysis::asprinted::on_state(state, &analysed, inc)
    });
    let stresses = match (unbalanced, bending_case, solved.next()) {
        (Some(u), Some(case), Some(st)) => Some(u.stresses(state, &shell, &case, &st)),
        _ => None,
    };
    let mode = mode
        .into_iter()
        .map(|(k, d)| (analysed.full_index(k).unwrap_or(k), d))
        .collect();
    let next = full
        .map(|m| {
            keys.iter()
                .zip(m)
                .filter_map(|(key, d)| key.map(|key| (key, d)))
                .collect()
        })
        .unwrap_or_default();
    Ok(StateSolve {
        buckling: b,
        mode,
        next,
        increment,
        stresses,
    })
}

/// Buckling analysis of a shell model built by [`state_shell`] (`state` names the state in
/// errors). A mechanism is reported with the layers of the free DOFs, not as an error.
pub fn shell_buckling(
    shell: &StateShell,
    state: usize,
    options: &AnalysisOptions,
) -> Result<ShellSolve, DesignError> {
    shell_buckling_run(shell, state, options, None, &[]).map(|r| ShellSolve {
        buckling: r.buckling,
        mode: r.mode,
        static_result: r.static_result,
    })
}

/// What [`shell_buckling`] gives.
#[derive(Debug, Clone)]
pub struct ShellSolve {
    /// The buckling analysis.
    pub buckling: StateBuckling,
    /// Mode 1 per network node.
    pub mode: NetworkMode,
    /// The linear static solution the buckling solve started from (`None` for a mechanism):
    /// the green-state strength checks read its membrane stresses, so they cost no second
    /// factorization (issue 11).
    pub static_result: Option<kappe_fe::StaticResult>,
}

/// What [`shell_buckling_run`] returns.
struct Run {
    buckling: StateBuckling,
    mode: NetworkMode,
    /// Mode 1 with all six freedoms per shell node.
    full: Option<Vec<[f64; 6]>>,
    /// The static solution the buckling solve started from (None for a mechanism).
    static_result: Option<kappe_fe::StaticResult>,
    /// The further load cases' static solutions, in order (empty for a mechanism).
    cases: Vec<kappe_fe::StaticResult>,
}

/// One buckling solve of a shell model, started from `start` (per shell node) if given; also
/// returns mode 1 with all six freedoms per shell node and the static solutions of `cases` on
/// the same factor of K.
fn shell_buckling_run(
    shell: &StateShell,
    state: usize,
    options: &AnalysisOptions,
    start: Option<Vec<[f64; 6]>>,
    cases: &[kappe_fe::LoadCase],
) -> Result<Run, DesignError> {
    let fe_opts = fe_options(options, start);
    let n = shell.model.nodes.len();
    let solved = if cases.is_empty() {
        kappe_fe::buckling(&shell.model, &fe_opts).map(|r| (r, Vec::new()))
    } else {
        kappe_fe::BucklingSolver::new(&shell.model)
            .and_then(|s| s.buckling_with_cases(&shell.model, &fe_opts, cases))
    };
    match solved {
        Ok((r, solved_cases)) => {
            let static_result = Some(r.static_result.clone());
            let location = r.modes.first().and_then(|m| {
                let (i, _) = m
                    .iter()
                    .enumerate()
                    .map(|(i, d)| (i, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
                    .max_by(|a, b| a.1.total_cmp(&b.1))?;
                Some((*shell.node_layer.get(i)?, *shell.model.nodes.get(i)?))
            });
            let mode = r
                .modes
                .first()
                .map(|m| {
                    m.iter()
                        .zip(&shell.network_node)
                        .map(|(d, &ni)| (ni, [d[0], d[1], d[2]]))
                        .collect()
                })
                .unwrap_or_default();
            // `blf_max_split` 1: the print-layer mesh alone (the first pass of `analyze`).
            let convergence = if options.converged_blf && options.blf_max_split >= 2 {
                kappe_fe::converge_factor(
                    &shell.model,
                    &r,
                    &fe_opts,
                    options.blf_tolerance,
                    options.blf_max_split,
                )
                .map_err(|e| DesignError::State {
                    state,
                    message: format!("buckling analysis of the refined mesh failed: {e}"),
                })?
            } else {
                None
            };
            let full = r.modes.into_iter().next();
            Ok(Run {
                buckling: StateBuckling {
                    status: if r.factors.is_empty() {
                        BucklingStatus::NoPositiveFactor
                    } else {
                        BucklingStatus::Analysed
                    },
                    factors: r.factors,
                    location,
                    mechanism: None,
                    shell_nodes: n,
                    convergence,
                },
                mode,
                full,
                static_result,
                cases: solved_cases,
            })
        }
        Err(kappe_fe::FeError::Mechanism { free_dofs }) => {
            let mut layers: Vec<i32> = free_dofs
                .iter()
                .filter_map(|d| shell.node_layer.get(d.node).copied())
                .collect();
            let first = free_dofs.first().and_then(|d| {
                Some((
                    *shell.node_layer.get(d.node)?,
                    *shell.model.nodes.get(d.node)?,
                ))
            });
            layers.sort_unstable();
            layers.dedup();
            let dofs: Vec<String> = free_dofs.iter().take(6).map(|d| d.to_string()).collect();
            Ok(Run {
                buckling: StateBuckling {
                    status: BucklingStatus::Mechanism,
                    factors: Vec::new(),
                    location: first,
                    mechanism: Some(format!(
                        "the shell model is a mechanism in layer(s) {layers:?} (free DOFs: {})",
                        dofs.join(", ")
                    )),
                    shell_nodes: n,
                    convergence: None,
                },
                mode: Vec::new(),
                full: None,
                static_result: None,
                cases: Vec::new(),
            })
        }
        Err(e) => Err(DesignError::State {
            state,
            message: format!("buckling analysis failed: {e}"),
        }),
    }
}

/// The eigen-solver options of a state's buckling solve (the print-layer mesh and its splits).
fn fe_options(
    options: &AnalysisOptions,
    start: Option<Vec<[f64; 6]>>,
) -> kappe_fe::BucklingOptions {
    kappe_fe::BucklingOptions {
        modes: options.modes,
        // The BLF is compared with a calibrated threshold; 1e-8 relative is far below any
        // modelling error and saves Lanczos steps over the default 1e-10. A graded mesh is
        // itself an approximation (≤ 1 %, `crate::analysis::graded`): there 1e-6 suffices, since a Ritz
        // value with relative residual r lies within r (and, given the gap to the next mode,
        // within ~r²) of an eigenvalue of the symmetric operator.
        // With the mesh error controlled (0.5 % by default) 1e-5 is still 500 times below it
        // (a Ritz value is within its relative residual of an eigenvalue).
        tolerance: if options.converged_blf {
            1e-5
        } else if options.grading.is_some() {
            1e-6
        } else {
            1e-8
        },
        sturm_check: options.sturm_check,
        start,
        ..Default::default()
    }
}

/// A mode kept as a [`ModeGuess`] (the analysis's first pass keeps each state's mode 1 so)
/// on the nodes of `shell`, the ungraded shell of `state` (the collapse check's,
/// docs/collapse.md §3): `None` unless every node of `shell` has a key, no two share one and
/// the guess holds exactly these keys. Then the vector is the kept mode itself, node for node,
/// and the guess was solved on this very mesh.
pub fn mode_on_shell(state: &State, shell: &StateShell, mode: &ModeGuess) -> Option<Vec<[f64; 6]>> {
    let analysed = crate::analysis::graded::AnalysedState::new(state, None);
    let keys = crate::analysis::asprinted::node_keys_of(state, &analysed, shell);
    if keys.len() != mode.len() {
        return None;
    }
    let mut seen = HashSet::with_capacity(keys.len());
    keys.iter()
        .map(|k| {
            let k = (*k)?;
            seen.insert(k).then_some(())?;
            mode.get(&k).copied()
        })
        .collect()
}

/// A start vector per shell node (`keys`: [`crate::analysis::asprinted::node_keys_of`]) from
/// the mode `g`: a layer missing from `g` takes the nearest layer below it, a node without a key
/// zero.
fn guess_start(keys: &[Option<(i32, usize)>], g: &ModeGuess) -> Vec<[f64; 6]> {
    keys.iter()
        .map(|key| {
            key.and_then(|(layer, k)| {
                (0..GUESS_REACH).find_map(|down| g.get(&(layer - down, k)).copied())
            })
            .unwrap_or([0.0; 6])
        })
        .collect()
}

/// The mesh-error levels (`kappe_fe::converge_from`: the 2×2 split, and further up to
/// `options.blf_max_split` while the error exceeds `blf_tolerance`) of a state whose
/// print-layer mesh was already solved by [`state_buckling`] with the same `material` and
/// `options`: `coarse` is that solve's lowest factor and `mode` its mode 1 (the [`ModeGuess`] it
/// returned), which starts the split's Lanczos. Solving the print-layer mesh again, from a cold
/// start, cost the mesh-error pass about a sixth of its time (docs/convergence.md, "Speed").
/// `None` when the state has no shell or the split has no positive factor.
///
/// # Errors
/// A split mesh that cannot be solved.
pub fn state_refine(
    state: &State,
    material: &ShellMaterial,
    options: &AnalysisOptions,
    coarse: f64,
    mode: &ModeGuess,
) -> Result<Option<kappe_fe::ConvergedFactor>, DesignError> {
    let analysed = crate::analysis::graded::AnalysedState::new(state, options.grading.as_ref());
    let Ok(shell) = state_shell(analysed.state(), material, options.row_stride) else {
        return Ok(None);
    };
    let keys = crate::analysis::asprinted::node_keys_of(state, &analysed, &shell);
    let start = (!mode.is_empty()).then(|| guess_start(&keys, mode));
    let fe_opts = fe_options(options, None);
    let level = kappe_fe::MeshLevel {
        split: 1,
        factor: coarse,
        n_free_dofs: 0,
        steps: 0,
    };
    kappe_fe::converge_from(
        &shell.model,
        level,
        start,
        &fe_opts,
        options.blf_tolerance,
        options.blf_max_split,
    )
    .map_err(|e| DesignError::State {
        state: state.index,
        message: format!("buckling analysis of the refined mesh failed: {e}"),
    })
}
