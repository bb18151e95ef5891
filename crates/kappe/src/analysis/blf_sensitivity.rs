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
use crate::form::states::build_state;
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
    let ne = model.triangles.len();
    if let Some(bad) = de.iter().find(|row| row.len() != ne) {
        return Err(FeError::Numerical {
            stage: "buckling sensitivity",
            detail: format!(
                "{} modulus derivatives for {ne} elements; give one per element",
                bad.len()
            ),
        });
    }
    let el = model.element.implementation();
    let fixed = model.fixed_mask();
    let np = de.len();
    let mut a = vec![0.0; np];
    let mut denom = 0.0;
    let mut loads = vec![vec![[0.0; 6]; model.nodes.len()]; np];
    let mut geo = Vec::with_capacity(ne);
    for (e, tri) in model.triangles.iter().enumerate() {
        let g = TriangleGeometry::new(&[
            model.nodes[tri[0]],
            model.nodes[tri[1]],
            model.nodes[tri[2]],
        ]);
        let t = model.thickness_of(e);
        let m = model.material_of(e);
        let phi = gather(mode, tri, &fixed);
        let u = gather(&st.displacements, tri, &fixed);
        let ke = el.stiffness(&g, t, &m, model.drilling_alpha);
        let n = st
            .elements
            .get(e)
            .map_or([0.0; 3], |r| r.resultants.membrane);
        denom += quad(&el.geometric_stiffness(&g, t, &m, &n), &phi);
        let kphi = quad(&ke, &phi);
        let mut ku = [0.0; 18];
        for i in 0..18 {
            for j in 0..18 {
                ku[i] += ke[(i, j)] * u[j];
            }
        }
        for k in 0..np {
            let r = de[k][e] / m.youngs_modulus;
            if r == 0.0 {
                continue;
            }
            a[k] += r * kphi;
            for (q, &node) in tri.iter().enumerate() {
                for d in 0..6 {
                    loads[k][node][d] -= r * ku[6 * q + d];
                }
            }
        }
        geo.push((g, t, m, n));
    }
    if !(denom.is_finite() && denom != 0.0) {
        return Err(FeError::Numerical {
            stage: "buckling sensitivity",
            detail: "the mode has φᵀK_Gφ = 0: not a buckling mode of this model".into(),
        });
    }
    let mut out = Vec::with_capacity(np);
    for k in 0..np {
        let mut dm = model.clone();
        dm.gravity = [0.0; 3];
        dm.nodal_loads = loads[k]
            .iter()
            .enumerate()
            .filter(|(_, f)| f.iter().any(|v| *v != 0.0))
            .map(|(node, f)| NodalLoad {
                node,
                force: [f[0], f[1], f[2]],
                moment: [f[3], f[4], f[5]],
            })
            .collect();
        let c = if dm.nodal_loads.is_empty() {
            // E′ = 0 everywhere: ∂u/∂p = 0 and the direct term vanishes too.
            0.0
        } else {
            let du = kappe_fe::linear_static(&dm)?;
            let mut c = 0.0;
            for (e, (g, t, m, n)) in geo.iter().enumerate() {
                let r = de[k][e] / m.youngs_modulus;
                let n2 = du
                    .elements
                    .get(e)
                    .map_or([0.0; 3], |x| x.resultants.membrane);
                let dn: [f64; 3] = std::array::from_fn(|i| r * n[i] + n2[i]);
                let phi = gather(mode, &model.triangles[e], &fixed);
                c += quad(&el.geometric_stiffness(g, *t, m, &dn), &phi);
            }
            c
        };
        out.push(-(a[k] + blf * c) / denom);
    }
    Ok(out)
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
    let state = build_state(
        &cap.sections,
        &cap.frame,
        cap.design.print.start_arch_fraction,
        top,
    )?;
    let analysed = AnalysedState::new(&state, options.grading.as_ref());
    let age_of: HashMap<i32, (f64, f64)> = cap
        .sections
        .layers
        .iter()
        .zip(ages)
        .enumerate()
        .map(|(k, (l, &t))| (l.id, (t, dages.get(k).copied().unwrap_or(0.0))))
        .collect();
    let d = &cap.design;
    let material = ShellMaterial {
        thickness: d.print.layer_width,
        poisson_ratio: d.material.poisson_ratio,
        unit_weight: d.material.specific_weight,
        layer_modulus: age_of
            .iter()
            .map(|(&id, &(t, _))| (id, time.modulus(t)))
            .collect(),
        youngs_modulus: d.material.youngs_modulus,
        element: options.element,
    };
    let Ok(shell) = state_shell(analysed.state(), &material, options.row_stride) else {
        return Ok(None);
    };
    let fe = |e: FeError| DesignError::State {
        state: top,
        message: format!("buckling re-solve for the reliability analysis failed: {e}"),
    };
    let r = kappe_fe::buckling(
        &shell.model,
        &kappe_fe::BucklingOptions {
            modes: 1,
            tolerance,
            sturm_check: false,
            ..Default::default()
        },
    )
    .map_err(fe)?;
    let (Some(&blf), Some(mode)) = (r.factors.first(), r.modes.first()) else {
        return Ok(None);
    };
    let ne = shell.element_layers.len();
    let rows = if dages.is_empty() { 2 } else { 3 };
    let mut de = vec![Vec::with_capacity(ne); rows];
    for (a, b) in &shell.element_layers {
        // The element takes the mean of its two layers' moduli (`state_shell`).
        let (ta, sa) = age_of.get(a).copied().unwrap_or((0.0, 0.0));
        let (tb, sb) = age_of.get(b).copied().unwrap_or((0.0, 0.0));
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
    let g = blf_derivatives(&shell.model, blf, mode, &r.static_result, &de).map_err(fe)?;
    let get = |k: usize| g.get(k).copied().unwrap_or(0.0);
    Ok(Some((blf, [get(0), get(1), get(2)])))
}
