//! The Monte Carlo of a design's print (issue 24: "FORM P_f against Monte Carlo with ≥ 10⁴
//! samples"): `[uncertainty] monte_carlo = N` samples the print's **governing states** and
//! evaluates every limit-state component FORM built for them — the same g functions
//! ([`super::reliability::limit_state`], [`super::reliability::GreenField::components`],
//! [`super::reliability::time_buckling_g`]) — at each sample; the print fails at a sample when
//! any component of any governing state has g ≤ 0. docs/reliability.md, "Monte Carlo of a
//! design", has the formulas; the steps are plain functions over plain data, so a Dask client
//! runs them as tasks (python/kappe/_design_mc.py):
//!
//! 1. [`plan`]: the governing states from the FORM run (the rule: [`GOVERNING_SHARE`],
//!    [`GOVERNING_DELTA`]) and their components' data.
//! 2. [`build_tables`]: per governing state with the time model uncertain, λ tabulated in
//!    ln(Ė/E₀) (and the speed factor s) through Chebyshev points, since λ = E₀·Λ(Ė/E₀[, s]);
//!    any subset of the states, so the tables can be built in parts.
//! 3. [`setup`]: the importance-sampling centres (FORM of every component on the tables).
//! 4. [`sample_batch`]: batch i of n of the samples, blocks of [`BLOCK`] on their own ChaCha8
//!    streams; [`merge`] adds the blocks in block order, so any split equals one run bit for bit.

use std::sync::atomic::{AtomicU64, Ordering};

use kappe_reliability::{
    Batch, Drift, EvalError, Fallible, FormOptions, LimitState, Model, SamplingBatch,
    SamplingMethod, SamplingOptions, form,
};
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use super::collapse_reliability::{CapCollapseModel, CapCollapseTables};
use super::reliability::{
    Check, FAR_BETA, GreenField, RESOLVE_TOLERANCE, Reliability, TimeBuckling, Vars, limit_state,
    scaled_ages, screen_delta, state_checks, time_buckling_g,
};
use super::{AnalysisOptions, check::Analysis};
use crate::form::cap::Cap;
use crate::input::error::DesignError;
use crate::input::material::{TimeLaw, TimeModel};
use crate::schedule::Schedule;

/// The states left out of the Monte Carlo hold at most this share of the print's FORM P_f:
/// Σ_{q left out} Φ(−(β_q − Δ_q)) ≤ GOVERNING_SHARE·P_f,FORM (a bound of their union, by
/// Boole's inequality, with each state's β lowered by its margin Δ_q), so the sampled P_f of the
/// governing states misses at most 1 % of the print's — well inside a 10⁴-sample interval.
pub const GOVERNING_SHARE: f64 = 1e-2;

/// Δ_q of a state whose β is FORM's: FORM's first-order error measured against Monte Carlo on
/// study No. 14's last state with E₀ and Ė uncertain (0.128 against 0.113: Δβ ≈ 0.07,
/// docs/reliability.md, Limits) times a safety factor of about 7. A screened state (first-order
/// β₁, `beta_first_order`) takes the screening rule's δ(β₁), [`screen_delta`].
pub const GOVERNING_DELTA: f64 = 0.5;

/// Chebyshev points of ln ρ (ρ = Ė/E₀) per state: ln Λ is smooth in ln ρ (from the uniform
/// modulus at ρ → 0 to the age-proportional one at ρ → ∞); 17 points (× 7 in s) keep λ within
/// 1.1e-6 relative of direct solves over the ±5 standard-deviation box of E₀ (cov 0.2), Ė
/// (0.3) and the speed (0.1) on study No. 14's cap (test
/// `design_monte_carlo::table_matches_direct_solves`, bound 1e-5).
pub const RHO_NODES: usize = 17;

/// Chebyshev points of the print-duration factor s = v₀/v (when the print speed is uncertain).
pub const SPEED_NODES: usize = 7;

/// Half-width, in standard deviations of each time variable, of the box the tables cover for
/// crude sampling; importance sampling adds the largest governing β (its samples sit around
/// the design points). A sample outside is evaluated by a direct re-solve.
pub const Z_BOX: f64 = 5.0;

/// Importance-sampling centres: the design points of the components whose FORM P_f is at least
/// this share of the largest (the others add nothing to the mixture's coverage of the failure
/// domain that the union of the first does not; the estimator is unbiased whatever the centres).
pub const CENTER_SHARE: f64 = 1e-3;

/// Samples per block: the unit of the batches and of the random streams.
pub const BLOCK: u64 = 1000;

pub use crate::input::uncertainty::McMethod;

/// `reliability.monte_carlo` of summary.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DesignMonteCarlo {
    /// `crude` or `importance`.
    pub method: McMethod,
    /// Samples N.
    pub samples: u64,
    /// Seed of the streams.
    pub seed: u64,
    /// Sampled P_f of the governing states (series system).
    pub pf: f64,
    /// −Φ⁻¹(P̂_f).
    pub beta: f64,
    /// 95 % interval: Wilson's for crude sampling, P̂ ± 1.96·s/√N for importance sampling.
    pub pf_interval: [f64; 2],
    /// Coefficient of variation of P̂_f.
    pub cov: f64,
    /// Failing samples.
    pub failures: u64,
    /// FORM's P_f of the print (`reliability.pf`), to compare.
    pub form_pf: f64,
    /// Whether FORM's P_f lies in the interval.
    pub form_in_interval: bool,
    /// SORM's P_f of the print (`reliability.sorm.pf`), to compare (absent without it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sorm_pf: Option<f64>,
    /// Whether SORM's P_f lies in the interval.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sorm_in_interval: Option<bool>,
    /// The governing states sampled.
    pub states: Vec<usize>,
    /// Bound of the share of the print's FORM P_f held by the states left out.
    pub excluded_share: f64,
    /// States whose buckling λ is tabulated, and the shell solves the tables took.
    pub tables: usize,
    /// Shell solves of the tables.
    pub table_solves: usize,
    /// Samples a buckling component evaluated by a direct re-solve (outside the table).
    pub resolved_samples: u64,
    /// Importance-sampling centres (components' design points).
    pub centers: usize,
    /// Wall-clock seconds (tables and samples).
    pub seconds: f64,
}

/// The kind of a [`McCheck`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CheckKind {
    /// [`Check::Buckling`]: values BLF₀, s_ν.
    Buckling,
    /// [`Check::Compression`]: σ_min,q,₀.
    Compression,
    /// [`Check::Tension`]: σ_max,q,₀.
    Tension,
    /// [`Check::Strength`]: u₀.
    Strength,
    /// [`Check::GreenLayers`]: u₀.
    GreenLayers,
    /// [`Check::BucklingTime`]: BLF₀, s_ν, λ at the design's values (NaN: none).
    BucklingTime,
}

/// A [`Check`] as plain data (numbers as bit patterns), for shipping to workers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct McCheck {
    /// Which check.
    pub kind: CheckKind,
    /// Its numbers (see [`CheckKind`]).
    #[serde(with = "bits")]
    pub values: Vec<f64>,
    /// Top print index (buckling with the time model).
    pub top: usize,
}

impl McCheck {
    fn of(c: Check) -> McCheck {
        let (kind, values, top) = match c {
            Check::Buckling { blf, s_nu } => (CheckKind::Buckling, vec![blf, s_nu], 0),
            Check::Compression(s) => (CheckKind::Compression, vec![s], 0),
            Check::Tension(s) => (CheckKind::Tension, vec![s], 0),
            Check::Strength(u) => (CheckKind::Strength, vec![u], 0),
            Check::GreenLayers(u) => (CheckKind::GreenLayers, vec![u], 0),
            Check::BucklingTime {
                blf,
                s_nu,
                top,
                shell0,
            } => (
                CheckKind::BucklingTime,
                vec![blf, s_nu, shell0.unwrap_or(f64::NAN)],
                top,
            ),
        };
        McCheck { kind, values, top }
    }

    fn check(&self) -> Check {
        let v = |i: usize| self.values.get(i).copied().unwrap_or(f64::NAN);
        match self.kind {
            CheckKind::Buckling => Check::Buckling {
                blf: v(0),
                s_nu: v(1),
            },
            CheckKind::Compression => Check::Compression(v(0)),
            CheckKind::Tension => Check::Tension(v(0)),
            CheckKind::Strength => Check::Strength(v(0)),
            CheckKind::GreenLayers => Check::GreenLayers(v(0)),
            CheckKind::BucklingTime => Check::BucklingTime {
                blf: v(0),
                s_nu: v(1),
                top: self.top,
                shell0: Some(v(2)).filter(|l| l.is_finite()),
            },
        }
    }
}

/// One governing state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GovState {
    /// State index.
    pub index: usize,
    /// Print time, h (the drift's).
    #[serde(with = "bits::one")]
    pub t_hours: f64,
    /// The state's β (FORM or first order).
    #[serde(with = "bits::one")]
    pub beta: f64,
    /// Its random checks.
    pub checks: Vec<McCheck>,
    /// Whether it has a collapse component ([`McPlan::collapse`]'s table).
    #[serde(default)]
    pub collapse: bool,
}

/// What the Monte Carlo samples: [`plan`]'s output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct McPlan {
    /// The estimator (never `Auto`).
    pub method: McMethod,
    /// Samples N.
    pub samples: u64,
    /// Seed.
    pub seed: u64,
    /// The print's FORM P_f.
    #[serde(with = "bits::one")]
    pub form_pf: f64,
    /// The print's SORM P_f (compared only, never sampled with: plain JSON is enough).
    #[serde(default)]
    pub sorm_pf: Option<f64>,
    /// Bound of the left-out states' share of it.
    #[serde(with = "bits::one")]
    pub excluded_share: f64,
    /// The governing states, in state order.
    pub states: Vec<GovState>,
    /// The collapse tables of the design's states (`[analysis.nonlinear]` with
    /// `[uncertainty]`, [`super::collapse_reliability`]), shipped with the plan so that every
    /// worker samples the same tables.
    #[serde(default)]
    pub collapse: Option<CapCollapseTables>,
}

/// λ of one state tabulated: ln Λ at the Chebyshev points of ln ρ (× s), Λ = λ/E₀.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateTable {
    /// State index.
    pub index: usize,
    /// ln ρ range [lo, hi] (lo = hi: ρ does not vary, one point).
    #[serde(with = "bits")]
    pub rho: Vec<f64>,
    /// s range [lo, hi] (empty: the speed is not uncertain, s = 1).
    #[serde(with = "bits")]
    pub speed: Vec<f64>,
    /// Points in ln ρ and in s.
    pub nodes: [usize; 2],
    /// ln Λ, row-major (ρ point, s point).
    #[serde(with = "bits")]
    pub log_lambda: Vec<f64>,
    /// λ at the design's values (the ratio's denominator).
    #[serde(with = "bits::one")]
    pub shell0: f64,
    /// The state's λ is not homogeneous in the moduli (a modulus cap, the constant law): every
    /// sample re-solves.
    pub exact: bool,
    /// Shell solves the table took.
    pub solves: usize,
}

/// The plan, its tables and the importance-sampling centres: what every batch needs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct McSetup {
    /// The plan.
    pub plan: McPlan,
    /// Tables of the states with the time model uncertain, in state order.
    pub tables: Vec<StateTable>,
    /// Mixture weights (Σ = 1) of the centres.
    #[serde(with = "bits")]
    pub weights: Vec<f64>,
    /// Centres u*_i, row-major (n variables each).
    #[serde(with = "bits")]
    pub centers: Vec<f64>,
    /// Wall-clock seconds of the tables and centres.
    #[serde(with = "bits::one")]
    pub seconds: f64,
}

/// One block's sums.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct McBlock {
    /// Block index.
    pub block: u64,
    /// Samples in it.
    pub samples: u64,
    /// Failing samples.
    pub failures: u64,
    /// Σ of the scores 1[fail]·w.
    #[serde(with = "bits::one")]
    pub sum_w: f64,
    /// Σ of their squares.
    #[serde(with = "bits::one")]
    pub sum_w2: f64,
    /// Samples re-solved outside a table.
    pub resolved: u64,
}

/// What one batch returns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct McBatch {
    /// N and the seed of the run.
    pub samples: u64,
    /// Seed.
    pub seed: u64,
    /// The batch's blocks.
    pub blocks: Vec<McBlock>,
    /// Wall-clock seconds of the batch.
    #[serde(with = "bits::one")]
    pub seconds: f64,
}

/// Where a design's Monte Carlo runs: the cap, the analysis options, the schedule, and the
/// uncertain model.
pub struct McContext<'a> {
    /// The cap.
    pub cap: &'a Cap,
    /// The analysis options (the shells the checks use).
    pub options: &'a AnalysisOptions,
    /// The run's schedule.
    pub schedule: &'a Schedule,
    model: Model,
    drifts: Vec<(String, Drift)>,
    vars: Vars,
    time: Option<TimeModel>,
    collapse: Option<CapCollapseModel<'a>>,
}

fn uerr(message: String) -> DesignError {
    DesignError::Uncertainty {
        field: "uncertainty.monte_carlo".into(),
        message,
    }
}

impl<'a> McContext<'a> {
    /// The context of `cap`'s `[uncertainty]`.
    ///
    /// # Errors
    /// No or an invalid `[uncertainty]`.
    pub fn new(
        cap: &'a Cap,
        options: &'a AnalysisOptions,
        schedule: &'a Schedule,
    ) -> Result<Self, DesignError> {
        let Some(table) = &cap.design.uncertainty else {
            return Err(uerr("the design has no [uncertainty]".into()));
        };
        let model = table.model(&cap.design)?;
        let vars = Vars::of(&model, cap);
        let has_time = cap.design.material.time.is_some() || cap.design.analysis.ageing.is_some();
        let time = if has_time {
            Some(cap.design.time_model()?)
        } else {
            None
        };
        let collapse = CapCollapseModel::new(cap, options, schedule, &model)?;
        Ok(McContext {
            cap,
            options,
            schedule,
            collapse,
            model,
            drifts: table.drifts(),
            vars,
            time,
        })
    }

    fn state_model(&self, s: &GovState) -> Result<Model, DesignError> {
        self.model
            .drifted(&self.drifts, s.t_hours)
            .map_err(|e| DesignError::Uncertainty {
                field: "uncertainty.drift".into(),
                message: format!("state {} at {:.3} h: {e}", s.index, s.t_hours),
            })
    }
}

/// The governing states of a design's print from its FORM run `r` (the rule: the states sorted
/// by β − Δ_q; the longest tail whose Σ Φ(−(β_q − Δ_q)) stays within [`GOVERNING_SHARE`] of
/// the print's FORM P_f is left out), with `samples`, `seed` and the estimator.
///
/// # Errors
/// A state that cannot be built.
pub fn plan(
    ctx: &McContext<'_>,
    analysis: &Analysis,
    r: &Reliability,
    samples: u64,
    seed: u64,
    method: McMethod,
) -> Result<McPlan, DesignError> {
    let per_state = state_checks(ctx.cap, analysis, ctx.schedule, ctx.vars)?;
    let mut ranked: Vec<(f64, &super::reliability::StateReliability)> = r
        .states
        .iter()
        .map(|s| {
            let delta = if s.beta_first_order {
                screen_delta(s.beta)
            } else {
                GOVERNING_DELTA
            };
            (s.beta - delta, s)
        })
        .collect();
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.index.cmp(&b.1.index)));
    // Leave out the longest tail within the share (summed from the safest state up).
    let budget = GOVERNING_SHARE * r.pf;
    let mut excluded = 0.0;
    let mut keep = ranked.len();
    while keep > 1 {
        let Some((b, _)) = ranked.get(keep - 1) else {
            break;
        };
        let p = kappe_reliability::stdnormal::cdf(-b);
        if excluded + p > budget {
            break;
        }
        excluded += p;
        keep -= 1;
    }
    let mut chosen: Vec<usize> = ranked.iter().take(keep).map(|(_, s)| s.index).collect();
    chosen.sort_unstable();
    let collapse = r.collapse_tables.clone();
    let has_collapse = |i: usize| collapse.as_ref().is_some_and(|t| t.has(i));
    let states = per_state
        .into_iter()
        .filter(|(i, _, c)| chosen.contains(i) && (!c.is_empty() || has_collapse(*i)))
        .map(|(index, t_hours, checks)| GovState {
            collapse: has_collapse(index),
            index,
            t_hours,
            beta: r
                .states
                .iter()
                .find(|s| s.index == index)
                .map_or(f64::NAN, |s| s.beta),
            checks: checks.into_iter().map(McCheck::of).collect(),
        })
        .collect();
    let method = match method {
        McMethod::Auto if samples as f64 * r.pf >= 100.0 => McMethod::Crude,
        McMethod::Auto => McMethod::Importance,
        m => m,
    };
    Ok(McPlan {
        method,
        samples,
        seed,
        form_pf: r.pf,
        sorm_pf: r.sorm.as_ref().map(|s| s.pf),
        excluded_share: if r.pf > 0.0 { excluded / r.pf } else { 0.0 },
        states,
        collapse,
    })
}

/// Chebyshev points of the first kind on [lo, hi] and their barycentric weights (Berrut &
/// Trefethen 2004, (5.3)); one point (lo) when k = 1 or lo = hi. The design's and the
/// buildability objects' tables both use it.
pub(crate) fn cheb(lo: f64, hi: f64, k: usize) -> (Vec<f64>, Vec<f64>) {
    if k <= 1 || lo == hi {
        return (vec![lo], vec![1.0]);
    }
    let pi = std::f64::consts::PI;
    let th = |j: usize| (2 * j + 1) as f64 * pi / (2 * k) as f64;
    let nodes = (0..k)
        .map(|j| 0.5 * (lo + hi) + 0.5 * (hi - lo) * th(j).cos())
        .collect();
    let weights = (0..k)
        .map(|j| {
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            sign * th(j).sin()
        })
        .collect();
    (nodes, weights)
}

/// The barycentric coefficients c_j of the interpolant at s, f(s) = Σ c_j f_j, into `out`
/// (as long as `nodes`).
pub(crate) fn bary_into(nodes: &[f64], weights: &[f64], s: f64, out: &mut [f64]) {
    if let Some(j) = nodes.iter().position(|&x| x == s) {
        out.iter_mut().for_each(|c| *c = 0.0);
        out[j] = 1.0;
        return;
    }
    let mut sum = 0.0;
    for ((c, &x), &w) in out.iter_mut().zip(nodes).zip(weights) {
        *c = w / (s - x);
        sum += *c;
    }
    out.iter_mut().for_each(|c| *c /= sum);
}

/// Most points per axis of any table that [`bary_continued`] continues (the buildability
/// objects' 9, the collapse tables' 5, this module's [`RHO_NODES`]).
pub(crate) const MAX_TABLE_NODES: usize = 17;

/// The barycentric coefficients at s outside the range [lo, hi] of `nodes`, for FORM only:
/// the tables (all logarithms) continued as straight lines in s from the nearer edge (C¹;
/// power laws in the variable), so that FORM's far iterates see a smooth surface. `out` is as
/// long as `nodes` (at most [`MAX_TABLE_NODES`]).
fn bary_continued(nodes: &[f64], weights: &[f64], [lo, hi]: [f64; 2], s: f64, out: &mut [f64]) {
    let k = nodes.len().min(MAX_TABLE_NODES);
    let (e, inner) = if s < lo {
        (lo, lo + 1e-3 * (hi - lo))
    } else {
        (hi, hi - 1e-3 * (hi - lo))
    };
    let mut ce = [0.0; MAX_TABLE_NODES];
    let mut ci = [0.0; MAX_TABLE_NODES];
    bary_into(nodes, weights, e, &mut ce[..k]);
    bary_into(nodes, weights, inner, &mut ci[..k]);
    let t = (s - e) / (e - inner);
    for (j, c) in out.iter_mut().enumerate().take(k) {
        *c = ce[j] + (ce[j] - ci[j]) * t;
    }
}

/// The barycentric coefficients of a table axis over `[lo, hi]` at s, into `out`: inside the
/// range the interpolant's; outside it, with `clamp` (FORM), the straight continuation of
/// [`bary_continued`], s held at 10³ box widths beyond the edge (FORM's far iterates, where
/// x → 0 or ∞ underflows the logarithm, stay finite so FORM reports a far β instead of failing
/// on an evaluation). `false` when s is outside without `clamp` (or NaN): the caller falls back
/// to a direct solve and counts it.
pub(crate) fn table_coefficients(
    nodes: &[f64],
    weights: &[f64],
    [lo, hi]: [f64; 2],
    s: f64,
    clamp: bool,
    out: &mut [f64],
) -> bool {
    if (lo..=hi).contains(&s) {
        bary_into(nodes, weights, s, out);
        true
    } else if clamp && !s.is_nan() {
        let far = 1e3 * (hi - lo);
        bary_continued(nodes, weights, [lo, hi], s.clamp(lo - far, hi + far), out);
        true
    } else {
        false
    }
}

/// [`bary_into`] into a new vector.
fn bary(nodes: &[f64], weights: &[f64], s: f64) -> Vec<f64> {
    let mut out = vec![0.0; nodes.len()];
    bary_into(nodes, weights, s, &mut out);
    out
}

/// Whether λ is homogeneous of degree 1 in (E₀, Ė): a law linear in them (linear, exponential)
/// and no modulus cap.
fn homogeneous(time: &TimeModel) -> bool {
    matches!(time.law, TimeLaw::Linear | TimeLaw::Exponential)
        && time.youngs_modulus.max.is_none()
        && time.youngs_modulus.initial > 0.0
}

/// The ranges [ln ρ_lo, ln ρ_hi] and [s_lo, s_hi] over the box of ±`z` standard deviations of
/// each variable of `model` (ρ and s are monotone in each variable, so the corners bound them).
fn ranges(ctx: &McContext<'_>, model: &Model, time: &TimeModel, z: f64) -> ([f64; 2], [f64; 2]) {
    let n = model.len();
    let vars = model.variables();
    let mut rho = [f64::INFINITY, f64::NEG_INFINITY];
    let mut s = [f64::INFINITY, f64::NEG_INFINITY];
    // 3ⁿ would do; the corners (2ⁿ, n ≤ 11) and the means.
    let corners = if n <= 12 { 1usize << n } else { 1 };
    for c in 0..=corners {
        let x: Vec<f64> = vars
            .iter()
            .enumerate()
            .map(|(i, v)| {
                if c == corners {
                    v.distribution.mean()
                } else {
                    v.distribution
                        .from_standard(if (c >> i) & 1 == 1 { z } else { -z })
                }
            })
            .collect();
        let t = ctx.vars.time_at(time, &x);
        let r = t.youngs_modulus.rate / t.youngs_modulus.initial;
        let lr = if r > 0.0 { r.ln() } else { f64::NEG_INFINITY };
        rho = [rho[0].min(lr), rho[1].max(lr)];
        let a = ctx.vars.age_scale(&x);
        s = [s[0].min(a), s[1].max(a)];
    }
    (rho, s)
}

/// The tables of the governing states `which` (indices into `plan.states`) that have a buckling
/// component with the time model uncertain, in parallel; each state's points are solved in
/// order on one shell, each Lanczos started from the previous mode.
///
/// # Errors
/// A state that cannot be built or a failed solve.
pub fn build_tables(
    ctx: &McContext<'_>,
    plan: &McPlan,
    which: std::ops::Range<usize>,
) -> Result<Vec<StateTable>, DesignError> {
    use rayon::prelude::*;
    let Some(time) = &ctx.time else {
        return Ok(Vec::new());
    };
    let zmax = match plan.method {
        McMethod::Importance => {
            Z_BOX
                + plan
                    .states
                    .iter()
                    .map(|s| s.beta)
                    .filter(|b| b.is_finite())
                    .fold(0.0, f64::max)
        }
        _ => Z_BOX,
    };
    let speed = ctx
        .model
        .variables()
        .iter()
        .any(|v| v.name == crate::input::uncertainty::SPEED);
    plan.states
        .get(which)
        .unwrap_or(&[])
        .par_iter()
        .filter_map(|s| {
            s.checks
                .iter()
                .find(|c| c.kind == CheckKind::BucklingTime)
                .map(|c| (s, c))
        })
        .map(|(s, c)| {
            let model = ctx.state_model(s)?;
            let Some(mut shell) =
                super::blf_sensitivity::TimeShell::new(ctx.cap, ctx.options, c.top)?
            else {
                return Err(uerr(format!("state {}: no shell to tabulate", s.index)));
            };
            let mut solves = 0;
            let mut solve = |t: &TimeModel, scale: f64| -> Result<f64, DesignError> {
                let (ages, _) = scaled_ages(ctx.schedule, c.top, scale);
                solves += 1;
                shell
                    .solve(&ages, &[], t, RESOLVE_TOLERANCE)?
                    .map(|(l, _)| l)
                    .ok_or_else(|| {
                        uerr(format!(
                            "state {}: no positive buckling factor at E₀ = {} Pa, Ė = {} Pa/s, \
                             print durations × {scale}",
                            s.index, t.youngs_modulus.initial, t.youngs_modulus.rate
                        ))
                    })
            };
            let shell0 = match c.check() {
                Check::BucklingTime {
                    shell0: Some(l), ..
                } => l,
                _ => solve(time, 1.0)?,
            };
            if !homogeneous(time) {
                return Ok(StateTable {
                    index: s.index,
                    rho: Vec::new(),
                    speed: Vec::new(),
                    nodes: [0, 0],
                    log_lambda: Vec::new(),
                    shell0,
                    exact: true,
                    solves,
                });
            }
            let (rho, sr) = ranges(ctx, &model, time, zmax);
            let nr = if rho[0] < rho[1] { RHO_NODES } else { 1 };
            let ns = if speed && sr[0] < sr[1] {
                SPEED_NODES
            } else {
                1
            };
            let (rn, _) = cheb(rho[0], rho[1], nr);
            let (sn, _) = cheb(sr[0], sr[1], ns);
            let e = time.youngs_modulus.initial;
            let mut log_lambda = Vec::with_capacity(nr * ns);
            for &lr in &rn {
                for &sc in &sn {
                    let mut t = time.clone();
                    t.youngs_modulus.rate = if lr.is_finite() { lr.exp() * e } else { 0.0 };
                    let scale = if ns > 1 { sc } else { 1.0 };
                    log_lambda.push((solve(&t, scale)? / e).ln());
                }
            }
            Ok(StateTable {
                index: s.index,
                rho: rho.to_vec(),
                speed: if ns > 1 { sr.to_vec() } else { Vec::new() },
                nodes: [nr, ns],
                log_lambda,
                shell0,
                exact: false,
                solves,
            })
        })
        .collect()
}

impl StateTable {
    /// λ at `time` (E₀, Ė) and print-duration factor `scale` from the table; None outside it.
    #[must_use]
    pub fn lambda(&self, time: &TimeModel, scale: f64) -> Option<f64> {
        if self.exact {
            return None;
        }
        let e = time.youngs_modulus.initial;
        let r = time.youngs_modulus.rate / e;
        let lr = if r > 0.0 { r.ln() } else { f64::NEG_INFINITY };
        let [lo, hi] = [*self.rho.first()?, *self.rho.get(1)?];
        let [nr, ns] = self.nodes;
        if !(lr >= lo && lr <= hi) {
            return None;
        }
        let cr = if nr > 1 {
            let (n, w) = cheb(lo, hi, nr);
            bary(&n, &w, lr)
        } else {
            vec![1.0]
        };
        let cs = if ns > 1 {
            let [a, b] = [*self.speed.first()?, *self.speed.get(1)?];
            if !(scale >= a && scale <= b) {
                return None;
            }
            let (n, w) = cheb(a, b, ns);
            bary(&n, &w, scale)
        } else {
            vec![1.0]
        };
        let mut v = 0.0;
        for (j, a) in cr.iter().enumerate() {
            for (k, b) in cs.iter().enumerate() {
                v += a * b * self.log_lambda.get(j * ns + k)?;
            }
        }
        Some(e * v.exp())
    }
}

/// A buckling component with the time model uncertain, λ from the state's table (a direct
/// re-solve, [`TimeBuckling`], outside it): g by [`time_buckling_g`], FORM's own formula.
struct TableBuckling<'a> {
    ctx: &'a McContext<'a>,
    table: &'a StateTable,
    check: Check,
    resolved: &'a AtomicU64,
    exact: Option<Box<TimeBuckling<'a>>>,
}

impl LimitState for TableBuckling<'_> {
    fn value(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        let Check::BucklingTime { blf, s_nu, top, .. } = self.check else {
            return Err("not a time-model buckling check".into());
        };
        let Some(time) = &self.ctx.time else {
            return Err("no time model".into());
        };
        let v = self.ctx.vars;
        let blf_min = self.ctx.cap.design.constraints.blf_min;
        let t = v.time_at(time, x);
        if let Some(l) = self.table.lambda(&t, v.age_scale(x)) {
            return Ok(time_buckling_g(
                (blf, s_nu),
                self.table.shell0,
                blf_min,
                v,
                x,
                (l, [0.0; 3]),
                &mut [],
            ));
        }
        self.resolved.fetch_add(1, Ordering::Relaxed);
        let ctx = self.ctx;
        let shell0 = self.table.shell0;
        let g = self.exact.get_or_insert_with(|| {
            Box::new(TimeBuckling::new(
                (ctx.cap, ctx.options, ctx.schedule),
                time.clone(),
                v,
                (blf, s_nu, top),
                blf_min,
                Some(shell0),
            ))
        });
        g.value(x)
    }
}

/// The components of one governing state: boxed limit states in its drifted model.
type StateComponents<'a> = (Model, Vec<Box<dyn LimitState + 'a>>);

/// Per governing state: its drifted model and its components (`fields`: the states' stress
/// fields for the strength layers).
fn components<'a>(
    ctx: &'a McContext<'a>,
    setup_tables: &'a [StateTable],
    plan: &'a McPlan,
    fields: &'a [Option<GreenField>],
    resolved: &'a AtomicU64,
    clamp: bool,
) -> Result<Vec<StateComponents<'a>>, DesignError> {
    let k = &ctx.cap.design.constraints;
    let limits = (k.sigma_min, k.sigma_max, k.blf_min);
    let v = ctx.vars;
    let mut out = Vec::with_capacity(plan.states.len());
    for (s, field) in plan.states.iter().zip(fields) {
        let model = ctx.state_model(s)?;
        let mut comps: Vec<Box<dyn LimitState + 'a>> = Vec::new();
        for c in &s.checks {
            let check = c.check();
            match check {
                Check::GreenLayers(_) => {
                    if let (Some(f), Some(time)) = (field, &ctx.time) {
                        comps.extend(f.components(v, time).into_iter().map(|(_, g)| g));
                    }
                }
                Check::BucklingTime { .. } => {
                    let Some(table) = setup_tables.iter().find(|t| t.index == s.index) else {
                        return Err(uerr(format!("state {}: no table shipped", s.index)));
                    };
                    comps.push(Box::new(TableBuckling {
                        ctx,
                        table,
                        check,
                        resolved,
                        exact: None,
                    }));
                }
                _ => comps.push(Box::new(Fallible(move |x: &[f64]| {
                    Ok(limit_state(check, v, limits, x, &mut []))
                }))),
            }
        }
        // The collapse component on its table: FORM's continuation outside the box for the
        // importance-sampling centres (`clamp`), a direct path there for a sample (counted).
        if s.collapse {
            let (Some(m), Some(t)) = (&ctx.collapse, &plan.collapse) else {
                return Err(uerr(format!(
                    "state {}: a collapse component without its table or the collapse check",
                    s.index
                )));
            };
            let index = s.index;
            comps.push(if clamp {
                Box::new(Fallible(move |x: &[f64]| t.g(m, index, x)))
            } else {
                Box::new(Fallible(move |x: &[f64]| {
                    t.sample_g(m, index, x, resolved)
                        .map_err(|e| EvalError::from(e.to_string()))
                }))
            });
        }
        out.push((model, comps));
    }
    Ok(out)
}

/// The governing states' stress fields for their strength layers (one static solve each).
fn fields(ctx: &McContext<'_>, plan: &McPlan) -> Result<Vec<Option<GreenField>>, DesignError> {
    use rayon::prelude::*;
    plan.states
        .par_iter()
        .map(|s| {
            if s.checks.iter().any(|c| c.kind == CheckKind::GreenLayers) {
                GreenField::solve(ctx.cap, ctx.options, ctx.schedule, s.index)
            } else {
                Ok(None)
            }
        })
        .collect()
}

/// The plan with its tables (all parts, any order) and the importance-sampling centres: FORM of
/// every component on the tables, the design points of those within [`CENTER_SHARE`] of the
/// largest P_f, weighted by their P_f.
///
/// # Errors
/// Tables that do not cover the plan's states, or a failed FORM.
pub fn setup(
    ctx: &McContext<'_>,
    plan: McPlan,
    mut tables: Vec<StateTable>,
    seconds: f64,
) -> Result<McSetup, DesignError> {
    let t0 = kappe_fe::clock::Instant::now();
    tables.sort_by_key(|t| t.index);
    let mut setup = McSetup {
        plan,
        tables,
        weights: Vec::new(),
        centers: Vec::new(),
        seconds,
    };
    if setup.plan.method == McMethod::Importance {
        let fields = fields(ctx, &setup.plan)?;
        let resolved = AtomicU64::new(0);
        let states = components(ctx, &setup.tables, &setup.plan, &fields, &resolved, true)?;
        let mut found: Vec<(f64, Vec<f64>)> = Vec::new();
        for (model, comps) in states {
            for mut g in comps {
                match form(&model, g.as_mut(), &FormOptions::default()) {
                    Ok(r) => found.push((r.pf, r.u_star)),
                    // As the run: a component beyond FAR_BETA adds nothing.
                    Err(kappe_reliability::Error::FormNotConverged { beta, .. })
                        if beta > FAR_BETA => {}
                    Err(e) => {
                        return Err(uerr(format!("importance-sampling centres: {e}")));
                    }
                }
            }
        }
        let top = found.iter().map(|f| f.0).fold(0.0, f64::max);
        found.retain(|f| f.0 >= CENTER_SHARE * top && f.0 > 0.0);
        if found.is_empty() {
            return Err(uerr(
                "importance sampling: no component has a design point (every FORM P_f is 0); \
                 use monte_carlo_method = \"crude\""
                    .into(),
            ));
        }
        let total: f64 = found.iter().map(|f| f.0).sum();
        setup.weights = found.iter().map(|f| f.0 / total).collect();
        setup.centers = found.into_iter().flat_map(|f| f.1).collect();
    }
    setup.seconds += t0.elapsed().as_secs_f64();
    Ok(setup)
}

/// A uniform number in (0, 1) from one 64-bit word (the reliability crate's sampler's: the top
/// 53 bits, + ½), and a standard normal number by its inverse transform: one word per number,
/// so a sample's position in its block's stream is fixed.
fn open01(rng: &mut ChaCha8Rng) -> f64 {
    ((rng.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

/// Batch `batch` of the samples: its blocks in parallel, each on its own stream
/// (`ChaCha8Rng::seed_from_u64(seed)`, stream = block index), summed in sample order.
///
/// # Errors
/// A bad batch, or a component that cannot be evaluated.
pub fn sample_batch(
    ctx: &McContext<'_>,
    setup: &McSetup,
    batch: Batch,
) -> Result<McBatch, DesignError> {
    use rayon::prelude::*;
    let t0 = kappe_fe::clock::Instant::now();
    let plan = &setup.plan;
    if batch.count == 0 || batch.index >= batch.count {
        return Err(uerr(format!(
            "batch {} of {}: allowed 0 ≤ index < count",
            batch.index, batch.count
        )));
    }
    if plan.samples < 2 {
        return Err(uerr("allowed: at least 2 samples".into()));
    }
    let n = ctx.model.len();
    if plan.method == McMethod::Importance
        && (setup.weights.is_empty() || setup.centers.len() != setup.weights.len() * n)
    {
        return Err(uerr(
            "importance sampling without its centres (run setup first)".into(),
        ));
    }
    let fields = fields(ctx, plan)?;
    let total = plan.samples.div_ceil(BLOCK);
    let (first, last) = (
        batch.index * total / batch.count,
        (batch.index + 1) * total / batch.count,
    );
    let blocks = (first..last)
        .into_par_iter()
        .map(|b| run_block(ctx, setup, &fields, b))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(McBatch {
        samples: plan.samples,
        seed: plan.seed,
        blocks,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

fn run_block(
    ctx: &McContext<'_>,
    setup: &McSetup,
    fields: &[Option<GreenField>],
    b: u64,
) -> Result<McBlock, DesignError> {
    let plan = &setup.plan;
    let resolved = AtomicU64::new(0);
    let mut states = components(ctx, &setup.tables, plan, fields, &resolved, false)?;
    let n = ctx.model.len();
    let mut rng = ChaCha8Rng::seed_from_u64(plan.seed);
    rng.set_stream(b);
    let count = BLOCK.min(plan.samples - b * BLOCK);
    let half: Vec<f64> = setup
        .centers
        .chunks(n.max(1))
        .map(|c| 0.5 * c.iter().map(|v| v * v).sum::<f64>())
        .collect();
    let mut sums = McBlock {
        block: b,
        samples: count,
        failures: 0,
        sum_w: 0.0,
        sum_w2: 0.0,
        resolved: 0,
    };
    let mut u = vec![0.0; n];
    for _ in 0..count {
        let mut w = 1.0;
        if plan.method == McMethod::Importance {
            // Pick a centre by its weight (one word), then u = c + y.
            let p = open01(&mut rng);
            let mut acc = 0.0;
            let mut pick = setup.weights.len() - 1;
            for (i, wi) in setup.weights.iter().enumerate() {
                acc += wi;
                if p < acc {
                    pick = i;
                    break;
                }
            }
            let c = setup.centers.chunks(n).nth(pick).unwrap_or(&[]);
            for (v, ci) in u.iter_mut().zip(c) {
                *v = kappe_reliability::stdnormal::inv_cdf(open01(&mut rng)) + ci;
            }
            // w = φ(u)/Σ_i p_i φ(u − c_i) = 1/Σ_i p_i exp(c_iᵀu − ½‖c_i‖²), by log-sum-exp.
            let e: Vec<f64> = setup
                .centers
                .chunks(n)
                .zip(&half)
                .map(|(c, h)| c.iter().zip(&u).map(|(a, b)| a * b).sum::<f64>() - h)
                .collect();
            let m = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let s: f64 = e
                .iter()
                .zip(&setup.weights)
                .map(|(x, p)| p * (x - m).exp())
                .sum();
            w = (-m).exp() / s;
        } else {
            for v in u.iter_mut() {
                *v = kappe_reliability::stdnormal::inv_cdf(open01(&mut rng));
            }
        }
        let mut fail = false;
        'states: for (model, comps) in states.iter_mut() {
            let x = model.x_from_u(&u);
            for g in comps.iter_mut() {
                let v = g
                    .value(&x)
                    .map_err(|e| uerr(format!("at x = {x:?}: {e}")))?;
                if v.is_nan() {
                    return Err(uerr(format!("limit state NaN at x = {x:?}")));
                }
                if v <= 0.0 {
                    fail = true;
                    break 'states;
                }
            }
        }
        if fail {
            sums.failures += 1;
            sums.sum_w += w;
            sums.sum_w2 += w * w;
        }
    }
    sums.resolved = resolved.load(Ordering::Relaxed);
    Ok(sums)
}

/// The batches of one run (any order) merged in block order: the estimate and its interval by
/// [`kappe_reliability::merge`] (Wilson for crude, the CLT interval for importance sampling).
///
/// # Errors
/// Batches of another run, missing or duplicate blocks.
pub fn merge(setup: &McSetup, batches: &[McBatch]) -> Result<DesignMonteCarlo, DesignError> {
    let plan = &setup.plan;
    if let Some(b) = batches
        .iter()
        .find(|b| b.samples != plan.samples || b.seed != plan.seed)
    {
        return Err(uerr(format!(
            "a batch of another run ({} samples, seed {}; the run: {}, {})",
            b.samples, b.seed, plan.samples, plan.seed
        )));
    }
    let method = match plan.method {
        McMethod::Importance => SamplingMethod::ImportanceSampling { center: Vec::new() },
        _ => SamplingMethod::MonteCarlo,
    };
    let options = SamplingOptions {
        samples: plan.samples,
        seed: plan.seed,
        block_size: BLOCK,
    };
    let as_batches: Vec<SamplingBatch> = batches
        .iter()
        .map(|b| SamplingBatch {
            method: method.clone(),
            options: options.clone(),
            blocks: b
                .blocks
                .iter()
                .map(|k| kappe_reliability::sampling::BlockSums {
                    block: k.block,
                    samples: k.samples,
                    failures: k.failures,
                    sum_w: k.sum_w,
                    sum_w2: k.sum_w2,
                })
                .collect(),
        })
        .collect();
    let r = kappe_reliability::merge(&as_batches).map_err(|e| uerr(e.to_string()))?;
    let seconds = setup.seconds + batches.iter().map(|b| b.seconds).sum::<f64>();
    Ok(DesignMonteCarlo {
        method: plan.method,
        samples: r.samples,
        seed: plan.seed,
        pf: r.pf,
        beta: r.beta,
        pf_interval: r.interval,
        cov: r.cov,
        failures: r.failures,
        form_pf: plan.form_pf,
        form_in_interval: plan.form_pf >= r.interval[0] && plan.form_pf <= r.interval[1],
        sorm_pf: plan.sorm_pf,
        sorm_in_interval: plan
            .sorm_pf
            .map(|p| p >= r.interval[0] && p <= r.interval[1]),
        states: plan.states.iter().map(|s| s.index).collect(),
        excluded_share: plan.excluded_share,
        tables: setup.tables.iter().filter(|t| !t.exact).count(),
        table_solves: setup.tables.iter().map(|t| t.solves).sum(),
        resolved_samples: batches
            .iter()
            .flat_map(|b| &b.blocks)
            .map(|k| k.resolved)
            .sum(),
        centers: setup.weights.len(),
        seconds,
    })
}

/// The design's Monte Carlo in one process (`[uncertainty] monte_carlo = N`; None without it):
/// plan, tables, centres, one batch, merge.
///
/// # Errors
/// As the steps.
pub fn design_monte_carlo(
    cap: &Cap,
    analysis: &Analysis,
    schedule: &Schedule,
    r: &Reliability,
) -> Result<Option<DesignMonteCarlo>, DesignError> {
    let Some(table) = &cap.design.uncertainty else {
        return Ok(None);
    };
    let Some(samples) = table.monte_carlo else {
        return Ok(None);
    };
    let t0 = kappe_fe::clock::Instant::now();
    let ctx = McContext::new(cap, &analysis.options, schedule)?;
    let plan = plan(
        &ctx,
        analysis,
        r,
        samples,
        table.seed.unwrap_or(0),
        table.monte_carlo_method.unwrap_or_default(),
    )?;
    let tables = build_tables(&ctx, &plan, 0..plan.states.len())?;
    let setup = setup(&ctx, plan, tables, t0.elapsed().as_secs_f64())?;
    let batch = sample_batch(&ctx, &setup, Batch { index: 0, count: 1 })?;
    merge(&setup, &[batch]).map(Some)
}

/// Numbers as their bit patterns (JSON has no NaN, and the bits round-trip exactly); the
/// design's and the buildability objects' shipped tables both use it.
pub(crate) mod bits {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|x| x.to_bits()))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<u64>::deserialize(d)?
            .into_iter()
            .map(f64::from_bits)
            .collect())
    }

    /// One number.
    pub mod one {
        use serde::{Deserialize, Deserializer, Serializer};

        pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
            s.serialize_u64(v.to_bits())
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
            Ok(f64::from_bits(u64::deserialize(d)?))
        }
    }

    /// The same for `Option<Vec<f64>>`.
    pub mod option {
        use serde::{Deserialize, Deserializer, Serializer};

        pub fn serialize<S: Serializer>(v: &Option<Vec<f64>>, s: S) -> Result<S::Ok, S::Error> {
            match v {
                Some(v) => s.serialize_some(&v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()),
                None => s.serialize_none(),
            }
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<f64>>, D::Error> {
            Ok(Option::<Vec<u64>>::deserialize(d)?
                .map(|v| v.into_iter().map(f64::from_bits).collect()))
        }
    }
}
