//! The green-state check of one print state on its shell model (green-state.md §1, §3): the
//! three failure modes of fresh printed material, each with the age of the layers involved.
//!
//! The same function checks the cap's states and the buildability test objects; only the mesh
//! differs. Given the state's shell model, the age of every printed layer and the time model
//! ([`crate::input::material::TimeModel`]):
//! - **Elastic buckling.** E of every element from its layers' ages (an element joining two
//!   layers takes the mean of their moduli); the lowest positive linear buckling factor under
//!   self-weight must reach `blf_min` (1 for a real material: the load factor at which the
//!   state buckles).
//! - **Strength (plastic collapse).** Mohr–Coulomb on the membrane stresses σ = N/t of every
//!   element at its centroid (CST: constant per element), with c(t), φ(t) at the age of the
//!   younger layer the element touches. Utilisation 1 = yield; uniaxial compression −f_c gives
//!   exactly 1. Why Mohr–Coulomb: see [`crate::input::material`].
//! - **Bed-joint sliding.** The traction of the membrane stress tensor S (3×3, global) on the
//!   bed plane with unit normal n (the plane of the layer above the joint): σ_n = n·S·n,
//!   τ = |S·n − σ_n·n|, checked as |τ| ≤ c(t) + (−σ_n)·tan φ(t) with the younger layer's age.
//!   In the cap's centre section the leaning layer gives τ/σ_n = tan am (method.md §5).
//!
//! The membrane stresses come from the linear static solution that the buckling solve computes
//! anyway, so strength and sliding cost nothing extra when buckling is checked.

use kappe_fe::{BucklingOptions, FeError, Material, ShellModel};
use serde::Serialize;

use crate::input::error::DesignError;
use crate::input::material::TimeModel;

/// Which layers an element belongs to, by print index (0 = first printed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementLayers {
    /// The two layers whose moduli the element averages (equal for an element inside one
    /// layer).
    pub stiffness: (usize, usize),
    /// The younger layer the element touches: its age sets the strength and the joint's
    /// strength.
    pub younger: usize,
    /// Unit normal of the bed plane through the element (global frame).
    pub bed_normal: [f64; 3],
}

/// Options of [`check_state`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GreenOptions {
    /// Smallest admissible buckling factor.
    pub blf_min: f64,
    /// Check buckling.
    pub buckling: bool,
    /// Check strength (needs a strength model).
    pub strength: bool,
    /// Check bed-joint sliding (needs a strength model).
    pub sliding: bool,
    /// Relative tolerance of the Lanczos solve.
    pub tolerance: f64,
}

impl Default for GreenOptions {
    fn default() -> Self {
        GreenOptions {
            blf_min: 1.0,
            buckling: true,
            strength: true,
            sliding: true,
            // A relative residual of 1e-6 bounds the factor's relative error by about
            // 1e-12 / (relative gap to the next factor) (symmetric pencil: |λ − θ| ≤ ‖r‖²/gap),
            // far below any modelling error; it saves Lanczos steps over 1e-8.
            tolerance: 1e-6,
        }
    }
}

/// The failure modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureMode {
    /// Elastic buckling: BLF < BLF_min.
    Buckling,
    /// Plastic collapse: Mohr–Coulomb utilisation > 1.
    Strength,
    /// Bed-joint sliding: |τ| > c + σ_n·tan φ.
    Sliding,
    /// Nonlinear collapse of the imperfect state below `collapse_min` (limit point or the
    /// material along the path; `crate::analysis::collapse`).
    Collapse,
}

impl FailureMode {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            FailureMode::Buckling => "buckling",
            FailureMode::Strength => "strength",
            FailureMode::Sliding => "sliding",
            FailureMode::Collapse => "collapse",
        }
    }
}

/// The worst element of one check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WorstElement {
    /// Utilisation (demand / capacity; > 1 fails).
    pub utilisation: f64,
    /// Element index in the state's shell model.
    pub element: usize,
    /// The younger layer at the element (print index).
    pub layer: usize,
    /// Its age, s.
    pub age_s: f64,
    /// Membrane stresses there, Pa: for strength the principal stresses (σ₁ ≥ σ₂), for sliding
    /// (σ_n, τ) on the bed plane; tension positive.
    pub stresses: [f64; 2],
}

/// What the buckling check did.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "status")]
pub enum BucklingOutcome {
    /// Not checked.
    Skipped,
    /// Lowest positive factor.
    Factor {
        /// BLF.
        blf: f64,
    },
    /// No positive factor: the load cannot buckle the state.
    NoPositiveFactor,
    /// The shell is a mechanism (BLF 0).
    Mechanism {
        /// Where.
        message: String,
    },
}

/// The check of one state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GreenState {
    /// Buckling.
    pub buckling: BucklingOutcome,
    /// Worst strength utilisation (None: not checked).
    pub strength: Option<WorstElement>,
    /// Worst bed-joint sliding utilisation (None: not checked).
    pub sliding: Option<WorstElement>,
    /// The failing check with the largest utilisation (None: the state stands).
    pub failure: Option<FailureMode>,
    /// The check with the largest utilisation, failing or not (BLF_min/BLF for buckling).
    pub governing: Option<FailureMode>,
}

impl GreenState {
    /// BLF if one was found (0 for a mechanism).
    pub fn blf(&self) -> Option<f64> {
        match &self.buckling {
            BucklingOutcome::Factor { blf } => Some(*blf),
            BucklingOutcome::Mechanism { .. } => Some(0.0),
            _ => None,
        }
    }
}

/// Mode 1 of a state per shell node (`[ux, uy, uz, rx, ry, rz]`, any scale): the start of the
/// next state's eigensolve ([`check_state`]).
pub type ModeStart = Vec<[f64; 6]>;

/// Check one state (see the module docs). `model` holds the geometry, thickness, supports and
/// the base material (ν, γ); its materials are replaced by the aged ones. `ages[k]` is the age of
/// the layer with print index k, s. The Lanczos iteration starts from `start` when given (e.g.
/// the previous state's mode mapped onto this mesh), and this state's mode is returned for the
/// next one. The start saves steps only: the result meets the same residual bound
/// (`kappe_fe::BucklingOptions::start`).
///
/// # Errors
/// An invalid time model at an age, a model the solver refuses.
pub fn check_state(
    model: &mut ShellModel,
    elements: &[ElementLayers],
    ages: &[f64],
    time: &TimeModel,
    options: &GreenOptions,
    start: Option<ModeStart>,
) -> Result<(GreenState, Option<ModeStart>), DesignError> {
    let want_stress = (options.strength || options.sliding) && time.strength.is_some();
    let (buckling, static_result, mode) =
        solve_state(model, elements, ages, time, options, start, want_stress)?;
    let (strength, sliding) = match (want_stress, &static_result) {
        (true, Some(st)) => stress_checks(st, elements, ages, time, options),
        _ => (None, None),
    };

    let buckling_u = match &buckling {
        BucklingOutcome::Factor { blf } => Some(options.blf_min / blf),
        BucklingOutcome::Mechanism { .. } => Some(f64::INFINITY),
        _ => None,
    };
    let candidates = [
        (FailureMode::Buckling, buckling_u),
        (FailureMode::Strength, strength.map(|w| w.utilisation)),
        (FailureMode::Sliding, sliding.map(|w| w.utilisation)),
    ];
    let governing = candidates
        .iter()
        .filter_map(|(m, u)| u.map(|u| (*m, u)))
        .max_by(|a, b| a.1.total_cmp(&b.1));
    let failure = governing.filter(|(_, u)| *u > 1.0).map(|g| g.0);
    Ok((
        GreenState {
            buckling,
            strength,
            sliding,
            failure,
            governing: governing.map(|g| g.0),
        },
        mode,
    ))
}

/// The solves behind [`check_state`]: the aged moduli set on `model` (each element the
/// mean of its two layers' E), the buckling solve (when `options.buckling`) and the pre-buckling
/// static solution (also without buckling when `want_stress`), and mode 1. Shared with the
/// buildability reliability, which needs the whole stress field, not only the worst elements.
///
/// # Errors
/// A failed FE solve other than a mechanism.
pub fn solve_state(
    model: &mut ShellModel,
    elements: &[ElementLayers],
    ages: &[f64],
    time: &TimeModel,
    options: &GreenOptions,
    start: Option<ModeStart>,
    want_stress: bool,
) -> Result<SolvedState, DesignError> {
    let mut mode = None;
    set_aged_moduli(model, elements, ages, time);
    let (buckling, static_result) = if options.buckling {
        let opts = BucklingOptions {
            modes: 1,
            tolerance: options.tolerance,
            sturm_check: false,
            // `kappe_fe` blends the start with seeded noise (a cylinder's circumferential
            // harmonics are orthogonal: a start of one wave number alone never finds another).
            start,
            ..Default::default()
        };
        match kappe_fe::buckling(model, &opts) {
            Ok(mut r) => {
                if !r.modes.is_empty() {
                    mode = Some(r.modes.swap_remove(0));
                }
                let b = match r.factors.first() {
                    Some(&blf) => BucklingOutcome::Factor { blf },
                    None => BucklingOutcome::NoPositiveFactor,
                };
                (b, Some(r.static_result))
            }
            Err(FeError::Mechanism { free_dofs }) => {
                let dofs: Vec<String> = free_dofs.iter().take(4).map(|d| d.to_string()).collect();
                (
                    BucklingOutcome::Mechanism {
                        message: format!("mechanism (free DOFs: {})", dofs.join(", ")),
                    },
                    None,
                )
            }
            Err(e) => return Err(fe_error(e)),
        }
    } else if want_stress {
        (
            BucklingOutcome::Skipped,
            Some(kappe_fe::linear_static(model).map_err(fe_error)?),
        )
    } else {
        (BucklingOutcome::Skipped, None)
    };

    Ok((buckling, static_result, mode))
}

/// Every element's E the mean of its two layers' moduli at their ages (`ages[k]`: the age of
/// the layer with print index k, s); the model's own material for a constant time model.
pub fn set_aged_moduli(
    model: &mut ShellModel,
    elements: &[ElementLayers],
    ages: &[f64],
    time: &TimeModel,
) {
    let age = |k: usize| ages.get(k).copied().unwrap_or(0.0);
    let base = model.material_of(0);
    if !time.is_constant() {
        model.materials = elements
            .iter()
            .map(|e| Material {
                youngs_modulus: 0.5
                    * (time.modulus(age(e.stiffness.0)) + time.modulus(age(e.stiffness.1))),
                ..base
            })
            .collect();
    }
}

/// Buckling outcome, the static solution (None: not solved or a mechanism) and mode 1.
pub type SolvedState = (
    BucklingOutcome,
    Option<kappe_fe::StaticResult>,
    Option<ModeStart>,
);

/// The worst strength and the worst bed-joint sliding element of a state.
pub type StressWorst = (Option<WorstElement>, Option<WorstElement>);

/// [`CapGreen::state_checks`] of one cap state: its buckling, mode 1 (per network node) and
/// the worst strength and sliding elements (None for a mechanism).
pub type CapStateCheck = (
    crate::analysis::buckling::StateBuckling,
    crate::analysis::buckling::NetworkMode,
    Option<StressWorst>,
);

/// The strength and bed-joint sliding checks of a solved state: the worst element of each
/// (None when not asked for or without a strength model). `st` is the linear static solution of
/// the state's shell model, `elements` its elements' layers, `ages[k]` the age of layer k.
pub fn stress_checks(
    st: &kappe_fe::StaticResult,
    elements: &[ElementLayers],
    ages: &[f64],
    time: &TimeModel,
    options: &GreenOptions,
) -> StressWorst {
    let age = |k: usize| ages.get(k).copied().unwrap_or(0.0);
    let mut strength: Option<WorstElement> = None;
    let mut sliding: Option<WorstElement> = None;
    for (i, (res, info)) in st.elements.iter().zip(elements).enumerate() {
        let t = age(info.younger);
        let Some(mc) = time.mohr_coulomb(t) else {
            continue;
        };
        let [sx, sy, sxy] = res.membrane_stress();
        if options.strength {
            let (s1, s2) = principal(sx, sy, sxy);
            let u = mc.utilisation(s1, s2);
            if strength.is_none_or(|w| u > w.utilisation) {
                strength = Some(WorstElement {
                    utilisation: u,
                    element: i,
                    layer: info.younger,
                    age_s: t,
                    stresses: [s1, s2],
                });
            }
        }
        if options.sliding {
            let (sn, tau) = bed_traction(&res.frame, [sx, sy, sxy], info.bed_normal);
            let u = mc.sliding_utilisation(tau, sn);
            if sliding.is_none_or(|w| u > w.utilisation) {
                sliding = Some(WorstElement {
                    utilisation: u,
                    element: i,
                    layer: info.younger,
                    age_s: t,
                    stresses: [sn, tau],
                });
            }
        }
    }
    (strength, sliding)
}

fn fe_error(e: FeError) -> DesignError {
    DesignError::FormFinding(format!("green-state shell analysis: {e}"))
}

/// In-plane principal stresses (σ₁ ≥ σ₂) of a plane stress state.
pub fn principal(sx: f64, sy: f64, sxy: f64) -> (f64, f64) {
    let m = 0.5 * (sx + sy);
    let r = (0.25 * (sx - sy).powi(2) + sxy * sxy).sqrt();
    (m + r, m - r)
}

/// Normal stress and shear magnitude of the membrane stress `[σx, σy, τxy]` (element frame with
/// rows e1, e2, e3) on the plane with global unit normal `n`.
pub fn bed_traction(frame: &[[f64; 3]; 3], s: [f64; 3], n: [f64; 3]) -> (f64, f64) {
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // n in the element frame; the out-of-plane component carries no membrane stress.
    let (n1, n2) = (dot(&frame[0], &n), dot(&frame[1], &n));
    let t1 = s[0] * n1 + s[2] * n2;
    let t2 = s[2] * n1 + s[1] * n2;
    let traction: [f64; 3] = std::array::from_fn(|k| t1 * frame[0][k] + t2 * frame[1][k]);
    let sn = dot(&traction, &n);
    let shear: [f64; 3] = std::array::from_fn(|k| traction[k] - sn * n[k]);
    (sn, dot(&shear, &shear).sqrt())
}

/// The green-state inputs of a cap's analysis: the time model, the schedule and the print
/// index of every layer id.
#[derive(Debug, Clone)]
pub struct CapGreen {
    /// The design's time model.
    pub time: TimeModel,
    /// The cap's schedule (path length / speed + waits).
    pub schedule: crate::schedule::Schedule,
    index_of: std::collections::HashMap<i32, usize>,
    bed_normal: [f64; 3],
}

impl CapGreen {
    /// From a designed cap with its schedule from path length / print speed and the waits
    /// (errors: an invalid time model or schedule).
    pub fn new(cap: &crate::form::cap::Cap) -> Result<CapGreen, DesignError> {
        CapGreen::with_schedule(cap, None)
    }

    /// From a designed cap and the schedule of its timed robot plan (`None`: path length /
    /// print speed and the waits, [`crate::schedule::cap_schedule`]).
    pub fn with_schedule(
        cap: &crate::form::cap::Cap,
        schedule: Option<&crate::schedule::Schedule>,
    ) -> Result<CapGreen, DesignError> {
        let n = cap.frame.n;
        Ok(CapGreen {
            time: cap.design.time_model()?,
            schedule: match schedule {
                Some(s) => s.clone(),
                None => crate::schedule::cap_schedule(cap)?,
            },
            index_of: cap
                .sections
                .layers
                .iter()
                .enumerate()
                .map(|(q, l)| (l.id, q))
                .collect(),
            bed_normal: [n.x, n.y, n.z],
        })
    }

    /// E of every printed layer (by id) at the state with top print index `top`; empty for the
    /// constant model (the shell then uses `[material] youngs_modulus` everywhere, exactly as
    /// without a time model).
    pub fn layer_moduli(
        &self,
        cap: &crate::form::cap::Cap,
        top: usize,
    ) -> std::collections::HashMap<i32, f64> {
        if self.time.is_constant() {
            return std::collections::HashMap::new();
        }
        let ages = self.schedule.ages(top + 1);
        cap.sections
            .layers
            .iter()
            .zip(ages)
            .map(|(l, t)| (l.id, self.time.modulus(t)))
            .collect()
    }

    /// Strength and bed-joint sliding of the state with top print index `top` (None: no
    /// strength model, or a single layer without a shell). One linear static solve of the
    /// state's shell with `material` (its E per layer already aged).
    pub fn stress_checks(
        &self,
        state: &crate::form::states::State,
        material: &crate::analysis::shell::ShellMaterial,
        row_stride: usize,
        top: usize,
    ) -> Result<Option<StressWorst>, DesignError> {
        if self.time.strength.is_none() {
            return Ok(None);
        }
        let Ok(shell) = crate::analysis::shell::state_shell(state, material, row_stride) else {
            return Ok(None);
        };
        let st = match kappe_fe::linear_static(&shell.model) {
            Ok(st) => st,
            // A mechanism is reported by the buckling check.
            Err(FeError::Mechanism { .. }) => return Ok(None),
            Err(e) => {
                return Err(DesignError::State {
                    state: top,
                    message: format!("static analysis for the strength check failed: {e}"),
                });
            }
        };
        Ok(Some(self.stress_checks_on(&shell, &st, top)))
    }

    /// Buckling, strength and bed-joint sliding of one cap state from one solve: the state's
    /// shell (on the graded mesh of `options.grading` when set, `crate::analysis::graded`) with
    /// `material` (E per layer already aged), its buckling solve, and the strength and sliding
    /// checks on that solve's static solution. The mode is keyed by the state's own network
    /// nodes either way. `None` without a strength model or without a shell (a single layer):
    /// the caller's plain buckling path then covers the state.
    ///
    /// On a graded mesh ([`crate::analysis::graded::Grading::for_stresses`]) an element spanning several
    /// layers carries their mean membrane stress and is checked with the age of its upper
    /// (younger, weaker) row: the stress peak at a coarse row is smoothed, its strength taken low
    /// (`tests/green_state.rs` states how far from the full mesh this lands).
    pub fn state_checks(
        &self,
        state: &crate::form::states::State,
        material: &crate::analysis::shell::ShellMaterial,
        options: &crate::analysis::AnalysisOptions,
        top: usize,
    ) -> Result<Option<CapStateCheck>, DesignError> {
        if self.time.strength.is_none() {
            return Ok(None);
        }
        // Stresses are checked here too: the grading's finer zones for stresses.
        let grading = options
            .grading
            .as_ref()
            .map(crate::analysis::graded::Grading::for_stresses);
        let analysed = crate::analysis::graded::AnalysedState::new(state, grading.as_ref());
        let Ok(shell) =
            crate::analysis::shell::state_shell(analysed.state(), material, options.row_stride)
        else {
            return Ok(None);
        };
        let crate::analysis::buckling::ShellSolve {
            buckling: b,
            mut mode,
            static_result: st,
        } = crate::analysis::buckling::shell_buckling(&shell, state.index, options)?;
        for (k, _) in &mut mode {
            *k = analysed.full_index(*k).unwrap_or(*k);
        }
        let worst = st.map(|st| self.stress_checks_on(&shell, &st, top));
        Ok(Some((b, mode, worst)))
    }

    /// Strength and bed-joint sliding of the state with top print index `top` from the static
    /// solution `st` of its shell model `shell` (the one its buckling solve computed).
    pub fn stress_checks_on(
        &self,
        shell: &crate::analysis::shell::StateShell,
        st: &kappe_fe::StaticResult,
        top: usize,
    ) -> StressWorst {
        let elements = self.element_layers(shell);
        let ages = self.schedule.ages(top + 1);
        stress_checks(st, &elements, &ages, &self.time, &GreenOptions::default())
    }

    /// The print indices of the layers of every element of a state's shell (by layer id) and
    /// the cap's bed normal: what the strength and sliding checks need per element.
    pub fn element_layers(&self, shell: &crate::analysis::shell::StateShell) -> Vec<ElementLayers> {
        shell
            .element_layers
            .iter()
            .map(|(a, b)| {
                let qa = self.index_of.get(a).copied().unwrap_or(0);
                let qb = self.index_of.get(b).copied().unwrap_or(0);
                ElementLayers {
                    stiffness: (qa, qb),
                    younger: qa.max(qb),
                    bed_normal: self.bed_normal,
                }
            })
            .collect()
    }
}
