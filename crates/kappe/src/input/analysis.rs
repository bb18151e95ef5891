//! Options of the analysis (`crate::analysis::analyze`): which states get a buckling run, how many
//! modes, the ageing model, the shell mesh density. Plain data with serde defaults: the
//! `[analysis]` table of a design or study file.

use std::str::FromStr;

use kappe_fe::ElementKind;
use serde::{Deserialize, Serialize};

use super::ageing::Ageing;
use crate::input::error::DesignError;

/// Which states get a buckling analysis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum StateSelection {
    /// Every state (default; the paper used 25 % steps, Kappe checks every layer).
    #[default]
    All,
    /// States 0, N, 2N, … and the final state (`"every:N"`).
    Every(usize),
    /// States at every P % of print progress and the final state (`"25%"`).
    Percent(f64),
}

/// A `--states` value that is not `all`, `every:N` or `P%`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "state selection {given:?}: {reason}; allowed: \"all\", \"every:N\" with N ≥ 1, or \"P%\" with 0 < P ≤ 100"
)]
pub struct SelectionError {
    /// The text given.
    pub given: String,
    /// What is wrong with it.
    pub reason: String,
}

impl FromStr for StateSelection {
    type Err = SelectionError;

    /// Parse `"all"`, `"every:N"` or `"P%"`.
    ///
    /// ```
    /// use kappe::analysis::StateSelection;
    /// assert_eq!("every:4".parse::<StateSelection>().unwrap(), StateSelection::Every(4));
    /// assert_eq!("25%".parse::<StateSelection>().unwrap(), StateSelection::Percent(25.0));
    /// assert!("every:0".parse::<StateSelection>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        let err = |reason: &str| SelectionError {
            given: s.to_string(),
            reason: reason.to_string(),
        };
        if t.eq_ignore_ascii_case("all") {
            return Ok(StateSelection::All);
        }
        if let Some(n) = t.strip_prefix("every:") {
            let n: usize = n
                .trim()
                .parse()
                .map_err(|_| err("N is not a whole number"))?;
            if n == 0 {
                return Err(err("N must be at least 1"));
            }
            return Ok(StateSelection::Every(n));
        }
        if let Some(p) = t.strip_suffix('%') {
            let p: f64 = p.trim().parse().map_err(|_| err("P is not a number"))?;
            if !(p > 0.0 && p <= 100.0) {
                return Err(err("P is out of range"));
            }
            return Ok(StateSelection::Percent(p));
        }
        Err(err("unknown form"))
    }
}

impl std::fmt::Display for StateSelection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StateSelection::All => write!(f, "all"),
            StateSelection::Every(n) => write!(f, "every:{n}"),
            StateSelection::Percent(p) => write!(f, "{p}%"),
        }
    }
}

impl Serialize for StateSelection {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for StateSelection {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

impl StateSelection {
    /// The selected state indices among `total` states, ascending; always includes the final
    /// state. `Percent(p)` takes the states whose progress first reaches k·p % (k = 1, 2, …).
    pub fn indices(&self, total: usize) -> Vec<usize> {
        if total == 0 {
            return Vec::new();
        }
        let mut v: Vec<usize> = match *self {
            StateSelection::All => (0..total).collect(),
            StateSelection::Every(n) => (0..total).step_by(n.max(1)).collect(),
            StateSelection::Percent(p) => {
                let steps = (100.0 / p).ceil() as usize;
                (1..=steps)
                    .map(|k| {
                        let pp = (k as f64 * p / 100.0).min(1.0);
                        // progress of state i is (i + 1) / total
                        ((pp * total as f64).ceil() as usize).clamp(1, total) - 1
                    })
                    .collect()
            }
        };
        v.push(total - 1);
        v.sort_unstable();
        v.dedup();
        v
    }
}

fn default_modes() -> usize {
    1
}
fn default_stride() -> usize {
    1
}
fn default_true() -> bool {
    true
}
/// The default mesh-error tolerance of the buckling factor (0.5 %, issue 23).
pub const DEFAULT_BLF_TOLERANCE: f64 = 0.005;
fn default_blf_tolerance() -> f64 {
    DEFAULT_BLF_TOLERANCE
}
fn default_blf_max_split() -> usize {
    4
}
/// The shell element of the buckling analysis: the shear-deformable ANDES+DKMT (issue 17) —
/// printed shells are thick (span/t ≈ 40) and the Kirchhoff DKT overestimates their BLF.
fn default_element() -> ElementKind {
    ElementKind::AndesDkmt
}

/// Options of `crate::analysis::analyze`; every field has a serde default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisOptions {
    /// States that get a buckling analysis (stresses and overhangs: always every state).
    #[serde(default)]
    pub states: StateSelection,
    /// Buckling modes per state (the BLF is the lowest); ≥ 1.
    #[serde(default = "default_modes")]
    pub modes: usize,
    /// Layer ageing; `None`: E of the design everywhere.
    #[serde(default)]
    pub ageing: Option<Ageing>,
    /// Printed layers per shell mesh row (1 = every layer is a row).
    #[serde(default = "default_stride")]
    pub row_stride: usize,
    /// Run the buckling analysis at all (false: stresses and overhang only).
    #[serde(default = "default_true")]
    pub buckling: bool,
    /// Prove with a Sturm count that no lower factor was missed (one extra factorization).
    #[serde(default)]
    pub sturm_check: bool,
    /// Shell element (`kappe_fe::ElementKind` by name): `"andes_dkmt"` (default,
    /// Reissner–Mindlin: transverse shear of the thick printed shell), `"cst_dkt"` (the
    /// Kirchhoff element used before issue 17), `"andes_dkt"`, `"cst_dkmt"`.
    #[serde(default = "default_element")]
    pub element: ElementKind,
    /// A graded shell mesh along the print direction (`crate::analysis::graded`): every layer a row near
    /// the top, rows thinning out with depth, so the cost per state stops growing with the bay
    /// length (issue 15). `None` (default): every layer is a row.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grading: Option<Grading>,
    /// `[analysis.nonlinear]`: the collapse check (docs/collapse.md). `None` (default): off;
    /// the table given (even empty): on, with the defaults of
    /// [`crate::input::nonlinear::NonlinearSpec`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonlinear: Option<crate::input::nonlinear::NonlinearSpec>,
    /// Control the mesh error of every state's buckling factor (`kappe_fe::convergence`, docs/convergence.md,
    /// issue 23): the shell mesh and its 2×2 split, Richardson-extrapolated at order 1 (the
    /// safe side). `false`: the factor of the print-layer mesh alone, as before (up to ~4 %
    /// high on the default cap).
    #[serde(default = "default_true")]
    pub converged_blf: bool,
    /// Relative error allowed on the converged buckling factor (default 0.005): a state that
    /// could govern is refined further (up to `blf_max_split`) until its error estimate is
    /// within it.
    #[serde(default = "default_blf_tolerance")]
    pub blf_tolerance: f64,
    /// Largest number of splits per edge of the print-layer mesh (a power of two, 2…16).
    #[serde(default = "default_blf_max_split")]
    pub blf_max_split: usize,
    /// Solve the 2×2 split on an adaptive sample of the states and interpolate the mesh
    /// correction of the others (`crate::analysis::convergence`; the states that could govern
    /// are always solved). `false`: the split is solved in every state.
    #[serde(default = "default_true")]
    pub blf_sampling: bool,
    /// Solve the splits of the mesh-error pass with the two-level solver
    /// (`kappe_fe::twolevel`: PCG and LOBPCG preconditioned by the coarser mesh's LLᵀ, no LLᵀ of
    /// the split), falling back to the direct solve wherever its guards decline
    /// (docs/convergence.md, "The `twogrid` branch"). `false` (default): the direct solve.
    #[serde(default)]
    pub blf_two_level: bool,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        AnalysisOptions {
            states: StateSelection::All,
            modes: default_modes(),
            ageing: None,
            row_stride: default_stride(),
            buckling: true,
            sturm_check: false,
            element: default_element(),
            grading: None,
            nonlinear: None,
            converged_blf: true,
            blf_tolerance: DEFAULT_BLF_TOLERANCE,
            blf_max_split: default_blf_max_split(),
            blf_sampling: true,
            blf_two_level: false,
        }
    }
}

impl AnalysisOptions {
    /// These options with `blf_max_split` at most `n`: a single state solved outside
    /// [`crate::analysis::analyze`] stops at the 2×2 split (`n` = 2), the first pass of
    /// `analyze` at the print-layer mesh (`n` = 1; docs/convergence.md).
    pub fn with_split_at_most(&self, n: usize) -> Self {
        Self {
            blf_max_split: self.blf_max_split.min(n),
            ..self.clone()
        }
    }

    /// Check the options (typed errors naming the field).
    pub fn validate(&self) -> Result<(), DesignError> {
        let bad = |field: &'static str, value: String, allowed: &str| DesignError::Invalid {
            field,
            value,
            allowed: allowed.to_string(),
        };
        if let Some(n) = &self.nonlinear {
            n.validate()?;
        }
        if self.modes == 0 || self.modes > 50 {
            return Err(bad(
                "analysis.modes",
                self.modes.to_string(),
                "allowed: 1 ≤ modes ≤ 50",
            ));
        }
        if self.row_stride == 0 || self.row_stride > 16 {
            return Err(bad(
                "analysis.row_stride",
                self.row_stride.to_string(),
                "allowed: 1 ≤ layers per mesh row ≤ 16",
            ));
        }
        if !(self.blf_tolerance.is_finite()
            && self.blf_tolerance > 0.0
            && self.blf_tolerance <= 0.1)
        {
            return Err(bad(
                "analysis.blf_tolerance",
                self.blf_tolerance.to_string(),
                "allowed: 0 < relative tolerance ≤ 0.1",
            ));
        }
        if !(2..=16).contains(&self.blf_max_split) || !self.blf_max_split.is_power_of_two() {
            return Err(bad(
                "analysis.blf_max_split",
                self.blf_max_split.to_string(),
                "allowed: 2, 4, 8 or 16 splits per edge",
            ));
        }
        if let Some(a) = &self.ageing {
            if !(a.initial_modulus.is_finite() && a.initial_modulus > 0.0) {
                return Err(bad(
                    "analysis.ageing.initial_modulus",
                    a.initial_modulus.to_string(),
                    "allowed: E₀ > 0 Pa",
                ));
            }
            if !(a.rate.is_finite() && a.rate >= 0.0) {
                return Err(bad(
                    "analysis.ageing.rate",
                    a.rate.to_string(),
                    "allowed: Ė ≥ 0 Pa/s",
                ));
            }
            if let Some(m) = a.max_modulus
                && !(m.is_finite() && m >= a.initial_modulus)
            {
                return Err(bad(
                    "analysis.ageing.max_modulus",
                    m.to_string(),
                    "allowed: E_max ≥ E₀",
                ));
            }
        }
        Ok(())
    }
}

/// A graded shell mesh along the print direction: every layer is a row near the top of the state,
/// and the rows thin out with depth (see `crate::analysis::graded::graded_rows`); deep rows also thin out across the
/// span ([`Grading::transverse`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Grading {
    /// The newest `fine` layers are all rows (stride 1).
    pub fine: usize,
    /// Largest stride (layers per mesh row) deep in the stack; a power of two.
    pub max_stride: usize,
    /// Rows of every coarser zone (strides 2, 4, … below `max_stride`; the last zone is
    /// unbounded).
    pub zone_rows: usize,
    /// Largest transverse coarsening: a row at stride s keeps every c-th node along the layer,
    /// c the largest power of two with c·Δs ≤ s·pitch (near-square facets; Δs the node spacing
    /// along the layer, pitch the spacing of the layers), at most `transverse`. 1: off.
    pub transverse: usize,
    /// Largest stride in the start section (layers with id < 0). Their feet stand on the base
    /// plane, pinned one per layer: a coarse row there leaves the support line pinned only
    /// every few layers, which is where a coarse grading loses its accuracy (`crate::analysis::graded`). The
    /// start section has a fixed number of layers, so this costs the same at every length.
    pub start_stride: usize,
    /// Zone rows when the shell's membrane stresses are checked too (a strength model in
    /// `[material.time]`): a stress peak is local where the BLF is an integral over the shell, so
    /// the coarse zones start deeper ([`Self::for_stresses`]). Against the full mesh on a 0.6 m
    /// cap with linear E(t) and Mohr–Coulomb strength, the largest strength difference is 24 %
    /// (over, the safe side) with 4 zone rows, 4.5 % with 6, 2.1 % with 10 and under 2 % with 12
    /// (`tests/green_state.rs`).
    pub stress_zone_rows: usize,
}

impl Default for Grading {
    fn default() -> Self {
        // Checked against the full mesh in every state of the default and the 1.2 m cap
        // (`crate::analysis::graded`, `examples/graded_check.rs`).
        Grading {
            fine: 32,
            max_stride: 128,
            zone_rows: 4,
            transverse: 2,
            start_stride: 1,
            stress_zone_rows: 12,
        }
    }
}

impl Grading {
    /// The stride of a row `depth` layers below the top (0 = the top layer).
    pub fn stride_at(&self, depth: usize) -> usize {
        let max_stride = self.max_stride.max(1);
        let zone_rows = self.zone_rows.max(1);
        if depth < self.fine.max(1) {
            return 1;
        }
        let (mut start, mut stride) = (self.fine.max(1), 2usize);
        while stride < max_stride {
            let end = start + zone_rows * stride;
            if depth < end {
                return stride;
            }
            start = end;
            stride *= 2;
        }
        max_stride
    }

    /// The grading for a shell whose membrane stresses are checked as well as its BLF: at least
    /// [`Self::stress_zone_rows`] rows per zone.
    pub fn for_stresses(&self) -> Grading {
        Grading {
            zone_rows: self.zone_rows.max(self.stress_zone_rows),
            ..*self
        }
    }

    /// The stride of a row `depth` layers below the top, in the start section or not: the
    /// smaller of [`Self::stride_at`] and, in the start section, the largest power of two not
    /// above `start_stride`.
    pub fn row_stride(&self, depth: usize, in_start: bool) -> usize {
        let s = self.stride_at(depth);
        if !in_start {
            return s;
        }
        s.min(1usize << self.start_stride.max(1).ilog2())
    }
}
