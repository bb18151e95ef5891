//! The chance that a buildability object stands (issue 24): `[uncertainty]` in a buildability
//! spec, β and P_f of every layer count by FORM and of the print as a series system (the cap's
//! implementation: [`crate::analysis::reliability::form_checks`] and
//! [`crate::analysis::reliability::print_reliability`]), and a seeded Monte Carlo of the whole
//! print that counts, for every layer count, the samples in which it fails.
//!
//! # Parameters
//!
//! γ (`material.specific_weight`), the time model's E₀ and Ė (`material.time.youngs_modulus`,
//! `…_rate`), its uniaxial strength f₀ and ḟ (`material.time.compressive_strength`, `…_rate`)
//! and the layer time T (`process.layer_time`, which moves every layer's age).
//!
//! # Exact reductions (docs/reliability.md, "Buildability")
//!
//! In a state with n layers the element of row k has the modulus E₀ + Ė·h(a_k) (h(a) = a for the
//! linear law, t_c(e^{a/t_c} − 1) for the exponential one) with a_k the age of layer k. Without
//! waits a_k = T·m_k, so for the linear law E_k = E₀(1 + ρ·a_k(T₀)) with the one shape
//! parameter ρ = (Ė/E₀)(T/T₀); with T fixed ρ = Ė/E₀ for any law. The shell's stiffness is then
//! E₀·K̂(ρ), its self-weight load and hence its geometric stiffness are proportional to γ, so
//!
//! BLF(x) = (E₀/E₀⁰)(γ₀/γ)·Λ(ρ),
//!
//! and its static stresses are (γ/γ₀)·σ̂(ρ) (the load is linear in γ; a uniform factor on the
//! stiffness does not change the stresses). The Mohr–Coulomb demand of a membrane stress state
//! is homogeneous of degree 1 in the stresses at a fixed friction angle, so layer k's strength
//! utilisation is (γ/γ₀)·D_k(ρ)/(c_k·cos φ), with D_k the largest demand among its elements and
//! c_k = f_c(a_k)·(1 − sin φ)/(2 cos φ) its cohesion at the sample's f₀, ḟ and T; with φ = 0 its
//! bed-joint sliding utilisation is (γ/γ₀)·S_k(ρ)/c_k, S_k the largest |τ| of its joints.
//!
//! Λ, D_k and S_k are functions of the one variable ρ: each is interpolated by the polynomial
//! through [`NODES`] Chebyshev points of ln ρ (barycentric form, Berrut & Trefethen 2004) spanning
//! the ρ of every sample whose variables lie within ±[`Z_RANGE`] standard deviations; a sample
//! outside that box, or a spec the reductions do not cover (waits with an uncertain T, a law other
//! than linear with an uncertain T, a modulus cap, a Mohr–Coulomb c(t), φ(t) strength or sliding
//! with φ ≠ 0) is evaluated by a re-solve of the state ([`crate::commands::buildability::
//! check_layers`], the deterministic check itself). [`Surrogate::verify`] compares the two.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use kappe_reliability::{
    Batch, EvalError, Fallible, FormResult, Model, SamplingOptions, SamplingResult, SystemOptions,
    merge_events, sample_events,
};

use crate::analysis::design_monte_carlo::{bits, cheb, table_coefficients};
use crate::analysis::green::{BucklingOutcome, ModeStart, bed_traction, principal, solve_state};
use crate::analysis::reliability::{Reliability, form_checks, print_reliability};
use crate::commands::buildability::{Resolved, check_layers, object_shell};
use crate::commands::buildability_collapse::{
    CollapseTables, IMPERFECTION, check_collapse_axes, imperfection_nominal,
};
use crate::input::error::DesignError;
use crate::input::material::{MohrCoulomb, Strength, TimeLaw, TimeModel};
use crate::input::uncertainty::{BETA_MIN_DEFAULT, UncertaintyTable};

/// The names a buildability spec's `[uncertainty]` accepts and whether each is positive.
pub const PARAMETERS: [(&str, bool); 6] = [
    ("material.specific_weight", false),
    ("material.time.youngs_modulus", true),
    ("material.time.youngs_modulus_rate", true),
    ("material.time.compressive_strength", true),
    ("material.time.compressive_strength_rate", true),
    ("process.layer_time", true),
];

/// Chebyshev points of ln ρ per state: the interpolation error of the smooth Λ(ρ) and D_k(ρ)
/// over the range falls geometrically with their number; 9 keep it below 1e-4 relative on the
/// Wolfs cylinder ([`Surrogate::verify`], `cargo run --release -p kappe --example
/// buildability_mc`).
pub const NODES: usize = 9;

/// Half-width of the box of variables the interpolation covers, in standard deviations of each
/// variable: P(|z| > 5) = 5.7e-7 per normal number, so 10⁴ samples of 3 variables fall outside
/// with probability ≈ 2 %, and such a sample is re-solved exactly, not extrapolated.
pub const Z_RANGE: f64 = 5.0;

pub(crate) const GAMMA: usize = 0;
pub(crate) const E0: usize = 1;
pub(crate) const RATE: usize = 2;
pub(crate) const F0: usize = 3;
pub(crate) const FRATE: usize = 4;
pub(crate) const T: usize = 5;

/// Nominal values of the six parameters, in [`PARAMETERS`] order.
fn nominal(r: &Resolved) -> [f64; 6] {
    let (f0, fr) = match r.time.strength {
        Some(Strength::Uniaxial {
            compressive_strength: p,
            ..
        }) => (p.initial, p.rate),
        _ => (f64::NAN, f64::NAN),
    };
    [
        r.spec.material.specific_weight,
        r.time.youngs_modulus.initial,
        r.time.youngs_modulus.rate,
        f0,
        fr,
        r.layer_time,
    ]
}

/// The example spec (`kappe init --kind buildability`, the Wolfs 2018 cylinder) with every layer
/// count checked up to `max_layers`, `segments` shell elements around (None: the default 48) and
/// its strength at age 0 replaced by `f0` Pa (None: kept); append [`example_scatter`] for the
/// uncertain one. The buildability fixture of the `buildability_mc` example and the tests.
pub fn example_spec(max_layers: usize, segments: Option<usize>, f0: Option<f64>) -> String {
    let mut text = crate::commands::buildability::EXAMPLE_TOML
        .replace("max_layers = 60 ", &format!("max_layers = {max_layers} "))
        .replace("stop_at_failure = true", "stop_at_failure = false");
    if let Some(n) = segments {
        text = text.replace("# segments = 48 ", &format!("segments = {n} "));
    }
    if let Some(f) = f0 {
        text = text.replace(
            "compressive_strength = 5984.0",
            &format!("compressive_strength = {f:?}"),
        );
    }
    text
}

/// An illustrative scatter of [`example_spec`]'s mix, not calibrated to the five specimens: E₀,
/// Ė, f₀, ḟ lognormal with coefficients of variation 0.15, 0.15, 0.10, 0.10, γ normal with 0.02
/// and the layer time lognormal with 0.05, sampled with `seed`: an `[uncertainty]` table to
/// append (more keys of the table may follow it).
pub fn example_scatter(seed: u64) -> String {
    format!(
        "
[uncertainty]
\"material.time.youngs_modulus\" = {{ dist = \"lognormal\", cov = 0.15 }}
\"material.time.youngs_modulus_rate\" = {{ dist = \"lognormal\", cov = 0.15 }}
\"material.time.compressive_strength\" = {{ dist = \"lognormal\", cov = 0.10 }}
\"material.time.compressive_strength_rate\" = {{ dist = \"lognormal\", cov = 0.10 }}
\"material.specific_weight\" = {{ dist = \"normal\", cov = 0.02 }}
\"process.layer_time\" = {{ dist = \"lognormal\", cov = 0.05 }}
seed = {seed}
"
    )
}

pub(crate) fn uerr(field: impl Into<String>, message: impl Into<String>) -> DesignError {
    DesignError::Uncertainty {
        field: field.into(),
        message: message.into(),
    }
}

/// The uncertain model of a buildability spec and where each parameter sits in it.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The random variables.
    pub model: Model,
    /// Their drifts over print time.
    pub drifts: Vec<(String, kappe_reliability::Drift)>,
    /// `idx[p]`: the model index of parameter p ([`PARAMETERS`] order), if uncertain.
    pub idx: [Option<usize>; 6],
    /// Nominal values.
    pub nominal: [f64; 6],
    /// The model index of `analysis.nonlinear.imperfection`, if uncertain
    /// ([`crate::commands::buildability_collapse`]).
    pub imperfection: Option<usize>,
}

impl Prepared {
    /// `x` with every positive variable (all but γ) floored at the least positive number: a
    /// FORM iterate on a surface nearly flat in a lognormal variable (strength with E₀ alone
    /// uncertain depends on it only through ρ) steps towards u → −∞, where x underflows to 0
    /// and a central difference then crosses into x < 0. Floored, every g stays finite, and
    /// FORM reports the component's far β (left out beyond `FAR_BETA`) instead of failing.
    pub fn floored(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .enumerate()
            .map(|(i, &v)| {
                if Some(i) == self.idx[GAMMA] {
                    v
                } else {
                    v.max(f64::MIN_POSITIVE)
                }
            })
            .collect()
    }

    /// The six parameters at the model point x (nominal where not uncertain).
    pub fn params(&self, x: &[f64]) -> [f64; 6] {
        std::array::from_fn(|p| {
            self.idx[p]
                .and_then(|i| x.get(i).copied())
                .unwrap_or(self.nominal[p])
        })
    }
}

/// The model of `table` for the spec `r`; named errors for unknown names, a strength
/// parameter without a uniaxial strength model, and the rest of [`UncertaintyTable::model_with`].
///
/// # Errors
/// [`DesignError::Uncertainty`] naming the field.
pub fn prepare(r: &Resolved, table: &UncertaintyTable) -> Result<Prepared, DesignError> {
    let nom = nominal(r);
    let allowed = PARAMETERS
        .iter()
        .map(|(n, _)| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ");
    let model = table.model_with(&|name: &str| {
        if name == IMPERFECTION {
            return imperfection_nominal(r);
        }
        let Some(p) = PARAMETERS.iter().position(|(n, _)| *n == name) else {
            return Err(format!(
                "unknown parameter of a buildability spec; allowed names: {allowed} and, with \
                 [analysis.nonlinear], \"{IMPERFECTION}\""
            ));
        };
        if nom[p].is_nan() {
            return Err(
                "a strength parameter needs the uniaxial strength model: give \
                        compressive_strength (and compressive_strength_rate) in [material.time]"
                    .to_owned(),
            );
        }
        Ok((nom[p], PARAMETERS[p].1))
    })?;
    let idx = std::array::from_fn(|p| {
        model
            .variables()
            .iter()
            .position(|v| v.name == PARAMETERS[p].0)
    });
    let imperfection = model
        .variables()
        .iter()
        .position(|v| v.name == IMPERFECTION);
    let prepared = Prepared {
        model,
        drifts: table.drifts(),
        idx,
        nominal: nom,
        imperfection,
    };
    check_collapse_axes(r, &prepared)?;
    Ok(prepared)
}

/// The spec at parameters `p` (time model, γ and layer time replaced), resolved again.
///
/// # Errors
/// A parameter the spec's checks refuse (e.g. a layer time ≤ 0).
pub fn resolved_at(r: &Resolved, p: &[f64; 6]) -> Result<Resolved, DesignError> {
    let mut spec = r.spec.clone();
    spec.uncertainty = None;
    spec.material.specific_weight = p[GAMMA];
    if p[T] != r.layer_time {
        spec.process.layer_time = Some(p[T]);
        spec.process.print_speed = None;
    }
    let mut out = spec.resolve()?;
    out.time = time_at(&r.time, p);
    Ok(out)
}

fn time_at(time: &TimeModel, p: &[f64; 6]) -> TimeModel {
    let mut t = time.clone();
    t.youngs_modulus.initial = p[E0];
    t.youngs_modulus.rate = p[RATE];
    if let Some(Strength::Uniaxial {
        compressive_strength,
        ..
    }) = &mut t.strength
    {
        compressive_strength.initial = p[F0];
        compressive_strength.rate = p[FRATE];
    }
    t
}

/// BLF (None: not checked or none), strength and sliding utilisations of one state.
pub type StateValues = (Option<f64>, Option<f64>, Option<f64>);

/// One state's values by a re-solve at parameters `p` (the deterministic check itself).
///
/// # Errors
/// A failed solve or a refused parameter.
pub fn exact_state(r: &Resolved, n: usize, p: &[f64; 6]) -> Result<StateValues, DesignError> {
    let mut at = resolved_at(r, p)?;
    // The linear checks only: the collapse path (its own limit state) would be wasted here.
    if let Some(nl) = at.spec.analysis.as_mut().and_then(|a| a.nonlinear.as_mut()) {
        nl.enabled = false;
    }
    let s = check_layers(&at, n)?;
    Ok((s.blf, s.strength_utilisation, s.sliding_utilisation))
}

/// One layer count's tables at the interpolation points.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct StateTable {
    /// ln Λ per point (None: no buckling check, or a point without a positive factor).
    #[serde(with = "bits::option")]
    log_blf: Option<Vec<f64>>,
    /// D_k per point (row-major: point j, layer k).
    #[serde(with = "bits::option")]
    strength: Option<Vec<f64>>,
    /// S_k per point.
    #[serde(with = "bits::option")]
    sliding: Option<Vec<f64>>,
    /// Ages of the layers at the nominal T, s.
    #[serde(with = "bits")]
    ages: Vec<f64>,
    /// A point without a positive buckling factor: the state is re-solved at every sample.
    exact: bool,
}

/// The interpolated state values of a buildability spec; see the module docs.
#[derive(Debug)]
pub struct Surrogate {
    /// The uncertain model.
    pub prepared: Prepared,
    /// ln ρ of the points (empty: ρ does not vary, one table per state at the nominal ρ).
    nodes: Vec<f64>,
    weights: Vec<f64>,
    /// [ln ρ_lo, ln ρ_hi] covered.
    range: [f64; 2],
    /// Whether ρ scales with T (an uncertain T reduces exactly).
    t_scales: bool,
    /// Whether the reductions hold (else every evaluation is a re-solve).
    pub reducible: bool,
    /// Per layer count n (index n − `first`).
    states: Vec<StateTable>,
    /// The layer count of `states[0]` (1 but in a part, [`Surrogate::build_layers`]).
    first: usize,
    sin_phi: f64,
    cos_phi: f64,
    /// Re-solves done for samples outside the box.
    pub fallbacks: std::sync::atomic::AtomicU64,
    /// Wall-clock seconds of building the tables.
    pub build_seconds: f64,
    /// The collapse factor's tables (with `[analysis.nonlinear]`; set by [`analyse`] from the
    /// run's states, or by [`collapse_tables`]; shipped with [`SurrogateTables`]).
    pub collapse: Option<CollapseTables>,
}

/// A [`Surrogate`]'s tables without its uncertain model: what a Dask client has built once and
/// ships to its workers ([`Surrogate::tables`], [`Surrogate::from_tables`]), so that no worker
/// solves them again. Every number travels as its bit pattern (JSON has no NaN, and the bits
/// round-trip exactly), so a worker's samples equal the builder's bit for bit.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SurrogateTables {
    /// The spec text the tables were built for (a worker refuses tables of another spec).
    spec: String,
    #[serde(with = "bits")]
    nodes: Vec<f64>,
    #[serde(with = "bits")]
    weights: Vec<f64>,
    #[serde(with = "bits")]
    range: Vec<f64>,
    t_scales: bool,
    reducible: bool,
    states: Vec<StateTable>,
    /// The layer count of `states[0]`.
    first: usize,
    #[serde(with = "bits")]
    phi: Vec<f64>,
    build_seconds: f64,
    /// The collapse tables (with `[analysis.nonlinear]`; [`collapse_tables`], attached by
    /// [`SurrogateTables::with_collapse`]): a nonlinear spec's tables without them are refused
    /// ([`Surrogate::from_tables`]), so that no sample silently leaves out the collapse.
    #[serde(default)]
    collapse: Option<CollapseTables>,
}

/// The layer counts of part `index` of `count` of the tables of a `max`-layer print, for
/// [`Surrogate::build_layers`]: consecutive ranges that tile 1..=`max` (some empty when
/// `count` > `max`), cut so that each holds about the same Σ n (a layer count's table costs
/// about in proportion to its layers).
#[must_use]
pub fn table_part_layers(
    max: usize,
    index: usize,
    count: usize,
) -> std::ops::RangeInclusive<usize> {
    let count = count.max(1);
    // The first layer count of part i: the least n with Σ_{m<n} m ≥ i/count of the whole.
    let start = |i: usize| {
        if i >= count {
            return max + 1;
        }
        let goal = (max * (max + 1) / 2) * i / count;
        (1..=max + 1)
            .find(|&n| (n - 1) * n / 2 >= goal)
            .unwrap_or(max + 1)
    };
    start(index)..=start(index + 1) - 1
}

impl SurrogateTables {
    /// The tables of a whole print from its parts ([`Surrogate::build_layers`] of consecutive
    /// layer-count ranges, in any order), so that the tables can be built on several workers.
    ///
    /// # Errors
    /// Parts of different specs or frames, or ranges that do not tile 1, 2, … without gaps.
    pub fn join(mut parts: Vec<SurrogateTables>) -> Result<SurrogateTables, DesignError> {
        // What every part of one spec's tables shares (the numbers by their bits).
        fn frame(t: &SurrogateTables) -> (&str, Vec<u64>, bool, bool) {
            let numbers = t
                .nodes
                .iter()
                .chain(&t.weights)
                .chain(&t.range)
                .chain(&t.phi);
            (
                t.spec.as_str(),
                numbers.map(|x| x.to_bits()).collect(),
                t.t_scales,
                t.reducible,
            )
        }
        let bad = |m: String| uerr("uncertainty", format!("Monte Carlo table parts: {m}"));
        parts.sort_by_key(|p| p.first);
        let mut it = parts.into_iter();
        let Some(mut all) = it.next() else {
            return Err(bad("none given".into()));
        };
        if all.first != 1 {
            return Err(bad(format!(
                "the first part starts at layer count {}",
                all.first
            )));
        }
        for p in it {
            if frame(&p) != frame(&all) {
                return Err(bad("built for different specs".into()));
            }
            let next = all.first + all.states.len();
            if all.reducible && p.first != next {
                return Err(bad(format!(
                    "a part starts at layer count {} where {next} was due",
                    p.first
                )));
            }
            all.states.extend(p.states);
            all.build_seconds += p.build_seconds;
            if all.collapse.is_none() {
                all.collapse = p.collapse;
            }
        }
        Ok(all)
    }

    /// These tables with the print's collapse tables ([`collapse_tables`], built on their own
    /// worker beside the parts).
    #[must_use]
    pub fn with_collapse(mut self, collapse: Option<CollapseTables>) -> SurrogateTables {
        self.collapse = collapse;
        self
    }
}

/// The collapse tables of a buildability spec with `[analysis.nonlinear]` (None without it),
/// as [`analyse`] builds them: from the deterministic states of [`run`]
/// ([`crate::commands::buildability::layer_states`]), so that a Monte Carlo outside `run`
/// (Python, a Dask worker) counts the collapse as `kappe buildability` does.
///
/// # Errors
/// A failed solve or path; see [`CollapseTables::build`].
///
/// [`run`]: crate::commands::buildability::run
pub fn collapse_tables(
    r: &Resolved,
    prepared: &Prepared,
) -> Result<Option<CollapseTables>, DesignError> {
    if r.spec.nonlinear().is_none() {
        return Ok(None);
    }
    let states = crate::commands::buildability::layer_states(r, &|_| {})?;
    CollapseTables::build(r, prepared, &states).map(Some)
}

/// Print time of the state with n layers, h.
pub(crate) fn t_hours(r: &Resolved, n: usize) -> f64 {
    r.schedule
        .layers
        .get(n.saturating_sub(1))
        .map_or(0.0, |l| l.end_s)
        / 3600.0
}

/// Per model variable, the range [lo, hi] of ±[`Z_RANGE`] standard deviations over every
/// state's drifted model (layer counts 1..=`max_layers`): the box the tables cover.
///
/// # Errors
/// A drift factor that is not positive within the print.
pub(crate) fn variable_box(
    r: &Resolved,
    prepared: &Prepared,
) -> Result<Vec<[f64; 2]>, DesignError> {
    let k = prepared.model.variables().len();
    let mut out = vec![[f64::INFINITY, f64::NEG_INFINITY]; k];
    for n in 1..=r.spec.object.max_layers {
        let m = prepared
            .model
            .drifted(&prepared.drifts, t_hours(r, n))
            .map_err(|e| uerr("uncertainty.drift", format!("state {n}: {e}")))?;
        for (b, v) in out.iter_mut().zip(m.variables()) {
            b[0] = b[0].min(v.distribution.from_standard(-Z_RANGE));
            b[1] = b[1].max(v.distribution.from_standard(Z_RANGE));
        }
    }
    Ok(out)
}

impl Surrogate {
    /// The tables of every layer count 1..=`max_layers` (states in parallel, the points of one
    /// state in sequence, each eigensolve started from the previous point's mode).
    ///
    /// # Errors
    /// A failed solve, or a drift factor that is not positive within the print.
    pub fn build(r: &Resolved, prepared: Prepared) -> Result<Surrogate, DesignError> {
        Self::build_layers(r, prepared, 1..=r.spec.object.max_layers)
    }

    /// [`Surrogate::build`] with the tables of the layer counts `layers` only: a part of the
    /// tables for [`SurrogateTables::join`] (each layer count's table is the same function of
    /// the spec wherever it is built), not a surrogate to sample.
    ///
    /// # Errors
    /// As [`Surrogate::build`]; layer counts outside 1..=`max_layers`.
    pub fn build_layers(
        r: &Resolved,
        prepared: Prepared,
        layers: std::ops::RangeInclusive<usize>,
    ) -> Result<Surrogate, DesignError> {
        let max = r.spec.object.max_layers;
        if *layers.start() < 1 || *layers.end() > max {
            return Err(uerr(
                "uncertainty",
                format!(
                    "Monte Carlo tables of layer counts {}..={}: allowed within 1..={max}",
                    layers.start(),
                    layers.end()
                ),
            ));
        }
        let first = *layers.start();
        let t0 = kappe_fe::clock::Instant::now();
        let nom = prepared.nominal;
        let time = &r.time;
        let c = &r.spec.checks;
        let t_unc = prepared.idx[T].is_some();
        let no_waits = r.schedule.total_wait_s() == 0.0;
        let t_scales = t_unc && no_waits && time.law == TimeLaw::Linear;
        let (phi, uniaxial) = match time.strength {
            Some(Strength::Uniaxial {
                friction_angle_deg, ..
            }) => (friction_angle_deg.to_radians(), true),
            Some(Strength::MohrCoulomb { .. }) => (0.0, false),
            None => (0.0, true),
        };
        let stress = (c.strength || c.sliding) && time.strength.is_some();
        let reducible = time.youngs_modulus.max.is_none()
            && (!t_unc || t_scales)
            && (uniaxial || !stress)
            && (!(c.sliding && stress) || phi == 0.0)
            && nom[E0] > 0.0;
        // The box of every state's (drifted) variables.
        let boxes = variable_box(r, &prepared)?;
        let (mut lo, mut hi) = (nom, nom);
        for p in 0..6 {
            if let Some(b) = prepared.idx[p].and_then(|i| boxes.get(i)) {
                [lo[p], hi[p]] = *b;
            }
        }
        let tf = |t: f64| if t_scales { t / nom[T] } else { 1.0 };
        let rho_lo = lo[RATE] / hi[E0] * tf(lo[T]);
        let rho_hi = hi[RATE] / lo[E0] * tf(hi[T]);
        let varies = nom[RATE] > 0.0 && rho_lo > 0.0 && rho_hi > rho_lo;
        let range = if varies {
            [rho_lo.ln(), rho_hi.ln()]
        } else {
            [f64::NAN; 2]
        };
        let (nodes, weights) = if varies {
            cheb(range[0], range[1], NODES)
        } else {
            (Vec::new(), Vec::new())
        };
        let rhos: Vec<f64> = if varies {
            nodes.iter().map(|s| s.exp()).collect()
        } else {
            vec![nom[RATE] / nom[E0]]
        };
        let (sin_phi, cos_phi) = phi.sin_cos();
        let states = if reducible {
            layers
                .into_par_iter()
                .map(|n| state_table(r, n, &rhos, phi, stress))
                .collect::<Result<Vec<_>, _>>()?
        } else {
            Vec::new()
        };
        Ok(Surrogate {
            prepared,
            nodes,
            weights,
            range,
            t_scales,
            reducible,
            states,
            first,
            sin_phi,
            cos_phi,
            fallbacks: std::sync::atomic::AtomicU64::new(0),
            build_seconds: t0.elapsed().as_secs_f64(),
            collapse: None,
        })
    }

    /// The tables of this surrogate for the spec `text` it was built from, to ship to where
    /// [`Surrogate::from_tables`] makes the same surrogate without solving them again.
    #[must_use]
    pub fn tables(&self, text: &str) -> SurrogateTables {
        SurrogateTables {
            spec: text.to_owned(),
            nodes: self.nodes.clone(),
            weights: self.weights.clone(),
            range: self.range.to_vec(),
            t_scales: self.t_scales,
            reducible: self.reducible,
            states: self.states.clone(),
            first: self.first,
            phi: vec![self.sin_phi, self.cos_phi],
            build_seconds: self.build_seconds,
            collapse: self.collapse.clone(),
        }
    }

    /// The surrogate of the spec `text` (resolved as `r`, its uncertain model `prepared`) from
    /// `tables` built elsewhere on the same spec ([`Surrogate::build`], or its parts joined by
    /// [`SurrogateTables::join`]): the same numbers without a solve.
    ///
    /// # Errors
    /// Tables of another spec, or of another print (not one table per layer count).
    pub fn from_tables(
        r: &Resolved,
        text: &str,
        prepared: Prepared,
        tables: SurrogateTables,
    ) -> Result<Surrogate, DesignError> {
        let max = r.spec.object.max_layers;
        let bad = |m: &str| uerr("uncertainty", format!("shipped Monte Carlo tables: {m}"));
        if tables.spec != text {
            return Err(bad("they were built for another spec"));
        }
        let (Ok(range), [sin_phi, cos_phi]) =
            (<[f64; 2]>::try_from(tables.range), tables.phi.as_slice())
        else {
            return Err(bad("malformed (range or friction angle)"));
        };
        if tables.reducible && (tables.first != 1 || tables.states.len() != max) {
            return Err(bad(&format!(
                "{} layer counts, the spec prints {max}",
                tables.states.len()
            )));
        }
        if r.spec.nonlinear().is_some() && tables.collapse.is_none() {
            return Err(bad(
                "the spec has [analysis.nonlinear] and the tables have no collapse tables \
                 (build them with collapse_tables and attach them with \
                 SurrogateTables::with_collapse): sampling without them would leave the \
                 collapse out",
            ));
        }
        Ok(Surrogate {
            prepared,
            nodes: tables.nodes,
            weights: tables.weights,
            range,
            t_scales: tables.t_scales,
            reducible: tables.reducible,
            states: tables.states,
            first: 1,
            sin_phi: *sin_phi,
            cos_phi: *cos_phi,
            fallbacks: std::sync::atomic::AtomicU64::new(0),
            build_seconds: tables.build_seconds,
            collapse: tables.collapse,
        })
    }

    /// The values of the state with `n` layers at parameters `p` ([`PARAMETERS`] order): from
    /// the tables where the reductions hold, else by a re-solve.
    ///
    /// # Errors
    /// A failed re-solve.
    pub fn state(&self, r: &Resolved, n: usize, p: &[f64; 6]) -> Result<StateValues, DesignError> {
        self.state_with(r, n, p, false)
    }

    /// [`Surrogate::state`], but with ρ outside the box clamped to its edge instead of a
    /// re-solve (`clamp`): for FORM, whose iterates may wander far out. A point outside the box
    /// has some |zᵢ| > [`Z_RANGE`], so a design point there has β > 5 (P_f < 3·10⁻⁷); its β is
    /// then approximate (the shape ρ held at the edge, the exact scalings in E₀, γ, f₀, ḟ, T
    /// still applied).
    ///
    /// # Errors
    /// A failed re-solve.
    pub fn state_with(
        &self,
        r: &Resolved,
        n: usize,
        p: &[f64; 6],
        clamp: bool,
    ) -> Result<StateValues, DesignError> {
        self.state_layers(r, n, p, clamp, None)
    }

    /// [`Surrogate::state_with`] with the strength and sliding of layer `layer` only (None:
    /// the worst layer).
    ///
    /// # Errors
    /// A failed re-solve.
    pub fn state_layers(
        &self,
        r: &Resolved,
        n: usize,
        p: &[f64; 6],
        clamp: bool,
        layer: Option<usize>,
    ) -> Result<StateValues, DesignError> {
        let nom = &self.prepared.nominal;
        let table = match self.states.get(n.wrapping_sub(self.first)) {
            Some(t) if self.reducible && !t.exact => t,
            _ => return exact_state(r, n, p),
        };
        let k = self.nodes.len().max(1);
        let mut coef = [0.0; NODES];
        let coef = &mut coef[..k];
        if self.nodes.is_empty() {
            coef[0] = 1.0;
        } else {
            let tf = if self.t_scales { p[T] / nom[T] } else { 1.0 };
            let rho = p[RATE] / p[E0] * tf;
            let s = rho.ln();
            if !table_coefficients(&self.nodes, &self.weights, self.range, s, clamp, coef) {
                self.fallbacks
                    .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                return exact_state(r, n, p);
            }
        }
        let at = |v: &[f64], stride: usize, i: usize| -> f64 {
            coef.iter()
                .enumerate()
                .map(|(j, c)| c * v.get(j * stride + i).copied().unwrap_or(0.0))
                .sum()
        };
        let rg = p[GAMMA] / nom[GAMMA];
        let blf = table
            .log_blf
            .as_ref()
            .map(|l| at(l, 1, 0).exp() * (p[E0] / nom[E0]) / rg);
        let time = time_at(&r.time, p);
        let scale_t = if self.t_scales { p[T] / nom[T] } else { 1.0 };
        let layers = table.ages.len();
        let worst = |v: &Option<Vec<f64>>, capacity: &dyn Fn(&MohrCoulomb) -> f64| {
            v.as_ref().map(|v| {
                let range = match layer {
                    Some(l) => l.min(layers)..(l + 1).min(layers),
                    None => 0..layers,
                };
                range.fold(0.0_f64, |m, kl| {
                    let age = table.ages.get(kl).copied().unwrap_or(0.0) * scale_t;
                    let d = rg * at(v, layers, kl).exp();
                    let u = match time.mohr_coulomb(age) {
                        Some(mc) if capacity(&mc) > 0.0 => d / capacity(&mc),
                        _ if d > 0.0 => f64::INFINITY,
                        _ => 0.0,
                    };
                    m.max(u)
                })
            })
        };
        let cos_phi = self.cos_phi;
        let _ = self.sin_phi;
        let strength = worst(&table.strength, &|mc| mc.cohesion * cos_phi);
        let sliding = worst(&table.sliding, &|mc| mc.cohesion);
        Ok((blf, strength, sliding))
    }

    /// The largest relative differences (BLF, strength, sliding) between the tables and
    /// re-solves at `points` parameter sets of the model (drawn by the model's own seeded
    /// Monte Carlo stream `seed`, every `stride`-th layer count).
    ///
    /// # Errors
    /// A failed solve.
    pub fn verify(
        &self,
        r: &Resolved,
        points: u64,
        seed: u64,
        stride: usize,
    ) -> Result<[f64; 3], DesignError> {
        let mut worst = [0.0_f64; 3];
        let m = &self.prepared.model;
        let mut xs = Vec::new();
        let collect = std::sync::Mutex::new(&mut xs);
        sample_events(
            m,
            0,
            &|_u: &[f64], x: &[f64], _h: &mut [bool]| {
                if let Ok(mut g) = collect.lock() {
                    g.push(x.to_vec());
                }
                Ok(())
            },
            &SamplingOptions::new(points.max(2), seed),
            Batch { index: 0, count: 1 },
        )
        .map_err(|e| uerr("uncertainty", e.to_string()))?;
        let stride = stride.max(1);
        let max = r.spec.object.max_layers;
        let pairs: Vec<(usize, Vec<f64>)> = xs
            .iter()
            .flat_map(|x| (1..=max).step_by(stride).map(move |n| (n, x.clone())))
            .collect();
        let diffs = pairs
            .par_iter()
            .map(|(n, x)| {
                let p = self.prepared.params(x);
                let a = self.state(r, *n, &p)?;
                let b = exact_state(r, *n, &p)?;
                let rel = |a: Option<f64>, b: Option<f64>| match (a, b) {
                    (Some(a), Some(b)) if b.abs() > 0.0 && b.is_finite() => ((a - b) / b).abs(),
                    _ => 0.0,
                };
                Ok([rel(a.0, b.0), rel(a.1, b.1), rel(a.2, b.2)])
            })
            .collect::<Result<Vec<_>, DesignError>>()?;
        for d in diffs {
            for k in 0..3 {
                worst[k] = worst[k].max(d[k]);
            }
        }
        Ok(worst)
    }
}

/// One state's tables at the points `rhos` (see [`StateTable`]).
fn state_table(
    r: &Resolved,
    n: usize,
    rhos: &[f64],
    phi: f64,
    stress: bool,
) -> Result<StateTable, DesignError> {
    let (mut model, layers) = object_shell(r, n);
    let ages = r.schedule.ages(n);
    let c = &r.spec.checks;
    let opts = c.green_options();
    // A unit capacity: `utilisation` then returns the Mohr–Coulomb demand itself.
    let unit = MohrCoulomb {
        cohesion: 1.0 / phi.cos(),
        friction_angle: phi,
    };
    let mut log_blf = c.buckling.then(Vec::new);
    let mut strength = (stress && c.strength).then(Vec::new);
    let mut sliding = (stress && c.sliding).then(Vec::new);
    let mut start: Option<ModeStart> = None;
    for &rho in rhos {
        let mut time = r.time.clone();
        time.youngs_modulus.rate = rho * r.time.youngs_modulus.initial;
        let (b, st, mode) = solve_state(
            &mut model,
            &layers,
            &ages,
            &time,
            &opts,
            start.take(),
            stress,
        )?;
        start = mode;
        if let Some(l) = log_blf.as_mut() {
            match b {
                BucklingOutcome::Factor { blf } if blf > 0.0 => l.push(blf.ln()),
                // A point without a positive factor: this state is re-solved instead.
                _ => {
                    return Ok(StateTable {
                        log_blf: None,
                        strength: None,
                        sliding: None,
                        ages: Vec::new(),
                        exact: true,
                    });
                }
            }
        }
        let (mut d, mut sl) = (vec![0.0_f64; n], vec![0.0_f64; n]);
        if let Some(st) = &st {
            for (res, info) in st.elements.iter().zip(&layers) {
                let [sx, sy, sxy] = res.membrane_stress();
                let k = info.younger.min(n - 1);
                let (s1, s2) = principal(sx, sy, sxy);
                d[k] = d[k].max(unit.utilisation(s1, s2));
                let (_, tau) = bed_traction(&res.frame, [sx, sy, sxy], info.bed_normal);
                sl[k] = sl[k].max(tau.abs());
            }
        }
        // Logarithms (floored at 1e-12 of the state's largest, so that a layer without
        // stress stays finite): interpolated and continued in log–log.
        for (v, x) in [(strength.as_mut(), d), (sliding.as_mut(), sl)] {
            if let Some(v) = v {
                let top = x.iter().copied().fold(0.0_f64, f64::max);
                let floor = (1e-12 * top).max(f64::MIN_POSITIVE);
                v.extend(x.iter().map(|y| y.max(floor).ln()));
            }
        }
    }
    Ok(StateTable {
        log_blf,
        strength,
        sliding,
        ages,
        exact: false,
    })
}

/// The crude Monte Carlo of a buildability print (`[uncertainty] monte_carlo = N`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrintMonteCarlo {
    /// Samples N.
    pub samples: u64,
    /// Seed.
    pub seed: u64,
    /// P_f of the print (some layer count up to `max_layers` fails), its 95 % (Wilson)
    /// interval and β.
    pub pf: f64,
    /// 95 % interval of `pf`.
    pub pf_interval: [f64; 2],
    /// β = −Φ⁻¹(P_f).
    pub beta: f64,
    /// Per layer count n = 1, 2, …: P(state n fails) and its 95 % interval.
    pub state_pf: Vec<[f64; 3]>,
    /// Per layer count n: P(the print has failed by layer n).
    pub failed_by: Vec<f64>,
    /// Mean and standard deviation of the failure layer among the samples that fail.
    pub failure_layer_mean: Option<f64>,
    /// Standard deviation of the failure layer.
    pub failure_layer_std: Option<f64>,
    /// Samples evaluated by a re-solve (outside the tables' box).
    pub resolves: u64,
    /// Wall-clock seconds of the tables and of the sampling.
    pub seconds: [f64; 2],
}

/// Whether the state fails at these values (the deterministic verdict's rules).
fn fails(v: StateValues, blf_min: f64) -> bool {
    v.0.is_some_and(|b| b < blf_min) || v.1.is_some_and(|u| u > 1.0) || v.2.is_some_and(|u| u > 1.0)
}

/// Batch `batch` of the print's Monte Carlo: 2N events per sample, "state n fails" (0 ≤ n − 1
/// < N) and "failed by layer n" (N + n − 1), each state at its print time's drifted variables
/// (the same u for every state: the same batch of concrete drifting).
///
/// # Errors
/// A drift factor that is not positive, or a failed re-solve.
pub fn monte_carlo_batch(
    r: &Resolved,
    sur: &Surrogate,
    options: &SamplingOptions,
    batch: Batch,
) -> Result<kappe_reliability::EventBatch, DesignError> {
    let max = r.spec.object.max_layers;
    let p = &sur.prepared;
    let models = (1..=max)
        .map(|n| {
            if p.drifts.is_empty() {
                Ok(None)
            } else {
                p.model
                    .drifted(&p.drifts, t_hours(r, n))
                    .map(Some)
                    .map_err(|e| uerr("uncertainty.drift", format!("state {n}: {e}")))
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    let blf_min = r.spec.checks.blf_min;
    let indicator = |u: &[f64], x: &[f64], hits: &mut [bool]| -> Result<(), EvalError> {
        let mut failed = false;
        for n in 1..=max {
            let xn = match models.get(n - 1) {
                Some(Some(m)) => m.x_from_u(u),
                _ => x.to_vec(),
            };
            let v = sur
                .state(r, n, &p.params(&xn))
                .map_err(|e| EvalError::from(e.to_string()))?;
            let collapses = || match &sur.collapse {
                Some(c) => c
                    .fails(r, p, n, &xn, false, &sur.fallbacks)
                    .map_err(|e| EvalError::from(e.to_string())),
                None => Ok(false),
            };
            if fails(v, blf_min) || collapses()? {
                hits[n - 1] = true;
                failed = true;
            }
            if failed {
                hits[max + n - 1] = true;
            }
        }
        Ok(())
    };
    sample_events(&p.model, 2 * max, &indicator, options, batch)
        .map_err(|e| uerr("uncertainty", format!("Monte Carlo: {e}")))
}

/// The print's Monte Carlo from its merged batches.
///
/// # Errors
/// Batches that do not make up one run.
pub fn monte_carlo_result(
    batches: &[kappe_reliability::EventBatch],
    resolves: u64,
    seconds: [f64; 2],
) -> Result<PrintMonteCarlo, DesignError> {
    let res: Vec<SamplingResult> =
        merge_events(batches).map_err(|e| uerr("uncertainty", e.to_string()))?;
    let max = res.len() / 2;
    let (Some(first), Some(last)) = (batches.first(), res.last()) else {
        return Err(uerr("uncertainty", "Monte Carlo: no batches"));
    };
    let failed_by: Vec<f64> = res.iter().skip(max).map(|s| s.pf).collect();
    let total = failed_by.last().copied().unwrap_or(0.0);
    let (mut m1, mut m2, mut prev) = (0.0, 0.0, 0.0);
    for (k, f) in failed_by.iter().enumerate() {
        let pk = f - prev;
        prev = *f;
        let n = (k + 1) as f64;
        m1 += pk * n;
        m2 += pk * n * n;
    }
    let (mean, std) = if total > 0.0 {
        let mean = m1 / total;
        (Some(mean), Some((m2 / total - mean * mean).max(0.0).sqrt()))
    } else {
        (None, None)
    };
    Ok(PrintMonteCarlo {
        samples: first.options.samples,
        seed: first.options.seed,
        pf: last.pf,
        pf_interval: last.interval,
        beta: last.beta,
        state_pf: res
            .iter()
            .take(max)
            .map(|s| [s.pf, s.interval[0], s.interval[1]])
            .collect(),
        failed_by,
        failure_layer_mean: mean,
        failure_layer_std: std,
        resolves,
        seconds,
    })
}

/// The print's Monte Carlo in one process (every block in parallel).
///
/// # Errors
/// See [`monte_carlo_batch`].
pub fn monte_carlo(
    r: &Resolved,
    sur: &Surrogate,
    samples: u64,
    seed: u64,
) -> Result<PrintMonteCarlo, DesignError> {
    let t0 = kappe_fe::clock::Instant::now();
    let before = sur.fallbacks.load(std::sync::atomic::Ordering::Relaxed);
    let b = monte_carlo_batch(
        r,
        sur,
        &SamplingOptions::new(samples, seed),
        Batch { index: 0, count: 1 },
    )?;
    let after = sur.fallbacks.load(std::sync::atomic::Ordering::Relaxed);
    monte_carlo_result(
        &[b],
        after - before,
        [sur.build_seconds, t0.elapsed().as_secs_f64()],
    )
}

/// Which checks of a state the random variables enter: buckling when γ, E₀, Ė or T is
/// uncertain; strength and sliding when any is (the stresses scale with γ and change with ρ,
/// the capacities with f₀, ḟ and T).
fn random_checks(p: &Prepared, v: StateValues) -> Vec<&'static str> {
    let any = p.idx.iter().any(Option::is_some);
    let stiff = [GAMMA, E0, RATE, T].iter().any(|&k| p.idx[k].is_some());
    let mut out = Vec::new();
    if stiff && v.0.is_some_and(|b| b > 0.0) {
        out.push("buckling");
    }
    if any && v.1.is_some_and(|u| u > 0.0) {
        out.push("strength");
    }
    if any && v.2.is_some_and(|u| u > 0.0) {
        out.push("sliding");
    }
    out
}

/// A component's first-order β at the means, G(0)/‖∇ᵤG(0)‖ by central differences (step 10⁻³
/// in u, on the tables: microseconds), above which it is left out of FORM.
pub const FAR_FIRST_ORDER: f64 = 16.0;

/// A component's first-order β at the means (∞ when it does not depend on the variables, NaN
/// when an evaluation fails: kept). Beyond [`FAR_FIRST_ORDER`] a state's component is left out
/// unless it is the state's nearest. Such a component holds P_f ≪ 10⁻⁵⁰
/// unless its surface curves towards the origin by more than half its distance, and FORM far
/// out fails on it instead: the strength of a layer at u = 0.3 with only γ (cov 0.02) and E₀
/// uncertain lies ~60 σ of γ away, beyond γ = 0, and a check that depends on E₀ only through
/// ρ is nearly flat (HL-RF steps to E₀ → 0). A component whose evaluation fails here is kept
/// (FORM reports it).
fn first_order_at_the_means(
    model: &kappe_reliability::Model,
    g: &mut dyn kappe_reliability::LimitState,
) -> f64 {
    let k = model.variables().len();
    let at = |g: &mut dyn kappe_reliability::LimitState, i: usize, h: f64| {
        let mut u = vec![0.0; k];
        if let Some(v) = u.get_mut(i) {
            *v = h;
        }
        g.value(&model.x_from_u(&u))
    };
    let Ok(g0) = at(g, k, 0.0) else {
        return f64::NAN;
    };
    let h = 1e-3;
    let mut norm2 = 0.0;
    for i in 0..k {
        match (at(g, i, h), at(g, i, -h)) {
            (Ok(a), Ok(b)) => norm2 += ((a - b) / (2.0 * h)).powi(2),
            _ => return f64::NAN,
        }
    }
    if norm2 > 0.0 {
        g0 / norm2.sqrt()
    } else if g0 > 0.0 {
        f64::INFINITY
    } else {
        f64::NEG_INFINITY
    }
}

/// FORM of every check of the layer counts `states` (n, its deterministic values) and the
/// print's series system; per state its [`crate::analysis::reliability::StateReliability`] (index = n) and its check results.
///
/// # Errors
/// A drift factor that is not positive, a failed re-solve, FORM that does not converge, or no
/// random check at all.
pub fn reliability(
    r: &Resolved,
    sur: &Surrogate,
    states: &[(usize, StateValues)],
    table: &UncertaintyTable,
) -> Result<Reliability, DesignError> {
    reliability_with_points(r, sur, states, table).map(|(rel, _)| rel)
}

/// [`reliability`] and the FORM result of every state's `collapse` component (layer count,
/// result): the design points [`crate::commands::buildability_collapse::check_design_points`]
/// re-solves.
///
/// # Errors
/// See [`reliability`].
pub fn reliability_with_points(
    r: &Resolved,
    sur: &Surrogate,
    states: &[(usize, StateValues)],
    table: &UncertaintyTable,
) -> Result<(Reliability, Vec<(usize, FormResult)>), DesignError> {
    let t0 = kappe_fe::clock::Instant::now();
    let p = &sur.prepared;
    let blf_min = r.spec.checks.blf_min;
    let seed = table.seed.unwrap_or(0);
    type StateOut = Option<crate::analysis::reliability::StateForm>;
    let per_state: Vec<StateOut> = states
        .par_iter()
        .map(|&(n, v)| -> Result<StateOut, DesignError> {
            let checks = random_checks(p, v);
            let collapse = sur.collapse.as_ref().filter(|c| c.has(n));
            if checks.is_empty() && collapse.is_none() {
                return Ok(None);
            }
            let th = t_hours(r, n);
            let model = p
                .model
                .drifted(&p.drifts, th)
                .map_err(|e| uerr("uncertainty.drift", format!("state {n} at {th:.3} h: {e}")))?;
            // Buckling one component; strength and sliding one per layer (each layer's
            // utilisation is smooth in the parameters, their maximum is not: the worst layer
            // switches between the old bottom and the young top as f₀ and ḟ trade off, and
            // HL-RF would zigzag on that kink). Only layers within a factor 5 of the state's
            // worst nominal utilisation: a ln-margin 1.6 larger, about 16 standard deviations
            // of a 10 % scatter, adds nothing to the state's P_f, and FORM far out (β ≫ 10)
            // meets the round-off of its difference gradients.
            let mut comps: Vec<(&'static str, Option<usize>)> = Vec::new();
            for &name in &checks {
                if name == "buckling" {
                    comps.push((name, None));
                    continue;
                }
                let pick = |v: StateValues| if name == "strength" { v.1 } else { v.2 };
                let worst = pick(sur.state_layers(r, n, &p.nominal, true, None)?).unwrap_or(0.0);
                for layer in 0..n {
                    let u = pick(sur.state_layers(r, n, &p.nominal, true, Some(layer))?);
                    if u.is_some_and(|u| u >= 0.2 * worst && u > 0.0 && u.is_finite()) {
                        comps.push((name, Some(layer)));
                    }
                }
            }
            let named: Vec<(&'static str, Box<dyn kappe_reliability::LimitState + '_>)> = comps
                .iter()
                .map(|&(name, layer)| {
                    let g = move |x: &[f64]| -> Result<f64, EvalError> {
                        let x = &p.floored(x);
                        let v = sur
                            .state_layers(r, n, &p.params(x), true, layer)
                            .map_err(|e| EvalError::from(e.to_string()))?;
                        // Logarithmic forms: the same failure surfaces as BLF − BLF_min and
                        // 1 − u (so the same β), but nearly linear in u-space for the products
                        // of powers the reductions give, which FORM needs far out (β ≫ 5).
                        let val = match name {
                            "buckling" => v.0.map(|b| (b / blf_min).ln()),
                            "strength" => v.1.map(|u| -u.ln()),
                            _ => v.2.map(|u| -u.ln()),
                        };
                        val.ok_or_else(|| {
                            EvalError::from(format!("state {n}: no {name} value at x = {x:?}"))
                        })
                    };
                    let b: Box<dyn kappe_reliability::LimitState + '_> = Box::new(Fallible(g));
                    (name, b)
                })
                .collect();
            let mut named = named;
            if let Some(c) = collapse {
                named.push(("collapse", c.limit_state(r, p, n)));
            }
            // Far components left out, but the nearest one kept so that every state keeps a β.
            let b1: Vec<f64> = named
                .iter_mut()
                .map(|(_, g)| first_order_at_the_means(&model, g.as_mut()))
                .collect();
            let nearest = b1
                .iter()
                .enumerate()
                .filter(|b| b.1.is_finite())
                .min_by(|a, b| a.1.total_cmp(b.1))
                .map(|b| b.0);
            let mut k = 0;
            named.retain(|_| {
                k += 1;
                b1.get(k - 1)
                    .is_none_or(|&b| b.is_nan() || b <= FAR_FIRST_ORDER)
                    || nearest == Some(k - 1)
            });
            form_checks(&model, named, n, th, seed)
                .map(Some)
                .map_err(|e| {
                    uerr(
                        "uncertainty",
                        format!("state {n}: reliability analysis: {e}"),
                    )
                })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut results = Vec::new();
    let mut out = Vec::new();
    let mut points = Vec::new();
    for (s, rs) in per_state.into_iter().flatten() {
        for (name, f, so) in rs {
            if name == "collapse" {
                points.push((s.index, f.clone()));
            }
            results.push((s.index, name, f, so));
        }
        out.push(s);
    }
    if results.is_empty() {
        return Err(uerr(
            "uncertainty",
            "no checked state depends on the uncertain parameters",
        ));
    }
    print_reliability(
        results,
        out,
        &SystemOptions {
            samples: table.system_samples.unwrap_or(20_000),
            seed,
            ditlevsen: false,
        },
        BETA_MIN_DEFAULT,
        t0,
    )
    .map(|rel| (rel, points))
}

/// FORM of every checked layer count and of the print, and the Monte Carlo when
/// `[uncertainty] monte_carlo` asks for it: what [`crate::commands::buildability::run`] adds
/// with `[uncertainty]`.
///
/// # Errors
/// See [`Surrogate::build`], [`reliability`] and [`monte_carlo`].
pub fn analyse(
    r: &Resolved,
    table: &UncertaintyTable,
    states: &[crate::commands::buildability::BuildState],
) -> Result<Analysed, DesignError> {
    let mut sur = Surrogate::build(r, prepare(r, table)?)?;
    if r.spec.nonlinear().is_some() {
        sur.collapse = Some(CollapseTables::build(r, &sur.prepared, states)?);
    }
    let values: Vec<(usize, StateValues)> = states
        .iter()
        .map(|s| {
            (
                s.layers,
                (s.blf, s.strength_utilisation, s.sliding_utilisation),
            )
        })
        .collect();
    let (rel, points) = reliability_with_points(r, &sur, &values, table)?;
    let collapse = match &sur.collapse {
        Some(c) => Some(c.report(r, &sur.prepared, &points)?),
        None => None,
    };
    let mc = match table.monte_carlo {
        Some(n) => Some(monte_carlo(r, &sur, n, table.seed.unwrap_or(0))?),
        None => None,
    };
    Ok((rel, mc, collapse))
}

/// What [`analyse`] adds to a buildability run: FORM, the Monte Carlo (if asked for) and the
/// collapse limit state's tables and design-point checks (with `[analysis.nonlinear]`).
pub type Analysed = (
    Reliability,
    Option<PrintMonteCarlo>,
    Option<crate::commands::buildability_collapse::CollapseReliability>,
);
