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
    /// Base-pose errors the chosen poses must tolerate (issue 28): a layer counts as covered
    /// by a candidate only when it is also reachable with the base at every corner of this
    /// error box ([`crate::tolerance`]), so a station does not end at the edge of the reach,
    /// where a base a few millimetres off can no longer print its last layers. `None`: the
    /// nominal pose only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub margin: Option<BaseTolerance>,
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
            // 0.1 m. A 25 mm grid finds the pose (y = 1.029 m) from which the default cap prints
            // in one station instead of three, at the same cost, but the margin search counts a
            // layer covered when *some* configuration reaches it from every corner of the error
            // box, and the finer grid then picks poses whose *planned* branch a corner loses
            // (the designer's rise-slider cap failed its tolerance check that way). Until the
            // search verifies each station under the box, the coarser grid stays the default.
            step: 0.1,
            yaw_deg: vec![270.0],
            z: 0.0,
            score_stride: 5,
            margin: None,
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
    /// Unused since the layer change is a printed move (kept so older files parse).
    pub transition_speed_fraction: f64,
    /// Unused since the layer change is a printed move (kept so older files parse).
    pub reconfiguration_penalty: f64,
    /// Time (s) allowed to move the mobile base between stations (and bring the arm to the
    /// safe pose above the station's first target).
    pub station_change_time: f64,
    /// Joint speed and acceleration limits used by the planner and the timing.
    pub limits: JointLimitOptions,
    /// The pump: flow output, calibration, priming, pauses.
    pub pump: PumpOptions,
    /// Per-layer waits (minimum layer time) when no schedule supplies them.
    pub waits: WaitOptions,
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
            limits: JointLimitOptions::default(),
            pump: PumpOptions::default(),
            waits: WaitOptions::default(),
            program: ProgramOptions::default(),
        }
    }
}

/// Joint position, speed and acceleration limits (UR10e defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct JointLimitOptions {
    /// Maximum joint speeds (°/s): UR10e 120 for base and shoulder, 180 for elbow and wrists.
    pub max_speed_deg_s: [f64; 6],
    /// Maximum joint accelerations (rad/s²). UR publishes none (the arm is torque-limited);
    /// 5 rad/s² is the conservative value of UR's own MoveIt configuration
    /// (`ur_moveit_config/config/joint_limits.yaml`).
    pub max_acceleration: [f64; 6],
    /// Joint position limits `[min, max]` (°), used by the planner, the check and the program
    /// lint. UR10e: ±360° on every joint (the controller's range, UR10e manual), the elbow ±180°
    /// (the arm's own structure blocks it beyond about ±180°; UR's ROS description halves it
    /// for that reason; robot.md §1.1). Allowed: finite, min < max, within ±360°.
    pub position_deg: [[f64; 2]; 6],
}

/// UR10e joint position limits (°), see [`JointLimitOptions::position_deg`].
pub const UR10E_POSITION_DEG: [[f64; 2]; 6] = [
    [-360.0, 360.0],
    [-360.0, 360.0],
    [-180.0, 180.0],
    [-360.0, 360.0],
    [-360.0, 360.0],
    [-360.0, 360.0],
];

impl Default for JointLimitOptions {
    fn default() -> Self {
        JointLimitOptions {
            max_speed_deg_s: [120.0, 120.0, 180.0, 180.0, 180.0, 180.0],
            max_acceleration: [5.0; 6],
            position_deg: UR10E_POSITION_DEG,
        }
    }
}

impl JointLimitOptions {
    /// Position limits in rad.
    pub fn position(&self) -> [[f64; 2]; 6] {
        self.position_deg.map(|r| r.map(f64::to_radians))
    }

    /// Check the position limits: finite, min < max, within ±360° (the controller's range);
    /// [`crate::error::RobotError::JointPositionLimit`] names the first bad joint.
    pub fn validate_positions(&self) -> Result<(), crate::error::RobotError> {
        for (j, &[min, max]) in self.position_deg.iter().enumerate() {
            let ok =
                min.is_finite() && max.is_finite() && min < max && min >= -360.0 && max <= 360.0;
            if !ok {
                return Err(crate::error::RobotError::JointPositionLimit {
                    joint: j + 1,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }

    /// Speed limits in rad/s.
    pub fn max_speed(&self) -> [f64; 6] {
        self.max_speed_deg_s.map(f64::to_radians)
    }
}

/// Voltage or current range of a standard analog output (`set_analog_outputdomain`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AnalogDomain {
    /// 4–20 mA (domain 0).
    Current,
    /// 0–10 V (domain 1).
    #[default]
    Voltage,
}

/// A digital output of the UR e-Series controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "number", rename_all = "snake_case")]
pub enum DigitalOutput {
    /// `set_standard_digital_out(n, b)`, n = 0..=7.
    Standard(u8),
    /// `set_configurable_digital_out(n, b)`, n = 0..=7.
    Configurable(u8),
    /// `set_tool_digital_out(n, b)`, n = 0..=1.
    Tool(u8),
}

impl DigitalOutput {
    /// The URScript call that sets it.
    pub fn call(&self, on: bool) -> String {
        let b = if on { "True" } else { "False" };
        match self {
            DigitalOutput::Standard(n) => format!("set_standard_digital_out({n}, {b})"),
            DigitalOutput::Configurable(n) => format!("set_configurable_digital_out({n}, {b})"),
            DigitalOutput::Tool(n) => format!("set_tool_digital_out({n}, {b})"),
        }
    }

    /// Highest output number the controller has for this kind.
    pub fn max_number(&self) -> u8 {
        match self {
            DigitalOutput::Standard(_) | DigitalOutput::Configurable(_) => 7,
            DigitalOutput::Tool(_) => 1,
        }
    }

    fn number(&self) -> u8 {
        match self {
            DigitalOutput::Standard(n)
            | DigitalOutput::Configurable(n)
            | DigitalOutput::Tool(n) => *n,
        }
    }
}

/// What a pause (layer wait, program change) does with the pump.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PauseMode {
    /// The pump stays enabled at the hold output (`hold_output`), so it does not have to be
    /// primed again.
    #[default]
    KeepPrimed,
    /// The pump is switched off and primed again (`prime_dwell`) before the print resumes.
    Stop,
}

/// The earth pump: an analog flow set-point proportional to the volumetric flow lw·lh·v, an
/// enable output, priming and pauses.
///
/// Output ratio (0..1 of the analog domain) = `flow_offset` + `flow_factor` · Q, with Q the
/// volumetric flow in L/min (Q = lw·lh·v·60 000, lw = 2·bead_radius, lh = 2·bead_offset).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PumpOptions {
    /// Standard analog output carrying the flow set-point (0 or 1).
    pub flow_output: u8,
    /// Its domain.
    pub flow_domain: AnalogDomain,
    /// Calibration factor: output ratio per L/min (> 0).
    pub flow_factor: f64,
    /// Calibration offset: output ratio at zero flow (the pump's dead band).
    pub flow_offset: f64,
    /// The pump's run/enable output; `None` if the flow set-point alone drives it.
    pub enable_output: Option<DigitalOutput>,
    /// Dwell (s) at a station's first target with the pump running before the bead starts.
    pub prime_dwell: f64,
    /// What a pause does with the pump.
    pub pause: PauseMode,
    /// Output ratio while paused with [`PauseMode::KeepPrimed`] (default: the offset, i.e. zero
    /// flow with the pump enabled).
    pub hold_output: Option<f64>,
}

impl Default for PumpOptions {
    /// Flow on analog output 0 (0–10 V), 1.0 per L/min (the default bead, 20 × 8 mm at
    /// 0.05 m/s, is 0.48 L/min → 0.48), no offset; enable on standard digital output 0; 2 s of
    /// priming; pauses keep the pump primed.
    fn default() -> Self {
        PumpOptions {
            flow_output: 0,
            flow_domain: AnalogDomain::Voltage,
            flow_factor: 1.0,
            flow_offset: 0.0,
            enable_output: Some(DigitalOutput::Standard(0)),
            prime_dwell: 2.0,
            pause: PauseMode::KeepPrimed,
            hold_output: None,
        }
    }
}

impl PumpOptions {
    /// The analog output ratio for volumetric flow `q_m3s` (m³/s).
    pub fn output_for_flow(&self, q_m3s: f64) -> f64 {
        self.flow_offset + self.flow_factor * q_m3s * 60_000.0
    }

    /// The output ratio while paused.
    pub fn hold(&self) -> f64 {
        self.hold_output.unwrap_or(self.flow_offset)
    }

    /// Check the outputs exist on the controller and the calibration is usable for flows up
    /// to `max_flow_m3s`.
    pub fn validate(&self, max_flow_m3s: f64) -> Result<(), crate::error::RobotError> {
        use crate::error::RobotError;
        if self.flow_output > 1 {
            return Err(RobotError::invalid(
                "pump.flow_output",
                format!(
                    "standard analog output {}: the UR e-Series controller has outputs 0 and 1",
                    self.flow_output
                ),
            ));
        }
        if let Some(e) = self.enable_output
            && e.number() > e.max_number()
        {
            return Err(RobotError::invalid(
                "pump.enable_output",
                format!(
                    "{e:?}: the controller has outputs 0..={} of this kind",
                    e.max_number()
                ),
            ));
        }
        if !(self.flow_factor.is_finite() && self.flow_factor > 0.0) {
            return Err(RobotError::invalid(
                "pump.flow_factor",
                format!(
                    "{}: must be finite and > 0 (output ratio per L/min)",
                    self.flow_factor
                ),
            ));
        }
        if !(self.flow_offset.is_finite() && (0.0..1.0).contains(&self.flow_offset)) {
            return Err(RobotError::invalid(
                "pump.flow_offset",
                format!("{}: must be in [0, 1) (output ratio)", self.flow_offset),
            ));
        }
        if !(self.prime_dwell.is_finite() && self.prime_dwell >= 0.0) {
            return Err(RobotError::invalid(
                "pump.prime_dwell",
                format!("{} s: must be finite and ≥ 0", self.prime_dwell),
            ));
        }
        let h = self.hold();
        if !(h.is_finite() && (0.0..=1.0).contains(&h)) {
            return Err(RobotError::invalid(
                "pump.hold_output",
                format!("{h}: must be in [0, 1] (output ratio)"),
            ));
        }
        let top = self.output_for_flow(max_flow_m3s);
        if top > 1.0 {
            return Err(RobotError::invalid(
                "pump.flow_factor",
                format!(
                    "the design flow {:.4} L/min needs output {top:.3} > 1 (the full range): lower flow_factor or flow_offset",
                    max_flow_m3s * 60_000.0
                ),
            ));
        }
        Ok(())
    }
}

/// Per-layer waits used when no schedule supplies them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WaitOptions {
    /// Minimum time (s) from the start of a layer to the start of the next; a shorter layer is
    /// followed by a pause. 0 = no waits.
    pub min_layer_time: f64,
}

impl Default for WaitOptions {
    fn default() -> Self {
        WaitOptions {
            min_layer_time: 0.0,
        }
    }
}

/// URScript export settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProgramOptions {
    /// Blend radius (m) of `movep` along a layer (keep < half the point spacing).
    pub blend_radius: f64,
    /// Tool acceleration (m/s²) of `movep`/`movel`.
    pub tool_acceleration: f64,
    /// `movej` joint speed (rad/s) and acceleration (rad/s²) of approach moves.
    pub joint_speed: f64,
    pub joint_acceleration: f64,
    /// Use `movel` instead of `movep` along layers.
    pub use_movel: bool,
    /// Most motion targets (move commands) per program file: controllers fail on long files
    /// above ~1–2.5 k targets (robot.md §4). Programs are cut at layer boundaries.
    #[serde(alias = "max_targets")]
    pub max_moves_per_program: usize,
    /// Distance (m) of the safe approach pose behind the first target along the tool axis.
    pub approach_distance: f64,
    /// Tool speed (m/s) of the `movel` from the approach pose down to the first target.
    pub approach_speed: f64,
    /// Time (s) to load and start the next program file within a station (a pause that keeps
    /// the pump primed).
    pub program_switch_time: f64,
    /// Payload (kg) and its centre of gravity (m, flange frame) for `set_payload`.
    pub payload_mass: f64,
    pub payload_cog: [f64; 3],
}

impl Default for ProgramOptions {
    fn default() -> Self {
        ProgramOptions {
            blend_radius: 0.002,
            tool_acceleration: 1.2,
            joint_speed: 0.5,
            joint_acceleration: 1.0,
            use_movel: false,
            max_moves_per_program: 1000,
            approach_distance: 0.05,
            approach_speed: 0.05,
            program_switch_time: 10.0,
            payload_mass: 3.0,
            payload_cog: [0.0, 0.0, 0.1],
        }
    }
}

/// The base-pose errors a plan must tolerate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BaseTolerance {
    /// Largest position error of the base in x and y, m (default 0.010).
    pub position: f64,
    /// Largest yaw error of the base, degrees (default 1.0).
    pub yaw_deg: f64,
    /// Check every n-th waypoint of a layer (and always its first and last); 1 = every waypoint.
    pub stride: usize,
}

impl Default for BaseTolerance {
    fn default() -> Self {
        BaseTolerance {
            position: 0.010,
            yaw_deg: 1.0,
            stride: 1,
        }
    }
}

/// The 9 sampled base errors `(dx, dy, dyaw)`: the box's corners and its centre.
pub fn sampled_errors(tol: &BaseTolerance) -> Vec<(f64, f64, f64)> {
    let (p, a) = (tol.position, tol.yaw_deg.to_radians());
    let mut out = vec![(0.0, 0.0, 0.0)];
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sa in [-1.0, 1.0] {
                out.push((sx * p, sy * p, sa * a));
            }
        }
    }
    out
}
