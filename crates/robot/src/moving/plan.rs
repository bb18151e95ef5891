//! Planning with a moving base: the lead search, the full plan at a lead, the base trajectory
//! and its limits, and resuming from a layer (module docs of [`super`]).

use parry3d_f64::glamx::DVec3;
use rayon::prelude::*;

use super::check::{check_moving, verify_meshes_moving};
use super::{Geometry, MovingBase, MovingCheck, MovingPlan, front_offsets, front_sign};
use crate::base_trajectory::{BaseSample, BaseTrajectory};
use crate::error::{FailureKind, PlanFailure, RobotError};
use crate::frames::Iso;
use crate::ladder::LadderFailure;
use crate::plan::{LayerPlan, Plan, Station, Waypoint};
use crate::planner::{
    Context, Rejections, Vertex, WindUp, solve_rungs, summarise, unwrap_path, validate,
};
use crate::setup::{PlanOptions, PrintLayer, RobotSetup};
use crate::timing::LayerWait;

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
    let q = match unwrap_path(ctx, &built, &path) {
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
            min_c = min_c.min(built[r].0[path.vertices[r]].clearance);
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
