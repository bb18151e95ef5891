//! Calibration of the time model from buildability prints (the paper's "material calibration
//! prototypes", issue 11 §6): walls or cylinders printed until they failed (or stood to a
//! height) pin down one parameter of `[material.time]`.
//!
//! **Method.** One parameter p (e.g. `compressive_strength_rate`) is fitted, the others are
//! held at the spec's values. For a layer count n let p*(n) be the smallest p at which the state
//! "n layers complete" passes every check ([`crate::commands::buildability::check_layers`]); found by
//! bisection, assuming the checks only improve as p grows (true for every E, strength and rate
//! parameter: larger values mean a stiffer, stronger layer at every age). Then
//! - a print that **failed at layer k** says p*(k − 1) ≤ p < p*(k): layer k − 1 stood, layer k
//!   did not;
//! - a print that **stood to n** says p ≥ p*(n).
//!
//! The evidence is the intersection of these intervals. If it is not empty, the estimate is its
//! midpoint and its half-width the uncertainty (the data cannot tell values inside it apart). If
//! prints that failed disagree (scatter under equal conditions: Wolfs 2018's cylinders failed at
//! 25–31 layers), the intervals are disjoint: the estimate is the median of the interval
//! midpoints and the uncertainty spans all intervals. A print that **stood** above the value a
//! failure demands cannot be separated from it by this parameter: that is an error naming the
//! two prints (the model or the parameter choice cannot explain the data).
//!
//! Only states are checked, not whole prints: "state n passes" is taken to imply the states
//! before it pass (true for self-weight that grows with n and a strength that grows with age).

use serde::{Deserialize, Serialize};

use crate::analysis::green::FailureMode;
use crate::commands::buildability::{Buildability, BuildabilitySpec, Resolved, check_layers, run};
use crate::input::error::DesignError;

/// A time-model parameter that can be fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Parameter {
    /// E₀, Pa.
    YoungsModulus,
    /// Ė, Pa/s.
    YoungsModulusRate,
    /// f_c at age 0, Pa.
    CompressiveStrength,
    /// ḟ_c, Pa/s.
    CompressiveStrengthRate,
    /// c at age 0, Pa.
    Cohesion,
    /// ċ, Pa/s.
    CohesionRate,
}

impl Parameter {
    /// The field name in `[material.time]`.
    pub fn name(self) -> &'static str {
        match self {
            Parameter::YoungsModulus => "youngs_modulus",
            Parameter::YoungsModulusRate => "youngs_modulus_rate",
            Parameter::CompressiveStrength => "compressive_strength",
            Parameter::CompressiveStrengthRate => "compressive_strength_rate",
            Parameter::Cohesion => "cohesion",
            Parameter::CohesionRate => "cohesion_rate",
        }
    }

    /// The failure mode this parameter governs.
    pub fn governs(self) -> FailureMode {
        match self {
            Parameter::YoungsModulus | Parameter::YoungsModulusRate => FailureMode::Buckling,
            _ => FailureMode::Strength,
        }
    }
}

/// `[fit]`: which parameter, within which bounds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSpec {
    /// The parameter.
    pub parameter: Parameter,
    /// Lower bound of the search.
    pub min: f64,
    /// Upper bound of the search.
    pub max: f64,
}

/// The buildability spec of the prints: a path (relative to the calibration file) or inline.
pub type SpecSource = crate::input::resolve::Source<BuildabilitySpec>;

/// One observed print.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrintObservation {
    /// A name for the report.
    pub name: String,
    /// It collapsed when layer k was complete.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failed_at_layer: Option<usize>,
    /// It stood with n layers (printing stopped there).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stood_to: Option<usize>,
    /// Its layer time, s (default: the spec's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_time: Option<f64>,
}

/// The calibration file's buildability part (`kappe calibrate FILE` with `[buildability]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrintCalibrationFile {
    /// The common spec of the prints.
    pub buildability: SpecSource,
    /// The parameter to fit.
    pub fit: FitSpec,
    /// The prints.
    #[serde(rename = "print")]
    pub prints: Vec<PrintObservation>,
}

impl PrintCalibrationFile {
    /// Parse TOML (unknown fields are errors).
    pub fn from_toml_str(text: &str) -> Result<PrintCalibrationFile, DesignError> {
        crate::input::design::parse_toml(text)
    }
}

/// What one print says.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrintEvidence {
    /// Print name.
    pub name: String,
    /// p must be at least this.
    pub lower: f64,
    /// p must be below this (infinite: no upper bound).
    pub upper: f64,
    /// Failure layer the fitted model predicts for this print (None: stands to its height).
    pub predicted_failure_layer: Option<usize>,
    /// Its mode.
    pub predicted_mode: Option<FailureMode>,
    /// Observed failure layer.
    pub observed_failure_layer: Option<usize>,
}

/// The fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrintCalibration {
    /// The parameter.
    pub parameter: Parameter,
    /// Estimate.
    pub value: f64,
    /// Half-width of the interval of values the data allow (or of the scatter).
    pub uncertainty: f64,
    /// The interval [low, high] the data allow (intersection, or the span of the scatter).
    pub interval: [f64; 2],
    /// The intervals intersect (no scatter).
    pub consistent: bool,
    /// Per print.
    pub prints: Vec<PrintEvidence>,
    /// Plain-language explanation.
    pub explanation: String,
}

fn with_parameter(
    spec: &BuildabilitySpec,
    p: Parameter,
    value: f64,
    layer_time: Option<f64>,
    max_layers: usize,
) -> Result<Resolved, DesignError> {
    let mut s = spec.clone();
    let t = &mut s.material.time;
    let slot = match p {
        Parameter::YoungsModulus => &mut t.youngs_modulus,
        Parameter::YoungsModulusRate => &mut t.youngs_modulus_rate,
        Parameter::CompressiveStrength => &mut t.compressive_strength,
        Parameter::CompressiveStrengthRate => &mut t.compressive_strength_rate,
        Parameter::Cohesion => &mut t.cohesion,
        Parameter::CohesionRate => &mut t.cohesion_rate,
    };
    *slot = Some(value);
    if let Some(lt) = layer_time {
        s.process.layer_time = Some(lt);
        s.process.print_speed = None;
    }
    s.object.max_layers = max_layers.max(1);
    s.process.waits.clear();
    s.resolve()
}

/// Smallest p in [min, max] at which state n passes (max + 1 step: it fails even at max; min:
/// it passes at min). Resolution 1e-3 of the range (finer than the one-layer steps of the
/// observations resolve at any practical bound).
fn threshold(
    spec: &BuildabilitySpec,
    fit: &FitSpec,
    layer_time: Option<f64>,
    n: usize,
) -> Result<f64, DesignError> {
    if n == 0 {
        return Ok(f64::NEG_INFINITY);
    }
    let passes = |p: f64| -> Result<bool, DesignError> {
        let r = with_parameter(spec, fit.parameter, p, layer_time, n)?;
        Ok(check_layers(&r, n)?.failure.is_none())
    };
    if passes(fit.min)? {
        return Ok(f64::NEG_INFINITY);
    }
    if !passes(fit.max)? {
        return Ok(f64::INFINITY);
    }
    let (mut lo, mut hi) = (fit.min, fit.max);
    while hi - lo > 1e-3 * (fit.max - fit.min) {
        let mid = 0.5 * (lo + hi);
        if passes(mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(hi)
}

fn invalid(field: &'static str, value: String, allowed: String) -> DesignError {
    DesignError::Invalid {
        field,
        value,
        allowed,
    }
}

/// Fit the parameter (see the module docs).
pub fn calibrate_prints(
    spec: &BuildabilitySpec,
    fit: &FitSpec,
    prints: &[PrintObservation],
) -> Result<PrintCalibration, DesignError> {
    if !(fit.min.is_finite() && fit.max.is_finite() && fit.min >= 0.0 && fit.max > fit.min) {
        return Err(invalid(
            "fit.max",
            format!("[{}, {}]", fit.min, fit.max),
            "allowed: finite bounds 0 ≤ min < max".into(),
        ));
    }
    if prints.is_empty() {
        return Err(invalid(
            "print",
            "[]".into(),
            "allowed: at least one [[print]]".into(),
        ));
    }
    // The spec must be valid with the parameter anywhere in the bounds.
    with_parameter(spec, fit.parameter, fit.min, None, 1)?;
    let mut intervals = Vec::with_capacity(prints.len());
    for pr in prints {
        if let Some(lt) = pr.layer_time
            && !(lt.is_finite() && lt > 0.0)
        {
            return Err(invalid(
                "print.layer_time",
                format!("{lt} for {:?}", pr.name),
                "allowed: a finite layer time > 0 s".into(),
            ));
        }
        let (lower, upper) = match (pr.failed_at_layer, pr.stood_to) {
            (Some(k), None) if k >= 1 => (
                threshold(spec, fit, pr.layer_time, k - 1)?,
                threshold(spec, fit, pr.layer_time, k)?,
            ),
            (None, Some(n)) if n >= 1 => (threshold(spec, fit, pr.layer_time, n)?, f64::INFINITY),
            _ => {
                return Err(invalid(
                    "print.failed_at_layer",
                    format!(
                        "{:?} / stood_to {:?} for {:?}",
                        pr.failed_at_layer, pr.stood_to, pr.name
                    ),
                    "allowed: exactly one of failed_at_layer = k ≥ 1 or stood_to = n ≥ 1".into(),
                ));
            }
        };
        if upper == f64::NEG_INFINITY {
            return Err(invalid(
                "fit.min",
                format!("{} (print {:?})", fit.min, pr.name),
                format!(
                    "the model stands at the failure layer of {:?} for every {} ≥ {}: lower the \
                     bound, or fit another parameter",
                    pr.name,
                    fit.parameter.name(),
                    fit.min
                ),
            ));
        }
        if lower == f64::INFINITY {
            return Err(invalid(
                "fit.max",
                format!("{} (print {:?})", fit.max, pr.name),
                format!(
                    "the model fails below the height {:?} reached for every {} ≤ {}: raise \
                     the bound, or fit another parameter",
                    pr.name,
                    fit.parameter.name(),
                    fit.max
                ),
            ));
        }
        intervals.push((pr, lower, upper));
    }
    // Stood vs failed: a print that stood needs p ≥ its lower bound; a failure needs p < upper.
    let stood_lo = intervals
        .iter()
        .filter(|(p, ..)| p.stood_to.is_some())
        .max_by(|a, b| a.1.total_cmp(&b.1));
    let failed_hi = intervals
        .iter()
        .filter(|(p, ..)| p.failed_at_layer.is_some())
        .min_by(|a, b| a.2.total_cmp(&b.2));
    if let (Some(s), Some(f)) = (stood_lo, failed_hi)
        && s.1 >= f.2
    {
        return Err(invalid(
            "print",
            format!("{:?} and {:?}", s.0.name, f.0.name),
            format!(
                "the calibration set cannot separate stood from failed with {}: {:?} stood, which \
                 needs {} ≥ {:.6e}, but {:?} failed, which needs {} < {:.6e}. Fit another \
                 parameter, or check the prints (different material batches?)",
                fit.parameter.name(),
                s.0.name,
                fit.parameter.name(),
                s.1,
                f.0.name,
                fit.parameter.name(),
                f.2
            ),
        ));
    }
    let lo = intervals
        .iter()
        .map(|i| i.1)
        .fold(f64::NEG_INFINITY, f64::max);
    let hi = intervals.iter().map(|i| i.2).fold(f64::INFINITY, f64::min);
    let clamp = |v: f64| v.clamp(fit.min, fit.max);
    let (consistent, value, interval) = if lo < hi {
        let (a, b) = (clamp(lo), clamp(hi));
        (true, 0.5 * (a + b), [a, b])
    } else {
        let mut mids: Vec<f64> = intervals
            .iter()
            .map(|i| 0.5 * (clamp(i.1) + clamp(i.2)))
            .collect();
        mids.sort_by(f64::total_cmp);
        let m = mids.len();
        let median = if m % 2 == 1 {
            mids[m / 2]
        } else {
            0.5 * (mids[m / 2 - 1] + mids[m / 2])
        };
        let a = intervals
            .iter()
            .map(|i| clamp(i.1))
            .fold(f64::INFINITY, f64::min);
        let b = intervals
            .iter()
            .map(|i| clamp(i.2))
            .fold(f64::NEG_INFINITY, f64::max);
        (false, median, [a, b])
    };
    let mut evidence = Vec::with_capacity(intervals.len());
    // Prints with the same layer time share one prediction.
    let mut predicted: Vec<(Option<u64>, usize, Buildability)> = Vec::new();
    for (pr, lower, upper) in &intervals {
        let height = pr.failed_at_layer.or(pr.stood_to).unwrap_or(1) + 20;
        let key = pr.layer_time.map(f64::to_bits);
        let known = predicted
            .iter()
            .position(|(k, h, _)| *k == key && *h >= height);
        let b = match known {
            Some(i) => &predicted[i].2,
            None => {
                let r = with_parameter(spec, fit.parameter, value, pr.layer_time, height)?;
                predicted.push((key, height, run(&r, &|_| {})?));
                &predicted[predicted.len() - 1].2
            }
        };
        evidence.push(PrintEvidence {
            name: pr.name.clone(),
            lower: *lower,
            upper: *upper,
            predicted_failure_layer: b.failure_layer,
            predicted_mode: b.failure_mode,
            observed_failure_layer: pr.failed_at_layer,
        });
    }
    let name = fit.parameter.name();
    let mut modes: Vec<&str> = evidence
        .iter()
        .filter_map(|e| e.predicted_mode.map(|m| m.name()))
        .collect();
    modes.sort_unstable();
    modes.dedup();
    let mut explanation = if consistent {
        format!(
            "Every print is explained by {name} in [{:.6e}, {:.6e}]; the estimate {value:.6e} is \
             its midpoint and ± {:.3e} its half-width: values inside cannot be told apart by \
             these prints. ",
            interval[0],
            interval[1],
            0.5 * (interval[1] - interval[0])
        )
    } else {
        format!(
            "The prints disagree: no single {name} explains all of them (scatter between \
             nominally equal prints). The estimate {value:.6e} is the median of the prints' \
             intervals and [{:.6e}, {:.6e}] spans them; the scatter, not the fit, is the \
             uncertainty. ",
            interval[0], interval[1]
        )
    };
    explanation.push_str(&format!(
        "Only {name} was fitted; every other parameter of [material.time] was held at the spec's \
         value, so the result is conditional on them. {} governs {} failures; the fitted model \
         fails these prints by {}. ",
        name,
        fit.parameter.governs().name(),
        if modes.is_empty() {
            "nothing within their height".to_string()
        } else {
            modes.join(", ")
        }
    ));
    if modes.iter().any(|m| *m != fit.parameter.governs().name()) {
        explanation.push_str(&format!(
            "Where another mode governs, the prints bound {name} only from one side (it must not \
             fail earlier); fit the parameter of that mode as well. "
        ));
    }
    if intervals.iter().all(|i| i.0.stood_to.is_some()) {
        explanation.push_str("No print failed, so there is no upper bound: print one to failure. ");
    }
    if intervals.iter().all(|i| i.0.failed_at_layer.is_some()) && consistent {
        explanation.push_str(
            "Only failures: a print that stands (stopped before failing) would confirm the lower \
             bound directly. ",
        );
    }
    Ok(PrintCalibration {
        parameter: fit.parameter,
        value,
        uncertainty: 0.5 * (interval[1] - interval[0]),
        interval,
        consistent,
        prints: evidence,
        explanation: explanation.trim_end().to_string(),
    })
}

/// The buildability spec a print calibration file names: inline, or read relative to `base`
/// (the calibration file's directory).
///
/// # Errors
/// The spec cannot be read or does not parse.
pub fn resolve_spec(
    file: &PrintCalibrationFile,
    base: &std::path::Path,
) -> Result<BuildabilitySpec, crate::commands::calibrate_blf::SourceError> {
    use crate::commands::calibrate_blf::SourceError;
    use crate::input::resolve::ResolveError;
    file.buildability
        .resolve(base, |_| Ok(()), BuildabilitySpec::parse)
        .map_err(|e| match e {
            ResolveError::Read { path, source } => SourceError::ReadSpec { path, source },
            ResolveError::Invalid { path, source } => SourceError::Spec {
                path: path.unwrap_or_default(),
                source,
            },
        })
}

/// The calibration as the JSON document `kappe calibrate --json/--out` writes.
pub fn document(file: &PrintCalibrationFile, cal: &PrintCalibration) -> serde_json::Value {
    serde_json::json!({
        "format": "kappe.calibration.prints",
        "version": 1,
        "fit": file.fit,
        "calibration": cal,
    })
}

/// The calibration as the text report `kappe calibrate` prints (one line per print, the
/// estimate with its interval, the explanation), newline-terminated.
pub fn text_report(cal: &PrintCalibration) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let name = cal.parameter.name();
    let _ = writeln!(s, "Calibration of {name} from {} prints", cal.prints.len());
    let _ = writeln!(
        s,
        "  {:<12} {:>9} {:>14} {:>14} {:>10} {:>9}",
        "print", "observed", "lower", "upper", "predicted", "mode"
    );
    let f = |v: Option<usize>| v.map_or("stood".to_string(), |x| x.to_string());
    for e in &cal.prints {
        let _ = writeln!(
            s,
            "  {:<12} {:>9} {:>14.6e} {:>14.6e} {:>10} {:>9}",
            e.name,
            f(e.observed_failure_layer),
            e.lower,
            e.upper,
            f(e.predicted_failure_layer),
            e.predicted_mode.map_or("-", |m| m.name())
        );
    }
    let _ = writeln!(
        s,
        "  {name} = {:.6e} ± {:.3e}  (allowed by the data: [{:.6e}, {:.6e}])",
        cal.value, cal.uncertainty, cal.interval[0], cal.interval[1]
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "{}", cal.explanation);
    s
}
