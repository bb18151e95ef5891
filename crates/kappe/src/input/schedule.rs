//! The `[schedule]` table of a design: the waits the designer asks for after each layer and the
//! time of a station change. Plain data, checked; the clock that turns them into layer ages is
//! [`crate::schedule`].

use serde::{Deserialize, Serialize};

use crate::input::error::DesignError;

/// The `[schedule]` table of a design (and of a buildability spec's `[process]`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleSpec {
    /// Wait after every layer, s (added to `waits`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wait: Option<f64>,
    /// Wait after each layer in print order, s: empty, or one entry per layer (the last one,
    /// after the final layer, does not matter and may be left out).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub waits: Vec<f64>,
    /// Time of one station change of the mobile robot, s (default 60 s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relocation_time: Option<f64>,
}

/// Default station-change time, s (choice: the mobile base drives a metre and re-localises).
pub const DEFAULT_RELOCATION_TIME: f64 = 60.0;

impl ScheduleSpec {
    /// Nothing set (the table is left out when a design is written back).
    pub fn is_empty(&self) -> bool {
        self == &ScheduleSpec::default()
    }

    /// The wait after each of `layers` layers, checked: finite, ≥ 0, and a list that covers the
    /// print.
    pub fn waits(&self, layers: usize) -> Result<Vec<f64>, DesignError> {
        let w0 = self.wait.unwrap_or(0.0);
        if !(w0.is_finite() && w0 >= 0.0) {
            return Err(DesignError::Invalid {
                field: "schedule.wait",
                value: w0.to_string(),
                allowed: "allowed: a finite wait ≥ 0 s".into(),
            });
        }
        if !self.waits.is_empty() && self.waits.len() != layers && self.waits.len() + 1 != layers {
            return Err(DesignError::Invalid {
                field: "schedule.waits",
                value: format!("{} entries", self.waits.len()),
                allowed: format!(
                    "allowed: none, or one wait per layer of the print ({layers}, or {} without \
                     the one after the final layer); a schedule shorter or longer than the print \
                     is ambiguous",
                    layers.saturating_sub(1)
                ),
            });
        }
        let mut out = vec![w0; layers];
        for (k, &w) in self.waits.iter().enumerate() {
            if !(w.is_finite() && w >= 0.0) {
                return Err(DesignError::Invalid {
                    field: "schedule.waits",
                    value: format!("{w} at layer {k}"),
                    allowed: "allowed: finite waits ≥ 0 s".into(),
                });
            }
            if let Some(o) = out.get_mut(k) {
                *o += w;
            }
        }
        Ok(out)
    }

    /// The station-change time, checked.
    pub fn relocation_time(&self) -> Result<f64, DesignError> {
        let r = self.relocation_time.unwrap_or(DEFAULT_RELOCATION_TIME);
        if r.is_finite() && r >= 0.0 {
            Ok(r)
        } else {
            Err(DesignError::Invalid {
                field: "schedule.relocation_time",
                value: r.to_string(),
                allowed: "allowed: a finite time ≥ 0 s".into(),
            })
        }
    }
}
