//! Plan inputs: print targets, robot setup (base, tool, mobile base, obstacles) and options, all
//! serde-deserialisable with documented defaults for a UR10e on a mobile base beside a 0.8 m
//! span cap (world: x across the span, y along the cap, z up, base plane z = 0; method.md §1).

use serde::{Deserialize, Serialize};

use crate::collision::{BodyBox, Obstacle};
use crate::frames::{Iso, Mat4};

/// One print target: the nozzle-tip position and the unit tool axis (pointing out of the nozzle,
/// along −n into the preceding layer; method.md §7), world frame, metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathPoint {
    /// Index of the point within its layer (the `index` column of `path.csv`).
    pub index: usize,
    pub position: [f64; 3],
    pub axis: [f64; 3],
}

/// The targets of one layer in print order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrintLayer {
    /// Layer id (the `layer` column of `path.csv`; start layers may be negative).
    pub layer: i64,
    pub points: Vec<PathPoint>,
}

/// One tool capsule in the flange frame (m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolCapsule {
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub radius: f64,
}

/// The extruder: TCP pose in the flange frame, its collision capsules and a tip zone that may
/// touch the work.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Tool {
    /// `flange_from_tcp`, row-major 4×4; the TCP z axis is the tool axis.
    pub flange_from_tcp: Mat4,
    /// Collision capsules of the tool body (flange frame).
    pub capsules: Vec<ToolCapsule>,
    /// Length (m) behind the tip, along the tool axis, that is not checked against the
    /// environment: the thin nozzle end must reach the bead, the beam top and the last layer.
    pub tip_exclusion: f64,
}

impl Default for Tool {
    /// The assumed nozzle of robot.md §2.1: a capsule (0,0,0.02)–(0,0,0.23), r = 0.04, coaxial
    /// with the flange, TCP at its end (`flange_from_tcp = Tz(0.23)`); the last 0.12 m are the
    /// tip zone (with the axis 25° below horizontal a 0.04 m body needs ≈ (0.04 + 0.01)/sin 25°
    /// ≈ 0.12 m to clear a beam top at tip height by the 10 mm margin).
    fn default() -> Self {
        Tool {
            flange_from_tcp: Iso::translation(0.0, 0.0, 0.23).to_mat4(),
            capsules: vec![ToolCapsule {
                a: [0.0, 0.0, 0.02],
                b: [0.0, 0.0, 0.23],
                radius: 0.04,
            }],
            tip_exclusion: 0.12,
        }
    }
}

/// Where the robot base stands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case", deny_unknown_fields)]
pub enum BasePlacement {
    /// One fixed `world_from_base` (4×4 row-major) for the whole print.
    Fixed { world_from_base: Mat4 },
    /// Search a grid of base poses; split into stations when no single pose plans every layer.
    Search(BaseSearch),
}

/// A grid of candidate base poses (x, y, yaw) at a fixed mount height.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BaseSearch {
    /// Range of the base x (m), world.
    pub x: [f64; 2],
    /// Range of the base y (m), world; `None` = from 0.6 m beyond the print's smallest y to
    /// 0.8 m beyond its largest y (in front of the printing front, which advances toward +y).
    pub y: Option<[f64; 2]>,
    /// Grid step (m).
    pub step: f64,
    /// Candidate yaw angles (deg) of the base x axis from world x.
    pub yaw_deg: Vec<f64>,
    /// Height of the robot base (DH frame 0) in the world (m).
    pub z: f64,
    /// Every n-th point of each layer is used to score a candidate.
    pub score_stride: usize,
}

impl Default for BaseSearch {
    /// In front of the printing front on the cap's centre line: x = 0, y as in
    /// [`BaseSearch::y`], 0.1 m steps, yaw 270° (base x axis pointing to −y, the mobile base body
    /// extending away from the cap), base at z = 0 (top plate of the mobile base, 0.70 m
    /// above the floor). With a 1.3 m reach, the tool pointing along −n and a 0.8 m span, a base
    /// beside the span cannot reach the far springing, hence the centre line.
    fn default() -> Self {
        BaseSearch {
            x: [0.0, 0.0],
            y: None,
            step: 0.1,
            yaw_deg: vec![270.0],
            z: 0.0,
            score_stride: 5,
        }
    }
}

impl Default for BasePlacement {
    fn default() -> Self {
        BasePlacement::Search(BaseSearch::default())
    }
}

/// The robot cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotSetup {
    pub base: BasePlacement,
    pub tool: Tool,
    /// Boxes of the mobile base body in the robot base frame (they move with the base).
    pub mobile_base: Vec<BodyBox>,
    /// Floor height (m, world), a half-space obstacle; `None` for no floor.
    pub floor_z: Option<f64>,
    /// Static obstacles: beams, support structure, scaffold (world frame).
    pub obstacles: Vec<Obstacle>,
}

impl Default for RobotSetup {
    /// RB-Vogui XL body (robot.md §5): a 1.27 × 0.82 × 0.67 m box whose top is 0.036 m below the
    /// arm base, extending behind it (−x of the base frame); floor 0.70 m below the arm base
    /// (`floor_z = −0.70` with the default base height 0). No static obstacles: the caller adds
    /// the beams (see [`beams`]).
    fn default() -> Self {
        RobotSetup {
            base: BasePlacement::default(),
            tool: Tool::default(),
            mobile_base: vec![BodyBox {
                name: "mobile_base".into(),
                center: [-0.45, 0.0, -0.036 - 0.335],
                half_extents: [0.635, 0.41, 0.335],
            }],
            floor_z: Some(-0.70),
            obstacles: Vec::new(),
        }
    }
}

/// Two support beams along y under the springing lines: boxes of `width` × `height` with their
/// top at z = 0 and inner faces at x = ±span/2, from `y0` to `y1`.
pub fn beams(span: f64, width: f64, height: f64, y0: f64, y1: f64) -> Vec<Obstacle> {
    [-1.0, 1.0]
        .iter()
        .map(|s: &f64| Obstacle::Box {
            name: if *s < 0.0 {
                "beam_left".into()
            } else {
                "beam_right".into()
            },
            center: [
                s * (span / 2.0 + width / 2.0),
                0.5 * (y0 + y1),
                -height / 2.0,
            ],
            half_extents: [width / 2.0, 0.5 * (y1 - y0).abs(), height / 2.0],
            yaw: 0.0,
        })
        .collect()
}

/// Which ladder search to run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlannerKind {
    /// Exact shortest path over the ladder graph (minimum Σ Δq²).
    #[default]
    Optimal,
    /// The paper's random choice of compatible segments, best of `random_trials`, seeded.
    Random,
}

/// Planner settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlanOptions {
    pub planner: PlannerKind,
    /// Seed of the random planner.
    pub seed: u64,
    /// Trials of the random planner.
    pub random_trials: usize,
    /// Compatibility ε (rad²): consecutive configurations need Σ Δq² ≤ ε (paper; fixture 0.05).
    pub epsilon: f64,
    /// Rotations sampled about the tool axis per frame (2π/n steps). For a coaxial round nozzle
    /// the rotation is exactly q6 (robot.md §1.4), so one sample is used and q6 is held at `q6`.
    pub rotation_steps: usize,
    /// Value of q6 (rad) for a coaxial tool (winds the hose least when constant).
    pub q6: f64,
    /// Nozzle speed while printing (m/s; design default 0.05).
    pub print_speed: f64,
    /// Fraction s of the joint speed limits usable while printing: |Δq_j| ≤ s·v_j,max·Δt.
    pub speed_fraction: f64,
    /// Clearance margin to the environment (m).
    pub clearance: f64,
    /// Margin between checked self-collision pairs (m).
    pub self_clearance: f64,
    /// Wrist singularity margin: |sin q5| ≥ this.
    pub min_abs_sin_q5: f64,
    /// Elbow singularity margin: |sin q3| ≥ this.
    pub min_abs_sin_q3: f64,
    /// Shoulder singularity margin (m): distance of the wrist centre from the d4 cylinder.
    pub min_shoulder_margin: f64,
    /// Check the robot against the layers printed before the current one.
    pub printed_layers_as_obstacles: bool,
    /// Bead radius (m, half the layer width) of printed layers.
    pub bead_radius: f64,
    /// Offset (m) from the nozzle tip to the bead centre line along the tool axis (lh/2).
    pub bead_offset: f64,
    /// Fraction of the joint speed limits used by `movej` between layers.
    pub transition_speed_fraction: f64,
    /// Cost added when a layer change switches IK branch (shoulder/elbow/wrist).
    pub reconfiguration_penalty: f64,
    /// Time (s) allowed to move the mobile base between stations.
    pub station_change_time: f64,
    pub program: ProgramOptions,
}

impl Default for PlanOptions {
    /// ε = 0.05 rad² (paper/fixture), 36 rotations (10°) for non-coaxial tools, v = 0.05 m/s,
    /// s = 0.8, 10 mm clearance, singularity margins 0.05 / 0.05 / 10 mm (robot.md §1.3),
    /// printed layers as 10 mm capsules 4 mm ahead of the tip (lw/2, lh/2 of the default design).
    fn default() -> Self {
        PlanOptions {
            planner: PlannerKind::Optimal,
            seed: 1,
            random_trials: 10,
            epsilon: 0.05,
            rotation_steps: 36,
            q6: 0.0,
            print_speed: 0.05,
            speed_fraction: 0.8,
            clearance: 0.01,
            self_clearance: 0.0,
            min_abs_sin_q5: 0.05,
            min_abs_sin_q3: 0.05,
            min_shoulder_margin: 0.01,
            printed_layers_as_obstacles: true,
            bead_radius: 0.01,
            bead_offset: 0.004,
            transition_speed_fraction: 0.25,
            reconfiguration_penalty: 10.0,
            station_change_time: 60.0,
            program: ProgramOptions::default(),
        }
    }
}

/// URScript export settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProgramOptions {
    /// Standard digital output switching the pump.
    pub pump_output: u8,
    /// Pump lead time (s) before the first print move of a layer.
    pub pump_lead: f64,
    /// Blend radius (m) of `movep` along a layer (keep < half the point spacing).
    pub blend_radius: f64,
    /// Tool acceleration (m/s²) of `movep`/`movel`.
    pub tool_acceleration: f64,
    /// `movej` joint speed (rad/s) and acceleration (rad/s²).
    pub joint_speed: f64,
    pub joint_acceleration: f64,
    /// Use `movel` instead of `movep` along layers.
    pub use_movel: bool,
    /// Most moves per subprogram (long programs fail on the controller above ~1–2.5 k targets).
    pub max_moves_per_program: usize,
}

impl Default for ProgramOptions {
    fn default() -> Self {
        ProgramOptions {
            pump_output: 0,
            pump_lead: 0.5,
            blend_radius: 0.002,
            tool_acceleration: 1.2,
            joint_speed: 0.5,
            joint_acceleration: 1.0,
            use_movel: false,
            max_moves_per_program: 1000,
        }
    }
}
