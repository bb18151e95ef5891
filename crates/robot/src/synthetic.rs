//! A synthetic cap print path for tests, examples and benchmarks (not the designed cap): every
//! layer is a parabolic arch of span `span` and vertical rise `rise` in a plane tilted `tilt` from
//! the vertical (method.md §2 defaults 0.8 m, 0.2 m, 25°), layer planes `layer_height` apart along
//! their normal n = (0, cos tilt, sin tilt). The nozzle tip is `layer_height/2` above the bead
//! centre along n and the tool axis is −n (method.md §7); the direction alternates every layer.

use crate::setup::{PathPoint, PrintLayer};

/// Synthetic cap: `layers` layers of `points` points each.
pub fn cap_path(
    span: f64,
    rise: f64,
    tilt_deg: f64,
    layer_height: f64,
    layers: usize,
    points: usize,
) -> Vec<PrintLayer> {
    let (s, c) = tilt_deg.to_radians().sin_cos();
    let n = [0.0, c, s];
    let axis = [0.0, -c, -s];
    (0..layers)
        .map(|i| {
            // Foot of the layer plane on z = 0 advances by lh / cos(tilt) along y.
            let y0 = i as f64 * layer_height / c;
            let pts = (0..points)
                .map(|k| {
                    let u = if points > 1 {
                        k as f64 / (points - 1) as f64
                    } else {
                        0.5
                    };
                    let u = if i % 2 == 0 { u } else { 1.0 - u };
                    let x = span * (u - 0.5);
                    let z = rise * (1.0 - (2.0 * x / span).powi(2));
                    // In the plane: y = y0 − z·tan(tilt).
                    let bead = [x, y0 - z * s / c, z];
                    PathPoint {
                        index: k,
                        position: [
                            bead[0] + n[0] * layer_height / 2.0,
                            bead[1] + n[1] * layer_height / 2.0,
                            bead[2] + n[2] * layer_height / 2.0,
                        ],
                        axis,
                    }
                })
                .collect();
            PrintLayer {
                layer: i as i64,
                points: pts,
            }
        })
        .collect()
}

/// The set-up the tests and benchmarks plan [`cap_path`] from: the default UR10e on its mobile
/// base, fixed 1.0 m in front of the first layer (world y = 1 m) and turned to face it (−90°
/// about z: the base's x axis along world −y). From there the first ~60 layers of the default
/// synthetic cap are reachable (`examples/try_bases.rs`).
pub fn fixed_base_setup() -> crate::setup::RobotSetup {
    use crate::frames::Iso;
    crate::setup::RobotSetup {
        base: crate::setup::BasePlacement::Fixed {
            world_from_base: Iso::translation(0.0, 1.0, 0.0)
                .mul(&Iso::rot_z(1.5 * std::f64::consts::PI))
                .to_mat4(),
        },
        ..crate::setup::RobotSetup::default()
    }
}
