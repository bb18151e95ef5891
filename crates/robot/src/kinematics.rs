//! UR10e kinematics: standard DH forward kinematics and the closed-form inverse kinematics of
//! Hawkins (2013, "Analytic inverse kinematics for the Universal Robots UR-5/UR-10 arms"; the
//! same algorithm as ros-industrial `ur_kinematics/ur_kin.cpp`). See `robot.md` §1.
//!
//! Hand-written because no crate fits: `rs-opw-kinematics` assumes a spherical wrist (the UR
//! wrist is offset), `k` solves IK numerically, `ik-geo` has no licence.
//!
//! Frames: `base` is DH frame 0 (controller Base, ROS `base`), the flange is DH frame 6 (ROS
//! `tool0`). `T_i = Rz(θi)·Tz(di)·Tx(ai)·Rx(αi)`.

use std::f64::consts::{PI, TAU};

use parry3d_f64::glamx::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::RobotError;
use crate::frames::Iso;

/// Six joint values (rad), joints 1 (base) … 6 (wrist 3).
pub type Joints = [f64; 6];

/// Nominal UR10e DH parameters (m), UR support article "Parameters for calculations of
/// kinematics and dynamics"; α = (π/2, 0, 0, π/2, −π/2, 0), a1 = a4 = a5 = a6 = d2 = d3 = 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dh {
    pub d1: f64,
    pub a2: f64,
    pub a3: f64,
    pub d4: f64,
    pub d5: f64,
    pub d6: f64,
}

/// The UR10e (and UR12e) nominal values.
pub const UR10E: Dh = Dh {
    d1: 0.1807,
    a2: -0.6127,
    a3: -0.57155,
    d4: 0.17415,
    d5: 0.11985,
    d6: 0.11655,
};

impl Default for Dh {
    fn default() -> Self {
        UR10E
    }
}

/// Joint position limits (rad) used for planning: ±2π, elbow ±π (the arm blocks the elbow beyond
/// about ±π; ROS `joint_limits.yaml`, robot.md §1.1).
pub const JOINT_LIMITS: [[f64; 2]; 6] = [
    [-TAU, TAU],
    [-TAU, TAU],
    [-PI, PI],
    [-TAU, TAU],
    [-TAU, TAU],
    [-TAU, TAU],
];

/// Maximum joint speeds (rad/s): 120 °/s for base and shoulder, 180 °/s for the others.
pub const MAX_JOINT_SPEED: [f64; 6] = [120.0 * PI / 180.0, 120.0 * PI / 180.0, PI, PI, PI, PI];

/// Wrap an angle to (−π, π].
#[inline]
pub fn wrap(x: f64) -> f64 {
    let w = (x + PI).rem_euclid(TAU) - PI;
    if w <= -PI { w + TAU } else { w }
}

/// Configuration-space difference `q1 − q0` with joints 1, 2, 4, 5, 6 wrapped to (−π, π] and the
/// elbow (joint 3) raw, because the elbow must never cross ±π (robot.md §1.3).
#[inline]
pub fn joint_delta(q0: &Joints, q1: &Joints) -> Joints {
    let mut d = [0.0; 6];
    for j in 0..6 {
        let raw = q1[j] - q0[j];
        d[j] = if j == 2 { raw } else { wrap(raw) };
    }
    d
}

/// The six DH link transforms `T_{i-1,i}` for `q` (exact 0/±1 for cos α, sin α).
#[inline]
fn link(theta: f64, d: f64, a: f64, ca: f64, sa: f64) -> Iso {
    let (s, c) = theta.sin_cos();
    Iso::new(
        DMat3::from_cols(
            DVec3::new(c, s, 0.0),
            DVec3::new(-s * ca, c * ca, sa),
            DVec3::new(s * sa, -c * sa, ca),
        ),
        DVec3::new(a * c, a * s, d),
    )
}

impl Dh {
    #[inline]
    fn links(&self, q: &Joints) -> [Iso; 6] {
        [
            link(q[0], self.d1, 0.0, 0.0, 1.0),
            link(q[1], 0.0, self.a2, 1.0, 0.0),
            link(q[2], 0.0, self.a3, 1.0, 0.0),
            link(q[3], self.d4, 0.0, 0.0, 1.0),
            link(q[4], self.d5, 0.0, 0.0, -1.0),
            link(q[5], self.d6, 0.0, 1.0, 0.0),
        ]
    }

    /// Forward kinematics `base_from_flange(q)`.
    pub fn fk(&self, q: &Joints) -> Iso {
        let l = self.links(q);
        let mut t = l[0];
        for li in &l[1..] {
            t = t.mul(li);
        }
        t
    }

    /// All DH frames `base_from_frame_i` for i = 0 … 6 (frame 0 is the identity).
    pub fn fk_frames(&self, q: &Joints) -> [Iso; 7] {
        let l = self.links(q);
        let mut out = [Iso::IDENTITY; 7];
        for i in 0..6 {
            out[i + 1] = out[i].mul(&l[i]);
        }
        out
    }

    /// Shoulder margin `r − d4` (m) of a flange pose: distance of the wrist-2 centre
    /// `P5 = p − d6·z6` from the cylinder of radius d4 about joint 1. Negative: unreachable.
    pub fn shoulder_margin(&self, base_from_flange: &Iso) -> f64 {
        let p5 = base_from_flange.t - self.d6 * base_from_flange.r.z_axis;
        p5.x.hypot(p5.y) - self.d4
    }

    /// Closed-form IK of a flange pose: every solution, canonical (each joint in (−π, π]).
    ///
    /// Steps (robot.md §1.3): θ1 from the wrist-2 centre (2 branches), θ5 (2), θ6, then a planar
    /// 3R problem for θ2, θ3, θ4 (2 elbow branches): up to 8 solutions, 0 if unreachable. Never
    /// panics; non-finite input gives no solution. At the wrist singularity (sin θ5 ≈ 0) θ6 is set
    /// to 0 and θ4 absorbs the rest.
    pub fn ik(&self, base_from_flange: &Iso) -> IkSolutions {
        let mut out = IkSolutions::default();
        let r = &base_from_flange.r;
        let p = base_from_flange.t;
        if !(p.is_finite() && r.is_finite()) {
            return out;
        }
        // Row/col access: Rij = row i, col j; glam stores columns.
        let (r00, r10, r20) = (r.x_axis.x, r.x_axis.y, r.x_axis.z);
        let (r01, r11, r21) = (r.y_axis.x, r.y_axis.y, r.y_axis.z);
        let (r02, r12, r22) = (r.z_axis.x, r.z_axis.y, r.z_axis.z);
        let Dh {
            d1,
            a2,
            a3,
            d4,
            d5,
            d6,
        } = *self;

        // θ1
        let p5x = p.x - d6 * r02;
        let p5y = p.y - d6 * r12;
        let rr = p5x.hypot(p5y);
        if rr < d4 || rr == 0.0 {
            return out;
        }
        let psi = p5y.atan2(p5x);
        let phi = (d4 / rr).clamp(-1.0, 1.0).acos();
        let th1s = [psi + phi + PI / 2.0, psi - phi + PI / 2.0];
        let n_th1 = if phi == 0.0 { 1 } else { 2 };

        for &th1 in &th1s[..n_th1] {
            let (s1, c1) = th1.sin_cos();
            // θ5
            let mut c5 = (p.x * s1 - p.y * c1 - d4) / d6;
            if c5.abs() > 1.0 {
                if c5.abs() > 1.0 + 1e-10 {
                    continue;
                }
                c5 = c5.signum();
            }
            let a5 = c5.acos();
            let th5s = [a5, -a5];
            let n_th5 = if a5 == 0.0 { 1 } else { 2 };
            for &th5 in &th5s[..n_th5] {
                let s5 = th5.sin();
                // θ6
                let th6 = if s5.abs() < 1e-10 {
                    0.0
                } else {
                    ((-r01 * s1 + r11 * c1) / s5).atan2((r00 * s1 - r10 * c1) / s5)
                };
                let (s6, c6) = th6.sin_cos();
                // planar 3R
                let p13x = d5 * (s6 * (r00 * c1 + r10 * s1) + c6 * (r01 * c1 + r11 * s1))
                    - d6 * (r02 * c1 + r12 * s1)
                    + p.x * c1
                    + p.y * s1;
                let p13y = p.z - d1 - d6 * r22 + d5 * (r21 * c6 + r20 * s6);
                let mut c3 = (p13x * p13x + p13y * p13y - a2 * a2 - a3 * a3) / (2.0 * a2 * a3);
                if c3.abs() > 1.0 {
                    if c3.abs() > 1.0 + 1e-10 {
                        continue;
                    }
                    c3 = c3.signum();
                }
                let a3c = c3.acos();
                let th3s = [a3c, -a3c];
                let n_th3 = if a3c == 0.0 { 1 } else { 2 };
                let x04x = -s5 * (r02 * c1 + r12 * s1)
                    - c5 * (s6 * (r01 * c1 + r11 * s1) - c6 * (r00 * c1 + r10 * s1));
                let x04y = c5 * (r20 * c6 - r21 * s6) - r22 * s5;
                let th234 = x04y.atan2(x04x);
                let base_angle = p13y.atan2(p13x);
                for &th3 in &th3s[..n_th3] {
                    let s3 = th3.sin();
                    let th2 = base_angle - (a3 * s3).atan2(a2 + a3 * c3);
                    let th4 = th234 - th2 - th3;
                    out.push([
                        wrap(th1),
                        wrap(th2),
                        wrap(th3),
                        wrap(th4),
                        wrap(th5),
                        wrap(th6),
                    ]);
                }
            }
        }
        out
    }

    /// IK of a TCP pose for a tool: `IK(base_from_tcp · flange_from_tcp⁻¹)`.
    pub fn ik_tcp(&self, base_from_tcp: &Iso, tcp_from_flange: &Iso) -> IkSolutions {
        self.ik(&base_from_tcp.mul(tcp_from_flange))
    }
}

/// Up to 8 IK solutions without allocation.
#[derive(Clone, Copy, Debug, Default)]
pub struct IkSolutions {
    q: [Joints; 8],
    n: usize,
}

impl IkSolutions {
    #[inline]
    fn push(&mut self, q: Joints) {
        if self.n < 8 && q.iter().all(|v| v.is_finite()) {
            self.q[self.n] = q;
            self.n += 1;
        }
    }
    /// The solutions.
    pub fn as_slice(&self) -> &[Joints] {
        &self.q[..self.n]
    }
    /// Number of solutions.
    pub fn len(&self) -> usize {
        self.n
    }
    /// No solution.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
}

/// Whether some whole-turn variant of `q` (the elbow as it is) lies inside `limits`: the
/// planner's test of a canonical IK solution before the station's 2π offsets are chosen. For
/// the UR10e limits this is the same as [`within_limits`] on canonical angles.
pub fn representable_in_limits(q: &Joints, limits: &[[f64; 2]; 6]) -> bool {
    (0..6).all(|j| {
        // The elbow is never wound (its raw value is the configuration), the others may be
        // shifted by whole turns when the station is unwrapped.
        let ks: &[i32] = if j == 2 { &[0] } else { &[-2, -1, 0, 1, 2] };
        ks.iter().any(|&k| {
            let v = q[j] + f64::from(k) * TAU;
            v >= limits[j][0] - 1e-12 && v <= limits[j][1] + 1e-12
        })
    })
}

/// Every joint vector equal to `q` modulo 2π per joint that lies inside `limits` (the ±2π
/// "wind-up" variants; up to 2⁵·… of them). Joints whose canonical value is outside the limits
/// yield nothing.
pub fn equivalents_in_limits(q: &Joints, limits: &[[f64; 2]; 6]) -> Vec<Joints> {
    let mut options: Vec<Vec<f64>> = Vec::with_capacity(6);
    for j in 0..6 {
        let mut o = Vec::new();
        for k in -2i32..=2 {
            let v = q[j] + f64::from(k) * TAU;
            if v >= limits[j][0] - 1e-12 && v <= limits[j][1] + 1e-12 {
                o.push(v);
            }
        }
        if o.is_empty() {
            return Vec::new();
        }
        options.push(o);
    }
    let mut out = vec![[0.0; 6]];
    for (j, o) in options.iter().enumerate() {
        let mut next = Vec::with_capacity(out.len() * o.len());
        for base in &out {
            for &v in o {
                let mut b = *base;
                b[j] = v;
                next.push(b);
            }
        }
        out = next;
    }
    out
}

/// Whether `q` is inside `limits` (inclusive, with 1e-12 rad slack for round-off).
pub fn within_limits(q: &Joints, limits: &[[f64; 2]; 6]) -> bool {
    q.iter()
        .zip(limits)
        .all(|(v, l)| *v >= l[0] - 1e-12 && *v <= l[1] + 1e-12)
}

/// The safe approach configuration: the first target backed off `dist` along the tool axis,
/// the IK solution nearest `q` (same branch), unwrapped next to `q`.
pub(crate) fn approach_config(
    q: &Joints,
    tool: &Iso,
    dist: f64,
    limits: &[[f64; 2]; 6],
) -> Result<Joints, RobotError> {
    let tcp = UR10E.fk(q).mul(tool);
    let back = tcp.mul(&Iso::translation(0.0, 0.0, -dist));
    let flange = back.mul(&tool.inverse());
    let sols = UR10E.ik(&flange);
    let mut best: Option<(f64, Joints)> = None;
    for s in sols.as_slice() {
        let d = joint_delta(q, s);
        let cand: Joints = std::array::from_fn(|j| q[j] + d[j]);
        if !within_limits(&cand, limits) {
            continue;
        }
        let c: f64 = d.iter().map(|v| v * v).sum();
        if best.is_none_or(|b| c < b.0) {
            best = Some((c, cand));
        }
    }
    best.map(|b| b.1).ok_or_else(|| {
        RobotError::invalid(
            "program.approach_distance",
            format!(
                "no joint configuration reaches the approach pose {dist} m behind the target {:?}",
                tcp.t.to_array()
            ),
        )
    })
}
