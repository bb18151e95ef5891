//! Checking a moving plan from its joints and base trajectory alone: the re-verification, the
//! meshes, and the feasibility under base-pose errors (module docs of [`super`]).

use parry3d_f64::glamx::DVec3;
use rayon::prelude::*;

use super::{Geometry, MovingCheck, MovingPlan};
use crate::error::RobotError;
use crate::frames::{Iso, angle_between};
use crate::kinematics::{Joints, UR10E, within_limits};
use crate::plan::{CLEARANCE_CUTOFF, Waypoint, plan_layers};
use crate::planner::{Context, Select, branch, validate};

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
    let Some((ctx, geo)) = scene(mp, &mut rep.problems) else {
        return rep;
    };
    let plan = &mp.plan;
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
        let c = ctx.clearance(&geo.scene, q, w, order, CLEARANCE_CUTOFF);
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
    crate::error::shorten(&mut problems, 20);
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
    let Some((ctx, geo)) = scene(mp, &mut rep.problems) else {
        return rep;
    };
    let plan = &mp.plan;
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
                let (verts, rej) =
                    geo.vertices_where(&off(k), li, k, Select::on_branch(branch(&w.q), min_c));
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
    crate::error::shorten(&mut rep.problems, 20);
    rep
}

/// The planner's context and the moving scene of `mp`'s plan; `None` with the problem added to
/// `problems` when a check cannot start (the plan's shape, its input, its scene).
fn scene(mp: &MovingPlan, problems: &mut Vec<String>) -> Option<(Context, Geometry)> {
    let built = mp
        .validate_shape()
        .map_err(|e| e.to_string())
        .and_then(|()| {
            let plan = &mp.plan;
            let ctx = validate(&plan_layers(plan), &plan.setup, &plan.options)
                .map_err(|e| format!("invalid plan input: {e}"))?;
            let geo = Geometry::new(&ctx).map_err(|e| format!("scene: {e}"))?;
            Ok((ctx, geo))
        });
    built.map_err(|e| problems.push(e)).ok()
}
