//! The design specification: every parameter and constraint of `method.md` §2–3, with defaults,
//! read from TOML and validated field by field.
//!
//! Units are SI (m, N, Pa, s); angles are degrees in the file and radians in code.

use serde::{Deserialize, Serialize};

use crate::input::error::DesignError;

/// A complete cap-ceiling design: geometry, material, printing, constraints, robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Design {
    /// A name for reports.
    pub name: String,
    /// Global geometry of the cap.
    pub cap: CapSpec,
    /// Material of the printed bead (green state).
    pub material: MaterialSpec,
    /// Bead and print-path settings.
    pub print: PrintSpec,
    /// Structural and fabrication limits.
    pub constraints: ConstraintSpec,
    /// Robot and tool settings (used by the motion planner).
    pub robot: RobotSpec,
    /// The print schedule: waits after layers, station-change time (green-state.md §3).
    #[serde(skip_serializing_if = "crate::input::schedule::ScheduleSpec::is_empty")]
    pub schedule: crate::input::schedule::ScheduleSpec,
    /// Analysis settings: which states get a buckling analysis, modes, layer ageing.
    pub analysis: crate::input::analysis::AnalysisOptions,
    /// Uncertain parameters, correlation and drift (issue 24); absent: deterministic only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<crate::input::uncertainty::UncertaintyTable>,
}

/// Global geometry (method.md §2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CapSpec {
    /// Cs: clear span between the springing lines, m.
    pub span: f64,
    /// Cr: height of the crown above the base plane, m.
    pub rise: f64,
    /// Cl: length of the centre section along y, measured on the base plane, m.
    pub length: f64,
    /// am: tilt of every layer plane from the vertical, degrees.
    pub tilt_deg: f64,
    /// What the first centre layer leans on: `"start_section"` (default, method.md §6) or
    /// `"end_wall"` (an end wall takes the stack thrust; `kappe::form::ends`).
    #[serde(skip_serializing_if = "EndKind::is_default")]
    pub end: EndKind,
    /// `[cap.corrugation]`: a wave of the centre layers' rise along the cap (issue 26,
    /// `docs/corrugation.md`). Absent or `amplitude = 0`: the prismatic centre section.
    /// Not written back when absent or of amplitude 0, so that a cap with `amplitude = 0` is the
    /// prismatic cap byte for byte, down to the design echoed in `summary.json`.
    #[serde(default, skip_serializing_if = "no_corrugation")]
    pub corrugation: Option<CorrugationSpec>,
}

fn no_corrugation(c: &Option<CorrugationSpec>) -> bool {
    c.as_ref().is_none_or(|c| c.amplitude == 0.0)
}

/// How the corrugation varies across the span.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CorrugationShape {
    /// Each centre layer is form-found to its own rise `Cr + a·sin(2π·y/λ)`: the wave is zero
    /// at the beams (the feet stay on the springing lines) and largest at the crown.
    #[default]
    Crown,
}

/// `[cap.corrugation]`: the centre section undulates along the cap (docs/corrugation.md).
///
/// Centre layer k (its plane crossing the base at `y_k = k·lh/cos(am)`) is form-found with CEM
/// in its tilted plane to the rise `Cr_k = Cr + a·sin(2π·y_k/λ)`; layer 0 keeps `Cr`, so the
/// start section (translates of layer 0) and an end wall meet the wave where it is zero.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CorrugationSpec {
    /// a: crown amplitude of the wave, m (0: no corrugation).
    pub amplitude: f64,
    /// λ: wavelength along the cap (y, on the base plane), m.
    pub wavelength: f64,
    /// How the wave varies across the span (`"crown"`).
    pub shape: CorrugationShape,
}

impl Default for CorrugationSpec {
    fn default() -> Self {
        CorrugationSpec {
            amplitude: 0.0,
            wavelength: 0.3,
            shape: CorrugationShape::Crown,
        }
    }
}

/// A wavelength must span at least this many layer steps: a sine sampled at 8 points per
/// period keeps every peak within 1 − cos(π/8) ≈ 8 % of the amplitude, and successive layers
/// then differ by at most `a·2π/8` in rise, so the wave is printed, not aliased.
pub const MIN_LAYERS_PER_WAVELENGTH: f64 = 8.0;

impl CorrugationSpec {
    /// The rise target of centre layer `k` for the cap rise `rise` and layer step `step`
    /// (`lh/cos(am)`), m.
    pub fn layer_rise(&self, rise: f64, step: f64, k: usize) -> f64 {
        match self.shape {
            CorrugationShape::Crown => {
                rise + self.amplitude
                    * (2.0 * std::f64::consts::PI * step * k as f64 / self.wavelength).sin()
            }
        }
    }
}

/// Material (method.md §2–3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialSpec {
    /// γ: specific weight of the green material, N/m³.
    pub specific_weight: f64,
    /// E: Young's modulus used for the buckling analysis, Pa.
    pub youngs_modulus: f64,
    /// ν: Poisson's ratio.
    pub poisson_ratio: f64,
    /// `[material.time]`: E and strength growing with the age of a layer (None: constant E
    /// and the σ limits of `[constraints]`, as before).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time: Option<crate::input::material::TimeModelSpec>,
}

/// Bead and path (method.md §2, §7).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PrintSpec {
    /// lh: spacing of consecutive layer planes along their normal, m.
    pub layer_height: f64,
    /// lw: bead width = shell thickness, m.
    pub layer_width: f64,
    /// d_n: nozzle diameter, m.
    pub nozzle_diameter: f64,
    /// Δs: target node spacing along a layer, m.
    pub path_sampling: f64,
    /// φ: share of the centre arch force that start layers keep in the final state, [0, 1).
    pub start_arch_fraction: f64,
    /// Nozzle speed along the path while printing, m/s.
    pub print_speed: f64,
}

/// Constraints (method.md §3). Stresses are negative in compression.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ConstraintSpec {
    /// σ_min: most negative allowed normal stress (compressive strength), Pa.
    pub sigma_min: f64,
    /// σ_max: largest allowed normal stress (tensile strength), Pa.
    pub sigma_max: f64,
    /// BLF_min: calibrated lower bound of the linear buckling load factor.
    pub blf_min: f64,
    /// l_o,max: largest allowed layer overhang, m. Default lw/2 (method.md §3).
    pub overhang_max: Option<f64>,
    /// β_min: least reliability index of the print (issue 24), checked only when the design has
    /// an `[uncertainty]` table. Default [`crate::input::uncertainty::BETA_MIN_DEFAULT`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta_min: Option<f64>,
    /// Least collapse factor of the imperfect print states (`[analysis.nonlinear]`,
    /// docs/collapse.md). Default 1.0: the state collapses under its own weight.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collapse_min: Option<f64>,
    /// Largest allowed deviation of the as-printed shape from the design, m (issue 23,
    /// docs/as-printed.md). Default half the layer height ([`Design::deviation_max`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deviation_max: Option<f64>,
}

impl ConstraintSpec {
    /// `collapse_min`, default 1.0.
    pub fn collapse_min(&self) -> f64 {
        self.collapse_min.unwrap_or(1.0)
    }
}

/// Robot and tool settings for the motion planner (method.md §8, robot.md).
///
/// `setup` and `plan` are the planner's own settings (`kappe_robot::RobotSetup` and
/// `kappe_robot::PlanOptions`, documented there). The print speed, bead radius and bead offset
/// of `plan` are always taken from `[print]` (speed, lw/2, lh/2), and the two support beams of
/// `beams` are added to the obstacles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSpec {
    /// Plan the robot motion as part of `kappe design`.
    pub enabled: bool,
    /// The support beams under the springing lines.
    pub beams: BeamSpec,
    /// Robot cell: base placement, tool, mobile base, floor, extra obstacles.
    pub setup: kappe_robot::setup::RobotSetup,
    /// How the base takes part in the print (issue 27): `[robot.base] mode = "stations"` (the
    /// default: print, stop, drive, re-localise; `setup.base` places the stations) or
    /// `mode = "moving"` (the base creeps along the bay while the arm prints, one take). A
    /// table of its own rather than a field of `[robot.setup]`: `setup.base` already names the
    /// station placement. The moving limits and their defaults are `kappe_robot::MovingBase`'s:
    /// `speed_max` 0.1 m/s, `accel_max` 0.1 m/s², `x` 0 m, `z` 0 m, `yaw_deg` 270°, `lead`
    /// searched in `lead_range` 0.3–1.6 m by `lead_step` 0.02 m, `min_reach_margin` 0.02 m,
    /// `score_layers` 40, `score_stride` 5, `body_check_step` 0.01 m.
    #[serde(skip_serializing_if = "is_stations")]
    pub base: kappe_robot::BaseMode,
    /// Planner settings.
    pub plan: kappe_robot::setup::PlanOptions,
    /// The base-pose tolerance check of the plan (issue 15): `[robot.tolerance]`.
    #[serde(skip_serializing_if = "ToleranceSpec::is_default")]
    pub tolerance: ToleranceSpec,
}

/// Whether the base mode is the default (kept out of resolved design files and summaries, so a
/// station design's outputs do not change).
fn is_stations(m: &kappe_robot::BaseMode) -> bool {
    *m == kappe_robot::BaseMode::Stations
}

/// Check the moving-base settings of `[robot.base]`, each error naming its field.
/// `[cap.corrugation]` against the cap: the wave must leave every layer a cap arch of this
/// method (0.05 ≤ rise/span ≤ 1, as `cap.rise`) and be resolved by the layers.
fn validate_corrugation(w: &CorrugationSpec, c: &CapSpec, step: f64) -> Result<(), DesignError> {
    let a = w.amplitude;
    if !(a.is_finite() && a >= 0.0) {
        return Err(DesignError::Invalid {
            field: "cap.corrugation.amplitude",
            value: format!("{a}"),
            allowed: "allowed: a finite amplitude ≥ 0 m".into(),
        });
    }
    let lambda = w.wavelength;
    let min_lambda = MIN_LAYERS_PER_WAVELENGTH * step;
    if !(lambda.is_finite() && lambda >= min_lambda) {
        return Err(DesignError::Invalid {
            field: "cap.corrugation.wavelength",
            value: format!("{lambda}"),
            allowed: format!(
                "allowed: wavelength ≥ {MIN_LAYERS_PER_WAVELENGTH} layer steps = {:.1} mm \
                 (layer step lh/cos(am) = {:.2} mm); a shorter wave is not resolved by the layers",
                min_lambda * 1e3,
                step * 1e3
            ),
        });
    }
    if a == 0.0 {
        return Ok(());
    }
    let (lo, hi) = (c.rise - a, c.rise + a);
    if lo < 0.05 * c.span || hi > c.span {
        return Err(DesignError::Invalid {
            field: "cap.corrugation.amplitude",
            value: format!("{a}"),
            allowed: format!(
                "the layers' rises run from {:.1} mm to {:.1} mm; allowed: every layer's \
                 rise/span in [0.05, 1] (rise − amplitude ≥ {:.1} mm and rise + amplitude ≤ span \
                 = {:.1} mm), as for cap.rise",
                lo * 1e3,
                hi * 1e3,
                0.05 * c.span * 1e3,
                c.span * 1e3
            ),
        });
    }
    Ok(())
}

fn validate_moving(m: &kappe_robot::MovingBase) -> Result<(), DesignError> {
    let check = |field: &'static str, value: f64, ok: bool, allowed: &str| {
        if value.is_finite() && ok {
            Ok(())
        } else {
            Err(DesignError::Invalid {
                field,
                value: format!("{value}"),
                allowed: allowed.to_string(),
            })
        }
    };
    check(
        "robot.base.speed_max",
        m.speed_max,
        m.speed_max > 0.0,
        "allowed: speed_max > 0 m/s",
    )?;
    check(
        "robot.base.accel_max",
        m.accel_max,
        m.accel_max > 0.0,
        "allowed: accel_max > 0 m/s²",
    )?;
    check("robot.base.x", m.x, true, "allowed: a finite x, m")?;
    check("robot.base.z", m.z, true, "allowed: a finite z, m")?;
    check(
        "robot.base.yaw_deg",
        m.yaw_deg,
        true,
        "allowed: a finite yaw, degrees",
    )?;
    let [lo, hi] = m.lead_range;
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
        return Err(DesignError::Invalid {
            field: "robot.base.lead_range",
            value: format!("[{lo}, {hi}]"),
            allowed: "allowed: [min, max] with 0 ≤ min < max, m".into(),
        });
    }
    check(
        "robot.base.lead_step",
        m.lead_step,
        m.lead_step > 0.0,
        "allowed: lead_step > 0 m",
    )?;
    if let Some(l) = m.lead {
        check("robot.base.lead", l, l >= 0.0, "allowed: lead ≥ 0 m")?;
    }
    check(
        "robot.base.min_reach_margin",
        m.min_reach_margin,
        m.min_reach_margin >= 0.0,
        "allowed: min_reach_margin ≥ 0 m",
    )?;
    check(
        "robot.base.body_check_step",
        m.body_check_step,
        m.body_check_step > 0.0,
        "allowed: body_check_step > 0 m",
    )?;
    for (field, n) in [
        ("robot.base.score_layers", m.score_layers),
        ("robot.base.score_stride", m.score_stride),
    ] {
        if n == 0 {
            return Err(DesignError::Invalid {
                field,
                value: "0".into(),
                allowed: "allowed: ≥ 1".into(),
            });
        }
    }
    Ok(())
}

/// `[robot.tolerance]`: the base-pose errors a relocated mobile base must tolerate
/// (`kappe_robot::tolerance::check_base_tolerance`, run by `kappe design` on every plan and
/// reported in `summary.json` under `robot.base_tolerance`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ToleranceSpec {
    /// Run the check at all.
    pub check: bool,
    /// Largest position error of the base in x and y, m.
    pub position: f64,
    /// Largest yaw error of the base, degrees.
    pub yaw_deg: f64,
    /// Check every n-th waypoint of a layer (and always its first and last).
    pub stride: usize,
    /// A plan that does not tolerate the errors fails the design (on by default, issue 28:
    /// the base search keeps the same margin, so the default design's plan survives ±10 mm,
    /// ±1°; a plan that does not is never written as "verified" without a word).
    pub verdict: bool,
    /// Also find, per station, the largest base error it survives (the tolerance box scaled
    /// up or down, `kappe_robot::tolerance::station_margins`), for the station sheet and
    /// `summary.json`. Off by default: it costs about 3× the check.
    pub margins: bool,
}

impl Default for ToleranceSpec {
    fn default() -> Self {
        let t = kappe_robot::tolerance::BaseTolerance::default();
        ToleranceSpec {
            check: true,
            position: t.position,
            yaw_deg: t.yaw_deg,
            stride: t.stride,
            verdict: true,
            margins: false,
        }
    }
}

impl ToleranceSpec {
    /// Whether this is the default (kept out of resolved design files).
    pub fn is_default(&self) -> bool {
        *self == ToleranceSpec::default()
    }

    /// The robot crate's tolerance.
    pub fn base_tolerance(&self) -> kappe_robot::tolerance::BaseTolerance {
        kappe_robot::tolerance::BaseTolerance {
            position: self.position,
            yaw_deg: self.yaw_deg,
            stride: self.stride,
        }
    }
}

/// Two beams along y whose tops are the base plane and whose inner faces are the springing lines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BeamSpec {
    /// Beam width across x, m.
    pub width: f64,
    /// Beam height below the base plane, m.
    pub height: f64,
    /// How far the beams run beyond the printed cap at both ends, m.
    pub overrun: f64,
}

impl Default for BeamSpec {
    fn default() -> Self {
        BeamSpec {
            width: 0.12,
            height: 0.24,
            overrun: 0.05,
        }
    }
}

impl Default for RobotSpec {
    fn default() -> Self {
        RobotSpec {
            enabled: true,
            beams: BeamSpec::default(),
            setup: kappe_robot::setup::RobotSetup::default(),
            base: kappe_robot::BaseMode::Stations,
            plan: kappe_robot::setup::PlanOptions::default(),
            tolerance: ToleranceSpec::default(),
        }
    }
}

impl Default for Design {
    fn default() -> Self {
        Design {
            name: "default".into(),
            cap: CapSpec::default(),
            material: MaterialSpec::default(),
            print: PrintSpec::default(),
            constraints: ConstraintSpec::default(),
            robot: RobotSpec::default(),
            schedule: crate::input::schedule::ScheduleSpec::default(),
            analysis: crate::input::analysis::AnalysisOptions::default(),
            uncertainty: None,
        }
    }
}

impl Default for CapSpec {
    fn default() -> Self {
        CapSpec {
            span: 0.8,
            rise: 0.2,
            length: 0.6,
            tilt_deg: 25.0,
            end: EndKind::StartSection,
            corrugation: None,
        }
    }
}

impl Default for MaterialSpec {
    fn default() -> Self {
        MaterialSpec {
            specific_weight: 23044.0,
            youngs_modulus: 10.0e6,
            poisson_ratio: 0.35,
            time: None,
        }
    }
}

impl Default for PrintSpec {
    fn default() -> Self {
        PrintSpec {
            layer_height: 0.008,
            layer_width: 0.020,
            nozzle_diameter: 0.015,
            path_sampling: 0.02,
            start_arch_fraction: 0.0,
            print_speed: 0.05,
        }
    }
}

impl Default for ConstraintSpec {
    fn default() -> Self {
        ConstraintSpec {
            sigma_min: -20.0e3,
            sigma_max: 0.0,
            blf_min: 1.0,
            overhang_max: None,
            beta_min: None,
            collapse_min: None,
            deviation_max: None,
        }
    }
}

/// The embedded default design file, with comments (what `kappe init` writes).
pub const EXAMPLE_TOML: &str = include_str!("default_design.toml");

impl Design {
    /// Parse a design from TOML; every missing field takes its default. Unknown fields are errors.
    ///
    /// ```
    /// let d = kappe::Design::from_toml_str("[cap]\nspan = 1.0\n").unwrap();
    /// assert_eq!(d.cap.span, 1.0);
    /// assert_eq!(d.cap.rise, 0.2);
    /// ```
    pub fn from_toml_str(text: &str) -> Result<Design, DesignError> {
        let design: Design = parse_toml(text)?;
        design.validate()?;
        Ok(design)
    }

    /// Serialize to TOML (the resolved design, every field explicit).
    ///
    /// # Errors
    /// [`DesignError::ToToml`] for a value TOML cannot hold (e.g. a non-finite number).
    pub fn to_toml_string(&self) -> Result<String, DesignError> {
        toml::to_string(self).map_err(|e| DesignError::ToToml(e.to_string()))
    }

    /// Layer tilt am in radians.
    pub fn tilt(&self) -> f64 {
        self.cap.tilt_deg.to_radians()
    }

    /// The green-state time model: `[material.time]`, or the older `[analysis.ageing]` (linear
    /// E only) read as the same model; the constant model with `[material] youngs_modulus`
    /// when neither is given. Both at once is an error.
    pub fn time_model(&self) -> Result<crate::input::material::TimeModel, DesignError> {
        use crate::input::material::{Property, TimeLaw, TimeModel};
        match (&self.material.time, &self.analysis.ageing) {
            (Some(_), Some(_)) => Err(DesignError::Invalid {
                field: "analysis.ageing",
                value: "given together with [material.time]".into(),
                allowed: "allowed: one time model; [analysis.ageing] is the older form of \
                          [material.time] (model = \"linear\", youngs_modulus, \
                          youngs_modulus_rate, youngs_modulus_max): move it there"
                    .into(),
            }),
            (Some(t), None) => t.resolve(self.material.youngs_modulus),
            (None, Some(a)) => Ok(TimeModel {
                law: TimeLaw::Linear,
                time_constant: f64::INFINITY,
                youngs_modulus: Property {
                    initial: a.initial_modulus,
                    rate: a.rate,
                    max: a.max_modulus,
                },
                strength: None,
            }),
            (None, None) => Ok(TimeModel::constant(self.material.youngs_modulus)),
        }
    }

    /// The corrugation of the centre section, if its amplitude is not zero (amplitude 0 is the
    /// prismatic cap on exactly its own code path).
    pub fn corrugation(&self) -> Option<&CorrugationSpec> {
        self.cap.corrugation.as_ref().filter(|c| c.amplitude != 0.0)
    }

    /// l_o,max, defaulting to lw/2 (method.md §3).
    pub fn overhang_max(&self) -> f64 {
        self.constraints
            .overhang_max
            .unwrap_or(0.5 * self.print.layer_width)
    }

    /// The largest allowed as-printed deviation, m: `constraints.deviation_max`, defaulting to
    /// half the layer height (docs/as-printed.md §4: a bead laid at its programmed height over
    /// a layer sunk by more than lh/2 bonds to it over less than half its designed contact).
    pub fn deviation_max(&self) -> f64 {
        self.constraints
            .deviation_max
            .unwrap_or(0.5 * self.print.layer_height)
    }

    /// Check every field against its allowed range (method.md §2–3).
    pub fn validate(&self) -> Result<(), DesignError> {
        fn check(
            field: &'static str,
            value: f64,
            ok: bool,
            allowed: impl Into<String>,
        ) -> Result<(), DesignError> {
            if value.is_finite() && ok {
                Ok(())
            } else {
                Err(DesignError::Invalid {
                    field,
                    value: format!("{value}"),
                    allowed: allowed.into(),
                })
            }
        }
        let c = &self.cap;
        let p = &self.print;
        let m = &self.material;
        let k = &self.constraints;
        check(
            "cap.span",
            c.span,
            c.span > 0.05 && c.span <= 20.0,
            "allowed: 0.05 m < span ≤ 20 m",
        )?;
        check("cap.rise", c.rise, c.rise > 0.0, "allowed: rise > 0 m")?;
        let ratio = c.rise / c.span;
        check(
            "cap.rise",
            c.rise,
            (0.05..=1.0).contains(&ratio),
            format!(
                "rise/span = {ratio:.3}; allowed: 0.05 ≤ rise/span ≤ 1 for a compression arch of this method \
                 (flatter arches have unbounded thrust, steeper ones are not caps)"
            ),
        )?;
        check(
            "cap.length",
            c.length,
            c.length > 0.0 && c.length <= 50.0,
            "allowed: 0 < length ≤ 50 m",
        )?;
        check(
            "cap.tilt_deg",
            c.tilt_deg,
            c.tilt_deg > 0.0 && c.tilt_deg <= 60.0,
            "allowed: 0° < tilt ≤ 60° (layer plane from the vertical)",
        )?;
        check(
            "material.specific_weight",
            m.specific_weight,
            m.specific_weight > 0.0,
            "allowed: specific weight > 0 N/m³",
        )?;
        check(
            "material.youngs_modulus",
            m.youngs_modulus,
            m.youngs_modulus > 0.0,
            "allowed: E > 0 Pa",
        )?;
        check(
            "material.poisson_ratio",
            m.poisson_ratio,
            (0.0..0.5).contains(&m.poisson_ratio),
            "allowed: 0 ≤ ν < 0.5",
        )?;
        check(
            "print.nozzle_diameter",
            p.nozzle_diameter,
            p.nozzle_diameter > 0.0,
            "allowed: > 0 m",
        )?;
        let dn = p.nozzle_diameter;
        check(
            "print.layer_height",
            p.layer_height,
            p.layer_height >= 0.4 * dn - 1e-12 && p.layer_height <= dn + 1e-12,
            format!(
                "allowed: 0.4·d_n ≤ layer height ≤ d_n, i.e. [{:.4}, {:.4}] m for this nozzle",
                0.4 * dn,
                dn
            ),
        )?;
        check(
            "print.layer_width",
            p.layer_width,
            p.layer_width >= dn - 1e-12 && p.layer_width <= 2.0 * dn + 1e-12,
            format!(
                "allowed: d_n ≤ layer width ≤ 2·d_n, i.e. [{:.4}, {:.4}] m for this nozzle",
                dn,
                2.0 * dn
            ),
        )?;
        check(
            "print.path_sampling",
            p.path_sampling,
            // The cost guard (issue 28): a bead smooths out path detail finer than half its
            // width, so finer sampling only multiplies nodes, states' meshes and robot targets
            // (1e-7 m ran for minutes into gigabytes before).
            p.path_sampling >= 0.5 * p.layer_width - 1e-12 && p.path_sampling <= c.span / 8.0,
            format!(
                "allowed: {:.1} mm (half the layer width: the bead smooths out finer detail, \
                 finer sampling only multiplies the run time) to {:.1} mm (span/8: at least 8 \
                 segments per arch)",
                0.5 * p.layer_width * 1e3,
                c.span / 8.0 * 1e3
            ),
        )?;
        check(
            "print.start_arch_fraction",
            p.start_arch_fraction,
            (0.0..1.0).contains(&p.start_arch_fraction),
            "allowed: 0 ≤ φ < 1",
        )?;
        check(
            "print.print_speed",
            p.print_speed,
            p.print_speed > 0.0 && p.print_speed <= 1.0,
            "allowed: 0 < speed ≤ 1 m/s",
        )?;
        let n_layers = c.length * self.tilt().cos() / p.layer_height;
        check(
            "cap.length",
            c.length,
            (1.0..=5000.0).contains(&n_layers),
            format!(
                "gives {n_layers:.1} centre layers; allowed 1 to 5000 (length·cos(tilt)/layer height)"
            ),
        )?;
        if let Some(w) = &c.corrugation {
            validate_corrugation(w, c, p.layer_height / self.tilt().cos())?;
        }
        check(
            "constraints.sigma_min",
            k.sigma_min,
            k.sigma_min < 0.0,
            "allowed: σ_min < 0 Pa (compression is negative)",
        )?;
        check(
            "constraints.sigma_max",
            k.sigma_max,
            k.sigma_max >= 0.0,
            "allowed: σ_max ≥ 0 Pa",
        )?;
        check(
            "constraints.blf_min",
            k.blf_min,
            k.blf_min > 0.0,
            "allowed: BLF_min > 0",
        )?;
        if let Some(c) = k.collapse_min {
            check(
                "constraints.collapse_min",
                c,
                c.is_finite() && c > 0.0,
                "allowed: collapse_min > 0 (1: collapse under the state's own weight)",
            )?;
        }
        if let Some(d) = k.deviation_max {
            check(
                "constraints.deviation_max",
                d,
                d.is_finite() && d > 0.0,
                "allowed: deviation_max > 0 m",
            )?;
        }
        if let Some(lo) = k.overhang_max {
            check(
                "constraints.overhang_max",
                lo,
                lo > 0.0,
                "allowed: l_o,max > 0 m",
            )?;
        }
        if let Some(b) = k.beta_min {
            check(
                "constraints.beta_min",
                b,
                b > 0.0 && b < 8.0,
                "allowed: 0 < β_min < 8 (P_f from 0.5 to 6e-16)",
            )?;
        }
        self.analysis.validate()?;
        self.time_model()?;
        if let Some(u) = &self.uncertainty {
            u.model(self)?;
        }
        self.schedule.waits(self.schedule.waits.len().max(1))?;
        self.schedule.relocation_time()?;
        let bm = &self.robot.beams;
        check(
            "robot.beams.width",
            bm.width,
            bm.width > 0.0,
            "allowed: width > 0 m",
        )?;
        check(
            "robot.beams.height",
            bm.height,
            bm.height > 0.0,
            "allowed: height > 0 m",
        )?;
        check(
            "robot.beams.overrun",
            bm.overrun,
            bm.overrun >= 0.0,
            "allowed: overrun ≥ 0 m",
        )?;
        // Checked here, before any computing, not first by the planner after the analysis.
        let moves = self.robot.plan.program.max_moves_per_program;
        if moves < 4 {
            return Err(DesignError::Invalid {
                field: "robot.plan.program.max_moves_per_program",
                value: moves.to_string(),
                allowed: "allowed: at least 4 (a program needs an approach, a descent, a print \
                          move and a retract)"
                    .into(),
            });
        }
        if let kappe_robot::BaseMode::Moving(m) = &self.robot.base {
            validate_moving(m)?;
        }
        Ok(())
    }
}

/// Deserialize TOML text into `T`, reporting the dotted path of a bad entry and, for an unknown
/// field, the closest allowed name. Every TOML file Kappe reads goes through here.
///
/// A file that sets nothing (empty, or only comments) is an error rather than silently meaning
/// "all defaults": a user who runs an empty file almost certainly meant another file.
pub(crate) fn parse_toml<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, DesignError> {
    if toml::from_str::<toml::Table>(text).is_ok_and(|t| t.is_empty()) {
        return Err(DesignError::Parse {
            path: String::new(),
            message: "the file is empty (it sets no table and no field); `kappe init` writes a \
                      commented example, and `kappe design` without a file runs the default design"
                .into(),
        });
    }
    let de = toml::Deserializer::parse(text).map_err(|e| DesignError::Parse {
        path: String::new(),
        message: e.to_string().trim().to_string(),
    })?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let message = plain_types(e.into_inner().message().trim());
        let message = match did_you_mean(&message) {
            Some(hint) => format!("{message} (did you mean `{hint}`?)"),
            None => message,
        };
        DesignError::Parse { path, message }
    })
}

/// serde names Rust types ("invalid type: integer `1`, expected struct CapSpec"); the user wrote
/// a TOML file, in which such a thing is a table.
fn plain_types(message: &str) -> String {
    let mut out = String::new();
    let mut rest = message;
    while let Some(i) = rest.find("struct ") {
        out.push_str(&rest[..i]);
        let after = &rest[i + "struct ".len()..];
        let end = after
            .find(|c: char| !c.is_alphanumeric() && c != '_')
            .unwrap_or(after.len());
        out.push_str("a table");
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// For serde's "unknown field `x`, expected one of `a`, `b`, …", the expected name closest to `x`
/// by edit distance (at most 3 edits), so a typo gets a concrete suggestion.
fn did_you_mean(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    let (typo, rest) = rest.split_once('`')?;
    let candidates: Vec<&str> = rest.split('`').skip(1).step_by(2).collect();
    candidates
        .into_iter()
        .map(|c| (edit_distance(typo, c), c))
        .filter(|(d, _)| *d <= 3)
        .min()
        .map(|(_, c)| c.to_string())
}

/// Levenshtein distance between two short strings.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// What the first centre layer of a cap leans on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EndKind {
    /// Printed start layers along the final-state thrust line to the base plane (method.md §6).
    #[default]
    StartSection,
    /// An end wall (or abutment) whose inclined face carries the stack thrust (module docs).
    EndWall,
}

impl EndKind {
    /// Whether this is the default end (used to keep the resolved design files unchanged).
    pub fn is_default(&self) -> bool {
        *self == EndKind::default()
    }
}
