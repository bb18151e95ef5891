//! Dense reference solution of the buckling pencil for small models (test oracle, O(n³)).
//!
//! `K = L Lᵀ` (dense Cholesky), `C = L⁻¹ (−K_G) L⁻ᵀ`, all eigenvalues μ of C by faer's
//! symmetric eigensolver; λ = 1/μ for μ > 0, ascending. Independent of the Lanczos path
//! except for the element matrices (acceptance check A12).

use faer::{Mat, Par, Side};

use crate::error::FeError;
use crate::model::ShellModel;
use crate::solver::BucklingSolver;

/// All positive buckling factors of `model`, ascending, from the dense pencil.
/// Meant for models below ~3 000 free DOFs.
pub fn dense_buckling_factors(model: &ShellModel) -> Result<Vec<f64>, FeError> {
    let solver = BucklingSolver::new(model)?;
    let (n, kd, gd) = solver.dense_matrices(model)?;
    let k = Mat::<f64>::from_fn(n, n, |i, j| kd[i * n + j]);
    let llt = k.llt(Side::Lower).map_err(|e| FeError::Numerical {
        stage: "dense Cholesky",
        detail: format!("{e:?}"),
    })?;
    let l = llt.L();
    // X = L⁻¹ A, then C = L⁻¹ Xᵀ (= L⁻¹ A L⁻ᵀ because A is symmetric).
    let mut x = Mat::<f64>::from_fn(n, n, |i, j| -gd[i * n + j]);
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l, x.as_mut(), Par::Seq);
    let mut c = x.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
    // Symmetrise against round-off before the symmetric eigensolver.
    let cs = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let mu = cs
        .self_adjoint_eigenvalues(Side::Lower)
        .map_err(|e| FeError::Numerical {
            stage: "dense eigenvalues",
            detail: format!("{e:?}"),
        })?;
    let radius = mu.iter().map(|m| m.abs()).fold(0.0, f64::max);
    let mut lam: Vec<f64> = mu
        .iter()
        .filter(|&&m| m > 1e-10 * radius)
        .map(|m| 1.0 / m)
        .collect();
    lam.sort_by(f64::total_cmp);
    Ok(lam)
}
