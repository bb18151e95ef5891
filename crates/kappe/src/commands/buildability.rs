//! Buildability of the standard test objects (green-state.md §3–5): a free-standing straight
//! wall or a cylinder printed layer by layer on the bed, every layer count n = 1, 2, … checked
//! with the green-state check of the cap ([`crate::analysis::check_state`]: the time model, the
//! shell FE, strength and bed-joint sliding). Only the geometry differs from the cap.
//!
//! **Mesh.** One shell row per bed joint: rows at z = 0, h, …, n·h on the centre line (wall:
//! the segment x ∈ [0, L] in y = 0; cylinder: the circle of radius R), `segments` elements
//! along it, so the strip between rows k and k + 1 is layer k (print index) and its elements
//! take layer k's age. Thickness = bead width. The base row is clamped (the first layer is
//! bonded to the bed); the top and (wall) the ends are free. Self-weight γ·t per unit area.
//!
//! **Schedule.** Constant layer time T (given, or centre-line length / print speed) plus the
//! optional waits; a layer's age is the time since it was completed, so with no waits layer k
//! below the top has age k·T.
//!
//! A state fails when BLF < `blf_min`, or a strength or sliding utilisation exceeds 1; the
//! `failure_mode` is the failing check with the largest utilisation (BLF_min/BLF for
//! buckling).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use kappe_fe::{Material, ShellModel, Support};

use crate::analysis::collapse::{
    Collapse, CollapseMode, CollapseOptions, ObjectIncrements, collapse_factor,
    object_as_printed_shift_cached, shifted,
};
use crate::analysis::green::{
    BucklingOutcome, ElementLayers, FailureMode, GreenOptions, ModeStart, WorstElement, check_state,
};
use crate::input::error::DesignError;
use crate::input::material::{TimeModel, TimeModelSpec};
use crate::input::nonlinear::{BaseRestraint, NonlinearSpec, PathStart};
use crate::schedule::{Schedule, ScheduleSpec};

/// The test object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectKind {
    /// A straight wall, ends free.
    Wall,
    /// A circular cylinder.
    Cylinder,
}

/// `[object]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Wall or cylinder.
    pub kind: ObjectKind,
    /// Wall: length on the bed, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<f64>,
    /// Cylinder: centre-line radius, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Bead width = wall thickness, m.
    pub width: f64,
    /// Layer height, m.
    pub layer_height: f64,
    /// Stop here if nothing fails.
    pub max_layers: usize,
    /// Elements along the centre line (default: wall ⌈L/(4h)⌉ in [4, 64]; cylinder 48).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<usize>,
}

/// `[process]`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcessSpec {
    /// Time per layer, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_time: Option<f64>,
    /// Nozzle speed along the centre line, m/s (layer time = centre-line length / speed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub print_speed: Option<f64>,
    /// Wait after every layer, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wait: Option<f64>,
    /// Wait after each layer, s (empty or one per layer up to `max_layers`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub waits: Vec<f64>,
}

/// `[material]` of a buildability spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildMaterial {
    /// γ, N/m³.
    pub specific_weight: f64,
    /// ν.
    pub poisson_ratio: f64,
    /// E₀ if `[material.time]` gives none, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    /// The time model (the same table as a cap design's).
    pub time: TimeModelSpec,
}

/// `[checks]` (optional).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ChecksSpec {
    /// Smallest admissible BLF (1: the state buckles under its own weight).
    pub blf_min: f64,
    /// Check elastic buckling.
    pub buckling: bool,
    /// Check strength.
    pub strength: bool,
    /// Check bed-joint sliding.
    pub sliding: bool,
    /// Stop at the first failing layer count (false: check up to `max_layers`).
    pub stop_at_failure: bool,
    /// Smallest admissible collapse factor (with `[analysis.nonlinear]`; docs/collapse.md).
    pub collapse_min: f64,
}

impl ChecksSpec {
    /// The green-state check of one layer count with these checks (the deterministic check and
    /// the reliability tables solve the same one).
    pub fn green_options(&self) -> GreenOptions {
        GreenOptions {
            blf_min: self.blf_min,
            buckling: self.buckling,
            strength: self.strength,
            sliding: self.sliding,
            ..Default::default()
        }
    }
}

impl Default for ChecksSpec {
    fn default() -> Self {
        ChecksSpec {
            blf_min: 1.0,
            buckling: true,
            strength: true,
            sliding: true,
            stop_at_failure: true,
            collapse_min: 1.0,
        }
    }
}

/// A buildability spec file (`kappe buildability SPEC.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildabilitySpec {
    /// A name for reports.
    #[serde(default)]
    pub name: String,
    /// The object.
    pub object: ObjectSpec,
    /// Printing.
    #[serde(default)]
    pub process: ProcessSpec,
    /// Material.
    pub material: BuildMaterial,
    /// Checks.
    #[serde(default)]
    pub checks: ChecksSpec,
    /// `[analysis]`: the nonlinear collapse check (`[analysis.nonlinear]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub analysis: Option<BuildAnalysis>,
    /// `[uncertainty]`: the chance the object stands (issue 24;
    /// [`crate::commands::buildability_reliability`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<crate::input::uncertainty::UncertaintyTable>,
}

/// `[analysis]` of a buildability spec.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildAnalysis {
    /// The collapse check of every layer count (docs/collapse.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonlinear: Option<NonlinearSpec>,
}

impl BuildabilitySpec {
    /// The collapse check's options, if `[analysis.nonlinear]` is given and enabled.
    pub fn nonlinear(&self) -> Option<&NonlinearSpec> {
        self.analysis
            .as_ref()
            .and_then(|a| a.nonlinear.as_ref())
            .filter(|n| n.enabled)
    }

    /// How the first layer is held (clamped unless `[analysis.nonlinear] base` says otherwise).
    pub fn base(&self) -> BaseRestraint {
        self.analysis
            .as_ref()
            .and_then(|a| a.nonlinear.as_ref())
            .map_or(BaseRestraint::Clamped, |n| n.base)
    }
}

/// The commented example `kappe init --kind buildability` writes: the Wolfs 2018 cylinder.
pub const EXAMPLE_TOML: &str = include_str!("buildability_example.toml");

fn bad(field: &'static str, value: impl ToString, allowed: &str) -> DesignError {
    DesignError::Invalid {
        field,
        value: value.to_string(),
        allowed: format!("allowed: {allowed}"),
    }
}

fn pos(field: &'static str, v: f64) -> Result<f64, DesignError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(bad(field, v, "a finite value > 0"))
    }
}

/// A checked spec, ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    /// The spec.
    pub spec: BuildabilitySpec,
    /// The time model.
    pub time: TimeModel,
    /// Layer time, s.
    pub layer_time: f64,
    /// Schedule for `max_layers` layers.
    pub schedule: Schedule,
    /// Elements along the centre line.
    pub segments: usize,
    /// Centre-line length of one layer, m.
    pub path_length: f64,
}

impl BuildabilitySpec {
    /// Parse TOML (unknown fields are errors with a did-you-mean hint) without checking the
    /// values (see [`BuildabilitySpec::resolve`]).
    pub fn parse(text: &str) -> Result<BuildabilitySpec, DesignError> {
        crate::input::design::parse_toml(text)
    }

    /// Parse TOML (unknown fields are errors with a did-you-mean hint) and check it.
    pub fn from_toml_str(text: &str) -> Result<Resolved, DesignError> {
        let spec: BuildabilitySpec = crate::input::design::parse_toml(text)?;
        spec.resolve()
    }

    /// Check every field and resolve the time model and schedule.
    pub fn resolve(&self) -> Result<Resolved, DesignError> {
        let o = &self.object;
        pos("object.width", o.width)?;
        pos("object.layer_height", o.layer_height)?;
        if o.max_layers == 0 || o.max_layers > 2000 {
            return Err(bad(
                "object.max_layers",
                o.max_layers,
                "1 ≤ max_layers ≤ 2000",
            ));
        }
        let path_length = match o.kind {
            ObjectKind::Wall => {
                let Some(l) = o.length else {
                    return Err(bad("object.length", "missing", "a wall needs length > 0 m"));
                };
                pos("object.length", l)?
            }
            ObjectKind::Cylinder => {
                let Some(r) = o.radius else {
                    return Err(bad(
                        "object.radius",
                        "missing",
                        "a cylinder needs its centre-line radius > 0 m",
                    ));
                };
                let r = pos("object.radius", r)?;
                if o.width >= 2.0 * r {
                    return Err(bad(
                        "object.width",
                        o.width,
                        "a wall thinner than the cylinder's diameter",
                    ));
                }
                2.0 * std::f64::consts::PI * r
            }
        };
        let segments = match o.segments {
            Some(s) if (3..=2000).contains(&s) => s,
            Some(s) => return Err(bad("object.segments", s, "3 ≤ segments ≤ 2000")),
            None => match o.kind {
                ObjectKind::Wall => {
                    ((path_length / (4.0 * o.layer_height)).ceil() as usize).clamp(4, 64)
                }
                ObjectKind::Cylinder => 48,
            },
        };
        let m = &self.material;
        pos("material.specific_weight", m.specific_weight)?;
        if !(m.poisson_ratio.is_finite() && (0.0..0.5).contains(&m.poisson_ratio)) {
            return Err(bad(
                "material.poisson_ratio",
                m.poisson_ratio,
                "0 ≤ ν < 0.5",
            ));
        }
        let e_default = match m.youngs_modulus {
            Some(e) => pos("material.youngs_modulus", e)?,
            None => m.time.with_preset().youngs_modulus.ok_or_else(|| {
                bad(
                    "material.time.youngs_modulus",
                    "missing",
                    "E at age 0 in [material.time] (or [material] youngs_modulus)",
                )
            })?,
        };
        let time = m.time.resolve(e_default)?;
        let c = &self.checks;
        if (c.strength || c.sliding) && time.strength.is_none() {
            return Err(bad(
                "material.time.compressive_strength",
                "missing",
                "the strength and sliding checks need a strength model: compressive_strength \
                 (uniaxial, optional friction_angle_deg) or cohesion + friction_angle_deg; or \
                 switch them off in [checks]",
            ));
        }
        pos("checks.blf_min", c.blf_min)?;
        pos("checks.collapse_min", c.collapse_min)?;
        if let Some(n) = self.analysis.as_ref().and_then(|a| a.nonlinear.as_ref()) {
            n.validate()?;
            if n.enabled && !c.buckling {
                return Err(bad(
                    "checks.buckling",
                    false,
                    "true with [analysis.nonlinear] (its imperfection is the lowest buckling \
                     mode); or set [analysis.nonlinear] enabled = false",
                ));
            }
        }
        let p = &self.process;
        let layer_time = match (p.layer_time, p.print_speed) {
            (Some(_), Some(_)) => {
                return Err(bad(
                    "process.print_speed",
                    "given together with layer_time",
                    "either layer_time (s) or print_speed (m/s)",
                ));
            }
            (Some(t), None) => pos("process.layer_time", t)?,
            (None, Some(v)) => path_length / pos("process.print_speed", v)?,
            (None, None) => {
                return Err(bad(
                    "process.layer_time",
                    "missing",
                    "layer_time (s per layer) or print_speed (m/s along the centre line)",
                ));
            }
        };
        let waits = ScheduleSpec {
            wait: p.wait,
            waits: p.waits.clone(),
            relocation_time: None,
        }
        .waits(o.max_layers)
        .map_err(|e| match e {
            DesignError::Invalid {
                field,
                value,
                allowed,
            } => DesignError::Invalid {
                field: if field == "schedule.wait" {
                    "process.wait"
                } else {
                    "process.waits"
                },
                value,
                allowed,
            },
            other => other,
        })?;
        let schedule = Schedule::uniform(o.max_layers, layer_time, &waits)?;
        let resolved = Resolved {
            spec: self.clone(),
            time,
            layer_time,
            schedule,
            segments,
            path_length,
        };
        if let Some(table) = &self.uncertainty {
            // Checked here so that a bad table stops before anything is solved or written.
            crate::commands::buildability_reliability::prepare(&resolved, table)?;
        }
        Ok(resolved)
    }
}

/// The shell model of the object with `n` layers complete and the layers of its elements.
pub fn object_shell(r: &Resolved, n: usize) -> (ShellModel, Vec<ElementLayers>) {
    let o = &r.spec.object;
    let h = o.layer_height;
    let s = r.segments;
    let (cols, closed) = match o.kind {
        ObjectKind::Wall => (s + 1, false),
        ObjectKind::Cylinder => (s, true),
    };
    let mut nodes = Vec::with_capacity(cols * (n + 1));
    for j in 0..=n {
        let z = h * j as f64;
        for i in 0..cols {
            nodes.push(match o.kind {
                ObjectKind::Wall => [r.path_length * i as f64 / s as f64, 0.0, z],
                ObjectKind::Cylinder => {
                    let th = std::f64::consts::TAU * i as f64 / s as f64;
                    let rad = o.radius.unwrap_or(0.0);
                    [rad * th.cos(), rad * th.sin(), z]
                }
            });
        }
    }
    let id = |i: usize, j: usize| j * cols + (i % cols);
    let mut tris = Vec::with_capacity(2 * s * n);
    let mut layers = Vec::with_capacity(2 * s * n);
    for j in 0..n {
        for i in 0..s {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // Diagonals alternate (the fixtures' pattern); both triangles keep the winding.
            if (i + j) % 2 == 0 || (closed && s % 2 == 1 && i + 1 == s) {
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            } else {
                tris.push([a, b, d]);
                tris.push([b, c, d]);
            }
            let info = ElementLayers {
                stiffness: (j, j),
                younger: j,
                bed_normal: [0.0, 0.0, 1.0],
            };
            layers.push(info);
            layers.push(info);
        }
    }
    let m = &r.spec.material;
    let mut model = ShellModel::new(
        nodes,
        tris,
        o.width,
        Material {
            youngs_modulus: r.time.modulus(0.0),
            poisson_ratio: m.poisson_ratio,
            unit_weight: m.specific_weight,
        },
    );
    model.supports = match r.spec.base() {
        BaseRestraint::Clamped => (0..cols).map(Support::clamped).collect(),
        BaseRestraint::Pinned => (0..cols).map(Support::pinned).collect(),
    };
    (model, layers)
}

/// One layer count.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BuildState {
    /// n: layers complete.
    pub layers: usize,
    /// Height n·h, m.
    pub height_m: f64,
    /// Time when layer n is complete, s.
    pub time_s: f64,
    /// Age of the bottom layer, s.
    pub bottom_age_s: f64,
    /// Lowest positive buckling factor (0 for a mechanism; None if not checked or none).
    pub blf: Option<f64>,
    /// Worst Mohr–Coulomb utilisation.
    pub strength_utilisation: Option<f64>,
    /// Worst bed-joint sliding utilisation.
    pub sliding_utilisation: Option<f64>,
    /// Where strength is worst (layer, age, principal stresses).
    pub strength_worst: Option<WorstElement>,
    /// Where sliding is worst (layer, age, σ_n and τ).
    pub sliding_worst: Option<WorstElement>,
    /// Buckling outcome.
    pub buckling: BucklingOutcome,
    /// The check with the largest utilisation.
    pub governing: Option<FailureMode>,
    /// The failing check, if any.
    pub failure: Option<FailureMode>,
    /// Collapse factor of the imperfect state (with `[analysis.nonlinear]`).
    pub collapse_factor: Option<f64>,
    /// What ends the path there (`limit_point`, `strength`, `sliding`, …).
    pub collapse_mode: Option<CollapseMode>,
    /// The collapse check in full (imperfection, LBA, sag at λ = 1, steps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collapse: Option<Collapse>,
    /// β of the state's random checks as a series system (with `[uncertainty]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// P_f of the state (with `[uncertainty]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pf: Option<f64>,
    /// β per check (`buckling`, `strength`, `sliding`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta_by_check: Option<std::collections::BTreeMap<String, f64>>,
    /// β of the state's series system with each component's SORM P_f (docs/reliability.md,
    /// "SORM"; with `[uncertainty]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta_sorm: Option<f64>,
    /// P_f of that system.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pf_sorm: Option<f64>,
}

/// The result (`buildability.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Buildability {
    /// Name.
    pub name: String,
    /// Object kind.
    pub object: ObjectKind,
    /// First n at which a check fails (None: stood to `max_layers`).
    pub failure_layer: Option<usize>,
    /// Mode at `failure_layer`.
    pub failure_mode: Option<FailureMode>,
    /// Layer time, s.
    pub layer_time_s: f64,
    /// Elements along the centre line.
    pub segments: usize,
    /// Closed-form estimate: the first n at which the bottom layer's uniaxial stress at the
    /// base, γ·n·h, reaches f_c of its age (green-state.md §4), if within `max_layers`.
    pub plastic_collapse_estimate: Option<usize>,
    /// The time model used.
    pub time_model: TimeModel,
    /// Per layer count, ascending.
    pub states: Vec<BuildState>,
    /// The print's reliability by FORM (with `[uncertainty]`): β, P_f, design point and
    /// sensitivities of the series system over the checked layer counts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reliability: Option<crate::analysis::reliability::Reliability>,
    /// The print's crude Monte Carlo (with `[uncertainty] monte_carlo = N`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<crate::commands::buildability_reliability::PrintMonteCarlo>,
    /// The collapse limit state's tables and their check at the design points (with
    /// `[analysis.nonlinear]` and `[uncertainty]`; docs/reliability.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collapse_reliability: Option<crate::commands::buildability_collapse::CollapseReliability>,
}

/// The `n`-layer object of `r` with every element's modulus at its layer's age (the model
/// that [`check_layers`] solves at `n` layers, before any solve), its elements' layers and
/// the layers' ages: the one setup of the collapse tests and benchmarks.
pub fn aged_object_shell(r: &Resolved, n: usize) -> (ShellModel, Vec<ElementLayers>, Vec<f64>) {
    let (mut model, layers) = object_shell(r, n);
    let ages = r.schedule.ages(n);
    crate::analysis::set_aged_moduli(&mut model, &layers, &ages, &r.time);
    (model, layers, ages)
}

/// Check one layer count.
pub fn check_layers(r: &Resolved, n: usize) -> Result<BuildState, DesignError> {
    check_layers_warm(r, n, None).map(|(s, _)| s)
}

/// The mode of a state with fewer layers as the start of this one's eigensolve: the nodes are
/// numbered row by row from the bed with the same row length, so the shared rows keep their
/// values and every new row copies the old top row.
fn extend_mode(prev: &[[f64; 6]], nodes: usize, cols: usize) -> Option<ModeStart> {
    if prev.len() < cols || cols == 0 {
        return None;
    }
    let top = prev.len() - cols;
    Some(
        (0..nodes)
            .map(|k| {
                prev.get(k)
                    .or_else(|| prev.get(top + k % cols))
                    .copied()
                    .unwrap_or([0.0; 6])
            })
            .collect(),
    )
}

/// [`check_layers`] started from the mode of a state with fewer layers (`prev`), returning this
/// state's mode for the next.
pub fn check_layers_warm(
    r: &Resolved,
    n: usize,
    prev: Option<&[[f64; 6]]>,
) -> Result<(BuildState, Option<ModeStart>), DesignError> {
    check_layers_cached(r, n, prev, &ObjectIncrements::default())
}

/// [`check_layers_warm`] with the as-printed increments of the layer counts kept in `cache`
/// across calls on the same `r` (docs/as-printed.md; used only with `start = "as_printed"`).
pub fn check_layers_cached(
    r: &Resolved,
    n: usize,
    prev: Option<&[[f64; 6]]>,
    cache: &ObjectIncrements,
) -> Result<(BuildState, Option<ModeStart>), DesignError> {
    let (mut model, layers) = object_shell(r, n);
    let cols = model.nodes.len() / (n + 1);
    let start = prev.and_then(|p| extend_mode(p, model.nodes.len(), cols));
    let ages = r.schedule.ages(n);
    let c = &r.spec.checks;
    let opts = c.green_options();
    let (g, mode) = check_state(&mut model, &layers, &ages, &r.time, &opts, start)?;
    let o = &r.spec.object;
    let collapse = match (r.spec.nonlinear(), g.blf()) {
        (Some(nl), Some(blf)) => {
            let options = CollapseOptions {
                w0: nl.amplitude(o.width, n as f64 * o.layer_height),
                // A closed cylinder's modes are sign-symmetric (docs/collapse.md §1).
                signs: nl.signs.unwrap_or(match o.kind {
                    ObjectKind::Cylinder => 1,
                    ObjectKind::Wall => 2,
                }),
                strength: c.strength && nl.material,
                sliding: c.sliding && nl.material,
                fast_path: false,
                stop_above: f64::INFINITY,
            };
            let shape = mode.clone().unwrap_or_default();
            // docs/collapse.md §8: the path from the as-printed geometry.
            let start = match nl.start {
                PathStart::Design => None,
                PathStart::AsPrinted => Some(shifted(
                    &model,
                    &object_as_printed_shift_cached(
                        n,
                        &|k| object_shell(r, k),
                        &|k| r.schedule.ages(k),
                        &r.time,
                        &model,
                        cache,
                    )?,
                )),
            };
            Some(collapse_factor(
                start.as_ref().unwrap_or(&model),
                &shape,
                blf,
                g.strength.map(|w| w.utilisation),
                &layers,
                &ages,
                &r.time,
                &options,
            )?)
        }
        _ => None,
    };
    let (governing, failure) = match &collapse {
        None => (g.governing, g.failure),
        Some(col) => {
            let u = |v: Option<f64>| v.filter(|x| !x.is_nan());
            let candidates = [
                (
                    FailureMode::Buckling,
                    u(g.blf().map(|b| {
                        if b > 0.0 {
                            c.blf_min / b
                        } else {
                            f64::INFINITY
                        }
                    })),
                ),
                (FailureMode::Strength, u(g.strength.map(|w| w.utilisation))),
                (FailureMode::Sliding, u(g.sliding.map(|w| w.utilisation))),
                (
                    FailureMode::Collapse,
                    Some(if col.factor > 0.0 {
                        c.collapse_min / col.factor
                    } else {
                        f64::INFINITY
                    }),
                ),
            ];
            let gov = candidates
                .iter()
                .filter_map(|(m, u)| u.map(|u| (*m, u)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            (gov.map(|g| g.0), gov.filter(|(_, u)| *u > 1.0).map(|g| g.0))
        }
    };
    Ok((
        BuildState {
            layers: n,
            height_m: n as f64 * r.spec.object.layer_height,
            time_s: r.schedule.layers.get(n - 1).map_or(0.0, |l| l.end_s),
            bottom_age_s: ages.first().copied().unwrap_or(0.0),
            blf: g.blf(),
            strength_utilisation: g.strength.map(|w| w.utilisation),
            sliding_utilisation: g.sliding.map(|w| w.utilisation),
            strength_worst: g.strength,
            sliding_worst: g.sliding,
            buckling: g.buckling,
            governing,
            failure,
            collapse_factor: collapse.as_ref().map(|x| x.factor),
            collapse_mode: collapse.as_ref().map(|x| x.mode),
            collapse,
            beta: None,
            pf: None,
            beta_by_check: None,
            beta_sorm: None,
            pf_sorm: None,
        },
        mode,
    ))
}

/// One chain's states of a round and its last mode.
type ChainPart = (Vec<BuildState>, Option<ModeStart>);

/// The deterministic states of [`run`]: every layer count 1, 2, … up to `max_layers` (or the
/// first failure when `stop_at_failure`), `on_state(n)` called after each; the chains as
/// [`run`] describes. The buildability Monte Carlo's collapse tables are built from these
/// (`buildability_reliability::collapse_tables`), on a Dask worker as in `run`.
///
/// # Errors
/// A failed solve.
pub fn layer_states(
    r: &Resolved,
    on_state: &(dyn Fn(usize) + Sync),
) -> Result<Vec<BuildState>, DesignError> {
    let max = r.spec.object.max_layers;
    let stop = r.spec.checks.stop_at_failure;
    let chains = rayon::current_num_threads().clamp(1, max);
    let mut modes: Vec<Option<ModeStart>> = vec![None; chains];
    let mut states: Vec<BuildState> = Vec::with_capacity(max);
    // Without stop_at_failure one round covers every layer count.
    let rounds_per_batch = if stop { 2 } else { max.div_ceil(chains) };
    let mut next = 1;
    let increments = ObjectIncrements::default();
    while next <= max {
        let hi = (next + chains * rounds_per_batch - 1).min(max);
        let results: Vec<Result<ChainPart, DesignError>> = modes
            .par_iter()
            .enumerate()
            .map(|(i, m)| {
                let mut prev = m.clone();
                let mut out = Vec::new();
                let mut n = next + i;
                while n <= hi {
                    let (s, mode) = check_layers_cached(r, n, prev.as_deref(), &increments)?;
                    on_state(n);
                    out.push(s);
                    if mode.is_some() {
                        prev = mode;
                    }
                    n += chains;
                }
                Ok((out, prev))
            })
            .collect();
        let mut part = Vec::with_capacity(hi + 1 - next);
        for (slot, res) in modes.iter_mut().zip(results) {
            let (out, last) = res?;
            *slot = last;
            part.extend(out);
        }
        part.sort_by_key(|s| s.layers);
        let failed = part.iter().position(|s| s.failure.is_some());
        if let (true, Some(k)) = (stop, failed) {
            part.truncate(k + 1);
            states.extend(part);
            break;
        }
        states.extend(part);
        next = hi + 1;
    }
    Ok(states)
}

/// Check every layer count 1, 2, … up to `max_layers` (or the first failure when
/// `stop_at_failure`). `on_state(n)` is called after each.
///
/// The layer counts run in `c` interleaved chains (c = the worker threads): chain i checks
/// n = i + 1, i + 1 + c, …, each started from the previous mode of its chain (a state with c
/// fewer layers, whose mode is close): the chains' costs are equal and each eigensolve needs
/// a few Lanczos steps instead of ~20 (`cargo run --release -p kappe --example
/// buildability`). With `stop_at_failure` the chains advance in rounds of c states and stop
/// after the round with the first failure.
pub fn run(r: &Resolved, on_state: &(dyn Fn(usize) + Sync)) -> Result<Buildability, DesignError> {
    let mut states = layer_states(r, on_state)?;
    let (reliability, monte_carlo, collapse_reliability) = match &r.spec.uncertainty {
        Some(table) => {
            let (rel, mc, col) =
                crate::commands::buildability_reliability::analyse(r, table, &states)?;
            for s in &mut states {
                if let Some(x) = rel.states.iter().find(|x| x.index == s.layers) {
                    s.beta = Some(x.beta);
                    s.pf = Some(x.pf);
                    s.beta_by_check = Some(x.beta_by_check.clone());
                    s.beta_sorm = x.beta_sorm;
                    s.pf_sorm = x.pf_sorm;
                }
            }
            (Some(rel), mc, col)
        }
        None => (None, None, None),
    };
    let first_fail = states.iter().find(|s| s.failure.is_some());
    Ok(Buildability {
        name: r.spec.name.clone(),
        object: r.spec.object.kind,
        failure_layer: first_fail.map(|s| s.layers),
        failure_mode: first_fail.and_then(|s| s.failure),
        layer_time_s: r.layer_time,
        segments: r.segments,
        plastic_collapse_estimate: plastic_collapse_estimate(r),
        time_model: r.time.clone(),
        states,
        reliability,
        monte_carlo,
        collapse_reliability,
    })
}

/// First n with γ·n·h ≥ f_c(age of the bottom layer) (uniaxial, stress at the base).
pub fn plastic_collapse_estimate(r: &Resolved) -> Option<usize> {
    let o = &r.spec.object;
    let g = r.spec.material.specific_weight;
    (1..=o.max_layers).find(|&n| {
        let age = r.schedule.ages(n).first().copied().unwrap_or(0.0);
        r.time
            .compressive_strength(age)
            .is_some_and(|fc| g * n as f64 * o.layer_height >= fc)
    })
}

/// `buildability.json`: the spec, the failure layer and mode, and the whole result.
pub fn document(r: &Resolved, b: &Buildability) -> serde_json::Value {
    serde_json::json!({
        "format": "kappe.buildability",
        "version": 1,
        "spec": r.spec,
        "failure_layer": b.failure_layer,
        "failure_mode": b.failure_mode,
        "result": b,
    })
}

/// The schedule of the layers checked (`schedule.csv`): the spec's schedule up to the last
/// checked layer count.
pub fn checked_schedule(r: &Resolved, b: &Buildability) -> Schedule {
    let mut schedule = r.schedule.clone();
    schedule.layers.truncate(b.states.len());
    schedule
}

/// The text `kappe buildability` prints: the object, a table of about 20 layer counts (and the
/// failing one), the verdict, the closed-form estimate and, with `out`, where the files went.
pub fn text_report(r: &Resolved, b: &Buildability, out: Option<&std::path::Path>) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    let o = &r.spec.object;
    let _ = writeln!(
        t,
        "{} ({}): {} layers of {:.1} mm, {:.2} s per layer, {} elements along the centre line",
        if r.spec.name.is_empty() {
            "buildability"
        } else {
            &r.spec.name
        },
        match o.kind {
            ObjectKind::Wall => "wall",
            ObjectKind::Cylinder => "cylinder",
        },
        b.states.len(),
        o.layer_height * 1e3,
        b.layer_time_s,
        b.segments
    );
    let _ = writeln!(
        t,
        "  {:>5} {:>8} {:>9} {:>10} {:>9} {:>9} {:>9}  governs",
        "n", "H [m]", "age0 [s]", "BLF", "strength", "sliding", "collapse"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
    let step = (b.states.len() / 20).max(1);
    for s in &b.states {
        if s.layers % step == 0 || s.failure.is_some() || s.layers == 1 {
            let _ = writeln!(
                t,
                "  {:>5} {:>8.3} {:>9.1} {:>10} {:>9} {:>9} {:>9}  {}{}",
                s.layers,
                s.height_m,
                s.bottom_age_s,
                f(s.blf),
                f(s.strength_utilisation),
                f(s.sliding_utilisation),
                f(s.collapse_factor),
                s.governing.map_or("-", |m| m.name()),
                match (s.governing, s.collapse_mode) {
                    (Some(FailureMode::Collapse), Some(m)) => format!(" ({})", m.name()),
                    _ => String::new(),
                }
            );
        }
    }
    match (b.failure_layer, b.failure_mode) {
        (Some(n), Some(m)) => {
            let failed = b.states.iter().find(|s| s.layers == n);
            let how = match (m, failed.and_then(|s| s.collapse.as_ref())) {
                (FailureMode::Collapse, Some(c)) => format!(
                    " (collapse factor {:.3}, {}, w0 = {:.2} mm)",
                    c.factor,
                    c.mode.name(),
                    c.w0 * 1e3
                ),
                _ => String::new(),
            };
            let _ = writeln!(t, "fails at layer {n} by {}{how}", m.name());
        }
        _ => {
            let _ = writeln!(t, "stands to {} layers", o.max_layers);
        }
    }
    if let Some(n) = b.plastic_collapse_estimate {
        let _ = writeln!(
            t,
            "  (closed-form uniaxial plastic collapse at the base: layer {n})"
        );
    }
    if let Some(rel) = &b.reliability {
        let _ = writeln!(
            t,
            "reliability: print β {:.2}, P_f {:.3e} (governing: layer {} {})",
            rel.beta, rel.pf, rel.governing_state, rel.governing_check
        );
    }
    if let Some(c) = &b.collapse_reliability {
        let _ = writeln!(
            t,
            "collapse limit state: tables of {} layer counts over {} ({} path solves); at the \
             design points table vs re-solve ≤ {:.2e} relative (Δβ ≤ {:.3})",
            c.states.len(),
            if c.parameters.is_empty() {
                "γ alone (exact scaling)".to_owned()
            } else {
                c.parameters.join(", ")
            },
            c.solves,
            c.max_relative_error,
            c.max_beta_error
        );
    }
    if let Some(mc) = &b.monte_carlo {
        let _ = writeln!(
            t,
            "Monte Carlo ({} samples): P_f {:.4} [{:.4}, {:.4}], failure layer {}",
            mc.samples,
            mc.pf,
            mc.pf_interval[0],
            mc.pf_interval[1],
            match (mc.failure_layer_mean, mc.failure_layer_std) {
                (Some(m), Some(s)) => format!("{m:.1} ± {s:.1}"),
                _ => "-".into(),
            }
        );
    }
    if let Some(out) = out {
        let _ = writeln!(t, "wrote {}", out.display());
    }
    t
}
