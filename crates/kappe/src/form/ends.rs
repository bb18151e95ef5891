//! The ends of a cap: what takes the thrust of the centre stack (method.md §5–6).
//!
//! The centre stack leans back on whatever the first centre layer (layer 0) rests on: with the
//! state's top layer t, column i hands over the horizontal force `(t + 1)·W_i·tan(am)·e_y`
//! (method.md §5: the bed-joint forces are horizontal because consecutive layers are horizontal
//! translates). Kappe offers two ends for that thrust:
//!
//! - [`EndKind::StartSection`] (the paper's T3, method.md §6): printed start layers follow the
//!   final-state thrust line down to the base plane. Only the weight of the start layers turns the
//!   thrust down, so the column feet of a long cap carry a growing, flat thrust and crush.
//! - [`EndKind::EndWall`]: layer 0 is printed against an end wall (gable wall, abutment) whose face
//!   lies in the plane of layer −1 (layer 0 translated by `−(lh / cos am)·e_y`), i.e. a wall face
//!   inclined by am like the layers, as the first course of a Nubian vault leans on its gable wall
//!   (a vertical wall gets a wedge-shaped inclined bearing face or a cast wedge). Each column's last
//!   trail edge is the horizontal bed joint from layer 0 to the wall face; the wall is its support.
//!   **Equilibrium:** every centre layer has layer factor d = 1 (its weight goes to its arch and
//!   the feet on the beams), so the column force below layer 0 is `(t + 1)·W_i·tan(am)·e_y`,
//!   horizontal, and the wall reaction of column i is exactly its negative. The wall carries no
//!   vertical load from the cap; the beams carry all of its weight. The wall must carry, per unit
//!   width of its bearing face, that horizontal line load; [`WallLoad`] reports it per column and
//!   in total, and [`stack_thrust`] gives the closed form the force pass is checked against.
//!
//! A third end every bay has: its **far end** (the last printed layer) is free. The stack leans
//! back toward the start, so the last layer hands nothing forward; a far end wall only closes the
//! room. The wedge between the last layer (leaning back by `Cr·tan(am)` at the crown) and a
//! vertical far wall is a non-structural closure ([`far_end_gap`]).
//!
//! With an end wall the bed joints of the stack still carry the stack thrust; the bottom one
//! (layer 0 on the wall) carries `N·W_i·tan(am)` over the area `lw·l_trib`, i.e. a stress of
//! `γ·lh·N·tan(am) ≈ γ·Cl·sin(am)`: a bay printed from one end is limited to
//! `Cl ≤ |σ_min| / (γ·sin am)` (2.05 m at the defaults). Longer bays are printed from both end walls
//! toward the middle (two mirrored halves, each an end-wall cap; see [`crate::commands::ceiling`]).

use serde::Serialize;

use crate::form::forces::Sections2D;
use crate::form::frame::{LayerFrame, V3};
use crate::form::section::Sections;
use crate::form::states::{Role, State};

pub use crate::input::design::EndKind;

/// The load an end wall must carry in one state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WallLoad {
    /// Force of the cap on the wall per column, N, world frame (the negative of the support
    /// reaction), in column order across the span.
    pub per_column: Vec<ColumnLoad>,
    /// Sum over the columns, N.
    pub total: [f64; 3],
    /// The largest bearing stress on the wall face: the largest column force over the bed-joint
    /// area `lw·l_trib`, Pa (negative: compression).
    pub max_bearing_stress: f64,
    /// Horizontal line load on the wall along its bearing line (total / developed length of
    /// layer 0), N/m.
    pub line_load: f64,
}

/// The load of one column on the end wall.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ColumnLoad {
    /// Where the column meets the wall: x across the span and height z, m.
    pub x: f64,
    /// Height of the bearing point, m.
    pub z: f64,
    /// Force on the wall, N.
    pub force: [f64; 3],
}

/// The load on the end wall from the force-pass reactions of `state` (`reactions[i]` of node i).
/// `None` when the state has no wall (a start-section cap).
pub fn wall_load(
    state: &State,
    reactions: &[V3],
    areas: Sections2D,
    layer0_length: f64,
) -> Option<WallLoad> {
    let net = &state.network;
    let mut per_column = Vec::new();
    let mut total = V3::zeros();
    let mut fmax: f64 = 0.0;
    for trail in &net.trails {
        let end = *trail.last()?;
        let node = net.nodes.get(end)?;
        if node.role != Role::ColumnEnd || node.xyz.z <= 0.0 {
            // A column end on the base plane: a start section, not a wall.
            return None;
        }
        let f = -reactions.get(end).copied()?;
        total += f;
        fmax = fmax.max(f.norm());
        per_column.push(ColumnLoad {
            x: node.xyz.x,
            z: node.xyz.z,
            force: [f.x, f.y, f.z],
        });
    }
    if per_column.is_empty() {
        return None;
    }
    Some(WallLoad {
        per_column,
        total: [total.x, total.y, total.z],
        max_bearing_stress: -fmax / areas.bed_joint,
        line_load: if layer0_length > 0.0 {
            total.norm() / layer0_length
        } else {
            0.0
        },
    })
}

/// Closed form of the stack thrust on the first centre layer's support in the state whose top
/// printed layer has print index `top`: `Σ_i (t + 1)·W_i·tan(am)·e_y` over the columns of layer 0,
/// with t the top layer's id (method.md §5). This is the force the stack exerts toward −y on
/// what layer 0 rests on, returned as that force (its y component is negative).
pub fn stack_thrust(sections: &Sections, frame: &LayerFrame, top: usize) -> V3 {
    let Some(layer0) = sections.print_index(0).and_then(|q| sections.layers.get(q)) else {
        return V3::zeros();
    };
    let t = sections.layers.get(top).map_or(-1, |l| l.id);
    if t < 0 {
        return V3::zeros();
    }
    let w: f64 = layer0
        .nodes
        .iter()
        .filter(|n| matches!(n.kind, crate::form::section::NodeKind::Column(_)))
        .map(|n| n.weight)
        .sum();
    -frame.lean() * ((t + 1) as f64 * w)
}

/// Horizontal gap at the crown between the last layer (leaning back) and a vertical far end wall
/// through its feet: `Cr·tan(am)`, m (a non-structural closure).
pub fn far_end_gap(rise: f64, tilt: f64) -> f64 {
    rise * tilt.tan()
}

/// The end-wall load of the final state of `cap` (`None` for a start-section cap), with the
/// stack thrust it must equal.
pub fn cap_wall_load(cap: &crate::form::cap::Cap) -> Option<CapWallLoad> {
    let layer0 = cap
        .sections
        .print_index(0)
        .and_then(|q| cap.sections.layers.get(q))?;
    let load = wall_load(
        &cap.final_state,
        &cap.final_forces.reactions,
        cap.areas(),
        layer0.length(),
    )?;
    let thrust = stack_thrust(&cap.sections, &cap.frame, cap.sections.layers.len() - 1);
    Some(CapWallLoad {
        stack_thrust_n: [thrust.x, thrust.y, thrust.z],
        max_column_force_n: load
            .per_column
            .iter()
            .map(|c| V3::from(c.force).norm())
            .fold(0.0, f64::max),
        load,
    })
}

/// The end-wall block of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CapWallLoad {
    /// The wall load of the final state (the largest: it grows with every layer).
    #[serde(flatten)]
    pub load: WallLoad,
    /// Closed form Σ_i N·W_i·tan(am) toward −y, N: equals `total` (equilibrium check).
    pub stack_thrust_n: [f64; 3],
    /// Largest force of one column on the wall, N.
    pub max_column_force_n: f64,
}
