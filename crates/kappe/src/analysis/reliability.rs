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

use std::collections::BTreeMap;

use kappe_reliability::{
    Component, Drift, FormOptions, FormResult, Model, SystemOptions, WithGradient, form,
    series_system,
};
use serde::{Deserialize, Serialize};

use super::buckling::{state_buckling, state_material};
use super::check::Analysis;
use crate::form::cap::Cap;
use crate::form::states::build_state;
use crate::input::error::DesignError;
use crate::input::uncertainty::BETA_MIN_DEFAULT;

/// Absolute step in ν of the central difference ∂BLF/∂ν: small against ν's range (0, 0.5) and its
/// scatter, large against the eigensolver's relative residual (1e-8) times BLF/h.
pub const NU_STEP: f64 = 1e-3;

/// β beyond which a component that FORM cannot converge is left out of a state (P_f < 1e-15).
pub const FAR_BETA: f64 = 8.0;

/// Samples of each state's own series system (its few checks).
const STATE_SYSTEM_SAMPLES: u64 = 4_000;

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
    /// Buckling with the time model's E₀ and/or Ė uncertain: BLF₀, s_ν and the state's top
    /// print index; g from re-solves of the state's shell ([`TimeBuckling`]).
    BucklingTime {
        /// BLF at the design's values.
        blf: f64,
        /// (∂BLF/∂ν)/BLF₀.
        s_nu: f64,
        /// Top print index of the state.
        top: usize,
    },
}

impl Check {
    fn name(self) -> &'static str {
        match self {
            Check::Buckling { .. } | Check::BucklingTime { .. } => "buckling",
            Check::Compression(_) => "sigma_min",
            Check::Tension(_) => "sigma_max",
            Check::Strength(_) => "strength",
        }
    }
}

/// Indices of γ, E, ν in the model, and their analysed values.
#[derive(Debug, Clone, Copy)]
pub struct Vars {
    gamma: Option<usize>,
    e: Option<usize>,
    nu: Option<usize>,
    gamma0: f64,
    e0: f64,
    nu0: f64,
    /// The time model's E₀ and Ė (`material.time.*`).
    e0t: Option<usize>,
    rate: Option<usize>,
}

impl Vars {
    /// Whether a time-model parameter is uncertain.
    pub fn has_time(&self) -> bool {
        self.e0t.is_some() || self.rate.is_some()
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
        Check::Strength(u) => {
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
}

/// Lanczos relative residual of the re-solves: the eigenvalue error is of the order of its
/// square (symmetric pencil), far below FORM's tolerance on g (1e-6 relative).
pub const RESOLVE_TOLERANCE: f64 = 1e-8;

impl TimeBuckling<'_> {
    fn solve(&self, e0: f64, rate: f64) -> Result<(f64, [f64; 2]), kappe_reliability::EvalError> {
        let mut time = self.time.clone();
        time.youngs_modulus.initial = e0;
        time.youngs_modulus.rate = rate;
        let top = self.check.2;
        crate::analysis::blf_sensitivity::time_state_blf(
            self.cap,
            self.options,
            self.schedule,
            &time,
            top,
            RESOLVE_TOLERANCE,
        )?
        .ok_or_else(|| {
            format!("state {top}: no positive buckling factor at E₀ = {e0} Pa, Ė = {rate} Pa/s")
                .into()
        })
    }

    fn eval(&mut self, x: &[f64], grad: &mut [f64]) -> Result<f64, kappe_reliability::EvalError> {
        let v = self.vars;
        let p = self.time.youngs_modulus;
        let at =
            |i: Option<usize>, nominal: f64| i.and_then(|i| x.get(i).copied()).unwrap_or(nominal);
        let shell0 = match self.shell0 {
            Some(l) => l,
            None => {
                let l = self.solve(p.initial, p.rate)?.0;
                self.shell0 = Some(l);
                l
            }
        };
        let (blf, s_nu, _) = self.check;
        let (l, dl) = self.solve(at(v.e0t, p.initial), at(v.rate, p.rate))?;
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
        set(v.gamma, -val / gamma);
        set(v.nu, k * l / rg * s_nu);
        Ok(val - self.blf_min)
    }
}

impl kappe_reliability::LimitState for TimeBuckling<'_> {
    fn value(&mut self, x: &[f64]) -> Result<f64, kappe_reliability::EvalError> {
        let mut g = vec![0.0; x.len()];
        self.eval(x, &mut g)
    }

    fn value_and_gradient(
        &mut self,
        x: &[f64],
        grad: &mut [f64],
    ) -> Result<Option<f64>, kappe_reliability::EvalError> {
        self.eval(x, grad).map(Some)
    }
}

/// The checks of every state that a random variable enters, with the state's print time (h).
fn state_checks(
    cap: &Cap,
    analysis: &Analysis,
    schedule: &crate::schedule::Schedule,
    v: Vars,
) -> Result<Vec<(usize, f64, Vec<Check>)>, DesignError> {
    let scale = analysis.states.iter().fold(0.0_f64, |m, s| {
        m.max(s.max_compression_stress_pa.abs())
            .max(s.max_tension_stress_pa.abs())
    });
    let stol = super::stress::STRESS_REL_TOL * scale;
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
            let phi = cap.design.print.start_arch_fraction;
            let state = build_state(&cap.sections, &cap.frame, phi, s.index)?;
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
        if let Some(u) = s.strength.filter(|u| *u > 0.0) {
            checks.push(Check::Strength(u));
        }
    }
    Ok(checks)
}

/// A design's uncertain model, its drifts and where the variables sit.
pub type Prepared = (Model, Vec<(String, Drift)>, Vars);

/// FORM results of one state: its reliability and each check's FORM result by check name.
pub type StateForm = (StateReliability, Vec<(&'static str, FormResult)>);

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
    if checks.is_empty() {
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
    let mut states: Vec<Box<dyn kappe_reliability::LimitState + '_>> = Vec::new();
    for &check in checks {
        states.push(match (check, &time) {
            (Check::BucklingTime { blf, s_nu, top }, Some(time)) => Box::new(TimeBuckling {
                cap,
                options,
                schedule,
                time: time.clone(),
                vars: v,
                check: (blf, s_nu, top),
                blf_min: k.blf_min,
                shell0: None,
            }),
            _ => Box::new(WithGradient(move |x: &[f64], grad: &mut [f64]| {
                limit_state(check, v, limits, x, grad)
            })),
        });
    }
    let named = checks.iter().map(|c| c.name()).zip(states).collect();
    form_checks(&state_model, named, index, t_hours, seed)
        .map(Some)
        .map_err(rel_err)
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
    let mut by_check = BTreeMap::new();
    let mut own = Vec::new();
    let mut results = Vec::new();
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
        // Several components of one check (e.g. a buildability object's layers): the
        // weakest one's β.
        by_check
            .entry(name.to_owned())
            .and_modify(|b: &mut f64| *b = b.min(r.beta))
            .or_insert(r.beta);
        own.push(Component::from(&r));
        results.push((name, r));
    }
    let sys = series_system(
        &own,
        &SystemOptions {
            samples: STATE_SYSTEM_SAMPLES,
            seed,
            ditlevsen: false,
        },
    )?;
    Ok((
        StateReliability {
            index,
            t_hours,
            beta: sys.beta,
            pf: sys.pf,
            beta_by_check: by_check,
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
    let mut results: Vec<(usize, &'static str, FormResult)> = Vec::new();
    let mut states = Vec::new();
    // States are independent (each its own FORM, its own re-solves): in parallel, collected in
    // state order, so the result is the sequential one bit for bit.
    use rayon::prelude::*;
    let per_state: Vec<_> = per_state
        .par_iter()
        .map(|(index, t_hours, checks)| {
            state_form(
                cap,
                &analysis.options,
                schedule,
                (&model, &drifts, v),
                *index,
                *t_hours,
                checks,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    for (state, rs) in per_state.into_iter().flatten() {
        let index = state.index;
        for (name, r) in rs {
            results.push((index, name, r));
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
    print_reliability(
        results,
        states,
        &SystemOptions {
            samples: table.system_samples.unwrap_or(20_000),
            seed: table.seed.unwrap_or(0),
            ditlevsen: false,
        },
        k.beta_min.unwrap_or(BETA_MIN_DEFAULT),
        t0,
    )
    .map(Some)
}

/// The print's reliability from every state's FORM results (state index, check name, result):
/// the series system over all of them, its governing component's design point and
/// sensitivities. The one implementation behind the cap's and the buildability objects' blocks.
///
/// # Errors
/// No component, or a failed series-system estimate.
pub fn print_reliability(
    results: Vec<(usize, &'static str, FormResult)>,
    states: Vec<StateReliability>,
    system: &SystemOptions,
    beta_min: f64,
    t0: kappe_fe::clock::Instant,
) -> Result<Reliability, DesignError> {
    let components: Vec<Component> = results.iter().map(|(_, _, r)| Component::from(r)).collect();
    let sys = series_system(&components, system).map_err(rel_err)?;
    let Some((gov_state, gov_check, gov)) = results.get(sys.governing) else {
        return Err(rel_err(kappe_reliability::Error::NoComponents));
    };
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
    })
}
