//! The real arm's geometry: UR's convex collision meshes of the UR10e (binary STL, BSD-3, in
//! `assets/ur10e/`, read with `stl_io`, each loaded as a parry `ConvexPolyhedron`), posed by the
//! URDF's own kinematic chain (joint origins and collision origins of
//! `shared/robot/ur10e/urdf/robot_description.urdf`, written out below), and a verification of a
//! plan against them next to the capsule model the planner uses.
//!
//! For every checked waypoint both models are measured against the same environment (beams,
//! mobile base, floor, the layers printed before) and on the same 13 self-collision pairs; the
//! nozzle has no mesh, so it stays a capsule in both. Clearances use `parry3d_f64::query::distance`
//! (GJK on the hulls), which reports 0 for touching or overlapping shapes.

use parry3d_f64::glamx::{DMat3, DQuat, DVec3};
use parry3d_f64::math::Pose;
use parry3d_f64::query;
use parry3d_f64::shape::{Capsule, ConvexPolyhedron};
use rayon::prelude::*;

use crate::collision::{LINK_NAMES, TOOL_LINK};
use crate::error::RobotError;
use crate::frames::Iso;
use crate::kinematics::Joints;
pub use crate::plan::{AlongMotion, ClearanceAt, MESH_CUTOFF, MeshReport, ModelClearance};
use crate::plan::{Plan, plan_layers};
use crate::planner::validate;

const STL: [&[u8]; 7] = [
    include_bytes!("../assets/ur10e/base.stl"),
    include_bytes!("../assets/ur10e/shoulder.stl"),
    include_bytes!("../assets/ur10e/upperarm.stl"),
    include_bytes!("../assets/ur10e/forearm.stl"),
    include_bytes!("../assets/ur10e/wrist1.stl"),
    include_bytes!("../assets/ur10e/wrist2.stl"),
    include_bytes!("../assets/ur10e/wrist3.stl"),
];

/// URDF joint origins (xyz, rpy) of joints 1–6 (`shoulder_pan_joint` … `wrist_3_joint`), with
/// the URDF's own rounding of π/2 (1.570796327), so the chain is exactly the URDF's.
#[allow(clippy::approx_constant)]
const JOINTS: [([f64; 3], [f64; 3]); 6] = [
    ([0.0, 0.0, 0.1807], [0.0, 0.0, 0.0]),
    ([0.0, 0.0, 0.0], [1.570796327, 0.0, 0.0]),
    ([-0.6127, 0.0, 0.0], [0.0, 0.0, 0.0]),
    ([-0.57155, 0.0, 0.17415], [0.0, 0.0, 0.0]),
    (
        [0.0, -0.11985, -2.458164590756244e-11],
        [1.570796327, 0.0, 0.0],
    ),
    (
        [0.0, 0.11655, -2.390480459346185e-11],
        [
            -1.5707963270000003,
            1.2246467991473532e-16,
            -1.2246467991473532e-16,
        ],
    ),
];

const HALF_PI: f64 = std::f64::consts::FRAC_PI_2;
const PI: f64 = std::f64::consts::PI;

/// URDF `<collision><origin>` of each link (base_link_inertia, shoulder … wrist_3).
const COLLISION_ORIGINS: [([f64; 3], [f64; 3]); 7] = [
    ([0.0, 0.0, 0.0], [0.0, 0.0, PI]),
    ([0.0, 0.0, 0.0], [0.0, 0.0, PI]),
    ([0.0, 0.0, 0.1762], [HALF_PI, 0.0, -HALF_PI]),
    ([0.0, 0.0, 0.0393], [HALF_PI, 0.0, -HALF_PI]),
    ([0.0, 0.0, -0.135], [HALF_PI, 0.0, 0.0]),
    ([0.0, 0.0, -0.12], [0.0, 0.0, 0.0]),
    ([0.0, 0.0, -0.1168], [HALF_PI, 0.0, 0.0]),
];

/// URDF origin: `Tr(xyz) · Rz(yaw) · Ry(pitch) · Rx(roll)`.
fn origin(xyz: [f64; 3], rpy: [f64; 3]) -> Iso {
    let r = DMat3::from_rotation_z(rpy[2])
        * DMat3::from_rotation_y(rpy[1])
        * DMat3::from_rotation_x(rpy[0]);
    Iso::new(r, DVec3::from(xyz))
}

/// `base_from_link` of the URDF links base_link_inertia, shoulder … wrist_3 for `q`, and
/// `base_from_tool0`. `base` is the DH base (URDF `base`, = `base_link` turned by π about z).
pub fn urdf_link_frames(q: &Joints) -> ([Iso; 7], Iso) {
    // base_link → base is Rz(π); its inverse is the same rotation.
    let base_from_base_link = Iso::rot_z(PI);
    let mut t = base_from_base_link.mul(&origin([0.0; 3], [0.0, 0.0, PI]));
    let mut frames = [Iso::IDENTITY; 7];
    frames[0] = t;
    for j in 0..6 {
        let (xyz, rpy) = JOINTS[j];
        t = t.mul(&origin(xyz, rpy)).mul(&Iso::rot_z(q[j]));
        frames[j + 1] = t;
    }
    let tool0 = t
        .mul(&origin([0.0; 3], [-HALF_PI, -HALF_PI, 0.0]))
        .mul(&origin([0.0; 3], [HALF_PI, 0.0, HALF_PI]));
    (frames, tool0)
}

/// The seven convex link meshes (in their mesh frames) with their vertex counts.
pub struct ArmMeshes {
    pub hulls: Vec<ConvexPolyhedron>,
    pub vertices: Vec<usize>,
    /// How far (m) each hull reaches outside its link's capsules (≥ 0): the hull lies inside
    /// the capsules inflated by this, so capsule distances minus it bound mesh distances from
    /// below and let most exact hull queries be skipped.
    pub outside_capsules: [f64; 7],
}

impl ArmMeshes {
    /// Read the embedded STL files and build one convex hull per link.
    pub fn load() -> Result<Self, RobotError> {
        let mut hulls = Vec::new();
        let mut vertices = Vec::new();
        for (i, bytes) in STL.iter().enumerate() {
            let mesh = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).map_err(|e| {
                RobotError::invalid(
                    format!("collision mesh of {}", LINK_NAMES[i]),
                    e.to_string(),
                )
            })?;
            let pts: Vec<DVec3> = mesh
                .vertices
                .iter()
                .map(|v| DVec3::new(f64::from(v.0[0]), f64::from(v.0[1]), f64::from(v.0[2])))
                .collect();
            let hull = ConvexPolyhedron::from_convex_hull(&pts).ok_or_else(|| {
                RobotError::invalid(
                    format!("collision mesh of {}", LINK_NAMES[i]),
                    "degenerate: no convex hull",
                )
            })?;
            vertices.push(pts.len());
            hulls.push(hull);
        }
        let mut m = ArmMeshes {
            hulls,
            vertices,
            outside_capsules: [0.0; 7],
        };
        // The offset between a URDF collision frame and its DH frame is constant in q
        // (robot.md §2.1), so one configuration gives it.
        let q = [0.0; 6];
        let poses = m.poses(&q, &Iso::IDENTITY);
        let dh = crate::kinematics::UR10E.fk_frames(&q);
        let caps = crate::collision::ur10e_arm_capsules();
        for i in 0..7 {
            let mut worst = 0.0f64;
            for v in m.hulls[i].points() {
                let p = poses[i].transform_point(*v);
                let d = caps
                    .iter()
                    .filter(|c| c.link == i)
                    .map(|c| {
                        let a = dh[i].point(DVec3::from(c.a));
                        let b = dh[i].point(DVec3::from(c.b));
                        crate::collision::segment_distance(p, p, a, b) - c.radius
                    })
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(d);
            }
            // 1e-9 m: round-off of the transforms.
            m.outside_capsules[i] = worst + 1e-9;
        }
        Ok(m)
    }

    /// World poses of the seven meshes for `q` at base `world_from_base`.
    pub fn poses(&self, q: &Joints, world_from_base: &Iso) -> [Pose; 7] {
        let (frames, _) = urdf_link_frames(q);
        std::array::from_fn(|i| {
            let (xyz, rpy) = COLLISION_ORIGINS[i];
            let w = world_from_base.mul(&frames[i]).mul(&origin(xyz, rpy));
            Pose::from_parts(w.t, DQuat::from_mat3(&w.r).normalize())
        })
    }
}

#[derive(Clone, Debug)]
pub(crate) struct One {
    pub(crate) at: (usize, i64, usize),
    pub(crate) cap_env: (f64, String),
    pub(crate) cap_self: (f64, String),
    pub(crate) nozzle: (f64, String),
    pub(crate) mesh_env: (f64, String),
    pub(crate) mesh_self: (f64, String),
}

fn better(a: &mut ClearanceAt, d: f64, at: (usize, i64, usize), what: &str, first: bool) {
    if first || d < a.distance {
        *a = ClearanceAt {
            distance: d,
            station: at.0,
            layer: at.1,
            index: at.2,
            what: what.to_string(),
        };
    }
}

/// A layer's moves for the along-the-motion bound: print order, layer id, the joint path from
/// the previous layer's end, and its waypoints' rows in the measured list (when all measured).
type LayerPath = (usize, i64, Vec<Joints>, Option<std::ops::Range<usize>>);

/// What one configuration is measured against.
pub(crate) struct Probe<'a> {
    pub(crate) ctx: &'a crate::planner::Context,
    pub(crate) meshes: &'a ArmMeshes,
    pub(crate) scene: &'a crate::collision::Scene,
    pub(crate) world_from_base: Iso,
    pub(crate) tool_caps: &'a [crate::collision::CapsuleSpec],
}

impl Probe<'_> {
    /// Both models at `q`, with the layers printed before print order `o` as obstacles.
    pub(crate) fn measure(&self, q: &Joints, o: usize) -> One {
        let (ctx, meshes, scene, tool_caps) = (self.ctx, self.meshes, self.scene, self.tool_caps);
        let world_from_base = self.world_from_base;
        let q = *q;
        // Capsules, as the planner and check_plan see them.
        let env = ctx.env_model.pose(&q, &world_from_base);
        let arm: Vec<_> = env
            .as_slice()
            .iter()
            .copied()
            .filter(|c| c.link != TOOL_LINK)
            .collect();
        let c = scene.clearance(&arm, o, MESH_CUTOFF);
        let cap_env = (
            c.distance,
            format!("{} – {}", LINK_NAMES[c.link], c.object.unwrap_or_default()),
        );
        let posed = ctx.self_model.pose(&q, &Iso::IDENTITY);
        let (ds, pair) = ctx.self_model.min_self_distance_posed(&posed);
        let cap_self = (ds, format!("{}–{}", LINK_NAMES[pair.0], LINK_NAMES[pair.1]));
        // Meshes: links 1–6 against the environment (the base stands on the mobile
        // base, as in the capsule model), the clipped tool capsules as the nozzle.
        let poses = meshes.poses(&q, &world_from_base);
        let tool_env: Vec<_> = env
            .as_slice()
            .iter()
            .copied()
            .filter(|c| c.link == TOOL_LINK)
            .collect();
        let t = scene.clearance(&tool_env, o, MESH_CUTOFF);
        let nozzle = (
            t.distance,
            format!("nozzle – {}", t.object.unwrap_or_default()),
        );
        let mut mesh_env = (MESH_CUTOFF, String::new());
        for i in 1..7 {
            let link: Vec<_> = env
                .as_slice()
                .iter()
                .copied()
                .filter(|c| c.link == i)
                .collect();
            let lower =
                scene.clearance(&link, o, MESH_CUTOFF).distance - meshes.outside_capsules[i];
            if lower >= mesh_env.0 {
                continue;
            }
            let (d, name) = scene.shape_clearance(&poses[i], &meshes.hulls[i], o, MESH_CUTOFF);
            if d < mesh_env.0 {
                mesh_env = (
                    d,
                    format!("{} – {}", LINK_NAMES[i], name.unwrap_or_default()),
                );
            }
        }
        // Self pairs on the meshes (the nozzle as its full capsules).
        let base_poses = meshes.poses(&q, &Iso::IDENTITY);
        let flange = crate::kinematics::UR10E.fk(&q);
        let mut mesh_self = (f64::INFINITY, String::new());
        let cap_pairs = ctx.self_model.self_pair_distances(&q);
        let mut order: Vec<(f64, usize)> = ctx
            .self_model
            .self_pairs
            .iter()
            .enumerate()
            .map(|(p, &(a, b))| {
                let out_b = if b == TOOL_LINK {
                    0.0
                } else {
                    meshes.outside_capsules[b]
                };
                (cap_pairs[p] - meshes.outside_capsules[a] - out_b, p)
            })
            .collect();
        order.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (lower, p) in order {
            if lower >= mesh_self.0 {
                break;
            }
            let (a, b) = ctx.self_model.self_pairs[p];
            let d = if b == TOOL_LINK {
                tool_caps
                    .iter()
                    .filter_map(|c| {
                        let cap = Capsule::new(
                            flange.point(DVec3::from(c.a)),
                            flange.point(DVec3::from(c.b)),
                            c.radius,
                        );
                        query::distance(&base_poses[a], &meshes.hulls[a], &Pose::IDENTITY, &cap)
                            .ok()
                            .map(|d| d.distance)
                    })
                    .fold(f64::INFINITY, f64::min)
            } else {
                query::distance(
                    &base_poses[a],
                    &meshes.hulls[a],
                    &base_poses[b],
                    &meshes.hulls[b],
                )
                .map_or(f64::INFINITY, |d| d.distance)
            };
            if d < mesh_self.0 {
                mesh_self = (d, format!("{}–{}", LINK_NAMES[a], LINK_NAMES[b]));
            }
        }
        One {
            at: (0, 0, 0),
            cap_env,
            cap_self,
            nozzle,
            mesh_env,
            mesh_self,
        }
    }
}

/// Verify `plan` against UR's convex collision meshes and the capsules, every `stride`-th
/// waypoint of each layer plus each layer's first and last.
pub fn verify_meshes(plan: &Plan, stride: usize) -> Result<MeshReport, RobotError> {
    let stride = stride.max(1);
    let meshes = ArmMeshes::load()?;
    let layers = plan_layers(plan);
    let ctx = validate(&layers, &plan.setup, &plan.options)?;
    let tool_caps: Vec<_> = ctx
        .self_model
        .capsules
        .iter()
        .filter(|c| c.link == TOOL_LINK)
        .cloned()
        .collect();
    // Motion bounds of the mesh model: the hulls lie inside their capsules inflated by
    // `outside_capsules`, the nozzle is its full capsules (crate::sweep).
    let mut extra = [0.0; 8];
    extra[..7].copy_from_slice(&meshes.outside_capsules);
    let bounds = crate::sweep::SweepBounds::for_capsules(
        &crate::kinematics::UR10E,
        &ctx.self_model.capsules,
        extra,
    );
    let self_pairs = ctx.self_model.self_pairs.clone();
    let displacement = |tv: &[f64; 6]| -> [f64; 3] {
        let env = (1..7).map(|k| bounds.world(tv, k)).fold(0.0, f64::max);
        let slf = self_pairs
            .iter()
            .map(|&(a, b)| bounds.relative(tv, a, b))
            .fold(0.0, f64::max);
        [env, bounds.world(tv, TOOL_LINK), slf]
    };
    let mut along = AlongMotion::default();
    let mut along_min = [(f64::INFINITY, 0usize, 0i64); 3];
    let mut along_problems: Vec<String> = Vec::new();
    let mut out: Vec<One> = Vec::new();
    let mut order = 0usize;
    for (si, st) in plan.stations.iter().enumerate() {
        let world_from_base = Iso::from_mat4(&st.world_from_base)
            .map_err(|e| RobotError::invalid(format!("station {} world_from_base", si + 1), e))?;
        let scene = ctx.scene(&world_from_base)?;
        let probe = Probe {
            ctx: &ctx,
            meshes: &meshes,
            scene: &scene,
            world_from_base,
            tool_caps: &tool_caps,
        };
        let first_order = order;
        let mut jobs: Vec<(usize, i64, usize, Joints)> = Vec::new();
        for l in &st.layers {
            let n = l.waypoints.len();
            for (k, w) in l.waypoints.iter().enumerate() {
                if k % stride == 0 || k + 1 == n {
                    jobs.push((order, l.layer, w.index, w.q));
                }
            }
            order += 1;
        }
        let res: Vec<One> = jobs
            .par_iter()
            .map(|&(o, layer, index, q)| {
                let mut one = probe.measure(&q, o);
                one.at = (si, layer, index);
                one
            })
            .collect();
        let station_rows = out.len();
        out.extend(res);
        // Along the motion: each layer's moves from the previous layer's end (crate::sweep),
        // split where a bound is below the planner's margins (contact is the failure).
        // With every waypoint measured above (stride 1), a layer's rows are reused; only the
        // previous layer's end is measured again, with this layer's obstacles.
        let mut paths: Vec<LayerPath> = Vec::new();
        let mut row = station_rows;
        for (k, (l, path)) in st.layers.iter().zip(st.layer_paths()).enumerate() {
            let rows = (stride == 1).then(|| row..row + l.waypoints.len());
            row += l.waypoints.len();
            paths.push((first_order + k, l.layer, path, rows));
        }
        let required = [
            plan.options.clearance,
            plan.options.clearance,
            plan.options.self_clearance,
        ];
        // A mesh fails only on contact (0 = touching).
        let contact = [0.0; 3];
        let certified: Vec<(i64, [f64; 3], usize)> = paths
            .par_iter()
            .map(|(o, layer, path, rows)| {
                let measure = |q: &Joints| {
                    let m = probe.measure(q, *o);
                    [m.mesh_env.0, m.nozzle.0, m.mesh_self.0]
                };
                let Some(rows) = rows.clone().filter(|r| r.end <= out.len()) else {
                    let (lb, n) = crate::sweep::certify(
                        path,
                        &measure,
                        &displacement,
                        required,
                        contact,
                        None,
                    );
                    return (*layer, lb, n);
                };
                let skip = path.len() - rows.len();
                let measured: Vec<[f64; 3]> = path[..skip]
                    .iter()
                    .map(measure)
                    .chain(
                        out[rows]
                            .iter()
                            .map(|m| [m.mesh_env.0, m.nozzle.0, m.mesh_self.0]),
                    )
                    .collect();
                let (lb, n) = crate::sweep::certify_measured(
                    path,
                    &measured,
                    &measure,
                    &displacement,
                    required,
                    contact,
                    None,
                );
                (*layer, lb, n + measured.len())
            })
            .collect();
        for (layer, lb, n) in certified {
            along.configurations += n;
            for (c, v) in lb.iter().enumerate() {
                if *v < along_min[c].0 {
                    along_min[c] = (*v, si, layer);
                }
            }
            if lb.iter().any(|v| *v <= 0.0) && along_problems.len() < 20 {
                along_problems.push(format!(
                    "station {} layer {layer}: between the waypoints the collision meshes may touch (certified clearance to the environment {:.4} m, nozzle {:.4} m, self {:.4} m)",
                    si + 1,
                    lb[0],
                    lb[1],
                    lb[2]
                ));
            }
        }
    }
    let at = |c: usize| ClearanceAt {
        distance: along_min[c].0,
        station: along_min[c].1,
        layer: along_min[c].2,
        index: 0,
        what: String::new(),
    };
    along.environment = at(0);
    along.nozzle = at(1);
    along.self_distance = at(2);
    let mut rep = report_of(&out, &meshes, Some(along));
    rep.problems.extend(along_problems);
    Ok(rep)
}

/// The report of measured configurations `out`: the least clearance of each model and where,
/// and a problem per contact (at most 20).
pub(crate) fn report_of(out: &[One], meshes: &ArmMeshes, along: Option<AlongMotion>) -> MeshReport {
    let mut rep = MeshReport {
        waypoints_checked: out.len(),
        mesh_vertices: meshes.vertices.clone(),
        along_motion: along,
        ..Default::default()
    };
    for (k, o) in out.iter().enumerate() {
        let first = k == 0;
        better(
            &mut rep.capsules.environment,
            o.cap_env.0,
            o.at,
            &o.cap_env.1,
            first,
        );
        better(
            &mut rep.capsules.self_distance,
            o.cap_self.0,
            o.at,
            &o.cap_self.1,
            first,
        );
        better(
            &mut rep.meshes.environment,
            o.mesh_env.0,
            o.at,
            &o.mesh_env.1,
            first,
        );
        better(&mut rep.nozzle, o.nozzle.0, o.at, &o.nozzle.1, first);
        better(
            &mut rep.meshes.self_distance,
            o.mesh_self.0,
            o.at,
            &o.mesh_self.1,
            first,
        );
        if o.mesh_env.0.min(o.nozzle.0) <= 0.0 && rep.problems.len() < 20 {
            rep.problems.push(format!(
                "station {} layer {} point {}: the collision mesh touches the environment ({})",
                o.at.0 + 1,
                o.at.1,
                o.at.2,
                o.mesh_env.1
            ));
        }
        if o.mesh_self.0 <= 0.0 && rep.problems.len() < 20 {
            rep.problems.push(format!(
                "station {} layer {} point {}: the collision meshes {} touch",
                o.at.0 + 1,
                o.at.1,
                o.at.2,
                o.mesh_self.1
            ));
        }
    }
    rep
}

/// Run [`verify_meshes`] and keep the report in the plan (`Plan::meshes`); a mesh contact is an
/// error, like any failed verification.
pub fn attach_mesh_report(plan: &mut Plan, stride: usize) -> Result<(), RobotError> {
    let rep = verify_meshes(plan, stride)?;
    if !rep.problems.is_empty() {
        return Err(RobotError::Verification(rep.problems));
    }
    plan.meshes = Some(rep);
    Ok(())
}
