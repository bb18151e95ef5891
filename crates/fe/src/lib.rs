//! # kappe-fe — flat shell finite elements: linear statics and linear buckling
//!
//! A 3-node facet shell (CST membrane + DKT plate + weak drilling spring, 6 DOF/node) for
//! the buckling check of every print state of a vault (`../shared/reference/buckling.md`).
//!
//! * [`ShellModel`]: nodes, triangles, per-element thickness and [`Material`], [`Support`]s per
//!   DOF, self-weight (γ·t·`gravity`) and [`NodalLoad`]s; [`ShellModel::validate`].
//! * [`linear_static`] → [`StaticResult`] (displacements, membrane forces/moments/stresses per
//!   element, reactions).
//! * [`buckling`] → [`BucklingResult`]: lowest positive factors λ of `(K + λ K_G) φ = 0`, their
//!   modes, residuals and a Sturm-count proof that no lower factor was missed.
//! * [`BucklingSolver`] caches the symbolic factorization for models with the same mesh and
//!   supports (e.g. the ~100 print states of a vault);
//!   [`BucklingSolver::buckling_with_cases`] also solves further load cases ([`LoadCase`]: part
//!   of the self-weight, nodal loads) on the buckling solve's own factor of K.
//! * [`element::ShellElement`] is the element boundary; [`element::cst_dkt::CstDkt`] the
//!   reference element (default), [`element::andes_dkt::AndesDkt`] the ANDES/OPT membrane with
//!   drilling freedoms + DKT, [`element::dkmt::AndesDkmt`] / [`element::dkmt::CstDkmt`] the
//!   shear-deformable (Reissner–Mindlin, DKMT plate) variants for thick shells, chosen by
//!   [`ShellModel::element`] ([`ElementKind`]).
//! * [`nonlinear`]: geometrically nonlinear statics — co-rotational facets (small strains,
//!   large rotations), [`nonlinear_path`] (Newton–Raphson with Crisfield's arc length or load
//!   control, limit points and bifurcations from the tangent's inertia, residual per step),
//!   [`with_imperfection`] (a scaled buckling mode added to the nodes) and
//!   [`deformed_resultants`] (stresses in a deformed state).
//! * [`mesh_json`] reads the fixture mesh format of `../shared/fixtures/fe/`.
//!
//! ```
//! use kappe_fe::{Material, ShellModel, Support, BucklingOptions, buckling};
//! // A 1 m × 0.1 m vertical strip, clamped at the base, under self-weight: a heavy column.
//! let (h, b, ny) = (1.0, 0.1, 8);
//! let mut nodes = Vec::new();
//! for j in 0..=ny { for x in [0.0, b] { nodes.push([x, 0.0, h * j as f64 / ny as f64]); } }
//! let mut tris = Vec::new();
//! for j in 0..ny { let a = 2 * j; tris.push([a, a + 1, a + 3]); tris.push([a, a + 3, a + 2]); }
//! let mat = Material { youngs_modulus: 1e6, poisson_ratio: 0.0, unit_weight: 2e4 };
//! let mut m = ShellModel::new(nodes, tris, 0.01, mat);
//! m.supports = vec![Support::clamped(0), Support::clamped(1)];
//! let r = buckling(&m, &BucklingOptions { modes: 1, ..Default::default() }).unwrap();
//! // Greenhill: q H³/(EI) = 7.837 → λ = 7.837 E I / (q H³)
//! let (ei, q) = (1e6 * b * 0.01f64.powi(3) / 12.0, 2e4 * 0.01 * b);
//! let exact = 7.837 * ei / (q * h.powi(3));
//! assert!((r.factors[0] / exact - 1.0).abs() < 0.03);
//! ```

// Element and sparse-matrix code indexes several arrays with the same DOF/entry index;
// index loops read closer to the formulas than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod assembly;
pub mod ccx;
pub mod clock;
pub mod convergence;
pub mod element;
pub mod error;
mod factor;
pub mod generate;
pub mod mesh_json;
pub mod model;
pub mod nonlinear;
pub mod oracle;
pub mod refine;
mod solver;
pub mod summary;
pub mod twolevel;

pub use convergence::{
    ConvergedFactor, LevelSolve, MeshLevel, SplitSolver, converge_factor, converge_from,
    converge_from_with,
};
pub use error::{FeError, NodeDof};
pub use model::{ElementKind, Material, NodalLoad, ShellModel, Support};
pub use nonlinear::{
    Linearisation, LinearisedCritical, Path, PathControl, PathOptions, PathStep, StopReason,
    deformed_resultants, linearised_critical_factor, nonlinear_path, with_imperfection,
};
pub use solver::{
    BucklingOptions, BucklingResult, BucklingSolver, ElementResult, LoadCase, SolveStats,
    StaticResult, SturmCheck, buckling, linear_static,
};
