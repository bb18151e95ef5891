//! The design loop (paper Figure 3; `kappe optimize`): vary the parameters the file marks free,
//! within their bounds, until every constraint holds, with the least material.
//!
//! The problem is small (a handful of parameters), every evaluation is a full form-finding plus
//! analysis, and the constraints are not smooth in the parameters (state count, node counts and
//! the start section change in steps). So the search is derivative-free: a **compass search**
//! (Kolda, Lewis & Torczon, SIAM Review 45 (2003) §3) on the parameters scaled to [0, 1]: try
//! ±h along each parameter, move to the first better point, halve h when no move helps, stop
//! at h < 1/64 or the evaluation budget. "Better" is lexicographic: a smaller total constraint
//! violation first, then less material (the printed volume lw·lh·path length). Infeasible
//! designs (form-finding fails, a parameter outside its physical range) count as violating.
//!
//! With `[uncertainty]` the print's β counts like a constraint: β < `beta_min` adds its relative
//! shortfall (β_min − β)/β_min to the violation, so the search moves towards reliable designs.
//!
//! The loop analyses buckling on a thinned state selection (`[analysis]` of the file, default
//! every 25 % of progress, which always includes the final state); the result is verified with
//! the final analysis options (default: every state) and the verdict reported.
//!
//! Hand-written: a compass search is ~60 lines, and the mixed feasibility/objective ordering is
//! specific to this problem.

use std::collections::BTreeMap;
use std::ops::ControlFlow;

use serde::{Deserialize, Serialize};

use crate::analysis::{Analysis, AnalysisOptions, StateSelection};
use crate::commands::calibrate_blf::DesignSource;
use crate::input::design::Design;
use crate::input::error::DesignError;

/// The parameters `kappe optimize` can vary, with their design-file names.
pub const FREE_PARAMETERS: [&str; 9] = [
    "cap.span",
    "cap.rise",
    "cap.length",
    "cap.tilt_deg",
    "print.layer_height",
    "print.layer_width",
    "print.start_arch_fraction",
    // Issue 26: the corrugation of the centre section (docs/corrugation.md). A design without
    // `[cap.corrugation]` starts at amplitude 0 and the default wavelength; amplitude 0 is the
    // smooth cap on exactly its code path, so the search can keep or drop the wave.
    "cap.corrugation.amplitude",
    "cap.corrugation.wavelength",
];

/// Bounds of a free parameter (both required).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bounds {
    /// Lower bound.
    pub min: Option<f64>,
    /// Upper bound.
    pub max: Option<f64>,
}

fn default_loop_analysis() -> AnalysisOptions {
    AnalysisOptions {
        states: StateSelection::Percent(25.0),
        ..AnalysisOptions::default()
    }
}

fn default_budget() -> usize {
    80
}

/// The optimize file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OptimizeFile {
    /// The starting design: a path (relative to this file) or an inline table; default design if
    /// absent.
    #[serde(default)]
    pub design: Option<DesignSource>,
    /// Free parameters by design-file name, each with `min` and `max`.
    pub free: BTreeMap<String, Bounds>,
    /// Analysis options inside the loop (default: buckling every 25 % of progress).
    #[serde(default = "default_loop_analysis")]
    pub analysis: AnalysisOptions,
    /// Analysis options of the final verification (default: every state).
    #[serde(default)]
    pub verify: AnalysisOptions,
    /// Largest number of design evaluations.
    #[serde(default = "default_budget")]
    pub max_evaluations: usize,
}

/// A free parameter with checked bounds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FreeParameter {
    /// Design-file name.
    pub name: String,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
}

impl OptimizeFile {
    /// Parse TOML (unknown fields are errors naming the entry).
    pub fn from_toml_str(text: &str) -> Result<OptimizeFile, DesignError> {
        let file: OptimizeFile = crate::input::design::parse_toml(text)?;
        file.analysis.validate()?;
        file.verify.validate()?;
        file.parameters()?;
        if file.max_evaluations == 0 || file.max_evaluations > 10_000 {
            return Err(DesignError::Invalid {
                field: "max_evaluations",
                value: file.max_evaluations.to_string(),
                allowed: "allowed: 1 ≤ max_evaluations ≤ 10000".into(),
            });
        }
        Ok(file)
    }

    /// Read either an optimize file (top-level `free`) or a design file with an `[optimize]`
    /// table holding the optimize fields (`free`, `analysis`, `verify`, `max_evaluations`); the
    /// rest of such a file is the starting design, returned alongside.
    ///
    /// ```
    /// let text = "[cap]\nrise = 0.25\n[optimize.free]\n\"cap.rise\" = { min = 0.15, max = 0.3 }\n";
    /// let (file, design) = kappe::commands::optimize::OptimizeFile::from_any_toml_str(text).unwrap();
    /// assert_eq!(design.unwrap().cap.rise, 0.25);
    /// assert_eq!(file.parameters().unwrap()[0].name, "cap.rise");
    /// ```
    pub fn from_any_toml_str(text: &str) -> Result<(OptimizeFile, Option<Design>), DesignError> {
        let mut table: toml::Table =
            text.parse()
                .map_err(|e: toml::de::Error| DesignError::Parse {
                    path: String::new(),
                    message: e.to_string().trim().to_string(),
                })?;
        let Some(opt) = table.remove("optimize") else {
            // A design file (it has design tables but no `free`) without its [optimize] table:
            // say that, rather than "unknown field `cap`" from the optimize-file schema.
            let design_tables = [
                "cap",
                "material",
                "print",
                "constraints",
                "robot",
                "analysis",
            ];
            if !table.contains_key("free") && design_tables.iter().any(|k| table.contains_key(*k)) {
                return Err(DesignError::Parse {
                    path: "optimize".into(),
                    message: "this is a design file without an [optimize] table: add \
                              [optimize.free] with the parameters to vary (e.g. \
                              \"cap.rise\" = { min = 0.15, max = 0.3 }), or give an optimize \
                              file (`kappe init --kind optimize`)"
                        .into(),
                });
            }
            return Ok((OptimizeFile::from_toml_str(text)?, None));
        };
        let toml::Value::Table(opt) = opt else {
            return Err(DesignError::Parse {
                path: "optimize".into(),
                message: "expected a table [optimize]".into(),
            });
        };
        if opt.contains_key("design") {
            return Err(DesignError::Parse {
                path: "optimize.design".into(),
                message: "not allowed inside a design file: the file itself is the design".into(),
            });
        }
        let ser = |t: &toml::Table| {
            toml::to_string(t).map_err(|e| DesignError::Parse {
                path: String::new(),
                message: e.to_string(),
            })
        };
        // Only an [optimize] table: the starting design is the default one.
        let design = if table.is_empty() {
            Design::default()
        } else {
            Design::from_toml_str(&ser(&table)?)?
        };
        let file = OptimizeFile::from_toml_str(&ser(&opt)?).map_err(|e| match e {
            DesignError::Parse { path, message } => DesignError::Parse {
                path: if path.is_empty() {
                    "optimize".into()
                } else {
                    format!("optimize.{path}")
                },
                message,
            },
            other => other,
        })?;
        Ok((file, Some(design)))
    }

    /// The free parameters, checked: known name, both bounds, finite, min < max.
    pub fn parameters(&self) -> Result<Vec<FreeParameter>, DesignError> {
        if self.free.is_empty() {
            return Err(DesignError::Invalid {
                field: "free",
                value: "{}".into(),
                allowed: format!(
                    "allowed: at least one free parameter, one of {}",
                    FREE_PARAMETERS.join(", ")
                ),
            });
        }
        let mut out = Vec::new();
        for (name, b) in &self.free {
            if !FREE_PARAMETERS.contains(&name.as_str()) {
                return Err(DesignError::Invalid {
                    field: "free",
                    value: format!("{name:?}"),
                    allowed: format!("allowed parameters: {}", FREE_PARAMETERS.join(", ")),
                });
            }
            let (Some(min), Some(max)) = (b.min, b.max) else {
                return Err(DesignError::Invalid {
                    field: "free",
                    value: format!("{name:?} with min = {:?}, max = {:?}", b.min, b.max),
                    allowed: "allowed: every free parameter needs both bounds, \
                              e.g. { min = 0.12, max = 0.3 }"
                        .into(),
                });
            };
            if !(min.is_finite() && max.is_finite() && min < max) {
                return Err(DesignError::Invalid {
                    field: "free",
                    value: format!("{name:?} with min = {min}, max = {max}"),
                    allowed: "allowed: finite bounds with min < max".into(),
                });
            }
            out.push(FreeParameter {
                name: name.clone(),
                min,
                max,
            });
        }
        Ok(out)
    }
}

fn get(d: &Design, name: &str) -> f64 {
    match name {
        "cap.span" => d.cap.span,
        "cap.rise" => d.cap.rise,
        "cap.length" => d.cap.length,
        "cap.tilt_deg" => d.cap.tilt_deg,
        "print.layer_height" => d.print.layer_height,
        "print.layer_width" => d.print.layer_width,
        "print.start_arch_fraction" => d.print.start_arch_fraction,
        "cap.corrugation.amplitude" => d.cap.corrugation.as_ref().map_or(0.0, |c| c.amplitude),
        "cap.corrugation.wavelength" => d.cap.corrugation.clone().unwrap_or_default().wavelength,
        _ => f64::NAN,
    }
}

fn set(d: &mut Design, name: &str, v: f64) {
    match name {
        "cap.span" => d.cap.span = v,
        "cap.rise" => d.cap.rise = v,
        "cap.length" => d.cap.length = v,
        "cap.tilt_deg" => d.cap.tilt_deg = v,
        "print.layer_height" => d.print.layer_height = v,
        "print.layer_width" => d.print.layer_width = v,
        "print.start_arch_fraction" => d.print.start_arch_fraction = v,
        "cap.corrugation.amplitude" => {
            d.cap
                .corrugation
                .get_or_insert_with(Default::default)
                .amplitude = v;
        }
        "cap.corrugation.wavelength" => {
            d.cap
                .corrugation
                .get_or_insert_with(Default::default)
                .wavelength = v;
        }
        _ => {}
    }
}

/// One evaluated design.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// 1-based evaluation number.
    pub evaluation: usize,
    /// Free parameter values.
    pub parameters: BTreeMap<String, f64>,
    /// Printed volume lw·lh·path length, m³ (None if the design could not be built).
    pub volume_m3: Option<f64>,
    /// Sum of the relative constraint violations (0 = feasible).
    pub violation: f64,
    /// Constraints that fail, or why the design could not be built.
    pub failing: Vec<String>,
    /// Whether the search moved here.
    pub accepted: bool,
}

/// The outcome of the design loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OptimizeResult {
    /// The best design found.
    pub design: Design,
    /// Its free parameters.
    pub parameters: BTreeMap<String, f64>,
    /// Its printed volume, m³.
    pub volume_m3: Option<f64>,
    /// The starting design's volume, m³.
    pub start_volume_m3: Option<f64>,
    /// Every evaluation in order (`accepted` marks the path taken).
    pub evaluations: Vec<Evaluation>,
    /// The result passes `kappe design`'s verdict (every constraint of the verification
    /// analysis, the robot plan, the base tolerance when in the verdict).
    pub feasible: bool,
    /// Constraints that bind: failing ones if infeasible, else those within 5 % of their limit.
    pub binding: Vec<String>,
    /// Free parameters that end on a bound.
    pub at_bounds: Vec<String>,
    /// The verification analysis of the result (None if it could not be built).
    pub verification: Option<Analysis>,
    /// The verdict of `kappe design`'s run on the result (analysis, robot plan, base
    /// tolerance); `feasible` is its `ok`. None if the design could not be run.
    pub verdict: Option<crate::verdict::Verdict>,
}

/// Relative violation of each failing constraint of an analysis.
fn violations(a: &Analysis) -> Vec<(String, f64)> {
    a.constraints
        .iter()
        .filter(|c| !c.pass)
        .map(|c| {
            let w = c.worst.unwrap_or(0.0);
            let scale = c.limit.abs().max(1e-12);
            let v = match c.name {
                "sigma_min" => (c.limit - w) / scale,
                "blf_min" => (c.limit - w) / scale,
                // σ_max may be 0: scale by the compressive limit's size instead.
                "sigma_max" => (w - c.limit) / a.constraints[0].limit.abs().max(1.0),
                _ => (w - c.limit) / scale,
            };
            (c.name.to_string(), v.max(1e-6))
        })
        .collect()
}

/// What one evaluation found.
struct Evaluated {
    volume: Option<f64>,
    violation: f64,
    failing: Vec<String>,
    analysis: Option<Analysis>,
    verdict: Option<crate::verdict::Verdict>,
}

/// Evaluate one design with `kappe design`'s run and verdict (issue 22: the optimum must pass
/// `kappe design`), its `[analysis]` replaced by `options`: the relative violations of the
/// failing constraints, plus [`ROBOT_FAILURE`] for a robot plan (or base tolerance in the
/// verdict) that fails.
fn evaluate(d: &Design, options: &AnalysisOptions) -> Evaluated {
    // Designs the method cannot build are infeasible by a large margin, so any buildable design
    // is preferred.
    const UNBUILDABLE: f64 = 1e3;
    let unbuildable = |e: &DesignError| Evaluated {
        volume: None,
        violation: UNBUILDABLE,
        failing: vec![e.to_string()],
        analysis: None,
        verdict: None,
    };
    let mut d = d.clone();
    d.analysis = options.clone();
    if let Err(e) = d.validate() {
        return unbuildable(&e);
    }
    match crate::run(&d, &crate::run::Options::of(&d), &crate::run::no_progress) {
        Ok(out) => {
            let mut v = out.analysis.as_ref().map(violations).unwrap_or_default();
            for f in &out.verdict.failures {
                match f {
                    // The print's reliability (issue 24): not an analysis constraint, so graded
                    // here by its relative shortfall, as `blf_min` is.
                    crate::verdict::Failure::Constraint {
                        name,
                        worst: Some(beta),
                        limit,
                        ..
                    } if name == "beta_min" => {
                        let shortfall = (limit - beta) / limit.abs().max(1e-12);
                        v.push((name.clone(), shortfall.max(1e-6)));
                    }
                    crate::verdict::Failure::Constraint { .. } => {}
                    _ => v.push((f.to_string(), ROBOT_FAILURE)),
                }
            }
            // `+ 0.0` turns the −0.0 of an empty sum into 0.
            let total: f64 = v.iter().map(|x| x.1).sum::<f64>() + 0.0;
            Evaluated {
                volume: Some(out.cap.path.volume),
                violation: total,
                failing: v.into_iter().map(|x| x.0).collect(),
                analysis: out.analysis,
                verdict: Some(out.verdict),
            }
        }
        Err(e) => unbuildable(&e),
    }
}

/// The violation a failing robot plan counts as: a constraint missed by 100 %, so a design the
/// robot can print is preferred to one it cannot, but a buildable design to neither.
const ROBOT_FAILURE: f64 = 1.0;

fn better(a: (f64, Option<f64>), b: (f64, Option<f64>)) -> bool {
    const EPS: f64 = 1e-12;
    if a.0 < b.0 - EPS {
        return true;
    }
    if a.0 > b.0 + EPS {
        return false;
    }
    matches!((a.1, b.1), (Some(va), Some(vb)) if va < vb * (1.0 - 1e-9))
}

/// Run the design loop from `start` (see the module docs). `on_eval` sees every evaluation;
/// `ControlFlow::Break` after one ends the loop with [`DesignError::Cancelled`] (the Python
/// package's Ctrl-C).
pub fn optimize(
    file: &OptimizeFile,
    start: &Design,
    on_eval: &dyn Fn(&Evaluation) -> ControlFlow<()>,
) -> Result<OptimizeResult, DesignError> {
    let stopped = std::cell::Cell::new(false);
    let params = file.parameters()?;
    file.analysis.validate()?;
    file.verify.validate()?;
    let n = params.len();
    let to_design = |x: &[f64]| -> Design {
        let mut d = start.clone();
        for (p, &xi) in params.iter().zip(x) {
            set(&mut d, &p.name, p.min + xi * (p.max - p.min));
        }
        d
    };
    let named = |x: &[f64]| -> BTreeMap<String, f64> {
        params
            .iter()
            .zip(x)
            .map(|(p, &xi)| (p.name.clone(), p.min + xi * (p.max - p.min)))
            .collect()
    };
    let mut x: Vec<f64> = params
        .iter()
        .map(|p| ((get(start, &p.name) - p.min) / (p.max - p.min)).clamp(0.0, 1.0))
        .collect();
    let mut evaluations: Vec<Evaluation> = Vec::new();
    let mut cache: BTreeMap<Vec<i64>, (f64, Option<f64>)> = BTreeMap::new();
    let key = |x: &[f64]| -> Vec<i64> { x.iter().map(|v| (v * 1e9).round() as i64).collect() };
    let mut run = |x: &[f64], evaluations: &mut Vec<Evaluation>| -> (f64, Option<f64>) {
        if let Some(&c) = cache.get(&key(x)) {
            return c;
        }
        let Evaluated {
            volume,
            violation,
            failing,
            ..
        } = evaluate(&to_design(x), &file.analysis);
        let e = Evaluation {
            evaluation: evaluations.len() + 1,
            parameters: named(x),
            volume_m3: volume,
            violation,
            failing,
            accepted: false,
        };
        if on_eval(&e).is_break() {
            stopped.set(true);
        }
        evaluations.push(e);
        cache.insert(key(x), (violation, volume));
        (violation, volume)
    };
    let mut best = run(&x, &mut evaluations);
    if stopped.get() {
        return Err(DesignError::Cancelled);
    }
    if let Some(e) = evaluations.last_mut() {
        e.accepted = true;
    }
    let start_volume = best.1;
    let mut h = 0.25;
    while h >= 1.0 / 64.0 && evaluations.len() < file.max_evaluations {
        let mut moved = false;
        'sweep: for i in 0..n {
            for sign in [-1.0, 1.0] {
                if evaluations.len() >= file.max_evaluations {
                    break 'sweep;
                }
                let mut y = x.clone();
                y[i] = (y[i] + sign * h).clamp(0.0, 1.0);
                if (y[i] - x[i]).abs() < 1e-12 {
                    continue;
                }
                let before = evaluations.len();
                let f = run(&y, &mut evaluations);
                if stopped.get() {
                    return Err(DesignError::Cancelled);
                }
                if better(f, best) {
                    best = f;
                    x = y;
                    moved = true;
                    if evaluations.len() > before
                        && let Some(e) = evaluations.last_mut()
                    {
                        e.accepted = true;
                    }
                    break;
                }
            }
        }
        if !moved {
            h *= 0.5;
        }
    }

    // The optimum is confirmed by the run and verdict of `kappe design` with the verification
    // analysis, which is written into the design, so that `kappe design` of the written file
    // reaches the same verdict (issue 22).
    let mut design = to_design(&x);
    design.analysis = file.verify.clone();
    let Evaluated {
        volume,
        mut failing,
        analysis: verification,
        verdict,
        ..
    } = evaluate(&design, &file.verify);
    let feasible = verdict.as_ref().is_some_and(|v| v.ok);
    if let Some(v) = verdict.as_ref().filter(|v| !v.ok) {
        // Constraints by name (as the search reports them), other checks in words.
        failing = v
            .failures
            .iter()
            .map(|f| match f {
                crate::verdict::Failure::Constraint { name, .. } => name.clone(),
                other => other.to_string(),
            })
            .collect();
    }
    let binding = match &verification {
        Some(a) if feasible => a
            .constraints
            .iter()
            .filter(|c| match c.worst {
                Some(w) if c.limit != 0.0 => (w / c.limit - 1.0).abs() < 0.05,
                // A zero limit (no tension) is met with equality by every zero-force element;
                // that is not a binding design choice.
                Some(_) => false,
                None => false,
            })
            .map(|c| c.name.to_string())
            .collect(),
        _ => failing,
    };
    let at_bounds = params
        .iter()
        .zip(&x)
        .filter(|(_, xi)| **xi <= 1e-12 || **xi >= 1.0 - 1e-12)
        .map(|(p, xi)| {
            format!(
                "{} at its {}",
                p.name,
                if *xi <= 1e-12 { "min" } else { "max" }
            )
        })
        .collect();
    Ok(OptimizeResult {
        parameters: named(&x),
        design,
        volume_m3: volume,
        start_volume_m3: start_volume,
        evaluations,
        feasible,
        binding,
        at_bounds,
        verification,
        verdict,
    })
}

/// Why the starting design of an optimize file cannot be had.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The inline `[design]` table is out of range.
    #[error("invalid inline design")]
    Inline(#[source] DesignError),
    /// `design = "FILE"` cannot be read.
    #[error("cannot read the design file {}", path.display())]
    Read {
        /// The file named.
        path: std::path::PathBuf,
        /// What reading it said.
        #[source]
        source: std::io::Error,
    },
    /// `design = "FILE"` is not a valid design.
    #[error("invalid design file {}", path.display())]
    Invalid {
        /// The file named.
        path: std::path::PathBuf,
        /// What is wrong in it.
        #[source]
        source: DesignError,
    },
}

/// The design the loop starts from: the design of a design file with an `[optimize]` table
/// (`embedded`, from [`OptimizeFile::from_any_toml_str`]), else the optimize file's `design`
/// (inline, or a path relative to `base`, the file's directory), else the default design.
pub fn start_design(
    file: &OptimizeFile,
    embedded: Option<Design>,
    base: &std::path::Path,
) -> Result<Design, StartError> {
    if let Some(d) = embedded {
        return Ok(d);
    }
    Ok(match &file.design {
        None => Design::default(),
        Some(source) => {
            use crate::input::resolve::ResolveError;
            source
                .resolve(base, Design::validate, Design::from_toml_str)
                .map_err(|e| match e {
                    ResolveError::Read { path, source } => StartError::Read { path, source },
                    ResolveError::Invalid { path: None, source } => StartError::Inline(source),
                    ResolveError::Invalid {
                        path: Some(path),
                        source,
                    } => StartError::Invalid { path, source },
                })?
        }
    })
}

/// `optimize.json`: the free parameters and the result (every evaluation, the path taken,
/// the verification).
pub fn document(
    file: &OptimizeFile,
    result: &OptimizeResult,
) -> Result<serde_json::Value, DesignError> {
    Ok(serde_json::json!({
        "format": "kappe.optimize",
        "version": 1,
        "free": file.parameters()?,
        "result": result,
    }))
}

/// The cubic decimetres of a volume, or `-`.
fn dm3(v: Option<f64>, unit: bool) -> String {
    v.map_or("-".into(), |v| {
        if unit {
            format!("{:.4} dm³", v * 1e3)
        } else {
            format!("{:.4}", v * 1e3)
        }
    })
}

/// The header of [`Evaluation::line`].
pub fn evaluation_header() -> String {
    format!(
        "{:>5} {:>10} {:>10}  {:<40} failing",
        "eval", "volume dm³", "violation", "parameters"
    )
}

impl Evaluation {
    /// One line per evaluation, under [`evaluation_header`] (parameters by their last name).
    pub fn line(&self) -> String {
        let params: Vec<String> = self
            .parameters
            .iter()
            .map(|(k, v)| format!("{}={v:.4}", k.rsplit('.').next().unwrap_or(k)))
            .collect();
        format!(
            "{:>5} {:>10} {:>10.4}  {:<40} {}",
            self.evaluation,
            dm3(self.volume_m3, false),
            self.violation,
            params.join(" "),
            self.failing.join(", ")
        )
    }
}

impl OptimizeResult {
    /// The outcome in words (what `kappe optimize` prints after the loop): the path taken,
    /// the volumes, the verification, parameters at bounds and the binding constraints.
    pub fn report(&self) -> String {
        use std::fmt::Write;
        let mut s = String::from("\npath taken (accepted moves):\n");
        for e in self.evaluations.iter().filter(|e| e.accepted) {
            let params: Vec<String> = e
                .parameters
                .iter()
                .map(|(k, v)| format!("{k} = {v:.5}"))
                .collect();
            let _ = writeln!(
                s,
                "  #{:<4} {}  volume {}",
                e.evaluation,
                params.join(", "),
                dm3(e.volume_m3, true)
            );
        }
        let _ = writeln!(
            s,
            "{} evaluations; volume {} → {}",
            self.evaluations.len(),
            dm3(self.start_volume_m3, true),
            dm3(self.volume_m3, true),
        );
        if let Some(a) = &self.verification {
            s.push_str(&a.report());
        }
        if !self.at_bounds.is_empty() {
            let _ = writeln!(s, "at bounds: {}", self.at_bounds.join(", "));
        }
        if self.feasible {
            if !self.binding.is_empty() {
                let _ = writeln!(
                    s,
                    "binding constraints (within 5 % of their limit): {}",
                    self.binding.join(", ")
                );
            }
        } else {
            let _ = writeln!(
                s,
                "INFEASIBLE within the bounds; binding constraints: {}",
                self.binding.join(", ")
            );
        }
        s
    }
}
