//! Certified clearances along a motion, not only at its waypoints.
//!
//! **Bound.** Joint j (0-based) turns the links beyond it about an axis through the DH origin
//! `o_j`. A point x of link k (DH frame k' = min(k, 6); the tool rides on frame 6) is at most
//! `r[j][k] = Σ_{i=j+1..k'} L_i + e_k` from that axis, with `L_i = √(a_i² + d_i²)` the constant
//! distance `|o_i − o_{i−1}|` of DH row i and `e_k` the largest distance of link k's geometry
//! (capsules incl. radius, or meshes) from `o_k'`. Along a joint-space motion whose joint j
//! travels `TV_j` in total (|Δq_j| for a straight joint interpolation), x therefore moves at most
//! `D_k = Σ_{j<k'} TV_j · r[j][k]` in the world, and relative to link a (a self pair a < b) at
//! most `Σ_{a≤j<b'} TV_j · r[j][b]`. A distance to anything is 1-Lipschitz in the positions, so
//! with distances `d_a`, `d_b` at the two ends the distance anywhere along the motion is at least
//! `max(d_a − sD, d_b − (1 − s)D) ≥ (d_a + d_b − D)/2` (and ≤ both ends' values for any valid
//! bound). Where that bound is below the required clearance the motion is split at its middle
//! (the middle waypoint, or the joint-space midpoint of a single step) and both halves are
//! bounded again, down to [`MAX_DEPTH`] halvings. The certified minimum is the smallest bound
//! over all pieces: a lower bound of the true clearance along the motion, not an estimate.
//!
//! Capped distances (`min(d, cutoff)`) are 1-Lipschitz too, so the bound holds for them.

use crate::collision::CapsuleSpec;
use crate::kinematics::{Dh, Joints};

/// Most halvings of one step (2^-14 of the step: far below any clearance that matters).
pub const MAX_DEPTH: usize = 14;

/// Links of the model: DH frames 0–6 and the tool (on frame 6).
pub const LINKS: usize = 8;

/// `r[j][k]`: the largest distance from joint j's axis to any point of link k (0 if link k does
/// not move with joint j).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepBounds {
    pub r: [[f64; LINKS]; 6],
}

impl SweepBounds {
    /// Bounds for links whose geometry reaches at most `extent[k]` from its frame origin.
    pub fn new(dh: &Dh, extent: [f64; LINKS]) -> Self {
        let l = [
            dh.d1.abs(),
            dh.a2.abs(),
            dh.a3.abs(),
            dh.d4.abs(),
            dh.d5.abs(),
            dh.d6.abs(),
        ];
        let mut r = [[0.0; LINKS]; 6];
        for (j, row) in r.iter_mut().enumerate() {
            for (k, v) in row.iter_mut().enumerate() {
                let kf = k.min(6);
                if kf > j {
                    // Σ_{i=j+1..k'} L_i, with L_i = l[i − 1].
                    *v = l[j..kf].iter().sum::<f64>() + extent[k];
                }
            }
        }
        SweepBounds { r }
    }

    /// Extents of a capsule model (each capsule's farthest end plus its radius) plus
    /// `extra[k]` (e.g. how far a mesh reaches outside its capsules).
    pub fn for_capsules(dh: &Dh, caps: &[CapsuleSpec], extra: [f64; LINKS]) -> Self {
        let mut e = [0.0f64; LINKS];
        for c in caps {
            let n = |p: [f64; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            if let Some(v) = e.get_mut(c.link) {
                *v = v.max(n(c.a).max(n(c.b)) + c.radius);
            }
        }
        for k in 0..LINKS {
            e[k] += extra[k];
        }
        Self::new(dh, e)
    }

    /// Largest world displacement of a point of link `k` for joint travels `tv`.
    pub fn world(&self, tv: &[f64; 6], k: usize) -> f64 {
        (0..6).map(|j| tv[j] * self.r[j][k]).sum()
    }

    /// Largest displacement of a point of link `b` relative to link `a` (a < b).
    pub fn relative(&self, tv: &[f64; 6], a: usize, b: usize) -> f64 {
        (a.min(6)..6).map(|j| tv[j] * self.r[j][b]).sum()
    }
}

/// Total travel of each joint along a piecewise-linear joint path.
pub fn travel(path: &[Joints]) -> [f64; 6] {
    let mut tv = [0.0; 6];
    for w in path.windows(2) {
        for j in 0..6 {
            tv[j] += (w[1][j] - w[0][j]).abs();
        }
    }
    tv
}

/// The certified lower bound of one channel over a piece: `min(d_a, d_b, (d_a + d_b − D)/2)`.
#[inline]
pub fn piece_bound(da: f64, db: f64, d: f64) -> f64 {
    da.min(db).min(0.5 * (da + db - d))
}

/// A piece of a joint path: straight joint interpolation from `qa` to `qb`, with the channels'
/// distances measured at both ends.
#[derive(Clone, Copy, Debug)]
struct Piece<const N: usize> {
    qa: Joints,
    ma: [f64; N],
    qb: Joints,
    mb: [f64; N],
    depth: usize,
}

/// Certified minima of `N` distance channels along the joint path `path` (consecutive
/// configurations joined by straight joint interpolation).
///
/// - `measure(q)` gives the channels' distances at `q`;
/// - `displacement(tv)` the channels' motion bounds `D` for joint travels `tv`;
/// - `required` the clearances below which a piece must be split (the check);
/// - `fails_below`: once a measured configuration of a channel is below this, the channel has
///   failed and is split no further (a long stretch that is too close would otherwise cost
///   2^[`MAX_DEPTH`] configurations per step); `required` for a check that fails below its
///   margin, 0 for one that fails only on contact;
/// - `tolerance`, if given: afterwards the pieces holding each channel's smallest bound are split
///   further until that bound is within `tolerance` of the smallest distance measured (so the
///   reported minimum is tight), at most [`TIGHTEN_BUDGET`] extra configurations per channel.
///
/// Returns the certified minima and the number of configurations measured (the path's own and
/// the midpoints added).
pub fn certify<const N: usize>(
    path: &[Joints],
    measure: &(dyn Fn(&Joints) -> [f64; N] + Sync),
    displacement: &(dyn Fn(&[f64; 6]) -> [f64; N] + Sync),
    required: [f64; N],
    fails_below: [f64; N],
    tolerance: Option<[f64; N]>,
) -> ([f64; N], usize) {
    let measured: Vec<[f64; N]> = path.iter().map(measure).collect();
    let (best, added) = certify_measured(
        path,
        &measured,
        measure,
        displacement,
        required,
        fails_below,
        tolerance,
    );
    (best, measured.len() + added)
}

/// [`certify`] with the distances at the path's configurations already measured
/// (`measured[k]` at `path[k]`); returns the minima and the number of midpoints added.
pub fn certify_measured<const N: usize>(
    path: &[Joints],
    measured: &[[f64; N]],
    measure: &(dyn Fn(&Joints) -> [f64; N] + Sync),
    displacement: &(dyn Fn(&[f64; 6]) -> [f64; N] + Sync),
    required: [f64; N],
    fails_below: [f64; N],
    tolerance: Option<[f64; N]>,
) -> ([f64; N], usize) {
    let n = path.len().min(measured.len());
    let Some(first) = measured.first() else {
        return ([f64::INFINITY; N], 0);
    };
    let mut count = 0;
    let mut lowest = *first;
    let mut pieces: Vec<Piece<N>> = Vec::with_capacity(n);
    for k in 1..n {
        pieces.push(Piece {
            qa: path[k - 1],
            ma: measured[k - 1],
            qb: path[k],
            mb: measured[k],
            depth: 0,
        });
    }
    let bound = |p: &Piece<N>| -> [f64; N] {
        let tv: [f64; 6] = std::array::from_fn(|j| (p.qb[j] - p.qa[j]).abs());
        let d = displacement(&tv);
        std::array::from_fn(|c| piece_bound(p.ma[c], p.mb[c], d[c]))
    };
    let split = |p: &Piece<N>, count: &mut usize, lowest: &mut [f64; N]| -> [Piece<N>; 2] {
        let qm: Joints = std::array::from_fn(|j| 0.5 * (p.qa[j] + p.qb[j]));
        let mm = measure(&qm);
        *count += 1;
        for c in 0..N {
            lowest[c] = lowest[c].min(mm[c]);
        }
        [
            Piece {
                qb: qm,
                mb: mm,
                depth: p.depth + 1,
                ..*p
            },
            Piece {
                qa: qm,
                ma: mm,
                depth: p.depth + 1,
                ..*p
            },
        ]
    };
    for p in &pieces {
        for c in 0..N {
            lowest[c] = lowest[c].min(p.mb[c]);
        }
    }
    // The check: split every piece whose bound is below the requirement, for the channels not
    // yet shown to fail (a measured configuration below the requirement settles the check, and
    // splitting on would only cost time where a long stretch is too close).
    let mut done: Vec<(Piece<N>, [f64; N])> = Vec::with_capacity(pieces.len());
    while let Some(p) = pieces.pop() {
        let lb = bound(&p);
        let open = |c: usize| lb[c] < required[c] && lowest[c] >= fails_below[c];
        if p.depth >= MAX_DEPTH || !(0..N).any(open) {
            done.push((p, lb));
        } else {
            pieces.extend(split(&p, &mut count, &mut lowest));
        }
    }
    // Tightening: split the piece with the smallest bound of each channel until the bound is
    // within the tolerance of the smallest measured distance.
    for c in 0..tolerance.map_or(0, |_| N) {
        let tol = tolerance.map_or(0.0, |t| t[c]);
        let mut extra = 0;
        while extra < TIGHTEN_BUDGET {
            let Some((k, lb)) = done
                .iter()
                .enumerate()
                .map(|(k, (_, lb))| (k, lb[c]))
                .min_by(|a, b| a.1.total_cmp(&b.1))
            else {
                break;
            };
            if lb >= lowest[c] - tol || done[k].0.depth >= MAX_DEPTH {
                break;
            }
            let (p, _) = done.swap_remove(k);
            for h in split(&p, &mut count, &mut lowest) {
                let lb = bound(&h);
                done.push((h, lb));
            }
            extra += 1;
        }
    }
    let best = std::array::from_fn(|c| done.iter().map(|(_, lb)| lb[c]).fold(lowest[c], f64::min));
    (best, count)
}

/// Most extra configurations per channel and call spent on tightening the reported minimum.
pub const TIGHTEN_BUDGET: usize = 200;
