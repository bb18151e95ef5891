//! From a designed cap to the HTML report input (issue 8).
//!
//! [`report_input`] maps a [`Cap`] plus optional analysis and robot results
//! ([`ReportExtras`], plain data filled by [`crate::run`]) to [`kappe_report::ReportInput`]:
//!
//! - `layers`: `cap.sections.layers` in print order; the final-state stress of segment `i` of the
//!   layer at print index `q` is `σ = F_i · d_q / (lw·lh)` (method.md §3, §6: `F_i` the layer-0
//!   force, `d_q` the layer factor of the final state); overhang `l_o` from `cap.overhangs`
//!   (`None` for the first layer).
//! - `bed_joints`: the final state's trail edges, `σ = N / (lw·l_trib)` with the trail forces of
//!   the final force pass, drawn from the lower node to the upper one; a column's last edge ends
//!   on the base plane.
//! - `states`: one per `cap.states`, with σ_min/σ_max of the force pass, the largest |l_o| of the
//!   printed layers and, while the page stays small, per-state segment stresses
//!   `F_i · d_q(state) / (lw·lh)` (the factors of every state, kept by `design_cap`; they
//!   differ from the final ones only in the start section).
//! - `constraints`: [`preliminary_constraints`] (σ_min, σ_max, overhang, worst over all states),
//!   then the analysis rows of [`ReportExtras::constraints`], which replace rows of the same
//!   name and add new ones (BLF, robot reach, …).
//! - `robot`, `timeline`, `cell` (issue 14): every waypoint of the robot plan (a second frame
//!   at the end of a hold) with its station; the arrival time of the waypoint of each path point
//!   (`layer, index`) is that point's time on the one timeline (without a plan: arc length over
//!   the print speed); the cell is the plan's stations, tool, mobile base, box obstacles (the
//!   beams) and floor.
//! - `modes`: mode 1 of every analysed state (`StateAnalysis::mode`, per shell node) moved onto
//!   the bead nodes: each shell node's network node goes to the nearest bead node of its layer.
//! - `worst_places`: σ_min/σ_max at the midpoint of the extreme element of the worst state (one
//!   force pass of that state), BLF at the peak of that state's mode 1, the overhang at the
//!   crown of its layer (with the signed l_o).
//! - `quantities`: with a time model, each printed layer's age and modulus per state, on the
//!   run's one clock ([`crate::schedule::Schedule::ages`]), as the analysis used them.

use std::collections::HashMap;

use kappe_report::{
    BedJoint, Bound, BoxBody, Capsule, Cell, ConstraintRow, Layer, ModeShape, Parameter, Plot,
    PrintPath, PrintState, Quantity, QuantityPer, ReportInput, RobotAnimation, Series, Station,
    Timeline, WorstPlace,
};

use crate::analysis::NetworkMode;

use crate::form::cap::Cap;
use crate::verdict::{
    max_overhang, preliminary_constraints, state_ok_preliminary, stress_tolerance,
};

/// Above this many per-state segment stresses in total, the states carry none and the viewer
/// colours every state by the final-state stresses: the page grows by ~10 bytes per value,
/// so this bounds the island at ~20 MB (the default design needs ~0.3 million).
const MAX_STATE_STRESS_VALUES: usize = 2_000_000;

/// Results of one print state from the analysis ([`crate::analysis::analyze`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateCheck {
    /// Lowest positive linear buckling load factor of the state, if computed.
    pub blf: Option<f64>,
    /// Whether the state meets every structural constraint.
    pub ok: bool,
}

/// What the analysis and the robot planner add to a designed cap. Plain data: the caller fills
/// it; [`ReportExtras::default`] means "not analysed, no robot".
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReportExtras {
    /// One entry per `cap.states` (same order), or empty when there is no analysis. An entry's
    /// `ok` replaces the preliminary per-state verdict; its `blf` feeds the BLF plot.
    pub states: Vec<StateCheck>,
    /// Constraint rows of the analysis (worst over all states). A row replaces the preliminary
    /// row of the same `name` (`sigma_min`, `sigma_max`, `overhang_max`); other rows (`blf_min`,
    /// robot checks) are appended.
    pub constraints: Vec<ConstraintRow>,
    /// The robot moving along its trajectory.
    pub robot: Option<RobotAnimation>,
    /// Extra plots after the standard ones.
    pub plots: Vec<Plot>,
    /// Arrival time of every waypoint of the plan, by (layer id, point index), s.
    pub waypoint_times: Vec<(i64, usize, f64)>,
    /// End of the robot plan, s.
    pub plan_end: Option<f64>,
    /// The robot cell of the plan.
    pub cell: Option<Cell>,
    /// Mode 1 of each analysed state: state position, its BLF, translations per network node.
    pub modes: Vec<(usize, f64, NetworkMode)>,
    /// The time model and the run's schedule, when the modulus varies with age: the layers'
    /// ages and moduli as the analysis used them.
    pub clock: Option<(crate::input::material::TimeModel, crate::schedule::Schedule)>,
    /// The print schedule, governing checks and layer ages (`crate::schedule::report_schedule`).
    pub schedule: Option<kappe_report::PrintSchedule>,
    /// The robot plan's slowdowns and clearances ([`robot_summary`]).
    pub robot_summary: Option<kappe_report::RobotSummary>,
}

/// The analysis of `crate::analysis::analyze` as report extras: per-state BLF and verdict,
/// the constraint rows in the report's units (stresses in kPa, overhang in mm; the analysis
/// gives Pa and m), and the overall verdict. A constraint that no state was checked for (e.g.
/// `blf_min` with buckling switched off) has no worst value and is left out of the table.
pub fn extras_from_analysis(analysis: &crate::analysis::Analysis) -> ReportExtras {
    let states = analysis
        .states
        .iter()
        .map(|s| StateCheck {
            blf: s.blf,
            ok: s.ok,
        })
        .collect();
    let constraints = analysis.constraints.iter().filter_map(row_of).collect();
    let modes = analysis
        .states
        .iter()
        .enumerate()
        .filter_map(|(i, s)| Some((i, s.blf?, s.mode.clone())))
        .filter(|(_, _, m)| !m.is_empty())
        .collect();
    let plots = analysis
        .as_printed
        .as_ref()
        .map(|a| {
            let limit = analysis
                .constraints
                .iter()
                .find(|c| c.name == "deviation_max")
                .map(|c| c.limit);
            as_printed_plot(a, limit)
        })
        .into_iter()
        .chain(collapse_plot(analysis))
        .collect();
    ReportExtras {
        states,
        constraints,
        modes,
        plots,
        ..ReportExtras::default()
    }
}

/// The as-printed deviation over the print (docs/as-printed.md): crown sag and the largest
/// deviation after every state, with the limit `deviation_max`, in mm.
fn as_printed_plot(a: &crate::analysis::asprinted::AsPrinted, limit: Option<f64>) -> Plot {
    let mm = |f: &dyn Fn(&crate::analysis::asprinted::StateDeviation) -> f64| -> Vec<[f64; 2]> {
        a.states
            .iter()
            .map(|s| [s.state as f64, 1e3 * f(s)])
            .collect()
    };
    let mut series = vec![
        Series {
            name: "largest deviation".into(),
            points: mm(&|s| s.deviation_m),
        },
        Series {
            name: "crown sag".into(),
            points: mm(&|s| s.crown_sag_m),
        },
    ];
    if let (Some(l), Some(first), Some(last)) = (limit, a.states.first(), a.states.last()) {
        series.push(Series {
            name: format!("deviation_max = {:.1} mm", 1e3 * l),
            points: vec![[first.state as f64, 1e3 * l], [last.state as f64, 1e3 * l]],
        });
    }
    Plot {
        title: format!(
            "As-printed deviation from the design per state (largest {:.2} mm{})",
            1e3 * a.deviation_m,
            a.state.map_or(String::new(), |s| format!(" at state {s}"))
        ),
        x_label: "print state".into(),
        y_label: "deviation [mm]".into(),
        series,
    }
}

/// The waves of a corrugated cap (issue 26): the crown height of every centre layer along the
/// cap against the smooth cap's (layer 0's); `None` for a smooth cap. The 3D view shows the
/// same waves and, per state, the buckling mode on them.
fn corrugation_plot(cap: &Cap) -> Option<Plot> {
    let crown = |a: &crate::form::arch::Arch| a.points.get(a.points.len() / 2).map(|p| p.z);
    if cap.centre_arches.is_empty() {
        return None;
    }
    let wave: Vec<[f64; 2]> = cap
        .centre_arches
        .iter()
        .enumerate()
        .filter_map(|(k, a)| crown(a).map(|z| [k as f64, 1e3 * z]))
        .collect();
    let smooth = crown(&cap.arch)?;
    let last = (cap.centre_arches.len() - 1) as f64;
    let w = cap.design.corrugation();
    Some(Plot {
        title: format!(
            "Corrugation: crown height of each centre layer{}",
            w.map_or(String::new(), |w| format!(
                " (amplitude {:.1} mm, wavelength {:.3} m)",
                1e3 * w.amplitude,
                w.wavelength
            ))
        ),
        x_label: "centre layer (print order)".into(),
        y_label: "crown height in the layer's plane [mm]".into(),
        series: vec![
            Series {
                name: "corrugated layers".into(),
                points: wave,
            },
            Series {
                name: "smooth cap (layer 0)".into(),
                points: vec![[0.0, 1e3 * smooth], [last, 1e3 * smooth]],
            },
        ],
    })
}

/// The governing collapse state's load–deflection curve (`[analysis.nonlinear]`): load factor
/// against the largest displacement along the path.
fn collapse_plot(analysis: &crate::analysis::Analysis) -> Option<Plot> {
    let s = analysis
        .states
        .iter()
        .filter(|s| !s.collapse_curve.is_empty())
        .min_by(|a, b| {
            let f = |s: &crate::analysis::StateAnalysis| s.collapse_factor.unwrap_or(f64::INFINITY);
            f(a).total_cmp(&f(b))
        })?;
    Some(Plot {
        title: format!(
            "Collapse path of the governing state {} (collapse factor {:.3}, {})",
            s.index,
            s.collapse_factor.unwrap_or(f64::NAN),
            s.collapse_mode.map_or("", |m| m.name())
        ),
        x_label: "largest displacement [mm]".into(),
        y_label: "load factor λ [-]".into(),
        series: vec![Series {
            name: format!("state {}", s.index),
            points: s
                .collapse_curve
                .iter()
                .map(|p| [1e3 * p[1], p[0]])
                .collect(),
        }],
    })
}

/// A constraint in the report's units (stresses in kPa, overhang in mm; the analysis gives Pa
/// and m); `None` when no state was checked for it (no worst value).
fn row_of(c: &crate::analysis::ConstraintResult) -> Option<ConstraintRow> {
    let worst = c.worst?;
    let (scale, unit) = match c.unit {
        "Pa" => (1e-3, "kPa"),
        "m" => (1e3, "mm"),
        "1" => (1.0, ""),
        other => (1.0, other),
    };
    let bound = match c.name {
        "sigma_max" | "overhang_max" | "deviation_max" => Bound::AtMost,
        _ => Bound::AtLeast,
    };
    Some(ConstraintRow {
        name: c.name.to_string(),
        bound,
        limit: c.limit * scale,
        worst: worst * scale,
        unit: unit.to_string(),
        state: c.state,
        // A failing row says what to change (issue 28), as the terminal does.
        element: match (c.pass, c.element.is_empty()) {
            (true, true) => None,
            (true, false) => Some(c.element.clone()),
            (false, true) => Some(format!(
                "to fix: {}",
                crate::analysis::check::levers(c.name)
            )),
            (false, false) => Some(format!(
                "{}; to fix: {}",
                c.element,
                crate::analysis::check::levers(c.name)
            )),
        },
        pass: c.pass,
    })
}

/// Every waypoint of `plan` as the report's animation (joints and station per frame; a second
/// frame at the end of a hold, so the arm waits where the plan waits), and the arrival time of
/// each waypoint by (layer id, point index). About 32 bytes per frame in the page.
pub fn plan_animation(plan: &kappe_robot::Plan) -> (RobotAnimation, Vec<(i64, usize, f64)>) {
    let mut anim = RobotAnimation::default();
    let mut times = Vec::new();
    for (s, st) in plan.stations.iter().enumerate() {
        for l in &st.layers {
            for w in &l.waypoints {
                anim.times.push(w.t);
                anim.joints.push(w.q);
                anim.station.push(s);
                times.push((l.layer, w.index, w.t));
                if w.hold > 0.0 {
                    anim.times.push(w.t + w.hold);
                    anim.joints.push(w.q);
                    anim.station.push(s);
                }
            }
        }
    }
    (anim, times)
}

/// The robot cell of `plan`: stations, tool, mobile base, box obstacles (the beams) and floor.
pub fn plan_cell(plan: &kappe_robot::Plan) -> Cell {
    let setup = &plan.setup;
    Cell {
        stations: plan
            .stations
            .iter()
            .map(|s| Station {
                world_from_base: s.world_from_base,
                layers: s
                    .layers
                    .iter()
                    .filter_map(|l| i32::try_from(l.layer).ok())
                    .collect(),
            })
            .collect(),
        flange_from_tcp: plan.flange_from_tcp,
        tool: setup
            .tool
            .capsules
            .iter()
            .map(|c| Capsule {
                a: c.a,
                b: c.b,
                radius: c.radius,
            })
            .collect(),
        mobile_base: setup
            .mobile_base
            .iter()
            .map(|b| BoxBody {
                name: b.name.clone(),
                center: b.center,
                half_extents: b.half_extents,
                yaw: 0.0,
            })
            .collect(),
        obstacles: setup
            .obstacles
            .iter()
            .filter_map(|o| match o {
                kappe_robot::collision::Obstacle::Box {
                    name,
                    center,
                    half_extents,
                    yaw,
                } => Some(BoxBody {
                    name: name.clone(),
                    center: *center,
                    half_extents: *half_extents,
                    yaw: *yaw,
                }),
                _ => None,
            })
            .collect(),
        floor_z: setup.floor_z,
    }
}

/// Adds the outcome of robot planning (`crate::robot_plan::plan_robot`): for a plan, the
/// animation ([`plan_animation`]), the timeline and the cell ([`plan_cell`]) and a passing `robot_plan` row whose element tells the
/// stations and the minimum clearance; for a failure, [`ReportExtras::robot_error`] and a
/// failing row whose element is the planner's reason.
pub fn add_robot(
    extras: &mut ReportExtras,
    plan: &Result<kappe_robot::Plan, kappe_robot::RobotError>,
) {
    let (pass, element) = match plan {
        Ok(p) => {
            let (anim, times) = plan_animation(p);
            extras.robot = (!anim.times.is_empty()).then_some(anim);
            extras.waypoint_times = times;
            extras.plan_end = Some(p.total_time);
            extras.cell = Some(plan_cell(p));
            extras.robot_summary = Some(robot_summary(p));
            (
                true,
                format!(
                    "{} station(s), min clearance {:.1} mm, {:.1} min",
                    p.stations.len(),
                    p.min_clearance * 1e3,
                    p.total_time / 60.0
                ),
            )
        }
        Err(e) => (false, e.to_string()),
    };
    extras.constraints.push(ConstraintRow {
        name: "robot_plan".into(),
        bound: Bound::AtMost,
        limit: 0.0,
        worst: if pass { 0.0 } else { 1.0 },
        unit: "failures".into(),
        state: None,
        element: Some(element),
        pass,
    });
}

/// Where a plan's tool is slower than the design speed (and why), and the clearances of the
/// capsules and of UR's collision meshes, at the waypoints and certified along the motion
/// (`Plan::meshes`, `Plan::certified`), for the report's robot section.
pub fn robot_summary(p: &kappe_robot::Plan) -> kappe_report::RobotSummary {
    use kappe_report::{ClearanceRow, SlowdownRow};
    let at = |c: &kappe_robot::meshes::ClearanceAt| {
        format!(
            "{} (station {}, layer {}, point {})",
            c.what,
            c.station + 1,
            c.layer,
            c.index
        )
    };
    let mut clearances = Vec::new();
    let certified = p.certified.as_ref();
    clearances.push(ClearanceRow {
        model: "capsules (arm and nozzle)".into(),
        to: "environment".into(),
        at_waypoints: p.min_clearance,
        at: "print moves and layer changes, as planned".into(),
        along_motion: certified.map(|c| c.clearance),
    });

    clearances.push(ClearanceRow {
        model: "capsules".into(),
        to: "self".into(),
        at_waypoints: p.min_self_distance,
        at: "as planned".into(),
        along_motion: certified.map(|c| c.self_distance),
    });
    if let Some(m) = &p.meshes {
        let along = m.along_motion.as_ref();
        clearances.push(ClearanceRow {
            model: "arm capsules".into(),
            to: "environment".into(),
            at_waypoints: m.capsules.environment.distance,
            at: at(&m.capsules.environment),
            along_motion: None,
        });
        clearances.push(ClearanceRow {
            model: "arm meshes (UR)".into(),
            to: "environment".into(),
            at_waypoints: m.meshes.environment.distance,
            at: at(&m.meshes.environment),
            along_motion: along.map(|a| a.environment.distance),
        });
        clearances.push(ClearanceRow {
            model: "nozzle (capsule)".into(),
            to: "environment".into(),
            at_waypoints: m.nozzle.distance,
            at: at(&m.nozzle),
            along_motion: along.map(|a| a.nozzle.distance),
        });
        clearances.push(ClearanceRow {
            model: "arm capsules".into(),
            to: "self".into(),
            at_waypoints: m.capsules.self_distance.distance,
            at: at(&m.capsules.self_distance),
            along_motion: None,
        });
        clearances.push(ClearanceRow {
            model: "arm meshes (UR)".into(),
            to: "self".into(),
            at_waypoints: m.meshes.self_distance.distance,
            at: at(&m.meshes.self_distance),
            along_motion: along.map(|a| a.self_distance.distance),
        });
    }
    kappe_report::RobotSummary {
        design_speed: p.options.print_speed,
        max_speed_ratio: p.max_speed_ratio,
        max_acceleration_ratio: p.max_acceleration_ratio,
        slowdowns: p
            .slowdowns
            .iter()
            .map(|s| SlowdownRow {
                station: s.station + 1,
                from: s.from,
                to: s.to,
                min_speed_ratio: s.min_speed_ratio,
                reason: s.reason.clone(),
            })
            .collect(),
        clearances,
        margin: p.options.clearance,
        self_margin: p.options.self_clearance,
    }
}

/// The constraint table: preliminary rows, replaced or extended by the analysis rows.
fn constraint_rows(cap: &Cap, extras: &ReportExtras) -> Vec<ConstraintRow> {
    let mut rows: Vec<ConstraintRow> = preliminary_constraints(cap)
        .iter()
        .filter_map(row_of)
        .collect();
    for row in &extras.constraints {
        match rows.iter_mut().find(|r| r.name == row.name) {
            Some(slot) => *slot = row.clone(),
            None => rows.push(row.clone()),
        }
    }
    rows
}

fn v3(v: &crate::form::frame::V3) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// `print_time`: the one print time of the run (`Outcome::print_time`: the robot plan's when
/// there is one), so the page shows what the summary, the table and the programs show.
fn parameters(cap: &Cap, print_time: f64) -> Vec<Parameter> {
    let d = &cap.design;
    let p = |key: &str, value: String, unit: &str| Parameter {
        key: key.into(),
        value,
        unit: unit.into(),
    };
    let mut out = vec![
        p("span Cs", format!("{}", d.cap.span), "m"),
        p("rise Cr", format!("{}", d.cap.rise), "m"),
        p("length Cl", format!("{}", d.cap.length), "m"),
        p("layer tilt am", format!("{}", d.cap.tilt_deg), "deg"),
        p(
            "specific weight γ",
            format!("{}", d.material.specific_weight),
            "N/m³",
        ),
        p(
            "Young's modulus E",
            format!("{}", d.material.youngs_modulus / 1e6),
            "MPa",
        ),
        p(
            "Poisson's ratio ν",
            format!("{}", d.material.poisson_ratio),
            "",
        ),
        p(
            "layer height lh",
            format!("{}", d.print.layer_height * 1e3),
            "mm",
        ),
        p(
            "layer width lw",
            format!("{}", d.print.layer_width * 1e3),
            "mm",
        ),
        p(
            "nozzle diameter d_n",
            format!("{}", d.print.nozzle_diameter * 1e3),
            "mm",
        ),
        p(
            "path sampling Δs",
            format!("{}", d.print.path_sampling * 1e3),
            "mm",
        ),
        p(
            "start-layer arch fraction φ",
            format!("{}", d.print.start_arch_fraction),
            "",
        ),
        p("print speed", format!("{}", d.print.print_speed), "m/s"),
        p("σ_min", format!("{}", d.constraints.sigma_min / 1e3), "kPa"),
        p("σ_max", format!("{}", d.constraints.sigma_max / 1e3), "kPa"),
        p("BLF_min", format!("{}", d.constraints.blf_min), ""),
        p("l_o,max", format!("{}", d.overhang_max() * 1e3), "mm"),
    ];
    out.extend([
        p("centre layers N", format!("{}", cap.sections.n_centre), ""),
        p("start layers K", format!("{}", cap.sections.n_start), ""),
        p("catenary a", format!("{:.6}", cap.catenary.a), "m"),
        p("mass", format!("{:.2}", cap.path.mass), "kg"),
        p("print time", format!("{:.1}", print_time / 60.0), "min"),
    ]);
    out
}

/// Per-state segment stresses: the printed layers' segments, concatenated in print order, with
/// that state's layer factors (kept by `design_cap`). `None` when the total is too large.
fn state_segment_stresses(cap: &Cap, area: f64) -> Option<Vec<Vec<f64>>> {
    let seg_counts: Vec<usize> = cap
        .sections
        .layers
        .iter()
        .map(|l| l.segment_forces.len())
        .collect();
    let total: usize = cap
        .states
        .iter()
        .map(|s| seg_counts.iter().take(s.layers_printed).sum::<usize>())
        .sum();
    if total > MAX_STATE_STRESS_VALUES {
        return None;
    }
    let per_state = cap
        .states
        .iter()
        .map(|s| {
            let mut out = Vec::new();
            for (layer, d) in cap.sections.layers.iter().zip(&s.factors) {
                out.extend(layer.segment_forces.iter().map(|f| f * d / area));
            }
            out
        })
        .collect();
    Some(per_state)
}

/// Maps a designed cap (plus optional analysis and robot results) to the report input.
/// See the module docs for the mapping.
pub fn report_input(cap: &Cap, extras: &ReportExtras) -> ReportInput {
    let d = &cap.design;
    let areas = cap.areas();
    let normal = v3(&cap.frame.n);
    let final_factors = &cap.final_state.factors;

    let layers: Vec<Layer> = cap
        .sections
        .layers
        .iter()
        .enumerate()
        .map(|(q, l)| {
            let factor = final_factors.get(q).copied().unwrap_or(1.0);
            Layer {
                id: l.id,
                nodes: l.nodes.iter().map(|n| v3(&n.xyz)).collect(),
                segment_stress: l
                    .segment_forces
                    .iter()
                    .map(|f| f * factor / areas.along_layer)
                    .collect(),
                plane_normal: normal,
                bead_width: d.print.layer_width,
                bead_height: d.print.layer_height,
                overhang: if q == 0 {
                    None
                } else {
                    cap.overhangs.get(q).copied()
                },
            }
        })
        .collect();

    // Trails run from the top layer down to the base: `u` is the upper node, `v` the lower.
    let net = &cap.final_state.network;
    let bed_joints: Vec<BedJoint> = cap
        .final_topology
        .trail_edges
        .iter()
        .zip(&cap.final_forces.trail_forces)
        .filter_map(|(e, f)| {
            let upper = net.nodes.get(usize::try_from(e.u).ok()?)?;
            let lower = net.nodes.get(usize::try_from(e.v).ok()?)?;
            Some(BedJoint {
                layer: upper.layer,
                a: v3(&lower.xyz),
                b: v3(&upper.xyz),
                stress: f / areas.bed_joint,
            })
        })
        .collect();

    let print_path = PrintPath {
        points: cap.path.points.iter().map(|p| v3(&p.tip)).collect(),
        tool_axis: cap.path.points.iter().map(|p| v3(&p.axis)).collect(),
        layer: cap.path.points.iter().map(|p| p.layer).collect(),
    };

    let tol = stress_tolerance(cap);
    let mut per_state = state_segment_stresses(cap, areas.along_layer);
    let states: Vec<PrintState> = cap
        .states
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let check = extras.states.get(i);
            PrintState {
                index: s.index,
                progress: s.progress.clamp(0.0, 1.0),
                layers_printed: s.layers_printed,
                blf: check.and_then(|c| c.blf),
                sigma_min: s.forces.max_compression_stress,
                sigma_max: s.forces.max_tension_stress,
                max_overhang: max_overhang(cap, s.layers_printed),
                ok: check.map_or_else(|| state_ok_preliminary(cap, s, tol), |c| c.ok),
                segment_stress: per_state
                    .as_mut()
                    .and_then(|v| v.get_mut(i))
                    .map(std::mem::take),
            }
        })
        .collect();

    let mut input = ReportInput {
        name: d.name.clone(),
        parameters: parameters(cap, extras.plan_end.unwrap_or(cap.path.time)),
        layers,
        bed_joints,
        print_path,
        states,
        constraints: constraint_rows(cap, extras),
        robot: extras.robot.clone(),
        plots: extras
            .plots
            .iter()
            .cloned()
            .chain(corrugation_plot(cap))
            .collect(),
        timeline: Some(timeline(cap, extras)),
        cell: extras.cell.clone(),
        modes: mode_shapes(cap, extras),
        worst_places: Vec::new(),
        quantities: ageing_quantities(cap, extras),
        schedule: extras.schedule.clone(),
        robot_summary: extras.robot_summary.clone(),
    };
    input.worst_places = worst_places(cap, &input);
    input
}

/// The time of each path point: the arrival time of its waypoint in the plan, or (without a
/// plan, or for a point the plan does not list) the time of the point before plus the distance
/// over the print speed.
fn timeline(cap: &Cap, extras: &ReportExtras) -> Timeline {
    let planned: HashMap<(i64, usize), f64> = extras
        .waypoint_times
        .iter()
        .map(|&(l, i, t)| ((l, i), t))
        .collect();
    let speed = cap.design.print.print_speed.max(1e-9);
    let mut point_time = Vec::with_capacity(cap.path.points.len());
    let mut last: Option<(f64, [f64; 3])> = None;
    for p in &cap.path.points {
        let xyz = v3(&p.tip);
        let walked = last.map_or(0.0, |(t, q)| {
            t + ((xyz[0] - q[0]).powi(2) + (xyz[1] - q[1]).powi(2) + (xyz[2] - q[2]).powi(2)).sqrt()
                / speed
        });
        let t = planned
            .get(&(i64::from(p.layer), p.index))
            .copied()
            .unwrap_or(walked)
            .max(last.map_or(0.0, |(t, _)| t));
        point_time.push(t);
        last = Some((t, xyz));
    }
    let end = point_time.last().copied().unwrap_or(0.0);
    Timeline {
        point_time,
        total_time: extras.plan_end.unwrap_or(end).max(end),
    }
}

/// For every bead node (print order), its layer's print index and its index in that layer.
fn bead_index(cap: &Cap) -> (HashMap<i32, usize>, Vec<usize>) {
    let by_id = cap
        .sections
        .layers
        .iter()
        .enumerate()
        .map(|(k, l)| (l.id, k))
        .collect();
    let mut first = Vec::with_capacity(cap.sections.layers.len() + 1);
    let mut n = 0;
    for l in &cap.sections.layers {
        first.push(n);
        n += l.nodes.len();
    }
    first.push(n);
    (by_id, first)
}

/// Global bead node nearest to network node `ni` of `net`, within its layer.
fn nearest_bead(
    cap: &Cap,
    by_id: &HashMap<i32, usize>,
    first: &[usize],
    net: &crate::form::states::Network,
    ni: usize,
) -> Option<usize> {
    let node = net.nodes.get(ni)?;
    let k = *by_id.get(&node.layer)?;
    let layer = cap.sections.layers.get(k)?;
    let (j, _) = layer
        .nodes
        .iter()
        .enumerate()
        .map(|(j, b)| (j, (b.xyz - node.xyz).norm()))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(first.get(k)? + j)
}

/// Mode 1 of every analysed state on the bead nodes of its printed layers (see the module docs).
/// A state whose network cannot be rebuilt is left out (the page then shows the previous mode).
fn mode_shapes(cap: &Cap, extras: &ReportExtras) -> Vec<ModeShape> {
    let (by_id, first) = bead_index(cap);
    let phi = cap.design.print.start_arch_fraction;
    extras
        .modes
        .iter()
        .filter_map(|(q, blf, mode)| {
            let state = cap.states.get(*q)?;
            let net = crate::form::states::build_state(&cap.sections, &cap.frame, phi, state.index)
                .ok()?
                .network;
            let n = *first.get(state.layers_printed)?;
            let mut displacement = vec![[0.0; 3]; n];
            for (ni, u) in mode {
                if let Some(slot) = nearest_bead(cap, &by_id, &first, &net, *ni)
                    .and_then(|b| displacement.get_mut(b))
                {
                    *slot = *u;
                }
            }
            Some(ModeShape {
                state: *q,
                blf: *blf,
                displacement,
            })
        })
        .collect()
}

/// With a time model: the age (min) and the modulus (MPa) of every printed layer in every
/// state, on the run's clock.
fn ageing_quantities(cap: &Cap, extras: &ReportExtras) -> Vec<Quantity> {
    let Some((time, schedule)) = &extras.clock else {
        return Vec::new();
    };
    let ages: Vec<Vec<f64>> = cap
        .states
        .iter()
        .map(|s| schedule.ages(s.layers_printed))
        .collect();
    let moduli = ages
        .iter()
        .map(|a| a.iter().map(|&t| time.modulus(t)).collect())
        .collect();
    vec![
        Quantity {
            key: "layer_age".into(),
            label: "layer age".into(),
            unit: "min".into(),
            to_unit: 1.0 / 60.0,
            per: QuantityPer::Layer,
            diverging: false,
            states: ages,
            note: Some(
                "time since the layer was printed, on the run's clock (as the analysis ages it)"
                    .into(),
            ),
        },
        Quantity {
            key: "layer_modulus".into(),
            label: "layer stiffness E".into(),
            unit: "MPa".into(),
            to_unit: 1e-6,
            per: QuantityPer::Layer,
            diverging: false,
            states: moduli,
            note: Some("Young's modulus of the green layer at its age (the time model)".into()),
        },
    ]
}

/// Where each state-dependent constraint of `input` is worst (see the module docs).
fn worst_places(cap: &Cap, input: &ReportInput) -> Vec<WorstPlace> {
    {
        let phi = cap.design.print.start_arch_fraction;
        let areas = cap.areas();
        let mut places = Vec::new();
        for row in &input.constraints {
            let Some(q) = row.state else { continue };
            let Some(state) = cap.states.get(q) else {
                continue;
            };
            let place = match row.name.as_str() {
                "sigma_min" | "sigma_max" => {
                    let Ok(st) = crate::form::states::build_state(
                        &cap.sections,
                        &cap.frame,
                        phi,
                        state.index,
                    ) else {
                        continue;
                    };
                    let Ok(stresses) = crate::analysis::element_stresses(&st, areas) else {
                        continue;
                    };
                    let pick = if row.name == "sigma_min" {
                        stresses.iter().min_by(|a, b| a.stress.total_cmp(&b.stress))
                    } else {
                        stresses.iter().max_by(|a, b| a.stress.total_cmp(&b.stress))
                    };
                    pick.and_then(|e| {
                        let a = st.network.nodes.get(e.nodes[0])?;
                        let b = st.network.nodes.get(e.nodes[1])?;
                        let m = (a.xyz + b.xyz) * 0.5;
                        Some(WorstPlace {
                            constraint: row.name.clone(),
                            state: Some(q),
                            layer: Some(a.layer.max(b.layer)),
                            position: v3(&m),
                            signed_value: None,
                        })
                    })
                }
                "overhang_max" => cap.sections.layers.get(q).and_then(|l| {
                    let crown = l.nodes.iter().max_by(|a, b| a.xyz.z.total_cmp(&b.xyz.z))?;
                    Some(WorstPlace {
                        constraint: row.name.clone(),
                        state: Some(q),
                        layer: Some(l.id),
                        position: v3(&crown.xyz),
                        signed_value: cap.overhangs.get(q).map(|o| o * 1e3),
                    })
                }),
                "blf_min" => input.modes.iter().find(|m| m.state == q).and_then(|m| {
                    let (b, _) = m
                        .displacement
                        .iter()
                        .enumerate()
                        .map(|(i, d)| (i, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
                        .max_by(|a, b| a.1.total_cmp(&b.1))?;
                    let p = input.layers.iter().flat_map(|l| l.nodes.iter()).nth(b)?;
                    let (_, first) = bead_index(cap);
                    let k = first.iter().rposition(|&f| f <= b)?;
                    Some(WorstPlace {
                        constraint: row.name.clone(),
                        state: Some(q),
                        layer: input.layers.get(k).map(|l| l.id),
                        position: *p,
                        signed_value: None,
                    })
                }),
                _ => None,
            };
            places.extend(place);
        }
        places
    }
}

/// β of every state over the print, with the target β_min (issue 24: where in the print the
/// chance of a collapse is largest). β rather than P_f on the axis: P_f = Φ(−β) spans many
/// decades, and β is what the constraint `beta_min` bounds; the title says how to read P_f.
fn reliability_plot(cap: &Cap, r: &crate::analysis::reliability::Reliability) -> Plot {
    let progress = |i: usize| 100.0 * cap.states.get(i).map_or(0.0, |s| s.progress);
    let beta: Vec<[f64; 2]> = r
        .states
        .iter()
        .filter(|s| s.beta.is_finite())
        .map(|s| [progress(s.index), s.beta])
        .collect();
    let target = match (beta.first(), beta.last()) {
        (Some(a), Some(b)) => vec![[a[0], r.beta_min], [b[0], r.beta_min]],
        _ => Vec::new(),
    };
    Plot {
        title: format!(
            "Reliability index β per state (P_f = Φ(−β); print β {:.2}, P_f {:.2e})",
            r.beta, r.pf
        ),
        x_label: "print progress [%]".into(),
        y_label: "β [-]".into(),
        series: vec![
            Series {
                name: "β of the state".into(),
                points: beta,
            },
            Series {
                name: format!("β_min = {}", r.beta_min),
                points: target,
            },
        ],
    }
}

impl crate::Outcome {
    /// The input of the HTML report: the cap with the analysis, the robot plan, the schedule
    /// and the verdict's robot failures.
    pub fn report_input(&self) -> ReportInput {
        let mut extras = self
            .analysis
            .as_ref()
            .map(extras_from_analysis)
            .unwrap_or_default();
        if let Some(plan) = &self.robot {
            add_robot(&mut extras, plan);
        }
        // A moving base (issue 27): the arm's base follows the base trajectory, frame by frame,
        // as `base_trajectory.csv` has it.
        if let (Some(m), Some(anim)) = (&self.moving, extras.robot.as_mut()) {
            anim.base = anim
                .times
                .iter()
                .map(|&t| {
                    let s = m.plan.trajectory.sample_at(t);
                    [s.base_x, s.base_y, s.base_yaw]
                })
                .collect();
        }
        // The constraint table says whether the plan survives its stated base error (issue 28).
        if let Some(r) = &self.base_tolerance {
            let tol = &self.cap.design.robot.tolerance;
            extras.constraints.push(ConstraintRow {
                name: "base_tolerance".into(),
                bound: Bound::AtMost,
                limit: 0.0,
                worst: r.problems.len() as f64,
                unit: "problems".into(),
                state: None,
                element: Some(if r.ok() {
                    format!(
                        "survives a base up to ±{:.1} mm, ±{:.1}° off (every station, {} points \
                         re-solved)",
                        tol.position * 1e3,
                        tol.yaw_deg,
                        r.waypoints_checked
                    )
                } else {
                    r.problems.first().cloned().unwrap_or_default()
                }),
                pass: r.ok(),
            });
        }
        if let Some(r) = &self.reliability {
            extras.plots.push(reliability_plot(&self.cap, r));
        }
        extras.schedule = Some(crate::output::schedule_report::report_schedule(
            &self.cap,
            self.analysis.as_ref(),
            &self.schedule,
        ));
        extras.clock = self
            .cap
            .design
            .time_model()
            .ok()
            .filter(|t| !t.is_constant())
            .map(|t| (t, self.schedule.clone()));
        report_input(&self.cap, &extras)
    }

    /// The HTML report.
    ///
    /// # Errors
    /// What [`kappe_report::render_html`] rejects (a report input that does not validate).
    pub fn report_html(&self) -> Result<String, kappe_report::ReportError> {
        kappe_report::render_html(&self.report_input())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cheap_cap() -> Cap {
        // 3 centre layers and lh = 15 mm: a few start layers, a fast design.
        let design =
            crate::Design::from_toml_str("[cap]\nlength = 0.05\n[print]\nlayer_height = 0.015\n")
                .unwrap();
        crate::design_cap(&design, crate::Context::default()).unwrap()
    }

    #[test]
    fn a_corrugated_cap_has_its_wave_plot_and_a_smooth_one_none() {
        assert!(corrugation_plot(&cheap_cap()).is_none());
        let design = crate::Design::from_toml_str(
            "[cap]\nlength = 0.2\n[print]\nlayer_height = 0.015\n[constraints]\n\
             overhang_max = 0.05\n[cap.corrugation]\namplitude = 0.03\nwavelength = 0.15\n",
        )
        .unwrap();
        let cap = crate::design_cap(&design, crate::Context::default()).unwrap();
        let input = report_input(&cap, &ReportExtras::default());
        input.validate().unwrap();
        let plot = input
            .plots
            .iter()
            .find(|p| p.title.starts_with("Corrugation"))
            .expect("the wave plot");
        let wave = &plot.series[0].points;
        assert_eq!(wave.len(), cap.sections.n_centre);
        // The crowns follow rise + a·sin(2π·y/λ) (a = 30 mm, λ = 0.15 m; crest at y = 37.5 mm,
        // trough at 112.5 mm, both inside the 0.2 m centre section). Consecutive layers are
        // lh / cos(tilt) ≤ 20 mm apart (tilts up to 41°), so a crown lies within 10 mm of each
        // extreme: the spread is at least 2·30·cos(π·0.01/0.15) = 58.7 mm and at most 60 mm.
        let (lo, hi) = wave
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[1]), h.max(p[1]))
            });
        assert!(
            hi - lo >= 48.0 && hi - lo <= 60.0 + 1e-6,
            "spread {} mm",
            hi - lo
        );
    }

    #[test]
    fn input_validates_and_matches_the_cap() {
        let cap = cheap_cap();
        let input = report_input(&cap, &ReportExtras::default());
        input.validate().unwrap();
        assert_eq!(input.layers.len(), cap.sections.layers.len());
        assert_eq!(input.states.len(), cap.states.len());
        assert_eq!(input.print_path.points.len(), cap.path.points.len());
        assert_eq!(input.bed_joints.len(), cap.final_topology.trail_edges.len());
        // The last state is the final state: its per-state stresses equal the layers' ones.
        let last = input.states.last().unwrap();
        let from_layers: Vec<f64> = input
            .layers
            .iter()
            .flat_map(|l| l.segment_stress.iter().copied())
            .collect();
        assert_eq!(last.segment_stress.as_deref(), Some(from_layers.as_slice()));
        // The most compressive arch stress of the final state cannot be below the state's
        // σ_min, which also covers the bed joints.
        let min_arch = from_layers.iter().copied().fold(0.0, f64::min);
        assert!(min_arch >= last.sigma_min);
    }

    #[test]
    fn analysis_rows_replace_and_extend() {
        let cap = cheap_cap();
        let extras = ReportExtras {
            states: vec![
                StateCheck {
                    blf: Some(3.0),
                    ok: true
                };
                cap.states.len()
            ],
            constraints: vec![ConstraintRow {
                name: "blf".into(),
                bound: Bound::AtLeast,
                limit: 1.0,
                worst: 3.0,
                unit: String::new(),
                state: Some(0),
                element: None,
                pass: true,
            }],
            ..ReportExtras::default()
        };
        let input = report_input(&cap, &extras);
        let names: Vec<&str> = input.constraints.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["sigma_min", "sigma_max", "overhang_max", "blf"]);
        assert!(input.states.iter().all(|s| s.blf == Some(3.0) && s.ok));
    }

    #[test]
    fn the_analysis_replaces_the_preliminary_rows_and_agrees_with_them() {
        let cap = cheap_cap();
        let options = crate::analysis::AnalysisOptions {
            // Stresses and overhang only: the FE buckling solve is tested in crates/kappe.
            buckling: false,
            ..Default::default()
        };
        let analysis =
            crate::analysis::analyze(&cap, &options, crate::analysis::Request::default()).unwrap();
        let extras = extras_from_analysis(&analysis);
        assert_eq!(extras.states.len(), cap.states.len());
        let input = report_input(&cap, &extras);
        input.validate().unwrap();
        // blf_min was checked in no state, so it has no row; the other three replace the
        // preliminary rows and must agree with them in verdict, limit and worst value.
        let pre: Vec<ConstraintRow> = preliminary_constraints(&cap)
            .iter()
            .filter_map(row_of)
            .collect();
        assert_eq!(input.constraints.len(), pre.len());
        for (a, p) in input.constraints.iter().zip(&pre) {
            assert_eq!(
                (a.name.as_str(), a.pass, a.bound),
                (p.name.as_str(), p.pass, p.bound)
            );
            assert_eq!(a.unit, p.unit);
            assert!(
                (a.limit - p.limit).abs() <= 1e-12 * p.limit.abs().max(1.0),
                "{a:?} {p:?}"
            );
            // Both take the extreme over all states of the same force pass: equal to roundoff.
            assert!(
                (a.worst - p.worst).abs() <= 1e-9 * p.worst.abs().max(1e-6),
                "{a:?} {p:?}"
            );
        }
        for (s, p) in input
            .states
            .iter()
            .zip(&report_input(&cap, &ReportExtras::default()).states)
        {
            assert_eq!(s.ok, p.ok, "state {}", s.index);
        }
    }

    #[test]
    fn modes_places_and_timeline_follow_the_analysis() {
        let cap = cheap_cap();
        let options = crate::analysis::AnalysisOptions::default();
        let analysis =
            crate::analysis::analyze(&cap, &options, crate::analysis::Request::default()).unwrap();
        let extras = extras_from_analysis(&analysis);
        let input = report_input(&cap, &extras);
        input.validate().unwrap();

        // Every analysed state with a factor has its mode on the bead nodes; not all zero.
        let analysed = analysis.states.iter().filter(|s| s.blf.is_some()).count();
        assert!(analysed > 0);
        assert_eq!(input.modes.len(), analysed);
        // The mapping copies translations: the largest one on the bead nodes is the largest of
        // the shell mode (every shell node of a row is a bead node of its layer).
        let norm = |d: &[f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        for m in &input.modes {
            let bead = m.displacement.iter().map(norm).fold(0.0, f64::max);
            let shell = analysis.states[m.state]
                .mode
                .iter()
                .map(|(_, d)| norm(d))
                .fold(0.0, f64::max);
            assert!(shell > 0.0);
            assert!((bead - shell).abs() <= 1e-12 * shell, "{bead} vs {shell}");
        }

        // The BLF place is the peak of the governing mode: in the layer where the analysis
        // says mode 1 peaks (its element text), on a bead node of that layer.
        let row = input
            .constraints
            .iter()
            .find(|c| c.name == "blf_min")
            .unwrap();
        let place = input
            .worst_places
            .iter()
            .find(|w| w.constraint == "blf_min")
            .unwrap();
        let layer = place.layer.unwrap();
        let text = row.element.as_deref().unwrap();
        assert!(
            text.contains(&format!("layer {layer} ")),
            "{text} vs layer {layer}"
        );
        let bead = input.layers.iter().find(|l| l.id == layer).unwrap();
        assert!(bead.nodes.contains(&place.position));

        // σ_min's place is the midpoint of an element of the worst state in the named layer:
        // within half a path sampling step (20 mm) plus the bed joint's length of a bead node.
        let row = input
            .constraints
            .iter()
            .find(|c| c.name == "sigma_min")
            .unwrap();
        let place = input
            .worst_places
            .iter()
            .find(|w| w.constraint == "sigma_min")
            .unwrap();
        assert_eq!(place.state, row.state);
        let near = input
            .layers
            .iter()
            .flat_map(|l| l.nodes.iter())
            .map(|p| {
                ((p[0] - place.position[0]).powi(2)
                    + (p[1] - place.position[1]).powi(2)
                    + (p[2] - place.position[2]).powi(2))
                .sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(near <= 0.02, "{near}");

        // Without a plan the timeline walks the path at the print speed: Δt = |Δx| / v.
        let t = input.timeline.as_ref().unwrap();
        let v = cap.design.print.print_speed;
        for (i, w) in input.print_path.points.windows(2).enumerate() {
            let d = ((w[1][0] - w[0][0]).powi(2)
                + (w[1][1] - w[0][1]).powi(2)
                + (w[1][2] - w[0][2]).powi(2))
            .sqrt();
            let dt = t.point_time[i + 1] - t.point_time[i];
            // Sums of f64 times of ~100 s: 1e-9 s is far above their round-off.
            assert!((dt - d / v).abs() < 1e-9, "{dt} vs {}", d / v);
        }
    }
}
