//! The plan's data: what a planned print is (stations of timed layers of waypoints) and what it
//! carries (program parts, slowdowns, mesh and certified clearances, the operator's mark). Plain
//! data, serialised to `plan.json`; the planning that makes it is in [`crate::planner`] and
//! [`crate::stationary`], the checks and the timing that fill it in [`crate::check`],
//! [`crate::timing`] and [`crate::meshes`].

use serde::{Deserialize, Serialize};

use crate::frames::Mat4;
use crate::kinematics::Joints;
use crate::setup::{PathPoint, PlanOptions, PrintLayer, RobotSetup};

/// Clearances above this (m) are reported as this value.
pub const CLEARANCE_CUTOFF: f64 = 0.5;

/// One planned print waypoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    /// Point index within the layer (row of `path.csv`).
    pub index: usize,
    /// Time from the start of the plan (s).
    pub t: f64,
    /// Joint values (rad), unwrapped and inside the limits.
    pub q: Joints,
    /// Target nozzle-tip position and tool axis (world), kept for re-verification.
    pub position: [f64; 3],
    pub axis: [f64; 3],
    /// Planned tool speed (m/s) of the move arriving here (0 at a station's first waypoint);
    /// the flow follows it.
    #[serde(default)]
    pub speed: f64,
    /// Time (s) the robot stays here after arriving: priming at a station's first waypoint, a
    /// pause (wait, program change, re-priming) at a layer's last.
    #[serde(default)]
    pub hold: f64,
}

/// One planned layer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LayerPlan {
    pub layer: i64,
    pub waypoints: Vec<Waypoint>,
    /// Σ Δq² along the layer (rad²).
    pub cost: f64,
    /// Smallest clearance to the environment along the layer (m, capped at 0.5).
    pub min_clearance: f64,
    /// Largest |q̇_j|/v_j,max along the layer.
    pub max_speed_ratio: f64,
    /// Scheduled wait after the layer (s): from the schedule, or the minimum layer time.
    #[serde(default)]
    pub wait: f64,
}

impl LayerPlan {
    /// A layer as the planners' joint search leaves it: its timing (the speed ratio and the
    /// wait) is not known until the timing pass runs over the whole plan.
    pub(crate) fn untimed(
        layer: i64,
        waypoints: Vec<Waypoint>,
        cost: f64,
        min_clearance: f64,
    ) -> LayerPlan {
        LayerPlan {
            layer,
            waypoints,
            cost,
            min_clearance,
            max_speed_ratio: 0.0,
            wait: 0.0,
        }
    }
}

/// All layers printed from one base pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Station {
    /// Robot base pose, row-major 4×4.
    pub world_from_base: Mat4,
    pub layers: Vec<LayerPlan>,
}

impl Station {
    /// The joint path of every layer's motion, in layer order: its waypoints, preceded (from the
    /// second layer on) by the previous layer's last configuration, so the printed layer change
    /// is part of the layer that it leads into.
    pub fn layer_paths(&self) -> Vec<Vec<Joints>> {
        let mut prev: Option<Joints> = None;
        self.layers
            .iter()
            .map(|l| {
                let path: Vec<Joints> = prev
                    .into_iter()
                    .chain(l.waypoints.iter().map(|w| w.q))
                    .collect();
                prev = l.waypoints.last().map(|w| w.q);
                path
            })
            .collect()
    }
}

/// A verified-ready plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub stations: Vec<Station>,
    /// The tool transform used, row-major 4×4.
    pub flange_from_tcp: Mat4,
    /// Σ Δq² over all print and transition steps (rad²), the optimised cost without penalties.
    pub cost: f64,
    /// Σ_j Σ_k |Δq_j| over the whole plan (rad).
    pub joint_motion: f64,
    /// Time spent printing (s).
    pub print_time: f64,
    /// The plan's clock at the arrival at the last target (s). The clock starts (0) when the
    /// first program starts its approach from the safe pose and counts every approach,
    /// priming, print move, pause, program change and station change; every waypoint's `t`,
    /// trajectory.csv's `t`, [`crate::layer_times`] and programs.json's `start_s`/`end_s` are
    /// on it, so this is also the end of the last layer. The final retract comes after it.
    pub total_time: f64,
    /// Smallest clearance to the environment over all waypoints (m, capped at 0.5).
    pub min_clearance: f64,
    /// Smallest signed distance of the checked self-collision pairs (m).
    pub min_self_distance: f64,
    /// Largest |q̇_j|/v_j,max while printing.
    pub max_speed_ratio: f64,
    /// Largest |q̈_j|/a_j,max over the rows of the trajectory.
    #[serde(default)]
    pub max_acceleration_ratio: f64,
    /// Where the tool is slower than the design speed (the flow follows it).
    #[serde(default)]
    pub slowdowns: Vec<Slowdown>,
    /// The program files, in order.
    #[serde(default)]
    pub parts: Vec<ProgramPart>,
    /// Clearances measured with UR's collision meshes and with the capsules, when checked
    /// ([`crate::meshes::attach_mesh_report`]).
    #[serde(default)]
    pub meshes: Option<MeshReport>,
    /// Certified capsule clearances along the motion from the plan's check
    /// ([`crate::check::CheckReport`]), when checked.
    #[serde(default)]
    pub certified: Option<CertifiedClearance>,
    /// What the operator must know before running this plan's programs (a failing design, a
    /// resumed print); every program's title, header, function name and `programs.json` say it.
    #[serde(default, skip_serializing_if = "PlanMark::is_plain")]
    pub mark: PlanMark,
    /// The setup (with the base placement resolved to the stations) and options used.
    pub setup: RobotSetup,
    pub options: PlanOptions,
}

/// Marks a plan whose programs are not the plain print of a passing design (issue 28): an
/// operator who picks up a program file must see it in the file itself, not only in the run's
/// terminal output.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlanMark {
    /// The design fails its checks (programs written only with `--allow-fail`): what fails.
    pub failing_design: Option<String>,
    /// The plan continues an interrupted print from this layer (`kappe robot resume`).
    pub resumed_from_layer: Option<i64>,
    /// Stations of the original plan before this one's first (a resumed plan keeps the
    /// original station numbers, which the operator's station sheet uses).
    pub station_offset: usize,
}

impl PlanMark {
    /// Neither mark.
    pub fn is_plain(&self) -> bool {
        self.failing_design.is_none()
            && self.resumed_from_layer.is_none()
            && self.station_offset == 0
    }

    /// The words for a program's title, e.g. `RESUME FROM LAYER -45, FAILING DESIGN`; empty
    /// when plain.
    pub fn title(&self) -> String {
        let mut words = Vec::new();
        if let Some(k) = self.resumed_from_layer {
            words.push(format!("RESUME FROM LAYER {k}"));
        }
        if self.failing_design.is_some() {
            words.push("FAILING DESIGN".to_string());
        }
        words.join(", ")
    }

    /// The comment lines every program of a marked plan starts with after its title (station
    /// and tracking programs alike): the failing design's warning, the resume note and the
    /// operator's guide.
    pub fn header_lines(&self) -> String {
        let mut text = String::new();
        if let Some(why) = &self.failing_design {
            let why = why.split_whitespace().collect::<Vec<_>>().join(" ");
            text.push_str(&format!(
                "# WARNING: the design FAILS its checks ({why}); written only because of --allow-fail\n"
            ));
        }
        if let Some(k) = self.resumed_from_layer {
            text.push_str(&format!(
                "# RESUME: continues an interrupted print from layer {k}; the layers before it must stand\n"
            ));
        }
        text.push_str(
            "# operator's guide: docs/operator.md in the Kappe repository (origin, base placement, \
             stopped prints)\n",
        );
        text
    }

    /// The suffix of a program's function name, e.g. `_resume_m45_failing`; empty when plain.
    /// URScript names allow only letters, digits and `_`, so a negative layer is `m45`.
    pub fn function_suffix(&self) -> String {
        let mut s = String::new();
        if let Some(k) = self.resumed_from_layer {
            let sign = if k < 0 { "m" } else { "" };
            s.push_str(&format!("_resume_{sign}{}", k.unsigned_abs()));
        }
        if self.failing_design.is_some() {
            s.push_str("_failing");
        }
        s
    }
}

/// Certified lower bounds of the capsule model's clearances along the whole motion (print moves,
/// layer changes, station approaches and retracts; [`crate::sweep`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CertifiedClearance {
    /// To the environment along the print moves and layer changes (m, capped at 0.5), which
    /// hold the planner's margin.
    pub clearance: f64,
    /// To the environment along the station approaches and retracts, which need only be clear
    /// of contact (m).
    #[serde(default)]
    pub approach_clearance: f64,
    /// Of the checked self pairs (m).
    pub self_distance: f64,
    /// Configurations measured (waypoints and added midpoints).
    pub configurations: usize,
}

impl Plan {
    /// Number of print waypoints.
    pub fn waypoint_count(&self) -> usize {
        self.stations
            .iter()
            .flat_map(|s| &s.layers)
            .map(|l| l.waypoints.len())
            .sum()
    }
}

/// The print targets of a plan as the planner's input layers (every station's layers in print
/// order), so a check can validate them with the planner's own rules.
pub(crate) fn plan_layers(plan: &Plan) -> Vec<PrintLayer> {
    plan.stations
        .iter()
        .flat_map(|s| &s.layers)
        .map(|l| PrintLayer {
            layer: l.layer,
            points: l
                .waypoints
                .iter()
                .map(|w| PathPoint {
                    index: w.index,
                    position: w.position,
                    axis: w.axis,
                })
                .collect(),
        })
        .collect()
}

/// A range of consecutive print moves that is slower than the design speed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Slowdown {
    pub station: usize,
    /// Layer and point index of the first and last waypoint reached by a slow move.
    pub from: (i64, usize),
    pub to: (i64, usize),
    /// Lowest tool speed / design speed in the range.
    pub min_speed_ratio: f64,
    /// Why: "joint speed (joint j)" or "joint acceleration".
    pub reason: String,
}

/// One program file: a contiguous range of layers of one station.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProgramPart {
    pub station: usize,
    /// Layer slots (indices into the station's `layers`), inclusive.
    pub first: usize,
    pub last: usize,
    /// Their layer ids.
    pub first_layer: i64,
    pub last_layer: i64,
    /// Motion targets (move commands) in the file.
    pub targets: usize,
    /// The part starts the station: approach from the safe pose and prime the pump.
    pub starts_station: bool,
    /// The part ends the station: pump off and retract.
    pub ends_station: bool,
}

/// Environment clearances of the meshes above this (m) are reported as this value.
pub const MESH_CUTOFF: f64 = 0.1;

/// Where a model's smallest clearance or self distance occurs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ClearanceAt {
    /// Metres (0 = touching or overlapping for the meshes; negative = overlap depth for capsules).
    pub distance: f64,
    pub station: usize,
    pub layer: i64,
    pub index: usize,
    /// Link or link pair, and the object.
    pub what: String,
}

/// Clearance of one geometric model over the checked waypoints.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ModelClearance {
    /// Smallest distance of the arm (links 1–6) to the environment (beams, mobile base, floor,
    /// printed layers), capped at [`MESH_CUTOFF`].
    pub environment: ClearanceAt,
    /// Smallest distance of the 13 self-collision pairs.
    pub self_distance: ClearanceAt,
}

/// The plan measured with the capsules and with UR's collision meshes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshReport {
    pub waypoints_checked: usize,
    pub mesh_vertices: Vec<usize>,
    pub capsules: ModelClearance,
    pub meshes: ModelClearance,
    /// The nozzle (a capsule in both models, clipped near the tip) to the environment.
    pub nozzle: ClearanceAt,
    /// Certified smallest clearances of the meshes between the waypoints (joint-interpolated
    /// print moves and layer changes; [`crate::sweep`]), when measured.
    #[serde(default)]
    pub along_motion: Option<AlongMotion>,
    /// Mesh contacts (distance 0 to the environment or on a self pair).
    pub problems: Vec<String>,
}

/// Certified lower bounds of the mesh model's clearances along the whole motion (the layer
/// where each occurs; `index` and `what` are not resolved for a bound).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AlongMotion {
    /// Arm meshes (links 1–6) to the environment, capped at [`MESH_CUTOFF`].
    pub environment: ClearanceAt,
    /// The nozzle capsules to the environment.
    pub nozzle: ClearanceAt,
    /// The 13 self pairs on the meshes.
    pub self_distance: ClearanceAt,
    /// Configurations measured (waypoints and midpoints added by the splits).
    pub configurations: usize,
}
