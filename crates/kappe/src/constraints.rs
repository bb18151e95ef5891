//! Analysis of every print state against the structural constraints of method.md §3, and the
//! constraint report (the paper's design loop, Figure 3: "analyse every state globally and
//! locally").
//!
//! Per state:
//! - **Stresses.** Every element's normal stress σ = N / A (compression negative), with
//!   A = lw·lh for arch segments (along a layer) and A = lw·l_trib for the bed joints between
//!   layers (the column edges), from CEM's fixed-geometry force pass over the constructed
//!   network ([`crate::forces`]). Checked against σ_min ≤ σ ≤ σ_max.
//! - **Overhang.** |l_o| of every printed layer over the preceding one
//!   ([`crate::analysis::layer_overhangs`]) against l_o,max.
//! - **Buckling.** The lowest positive linear buckling factor of the state's shell model
//!   ([`crate::shell`], `kappe_fe`) under self-weight, against BLF_min. A state whose shell
//!   model is a mechanism is reported with the layer where the free motion sits.
//!
//! The report ([`ConstraintResult`]) gives for each constraint its limit, the worst value over all
//! states, where it occurs (state and element) and pass/fail; the design passes only if all hold.
//!
//! Stresses and overhangs are cheap and always checked in every state; [`StateSelection`] thins
//! out only the buckling analysis (the final state is always included, as it carries the most
//! load). States are analysed in parallel (rayon) and reported in print order.
//!
//! Tolerances: a stress passes if it is within `1e-9·max|σ|` of its limit (the relative size of
//! the force pass's residuals, method.md §9), so that σ_max = 0 is not failed by round-off.

use std::collections::HashMap;
use std::str::FromStr;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::DesignError;
use crate::forces::{Sections2D, state_forces};
use crate::pipeline::Cap;
use crate::shell::{NoShell, ShellMaterial, StateShell, state_shell};
use crate::states::{Role, State, build_state};

/// Relative tolerance on stress limits (see the module docs).
pub const STRESS_REL_TOL: f64 = 1e-9;

/// Which states get a buckling analysis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum StateSelection {
    /// Every state (default; the paper used 25 % steps, Kappe checks every layer).
    #[default]
    All,
    /// States 0, N, 2N, … and the final state (`"every:N"`).
    Every(usize),
    /// States at every P % of print progress and the final state (`"25%"`).
    Percent(f64),
}

/// A `--states` value that is not `all`, `every:N` or `P%`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "state selection {given:?}: {reason}; allowed: \"all\", \"every:N\" with N ≥ 1, or \"P%\" with 0 < P ≤ 100"
)]
pub struct SelectionError {
    /// The text given.
    pub given: String,
    /// What is wrong with it.
    pub reason: String,
}

impl FromStr for StateSelection {
    type Err = SelectionError;

    /// Parse `"all"`, `"every:N"` or `"P%"`.
    ///
    /// ```
    /// use kappe::constraints::StateSelection;
    /// assert_eq!("every:4".parse::<StateSelection>().unwrap(), StateSelection::Every(4));
    /// assert_eq!("25%".parse::<StateSelection>().unwrap(), StateSelection::Percent(25.0));
    /// assert!("every:0".parse::<StateSelection>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        let err = |reason: &str| SelectionError {
            given: s.to_string(),
            reason: reason.to_string(),
        };
        if t.eq_ignore_ascii_case("all") {
            return Ok(StateSelection::All);
        }
        if let Some(n) = t.strip_prefix("every:") {
            let n: usize = n
                .trim()
                .parse()
                .map_err(|_| err("N is not a whole number"))?;
            if n == 0 {
                return Err(err("N must be at least 1"));
            }
            return Ok(StateSelection::Every(n));
        }
        if let Some(p) = t.strip_suffix('%') {
            let p: f64 = p.trim().parse().map_err(|_| err("P is not a number"))?;
            if !(p > 0.0 && p <= 100.0) {
                return Err(err("P is out of range"));
            }
            return Ok(StateSelection::Percent(p));
        }
        Err(err("unknown form"))
    }
}

impl std::fmt::Display for StateSelection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StateSelection::All => write!(f, "all"),
            StateSelection::Every(n) => write!(f, "every:{n}"),
            StateSelection::Percent(p) => write!(f, "{p}%"),
        }
    }
}

impl Serialize for StateSelection {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for StateSelection {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

impl StateSelection {
    /// The selected state indices among `total` states, ascending; always includes the final
    /// state. `Percent(p)` takes the states whose progress first reaches k·p % (k = 1, 2, …).
    pub fn indices(&self, total: usize) -> Vec<usize> {
        if total == 0 {
            return Vec::new();
        }
        let mut v: Vec<usize> = match *self {
            StateSelection::All => (0..total).collect(),
            StateSelection::Every(n) => (0..total).step_by(n.max(1)).collect(),
            StateSelection::Percent(p) => {
                let steps = (100.0 / p).ceil() as usize;
                (1..=steps)
                    .map(|k| {
                        let pp = (k as f64 * p / 100.0).min(1.0);
                        // progress of state i is (i + 1) / total
                        ((pp * total as f64).ceil() as usize).clamp(1, total) - 1
                    })
                    .collect()
            }
        };
        v.push(total - 1);
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// Linear ageing of the green material (buckling.md §6, Wolfs et al. 2018):
/// `E(t) = min(E₀ + Ė·t, E_max)`, t the age of a layer at the state (time since it was printed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ageing {
    /// E₀: modulus of a freshly printed layer, Pa (> 0).
    pub initial_modulus: f64,
    /// Ė: growth rate, Pa/s (≥ 0).
    pub rate: f64,
    /// E_max: cap on the modulus, Pa (optional).
    #[serde(default)]
    pub max_modulus: Option<f64>,
}

impl Ageing {
    /// E at age `t` seconds.
    pub fn modulus(&self, t: f64) -> f64 {
        let e = self.initial_modulus + self.rate * t.max(0.0);
        match self.max_modulus {
            Some(m) => e.min(m),
            None => e,
        }
    }
}

fn default_modes() -> usize {
    1
}
fn default_stride() -> usize {
    1
}
fn default_true() -> bool {
    true
}

/// Options of [`analyze`]; every field has a serde default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisOptions {
    /// States that get a buckling analysis (stresses and overhangs: always every state).
    #[serde(default)]
    pub states: StateSelection,
    /// Buckling modes per state (the BLF is the lowest); ≥ 1.
    #[serde(default = "default_modes")]
    pub modes: usize,
    /// Layer ageing; `None`: E of the design everywhere.
    #[serde(default)]
    pub ageing: Option<Ageing>,
    /// Printed layers per shell mesh row (1 = every layer is a row).
    #[serde(default = "default_stride")]
    pub row_stride: usize,
    /// Run the buckling analysis at all (false: stresses and overhang only).
    #[serde(default = "default_true")]
    pub buckling: bool,
    /// Prove with a Sturm count that no lower factor was missed (one extra factorization).
    #[serde(default)]
    pub sturm_check: bool,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        AnalysisOptions {
            states: StateSelection::All,
            modes: default_modes(),
            ageing: None,
            row_stride: default_stride(),
            buckling: true,
            sturm_check: false,
        }
    }
}

impl AnalysisOptions {
    /// Check the options (typed errors naming the field).
    pub fn validate(&self) -> Result<(), DesignError> {
        let bad = |field: &'static str, value: String, allowed: &str| DesignError::Invalid {
            field,
            value,
            allowed: allowed.to_string(),
        };
        if self.modes == 0 || self.modes > 50 {
            return Err(bad(
                "analysis.modes",
                self.modes.to_string(),
                "allowed: 1 ≤ modes ≤ 50",
            ));
        }
        if self.row_stride == 0 || self.row_stride > 16 {
            return Err(bad(
                "analysis.row_stride",
                self.row_stride.to_string(),
                "allowed: 1 ≤ layers per mesh row ≤ 16",
            ));
        }
        if let Some(a) = &self.ageing {
            if !(a.initial_modulus.is_finite() && a.initial_modulus > 0.0) {
                return Err(bad(
                    "analysis.ageing.initial_modulus",
                    a.initial_modulus.to_string(),
                    "allowed: E₀ > 0 Pa",
                ));
            }
            if !(a.rate.is_finite() && a.rate >= 0.0) {
                return Err(bad(
                    "analysis.ageing.rate",
                    a.rate.to_string(),
                    "allowed: Ė ≥ 0 Pa/s",
                ));
            }
            if let Some(m) = a.max_modulus
                && !(m.is_finite() && m >= a.initial_modulus)
            {
                return Err(bad(
                    "analysis.ageing.max_modulus",
                    m.to_string(),
                    "allowed: E_max ≥ E₀",
                ));
            }
        }
        Ok(())
    }
}

/// What the buckling analysis of a state did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
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

/// The analysis of one print state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StateAnalysis {
    /// State index (0 = first layer printed).
    pub index: usize,
    /// Id of the top layer.
    pub top_layer: i32,
    /// Lowest positive buckling factor (None: not analysed, no shell or mechanism).
    pub blf: Option<f64>,
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
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
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
}

impl Analysis {
    /// The constraints that fail.
    pub fn failing(&self) -> impl Iterator<Item = &ConstraintResult> {
        self.constraints.iter().filter(|c| !c.pass)
    }

    /// The report as plain text, one line per constraint.
    pub fn report(&self) -> String {
        let mut s = String::new();
        for c in &self.constraints {
            let worst = c.worst.map_or("n/a".to_string(), |w| format!("{w:.6e}"));
            let at = c
                .state
                .map_or(String::new(), |st| format!(" at state {st}, {}", c.element));
            s.push_str(&format!(
                "{:<13} {:<4} limit {:.6e} {}, worst {worst}{at}\n",
                c.name,
                if c.pass { "PASS" } else { "FAIL" },
                c.limit,
                c.unit,
            ));
        }
        s.push_str(if self.ok {
            "design passes every constraint\n"
        } else {
            "design FAILS\n"
        });
        s
    }
}

/// Kind and place of an element of a state network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ElementKind {
    /// Arch segment `segment` (0 = from the left foot) of layer `layer`: A = lw·lh.
    ArchSegment {
        /// Layer id.
        layer: i32,
        /// Segment index along the layer.
        segment: usize,
    },
    /// Column edge from layer `upper` to layer `lower` (a bed joint): A = lw·l_trib.
    BedJoint {
        /// Layer id of the upper node.
        upper: i32,
        /// Layer id of the lower node.
        lower: i32,
    },
    /// The last column edge below layer `layer`, to the base plane: A = lw·l_trib.
    ColumnFoot {
        /// Layer id.
        layer: i32,
    },
}

impl std::fmt::Display for ElementKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ElementKind::ArchSegment { layer, segment } => {
                write!(f, "arch segment {segment} of layer {layer}")
            }
            ElementKind::BedJoint { upper, lower } => {
                write!(f, "bed joint between layers {lower} and {upper}")
            }
            ElementKind::ColumnFoot { layer } => {
                write!(f, "column foot below layer {layer} (on the base plane)")
            }
        }
    }
}

/// Normal stress of one element of a state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ElementStress {
    /// What and where.
    pub kind: ElementKind,
    /// Network node indices.
    pub nodes: [usize; 2],
    /// Signed force, N.
    pub force: f64,
    /// Area, m².
    pub area: f64,
    /// σ = N / A, Pa.
    pub stress: f64,
}

/// The normal stress of every element of `state` (method.md §3): arch segments with
/// A = lw·lh, column edges with A = lw·l_trib.
pub fn element_stresses(
    state: &State,
    areas: Sections2D,
) -> Result<Vec<ElementStress>, DesignError> {
    let net = &state.network;
    let (topo, fp, _) = state_forces(state, areas)?;
    let mut out = Vec::with_capacity(topo.trail_edges.len() + topo.deviation_edges.len());
    // Segment index of a node within its layer: nodes of a layer are contiguous, foot first.
    let mut first_of_layer: HashMap<i32, usize> = HashMap::new();
    for (i, n) in net.nodes.iter().enumerate() {
        if n.role != Role::ColumnEnd {
            first_of_layer.entry(n.layer).or_insert(i);
        }
    }
    for e in &net.deviation_edges {
        let first = first_of_layer.get(&e.layer).copied().unwrap_or(e.u);
        out.push(ElementStress {
            kind: ElementKind::ArchSegment {
                layer: e.layer,
                segment: e.u.min(e.v).saturating_sub(first),
            },
            nodes: [e.u, e.v],
            force: e.force,
            area: areas.along_layer,
            stress: e.force / areas.along_layer,
        });
    }
    for (edge, &f) in topo.trail_edges.iter().zip(&fp.trail_forces) {
        let (u, v) = (edge.u as usize, edge.v as usize);
        let (Some(nu), Some(nv)) = (net.nodes.get(u), net.nodes.get(v)) else {
            continue;
        };
        let kind = if nv.role == Role::ColumnEnd {
            ElementKind::ColumnFoot { layer: nu.layer }
        } else {
            ElementKind::BedJoint {
                upper: nu.layer.max(nv.layer),
                lower: nu.layer.min(nv.layer),
            }
        };
        out.push(ElementStress {
            kind,
            nodes: [u, v],
            force: f,
            area: areas.bed_joint,
            stress: f / areas.bed_joint,
        });
    }
    Ok(out)
}

/// Age of every layer (print order) at the state whose top has print index `top`, s: the print
/// time of the layers printed after it (layer length / print speed).
fn layer_ages(cap: &Cap, top: usize) -> Vec<(i32, f64)> {
    let speed = cap.design.print.print_speed;
    let layers = &cap.sections.layers;
    let mut ages = Vec::with_capacity(top + 1);
    let mut t = 0.0;
    for q in (0..=top.min(layers.len().saturating_sub(1))).rev() {
        ages.push((layers[q].id, t));
        t += layers[q].length() / speed;
    }
    ages.reverse();
    ages
}

/// The shell material of the state with top print index `top`.
pub fn state_material(cap: &Cap, options: &AnalysisOptions, top: usize) -> ShellMaterial {
    let d = &cap.design;
    let layer_modulus = match &options.ageing {
        None => HashMap::new(),
        Some(a) => layer_ages(cap, top)
            .into_iter()
            .map(|(id, t)| (id, a.modulus(t)))
            .collect(),
    };
    ShellMaterial {
        thickness: d.print.layer_width,
        poisson_ratio: d.material.poisson_ratio,
        unit_weight: d.material.specific_weight,
        layer_modulus,
        youngs_modulus: d.material.youngs_modulus,
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
}

/// Buckling analysis of one state (shell model + `kappe_fe::buckling`).
pub fn state_buckling(
    state: &State,
    material: &ShellMaterial,
    options: &AnalysisOptions,
) -> Result<StateBuckling, DesignError> {
    let shell = match state_shell(state, material, options.row_stride) {
        Ok(s) => s,
        Err(NoShell::SingleLayer) => {
            return Ok(StateBuckling {
                status: BucklingStatus::SingleLayer,
                factors: Vec::new(),
                location: None,
                mechanism: None,
                shell_nodes: 0,
            });
        }
    };
    shell_buckling(&shell, state.index, options)
}

/// Buckling analysis of a shell model built by [`state_shell`] (`state` names the state in
/// errors). A mechanism is reported with the layers of the free DOFs, not as an error.
pub fn shell_buckling(
    shell: &StateShell,
    state: usize,
    options: &AnalysisOptions,
) -> Result<StateBuckling, DesignError> {
    let fe_opts = kappe_fe::BucklingOptions {
        modes: options.modes,
        // The BLF is compared with a calibrated threshold; 1e-8 relative is far below any
        // modelling error and saves Lanczos steps over the default 1e-10.
        tolerance: 1e-8,
        sturm_check: options.sturm_check,
        ..Default::default()
    };
    let n = shell.model.nodes.len();
    match kappe_fe::buckling(&shell.model, &fe_opts) {
        Ok(r) => {
            let location = r.modes.first().and_then(|m| {
                let (i, _) = m
                    .iter()
                    .enumerate()
                    .map(|(i, d)| (i, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
                    .max_by(|a, b| a.1.total_cmp(&b.1))?;
                Some((*shell.node_layer.get(i)?, *shell.model.nodes.get(i)?))
            });
            Ok(StateBuckling {
                status: if r.factors.is_empty() {
                    BucklingStatus::NoPositiveFactor
                } else {
                    BucklingStatus::Analysed
                },
                factors: r.factors,
                location,
                mechanism: None,
                shell_nodes: n,
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
            Ok(StateBuckling {
                status: BucklingStatus::Mechanism,
                factors: Vec::new(),
                location: first,
                mechanism: Some(format!(
                    "the shell model is a mechanism in layer(s) {layers:?} (free DOFs: {})",
                    dofs.join(", ")
                )),
                shell_nodes: n,
            })
        }
        Err(e) => Err(DesignError::State {
            state,
            message: format!("buckling analysis failed: {e}"),
        }),
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

/// Analyse every state of `cap` (see the module docs). `on_state(n)` is called once per
/// buckling analysis finished (for a progress bar), with the number `n` of them.
pub fn analyze(
    cap: &Cap,
    options: &AnalysisOptions,
    on_state: &(dyn Fn(usize) + Sync),
) -> Result<Analysis, DesignError> {
    options.validate()?;
    let t_all = Instant::now();
    let design = &cap.design;
    let total = cap.states.len();
    let areas = cap.areas();
    let phi = design.print.start_arch_fraction;
    let selected: Vec<bool> = {
        let mut s = vec![false; total];
        if options.buckling {
            for i in options.states.indices(total) {
                if let Some(x) = s.get_mut(i) {
                    *x = true;
                }
            }
        }
        s
    };

    struct PerState {
        stresses: Vec<ElementStress>,
        stress_seconds: f64,
        buckling: Option<StateBuckling>,
        fe_seconds: f64,
        top_layer: i32,
    }
    // Phase 1: every state's force pass and element stresses (cheap).
    let t_phase = Instant::now();
    let mut per: Vec<PerState> = (0..total)
        .into_par_iter()
        .map(|top| {
            let t0 = Instant::now();
            let state = build_state(&cap.sections, &cap.frame, phi, top)?;
            let stresses = element_stresses(&state, areas)?;
            Ok(PerState {
                stresses,
                stress_seconds: t0.elapsed().as_secs_f64(),
                buckling: None,
                fe_seconds: 0.0,
                top_layer: state.top_layer,
            })
        })
        .collect::<Result<_, DesignError>>()?;
    let wall_stresses = t_phase.elapsed().as_secs_f64();
    // Phase 2: the buckling analysis of the selected states, largest first so the two cores
    // finish together.
    let t_phase = Instant::now();
    let mut order: Vec<usize> = (0..total).filter(|&i| selected[i]).collect();
    order.reverse();
    let n_fe = order.len();
    let fe: Vec<(usize, StateBuckling, f64)> = order
        .into_par_iter()
        .map(|top| {
            let t0 = Instant::now();
            let state = build_state(&cap.sections, &cap.frame, phi, top)?;
            let mat = state_material(cap, options, top);
            let b = state_buckling(&state, &mat, options)?;
            on_state(n_fe);
            Ok((top, b, t0.elapsed().as_secs_f64()))
        })
        .collect::<Result<_, DesignError>>()?;
    let wall_fe = t_phase.elapsed().as_secs_f64();
    for (top, b, secs) in fe {
        if let Some(p) = per.get_mut(top) {
            p.buckling = Some(b);
            p.fe_seconds = secs;
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
    let stress_scale = per
        .iter()
        .flat_map(|p| p.stresses.iter())
        .fold(0.0_f64, |m, s| m.max(s.stress.abs()));
    let stol = STRESS_REL_TOL * stress_scale;

    let mut w_comp: Option<Worst> = None;
    let mut w_tens: Option<Worst> = None;
    let mut w_blf: Option<Worst> = None;
    let mut w_lo: Option<Worst> = None;
    let mut blf_checked = 0;
    let mut states = Vec::with_capacity(total);
    let mut running_lo: f64 = 0.0;
    let (mut t_stress, mut t_fe) = (0.0, 0.0);
    for (q, p) in per.iter().enumerate() {
        t_stress += p.stress_seconds;
        t_fe += p.fe_seconds;
        let mut smin: f64 = 0.0;
        let mut smax: f64 = 0.0;
        for s in &p.stresses {
            smin = smin.min(s.stress);
            smax = smax.max(s.stress);
            keep_min(&mut w_comp, s.stress, q, || s.kind.to_string());
            keep_max(&mut w_tens, s.stress, q, || s.kind.to_string());
        }
        let lo = overhang_of(q);
        let layer_id = cap.sections.layers.get(q).map_or(0, |l| l.id);
        keep_max(&mut w_lo, lo, q, || format!("layer {layer_id}"));
        running_lo = running_lo.max(lo);
        let mut ok = smin >= sigma_min - stol && smax <= sigma_max + stol && running_lo <= lo_max;
        let (mut blf, mut modes, mut status, mut mechanism, mut nodes) =
            (None, Vec::new(), BucklingStatus::Skipped, None, 0);
        if let Some(b) = &p.buckling {
            status = b.status;
            modes = b.factors.clone();
            blf = b.factors.first().copied();
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
        states.push(StateAnalysis {
            index: q,
            top_layer: p.top_layer,
            blf,
            blf_modes: modes,
            buckling: status,
            max_compression_stress_pa: smin,
            max_tension_stress_pa: smax,
            max_overhang_m: running_lo,
            ok,
            mechanism,
            shell_nodes: nodes,
            fe_seconds: p.fe_seconds,
        });
    }

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
    let constraints = vec![
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
    let ok = constraints.iter().all(|c| c.pass);
    Ok(Analysis {
        states,
        constraints,
        ok,
        options: options.clone(),
        timings: Timings {
            stresses: wall_stresses,
            stresses_sum: t_stress,
            fe: wall_fe,
            fe_sum: t_fe,
            total: t_all.elapsed().as_secs_f64(),
        },
    })
}
