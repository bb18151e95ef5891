//! Capsule model and self-collision pairs against `ur10e_capsules.json` (robot.md §7 "Capsules"),
//! and robot-vs-environment distances against closed forms.

use kappe_robot::UR10E;
use kappe_robot::collision::{
    CapsuleSpec, LINK_NAMES, Obstacle, PlacedCapsule, RobotModel, Scene, ur10e_arm_capsules,
};
use parry3d_f64::glamx::DVec3;

use crate::common::*;

fn fixture_model(f: &serde_json::Value) -> RobotModel {
    let mut caps = Vec::new();
    for (li, name) in LINK_NAMES.iter().enumerate() {
        let link = &f["model"][*name];
        assert_eq!(link["dh_frame"].as_u64().unwrap() as usize, li.min(6));
        for c in link["capsules"].as_array().unwrap() {
            caps.push(CapsuleSpec {
                link: li,
                name: c["name"].as_str().unwrap().into(),
                a: vec3(&c["a"]),
                b: vec3(&c["b"]),
                radius: c["radius"].as_f64().unwrap(),
            });
        }
    }
    let idx = |n: &str| LINK_NAMES.iter().position(|x| *x == n).unwrap();
    let pairs = f["self_pairs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (idx(p[0].as_str().unwrap()), idx(p[1].as_str().unwrap())))
        .collect();
    RobotModel::new(UR10E, caps, pairs).unwrap()
}

#[test]
fn built_in_model_equals_fixture_model() {
    let f = fixture("ur10e_capsules.json");
    let fx = fixture_model(&f);
    let arm = ur10e_arm_capsules();
    assert_eq!(arm.len(), fx.capsules.len() - 1);
    for (a, b) in arm.iter().zip(&fx.capsules) {
        assert_eq!(a, b);
    }
    let builtin_pairs: Vec<_> = kappe_robot::collision::SELF_PAIRS.to_vec();
    assert_eq!(builtin_pairs, fx.self_pairs);
}

#[test]
fn self_pair_distances_match_fixture() {
    let f = fixture("ur10e_capsules.json");
    let model = fixture_model(&f);
    let cases = f["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 200);
    let mut colliding = 0;
    for c in cases {
        let q = joints(&c["q"]);
        let d = model.self_pair_distances(&q);
        for (k, p) in c["pairs"].as_array().unwrap().iter().enumerate() {
            let want = p["signed_distance"].as_f64().unwrap();
            // 1e-9 m (robot.md §7): exact segment distances on the same FK.
            assert!(
                (d[k] - want).abs() <= 1e-9,
                "{} pair {k}: {} vs {want}",
                c["id"],
                d[k]
            );
        }
        let flag = c["self_collision"].as_bool().unwrap();
        assert_eq!(model.self_collides(&q, 0.0), flag, "{}", c["id"]);
        colliding += usize::from(flag);
    }
    assert_eq!(colliding, 89);
}

#[test]
fn environment_distances_closed_form() {
    // A unit box centred at x = 1 and a floor at z = −1; a sphere (degenerate capsule) of radius
    // 0.1 at the origin is 0.5 − 0.1 = 0.4 from the box and 1 − 0.1 = 0.9 from the floor.
    let scene = Scene::new(&[
        Obstacle::Box {
            name: "box".into(),
            center: [1.0, 0.0, 0.0],
            half_extents: [0.5, 0.5, 0.5],
            yaw: 0.3,
        },
        Obstacle::HalfSpace {
            name: "floor".into(),
            point: [0.0, 0.0, -1.0],
            normal: [0.0, 0.0, 1.0],
        },
        Obstacle::Capsules {
            name: "bead".into(),
            points: vec![[0.0, 2.0, -5.0], [0.0, 2.0, 5.0]],
            radius: 0.01,
        },
    ])
    .unwrap();
    let sphere = PlacedCapsule {
        a: DVec3::ZERO,
        b: DVec3::ZERO,
        radius: 0.1,
        link: 3,
    };
    let c = scene.clearance(&[sphere], 0, 10.0);
    // In the box frame (rotated by yaw = 0.3 about its centre) the origin sits at
    // (−cos 0.3, sin 0.3, 0); |sin 0.3| < 0.5, so the nearest box point differs only in x and
    // the gap is cos 0.3 − 0.5, minus the sphere radius.
    let want_box = 0.3f64.cos() - 0.5 - 0.1;
    // 1e-7 m: parry's GJK tolerance on curved shapes is ~1e-8 m (robot.md §2.4).
    assert!((c.distance - want_box).abs() < 1e-7, "{c:?} vs {want_box}");
    assert_eq!(c.object.as_deref(), Some("box"));
    // Move it to (0, 0.5, 2): the bead line (x = 0, y = 2) is 1.5 − 0.11 away, the floor
    // 3 − 0.1 and the box more than 1.45 (its top is at z = 0.5).
    let up = PlacedCapsule {
        a: DVec3::new(0.0, 0.5, 2.0),
        b: DVec3::new(0.0, 0.5, 2.0),
        ..sphere
    };
    let c = scene.clearance(&[up], 0, 10.0);
    let want = 1.5 - 0.11;
    assert!((c.distance - want).abs() < 1e-12, "{c:?} vs {want}");
    assert_eq!(c.object.as_deref(), Some("bead"));
    // Cut-off: nothing within 0.5 m.
    let c = scene.clearance(&[up], 0, 0.5);
    assert_eq!((c.distance, c.object), (0.5, None));
}

#[test]
fn invalid_obstacles_are_rejected() {
    let bad = Obstacle::Box {
        name: "beam".into(),
        center: [0.0; 3],
        half_extents: [0.1, 0.0, 0.1],
        yaw: 0.0,
    };
    let err = Scene::new(&[bad]).err().unwrap().to_string();
    assert!(
        err.contains("obstacles[0]") && err.contains("beam"),
        "{err}"
    );
}

/// The URDF chain that poses the collision meshes ends at `tool0` = the DH flange: the two
/// kinematic descriptions agree (robot.md §1.2: 6e-10, the URDF rounds π/2 to 1.570796327;
/// 1e-8 m / 1e-8 rad leaves room for that and f64 round-off).
#[test]
fn urdf_chain_of_the_meshes_matches_the_dh_flange() {
    use kappe_robot::meshes::urdf_link_frames;
    let fx = fixture("ur10e_ik.json");
    for case in fx["fk_cases"].as_array().unwrap().iter().take(50) {
        let q = joints(&case["q"]);
        let (_, tool0) = urdf_link_frames(&q);
        let dh = kappe_robot::UR10E.fk(&q);
        assert!((tool0.t - dh.t).length() < 1e-8, "{q:?}");
        assert!(tool0.rotation_angle_to(&dh) < 1e-8, "{q:?}");
    }
}

/// The meshes load as convex hulls with the vertex counts of the STL files (robot.md: 71–939),
/// and every hull lies inside its link's capsules inflated by a few centimetres (the capsules
/// were fitted to the visual meshes, which the collision hulls wrap): a gross misplacement of a
/// mesh (wrong origin or rotation) would put it tens of centimetres away.
#[test]
fn meshes_sit_on_their_links() {
    use kappe_robot::collision::ur10e_arm_capsules;
    use kappe_robot::meshes::ArmMeshes;
    use parry3d_f64::shape::Shape;
    let m = ArmMeshes::load().unwrap();
    assert_eq!(m.hulls.len(), 7);
    let q = [0.3, -1.2, 1.4, -0.7, 1.1, 0.4];
    let poses = m.poses(&q, &kappe_robot::Iso::IDENTITY);
    let frames = kappe_robot::UR10E.fk_frames(&q);
    let caps = ur10e_arm_capsules();
    for i in 0..7 {
        // Mesh centre (AABB centre) to the nearest capsule axis of the same link.
        let bb = m.hulls[i].compute_aabb(&poses[i]);
        let c = (bb.mins + bb.maxs) * 0.5;
        let d = caps
            .iter()
            .filter(|k| k.link == i)
            .map(|k| {
                let a = frames[i].point(k.a.into());
                let b = frames[i].point(k.b.into());
                let t = ((c - a).dot(b - a) / (b - a).length_squared().max(1e-12)).clamp(0.0, 1.0);
                (a + (b - a) * t - c).length() - k.radius
            })
            .fold(f64::INFINITY, f64::min);
        // 0.05 m: the hull's box centre may sit off the capsule axis by up to its radius
        // plus the hull/capsule fit difference.
        assert!(d < 0.05, "link {i}: mesh centre {d} m outside its capsules");
    }
}
