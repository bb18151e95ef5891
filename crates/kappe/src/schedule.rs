//! The print schedule: when every layer starts and ends, and so the age of every layer in every
//! state (green-state.md §3).
//!
//! Layer k (print index, 0 = first) prints from `start[k]` to `end[k]`; after it the printer
//! pauses `wait[k]` (chosen) plus `relocation[k]` (a station change of the mobile robot before
//! layer k + 1) plus the layer change itself, so
//! `start[k+1] = end[k] + wait[k] + relocation[k] + change[k]`. A state is "n layers complete" and is checked at the moment layer n − 1 is
//! completed (its weakest moment: the load is all there and the top has age 0); the age of layer
//! k there is `end[n−1] − end[k]`. A wait therefore adds to the age of every layer below it in
//! every later state.

use serde::{Deserialize, Serialize};

use crate::error::DesignError;

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

/// One layer of a schedule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LayerTime {
    /// Print index (0 = first).
    pub layer: usize,
    /// Start of printing, s.
    pub start_s: f64,
    /// End of printing, s.
    pub end_s: f64,
    /// Chosen wait after the layer, s.
    pub wait_s: f64,
    /// Station change after the layer, s.
    pub relocation_s: f64,
}

/// Where the layer times came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeSource {
    /// Path length / print speed (no robot plan).
    PathLength,
    /// The timed robot plan.
    RobotPlan,
    /// A constant layer time.
    LayerTime,
}

/// The whole schedule.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Schedule {
    /// Per layer, in print order.
    pub layers: Vec<LayerTime>,
    /// Where the print times came from.
    pub source: TimeSource,
}

impl Schedule {
    /// From per-layer print durations, waits, station changes and layer-change moves (all s,
    /// one per layer; missing entries are 0).
    pub fn new(
        durations: &[f64],
        waits: &[f64],
        relocations: &[f64],
        changes: &[f64],
        source: TimeSource,
    ) -> Result<Schedule, DesignError> {
        let get = |v: &[f64], k: usize| v.get(k).copied().unwrap_or(0.0);
        let mut t = 0.0;
        let mut layers = Vec::with_capacity(durations.len());
        for (k, &d) in durations.iter().enumerate() {
            if !(d.is_finite() && d >= 0.0) {
                return Err(DesignError::Invalid {
                    field: "schedule.layer_time",
                    value: format!("{d} at layer {k}"),
                    allowed: "allowed: finite layer times ≥ 0 s".into(),
                });
            }
            let (w, r) = (get(waits, k), get(relocations, k));
            layers.push(LayerTime {
                layer: k,
                start_s: t,
                end_s: t + d,
                wait_s: w,
                relocation_s: r,
            });
            t += d + w + r + get(changes, k);
        }
        Ok(Schedule { layers, source })
    }

    /// Constant layer time for `n` layers.
    pub fn uniform(n: usize, layer_time: f64, waits: &[f64]) -> Result<Schedule, DesignError> {
        Schedule::new(&vec![layer_time; n], waits, &[], &[], TimeSource::LayerTime)
    }

    /// Age of layers 0..n at the state "n layers complete", s (empty for n = 0).
    pub fn ages(&self, n: usize) -> Vec<f64> {
        let n = n.min(self.layers.len());
        let Some(top) = n.checked_sub(1).and_then(|t| self.layers.get(t)) else {
            return Vec::new();
        };
        self.layers[..n]
            .iter()
            .map(|l| top.end_s - l.end_s)
            .collect()
    }

    /// End of the last layer, s.
    pub fn total_s(&self) -> f64 {
        self.layers.last().map_or(0.0, |l| l.end_s)
    }

    /// Sum of the chosen waits, s.
    pub fn total_wait_s(&self) -> f64 {
        self.layers.iter().map(|l| l.wait_s).sum()
    }

    /// `schedule.csv`: `layer,start_s,end_s,wait_s,relocation_s`.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("layer,start_s,end_s,wait_s,relocation_s\n");
        for l in &self.layers {
            s.push_str(&format!(
                "{},{:.3},{:.3},{:.3},{:.3}\n",
                l.layer, l.start_s, l.end_s, l.wait_s, l.relocation_s
            ));
        }
        s
    }
}
