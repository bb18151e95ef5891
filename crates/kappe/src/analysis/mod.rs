//! Analysis of every print state against the structural constraints of method.md §3, and the
//! constraint report (the paper's design loop, Figure 3: "analyse every state globally and
//! locally").
//!
//! Per state:
//! - **Stresses.** Every element's normal stress σ = N / A (compression negative), with
//!   A = lw·lh for arch segments (along a layer) and A = lw·l_trib for the bed joints between
//!   layers (the column edges), from CEM's fixed-geometry force pass over the constructed
//!   network ([`crate::form::forces`]). Checked against σ_min ≤ σ ≤ σ_max.
//! - **Overhang.** |l_o| of every printed layer over the preceding one
//!   ([`overhang::layer_overhangs`]) against l_o,max.
//! - **Buckling.** The lowest positive linear buckling factor of the state's shell model
//!   ([`crate::analysis::shell`], `kappe_fe`) under self-weight, against BLF_min. A state whose shell
//!   model is a mechanism is reported with the layer where the free motion sits.
//!
//! The report ([`ConstraintResult`]) gives for each constraint its limit, the worst value over all
//! states, where it occurs (state and element) and pass/fail; the design passes only if all hold.
//!
//! Stresses and overhangs are cheap and always checked in every state; [`StateSelection`] thins
//! out only the buckling analysis (the final state is always included, as it carries the most
//! load). States are analysed in parallel (rayon) and reported in print order.
//!
//! Tolerances: a stress passes if it is within `1e-9·max|σ|` of its limit (the relative size of
//! the force pass's residuals, method.md §9), so that σ_max = 0 is not failed by round-off.
//!
//! The modules follow the analysis: [`buckling`] (the shell buckling run of one state, on the
//! mesh of [`shell`] or [`graded`]), [`convergence`] (the converged factor), [`asprinted`] (the
//! shape as printed), [`green`] (the aged material's strength), [`bending`] (a corrugated
//! state's bending), [`collapse`] (the nonlinear path), [`reliability`] and
//! [`blf_sensitivity`] (FORM), and [`check`] ([`analyze`]: every state against every
//! constraint, and the report). The element stresses and the overhangs come with the form
//! ([`crate::form::stresses`], [`crate::form::overhang`]).

pub(crate) mod asprinted;
pub(crate) mod bending;
pub(crate) mod blf_sensitivity;
pub(crate) mod buckling;
pub(crate) mod check;
pub(crate) mod collapse;
pub mod collapse_reliability;
pub(crate) mod convergence;
pub mod design_monte_carlo;
pub(crate) mod graded;
pub(crate) mod green;
pub(crate) mod reliability;
pub(crate) mod shell;

pub use crate::form::overhang::layer_overhangs;
pub use crate::form::stresses::{ElementKind, ElementStress, STRESS_REL_TOL, element_stresses};
pub use crate::input::ageing::Ageing;
pub use crate::input::analysis::{AnalysisOptions, SelectionError, StateSelection};
pub use buckling::{
    BucklingStatus, NetworkMode, ShellSolve, StateBuckling, shell_buckling, state_buckling,
    state_material,
};
pub use check::{Analysis, ConstraintResult, Request, StateAnalysis, Timings, analyze};

// The items users outside the crate need (the CLI, Python, the designer, the tests).
pub use asprinted::{
    AsPrinted, Increment, NodeKey, StateDeviation, accumulate, cap_as_printed, increment,
    shares_mesh,
};
pub use bending::corrugated_stresses;
pub use blf_sensitivity::{blf_derivatives, time_state_blf, time_state_blf_ages};
pub use buckling::{BucklingRequest, ModeGuess, StateSolve, state_refine};
pub use check::{
    FeRequest, RefineBatch, RefineSolves, StateFe, StateFeSolve, analysis_green, fe_runs, levers,
    state_fe, state_fe_refine,
};
pub use collapse::{
    CURVE_POINTS, Collapse, CollapseMode, CollapseOptions, FirstPass, ObjectIncrements, StateLba,
    cap_as_printed_shift, cap_state_collapse, cap_state_collapse_from, cap_state_lba,
    cap_state_lba_from, collapse_factor, object_as_printed_shift, object_as_printed_shift_cached,
    shifted, state_amplitude,
};
pub use graded::{Grading, coarsened_state, graded_rows, graded_state};
pub use green::{
    CapGreen, ElementLayers, FailureMode, GreenOptions, WorstElement, check_state, set_aged_moduli,
};
pub use reliability::{
    Check, ComponentSorm, GreenField, ReducedAgainstForm, SCREEN_DELTA_RATIO, SCREEN_SAFETY,
    SCREEN_SHARE, SormSystem, StateForm, StateReliability, TimeBuckling, Vars, check_form,
    first_order_against_form, limit_state, prepare, reduced_against_form, reliability, scaled_ages,
    screen_delta, state_form, time_buckling_form, time_buckling_sorm,
};
pub use shell::{StateShell, state_shell};
