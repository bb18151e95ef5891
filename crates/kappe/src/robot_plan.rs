//! From the print path to a verified UR10e plan (paper §3.4, method.md §8): the layers' targets
//! go to `kappe_robot::plan_print` with the support beams as obstacles and the bead settings of
//! the design. The planner verifies the plan before it returns it.

use kappe_robot::Plan;
use kappe_robot::setup::{PathPoint as RobotPoint, PrintLayer, beams};

use crate::form::cap::Cap;
use crate::form::path::PrintPath;

/// The print targets grouped by layer, in print order (the `layer,index` of `path.csv`).
pub fn print_layers(path: &PrintPath) -> Vec<PrintLayer> {
    let mut layers: Vec<PrintLayer> = Vec::new();
    for p in &path.points {
        let point = RobotPoint {
            index: p.index,
            position: [p.tip.x, p.tip.y, p.tip.z],
            axis: [p.axis.x, p.axis.y, p.axis.z],
        };
        match layers.last_mut() {
            Some(l) if l.layer == i64::from(p.layer) => l.points.push(point),
            _ => layers.push(PrintLayer {
                layer: i64::from(p.layer),
                points: vec![point],
            }),
        }
    }
    layers
}

/// The robot cell and planner options of a design, with the beams under the cap added.
pub fn robot_inputs(
    cap: &Cap,
) -> (
    kappe_robot::setup::RobotSetup,
    kappe_robot::setup::PlanOptions,
) {
    let d = &cap.design;
    let r = &d.robot;
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &cap.path.points {
        y0 = y0.min(p.bead.y);
        y1 = y1.max(p.bead.y);
    }
    let mut setup = r.setup.clone();
    // Place the bases with the margin the tolerance check then verifies (issue 28).
    if r.tolerance.check
        && let kappe_robot::BasePlacement::Search(search) = &mut setup.base
        && search.margin.is_none()
    {
        search.margin = Some(r.tolerance.base_tolerance());
    }
    setup.obstacles.extend(beams(
        d.cap.span,
        r.beams.width,
        r.beams.height,
        y0 - r.beams.overrun,
        y1 + r.beams.overrun,
    ));
    setup.obstacles.extend(end_wall(cap, setup.floor_z));
    let mut opts = r.plan.clone();
    opts.print_speed = d.print.print_speed;
    opts.bead_radius = 0.5 * d.print.layer_width;
    opts.bead_offset = 0.5 * d.print.layer_height;
    (setup, opts)
}

/// Thickness of the end wall drawn as an obstacle, m (a masonry gable wall; only its face
/// matters to the robot, which works in front of it).
const END_WALL_THICKNESS: f64 = 0.25;
/// How far the end wall reaches beyond the beams' outer faces and above the crown, m.
const END_WALL_MARGIN: f64 = 0.5;

/// The end wall of an end-wall cap (issue 15, `crate::form::ends`) as a robot obstacle: a vertical
/// box behind the wall face, from the floor (or the beams' underside) to `END_WALL_MARGIN` above
/// the crown, its front face through the crown of the inclined bearing plane (the point of the
/// face farthest back: the vertical gable wall, with the inclined wedge in front of it below the
/// crown, which lies behind layer 0 and so never in the robot's way). None for other ends.
fn end_wall(cap: &Cap, floor_z: Option<f64>) -> Option<kappe_robot::collision::Obstacle> {
    if cap.design.cap.end != crate::form::ends::EndKind::EndWall {
        return None;
    }
    let face_y = cap
        .final_state
        .network
        .nodes
        .iter()
        .filter(|n| n.role == crate::form::states::Role::ColumnEnd)
        .map(|n| n.xyz.y)
        .fold(f64::INFINITY, f64::min);
    if !face_y.is_finite() {
        return None;
    }
    let d = &cap.design;
    let bottom = floor_z.unwrap_or(-d.robot.beams.height);
    let top = d.cap.rise + END_WALL_MARGIN;
    let half_x = 0.5 * d.cap.span + d.robot.beams.width + END_WALL_MARGIN;
    Some(kappe_robot::collision::Obstacle::Box {
        name: "end_wall".into(),
        center: [0.0, face_y - 0.5 * END_WALL_THICKNESS, 0.5 * (bottom + top)],
        half_extents: [half_x, 0.5 * END_WALL_THICKNESS, 0.5 * (top - bottom).abs()],
        yaw: 0.0,
    })
}

/// Plan the robot for the whole print: a continuous bead per station, timed on one clock (the
/// design's minimum layer time gives the waits), cut into controller-sized programs, and
/// verified with the capsules and with UR's collision meshes (`Plan::meshes`).
pub fn plan_robot(cap: &Cap) -> Result<Plan, kappe_robot::RobotError> {
    plan_robot_with_waits(cap, None)
}

/// [`plan_robot`] with per-layer waits (seconds after each layer, e.g. from the time-dependent
/// schedule) instead of the minimum layer time. To change only the waits of a plan you already
/// have, use [`kappe_robot::retime`].
pub fn plan_robot_with_waits(
    cap: &Cap,
    waits: Option<&[kappe_robot::LayerWait]>,
) -> Result<Plan, kappe_robot::RobotError> {
    let (setup, opts) = robot_inputs(cap);
    let mut plan =
        kappe_robot::plan_print_with_waits(&print_layers(&cap.path), &setup, &opts, waits)?;
    kappe_robot::meshes::attach_mesh_report(&mut plan, 1)?;
    Ok(plan)
}

/// Plan the robot with the base moving while it prints (issue 27, `[robot.base] mode =
/// "moving"`): `kappe_robot::plan_moving` on the same layers, cell and options as
/// [`plan_robot_with_waits`]. The returned plan's `plan` is an ordinary [`Plan`] with one
/// station (the base at travel 0) on the moving clock, so the schedule and the summary read it
/// as any plan. UR's collision meshes are not attached: their report poses the arm from fixed
/// stations, which a moving base has not (the moving check certifies the capsules along every
/// move with arm and base moving together instead).
pub fn plan_robot_moving(
    cap: &Cap,
    base: &kappe_robot::MovingBase,
    waits: Option<&[kappe_robot::LayerWait]>,
) -> Result<kappe_robot::MovingPlan, kappe_robot::RobotError> {
    let (setup, opts) = robot_inputs(cap);
    kappe_robot::plan_moving(&print_layers(&cap.path), &setup, &opts, base, waits)
}

/// When each layer is printed on the plan's clock (start = arrival at its first target, end =
/// arrival at its last, and the wait and whole pause after it): the times the programs and
/// `trajectory.csv` use, for the structural schedule.
pub fn layer_schedule(plan: &Plan) -> Vec<kappe_robot::LayerTime> {
    kappe_robot::layer_times(plan)
}

/// The arm drawn as capsules over time, for the report's animation.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ArmFrames {
    /// Time of each frame, s.
    pub times: Vec<f64>,
    /// Joint values of each frame, rad.
    pub joints: Vec<[f64; 6]>,
    /// Radius of each capsule, m.
    pub radii: Vec<f64>,
    /// Per frame, the world end points of each capsule.
    pub segments: Vec<Vec<[[f64; 3]; 2]>>,
}

/// Pose the UR10e capsule model (arm + tool) along the plan, at most `max_frames` evenly spread
/// waypoints (the report embeds them; every waypoint would make the page large).
pub fn arm_frames(
    plan: &Plan,
    tool: &kappe_robot::setup::Tool,
    max_frames: usize,
) -> Result<ArmFrames, kappe_robot::RobotError> {
    use kappe_robot::collision::{CapsuleSpec, RobotModel};
    // Tool capsules live on link 7 (the flange frame) in the robot crate's model.
    let tool_specs: Vec<CapsuleSpec> = tool
        .capsules
        .iter()
        .enumerate()
        .map(|(i, c)| CapsuleSpec {
            link: 7,
            name: format!("tool_{i}"),
            a: c.a,
            b: c.b,
            radius: c.radius,
        })
        .collect();
    let model = RobotModel::ur10e_with_tool(&tool_specs)?;
    let all: Vec<(usize, &kappe_robot::Waypoint)> = plan
        .stations
        .iter()
        .enumerate()
        .flat_map(|(s, st)| {
            st.layers
                .iter()
                .flat_map(move |l| l.waypoints.iter().map(move |w| (s, w)))
        })
        .collect();
    let stride = all.len().div_ceil(max_frames.max(1)).max(1);
    let bases: Vec<kappe_robot::Iso> = plan
        .stations
        .iter()
        .map(|s| kappe_robot::Iso::from_mat4_unchecked(&s.world_from_base))
        .collect();
    let mut out = ArmFrames::default();
    for (k, (s, w)) in all.iter().enumerate() {
        if k % stride != 0 && k + 1 != all.len() {
            continue;
        }
        let posed = model.pose(&w.q, &bases[*s]);
        let caps = posed.as_slice();
        if out.radii.is_empty() {
            out.radii = caps.iter().map(|c| c.radius).collect();
        }
        out.times.push(w.t);
        out.joints.push(w.q);
        out.segments.push(
            caps.iter()
                .map(|c| [[c.a.x, c.a.y, c.a.z], [c.b.x, c.b.y, c.b.z]])
                .collect(),
        );
    }
    Ok(out)
}
