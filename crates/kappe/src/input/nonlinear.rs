//! `[analysis.nonlinear]`: the collapse check of print states (docs/collapse.md). Plain data
//! with serde defaults, shared by design files and buildability specs.

use serde::{Deserialize, Serialize};

use crate::input::error::DesignError;

/// How the first layer is held on its bed (docs/collapse.md §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BaseRestraint {
    /// Bonded, no uplift: translations and rotations held (default).
    #[default]
    Clamped,
    /// Free to rotate (the edge of the bead lifts): translations held only. The lower bound.
    Pinned,
}

impl BaseRestraint {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            BaseRestraint::Clamped => "clamped",
            BaseRestraint::Pinned => "pinned",
        }
    }
}

/// The geometry a state's collapse path starts from (docs/collapse.md §8), before the mode
/// imperfection is added.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PathStart {
    /// The design geometry (default).
    #[default]
    Design,
    /// The as-printed geometry: the design moved by the deviation the print locks in (each
    /// layer laid at its programmed position onto the sagged earlier ones), i.e. the
    /// as-printed displacement minus the state's own linear displacement under its weight.
    AsPrinted,
}

impl PathStart {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            PathStart::Design => "design",
            PathStart::AsPrinted => "as_printed",
        }
    }

    fn is_design(&self) -> bool {
        *self == PathStart::Design
    }
}

/// `[analysis.nonlinear]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NonlinearSpec {
    /// Run the collapse check (default true when the table is given).
    pub enabled: bool,
    /// Imperfection amplitude w0, m (largest translation of the scaled lowest mode; 0: the
    /// perfect path). `None`: the rule w0 = max(t/20, 2H/450, placement_tolerance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub imperfection: Option<f64>,
    /// Measured lateral deviation of the beads from the programmed path, m (default 0: not
    /// measured; a term of the imperfection rule).
    pub placement_tolerance: f64,
    /// Restraint of the first layer on its bed (buildability objects).
    pub base: BaseRestraint,
    /// Imperfection signs run (1: the mode as found; 2: both, the lower collapse factor kept).
    /// `None`: 1 for a closed cylinder (its modes are sign-symmetric), 2 otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub signs: Option<usize>,
    /// Check Mohr–Coulomb strength and bed-joint sliding at the shell's faces along the path.
    pub material: bool,
    /// The geometry the path starts from: `"design"` (default) or `"as_printed"`.
    #[serde(skip_serializing_if = "PathStart::is_design")]
    pub start: PathStart,
}

impl Default for NonlinearSpec {
    fn default() -> Self {
        NonlinearSpec {
            enabled: true,
            imperfection: None,
            placement_tolerance: 0.0,
            base: BaseRestraint::Clamped,
            signs: None,
            material: true,
            start: PathStart::Design,
        }
    }
}

fn bad(field: &'static str, value: impl ToString, allowed: &str) -> DesignError {
    DesignError::Invalid {
        field,
        value: value.to_string(),
        allowed: format!("allowed: {allowed}"),
    }
}

impl NonlinearSpec {
    /// Check the values (`prefix` names the table in errors: `analysis.nonlinear`).
    pub fn validate(&self) -> Result<(), DesignError> {
        if let Some(w) = self.imperfection
            && !(w.is_finite() && (0.0..1.0).contains(&w))
        {
            return Err(bad(
                "analysis.nonlinear.imperfection",
                w,
                "0 ≤ w0 < 1 m (the largest translation of the imperfection)",
            ));
        }
        let p = self.placement_tolerance;
        if !(p.is_finite() && (0.0..1.0).contains(&p)) {
            return Err(bad(
                "analysis.nonlinear.placement_tolerance",
                p,
                "0 ≤ placement_tolerance < 1 m",
            ));
        }
        if let Some(s) = self.signs
            && !(1..=2).contains(&s)
        {
            return Err(bad(
                "analysis.nonlinear.signs",
                s,
                "1 (the mode as found) or 2 (both signs)",
            ));
        }
        Ok(())
    }

    /// The imperfection amplitude of a state with shell thickness `t` and height `h` above its
    /// lowest support (docs/collapse.md §1): the given `imperfection`, or
    /// max(t/20, 2h/450, placement_tolerance).
    pub fn amplitude(&self, t: f64, h: f64) -> f64 {
        self.imperfection.unwrap_or_else(|| {
            (t / 20.0)
                .max(2.0 * h / 450.0)
                .max(self.placement_tolerance)
        })
    }
}
