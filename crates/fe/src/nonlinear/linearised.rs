//! The co-rotational model's own linearised buckling problem, for verification: the critical
//! factor of `K + λ K_G^CR`, `K_G^CR = ∂K_T/∂λ` at the reference state (central difference of
//! the assembled tangent along the linear displacement `u₁ = K⁻¹ q`), located by bisection
//! on the tangent's inertia (Sylvester). `K_G^CR` holds everything the nonlinear model's
//! tangent gains per unit load at the start of the path: the facets' rigid-rotation terms,
//! their local initial-stress terms and the first-order change of the deformational
//! kinematics (initial-displacement terms). Comparing its factor with [`crate::buckling`]'s
//! on the same mesh separates a mismatch of the geometric stiffness (this factor ≠ λ_LBA)
//! from pre-buckling nonlinearity (the path's bifurcation ≠ this factor).

use faer::Mat;

use super::{Problem, State};
use crate::error::FeError;
use crate::model::ShellModel;

/// Which `K_G^CR` [`linearised_critical_factor`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Linearisation {
    /// `∂K_T/∂λ` along the linear displacement (central difference): initial-stress and
    /// initial-displacement terms. Plain EICR facets if `local_geometric` is false.
    Derivative {
        /// Facets with their local initial-stress terms.
        local_geometric: bool,
    },
    /// The initial-stress stiffness alone (the tangent's terms linear in the element forces
    /// of the linear solution, on the undeformed geometry): the co-rotational analogue of
    /// the linear solver's K_G. Plain EICR facets if `local_geometric` is false.
    InitialStress {
        /// Facets with their local initial-stress terms.
        local_geometric: bool,
    },
}

/// Result of [`linearised_critical_factor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearisedCritical {
    /// Smallest λ > 0 with `K + λ K_G^CR` singular (bracketed to `tolerance` relative).
    pub lambda: f64,
    /// LDLᵀ factorizations used.
    pub factorizations: usize,
}

/// The smallest positive critical factor of the co-rotational tangent linearised at the
/// reference state (module docs). `hint`: a guess (e.g. λ_LBA) that starts the bracket;
/// `tolerance`: relative width of the final bracket.
pub fn linearised_critical_factor(
    model: &ShellModel,
    hint: f64,
    tolerance: f64,
    which: Linearisation,
) -> Result<LinearisedCritical, FeError> {
    if !(hint.is_finite() && hint > 0.0) {
        return Err(FeError::OutOfRange {
            field: "hint".into(),
            value: hint,
            allowed: "finite and > 0",
        });
    }
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 0.5) {
        return Err(FeError::OutOfRange {
            field: "tolerance".into(),
            value: tolerance,
            allowed: "in (0, 0.5)",
        });
    }
    let local = match which {
        Linearisation::Derivative { local_geometric }
        | Linearisation::InitialStress { local_geometric } => local_geometric,
    };
    let p = Problem::new(model, None, local)?;
    let singular = || FeError::Numerical {
        stage: "linearised critical factor",
        detail: "zero pivot in the tangent".into(),
    };
    let st0 = State::initial(model);
    let (_, k0) = p.evaluate(&st0, true)?;
    let k0 = k0.ok_or_else(singular)?;
    let mut factorizations = 1;
    let f0 = p.symbolic.ldlt(&p.pattern, &k0.sym)?.ok_or_else(singular)?;
    let n = p.q.len();
    let mut u1 = Mat::<f64>::from_fn(n, 1, |i, _| p.q[i]);
    f0.solve_in_place(u1.as_mut())?;
    // Step in λ for the central difference: 10⁻⁴ of the hint keeps the displacements within
    // round-off-free small strains, and the central difference's error (second order in it)
    // below 10⁻⁸ relative.
    let h = 1e-4 * hint;
    let tangent_at = |s: f64| -> Result<Vec<f64>, FeError> {
        let mut st = State::initial(model);
        let du: Vec<f64> = (0..n).map(|i| s * u1[(i, 0)]).collect();
        p.apply(&mut st, &du);
        let (_, k) = p.evaluate(&st, true)?;
        Ok(k.ok_or_else(singular)?.sym)
    };
    let kg: Vec<f64> = match which {
        Linearisation::Derivative { .. } => {
            let kp = tangent_at(h)?;
            let km = tangent_at(-h)?;
            kp.iter()
                .zip(&km)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        }
        Linearisation::InitialStress { .. } => {
            let mut u = vec![0.0; 6 * model.nodes.len()];
            for (i, &g) in p.dofs.free.iter().enumerate() {
                u[g] = u1[(i, 0)];
            }
            p.initial_stress(&u)?
        }
    };
    let mut count = |lam: f64| -> Result<usize, FeError> {
        factorizations += 1;
        let vals: Vec<f64> = k0.sym.iter().zip(&kg).map(|(k, g)| k + lam * g).collect();
        Ok(p.symbolic
            .ldlt(&p.pattern, &vals)?
            .map_or(usize::MAX, |f| f.negative))
    };
    let (mut lo, mut hi) = (0.0, hint);
    let mut tries = 0;
    while count(hi)? == 0 {
        lo = hi;
        hi *= 2.0;
        tries += 1;
        if tries > 30 {
            return Err(FeError::Numerical {
                stage: "linearised critical factor",
                detail: format!("no critical factor below {hi:e}"),
            });
        }
    }
    while hi - lo > tolerance * hi {
        let mid = 0.5 * (lo + hi);
        if count(mid)? == 0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(LinearisedCritical {
        lambda: 0.5 * (lo + hi),
        factorizations,
    })
}
