//! The print path (method.md §7): the bead centre line of every layer, in print order, with the
//! nozzle-tip target lh/2 above it along the layer normal and the tool axis along −n.
//! The direction alternates from layer to layer so the bead never stops; the layer change is the
//! short move to the next layer's nearer foot, and it is printed (the robot plan keeps the pump
//! running through it within a station, issue 13).

use crate::form::frame::{LayerFrame, V3};
use crate::form::section::Sections;

/// One target of the print path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPoint {
    /// Layer id.
    pub layer: i32,
    /// Index of the point along the layer, in print direction.
    pub index: usize,
    /// Nozzle-tip target, m.
    pub tip: V3,
    /// Unit tool axis (from the flange toward the tip), along −n.
    pub axis: V3,
    /// Bead centre-line point under the tip, m.
    pub bead: V3,
}

/// The print path of the whole cap and its fabrication figures.
#[derive(Debug, Clone, PartialEq)]
pub struct PrintPath {
    /// Targets in print order.
    pub points: Vec<PathPoint>,
    /// Length printed (bead centre line), m.
    pub print_length: f64,
    /// Length of the layer-change moves (printed, but not in `print_length` or `volume`), m.
    pub travel_length: f64,
    /// Printed volume lw·lh·length, m³.
    pub volume: f64,
    /// Mass, kg (γ / g with g = 9.81 m/s²).
    pub mass: f64,
    /// Time at the print speed (printing and layer changes), s.
    pub time: f64,
}

/// Standard gravity used to turn specific weight into density, m/s².
pub const GRAVITY: f64 = 9.81;

/// Build the print path of all layers.
pub fn print_path(
    sections: &Sections,
    frame: &LayerFrame,
    layer_height: f64,
    layer_width: f64,
    specific_weight: f64,
    speed: f64,
) -> PrintPath {
    let lift = frame.n * (0.5 * layer_height);
    let axis = -frame.n;
    let mut points = Vec::new();
    let mut print_length = 0.0;
    let mut travel_length = 0.0;
    for (q, layer) in sections.layers.iter().enumerate() {
        let forward = q % 2 == 0;
        let n = layer.nodes.len();
        for j in 0..n {
            let node = if forward {
                &layer.nodes[j]
            } else {
                &layer.nodes[n - 1 - j]
            };
            let p = PathPoint {
                layer: layer.id,
                index: j,
                tip: node.xyz + lift,
                axis,
                bead: node.xyz,
            };
            if let Some(prev) = points.last() {
                let prev: &PathPoint = prev;
                let d = (p.bead - prev.bead).norm();
                if j == 0 {
                    travel_length += d
                } else {
                    print_length += d
                }
            }
            points.push(p);
        }
    }
    let volume = print_length * layer_width * layer_height;
    PrintPath {
        points,
        print_length,
        travel_length,
        volume,
        mass: volume * specific_weight / GRAVITY,
        time: (print_length + travel_length) / speed,
    }
}

impl PrintPath {
    /// `layer,index,x,y,z,tx,ty,tz` rows (nozzle tip and unit tool axis), with a header.
    pub fn to_csv(&self) -> String {
        let mut s = String::with_capacity(self.points.len() * 96 + 32);
        s.push_str("layer,index,x,y,z,tx,ty,tz\n");
        for p in &self.points {
            s.push_str(&format!(
                "{},{},{:.9},{:.9},{:.9},{:.12},{:.12},{:.12}\n",
                p.layer,
                p.index,
                p.tip.x + 0.0,
                p.tip.y + 0.0,
                p.tip.z + 0.0,
                p.axis.x + 0.0,
                p.axis.y + 0.0,
                p.axis.z + 0.0
            ));
        }
        s
    }
}
