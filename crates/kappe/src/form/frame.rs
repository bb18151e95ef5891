//! The layer frame of method.md §1, §4.
//!
//! World: x across the span, y along the cap (printing advances toward +y), z up, base plane z = 0.
//! Every layer lies in a plane tilted by am from the vertical with
//! normal `n = (0, cos am, sin am)` (from the printed part toward the new layer) and in-plane
//! up direction `u = (0, −sin am, cos am)` (the layer leans back over the printed part).

use nalgebra::Vector3;

/// A 3-vector of f64 (world coordinates, m or N).
pub type V3 = Vector3<f64>;

/// The tilted layer frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerFrame {
    /// Tilt from the vertical, rad.
    pub tilt: f64,
    /// Unit layer normal n.
    pub n: V3,
    /// Unit in-plane up direction u.
    pub u: V3,
}

impl LayerFrame {
    /// The frame for tilt `am` (radians).
    pub fn new(tilt: f64) -> Self {
        let (s, c) = tilt.sin_cos();
        LayerFrame {
            tilt,
            n: V3::new(0.0, c, s),
            u: V3::new(0.0, -s, c),
        }
    }

    /// The horizontal translation between consecutive centre layers, `(lh / cos am)·e_y`.
    pub fn layer_step(&self, layer_height: f64) -> V3 {
        V3::new(0.0, layer_height / self.tilt.cos(), 0.0)
    }

    /// Direction of the auxiliary (bed-joint) force per unit weight: `tan(am)·e_y`.
    pub fn lean(&self) -> V3 {
        V3::new(0.0, self.tilt.tan(), 0.0)
    }
}
