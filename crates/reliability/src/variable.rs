//! Random variables: normal, lognormal and uniform marginals, their cdf, inverse cdf, pdf and the
//! map to and from a standard normal variable z = Φ⁻¹(F(x)).
//!
//! # Parameters
//!
//! Every distribution is given by the mean μ and the standard deviation σ of the variable
//! itself (or its coefficient of variation δ = σ/μ), or by bounds for the uniform one.
//!
//! * **Normal** N(μ, σ): z = (x − μ)/σ, x = μ + σz (exact, no round trip through Φ).
//! * **Lognormal** with mean μ > 0 and std σ of X (not of ln X): ln X ~ N(λ, ζ) with
//!   ζ² = ln(1 + δ²), λ = ln μ − ζ²/2, δ = σ/μ. Then z = (ln x − λ)/ζ, x = exp(λ + ζz),
//!   F(x) = Φ(z), f(x) = φ(z)/(ζx). (Ang & Tang 2007, eq. 3.28; Der Kiureghian 2022, §2.)
//! * **Uniform** U(a, b): μ = (a + b)/2, σ = (b − a)/√12, F(x) = (x − a)/(b − a),
//!   z = Φ⁻¹(F(x)), x = a + (b − a)Φ(z) (for z > 0 computed as b − (b − a)Φ(−z), so the upper tail
//!   keeps its precision).
//!
//! The Jacobian of the map, dx/dz = φ(z)/f(x), is σ (normal), ζx (lognormal) and (b − a)φ(z)
//! (uniform); FORM uses it for the chain rule ∇_z G = (dx/dz) ∇_x g.

use crate::error::{Error, Result};
use crate::stdnormal;
use serde::{Deserialize, Serialize};

/// A marginal distribution with validated parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "dist", rename_all = "lowercase")]
pub enum Distribution {
    /// N(mean, std).
    Normal { mean: f64, std: f64 },
    /// ln X ~ N(lambda, zeta); `mean`, `std` are those of X.
    Lognormal {
        mean: f64,
        std: f64,
        lambda: f64,
        zeta: f64,
    },
    /// U(lower, upper).
    Uniform { lower: f64, upper: f64 },
}

impl Distribution {
    /// Short name ("normal", "lognormal", "uniform").
    pub fn kind(&self) -> &'static str {
        match self {
            Distribution::Normal { .. } => "normal",
            Distribution::Lognormal { .. } => "lognormal",
            Distribution::Uniform { .. } => "uniform",
        }
    }

    /// Mean of X.
    pub fn mean(&self) -> f64 {
        match *self {
            Distribution::Normal { mean, .. } | Distribution::Lognormal { mean, .. } => mean,
            Distribution::Uniform { lower, upper } => 0.5 * (lower + upper),
        }
    }

    /// Standard deviation of X.
    pub fn std(&self) -> f64 {
        match *self {
            Distribution::Normal { std, .. } | Distribution::Lognormal { std, .. } => std,
            Distribution::Uniform { lower, upper } => (upper - lower) / 12f64.sqrt(),
        }
    }

    /// Cumulative distribution F(x).
    pub fn cdf(&self, x: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, std } => stdnormal::cdf((x - mean) / std),
            Distribution::Lognormal { lambda, zeta, .. } => {
                if x <= 0.0 {
                    0.0
                } else {
                    stdnormal::cdf((x.ln() - lambda) / zeta)
                }
            }
            Distribution::Uniform { lower, upper } => {
                ((x - lower) / (upper - lower)).clamp(0.0, 1.0)
            }
        }
    }

    /// Inverse cumulative distribution F⁻¹(p), p ∈ [0, 1].
    pub fn inv_cdf(&self, p: f64) -> f64 {
        match *self {
            Distribution::Uniform { lower, upper } => lower + (upper - lower) * p.clamp(0.0, 1.0),
            _ => self.from_standard(stdnormal::inv_cdf(p)),
        }
    }

    /// Probability density f(x).
    pub fn pdf(&self, x: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, std } => stdnormal::pdf((x - mean) / std) / std,
            Distribution::Lognormal { lambda, zeta, .. } => {
                if x <= 0.0 {
                    0.0
                } else {
                    stdnormal::pdf((x.ln() - lambda) / zeta) / (zeta * x)
                }
            }
            Distribution::Uniform { lower, upper } => {
                if (lower..=upper).contains(&x) {
                    1.0 / (upper - lower)
                } else {
                    0.0
                }
            }
        }
    }

    /// z = Φ⁻¹(F(x)).
    pub fn to_standard(&self, x: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, std } => (x - mean) / std,
            Distribution::Lognormal { lambda, zeta, .. } => {
                if x <= 0.0 {
                    f64::NEG_INFINITY
                } else {
                    (x.ln() - lambda) / zeta
                }
            }
            Distribution::Uniform { lower, upper } => {
                let p = (x - lower) / (upper - lower);
                // Above the median use the upper tail so that z keeps its precision there.
                if p > 0.5 {
                    -stdnormal::inv_cdf((upper - x) / (upper - lower))
                } else {
                    stdnormal::inv_cdf(p)
                }
            }
        }
    }

    /// x = F⁻¹(Φ(z)).
    pub fn from_standard(&self, z: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, std } => mean + std * z,
            Distribution::Lognormal { lambda, zeta, .. } => (lambda + zeta * z).exp(),
            Distribution::Uniform { lower, upper } => {
                if z > 0.0 {
                    upper - (upper - lower) * stdnormal::cdf(-z)
                } else {
                    lower + (upper - lower) * stdnormal::cdf(z)
                }
            }
        }
    }

    /// dx/dz at z (= φ(z)/f(x)).
    pub fn dx_dz(&self, z: f64) -> f64 {
        match *self {
            Distribution::Normal { std, .. } => std,
            Distribution::Lognormal { lambda, zeta, .. } => zeta * (lambda + zeta * z).exp(),
            Distribution::Uniform { lower, upper } => (upper - lower) * stdnormal::pdf(z),
        }
    }

    /// d²x/dz² at z: 0 (normal), ζ²x (lognormal), −(b − a)zφ(z) (uniform, φ′(z) = −zφ(z)).
    /// SORM's chain rule of the Hessian through the map ([`crate::sorm`]).
    pub fn d2x_dz2(&self, z: f64) -> f64 {
        match *self {
            Distribution::Normal { .. } => 0.0,
            Distribution::Lognormal { lambda, zeta, .. } => zeta * zeta * (lambda + zeta * z).exp(),
            Distribution::Uniform { lower, upper } => -(upper - lower) * z * stdnormal::pdf(z),
        }
    }

    /// The same kind of distribution with another mean and std (uniform: a = μ − √3σ,
    /// b = μ + √3σ). Used for the sensitivities dβ/dμ, dβ/dσ; parameters are not re-validated.
    pub(crate) fn with_mean_std(&self, mean: f64, std: f64) -> Distribution {
        match self {
            Distribution::Normal { .. } => Distribution::Normal { mean, std },
            Distribution::Lognormal { .. } => lognormal_params(mean, std),
            Distribution::Uniform { .. } => {
                let half = 3f64.sqrt() * std;
                Distribution::Uniform {
                    lower: mean - half,
                    upper: mean + half,
                }
            }
        }
    }

    /// X scaled by a factor c > 0: c·X has mean cμ, std cσ (the same δ), bounds ca, cb.
    pub(crate) fn scaled(&self, c: f64) -> Distribution {
        match *self {
            Distribution::Normal { mean, std } => Distribution::Normal {
                mean: c * mean,
                std: c * std,
            },
            Distribution::Lognormal {
                mean,
                std,
                lambda,
                zeta,
            } => Distribution::Lognormal {
                mean: c * mean,
                std: c * std,
                lambda: lambda + c.ln(),
                zeta,
            },
            Distribution::Uniform { lower, upper } => Distribution::Uniform {
                lower: c * lower,
                upper: c * upper,
            },
        }
    }
}

fn lognormal_params(mean: f64, std: f64) -> Distribution {
    let delta = std / mean;
    let zeta2 = (delta * delta).ln_1p();
    Distribution::Lognormal {
        mean,
        std,
        lambda: mean.ln() - 0.5 * zeta2,
        zeta: zeta2.sqrt(),
    }
}

/// A named random variable: its marginal distribution and whether the quantity must be positive
/// (a Young's modulus, a specific weight, a layer time).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RandomVariable {
    /// Name, e.g. `"material.time.youngs_modulus"`.
    pub name: String,
    /// The marginal distribution.
    pub distribution: Distribution,
    /// Declared positive: the model rejects distributions that allow values ≤ 0.
    pub positive: bool,
}

fn check(
    variable: &str,
    field: &'static str,
    value: f64,
    ok: bool,
    allowed: &'static str,
) -> Result<()> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            variable: variable.to_owned(),
            field,
            value,
            allowed,
        })
    }
}

impl RandomVariable {
    /// Normal N(mean, std), std > 0.
    pub fn normal(name: impl Into<String>, mean: f64, std: f64) -> Result<Self> {
        let name = name.into();
        check(&name, "mean", mean, true, "a finite number")?;
        check(&name, "std", std, std > 0.0, "std must be finite and > 0")?;
        Ok(Self::new(name, Distribution::Normal { mean, std }))
    }

    /// Normal with std = cov·|mean|, cov > 0, mean ≠ 0.
    pub fn normal_cov(name: impl Into<String>, mean: f64, cov: f64) -> Result<Self> {
        let name = name.into();
        check(
            &name,
            "mean",
            mean,
            mean != 0.0,
            "a finite number ≠ 0 when cov is given",
        )?;
        check(&name, "cov", cov, cov > 0.0, "cov must be finite and > 0")?;
        Self::normal(name, mean, cov * mean.abs())
    }

    /// Lognormal with mean > 0 and std > 0 of X itself (see the module docs for λ, ζ).
    pub fn lognormal(name: impl Into<String>, mean: f64, std: f64) -> Result<Self> {
        let name = name.into();
        check(
            &name,
            "mean",
            mean,
            mean > 0.0,
            "a lognormal mean must be finite and > 0",
        )?;
        check(&name, "std", std, std > 0.0, "std must be finite and > 0")?;
        let mut v = Self::new(name, lognormal_params(mean, std));
        v.positive = true;
        Ok(v)
    }

    /// Lognormal with mean > 0 and coefficient of variation cov = σ/μ > 0 of X itself.
    pub fn lognormal_cov(name: impl Into<String>, mean: f64, cov: f64) -> Result<Self> {
        let name = name.into();
        check(
            &name,
            "mean",
            mean,
            mean > 0.0,
            "a lognormal mean must be finite and > 0",
        )?;
        check(&name, "cov", cov, cov > 0.0, "cov must be finite and > 0")?;
        Self::lognormal(name, mean, cov * mean)
    }

    /// Uniform U(lower, upper), lower < upper.
    pub fn uniform(name: impl Into<String>, lower: f64, upper: f64) -> Result<Self> {
        let name = name.into();
        check(&name, "lower", lower, true, "a finite number")?;
        check(
            &name,
            "upper",
            upper,
            upper > lower,
            "upper must be finite and > lower",
        )?;
        Ok(Self::new(name, Distribution::Uniform { lower, upper }))
    }

    fn new(name: String, distribution: Distribution) -> Self {
        Self {
            name,
            distribution,
            positive: false,
        }
    }

    /// Re-checks the parameters (the fields are public and deserialisable, so a variable may not
    /// come from the validating constructors).
    pub(crate) fn check(&self) -> Result<()> {
        let name = self.name.as_str();
        match self.distribution {
            Distribution::Normal { mean, std } => {
                check(name, "mean", mean, true, "a finite number")?;
                check(name, "std", std, std > 0.0, "std must be finite and > 0")
            }
            Distribution::Lognormal {
                mean,
                std,
                lambda,
                zeta,
            } => {
                check(
                    name,
                    "mean",
                    mean,
                    mean > 0.0,
                    "a lognormal mean must be finite and > 0",
                )?;
                check(name, "std", std, std > 0.0, "std must be finite and > 0")?;
                check(name, "lambda", lambda, true, "a finite number")?;
                check(
                    name,
                    "zeta",
                    zeta,
                    zeta > 0.0,
                    "zeta must be finite and > 0",
                )
            }
            Distribution::Uniform { lower, upper } => {
                check(name, "lower", lower, true, "a finite number")?;
                check(
                    name,
                    "upper",
                    upper,
                    upper > lower,
                    "upper must be finite and > lower",
                )
            }
        }
    }

    /// Declares the quantity positive; [`crate::Model::new`] then rejects a normal distribution
    /// (unbounded below) and uniform bounds with lower ≤ 0.
    pub fn positive(mut self) -> Self {
        self.positive = true;
        self
    }

    /// Checks the `positive` declaration against the distribution.
    pub(crate) fn check_positive(&self) -> Result<()> {
        if !self.positive {
            return Ok(());
        }
        let reason = match self.distribution {
            Distribution::Normal { .. } => "is unbounded below (P(X ≤ 0) > 0)".to_owned(),
            Distribution::Uniform { lower, .. } if lower <= 0.0 => {
                format!("has lower bound {lower} ≤ 0")
            }
            _ => return Ok(()),
        };
        Err(Error::NotPositive {
            variable: self.name.clone(),
            distribution: self.distribution.kind(),
            reason,
        })
    }

    /// This variable scaled by a deterministic factor c > 0 (a drift factor, see
    /// [`crate::drift`]): c·X has mean cμ and std cσ, so its coefficient of variation and its
    /// standard normal variable z are unchanged — states scaled this way share one u-space.
    pub fn scaled(&self, factor: f64) -> Result<Self> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(Error::InvalidParameter {
                variable: self.name.clone(),
                field: "scale factor",
                value: factor,
                allowed: "a scale factor must be finite and > 0",
            });
        }
        Ok(Self {
            name: self.name.clone(),
            distribution: self.distribution.scaled(factor),
            positive: self.positive,
        })
    }
}
