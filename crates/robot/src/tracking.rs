//! Tolerance of a moving-base print: a simulation of the controller's conveyor tracking
//! ([`crate::conveyor`]) under the base's real motion errors, giving the nozzle-to-path
//! deviation envelope per layer (issue 27).
//!
//! **Model.** Per program part, tracking starts at plan time `t₀` with the base standing at
//! travel `S` (the handshake). With a planned travel `s(t)` the base really travels
//!
//! ```text
//! s_true(t) = S + a(S₀) + o·(S − S₀) + (1 + e)·(s(t) − S)              (t ≥ t₀)
//! ```
//!
//! — `a(S₀)` is the along-bay localisation error where the print starts (the base is localised
//! once, there), `o` the odometry's scale error (at each program change the base positions
//! itself at the next part's start by odometry from that anchor, not by re-localising: a new
//! localisation would shift every part by a different `a`, a seam of up to 2 × 9.9 mm between
//! two layers, which an earlier version of this simulation showed), `e` its speed error while it
//! drives a part (the three cases −e, 0, +e are simulated). It also drifts across the bay by `c(s)` and turns by
//! `ψ(s)` (localisation and path following; linear tracking cannot compensate either). The
//! controller sees the travel as encoder ticks: the odometry's travel since `t₀`, updated at
//! `tick_rate_hz`, late by `lag`, counted in whole ticks:
//!
//! ```text
//! m(t) = ⌊(s_true(t − lag − 1/rate) − s_true(t₀)) · tpm⌋ / tpm       (worst phase of the update)
//! ```
//!
//! and commands the target `B_S⁻¹·p(t) + m(t)·direction` in its base frame (`direction =
//! −R₀ᵀd`), where `p(t)` is the world target moving along the print move at the planned speed.
//! The nozzle is then at `B_true(t)·(…)` with `B_true = T(start + d·s_true + x̂·c)·R₀·Rz(ψ)`, and
//! the deviation is that minus `p(t)`: exact rigid-body composition, no linearisation. With no
//! errors it is zero (a unit test checks this to 1e-9 m).
//!
//! **Errors as functions of travel.** `a`, `c` and `ψ` are smooth random functions of the base's
//! travel (a creeping base's localisation error depends on where it is: markers, map), each a
//! sum of 8 sinusoids with wavelengths in `[L/2, 4L]` (`L = correlation_length`) and seeded
//! phases, scaled so that the mean |error| is `localisation_mean` (a Gaussian's mean |x| is
//! σ·√(2/π)) and clipped at `localisation_max` (yaw: σ = `yaw_max_deg`/3, clipped at it).
//!
//! **Defaults** from the issue's anchors: NTU (Tiryaki, Zhang & Pham, IROS 2019) measured base
//! segment errors of ≈ 2.2 mm mean and ≈ 9.9 mm max with floor markers and a Kalman filter →
//! `localisation_mean` 2.2 mm, `localisation_max` 9.9 mm. The rest are assumptions, stated as
//! such: speed error ±5 %, odometry scale error 0.2 %, lag 50 ms, odometry at 100 Hz,
//! 10 000 ticks/m, yaw ±0.1°, correlation length 0.5 m.
//!
//! **What is reported per layer:** the largest |deviation| (and where), its components across
//! the shell (`w = t × axis`, the bead's width direction; adds to the overhang) and along the
//! tool axis (the layer height; bead contact), and the same components *relative to the layer
//! below* (deviation at a target minus the deviation at the nearest target of the previous
//! layer), which is what changes a layer's overhang over the one below and the contact between
//! them. **Tolerance** ([`TrackingTolerance`]): |deviation| ≤ `max_deviation` (default 20 mm,
//! assumption: the geometric tolerance accepted for the vault), the relative across-shell shift
//! ≤ lw/4 (a quarter of the bead width: at least 3/4 of the bead stays on the one below) and the
//! relative shift along the axis ≤ lh/4 (the layer height within ±25 %), lw and lh from the
//! plan's bead (2·bead_radius, 2·bead_offset). The base's offset from its planned travel must
//! also stay within the plan's reach margin.

use parry3d_f64::glamx::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::RobotError;
use crate::frames::Iso;
use crate::moving::MovingPlan;

/// The base's motion errors (module docs for the sources of the defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackingErrors {
    /// Encoder ticks per metre of travel (> 0). Default 10 000.
    pub ticks_per_meter: f64,
    /// Rate (Hz) at which the base updates the travel it feeds as ticks (> 0). Default 100.
    pub tick_rate_hz: f64,
    /// Delay (s) from the base's travel to the ticks the controller counts (≥ 0). Default 0.05.
    pub lag: f64,
    /// Relative speed error of the base (≥ 0; simulated as −e, 0, +e). Default 0.05.
    pub speed_error: f64,
    /// Relative scale error of the base's odometry (≥ 0), by which it positions itself at each
    /// program's start. Default 0.002.
    pub odometry_error: f64,
    /// Mean |localisation error| along and across the bay (m, ≥ 0). Default 0.0022.
    pub localisation_mean: f64,
    /// Largest localisation error (m, ≥ mean). Default 0.0099.
    pub localisation_max: f64,
    /// Largest heading error (deg, ≥ 0). Default 0.1.
    pub yaw_max_deg: f64,
    /// Correlation length of the errors along the travel (m, > 0). Default 0.5.
    pub correlation_length: f64,
    /// Seed of the error functions.
    pub seed: u64,
    /// Points simulated per print move besides its end (≥ 0). Default 3.
    pub samples_per_move: usize,
}

impl Default for TrackingErrors {
    fn default() -> Self {
        TrackingErrors {
            ticks_per_meter: 10_000.0,
            tick_rate_hz: 100.0,
            lag: 0.05,
            speed_error: 0.05,
            odometry_error: 0.002,
            localisation_mean: 0.0022,
            localisation_max: 0.0099,
            yaw_max_deg: 0.1,
            correlation_length: 0.5,
            seed: 27,
            samples_per_move: 3,
        }
    }
}

impl TrackingErrors {
    /// No error at all (and no lag, a tick rate of 1 MHz, 10⁹ ticks/m): the simulated nozzle is
    /// on the path.
    pub fn none() -> Self {
        TrackingErrors {
            ticks_per_meter: 1e9,
            tick_rate_hz: 1e6,
            lag: 0.0,
            speed_error: 0.0,
            odometry_error: 0.0,
            localisation_mean: 0.0,
            localisation_max: 0.0,
            yaw_max_deg: 0.0,
            ..TrackingErrors::default()
        }
    }

    fn validate(&self) -> Result<(), RobotError> {
        let check = |name: &str, v: f64, positive: bool| {
            let ok = v.is_finite() && if positive { v > 0.0 } else { v >= 0.0 };
            if ok {
                Ok(())
            } else {
                Err(RobotError::invalid(
                    format!("tracking.{name}"),
                    format!(
                        "{v}: must be finite and {}",
                        if positive { "> 0" } else { "≥ 0" }
                    ),
                ))
            }
        };
        check("ticks_per_meter", self.ticks_per_meter, true)?;
        check("tick_rate_hz", self.tick_rate_hz, true)?;
        check("correlation_length", self.correlation_length, true)?;
        check("lag", self.lag, false)?;
        check("speed_error", self.speed_error, false)?;
        check("odometry_error", self.odometry_error, false)?;
        check("localisation_mean", self.localisation_mean, false)?;
        check("localisation_max", self.localisation_max, false)?;
        check("yaw_max_deg", self.yaw_max_deg, false)?;
        if self.localisation_max < self.localisation_mean {
            return Err(RobotError::invalid(
                "tracking.localisation_max",
                format!(
                    "{} m is below the mean {} m",
                    self.localisation_max, self.localisation_mean
                ),
            ));
        }
        Ok(())
    }
}

/// What the nozzle must keep (module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackingTolerance {
    /// Largest |nozzle − path| (m). Default 0.02.
    pub max_deviation: f64,
    /// Largest shift across the shell relative to the layer below (m); `None` = lw/4.
    pub relative_across: Option<f64>,
    /// Largest shift along the tool axis relative to the layer below (m); `None` = lh/4.
    pub relative_axial: Option<f64>,
}

impl Default for TrackingTolerance {
    fn default() -> Self {
        TrackingTolerance {
            max_deviation: 0.02,
            relative_across: None,
            relative_axial: None,
        }
    }
}

/// The deviation envelope of one layer (all speed-error cases).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LayerDeviation {
    pub layer: i64,
    /// Largest |deviation| (m), at point `index` (the move arriving there), plan time `t`.
    pub max_deviation: f64,
    pub index: usize,
    pub t: f64,
    /// Largest |component| across the shell and along the tool axis (m).
    pub max_across: f64,
    pub max_axial: f64,
    /// The same relative to the layer below (m; 0 for the first layer).
    pub max_relative_across: f64,
    pub max_relative_axial: f64,
}

/// The result of [`simulate_tracking`]; the nozzle keeps the tolerance when `problems` is empty.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TrackingReport {
    pub errors: TrackingErrors,
    /// The tolerance with lw/4 and lh/4 resolved.
    pub max_deviation_allowed: f64,
    pub relative_across_allowed: f64,
    pub relative_axial_allowed: f64,
    pub layers: Vec<LayerDeviation>,
    /// The largest deviation (m) and where: layer, point index, plan time.
    pub max_deviation: f64,
    pub at: (i64, usize, f64),
    pub max_relative_across: f64,
    pub max_relative_axial: f64,
    /// Largest distance of the base from its planned pose (m), against the plan's reach margin.
    pub max_base_offset: f64,
    pub reach_margin: Option<f64>,
    /// Configurations simulated.
    pub samples: usize,
    pub problems: Vec<String>,
}

/// A smooth random function of travel (module docs).
struct Field {
    waves: Vec<(f64, f64, f64)>,
    max: f64,
}

impl Field {
    fn new(rng: &mut ChaCha8Rng, sigma: f64, max: f64, length: f64) -> Field {
        let k = 8;
        // The RMS of k sinusoids of amplitude A is A·√(k/2).
        let amp = sigma * (2.0 / k as f64).sqrt();
        let waves = (0..k)
            .map(|_| {
                let lambda = length * 2f64.powf(rng.random_range(-1.0..2.0));
                let phase = rng.random_range(0.0..std::f64::consts::TAU);
                (amp, std::f64::consts::TAU / lambda, phase)
            })
            .collect();
        Field { waves, max }
    }

    fn at(&self, s: f64) -> f64 {
        let v: f64 = self
            .waves
            .iter()
            .map(|(a, w, p)| a * (w * s + p).sin())
            .sum();
        v.clamp(-self.max, self.max)
    }
}

/// Simulate the controller's tracking of `mp` under `errors` (module docs).
pub fn simulate_tracking(
    mp: &MovingPlan,
    errors: &TrackingErrors,
    tol: &TrackingTolerance,
) -> Result<TrackingReport, RobotError> {
    errors.validate()?;
    mp.validate_shape()?;
    if !(tol.max_deviation.is_finite() && tol.max_deviation > 0.0) {
        return Err(RobotError::invalid(
            "tracking.max_deviation",
            format!("{}: must be finite and > 0", tol.max_deviation),
        ));
    }
    let plan = &mp.plan;
    let o = &plan.options;
    let across_allowed = tol.relative_across.unwrap_or(0.5 * o.bead_radius);
    let axial_allowed = tol.relative_axial.unwrap_or(0.5 * o.bead_offset.abs());
    let st = plan
        .stations
        .first()
        .ok_or_else(|| RobotError::invalid("plan", "no station"))?;
    let start = Iso::from_mat4(&st.world_from_base)
        .map_err(|e| RobotError::invalid("world_from_base", e))?;
    let d = DVec3::from(mp.trajectory.direction);
    let lateral = DVec3::Z.cross(d).normalize_or_zero();
    let dir_b = -(start.r.transpose() * d);
    let mut rng = ChaCha8Rng::seed_from_u64(errors.seed);
    // σ from the mean |error| of a Gaussian: E|x| = σ·√(2/π).
    let sigma = errors.localisation_mean * (std::f64::consts::PI / 2.0).sqrt();
    let along = Field::new(
        &mut rng,
        sigma,
        errors.localisation_max,
        errors.correlation_length,
    );
    let across = Field::new(
        &mut rng,
        sigma,
        errors.localisation_max,
        errors.correlation_length,
    );
    let yaw_max = errors.yaw_max_deg.to_radians();
    let yaw = Field::new(&mut rng, yaw_max / 3.0, yaw_max, errors.correlation_length);
    let tpm = errors.ticks_per_meter;
    let stale = errors.lag + 1.0 / errors.tick_rate_hz;

    let mut rep = TrackingReport {
        errors: errors.clone(),
        max_deviation_allowed: tol.max_deviation,
        relative_across_allowed: across_allowed,
        relative_axial_allowed: axial_allowed,
        reach_margin: mp.reach_margin,
        ..Default::default()
    };
    // Arrival deviations per layer slot and waypoint, per case, for the relative shifts.
    let cases = [-errors.speed_error, 0.0, errors.speed_error];
    let n_layers = st.layers.len();
    let mut arrive: Vec<Vec<[DVec3; 3]>> = st
        .layers
        .iter()
        .map(|l| vec![[DVec3::ZERO; 3]; l.waypoints.len()])
        .collect();
    let mut layer_rep: Vec<LayerDeviation> = st
        .layers
        .iter()
        .map(|l| LayerDeviation {
            layer: l.layer,
            ..Default::default()
        })
        .collect();
    for part in &plan.parts {
        // Where tracking starts: after the first target's hold (starting) or the previous
        // layer's last (continuing).
        let (li0, k0) = if part.starts_station {
            (part.first, 0usize)
        } else {
            let li = part.first - 1;
            (li, st.layers[li].waypoints.len() - 1)
        };
        let w0 = &st.layers[li0].waypoints[k0];
        let t0 = w0.t + w0.hold;
        let s_start = mp.travel[li0][k0];
        let s_first = mp
            .travel
            .first()
            .and_then(|l| l.first())
            .copied()
            .unwrap_or(0.0);
        let anchor = along.at(s_first) + errors.odometry_error * (s_start - s_first);
        let s_plan = |t: f64| mp.trajectory.sample_at(t).travel;
        let b_s = Iso::new(start.r, start.t + d * s_start);
        let s_from_world = b_s.inverse();
        // Moves of the part: (layer slot, index) in print order, each with its predecessor.
        let mut prev: (usize, usize) = (li0, k0);
        for li in part.first..=part.last {
            for k in 0..st.layers[li].waypoints.len() {
                if (li, k) == (li0, k0) {
                    continue;
                }
                let a = &st.layers[prev.0].waypoints[prev.1];
                let b = &st.layers[li].waypoints[k];
                let pa = DVec3::from(a.position);
                let pb = DVec3::from(b.position);
                let ta = a.t + a.hold;
                let tangent = (pb - pa).normalize_or_zero();
                let axis = DVec3::from(b.axis);
                let w = tangent.cross(axis).normalize_or_zero();
                let n_s = errors.samples_per_move + 1;
                for (ci, &e) in cases.iter().enumerate() {
                    let s_true = |t: f64| {
                        let sp = if t <= t0 { s_start } else { s_plan(t) };
                        s_start + anchor + (1.0 + e) * (sp - s_start)
                    };
                    for i in 1..=n_s {
                        let u = i as f64 / n_s as f64;
                        let t = ta + u * (b.t - ta);
                        let p = pa + u * (pb - pa);
                        let st_now = s_true(t);
                        let m = ((s_true((t - stale).max(t0)) - s_true(t0)) * tpm).floor() / tpm;
                        let cmd = s_from_world.point(p) + dir_b * m;
                        let b_true = Iso::new(
                            start.r * Iso::rot_z(yaw.at(st_now)).r,
                            start.t + d * st_now + lateral * across.at(st_now),
                        );
                        let dev = b_true.point(cmd) - p;
                        rep.samples += 1;
                        let off = (st_now - s_plan(t)).abs() + across.at(st_now).abs();
                        rep.max_base_offset = rep.max_base_offset.max(off);
                        let lr = &mut layer_rep[li];
                        let len = dev.length();
                        if len > lr.max_deviation {
                            lr.max_deviation = len;
                            lr.index = b.index;
                            lr.t = t;
                        }
                        lr.max_across = lr.max_across.max(dev.dot(w).abs());
                        lr.max_axial = lr.max_axial.max(dev.dot(axis).abs());
                        if i == n_s {
                            arrive[li][k][ci] = dev;
                        }
                    }
                }
                prev = (li, k);
            }
        }
        // The tracked start point itself (the base stands still: only the anchoring error).
        for (ci, _) in cases.iter().enumerate() {
            let p = DVec3::from(w0.position);
            let b_true = Iso::new(
                start.r * Iso::rot_z(yaw.at(s_start)).r,
                start.t + d * (s_start + anchor) + lateral * across.at(s_start),
            );
            arrive[li0][k0][ci] = b_true.point(s_from_world.point(p)) - p;
        }
    }
    // Relative shifts against the nearest target of the layer below.
    for li in 1..n_layers {
        let below = &st.layers[li - 1].waypoints;
        for (k, wp) in st.layers[li].waypoints.iter().enumerate() {
            let p = DVec3::from(wp.position);
            let Some((kb, _)) = below
                .iter()
                .enumerate()
                .map(|(j, x)| (j, (DVec3::from(x.position) - p).length_squared()))
                .min_by(|x, y| x.1.total_cmp(&y.1))
            else {
                continue;
            };
            let pts = &st.layers[li].waypoints;
            let tangent = {
                let a = DVec3::from(pts[k.saturating_sub(1)].position);
                let b = DVec3::from(pts[(k + 1).min(pts.len() - 1)].position);
                (b - a).normalize_or_zero()
            };
            let axis = DVec3::from(wp.axis);
            let w = tangent.cross(axis).normalize_or_zero();
            for ci in 0..cases.len() {
                let rel = arrive[li][k][ci] - arrive[li - 1][kb][ci];
                let lr = &mut layer_rep[li];
                lr.max_relative_across = lr.max_relative_across.max(rel.dot(w).abs());
                lr.max_relative_axial = lr.max_relative_axial.max(rel.dot(axis).abs());
            }
        }
    }
    for lr in &layer_rep {
        if lr.max_deviation > rep.max_deviation {
            rep.max_deviation = lr.max_deviation;
            rep.at = (lr.layer, lr.index, lr.t);
        }
        rep.max_relative_across = rep.max_relative_across.max(lr.max_relative_across);
        rep.max_relative_axial = rep.max_relative_axial.max(lr.max_relative_axial);
    }
    if rep.max_deviation > tol.max_deviation {
        rep.problems.push(format!(
            "the nozzle leaves its path by {:.4} m (layer {}, point {}, t = {:.1} s), more than {} m",
            rep.max_deviation, rep.at.0, rep.at.1, rep.at.2, tol.max_deviation
        ));
    }
    for lr in &layer_rep {
        if lr.max_relative_across > across_allowed || lr.max_relative_axial > axial_allowed {
            rep.problems.push(format!(
                "layer {}: shifted against the layer below by {:.4} m across the shell (≤ {across_allowed}) and {:.4} m along the tool axis (≤ {axial_allowed})",
                lr.layer, lr.max_relative_across, lr.max_relative_axial
            ));
        }
    }
    if let Some(m) = mp.reach_margin
        && rep.max_base_offset > m
    {
        rep.problems.push(format!(
            "the base strays {:.4} m from its planned pose, more than the plan's reach margin {m:.3} m",
            rep.max_base_offset
        ));
    }
    crate::error::shorten(&mut rep.problems, 20);
    rep.layers = layer_rep;
    Ok(rep)
}
