//! A ceiling: a room of several parallel bays between beams, each bay a cap with its ends
//! (issue 15). One design file holds the room: `[ceiling]` (clear length between the end walls,
//! the ends of every bay), one `[[bay]]` table per bay (span, optional rise and tilt; spans may
//! differ) and the usual `[material]`, `[print]`, `[constraints]`, `[robot]`, `[analysis]` tables
//! shared by every bay. [`run_ceiling`] designs, analyses and plans every bay with
//! [`crate::run`] and sums the room up ([`CeilingOutcome::summary`], [`CeilingOutcome::index_html`]).
//!
//! **Ends** ([`BayEnds`]; the physics is in [`crate::form::ends`]). The end walls are vertical at
//! y = 0 and y = L. An end-wall cap leans its layer 0 on a bearing face in the plane of layer −1;
//! that plane leans back by `Cr·tan(am)` at the crown, so the bearing face is a wedge (cast or
//! printed) against the wall, and layer 0's feet stand `Cr·tan(am) + lh/cos(am)` in front of
//! the wall. The far end of a bay is free (no thrust); its wedge-shaped gap to a vertical wall or
//! to the other half is a non-structural closure of `Cr·tan(am)` at the crown per side.
//! - `both_walls` (default): the bay is printed from both end walls toward the middle, two
//!   mirrored halves of centre length `L/2 − Cr·tan(am) − lh/cos(am)`, each leaning on its wall.
//!   Each half stands on its own until the closure, so each is designed alone; by symmetry one
//!   analysis serves both halves, and the robot plans both (the second half mirrored). The stack
//!   thrust, and with it the bed-joint stress γ·Cl·sin(am), is that of half the bay.
//! - `one_wall`: one cap from the wall at y = 0, centre length `L − Cr·tan(am) − lh/cos(am)`.
//! - `start_section`: today's cap (method.md §6) with centre length `L`; its start section
//!   reaches beyond y = 0 (not checked against the wall).
//!
//! Bays sit side by side across x, a beam of `robot.beams.width` between neighbours; the
//! summary gives every bay's centre line.
//!
//! **A large ceiling on a cluster.** Bays are independent designs: [`CeilingDesign::bay_designs`]
//! gives one [`Design`] per bay (one half for `both_walls`), each a complete single-cap design
//! file (`Design::to_toml_string`). Spread them with the study path, one bay per task: write the
//! bays as a `kappe study` list (or call `kappe.study` / `kappe.design` from Python and map the bay
//! designs over a Dask cluster, one design per task), then gather the per-bay `summary.json`s; the
//! ceiling summary is the per-bay rows of [`BayOutcome::summary`] summed (mass, volume, times).
//! Within one bay the states already run in parallel on the task's cores.

use std::ops::ControlFlow;

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use crate::analysis::AnalysisOptions;
use crate::form::ends::EndKind;
use crate::input::design::{ConstraintSpec, Design, MaterialSpec, PrintSpec, RobotSpec};
use crate::input::error::DesignError;
use crate::output::{OutputError, OutputFile, moving_plan_files, plan_files};
use crate::run::{Options, Outcome, Progress};

/// The commented example ceiling that `kappe init --kind ceiling` writes: three bays of 1.2 m
/// span, 3 m long between end walls.
pub const EXAMPLE_TOML: &str = include_str!("ceiling_example.toml");

/// How every bay meets the end walls (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BayEnds {
    /// Two mirrored halves printed from both end walls toward the middle.
    #[default]
    BothWalls,
    /// One cap leaning on the wall at y = 0.
    OneWall,
    /// The start section of method.md §6.
    StartSection,
}

impl BayEnds {
    /// How the page and the terminal say it (the design file's words are `both_walls`, …).
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Self::BothWalls => "two halves printed from both end walls",
            Self::OneWall => "one cap leaning on the wall at y = 0",
            Self::StartSection => "a start section on the bed",
        }
    }
}

/// The room.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CeilingSpec {
    /// Clear length between the end walls, m.
    pub length: f64,
    /// How every bay meets the end walls.
    pub ends: BayEnds,
    /// Rise of a bay without its own `rise`, as a fraction of its span.
    pub rise_ratio: f64,
    /// Layer tilt of a bay without its own `tilt_deg`, degrees.
    pub tilt_deg: f64,
}

impl Default for CeilingSpec {
    fn default() -> Self {
        CeilingSpec {
            length: 3.0,
            ends: BayEnds::BothWalls,
            rise_ratio: 0.25,
            tilt_deg: 25.0,
        }
    }
}

/// One bay between two beams.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaySpec {
    /// A name for reports (default `bay N`).
    #[serde(default)]
    pub name: Option<String>,
    /// Clear span between the beams, m.
    pub span: f64,
    /// Crown rise, m (default `rise_ratio · span`).
    #[serde(default)]
    pub rise: Option<f64>,
    /// Layer tilt, degrees (default the ceiling's).
    #[serde(default)]
    pub tilt_deg: Option<f64>,
}

/// A ceiling design file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CeilingDesign {
    /// A name for reports.
    pub name: String,
    /// The room.
    pub ceiling: CeilingSpec,
    /// The bays, across x.
    pub bay: Vec<BaySpec>,
    /// Shared by every bay.
    pub material: MaterialSpec,
    /// Shared by every bay.
    pub print: PrintSpec,
    /// Shared by every bay.
    pub constraints: ConstraintSpec,
    /// Shared by every bay.
    pub robot: RobotSpec,
    /// Shared by every bay.
    pub analysis: AnalysisOptions,
    /// Uncertain inputs (issue 24), keyed by the design file's names as in a cap design: every
    /// bay's design gets the same table, so each bay reports its own reliability, and the room
    /// its bounds ([`ceiling_summary`]). Checked per bay like a design's (unknown names, bad
    /// distributions: named errors, with the bay).
    pub uncertainty: Option<crate::input::uncertainty::UncertaintyTable>,
}

impl Default for CeilingDesign {
    fn default() -> Self {
        let d = Design::default();
        CeilingDesign {
            name: "ceiling".into(),
            ceiling: CeilingSpec::default(),
            bay: Vec::new(),
            material: d.material,
            print: d.print,
            constraints: d.constraints,
            robot: d.robot,
            analysis: d.analysis,
            uncertainty: None,
        }
    }
}

/// Whether a TOML text is a ceiling (it has a `[ceiling]` table or `[[bay]]` tables) rather
/// than a single cap.
pub fn is_ceiling_toml(text: &str) -> bool {
    toml::from_str::<toml::Table>(text)
        .is_ok_and(|t| t.contains_key("ceiling") || t.contains_key("bay"))
}

impl CeilingDesign {
    /// Parse and validate a ceiling file (every bay's design is validated).
    pub fn from_toml_str(text: &str) -> Result<CeilingDesign, DesignError> {
        let c: CeilingDesign = crate::input::design::parse_toml(text)?;
        c.bay_designs()?;
        Ok(c)
    }

    /// The design of every bay (one half for `both_walls`), validated.
    pub fn bay_designs(&self) -> Result<Vec<Design>, DesignError> {
        let c = &self.ceiling;
        let bad = |field: &'static str, value: f64, allowed: &str| DesignError::Invalid {
            field,
            value: format!("{value}"),
            allowed: allowed.to_string(),
        };
        if self.bay.is_empty() {
            return Err(bad("bay", 0.0, "allowed: at least one [[bay]] table"));
        }
        if !(c.length.is_finite() && c.length > 0.0 && c.length <= 100.0) {
            return Err(bad(
                "ceiling.length",
                c.length,
                "allowed: 0 < length ≤ 100 m",
            ));
        }
        if !(c.rise_ratio.is_finite() && (0.05..=1.0).contains(&c.rise_ratio)) {
            return Err(bad(
                "ceiling.rise_ratio",
                c.rise_ratio,
                "allowed: 0.05 ≤ rise/span ≤ 1",
            ));
        }
        let mut out = Vec::with_capacity(self.bay.len());
        for (i, b) in self.bay.iter().enumerate() {
            let mut d = Design {
                name: b.name.clone().unwrap_or_else(|| format!("bay {}", i + 1)),
                material: self.material.clone(),
                print: self.print.clone(),
                constraints: self.constraints.clone(),
                robot: self.robot.clone(),
                analysis: self.analysis.clone(),
                uncertainty: self.uncertainty.clone(),
                ..Design::default()
            };
            d.cap.span = b.span;
            d.cap.rise = b.rise.unwrap_or(c.rise_ratio * b.span);
            d.cap.tilt_deg = b.tilt_deg.unwrap_or(c.tilt_deg);
            let am = d.tilt();
            let setback = d.cap.rise * am.tan() + d.print.layer_height / am.cos();
            let (end, length) = match c.ends {
                BayEnds::BothWalls => (EndKind::EndWall, 0.5 * c.length - setback),
                BayEnds::OneWall => (EndKind::EndWall, c.length - setback),
                BayEnds::StartSection => (EndKind::StartSection, c.length),
            };
            d.cap.end = end;
            d.cap.length = length;
            if length.is_nan() || length <= 0.0 {
                return Err(DesignError::Invalid {
                    field: "ceiling.length",
                    value: format!("{}", c.length),
                    allowed: format!(
                        "bay {}: the wall wedges (rise·tan(tilt) + lh/cos(tilt) = {setback:.3} m per wall) leave no room for layers",
                        i + 1
                    ),
                });
            }
            d.validate().map_err(|e| match e {
                DesignError::Invalid {
                    field,
                    value,
                    allowed,
                } => DesignError::Invalid {
                    field,
                    value,
                    allowed: format!("bay {} ({}): {allowed}", i + 1, d.name),
                },
                e => e,
            })?;
            out.push(d);
        }
        Ok(out)
    }
}

/// One designed bay.
#[derive(Debug)]
pub struct BayOutcome {
    /// The bay's design (one half for `both_walls`).
    pub design: Design,
    /// Centre line of the bay across the room, m (x of its mid-span).
    pub x_centre: f64,
    /// Halves printed (2 for `both_walls`, else 1); they are mirror images.
    pub halves: usize,
    /// Design, analysis, plan of the (first) half.
    pub outcome: Outcome,
    /// The robot plan of the mirrored second half (`both_walls` with the robot on).
    pub mirror_plan: Option<Result<kappe_robot::Plan, kappe_robot::RobotError>>,
    /// The base-pose tolerance check of the mirrored half's plan (`[robot.tolerance]`).
    pub mirror_tolerance: Option<kappe_robot::tolerance::ToleranceReport>,
    /// With a moving base (`[robot.base] mode = "moving"`, issue 27), the mirrored half's moving
    /// plan; `mirror_plan` then holds its arm plan (as `Outcome::robot` does for the first half).
    pub mirror_moving: Option<kappe_robot::MovingPlan>,
}

/// The whole ceiling.
#[derive(Debug)]
pub struct CeilingOutcome {
    /// The file.
    pub design: CeilingDesign,
    /// The bays, across x.
    pub bays: Vec<BayOutcome>,
    /// Every bay passes and every plan asked for exists.
    pub ok: bool,
}

/// Design, analyse and plan every bay of `ceiling` (bays one after another; each bay's states
/// run in parallel). `on_progress(bay, progress)` hears every bay's progress.
///
/// The same as [`run_bay`] for every bay, then [`CeilingOutcome::from_bays`]; a cluster runs
/// one [`run_bay`] per task instead (the Python package's `kappe.ceiling(..., client=...)`).
///
/// # Errors
/// An invalid bay, or what [`crate::run`] returns for one.
pub fn run_ceiling(
    ceiling: &CeilingDesign,
    options: &Options,
    on_progress: &(dyn Fn(usize, Progress) -> ControlFlow<()> + Sync),
) -> Result<CeilingOutcome, DesignError> {
    let n = ceiling.bay_designs()?.len();
    let bays = (0..n)
        .map(|i| run_bay(ceiling, i, options, &|p| on_progress(i, p)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(CeilingOutcome::from_bays(ceiling, bays))
}

/// Design, analyse and plan bay `index` (0-based, across x) of `ceiling`, with the mirrored
/// plan of its second half for `both_walls`. Independent of the other bays.
///
/// # Errors
/// `index` beyond the bays ([`DesignError::Invalid`]), an invalid bay, or what [`crate::run`]
/// returns for it.
pub fn run_bay(
    ceiling: &CeilingDesign,
    index: usize,
    options: &Options,
    on_progress: crate::run::OnProgress<'_>,
) -> Result<BayOutcome, DesignError> {
    let designs = ceiling.bay_designs()?;
    let n = designs.len();
    let beam = ceiling.robot.beams.width;
    // The bays stand side by side across x, a beam between neighbours.
    let x_start: f64 = designs.iter().take(index).map(|d| d.cap.span + beam).sum();
    let Some(d) = designs.into_iter().nth(index) else {
        return Err(DesignError::Invalid {
            field: "bay",
            value: index.to_string(),
            allowed: format!("a bay index 0..{n}"),
        });
    };
    let x_centre = x_start + 0.5 * d.cap.span;
    let outcome = crate::run::run(&d, options, on_progress)?;
    let halves = if ceiling.ceiling.ends == BayEnds::BothWalls {
        2
    } else {
        1
    };
    let mirrored = halves == 2 && options.robot && d.robot.enabled;
    let (mirror_plan, mirror_moving) = match (&d.robot.base, mirrored) {
        (_, false) => (None, None),
        (kappe_robot::BaseMode::Stations, true) => (Some(plan_mirrored(&outcome.cap)), None),
        // The second half on the first half's clock: its layers wait what the first half's do.
        (kappe_robot::BaseMode::Moving(base), true) => {
            let waits: Option<Vec<kappe_robot::LayerWait>> = outcome
                .robot
                .as_ref()
                .and_then(|p| p.as_ref().ok())
                .map(|p| {
                    kappe_robot::layer_times(p)
                        .iter()
                        .map(|t| kappe_robot::LayerWait {
                            layer: t.layer,
                            wait: t.wait,
                        })
                        .collect()
                });
            match plan_mirrored_moving(&outcome.cap, base, waits.as_deref()) {
                Ok(mp) => (Some(Ok(mp.plan.clone())), Some(mp)),
                Err(e) => (Some(Err(e)), None),
            }
        }
    };
    let tol = &d.robot.tolerance;
    let mirror_tolerance = match (&mirror_plan, &mirror_moving) {
        (Some(Ok(_)), Some(mp)) if tol.check => Some(kappe_robot::check_moving_tolerance(
            mp,
            &tol.base_tolerance(),
        )),
        (Some(Ok(plan)), None) if tol.check => Some(kappe_robot::tolerance::check_base_tolerance(
            plan,
            &tol.base_tolerance(),
        )),
        _ => None,
    };
    Ok(BayOutcome {
        design: d,
        x_centre,
        halves,
        outcome,
        mirror_plan,
        mirror_tolerance,
        mirror_moving,
    })
}

impl CeilingOutcome {
    /// The ceiling of `bays` (in order, as [`run_bay`] returns them).
    pub fn from_bays(ceiling: &CeilingDesign, bays: Vec<BayOutcome>) -> Self {
        let ok = bays.iter().all(|b| {
            b.outcome.verdict.ok
                && b.mirror_plan.as_ref().is_none_or(|p| p.is_ok())
                && !(b.design.robot.tolerance.verdict
                    && b.mirror_tolerance.as_ref().is_some_and(|t| !t.ok()))
        });
        CeilingOutcome {
            design: ceiling.clone(),
            bays,
            ok,
        }
    }
}

/// Plan the mirror image (y → −y) of a cap's print: the second half of a `both_walls` bay in its
/// own frame. The base search is mirrored too (in front of the printing front, which now
/// advances toward −y, the base heading reflected).
pub fn plan_mirrored(
    cap: &crate::form::cap::Cap,
) -> Result<kappe_robot::Plan, kappe_robot::RobotError> {
    let (layers, setup, opts) = mirrored_inputs(cap);
    kappe_robot::plan_print(&layers, &setup, &opts)
}

/// [`plan_mirrored`] with the base moving while it prints (issue 27): `kappe_robot::plan_moving`
/// on the mirrored layers and cell. The moving planner takes the front advancing toward −y
/// itself (the base's along-bay position and heading reflected, `kappe_robot::moving`).
pub fn plan_mirrored_moving(
    cap: &crate::form::cap::Cap,
    base: &kappe_robot::MovingBase,
    waits: Option<&[kappe_robot::LayerWait]>,
) -> Result<kappe_robot::MovingPlan, kappe_robot::RobotError> {
    let (layers, setup, opts) = mirrored_inputs(cap);
    kappe_robot::plan_moving(&layers, &setup, &opts, base, waits)
}

/// The layers, cell and options of a cap's print mirrored y → −y.
fn mirrored_inputs(
    cap: &crate::form::cap::Cap,
) -> (
    Vec<kappe_robot::setup::PrintLayer>,
    kappe_robot::setup::RobotSetup,
    kappe_robot::setup::PlanOptions,
) {
    use kappe_robot::setup::BasePlacement;
    let (mut setup, opts) = crate::robot_plan::robot_inputs(cap);
    let mut layers = crate::robot_plan::print_layers(&cap.path);
    for l in &mut layers {
        for p in &mut l.points {
            p.position[1] = -p.position[1];
            p.axis[1] = -p.axis[1];
        }
    }
    for o in &mut setup.obstacles {
        if let kappe_robot::collision::Obstacle::Box { center, yaw, .. } = o {
            center[1] = -center[1];
            *yaw = -*yaw;
        }
    }
    let (ylo, yhi) = cap
        .path
        .points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.tip.y), b.max(p.tip.y))
        });
    match &mut setup.base {
        BasePlacement::Search(s) => {
            let y = s.y.unwrap_or([ylo + 0.6, yhi + 0.8]);
            s.y = Some([-y[1], -y[0]]);
            // A heading θ reflected in the x–z plane is −θ (270° → 90°: facing +y).
            for a in &mut s.yaw_deg {
                *a = -*a;
            }
        }
        BasePlacement::Fixed { world_from_base } => {
            // Mirror the pose and keep it right-handed: reflect y, then turn the base by 180°
            // about its own z so x and y both flip (a proper rotation).
            let m = kappe_robot::Iso::from_mat4_unchecked(world_from_base);
            let x = m.r.x_axis;
            let yaw = (-x.y).atan2(x.x);
            *world_from_base = kappe_robot::Iso::translation(m.t.x, -m.t.y, m.t.z)
                .mul(&kappe_robot::Iso::rot_z(yaw))
                .to_mat4();
        }
    }
    (layers, setup, opts)
}

impl BayOutcome {
    /// The constraint with the largest utilisation (value / limit, or limit / value for the
    /// BLF): name, utilisation, where, pass.
    pub fn worst_constraint(&self) -> Option<Value> {
        let a = self.outcome.analysis.as_ref()?;
        a.constraints
            .iter()
            .filter_map(|c| {
                let w = c.worst?;
                let u = match c.name {
                    "blf_min" if w > 0.0 => c.limit / w,
                    "blf_min" => f64::INFINITY,
                    "sigma_max" if c.limit <= 0.0 => {
                        if c.pass {
                            0.0
                        } else {
                            f64::INFINITY
                        }
                    }
                    _ if c.limit != 0.0 => w / c.limit,
                    _ => 0.0,
                };
                Some((u, c))
            })
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(u, c)| {
                json!({
                    "name": c.name,
                    "utilisation": if u.is_finite() { json!(u) } else { Value::Null },
                    "worst": c.worst,
                    "limit": c.limit,
                    "state": c.state,
                    "element": c.element,
                    "pass": c.pass,
                })
            })
    }

    /// The bay's row of the ceiling summary.
    pub fn summary(&self) -> Value {
        let cap = &self.outcome.cap;
        let h = self.halves as f64;
        let plans: Vec<&kappe_robot::Plan> = self
            .outcome
            .robot
            .iter()
            .chain(self.mirror_plan.iter())
            .filter_map(|p| p.as_ref().ok())
            .collect();
        let drive = kappe_robot::stations::DriveSpec::default();
        let schedules: Vec<Value> = plans
            .iter()
            .filter_map(|p| kappe_robot::stations::station_schedule(p, &drive).ok())
            .map(|s| json!(s))
            .collect();
        let robot_time: f64 = plans.iter().map(|p| p.total_time).sum();
        // The base-pose tolerance of each planned half (issue 15, `[robot.tolerance]`).
        let tolerance: Vec<Value> = self
            .outcome
            .base_tolerance
            .iter()
            .chain(self.mirror_tolerance.iter())
            .map(|t| {
                json!({
                    "ok": t.ok(),
                    "min_clearance_m": t.min_clearance,
                    "problems": t.problems.len(),
                    "first_problem": t.problems.first(),
                })
            })
            .collect();
        let tolerance_fails = self.design.robot.tolerance.verdict
            && tolerance.iter().any(|t| t["ok"] == json!(false));
        let stations: usize = plans.iter().map(|p| p.stations.len()).sum();
        let relocation: f64 = schedules
            .iter()
            .filter_map(|s| s["relocation_time"].as_f64())
            .sum();
        let failures: Vec<String> = self
            .outcome
            .robot
            .iter()
            .chain(self.mirror_plan.iter())
            .filter_map(|p| p.as_ref().err().map(|e| e.to_string()))
            .collect();
        json!({
            "name": self.design.name,
            "span_m": self.design.cap.span,
            "rise_m": self.design.cap.rise,
            "tilt_deg": self.design.cap.tilt_deg,
            "x_centre_m": self.x_centre,
            "halves": self.halves,
            "centre_length_per_half_m": self.design.cap.length,
            "layers": cap.sections.layers.len() * self.halves,
            "volume_m3": cap.path.volume * h,
            "mass_kg": cap.path.mass * h,
            "print_time_s": cap.path.time * h,
            "robot": {
                "planned": !plans.is_empty(),
                "stations": stations,
                "time_s": robot_time,
                "relocation_time_s": relocation,
                "schedules": schedules,
                "failures": failures,
                "base_tolerance": tolerance,
            },
            "wall_load": crate::form::ends::cap_wall_load(cap).map(|w| json!({
                "per_wall_total_n": w.load.total,
                "line_load_n_per_m": w.load.line_load,
                "max_column_force_n": w.max_column_force_n,
                "walls": self.halves,
            })),
            "closure_gap_m": (self.halves == 2).then(|| 2.0 * crate::form::ends::far_end_gap(self.design.cap.rise, self.design.tilt())),
            "worst_constraint": self.worst_constraint(),
            "min_blf": self.outcome.min_blf(),
            // The bay's reliability under the ceiling's [uncertainty] (its summary.json has
            // every state's): FORM's and SORM's β and P_f of the bay's print (one half: the
            // mirrored half is the same model).
            "reliability": self.outcome.reliability.as_ref().map(|r| json!({
                "beta": r.beta,
                "pf": r.pf,
                "beta_sorm": r.sorm.as_ref().map(|s| s.beta),
                "pf_sorm": r.sorm.as_ref().map(|s| s.pf),
                "governing_state": r.governing_state,
                "governing_check": r.governing_check,
            })),
            "ok": self.outcome.verdict.ok && failures.is_empty() && !tolerance_fails,
        })
    }
}

/// `ceiling.json` from the bays' rows ([`BayOutcome::summary`], in order): the room, every
/// bay's row and the totals. The ceiling passes when every bay does. A cluster that ran one
/// [`run_bay`] per task assembles the room with this.
pub fn ceiling_summary(design: &CeilingDesign, bays: Vec<Value>) -> Value {
    let sum = |k: &str| bays.iter().filter_map(|b| b[k].as_f64()).sum::<f64>();
    let robot_sum = |k: &str| {
        bays.iter()
            .filter_map(|b| b["robot"][k].as_f64())
            .sum::<f64>()
    };
    let ok = bays.iter().all(|b| b["ok"].as_bool() == Some(true));
    json!({
        "reliability": room_reliability(&bays),
        "format": "kappe.ceiling.summary",
        "version": 1,
        "name": design.name,
        "length_m": design.ceiling.length,
        "ends": design.ceiling.ends,
        "total": {
            "volume_m3": sum("volume_m3"),
            "mass_kg": sum("mass_kg"),
            "print_time_s": sum("print_time_s"),
            "robot_time_s": robot_sum("time_s"),
            "relocation_time_s": robot_sum("relocation_time_s"),
        },
        "bays": bays,
        "ok": ok,
    })
}

/// The room's probability of failure from its bays' (rows of [`BayOutcome::summary`] with a
/// `reliability`; `None` when no bay has one): the room fails when any bay's print fails, so
/// P_room lies between the largest bay's P_f and the sum of every printed half's (Boole's
/// bounds: they hold whatever the correlation between the bays, which share the uncertain
/// material of one mix; the exact union would need every bay's components in one system). Per
/// estimate: FORM's `pf` and SORM's `pf_sorm` (SORM's where every bay has one). A bay printed
/// as two halves counts twice in the sum (two prints of the same model).
fn room_reliability(bays: &[Value]) -> Option<Value> {
    let rows: Vec<&Value> = bays
        .iter()
        .filter(|b| b["reliability"].is_object())
        .collect();
    if rows.is_empty() {
        return None;
    }
    let bounds = |key: &str| -> Option<[f64; 2]> {
        let mut lo = 0.0f64;
        let mut hi = 0.0f64;
        for b in &rows {
            let p = b["reliability"][key].as_f64()?;
            let halves = b["halves"].as_f64().unwrap_or(1.0);
            lo = lo.max(p);
            hi += halves * p;
        }
        Some([lo, hi.min(1.0)])
    };
    Some(json!({
        "bays_with_reliability": rows.len(),
        "pf_bounds": bounds("pf"),
        "pf_sorm_bounds": bounds("pf_sorm"),
    }))
}

impl CeilingOutcome {
    /// `ceiling.json`: the room, every bay's row and the totals ([`ceiling_summary`]).
    pub fn summary(&self) -> Value {
        ceiling_summary(
            &self.design,
            self.bays.iter().map(BayOutcome::summary).collect(),
        )
    }

    /// Every file of the ceiling's output directory: `ceiling.json`, `index.html` and every
    /// bay's [`BayOutcome::files`] under `bay_N/`.
    ///
    /// # Errors
    /// As [`BayOutcome::files`].
    pub fn files(&self, allow_fail: bool) -> Result<Vec<OutputFile>, OutputError> {
        let summary = self.summary();
        let text = serde_json::to_vec_pretty(&summary)
            .map_err(|e| OutputError::Produce(format!("cannot write ceiling.json: {e}")))?;
        let mut out = vec![
            OutputFile::new("ceiling.json", text),
            OutputFile::new("index.html", index_html(&self.design, &summary)),
        ];
        for (i, bay) in self.bays.iter().enumerate() {
            let dir = format!("bay_{}", i + 1);
            out.extend(bay.files(allow_fail)?.into_iter().map(|f| f.under(&dir)));
        }
        Ok(out)
    }

    /// The lines `kappe design ROOM.toml` prints: the bays and their verdicts; `out` is the
    /// output directory it names.
    pub fn table(&self, out: &std::path::Path) -> String {
        let mut t = format!(
            "Kappe ceiling: {} bay(s); wrote {}/{{ceiling.json, index.html, bay_N/}}\n",
            self.bays.len(),
            out.display()
        );
        // The small result table (issue 28): per bay its verdict, the governing check, the
        // lowest BLF, mass and print time, so the terminal answers "which bay, and why".
        t.push_str(&format!(
            "  {:<4} {:>8} {:<22} {:<7} {:<16} {:>9} {:>10} {:>10}\n",
            "bay",
            "span [m]",
            "printed as",
            "verdict",
            "governing check",
            "min BLF",
            "mass [kg]",
            "time [min]"
        ));
        // Every bay's row once: the table's columns and the room's reliability line below.
        let rows: Vec<Value> = self.bays.iter().map(BayOutcome::summary).collect();
        for (i, (bay, row)) in self.bays.iter().zip(&rows).enumerate() {
            let governing = row["worst_constraint"]["name"].as_str().unwrap_or("-");
            t.push_str(&format!(
                "  {:<4} {:>8.3} {:<22} {:<7} {:<16} {:>9} {:>10.1} {:>10.1}\n",
                i + 1,
                bay.design.cap.span,
                if bay.halves == 2 {
                    "two mirrored halves"
                } else {
                    "one piece"
                },
                if row["ok"] == json!(true) {
                    "passes"
                } else {
                    "FAILS"
                },
                governing,
                bay.outcome
                    .min_blf()
                    .map_or("-".to_string(), |b| format!("{b:.2}")),
                row["mass_kg"].as_f64().unwrap_or(0.0),
                row["robot"]["time_s"]
                    .as_f64()
                    .filter(|t| *t > 0.0)
                    .or(row["print_time_s"].as_f64())
                    .unwrap_or(0.0)
                    / 60.0
            ));
        }
        // The room's chance of failure in one line (issue 24), when [uncertainty] is given.
        let r = room_reliability(&rows).unwrap_or(Value::Null);
        let bounds = |k: &str| {
            r[k].as_array().and_then(|b| {
                Some(format!(
                    "[{:.3e}, {:.3e}]",
                    b.first()?.as_f64()?,
                    b.get(1)?.as_f64()?
                ))
            })
        };
        if let Some(f) = bounds("pf_bounds") {
            t.push_str(&format!(
                "  reliability: room P_f in {f} (FORM){} — between the likeliest bay and the sum over the printed halves\n",
                bounds("pf_sorm_bounds").map_or(String::new(), |s| format!(", {s} (SORM)"))
            ));
        }
        t
    }

    /// One line per failing bay, starting with `level` (`error`, or `warning` when failing is
    /// allowed).
    pub fn failure_lines(&self, level: &str) -> Vec<String> {
        (1..)
            .zip(&self.bays)
            .filter(|(_, b)| !b.outcome.verdict.ok)
            .map(|(n, _)| format!("{level}: bay {n} fails its checks (see bay_{n}/report.html)"))
            .collect()
    }

    /// The room's report ([`index_html`] of [`CeilingOutcome::summary`]).
    pub fn index_html(&self) -> String {
        index_html(&self.design, &self.summary())
    }
}

impl BayOutcome {
    /// The files of one bay's directory: `summary.json`, `report.html`, `path.csv`, and when
    /// the bay passes (or `allow_fail`) its robot plan's files ([`crate::output::plan_files`])
    /// and those of the mirrored second half under `mirror/`.
    ///
    /// # Errors
    /// [`OutputError::Produce`] when a file cannot be produced (a program failing the URScript
    /// check, a report that does not render).
    pub fn files(&self, allow_fail: bool) -> Result<Vec<OutputFile>, OutputError> {
        let eval = &self.outcome;
        let summary = serde_json::to_vec_pretty(&eval.summary())
            .map_err(|e| OutputError::Produce(format!("cannot write summary.json: {e}")))?;
        let report = eval
            .report_html()
            .map_err(|e| OutputError::Produce(format!("cannot write report.html: {e}")))?;
        let mut out = vec![
            OutputFile::new("summary.json", summary),
            OutputFile::new("report.html", report),
            OutputFile::new("path.csv", eval.cap.path.to_csv()),
        ];
        if eval.verdict.ok || allow_fail {
            // Each half with its station sheet (issue 28).
            let sheet =
                |plan: &kappe_robot::Plan,
                 tol: Option<&kappe_robot::tolerance::ToleranceReport>| {
                    OutputFile::new(
                        "stations.md",
                        kappe_robot::stations::station_sheet(plan, tol, Ok("program_part")),
                    )
                };
            // A moving base: each half's tracking programs and base trajectory (issue 27).
            match (&eval.robot, &eval.moving) {
                (Some(Ok(_)), Some(m)) => {
                    out.extend(moving_plan_files(
                        &eval.marked_moving(&m.plan),
                        "program_part",
                        true,
                    )?);
                }
                (Some(Ok(plan)), None) => {
                    let plan = eval.marked_plan(plan);
                    out.extend(plan_files(&plan, "program_part", true)?);
                    out.push(sheet(&plan, eval.base_tolerance.as_ref()));
                }
                _ => {}
            }
            if let Some(mp) = &self.mirror_moving {
                let files = moving_plan_files(&eval.marked_moving(mp), "program_part", true)?;
                out.extend(files.into_iter().map(|f| f.under("mirror")));
            } else if let Some(Ok(plan)) = &self.mirror_plan {
                let plan = eval.marked_plan(plan);
                let mut files = plan_files(&plan, "program_part", true)?;
                files.push(sheet(&plan, self.mirror_tolerance.as_ref()));
                out.extend(files.into_iter().map(|f| f.under("mirror")));
            }
        }
        Ok(out)
    }
}

/// The room's report: one self-contained page with the summary table of `summary`
/// ([`ceiling_summary`]), linking each bay's own report at `bay_N/report.html`.
pub fn index_html(design: &CeilingDesign, summary: &Value) -> String {
    let s = summary;
    let esc = |t: &str| {
        t.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut rows = String::new();
    for (i, b) in s["bays"].as_array().into_iter().flatten().enumerate() {
        let w = &b["worst_constraint"];
        rows.push_str(&format!(
                "<tr><td><a href=\"bay_{n}/report.html\">{name}</a></td><td>{span:.3}</td><td>{halves}</td>\
                 <td>{mass:.1}</td><td>{vol:.4}</td><td>{pt:.0}</td><td>{rt:.0}</td><td>{st}</td>\
                 <td>{wc} ({ut}) {el}</td><td>{blf}</td><td class=\"{cls}\">{ok}</td></tr>\n",
                n = i + 1,
                name = esc(b["name"].as_str().unwrap_or("")),
                span = b["span_m"].as_f64().unwrap_or(0.0),
                halves = b["halves"],
                mass = b["mass_kg"].as_f64().unwrap_or(0.0),
                vol = b["volume_m3"].as_f64().unwrap_or(0.0),
                pt = b["print_time_s"].as_f64().unwrap_or(0.0) / 60.0,
                rt = b["robot"]["time_s"].as_f64().unwrap_or(0.0) / 60.0,
                st = b["robot"]["stations"],
                wc = esc(w["name"].as_str().unwrap_or("n/a")),
                ut = w["utilisation"]
                    .as_f64()
                    .map_or("n/a".into(), |u| format!("{:.0} %", 100.0 * u)),
                el = esc(w["element"].as_str().unwrap_or("")),
                blf = b["min_blf"]
                    .as_f64()
                    .map_or("n/a".into(), |v| format!("{v:.2}")),
                cls = if b["ok"].as_bool() == Some(true) { "ok" } else { "fail" },
                ok = if b["ok"].as_bool() == Some(true) { "pass" } else { "FAIL" },
            ));
    }
    let t = &s["total"];
    format!(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>{name}</title>\
             <style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}\
             td,th{{border:1px solid #ccc;padding:4px 8px;text-align:right}}td:first-child{{text-align:left}}\
             .ok{{color:#070}}.fail{{color:#b00;font-weight:bold}}</style></head><body>\
             <h1>{name}</h1><p>{nb} bays, {len} m between end walls, ends: {ends}. Verdict: <b>{verdict}</b>.</p>\
             <table><tr><th>bay</th><th>span m</th><th>halves</th><th>mass kg</th><th>volume m³</th>\
             <th>print min</th><th>robot min</th><th>stations</th><th>worst constraint (utilisation)</th>\
             <th>min BLF</th><th>verdict</th></tr>\n{rows}</table>\
             <p>Total: {mass:.1} kg, {vol:.4} m³, print {pt:.0} min, robot {rt:.0} min (relocations {rl:.0} min).</p>\
             <script type=\"application/json\" id=\"ceiling\">{json}</script></body></html>\n",
        name = esc(design.name.as_str()),
        nb = s["bays"].as_array().map_or(0, Vec::len),
        len = design.ceiling.length,
        ends = design.ceiling.ends.describe(),
        verdict = if s["ok"].as_bool() == Some(true) {
            "pass"
        } else {
            "FAIL"
        },
        mass = t["mass_kg"].as_f64().unwrap_or(0.0),
        vol = t["volume_m3"].as_f64().unwrap_or(0.0),
        pt = t["print_time_s"].as_f64().unwrap_or(0.0) / 60.0,
        rt = t["robot_time_s"].as_f64().unwrap_or(0.0) / 60.0,
        rl = t["relocation_time_s"].as_f64().unwrap_or(0.0) / 60.0,
        json = s.to_string().replace("</", "<\\/"),
    )
}
