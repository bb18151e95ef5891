//! Calibration of the buckling threshold from printed prototypes (paper §3.3).
//!
//! The linear BLF of a green-earth shell is computed with an analysis modulus E that is not the
//! real green stiffness (buckling.md §1, §6). The paper therefore calibrates: prototypes that
//! stood or collapsed tell which values of the computed BLF are safe. Per prototype:
//! - **stood**: every state had a BLF the real structure survived, so BLF_min ≤ min BLF over
//!   its states;
//! - **failed at layer k** (k layers printed, counted from 1 in print order): the state with k
//!   layers collapsed, so BLF_min > its BLF; the states before it stood, so BLF_min ≤ their
//!   minimum.
//!
//! The evidence bounds the threshold to an interval (lower, upper]. Kappe takes **upper**, the
//! smallest BLF that a prototype is known to have survived (values inside the interval are
//! unproven either way). Because BLF ∝ E for a homogeneous material (buckling.md A11), the same
//! result can be read as an effective modulus E_eff = E / BLF_min with BLF_min = 1.
//!
//! If the prototypes cannot be separated (a failure above a survival), Kappe takes the lower
//! bound (rejecting every observed failure) and names the conflicting prototypes.

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::analysis::{AnalysisOptions, BucklingStatus, state_buckling, state_material};
use crate::form::cap::{Cap, design_cap};
use crate::input::design::Design;
use crate::input::error::DesignError;

/// What happened to a prototype.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// It was printed to the end and stood.
    Stood,
    /// It collapsed (see `failed_at_layer`).
    Failed,
}

/// A design given by path (relative to the prototype file) or inline.
pub type DesignSource = crate::input::resolve::Source<Design>;

/// One printed prototype.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prototype {
    /// A name for the report.
    pub name: String,
    /// Its design.
    pub design: DesignSource,
    /// Stood or failed.
    pub outcome: Outcome,
    /// For `failed`: the number of layers printed when it collapsed, counted from 1 in print
    /// order (start layers first).
    #[serde(default)]
    pub failed_at_layer: Option<usize>,
}

/// The prototype file (`kappe calibrate PROTOTYPES.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrototypeFile {
    /// Analysis options for the prototypes' BLFs (same defaults as `kappe design`).
    #[serde(default)]
    pub analysis: AnalysisOptions,
    /// The prototypes.
    #[serde(rename = "prototype")]
    pub prototypes: Vec<Prototype>,
}

impl PrototypeFile {
    /// Parse TOML; unknown fields and a `failed` prototype without `failed_at_layer` (or a
    /// `stood` one with it) are errors naming the entry.
    pub fn from_toml_str(text: &str) -> Result<PrototypeFile, DesignError> {
        let file: PrototypeFile = crate::input::design::parse_toml(text)?;
        file.analysis.validate()?;
        if file.prototypes.is_empty() {
            return Err(DesignError::Invalid {
                field: "prototype",
                value: "[]".into(),
                allowed: "allowed: at least one [[prototype]]".into(),
            });
        }
        for p in &file.prototypes {
            match (p.outcome, p.failed_at_layer) {
                (Outcome::Failed, None) => {
                    return Err(DesignError::Invalid {
                        field: "prototype.failed_at_layer",
                        value: format!("missing for {:?}", p.name),
                        allowed: "allowed: a failed prototype needs failed_at_layer = k ≥ 1 \
                                  (layers printed when it collapsed)"
                            .into(),
                    });
                }
                (Outcome::Failed, Some(0)) => {
                    return Err(DesignError::Invalid {
                        field: "prototype.failed_at_layer",
                        value: format!("0 for {:?}", p.name),
                        allowed: "allowed: k ≥ 1 (counted from 1 in print order)".into(),
                    });
                }
                (Outcome::Stood, Some(k)) => {
                    return Err(DesignError::Invalid {
                        field: "prototype.failed_at_layer",
                        value: format!("{k} for {:?}", p.name),
                        allowed: "allowed only with outcome = \"failed\"".into(),
                    });
                }
                _ => {}
            }
        }
        Ok(file)
    }
}

/// What one prototype says about the threshold.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evidence {
    /// Prototype name.
    pub name: String,
    /// Stood or failed.
    pub outcome: Outcome,
    /// Analysis modulus of its design, Pa.
    pub youngs_modulus: f64,
    /// Number of states of its design.
    pub states: usize,
    /// Smallest BLF over the states it survived (None: no state with a shell survived).
    pub min_blf_survived: Option<f64>,
    /// State index of that minimum.
    pub min_blf_state: Option<usize>,
    /// BLF of the state that collapsed (failed prototypes).
    pub blf_at_failure: Option<f64>,
    /// Index of the state that collapsed.
    pub failure_state: Option<usize>,
}

/// The derived threshold and how it was derived.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// Per prototype.
    pub evidence: Vec<Evidence>,
    /// BLF_min must exceed this (largest BLF of a collapsed state), if any failed.
    pub lower: Option<f64>,
    /// BLF_min may be at most this (smallest BLF survived), if any survived.
    pub upper: Option<f64>,
    /// The evidence is consistent (lower < upper, or one side missing).
    pub separable: bool,
    /// The derived BLF_min (with each prototype's analysis E).
    pub blf_min: f64,
    /// E_eff = E / BLF_min, Pa: with it, BLF_min = 1 is equivalent (only when all prototypes
    /// share one analysis E).
    pub effective_modulus: Option<f64>,
    /// Plain-language explanation.
    pub explanation: String,
}

/// BLFs of the given states of `design`, in state order (states without a shell are left out).
fn state_blfs(
    cap: &Cap,
    options: &AnalysisOptions,
    states: &[usize],
) -> Result<BTreeMap<usize, f64>, DesignError> {
    let total = cap.states.len();
    let found: Vec<Option<(usize, f64)>> = states
        .par_iter()
        .filter(|&&s| s < total)
        .map(|&s| {
            let st = cap.state(s)?;
            let mat = state_material(
                cap,
                options,
                s,
                Some(&crate::analysis::green::CapGreen::new(cap)?),
            );
            let b = state_buckling(
                &st,
                &mat,
                &options.with_split_at_most(2),
                &Default::default(),
            )?
            .buckling;
            match b.status {
                BucklingStatus::Analysed => Ok(b.factors.first().map(|&f| (s, f))),
                // A mechanism cannot stand: BLF 0.
                BucklingStatus::Mechanism => Ok(Some((s, 0.0))),
                _ => Ok(None),
            }
        })
        .collect::<Result<_, DesignError>>()?;
    Ok(found.into_iter().flatten().collect())
}

/// A prototype with its design resolved.
#[derive(Debug, Clone)]
pub struct Resolved {
    /// The prototype entry.
    pub prototype: Prototype,
    /// Its design.
    pub design: Design,
}

/// Derive BLF_min from the prototypes (see the module docs).
pub fn calibrate(
    prototypes: &[Resolved],
    options: &AnalysisOptions,
) -> Result<Calibration, DesignError> {
    options.validate()?;
    let mut evidence = Vec::with_capacity(prototypes.len());
    for r in prototypes {
        let p = &r.prototype;
        // The states to analyse: the selection, plus (for a failure) the collapsed state and
        // every state before it, which all stood.
        let cap = design_cap(&r.design, crate::Context::default())?;
        let total = cap.states.len();
        let (survived_upto, failure_state) = match (p.outcome, p.failed_at_layer) {
            (Outcome::Failed, Some(k)) => {
                if k > total {
                    return Err(DesignError::Invalid {
                        field: "prototype.failed_at_layer",
                        value: format!("{k} for {:?}", p.name),
                        allowed: format!("allowed: 1 ≤ k ≤ {total} (the layers of its design)"),
                    });
                }
                (k - 1, Some(k - 1))
            }
            _ => (total, None),
        };
        let mut states: Vec<usize> = options
            .states
            .indices(total)
            .into_iter()
            .filter(|&s| s < survived_upto)
            .collect();
        if survived_upto > 0 && survived_upto <= total {
            states.push(survived_upto - 1);
        }
        states.extend(failure_state);
        states.sort_unstable();
        states.dedup();
        let blfs = state_blfs(&cap, options, &states)?;
        let min_survived = blfs
            .iter()
            .filter(|(s, _)| **s < survived_upto)
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map(|(s, f)| (*s, *f));
        let at_failure = failure_state.and_then(|s| blfs.get(&s).copied());
        if failure_state.is_some() && at_failure.is_none() {
            return Err(DesignError::Invalid {
                field: "prototype.failed_at_layer",
                value: format!("{:?} for {:?}", p.failed_at_layer, p.name),
                allowed: "allowed: a state with at least two layers (a single layer on the bed \
                          has no buckling factor)"
                    .into(),
            });
        }
        evidence.push(Evidence {
            name: p.name.clone(),
            outcome: p.outcome,
            youngs_modulus: r.design.material.youngs_modulus,
            states: total,
            min_blf_survived: min_survived.map(|m| m.1),
            min_blf_state: min_survived.map(|m| m.0),
            blf_at_failure: at_failure,
            failure_state,
        });
    }
    Ok(derive(evidence))
}

/// The threshold from the evidence (pure; see the module docs).
pub fn derive(evidence: Vec<Evidence>) -> Calibration {
    let lower = evidence
        .iter()
        .filter_map(|e| e.blf_at_failure.map(|b| (b, e.name.clone())))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    let upper = evidence
        .iter()
        .filter_map(|e| e.min_blf_survived.map(|b| (b, e.name.clone())))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let (separable, blf_min, mut explanation) = match (lower.clone(), upper.clone()) {
        (Some((lo, lo_name)), Some((hi, hi_name))) if lo < hi => (
            true,
            hi,
            format!(
                "Prototype {lo_name:?} collapsed in a state with BLF {lo:.4}, so BLF_min must exceed \
                 {lo:.4}; prototype {hi_name:?} survived a state with BLF {hi:.4}, the smallest BLF \
                 any prototype survived. Every value in ({lo:.4}, {hi:.4}] separates the prototypes; \
                 BLF_min = {hi:.4} is the smallest value with direct evidence of standing."
            ),
        ),
        (Some((lo, lo_name)), Some((hi, hi_name))) => (
            false,
            lo,
            format!(
                "The prototypes cannot be separated by the BLF: {lo_name:?} collapsed at BLF {lo:.4} \
                 but {hi_name:?} survived BLF {hi:.4} ≤ {lo:.4}. Something other than linear \
                 buckling (material scatter, stresses, print defects) decided; BLF_min = {lo:.4} \
                 rejects every observed failure and is conservative."
            ),
        ),
        (Some((lo, lo_name)), None) => (
            true,
            lo,
            format!(
                "Only failures: {lo_name:?} collapsed at BLF {lo:.4}, so BLF_min must exceed {lo:.4}. \
                 No prototype stood, so no value is proven safe; print one that stands to close the \
                 interval."
            ),
        ),
        (None, Some((hi, hi_name))) => (
            true,
            hi,
            format!(
                "No failures: the smallest BLF survived is {hi:.4} ({hi_name:?}), so BLF_min = \
                 {hi:.4} is proven safe; lower values are not disproven."
            ),
        ),
        (None, None) => (
            false,
            f64::NAN,
            "No prototype has a state with a buckling factor (single layers only).".to_string(),
        ),
    };
    let e0 = evidence.first().map(|e| e.youngs_modulus);
    let same_e = e0.is_some_and(|e0| evidence.iter().all(|e| e.youngs_modulus == e0));
    let effective_modulus = match (same_e, e0) {
        (true, Some(e)) if blf_min.is_finite() && blf_min > 0.0 => Some(e / blf_min),
        _ => None,
    };
    if let (Some(ee), Some(e)) = (effective_modulus, e0) {
        explanation.push_str(&format!(
            " Equivalently, since the BLF is proportional to E: with the analysis modulus \
             {:.3} MPa scaled to E_eff = {:.3} MPa, BLF_min = 1.",
            e / 1e6,
            ee / 1e6
        ));
    }
    Calibration {
        evidence,
        lower: lower.map(|l| l.0),
        upper: upper.map(|u| u.0),
        separable,
        blf_min,
        effective_modulus,
        explanation,
    }
}

/// A file that a calibration file names could not be read or is invalid (each with its cause
/// as the error's source, so the CLI prints the same chain as before).
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// An inline prototype design does not validate.
    #[error("prototype {name:?}: invalid design")]
    InlineDesign {
        /// Prototype.
        name: String,
        /// Why.
        #[source]
        source: DesignError,
    },
    /// A prototype's design file cannot be read.
    #[error("prototype {name:?}: cannot read {}", path.display())]
    Read {
        /// Prototype.
        name: String,
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A prototype's design file is invalid.
    #[error("prototype {name:?}: invalid design file {}", path.display())]
    Design {
        /// Prototype.
        name: String,
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        #[source]
        source: DesignError,
    },
    /// The buildability spec of a print calibration cannot be read.
    #[error("cannot read the buildability spec {}", path.display())]
    ReadSpec {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The buildability spec of a print calibration is invalid.
    #[error("invalid buildability spec {}", path.display())]
    Spec {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        #[source]
        source: DesignError,
    },
}

/// Whether a calibration file's text is the buildability-prints form (a top-level
/// `buildability` key, [`crate::commands::calibrate_print`]) rather than prototypes.
pub fn is_prints_file(text: &str) -> bool {
    text.parse::<toml::Table>()
        .is_ok_and(|t| t.contains_key("buildability"))
}

/// The designs of a prototype file: inline ones validated, paths read relative to `base` (the
/// prototype file's directory).
///
/// # Errors
/// The first prototype whose design cannot be read or is invalid.
pub fn resolve_prototypes(
    file: &PrototypeFile,
    base: &std::path::Path,
) -> Result<Vec<Resolved>, SourceError> {
    file.prototypes
        .iter()
        .map(|p| {
            use crate::input::resolve::ResolveError;
            let design = p
                .design
                .resolve(base, Design::validate, Design::from_toml_str)
                .map_err(|e| match e {
                    ResolveError::Read { path, source } => SourceError::Read {
                        name: p.name.clone(),
                        path,
                        source,
                    },
                    ResolveError::Invalid { path: None, source } => SourceError::InlineDesign {
                        name: p.name.clone(),
                        source,
                    },
                    ResolveError::Invalid {
                        path: Some(path),
                        source,
                    } => SourceError::Design {
                        name: p.name.clone(),
                        path,
                        source,
                    },
                })?;
            Ok(Resolved {
                prototype: p.clone(),
                design,
            })
        })
        .collect()
}

/// The calibration as the JSON document `kappe calibrate --json/--out` writes.
pub fn document(file: &PrototypeFile, cal: &Calibration) -> serde_json::Value {
    serde_json::json!({
        "format": "kappe.calibration",
        "version": 1,
        "analysis": file.analysis,
        "calibration": cal,
    })
}

/// The calibration as the text report `kappe calibrate` prints (one line per prototype, the
/// threshold, the explanation), newline-terminated.
pub fn text_report(cal: &Calibration) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(s, "Calibration from {} prototypes", cal.evidence.len());
    let _ = writeln!(
        s,
        "  {:<16} {:>7} {:>8} {:>14} {:>14}",
        "prototype", "outcome", "E [MPa]", "min BLF stood", "BLF at failure"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
    for e in &cal.evidence {
        let _ = writeln!(
            s,
            "  {:<16} {:>7} {:>8.3} {:>14} {:>14}",
            e.name,
            match e.outcome {
                Outcome::Stood => "stood",
                Outcome::Failed => "failed",
            },
            e.youngs_modulus / 1e6,
            f(e.min_blf_survived),
            f(e.blf_at_failure)
        );
    }
    let _ = writeln!(s, "  BLF_min = {:.4}", cal.blf_min);
    if let Some(ee) = cal.effective_modulus {
        let _ = writeln!(
            s,
            "  (equivalently E_eff = {:.3} MPa with BLF_min = 1)",
            ee / 1e6
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "{}", cal.explanation);
    s
}
