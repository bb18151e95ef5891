//! The base placement drawing (issue 28): the plan-view geometry against hand-computed corners,
//! and the section on the page.

use kappe_report::{BoxBody, Cell, Station, demo_input, placement_shapes, render_html};

/// One station at (1, 2) turned +90°, one base box centred 0.5 m behind the arm base:
/// corners (−1.1, ±0.3) and (0.1, ±0.3) in the base frame map by (x, y) → (1 − y, 2 + x).
fn cell() -> Cell {
    Cell {
        stations: vec![
            Station {
                world_from_base: [
                    [0.0, -1.0, 0.0, 1.0],
                    [1.0, 0.0, 0.0, 2.0],
                    [0.0, 0.0, 1.0, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                ],
                layers: vec![3, 1, 2],
            },
            Station {
                world_from_base: [
                    [1.0, 0.0, 0.0, -0.5],
                    [0.0, 1.0, 0.0, 0.25],
                    [0.0, 0.0, 1.0, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                ],
                layers: vec![4, 5],
            },
        ],
        mobile_base: vec![BoxBody {
            name: "body".into(),
            center: [-0.5, 0.0, -0.2],
            half_extents: [0.6, 0.3, 0.2],
            yaw: 0.0,
        }],
        obstacles: vec![BoxBody {
            name: "beam".into(),
            center: [0.0, 0.0, -0.1],
            half_extents: [0.1, 1.0, 0.1],
            yaw: std::f64::consts::FRAC_PI_2,
        }],
        ..Cell::default()
    }
}

#[test]
fn station_outlines_are_the_base_boxes_moved_by_the_base_pose() {
    let mut input = demo_input();
    input.cell = Some(cell());
    let shapes = placement_shapes(&input).unwrap();
    assert_eq!(shapes.stations.len(), 2);
    let s1 = &shapes.stations[0];
    assert_eq!(s1.number, 1);
    assert_eq!(s1.origin, [1.0, 2.0]);
    assert!((s1.yaw_deg - 90.0).abs() < 1e-12);
    assert_eq!(s1.layers, Some((1, 3)));
    let want = [[1.3, 0.9], [1.3, 2.1], [0.7, 2.1], [0.7, 0.9]];
    // 1e-12 m: two rotations of numbers of order 1 in f64.
    for (got, want) in s1.outlines[0].iter().zip(want) {
        assert!(
            (got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12,
            "{got:?} vs {want:?}"
        );
    }
    // The second station is not turned: its box is only shifted by (−0.5, 0.25).
    let s2 = &shapes.stations[1];
    let c = s2.outlines[0][0];
    assert!(
        (c[0] + 1.6).abs() < 1e-12 && (c[1] + 0.05).abs() < 1e-12,
        "{c:?}"
    );
    assert!(s2.yaw_deg.abs() < 1e-12);
    // The beam turned by 90° about its centre: 2 m long along x.
    let (name, beam) = &shapes.obstacles[0];
    assert_eq!(name, "beam");
    let xs: Vec<f64> = beam.iter().map(|p| p[0]).collect();
    let span =
        xs.iter().copied().fold(f64::MIN, f64::max) - xs.iter().copied().fold(f64::MAX, f64::min);
    assert!((span - 2.0).abs() < 1e-12, "{span}");
    // The footprint is the cap's layers, one polyline per layer.
    assert_eq!(shapes.footprint.len(), input.layers.len());
}

#[test]
fn the_page_shows_the_drawing_and_the_poses() {
    let mut input = demo_input();
    input.cell = Some(cell());
    // The demo's arm animation belongs to its own cell.
    input.robot = None;
    let html = render_html(&input).unwrap();
    let start = html
        .find("<section id=\"placement\"")
        .expect("placement section");
    let sec = &html[start..];
    let sec = &sec[..sec.find("</section>").unwrap()];
    assert!(sec.contains("<svg"), "drawing inline");
    assert!(sec.contains("1: x 1.000, y 2.000, yaw 90.0°"), "label");
    assert!(sec.contains("<td>2</td><td>-0.500</td><td>0.250</td><td>0.0</td><td>4 to 5</td>"));
    // Without a cell there is nothing to place.
    input.cell = None;
    assert!(!render_html(&input).unwrap().contains("id=\"placement\""));
}
