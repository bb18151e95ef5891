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

/// Utilisation the report shows for a state that is a mechanism (BLF 0): larger than any
/// real one, finite so the page's JSON can carry it.
pub const MECHANISM_UTILISATION: f64 = f64::MAX;

/// The schedule, which check governs every state and the layer ages at the governing state(s),
/// for the report (issue 11). Utilisation = demand / capacity per check: BLF_min/BLF
/// (analysed states), strength and sliding (with a strength model), stress (the larger of
/// σ_min,state/σ_min and σ_max,state/σ_max) and overhang (largest |l_o| so far / l_o,max). The
/// ages are shown at the worst state of every age-dependent constraint (`blf_min`, `strength`,
/// `sliding`).
pub fn report_schedule(
    cap: &crate::form::cap::Cap,
    analysis: Option<&crate::analysis::Analysis>,
    schedule: &Schedule,
) -> kappe_report::PrintSchedule {
    let layer_id = |k: usize| cap.sections.layers.get(k).map_or(k as i32, |l| l.id);
    let layers = schedule
        .layers
        .iter()
        .map(|l| kappe_report::ScheduleRow {
            layer: layer_id(l.layer),
            start: l.start_s,
            end: l.end_s,
            wait: l.wait_s,
            pause: l.relocation_s,
        })
        .collect();
    let d = &cap.design;
    let (smin_lim, smax_lim, blf_min, lo_max) = (
        d.constraints.sigma_min,
        d.constraints.sigma_max,
        d.constraints.blf_min,
        d.overhang_max(),
    );
    let ratio = |v: f64, limit: f64| {
        if limit != 0.0 {
            (v / limit).max(0.0)
        } else if v != 0.0 {
            MECHANISM_UTILISATION
        } else {
            0.0
        }
    };
    let mut states = Vec::new();
    let mut ages = Vec::new();
    if let Some(a) = analysis {
        for s in &a.states {
            let mut checks = Vec::new();
            match s.buckling {
                crate::analysis::BucklingStatus::Analysed => {
                    if let Some(f) = s.blf {
                        let u = if f > 0.0 {
                            blf_min / f
                        } else {
                            MECHANISM_UTILISATION
                        };
                        checks.push(("buckling".to_string(), u));
                    }
                }
                crate::analysis::BucklingStatus::Mechanism => {
                    checks.push(("buckling".to_string(), MECHANISM_UTILISATION));
                }
                _ => {}
            }
            if let Some(u) = s.strength_utilisation {
                checks.push(("strength".to_string(), u));
            }
            if let Some(u) = s.sliding_utilisation {
                checks.push(("sliding".to_string(), u));
            }
            let stress = ratio(s.max_compression_stress_pa.min(0.0), smin_lim.min(0.0))
                .max(ratio(s.max_tension_stress_pa.max(0.0), smax_lim.max(0.0)));
            checks.push(("stress".to_string(), stress));
            checks.push(("overhang".to_string(), ratio(s.max_overhang_m, lo_max)));
            states.push(kappe_report::StateGoverning {
                state: s.index,
                checks,
            });
        }
        for (name, why) in [
            ("blf_min", "lowest BLF"),
            ("strength", "worst strength"),
            ("sliding", "worst sliding"),
        ] {
            let Some(q) = a
                .constraints
                .iter()
                .find(|c| c.name == name)
                .and_then(|c| c.state)
            else {
                continue;
            };
            if let Some(e) = ages
                .iter_mut()
                .find(|e: &&mut kappe_report::StateAges| e.state == q)
            {
                e.why.push_str(", ");
                e.why.push_str(why);
                continue;
            }
            ages.push(kappe_report::StateAges {
                state: q,
                why: why.to_string(),
                ages: schedule
                    .ages(q + 1)
                    .into_iter()
                    .enumerate()
                    .map(|(k, t)| (layer_id(k), t))
                    .collect(),
            });
        }
    }
    kappe_report::PrintSchedule {
        source: match schedule.source {
            TimeSource::RobotPlan => {
                "robot plan's clock (print moves, layer changes, dwell, station changes, waits)"
            }
            TimeSource::PathLength => {
                "path length / print speed and the [schedule] waits (no robot plan)"
            }
            TimeSource::LayerTime => "constant layer time",
        }
        .to_string(),
        layers,
        states,
        ages,
    }
}
