//! Printing while the base moves (issue 27): one continuous print along the whole bay, the
//! mobile base creeping along the beams while the arm prints each arch.
//!
//! **Base path.** A straight line along the bay axis at a fixed lateral position `x`, height `z`
//! and yaw `yaw_deg` (default x = 0, yaw 270°, z = 0: the pose family of the station search,
//! [`crate::setup::BaseSearch`]). The axis is world +y, the direction in which the printing front
//! advances (method.md §1), or −y when the front advances that way (the mirrored half of a
//! `both_walls` bay): then every along-bay position is taken as −y and the heading is reflected
//! to −yaw_deg, as the mirrored station search does. Only the along-bay position moves, which is what UR's linear
//! conveyor tracking compensates ([`crate::conveyor`]).
//!
//! **Base position tied to path progress.** Let `f_o` be the printing front of layer o: the mean
//! y of its targets, made non-decreasing by a running maximum (the base never backs up). Within
//! layer o the base moves from `f_o` to `f_{o+1}` in proportion to the arc length printed
//! (the printed layer change to the next layer's first target included):
//!
//! ```text
//! y_base(o, k) = lead + f_o + (f_{o+1} − f_o) · c_k / L_o      (f_n := f_{n−1})
//! ```
//!
//! with `c_k` the arc length from the layer's first target to target k and `L_o` the layer's
//! length plus the layer change. The base pose is thus a function of path progress, fixed
//! before the joints are searched, so the ladder graph keeps one rung per target (the joint
//! search is exactly the station planner's, with each rung's IK solved from its own base pose),
//! and the time law s(t) is the arm's clock ([`crate::timing`]): the base holds exactly when the
//! arm holds and moves at `v_base = v_tcp · (f_{o+1} − f_o)/L_o` while it prints, ≈ 0.4 mm/s for
//! the default cap (8.8 mm of front advance per ≈ 1 m arch at 50 mm/s). The nozzle's world speed
//! is the design speed on every print move by construction: the targets are world points, the
//! timing sets each move's duration from their world distance, and the arm's own TCP velocity is
//! the world velocity minus the base velocity (reported as [`MovingCheck::max_arm_tcp_speed`]).
//!
//! **Search: the lead.** Tying the base to the front keeps the arm's geometry relative to its
//! base nearly the same for every layer, so one scalar decides feasibility: the lead, the
//! distance of the base ahead of the front. Candidates on a grid (`lead_range`, `lead_step`) are
//! scored on a sample of the print (`score_layers` layers spread over it, every `score_stride`-th
//! target and each layer's last): a lead is feasible when every sampled target has a valid
//! configuration (the planner's own acceptance: limits, singularity margins, self-collision,
//! clearance to beams, floor and printed layers) and the base body clears the beams at every
//! sampled layer's start (the grid is scanned every 5th lead and each
//! feasibility boundary bisected, `coarse_to_fine`). Among the feasible leads the one farthest
//! (in grid steps) from any infeasible lead is taken: its **reach margin**, how far the base may be
//! off along the bay before a sampled target becomes unreachable, is `(m − 1)·lead_step` for
//! m steps to the nearest infeasible lead (the boundary lies somewhere in the last step).
//! This trades nothing against base speed: the base speed is the front's, set by the print, and
//! the margin is maximised at that speed. A ladder graph over (base pose, progress) would let
//! the base stop and jump between leads, i.e. stations again; one lead is what a creeping base
//! wants. The best leads are then planned in full (at most 4, in order of margin) and the first
//! whose full ladder succeeds is kept.
//!
//! **Collision.** Every rung's vertices are filtered as the station planner's (beams, floor and
//! printed layers in the world, the arm and tool in the robot base frame), and additionally
//! against the mobile-base body in the base frame (it moves with the base, so its clearance to
//! the arm depends on the joints only). The body against the static obstacles and the print is
//! checked at base poses every `body_check_step` of travel.
//!
//! Sources: the RB-Vogui XL's drive (robot.md §5: omnidirectional, 4 steered wheels). No
//! published creep-speed or acceleration limits were found; the defaults below are assumptions, far above what a creeping base needs (< 1 mm/s) and far below the platform's
//! driving speed, so they only catch a path the base cannot follow.

use parry3d_f64::glamx::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::base_trajectory::{BaseSample, BaseTrajectory};
use crate::collision::Scene;
use crate::error::{FailureKind, PlanFailure, RobotError};
use crate::frames::{Iso, angle_between};
use crate::kinematics::{Joints, UR10E, within_limits};
use crate::ladder::LadderFailure;
use crate::plan::{CLEARANCE_CUTOFF, LayerPlan, Plan, Station, Waypoint, plan_layers};
use crate::planner::{
    Context, Rejections, Vertex, WindUp, solve_rungs, summarise, unwrap_path, validate,
};
use crate::setup::{PlanOptions, PrintLayer, RobotSetup};
use crate::timing::LayerWait;

/// How the base takes part in the print: stations (print, stop, drive, re-localise) or moving
/// while printing. The design spec's `[robot.setup] base = "moving"` maps to
/// [`BaseMode::Moving`] with the defaults of [`MovingBase`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case")]
pub enum BaseMode {
    /// Today's plan: [`crate::plan_print`] with [`crate::setup::BasePlacement`].
    #[default]
    Stations,
    /// [`plan_moving`].
    Moving(MovingBase),
}

/// Settings of a moving base (module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MovingBase {
    /// Largest base speed while printing (m/s, > 0). Default 0.1 (assumption: a guided creep
    /// beside fresh work, as [`crate::stations::DriveSpec`]; the RB-Vogui XL drives far faster).
    pub speed_max: f64,
    /// Largest base acceleration (m/s², > 0). Default 0.1 (assumption; Robotnik publishes none).
    pub accel_max: f64,
    /// Lateral position of the robot base (m, world x). Default 0: the cap's centre line.
    pub x: f64,
    /// Height of the robot base (m, world z). Default 0 (top plate 0.70 m above the floor).
    pub z: f64,
    /// Heading of the base x axis from world x (deg). Default 270 (facing the print).
    pub yaw_deg: f64,
    /// A fixed lead (m) of the base ahead of the printing front; `None` searches it.
    pub lead: Option<f64>,
    /// Lead candidates: range (m) and step (m). Default 0.3–1.6 m in 0.02 m steps (the station
    /// search's y range, 0.6–0.8 m beyond the print, widened on both sides).
    pub lead_range: [f64; 2],
    pub lead_step: f64,
    /// Layers sampled to score a lead (spread evenly, first and last included; ≥ 1).
    pub score_layers: usize,
    /// Every n-th target of a sampled layer (and its last) is scored (≥ 1).
    pub score_stride: usize,
    /// Smallest acceptable reach margin along the bay (m). Default 0.02 m: twice the largest
    /// base segment error of the anchor (9.9 mm, Tiryaki et al., IROS 2019).
    pub min_reach_margin: f64,
    /// Travel step (m) at which the base body is checked against the obstacles. Default 0.01.
    pub body_check_step: f64,
}

impl Default for MovingBase {
    fn default() -> Self {
        MovingBase {
            speed_max: 0.1,
            accel_max: 0.1,
            x: 0.0,
            z: 0.0,
            yaw_deg: 270.0,
            lead: None,
            lead_range: [0.3, 1.6],
            lead_step: 0.02,
            score_layers: 40,
            score_stride: 5,
            min_reach_margin: 0.02,
            body_check_step: 0.01,
        }
    }
}

impl MovingBase {
    /// Check the settings; the error names the field (`moving.<field>`) and what is allowed.
    pub fn validate(&self) -> Result<(), RobotError> {
        let positive = |name: &str, v: f64, unit: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(RobotError::invalid(
                    format!("moving.{name}"),
                    format!("{v} {unit}: must be finite and > 0"),
                ))
            }
        };
        positive("speed_max", self.speed_max, "m/s")?;
        positive("accel_max", self.accel_max, "m/s²")?;
        positive("lead_step", self.lead_step, "m")?;
        positive("body_check_step", self.body_check_step, "m")?;
        for (name, v) in [
            ("x", self.x),
            ("z", self.z),
            ("yaw_deg", self.yaw_deg),
            ("min_reach_margin", self.min_reach_margin),
        ] {
            if !v.is_finite() {
                return Err(RobotError::invalid(
                    format!("moving.{name}"),
                    format!("{v}: must be finite"),
                ));
            }
        }
        if self.min_reach_margin < 0.0 {
            return Err(RobotError::invalid(
                "moving.min_reach_margin",
                format!("{} m: must be ≥ 0", self.min_reach_margin),
            ));
        }
        let [lo, hi] = self.lead_range;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(RobotError::invalid(
                "moving.lead_range",
                format!("{:?} m: need finite lo ≤ hi", self.lead_range),
            ));
        }
        if let Some(l) = self.lead
            && !l.is_finite()
        {
            return Err(RobotError::invalid(
                "moving.lead",
                format!("{l} m: must be finite"),
            ));
        }
        if self.score_layers == 0 || self.score_stride == 0 {
            return Err(RobotError::invalid(
                "moving.score_layers / moving.score_stride",
                format!(
                    "{} / {}: both must be ≥ 1",
                    self.score_layers, self.score_stride
                ),
            ));
        }
        Ok(())
    }

    /// The base pose at along-bay position `y`.
    pub fn pose_at(&self, y: f64) -> Iso {
        Iso::translation(self.x, y, self.z).mul(&Iso::rot_z(self.yaw_deg.to_radians()))
    }
}

/// A plan whose base moves while the arm prints.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MovingPlan {
    /// The arm's plan on the one clock: one station whose `world_from_base` is the base pose at
    /// travel 0 (the first target's); waypoints, times, parts, slowdowns as for stations.
    pub plan: Plan,
    /// The settings used, with the lead resolved (and the heading reflected for a front that
    /// advances along −y).
    pub base: MovingBase,
    /// Lead of the base ahead of the printing front (m).
    pub lead: f64,
    /// Along-bay reach margin of the chosen lead (m, module docs); `None` for a given lead.
    pub reach_margin: Option<f64>,
    /// Per layer (plan order), per waypoint: base travel from the pose at travel 0 (m).
    pub travel: Vec<Vec<f64>>,
    /// The time-stamped base trajectory.
    pub trajectory: BaseTrajectory,
    /// The independent check of the plan.
    pub check: MovingCheck,
}

impl MovingPlan {
    /// Check the plan's shape (it may come from a file): one station, a travel per waypoint,
    /// program parts inside the layers, a non-empty time-ordered finite base trajectory. The
    /// error names the field.
    pub fn validate_shape(&self) -> Result<(), RobotError> {
        let bad = |field: &str, m: String| Err(RobotError::invalid(field, m));
        let [st] = self.plan.stations.as_slice() else {
            return bad(
                "plan.stations",
                format!(
                    "a moving plan has exactly one station, found {}",
                    self.plan.stations.len()
                ),
            );
        };
        if st.layers.is_empty() || st.layers.iter().any(|l| l.waypoints.is_empty()) {
            return bad("plan.stations[0].layers", "an empty layer or none".into());
        }
        if self.travel.len() != st.layers.len()
            || self
                .travel
                .iter()
                .zip(&st.layers)
                .any(|(t, l)| t.len() != l.waypoints.len() || t.iter().any(|v| !v.is_finite()))
        {
            return bad(
                "travel",
                "needs one finite travel per waypoint of every layer".into(),
            );
        }
        for (i, p) in self.plan.parts.iter().enumerate() {
            if p.station != 0 || p.first > p.last || p.last >= st.layers.len() {
                return bad(
                    &format!("plan.parts[{i}]"),
                    format!(
                        "station {} layers {}..={}: must be station 0 and inside its {} layers",
                        p.station,
                        p.first,
                        p.last,
                        st.layers.len()
                    ),
                );
            }
        }
        let s = &self.trajectory.samples;
        let finite = s.iter().all(|x| {
            [x.t, x.base_x, x.base_y, x.base_yaw, x.travel]
                .iter()
                .all(|v| v.is_finite())
        });
        if s.is_empty() || !finite || s.windows(2).any(|w| w[1].t < w[0].t) {
            return bad(
                "trajectory.samples",
                "needs at least one sample, finite values and non-decreasing times".into(),
            );
        }
        Ok(())
    }

    /// The base pose (world) at waypoint `k` of layer slot `li`.
    pub fn base_pose(&self, li: usize, k: usize) -> Iso {
        let s = self
            .travel
            .get(li)
            .and_then(|l| l.get(k))
            .copied()
            .unwrap_or(0.0);
        let start = Iso::from_mat4_unchecked(&self.plan.stations[0].world_from_base);
        let d = DVec3::from(self.trajectory.direction);
        Iso::new(start.r, start.t + d * s)
    }

    /// `trajectory.csv` with the base pose at every row: `station,layer,index,t,q1..q6,v_tool,
    /// flow,base_x,base_y,base_yaw` (world, m, rad), rows as [`crate::write_trajectory_csv`].
    pub fn trajectory_csv(&self) -> String {
        let plan = &self.plan;
        let mut out = String::from(
            "station,layer,index,t,q1,q2,q3,q4,q5,q6,v_tool,flow,base_x,base_y,base_yaw\n",
        );
        let pump = &plan.options.pump;
        let pause = match pump.pause {
            crate::setup::PauseMode::KeepPrimed => pump.hold(),
            crate::setup::PauseMode::Stop => 0.0,
        };
        let all: Vec<(usize, i64, usize, &Waypoint)> = plan.stations[0]
            .layers
            .iter()
            .enumerate()
            .flat_map(|(li, l)| {
                l.waypoints
                    .iter()
                    .enumerate()
                    .map(move |(k, w)| (li, l.layer, k, w))
            })
            .collect();
        for (n, &(li, layer, k, p)) in all.iter().enumerate() {
            let (f_arrive, f_hold) = if n == 0 {
                let v1 = all.get(1).map_or(plan.options.print_speed, |w| w.3.speed);
                (0.0, crate::program::flow_output(plan, v1))
            } else {
                (crate::program::flow_output(plan, p.speed), pause)
            };
            let b = self.base_pose(li, k);
            let yaw = b.r.x_axis.y.atan2(b.r.x_axis.x);
            let row = |t: f64, v: f64, f: f64| {
                let q: Vec<String> = p.q.iter().map(|x| x.to_string()).collect();
                format!(
                    "0,{layer},{},{t},{},{v},{f},{},{},{yaw}\n",
                    p.index,
                    q.join(","),
                    b.t.x,
                    b.t.y
                )
            };
            out.push_str(&row(p.t, p.speed, f_arrive));
            if p.hold > 0.0 {
                out.push_str(&row(p.t + p.hold, 0.0, f_hold));
            }
        }
        out
    }
}

/// The independent check of a moving plan ([`check_moving`]); valid when `problems` is empty.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MovingCheck {
    pub waypoints: usize,
    /// Largest |world_from_base(t)·FK(q)·tool − target| (m) and tool-axis angle (rad), with the
    /// base pose read from the time-stamped trajectory at the waypoint's time.
    pub max_position_error: f64,
    pub max_axis_error: f64,
    /// Certified smallest clearance to the environment along every print move (base and arm
    /// moving together; m, capped at 0.5) and at the waypoints.
    pub certified_clearance: f64,
    /// Smallest self distance at the waypoints (m).
    pub min_self_distance: f64,
    /// Largest Σ Δq² between consecutive waypoints (rad²; ≤ ε).
    pub max_step: f64,
    /// Largest base speed (m/s) and acceleration (m/s²) over the trajectory rows.
    pub max_base_speed: f64,
    pub max_base_acceleration: f64,
    /// Largest |world nozzle speed / planned speed − 1| over the print moves.
    pub max_tcp_speed_error: f64,
    /// Largest speed of the TCP relative to the arm base (m/s): world velocity − base velocity.
    pub max_arm_tcp_speed: f64,
    pub problems: Vec<String>,
}

/// Along-bay front position per layer (mean y, running max) and per-waypoint progress offsets
/// `f_o + (f_{o+1} − f_o)·c_k/L_o` (module docs).
fn front_offsets(layers: &[PrintLayer], sign: f64) -> Vec<Vec<f64>> {
    let mut front: Vec<f64> = Vec::with_capacity(layers.len());
    for l in layers {
        let m = sign * l.points.iter().map(|p| p.position[1]).sum::<f64>() / l.points.len() as f64;
        let f = front.last().map_or(m, |&prev: &f64| prev.max(m));
        front.push(f);
    }
    let n = layers.len();
    let mut out = Vec::with_capacity(n);
    for (o, l) in layers.iter().enumerate() {
        let f0 = front[o];
        let f1 = front.get(o + 1).copied().unwrap_or(f0);
        let pts: Vec<DVec3> = l.points.iter().map(|p| DVec3::from(p.position)).collect();
        let mut c = vec![0.0; pts.len()];
        for k in 1..pts.len() {
            c[k] = c[k - 1] + (pts[k] - pts[k - 1]).length();
        }
        let change = layers
            .get(o + 1)
            .and_then(|nl| nl.points.first())
            .zip(pts.last())
            .map_or(0.0, |(p, last)| (DVec3::from(p.position) - *last).length());
        let len = c.last().copied().unwrap_or(0.0) + change;
        out.push(
            c.iter()
                .map(|ck| {
                    if len > 0.0 {
                        f0 + (f1 - f0) * ck / len
                    } else {
                        f0
                    }
                })
                .collect(),
        );
    }
    out
}

/// +1 when the printing front advances along +y (the last layer's mean y ≥ the first's), else −1.
fn front_sign(layers: &[PrintLayer]) -> f64 {
    let mean = |l: &PrintLayer| {
        l.points.iter().map(|p| p.position[1]).sum::<f64>() / l.points.len().max(1) as f64
    };
    match (layers.first(), layers.last()) {
        (Some(a), Some(b)) if mean(b) < mean(a) => -1.0,
        _ => 1.0,
    }
}

/// World geometry shared by the rungs: the context without the mobile-base body (the body moves
/// with the base and is checked in the base frame), its world scene, and the body in the base
/// frame.
pub(crate) struct Geometry {
    /// The plan's context without the mobile base's body (the world's obstacles only).
    pub(crate) world: Context,
    /// The world's obstacles (beams, floor, printed layers).
    pub(crate) scene: Scene,
    /// The mobile base's body in the base frame (it moves with the arm).
    pub(crate) body: Option<Scene>,
}

impl Geometry {
    pub(crate) fn new(ctx: &Context) -> Result<Geometry, RobotError> {
        let mut setup = ctx.setup.clone();
        setup.mobile_base.clear();
        let world = validate(&ctx.layers, &setup, &ctx.opts)?;
        let scene = world.scene(&Iso::IDENTITY)?;
        let boxes: Vec<_> = ctx
            .setup
            .mobile_base
            .iter()
            .map(|b| b.to_world(&Iso::IDENTITY))
            .collect();
        let body = if boxes.is_empty() {
            None
        } else {
            Some(Scene::new(&boxes)?)
        };
        Ok(Geometry { world, scene, body })
    }

    /// Clearance of the arm and tool (environment model) to the body, in the base frame.
    fn body_clearance(&self, q: &Joints, cutoff: f64) -> f64 {
        match &self.body {
            None => cutoff,
            Some(b) => {
                let posed = self.world.env_model.pose(q, &Iso::IDENTITY);
                b.clearance(posed.as_slice(), 0, cutoff).distance
            }
        }
    }

    /// Valid vertices of target (o, k) from base pose `w`.
    fn vertices(&self, w: &Iso, o: usize, k: usize) -> (Vec<Vertex>, Rejections) {
        let frame = self.world.target_frame(&self.world.layers[o], k);
        let (mut v, mut rej) = self.world.vertices(&self.scene, &w.inverse(), w, &frame, o);
        let need = self.world.opts.clearance;
        v.retain_mut(|x| {
            let c = self.body_clearance(&x.q, CLEARANCE_CUTOFF);
            if c < need {
                rej.collision += 1;
                if rej.collision_example.is_none() {
                    rej.collision_example = Some((0, "mobile_base".into(), c));
                }
                return false;
            }
            x.clearance = x.clearance.min(c);
            true
        });
        (v, rej)
    }

    /// Whether target (o, k) has a valid vertex from `w`.
    fn reachable(&self, w: &Iso, o: usize, k: usize) -> bool {
        let frame = self.world.target_frame(&self.world.layers[o], k);
        if self.body.is_none() {
            return self
                .world
                .has_vertex(&self.scene, &w.inverse(), w, &frame, o);
        }
        !self.vertices(w, o, k).0.is_empty()
    }
}

/// Plan the print with a moving base (module docs); `waits` as in
/// [`crate::plan_print_with_waits`]. The result is checked by [`check_moving`] and refused if
/// the check fails.
pub fn plan_moving(
    layers: &[PrintLayer],
    setup: &RobotSetup,
    opts: &PlanOptions,
    base: &MovingBase,
    waits: Option<&[LayerWait]>,
) -> Result<MovingPlan, RobotError> {
    base.validate()?;
    let ctx = validate(layers, setup, opts)?;
    let geo = Geometry::new(&ctx)?;
    // A front advancing along −y (a mirrored bay) is the mirror image: positions along the bay
    // are measured as u = sign·y and the heading is reflected.
    let sign = front_sign(&ctx.layers);
    let eff = MovingBase {
        yaw_deg: sign * base.yaw_deg,
        ..base.clone()
    };
    let base = &eff;
    let offsets = front_offsets(&ctx.layers, sign);
    let leads: Vec<(f64, Option<f64>)> = match base.lead {
        Some(l) => vec![(l, None)],
        None => search_leads(&geo, &|w| ctx.check_base(w).is_ok(), &offsets, base, sign)?,
    };
    let mut last_err: Option<RobotError> = None;
    for &(lead, margin) in leads.iter().take(4) {
        match plan_with_lead(&ctx, &geo, (&offsets, sign), base, lead, margin, waits) {
            Ok(p) => return Ok(p),
            Err(e) => last_err = Some(e),
        }
    }
    Err(last_err
        .unwrap_or_else(|| RobotError::invalid("moving.lead_range", "no lead candidate to plan")))
}

/// The feasible leads, best reach margin first: (lead, margin).
fn search_leads(
    geo: &Geometry,
    body_ok: &(dyn Fn(&Iso) -> bool + Sync),
    offsets: &[Vec<f64>],
    base: &MovingBase,
    sign: f64,
) -> Result<Vec<(f64, Option<f64>)>, RobotError> {
    let [lo, hi] = base.lead_range;
    let n = (((hi - lo) / base.lead_step).floor() as usize).min(2000);
    let cands: Vec<f64> = (0..=n).map(|i| lo + i as f64 * base.lead_step).collect();
    let nl = geo.world.layers.len();
    let ns = base.score_layers.min(nl);
    let mut sample_layers: Vec<usize> = (0..ns)
        .map(|i| if ns == 1 { 0 } else { i * (nl - 1) / (ns - 1) })
        .collect();
    sample_layers.dedup();
    let samples: Vec<(usize, usize)> = sample_layers
        .iter()
        .flat_map(|&o| {
            let len = geo.world.layers[o].points.len();
            (0..len)
                .filter(move |k| k % base.score_stride == 0 || k + 1 == len)
                .map(move |k| (o, k))
        })
        .collect();
    // The body against the beams and the print at every sampled layer's start, then the targets.
    let eval = |lead: f64| {
        sample_layers
            .iter()
            .all(|&o| body_ok(&base.pose_at(sign * (lead + offsets[o][0]))))
            && samples
                .iter()
                .all(|&(o, k)| geo.reachable(&base.pose_at(sign * (lead + offsets[o][k])), o, k))
    };
    let feasible = coarse_to_fine(cands.len(), COARSE, &|i| eval(cands[i]));
    // Grid steps to the nearest infeasible lead (the grid's ends count as infeasible beyond).
    let m = cands.len();
    let steps: Vec<usize> = (0..m)
        .map(|i| {
            if !feasible[i] {
                return 0;
            }
            let up = (i..m).find(|&j| !feasible[j]).map_or(m - i, |j| j - i);
            let down = (0..=i)
                .rev()
                .find(|&j| !feasible[j])
                .map_or(i + 1, |j| i - j);
            up.min(down)
        })
        .collect();
    let mut order: Vec<usize> = (0..m).filter(|&i| feasible[i]).collect();
    order.sort_by(|&a, &b| steps[b].cmp(&steps[a]).then(a.cmp(&b)));
    let Some(&best) = order.first() else {
        return Err(RobotError::Unplannable(Box::new(PlanFailure {
            station: 0,
            layer: geo.world.layers[0].layer,
            index: geo.world.layers[0].points[0].index,
            kind: FailureKind::BasePlacement,
            detail: format!(
                "no lead of the moving base in {:?} m (step {} m) reaches every sampled target with the base body clear of the beams and the print (a body wider than the span cannot drive between the beams)",
                base.lead_range, base.lead_step
            ),
        })));
    };
    let margin = |i: usize| (steps[i].saturating_sub(1)) as f64 * base.lead_step;
    if margin(best) < base.min_reach_margin {
        return Err(RobotError::invalid(
            "moving.min_reach_margin",
            format!(
                "the best lead {:.3} m leaves a reach margin of {:.3} m along the bay, less than the required {} m (lower it, or widen lead_range {:?})",
                cands[best],
                margin(best),
                base.min_reach_margin,
                base.lead_range
            ),
        ));
    }
    Ok(order
        .into_iter()
        .filter(|&i| margin(i) >= base.min_reach_margin)
        .map(|i| (cands[i], Some(margin(i))))
        .collect())
}

/// Coarse grid stride of the lead search.
const COARSE: usize = 5;

/// Feasibility of grid points `0..m`, evaluating every `coarse`-th point (and the last) and then
/// bisecting each boundary between a feasible and an infeasible coarse point down to one grid
/// step. Points between two feasible coarse points are taken as feasible: a pocket narrower than
/// `coarse` steps inside a feasible run would be missed, which can only make a reach margin
/// optimistic (the full ladder over every target still decides the plan), and it cuts the
/// expensive evaluations (feasible leads run through every sample) about `coarse`-fold.
fn coarse_to_fine(m: usize, coarse: usize, eval: &(dyn Fn(usize) -> bool + Sync)) -> Vec<bool> {
    if m == 0 {
        return Vec::new();
    }
    let mut idx: Vec<usize> = (0..m).step_by(coarse.max(1)).collect();
    if idx.last() != Some(&(m - 1)) {
        idx.push(m - 1);
    }
    let ok: Vec<bool> = idx.par_iter().map(|&i| eval(i)).collect();
    let mut out = vec![false; m];
    for w in 0..idx.len() {
        if ok[w] {
            out[idx[w]] = true;
        }
        let Some(&next) = idx.get(w + 1) else { break };
        let (a, b) = (idx[w], next);
        match (ok[w], ok[w + 1]) {
            (true, true) => out[a..=b].iter_mut().for_each(|v| *v = true),
            (false, false) => {}
            (fa, _) => {
                // One boundary in (a, b): bisect for the last point on a's side.
                let (mut lo, mut hi) = (a, b);
                while hi - lo > 1 {
                    let mid = lo + (hi - lo) / 2;
                    if eval(mid) == fa {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                if fa {
                    out[a..=lo].iter_mut().for_each(|v| *v = true);
                } else {
                    out[hi..=b].iter_mut().for_each(|v| *v = true);
                }
            }
        }
    }
    out
}

/// `along`: the per-target front offsets and the direction sign (u = sign·y).
fn plan_with_lead(
    ctx: &Context,
    geo: &Geometry,
    along: (&[Vec<f64>], f64),
    base: &MovingBase,
    lead: f64,
    margin: Option<f64>,
    waits: Option<&[LayerWait]>,
) -> Result<MovingPlan, RobotError> {
    let (offsets, sign) = along;
    let fail = |o: usize, k: usize, kind: FailureKind, detail: String| {
        RobotError::Unplannable(Box::new(PlanFailure {
            station: 0,
            layer: ctx.layers[o].layer,
            index: ctx.layers[o].points[k].index,
            kind,
            detail,
        }))
    };
    let y0 = lead + offsets[0][0];
    let start = base.pose_at(sign * y0);
    // The body along the base path (every body_check_step of travel and at both ends).
    let y1 = lead
        + offsets
            .last()
            .and_then(|l| l.last())
            .copied()
            .unwrap_or(0.0);
    let nb = ((y1 - y0) / base.body_check_step).ceil().max(0.0) as usize;
    for i in 0..=nb {
        let y = (y0 + i as f64 * base.body_check_step).min(y1);
        if let Err(e) = ctx.check_base(&base.pose_at(sign * y)) {
            return Err(fail(
                0,
                0,
                FailureKind::BasePlacement,
                format!(
                    "base at y = {:.3} m (travel {:.3} m): {e}",
                    sign * y,
                    y - y0
                ),
            ));
        }
    }
    let rung_ids: Vec<(usize, usize)> = (0..ctx.layers.len())
        .flat_map(|o| (0..ctx.layers[o].points.len()).map(move |k| (o, k)))
        .collect();
    let built: Vec<(Vec<Vertex>, Rejections)> = rung_ids
        .par_iter()
        .map(|&(o, k)| geo.vertices(&base.pose_at(sign * (lead + offsets[o][k])), o, k))
        .collect();
    let n_cost = if ctx.coaxial { 5 } else { 6 };
    let result = solve_rungs(ctx, &rung_ids, &built, ctx.opts.seed);
    let path = match result {
        Ok(p) => p,
        Err(LadderFailure::EmptyRung { rung }) => {
            let (o, k) = rung_ids[rung];
            let (kind, detail) = built[rung].1.failure();
            return Err(fail(
                o,
                k,
                kind,
                format!("moving base, lead {lead:.3} m: {detail}"),
            ));
        }
        Err(LadderFailure::NoEdge { rung }) => {
            let (o, k) = rung_ids[rung];
            return Err(fail(
                o,
                k,
                FailureKind::NoCompatibleNeighbour,
                format!(
                    "moving base, lead {lead:.3} m: {} valid configurations here, {} at the previous target, none within ε = {} and the joint speeds at {} m/s",
                    built[rung].0.len(),
                    built[rung - 1].0.len(),
                    ctx.opts.epsilon,
                    ctx.opts.print_speed
                ),
            ));
        }
    };
    // Unwrap (elbow raw) and one 2π offset per joint, as the station planner.
    let (q, clear) = match unwrap_path(ctx, &built, &path) {
        Ok(p) => p,
        Err(WindUp { joint: j, lo, hi }) => {
            return Err(fail(
                0,
                0,
                FailureKind::WindUp,
                format!(
                    "joint {} travels from {lo:.3} to {hi:.3} rad over the whole print, more than its range",
                    j + 1
                ),
            ));
        }
    };
    let mut layers_out = Vec::with_capacity(ctx.layers.len());
    let mut travel = Vec::with_capacity(ctx.layers.len());
    let mut r = 0;
    for (o, layer) in ctx.layers.iter().enumerate() {
        let mut wps = Vec::with_capacity(layer.points.len());
        let mut tr = Vec::with_capacity(layer.points.len());
        let (mut cost, mut min_c) = (0.0, f64::INFINITY);
        for (k, p) in layer.points.iter().enumerate() {
            if k > 0 {
                cost += (0..n_cost)
                    .map(|j| (q[r][j] - q[r - 1][j]).powi(2))
                    .sum::<f64>();
            }
            min_c = min_c.min(clear[r]);
            wps.push(Waypoint {
                index: p.index,
                t: 0.0,
                q: q[r],
                position: p.position,
                axis: p.axis,
                speed: 0.0,
                hold: 0.0,
            });
            tr.push(lead + offsets[o][k] - y0);
            r += 1;
        }
        layers_out.push(LayerPlan::untimed(layer.layer, wps, cost, min_c));
        travel.push(tr);
    }
    let station = Station {
        world_from_base: start.to_mat4(),
        layers: layers_out,
    };
    let mut plan = summarise(ctx, vec![station]);
    plan.parts = crate::program::split_parts(&plan)?;
    crate::timing::apply_timing(&mut plan, waits)?;
    let resolved = MovingBase {
        lead: Some(lead),
        ..base.clone()
    };
    let mut mp = MovingPlan {
        trajectory: base_trajectory(&plan, &travel, &start, base, DVec3::Y * sign),
        plan,
        base: resolved,
        lead,
        reach_margin: margin,
        travel,
        check: MovingCheck::default(),
    };
    limits_of_base(&mp)?;
    mp.check = check_moving(&mp);
    if !mp.check.problems.is_empty() {
        return Err(RobotError::Verification(mp.check.problems.clone()));
    }
    attach_moving_meshes(&mut mp)?;
    Ok(mp)
}

/// UR's collision meshes at every waypoint with the base where it is at that moment
/// ([`verify_meshes_moving`]), kept in the plan (`Plan::meshes`); a mesh contact
/// is a failed verification.
fn attach_moving_meshes(mp: &mut MovingPlan) -> Result<(), RobotError> {
    let rep = verify_meshes_moving(mp, 1)?;
    if !rep.problems.is_empty() {
        return Err(RobotError::Verification(rep.problems));
    }
    mp.plan.meshes = Some(rep);
    Ok(())
}

/// [`crate::meshes::verify_meshes`] for a base that moves while printing (issue 27): every `stride`-th
/// waypoint of each layer (and its first and last), the arm posed from the base's pose at that
/// waypoint ([`MovingPlan::base_pose`]). The environment (beams, floor, printed
/// layers) stands in the world; the mobile base's own body moves with the arm, so the arm's
/// distance to it is measured in the base frame, independent of the travel. At the waypoints
/// only: the clearance along the motion with the base moving is certified on the capsules by
/// [`check_moving`].
///
/// # Errors
/// An invalid plan (shape, setup, targets) or mesh asset.
pub fn verify_meshes_moving(
    mp: &MovingPlan,
    stride: usize,
) -> Result<crate::plan::MeshReport, RobotError> {
    mp.validate_shape()?;
    let stride = stride.max(1);
    let plan = &mp.plan;
    let meshes = crate::meshes::ArmMeshes::load()?;
    let layers = plan_layers(plan);
    // The moving check's own split: the world without the body, the body in the base frame.
    let Geometry {
        world: ctx,
        scene: world,
        body,
    } = Geometry::new(&validate(&layers, &plan.setup, &plan.options)?)?;
    let tool_caps: Vec<_> = ctx
        .self_model
        .capsules
        .iter()
        .filter(|c| c.link == crate::collision::TOOL_LINK)
        .cloned()
        .collect();
    let mut jobs: Vec<(usize, usize, i64, usize, Joints)> = Vec::new();
    for (o, l) in plan.stations[0].layers.iter().enumerate() {
        let n = l.waypoints.len();
        for (k, w) in l.waypoints.iter().enumerate() {
            if k % stride == 0 || k + 1 == n {
                jobs.push((o, k, l.layer, w.index, w.q));
            }
        }
    }
    let out: Vec<crate::meshes::One> = jobs
        .par_iter()
        .map(|&(o, k, layer, index, q)| {
            let probe = crate::meshes::Probe {
                ctx: &ctx,
                meshes: &meshes,
                scene: &world,
                world_from_base: mp.base_pose(o, k),
                tool_caps: &tool_caps,
            };
            let mut one = probe.measure(&q, o);
            if let Some(body) = &body {
                let on_base = crate::meshes::Probe {
                    scene: body,
                    world_from_base: Iso::IDENTITY,
                    ..probe
                };
                let b = on_base.measure(&q, o);
                for (mine, theirs) in [
                    (&mut one.cap_env, b.cap_env),
                    (&mut one.nozzle, b.nozzle),
                    (&mut one.mesh_env, b.mesh_env),
                ] {
                    if theirs.0 < mine.0 {
                        *mine = theirs;
                    }
                }
            }
            one.at = (0, layer, index);
            one
        })
        .collect();
    Ok(crate::meshes::report_of(&out, &meshes, None))
}

/// The base trajectory of a timed plan: a sample at the start of the clock (the approach, base
/// at the first target's pose), one at every waypoint's arrival and one at its departure where
/// the arm holds.
fn base_trajectory(
    plan: &Plan,
    travel: &[Vec<f64>],
    start: &Iso,
    base: &MovingBase,
    dir: DVec3,
) -> BaseTrajectory {
    // Wrapped to (−π, π], the convention of every other base yaw Kappe writes (atan2 of the
    // pose, e.g. trajectory.csv's `base_yaw`): one number for one heading in every file.
    let yaw = crate::kinematics::wrap(base.yaw_deg.to_radians());
    let mut samples = Vec::new();
    let sample = |t: f64, s: f64| {
        let p = start.t + dir * s;
        BaseSample {
            t,
            base_x: p.x,
            base_y: p.y,
            base_yaw: yaw,
            travel: s,
        }
    };
    samples.push(sample(
        0.0,
        travel
            .first()
            .and_then(|l| l.first())
            .copied()
            .unwrap_or(0.0),
    ));
    for (l, tr) in plan.stations[0].layers.iter().zip(travel) {
        for (w, &s) in l.waypoints.iter().zip(tr) {
            if w.t > 0.0 {
                samples.push(sample(w.t, s));
            }
            if w.hold > 0.0 {
                samples.push(sample(w.t + w.hold, s));
            }
        }
    }
    BaseTrajectory {
        z: start.t.z,
        direction: dir.to_array(),
        samples,
    }
}

/// The base's speed and acceleration limits on the trajectory rows; the error names the first
/// row that breaks one (a path the base cannot follow at this print speed).
fn limits_of_base(mp: &MovingPlan) -> Result<(), RobotError> {
    let tr = &mp.trajectory;
    let v = tr.speeds();
    if let Some((k, &vk)) = v
        .iter()
        .enumerate()
        .find(|(_, vk)| **vk > mp.base.speed_max * (1.0 + 1e-9))
    {
        return Err(RobotError::invalid(
            "moving.speed_max",
            format!(
                "the base must move at {vk:.6} m/s from t = {:.3} s to {:.3} s to keep up with the printing front, more than speed_max = {} m/s (raise it or lower the print speed)",
                tr.samples[k].t,
                tr.samples[k + 1].t,
                mp.base.speed_max
            ),
        ));
    }
    let a = tr.accelerations();
    if let Some(&amax) = a.iter().max_by(|x, y| x.total_cmp(y))
        && amax > mp.base.accel_max * (1.0 + 1e-9)
    {
        return Err(RobotError::invalid(
            "moving.accel_max",
            format!(
                "the base must accelerate at {amax:.6} m/s² (between trajectory rows), more than accel_max = {} m/s²",
                mp.base.accel_max
            ),
        ));
    }
    Ok(())
}

/// Re-verify a moving plan from its joint values and its time-stamped base trajectory alone:
/// for every waypoint the base pose is read from the trajectory at the waypoint's time and
/// `world_from_base · FK(q) · tool` must hit the target (1e-6 m, 1e-6 rad); joint limits, the
/// elbow/wrist branch, ε between consecutive waypoints; self distance and clearance (beams,
/// floor, printed layers in the world, the body in the base frame) at the waypoints, and
/// certified along each print move with the base moving ([`crate::sweep`]'s bound plus the base's
/// own displacement); the nozzle's world speed on every print move; the base's speed,
/// acceleration and monotone travel.
pub fn check_moving(mp: &MovingPlan) -> MovingCheck {
    let mut rep = MovingCheck {
        certified_clearance: f64::INFINITY,
        min_self_distance: f64::INFINITY,
        ..Default::default()
    };
    if let Err(e) = mp.validate_shape() {
        rep.problems.push(e.to_string());
        return rep;
    }
    let plan = &mp.plan;
    let layers = plan_layers(plan);
    let ctx = match validate(&layers, &plan.setup, &plan.options) {
        Ok(c) => c,
        Err(e) => {
            rep.problems.push(format!("invalid plan input: {e}"));
            return rep;
        }
    };
    let geo = match Geometry::new(&ctx) {
        Ok(g) => g,
        Err(e) => {
            rep.problems.push(format!("scene: {e}"));
            return rep;
        }
    };
    let tool = match Iso::from_mat4(&plan.flange_from_tcp) {
        Ok(t) => t,
        Err(e) => {
            rep.problems.push(format!("flange_from_tcp: {e}"));
            return rep;
        }
    };
    let opts = &plan.options;
    let mut problems = Vec::new();
    let Some(st) = plan.stations.first() else {
        rep.problems.push("no station".into());
        return rep;
    };
    if plan.stations.len() != 1 {
        problems.push(format!(
            "a moving plan has one station, this one has {}",
            plan.stations.len()
        ));
    }
    let env_bounds =
        crate::sweep::SweepBounds::for_capsules(&UR10E, &ctx.env_model.capsules, [0.0; 8]);
    let env_links: Vec<usize> = ctx.env_model.capsules.iter().map(|c| c.link).collect();
    let arm_bound = |tv: &[f64; 6]| {
        env_links
            .iter()
            .map(|&k| env_bounds.world(tv, k))
            .fold(0.0, f64::max)
    };
    // (order, waypoint, base pose) in print order.
    let mut rows: Vec<(usize, &Waypoint, Iso)> = Vec::new();
    for (o, l) in st.layers.iter().enumerate() {
        for w in &l.waypoints {
            rows.push((o, w, mp.trajectory.pose_at(w.t)));
        }
    }
    rep.waypoints = rows.len();
    let measure = |q: &Joints, w: &Iso, order: usize| -> f64 {
        let env = ctx.env_model.pose(q, w);
        let c = geo.scene.clearance(env.as_slice(), order, CLEARANCE_CUTOFF);
        c.distance.min(geo.body_clearance(q, CLEARANCE_CUTOFF))
    };
    let per_row: Vec<(f64, f64, f64, f64, Vec<String>)> = rows
        .par_iter()
        .map(|(o, w, b)| {
            let mut pr = Vec::new();
            let tcp = b.mul(&UR10E.fk(&w.q)).mul(&tool);
            let pe = (tcp.t - DVec3::from(w.position)).length();
            let ae = angle_between(tcp.r.z_axis, DVec3::from(w.axis));
            if !within_limits(&w.q, &ctx.limits) {
                pr.push(format!(
                    "layer {} point {}: joints beyond the limits",
                    st.layers[*o].layer, w.index
                ));
            }
            let posed = ctx.self_model.pose(&w.q, &Iso::IDENTITY);
            let ds = ctx.self_model.min_self_distance_posed(&posed).0;
            let c = measure(&w.q, b, *o);
            if c < opts.clearance - 1e-12 {
                pr.push(format!(
                    "layer {} point {}: clearance {c:.4} m < {} m",
                    st.layers[*o].layer, w.index, opts.clearance
                ));
            }
            (pe, ae, ds, c, pr)
        })
        .collect();
    // Certified along each move from the previous waypoint (the base interpolated too), with the
    // waypoint's own order (the layer being printed) for the printed layers.
    let certified: Vec<f64> = (1..rows.len())
        .into_par_iter()
        .map(|i| {
            let (_, pw, pb) = &rows[i - 1];
            let (o, w, b) = &rows[i];
            certify_step(
                (&pw.q, pb, per_row[i - 1].3),
                (&w.q, b, per_row[i].3),
                *o,
                &measure,
                &arm_bound,
                opts.clearance,
                0,
            )
        })
        .collect();
    for c in certified {
        rep.certified_clearance = rep.certified_clearance.min(c);
    }
    for (pe, ae, ds, cert, pr) in per_row {
        rep.max_position_error = rep.max_position_error.max(pe);
        rep.max_axis_error = rep.max_axis_error.max(ae);
        rep.min_self_distance = rep.min_self_distance.min(ds);
        rep.certified_clearance = rep.certified_clearance.min(cert);
        problems.extend(pr);
    }
    if rep.max_position_error > crate::check::TARGET_TOL
        || rep.max_axis_error > crate::check::TARGET_TOL
    {
        problems.push(format!(
            "FK composed with the base trajectory misses the targets by {:.3e} m / {:.3e} rad (> 1e-6)",
            rep.max_position_error, rep.max_axis_error
        ));
    }
    if rep.min_self_distance < opts.self_clearance {
        problems.push(format!(
            "self distance {:.4} m < {} m",
            rep.min_self_distance, opts.self_clearance
        ));
    }
    if rep.certified_clearance < opts.clearance - 1e-12 {
        problems.push(format!(
            "certified clearance along the moves {:.4} m < {} m",
            rep.certified_clearance, opts.clearance
        ));
    }
    let branch = |q: &Joints| (q[2].sin() > 0.0, q[4].sin() > 0.0);
    let n_cost = if ctx.coaxial { 5 } else { 6 };
    for pair in rows.windows(2) {
        let (_, a, ba) = &pair[0];
        let (o, b, bb) = &pair[1];
        let d2: f64 = (0..n_cost).map(|j| (b.q[j] - a.q[j]).powi(2)).sum();
        rep.max_step = rep.max_step.max(d2);
        if d2 > opts.epsilon + 1e-12 || branch(&a.q) != branch(&b.q) {
            problems.push(format!(
                "layer {} point {}: step Σ Δq² = {d2:.4} rad² (ε = {}) or a branch change",
                st.layers[*o].layer, b.index, opts.epsilon
            ));
        }
        // Print moves: the nozzle's world speed is the planned speed; the arm's own TCP speed is
        // the world speed less the base's.
        let dt = b.t - (a.t + a.hold);
        if dt > 0.0 && b.speed > 0.0 {
            let dp = DVec3::from(b.position) - DVec3::from(a.position);
            let v = dp.length() / dt;
            rep.max_tcp_speed_error = rep.max_tcp_speed_error.max((v / b.speed - 1.0).abs());
            let arm = (dp - (bb.t - ba.t)).length() / dt;
            rep.max_arm_tcp_speed = rep.max_arm_tcp_speed.max(arm);
        }
    }
    // 1e-6 relative: the times are sums of f64 durations.
    if rep.max_tcp_speed_error > 1e-6 {
        problems.push(format!(
            "the nozzle's world speed differs from the planned speed by {:.3e} (relative)",
            rep.max_tcp_speed_error
        ));
    }
    let s = mp.trajectory.summary();
    rep.max_base_speed = s.max_speed;
    rep.max_base_acceleration = s.max_acceleration;
    if s.max_speed > mp.base.speed_max * (1.0 + 1e-9) {
        problems.push(format!("base speed {:.6} m/s > speed_max", s.max_speed));
    }
    if s.max_acceleration > mp.base.accel_max * (1.0 + 1e-9) {
        problems.push(format!(
            "base acceleration {:.6} m/s² > accel_max",
            s.max_acceleration
        ));
    }
    for w in mp.trajectory.samples.windows(2) {
        if w[1].t < w[0].t || w[1].travel < w[0].travel - 1e-12 {
            problems.push(format!(
                "the base trajectory is not monotone at t = {:.3} s",
                w[1].t
            ));
            break;
        }
    }
    let n = problems.len();
    if n > 20 {
        problems.truncate(20);
        problems.push(format!("… and {} more", n - 20));
    }
    rep.problems = problems;
    rep
}

/// Certified lower bound of the clearance along one move (joints and base interpolated linearly
/// together): any point moves at most `arm_bound(|Δq|) + |Δbase|`, so the clearance is at least
/// `(d_a + d_b − D)/2`; halve where that is below `need` (at most 10 times).
fn certify_step(
    a: (&Joints, &Iso, f64),
    b: (&Joints, &Iso, f64),
    order: usize,
    measure: &(dyn Fn(&Joints, &Iso, usize) -> f64 + Sync),
    arm_bound: &(dyn Fn(&[f64; 6]) -> f64 + Sync),
    need: f64,
    depth: usize,
) -> f64 {
    let (qa, ba, da) = a;
    let (qb, bb, db) = b;
    let tv: [f64; 6] = std::array::from_fn(|j| (qb[j] - qa[j]).abs());
    let d = arm_bound(&tv) + (bb.t - ba.t).length();
    let bound = 0.5 * (da + db - d);
    if bound >= need || depth >= 10 {
        return bound.min(da).min(db);
    }
    let qm: Joints = std::array::from_fn(|j| 0.5 * (qa[j] + qb[j]));
    let bm = Iso::new(ba.r, 0.5 * (ba.t + bb.t));
    let dm = measure(&qm, &bm, order);
    let left = certify_step(
        a,
        (&qm, &bm, dm),
        order,
        measure,
        arm_bound,
        need,
        depth + 1,
    );
    let right = certify_step(
        (&qm, &bm, dm),
        b,
        order,
        measure,
        arm_bound,
        need,
        depth + 1,
    );
    left.min(right)
}

/// The moving plan that continues the print from layer `layer`: earlier layers dropped, the
/// programs cut again and everything re-timed from 0 (approach and priming with the base
/// standing at that layer's start), the base trajectory rebuilt and the result re-checked.
pub fn resume_moving(mp: &MovingPlan, layer: i64) -> Result<MovingPlan, RobotError> {
    mp.validate_shape()?;
    let plan = crate::program::resume_plan(&mp.plan, layer)?;
    let dropped = mp.plan.stations[0].layers.len() - plan.stations[0].layers.len();
    let travel: Vec<Vec<f64>> = mp.travel[dropped..].to_vec();
    let start = Iso::from_mat4_unchecked(&mp.plan.stations[0].world_from_base);
    let mut out = MovingPlan {
        trajectory: base_trajectory(
            &plan,
            &travel,
            &start,
            &mp.base,
            DVec3::from(mp.trajectory.direction),
        ),
        plan,
        base: mp.base.clone(),
        lead: mp.lead,
        reach_margin: mp.reach_margin,
        travel,
        check: MovingCheck::default(),
    };
    limits_of_base(&out)?;
    out.check = check_moving(&out);
    if !out.check.problems.is_empty() {
        return Err(RobotError::Verification(out.check.problems.clone()));
    }
    attach_moving_meshes(&mut out)?;
    Ok(out)
}

/// The plan's feasibility under base-pose errors (as [`crate::tolerance::check_base_tolerance`]
/// for stations): at every `stride`-th waypoint of every layer (and its last), with the base off
/// its planned pose at that instant by each sampled error `(dx, dy, dyaw)`
/// ([`crate::tolerance::sampled_errors`]: the corners of the box and its centre), a valid
/// configuration on the planned elbow/wrist branch must exist (the planner's own acceptance,
/// the body included), consecutive re-solved ones within ε·stride², and the body clear of the
/// obstacles at each layer's start. Corners suffice for small errors (the clearances are then
/// affine in the error, minimised at a corner; see `tolerance`).
pub fn check_moving_tolerance(
    mp: &MovingPlan,
    tol: &crate::tolerance::BaseTolerance,
) -> crate::tolerance::ToleranceReport {
    use crate::tolerance::{Resolver, ToleranceReport, sampled_errors};
    let mut rep = ToleranceReport {
        tolerance: tol.clone(),
        min_clearance: f64::INFINITY,
        ..Default::default()
    };
    let ok = tol.position.is_finite()
        && tol.position >= 0.0
        && tol.yaw_deg.is_finite()
        && tol.yaw_deg >= 0.0
        && tol.stride > 0;
    if !ok {
        rep.problems.push(format!(
            "base tolerance position {} m, yaw {}°, stride {}: need finite values ≥ 0 and stride ≥ 1",
            tol.position, tol.yaw_deg, tol.stride
        ));
        return rep;
    }
    if let Err(e) = mp.validate_shape() {
        rep.problems.push(e.to_string());
        return rep;
    }
    let plan = &mp.plan;
    let layers = plan_layers(plan);
    let ctx = match validate(&layers, &plan.setup, &plan.options) {
        Ok(c) => c,
        Err(e) => {
            rep.problems.push(format!("invalid plan input: {e}"));
            return rep;
        }
    };
    let geo = match Geometry::new(&ctx) {
        Ok(g) => g,
        Err(e) => {
            rep.problems.push(format!("scene: {e}"));
            return rep;
        }
    };
    let errors = sampled_errors(tol);
    rep.poses_per_station = errors.len();
    let st = &plan.stations[0];
    let eps = plan.options.epsilon;
    let jobs: Vec<(usize, (f64, f64, f64))> = (0..st.layers.len())
        .flat_map(|li| errors.iter().map(move |e| (li, *e)))
        .collect();
    let results: Vec<(usize, f64, Vec<String>)> = jobs
        .par_iter()
        .map(|&(li, (dx, dy, da))| {
            let (mut n, mut min_c, mut pr) = (0usize, f64::INFINITY, Vec::new());
            let l = &st.layers[li];
            let off = |k: usize| {
                Iso::translation(dx, dy, 0.0)
                    .mul(&mp.base_pose(li, k))
                    .mul(&Iso::rot_z(da))
            };
            let at = format!(
                "layer {}, base off by ({:+.1} mm, {:+.1} mm, {:+.2}°)",
                l.layer,
                dx * 1e3,
                dy * 1e3,
                da.to_degrees()
            );
            if let Err(e) = ctx.check_base(&off(0)) {
                pr.push(format!("{at}: {e}"));
            }
            let len = l.waypoints.len();
            let mut resolver = Resolver::new(eps, tol.stride, len);
            for (k, w) in l.waypoints.iter().enumerate() {
                if k % tol.stride != 0 && k + 1 != len {
                    continue;
                }
                n += 1;
                let (verts, rej) = geo.vertices(&off(k), li, k);
                let point = format!("{at}: point {}", w.index);
                resolver.next(&w.q, &verts, &rej, &point, &mut min_c, &mut pr);
            }
            (n, min_c, pr)
        })
        .collect();
    for (n, c, pr) in results {
        rep.waypoints_checked += n;
        rep.min_clearance = rep.min_clearance.min(c);
        rep.problems.extend(pr);
    }
    let n = rep.problems.len();
    if n > 20 {
        rep.problems.truncate(20);
        rep.problems.push(format!("… and {} more", n - 20));
    }
    rep
}

#[cfg(test)]
mod tests {
    use super::coarse_to_fine;

    #[test]
    fn coarse_to_fine_finds_the_exact_boundaries_of_an_interval() {
        // Feasible exactly on 7..=23 of 0..40: the result must equal the brute-force scan.
        for (lo, hi) in [(7usize, 23usize), (0, 39), (10, 10), (0, 3), (36, 39)] {
            let f = |i: usize| (lo..=hi).contains(&i);
            let got = coarse_to_fine(40, 5, &f);
            let want: Vec<bool> = (0..40).map(f).collect();
            assert_eq!(got, want, "{lo}..={hi}");
        }
        // Nothing feasible; and, as documented, a run narrower than the stride between two
        // infeasible coarse points is not seen.
        assert!(coarse_to_fine(40, 5, &|_| false).iter().all(|v| !v));
        assert!(
            coarse_to_fine(40, 5, &|i| (12..=13).contains(&i))
                .iter()
                .all(|v| !v)
        );
    }
}
