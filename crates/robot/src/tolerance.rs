//! Base-pose tolerance: a relocated mobile base is never exactly where the plan put it. After a
//! drive the base is localised (measured) and the controller re-solves the joints for the same
//! nozzle targets from the measured pose, so what must survive a pose error is not the joint
//! trajectory but its *feasibility*: every target reachable with a valid configuration on the
//! planned IK branch, joint limits and singularity margins kept, clearance to the environment at
//! least the plan's margin, and the mobile-base body clear of every static obstacle.
//!
//! [`check_base_tolerance`] checks this for every station of a plan over the box of base-pose
//! errors `|dx|, |dy| ≤ position`, `|dyaw| ≤ yaw` (the base drives on the floor: z, roll and pitch
//! are fixed by the floor and the platform). It samples the 8 corners of that box and its centre.
//! Why corners suffice: the errors are small (≤ 10 mm, ≤ 1° by default) against the lengths that
//! set the clearances (links ~0.6 m, distances ≥ 10 mm), so every clearance is, to first order, an
//! affine function of (dx, dy, dyaw), and an affine function takes its minimum over a box at a
//! corner. The mobile-base body is rigid with the base, so its clearance is checked exactly at the
//! corners too (a box's distance to a fixed box is minimised at an extreme pose for small
//! rotations, by the same argument).
//!
//! Per corner and waypoint the valid IK configurations are those the planner itself accepts
//! ([`crate::planner`]: limits, singularity margins, self-collision, clearance ≥ the plan's margin,
//! printed layers as obstacles); the one nearest the planned joints on the same elbow/wrist branch
//! is taken, and consecutive ones must stay within the plan's compatibility ε (the trajectory is
//! re-solvable without a reconfiguration). Only the planned branch's IK solutions are checked at
//! all ([`crate::planner::Select::on_branch`]): the other six of the eight could never
//! be taken, and measuring their clearances was most of the check's time (`kappe design` of the
//! moving bay example: 95 → 37 s; the 1.5 m × 4 m bay: 78 → 58 s; the same reports). Hand-written: it is a property of this planner's
//! acceptance rules, which no crate knows.

use rayon::prelude::*;
use serde::Serialize;

use crate::collision::{Obstacle, Scene};
use crate::frames::Iso;
use crate::kinematics::{Joints, joint_delta};
use crate::plan::{Plan, plan_layers};
use crate::planner::{Rejections, Select, Vertex, branch, validate};
pub use crate::setup::{BaseTolerance, sampled_errors};

/// The result of [`check_base_tolerance`]; the plan tolerates the errors when `problems` is empty.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ToleranceReport {
    /// The tolerance checked.
    pub tolerance: BaseTolerance,
    /// Perturbed base poses checked (per station).
    pub poses_per_station: usize,
    /// Waypoints re-solved, over all poses.
    pub waypoints_checked: usize,
    /// Smallest clearance of the arm to the environment over all perturbed poses, m.
    pub min_clearance: f64,
    /// Smallest distance of the mobile-base body to a static obstacle over all perturbed poses,
    /// m (`None` without obstacles or body).
    pub min_body_distance: Option<f64>,
    /// What fails, at most 20 entries.
    pub problems: Vec<String>,
    /// Per station, the largest base error it survives ([`station_margins`]; empty unless
    /// asked for, it costs about 3× the check).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub margins: Vec<StationMargin>,
}

impl ToleranceReport {
    /// No problem found.
    pub fn ok(&self) -> bool {
        self.problems.is_empty()
    }
}

/// Check every station of `plan` under base-pose errors up to `tol` (see the module docs).
pub fn check_base_tolerance(plan: &Plan, tol: &BaseTolerance) -> ToleranceReport {
    let mut rep = ToleranceReport {
        tolerance: tol.clone(),
        min_clearance: f64::INFINITY,
        ..Default::default()
    };
    let position_ok = tol.position.is_finite() && tol.position >= 0.0;
    let yaw_ok = tol.yaw_deg.is_finite() && tol.yaw_deg >= 0.0;
    if !position_ok || !yaw_ok || tol.stride == 0 {
        rep.problems.push(format!(
            "base tolerance position {} m, yaw {}°, stride {}: need finite values ≥ 0 and stride ≥ 1",
            tol.position, tol.yaw_deg, tol.stride
        ));
        return rep;
    }
    let layers = plan_layers(plan);
    let ctx = match validate(&layers, &plan.setup, &plan.options) {
        Ok(c) => c,
        Err(e) => {
            rep.problems
                .push(format!("the plan's setup or targets are invalid: {e}"));
            return rep;
        }
    };
    let errors = sampled_errors(tol);
    rep.poses_per_station = errors.len();

    let first_order = first_orders(plan);
    let jobs: Vec<(usize, (f64, f64, f64))> = (0..plan.stations.len())
        .flat_map(|s| errors.iter().map(move |e| (s, *e)))
        .collect();
    let results: Vec<PoseResult> = jobs
        .par_iter()
        .map(|&(si, err)| check_pose(plan, &ctx, &first_order, si, err, tol.stride, false))
        .collect();
    for r in results {
        rep.waypoints_checked += r.checked;
        rep.min_clearance = rep.min_clearance.min(r.min_clearance);
        if let Some(b) = r.min_body {
            rep.min_body_distance = Some(rep.min_body_distance.map_or(b, |m| m.min(b)));
        }
        rep.problems.extend(r.problems);
    }
    crate::error::shorten(&mut rep.problems, 20);
    rep
}

/// Print order of the first layer of every station.
fn first_orders(plan: &Plan) -> Vec<usize> {
    let mut first_order = Vec::with_capacity(plan.stations.len());
    let mut o = 0usize;
    for st in &plan.stations {
        first_order.push(o);
        o += st.layers.len();
    }
    first_order
}

/// What one perturbed base pose of one station gives.
struct PoseResult {
    checked: usize,
    min_clearance: f64,
    min_body: Option<f64>,
    problems: Vec<String>,
}

/// Re-solving one layer's checked waypoints from a perturbed base (module docs), for the
/// stations ([`check_base_tolerance`]) and the moving base
/// ([`crate::moving::check_moving_tolerance`]) alike: of the valid configurations the planner
/// accepts at a waypoint, the one on the planned elbow/wrist branch (signs of sin q3, sin q5)
/// nearest the planned joints is taken, and consecutive ones must stay within
/// `Σ Δq² ≤ ε·stride²`.
pub(crate) struct Resolver {
    prev: Option<Joints>,
    allowed: f64,
}

impl Resolver {
    /// For a layer of `n` waypoints checked every `stride`-th, with the plan's compatibility
    /// `epsilon`.
    pub(crate) fn new(epsilon: f64, stride: usize, n: usize) -> Self {
        // Only consecutive checked points are compared: with a stride the allowed motion grows
        // with the number of steps skipped.
        Resolver {
            prev: None,
            allowed: epsilon * (stride.min(n) as f64).powi(2),
        }
    }

    /// The next checked waypoint (planned joints `planned`) among its valid configurations
    /// `verts` (`rej`: why the others were refused): the chosen one's clearance lowers
    /// `min_clearance`; what fails goes to `problems`, after `point` (where it is).
    pub(crate) fn next(
        &mut self,
        planned: &Joints,
        verts: &[Vertex],
        rej: &Rejections,
        point: &str,
        min_clearance: &mut f64,
        problems: &mut Vec<String>,
    ) {
        let best = verts
            .iter()
            .filter(|v| branch(&v.q) == branch(planned))
            .map(|v| {
                let d2: f64 = joint_delta(planned, &v.q).iter().map(|d| d * d).sum();
                (d2, v)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let Some((_, v)) = best else {
            let (_, detail) = rej.failure();
            problems.push(format!(
                "{point} has no valid configuration on the planned branch ({detail})"
            ));
            self.prev = None;
            return;
        };
        *min_clearance = min_clearance.min(v.clearance);
        if let Some(p) = self.prev {
            let step: f64 = joint_delta(&p, &v.q).iter().map(|d| d * d).sum();
            if step > self.allowed {
                problems.push(format!(
                    "{point}: the re-solved joints jump by Σ Δq² = {step:.4} rad² (> ε·stride² = {:.4})",
                    self.allowed
                ));
            }
        }
        self.prev = Some(v.q);
    }
}

/// Station `si` of `plan` re-solved from its base moved by `(dx, dy, dyaw)` (see the module
/// docs); with `first_problem` it stops at the first problem (the margin search only needs
/// pass or fail).
fn check_pose(
    plan: &Plan,
    ctx: &crate::planner::Context,
    first_order: &[usize],
    si: usize,
    (dx, dy, da): (f64, f64, f64),
    stride: usize,
    first_problem: bool,
) -> PoseResult {
    let mut r = PoseResult {
        checked: 0,
        min_clearance: f64::INFINITY,
        min_body: None,
        problems: Vec::new(),
    };
    let st = &plan.stations[si];
    let Ok(nominal) = Iso::from_mat4(&st.world_from_base) else {
        r.problems.push(format!(
            "station {}: world_from_base is not a rigid transform",
            si + 1
        ));
        return r;
    };
    // The error is a drive error: a shift on the floor and a turn about the base's own
    // vertical axis.
    let world_from_base = Iso::translation(dx, dy, 0.0)
        .mul(&nominal)
        .mul(&Iso::rot_z(da));
    let at = format!(
        "station {}, base off by ({:+.1} mm, {:+.1} mm, {:+.2}°)",
        si + 1,
        dx * 1e3,
        dy * 1e3,
        da.to_degrees()
    );
    if let Err(e) = ctx.check_base(&world_from_base) {
        r.problems.push(format!("{at}: {e}"));
    }
    for b in &plan.setup.mobile_base {
        let body = b.to_world(&world_from_base);
        let Ok(body_scene) = Scene::new(std::slice::from_ref(&body)) else {
            continue;
        };
        for ob in &plan.setup.obstacles {
            if matches!(ob, Obstacle::HalfSpace { .. }) {
                continue;
            }
            if let Some(d) = body_scene.distance_to(ob) {
                r.min_body = Some(r.min_body.map_or(d, |m: f64| m.min(d)));
                if d <= 0.0 {
                    r.problems.push(format!(
                        "{at}: the mobile base body {:?} touches {:?} (distance {:.4} m)",
                        b.name,
                        ob.name(),
                        d
                    ));
                }
            }
        }
    }
    if first_problem && !r.problems.is_empty() {
        return r;
    }
    let scene = match ctx.scene(&world_from_base) {
        Ok(s) => s,
        Err(e) => {
            r.problems.push(format!("{at}: {e}"));
            return r;
        }
    };
    let eps = plan.options.epsilon;
    for (li, l) in st.layers.iter().enumerate() {
        let order = first_order[si] + li;
        let Some(layer) = ctx.layers.get(order) else {
            continue;
        };
        let n = l.waypoints.len();
        let mut resolver = Resolver::new(eps, stride, n);
        for (k, w) in l.waypoints.iter().enumerate() {
            if k % stride != 0 && k + 1 != n {
                continue;
            }
            if first_problem && !r.problems.is_empty() {
                return r;
            }
            r.checked += 1;
            let frame = ctx.target_frame(layer, k);
            let (verts, rej) = ctx.vertices(
                &scene,
                &world_from_base,
                &frame,
                order,
                Select::on_branch(branch(&w.q), r.min_clearance),
            );
            let point = format!("{at}: layer {} point {}", l.layer, w.index);
            resolver.next(
                &w.q,
                &verts,
                &rej,
                &point,
                &mut r.min_clearance,
                &mut r.problems,
            );
        }
    }
    r
}

/// How far one station's base may be off: the largest multiple `scale` of the checked
/// tolerance box (position and yaw scaled together) whose corners all pass, found by bisection
/// ([`station_margins`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StationMargin {
    /// Station, 1-based as in the station sheet (counting the stations a resumed plan dropped).
    pub station: usize,
    /// The largest passing multiple of the tolerance box found (0 when even a tiny error fails).
    pub scale: f64,
    /// `scale` × the tolerance's position error, m.
    pub position_m: f64,
    /// `scale` × the tolerance's yaw error, degrees.
    pub yaw_deg: f64,
    /// The search stopped at its upper end (`scale` is a lower bound only).
    pub at_least: bool,
}

/// Upper end of the margin search, as a multiple of the tolerance box: beyond 4× (±40 mm,
/// ±4° by default) the operator's answer is "more than enough" and the first-order argument
/// of the module docs (errors small against the links) weakens.
pub const MARGIN_SEARCH_MAX: f64 = 4.0;

/// Bisection stops when the bracket is this narrow (as a multiple of the box): ±0.125 × 10 mm
/// is about 1 mm, finer than a base can be placed.
const MARGIN_RESOLUTION: f64 = 0.125;

/// Per station, the largest base error it survives along the shape of `tol`'s box
/// ([`StationMargin`]): each trial checks the box's 8 corners as [`check_base_tolerance`] does
/// (same argument why corners suffice, same waypoint stride), stopping at the first problem.
/// A station that fails at `tol` itself gets the largest passing fraction below 1. The pass/fail
/// of a trial is monotone in the scale only to first order (a larger box contains the smaller
/// one's corners' effects): the result is a bisection estimate to within
/// `MARGIN_RESOLUTION` of the box, not a certified bound; the certified statement is the
/// pass/fail of [`check_base_tolerance`] at the stated tolerance.
pub fn station_margins(plan: &Plan, tol: &BaseTolerance) -> Vec<StationMargin> {
    let layers = plan_layers(plan);
    let Ok(ctx) = validate(&layers, &plan.setup, &plan.options) else {
        return Vec::new();
    };
    let finite = |v: f64| v.is_finite() && v >= 0.0;
    if !finite(tol.position)
        || !finite(tol.yaw_deg)
        || tol.stride == 0
        || (tol.position == 0.0 && tol.yaw_deg == 0.0)
    {
        return Vec::new();
    }
    let first_order = first_orders(plan);
    let offset = plan.mark.station_offset;
    (0..plan.stations.len())
        .into_par_iter()
        .map(|si| {
            let passes = |scale: f64| {
                let box_ = BaseTolerance {
                    position: tol.position * scale,
                    yaw_deg: tol.yaw_deg * scale,
                    stride: tol.stride,
                };
                sampled_errors(&box_).into_iter().skip(1).all(|e| {
                    check_pose(plan, &ctx, &first_order, si, e, tol.stride, true)
                        .problems
                        .is_empty()
                })
            };
            let (mut lo, mut hi, mut at_least) = if passes(1.0) {
                if passes(MARGIN_SEARCH_MAX) {
                    (MARGIN_SEARCH_MAX, MARGIN_SEARCH_MAX, true)
                } else {
                    (1.0, MARGIN_SEARCH_MAX, false)
                }
            } else {
                (0.0, 1.0, false)
            };
            while hi - lo > MARGIN_RESOLUTION {
                let mid = 0.5 * (lo + hi);
                if passes(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            if lo >= MARGIN_SEARCH_MAX {
                at_least = true;
            }
            StationMargin {
                station: si + 1 + offset,
                scale: lo,
                position_m: lo * tol.position,
                yaw_deg: lo * tol.yaw_deg,
                at_least,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup::PlanOptions;
    use crate::synthetic::cap_path;

    /// The tolerance check measures only the planned branch's configurations
    /// (`Select::on_branch`): at every waypoint of a small plan, from the planned base and from
    /// a corner of the default error box, they are exactly the full set's configurations on
    /// that branch (joints and clearances bit for bit), and the full set has the other
    /// branches besides. So the resolver takes the same configuration either way. Measured
    /// only below a bound `below` (the smallest clearance found so far, in the check), the same
    /// configurations come back, a clearance under the bound bit for bit and any other as the
    /// bound: so the smallest clearance over the waypoints is the same number.
    #[test]
    fn the_planned_branch_alone_gives_the_full_sets_vertices_on_it() {
        let layers = cap_path(0.8, 0.2, 25.0, 0.008, 16, 12);
        let setup = crate::synthetic::fixed_base_setup();
        let plan = crate::plan_print(&layers, &setup, &PlanOptions::default()).unwrap();
        let ctx = validate(&plan_layers(&plan), &plan.setup, &plan.options).unwrap();
        let st = &plan.stations[0];
        let nominal = Iso::from_mat4(&st.world_from_base).unwrap();
        let mut others = 0;
        let mut capped_any = false;
        for (dx, dy, da) in [(0.0, 0.0, 0.0), (0.01, -0.01, 1f64.to_radians())] {
            let w = Iso::translation(dx, dy, 0.0)
                .mul(&nominal)
                .mul(&Iso::rot_z(da));
            let scene = ctx.scene(&w).unwrap();
            for (order, l) in st.layers.iter().enumerate() {
                for (k, wp) in l.waypoints.iter().enumerate() {
                    let frame = ctx.target_frame(&ctx.layers[order], k);
                    let b = branch(&wp.q);
                    let (all, _) = ctx.vertices(&scene, &w, &frame, order, Select::ALL);
                    let (on, _) = ctx.vertices(
                        &scene,
                        &w,
                        &frame,
                        order,
                        Select::on_branch(b, f64::INFINITY),
                    );
                    let want: Vec<(Joints, f64)> = all
                        .iter()
                        .filter(|v| branch(&v.q) == b)
                        .map(|v| (v.q, v.clearance))
                        .collect();
                    let got: Vec<(Joints, f64)> = on.iter().map(|v| (v.q, v.clearance)).collect();
                    assert_eq!(got, want, "layer {order} point {k}");
                    assert!(!got.is_empty(), "layer {order} point {k}: planned branch");
                    // A bound between the required clearance and the cutoff, about half of
                    // this point's own clearances: some read below it, some at it.
                    let below = (got[0].1 * 0.999).max(ctx.opts.clearance);
                    let (capped, _) =
                        ctx.vertices(&scene, &w, &frame, order, Select::on_branch(b, below));
                    assert_eq!(capped.len(), got.len(), "layer {order} point {k}");
                    for (c, (q, full)) in capped.iter().zip(&got) {
                        assert_eq!(c.q, *q);
                        let expect = if *full < below { *full } else { below };
                        assert_eq!(c.clearance, expect, "layer {order} point {k}");
                        capped_any |= *full >= below;
                    }
                    others += all.len() - want.len();
                }
            }
        }
        assert!(others > 0, "the full sets hold other branches too");
        assert!(capped_any, "some clearances read as the bound");
    }
}
