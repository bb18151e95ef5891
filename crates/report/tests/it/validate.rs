//! Bad input gives typed errors naming the field, before anything is rendered.

use kappe_report::{ReportError, demo_input, render_html};

#[test]
fn nan_node_is_named() {
    let mut input = demo_input();
    input.layers[2].nodes[5][1] = f64::NAN;
    let err = render_html(&input).unwrap_err();
    match &err {
        ReportError::NotFinite { field, .. } => assert_eq!(field, "layers[2].nodes[5][1]"),
        other => panic!("unexpected {other:?}"),
    }
    assert!(err.to_string().contains("layers[2].nodes[5][1]"));
}

#[test]
fn stress_count_must_match_segments() {
    let mut input = demo_input();
    input.layers[0].segment_stress.pop();
    let err = render_html(&input).unwrap_err();
    assert!(
        matches!(&err, ReportError::LengthMismatch { field, .. } if field == "layers[0].segment_stress"),
        "{err}"
    );
}

#[test]
fn state_beyond_layers_is_rejected() {
    let mut input = demo_input();
    let n = input.layers.len();
    input.states[0].layers_printed = n + 1;
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::OutOfRange { field, .. } if field == "states[0].layers_printed"
    ));
    input.states[0].layers_printed = 0;
    assert!(render_html(&input).is_err());
}

#[test]
fn per_state_stress_length_is_checked() {
    let mut input = demo_input();
    if let Some(s) = input.states[3].segment_stress.as_mut() {
        s.push(0.0);
    }
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::LengthMismatch { field, .. } if field == "states[3].segment_stress"
    ));
}

#[test]
fn unknown_layer_and_robot_shapes_are_rejected() {
    let mut input = demo_input();
    input.bed_joints[0].layer = 999;
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::UnknownLayer { id: 999, .. }
    ));

    // Without a cell the robot needs its capsule poses.
    let mut input = demo_input();
    input.cell = None;
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::LengthMismatch { field, .. } if field == "robot.poses"
    ));

    let mut input = demo_input();
    input.robot.as_mut().unwrap().station[3] = 7;
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::OutOfRange { field, .. } if field == "robot.station[3]"
    ));

    let mut input = demo_input();
    input.timeline.as_mut().unwrap().point_time.pop();
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::LengthMismatch { field, .. } if field == "timeline.point_time"
    ));

    let mut input = demo_input();
    input.modes[2].displacement.pop();
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::LengthMismatch { field, .. } if field == "modes[2].displacement"
    ));

    let mut input = demo_input();
    input.quantities[0].states[4].push(1.0);
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::LengthMismatch { field, .. } if field == "quantities[0].states[4]"
    ));

    let mut input = demo_input();
    input.print_path.tool_axis.pop();
    assert!(render_html(&input).is_err());
}

#[test]
fn empty_input_is_rejected() {
    let mut input = demo_input();
    input.states.clear();
    assert!(matches!(
        render_html(&input).unwrap_err(),
        ReportError::Empty { field } if field == "states"
    ));
}
