//! The plain-data input of the report.
//!
//! [`ReportInput`] is everything the report shows, in world coordinates and SI units (m, Pa, s,
//! rad), with no dependency on the pipeline crates: the CLI fills it from the design, the
//! analysis and the robot plan. It is serialised verbatim as the JSON scene island of
//! `report.html` (`<script type="application/json" id="kappe-data">`), which the hand-written
//! viewer (`assets/viewer.js`) reads; the field names below are therefore also the viewer's
//! data format.
//!
//! Conventions (see `shared/reference/method.md` §1, §3, §7):
//! - world frame: x across the span, y along the cap (printing advances toward +y), z up;
//! - normal stress σ is signed, **compression negative**;
//! - `layers` are listed **in print order** (start layers −K..−1, then 0..N−1); a print state
//!   shows the first [`PrintState::layers_printed`] of them.

use serde::{Deserialize, Serialize};

use crate::error::ReportError;
pub use crate::series::{Plot, Series};

/// A point or vector in world coordinates (m for points).
pub type Vec3 = [f64; 3];

/// Everything the report shows. See the module docs for units and conventions.
///
/// The fields after `plots` are optional (serde defaults; build with `..Default::default()`),
/// so callers that do not have a robot plan or an analysis still fill the page.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct ReportInput {
    /// Design name, shown as the page title.
    pub name: String,
    /// Design parameters, shown as a table in the given order.
    pub parameters: Vec<Parameter>,
    /// Print layers in print order.
    pub layers: Vec<Layer>,
    /// Bed-joint edges between consecutive layers (the trail edges of method.md §5).
    pub bed_joints: Vec<BedJoint>,
    /// The nozzle path.
    pub print_path: PrintPath,
    /// Print states in print order (after each printed layer, or a coarser step).
    pub states: Vec<PrintState>,
    /// Constraint results (worst over all states), shown as a table, failures highlighted.
    pub constraints: Vec<ConstraintRow>,
    /// The robot moving along its trajectory, drawn as capsules.
    pub robot: Option<RobotAnimation>,
    /// Extra plots shown after the standard ones (which are derived from the fields above).
    pub plots: Vec<Plot>,
    /// When each print-path point is printed, on the robot's clock: the page's one timeline.
    /// `None`: the viewer uses the path's arc length at 1 m per time unit.
    #[serde(default)]
    pub timeline: Option<Timeline>,
    /// The robot cell: stations (base poses), tool, mobile base, beams, floor. With a cell and
    /// [`RobotAnimation::station`] the viewer draws the UR10e from its meshes.
    #[serde(default)]
    pub cell: Option<Cell>,
    /// First buckling mode of the states that have one.
    #[serde(default)]
    pub modes: Vec<ModeShape>,
    /// Where each constraint is worst, for the markers in 3D.
    #[serde(default)]
    pub worst_places: Vec<WorstPlace>,
    /// More quantities to colour the beads by and to plot (layer age, stiffness, …); each one
    /// appears in the colour menu and gets a min/max-over-progress plot.
    #[serde(default)]
    pub quantities: Vec<Quantity>,
    /// The print schedule (layer start/end/wait), which check governs each analysed state and
    /// the layer ages at the governing state(s) (issue 11).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub schedule: Option<PrintSchedule>,
    /// The robot plan's slowdowns and clearances (capsules and meshes, at the waypoints and
    /// certified along the motion; issue 13).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot_summary: Option<crate::robot_summary::RobotSummary>,
}

/// The print on one clock: when the nozzle reaches each print-path point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Timeline {
    /// Time at which `print_path.points[i]` is printed, s; non-decreasing, same length.
    pub point_time: Vec<f64>,
    /// End of the timeline, s (≥ the last point time, e.g. the robot plan's end).
    pub total_time: f64,
}

/// One base pose of the mobile robot and the layers printed from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Station {
    /// Robot base pose (DH frame 0 = ROS `base`) in the world, row-major 4×4, m.
    pub world_from_base: [[f64; 4]; 4],
    /// Ids of the layers printed from this station.
    pub layers: Vec<i32>,
}

/// A box: centre, half extents and a rotation about z.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct BoxBody {
    /// Name shown on hover, e.g. `beam_left`.
    pub name: String,
    /// Centre, m.
    pub center: Vec3,
    /// Half extents along the box axes, m.
    pub half_extents: Vec3,
    /// Rotation about z, rad.
    #[serde(default)]
    pub yaw: f64,
}

/// A capsule (cylinder with round ends) from `a` to `b`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Capsule {
    /// One end, m.
    pub a: Vec3,
    /// The other end, m.
    pub b: Vec3,
    /// Radius, m.
    pub radius: f64,
}

/// The robot cell around the print.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Cell {
    /// Base stations in the order the robot uses them.
    pub stations: Vec<Station>,
    /// TCP (nozzle tip) in the flange frame (ROS `tool0`), row-major 4×4.
    pub flange_from_tcp: [[f64; 4]; 4],
    /// The tool body as capsules in the flange frame.
    pub tool: Vec<Capsule>,
    /// Mobile-base body boxes in the robot base frame (they move with the base).
    pub mobile_base: Vec<BoxBody>,
    /// Static obstacles in the world (the beams under the springing lines).
    pub obstacles: Vec<BoxBody>,
    /// Floor height in the world, m.
    pub floor_z: Option<f64>,
}

/// The first buckling mode of one state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct ModeShape {
    /// Position of the state in [`ReportInput::states`].
    pub state: usize,
    /// Its buckling load factor.
    pub blf: f64,
    /// Displacement of every bead node of the state's printed layers (the `nodes` of the first
    /// `layers_printed` layers, concatenated), any scale (the viewer normalises it).
    pub displacement: Vec<Vec3>,
}

/// Where a constraint reaches its worst value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct WorstPlace {
    /// Name of the constraint row.
    pub constraint: String,
    /// Position of the state in [`ReportInput::states`], if state-dependent.
    pub state: Option<usize>,
    /// Layer id, if the place is in one layer.
    pub layer: Option<i32>,
    /// The place, m.
    pub position: Vec3,
    /// The signed worst value in the row's unit, when the row shows a magnitude.
    pub signed_value: Option<f64>,
}

/// What a [`Quantity`] has one value per.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum QuantityPer {
    /// One value per bead segment (the `segment_stress` layout).
    #[default]
    Segment,
    /// One value per layer.
    Layer,
}

/// A quantity to colour the beads by.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Quantity {
    /// Stable key, e.g. `layer_age`.
    pub key: String,
    /// Menu and legend label, e.g. `layer age`.
    pub label: String,
    /// Unit shown, e.g. `min`.
    pub unit: String,
    /// Shown value = value × `to_unit` (e.g. 1/60 for s → min).
    pub to_unit: f64,
    /// Per segment or per layer.
    pub per: QuantityPer,
    /// Diverging colours about zero (signed quantities) instead of a sequential ramp.
    #[serde(default)]
    pub diverging: bool,
    /// Values per state (same order as [`ReportInput::states`]), each covering that state's
    /// printed layers in print order; or exactly one entry covering every layer, used for
    /// every state (a final-state quantity).
    pub states: Vec<Vec<f64>>,
    /// A short note under the legend on how to read it.
    #[serde(default)]
    pub note: Option<String>,
}

/// One row of the parameters table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// Symbol or key, e.g. `span`.
    pub key: String,
    /// Value as the user should read it (already formatted, e.g. `0.8` or `25`).
    pub value: String,
    /// Unit, e.g. `m`, `deg`, `N/m³`; empty when dimensionless.
    pub unit: String,
}

/// One print layer: a closed arch whose bead centre line runs through `nodes`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    /// Layer id: negative for start layers (−K..−1), 0..N−1 for centre layers.
    pub id: i32,
    /// Bead centre line, from one foot over the crown to the other (at least 2 nodes), m.
    pub nodes: Vec<Vec3>,
    /// Normal stress of each segment `nodes[i]..nodes[i+1]` in the final state, Pa
    /// (compression negative); `nodes.len() − 1` values.
    pub segment_stress: Vec<f64>,
    /// Unit normal of the layer plane, pointing from the printed part to the new layer
    /// (method.md §4: n = (0, cos am, sin am)); the bead height is measured along it.
    pub plane_normal: Vec3,
    /// Bead width (shell thickness, in the layer plane across the path), m.
    pub bead_width: f64,
    /// Bead height (layer height, along `plane_normal`), m.
    pub bead_height: f64,
    /// Overhang of this layer over the preceding one (method.md §3), m; `None` for the first.
    pub overhang: Option<f64>,
}

/// A bed-joint edge between two layers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BedJoint {
    /// Id of the upper layer: the joint exists from the state in which that layer is printed.
    pub layer: i32,
    /// End on the lower layer, m.
    pub a: Vec3,
    /// End on the upper layer, m.
    pub b: Vec3,
    /// Normal stress in the final state, Pa (compression negative).
    pub stress: f64,
}

/// The nozzle path, struct-of-arrays: `points[i]`, `tool_axis[i]` and `layer[i]` belong together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PrintPath {
    /// Nozzle tip positions in print order, m.
    pub points: Vec<Vec3>,
    /// Unit tool axis at each point (method.md §7: along −n, into the preceding layer).
    pub tool_axis: Vec<Vec3>,
    /// Id of the layer each point prints.
    pub layer: Vec<i32>,
}

/// One print state: the structure after `layers_printed` layers (in print order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PrintState {
    /// State index (as the pipeline numbers it; shown to the user).
    pub index: usize,
    /// Print progress Pp = printed / total, in [0, 1].
    pub progress: f64,
    /// How many layers, in print order, are printed in this state (≥ 1, ≤ `layers.len()`).
    pub layers_printed: usize,
    /// Lowest positive linear buckling load factor, if it was computed for this state.
    pub blf: Option<f64>,
    /// Most compressive normal stress σ_min over all elements, Pa (compression negative).
    pub sigma_min: f64,
    /// Largest normal stress σ_max over all elements, Pa (> 0 is tension).
    pub sigma_max: f64,
    /// Largest layer overhang among the printed layers, m.
    pub max_overhang: f64,
    /// Whether this state meets every structural constraint.
    pub ok: bool,
    /// Optional per-state stresses of the printed layers' segments, Pa: the segments of the
    /// first `layers_printed` layers concatenated in print order. When absent the viewer
    /// colours by the final-state [`Layer::segment_stress`].
    pub segment_stress: Option<Vec<f64>>,
}

/// Whether a constraint bounds the value from above (`value ≤ limit`) or below (`value ≥ limit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    /// `value ≤ limit`.
    AtMost,
    /// `value ≥ limit`.
    AtLeast,
}

impl Bound {
    /// The relation as a symbol for tables.
    #[must_use]
    pub fn symbol(self) -> &'static str {
        match self {
            Bound::AtMost => "≤",
            Bound::AtLeast => "≥",
        }
    }
}

/// One row of the constraint table: the worst value of a constraint over all states.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstraintRow {
    /// Constraint name, e.g. `sigma_min`, `blf`, `overhang`, `reach`.
    pub name: String,
    /// Direction of the bound.
    pub bound: Bound,
    /// The limit, in `unit`.
    pub limit: f64,
    /// The worst value found, in `unit`.
    pub worst: f64,
    /// Unit of `limit` and `worst` (e.g. `kPa`, `mm`, `""`).
    pub unit: String,
    /// Index of the state where the worst value occurs, if state-dependent.
    pub state: Option<usize>,
    /// Element (edge, node, layer, frame) where the worst value occurs, as text.
    pub element: Option<String>,
    /// Whether the constraint holds.
    pub pass: bool,
}

/// The robot moving along its trajectory, for the viewer and the joint-angle plot.
///
/// The CLI computes the link segments with forward kinematics; the viewer draws link `j` at
/// time step `i` as a cylinder of radius `link_radii[j]` from `poses[i][j][0]` to
/// `poses[i][j][1]`, with a sphere at each end (a capsule). With a [`Cell`] and `station` the
/// viewer draws the UR10e meshes from `joints` instead, and `poses` may be empty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct RobotAnimation {
    /// Time of each step, s, non-decreasing.
    pub times: Vec<f64>,
    /// Joint values q1..q6 at each step, rad.
    pub joints: Vec<[f64; 6]>,
    /// Radius of each link capsule, m.
    pub link_radii: Vec<f64>,
    /// Per time step, the world end points of each link segment, m: `link_radii.len()` per step
    /// (or empty when the viewer poses the meshes of [`ReportInput::cell`]).
    pub poses: Vec<Vec<[Vec3; 2]>>,
    /// Station (index into [`Cell::stations`]) of each step; empty when there is one station.
    #[serde(default)]
    pub station: Vec<usize>,
    /// A base that moves while the arm prints (issue 27): the base pose of each step in the
    /// world, `[x, y, yaw]` (m, m, rad; the height is the first station's); empty when the base
    /// stands at its stations.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub base: Vec<[f64; 3]>,
}

// The print schedule's data (its rendering is `crate::schedule`).

/// The print schedule and what governs each state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PrintSchedule {
    /// Where the times come from, in words (e.g. `robot plan`, `path length / print speed`).
    pub source: String,
    /// One row per layer, in print order.
    pub layers: Vec<ScheduleRow>,
    /// Per analysed state, the utilisation of each check.
    pub states: Vec<StateGoverning>,
    /// The age of every printed layer at the governing state(s).
    pub ages: Vec<StateAges>,
}

/// One layer of the schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScheduleRow {
    /// Layer id.
    pub layer: i32,
    /// Start of printing, s.
    pub start: f64,
    /// End of printing, s.
    pub end: f64,
    /// Chosen wait after the layer, s.
    pub wait: f64,
    /// Other pause after it (station change, program change), s.
    pub pause: f64,
}

/// The checks of one state: each check's utilisation (demand / capacity; > 1 fails).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateGoverning {
    /// State index (as in [`crate::PrintState::index`]).
    pub state: usize,
    /// `(check, utilisation)` for every check made in this state: `buckling`, `strength`,
    /// `sliding`, `stress`, `overhang`.
    pub checks: Vec<(String, f64)>,
}

impl StateGoverning {
    /// The check with the largest utilisation.
    #[must_use]
    pub fn governing(&self) -> Option<(&str, f64)> {
        self.checks
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(c, u)| (c.as_str(), *u))
    }
}

/// The ages of the printed layers at one state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateAges {
    /// State index.
    pub state: usize,
    /// Why this state is shown, e.g. `lowest BLF`.
    pub why: String,
    /// Per printed layer in print order: (layer id, age s).
    pub ages: Vec<(i32, f64)>,
}

fn finite(field: impl FnOnce() -> String, value: f64) -> Result<(), ReportError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ReportError::NotFinite {
            field: field(),
            value,
        })
    }
}

fn finite3(field: impl Fn() -> String, v: &Vec3) -> Result<(), ReportError> {
    for (k, c) in v.iter().enumerate() {
        finite(|| format!("{}[{k}]", field()), *c)?;
    }
    Ok(())
}

fn mismatch(field: String, len: usize, expected: usize) -> ReportError {
    ReportError::LengthMismatch {
        field,
        len,
        expected,
    }
}

impl ReportInput {
    /// Checks everything the viewer and the plots rely on: every number finite (JSON has no
    /// NaN), array lengths consistent, states referring to existing layers.
    ///
    /// # Errors
    /// The first violation found, naming the field, its value and what is allowed.
    pub fn validate(&self) -> Result<(), ReportError> {
        if self.layers.is_empty() {
            return Err(ReportError::Empty {
                field: "layers".into(),
            });
        }
        if self.states.is_empty() {
            return Err(ReportError::Empty {
                field: "states".into(),
            });
        }
        for (li, layer) in self.layers.iter().enumerate() {
            if layer.nodes.len() < 2 {
                return Err(ReportError::TooFewNodes {
                    layer: layer.id,
                    len: layer.nodes.len(),
                });
            }
            if layer.segment_stress.len() + 1 != layer.nodes.len() {
                return Err(mismatch(
                    format!("layers[{li}].segment_stress"),
                    layer.segment_stress.len(),
                    layer.nodes.len() - 1,
                ));
            }
            for (ni, p) in layer.nodes.iter().enumerate() {
                finite3(|| format!("layers[{li}].nodes[{ni}]"), p)?;
            }
            for (si, s) in layer.segment_stress.iter().enumerate() {
                finite(|| format!("layers[{li}].segment_stress[{si}]"), *s)?;
            }
            finite3(|| format!("layers[{li}].plane_normal"), &layer.plane_normal)?;
            for (name, v) in [
                ("bead_width", layer.bead_width),
                ("bead_height", layer.bead_height),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(ReportError::OutOfRange {
                        field: format!("layers[{li}].{name}"),
                        value: v,
                        allowed: "a finite length > 0 m",
                    });
                }
            }
            if let Some(o) = layer.overhang {
                finite(|| format!("layers[{li}].overhang"), o)?;
            }
        }
        let has_layer = |id: i32| self.layers.iter().any(|l| l.id == id);
        for (bi, joint) in self.bed_joints.iter().enumerate() {
            if !has_layer(joint.layer) {
                return Err(ReportError::UnknownLayer {
                    field: format!("bed_joints[{bi}].layer"),
                    id: joint.layer,
                });
            }
            finite3(|| format!("bed_joints[{bi}].a"), &joint.a)?;
            finite3(|| format!("bed_joints[{bi}].b"), &joint.b)?;
            finite(|| format!("bed_joints[{bi}].stress"), joint.stress)?;
        }
        self.validate_path(&has_layer)?;
        self.validate_states()?;
        if let Some(schedule) = &self.schedule {
            schedule.validate()?;
        }
        for (ci, c) in self.constraints.iter().enumerate() {
            finite(|| format!("constraints[{ci}].limit"), c.limit)?;
            finite(|| format!("constraints[{ci}].worst"), c.worst)?;
        }
        if let Some(robot) = &self.robot {
            robot.validate(self.cell.as_ref())?;
        }
        if let Some(r) = &self.robot_summary {
            r.validate()?;
        }
        self.validate_extras()?;
        for (pi, plot) in self.plots.iter().enumerate() {
            for (si, s) in plot.series.iter().enumerate() {
                for (k, xy) in s.points.iter().enumerate() {
                    for (c, v) in xy.iter().enumerate() {
                        finite(|| format!("plots[{pi}].series[{si}].points[{k}][{c}]"), *v)?;
                    }
                }
            }
        }
        Ok(())
    }

    fn validate_path(&self, has_layer: &dyn Fn(i32) -> bool) -> Result<(), ReportError> {
        let path = &self.print_path;
        let n = path.points.len();
        if path.tool_axis.len() != n {
            return Err(mismatch(
                "print_path.tool_axis".into(),
                path.tool_axis.len(),
                n,
            ));
        }
        if path.layer.len() != n {
            return Err(mismatch("print_path.layer".into(), path.layer.len(), n));
        }
        for i in 0..n {
            if let (Some(p), Some(a), Some(&l)) =
                (path.points.get(i), path.tool_axis.get(i), path.layer.get(i))
            {
                finite3(|| format!("print_path.points[{i}]"), p)?;
                finite3(|| format!("print_path.tool_axis[{i}]"), a)?;
                if !has_layer(l) {
                    return Err(ReportError::UnknownLayer {
                        field: format!("print_path.layer[{i}]"),
                        id: l,
                    });
                }
            }
        }
        Ok(())
    }

    fn validate_states(&self) -> Result<(), ReportError> {
        for (si, s) in self.states.iter().enumerate() {
            if s.layers_printed == 0 || s.layers_printed > self.layers.len() {
                return Err(ReportError::OutOfRange {
                    field: format!("states[{si}].layers_printed"),
                    value: s.layers_printed as f64,
                    allowed: "1..=layers.len()",
                });
            }
            if !(0.0..=1.0).contains(&s.progress) {
                return Err(ReportError::OutOfRange {
                    field: format!("states[{si}].progress"),
                    value: s.progress,
                    allowed: "a fraction in [0, 1]",
                });
            }
            if let Some(b) = s.blf {
                finite(|| format!("states[{si}].blf"), b)?;
            }
            finite(|| format!("states[{si}].sigma_min"), s.sigma_min)?;
            finite(|| format!("states[{si}].sigma_max"), s.sigma_max)?;
            finite(|| format!("states[{si}].max_overhang"), s.max_overhang)?;
            if let Some(stress) = &s.segment_stress {
                let expected: usize = self
                    .layers
                    .iter()
                    .take(s.layers_printed)
                    .map(|l| l.segment_stress.len())
                    .sum();
                if stress.len() != expected {
                    return Err(mismatch(
                        format!("states[{si}].segment_stress"),
                        stress.len(),
                        expected,
                    ));
                }
                for (k, v) in stress.iter().enumerate() {
                    finite(|| format!("states[{si}].segment_stress[{k}]"), *v)?;
                }
            }
        }
        Ok(())
    }
}

impl ReportInput {
    /// Node count of the first `printed` layers.
    pub(crate) fn printed_nodes(&self, printed: usize) -> usize {
        self.layers
            .iter()
            .take(printed)
            .map(|l| l.nodes.len())
            .sum()
    }

    /// Segment count of the first `printed` layers.
    pub(crate) fn printed_segments(&self, printed: usize) -> usize {
        self.layers
            .iter()
            .take(printed)
            .map(|l| l.segment_stress.len())
            .sum()
    }

    fn validate_extras(&self) -> Result<(), ReportError> {
        if let Some(t) = &self.timeline {
            let n = self.print_path.points.len();
            if t.point_time.len() != n {
                return Err(mismatch(
                    "timeline.point_time".into(),
                    t.point_time.len(),
                    n,
                ));
            }
            let mut last = f64::NEG_INFINITY;
            for (i, &v) in t.point_time.iter().enumerate() {
                finite(|| format!("timeline.point_time[{i}]"), v)?;
                if v < last {
                    return Err(ReportError::OutOfRange {
                        field: format!("timeline.point_time[{i}]"),
                        value: v,
                        allowed: "times non-decreasing",
                    });
                }
                last = v;
            }
            if !t.total_time.is_finite() || t.total_time < last.max(0.0) {
                return Err(ReportError::OutOfRange {
                    field: "timeline.total_time".into(),
                    value: t.total_time,
                    allowed: "finite and at least the last point time",
                });
            }
        }
        if let Some(cell) = &self.cell {
            let mats = cell
                .stations
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    (
                        format!("cell.stations[{i}].world_from_base"),
                        s.world_from_base,
                    )
                })
                .chain(std::iter::once((
                    "cell.flange_from_tcp".to_string(),
                    cell.flange_from_tcp,
                )));
            for (name, m) in mats {
                for (r, row) in m.iter().enumerate() {
                    for (c, v) in row.iter().enumerate() {
                        finite(|| format!("{name}[{r}][{c}]"), *v)?;
                    }
                }
            }
            for (i, c) in cell.tool.iter().enumerate() {
                finite3(|| format!("cell.tool[{i}].a"), &c.a)?;
                finite3(|| format!("cell.tool[{i}].b"), &c.b)?;
                if !(c.radius.is_finite() && c.radius > 0.0) {
                    return Err(ReportError::OutOfRange {
                        field: format!("cell.tool[{i}].radius"),
                        value: c.radius,
                        allowed: "a finite radius > 0 m",
                    });
                }
            }
            let boxes = cell
                .mobile_base
                .iter()
                .enumerate()
                .map(|(i, b)| (format!("cell.mobile_base[{i}]"), b))
                .chain(
                    cell.obstacles
                        .iter()
                        .enumerate()
                        .map(|(i, b)| (format!("cell.obstacles[{i}]"), b)),
                );
            for (name, b) in boxes {
                finite3(|| format!("{name}.center"), &b.center)?;
                finite(|| format!("{name}.yaw"), b.yaw)?;
                for (k, h) in b.half_extents.iter().enumerate() {
                    if !(h.is_finite() && *h >= 0.0) {
                        return Err(ReportError::OutOfRange {
                            field: format!("{name}.half_extents[{k}]"),
                            value: *h,
                            allowed: "a finite length ≥ 0 m",
                        });
                    }
                }
            }
            if let Some(z) = cell.floor_z {
                finite(|| "cell.floor_z".into(), z)?;
            }
        }
        let state_ref = |field: String, s: usize| {
            if s < self.states.len() {
                Ok(())
            } else {
                Err(ReportError::OutOfRange {
                    field,
                    value: s as f64,
                    allowed: "an index into states",
                })
            }
        };
        for (mi, m) in self.modes.iter().enumerate() {
            state_ref(format!("modes[{mi}].state"), m.state)?;
            finite(|| format!("modes[{mi}].blf"), m.blf)?;
            let printed = self.states.get(m.state).map_or(0, |s| s.layers_printed);
            let expected = self.printed_nodes(printed);
            if m.displacement.len() != expected {
                return Err(mismatch(
                    format!("modes[{mi}].displacement"),
                    m.displacement.len(),
                    expected,
                ));
            }
            for (k, d) in m.displacement.iter().enumerate() {
                finite3(|| format!("modes[{mi}].displacement[{k}]"), d)?;
            }
        }
        for (wi, w) in self.worst_places.iter().enumerate() {
            if let Some(s) = w.state {
                state_ref(format!("worst_places[{wi}].state"), s)?;
            }
            finite3(|| format!("worst_places[{wi}].position"), &w.position)?;
            if let Some(v) = w.signed_value {
                finite(|| format!("worst_places[{wi}].signed_value"), v)?;
            }
        }
        for (qi, q) in self.quantities.iter().enumerate() {
            if !(q.to_unit.is_finite() && q.to_unit != 0.0) {
                return Err(ReportError::OutOfRange {
                    field: format!("quantities[{qi}].to_unit"),
                    value: q.to_unit,
                    allowed: "a finite, non-zero factor",
                });
            }
            let one = q.states.len() == 1;
            if !one && q.states.len() != self.states.len() {
                return Err(mismatch(
                    format!("quantities[{qi}].states"),
                    q.states.len(),
                    self.states.len(),
                ));
            }
            for (si, values) in q.states.iter().enumerate() {
                let printed = if one {
                    self.layers.len()
                } else {
                    self.states.get(si).map_or(0, |s| s.layers_printed)
                };
                let expected = match q.per {
                    QuantityPer::Layer => printed,
                    QuantityPer::Segment => self.printed_segments(printed),
                };
                if values.len() != expected {
                    return Err(mismatch(
                        format!("quantities[{qi}].states[{si}]"),
                        values.len(),
                        expected,
                    ));
                }
                for (k, v) in values.iter().enumerate() {
                    finite(|| format!("quantities[{qi}].states[{si}][{k}]"), *v)?;
                }
            }
        }
        Ok(())
    }
}

impl RobotAnimation {
    fn validate(&self, cell: Option<&Cell>) -> Result<(), ReportError> {
        let n = self.times.len();
        if self.joints.len() != n {
            return Err(mismatch("robot.joints".into(), self.joints.len(), n));
        }
        let meshes = cell.is_some_and(|c| !c.stations.is_empty());
        if self.poses.len() != n && !(meshes && self.poses.is_empty()) {
            return Err(mismatch("robot.poses".into(), self.poses.len(), n));
        }
        if !self.station.is_empty() {
            if self.station.len() != n {
                return Err(mismatch("robot.station".into(), self.station.len(), n));
            }
            let stations = cell.map_or(0, |c| c.stations.len());
            if let Some((i, &s)) = self
                .station
                .iter()
                .enumerate()
                .find(|(_, s)| **s >= stations)
            {
                return Err(ReportError::OutOfRange {
                    field: format!("robot.station[{i}]"),
                    value: s as f64,
                    allowed: "an index into cell.stations",
                });
            }
        }
        if !self.base.is_empty() {
            if self.base.len() != n {
                return Err(mismatch("robot.base".into(), self.base.len(), n));
            }
            for (i, b) in self.base.iter().enumerate() {
                for (j, v) in b.iter().enumerate() {
                    finite(|| format!("robot.base[{i}][{j}]"), *v)?;
                }
            }
        }
        let mut last = f64::NEG_INFINITY;
        for (i, &t) in self.times.iter().enumerate() {
            finite(|| format!("robot.times[{i}]"), t)?;
            if t < last {
                return Err(ReportError::OutOfRange {
                    field: format!("robot.times[{i}]"),
                    value: t,
                    allowed: "times non-decreasing",
                });
            }
            last = t;
        }
        for (i, q) in self.joints.iter().enumerate() {
            for (j, v) in q.iter().enumerate() {
                finite(|| format!("robot.joints[{i}][{j}]"), *v)?;
            }
        }
        for (j, &r) in self.link_radii.iter().enumerate() {
            if !(r.is_finite() && r > 0.0) {
                return Err(ReportError::OutOfRange {
                    field: format!("robot.link_radii[{j}]"),
                    value: r,
                    allowed: "a finite radius > 0 m",
                });
            }
        }
        for (i, pose) in self.poses.iter().enumerate() {
            if pose.len() != self.link_radii.len() {
                return Err(mismatch(
                    format!("robot.poses[{i}]"),
                    pose.len(),
                    self.link_radii.len(),
                ));
            }
            for (j, [a, b]) in pose.iter().enumerate() {
                finite3(|| format!("robot.poses[{i}][{j}][0]"), a)?;
                finite3(|| format!("robot.poses[{i}][{j}][1]"), b)?;
            }
        }
        Ok(())
    }
}
