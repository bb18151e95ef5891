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

use serde::Serialize;

use crate::input::error::DesignError;
pub use crate::input::schedule::{DEFAULT_RELOCATION_TIME, ScheduleSpec};

/// One layer of a schedule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize, schemars::JsonSchema)]
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
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize, schemars::JsonSchema,
)]
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
    /// Print duration of each layer, s (kept so ages are sums of durations, not differences of
    /// clock times: bit-for-bit the sums the analysis used before the schedule existed).
    #[serde(skip)]
    durations: Vec<f64>,
    /// Pause after each layer (wait + relocation + layer change), s.
    #[serde(skip)]
    gaps: Vec<f64>,
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
        let mut gaps = Vec::with_capacity(durations.len());
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
            let gap = w + r + get(changes, k);
            gaps.push(gap);
            t += d + gap;
        }
        Ok(Schedule {
            layers,
            source,
            durations: durations.to_vec(),
            gaps,
        })
    }

    /// Constant layer time for `n` layers.
    pub fn uniform(n: usize, layer_time: f64, waits: &[f64]) -> Result<Schedule, DesignError> {
        Schedule::new(&vec![layer_time; n], waits, &[], &[], TimeSource::LayerTime)
    }

    /// Age of layers 0..n at the state "n layers complete", s (empty for n = 0): summed from
    /// the top down, age[k] = Σ_{j=k+1}^{n−1} (gap[j−1] + duration[j]).
    pub fn ages(&self, n: usize) -> Vec<f64> {
        let n = n.min(self.durations.len());
        let mut ages = vec![0.0; n];
        let mut t = 0.0;
        for k in (0..n).rev() {
            if let Some(a) = ages.get_mut(k) {
                *a = t;
            }
            let d = self.durations.get(k).copied().unwrap_or(0.0);
            let gap = k
                .checked_sub(1)
                .and_then(|j| self.gaps.get(j))
                .copied()
                .unwrap_or(0.0);
            // A zero gap is skipped rather than added, so a schedule without waits gives the
            // bit-identical sums of the durations.
            t += d;
            if gap != 0.0 {
                t += gap;
            }
        }
        ages
    }

    /// Replace the chosen waits (one per layer; missing entries 0) and recompute the clock.
    pub fn with_waits(&self, waits: &[f64]) -> Result<Schedule, DesignError> {
        let relocations: Vec<f64> = self.layers.iter().map(|l| l.relocation_s).collect();
        let changes: Vec<f64> = self
            .layers
            .iter()
            .zip(&self.gaps)
            .map(|(l, g)| g - l.wait_s - l.relocation_s)
            .collect();
        Schedule::new(&self.durations, waits, &relocations, &changes, self.source)
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

/// The schedule of a cap without a robot plan: layer k prints for its path length / print speed,
/// then waits `[schedule]` waits. Station changes are not known before the robot is planned and
/// are left out, which is conservative: every pause only adds to the ages of the layers below
/// it, and the timed robot never prints faster than the design speed.
pub fn cap_schedule(cap: &crate::form::cap::Cap) -> Result<Schedule, DesignError> {
    let speed = cap.design.print.print_speed;
    let durations: Vec<f64> = cap
        .sections
        .layers
        .iter()
        .map(|l| l.length() / speed)
        .collect();
    let waits = cap.design.schedule.waits(durations.len())?;
    Schedule::new(&durations, &waits, &[], &[], TimeSource::PathLength)
}

/// The schedule of a timed robot plan (`kappe_robot::timing::layer_times`): each layer's start
/// and end on the plan's clock, its scheduled wait, and the rest of the pause after it (program
/// change, re-priming, station change) as relocation.
pub fn from_robot(times: &[kappe_robot::timing::LayerTime]) -> Result<Schedule, DesignError> {
    let durations: Vec<f64> = times.iter().map(|t| t.end - t.start).collect();
    let waits: Vec<f64> = times.iter().map(|t| t.wait).collect();
    let rest: Vec<f64> = times
        .windows(2)
        .map(|w| (w[1].start - w[0].end - w[0].wait).max(0.0))
        .collect();
    let mut s = Schedule::new(&durations, &waits, &rest, &[], TimeSource::RobotPlan)?;
    for (l, t) in s.layers.iter_mut().zip(times) {
        l.start_s = t.start;
        l.end_s = t.end;
    }
    Ok(s)
}
