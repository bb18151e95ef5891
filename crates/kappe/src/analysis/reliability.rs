//! Reliability of every analysed print state and of the print (issue 24): β and P_f of each
//! check under the design's `[uncertainty]`, by FORM ([`kappe_reliability::form`]), and the
//! print's P_f as a series system over states × checks ([`kappe_reliability::series_system`]).
//!
//! Limit states of state q (failure g ≤ 0), with γ the specific weight, E the uniform Young's
//! modulus, ν Poisson's ratio and a 0-subscript the design's (analysed) value:
//!
//! * buckling: g = BLF₀·(E/E₀)·(γ₀/γ)·(1 + s_ν(ν − ν₀)) − BLF_min;
//! * compression: g = σ_min,q,₀·γ/γ₀ − σ_min; tension: g = σ_max − σ_max,q,₀·γ/γ₀;
//! * strength (with a strength model): g = 1 − u₀·γ/γ₀.
//!
//! The γ and E factors are exact, not linearisations: the CEM force pass and the shell's static
//! solve are linear in the self-weight load, so every stress (and the Mohr–Coulomb demand, which is
//! homogeneous of degree 1 in the stresses) scales with γ; the element stresses of the statically
//! determinate force pass do not depend on E; and with one uniform modulus the shell's stiffness
//! K is linear in E while its geometric stiffness K_G is linear in the load, so the eigenvalue of
//! (K + λK_G)φ = 0 scales as E/γ. The ν term is not exact: s_ν = (∂BLF/∂ν)/BLF₀ is a central
//! difference of two re-solves at ν₀ ± [`NU_STEP`] per state (first order in ν; ν's coefficient of
//! variation is small, and the re-solve test bounds the error).
//!
//! A check that no random variable enters (e.g. stresses when only E is uncertain) is
//! deterministic: the deterministic verdict already holds it, and it is left out here.
//!
//! Drift: the state printed at t (h, the end of its top layer on the run's schedule) uses the
//! variables scaled by each drift's factor c(t) ([`kappe_reliability::Model::drifted`]); all states
//! share one u-space, which the series system needs.
//!
//! # Screening
//!
//! A buckling component with the time model uncertain ([`TimeBuckling`]) costs a re-solve of the
//! state's shell per FORM iterate. Every such state first gets the one solve FORM starts with, at
//! the drifted means, and from it ([`first_order`]) the first-order β₁ of G = ln(BLF/BLF_min)
//! (exact for a product of powers of lognormals, which λ nearly is). The state with the least
//! β₁ is solved by FORM; the largest component P_f it gives, P_b, bounds the print's P_f from
//! below (a series system fails at least as often as its weakest component). A state whose
//! N·Φ(−(β₁ − δ)) < [`SCREEN_SHARE`]·P_b (N the states with such a component) keeps its
//! first-order result as its buckling component, flagged `beta_first_order`: with
//! |β_FORM − β₁| ≤ δ, each such state's P_f is below SCREEN_SHARE·P_b/N, so all of them together
//! hold less than SCREEN_SHARE of the print's P_f, and none can govern. δ = [`screen_delta`]:
//! the largest |β_FORM − β₁|/max(1, β₁) measured over every state of two caps, times a safety
//! factor, times max(1, β₁). The other
//! states run FORM from the cached solve. `[uncertainty] screening = false` runs FORM on all.
//!
//! # The 1-D reduction
//!
//! With the moduli E₀ + Ė·h(a_k) at fixed ages, λ = E₀·Λ(Ė/E₀), so FORM of a [`TimeBuckling`]
//! component runs on a model of g with ln Λ(ln(Ė/E₀)) replaced by a Hermite cubic through the
//! last two re-solves, and the shell is re-solved only at the design points the model proposes,
//! until one meets FORM's own tolerances with the true g and gradient ([`time_buckling_form`];
//! docs/reliability.md, "The 1-D reduction").
//!
//! # SORM
//!
//! Every component also gets its second-order P_f at FORM's design point
//! ([`kappe_reliability::sorm`]: principal curvatures, Hohenbichler–Rackwitz), [`ComponentSorm`]:
//! the closed-form components (γ, E, ν scalings; stresses; strength and sliding layers) with
//! the Hessian by central differences in u (they cost microseconds); the time buckling
//! components through the 1-D reduction, whose Hermite cubic of ln Λ gives L″ at the design
//! point without another eigensolve ([`time_buckling_sorm`]). Where SORM does not apply the
//! component keeps FORM's P_f and says why (`ComponentSorm::form_only`, counted in
//! [`SormSystem::form_only`]): a screened component (no design point), a time buckling
//! component outside the reduction (a Hessian would cost 2n re-solves), 1 + ψκ ≤ 0, a failed
//! evaluation. The state's and the print's series systems are re-run with each component's
//! equivalent β = −Φ⁻¹(P_f,SORM) and FORM's α (the same sampler and seed), giving
//! `beta_sorm`/`pf_sorm` per state and [`Reliability::sorm`]; the `beta_min` verdict and
//! `kappe schedule`'s β target judge SORM's β ([`Reliability::verdict`]).

use std::collections::BTreeMap;

use kappe_reliability::{
    Component, Drift, FormOptions, FormResult, Model, SormOptions, SormResult, SystemOptions,
    WithGradient, form, series_system,
};
use serde::{Deserialize, Serialize};

use super::buckling::{state_buckling, state_material};
use super::check::Analysis;
use crate::form::cap::Cap;
use crate::input::error::DesignError;
use crate::input::material::{Strength, TimeModel};
use crate::input::uncertainty::BETA_MIN_DEFAULT;

/// Absolute step in ν of the central difference ∂BLF/∂ν: small against ν's range (0, 0.5) and its
/// scatter, large against the eigensolver's relative residual (1e-8) times BLF/h.
pub const NU_STEP: f64 = 1e-3;

/// β beyond which a component that FORM cannot converge is left out of a state (P_f < 1e-15).
pub const FAR_BETA: f64 = 8.0;

/// Samples of each state's own series system (its few checks).
const STATE_SYSTEM_SAMPLES: u64 = 4_000;

/// δ(β₁) of the screening rule, the allowance on the first-order β₁ of a state's buckling
/// component: [`SCREEN_SAFETY`] × [`SCREEN_DELTA_RATIO`] × max(1, β₁). The error of β₁ is the
/// curvature of ln λ over the distance to the design point, so it grows with β₁ (measured
/// 0.8–3.7 % of β over both caps); a constant δ sized at the largest β₁ measured was loose
/// where the rule decides (β₁ ≈ 6–9 on the default cap).
pub fn screen_delta(beta1: f64) -> f64 {
    SCREEN_SAFETY * SCREEN_DELTA_RATIO * beta1.max(1.0)
}

/// The largest |β_FORM − β₁|/max(1, β₁) measured over every analysed state of the default cap
/// (0.0401, state 8, β₁ 17.83) and study No. 14's cap (0.0261) with the time parameters
/// uncertain (`form_cost -- 0 13 delta`, docs/reliability.md, "Screening"), rounded up;
/// β₁ < β_FORM at every one of the 155 states.
pub const SCREEN_DELTA_RATIO: f64 = 0.0402;

/// Safety factor on the measured δ: the measured caps span E₀ cov 0.15–0.2, Ė cov 0.3; a design
/// with larger scatter bends ln λ more, and the factor covers that until it is measured.
pub const SCREEN_SAFETY: f64 = 2.0;

/// A state's buckling component is screened (first order, no FORM) when N·Φ(−(β₁ − δ)) is below
/// this share of the print's P_f bound (the largest component P_f solved so far): all screened
/// components together then hold less than this share of the print's P_f.
pub const SCREEN_SHARE: f64 = 1e-3;

/// The reliability of one state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct StateReliability {
    /// State index.
    pub index: usize,
    /// Print time of the state, h (drift is evaluated here).
    pub t_hours: f64,
    /// β of the state's checks as a series system.
    pub beta: f64,
    /// P_f of the state.
    pub pf: f64,
    /// β per check (`buckling`, `sigma_min`, `sigma_max`, `strength`).
    pub beta_by_check: BTreeMap<String, f64>,
    /// The state's buckling β is the first-order β₁ of ln(BLF/BLF_min) at the drifted means,
    /// not FORM's: the screening rule showed that it cannot move the print's P_f by more than
    /// [`SCREEN_SHARE`] of it (module docs, "Screening"). Absent when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub beta_first_order: bool,
    /// β of the state's series system with every component's SORM P_f (its equivalent
    /// β = −Φ⁻¹(P_f,SORM), FORM's α): module docs, "SORM". Absent where the state has no
    /// component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta_sorm: Option<f64>,
    /// P_f of that system.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pf_sorm: Option<f64>,
}

/// SORM of one component (module docs, "SORM"): its P_f by Hohenbichler–Rackwitz at FORM's
/// design point, or FORM's own P_f where SORM does not apply, with the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct ComponentSorm {
    /// P_f,SORM (FORM's where `form_only`).
    pub pf: f64,
    /// The equivalent β = −Φ⁻¹(P_f,SORM) (FORM's β where that is not finite: P_f underflows).
    pub beta: f64,
    /// Why the component keeps FORM's P_f (None: SORM's): [`FORM_ONLY_FIRST_ORDER`],
    /// [`FORM_ONLY_NO_HESSIAN`], [`FORM_ONLY_CURVATURE`], [`FORM_ONLY_FAILED`].
    pub form_only: Option<&'static str>,
    /// Seconds SORM took for this component (its Hessian and curvatures).
    pub seconds: f64,
}

/// A screened component (first-order β₁ at the means, no design point to take curvatures at):
/// its share of the print's P_f is below [`SCREEN_SHARE`] anyway.
pub const FORM_ONLY_FIRST_ORDER: &str = "first_order";
/// A time buckling component outside the 1-D reduction (the print speed uncertain, a modulus
/// cap, Ė ≤ 0) or whose reduction has no two distinct re-solves: no Hessian without 2n extra
/// re-solves, which SORM's budget does not take.
pub const FORM_ONLY_NO_HESSIAN: &str = "no_hessian";
/// A principal curvature with 1 + ψ(β)κ ≤ 0 (the formula does not hold).
pub const FORM_ONLY_CURVATURE: &str = "curvature";
/// The limit state failed at a point of SORM's differences.
pub const FORM_ONLY_FAILED: &str = "failed";

impl ComponentSorm {
    /// FORM's P_f, for `why`.
    pub fn form_only(r: &FormResult, why: &'static str) -> Self {
        ComponentSorm {
            pf: r.pf,
            beta: r.beta,
            form_only: Some(why),
            seconds: 0.0,
        }
    }

    /// From [`kappe_reliability::sorm`]'s answer at `r`'s design point.
    pub fn of(s: Result<SormResult, kappe_reliability::Error>, r: &FormResult) -> Self {
        match s {
            Ok(s) => ComponentSorm {
                pf: s.pf,
                beta: if s.beta.is_finite() { s.beta } else { r.beta },
                form_only: None,
                seconds: 0.0,
            },
            Err(kappe_reliability::Error::SormCurvature { .. }) => {
                Self::form_only(r, FORM_ONLY_CURVATURE)
            }
            Err(_) => Self::form_only(r, FORM_ONLY_FAILED),
        }
    }

    /// [`Self::of`] with the seconds since `t0`.
    fn timed(
        s: Result<SormResult, kappe_reliability::Error>,
        r: &FormResult,
        t0: kappe_fe::clock::Instant,
    ) -> Self {
        ComponentSorm {
            seconds: t0.elapsed().as_secs_f64(),
            ..Self::of(s, r)
        }
    }

    /// The component of the SORM series system: FORM's α with the equivalent β.
    fn component(&self, r: &FormResult) -> Component {
        Component {
            beta: self.beta,
            alpha: r.alpha.clone(),
        }
    }
}

/// The print's series system with every component's SORM P_f (module docs, "SORM").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SormSystem {
    /// β of the print: −Φ⁻¹(P_f). The `beta_min` verdict uses it.
    pub beta: f64,
    /// P_f of the print.
    pub pf: f64,
    /// 95 % interval of the series system's sampled P_f.
    pub pf_interval: [f64; 2],
    /// State of the governing component (largest SORM P_f).
    pub governing_state: usize,
    /// Check of the governing component.
    pub governing_check: String,
    /// Components that keep FORM's P_f, by reason (`first_order`: screened; `no_hessian`: a
    /// time buckling component outside the 1-D reduction; `curvature`: 1 + ψκ ≤ 0; `failed`:
    /// an evaluation failed). Absent when every component has its SORM P_f.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub form_only: BTreeMap<String, usize>,
    /// Seconds SORM added, summed over the components (on whichever thread each ran) and the
    /// print's second series system; the states' second systems (4 000 samples of a few
    /// components each) are not counted.
    pub seconds: f64,
}

/// One parameter's share in the governing check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Sensitivity {
    /// Importance factor γᵢ² (sums to 1 over the parameters).
    pub importance: f64,
    /// ∂β/∂μᵢ, per unit of the parameter.
    pub dbeta_dmean: f64,
    /// ∂β/∂σᵢ, per unit of the parameter.
    pub dbeta_dstd: f64,
}

/// The reliability of the print.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Reliability {
    /// β of the print (series system over states × checks).
    pub beta: f64,
    /// P_f of the print.
    pub pf: f64,
    /// 95 % interval of the sampled P_f.
    pub pf_interval: [f64; 2],
    /// The target β_min.
    pub beta_min: f64,
    /// State and check of the governing component (largest P_f).
    pub governing_state: usize,
    /// Check name of the governing component.
    pub governing_check: String,
    /// Most probable failing values of each parameter (governing component).
    pub design_point: BTreeMap<String, f64>,
    /// Sensitivities of the governing component's β.
    pub sensitivities: BTreeMap<String, Sensitivity>,
    /// Every state checked (in `summary.json` per state, not here).
    #[serde(skip)]
    pub states: Vec<StateReliability>,
    /// Components in the series system.
    pub components: usize,
    /// Wall-clock seconds of the reliability analysis (re-solves included).
    pub seconds: f64,
    /// The Monte Carlo of the print's governing states (`[uncertainty] monte_carlo`; absent
    /// without it): `crate::analysis::design_monte_carlo`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<super::design_monte_carlo::DesignMonteCarlo>,
    /// The same series system with every component's SORM P_f (module docs, "SORM"); the
    /// `beta_min` verdict uses its β ([`Reliability::verdict`]). FORM's numbers above stay.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sorm: Option<SormSystem>,
    /// The collapse limit state of the states (`[analysis.nonlinear]` with `[uncertainty]`):
    /// its tables and every state's design point against a direct path
    /// (`crate::analysis::collapse_reliability`). Absent without the collapse check.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collapse: Option<super::collapse_reliability::CapCollapseReliability>,
    /// The collapse tables themselves, for the design's Monte Carlo (not in the outputs).
    #[serde(skip)]
    #[schemars(skip)]
    pub collapse_tables: Option<super::collapse_reliability::CapCollapseTables>,
}

impl Reliability {
    /// The β the `beta_min` verdict judges, with its governing state and check: SORM's (the
    /// better estimate of the print's P_f: it takes the limit states' curvature at the design
    /// points, which FORM leaves out) where there is one, else FORM's.
    pub fn verdict(&self) -> (f64, usize, &str) {
        match &self.sorm {
            Some(s) => (s.beta, s.governing_state, &s.governing_check),
            None => (self.beta, self.governing_state, &self.governing_check),
        }
    }
}

/// What a check of one state depends on; see the module docs.
#[derive(Debug, Clone, Copy)]
pub enum Check {
    /// BLF₀ and s_ν.
    Buckling {
        /// BLF at the design's values.
        blf: f64,
        /// (∂BLF/∂ν)/BLF₀.
        s_nu: f64,
    },
    /// σ_min,q,₀ (≤ 0).
    Compression(f64),
    /// σ_max,q,₀ (≥ 0).
    Tension(f64),
    /// u₀.
    Strength(f64),
    /// Strength and bed-joint sliding of the state layer by layer, when a strength parameter or
    /// the print speed is uncertain: one component per layer and check ([`GreenField`]); the
    /// state's stresses from one static solve of its shell, u₀ the deterministic utilisation.
    GreenLayers(f64),
    /// Buckling with the time model's E₀ and/or Ė (or the print speed) uncertain: BLF₀, s_ν
    /// and the state's top print index; g from re-solves of the state's shell
    /// ([`TimeBuckling`]).
    BucklingTime {
        /// BLF at the design's values.
        blf: f64,
        /// (∂BLF/∂ν)/BLF₀.
        s_nu: f64,
        /// Top print index of the state.
        top: usize,
        /// λ of the state's shell (the re-solves' mesh) at the design's values when the
        /// deterministic analysis already solved it (its print-layer mesh factor, `blf_mesh`):
        /// the ratio's denominator without a re-solve.
        shell0: Option<f64>,
    },
}

impl Check {
    fn name(self) -> &'static str {
        match self {
            Check::Buckling { .. } | Check::BucklingTime { .. } => "buckling",
            Check::Compression(_) => "sigma_min",
            Check::Tension(_) => "sigma_max",
            Check::Strength(_) | Check::GreenLayers(_) => "strength",
        }
    }
}

/// Indices of γ, E, ν in the model, and their analysed values.
#[derive(Debug, Clone, Copy)]
pub struct Vars {
    pub(crate) gamma: Option<usize>,
    pub(crate) e: Option<usize>,
    pub(crate) nu: Option<usize>,
    pub(crate) gamma0: f64,
    pub(crate) e0: f64,
    pub(crate) nu0: f64,
    /// The time model's E₀ and Ė (`material.time.*`).
    pub(crate) e0t: Option<usize>,
    pub(crate) rate: Option<usize>,
    /// The time model's strength at age 0 (f₀ or c₀), its rate and the friction angle (°).
    pub(crate) f0: Option<usize>,
    pub(crate) frate: Option<usize>,
    pub(crate) phi: Option<usize>,
    /// The print speed and its nominal value.
    pub(crate) speed: Option<usize>,
    pub(crate) speed0: f64,
}

impl Vars {
    /// Whether a parameter of the layers' moduli is uncertain: the time model's E₀ or Ė, or
    /// the print speed (it moves every layer's age).
    pub fn has_time(&self) -> bool {
        self.e0t.is_some() || self.rate.is_some() || self.speed.is_some()
    }

    /// Whether a parameter of the layers' capacities is uncertain: a strength parameter or the
    /// print speed.
    pub fn has_capacity(&self) -> bool {
        self.f0.is_some() || self.frate.is_some() || self.phi.is_some() || self.speed.is_some()
    }

    /// The factor s = v₀/v on every layer's print duration at the point `x`.
    pub fn age_scale(&self, x: &[f64]) -> f64 {
        self.speed
            .and_then(|i| x.get(i))
            .map_or(1.0, |v| self.speed0 / v)
    }

    /// `time` with the time-model parameters of the point `x` (E₀, Ė, the strength at age 0,
    /// its rate, φ; the others as given).
    pub fn time_at(&self, time: &TimeModel, x: &[f64]) -> TimeModel {
        let at = |i: Option<usize>| i.and_then(|i| x.get(i).copied());
        let mut t = time.clone();
        if let Some(e) = at(self.e0t) {
            t.youngs_modulus.initial = e;
        }
        if let Some(r) = at(self.rate) {
            t.youngs_modulus.rate = r;
        }
        match &mut t.strength {
            Some(Strength::Uniaxial {
                compressive_strength: p,
                friction_angle_deg,
            }) => {
                p.initial = at(self.f0).unwrap_or(p.initial);
                p.rate = at(self.frate).unwrap_or(p.rate);
                *friction_angle_deg = at(self.phi).unwrap_or(*friction_angle_deg);
            }
            Some(Strength::MohrCoulomb {
                cohesion: p,
                friction_angle_deg,
            }) => {
                p.initial = at(self.f0).unwrap_or(p.initial);
                p.rate = at(self.frate).unwrap_or(p.rate);
                friction_angle_deg.initial = at(self.phi).unwrap_or(friction_angle_deg.initial);
            }
            None => {}
        }
        t
    }
}

impl Vars {
    /// Where γ, E and ν sit in `model`, and their nominal values from the cap's design.
    pub fn of(model: &Model, cap: &Cap) -> Self {
        let find = |n: &str| model.variables().iter().position(|v| v.name == n);
        let m = &cap.design.material;
        Vars {
            gamma: find("material.specific_weight"),
            e: find("material.youngs_modulus"),
            nu: find("material.poisson_ratio"),
            gamma0: m.specific_weight,
            e0: m.youngs_modulus,
            nu0: m.poisson_ratio,
            e0t: find("material.time.youngs_modulus"),
            rate: find("material.time.youngs_modulus_rate"),
            f0: find("material.time.compressive_strength").or(find("material.time.cohesion")),
            frate: find("material.time.compressive_strength_rate")
                .or(find("material.time.cohesion_rate")),
            phi: find("material.time.friction_angle_deg"),
            speed: find(crate::input::uncertainty::SPEED),
            speed0: cap.design.print.print_speed,
        }
    }
}

/// g(x) of `check` and its gradient (exact: every factor is a product of powers).
pub fn limit_state(
    check: Check,
    v: Vars,
    limits: (f64, f64, f64),
    x: &[f64],
    grad: &mut [f64],
) -> f64 {
    let (sigma_min, sigma_max, blf_min) = limits;
    grad.iter_mut().for_each(|g| *g = 0.0);
    let at = |i: Option<usize>, nominal: f64| i.and_then(|i| x.get(i).copied()).unwrap_or(nominal);
    let gamma = at(v.gamma, v.gamma0);
    let rg = gamma / v.gamma0;
    let mut set = |i: Option<usize>, d: f64| {
        if let Some(g) = i.and_then(|i| grad.get_mut(i)) {
            *g = d;
        }
    };
    match check {
        Check::Buckling { blf, s_nu } => {
            let e = at(v.e, v.e0);
            let nu = at(v.nu, v.nu0);
            let lin = 1.0 + s_nu * (nu - v.nu0);
            let val = blf * (e / v.e0) / rg * lin;
            set(v.e, val / e);
            set(v.gamma, -val / gamma);
            set(v.nu, blf * (e / v.e0) / rg * s_nu);
            val - blf_min
        }
        Check::Compression(s) => {
            set(v.gamma, s / v.gamma0);
            s * rg - sigma_min
        }
        Check::Tension(s) => {
            set(v.gamma, -s / v.gamma0);
            sigma_max - s * rg
        }
        // The layer components need the state's stresses ([`GreenField`]); here the
        // nominal-capacity value, which keeps this pure function total.
        Check::Strength(u) | Check::GreenLayers(u) => {
            set(v.gamma, -u / v.gamma0);
            1.0 - u * rg
        }
        // Needs re-solves: [`TimeBuckling`]. Here the nominal-stiffness value, which keeps this
        // pure function total.
        Check::BucklingTime { blf, s_nu, .. } => {
            let nu = at(v.nu, v.nu0);
            let lin = 1.0 + s_nu * (nu - v.nu0);
            let val = blf / rg * lin;
            set(v.gamma, -val / gamma);
            set(v.nu, blf / rg * s_nu);
            val - blf_min
        }
    }
}

/// The buckling limit state of one state when the time model's E₀ and/or Ė are uncertain:
/// g = BLF₀·(λ(E₀, Ė)/λ(E₀⁰, Ė⁰))·(γ₀/γ)·(1 + s_ν(ν − ν₀)) − BLF_min, with λ the lowest factor of
/// a re-solve of the state's shell at the trial E₀, Ė (their moduli change non-uniformly with
/// the layers' ages, so no scaling is exact) and ∂λ/∂E₀, ∂λ/∂Ė from the eigenvalue sensitivity
/// ([`crate::analysis::blf_sensitivity`]). The ratio keeps g equal to the deterministic verdict's
/// BLF₀ at the nominal values even when that BLF is the mesh-converged estimate.
pub struct TimeBuckling<'a> {
    /// The cap.
    pub cap: &'a Cap,
    /// The analysis options (the shell the analysis builds).
    pub options: &'a super::AnalysisOptions,
    /// The run's schedule (the layers' ages).
    pub schedule: &'a crate::schedule::Schedule,
    /// The design's time model (E₀, Ė replaced per trial point).
    pub time: crate::input::material::TimeModel,
    /// Where the variables sit.
    pub vars: Vars,
    /// BLF₀, s_ν and the top print index.
    pub check: (f64, f64, usize),
    /// BLF_min.
    pub blf_min: f64,
    /// λ of the shell at the nominal E₀, Ė (computed on first use).
    pub shell0: Option<f64>,
    /// The last point evaluated, its g and ∂g/∂x: FORM asks for g at a line-search trial point
    /// and then for g and its gradient at the same point once it is accepted; one re-solve
    /// (eigensolve and sensitivity solves) serves both, and the numbers are the same.
    pub last: Option<(Vec<f64>, f64, Vec<f64>)>,
    /// The state's shell and solver, built on first use and kept for every iterate (see
    /// [`crate::analysis::blf_sensitivity::TimeShell`]).
    pub shell: Option<crate::analysis::blf_sensitivity::TimeShell>,
    /// Every re-solve so far: E₀, Ė, λ and ∂λ/∂Ė (the data of the 1-D model of
    /// [`time_buckling_form`]).
    pub solves: Vec<[f64; 4]>,
}

impl<'a> TimeBuckling<'a> {
    /// A state's limit state before its first solve: `run` is the cap, the analysis options and
    /// the schedule; `check` is the state's (BLF₀, s_ν, top layer) and `shell0` its print-layer
    /// factor. The one place that knows the fields kept between re-solves start empty.
    pub fn new(
        run: (
            &'a Cap,
            &'a super::AnalysisOptions,
            &'a crate::schedule::Schedule,
        ),
        time: crate::input::material::TimeModel,
        vars: Vars,
        check: (f64, f64, usize),
        blf_min: f64,
        shell0: Option<f64>,
    ) -> Self {
        let (cap, options, schedule) = run;
        TimeBuckling {
            cap,
            options,
            schedule,
            time,
            vars,
            check,
            blf_min,
            shell0,
            last: None,
            shell: None,
            solves: Vec::new(),
        }
    }
}

/// Lanczos relative residual of the re-solves: the eigenvalue error is of the order of its
/// square (symmetric pencil), far below FORM's tolerance on g (1e-6 relative).
pub const RESOLVE_TOLERANCE: f64 = 1e-8;

impl TimeBuckling<'_> {
    /// λ and (∂λ/∂E₀, ∂λ/∂Ė, ∂λ/∂s) at the point `x` (nominal values where None), s = v₀/v
    /// the factor on every print duration.
    fn solve(
        &mut self,
        x: Option<&[f64]>,
    ) -> Result<(f64, [f64; 3]), kappe_reliability::EvalError> {
        let top = self.check.2;
        let (time, scale) = match x {
            Some(x) => (self.vars.time_at(&self.time, x), self.vars.age_scale(x)),
            None => (self.time.clone(), 1.0),
        };
        let (ages, print) = scaled_ages(self.schedule, top, scale);
        let dages = if self.vars.speed.is_some() {
            print
        } else {
            Vec::new()
        };
        if self.shell.is_none() {
            self.shell =
                crate::analysis::blf_sensitivity::TimeShell::new(self.cap, self.options, top)?;
        }
        let solved = match &mut self.shell {
            Some(shell) => shell.solve(&ages, &dages, &time, RESOLVE_TOLERANCE)?,
            None => None,
        };
        if let Some((l, dl)) = solved {
            self.solves.push([
                time.youngs_modulus.initial,
                time.youngs_modulus.rate,
                l,
                dl[1],
            ]);
        }
        solved.ok_or_else(|| {
            format!(
                "state {top}: no positive buckling factor at E₀ = {} Pa, Ė = {} Pa/s, print \
                 durations × {scale}",
                time.youngs_modulus.initial, time.youngs_modulus.rate
            )
            .into()
        })
    }

    fn eval(&mut self, x: &[f64], grad: &mut [f64]) -> Result<f64, kappe_reliability::EvalError> {
        let v = self.vars;
        let shell0 = match self.shell0 {
            Some(l) => l,
            None => {
                let l = self.solve(None)?.0;
                self.shell0 = Some(l);
                l
            }
        };
        let solved = self.solve(Some(x))?;
        Ok(time_buckling_g(
            (self.check.0, self.check.1),
            shell0,
            self.blf_min,
            v,
            x,
            solved,
            grad,
        ))
    }
}

/// g of [`TimeBuckling`] at `x` from λ and (∂λ/∂E₀, ∂λ/∂Ė, ∂λ/∂s) at `x` (a re-solve, or the
/// design Monte Carlo's table, `crate::analysis::design_monte_carlo`), BLF₀ and s_ν in `check`,
/// λ at the design's values `shell0`; `grad` (any length, empty for none) gets ∂g/∂x.
pub fn time_buckling_g(
    (blf, s_nu): (f64, f64),
    shell0: f64,
    blf_min: f64,
    v: Vars,
    x: &[f64],
    (l, dl): (f64, [f64; 3]),
    grad: &mut [f64],
) -> f64 {
    let at = |i: Option<usize>, nominal: f64| i.and_then(|i| x.get(i).copied()).unwrap_or(nominal);
    let gamma = at(v.gamma, v.gamma0);
    let rg = gamma / v.gamma0;
    let nu = at(v.nu, v.nu0);
    let lin = 1.0 + s_nu * (nu - v.nu0);
    let k = blf / shell0;
    let val = k * l / rg * lin;
    grad.iter_mut().for_each(|g| *g = 0.0);
    let mut set = |i: Option<usize>, d: f64| {
        if let Some(g) = i.and_then(|i| grad.get_mut(i)) {
            *g = d;
        }
    };
    set(v.e0t, k * dl[0] / rg * lin);
    set(v.rate, k * dl[1] / rg * lin);
    // s = v₀/v: ∂s/∂v = −s/v.
    let speed = at(v.speed, v.speed0);
    set(v.speed, -k * dl[2] * (v.speed0 / speed) / speed / rg * lin);
    set(v.gamma, -val / gamma);
    set(v.nu, k * l / rg * s_nu);
    val - blf_min
}

/// The ages of layers 0..=`top` at the state with top print index `top` when every print
/// duration is scaled by `scale` (the pauses kept), and their derivative with respect to
/// `scale`, the print time D_k after layer k: a_k(s) = a_k + (s − 1)·D_k, exactly the nominal
/// ages at s = 1.
pub fn scaled_ages(
    schedule: &crate::schedule::Schedule,
    top: usize,
    scale: f64,
) -> (Vec<f64>, Vec<f64>) {
    let nominal = schedule.ages(top + 1);
    let mut print = vec![0.0; nominal.len()];
    let mut d = 0.0;
    for k in (0..nominal.len()).rev() {
        print[k] = d;
        d += schedule.layers.get(k).map_or(0.0, |l| l.end_s - l.start_s);
    }
    let ages = if scale == 1.0 {
        nominal
    } else {
        nominal
            .iter()
            .zip(&print)
            .map(|(a, p)| a + (scale - 1.0) * p)
            .collect()
    };
    (ages, print)
}

impl TimeBuckling<'_> {
    /// g and ∂g/∂x at `x`, from the last evaluation when it was at the same point.
    fn cached(&mut self, x: &[f64]) -> Result<(f64, Vec<f64>), kappe_reliability::EvalError> {
        if let Some((at, g, grad)) = &self.last
            && at.as_slice() == x
        {
            return Ok((*g, grad.clone()));
        }
        let mut grad = vec![0.0; x.len()];
        let g = self.eval(x, &mut grad)?;
        self.last = Some((x.to_vec(), g, grad.clone()));
        Ok((g, grad))
    }
}

impl kappe_reliability::LimitState for TimeBuckling<'_> {
    fn value(&mut self, x: &[f64]) -> Result<f64, kappe_reliability::EvalError> {
        self.cached(x).map(|(g, _)| g)
    }

    fn value_and_gradient(
        &mut self,
        x: &[f64],
        grad: &mut [f64],
    ) -> Result<Option<f64>, kappe_reliability::EvalError> {
        let (g, d) = self.cached(x)?;
        grad.iter_mut().zip(&d).for_each(|(o, v)| *o = *v);
        Ok(Some(g))
    }
}

/// Most design points [`time_buckling_form`] proposes from its 1-D model before it falls back
/// to FORM on the re-solves: the model of ln Λ is a Hermite cubic through the last two
/// re-solves, whose error falls faster than quadratically as they close in (measured: 2–3
/// proposals per state, docs/reliability.md, "Cost").
pub const REDUCED_PROPOSALS: usize = 6;

/// Tolerances of FORM on the 1-D model (closed form, analytic gradient): 10 times below
/// FORM's on the true limit state, so the model's own residual takes at most a tenth of the
/// check at the proposed point. (HL-RF on the model stalls near 2·10⁻⁸·‖u‖ in u, measured on
/// study No. 14's states, so 10⁻⁸ is out of its reach.)
const MODEL_TOLERANCE: f64 = 1e-7;

/// HL-RF iterations allowed on the 1-D model: on these curved surfaces HL-RF converges
/// linearly at a rate near 0.9 per iterate (measured on study No. 14's states: 10⁻² to 3·10⁻⁸
/// in 100), and an iterate of the model costs microseconds, not a re-solve.
const MODEL_ITERATIONS: usize = 5_000;

impl TimeBuckling<'_> {
    /// Whether λ is E₀·Λ(Ė/E₀) for this component: the moduli are E₀ + Ė·h(a) (every law; h
    /// fixed by the ages), so homogeneous of degree 1 in (E₀, Ė), and λ with them (K linear in
    /// the moduli, K_G in the static solution's membrane forces, which do not change when every
    /// modulus is scaled by one factor). Not with the print speed uncertain (it moves the ages)
    /// or a modulus cap (it holds some moduli), nor without a positive rate (Λ at ρ = 0 only).
    fn reducible(&self) -> bool {
        self.vars.speed.is_none()
            && self.time.youngs_modulus.max.is_none()
            && (self.vars.e0t.is_some() || self.vars.rate.is_some())
            && self.time.youngs_modulus.rate > 0.0
    }
}

/// The buckling limit state of [`TimeBuckling`] with ln Λ(y), y = ln(Ė/E₀), replaced by the
/// Hermite cubic through two re-solves (their value and exact slope), or the tangent line of
/// one: g = (BLF₀/λ⁰)·E₀·e^{L(y)}·(γ₀/γ)·(1 + s_ν(ν − ν₀)) − BLF_min. Closed form.
struct ReducedBuckling {
    vars: Vars,
    /// Nominal E₀ and Ė (where they are not random).
    e0: f64,
    rate0: f64,
    /// BLF₀/λ⁰, s_ν, BLF_min.
    k: f64,
    s_nu: f64,
    blf_min: f64,
    /// (y, L, dL/dy) of the re-solves the model goes through, the latest last.
    points: Vec<[f64; 3]>,
}

impl ReducedBuckling {
    /// L(y), L′(y) and L″(y) (the cubic's; 0 for the tangent line).
    fn model(&self, y: f64) -> (f64, f64, f64) {
        match self.points.as_slice() {
            [.., [y1, f1, d1], [y2, f2, d2]] if (y2 - y1).abs() > 1e-12 => {
                // Cubic Hermite on [y1, y2] in t = (y − y1)/h (also outside it).
                let h = y2 - y1;
                let t = (y - y1) / h;
                let (t2, t3) = (t * t, t * t * t);
                let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
                let h10 = t3 - 2.0 * t2 + t;
                let h01 = -2.0 * t3 + 3.0 * t2;
                let h11 = t3 - t2;
                let v = h00 * f1 + h10 * h * d1 + h01 * f2 + h11 * h * d2;
                let dh00 = 6.0 * t2 - 6.0 * t;
                let dh10 = 3.0 * t2 - 4.0 * t + 1.0;
                let dh01 = -6.0 * t2 + 6.0 * t;
                let dh11 = 3.0 * t2 - 2.0 * t;
                let dv = (dh00 * f1 + dh01 * f2) / h + dh10 * d1 + dh11 * d2;
                let d2v = ((12.0 * t - 6.0) * (f1 - f2)) / (h * h)
                    + ((6.0 * t - 4.0) * d1 + (6.0 * t - 2.0) * d2) / h;
                (v, dv, d2v)
            }
            [.., [y1, f1, d1]] => (f1 + d1 * (y - y1), *d1, 0.0),
            [] => (0.0, 0.0, 0.0),
        }
    }

    fn eval(&self, x: &[f64], grad: &mut [f64]) -> f64 {
        let v = self.vars;
        let at =
            |i: Option<usize>, nominal: f64| i.and_then(|i| x.get(i).copied()).unwrap_or(nominal);
        let e0 = at(v.e0t, self.e0);
        let rate = at(v.rate, self.rate0);
        let (l, dl, _) = self.model((rate / e0).ln());
        let lambda = e0 * l.exp();
        let gamma = at(v.gamma, v.gamma0);
        let rg = gamma / v.gamma0;
        let nu = at(v.nu, v.nu0);
        let lin = 1.0 + self.s_nu * (nu - v.nu0);
        let val = self.k * lambda / rg * lin;
        grad.iter_mut().for_each(|g| *g = 0.0);
        let mut set = |i: Option<usize>, d: f64| {
            if let Some(g) = i.and_then(|i| grad.get_mut(i)) {
                *g = d;
            }
        };
        // ∂λ/∂E₀ = λ(1 − L′)/E₀, ∂λ/∂Ė = λL′/Ė.
        set(v.e0t, val * (1.0 - dl) / e0);
        set(v.rate, val * dl / rate);
        set(v.gamma, -val / gamma);
        set(v.nu, self.k * lambda / rg * self.s_nu);
        val - self.blf_min
    }
}

impl ReducedBuckling {
    /// G = ln(BLF/BLF_min) of the model, = ln k + ln E₀ + L(y) − ln(γ/γ₀) + ln(1 + s_ν(ν − ν₀))
    /// − ln BLF_min, with its gradient and Hessian in x (row-major): SORM's limit state. Its
    /// surface G = 0 is g's, and so are its curvatures (`kappe_reliability::sorm`, module
    /// docs); in ln form the Hessian is sparse and closed:
    /// ∂²G/∂E₀² = (L″ + L′ − 1)/E₀², ∂²G/∂E₀∂Ė = −L″/(E₀Ė), ∂²G/∂Ė² = (L″ − L′)/Ė²,
    /// ∂²G/∂γ² = 1/γ², ∂²G/∂ν² = −(s_ν/(1 + s_ν(ν − ν₀)))².
    fn ln_hessian(&self, x: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        let v = self.vars;
        let n = grad.len();
        let at =
            |i: Option<usize>, nominal: f64| i.and_then(|i| x.get(i).copied()).unwrap_or(nominal);
        let e0 = at(v.e0t, self.e0);
        let rate = at(v.rate, self.rate0);
        let (l, dl, d2l) = self.model((rate / e0).ln());
        let gamma = at(v.gamma, v.gamma0);
        let nu = at(v.nu, v.nu0);
        let lin = 1.0 + self.s_nu * (nu - v.nu0);
        grad.iter_mut().for_each(|g| *g = 0.0);
        hess.iter_mut().for_each(|h| *h = 0.0);
        let mut set = |i: Option<usize>, d: f64| {
            if let Some(g) = i.and_then(|i| grad.get_mut(i)) {
                *g = d;
            }
        };
        set(v.e0t, (1.0 - dl) / e0);
        set(v.rate, dl / rate);
        set(v.gamma, -1.0 / gamma);
        set(v.nu, self.s_nu / lin);
        let mut put = |i: Option<usize>, j: Option<usize>, d: f64| {
            if let (Some(i), Some(j)) = (i, j)
                && let Some(h) = hess.get_mut(i * n + j)
            {
                *h = d;
            }
        };
        put(v.e0t, v.e0t, (d2l + dl - 1.0) / (e0 * e0));
        put(v.e0t, v.rate, -d2l / (e0 * rate));
        put(v.rate, v.e0t, -d2l / (e0 * rate));
        put(v.rate, v.rate, (d2l - dl) / (rate * rate));
        put(v.gamma, v.gamma, 1.0 / (gamma * gamma));
        put(v.nu, v.nu, -(self.s_nu / lin).powi(2));
        self.k.ln() + e0.ln() + l - (gamma / v.gamma0).ln() + lin.ln() - self.blf_min.ln()
    }
}

/// Largest distance h in y = ln(Ė/E₀) between the design point's re-solve and the one before
/// it for the Hermite cubic's L″ at the design point (truncation ≈ h²L⁗/12: ≈ 3·10⁻⁵·L⁗ at
/// h = 0.02); the smallest is a tenth of it (the noise of the re-solves' L′, ≈ 10⁻⁸ by the
/// Lanczos residual, enters L″ as 2·10⁻⁸/h: ≤ 10⁻⁵ there). Outside that band one more
/// re-solve at y* + SORM_Y_STEP takes the other end. Measured on study No. 14's cap
/// (every-8th-row shell): with the last two re-solves as FORM left them (often within 10⁻⁶ of
/// each other in y, near convergence) L″ moved β by up to 0.06 and rejected one state's
/// curvature (docs/reliability.md, "SORM").
pub const SORM_Y_STEP: f64 = 0.02;

/// SORM of a [`TimeBuckling`] component at its FORM result `r` (module docs, "SORM"), through
/// the 1-D reduction: L = ln Λ is the Hermite cubic through the design point's re-solve and a
/// re-solve 0.1–1 × [`SORM_Y_STEP`] from it in y (the one before it when there, else one more
/// re-solve at y* + SORM_Y_STEP), so L and L′ there are the re-solve's own and L″ is the
/// cubic's, and the Hessian of G = ln(BLF/BLF_min) is closed-form
/// ([`ReducedBuckling::ln_hessian`]). FORM's P_f, flagged [`FORM_ONLY_NO_HESSIAN`], where the
/// reduction does not hold, the last re-solve is not at the design point, or the extra
/// re-solve fails.
pub fn time_buckling_sorm(
    model: &Model,
    g: &mut TimeBuckling<'_>,
    r: &FormResult,
) -> ComponentSorm {
    let t0 = kappe_fe::clock::Instant::now();
    let no_hessian = || ComponentSorm::form_only(r, FORM_ONLY_NO_HESSIAN);
    let Some(shell0) = g.shell0 else {
        return no_hessian();
    };
    if !g.reducible() {
        return no_hessian();
    }
    let v = g.vars;
    let (e00, rate0) = (g.time.youngs_modulus.initial, g.time.youngs_modulus.rate);
    let at = |i: Option<usize>, nominal: f64| {
        i.and_then(|i| r.x_star.get(i).copied()).unwrap_or(nominal)
    };
    let (e_star, rate_star) = (at(v.e0t, e00), at(v.rate, rate0));
    let y = |s: &[f64; 4]| (s[1] / s[0]).ln();
    let far = match g.solves.as_slice() {
        [.., a, b] => !(0.1 * SORM_Y_STEP..=SORM_Y_STEP).contains(&(y(b) - y(a)).abs()),
        _ => true,
    };
    if far {
        // One more re-solve at y* + SORM_Y_STEP: Ė × e^h where Ė is random, else E₀ × e^−h.
        use kappe_reliability::LimitState;
        let mut x = r.x_star.clone();
        let moved = match (v.rate, v.e0t) {
            (Some(i), _) => x.get_mut(i).map(|e| *e *= SORM_Y_STEP.exp()),
            (None, Some(i)) => x.get_mut(i).map(|e| *e *= (-SORM_Y_STEP).exp()),
            (None, None) => None,
        };
        if moved.is_none() || g.value(&x).is_err() {
            return no_hessian();
        }
        // The cubic runs from the extra point to the design point's (`b` last).
        if let Some(star) = g
            .solves
            .iter()
            .rev()
            .find(|s| s[0] == e_star && s[1] == rate_star)
            .copied()
        {
            g.solves.push(star);
        }
    }
    let last: Vec<&[f64; 4]> = g.solves.iter().rev().take(2).rev().collect();
    let &[a, b] = last.as_slice() else {
        return no_hessian();
    };
    let same = |p: f64, q: f64| (p - q).abs() <= 1e-12 * q.abs();
    if !(same(b[0], e_star) && same(b[1], rate_star))
        || [a, b]
            .iter()
            .any(|s| !(s[0] > 0.0 && s[1] > 0.0 && s[2] > 0.0))
    {
        return no_hessian();
    }
    let point = |[e0, rate, l, dl]: [f64; 4]| [(rate / e0).ln(), (l / e0).ln(), rate * dl / l];
    let points = vec![point(*a), point(*b)];
    if (points[1][0] - points[0][0]).abs() <= 1e-12 {
        return no_hessian();
    }
    let reduced = ReducedBuckling {
        vars: v,
        e0: e00,
        rate0,
        k: g.check.0 / shell0,
        s_nu: g.check.1,
        blf_min: g.blf_min,
        points,
    };
    let mut ls = kappe_reliability::WithHessian(|x: &[f64], grad: &mut [f64], hess: &mut [f64]| {
        reduced.ln_hessian(x, grad, hess)
    });
    ComponentSorm::timed(
        kappe_reliability::sorm(model, &mut ls, r, &SormOptions::default()),
        r,
        t0,
    )
}

/// FORM of a [`TimeBuckling`] component, through its 1-D reduction where λ = E₀·Λ(Ė/E₀)
/// ([`TimeBuckling::reducible`]; docs/reliability.md, "Cost"): the limit state depends on the
/// shell only through L(y) = ln Λ, y = ln(Ė/E₀), a function of one variable whose value and
/// exact slope L′ = Ė·(∂λ/∂Ė)/λ every re-solve gives. FORM runs on a model of g with L
/// replaced by the Hermite cubic through the last two re-solves (the tangent line of the
/// first, at the means), and the true limit state is re-solved only at the design point the
/// model proposes: when FORM's tolerances hold there with the true g and gradient (ε_G
/// relative to |g| at the means, as FORM's), that point is the result
/// ([`kappe_reliability::form_at`]), otherwise the re-solve joins the model and the next
/// point is proposed. After [`REDUCED_PROPOSALS`], or where the reduction does not hold, FORM
/// runs on the re-solves as before. `evaluations` and `iterations` of the result count the
/// re-solves and the proposals.
///
/// # Errors
/// As [`form`].
pub fn time_buckling_form(
    model: &Model,
    g: &mut TimeBuckling<'_>,
) -> Result<FormResult, kappe_reliability::Error> {
    use kappe_reliability::LimitState;
    let options = FormOptions::default();
    let before = g.solves.len();
    if !g.reducible() {
        return form(model, g, &options);
    }
    // The point FORM starts from (as `form` and `first_order` map it, so the cache holds).
    let u0 = model.u_from_x(&model.means());
    let x0 = model.x_from_u(&u0);
    let g0 = g
        .value(&x0)
        .map_err(|source| kappe_reliability::Error::LimitState {
            x: x0.clone(),
            source,
        })?;
    let (Some(shell0), true) = (g.shell0, g0 != 0.0 && g0.is_finite()) else {
        return form(model, g, &options);
    };
    let mut reduced = ReducedBuckling {
        vars: g.vars,
        e0: g.time.youngs_modulus.initial,
        rate0: g.time.youngs_modulus.rate,
        k: g.check.0 / shell0,
        s_nu: g.check.1,
        blf_min: g.blf_min,
        points: Vec::new(),
    };
    let tight = FormOptions {
        g_tolerance: MODEL_TOLERANCE,
        u_tolerance: MODEL_TOLERANCE,
        max_iterations: MODEL_ITERATIONS,
        ..FormOptions::default()
    };
    for proposal in 1..=REDUCED_PROPOSALS {
        reduced.points = g
            .solves
            .iter()
            .rev()
            .take(2)
            .rev()
            .filter(|[e0, rate, l, _]| *e0 > 0.0 && *rate > 0.0 && *l > 0.0)
            .map(|[e0, rate, l, dl]| [(rate / e0).ln(), (l / e0).ln(), rate * dl / l])
            .collect();
        let mut m = WithGradient(|x: &[f64], grad: &mut [f64]| reduced.eval(x, grad));
        // A model FORM cannot solve: FORM on the re-solves decides, as before.
        let Ok(proposed) = form(model, &mut m, &tight) else {
            break;
        };
        match kappe_reliability::form_at(model, g, &proposed.u_star, g0.abs(), &options) {
            Ok(Some(mut r)) => {
                r.iterations = proposal;
                r.evaluations = g.solves.len() - before;
                r.gradient_evaluations = r.evaluations;
                return Ok(r);
            }
            Ok(None) => {}
            // A proposal the shell cannot be solved at (e.g. far out while the model is a
            // tangent line): FORM on the re-solves decides, as before.
            Err(_) => break,
        }
    }
    form(model, g, &options)
}

/// [`time_buckling_form`], with a component whose FORM does not converge beyond [`FAR_BETA`]
/// left out (None), as every component is.
fn time_form(
    model: &Model,
    g: &mut TimeBuckling<'_>,
) -> Result<Option<FormResult>, kappe_reliability::Error> {
    match time_buckling_form(model, g) {
        Ok(r) => Ok(Some(r)),
        Err(kappe_reliability::Error::FormNotConverged { beta, .. }) if beta > FAR_BETA => Ok(None),
        Err(e) => Err(e),
    }
}

/// The checks of every state that a random variable enters, with the state's print time (h).
pub(crate) fn state_checks(
    cap: &Cap,
    analysis: &Analysis,
    schedule: &crate::schedule::Schedule,
    v: Vars,
) -> Result<Vec<(usize, f64, Vec<Check>)>, DesignError> {
    let scale = analysis.states.iter().fold(0.0_f64, |m, s| {
        m.max(s.max_compression_stress_pa.abs())
            .max(s.max_tension_stress_pa.abs())
    });
    let stol = crate::form::stresses::STRESS_REL_TOL * scale;
    let mut out = Vec::with_capacity(analysis.states.len());
    for s in &analysis.states {
        let t_hours = schedule.layers.get(s.index).map_or(0.0, |l| l.end_s) / 3600.0;
        let checks = checks_of(
            cap,
            &analysis.options,
            schedule,
            v,
            StateValues {
                index: s.index,
                blf: s.blf,
                stresses: Some((s.max_compression_stress_pa, s.max_tension_stress_pa, stol)),
                strength: s.strength_utilisation,
            },
        )?;
        // The deterministic analysis solved the re-solves' shell at the design's values (the
        // same mesh: grading, row stride, element; the same moduli): its factor is the
        // ratio's denominator (test `reliability::analysis_factor_is_the_resolve_at_the_mean`).
        let mesh = s.blf_mesh.or(if analysis.options.converged_blf {
            None
        } else {
            s.blf
        });
        let checks = checks
            .into_iter()
            .map(|c| match c {
                Check::BucklingTime { blf, s_nu, top, .. } => Check::BucklingTime {
                    blf,
                    s_nu,
                    top,
                    shell0: mesh,
                },
                c => c,
            })
            .collect();
        out.push((s.index, t_hours, checks));
    }
    Ok(out)
}

/// The deterministic results of one state that its random checks start from.
#[derive(Debug, Clone, Copy)]
pub struct StateValues {
    /// State index (top print index).
    pub index: usize,
    /// BLF at the design's values (None: no shell).
    pub blf: Option<f64>,
    /// σ_min,q,₀, σ_max,q,₀ and the tolerance below which a stress is round-off (None: the
    /// stress checks are not part of this evaluation, e.g. in `kappe schedule`, where the waits
    /// cannot change them).
    pub stresses: Option<(f64, f64, f64)>,
    /// Mohr–Coulomb utilisation u₀ (None: no strength model).
    pub strength: Option<f64>,
}

/// The checks of one state that a random variable enters (see the module docs), on the
/// schedule that sets its layers' ages (the ν re-solves use them).
///
/// # Errors
/// A state that cannot be built or a failed ν re-solve.
pub fn checks_of(
    cap: &Cap,
    options: &super::AnalysisOptions,
    schedule: &crate::schedule::Schedule,
    v: Vars,
    s: StateValues,
) -> Result<Vec<Check>, DesignError> {
    let k = &cap.design.constraints;
    let mut checks = Vec::new();
    if let Some(blf) = s.blf
        && (v.gamma.is_some() || v.e.is_some() || v.nu.is_some() || v.has_time())
    {
        let s_nu = if v.nu.is_some() {
            // ∂BLF/∂ν by a central difference of two re-solves (see the module docs).
            let green = crate::analysis::green::CapGreen::with_schedule(cap, Some(schedule))?;
            let green =
                (green.time.strength.is_some() || !green.time.is_constant()).then_some(green);
            let state = cap.state(s.index)?;
            let mut mat = state_material(cap, options, s.index, green.as_ref());
            let mut f = [0.0; 2];
            for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
                mat.poisson_ratio = v.nu0 + sign * NU_STEP;
                let b = state_buckling(
                    &state,
                    &mat,
                    &options.with_split_at_most(2),
                    &Default::default(),
                )?
                .buckling;
                f[k] = b.factors.first().copied().unwrap_or(blf);
            }
            (f[0] - f[1]) / (2.0 * NU_STEP) / blf
        } else {
            0.0
        };
        checks.push(if v.has_time() {
            Check::BucklingTime {
                blf,
                s_nu,
                top: s.index,
                shell0: None,
            }
        } else {
            Check::Buckling { blf, s_nu }
        });
    }
    if v.gamma.is_some() {
        // A stress check is random only when its sign can change with γ > 0: σ_min < 0 and a
        // compression above the deterministic tolerance; σ_max > 0 and a tension above it
        // (with σ_max = 0 a tension fails, and round-off passes, whatever γ is).
        if let Some((smin, smax, stol)) = s.stresses {
            if smin < -stol && k.sigma_min < 0.0 {
                checks.push(Check::Compression(smin));
            }
            if smax > stol && k.sigma_max > 0.0 {
                checks.push(Check::Tension(smax));
            }
        }
        if let Some(u) = s.strength.filter(|u| *u > 0.0)
            && !v.has_capacity()
        {
            checks.push(Check::Strength(u));
        }
    }
    if let Some(u) = s.strength.filter(|u| *u > 0.0)
        && v.has_capacity()
    {
        checks.push(Check::GreenLayers(u));
    }
    Ok(checks)
}

/// The membrane stresses of one state's shell at the design's values, layer by layer: what the
/// strength and bed-joint sliding checks need when the layers' capacities are uncertain
/// (docs/reliability.md, "Strength parameters and the print speed").
///
/// Layer k's capacity is the time model's Mohr–Coulomb c, φ at its age a_k, and its age moves
/// with the print speed v as a_k(s) = a_k + (s − 1)·D_k, s = v₀/v, D_k the print time after it
/// (pauses kept). The stresses scale exactly with γ (the load is linear in it) and do not
/// depend on the capacities; they are held at the design's moduli, so the redistribution by a
/// change of the moduli' ages (uncertain Ė, E₀ or v with E(t) not constant) is not followed
/// (docs/reliability.md, Limits). Layer k's utilisation is the largest of its elements' (each
/// element checked at the age of its younger layer, as the deterministic check does).
#[derive(Debug, Clone)]
pub struct GreenField {
    /// Age of layers 0..=top at the state on the run's schedule, s.
    pub ages: Vec<f64>,
    /// D_k: the print time after layer k, s (∂a_k/∂s).
    pub print: Vec<f64>,
    /// Per layer: the principal membrane stresses (σ₁, σ₂) of its elements, Pa.
    pub strength: Vec<Vec<[f64; 2]>>,
    /// Per layer: the bed-joint (σ_n, τ) of its elements, Pa.
    pub sliding: Vec<Vec<[f64; 2]>>,
}

/// Layers whose nominal utilisation is below this share of the state's worst are left out of
/// its components: their ln-margin is larger by ln 5 = 1.6, about 16 standard deviations of a
/// 10 % scatter, so they add nothing to the state's P_f (as the buildability objects' layers).
pub const LAYER_SHARE: f64 = 0.2;

impl GreenField {
    /// One static solve of the state with top print index `top` on `schedule`, on the shell the
    /// deterministic strength check uses (the grading's stress zones, `options.row_stride`).
    /// None: no strength model or no shell (a single layer, a mechanism).
    ///
    /// # Errors
    /// A state that cannot be built or a failed solve.
    pub fn solve(
        cap: &Cap,
        options: &super::AnalysisOptions,
        schedule: &crate::schedule::Schedule,
        top: usize,
    ) -> Result<Option<GreenField>, DesignError> {
        use crate::analysis::green::{bed_traction, principal};
        let green = crate::analysis::green::CapGreen::with_schedule(cap, Some(schedule))?;
        if green.time.strength.is_none() {
            return Ok(None);
        }
        let state = cap.state(top)?;
        let mut material = state_material(cap, options, top, Some(&green));
        if !green.time.is_constant() {
            material.layer_modulus = green.layer_moduli(cap, top);
        }
        let grading = options
            .grading
            .as_ref()
            .map(crate::analysis::graded::Grading::for_stresses);
        let analysed = crate::analysis::graded::AnalysedState::new(&state, grading.as_ref());
        let Ok(shell) =
            crate::analysis::shell::state_shell(analysed.state(), &material, options.row_stride)
        else {
            return Ok(None);
        };
        let st = match kappe_fe::linear_static(&shell.model) {
            Ok(st) => st,
            Err(kappe_fe::FeError::Mechanism { .. }) => return Ok(None),
            Err(e) => {
                return Err(DesignError::State {
                    state: top,
                    message: format!("static solve for the reliability analysis failed: {e}"),
                });
            }
        };
        let (ages, print) = scaled_ages(schedule, top, 1.0);
        let n = ages.len();
        let mut field = GreenField {
            ages,
            print,
            strength: vec![Vec::new(); n],
            sliding: vec![Vec::new(); n],
        };
        for (res, info) in st.elements.iter().zip(green.element_layers(&shell)) {
            let [sx, sy, sxy] = res.membrane_stress();
            let (s1, s2) = principal(sx, sy, sxy);
            let (sn, tau) = bed_traction(&res.frame, [sx, sy, sxy], info.bed_normal);
            if let (Some(a), Some(b)) = (
                field.strength.get_mut(info.younger),
                field.sliding.get_mut(info.younger),
            ) {
                a.push([s1, s2]);
                b.push([sn, tau]);
            }
        }
        Ok(Some(field))
    }

    /// The strength (or, with `sliding`, the bed-joint sliding) utilisation of `layer` (None:
    /// the largest over the state's layers) at the point `x` of the model `v` describes, under
    /// the design's time model `time`. Exactly the deterministic check's utilisation at the
    /// design's values.
    pub fn utilisation(
        &self,
        v: Vars,
        time: &TimeModel,
        x: &[f64],
        layer: Option<usize>,
        sliding: bool,
    ) -> f64 {
        let r = v.gamma.and_then(|i| x.get(i)).map_or(1.0, |g| g / v.gamma0);
        let s = v.age_scale(x);
        let t = v.time_at(time, x);
        let one = |k: usize| -> f64 {
            let age = self.ages.get(k).copied().unwrap_or(0.0)
                + (s - 1.0) * self.print.get(k).copied().unwrap_or(0.0);
            let Some(mc) = t.mohr_coulomb(age) else {
                return 0.0;
            };
            let rows = if sliding {
                &self.sliding
            } else {
                &self.strength
            };
            rows.get(k).map_or(0.0, |row| {
                row.iter().fold(0.0_f64, |m, &[a, b]| {
                    m.max(if sliding {
                        mc.sliding_utilisation(r * b, r * a)
                    } else {
                        mc.utilisation(r * a, r * b)
                    })
                })
            })
        };
        match layer {
            Some(k) => one(k),
            None => (0..self.ages.len()).map(one).fold(0.0, f64::max),
        }
    }

    /// The state's strength and sliding components: per check, one per layer within
    /// [`LAYER_SHARE`] of the worst nominal utilisation (each layer's utilisation is smooth in
    /// the parameters, their maximum is not: the worst layer moves between the old bottom and
    /// the young top as f₀ and ḟ trade off, and HL-RF would zigzag on that kink), each
    /// g = −ln u (the failure surface of 1 − u, nearly linear in u-space for the products of
    /// powers u is made of). Gradients: FORM's central differences (10⁻⁵ standard deviations;
    /// g is closed-form and cheap).
    pub fn components<'a>(
        &'a self,
        v: Vars,
        time: &'a TimeModel,
    ) -> Vec<(&'static str, Box<dyn kappe_reliability::LimitState + 'a>)> {
        let x0 = self.nominal_point(v, time);
        let mut out: Vec<(&'static str, Box<dyn kappe_reliability::LimitState + 'a>)> = Vec::new();
        for (name, sliding) in [("strength", false), ("sliding", true)] {
            let worst = self.utilisation(v, time, &x0, None, sliding);
            for k in 0..self.ages.len() {
                let u = self.utilisation(v, time, &x0, Some(k), sliding);
                if !(u > 0.0 && u.is_finite() && u >= LAYER_SHARE * worst) {
                    continue;
                }
                let g = move |x: &[f64]| -> Result<f64, kappe_reliability::EvalError> {
                    let u = self.utilisation(v, time, x, Some(k), sliding);
                    if u > 0.0 && !u.is_nan() {
                        Ok(-u.ln())
                    } else {
                        Err(format!("layer {k}: {name} utilisation {u} at x = {x:?}").into())
                    }
                };
                out.push((name, Box::new(kappe_reliability::Fallible(g))));
            }
        }
        out
    }

    /// The design's values of every variable `v` knows (a point where `utilisation` gives the
    /// deterministic one).
    fn nominal_point(&self, v: Vars, time: &TimeModel) -> Vec<f64> {
        let n = [
            v.gamma, v.e, v.nu, v.e0t, v.rate, v.f0, v.frate, v.phi, v.speed,
        ]
        .iter()
        .flatten()
        .max()
        .map_or(0, |m| m + 1);
        let mut x = vec![f64::NAN; n];
        let mut put = |i: Option<usize>, val: f64| {
            if let Some(s) = i.and_then(|i| x.get_mut(i)) {
                *s = val;
            }
        };
        put(v.gamma, v.gamma0);
        put(v.e, v.e0);
        put(v.nu, v.nu0);
        put(v.e0t, time.youngs_modulus.initial);
        put(v.rate, time.youngs_modulus.rate);
        put(v.speed, v.speed0);
        match time.strength {
            Some(Strength::Uniaxial {
                compressive_strength: p,
                friction_angle_deg,
            }) => {
                put(v.f0, p.initial);
                put(v.frate, p.rate);
                put(v.phi, friction_angle_deg);
            }
            Some(Strength::MohrCoulomb {
                cohesion: p,
                friction_angle_deg,
            }) => {
                put(v.f0, p.initial);
                put(v.frate, p.rate);
                put(v.phi, friction_angle_deg.initial);
            }
            None => {}
        }
        x
    }
}

/// A design's uncertain model, its drifts and where the variables sit.
pub type Prepared = (Model, Vec<(String, Drift)>, Vars);

/// FORM results of one state: its reliability and each component's check name, FORM result
/// and SORM.
pub type StateForm = (
    StateReliability,
    Vec<(&'static str, FormResult, ComponentSorm)>,
);

/// The uncertain model of a design, its drifts and where the variables sit: what every state's
/// FORM needs. None without `[uncertainty]`.
///
/// # Errors
/// An invalid `[uncertainty]`.
pub fn prepare(cap: &Cap) -> Result<Option<Prepared>, DesignError> {
    let Some(table) = &cap.design.uncertainty else {
        return Ok(None);
    };
    let model = table.model(&cap.design)?;
    let v = Vars::of(&model, cap);
    Ok(Some((model, table.drifts(), v)))
}

/// FORM of every check of one state printed at `t_hours` (the model drifted to that time), and
/// the state's β and P_f as a series system of its checks. None when no check is random.
/// The one implementation behind the run's reliability and `kappe schedule`'s β target.
///
/// # Errors
/// A drift factor that is not positive at `t_hours`, a failed re-solve, or FORM that does not
/// converge.
#[allow(clippy::too_many_arguments)]
pub fn state_form(
    cap: &Cap,
    options: &super::AnalysisOptions,
    schedule: &crate::schedule::Schedule,
    (model, drifts, v): (&Model, &[(String, Drift)], Vars),
    index: usize,
    t_hours: f64,
    checks: &[Check],
) -> Result<Option<StateForm>, DesignError> {
    state_form_with(
        cap,
        options,
        schedule,
        (model, drifts, v),
        index,
        t_hours,
        checks,
        None,
        Vec::new(),
    )
}

/// The buckling component of a state with the time model uncertain, prepared by
/// [`first_order`]: either its limit state (with the mean's solve cached) for FORM, or screened.
pub enum Prebuilt<'a> {
    /// Run FORM; the limit state already holds the solve at the means.
    Solve(Box<TimeBuckling<'a>>),
    /// Screened: the first-order result stands for FORM's.
    Screened(Box<FormResult>),
}

/// [`state_form`] with the state's buckling component prepared by [`first_order`].
#[allow(clippy::too_many_arguments)]
fn state_form_with<'a>(
    cap: &'a Cap,
    options: &'a super::AnalysisOptions,
    schedule: &'a crate::schedule::Schedule,
    (model, drifts, v): (&Model, &[(String, Drift)], Vars),
    index: usize,
    t_hours: f64,
    checks: &[Check],
    mut prebuilt: Option<Prebuilt<'a>>,
    extra: Vec<(&'static str, Box<dyn kappe_reliability::LimitState + 'a>)>,
) -> Result<Option<StateForm>, DesignError> {
    if checks.is_empty() && extra.is_empty() {
        return Ok(None);
    }
    let k = &cap.design.constraints;
    let limits = (k.sigma_min, k.sigma_max, k.blf_min);
    let seed = cap
        .design
        .uncertainty
        .as_ref()
        .and_then(|t| t.seed)
        .unwrap_or(0);
    let state_model = model
        .drifted(drifts, t_hours)
        .map_err(|e| DesignError::Uncertainty {
            field: "uncertainty.drift".into(),
            message: format!("state {index} at {t_hours:.3} h: {e}"),
        })?;
    let time = if checks
        .iter()
        .any(|c| matches!(c, Check::BucklingTime { .. }))
    {
        Some(cap.design.time_model()?)
    } else {
        None
    };
    let field = match checks.iter().find(|c| matches!(c, Check::GreenLayers(_))) {
        Some(_) => GreenField::solve(cap, options, schedule, index)?
            .map(|f| (f, cap.design.time_model()))
            .map(|(f, t)| t.map(|t| (f, t)))
            .transpose()?,
        None => None,
    };
    // The collapse component (`collapse_reliability`), a named limit state like the others.
    let mut named: Vec<(&'static str, Box<dyn kappe_reliability::LimitState + '_>)> = extra;
    let mut given = Vec::new();
    let mut first_order = false;
    for &check in checks {
        if let Check::GreenLayers(_) = check {
            if let Some((field, time)) = &field {
                named.extend(field.components(v, time));
            }
            continue;
        }
        // The time buckling component: screened, or FORM through its 1-D reduction
        // (`time_buckling_form`), from the solve at the means when `first_order` made it.
        let time_buckling = match (check, prebuilt.take(), &time) {
            (Check::BucklingTime { .. }, Some(Prebuilt::Screened(r)), _) => {
                let s = ComponentSorm::form_only(&r, FORM_ONLY_FIRST_ORDER);
                given.push((check.name(), *r, s));
                first_order = true;
                continue;
            }
            (Check::BucklingTime { .. }, Some(Prebuilt::Solve(g)), _) => Some(g),
            (
                Check::BucklingTime {
                    blf,
                    s_nu,
                    top,
                    shell0,
                },
                None,
                Some(time),
            ) => Some(Box::new(TimeBuckling::new(
                (cap, options, schedule),
                time.clone(),
                v,
                (blf, s_nu, top),
                k.blf_min,
                shell0,
            ))),
            _ => None,
        };
        if let Some(mut g) = time_buckling {
            if let Some(r) = time_form(&state_model, g.as_mut()).map_err(rel_err)? {
                let s = time_buckling_sorm(&state_model, &mut g, &r);
                given.push((check.name(), r, s));
            }
            continue;
        }
        named.push((
            check.name(),
            Box::new(WithGradient(move |x: &[f64], grad: &mut [f64]| {
                limit_state(check, v, limits, x, grad)
            })),
        ));
    }
    if named.is_empty() && given.is_empty() {
        return Ok(None);
    }
    form_checks_with(
        &state_model,
        named,
        given,
        first_order,
        index,
        t_hours,
        seed,
    )
    .map(Some)
    .map_err(rel_err)
}

/// The first-order β₁ of a state's buckling component, G = ln(BLF/BLF_min) linearised in u-space
/// at the drifted means (the point FORM starts from, so FORM's first iterate reuses this solve
/// through [`TimeBuckling::last`]): β₁ = (G₀ − ∇G·u₀)/‖∇G‖, α₁ = −∇G/‖∇G‖, as a FORM result
/// whose design point is β₁α₁ (module docs, "Screening").
///
/// # Errors
/// A failed solve, or a factor that is not positive at the means.
pub fn first_order(
    model: &Model,
    g: &mut TimeBuckling<'_>,
) -> Result<FormResult, kappe_reliability::EvalError> {
    use kappe_reliability::LimitState;
    let u0 = model.u_from_x(&model.means());
    let x0 = model.x_from_u(&u0);
    let mut grad = vec![0.0; x0.len()];
    let value = g.value_and_gradient(&x0, &mut grad)?.unwrap_or(f64::NAN);
    let blf = value + g.blf_min;
    if !(blf > 0.0 && blf.is_finite() && g.blf_min > 0.0) {
        return Err(format!(
            "state {}: buckling factor {blf} at the means (BLF_min {})",
            g.check.2, g.blf_min
        )
        .into());
    }
    let big_g = (blf / g.blf_min).ln();
    let grad_ln: Vec<f64> = grad.iter().map(|d| d / blf).collect();
    let gu = model.gradient_to_standard(&u0, &grad_ln);
    let norm = gu.iter().map(|d| d * d).sum::<f64>().sqrt();
    let (beta, alpha) = if norm > 0.0 && norm.is_finite() {
        let gu0: f64 = gu.iter().zip(&u0).map(|(a, b)| a * b).sum();
        (
            (big_g - gu0) / norm,
            gu.iter().map(|d| -d / norm).collect::<Vec<_>>(),
        )
    } else {
        // ln λ does not move with the variables: the state is safe or fails for every sample.
        let b = if big_g > 0.0 {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        };
        (b, vec![0.0; gu.len()])
    };
    let u_star: Vec<f64> = alpha.iter().map(|a| a * beta).collect();
    let x_star = if beta.is_finite() {
        model.x_from_u(&u_star)
    } else {
        x0.clone()
    };
    let n = x0.len();
    Ok(FormResult {
        names: model.variables().iter().map(|v| v.name.clone()).collect(),
        beta,
        pf: kappe_reliability::stdnormal::cdf(-beta),
        x_star,
        u_star,
        importance: alpha.iter().map(|a| a * a).collect(),
        gamma: alpha.clone(),
        alpha,
        dbeta_dmean: vec![f64::NAN; n],
        dbeta_dstd: vec![f64::NAN; n],
        g_at_design_point: f64::NAN,
        g_residual: f64::NAN,
        u_residual: f64::NAN,
        iterations: 0,
        evaluations: 1,
        gradient_evaluations: 1,
    })
}

/// Per state of `per_state` with a [`Check::BucklingTime`]: its limit state (the solve at the
/// drifted means done) and its first-order result ([`first_order`]); None for other states.
#[allow(clippy::type_complexity)]
fn first_orders<'a>(
    cap: &'a Cap,
    options: &'a super::AnalysisOptions,
    schedule: &'a crate::schedule::Schedule,
    (model, drifts, v): (&Model, &[(String, Drift)], Vars),
    per_state: &[(usize, f64, Vec<Check>)],
) -> Result<Vec<Option<(Box<TimeBuckling<'a>>, FormResult)>>, DesignError> {
    use rayon::prelude::*;
    let time = cap.design.time_model()?;
    let blf_min = cap.design.constraints.blf_min;
    per_state
        .par_iter()
        .map(|(index, t_hours, checks)| {
            let Some(&Check::BucklingTime {
                blf,
                s_nu,
                top,
                shell0,
            }) = checks
                .iter()
                .find(|c| matches!(c, Check::BucklingTime { .. }))
            else {
                return Ok(None);
            };
            let state_model =
                model
                    .drifted(drifts, *t_hours)
                    .map_err(|e| DesignError::Uncertainty {
                        field: "uncertainty.drift".into(),
                        message: format!("state {index} at {t_hours:.3} h: {e}"),
                    })?;
            let mut g = Box::new(TimeBuckling::new(
                (cap, options, schedule),
                time.clone(),
                v,
                (blf, s_nu, top),
                blf_min,
                shell0,
            ));
            let r = first_order(&state_model, &mut g).map_err(|e| DesignError::Uncertainty {
                field: "uncertainty".into(),
                message: format!("reliability analysis, state {index}: {e}"),
            })?;
            Ok(Some((g, r)))
        })
        .collect()
}

/// The buckling component of a state for [`state_form_with`]: screened or solved.
fn prebuild<'a>(
    f: Option<(Box<TimeBuckling<'a>>, FormResult)>,
    screen: bool,
) -> Option<Prebuilt<'a>> {
    f.map(|(g, r)| {
        if screen {
            Prebuilt::Screened(Box::new(r))
        } else {
            Prebuilt::Solve(g)
        }
    })
}

/// Every state's buckling β₁ and FORM β (states with a [`Check::BucklingTime`], in state
/// order; those FORM leaves out beyond [`FAR_BETA`] left out), screening off: the measurement
/// behind [`SCREEN_DELTA_RATIO`].
///
/// # Errors
/// As [`reliability`].
pub fn first_order_against_form(
    cap: &Cap,
    analysis: &Analysis,
    schedule: &crate::schedule::Schedule,
) -> Result<Vec<(usize, f64, f64)>, DesignError> {
    let Some((model, drifts, v)) = prepare(cap)? else {
        return Ok(Vec::new());
    };
    let per_state = state_checks(cap, analysis, schedule, v)?;
    let firsts = first_orders(
        cap,
        &analysis.options,
        schedule,
        (&model, &drifts, v),
        &per_state,
    )?;
    use rayon::prelude::*;
    firsts
        .into_par_iter()
        .zip(per_state.par_iter())
        .filter_map(|(f, (index, t_hours, _))| f.map(|f| (f, *index, *t_hours)))
        .map(|((mut g, first), index, t_hours)| {
            let state_model = model.drifted(&drifts, t_hours).map_err(rel_err)?;
            // As in the run: a component FORM cannot converge beyond FAR_BETA is left out.
            Ok(time_form(&state_model, g.as_mut())
                .map_err(rel_err)?
                .map(|r| (index, first.beta, r.beta)))
        })
        .collect::<Result<Vec<_>, DesignError>>()
        .map(|v| v.into_iter().flatten().collect())
}

/// One state's time buckling component by [`time_buckling_form`] and by FORM on the re-solves
/// ([`reduced_against_form`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReducedAgainstForm {
    /// State index.
    pub index: usize,
    /// β by the 1-D reduction and its re-solves (the means' included).
    pub beta_reduced: f64,
    /// Re-solves of the reduction.
    pub solves_reduced: usize,
    /// β by FORM on the re-solves (iHL-RF from the means).
    pub beta_form: f64,
    /// Re-solves of FORM.
    pub solves_form: usize,
}

/// Every state's time buckling component (states with a [`Check::BucklingTime`], in state
/// order) by [`time_buckling_form`] and by FORM on the re-solves, each from a fresh limit state
/// (the solve at the means counted): what the reduction saves and that it finds the same β.
/// States where either leaves the component out beyond [`FAR_BETA`] are left out.
///
/// # Errors
/// As [`reliability`].
pub fn reduced_against_form(
    cap: &Cap,
    analysis: &Analysis,
    schedule: &crate::schedule::Schedule,
) -> Result<Vec<ReducedAgainstForm>, DesignError> {
    use rayon::prelude::*;
    let Some((model, drifts, v)) = prepare(cap)? else {
        return Ok(Vec::new());
    };
    let per_state = state_checks(cap, analysis, schedule, v)?;
    let time = cap.design.time_model()?;
    let blf_min = cap.design.constraints.blf_min;
    let options = &analysis.options;
    per_state
        .par_iter()
        .map(|(index, t_hours, checks)| {
            let Some(&Check::BucklingTime {
                blf,
                s_nu,
                top,
                shell0,
            }) = checks
                .iter()
                .find(|c| matches!(c, Check::BucklingTime { .. }))
            else {
                return Ok(None);
            };
            let state_model = model.drifted(&drifts, *t_hours).map_err(rel_err)?;
            let fresh = || {
                TimeBuckling::new(
                    (cap, options, schedule),
                    time.clone(),
                    v,
                    (blf, s_nu, top),
                    blf_min,
                    shell0,
                )
            };
            let mut a = fresh();
            let reduced = time_form(&state_model, &mut a).map_err(rel_err)?;
            let mut b = fresh();
            let full = match form(&state_model, &mut b, &FormOptions::default()) {
                Ok(r) => Some(r),
                Err(kappe_reliability::Error::FormNotConverged { beta, .. }) if beta > FAR_BETA => {
                    None
                }
                Err(e) => return Err(rel_err(e)),
            };
            Ok(reduced.zip(full).map(|(r, f)| ReducedAgainstForm {
                index: *index,
                beta_reduced: r.beta,
                solves_reduced: a.solves.len(),
                beta_form: f.beta,
                solves_form: b.solves.len(),
            }))
        })
        .collect::<Result<Vec<_>, DesignError>>()
        .map(|v| v.into_iter().flatten().collect())
}

/// FORM of each named limit state of one state in the state's (drifted) `model`, and the
/// state's β and P_f as a series system of them ([`STATE_SYSTEM_SAMPLES`] importance samples,
/// `seed`); `beta_by_check` holds each name's lowest β. The one implementation behind the cap's
/// states and the buildability objects' states.
///
/// # Errors
/// FORM that does not converge, or no limit state.
pub fn form_checks<'a>(
    model: &Model,
    checks: Vec<(&'static str, Box<dyn kappe_reliability::LimitState + 'a>)>,
    index: usize,
    t_hours: f64,
    seed: u64,
) -> Result<StateForm, kappe_reliability::Error> {
    form_checks_with(model, checks, Vec::new(), false, index, t_hours, seed)
}

/// [`form_checks`] with `given` components (solved already, or screened: first-order results)
/// joining the state's system; the state is flagged `beta_first_order` when `first_order`.
/// Each component's SORM at its design point (module docs, "SORM"): the named limit states'
/// by [`kappe_reliability::sorm`] (their Hessian by differences), the given ones' as given.
fn form_checks_with<'a>(
    model: &Model,
    checks: Vec<(&'static str, Box<dyn kappe_reliability::LimitState + 'a>)>,
    given: Vec<(&'static str, FormResult, ComponentSorm)>,
    first_order: bool,
    index: usize,
    t_hours: f64,
    seed: u64,
) -> Result<StateForm, kappe_reliability::Error> {
    let mut by_check = BTreeMap::new();
    let mut own = Vec::new();
    let mut own_sorm = Vec::new();
    let mut results = Vec::new();
    for (name, r, s) in given {
        by_check
            .entry(name.to_owned())
            .and_modify(|b: &mut f64| *b = b.min(r.beta))
            .or_insert(r.beta);
        own.push(Component::from(&r));
        own_sorm.push(s.component(&r));
        results.push((name, r, s));
    }
    for (name, mut g) in checks {
        let r = match form(model, g.as_mut(), &FormOptions::default()) {
            Ok(r) => r,
            // A component whose HL-RF iterates stay beyond β = FAR_BETA without converging (the
            // difference gradients meet round-off there) is left out: its P_f < 1e-15 cannot
            // move the state's. Any other failure is an error.
            Err(kappe_reliability::Error::FormNotConverged { beta, .. }) if beta > FAR_BETA => {
                continue;
            }
            Err(e) => return Err(e),
        };
        let t0 = kappe_fe::clock::Instant::now();
        let s = ComponentSorm::timed(
            kappe_reliability::sorm(model, g.as_mut(), &r, &SormOptions::default()),
            &r,
            t0,
        );
        // Several components of one check (e.g. a buildability object's layers): the
        // weakest one's β.
        by_check
            .entry(name.to_owned())
            .and_modify(|b: &mut f64| *b = b.min(r.beta))
            .or_insert(r.beta);
        own.push(Component::from(&r));
        own_sorm.push(s.component(&r));
        results.push((name, r, s));
    }
    let options = SystemOptions {
        samples: STATE_SYSTEM_SAMPLES,
        seed,
        ditlevsen: false,
    };
    let sys = series_system(&own, &options)?;
    // The same sampler and seed: where every component keeps FORM's β the two agree to the bit.
    let sorm = series_system(&own_sorm, &options)?;
    Ok((
        StateReliability {
            index,
            t_hours,
            beta: sys.beta,
            pf: sys.pf,
            beta_by_check: by_check,
            beta_first_order: first_order,
            beta_sorm: Some(sorm.beta),
            pf_sorm: Some(sorm.pf),
        },
        results,
    ))
}

fn rel_err(e: kappe_reliability::Error) -> DesignError {
    DesignError::Uncertainty {
        field: "uncertainty".into(),
        message: format!("reliability analysis: {e}"),
    }
}

/// FORM of `check` in `model` (the state's drifted model).
pub fn check_form(
    model: &Model,
    check: Check,
    v: Vars,
    limits: (f64, f64, f64),
) -> Result<FormResult, kappe_reliability::Error> {
    let mut g = WithGradient(|x: &[f64], grad: &mut [f64]| limit_state(check, v, limits, x, grad));
    form(model, &mut g, &FormOptions::default())
}

/// The reliability of every state of `analysis` and of the print; None without `[uncertainty]`.
///
/// # Errors
/// An invalid `[uncertainty]`, a drift factor that reaches 0 within the print, a re-solve that
/// fails, or FORM that does not converge ([`DesignError::Uncertainty`]).
pub fn reliability(
    cap: &Cap,
    analysis: &Analysis,
    schedule: &crate::schedule::Schedule,
) -> Result<Option<Reliability>, DesignError> {
    let Some(table) = &cap.design.uncertainty else {
        return Ok(None);
    };
    let t0 = kappe_fe::clock::Instant::now();
    let model = table.model(&cap.design)?;
    let drifts = table.drifts();
    let v = Vars::of(&model, cap);
    let k = &cap.design.constraints;
    let per_state = state_checks(cap, analysis, schedule, v)?;
    let mut results: Vec<PrintComponent> = Vec::new();
    let mut states = Vec::new();
    let prepared = (&model, drifts.as_slice(), v);
    let options = &analysis.options;
    // The collapse limit state (`collapse_reliability`): tables of the states the rule
    // admits, from the deterministic check's collapse factors.
    let collapse_model =
        super::collapse_reliability::CapCollapseModel::new(cap, options, schedule, &model)?;
    let state_times: Vec<(usize, f64)> = per_state.iter().map(|p| (p.0, p.1)).collect();
    let collapse_tables = match &collapse_model {
        Some(m) => {
            let times: Vec<f64> = state_times.iter().map(|p| p.1).collect();
            let factors: Vec<(usize, f64)> = analysis
                .states
                .iter()
                .filter_map(|s| s.collapse_factor.map(|f| (s.index, f)))
                .collect();
            m.build(&model, &drifts, &times, &factors)?
        }
        None => None,
    };
    let collapse_of = |index: usize| collapse_component(&collapse_model, &collapse_tables, index);
    let mut firsts = if table.screening.unwrap_or(true) {
        first_orders(cap, options, schedule, prepared, &per_state)?
    } else {
        per_state.iter().map(|_| None).collect()
    };
    // Screening: the least-β₁ state first; the largest component P_f it gives bounds the print's
    // P_f from below, and a state whose N·Φ(−(β₁ − δ)) is below SCREEN_SHARE of that bound keeps
    // its first-order result (module docs, "Screening").
    let mut order: Vec<(usize, f64)> = firsts
        .iter()
        .enumerate()
        .filter_map(|(i, f)| f.as_ref().map(|(_, r)| (i, r.beta)))
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut screened = vec![false; per_state.len()];
    let mut solved: Vec<Option<StateForm>> = per_state.iter().map(|_| None).collect();
    if let Some(&(first, _)) = order.first()
        && let (Some((index, t_hours, checks)), Some(f)) =
            (per_state.get(first), firsts.get_mut(first))
    {
        let done = state_form_with(
            cap,
            options,
            schedule,
            prepared,
            *index,
            *t_hours,
            checks,
            prebuild(f.take(), false),
            collapse_of(*index),
        )?;
        let bound = done
            .iter()
            .flat_map(|(_, rs)| rs.iter().map(|(_, r, _)| r.pf))
            .fold(0.0_f64, f64::max);
        let n = order.len() as f64;
        for &(i, beta1) in order.iter().skip(1) {
            let share = n * kappe_reliability::stdnormal::cdf(-(beta1 - screen_delta(beta1)));
            if let Some(s) = screened.get_mut(i) {
                *s = share < SCREEN_SHARE * bound;
            }
        }
        if let Some(s) = solved.get_mut(first) {
            *s = done;
        }
    }
    let first = order.first().map(|&(i, _)| i);
    // States are independent (each its own FORM, its own re-solves): in parallel, collected in
    // state order, so the result is the sequential one bit for bit.
    use rayon::prelude::*;
    let rest: Vec<Option<StateForm>> = per_state
        .par_iter()
        .zip(firsts.into_par_iter())
        .zip(screened.into_par_iter())
        .enumerate()
        .map(|(i, (((index, t_hours, checks), f), screen))| {
            if Some(i) == first {
                return Ok(None);
            }
            state_form_with(
                cap,
                options,
                schedule,
                prepared,
                *index,
                *t_hours,
                checks,
                prebuild(f, screen),
                collapse_of(*index),
            )
        })
        .collect::<Result<Vec<_>, DesignError>>()?;
    let per_state = solved.into_iter().zip(rest).map(|(a, b)| a.or(b));
    for (state, rs) in per_state.flatten() {
        let index = state.index;
        for (name, r, s) in rs {
            results.push((index, name, r, s));
        }
        states.push(state);
    }
    if results.is_empty() {
        return Err(DesignError::Uncertainty {
            field: "uncertainty".into(),
            message: "no analysed check depends on the uncertain parameters (buckling needs an \
                      analysed state; the stresses depend on material.specific_weight only)"
                .into(),
        });
    }
    // Every collapse design point against a direct path there (the table's error as Δβ).
    let collapse = match (&collapse_model, &collapse_tables) {
        (Some(m), Some(t)) => {
            let points: Vec<(usize, f64, &FormResult)> = results
                .iter()
                .filter(|c| c.1 == "collapse")
                .map(|c| {
                    let th = state_times.iter().find(|p| p.0 == c.0).map_or(0.0, |p| p.1);
                    (c.0, th, &c.2)
                })
                .collect();
            let checks = points
                .par_iter()
                .map(|&(index, th, f)| {
                    let state_model =
                        model
                            .drifted(&drifts, th)
                            .map_err(|e| DesignError::Uncertainty {
                                field: "uncertainty.drift".into(),
                                message: format!("state {index} at {th:.3} h: {e}"),
                            })?;
                    m.check_point(t, &state_model, index, f)
                })
                .collect::<Result<Vec<_>, DesignError>>()?;
            Some(super::collapse_reliability::CapCollapseReliability::of(
                m, t, checks,
            ))
        }
        _ => None,
    };
    let mut r = print_reliability(
        results,
        states,
        &SystemOptions {
            samples: table.system_samples.unwrap_or(20_000),
            seed: table.seed.unwrap_or(0),
            ditlevsen: false,
        },
        k.beta_min.unwrap_or(BETA_MIN_DEFAULT),
        t0,
    )?;
    r.collapse = collapse;
    r.collapse_tables = collapse_tables;
    r.seconds = t0.elapsed().as_secs_f64();
    Ok(Some(r))
}

/// State `index`'s collapse component (`collapse_reliability`) for [`state_form_with`]: none
/// without the check, its tables, or a table of this state.
fn collapse_component<'b>(
    model: &'b Option<super::collapse_reliability::CapCollapseModel<'_>>,
    tables: &'b Option<super::collapse_reliability::CapCollapseTables>,
    index: usize,
) -> Vec<(&'static str, Box<dyn kappe_reliability::LimitState + 'b>)> {
    match (model, tables) {
        (Some(m), Some(t)) => m
            .limit_state(t, index)
            .map(|g| ("collapse", g))
            .into_iter()
            .collect(),
        _ => Vec::new(),
    }
}

/// One component of the print: state index, check name, FORM result and SORM.
pub type PrintComponent = (usize, &'static str, FormResult, ComponentSorm);

/// The print's reliability from every state's FORM results (state index, check name, result,
/// SORM): the series system over all of them, its governing component's design point and
/// sensitivities, and the same system with the components' SORM P_f ([`SormSystem`], the same
/// sampler and seed). The one implementation behind the cap's and the buildability objects'
/// blocks.
///
/// # Errors
/// No component, or a failed series-system estimate.
pub fn print_reliability(
    results: Vec<PrintComponent>,
    states: Vec<StateReliability>,
    system: &SystemOptions,
    beta_min: f64,
    t0: kappe_fe::clock::Instant,
) -> Result<Reliability, DesignError> {
    let components: Vec<Component> = results
        .iter()
        .map(|(_, _, r, _)| Component::from(r))
        .collect();
    let sys = series_system(&components, system).map_err(rel_err)?;
    let Some((gov_state, gov_check, gov, _)) = results.get(sys.governing) else {
        return Err(rel_err(kappe_reliability::Error::NoComponents));
    };
    let t_sorm = kappe_fe::clock::Instant::now();
    let with_sorm: Vec<Component> = results.iter().map(|(_, _, r, s)| s.component(r)).collect();
    let sorm_sys = series_system(&with_sorm, system).map_err(rel_err)?;
    let mut form_only = BTreeMap::new();
    for why in results.iter().filter_map(|(_, _, _, s)| s.form_only) {
        *form_only.entry(why.to_owned()).or_insert(0) += 1;
    }
    let sorm = results
        .get(sorm_sys.governing)
        .map(|(state, check, _, _)| SormSystem {
            beta: sorm_sys.beta,
            pf: sorm_sys.pf,
            pf_interval: sorm_sys.interval,
            governing_state: *state,
            governing_check: (*check).to_owned(),
            form_only,
            seconds: t_sorm.elapsed().as_secs_f64()
                + results.iter().map(|(_, _, _, s)| s.seconds).sum::<f64>(),
        });
    let names = &gov.names;
    let design_point = names.iter().cloned().zip(gov.x_star.clone()).collect();
    let sensitivities = names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let get = |v: &[f64]| v.get(i).copied().unwrap_or(0.0);
            (
                n.clone(),
                Sensitivity {
                    importance: get(&gov.importance),
                    dbeta_dmean: get(&gov.dbeta_dmean),
                    dbeta_dstd: get(&gov.dbeta_dstd),
                },
            )
        })
        .collect();
    Ok(Reliability {
        beta: sys.beta,
        pf: sys.pf,
        pf_interval: sys.interval,
        beta_min,
        governing_state: *gov_state,
        governing_check: (*gov_check).to_owned(),
        design_point,
        sensitivities,
        states,
        components: components.len(),
        seconds: t0.elapsed().as_secs_f64(),
        monte_carlo: None,
        sorm,
        collapse: None,
        collapse_tables: None,
    })
}
