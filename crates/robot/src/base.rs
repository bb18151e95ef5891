//! Base placement (robot.md §3.6 step 7): score a grid of base poses by how many consecutive
//! layers (from the next unprinted one) have every sampled frame reachable with a valid
//! configuration, plan from the best; when no pose covers the rest of the print, the mobile base
//! moves between layers and the print is split into stations (greedy, contiguous layer ranges).

use rayon::prelude::*;

use crate::error::{FailureKind, PlanFailure, RobotError};
use crate::frames::Iso;
use crate::plan::Station;
use crate::planner::{Context, RungCache, plan_station_cached};
use crate::setup::BaseSearch;
use crate::setup::{BaseTolerance, sampled_errors};

/// Candidate base poses of the grid, nearest the grid centre first (deterministic order).
fn candidates(ctx: &Context, s: &BaseSearch) -> Result<Vec<Iso>, RobotError> {
    let ys = ctx
        .layers
        .iter()
        .flat_map(|l| &l.points)
        .map(|p| p.position[1]);
    let (ylo, yhi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y), b.max(y))
    });
    let yr = s.y.unwrap_or([ylo + 0.6, yhi + 0.8]);
    let ok = s.step.is_finite()
        && s.step > 0.0
        && s.x.iter().chain(&yr).all(|v| v.is_finite())
        && s.z.is_finite();
    if !ok || s.x[0] > s.x[1] || yr[0] > yr[1] || s.yaw_deg.is_empty() || s.score_stride == 0 {
        return Err(RobotError::invalid(
            "base (search)",
            format!(
                "x {:?} y {:?} step {} yaw {:?} stride {}: need finite ranges lo ≤ hi, step > 0, ≥ 1 yaw, stride ≥ 1",
                s.x, yr, s.step, s.yaw_deg, s.score_stride
            ),
        ));
    }
    let grid = |r: [f64; 2]| -> Vec<f64> {
        let n = ((r[1] - r[0]) / s.step).floor() as usize;
        (0..=n.min(200)).map(|i| r[0] + i as f64 * s.step).collect()
    };
    let (cx, cy) = (0.5 * (s.x[0] + s.x[1]), 0.5 * (yr[0] + yr[1]));
    let mut out = Vec::new();
    for &x in &grid(s.x) {
        for &y in &grid(yr) {
            for (yi, &yaw) in s.yaw_deg.iter().enumerate() {
                let key = ((x - cx).powi(2) + (y - cy).powi(2), yi);
                out.push((
                    key,
                    Iso::translation(x, y, s.z).mul(&Iso::rot_z(yaw.to_radians())),
                ));
            }
        }
    }
    out.sort_by(|a, b| a.0.0.total_cmp(&b.0.0).then(a.0.1.cmp(&b.0.1)));
    Ok(out.into_iter().map(|(_, w)| w).collect())
}

/// How many consecutive layers from `start` have every `stride`-th point (and the last point)
/// reachable with a valid configuration from `w`.
fn coverage(ctx: &Context, w: &Iso, start: usize, stride: usize) -> usize {
    if ctx.check_base(w).is_err() {
        return 0;
    }
    let Ok(scene) = ctx.scene(w) else { return 0 };
    let inv = w.inverse();
    let mut n = 0;
    for o in start..ctx.layers.len() {
        let layer = &ctx.layers[o];
        let len = layer.points.len();
        let ok = (0..len)
            .filter(|k| k % stride == 0 || *k == len - 1)
            .all(|k| ctx.has_vertex(&scene, &inv, w, &ctx.target_frame(layer, k), o));
        if !ok {
            break;
        }
        n += 1;
    }
    n
}

/// How many of the best candidates (by nominal cover) are re-scored under the margin: the
/// re-score costs 8 coverages per candidate, and the planner tries only the first few anyway.
const MARGIN_CANDIDATES: usize = 12;

/// Re-score the best candidates of `order` by the layers they cover from every corner of the
/// error box `tol` as well (the least of the nine covers), and put the best of those first.
/// When no candidate keeps a layer under the margin, the nominal order stands (the plan's own
/// tolerance check then reports the failure).
fn robust_cover(
    ctx: &Context,
    cands: &[Iso],
    mut cover: Vec<usize>,
    order: &mut Vec<usize>,
    tol: &BaseTolerance,
    start: usize,
) -> Vec<usize> {
    let errors = sampled_errors(tol);
    let top: Vec<usize> = order.iter().copied().take(MARGIN_CANDIDATES).collect();
    let robust: Vec<usize> = top
        .par_iter()
        .map(|&ci| {
            errors
                .iter()
                .skip(1)
                .map(|&(dx, dy, da)| {
                    let w = Iso::translation(dx, dy, 0.0)
                        .mul(&cands[ci])
                        .mul(&Iso::rot_z(da));
                    // Every point: the corners sit at the edge of the reach, where a
                    // configuration can be lost between two sampled points.
                    coverage(ctx, &w, start, 1)
                })
                .fold(cover[ci], usize::min)
        })
        .collect();
    if robust.iter().all(|&r| r == 0) {
        return cover;
    }
    for (&ci, &r) in top.iter().zip(&robust) {
        cover[ci] = r;
    }
    let mut kept: Vec<usize> = top.into_iter().filter(|&ci| cover[ci] > 0).collect();
    kept.sort_by(|&a, &b| cover[b].cmp(&cover[a]).then(a.cmp(&b)));
    *order = kept;
    cover
}

/// Resolve the stations by search.
pub(crate) fn search_stations(ctx: &Context, s: &BaseSearch) -> Result<Vec<Station>, RobotError> {
    let cands = candidates(ctx, s)?;
    let mut stations: Vec<Station> = Vec::new();
    let mut start = 0;
    let mut t0 = 0.0;
    while start < ctx.layers.len() {
        let cover: Vec<usize> = cands
            .par_iter()
            .map(|w| coverage(ctx, w, start, s.score_stride))
            .collect();
        let mut order: Vec<usize> = (0..cands.len()).filter(|&i| cover[i] > 0).collect();
        // Most layers first; the grid order (nearest the centre) breaks ties.
        order.sort_by(|&a, &b| cover[b].cmp(&cover[a]).then(a.cmp(&b)));
        let cover = match &s.margin {
            Some(tol) => robust_cover(ctx, &cands, cover, &mut order, tol, start),
            None => cover,
        };
        let mut done = false;
        let mut last_err: Option<Box<PlanFailure>> = None;
        for &ci in order.iter().take(4) {
            let end = start + cover[ci];
            // Plan the covered range; on failure shrink to the layers before the failing one
            // (reusing this pose's vertices).
            let mut hi = end;
            let mut cache: RungCache = None;
            while hi > start {
                match plan_station_cached(
                    ctx,
                    stations.len(),
                    &cands[ci],
                    start..hi,
                    t0,
                    &mut cache,
                ) {
                    Ok(st) => {
                        let last = st.layers.last().and_then(|l| l.waypoints.last());
                        t0 = last.map_or(t0, |w| w.t) + ctx.opts.station_change_time;
                        stations.push(st);
                        start = hi;
                        done = true;
                        break;
                    }
                    Err(f) => {
                        let failed = ctx.layers[start..hi]
                            .iter()
                            .position(|l| l.layer == f.layer)
                            .map(|p| start + p);
                        last_err = Some(f);
                        match failed {
                            Some(p) if p > start && p < hi => hi = p,
                            _ => break,
                        }
                    }
                }
            }
            if done {
                break;
            }
        }
        if !done {
            let l = &ctx.layers[start];
            return Err(RobotError::Unplannable(last_err.unwrap_or_else(|| {
                Box::new(PlanFailure {
                    station: stations.len(),
                    layer: l.layer,
                    index: l.points[0].index,
                    kind: FailureKind::BasePlacement,
                    detail: format!("no candidate base pose of the search grid ({} poses) reaches every sampled point of this layer", cands.len()),
                })
            })));
        }
    }
    Ok(stations)
}
