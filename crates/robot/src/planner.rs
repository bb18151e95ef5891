//! Planning a print: target frames along each layer, IK vertices filtered by limits, singularity
//! margins, self-collision and clearance, then the ladder search ([`crate::ladder`]) over a whole
//! station (layers joined by `movej` transitions), 2π unwrapping, timing at the print speed and a
//! collision check of every transition. Base stations come from [`crate::base`];
//! [`crate::stationary`] ties the planning, the timing and the check together.
//!
//! Edge rules inside a layer (robot.md §3.6): Σ Δq² ≤ ε (the paper's compatibility),
//! |Δq_j| ≤ s·v_j,max·Δt with Δt = |Δp|/v_print, and the elbow and wrist branches
//! (sign sin q3, sign sin q5) unchanged. Edge cost Σ Δq² (Δq wrapped except the elbow; q6 left out
//! for a coaxial tool, whose q6 is held constant).

use parry3d_f64::glamx::DVec3;
use rayon::prelude::*;

use crate::collision::{
    CapsuleSpec, Clearance, LINK_NAMES, Obstacle, RobotModel, Scene, TOOL_LINK,
};
use crate::error::{FailureKind, PlanFailure, RobotError};
use crate::frames::{Iso, frame_from_z};
use crate::kinematics::{Joints, UR10E, joint_delta, representable_in_limits};
use crate::ladder::{LadderFailure, LadderPath, solve_optimal, solve_random};
use crate::plan::{CLEARANCE_CUTOFF, LayerPlan, Plan, PlanMark, Station, Waypoint};
use crate::setup::{BasePlacement, PlanOptions, PlannerKind, PrintLayer, RobotSetup};

/// The elbow/wrist branch of a configuration: the signs of sin q3 and sin q5. A re-solve of a
/// planned target (base-tolerance checks) must stay on the planned one.
pub fn branch(q: &Joints) -> (bool, bool) {
    (q[2].sin() > 0.0, q[4].sin() > 0.0)
}

/// Which valid vertices [`Context::vertices`] collects and how far it measures their
/// clearances.
#[derive(Clone, Copy, Debug)]
pub struct Select {
    /// At most this many (the first found).
    pub max: usize,
    /// Only those on this elbow/wrist branch ([`branch`]); the others are not checked at all,
    /// nor counted in the rejections.
    pub branch: Option<(bool, bool)>,
    /// How far the clearances are measured.
    pub measure: Measure,
}

/// How far [`Context::vertices`] measures clearances. A clearance at or above the bound reads as
/// the bound; the bound is never below the required clearance (so validity is exact) nor above
/// [`CLEARANCE_CUTOFF`].
#[derive(Clone, Copy, Debug)]
pub enum Measure {
    /// Up to [`CLEARANCE_CUTOFF`].
    Full,
    /// Only whether the required clearance holds: a query stops there, so most of the scene
    /// is skipped by its boxes.
    Validity,
    /// Below this bound: what a caller that wants only the smallest clearance over many
    /// configurations needs (the smallest so far).
    Below(f64),
}

impl Select {
    /// Every valid vertex, clearances in full.
    pub const ALL: Select = Select {
        max: usize::MAX,
        branch: None,
        measure: Measure::Full,
    };
    /// Every valid vertex, validity only: the station planner's ladder, which measures the
    /// configurations it chooses afterwards.
    pub const VALID: Select = Select {
        max: usize::MAX,
        branch: None,
        measure: Measure::Validity,
    };

    /// The valid vertices on `branch`, clearances below `below`: the base-tolerance checks,
    /// which take only the planned branch (two IK solutions of eight) and want only the
    /// smallest clearance over a pose's waypoints.
    pub fn on_branch(branch: (bool, bool), below: f64) -> Select {
        Select {
            max: usize::MAX,
            branch: Some(branch),
            measure: Measure::Below(below),
        }
    }
}

/// Geometry shared by all stations: models, static scene, tool.
pub(crate) struct Context {
    pub self_model: RobotModel,
    pub env_model: RobotModel,
    pub flange_from_tcp: Iso,
    pub tcp_from_flange: Iso,
    pub coaxial: bool,
    pub opts: PlanOptions,
    pub setup: RobotSetup,
    pub layers: Vec<PrintLayer>,
    /// Joint position limits (rad), validated.
    pub limits: [[f64; 2]; 6],
}

/// Clip a tool capsule to the part at least `excl` behind the tip along the tool axis.
fn clip_tool_capsule(c: &CapsuleSpec, tip: DVec3, axis: DVec3, excl: f64) -> Option<CapsuleSpec> {
    let a = DVec3::from(c.a);
    let b = DVec3::from(c.b);
    let sa = (tip - a).dot(axis);
    let sb = (tip - b).dot(axis);
    if sa < excl && sb < excl {
        return None;
    }
    let cut = |p: DVec3, sp: f64, q: DVec3, sq: f64| p + (q - p) * ((sp - excl) / (sp - sq));
    let (na, nb) = if sa < excl {
        (cut(b, sb, a, sa), b)
    } else if sb < excl {
        (a, cut(a, sa, b, sb))
    } else {
        (a, b)
    };
    Some(CapsuleSpec {
        a: na.to_array(),
        b: nb.to_array(),
        ..c.clone()
    })
}

pub(crate) fn validate(
    layers: &[PrintLayer],
    setup: &RobotSetup,
    opts: &PlanOptions,
) -> Result<Context, RobotError> {
    let pos = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(RobotError::invalid(
                name,
                format!("{v}: must be finite and > 0"),
            ))
        }
    };
    let non_negative = |name: &str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(RobotError::invalid(
                name,
                format!("{v}: must be finite and ≥ 0"),
            ))
        }
    };
    pos("epsilon (rad²)", opts.epsilon)?;
    pos("print_speed (m/s)", opts.print_speed)?;
    pos("transition_speed_fraction", opts.transition_speed_fraction)?;
    if !(opts.speed_fraction > 0.0 && opts.speed_fraction <= 1.0) {
        return Err(RobotError::invalid(
            "speed_fraction",
            format!("{}: must be in (0, 1]", opts.speed_fraction),
        ));
    }
    for (name, v) in [
        ("clearance (m)", opts.clearance),
        ("self_clearance (m)", opts.self_clearance),
        ("min_abs_sin_q5", opts.min_abs_sin_q5),
        ("min_abs_sin_q3", opts.min_abs_sin_q3),
        ("min_shoulder_margin (m)", opts.min_shoulder_margin),
        ("bead_radius (m)", opts.bead_radius),
        ("tool.tip_exclusion (m)", setup.tool.tip_exclusion),
        ("station_change_time (s)", opts.station_change_time),
        ("reconfiguration_penalty", opts.reconfiguration_penalty),
    ] {
        non_negative(name, v)?;
    }
    if !opts.bead_offset.is_finite()
        || !opts.q6.is_finite()
        || opts.q6.abs() > std::f64::consts::TAU
    {
        return Err(RobotError::invalid(
            "bead_offset / q6",
            format!(
                "{} / {}: must be finite, |q6| ≤ 2π",
                opts.bead_offset, opts.q6
            ),
        ));
    }
    let pr = &opts.program;
    if pr.max_moves_per_program < 4 {
        return Err(RobotError::invalid(
            "program.max_moves_per_program",
            format!(
                "{}: a program needs at least 4 targets (approach, descent, a print move, retract)",
                pr.max_moves_per_program
            ),
        ));
    }
    pos("program.approach_distance (m)", pr.approach_distance)?;
    pos("program.approach_speed (m/s)", pr.approach_speed)?;
    pos("program.tool_acceleration (m/s²)", pr.tool_acceleration)?;
    pos("program.joint_speed (rad/s)", pr.joint_speed)?;
    pos("program.joint_acceleration (rad/s²)", pr.joint_acceleration)?;
    for (name, v) in [
        ("program.blend_radius (m)", pr.blend_radius),
        ("program.program_switch_time (s)", pr.program_switch_time),
        ("program.payload_mass (kg)", pr.payload_mass),
    ] {
        non_negative(name, v)?;
    }
    if !pr.payload_cog.iter().all(|v| v.is_finite()) {
        return Err(RobotError::invalid(
            "program.payload_cog (m)",
            format!("{:?}: must be finite", pr.payload_cog),
        ));
    }
    opts.limits.validate_positions()?;
    for j in 0..6 {
        let (v, a) = (
            opts.limits.max_speed_deg_s[j],
            opts.limits.max_acceleration[j],
        );
        if !(v.is_finite() && v > 0.0 && a.is_finite() && a > 0.0) {
            return Err(RobotError::invalid(
                format!("limits (joint {})", j + 1),
                format!("speed {v} °/s, acceleration {a} rad/s²: must be finite and > 0"),
            ));
        }
    }
    // Flow at the design speed: Q = lw·lh·v with lw = 2·bead_radius, lh = 2·bead_offset.
    opts.pump
        .validate(4.0 * opts.bead_radius * opts.bead_offset.abs() * opts.print_speed)?;
    if opts.rotation_steps == 0 || opts.rotation_steps > 360 {
        return Err(RobotError::invalid(
            "rotation_steps",
            format!("{}: must be 1..=360", opts.rotation_steps),
        ));
    }
    if opts.planner == PlannerKind::Random && opts.random_trials == 0 {
        return Err(RobotError::invalid(
            "random_trials",
            "0: need at least 1 trial",
        ));
    }
    let flange_from_tcp = Iso::from_mat4(&setup.tool.flange_from_tcp)
        .map_err(|e| RobotError::invalid("tool.flange_from_tcp", e))?;
    if flange_from_tcp.t.length() < 1e-6 {
        return Err(RobotError::invalid(
            "tool.flange_from_tcp",
            format!(
                "TCP offset {:?} m: a tool of zero length cannot hold a nozzle",
                flange_from_tcp.t.to_array()
            ),
        ));
    }
    if layers.is_empty() {
        return Err(RobotError::invalid("layers", "no layer to plan"));
    }
    let mut cleaned = layers.to_vec();
    for (li, l) in cleaned.iter_mut().enumerate() {
        if l.points.is_empty() {
            return Err(RobotError::invalid(
                format!("layers[{li}] (layer {})", l.layer),
                "has no point",
            ));
        }
        for p in &mut l.points {
            let field = || format!("layer {} point {}", l.layer, p.index);
            if !p.position.iter().chain(&p.axis).all(|v| v.is_finite()) {
                return Err(RobotError::invalid(field(), "non-finite position or axis"));
            }
            let a = DVec3::from(p.axis);
            if (a.length() - 1.0).abs() > 1e-3 {
                return Err(RobotError::invalid(
                    field(),
                    format!(
                        "tool axis {:?} has length {:.6}, expected a unit vector",
                        p.axis,
                        a.length()
                    ),
                ));
            }
            p.axis = a.normalize().to_array();
        }
    }
    // Tool capsules: full for self-collision, clipped near the tip for the environment.
    let tip = flange_from_tcp.t;
    let axis = flange_from_tcp.r.z_axis;
    let tool_specs: Vec<CapsuleSpec> = setup
        .tool
        .capsules
        .iter()
        .enumerate()
        .map(|(i, c)| CapsuleSpec {
            link: TOOL_LINK,
            name: format!("tool_{i}"),
            a: c.a,
            b: c.b,
            radius: c.radius,
        })
        .collect();
    let self_model = RobotModel::ur10e_with_tool(&tool_specs)?;
    let mut env_caps: Vec<CapsuleSpec> = crate::collision::ur10e_arm_capsules()
        .into_iter()
        .filter(|c| c.link != 0)
        .collect();
    env_caps.extend(
        tool_specs
            .iter()
            .filter_map(|c| clip_tool_capsule(c, tip, axis, setup.tool.tip_exclusion)),
    );
    let env_model = RobotModel::new(UR10E, env_caps, Vec::new())?;
    // Coaxial: the tool axis is the flange z axis through the flange centre and every tool
    // capsule lies on it, so a rotation about the tool axis is exactly a change of q6.
    let on_axis = |p: [f64; 3]| p[0].abs() < 1e-9 && p[1].abs() < 1e-9;
    let coaxial = (axis - DVec3::Z).length() < 1e-9
        && tip.x.abs() < 1e-9
        && tip.y.abs() < 1e-9
        && setup
            .tool
            .capsules
            .iter()
            .all(|c| on_axis(c.a) && on_axis(c.b));
    Ok(Context {
        self_model,
        env_model,
        flange_from_tcp,
        tcp_from_flange: flange_from_tcp.inverse(),
        coaxial,
        opts: opts.clone(),
        setup: setup.clone(),
        layers: cleaned,
        limits: opts.limits.position(),
    })
}

/// A valid configuration of one frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vertex {
    pub q: Joints,
    pub clearance: f64,
}

/// Why the candidates of a frame were dropped.
#[derive(Clone, Debug, Default)]
pub(crate) struct Rejections {
    pub ik: usize,
    pub limits: usize,
    pub singular: usize,
    pub self_collision: usize,
    pub collision: usize,
    pub self_example: Option<(usize, usize)>,
    pub collision_example: Option<(usize, String, f64)>,
}

impl Rejections {
    pub fn failure(&self) -> (FailureKind, String) {
        if self.ik == 0 {
            return (
                FailureKind::Unreachable,
                "no IK solution: the target is out of reach".into(),
            );
        }
        let mut detail = format!(
            "{} IK solutions: {} outside joint limits, {} near a singularity, {} self-colliding, {} too close to the environment",
            self.ik, self.limits, self.singular, self.self_collision, self.collision
        );
        if let Some((a, b)) = self.self_example {
            detail += &format!("; self collision {}–{}", LINK_NAMES[a], LINK_NAMES[b]);
        }
        if let Some((l, o, d)) = &self.collision_example {
            detail += &format!("; {} within {:.4} m of {o:?}", LINK_NAMES[*l], d);
        }
        let kind = if self.collision > 0 {
            FailureKind::Collision
        } else if self.self_collision > 0 {
            FailureKind::SelfCollision
        } else if self.singular > 0 {
            FailureKind::Singularity
        } else {
            FailureKind::JointLimits
        };
        (kind, detail)
    }
}

impl Context {
    /// The ladder's edge cost Σ Δq² (Δq wrapped; q6 left out for a coaxial tool, module docs).
    pub(crate) fn step_cost(&self, a: &Joints, b: &Joints) -> f64 {
        let n_cost = if self.coaxial { 5 } else { 6 };
        let d = joint_delta(a, b);
        d[..n_cost].iter().map(|v| v * v).sum()
    }

    /// The arm's clearance to `scene` in configuration `q` from base `world_from_base`: its
    /// environment capsules against the static obstacles and the printed layers with print order
    /// < `order`, measured up to `cutoff` ([`Scene::clearance`]).
    pub fn clearance(
        &self,
        scene: &Scene,
        q: &Joints,
        world_from_base: &Iso,
        order: usize,
        cutoff: f64,
    ) -> Clearance {
        let env = self.env_model.pose(q, world_from_base);
        scene.clearance(env.as_slice(), order, cutoff)
    }

    /// TCP frame of a target (φ = 0), world: z = tool axis, x from the path tangent.
    pub fn target_frame(&self, layer: &PrintLayer, k: usize) -> Iso {
        let pts = &layer.points;
        let p = DVec3::from(pts[k].position);
        let prev = DVec3::from(pts[k.saturating_sub(1)].position);
        let next = DVec3::from(pts[(k + 1).min(pts.len() - 1)].position);
        let mut tangent = next - prev;
        if tangent.length_squared() < 1e-18 {
            tangent = DVec3::X;
        }
        frame_from_z(p, DVec3::from(pts[k].axis), tangent)
    }

    /// Singularity margins hold for `q` at flange pose `base_from_flange`.
    pub fn margins_ok(&self, q: &Joints, base_from_flange: &Iso) -> bool {
        q[4].sin().abs() >= self.opts.min_abs_sin_q5
            && q[2].sin().abs() >= self.opts.min_abs_sin_q3
            && UR10E.shoulder_margin(base_from_flange) >= self.opts.min_shoulder_margin
    }

    /// The valid vertices of a world TCP frame for base `world_from_base` that `select` asks
    /// for; printed layers with print order < `order` are obstacles.
    pub fn vertices(
        &self,
        scene: &Scene,
        world_from_base: &Iso,
        world_tcp: &Iso,
        order: usize,
        select: Select,
    ) -> (Vec<Vertex>, Rejections) {
        self.vertices_upto(
            scene,
            &world_from_base.inverse(),
            world_from_base,
            world_tcp,
            order,
            select,
        )
    }

    /// Whether a world TCP frame has any valid vertex ([`Self::vertices`] is non-empty): stops at
    /// the first one and measures clearances only up to the required clearance (a vertex is
    /// valid iff its clearance capped at any cutoff ≥ `clearance` is ≥ `clearance`), so the base
    /// search's scoring does a fraction of the distance queries.
    pub fn has_vertex(
        &self,
        scene: &Scene,
        base_from_world: &Iso,
        world_from_base: &Iso,
        world_tcp: &Iso,
        order: usize,
    ) -> bool {
        !self
            .vertices_upto(
                scene,
                base_from_world,
                world_from_base,
                world_tcp,
                order,
                Select {
                    max: 1,
                    ..Select::VALID
                },
            )
            .0
            .is_empty()
    }

    /// [`Self::vertices`] with the base's inverse given (the planner's rungs and the base search
    /// share one per pose).
    fn vertices_upto(
        &self,
        scene: &Scene,
        base_from_world: &Iso,
        world_from_base: &Iso,
        world_tcp: &Iso,
        order: usize,
        Select {
            max,
            branch: on_branch,
            measure,
        }: Select,
    ) -> (Vec<Vertex>, Rejections) {
        let floor = self.opts.clearance.min(CLEARANCE_CUTOFF);
        let cutoff = match measure {
            Measure::Full => CLEARANCE_CUTOFF,
            Measure::Validity => floor,
            Measure::Below(b) => b.clamp(floor, CLEARANCE_CUTOFF),
        };
        let mut rej = Rejections::default();
        let mut out = Vec::new();
        let n_rot = if self.coaxial {
            1
        } else {
            self.opts.rotation_steps
        };
        for r in 0..n_rot {
            let phi = std::f64::consts::TAU * r as f64 / n_rot as f64;
            let base_tcp = base_from_world.mul(world_tcp).mul(&Iso::rot_z(phi));
            let base_flange = base_tcp.mul(&self.tcp_from_flange);
            let sols = UR10E.ik(&base_flange);
            for q0 in sols.as_slice() {
                if on_branch.is_some_and(|b| branch(q0) != b) {
                    continue;
                }
                rej.ik += 1;
                let mut q = *q0;
                if self.coaxial {
                    q[5] = self.opts.q6;
                }
                if !representable_in_limits(&q, &self.limits) {
                    rej.limits += 1;
                    continue;
                }
                if !self.margins_ok(&q, &base_flange) {
                    rej.singular += 1;
                    continue;
                }
                let posed = self.self_model.pose(&q, &Iso::IDENTITY);
                let (ds, pair) = self.self_model.min_self_distance_posed(&posed);
                if ds < self.opts.self_clearance {
                    rej.self_collision += 1;
                    rej.self_example.get_or_insert(pair);
                    continue;
                }
                let c = self.clearance(scene, &q, world_from_base, order, cutoff);
                if c.distance < self.opts.clearance {
                    rej.collision += 1;
                    if rej.collision_example.is_none() {
                        rej.collision_example =
                            Some((c.link, c.object.unwrap_or_default(), c.distance));
                    }
                    continue;
                }
                out.push(Vertex {
                    q,
                    clearance: c.distance,
                });
                if out.len() >= max {
                    return (out, rej);
                }
            }
        }
        (out, rej)
    }

    /// The scene for one base pose: static obstacles, floor, mobile base body, printed layers.
    pub fn scene(&self, world_from_base: &Iso) -> Result<Scene, RobotError> {
        let mut obstacles: Vec<Obstacle> = self.setup.obstacles.clone();
        if let Some(z) = self.setup.floor_z {
            obstacles.push(Obstacle::HalfSpace {
                name: "floor".into(),
                point: [0.0, 0.0, z],
                normal: [0.0, 0.0, 1.0],
            });
        }
        for b in &self.setup.mobile_base {
            obstacles.push(b.to_world(world_from_base));
        }
        let mut scene = Scene::new(&obstacles)?;
        if self.opts.printed_layers_as_obstacles {
            for (order, l) in self.layers.iter().enumerate() {
                let pts: Vec<DVec3> = l
                    .points
                    .iter()
                    .map(|p| DVec3::from(p.position) + DVec3::from(p.axis) * self.opts.bead_offset)
                    .collect();
                scene.add_printed_layer(
                    order,
                    format!("printed layer {}", l.layer),
                    &pts,
                    self.opts.bead_radius,
                );
            }
        }
        Ok(scene)
    }

    /// Check the base pose itself: the arm base and the mobile base clear of static obstacles
    /// and of the print.
    pub fn check_base(&self, world_from_base: &Iso) -> Result<(), String> {
        let statics = Scene::new(&self.setup.obstacles).map_err(|e| e.to_string())?;
        let base_caps: Vec<_> = self
            .self_model
            .pose(&[0.0; 6], world_from_base)
            .as_slice()
            .iter()
            .copied()
            .filter(|c| c.link == 0)
            .collect();
        let c = statics.clearance(&base_caps, 0, CLEARANCE_CUTOFF);
        if c.distance < 0.0 + 1e-12 && c.object.is_some() {
            return Err(format!(
                "the robot base is inside {:?}",
                c.object.unwrap_or_default()
            ));
        }
        for b in &self.setup.mobile_base {
            let Obstacle::Box {
                center,
                half_extents,
                yaw,
                ..
            } = b.to_world(world_from_base)
            else {
                continue;
            };
            // Box vs statics: represent the body by its inscribed capsule along its longest axis
            // would miss corners; use parry on the box through a one-object scene instead.
            let body = Scene::new(&[Obstacle::Box {
                name: b.name.clone(),
                center,
                half_extents,
                yaw,
            }])
            .map_err(|e| e.to_string())?;
            for o in &self.setup.obstacles {
                if let Some(d) = body.distance_to(o)
                    && d <= 0.0
                {
                    return Err(format!(
                        "the mobile base body {:?} overlaps {:?}",
                        b.name,
                        o.name()
                    ));
                }
            }
            // No print target may lie inside the body (the cap is not under the robot).
            let inv = world_from_base.inverse();
            for l in &self.layers {
                for p in &l.points {
                    let local = inv.point(DVec3::from(p.position)) - DVec3::from(b.center);
                    let h = DVec3::from(b.half_extents);
                    if local.abs().cmple(h).all() {
                        return Err(format!(
                            "the mobile base body {:?} covers layer {} point {}",
                            b.name, l.layer, p.index
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Plan a station: layers `range` (print order) from `world_from_base`; `t0` is the start time.
pub(crate) fn plan_station(
    ctx: &Context,
    station: usize,
    world_from_base: &Iso,
    range: std::ops::Range<usize>,
    t0: f64,
) -> Result<Station, Box<PlanFailure>> {
    let mut cache = None;
    plan_station_cached(ctx, station, world_from_base, range, t0, &mut cache)
}

/// The valid vertices of every rung of layers `start..` built for one base pose; a retry of the
/// same pose over a shorter range (after a failure) reuses them.
pub(crate) type RungCache = Option<(usize, Vec<(Vec<Vertex>, Rejections)>)>;

/// [`plan_station`] reusing (or filling) `cache` for this base pose and `range.start`.
pub(crate) fn plan_station_cached(
    ctx: &Context,
    station: usize,
    world_from_base: &Iso,
    range: std::ops::Range<usize>,
    t0: f64,
    cache: &mut RungCache,
) -> Result<Station, Box<PlanFailure>> {
    let base_from_world = world_from_base.inverse();
    let fail = |layer: i64, index: usize, kind: FailureKind, detail: String| {
        Box::new(PlanFailure {
            station,
            layer,
            index,
            kind,
            detail,
        })
    };
    if let Err(e) = ctx.check_base(world_from_base) {
        let l = &ctx.layers[range.start];
        return Err(fail(
            l.layer,
            l.points[0].index,
            FailureKind::BasePlacement,
            e,
        ));
    }
    let scene = ctx
        .scene(world_from_base)
        .map_err(|e| fail(0, 0, FailureKind::BasePlacement, e.to_string()))?;
    // Rungs: (order, k) for every point of every layer of the station.
    let rung_ids: Vec<(usize, usize)> = range
        .clone()
        .flat_map(|o| (0..ctx.layers[o].points.len()).map(move |k| (o, k)))
        .collect();
    let usable =
        matches!(cache, Some((start, b)) if *start == range.start && b.len() >= rung_ids.len());
    if !usable {
        let built: Vec<(Vec<Vertex>, Rejections)> = rung_ids
            .par_iter()
            .map(|&(o, k)| {
                let frame = ctx.target_frame(&ctx.layers[o], k);
                ctx.vertices_upto(
                    &scene,
                    &base_from_world,
                    world_from_base,
                    &frame,
                    o,
                    Select::VALID,
                )
            })
            .collect();
        *cache = Some((range.start, built));
    }
    let built: &[(Vec<Vertex>, Rejections)] = match cache {
        Some((_, b)) => &b[..rung_ids.len()],
        None => &[],
    };
    let n_cost = if ctx.coaxial { 5 } else { 6 };
    let result = solve_rungs(
        ctx,
        &rung_ids,
        built,
        ctx.opts.seed.wrapping_add(station as u64),
    );
    let path = match result {
        Ok(p) => p,
        Err(LadderFailure::EmptyRung { rung }) => {
            let (o, k) = rung_ids[rung];
            let (kind, detail) = built[rung].1.failure();
            return Err(fail(
                ctx.layers[o].layer,
                ctx.layers[o].points[k].index,
                kind,
                detail,
            ));
        }
        Err(LadderFailure::NoEdge { rung }) => {
            let (o, k) = rung_ids[rung];
            let mut best = f64::INFINITY;
            for a in &built[rung - 1].0 {
                for b in &built[rung].0 {
                    best = best.min(ctx.step_cost(&a.q, &b.q));
                }
            }
            let detail = format!(
                "{} valid configurations here, {} at the previous point, but no step satisfies Σ Δq² ≤ ε = {} with unchanged elbow/wrist branch and joint speeds ≤ {} of the limits at {} m/s (smallest Σ Δq² between them {best:.4} rad²)",
                built[rung].0.len(),
                built[rung - 1].0.len(),
                ctx.opts.epsilon,
                ctx.opts.speed_fraction,
                ctx.opts.print_speed
            );
            return Err(fail(
                ctx.layers[o].layer,
                ctx.layers[o].points[k].index,
                FailureKind::NoCompatibleNeighbour,
                detail,
            ));
        }
    };
    let unwrapped = match unwrap_path(ctx, built, &path) {
        Ok(p) => p,
        Err(WindUp { joint: j, lo, hi }) => {
            let l = &ctx.layers[range.start];
            return Err(fail(
                l.layer,
                l.points[0].index,
                FailureKind::WindUp,
                format!(
                    "joint {} travels from {lo:.3} to {hi:.3} rad, more than its range {:?}",
                    j + 1,
                    ctx.limits[j]
                ),
            ));
        }
    };
    // Layer summaries and collision checks of the joint-interpolated layer changes; the times
    // come later from [`crate::timing`], once the whole plan is known.
    let mut layers_out = Vec::new();
    let mut r = 0;
    let mut prev_q: Option<Joints> = None;
    for o in range.clone() {
        let layer = &ctx.layers[o];
        if let Some(pq) = prev_q {
            let q1 = unwrapped[r];
            if let Some(msg) = transition_collision(ctx, &scene, world_from_base, &pq, &q1, o) {
                return Err(fail(
                    layer.layer,
                    layer.points[0].index,
                    FailureKind::Transition,
                    msg,
                ));
            }
        }
        let mut wps = Vec::with_capacity(layer.points.len());
        let (mut cost, mut min_c) = (0.0, f64::INFINITY);
        for (k, p) in layer.points.iter().enumerate() {
            let q = unwrapped[r];
            if k > 0 {
                let dq: Vec<f64> = (0..6).map(|j| q[j] - unwrapped[r - 1][j]).collect();
                cost += dq[..n_cost].iter().map(|v| v * v).sum::<f64>();
            }
            // The layer's smallest clearance, each configuration measured only below the
            // smallest so far: the same number as measuring every one in full (up to the
            // cutoff), at a fraction of the queries. Measured on the IK solution itself, not on
            // `q` (the same joints unwrapped by whole turns, whose link poses round differently).
            let canon = built[r].0[path.vertices[r]].q;
            let c = ctx.clearance(
                &scene,
                &canon,
                world_from_base,
                o,
                min_c.min(CLEARANCE_CUTOFF),
            );
            min_c = min_c.min(c.distance);
            wps.push(Waypoint {
                index: p.index,
                t: t0,
                q,
                position: p.position,
                axis: p.axis,
                speed: 0.0,
                hold: 0.0,
            });
            r += 1;
        }
        prev_q = wps.last().map(|w| w.q);
        layers_out.push(LayerPlan::untimed(layer.layer, wps, cost, min_c));
    }
    Ok(Station {
        world_from_base: world_from_base.to_mat4(),
        layers: layers_out,
    })
}

/// The ladder search over the rungs `built`: the valid vertices of the targets `rung_ids`
/// ((layer order, point), in print order). An edge keeps the elbow and wrist branches, moves
/// each joint at most its speed limit (`speed_fraction · v_max`) over the move's time at the
/// print speed, and costs Σ Δq² ≤ ε (module docs). The layer change is a printed move like any
/// other (continuous extrusion), so the same rules hold across it. `seed` drives the random
/// planner. Stations and the moving base search the same way.
pub(crate) fn solve_rungs(
    ctx: &Context,
    rung_ids: &[(usize, usize)],
    built: &[(Vec<Vertex>, Rejections)],
    seed: u64,
) -> Result<LadderPath, LadderFailure> {
    let sizes: Vec<usize> = built.iter().map(|b| b.0.len()).collect();
    let n_cost = if ctx.coaxial { 5 } else { 6 };
    let vmax = ctx.opts.limits.max_speed();
    let steps: Vec<[f64; 6]> = (0..rung_ids.len().saturating_sub(1))
        .map(|r| {
            let (o0, k0) = rung_ids[r];
            let (o1, k1) = rung_ids[r + 1];
            let p0 = DVec3::from(ctx.layers[o0].points[k0].position);
            let p1 = DVec3::from(ctx.layers[o1].points[k1].position);
            let dt = (p1 - p0).length() / ctx.opts.print_speed;
            std::array::from_fn(|j| ctx.opts.speed_fraction * vmax[j] * dt)
        })
        .collect();
    let branch = |q: &Joints| (q[2].sin() > 0.0, q[4].sin() > 0.0);
    let edge = |r: usize, i: usize, j: usize| -> Option<f64> {
        let a = &built[r].0[i].q;
        let b = &built[r + 1].0[j].q;
        let lim = &steps[r];
        if branch(a) != branch(b) {
            return None;
        }
        let d = joint_delta(a, b);
        if (0..n_cost).any(|j| d[j].abs() > lim[j]) {
            return None;
        }
        let c = ctx.step_cost(a, b);
        (c <= ctx.opts.epsilon).then_some(c)
    };
    match ctx.opts.planner {
        PlannerKind::Optimal => solve_optimal(&sizes, edge),
        PlannerKind::Random => solve_random(&sizes, edge, ctx.opts.random_trials, seed),
    }
}

/// No multiple of 2π fits joint `joint`'s travel `lo..hi` (rad) into its range.
pub(crate) struct WindUp {
    pub joint: usize,
    pub lo: f64,
    pub hi: f64,
}

/// The joints along a ladder path: the canonical vertices unwrapped (each step
/// the wrapped Δq; the elbow raw) and every joint shifted by the multiple of 2π that keeps its
/// whole travel inside the limits with its middle nearest zero.
pub(crate) fn unwrap_path(
    ctx: &Context,
    built: &[(Vec<Vertex>, Rejections)],
    path: &LadderPath,
) -> Result<Vec<Joints>, WindUp> {
    let canon: Vec<Joints> = path
        .vertices
        .iter()
        .enumerate()
        .map(|(r, &v)| built[r].0[v].q)
        .collect();
    let mut unwrapped = canon.clone();
    for r in 1..canon.len() {
        let d = joint_delta(&canon[r - 1], &canon[r]);
        for j in 0..6 {
            unwrapped[r][j] = unwrapped[r - 1][j] + d[j];
        }
    }
    let tau = std::f64::consts::TAU;
    for j in 0..6 {
        let lo = unwrapped.iter().map(|q| q[j]).fold(f64::INFINITY, f64::min);
        let hi = unwrapped
            .iter()
            .map(|q| q[j])
            .fold(f64::NEG_INFINITY, f64::max);
        let mid = 0.5 * (lo + hi);
        let mut best: Option<f64> = None;
        for m in -3i32..=3 {
            let s = f64::from(m) * tau;
            if lo + s >= ctx.limits[j][0] - 1e-12
                && hi + s <= ctx.limits[j][1] + 1e-12
                && best.is_none_or(|b| (mid + s).abs() < (mid + b).abs())
            {
                best = Some(s);
            }
        }
        let Some(s) = best else {
            return Err(WindUp { joint: j, lo, hi });
        };
        for q in &mut unwrapped {
            q[j] += s;
        }
    }
    Ok(unwrapped)
}

/// Check the joint-interpolated move a → b at ≤ 1° steps; `order` is the layer about to start
/// (layers before it are printed). Returns a description of the first collision.
pub(crate) fn transition_collision(
    ctx: &Context,
    scene: &Scene,
    world_from_base: &Iso,
    a: &Joints,
    b: &Joints,
    order: usize,
) -> Option<String> {
    let max = (0..6).map(|j| (b[j] - a[j]).abs()).fold(0.0, f64::max);
    let n = ((max / 1f64.to_radians()).ceil() as usize).max(1);
    for s in 1..n {
        let u = s as f64 / n as f64;
        let q: Joints = std::array::from_fn(|j| a[j] + u * (b[j] - a[j]));
        let posed = ctx.self_model.pose(&q, &Iso::IDENTITY);
        let (d, pair) = ctx.self_model.min_self_distance_posed(&posed);
        if d < ctx.opts.self_clearance {
            return Some(format!(
                "self collision {}–{} at {:.0} % of the move",
                LINK_NAMES[pair.0],
                LINK_NAMES[pair.1],
                100.0 * u
            ));
        }
        let c = ctx.clearance(scene, &q, world_from_base, order, CLEARANCE_CUTOFF);
        if c.distance < 0.0 + 1e-12 && c.object.is_some() {
            return Some(format!(
                "{} hits {:?} at {:.0} % of the move",
                LINK_NAMES[c.link],
                c.object.unwrap_or_default(),
                100.0 * u
            ));
        }
    }
    None
}

pub(crate) fn summarise(ctx: &Context, stations: Vec<Station>) -> Plan {
    let mut cost = 0.0;
    let mut motion = 0.0;
    let mut min_c = f64::INFINITY;
    let mut min_self = f64::INFINITY;
    for s in &stations {
        let mut prev: Option<Joints> = None;
        for l in &s.layers {
            min_c = min_c.min(l.min_clearance);
            for w in &l.waypoints {
                if let Some(p) = prev {
                    for j in 0..6 {
                        let d: f64 = w.q[j] - p[j];
                        if !(ctx.coaxial && j == 5) {
                            cost += d * d;
                        }
                        motion += d.abs();
                    }
                }
                let posed = ctx.self_model.pose(&w.q, &Iso::IDENTITY);
                min_self = min_self.min(ctx.self_model.min_self_distance_posed(&posed).0);
                prev = Some(w.q);
            }
        }
    }
    let mut setup = ctx.setup.clone();
    if let [only] = stations.as_slice() {
        setup.base = BasePlacement::Fixed {
            world_from_base: only.world_from_base,
        };
    }
    Plan {
        flange_from_tcp: ctx.flange_from_tcp.to_mat4(),
        cost,
        joint_motion: motion,
        print_time: 0.0,
        total_time: 0.0,
        min_clearance: min_c,
        min_self_distance: min_self,
        max_speed_ratio: 0.0,
        max_acceleration_ratio: 0.0,
        slowdowns: Vec::new(),
        parts: Vec::new(),
        meshes: None,
        certified: None,
        mark: PlanMark::default(),
        setup,
        options: ctx.opts.clone(),
        stations,
    }
}
