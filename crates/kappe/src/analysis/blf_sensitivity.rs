//! Exact derivatives of a buckling factor with respect to parameters of the element moduli
//! (issue 24): the sensitivity of the lowest root λ of (K + λK_G)φ = 0 to a parameter p that
//! sets every element's Young's modulus E_e(p), e.g. the time model's E₀ and Ė
//! (docs/reliability.md, "Eigenvalue sensitivity").
//!
//! Differentiating the pencil and multiplying by φᵀ (K, K_G symmetric) gives
//! dλ/dp = −φᵀ(∂K/∂p + λ ∂K_G/∂p)φ / φᵀK_Gφ. Every element's elastic stiffness is linear in
//! its E (membrane, plate, transverse shear and the drilling spring α·E·t·A alike), so
//! ∂K_e/∂p = (E′_e/E_e)·K_e with E′_e = ∂E_e/∂p.
//!
//! ∂K_G/∂p is **not** zero here: K_G is built from the membrane forces of the shell's own
//! static solve, which is statically indeterminate, and a non-uniform change of the moduli
//! (Ė ages the lower layers more than the top) redistributes the forces. It is included:
//! K_G is linear in the membrane forces N_e = E_e·D̂_e·B_e·u, so
//! ∂N_e/∂p = (E′_e/E_e)·N_e + E_e·D̂_e·B_e·∂u/∂p, with ∂u/∂p = −K⁻¹(∂K/∂p)u from one more
//! linear static solve of the same shell under the load −(∂K/∂p)u (the self-weight does not
//! depend on E). The element's geometric stiffness itself does not depend on E: a Kirchhoff
//! element ignores the material there, and a shear-deformable one uses only the ratio of its
//! bending to its shear stiffness, which does not change with E at fixed ν.
//!
//! Cost: one element pass and one linear static solve per parameter, against a Lanczos solve
//! for a re-solve; a central difference would need two buckling solves per parameter.

use std::collections::HashMap;

use kappe_fe::element::TriangleGeometry;
use kappe_fe::{FeError, NodalLoad, ShellModel, StaticResult};

use super::AnalysisOptions;
use super::graded::AnalysedState;
use super::shell::{ShellMaterial, state_shell};
use crate::form::cap::Cap;
use crate::input::error::DesignError;
use crate::input::material::{TimeLaw, TimeModel};
use crate::schedule::Schedule;

/// The 18 global values of element `tri` from per-node 6-vectors, zero on fixed freedoms.
fn gather(v: &[[f64; 6]], tri: &[usize; 3], fixed: &[[bool; 6]]) -> [f64; 18] {
    let mut out = [0.0; 18];
    for (a, &n) in tri.iter().enumerate() {
        for k in 0..6 {
            let free = !fixed.get(n).is_some_and(|f| f[k]);
            if free {
                out[6 * a + k] = v.get(n).map_or(0.0, |d| d[k]);
            }
        }
    }
    out
}

fn quad(m: &kappe_fe::element::Mat18, x: &[f64; 18]) -> f64 {
    let mut s = 0.0;
    for i in 0..18 {
        let mut r = 0.0;
        for j in 0..18 {
            r += m[(i, j)] * x[j];
        }
        s += x[i] * r;
    }
    s
}

/// dλ/dp_k for every parameter k (see the module docs).
///
/// `model` is the shell as solved, `blf` its factor λ with mode `mode` (per node, any scale),
/// `st` its pre-buckling static solution, and `de[k][e]` = ∂E_e/∂p_k for every element e.
/// The displacement sensitivities are solved here, one linear static solve (a factorization)
/// each; [`TimeShell`] solves them on the buckling solve's own factor instead.
///
/// # Errors
/// A `de` row of the wrong length, a mode with φᵀK_Gφ = 0, or a failed static solve.
pub fn blf_derivatives(
    model: &ShellModel,
    blf: f64,
    mode: &[[f64; 6]],
    st: &StaticResult,
    de: &[Vec<f64>],
) -> Result<Vec<f64>, FeError> {
    check_rows(model, de)?;
    let mut du = Vec::with_capacity(de.len());
    for loads in sensitivity_loads(model, st, de) {
        du.push(if loads.is_empty() {
            None
        } else {
            let mut dm = model.clone();
            dm.gravity = [0.0; 3];
            dm.nodal_loads = loads;
            Some(kappe_fe::linear_static(&dm)?)
        });
    }
    blf_derivatives_from(model, blf, mode, st, de, &du)
}

fn check_rows(model: &ShellModel, de: &[Vec<f64>]) -> Result<(), FeError> {
    let ne = model.triangles.len();
    match de.iter().find(|row| row.len() != ne) {
        Some(bad) => Err(FeError::Numerical {
            stage: "buckling sensitivity",
            detail: format!(
                "{} modulus derivatives for {ne} elements; give one per element",
                bad.len()
            ),
        }),
        None => Ok(()),
    }
}

/// Per parameter k, the nodal loads −(∂K/∂p_k)·u whose static solution is ∂u/∂p_k (empty
/// where E′ = 0 everywhere); `de` as in [`blf_derivatives`], rows of one entry per element.
pub fn sensitivity_loads(
    model: &ShellModel,
    st: &StaticResult,
    de: &[Vec<f64>],
) -> Vec<Vec<NodalLoad>> {
    let el = model.element.implementation();
    let fixed = model.fixed_mask();
    let mut loads = vec![vec![[0.0; 6]; model.nodes.len()]; de.len()];
    for (e, tri) in model.triangles.iter().enumerate() {
        let m = model.material_of(e);
        if de.iter().all(|row| row.get(e).is_none_or(|d| *d == 0.0)) {
            continue;
        }
        let g = TriangleGeometry::new(&[
            model.nodes[tri[0]],
            model.nodes[tri[1]],
            model.nodes[tri[2]],
        ]);
        let u = gather(&st.displacements, tri, &fixed);
        let ke = el.stiffness(&g, model.thickness_of(e), &m, model.drilling_alpha);
        let mut ku = [0.0; 18];
        for i in 0..18 {
            for j in 0..18 {
                ku[i] += ke[(i, j)] * u[j];
            }
        }
        for (k, row) in de.iter().enumerate() {
            let r = row.get(e).copied().unwrap_or(0.0) / m.youngs_modulus;
            if r == 0.0 {
                continue;
            }
            for (q, &node) in tri.iter().enumerate() {
                for d in 0..6 {
                    loads[k][node][d] -= r * ku[6 * q + d];
                }
            }
        }
    }
    loads
        .into_iter()
        .map(|l| {
            l.iter()
                .enumerate()
                .filter(|(_, f)| f.iter().any(|v| *v != 0.0))
                .map(|(node, f)| NodalLoad {
                    node,
                    force: [f[0], f[1], f[2]],
                    moment: [f[3], f[4], f[5]],
                })
                .collect()
        })
        .collect()
}

/// dλ/dp_k from the displacement sensitivities `du[k]` = ∂u/∂p_k (None: zero), the rest as
/// [`blf_derivatives`].
fn blf_derivatives_from(
    model: &ShellModel,
    blf: f64,
    mode: &[[f64; 6]],
    st: &StaticResult,
    de: &[Vec<f64>],
    du: &[Option<StaticResult>],
) -> Result<Vec<f64>, FeError> {
    check_rows(model, de)?;
    let el = model.element.implementation();
    let fixed = model.fixed_mask();
    let np = de.len();
    let mut a = vec![0.0; np];
    let mut c = vec![0.0; np];
    let mut denom = 0.0;
    for (e, tri) in model.triangles.iter().enumerate() {
        let g = TriangleGeometry::new(&[
            model.nodes[tri[0]],
            model.nodes[tri[1]],
            model.nodes[tri[2]],
        ]);
        let t = model.thickness_of(e);
        let m = model.material_of(e);
        let phi = gather(mode, tri, &fixed);
        let n = st
            .elements
            .get(e)
            .map_or([0.0; 3], |r| r.resultants.membrane);
        denom += quad(&el.geometric_stiffness(&g, t, &m, &n), &phi);
        let mut kphi = None;
        for k in 0..np {
            let r = de[k][e] / m.youngs_modulus;
            let n2 = du
                .get(k)
                .and_then(Option::as_ref)
                .and_then(|d| d.elements.get(e))
                .map_or([0.0; 3], |x| x.resultants.membrane);
            if r == 0.0 && n2 == [0.0; 3] {
                continue;
            }
            if r != 0.0 {
                let kp = *kphi.get_or_insert_with(|| {
                    quad(&el.stiffness(&g, t, &m, model.drilling_alpha), &phi)
                });
                a[k] += r * kp;
            }
            let dn: [f64; 3] = std::array::from_fn(|i| r * n[i] + n2[i]);
            c[k] += quad(&el.geometric_stiffness(&g, t, &m, &dn), &phi);
        }
    }
    if !(denom.is_finite() && denom != 0.0) {
        return Err(FeError::Numerical {
            stage: "buckling sensitivity",
            detail: "the mode has φᵀK_Gφ = 0: not a buckling mode of this model".into(),
        });
    }
    Ok((0..np).map(|k| -(a[k] + blf * c[k]) / denom).collect())
}

/// ∂E/∂E₀ and ∂E/∂Ė of the time model's modulus at age `t` s: (1, t) for the linear law,
/// (1, t_c·(e^{t/t_c} − 1)) for the exponential one, (1, 0) for the constant one, and (0, 0)
/// where the cap `youngs_modulus_max` holds E (a one-sided derivative: at the cap exactly, the
/// side below it).
pub fn modulus_derivatives(time: &TimeModel, t: f64) -> [f64; 2] {
    let t = t.max(0.0);
    let p = &time.youngs_modulus;
    let d_rate = match time.law {
        TimeLaw::Constant => 0.0,
        TimeLaw::Linear => t,
        TimeLaw::Exponential => time.time_constant * (t / time.time_constant).exp_m1(),
    };
    let uncapped = p.initial + p.rate * d_rate;
    if p.max.is_some_and(|m| uncapped > m) {
        [0.0, 0.0]
    } else {
        [1.0, d_rate]
    }
}

/// ∂E/∂a of the time model's modulus at age `t` s: Ė for the linear law, Ė·e^{t/t_c} for the
/// exponential one, 0 for the constant one and where the cap `youngs_modulus_max` holds E (a
/// one-sided derivative, as [`modulus_derivatives`]).
pub fn modulus_age_derivative(time: &TimeModel, t: f64) -> f64 {
    let t = t.max(0.0);
    let p = &time.youngs_modulus;
    let [_, h] = modulus_derivatives(time, t);
    if p.max.is_some_and(|m| p.initial + p.rate * h > m) {
        return 0.0;
    }
    match time.law {
        TimeLaw::Constant => 0.0,
        TimeLaw::Linear => p.rate,
        TimeLaw::Exponential => p.rate * (t / time.time_constant).exp(),
    }
}

/// The lowest buckling factor of the cap state with top print index `top` under the time model
/// `time` on `schedule` (the shell the analysis builds: grading and row stride of `options`),
/// and its derivatives with respect to the time model's E₀ and Ė ([`blf_derivatives`]).
/// `None`: no shell (a single layer) or no positive factor. `tolerance` is the Lanczos relative
/// residual.
///
/// # Errors
/// A state that cannot be built, a failed solve, or a mechanism.
pub fn time_state_blf(
    cap: &Cap,
    options: &AnalysisOptions,
    schedule: &Schedule,
    time: &TimeModel,
    top: usize,
    tolerance: f64,
) -> Result<Option<(f64, [f64; 2])>, DesignError> {
    let ages = schedule.ages(top + 1);
    Ok(
        time_state_blf_ages(cap, options, &ages, &[], time, top, tolerance)?
            .map(|(l, d)| (l, [d[0], d[1]])),
    )
}

/// [`time_state_blf`] with the layers' ages given (`ages[k]`, layer k in print order) and,
/// when `dages` is not empty, also ∂λ/∂s for ages a_k + s·`dages[k]` (the print speed's
/// factor on the print durations: ∂E_e/∂s = E′(a)·∂a/∂s); the third derivative is 0 when
/// `dages` is empty.
///
/// # Errors
/// A state that cannot be built, a failed solve, or a mechanism.
pub fn time_state_blf_ages(
    cap: &Cap,
    options: &AnalysisOptions,
    ages: &[f64],
    dages: &[f64],
    time: &TimeModel,
    top: usize,
    tolerance: f64,
) -> Result<Option<(f64, [f64; 3])>, DesignError> {
    match TimeShell::new(cap, options, top)? {
        Some(mut shell) => shell.solve(ages, dages, time, tolerance),
        None => Ok(None),
    }
}

/// One state's shell for repeated buckling solves at other layer moduli (FORM's iterates):
/// the mesh and the solver's symbolic analysis (ordering, pattern) are built once, and every
/// solve factors K once — the displacement sensitivities ∂u/∂p are load cases on the buckling
/// solve's own factor ([`kappe_fe::BucklingSolver::buckling_with_derived_cases`]) — and starts
/// Lanczos from the previous solve's mode.
pub struct TimeShell {
    shell: super::shell::StateShell,
    solver: kappe_fe::BucklingSolver,
    /// Layer id → print index.
    layer_index: HashMap<i32, usize>,
    /// The last mode found (the next solve's start vector).
    last_mode: Option<Vec<[f64; 6]>>,
    top: usize,
}

impl TimeShell {
    /// The shell of the cap state with top print index `top` (grading and row stride of
    /// `options`). None: no shell (a single layer).
    ///
    /// # Errors
    /// A state that cannot be built or a model the solver refuses.
    pub fn new(
        cap: &Cap,
        options: &AnalysisOptions,
        top: usize,
    ) -> Result<Option<TimeShell>, DesignError> {
        let state = cap.state(top)?;
        let analysed = AnalysedState::new(&state, options.grading.as_ref());
        let d = &cap.design;
        // The moduli are set per solve; the mesh does not depend on them.
        let material = ShellMaterial {
            thickness: d.print.layer_width,
            poisson_ratio: d.material.poisson_ratio,
            unit_weight: d.material.specific_weight,
            layer_modulus: HashMap::new(),
            youngs_modulus: d.material.youngs_modulus,
            element: options.element,
        };
        let Ok(shell) = state_shell(analysed.state(), &material, options.row_stride) else {
            return Ok(None);
        };
        let solver =
            kappe_fe::BucklingSolver::new(&shell.model).map_err(|e| DesignError::State {
                state: top,
                message: format!("buckling re-solve for the reliability analysis failed: {e}"),
            })?;
        let layer_index = cap
            .sections
            .layers
            .iter()
            .enumerate()
            .map(|(k, l)| (l.id, k))
            .collect();
        Ok(Some(TimeShell {
            shell,
            solver,
            layer_index,
            last_mode: None,
            top,
        }))
    }

    /// λ and (∂λ/∂E₀, ∂λ/∂Ė, ∂λ/∂s) as [`time_state_blf_ages`]. None: no positive factor.
    ///
    /// # Errors
    /// A failed solve or a mechanism.
    pub fn solve(
        &mut self,
        ages: &[f64],
        dages: &[f64],
        time: &TimeModel,
        tolerance: f64,
    ) -> Result<Option<(f64, [f64; 3])>, DesignError> {
        let top = self.top;
        let age_of = |id: &i32| -> Option<(f64, f64)> {
            let k = *self.layer_index.get(id)?;
            Some((*ages.get(k)?, dages.get(k).copied().unwrap_or(0.0)))
        };
        let mut model = self.shell.model.clone();
        let base = model.material_of(0);
        let modulus = |id: &i32| age_of(id).map_or(base.youngs_modulus, |(t, _)| time.modulus(t));
        model.materials = self
            .shell
            .element_layers
            .iter()
            .map(|(a, b)| kappe_fe::Material {
                // The facet joins two beads: their mean stiffness (as `state_shell`).
                youngs_modulus: 0.5 * (modulus(a) + modulus(b)),
                ..base
            })
            .collect();
        let ne = self.shell.element_layers.len();
        let rows = if dages.is_empty() { 2 } else { 3 };
        let mut de = vec![Vec::with_capacity(ne); rows];
        for (a, b) in &self.shell.element_layers {
            // The element takes the mean of its two layers' moduli.
            let (ta, sa) = age_of(a).unwrap_or((0.0, 0.0));
            let (tb, sb) = age_of(b).unwrap_or((0.0, 0.0));
            let da = modulus_derivatives(time, ta);
            let db = modulus_derivatives(time, tb);
            for k in 0..2 {
                de[k].push(0.5 * (da[k] + db[k]));
            }
            if let Some(row) = de.get_mut(2) {
                row.push(
                    0.5 * (modulus_age_derivative(time, ta) * sa
                        + modulus_age_derivative(time, tb) * sb),
                );
            }
        }
        let fe = |e: FeError| DesignError::State {
            state: top,
            message: format!("buckling re-solve for the reliability analysis failed: {e}"),
        };
        let cases = |st: &StaticResult| -> Vec<kappe_fe::LoadCase> {
            sensitivity_loads(&model, st, &de)
                .into_iter()
                .map(|nodal_loads| kappe_fe::LoadCase {
                    weight: Vec::new(),
                    nodal_loads,
                })
                .collect()
        };
        let (r, du) = self
            .solver
            .buckling_with_derived_cases(
                &model,
                &kappe_fe::BucklingOptions {
                    modes: 1,
                    tolerance,
                    sturm_check: false,
                    start: self.last_mode.clone(),
                    ..Default::default()
                },
                &cases,
            )
            .map_err(fe)?;
        let (Some(&blf), Some(mode)) = (r.factors.first(), r.modes.first()) else {
            return Ok(None);
        };
        let du: Vec<Option<StaticResult>> = du.into_iter().map(Some).collect();
        let g = blf_derivatives_from(&model, blf, mode, &r.static_result, &de, &du).map_err(fe)?;
        self.last_mode = Some(mode.clone());
        let get = |k: usize| g.get(k).copied().unwrap_or(0.0);
        Ok(Some((blf, [get(0), get(1), get(2)])))
    }
}
