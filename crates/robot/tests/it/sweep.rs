//! Certified clearances along a motion (`kappe_robot::sweep`): the motion bound is a true bound
//! (checked against densely sampled motions), and an obstacle that only the middle of a move
//! passes through is caught although both ends are clear.

use kappe_robot::collision::{CapsuleSpec, Obstacle, RobotModel, Scene, TOOL_LINK};
use kappe_robot::kinematics::Joints;
use kappe_robot::sweep::{SweepBounds, certify};
use kappe_robot::{Iso, UR10E};
use parry3d_f64::glamx::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn model() -> RobotModel {
    let tool = CapsuleSpec {
        link: TOOL_LINK,
        name: "tool".into(),
        a: [0.0, 0.0, 0.02],
        b: [0.0, 0.0, 0.23],
        radius: 0.04,
    };
    RobotModel::ur10e_with_tool(&[tool]).unwrap()
}

fn lerp(a: &Joints, b: &Joints, s: f64) -> Joints {
    std::array::from_fn(|j| a[j] + s * (b[j] - a[j]))
}

/// Points on each capsule's surface (its ends ± the radius along the link axes), in the DH
/// frame of the capsule's link.
fn surface_points(m: &RobotModel) -> Vec<(usize, DVec3)> {
    let mut out = Vec::new();
    for c in &m.capsules {
        for end in [c.a, c.b] {
            for u in [
                DVec3::X,
                DVec3::NEG_X,
                DVec3::Y,
                DVec3::NEG_Y,
                DVec3::Z,
                DVec3::NEG_Z,
            ] {
                out.push((c.link, DVec3::from(end) + u * c.radius));
            }
        }
    }
    out
}

#[test]
fn motion_bound_holds_on_densely_sampled_motions() {
    let m = model();
    let bounds = SweepBounds::for_capsules(&UR10E, &m.capsules, [0.0; 8]);
    let pts = surface_points(&m);
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let mut worst = 0.0f64;
    for _ in 0..40 {
        let qa: Joints = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
        let qb: Joints = std::array::from_fn(|j| qa[j] + rng.random_range(-0.5..0.5));
        let tv: [f64; 6] = std::array::from_fn(|j| (qb[j] - qa[j]).abs());
        let fa = UR10E.fk_frames(&qa);
        // 400 samples: the bound is on the whole motion, so every sample must be inside it.
        for s in 1..=400 {
            let q = lerp(&qa, &qb, f64::from(s) / 400.0);
            let f = UR10E.fk_frames(&q);
            for &(k, p) in &pts {
                let kf = k.min(6);
                let moved = (f[kf].point(p) - fa[kf].point(p)).length();
                let bound = bounds.world(&tv, k);
                // 1e-12 m: round-off of the transforms.
                assert!(
                    moved <= bound + 1e-12,
                    "link {k} moved {moved} > bound {bound}"
                );
                worst = worst.max(moved / bound);
                // Relative to every lower link (the self pairs' bound).
                for a in 0..kf {
                    let rel = |fr: &[Iso; 7]| fr[a].inverse().mul(&fr[kf]).point(p);
                    let moved = (rel(&f) - rel(&fa)).length();
                    let bound = bounds.relative(&tv, a, k);
                    assert!(
                        moved <= bound + 1e-12,
                        "link {k} moved {moved} relative to link {a} > bound {bound}"
                    );
                }
            }
        }
    }
    // The bound is not vacuous: some motion uses a fair part of it.
    assert!(worst > 0.2, "largest motion / bound {worst}");
}

#[test]
fn an_obstacle_in_the_middle_of_a_move_is_caught() {
    let m = model();
    let bounds = SweepBounds::for_capsules(&UR10E, &m.capsules, [0.0; 8]);
    let qa: Joints = [0.0, -1.2, 1.5, -1.9, -1.57, 0.0];
    let mut qb = qa;
    qb[0] += 0.6;
    let qm = lerp(&qa, &qb, 0.5);
    // A 4 cm cube at the middle of the tool capsule half-way through the move.
    let tool_mid = |q: &Joints| {
        let p = m.pose(q, &Iso::IDENTITY);
        let c = p.as_slice().iter().find(|c| c.link == TOOL_LINK).copied();
        c.map(|c| 0.5 * (c.a + c.b)).unwrap()
    };
    let centre = tool_mid(&qm);
    let scene = Scene::new(&[Obstacle::Box {
        name: "post".into(),
        center: centre.to_array(),
        half_extents: [0.02; 3],
        yaw: 0.0,
    }])
    .unwrap();
    let measure = |q: &Joints| -> [f64; 1] {
        let p = m.pose(q, &Iso::IDENTITY);
        [scene.clearance(p.as_slice(), 0, 0.5).distance]
    };
    let displacement =
        |tv: &[f64; 6]| -> [f64; 1] { [(1..8).map(|k| bounds.world(tv, k)).fold(0.0, f64::max)] };
    // Both ends are well clear (a waypoint check passes) …
    let (da, db) = (measure(&qa)[0], measure(&qb)[0]);
    assert!(da > 0.05 && db > 0.05, "ends {da} {db}");
    // … the middle is inside the cube …
    assert!(measure(&qm)[0] <= 0.0);
    // … and the certified bound with a 1 cm margin finds it.
    let (lb, n) = certify(&[qa, qb], &measure, &displacement, [0.01], [0.01], None);
    assert!(lb[0] <= 0.0, "certified {}", lb[0]);
    assert!(n > 2, "the move was split ({n} configurations)");
    // Once a measured configuration fails, the move is split no further (not 2^14 pieces).
    assert!(n < 10, "{n} configurations");
    // With the cube removed the same move is certified clear of the margin.
    let free = Scene::new(&[]).unwrap();
    let measure_free = |q: &Joints| -> [f64; 1] {
        let p = m.pose(q, &Iso::IDENTITY);
        [free.clearance(p.as_slice(), 0, 0.5).distance]
    };
    let (lb, _) = certify(
        &[qa, qb],
        &measure_free,
        &displacement,
        [0.01],
        [0.01],
        None,
    );
    assert!(lb[0] >= 0.01, "certified {}", lb[0]);
}

#[test]
fn certified_minimum_is_below_and_near_the_sampled_minimum() {
    let m = model();
    let bounds = SweepBounds::for_capsules(&UR10E, &m.capsules, [0.0; 8]);
    let qa: Joints = [0.3, -1.0, 1.2, -1.7, -1.57, 0.0];
    let qb: Joints = [-0.4, -1.4, 1.8, -2.0, -1.2, 0.3];
    // A wall: the nearest link changes along the move (a floor would be nearest to the base,
    // which does not move, and make the minimum flat).
    let scene = Scene::new(&[Obstacle::HalfSpace {
        name: "wall".into(),
        point: [0.0, 0.5, 0.0],
        normal: [0.0, -1.0, 0.0],
    }])
    .unwrap();
    let measure = |q: &Joints| -> [f64; 1] {
        let p = m.pose(q, &Iso::IDENTITY);
        let moving: Vec<_> = p
            .as_slice()
            .iter()
            .copied()
            .filter(|c| c.link > 0)
            .collect();
        [scene.clearance(&moving, 0, 2.0).distance]
    };
    let displacement =
        |tv: &[f64; 6]| -> [f64; 1] { [(1..8).map(|k| bounds.world(tv, k)).fold(0.0, f64::max)] };
    let dense = (0..=2000)
        .map(|s| measure(&lerp(&qa, &qb, f64::from(s) / 2000.0))[0])
        .fold(f64::INFINITY, f64::min);
    // 1 mm tolerance: the tightening stops once the bound is within it of the measured minimum.
    let (lb, _) = certify(
        &[qa, qb],
        &measure,
        &displacement,
        [0.0],
        [0.0],
        Some([1e-3]),
    );
    assert!(
        lb[0] <= dense + 1e-12,
        "certified {} > sampled {dense}",
        lb[0]
    );
    assert!(
        lb[0] >= dense - 2e-3,
        "certified {} ≪ sampled {dense}",
        lb[0]
    );
}
