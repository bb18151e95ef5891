//! The mobile base's time-stamped pose trajectory (issue 27): what a ROS navigation stack or the
//! RB-Vogui's own controller follows while the arm prints.
//!
//! **Frame and units.** World frame of the design (x across the span, y along the bay, z up;
//! method.md §1), metres, radians, seconds. A sample is the pose of the *robot base* (UR DH
//! frame 0, the controller's Base feature) projected on the floor: `base_x`, `base_y` and the
//! heading `base_yaw` of the base x axis from world x (counter-clockwise). The height of the
//! base above the world origin is fixed (`z`, in the JSON). A ROS stack that follows `base_link`
//! of the platform applies its fixed mount transform (`base_link` → arm base) once.
//!
//! **Time law.** `t` is the plan's clock ([`crate::plan::Plan::total_time`] and every waypoint's
//! `t`). Between samples the base moves at constant speed along the straight line between them
//! (linear interpolation of x, y; the yaw is constant along a moving-base plan), so the travel
//! s(t) is piecewise linear and non-decreasing; the base holds (two samples with the same pose)
//! wherever the arm holds (approach, priming, program changes, layer waits). Speeds
//! `v_k = Δs_k/Δt_k` and accelerations `|v_{k+1} − v_k| / τ_k`, `τ_k = (Δt_k + Δt_{k+1})/2`, are
//! the same row-based quantities [`crate::timing`] bounds for the joints.
//!
//! **Files.** CSV `t,base_x,base_y,base_yaw` (one row per sample, shortest round-trip numbers);
//! JSON `{"frame": "world", "units": {...}, "z": .., "samples": [{"t","base_x","base_y",
//! "base_yaw","travel"}], "summary": {...}}`.

use serde::{Deserialize, Serialize};

use crate::frames::Iso;

/// One sample of the base trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BaseSample {
    /// Plan time (s).
    pub t: f64,
    /// Base position in the world (m).
    pub base_x: f64,
    pub base_y: f64,
    /// Heading of the base x axis from world x (rad, counter-clockwise, in (−π, π]).
    pub base_yaw: f64,
    /// Distance travelled along the bay axis since the plan's base pose at travel 0 (m).
    pub travel: f64,
}

/// Summary of a base trajectory (`summary.json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BaseSummary {
    /// Samples.
    pub samples: usize,
    /// First and last sample time (s).
    pub start: f64,
    pub end: f64,
    /// Total travel (m).
    pub travel: f64,
    /// Largest speed and acceleration over the rows (m/s, m/s²).
    pub max_speed: f64,
    pub max_acceleration: f64,
    /// Mean speed while the arm prints (travel / time not holding), m/s.
    pub mean_moving_speed: f64,
    /// Time the base holds still (s).
    pub hold_time: f64,
}

/// A time-stamped base trajectory (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BaseTrajectory {
    /// Height of the robot base in the world (m).
    pub z: f64,
    /// Unit travel direction in the world (along the bay axis).
    pub direction: [f64; 3],
    /// Samples in time order (t non-decreasing).
    pub samples: Vec<BaseSample>,
}

impl BaseTrajectory {
    /// The base pose at time `t` (clamped to the first and last sample): x, y linearly
    /// interpolated between the samples around `t`, the yaw of the earlier sample (constant on a
    /// moving-base plan).
    pub fn pose_at(&self, t: f64) -> Iso {
        let s = self.sample_at(t);
        Iso::translation(s.base_x, s.base_y, self.z).mul(&Iso::rot_z(s.base_yaw))
    }

    /// The interpolated sample at time `t` (clamped).
    pub fn sample_at(&self, t: f64) -> BaseSample {
        let n = self.samples.len();
        let Some(first) = self.samples.first() else {
            return BaseSample {
                t,
                base_x: 0.0,
                base_y: 0.0,
                base_yaw: 0.0,
                travel: 0.0,
            };
        };
        if t <= first.t || n == 1 {
            return *first;
        }
        // Last sample with time ≤ t.
        let k = self.samples.partition_point(|s| s.t <= t).saturating_sub(1);
        let a = self.samples[k];
        let Some(b) = self.samples.get(k + 1) else {
            return a;
        };
        let dt = b.t - a.t;
        let u = if dt > 0.0 { (t - a.t) / dt } else { 0.0 };
        BaseSample {
            t,
            base_x: a.base_x + u * (b.base_x - a.base_x),
            base_y: a.base_y + u * (b.base_y - a.base_y),
            base_yaw: a.base_yaw,
            travel: a.travel + u * (b.travel - a.travel),
        }
    }

    /// Speeds of the rows' segments (m/s; 0 for a zero-length segment).
    pub fn speeds(&self) -> Vec<f64> {
        self.samples
            .windows(2)
            .map(|w| {
                let dt = w[1].t - w[0].t;
                if dt > 0.0 {
                    (w[1].travel - w[0].travel).abs() / dt
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Accelerations at the rows between segments, `|v_{k+1} − v_k| / τ_k` (m/s²), with the base
    /// at rest before the first and after the last sample (module docs).
    pub fn accelerations(&self) -> Vec<f64> {
        let v = self.speeds();
        let d: Vec<f64> = self.samples.windows(2).map(|w| w[1].t - w[0].t).collect();
        let mut out = Vec::with_capacity(v.len() + 1);
        // Rest → first segment and last segment → rest: τ is half the segment.
        if let (Some(&v0), Some(&d0)) = (v.first(), d.first())
            && d0 > 0.0
        {
            out.push(v0 / (0.5 * d0));
        }
        for k in 0..v.len().saturating_sub(1) {
            let tau = 0.5 * (d[k] + d[k + 1]);
            if tau > 0.0 {
                out.push((v[k + 1] - v[k]).abs() / tau);
            }
        }
        if let (Some(&vn), Some(&dn)) = (v.last(), d.last())
            && dn > 0.0
        {
            out.push(vn / (0.5 * dn));
        }
        out
    }

    /// Summary numbers.
    pub fn summary(&self) -> BaseSummary {
        let v = self.speeds();
        let mut hold = 0.0;
        let mut moving = 0.0;
        for (w, &sp) in self.samples.windows(2).zip(&v) {
            let dt = w[1].t - w[0].t;
            if sp > 0.0 {
                moving += dt;
            } else {
                hold += dt;
            }
        }
        let travel = match (self.samples.first(), self.samples.last()) {
            (Some(a), Some(b)) => b.travel - a.travel,
            _ => 0.0,
        };
        BaseSummary {
            samples: self.samples.len(),
            start: self.samples.first().map_or(0.0, |s| s.t),
            end: self.samples.last().map_or(0.0, |s| s.t),
            travel,
            max_speed: v.iter().copied().fold(0.0, f64::max),
            max_acceleration: self.accelerations().into_iter().fold(0.0, f64::max),
            mean_moving_speed: if moving > 0.0 { travel / moving } else { 0.0 },
            hold_time: hold,
        }
    }

    /// `base_trajectory.csv`: `t,base_x,base_y,base_yaw` (world frame, s, m, rad).
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t,base_x,base_y,base_yaw\n");
        for p in &self.samples {
            s.push_str(&format!(
                "{},{},{},{}\n",
                p.t, p.base_x, p.base_y, p.base_yaw
            ));
        }
        s
    }

    /// The JSON form: frame, units, height, direction, samples (with the travel) and summary.
    pub fn to_json(&self) -> String {
        let v = serde_json::json!({
            "frame": "world (x across the span, y along the bay, z up); pose of the UR base (DH frame 0) on the floor",
            "units": {"t": "s", "base_x": "m", "base_y": "m", "base_yaw": "rad", "travel": "m", "z": "m"},
            "z": self.z,
            "direction": self.direction,
            "samples": self.samples,
            "summary": self.summary(),
        });
        serde_json::to_string_pretty(&v).unwrap_or_else(|_| "{}".into())
    }

    /// Read `base_trajectory.csv` back (header `t,base_x,base_y,base_yaw`); the travel is
    /// measured along the path from the first sample.
    pub fn from_csv(text: &str, z: f64) -> Result<BaseTrajectory, String> {
        let mut lines = text.lines();
        match lines.next() {
            Some("t,base_x,base_y,base_yaw") => {}
            other => {
                return Err(format!(
                    "header {other:?}: expected \"t,base_x,base_y,base_yaw\""
                ));
            }
        }
        let mut samples: Vec<BaseSample> = Vec::new();
        for (i, l) in lines.enumerate() {
            if l.trim().is_empty() {
                continue;
            }
            let v: Result<Vec<f64>, _> = l.split(',').map(str::parse::<f64>).collect();
            let v = v.map_err(|e| format!("row {}: {e}", i + 2))?;
            let [t, x, y, yaw] = v[..] else {
                return Err(format!("row {}: {} values, expected 4", i + 2, v.len()));
            };
            let travel = samples.last().map_or(0.0, |p| {
                p.travel + ((x - p.base_x).powi(2) + (y - p.base_y).powi(2)).sqrt()
            });
            samples.push(BaseSample {
                t,
                base_x: x,
                base_y: y,
                base_yaw: yaw,
                travel,
            });
        }
        Ok(BaseTrajectory {
            z,
            direction: [0.0, 1.0, 0.0],
            samples,
        })
    }
}
