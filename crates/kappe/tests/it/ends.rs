//! Ends that carry the thrust (issue 15, `kappe::form::ends`): the end wall takes the stack thrust of
//! method.md §5, column by column, checked against the closed form and by equilibrium.

use kappe::Design;
use kappe::form::{ArchSpec, form_find_layer};
use kappe::form::{EndKind, stack_thrust, wall_load};
use kappe::form::{LayerFrame, V3};
use kappe::form::{NodeKind, Sections, build_sections_with_end};
use kappe::form::{Role, build_state};
use kappe::form::{Sections2D, state_forces};

/// The sections of `d` with the given end, built as the pipeline builds them.
fn sections(d: &Design, end: EndKind) -> (Sections, LayerFrame, Sections2D) {
    let tilt = d.tilt();
    let frame = LayerFrame::new(tilt);
    let arch = form_find_layer(&ArchSpec {
        span: d.cap.span,
        rise: d.cap.rise,
        tilt,
        specific_weight: d.material.specific_weight,
        layer_width: d.print.layer_width,
        layer_height: d.print.layer_height,
        path_sampling: d.print.path_sampling,
    })
    .unwrap();
    let w = d.material.specific_weight * d.print.layer_width * d.print.layer_height;
    let s = build_sections_with_end(
        &arch,
        &frame,
        d.cap.length,
        d.print.layer_height,
        d.print.start_arch_fraction,
        |c| 0.5 * c * w,
        end,
    )
    .unwrap();
    let areas = Sections2D {
        along_layer: d.print.layer_width * d.print.layer_height,
        bed_joint: d.print.layer_width * arch.segment_length,
    };
    (s, frame, areas)
}

/// Every state of an end-wall cap: the wall load equals the stack thrust Σ_i (t+1)·W_i·tan(am)
/// (issue 15: 1e-9 relative), column by column, and is horizontal.
///
/// 1e-9 relative: the force pass sums t + 1 bed-joint increments per column in floating point
/// (≤ 300 terms, ~1e-14 each) and the layer arch is form-found to 1e-13 (method.md §4), so the
/// wall reaction matches the closed form to ~1e-12; 1e-9 is the bound.
#[test]
fn wall_load_equals_stack_thrust_in_every_state() {
    for length in [0.6, 2.4] {
        let mut d = Design::default();
        d.cap.length = length;
        let (s, frame, areas) = sections(&d, EndKind::EndWall);
        assert_eq!(s.n_start, 0, "an end-wall cap has no start layers");
        assert_eq!(s.end, EndKind::EndWall);
        let layer0 = &s.layers[0];
        let tan = d.tilt().tan();
        let total = s.layers.len();
        let picks = [0, 1, total / 3, total / 2, total - 2, total - 1];
        for &top in &picks {
            let st = build_state(&s, &frame, 0.0, top).unwrap();
            assert!(
                st.factors.iter().all(|&f| f == 1.0),
                "centre layers have d = 1"
            );
            let (_, fp, forces) = state_forces(&st, areas).unwrap();
            assert!(forces.max_residual <= forces.residual_tolerance);
            let load = wall_load(&st, &fp.reactions, areas, layer0.length()).unwrap();
            let expected = stack_thrust(&s, &frame, top);
            // Independent closed form: (t + 1)·Σ W_i·tan(am), toward −y.
            let t = st.top_layer as f64;
            let w_sum: f64 = layer0
                .nodes
                .iter()
                .filter(|n| matches!(n.kind, NodeKind::Column(_)))
                .map(|n| n.weight)
                .sum();
            let closed = -(t + 1.0) * w_sum * tan;
            assert!((expected.y - closed).abs() <= 1e-12 * closed.abs());
            let got = V3::from(load.total);
            let rel = (got - expected).norm() / expected.norm();
            assert!(
                rel <= 1e-9,
                "L = {length}, state {top}: wall load {got:?} vs {expected:?} ({rel:e})"
            );
            // Per column: (t + 1)·W_i·tan(am) of that column, horizontal along −y.
            assert_eq!(load.per_column.len(), layer0.nodes.len() - 2);
            for c in &load.per_column {
                // The column keeps its x through the stack (layers are translates along y).
                let wi = layer0
                    .nodes
                    .iter()
                    .find(|n| {
                        matches!(n.kind, NodeKind::Column(_)) && (n.xyz.x - c.x).abs() < 1e-12
                    })
                    .map(|n| n.weight)
                    .unwrap();
                let (f, e) = (c.force, -(t + 1.0) * wi * tan);
                assert!(
                    (f[1] - e).abs() <= 1e-9 * e.abs(),
                    "column at x = {}: {} vs {e}",
                    c.x,
                    f[1]
                );
                assert!(
                    f[0].abs() + f[2].abs() <= 1e-9 * e.abs(),
                    "column at x = {}: load not horizontal: {f:?}",
                    c.x
                );
            }
            // The beams carry all the weight: the vertical base reaction is the total load.
            let weight: f64 = st.network.nodes.iter().map(|n| -n.load.z).sum();
            assert!((forces.base_reaction[2] - weight).abs() <= 1e-9 * weight);
        }
    }
}

/// Geometry: column ends lie on the wall face, one layer step behind layer 0, at their node's
/// height; no node lies below the base plane.
#[test]
fn column_ends_lie_on_the_wall_face() {
    let d = Design::default();
    let (s, frame, _) = sections(&d, EndKind::EndWall);
    let st = build_state(&s, &frame, 0.0, s.layers.len() - 1).unwrap();
    let step = frame.layer_step(d.print.layer_height);
    // 1e-12 m: one subtraction of O(1 m) coordinates.
    for trail in &st.network.trails {
        let end = &st.network.nodes[*trail.last().unwrap()];
        let above = &st.network.nodes[trail[trail.len() - 2]];
        assert_eq!(end.role, Role::ColumnEnd);
        assert_eq!(above.layer, 0);
        assert!((end.xyz - (above.xyz - step)).norm() < 1e-12);
        // On the plane of layer −1: n·x = −lh (layer 0's plane through the feet at y = 0 is n·x = 0).
        assert!((frame.n.dot(&end.xyz) + d.print.layer_height).abs() < 1e-12);
    }
    // 1e-12 m: the feet of layer 0 are form-found onto z = 0 to round-off.
    assert!(st.network.nodes.iter().all(|n| n.xyz.z >= -1e-12));
}

/// The design file option: `[cap] end = "end_wall"`; the default is the start section and is not
/// written to resolved design files (outputs of the default design stay byte-identical).
#[test]
fn design_file_end_option() {
    let d = Design::from_toml_str("[cap]\nend = \"end_wall\"\n").unwrap();
    assert_eq!(d.cap.end, EndKind::EndWall);
    let d0 = Design::default();
    assert_eq!(d0.cap.end, EndKind::StartSection);
    assert!(!d0.to_toml_string().unwrap().contains("end ="));
    assert!(d.to_toml_string().unwrap().contains("end = \"end_wall\""));
    let err = Design::from_toml_str("[cap]\nend = \"wall\"\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("cap.end"), "{err}");
    assert!(
        err.contains("end_wall"),
        "the error lists the allowed values: {err}"
    );
}

/// A start-section cap is unchanged by the option: the default sections are the same.
#[test]
fn start_section_is_the_default_end() {
    let d = Design::default();
    let (a, _, _) = sections(&d, EndKind::StartSection);
    assert_eq!(a.n_start, 45, "method.md §6: K = 45 at the defaults");
    assert_eq!(a.end, EndKind::StartSection);
}

/// The 2.4 m bay of issue 15. With today's start section it fails σ_min at a start-section column
/// foot. Against an end wall the start no longer crushes: the wall carries the thrust; the bay
/// then fails σ_min for the reason the report names, the bed joint of layer 0 on the end wall,
/// whose stress is the closed form N·W_i·tan(am) / (lw·l_trib) (method.md §5), and the wall
/// load equals the stack thrust (1e-9 relative, see above).
#[test]
fn long_bay_against_an_end_wall() {
    let stresses_only = kappe::Options {
        analysis: Some(kappe::analysis::AnalysisOptions {
            buckling: false,
            ..Default::default()
        }),
        robot: false,
        ..Default::default()
    };
    let mut d = Design::default();
    d.cap.length = 2.4;
    let start = kappe::run(&d, &stresses_only, &kappe::no_progress).unwrap();
    let a = start.analysis.as_ref().unwrap();
    let c = a
        .constraints
        .iter()
        .find(|c| c.name == "sigma_min")
        .unwrap();
    assert!(!c.pass && c.element.contains("column foot"), "{c:?}");

    d.cap.end = EndKind::EndWall;
    let wall = kappe::run(&d, &stresses_only, &kappe::no_progress).unwrap();
    assert!(!wall.verdict.ok);
    let a = wall.analysis.as_ref().unwrap();
    let c = a
        .constraints
        .iter()
        .find(|c| c.name == "sigma_min")
        .unwrap();
    assert!(!c.pass);
    assert!(
        c.element.contains("end wall"),
        "the report names the wall joint: {c:?}"
    );
    assert!(
        a.constraints.iter().filter(|c| !c.pass).count() == 1,
        "only σ_min fails"
    );
    let cap = &wall.cap;
    let n = cap.sections.n_centre as f64;
    let w_max = cap.sections.layers[0]
        .nodes
        .iter()
        .filter(|n| matches!(n.kind, NodeKind::Column(_)))
        .map(|n| n.weight)
        .fold(0.0, f64::max);
    let sigma = -n * w_max * d.tilt().tan() / cap.areas().bed_joint;
    // 1e-9 relative: the force pass sums N increments (see above).
    assert!(
        (c.worst.unwrap() - sigma).abs() <= 1e-9 * sigma.abs(),
        "{:?} vs {sigma}",
        c.worst
    );
    // ≈ γ·Cl·sin(am) (the interior tributary weight is γ·lw·lh·s): 23.4 kPa > 20 kPa.
    assert!(
        (sigma / -(d.material.specific_weight * d.cap.length * d.tilt().sin()) - 1.0).abs() < 0.01
    );
    // The wall load in summary.json equals the stack thrust.
    let s = serde_json::to_value(wall.summary()).unwrap();
    let total: Vec<f64> = serde_json::from_value(s["end_wall"]["total"].clone()).unwrap();
    let thrust: Vec<f64> = serde_json::from_value(s["end_wall"]["stack_thrust_n"].clone()).unwrap();
    assert!((total[1] - thrust[1]).abs() <= 1e-9 * thrust[1].abs());
    // The default design has no end-wall block (its summary is unchanged).
    let plain = kappe::run(&Design::default(), &stresses_only, &kappe::no_progress).unwrap();
    assert!(plain.summary().end_wall.is_none());
}

/// The end wall is a robot obstacle (`kappe::robot_plan::robot_inputs`): a box behind the wall
/// face, clear of every print target and bead (they all lie in front of the face), spanning the
/// beams; a start-section cap has no wall.
#[test]
fn end_wall_is_a_robot_obstacle() {
    use kappe_robot::collision::Obstacle;
    let mut d = Design::default();
    d.cap.length = 0.2;
    let start = kappe::design_cap(&d, kappe::Context::default()).unwrap();
    let (setup, _) = kappe::robot_plan::robot_inputs(&start);
    assert!(setup.obstacles.iter().all(|o| o.name() != "end_wall"));
    d.cap.end = EndKind::EndWall;
    let cap = kappe::design_cap(&d, kappe::Context::default()).unwrap();
    let (setup, _) = kappe::robot_plan::robot_inputs(&cap);
    let walls: Vec<_> = setup
        .obstacles
        .iter()
        .filter_map(|o| match o {
            Obstacle::Box {
                name,
                center,
                half_extents,
                yaw,
            } if name == "end_wall" => Some((*center, *half_extents, *yaw)),
            _ => None,
        })
        .collect();
    assert_eq!(walls.len(), 1);
    let (c, h, yaw) = walls[0];
    assert_eq!(yaw, 0.0);
    let front = c[1] + h[1];
    // Its front face is the wall face farthest back: the column ends (on the inclined face).
    let face = cap
        .final_state
        .network
        .nodes
        .iter()
        .filter(|n| n.role == Role::ColumnEnd)
        .map(|n| n.xyz.y)
        .fold(f64::INFINITY, f64::min);
    // 1e-12 m: the same number through one addition and subtraction.
    assert!((front - face).abs() < 1e-12, "{front} vs {face}");
    // Every bead centre lies in front of the wall by at least half a layer pitch (the bead of
    // layer 0 touches the inclined face at its own height, the vertical wall is behind that).
    let half_pitch = 0.5 * d.print.layer_height;
    for p in &cap.path.points {
        assert!(
            p.bead.y > front + half_pitch,
            "bead at y {} vs wall {front}",
            p.bead.y
        );
    }
    // It spans the beams and reaches from below the beams to above the crown.
    assert!(h[0] >= 0.5 * d.cap.span + d.robot.beams.width);
    assert!(c[2] - h[2] <= -d.robot.beams.height && c[2] + h[2] >= d.cap.rise);
}
