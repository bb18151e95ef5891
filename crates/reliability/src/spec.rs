//! Input-file form of an uncertain parameter, e.g. the issue-24 `[uncertainty]` entries
//!
//! ```toml
//! [uncertainty]
//! "material.specific_weight" = { dist = "normal", std = 1015.0 }
//! "material.time.youngs_modulus" = { dist = "lognormal", cov = 0.2 }
//! "print.layer_time" = { dist = "uniform", lower = 50.0, upper = 70.0 }
//! ```
//!
//! The mean is the design's own value unless `mean` is given. Normal and lognormal take exactly
//! one of `std`, `cov`; uniform takes `lower` and `upper`, or one of `std`, `cov` around the mean
//! (a, b = μ ∓ √3σ). Anything else is an [`Error::InvalidSpec`] naming the parameter and field.

use crate::error::{Error, Result};
use crate::variable::RandomVariable;
use serde::{Deserialize, Serialize};

/// The distribution family of a spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DistKind {
    /// Normal.
    Normal,
    /// Lognormal (mean and std/cov of the variable itself).
    Lognormal,
    /// Uniform.
    Uniform,
}

/// One uncertain parameter as written in an input file; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UncertaintySpec {
    /// Family.
    pub dist: DistKind,
    /// Mean (default: the design's value).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean: Option<f64>,
    /// Standard deviation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std: Option<f64>,
    /// Coefficient of variation σ/|μ|.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cov: Option<f64>,
    /// Uniform lower bound.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower: Option<f64>,
    /// Uniform upper bound.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upper: Option<f64>,
}

impl UncertaintySpec {
    /// The random variable `name`, with mean = `mean` or else the design's `nominal` value;
    /// `positive` declares the quantity positive (a normal distribution is then refused by
    /// [`crate::Model::new`]).
    pub fn to_variable(&self, name: &str, nominal: f64, positive: bool) -> Result<RandomVariable> {
        let spec_err = |field: &'static str, allowed: &'static str| Error::InvalidSpec {
            variable: name.to_owned(),
            field,
            allowed,
        };
        let mean = self.mean.unwrap_or(nominal);
        let v = match self.dist {
            DistKind::Normal | DistKind::Lognormal => {
                if self.lower.is_some() || self.upper.is_some() {
                    let field = if self.lower.is_some() {
                        "lower"
                    } else {
                        "upper"
                    };
                    return Err(spec_err(
                        field,
                        "bounds are for dist = \"uniform\"; give std or cov",
                    ));
                }
                let lognormal = self.dist == DistKind::Lognormal;
                match (self.std, self.cov) {
                    (Some(std), None) if lognormal => RandomVariable::lognormal(name, mean, std)?,
                    (Some(std), None) => RandomVariable::normal(name, mean, std)?,
                    (None, Some(cov)) if lognormal => {
                        RandomVariable::lognormal_cov(name, mean, cov)?
                    }
                    (None, Some(cov)) => RandomVariable::normal_cov(name, mean, cov)?,
                    (Some(_), Some(_)) => return Err(spec_err("cov", "give std or cov, not both")),
                    (None, None) => return Err(spec_err("std", "std or cov is required")),
                }
            }
            DistKind::Uniform => match (self.lower, self.upper, self.std, self.cov) {
                (Some(a), Some(b), None, None) if self.mean.is_none() => {
                    RandomVariable::uniform(name, a, b)?
                }
                (Some(_), Some(_), _, _) => {
                    return Err(spec_err(
                        "lower",
                        "bounds fix the distribution: give no mean, std or cov with them",
                    ));
                }
                (Some(_), None, _, _) => return Err(spec_err("upper", "lower needs upper")),
                (None, Some(_), _, _) => return Err(spec_err("lower", "upper needs lower")),
                (None, None, std, cov) => {
                    let std = match (std, cov) {
                        (Some(s), None) => s,
                        (None, Some(c)) => c * mean.abs(),
                        (Some(_), Some(_)) => {
                            return Err(spec_err("cov", "give std or cov, not both"));
                        }
                        (None, None) => {
                            return Err(spec_err(
                                "std",
                                "lower and upper, or std or cov, are required",
                            ));
                        }
                    };
                    if !(std.is_finite() && std > 0.0) {
                        return Err(Error::InvalidParameter {
                            variable: name.to_owned(),
                            field: if cov.is_some() { "cov" } else { "std" },
                            value: if cov.is_some() {
                                cov.unwrap_or(std)
                            } else {
                                std
                            },
                            allowed: "std and cov must be finite and > 0",
                        });
                    }
                    let half = 3f64.sqrt() * std;
                    RandomVariable::uniform(name, mean - half, mean + half)?
                }
            },
        };
        Ok(if positive { v.positive() } else { v })
    }
}
