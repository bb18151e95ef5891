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
use serde::{Deserialize, Serialize};

use crate::base_trajectory::BaseTrajectory;
use crate::collision::Scene;
use crate::error::RobotError;
use crate::frames::Iso;
use crate::kinematics::Joints;
use crate::plan::{CLEARANCE_CUTOFF, Plan, Waypoint};
use crate::planner::{Context, Rejections, Select, Vertex, validate};
use crate::setup::PrintLayer;

mod check;
mod plan;

pub use check::{check_moving, check_moving_tolerance, verify_meshes_moving};
pub use plan::{plan_moving, resume_moving};

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
        self.vertices_where(w, o, k, Select::ALL)
    }

    /// [`Self::vertices`] as `select` asks ([`crate::planner::Context::vertices`]), the mobile
    /// base's body included.
    fn vertices_where(
        &self,
        w: &Iso,
        o: usize,
        k: usize,
        select: Select,
    ) -> (Vec<Vertex>, Rejections) {
        let frame = self.world.target_frame(&self.world.layers[o], k);
        let (mut v, mut rej) = self.world.vertices(&self.scene, w, &frame, o, select);
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
