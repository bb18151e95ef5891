//! A synthetic but plausible [`ReportInput`] for trying the report without the pipeline
//! (`cargo run -p kappe-report --example demo -- OUT.html`) and for the tests.
//!
//! Geometry follows method.md §4–§6 in simplified form: every centre layer is the catenary
//! `h(x) = R − a(cosh(x/a) − 1)` (R = Cr / cos am, `a` from `a(cosh(Cs/2a) − 1) = R`) drawn in
//! a plane tilted `am` = 25° from the vertical, layer k translated by `k·lh/cos(am)·e_y`; the
//! start layers are layer 0 translated down and back by a fixed step (`lh` along the layer
//! normal plus a 4.5 mm overhang along the in-plane up direction) and trimmed by z = 0.
//! Stresses use the catenary closed form `σ = −γ·a·cosh(x/a)/cos(am)` for arch segments and
//! `σ = −(layers above + 1)·γ·lh·tan(am)` for bed joints (method.md §5), scaled mildly per state
//! so that the slider visibly changes the colours. BLF values are made up. The robot is a UR10e
//! (DH table of robot.md) whose nozzle tip follows the print path by a damped least-squares
//! position IK on q1..q3 with the wrist kept pointing down. Nothing here is an analysis result.

use std::f64::consts::{FRAC_PI_2, PI};

use crate::input::{
    BedJoint, Bound, BoxBody, Capsule, Cell, ConstraintRow, Layer, ModeShape, Parameter, PrintPath,
    PrintState, Quantity, QuantityPer, ReportInput, RobotAnimation, Station, Timeline, Vec3,
    WorstPlace,
};

const SPAN: f64 = 0.8;
const RISE: f64 = 0.2;
const TILT_DEG: f64 = 25.0;
const LAYER_H: f64 = 0.012;
const LAYER_W: f64 = 0.024;
const GAMMA: f64 = 23_044.0;
const DS: f64 = 0.02;
const CENTRE_LAYERS: i32 = 16;
/// Overhang of each start layer over the next one in print order, along the in-plane up u, m.
const START_OVERHANG: f64 = 0.0045;

fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

/// Catenary parameter `a` with `a(cosh(half/a) − 1) = r`, by bisection (the left side falls
/// monotonically in `a`).
fn catenary_a(half: f64, r: f64) -> f64 {
    let (mut lo, mut hi) = (1e-3, 1e3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid * ((half / mid).cosh() - 1.0) > r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// UR10e DH table (standard DH; robot.md, as compas_fab uses it): d, a, alpha.
const UR_D: [f64; 6] = [0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655];
const UR_A: [f64; 6] = [0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0];
const UR_ALPHA: [f64; 6] = [FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2, 0.0];
const NOZZLE: f64 = 0.12;
/// Capsule radii of the drawn segments (2 per joint, then the nozzle), m.
const RADII: [f64; 13] = [
    0.075, 0.075, 0.07, 0.06, 0.06, 0.05, 0.045, 0.045, 0.045, 0.045, 0.04, 0.04, 0.012,
];

/// Forward kinematics as a point chain: per joint, the point after `Tz(d)` and the frame
/// origin after `Tx(a)`, then the nozzle tip; frames are rotation columns + origin.
fn ur_chain(base: Vec3, q: &[f64; 6]) -> Vec<Vec3> {
    // Rotation as three columns (x, y, z axes in world) and the origin.
    let mut x = [1.0, 0.0, 0.0];
    let mut y = [0.0, 1.0, 0.0];
    let mut z = [0.0, 0.0, 1.0];
    let mut o = base;
    let mut pts = vec![base];
    for i in 0..6 {
        let (s, c) = q[i].sin_cos();
        // Rz(θ): rotate x, y about z.
        let xr = add(scale(x, c), scale(y, s));
        let yr = add(scale(x, -s), scale(y, c));
        let p = add(o, scale(z, UR_D[i]));
        pts.push(p);
        o = add(p, scale(xr, UR_A[i]));
        pts.push(o);
        // Rx(α): rotate y, z about the new x.
        let (sa, ca) = UR_ALPHA[i].sin_cos();
        let y2 = add(scale(yr, ca), scale(z, sa));
        let z2 = add(scale(yr, -sa), scale(z, ca));
        x = xr;
        y = y2;
        z = z2;
    }
    pts.push(add(o, scale(z, NOZZLE)));
    pts
}

/// Joint vector from the three solved joints; q4 keeps q2 + q3 + q4 = −π/2 so the tool
/// points down, q5 = −π/2, q6 = 0.
fn joints(q: [f64; 3]) -> [f64; 6] {
    [q[0], q[1], q[2], -FRAC_PI_2 - q[1] - q[2], -FRAC_PI_2, 0.0]
}

fn tip(base: Vec3, q: [f64; 3]) -> Vec3 {
    ur_chain(base, &joints(q)).last().copied().unwrap_or(base)
}

/// Damped least squares `Δq = Jᵀ(JJᵀ + λ²I)⁻¹ e` on q1..q3 with a forward-difference Jacobian.
fn ik_position(base: Vec3, target: Vec3, mut q: [f64; 3]) -> [f64; 3] {
    const LAMBDA2: f64 = 1e-4;
    for _ in 0..40 {
        let p = tip(base, q);
        let e = sub(target, p);
        if norm(e) < 1e-7 {
            break;
        }
        let h = 1e-7;
        let mut jac = [[0.0; 3]; 3]; // jac[row][col]
        for col in 0..3 {
            let mut qh = q;
            qh[col] += h;
            let d = scale(sub(tip(base, qh), p), 1.0 / h);
            for row in 0..3 {
                jac[row][col] = d[row];
            }
        }
        // A = J Jᵀ + λ² I, solve A y = e by Cramer's rule, Δq = Jᵀ y.
        let mut a = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                a[r][c] = dot(jac[r], jac[c]) + if r == c { LAMBDA2 } else { 0.0 };
            }
        }
        let det3 = |m: [[f64; 3]; 3]| {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        let det = det3(a);
        if det.abs() < 1e-30 {
            break;
        }
        let mut yv = [0.0; 3];
        for (k, yk) in yv.iter_mut().enumerate() {
            let mut m = a;
            for r in 0..3 {
                m[r][k] = e[r];
            }
            *yk = det3(m) / det;
        }
        for col in 0..3 {
            // Wrapped to (−π, π] so that the joint-angle plot shows no 2π jumps from winding.
            let v = q[col] + (0..3).map(|r| jac[r][col] * yv[r]).sum::<f64>();
            q[col] = (v + PI).rem_euclid(2.0 * PI) - PI;
        }
    }
    q
}

/// Builds the synthetic demo report input (see the module docs).
#[must_use]
#[allow(clippy::too_many_lines)] // one linear recipe; splitting it would only scatter it
pub fn demo_input() -> ReportInput {
    let am = TILT_DEG.to_radians();
    let (sa, ca) = am.sin_cos();
    let n: Vec3 = [0.0, ca, sa];
    let u: Vec3 = [0.0, -sa, ca];
    let r = RISE / ca;
    let a = catenary_a(SPAN / 2.0, r);
    let half_arc = a * (SPAN / (2.0 * a)).sinh();
    let segs = ((2.0 * half_arc / DS).round() as usize).max(2);

    // Layer 0 in plane coordinates: (x, h), sampled evenly in arc length s = a sinh(x/a).
    let layer0: Vec<(f64, Vec3)> = (0..=segs)
        .map(|i| {
            let s = -half_arc + 2.0 * half_arc * i as f64 / segs as f64;
            let x = a * (s / a).asinh();
            let h = (r - a * ((x / a).cosh() - 1.0)).max(0.0);
            (x, add([x, 0.0, 0.0], scale(u, h)))
        })
        .collect();
    let arch_stress = |x: f64| -GAMMA * a * (x / a).cosh() / ca;

    // Start layers: translates T_m = −m·(lh·n + o·u) of layer 0, kept while the crown is above 0.
    let step = add(scale(n, LAYER_H), scale(u, START_OVERHANG));
    let mut start_k = 0;
    while RISE - (start_k + 1) as f64 * step[2] > 2.0 * DS * sa {
        start_k += 1;
    }

    // Layers in print order.
    let mut layers: Vec<Layer> = Vec::new();
    let mut push_layer = |id: i32, t: Vec3, overhang: Option<f64>| {
        let moved: Vec<(f64, Vec3)> = layer0.iter().map(|(x, p)| (*x, add(*p, t))).collect();
        // Trim by z = 0: keep z > 0 and add the two feet where the chords cross z = 0.
        let mut pts: Vec<(f64, Vec3)> = Vec::new();
        for w in moved.windows(2) {
            let (&(xa, pa), &(xb, pb)) = (&w[0], &w[1]);
            if pa[2] > 0.0 && pts.is_empty() {
                pts.push((xa, pa));
            }
            if (pa[2] > 0.0) != (pb[2] > 0.0) {
                let f = pa[2] / (pa[2] - pb[2]);
                let foot = add(pa, scale(sub(pb, pa), f));
                pts.push((xa + f * (xb - xa), [foot[0], foot[1], 0.0]));
            }
            if pb[2] > 0.0 {
                pts.push((xb, pb));
            }
        }
        if t[2] == 0.0 {
            // Centre layers stand exactly on their feet.
            pts = moved;
        }
        let segment_stress = pts
            .windows(2)
            .map(|w| arch_stress(0.5 * (w[0].0 + w[1].0)))
            .collect();
        layers.push(Layer {
            id,
            nodes: pts.iter().map(|p| p.1).collect(),
            segment_stress,
            plane_normal: n,
            bead_width: LAYER_W,
            bead_height: LAYER_H,
            overhang,
        });
    };
    for m in (1..=start_k).rev() {
        let overhang = (m != start_k).then_some(START_OVERHANG);
        push_layer(-m, scale(step, -(m as f64)), overhang);
    }
    let dy = LAYER_H / ca;
    for k in 0..CENTRE_LAYERS {
        let overhang = (start_k > 0 || k > 0).then_some(LAYER_H * am.tan());
        push_layer(k, [0.0, f64::from(k) * dy, 0.0], overhang);
    }
    let total = layers.len();

    // Bed joints: each node of a layer to the nearest node of the layer below, method.md §5
    // stress for the final state: −(layers above incl. this one)·γ·lh·tan(am).
    let mut bed_joints = Vec::new();
    for k in 1..total {
        let (below, above) = (&layers[k - 1], &layers[k]);
        let stress = -((total - k) as f64) * GAMMA * LAYER_H * am.tan();
        for &b in &above.nodes {
            let nearest = below
                .nodes
                .iter()
                .copied()
                .min_by(|p, q| norm(sub(*p, b)).total_cmp(&norm(sub(*q, b))))
                .unwrap_or(b);
            bed_joints.push(BedJoint {
                layer: above.id,
                a: nearest,
                b,
                stress,
            });
        }
    }

    // Print path: nozzle tip lh/2 above the centre line, direction alternating per layer.
    let mut print_path = PrintPath::default();
    for (k, l) in layers.iter().enumerate() {
        let mut pts: Vec<Vec3> = l
            .nodes
            .iter()
            .map(|p| add(*p, scale(n, LAYER_H / 2.0)))
            .collect();
        if k % 2 == 1 {
            pts.reverse();
        }
        for p in pts {
            print_path.points.push(p);
            print_path.tool_axis.push(scale(n, -1.0));
            print_path.layer.push(l.id);
        }
    }

    // States: one per printed layer; arch compression grows mildly with the layers printed
    // on top (synthetic, so that the slider changes the colours), bed joints as above.
    let mut states = Vec::new();
    for printed in 1..=total {
        let mut stress = Vec::new();
        for (k, l) in layers.iter().take(printed).enumerate() {
            let above = (printed - 1 - k) as f64 / total as f64;
            stress.extend(l.segment_stress.iter().map(|s| s * (0.8 + 0.4 * above)));
        }
        let joint_max = (printed as f64 - 1.0) * GAMMA * LAYER_H * am.tan();
        let sigma_min = stress.iter().copied().fold(-joint_max, f64::min);
        let sigma_max = stress.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let max_overhang = layers
            .iter()
            .take(printed)
            .filter_map(|l| l.overhang)
            .fold(0.0, f64::max);
        let progress = printed as f64 / total as f64;
        states.push(PrintState {
            index: printed - 1,
            progress,
            layers_printed: printed,
            blf: Some(2.4 + 60.0 * (1.0 - progress).powi(2)),
            sigma_min,
            sigma_max,
            max_overhang,
            ok: true,
            segment_stress: Some(stress),
        });
    }
    let worst_min = states.iter().map(|s| s.sigma_min).fold(0.0, f64::min);
    let worst_min_state = states.iter().position(|s| s.sigma_min == worst_min);
    let worst_max = states
        .iter()
        .map(|s| s.sigma_max)
        .fold(f64::NEG_INFINITY, f64::max);
    let worst_blf = states
        .iter()
        .filter_map(|s| s.blf)
        .fold(f64::INFINITY, f64::min);
    let worst_overhang = states.iter().map(|s| s.max_overhang).fold(0.0, f64::max);

    // Robot: UR10e on a pedestal in front of the cap (+y), nozzle tip on the path.
    // Base 0.6 m in front of the middle of the cap's extent in y and 0.45 m up, so that every
    // path point (up to ~1.1 m away) is inside the UR10e's 1.3 m reach.
    let (y_min, y_max) = layers
        .iter()
        .flat_map(|l| l.nodes.iter().map(|p| p[1]))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
            (a.min(y), b.max(y))
        });
    // Two stations (the second 0.1 m further along +y for the second half of the path), so the
    // page shows a station change; the nozzle tip follows every path point.
    let base0 = [0.0, 0.5 * (y_min + y_max) + 0.6, 0.45];
    let base1 = add(base0, [0.0, 0.1, 0.0]);
    let switch = print_path.points.len() / 2;
    let speed = 0.05; // m/s along the path
    let mut robot = RobotAnimation {
        times: Vec::new(),
        joints: Vec::new(),
        link_radii: RADII.to_vec(),
        poses: Vec::new(),
        ..RobotAnimation::default()
    };
    let mut q = [-FRAC_PI_2, -1.2, 1.6];
    // Converge on the first path point before recording, so the animation starts settled.
    if let Some(p0) = print_path.points.first() {
        for _ in 0..10 {
            q = ik_position(base0, *p0, q);
        }
    }
    let mut t = 0.0;
    let mut last: Option<Vec3> = None;
    let mut point_time = Vec::with_capacity(print_path.points.len());
    let mut layer_of_last = None;
    for (i, p) in print_path.points.iter().enumerate() {
        let layer = print_path.layer.get(i).copied();
        if let Some(l) = last {
            t += norm(sub(*p, l)) / speed;
            // 4 s between layers (travel and settle), 20 s for the station change.
            if layer != layer_of_last {
                t += if i == switch { 20.0 } else { 4.0 };
            }
        }
        last = Some(*p);
        layer_of_last = layer;
        point_time.push(t);
        let (station, base) = if i < switch { (0, base0) } else { (1, base1) };
        if i == switch {
            for _ in 0..10 {
                q = ik_position(base, *p, q);
            }
        }
        q = ik_position(base, *p, q);
        let qq = joints(q);
        let chain = ur_chain(base, &qq);
        let mut pose: Vec<[Vec3; 2]> = chain.windows(2).map(|w| [w[0], w[1]]).collect();
        pose.truncate(RADII.len());
        robot.times.push(t);
        robot.joints.push(qq);
        robot.poses.push(pose);
        robot.station.push(station);
    }
    // The capsule poses are only the fallback when there is no cell; the cell draws the meshes.
    robot.poses.clear();
    let translation = |b: Vec3| {
        [
            [1.0, 0.0, 0.0, b[0]],
            [0.0, 1.0, 0.0, b[1]],
            [0.0, 0.0, 1.0, b[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]
    };
    let ids: Vec<i32> = layers.iter().map(|l| l.id).collect();
    let split_layer = print_path.layer.get(switch).copied().unwrap_or(0);
    let split = ids.iter().position(|&id| id == split_layer).unwrap_or(0);
    let floor = -0.3;
    let cell = Cell {
        stations: vec![
            Station {
                world_from_base: translation(base0),
                layers: ids.get(..split).unwrap_or(&[]).to_vec(),
            },
            Station {
                world_from_base: translation(base1),
                layers: ids.get(split..).unwrap_or(&[]).to_vec(),
            },
        ],
        flange_from_tcp: translation([0.0, 0.0, NOZZLE]),
        tool: vec![Capsule {
            a: [0.0, 0.0, 0.01],
            b: [0.0, 0.0, NOZZLE - 0.03],
            radius: 0.03,
        }],
        mobile_base: vec![BoxBody {
            name: "pedestal".into(),
            center: [0.0, 0.0, 0.5 * (floor - base0[2])],
            half_extents: [0.15, 0.15, 0.5 * (base0[2] - floor)],
            yaw: 0.0,
        }],
        obstacles: [-1.0, 1.0]
            .iter()
            .map(|sx: &f64| BoxBody {
                name: if *sx < 0.0 { "beam_left" } else { "beam_right" }.into(),
                center: [sx * (SPAN / 2.0 + 0.05), 0.5 * (y_min + y_max), floor / 2.0],
                half_extents: [0.05, 0.5 * (y_max - y_min) + 0.1, -floor / 2.0],
                yaw: 0.0,
            })
            .collect(),
        floor_z: Some(floor),
    };
    let total_time = t;

    // Mode shapes: a bulge of the top layers along the layer normal, half a sine over each
    // layer, decaying downward (synthetic).
    let modes: Vec<ModeShape> = states
        .iter()
        .enumerate()
        .filter(|(_, st)| st.layers_printed >= 2)
        .map(|(si, st)| {
            let top = st.layers_printed - 1;
            let displacement = layers
                .iter()
                .take(st.layers_printed)
                .enumerate()
                .flat_map(|(k, l)| {
                    let decay = (-((top - k) as f64) / 3.0).exp();
                    let m = l.nodes.len().max(2) - 1;
                    (0..l.nodes.len())
                        .map(move |j| scale(n, decay * (PI * j as f64 / m as f64).sin()))
                })
                .collect();
            ModeShape {
                state: si,
                blf: st.blf.unwrap_or(0.0),
                displacement,
            }
        })
        .collect();

    // Layer age: time since the layer was finished, per state (the state ends with its top layer).
    let layer_end: Vec<f64> = ids
        .iter()
        .map(|id| {
            print_path
                .layer
                .iter()
                .zip(&point_time)
                .filter(|(l, _)| *l == id)
                .map(|(_, t)| *t)
                .fold(0.0, f64::max)
        })
        .collect();
    let age = Quantity {
        key: "layer_age".into(),
        label: "layer age".into(),
        unit: "min".into(),
        to_unit: 1.0 / 60.0,
        per: QuantityPer::Layer,
        diverging: false,
        states: states
            .iter()
            .map(|st| {
                let now = layer_end.get(st.layers_printed - 1).copied().unwrap_or(0.0);
                layer_end
                    .iter()
                    .take(st.layers_printed)
                    .map(|e| now - e)
                    .collect()
            })
            .collect(),
        note: Some("time since the layer was finished (synthetic)".into()),
    };
    let crown = |k: usize| {
        layers.get(k).map_or([0.0; 3], |l| {
            l.nodes.get(l.nodes.len() / 2).copied().unwrap_or([0.0; 3])
        })
    };
    let worst_places = vec![
        WorstPlace {
            constraint: "sigma_min".into(),
            state: worst_min_state,
            layer: layers.first().map(|l| l.id),
            position: layers
                .first()
                .and_then(|l| l.nodes.first().copied())
                .unwrap_or([0.0; 3]),
            signed_value: None,
        },
        WorstPlace {
            constraint: "blf".into(),
            state: Some(total - 1),
            layer: layers.last().map(|l| l.id),
            position: crown(total - 1),
            signed_value: None,
        },
    ];

    let parameters = vec![
        Parameter {
            key: "span Cs".into(),
            value: format!("{SPAN}"),
            unit: "m".into(),
        },
        Parameter {
            key: "rise Cr".into(),
            value: format!("{RISE}"),
            unit: "m".into(),
        },
        Parameter {
            key: "layer tilt am".into(),
            value: format!("{TILT_DEG}"),
            unit: "deg".into(),
        },
        Parameter {
            key: "layer height lh".into(),
            value: format!("{LAYER_H}"),
            unit: "m".into(),
        },
        Parameter {
            key: "layer width lw".into(),
            value: format!("{LAYER_W}"),
            unit: "m".into(),
        },
        Parameter {
            key: "specific weight γ".into(),
            value: format!("{GAMMA}"),
            unit: "N/m³".into(),
        },
        Parameter {
            key: "centre layers N".into(),
            value: format!("{CENTRE_LAYERS}"),
            unit: String::new(),
        },
        Parameter {
            key: "start layers K".into(),
            value: format!("{start_k}"),
            unit: String::new(),
        },
        Parameter {
            key: "catenary a".into(),
            value: format!("{a:.6}"),
            unit: "m".into(),
        },
    ];
    let constraints = vec![
        ConstraintRow {
            name: "sigma_min".into(),
            bound: Bound::AtLeast,
            limit: -20.0,
            worst: worst_min / 1e3,
            unit: "kPa".into(),
            state: worst_min_state,
            element: Some("layer 0, springing segment".into()),
            pass: worst_min >= -20e3,
        },
        ConstraintRow {
            name: "sigma_max".into(),
            bound: Bound::AtMost,
            limit: 0.0,
            worst: worst_max / 1e3,
            unit: "kPa".into(),
            state: None,
            element: None,
            pass: worst_max <= 0.0,
        },
        ConstraintRow {
            name: "blf".into(),
            bound: Bound::AtLeast,
            limit: 1.0,
            worst: worst_blf,
            unit: String::new(),
            state: Some(total - 1),
            element: None,
            pass: worst_blf >= 1.0,
        },
        ConstraintRow {
            name: "overhang".into(),
            bound: Bound::AtMost,
            limit: LAYER_W / 2.0 * 1e3,
            worst: worst_overhang * 1e3,
            unit: "mm".into(),
            state: None,
            element: None,
            pass: worst_overhang <= LAYER_W / 2.0,
        },
        ConstraintRow {
            name: "robot collisions".into(),
            bound: Bound::AtMost,
            limit: 0.0,
            worst: 0.0,
            unit: "frames".into(),
            state: None,
            element: None,
            pass: true,
        },
    ];

    ReportInput {
        name: "demo cap (synthetic data)".into(),
        parameters,
        layers,
        bed_joints,
        print_path,
        states,
        constraints,
        robot: Some(robot),
        plots: Vec::new(),
        timeline: Some(Timeline {
            point_time,
            total_time,
        }),
        cell: Some(cell),
        modes,
        worst_places,
        quantities: vec![age],
        schedule: None,
        robot_summary: Some(crate::robot_summary::RobotSummary {
            design_speed: 0.05,
            max_speed_ratio: 0.62,
            max_acceleration_ratio: 0.81,
            slowdowns: vec![crate::robot_summary::SlowdownRow {
                station: 1,
                from: (3, 10),
                to: (3, 14),
                min_speed_ratio: 0.86,
                reason: "joint acceleration".into(),
            }],
            clearances: vec![crate::robot_summary::ClearanceRow {
                model: "arm capsules".into(),
                to: "environment".into(),
                at_waypoints: 0.0555,
                at: "wrist_3 – beam_right (station 1, layer 3)".into(),
                along_motion: Some(0.031),
            }],
            margin: 0.01,
            self_margin: 0.0,
        }),
    }
}
