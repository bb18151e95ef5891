//! Drift in print time: a parameter whose mean changes as the mix dries or a new batch starts.
//!
//! A drift is a deterministic factor c(t) > 0 of the print time t (hours since the print
//! started). A state printed at time t uses the variable X(t) = c(t)·X, with X the base variable:
//! its mean and standard deviation both scale by c(t) (the coefficient of variation stays), so
//! for every distribution the standard normal variable z of X(t) is that of X. This is a plain
//! function the caller applies per state ([`Drift::factor`], then [`crate::RandomVariable::scaled`] or
//! [`crate::Model::scaled`]); all states then share one u-space, so their FORM components can be
//! combined in one series system.
//!
//! c(t) = (1 + r·t/100) · ∏_{steps with tₖ ≤ t} cₖ
//!
//! with r the linear drift in % of the base value per hour (not compounded: −2 %/h gives 0.9
//! after 5 h) and each step (tₖ, cₖ) multiplying from time tₖ on (a new batch at tₖ whose
//! stiffness is cₖ times the first one's).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// A step of the drift factor at a print time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriftStep {
    /// Print time of the step, h.
    pub at_hours: f64,
    /// Factor from `at_hours` on (> 0).
    pub factor: f64,
}

/// A drift of a parameter's mean over print time; see the module docs.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Drift {
    /// Linear change in % of the base value per hour (negative: decreasing).
    pub percent_per_hour: f64,
    /// Steps (new batches), in any order.
    pub steps: Vec<DriftStep>,
}

impl Drift {
    /// No drift: c(t) = 1.
    pub fn none() -> Self {
        Self::default()
    }

    /// A linear drift of r %/h.
    pub fn linear(percent_per_hour: f64) -> Self {
        Self {
            percent_per_hour,
            steps: Vec::new(),
        }
    }

    /// A step to `factor` at `at_hours`.
    pub fn step(at_hours: f64, factor: f64) -> Self {
        Self {
            percent_per_hour: 0.0,
            steps: vec![DriftStep { at_hours, factor }],
        }
    }

    /// The factor c(t) at print time t (h); an error when it is not finite and > 0.
    pub fn factor(&self, t_hours: f64) -> Result<f64> {
        let mut c = 1.0 + self.percent_per_hour * t_hours / 100.0;
        for s in &self.steps {
            if s.at_hours <= t_hours {
                c *= s.factor;
            }
        }
        if c.is_finite() && c > 0.0 {
            Ok(c)
        } else {
            Err(Error::DriftFactorNotPositive {
                t_hours,
                factor: c,
                percent_per_hour: self.percent_per_hour,
                zero_at_hours: if self.percent_per_hour < 0.0 {
                    -100.0 / self.percent_per_hour
                } else {
                    f64::INFINITY
                },
            })
        }
    }
}
