//! `[uncertainty]`: the design's uncertain parameters (issue 24), keyed by the design file's own
//! names, their physical correlation and their drift over print time.
//!
//! ```toml
//! [uncertainty]
//! "material.specific_weight" = { dist = "normal", std = 1015.0 }
//! "material.youngs_modulus" = { dist = "lognormal", cov = 0.2 }
//!
//! [uncertainty.correlation]
//! "material.youngs_modulus" = { "material.specific_weight" = 0.3 }
//!
//! [uncertainty.drift]
//! "material.youngs_modulus" = { percent_per_hour = -2.0 }
//! ```
//!
//! Each entry is a [`kappe_reliability::UncertaintySpec`]; its mean is the design's value unless
//! `mean` is given. The stiffness is declared positive, so it takes a lognormal or a uniform with
//! lower bound > 0; the specific weight may be normal (the JCSS Probabilistic Model Code's model of
//! self-weight; at the coefficients of variation of a mix, P(γ ≤ 0) is below 1e-20) and Poisson's
//! ratio must stay in (0, 0.5), which a normal cannot guarantee, so it is declared positive too.

use std::collections::BTreeMap;

/// The name of the imperfection amplitude in `[uncertainty]`: an input of designs and
/// buildability specs with `[analysis.nonlinear]` (`crate::analysis::collapse_reliability`,
/// `commands::buildability_collapse`), refused without it.
pub const IMPERFECTION: &str = "analysis.nonlinear.imperfection";

/// The nominal value of [`IMPERFECTION`] under `nonlinear` and that it is positive: w0 (m)
/// when `imperfection = w0` is given, else 1 (a factor on the rule's w0); or why it cannot be
/// uncertain. The one rule of designs and buildability specs.
///
/// # Errors
/// No enabled collapse check, or `imperfection = 0` (the perfect path: nothing to scatter).
pub fn imperfection_nominal(
    nonlinear: Option<&crate::input::nonlinear::NonlinearSpec>,
) -> Result<(f64, bool), String> {
    match nonlinear.filter(|n| n.enabled) {
        None => Err(
            "the imperfection amplitude is an input of the nonlinear collapse check \
             only: give [analysis.nonlinear] (enabled) or remove it"
                .to_owned(),
        ),
        Some(nl) => match nl.imperfection {
            Some(w) if w <= 0.0 => Err(format!(
                "[analysis.nonlinear] imperfection = {w} is the perfect path, which has no \
                 scatter to model; give w0 > 0 m, or leave it to the rule, whose w0 the \
                 variable then multiplies (mean 1)"
            )),
            Some(w) => Ok((w, true)),
            None => Ok((1.0, true)),
        },
    }
}

use kappe_reliability::{Correlation, Drift, Model, UncertaintySpec};
use serde::{Deserialize, Serialize};

use crate::input::design::Design;
use crate::input::error::DesignError;

/// Default β_min when the design has `[uncertainty]` and no `constraints.beta_min`: 2.3, P_f =
/// Φ(−2.3) ≈ 1.1 %. ISO 2394:2015 Annex G and the JCSS Probabilistic Model Code (Part 1, Table
/// 2.1) give β = 2.3 as the one-year target for a large relative cost of safety measures and
/// minor consequences of failure — a temporary green-state print that fails in the lab.
pub const BETA_MIN_DEFAULT: f64 = 2.3;

/// The names `[uncertainty]` accepts, whether each is positive, and how it enters the analysis.
pub const PARAMETERS: [(&str, bool); 11] = [
    ("material.specific_weight", false),
    ("material.youngs_modulus", true),
    ("material.poisson_ratio", true),
    ("material.time.youngs_modulus", true),
    ("material.time.youngs_modulus_rate", true),
    ("material.time.compressive_strength", true),
    ("material.time.compressive_strength_rate", true),
    ("material.time.cohesion", true),
    ("material.time.cohesion_rate", true),
    ("material.time.friction_angle_deg", true),
    ("print.print_speed", true),
];

/// The time model's parameters among [`PARAMETERS`]: they set every layer's modulus by its age,
/// so they enter the buckling check through re-solves with exact eigenvalue sensitivities
/// (`crate::analysis::blf_sensitivity`), not through a scaling.
pub const TIME_PARAMETERS: [&str; 2] = [
    "material.time.youngs_modulus",
    "material.time.youngs_modulus_rate",
];

/// The time model's strength parameters among [`PARAMETERS`]: they set every layer's capacity
/// by its age and enter the strength and bed-joint sliding checks layer by layer
/// (`crate::analysis::reliability`, "Strength parameters and the print speed").
pub const STRENGTH_PARAMETERS: [&str; 5] = [
    "material.time.compressive_strength",
    "material.time.compressive_strength_rate",
    "material.time.cohesion",
    "material.time.cohesion_rate",
    "material.time.friction_angle_deg",
];

/// The print speed: every layer's print duration is its path length over it, so it moves every
/// layer's age through the schedule (the pauses — waits, station changes — do not move).
pub const SPEED: &str = "print.print_speed";

/// A parameter's nominal value and whether it is positive, or why its name is not allowed.
pub type Lookup<'a> = dyn Fn(&str) -> Result<(f64, bool), String> + 'a;

/// The estimator of a design's Monte Carlo (`[uncertainty] monte_carlo_method`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema, Default,
)]
#[serde(rename_all = "snake_case")]
pub enum McMethod {
    /// Crude when the expected failures N·P_f,FORM reach 100 (P̂'s cov ≤ 0.1), else importance.
    #[default]
    Auto,
    /// Crude Monte Carlo: u ~ N(0, I).
    Crude,
    /// Importance sampling from the mixture of N(u*_i, I) over the components' design points.
    Importance,
}

/// The `[uncertainty]` table; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UncertaintyTable {
    /// Physical correlation: `"a" = { "b" = ρ }`; pairs not listed are uncorrelated.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub correlation: BTreeMap<String, BTreeMap<String, f64>>,
    /// Drift of a parameter's mean and std over print time (%/h, steps).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub drift: BTreeMap<String, Drift>,
    /// Number of importance samples of the print's series system (default 20 000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub system_samples: Option<u64>,
    /// Seed of the series system's sampler (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Monte Carlo samples of the whole print: crude in `kappe buildability`; a design's
    /// governing states, crude or by importance sampling (`crate::analysis::design_monte_carlo`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<u64>,
    /// A design's sampling method: `auto` (default), `crude` or `importance`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monte_carlo_method: Option<McMethod>,
    /// The first-order screening of the states' buckling components (default true; false runs
    /// FORM on every state, see `crate::analysis::reliability`, "Screening").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub screening: Option<bool>,
    /// The uncertain parameters, by the design file's names.
    #[serde(flatten)]
    pub parameters: BTreeMap<String, UncertaintySpec>,
}

fn allowed_names() -> String {
    PARAMETERS
        .iter()
        .map(|(n, _)| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The design's nominal value of parameter `name`, or None for a name not in [`PARAMETERS`].
pub fn nominal(design: &Design, name: &str) -> Option<f64> {
    let m = &design.material;
    match name {
        "material.specific_weight" => Some(m.specific_weight),
        "material.youngs_modulus" => Some(m.youngs_modulus),
        "material.poisson_ratio" => Some(m.poisson_ratio),
        "material.time.youngs_modulus" | "material.time.youngs_modulus_rate" => {
            let has_time = m.time.is_some() || design.analysis.ageing.is_some();
            let t = design.time_model().ok().filter(|_| has_time)?;
            Some(if name.ends_with("_rate") {
                t.youngs_modulus.rate
            } else {
                t.youngs_modulus.initial
            })
        }
        "print.print_speed" => Some(design.print.print_speed),
        _ if STRENGTH_PARAMETERS.contains(&name) => {
            strength_nominal(&design.time_model().ok()?, name).ok()
        }
        _ => None,
    }
}

/// The nominal value of strength parameter `name` in `time`, or why the time model has none.
pub fn strength_nominal(
    time: &crate::input::material::TimeModel,
    name: &str,
) -> Result<f64, String> {
    use crate::input::material::Strength;
    let form = |given: &str, other: &str| {
        format!(
            "the design gives its strength as {given}; this parameter belongs to the other \
             form, {other} — make the design's own strength parameters uncertain"
        )
    };
    match (time.strength, name) {
        (None, _) => Err(
            "a strength parameter needs a strength model: give [material.time] \
                          compressive_strength (uniaxial, optional friction_angle_deg) or \
                          cohesion + friction_angle_deg"
                .to_owned(),
        ),
        (
            Some(Strength::Uniaxial {
                compressive_strength: p,
                ..
            }),
            _,
        ) if name.starts_with("material.time.compressive_strength") => {
            Ok(if name.ends_with("_rate") {
                p.rate
            } else {
                p.initial
            })
        }
        (
            Some(Strength::Uniaxial {
                friction_angle_deg, ..
            }),
            "material.time.friction_angle_deg",
        ) => Ok(friction_angle_deg),
        (Some(Strength::Uniaxial { .. }), _) => Err(form(
            "compressive_strength (uniaxial)",
            "cohesion + friction_angle_deg",
        )),
        (Some(Strength::MohrCoulomb { cohesion: p, .. }), _)
            if name.starts_with("material.time.cohesion") =>
        {
            Ok(if name.ends_with("_rate") {
                p.rate
            } else {
                p.initial
            })
        }
        (
            Some(Strength::MohrCoulomb {
                friction_angle_deg: p,
                ..
            }),
            "material.time.friction_angle_deg",
        ) => Ok(p.initial),
        (Some(Strength::MohrCoulomb { .. }), _) => Err(form(
            "cohesion + friction_angle_deg (Mohr–Coulomb)",
            "compressive_strength",
        )),
    }
}

fn err(field: String, e: impl std::fmt::Display) -> DesignError {
    DesignError::Uncertainty {
        field,
        message: e.to_string(),
    }
}

impl UncertaintyTable {
    /// The reliability model: one random variable per entry (in name order), the correlation
    /// mapped by Nataf; every problem a [`DesignError::Uncertainty`] naming the field.
    pub fn model(&self, design: &Design) -> Result<Model, DesignError> {
        if self.parameters.is_empty() {
            return Err(err(
                "uncertainty".into(),
                format!(
                    "no uncertain parameter given; allowed names: {}",
                    allowed_names()
                ),
            ));
        }
        if self.monte_carlo_method.is_some() && self.monte_carlo.is_none() {
            return Err(err(
                "uncertainty.monte_carlo_method".into(),
                "a sampling method needs a sample count: give monte_carlo = N (≥ 100)",
            ));
        }
        let time_model = design.material.time.is_some() || design.analysis.ageing.is_some();
        if time_model && self.parameters.contains_key("material.youngs_modulus") {
            return Err(err(
                "uncertainty.\"material.youngs_modulus\"".into(),
                "the design has a time model ([material.time] or [analysis.ageing]), whose \
                 moduli do not use material.youngs_modulus; give the time model's own \
                 \"material.time.youngs_modulus\" and \"material.time.youngs_modulus_rate\"",
            ));
        }
        self.model_of(&|name: &str| {
            if TIME_PARAMETERS.contains(&name) && !time_model {
                return Err(
                    "a time-model parameter needs a time model: give [material.time] \
                     (e.g. model = \"linear\" with youngs_modulus_rate)"
                        .to_owned(),
                );
            }
            if name == SPEED && !time_model {
                return Err(
                    "the print speed only moves the layers' ages, which no check of a design \
                     without a time model uses; give [material.time]"
                        .to_owned(),
                );
            }
            if name == IMPERFECTION {
                // The collapse limit state of the design's states
                // (`crate::analysis::collapse_reliability`): w0 in m when `imperfection` is
                // given, else a factor (mean 1) on every state's rule w0; positive only.
                return imperfection_nominal(design.analysis.nonlinear.as_ref());
            }
            if STRENGTH_PARAMETERS.contains(&name) {
                let time = design.time_model().map_err(|e| e.to_string())?;
                return strength_nominal(&time, name).map(|v| (v, true));
            }
            let positive = PARAMETERS.iter().find(|(n, _)| *n == name).map(|p| p.1);
            match (nominal(design, name), positive) {
                (Some(v), Some(p)) => Ok((v, p)),
                _ => Err(format!(
                    "unknown parameter; allowed names: {}",
                    allowed_names()
                )),
            }
        })
    }

    /// The reliability model of any input file: `lookup(name)` gives a parameter's nominal value
    /// and whether it is positive, or the message of why the name is not allowed (the design's
    /// [`UncertaintyTable::model`] and the buildability spec's share everything else).
    pub fn model_with(&self, lookup: &Lookup<'_>) -> Result<Model, DesignError> {
        // Only a design chooses its sampler; a buildability spec's Monte Carlo is crude.
        if self.monte_carlo_method.is_some() {
            return Err(err(
                "uncertainty.monte_carlo_method".into(),
                "a sampling method is a design's key (kappe design); a buildability spec's \
                 Monte Carlo is crude: remove it",
            ));
        }
        self.model_of(lookup)
    }

    /// [`UncertaintyTable::model_with`] without the buildability-only checks.
    fn model_of(&self, lookup: &Lookup<'_>) -> Result<Model, DesignError> {
        if self.parameters.is_empty() {
            return Err(err(
                "uncertainty".into(),
                "no uncertain parameter given; give at least one distribution keyed by a \
                 parameter name",
            ));
        }
        let known = |name: &str, context: &str| -> Result<(f64, bool), DesignError> {
            lookup(name).map_err(|m| err(format!("{context}\"{name}\""), m))
        };
        let mut variables = Vec::with_capacity(self.parameters.len());
        for (name, spec) in &self.parameters {
            let (nominal, positive) = known(name, "uncertainty.")?;
            let v = spec
                .to_variable(name, nominal, positive)
                .map_err(|e| err(format!("uncertainty.\"{name}\""), e))?;
            variables.push(v);
        }
        let mut pairs = Vec::new();
        for (a, row) in &self.correlation {
            known(a, "uncertainty.correlation.")?;
            for (b, &rho) in row {
                known(b, &format!("uncertainty.correlation.\"{a}\"."))?;
                for n in [a, b] {
                    if !self.parameters.contains_key(n) {
                        return Err(err(
                            format!("uncertainty.correlation.\"{a}\".\"{b}\""),
                            format!("`{n}` has no distribution in [uncertainty]; give it one"),
                        ));
                    }
                }
                pairs.push((a.clone(), b.clone(), rho));
            }
        }
        for (name, d) in &self.drift {
            known(name, "uncertainty.drift.")?;
            if !self.parameters.contains_key(name) {
                return Err(err(
                    format!("uncertainty.drift.\"{name}\""),
                    format!("`{name}` has no distribution in [uncertainty]; give it one"),
                ));
            }
            if !d.percent_per_hour.is_finite()
                || d.steps.iter().any(|s| {
                    !(s.at_hours.is_finite()
                        && s.at_hours >= 0.0
                        && s.factor.is_finite()
                        && s.factor > 0.0)
                })
            {
                return Err(err(
                    format!("uncertainty.drift.\"{name}\""),
                    "allowed: a finite percent_per_hour; steps at_hours ≥ 0 with factor > 0",
                ));
            }
        }
        if self.monte_carlo.is_some_and(|n| n < 100) {
            return Err(err(
                "uncertainty.monte_carlo".into(),
                "allowed: at least 100 samples",
            ));
        }
        if self.system_samples.is_some_and(|n| n < 100) {
            return Err(err(
                "uncertainty.system_samples".into(),
                "allowed: at least 100 samples",
            ));
        }
        let correlation = if pairs.is_empty() {
            Correlation::Independent
        } else {
            Correlation::Pairs(pairs)
        };
        Model::new(variables, &correlation).map_err(|e| {
            let field = match &e {
                kappe_reliability::Error::CorrelationNotPositiveDefinite { .. }
                | kappe_reliability::Error::CorrelationOutOfRange { .. }
                | kappe_reliability::Error::CorrelationNotAttainable { .. }
                | kappe_reliability::Error::CorrelationNotSymmetric { .. } => {
                    "uncertainty.correlation".to_owned()
                }
                kappe_reliability::Error::NotPositive { variable, .. }
                | kappe_reliability::Error::InvalidParameter { variable, .. } => {
                    format!("uncertainty.\"{variable}\"")
                }
                _ => "uncertainty".to_owned(),
            };
            err(field, e)
        })
    }

    /// The drifts as the engine takes them.
    pub fn drifts(&self) -> Vec<(String, Drift)> {
        self.drift
            .iter()
            .map(|(n, d)| (n.clone(), d.clone()))
            .collect()
    }
}
