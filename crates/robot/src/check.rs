//! Independent re-verification of a plan from its joint values alone: FK against the stored
//! targets, joint limits, singularity margins, self-collision, clearance to the environment and
//! the printed layers, continuity and joint speeds inside layers, monotonic time, and the
//! transitions between layers. Nothing computed by the planner (clearances, costs) is trusted.

use parry3d_f64::glamx::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::frames::{Iso, angle_between};
use crate::kinematics::{Joints, UR10E, within_limits};
use crate::plan::{CLEARANCE_CUTOFF, CertifiedClearance, Plan, Station, plan_layers};
use crate::planner::{transition_collision, validate};
use crate::setup::PlanOptions;

/// Smallest certified clearance of the approach and retract moves (m): clear of contact.
const CONTACT: f64 = 1e-9;

/// Tolerance of the TCP position (m) and tool axis (rad) on the targets (acceptance: 1e-6).
pub const TARGET_TOL: f64 = 1e-6;

// The certified values sit in the plan (`Plan::certified`), which stands below the check.
impl CertifiedClearance {
    /// The certified values of a check report.
    pub fn of(rep: &CheckReport) -> Self {
        CertifiedClearance {
            clearance: rep.certified_clearance,
            approach_clearance: rep.certified_approach_clearance,
            self_distance: rep.certified_self_distance,
            configurations: rep.certified_configurations,
        }
    }
}

/// Result of [`check_plan`]; the plan is valid when `problems` is empty.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CheckReport {
    pub waypoints: usize,
    pub max_position_error: f64,
    pub max_axis_error: f64,
    pub min_clearance: f64,
    pub min_self_distance: f64,
    /// Largest |q̇_j| / (s·v_j,max) and |q̈_j| / a_j,max over the rows of the trajectory.
    pub max_speed_ratio: f64,
    pub max_acceleration_ratio: f64,
    /// Certified smallest clearance to the environment along every print move (layer changes
    /// included), joint-interpolated between the waypoints ([`crate::sweep`]): a lower bound,
    /// not a sample (m, capped at 0.5); split until it holds the margin `clearance`.
    #[serde(default)]
    pub certified_clearance: f64,
    /// The same along the station approaches and retracts, which need only be clear of contact
    /// (they descend onto and leave the print).
    #[serde(default)]
    pub certified_approach_clearance: f64,
    /// Certified smallest self distance along the same motions (m).
    #[serde(default)]
    pub certified_self_distance: f64,
    /// Configurations measured for the certified bounds (waypoints and added midpoints).
    #[serde(default)]
    pub certified_configurations: usize,
    pub problems: Vec<String>,
}

/// Re-verify `plan`. At most 20 problems are listed (with a count of the rest).
pub fn check_plan(plan: &Plan) -> CheckReport {
    let mut rep = CheckReport {
        min_clearance: f64::INFINITY,
        min_self_distance: f64::INFINITY,
        certified_clearance: f64::INFINITY,
        certified_approach_clearance: f64::INFINITY,
        certified_self_distance: f64::INFINITY,
        ..Default::default()
    };
    let mut problems = Vec::new();
    let layers = plan_layers(plan);
    let ctx = match validate(&layers, &plan.setup, &plan.options) {
        Ok(c) => c,
        Err(e) => {
            rep.problems
                .push(format!("the plan's setup or targets are invalid: {e}"));
            return rep;
        }
    };
    let flange_from_tcp = match Iso::from_mat4(&plan.flange_from_tcp) {
        Ok(t) => t,
        Err(e) => {
            rep.problems.push(format!("flange_from_tcp: {e}"));
            return rep;
        }
    };
    if flange_from_tcp.max_abs_diff(&ctx.flange_from_tcp) > 1e-12 {
        problems.push("flange_from_tcp differs from the setup's tool".to_string());
    }
    let opts = &plan.options;
    // Motion bounds of the two models (see crate::sweep): the environment channel is any
    // environment capsule's world motion, the self channel any checked pair's relative motion.
    let env_bounds =
        crate::sweep::SweepBounds::for_capsules(&UR10E, &ctx.env_model.capsules, [0.0; 8]);
    let self_bounds =
        crate::sweep::SweepBounds::for_capsules(&UR10E, &ctx.self_model.capsules, [0.0; 8]);
    let env_links: Vec<usize> = ctx.env_model.capsules.iter().map(|c| c.link).collect();
    let displacement = |tv: &[f64; 6]| -> [f64; 2] {
        let env = env_links
            .iter()
            .map(|&k| env_bounds.world(tv, k))
            .fold(0.0, f64::max);
        let slf = ctx
            .self_model
            .self_pairs
            .iter()
            .map(|&(a, b)| self_bounds.relative(tv, a, b))
            .fold(0.0, f64::max);
        [env, slf]
    };
    let mut order = 0usize;
    let mut last_t = f64::NEG_INFINITY;
    for (si, st) in plan.stations.iter().enumerate() {
        let world_from_base = match Iso::from_mat4(&st.world_from_base) {
            Ok(w) => w,
            Err(e) => {
                problems.push(format!("station {}: world_from_base {e}", si + 1));
                order += st.layers.len();
                continue;
            }
        };
        if let Err(e) = ctx.check_base(&world_from_base) {
            problems.push(format!("station {}: {e}", si + 1));
        }
        let scene = match ctx.scene(&world_from_base) {
            Ok(s) => s,
            Err(e) => {
                problems.push(format!("station {}: {e}", si + 1));
                order += st.layers.len();
                continue;
            }
        };
        // The approach from the safe pose behind the station's first target and the retract
        // after its last (joint-interpolated, like the layer changes; the pose itself too).
        let ends = [
            st.layers
                .first()
                .and_then(|l| l.waypoints.first())
                .map(|w| (w.q, order, "approach")),
            st.layers
                .last()
                .and_then(|l| l.waypoints.last())
                .map(|w| (w.q, order + st.layers.len(), "retract")),
        ];
        for (q, tag, what) in ends.into_iter().flatten() {
            match crate::kinematics::approach_config(
                &q,
                &flange_from_tcp,
                opts.program.approach_distance,
                &ctx.limits,
            ) {
                Ok(qa) => {
                    let posed = ctx.self_model.pose(&qa, &Iso::IDENTITY);
                    let (ds, _) = ctx.self_model.min_self_distance_posed(&posed);
                    let c = ctx.clearance(&scene, &qa, &world_from_base, tag, CLEARANCE_CUTOFF);
                    if ds < opts.self_clearance || (c.distance <= 1e-12 && c.object.is_some()) {
                        problems.push(format!(
                            "station {}: the {what} pose collides ({:?})",
                            si + 1,
                            c.object.unwrap_or_default()
                        ));
                    } else if let Some(msg) =
                        transition_collision(&ctx, &scene, &world_from_base, &qa, &q, tag)
                    {
                        problems.push(format!("station {}: {what}: {msg}", si + 1));
                    }
                }
                Err(e) => problems.push(format!("station {}: {what}: {e}", si + 1)),
            }
        }
        // Certified along the motion: each layer's moves from the previous layer's end (the
        // layer change is a printed move), with that layer's obstacles; the approach and the
        // retract need only be clear of contact.
        let mut motions: Vec<(Vec<Joints>, usize, [f64; 2], String)> = Vec::new();
        for (what, q, tag) in ends.iter().flatten().map(|(q, tag, what)| (what, q, tag)) {
            if let Ok(qa) = crate::kinematics::approach_config(
                q,
                &flange_from_tcp,
                opts.program.approach_distance,
                &ctx.limits,
            ) {
                motions.push((
                    vec![qa, *q],
                    *tag,
                    [CONTACT, opts.self_clearance],
                    format!("station {}: the {what}", si + 1),
                ));
            }
        }
        for (o, (l, path)) in st.layers.iter().zip(st.layer_paths()).enumerate() {
            motions.push((
                path,
                order + o,
                [opts.clearance, opts.self_clearance],
                format!("station {}: the moves of layer {}", si + 1, l.layer),
            ));
        }
        let run = |k: usize| {
            // Split only where the bound is below the margin, so the certified minimum is a
            // proof that the margin holds (tight only where it is near the margin).
            let (path, tag, required, _) = &motions[k];
            let measure = |q: &Joints| -> [f64; 2] {
                let c = ctx.clearance(&scene, q, &world_from_base, *tag, CLEARANCE_CUTOFF);
                let posed = ctx.self_model.pose(q, &Iso::IDENTITY);
                [c.distance, ctx.self_model.min_self_distance_posed(&posed).0]
            };
            crate::sweep::certify(path, &measure, &displacement, *required, *required, None)
        };
        let certified: Vec<([f64; 2], usize)> =
            (0..motions.len()).into_par_iter().map(run).collect();
        for ((lb, n), (_, _, required, what)) in certified.iter().zip(&motions) {
            if required[0] == CONTACT {
                rep.certified_approach_clearance = rep.certified_approach_clearance.min(lb[0]);
            } else {
                rep.certified_clearance = rep.certified_clearance.min(lb[0]);
            }
            rep.certified_self_distance = rep.certified_self_distance.min(lb[1]);
            rep.certified_configurations += n;
            // 1e-9 m: round-off of re-posing the same capsules.
            if lb[0] < required[0] - 1e-9 || lb[1] < required[1] - 1e-9 {
                problems.push(format!(
                    "{what}: along the motion the clearance is only certified ≥ {:.4} m (needs {} m) and the self distance ≥ {:.4} m (needs {} m)",
                    lb[0], required[0], lb[1], required[1]
                ));
            }
        }
        let mut prev_end: Option<[f64; 6]> = None;
        for l in &st.layers {
            if let (Some(a), Some(w0)) = (prev_end, l.waypoints.first())
                && let Some(msg) =
                    transition_collision(&ctx, &scene, &world_from_base, &a, &w0.q, order)
            {
                problems.push(format!("move into layer {}: {msg}", l.layer));
            }
            let mut branch = None;
            for w in &l.waypoints {
                rep.waypoints += 1;
                let at = || format!("station {} layer {} point {}", si + 1, l.layer, w.index);
                let q = w.q;
                if !q.iter().all(|v| v.is_finite()) {
                    problems.push(format!("{}: non-finite joints", at()));
                    continue;
                }
                if w.t.partial_cmp(&last_t).is_none_or(|o| o.is_lt()) {
                    problems.push(format!("{}: time {} s goes backwards", at(), w.t));
                }
                last_t = w.t;
                let base_flange = UR10E.fk(&q);
                let world_tcp = world_from_base.mul(&base_flange).mul(&flange_from_tcp);
                let dp = (world_tcp.t - DVec3::from(w.position)).length();
                let da = angle_between(world_tcp.r.z_axis, DVec3::from(w.axis));
                rep.max_position_error = rep.max_position_error.max(dp);
                rep.max_axis_error = rep.max_axis_error.max(da);
                if dp > TARGET_TOL || da > TARGET_TOL {
                    problems.push(format!(
                        "{}: TCP misses the target by {dp:.3e} m, axis by {da:.3e} rad",
                        at()
                    ));
                }
                if !within_limits(&q, &ctx.limits) {
                    problems.push(format!("{}: joints {q:?} outside the limits", at()));
                }
                if !ctx.margins_ok(&q, &base_flange) {
                    problems.push(format!(
                        "{}: singularity margin violated (|sin q5| = {:.4}, |sin q3| = {:.4}, shoulder {:.4} m)",
                        at(),
                        q[4].sin().abs(),
                        q[2].sin().abs(),
                        UR10E.shoulder_margin(&base_flange)
                    ));
                }
                let b = (q[2].sin() > 0.0, q[4].sin() > 0.0);
                if *branch.get_or_insert(b) != b {
                    problems.push(format!(
                        "{}: elbow/wrist branch changes inside the layer",
                        at()
                    ));
                }
                let posed = ctx.self_model.pose(&q, &Iso::IDENTITY);
                let (ds, pair) = ctx.self_model.min_self_distance_posed(&posed);
                rep.min_self_distance = rep.min_self_distance.min(ds);
                // 1e-9 m: round-off of re-posing the same capsules.
                if ds < opts.self_clearance - 1e-9 {
                    problems.push(format!(
                        "{}: self distance {ds:.4} m between links {pair:?}",
                        at()
                    ));
                }
                let c = ctx.clearance(&scene, &q, &world_from_base, order, CLEARANCE_CUTOFF);
                rep.min_clearance = rep.min_clearance.min(c.distance);
                if c.distance < opts.clearance - 1e-9 {
                    problems.push(format!(
                        "{}: clearance {:.4} m to {:?} below the margin {} m",
                        at(),
                        c.distance,
                        c.object.unwrap_or_default(),
                        opts.clearance
                    ));
                }
                if !(w.hold.is_finite() && w.hold >= 0.0) {
                    problems.push(format!("{}: hold {} s is not ≥ 0", at(), w.hold));
                }
            }
            prev_end = l.waypoints.last().map(|w| w.q);
            order += 1;
        }
        let (ratio_v, ratio_a) = check_rates(si, st, opts, &mut problems);
        rep.max_speed_ratio = rep.max_speed_ratio.max(ratio_v);
        rep.max_acceleration_ratio = rep.max_acceleration_ratio.max(ratio_a);
    }
    crate::error::shorten(&mut problems, 20);
    rep.problems = problems;
    rep
}

/// Joint speeds and accelerations of one station from its rows alone (arrival and, where the
/// robot holds, departure of every waypoint; at rest before the first and after the last):
/// v = Δq/Δt per segment, a = Δv/τ with τ the mean of the two segment durations.
/// Returns the largest speed ratio (to s·v_max) and acceleration ratio (to a_max).
fn check_rates(
    si: usize,
    st: &Station,
    opts: &PlanOptions,
    problems: &mut Vec<String>,
) -> (f64, f64) {
    let vmax = opts.limits.max_speed();
    let amax = opts.limits.max_acceleration;
    // Rows: (time, q, label).
    let mut rows: Vec<(f64, [f64; 6], (i64, usize))> = Vec::new();
    for l in &st.layers {
        for w in &l.waypoints {
            rows.push((w.t, w.q, (l.layer, w.index)));
            if w.hold > 0.0 {
                rows.push((w.t + w.hold, w.q, (l.layer, w.index)));
            }
        }
    }
    // Segment velocities, with zero-length rests at both ends.
    let mut segs: Vec<(f64, [f64; 6])> = vec![(0.0, [0.0; 6])];
    let (mut rv, mut ra) = (0.0f64, 0.0f64);
    for k in 1..rows.len() {
        let (t0, q0, _) = rows[k - 1];
        let (t1, q1, at) = rows[k];
        let dt = t1 - t0;
        let moved = (0..6).any(|j| q1[j] != q0[j]);
        if dt <= 0.0 && moved {
            problems.push(format!(
                "station {} layer {} point {}: moves in {dt} s",
                si + 1,
                at.0,
                at.1
            ));
            continue;
        }
        let v: [f64; 6] =
            std::array::from_fn(|j| if dt > 0.0 { (q1[j] - q0[j]) / dt } else { 0.0 });
        for j in 0..6 {
            let r = v[j].abs() / (opts.speed_fraction * vmax[j]);
            rv = rv.max(r);
            // 1e-9: relative slack for the division.
            if r > 1.0 + 1e-9 {
                problems.push(format!(
                    "station {} layer {} point {}: joint {} at {:.3} of its usable speed",
                    si + 1,
                    at.0,
                    at.1,
                    j + 1,
                    r
                ));
            }
        }
        segs.push((dt.max(0.0), v));
    }
    segs.push((0.0, [0.0; 6]));
    for k in 0..segs.len().saturating_sub(1) {
        let tau = 0.5 * (segs[k].0 + segs[k + 1].0);
        if tau <= 0.0 {
            continue;
        }
        for j in 0..6 {
            let r = (segs[k + 1].1[j] - segs[k].1[j]).abs() / tau / amax[j];
            ra = ra.max(r);
            // 1e-6: the timing leaves ≥ 1e-9 relative margin; the rows' f64 round-off is far below.
            if r > 1.0 + 1e-6 {
                let at = rows
                    .get(k.min(rows.len().saturating_sub(1)))
                    .map_or((0, 0), |r| r.2);
                problems.push(format!(
                    "station {} near layer {} point {}: joint {} accelerates at {:.3} of its limit",
                    si + 1,
                    at.0,
                    at.1,
                    j + 1,
                    r
                ));
            }
        }
    }
    (rv, ra)
}
