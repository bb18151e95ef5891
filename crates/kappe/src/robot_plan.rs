//! From the print path to a verified UR10e plan (paper §3.4, method.md §8): the layers' targets
//! go to `kappe_robot::plan_print` with the support beams as obstacles and the bead settings of
//! the design. The planner verifies the plan before it returns it.

use kappe_robot::Plan;
use kappe_robot::setup::{PathPoint as RobotPoint, PrintLayer, beams};

use crate::path::PrintPath;
use crate::pipeline::Cap;

/// The print targets grouped by layer, in print order (the `layer,index` of `path.csv`).
pub fn print_layers(path: &PrintPath) -> Vec<PrintLayer> {
    let mut layers: Vec<PrintLayer> = Vec::new();
    for p in &path.points {
        let point = RobotPoint {
            index: p.index,
            position: [p.tip.x, p.tip.y, p.tip.z],
            axis: [p.axis.x, p.axis.y, p.axis.z],
        };
        match layers.last_mut() {
            Some(l) if l.layer == i64::from(p.layer) => l.points.push(point),
            _ => layers.push(PrintLayer {
                layer: i64::from(p.layer),
                points: vec![point],
            }),
        }
    }
    layers
}

/// The robot cell and planner options of a design, with the beams under the cap added.
pub fn robot_inputs(
    cap: &Cap,
) -> (
    kappe_robot::setup::RobotSetup,
    kappe_robot::setup::PlanOptions,
) {
    let d = &cap.design;
    let r = &d.robot;
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &cap.path.points {
        y0 = y0.min(p.bead.y);
        y1 = y1.max(p.bead.y);
    }
    let mut setup = r.setup.clone();
    setup.obstacles.extend(beams(
        d.cap.span,
        r.beams.width,
        r.beams.height,
        y0 - r.beams.overrun,
        y1 + r.beams.overrun,
    ));
    let mut opts = r.plan.clone();
    opts.print_speed = d.print.print_speed;
    opts.bead_radius = 0.5 * d.print.layer_width;
    opts.bead_offset = 0.5 * d.print.layer_height;
    (setup, opts)
}

/// Plan the robot for the whole print.
pub fn plan_robot(cap: &Cap) -> Result<Plan, kappe_robot::RobotError> {
    let (setup, opts) = robot_inputs(cap);
    kappe_robot::plan_print(&print_layers(&cap.path), &setup, &opts)
}
