//! A probabilistic model: named random variables, their correlation, and the Nataf transformation
//! x ↔ u between the physical space and the independent standard normal space.
//!
//! # Nataf model
//!
//! Each marginal is mapped to a standard normal variable, zᵢ = Φ⁻¹(Fᵢ(xᵢ)); the vector z is taken
//! jointly normal with correlation matrix R₀ (Nataf 1962; Liu & Der Kiureghian 1986). The entry
//! ρ₀,ᵢⱼ is chosen so that the physical correlation is the one asked for:
//!
//! ρᵢⱼ = E[ hᵢ(Z₁) hⱼ(ρ₀Z₁ + √(1−ρ₀²) Z₂) ],  hᵢ(z) = (Fᵢ⁻¹(Φ(z)) − μᵢ)/σᵢ,  Z₁, Z₂ ~ N(0, 1) independent.
//!
//! **This crate solves that exact integral numerically**, not the Liu & Der Kiureghian empirical
//! fits (those carry up to ~1 % error and exist only for listed pairs of distributions): a
//! 64-point Gauss–Hermite tensor rule (nodes and weights by the Golub–Welsch eigenvalue method for
//! the probabilists' Hermite weight e^{−z²/2}/√(2π)) evaluates the expectation, hᵢ is normalised
//! with the rule's own mean and standard deviation (so ρ₀ = 0 ↔ ρ = 0 and identical marginals with
//! ρ₀ = 1 give ρ = 1 exactly), and ρ₀ is found by bisection on the monotone map ρ₀ ↦ ρ to 1e−15.
//! Two normal marginals take ρ₀ = ρ directly. A ρ outside the range reachable with ρ₀ ∈ (−1, 1) is
//! an error ([`Error::CorrelationNotAttainable`]).
//!
//! R₀ = L Lᵀ (Cholesky); u = L⁻¹z are independent standard normal variables. A Cholesky pivot ≤ 0
//! names the variable that is (numerically) a linear combination of the ones before it.

use crate::drift::Drift;
use crate::error::{Error, Result};
use crate::variable::{Distribution, RandomVariable};
use serde::{Deserialize, Serialize};

/// How the variables are correlated (in the physical space).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub enum Correlation {
    /// No correlation.
    #[default]
    Independent,
    /// The full n×n matrix, rows in the order of the variables.
    Matrix(Vec<Vec<f64>>),
    /// Named pairs (first, second, ρ); pairs not listed are uncorrelated.
    Pairs(Vec<(String, String, f64)>),
}

/// Random variables with their Nataf transformation; see the module docs.
#[derive(Debug, Clone)]
pub struct Model {
    variables: Vec<RandomVariable>,
    /// Physical correlation, n×n row-major.
    rho_x: Vec<f64>,
    /// Correlation of z (Nataf), n×n row-major.
    rho_z: Vec<f64>,
    /// Lower Cholesky factor of `rho_z`, n×n row-major.
    chol: Vec<f64>,
}

impl Model {
    /// A model of independent variables.
    pub fn independent(variables: Vec<RandomVariable>) -> Result<Self> {
        Self::new(variables, &Correlation::Independent)
    }

    /// A model with a physical correlation; validates every variable, the matrix, and maps it
    /// to standard normal space (Nataf) and factors it (Cholesky).
    pub fn new(variables: Vec<RandomVariable>, correlation: &Correlation) -> Result<Self> {
        let n = variables.len();
        if n == 0 {
            return Err(Error::NoVariables);
        }
        for (i, v) in variables.iter().enumerate() {
            if variables[..i].iter().any(|w| w.name == v.name) {
                return Err(Error::DuplicateVariable {
                    variable: v.name.clone(),
                });
            }
            v.check()?;
            v.check_positive()?;
        }
        let rho_x = physical_matrix(&variables, correlation)?;
        let mut rho_z = rho_x.clone();
        let mut quadrature = None;
        for i in 0..n {
            for j in 0..i {
                let rho = rho_x[i * n + j];
                if rho == 0.0 {
                    continue;
                }
                let (di, dj) = (&variables[i].distribution, &variables[j].distribution);
                if matches!(di, Distribution::Normal { .. })
                    && matches!(dj, Distribution::Normal { .. })
                {
                    continue;
                }
                let q = quadrature.get_or_insert_with(|| GaussHermite::new(64));
                let r0 = nataf_rho0(q, di, dj, rho).map_err(|(min, max)| {
                    Error::CorrelationNotAttainable {
                        first: variables[i].name.clone(),
                        second: variables[j].name.clone(),
                        value: rho,
                        min,
                        max,
                    }
                })?;
                rho_z[i * n + j] = r0;
                rho_z[j * n + i] = r0;
            }
        }
        let chol = cholesky(&rho_z, n).map_err(|k| {
            let among: Vec<&str> = (0..k)
                .filter(|&j| rho_z[k * n + j] != 0.0)
                .map(|j| variables[j].name.as_str())
                .collect();
            Error::CorrelationNotPositiveDefinite {
                variable: variables[k].name.clone(),
                among: among.join(", "),
            }
        })?;
        Ok(Self {
            variables,
            rho_x,
            rho_z,
            chol,
        })
    }

    /// Number of variables.
    pub fn len(&self) -> usize {
        self.variables.len()
    }

    /// Always false (a model has at least one variable); for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.variables.is_empty()
    }

    /// The variables in order.
    pub fn variables(&self) -> &[RandomVariable] {
        &self.variables
    }

    /// Index of a variable by name.
    pub fn index_of(&self, name: &str) -> Result<usize> {
        self.variables
            .iter()
            .position(|v| v.name == name)
            .ok_or_else(|| unknown(name, "the model", &self.variables))
    }

    /// Means of the variables.
    pub fn means(&self) -> Vec<f64> {
        self.variables
            .iter()
            .map(|v| v.distribution.mean())
            .collect()
    }

    /// Standard deviations of the variables.
    pub fn stds(&self) -> Vec<f64> {
        self.variables
            .iter()
            .map(|v| v.distribution.std())
            .collect()
    }

    /// Physical correlation ρᵢⱼ.
    pub fn correlation(&self, i: usize, j: usize) -> f64 {
        self.rho_x[i * self.len() + j]
    }

    /// Nataf correlation ρ₀,ᵢⱼ of the standard normal zᵢ, zⱼ.
    pub fn standard_correlation(&self, i: usize, j: usize) -> f64 {
        self.rho_z[i * self.len() + j]
    }

    /// z = L u.
    pub fn z_from_u(&self, u: &[f64]) -> Vec<f64> {
        let n = self.len();
        (0..n)
            .map(|i| (0..=i).map(|j| self.chol[i * n + j] * u[j]).sum())
            .collect()
    }

    /// u = L⁻¹ z (forward substitution).
    pub fn u_from_z(&self, z: &[f64]) -> Vec<f64> {
        let n = self.len();
        let mut u = vec![0.0; n];
        for i in 0..n {
            let s: f64 = (0..i).map(|j| self.chol[i * n + j] * u[j]).sum();
            u[i] = (z[i] - s) / self.chol[i * n + i];
        }
        u
    }

    /// w = L⁻ᵀ a (backward substitution); used for dβ/dθ and the importance vector γ.
    pub(crate) fn solve_lt(&self, a: &[f64]) -> Vec<f64> {
        let n = self.len();
        let mut w = vec![0.0; n];
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|j| self.chol[j * n + i] * w[j]).sum();
            w[i] = (a[i] - s) / self.chol[i * n + i];
        }
        w
    }

    /// Lᵀ a.
    pub(crate) fn mul_lt(&self, a: &[f64]) -> Vec<f64> {
        let n = self.len();
        (0..n)
            .map(|j| (j..n).map(|i| self.chol[i * n + j] * a[i]).sum())
            .collect()
    }

    /// The physical point of a standard normal point: x = T⁻¹(u).
    pub fn x_from_u(&self, u: &[f64]) -> Vec<f64> {
        let z = self.z_from_u(u);
        self.variables
            .iter()
            .zip(z)
            .map(|(v, z)| v.distribution.from_standard(z))
            .collect()
    }

    /// The standard normal point of a physical point: u = T(x).
    pub fn u_from_x(&self, x: &[f64]) -> Vec<f64> {
        let z: Vec<f64> = self
            .variables
            .iter()
            .zip(x)
            .map(|(v, &x)| v.distribution.to_standard(x))
            .collect();
        self.u_from_z(&z)
    }

    /// ∇_u G = Lᵀ (dx/dz ∘ ∇_x g) at the point u.
    pub fn gradient_to_standard(&self, u: &[f64], grad_x: &[f64]) -> Vec<f64> {
        let z = self.z_from_u(u);
        let scaled: Vec<f64> = self
            .variables
            .iter()
            .zip(z)
            .zip(grad_x)
            .map(|((v, z), g)| v.distribution.dx_dz(z) * g)
            .collect();
        self.mul_lt(&scaled)
    }

    /// The Hessian of G(u) = g(x(u)) in standard normal space (n×n, row-major) from ∂g/∂x and
    /// ∂²g/∂x∂xᵀ at the point u, by the chain rule through xᵢ = Fᵢ⁻¹(Φ(zᵢ)), z = Lu:
    ///
    /// ∂²G/∂u∂uᵀ = Lᵀ (D H_x D + diag(x″ᵢ ∂g/∂xᵢ)) L,  D = diag(dxᵢ/dzᵢ), x″ᵢ = d²xᵢ/dzᵢ²
    ///
    /// (each xᵢ depends on zᵢ alone, and z is linear in u).
    pub fn hessian_to_standard(&self, u: &[f64], grad_x: &[f64], hess_x: &[f64]) -> Vec<f64> {
        let n = self.len();
        let z = self.z_from_u(u);
        let d: Vec<f64> = (0..n)
            .map(|i| self.variables[i].distribution.dx_dz(z[i]))
            .collect();
        let mut m = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                m[i * n + j] = d[i] * d[j] * hess_x[i * n + j];
            }
            m[i * n + i] += self.variables[i].distribution.d2x_dz2(z[i]) * grad_x[i];
        }
        // Lᵀ M L with L lower triangular: (Lᵀ M L)_ab = Σ_{i ≥ a} Σ_{j ≥ b} L_ia M_ij L_jb.
        let mut ml = vec![0.0; n * n];
        for i in 0..n {
            for b in 0..n {
                ml[i * n + b] = (b..n).map(|j| m[i * n + j] * self.chol[j * n + b]).sum();
            }
        }
        let mut h = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                h[a * n + b] = (a..n).map(|i| self.chol[i * n + a] * ml[i * n + b]).sum();
            }
        }
        h
    }

    /// The model of one print state: variable i scaled by `factors[i]` > 0 (drift factors, see
    /// [`crate::drift`]). Scaling keeps each zᵢ, so the correlation, R₀ and L are unchanged and the
    /// states share one u-space (which a series system over the states needs).
    pub fn scaled(&self, factors: &[f64]) -> Result<Self> {
        if factors.len() != self.len() {
            return Err(Error::DimensionMismatch {
                what: "drift factors",
                expected: self.len(),
                got: factors.len(),
            });
        }
        let variables = self
            .variables
            .iter()
            .zip(factors)
            .map(|(v, &c)| v.scaled(c))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            variables,
            ..self.clone()
        })
    }

    /// The model of the state printed at `t_hours`: each named variable scaled by its drift factor
    /// c(t) ([`Drift::factor`]), the others unchanged; unknown names are an error.
    pub fn drifted(&self, drifts: &[(String, Drift)], t_hours: f64) -> Result<Self> {
        let mut factors = vec![1.0; self.len()];
        for (name, drift) in drifts {
            let i = self
                .variables
                .iter()
                .position(|v| &v.name == name)
                .ok_or_else(|| unknown(name, "the drifts", &self.variables))?;
            factors[i] *= drift.factor(t_hours)?;
        }
        self.scaled(&factors)
    }

    pub(crate) fn distribution(&self, i: usize) -> &Distribution {
        &self.variables[i].distribution
    }
}

fn unknown(name: &str, context: &'static str, variables: &[RandomVariable]) -> Error {
    Error::UnknownVariable {
        name: name.to_owned(),
        context,
        known: variables
            .iter()
            .map(|v| v.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
    }
}

fn physical_matrix(variables: &[RandomVariable], correlation: &Correlation) -> Result<Vec<f64>> {
    let n = variables.len();
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        m[i * n + i] = 1.0;
    }
    let name = |i: usize| variables[i].name.clone();
    let check_range = |i: usize, j: usize, value: f64| {
        if value.is_finite() && value.abs() < 1.0 {
            Ok(())
        } else {
            Err(Error::CorrelationOutOfRange {
                first: name(i),
                second: name(j),
                value,
            })
        }
    };
    match correlation {
        Correlation::Independent => {}
        Correlation::Matrix(rows) => {
            let cols = rows.iter().map(Vec::len).find(|&c| c != n).unwrap_or(n);
            if rows.len() != n || cols != n {
                return Err(Error::CorrelationShape {
                    rows: rows.len(),
                    cols,
                    expected: n,
                });
            }
            for i in 0..n {
                if rows[i][i] != 1.0 {
                    return Err(Error::CorrelationDiagonal {
                        variable: name(i),
                        value: rows[i][i],
                    });
                }
                for j in 0..i {
                    let (lower, upper) = (rows[i][j], rows[j][i]);
                    if lower != upper && !(lower.is_nan() && upper.is_nan()) {
                        return Err(Error::CorrelationNotSymmetric {
                            first: name(j),
                            second: name(i),
                            upper,
                            lower,
                        });
                    }
                    check_range(j, i, lower)?;
                    m[i * n + j] = lower;
                    m[j * n + i] = lower;
                }
            }
        }
        Correlation::Pairs(pairs) => {
            let index = |s: &str| {
                variables
                    .iter()
                    .position(|v| v.name == s)
                    .ok_or_else(|| unknown(s, "the correlation pairs", variables))
            };
            for (a, b, rho) in pairs {
                let (i, j) = (index(a)?, index(b)?);
                if i == j {
                    if *rho != 1.0 {
                        return Err(Error::CorrelationDiagonal {
                            variable: name(i),
                            value: *rho,
                        });
                    }
                    continue;
                }
                check_range(i, j, *rho)?;
                let previous = m[i * n + j];
                if previous != 0.0 && previous != *rho {
                    return Err(Error::CorrelationNotSymmetric {
                        first: name(i),
                        second: name(j),
                        upper: previous,
                        lower: *rho,
                    });
                }
                m[i * n + j] = *rho;
                m[j * n + i] = *rho;
            }
        }
    }
    Ok(m)
}

/// Lower Cholesky factor of a symmetric n×n row-major matrix; Err(k) at the first pivot ≤ 0.
fn cholesky(a: &[f64], n: usize) -> std::result::Result<Vec<f64>, usize> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i * n + k] * l[j * n + k]).sum();
            if i == j {
                let d = a[i * n + i] - s;
                // A pivot below 1e−12 (relative to the unit diagonal) means the variable is a
                // linear combination of the previous ones to within round-off: u would blow up.
                if d <= 1e-12 || d.is_nan() {
                    return Err(i);
                }
                l[i * n + i] = d.sqrt();
            } else {
                l[i * n + j] = (a[i * n + j] - s) / l[j * n + j];
            }
        }
    }
    Ok(l)
}

/// Gauss–Hermite rule for E[f(Z)], Z ~ N(0, 1): nodes zₖ, weights wₖ with Σwₖ = 1.
pub(crate) struct GaussHermite {
    z: Vec<f64>,
    w: Vec<f64>,
}

impl GaussHermite {
    /// Golub–Welsch: the nodes are the eigenvalues of the Jacobi matrix of the probabilists'
    /// Hermite polynomials (zero diagonal, off-diagonal √k), the weights the squared first
    /// components of the normalised eigenvectors.
    pub(crate) fn new(n: usize) -> Self {
        let jacobi = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            if i.abs_diff(j) == 1 {
                (i.max(j) as f64).sqrt()
            } else {
                0.0
            }
        });
        let eig = nalgebra::SymmetricEigen::new(jacobi);
        let mut pairs: Vec<(f64, f64)> = (0..n)
            .map(|k| (eig.eigenvalues[k], eig.eigenvectors[(0, k)].powi(2)))
            .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let total: f64 = pairs.iter().map(|p| p.1).sum();
        Self {
            z: pairs.iter().map(|p| p.0).collect(),
            w: pairs.iter().map(|p| p.1 / total).collect(),
        }
    }
}

/// hᵢ(z) = (F⁻¹(Φ(z)) − m)/s, normalised with the rule's own moments.
struct Normalised<'a> {
    d: &'a Distribution,
    mean: f64,
    std: f64,
}

impl<'a> Normalised<'a> {
    fn new(q: &GaussHermite, d: &'a Distribution) -> Self {
        let mean: f64 =
            q.z.iter()
                .zip(&q.w)
                .map(|(&z, w)| w * d.from_standard(z))
                .sum();
        let var: f64 =
            q.z.iter()
                .zip(&q.w)
                .map(|(&z, w)| w * (d.from_standard(z) - mean).powi(2))
                .sum();
        Self {
            d,
            mean,
            std: var.sqrt(),
        }
    }

    fn h(&self, z: f64) -> f64 {
        (self.d.from_standard(z) - self.mean) / self.std
    }
}

/// ρ(ρ₀) = E[hᵢ(Z₁) hⱼ(ρ₀Z₁ + √(1−ρ₀²)Z₂)] by the tensor rule.
fn nataf_rho(q: &GaussHermite, hi: &Normalised, hj: &Normalised, rho0: f64) -> f64 {
    let s = (1.0 - rho0 * rho0).max(0.0).sqrt();
    let mut total = 0.0;
    for (&z1, &w1) in q.z.iter().zip(&q.w) {
        let a = hi.h(z1);
        let inner: f64 = if s == 0.0 {
            hj.h(rho0 * z1)
        } else {
            q.z.iter()
                .zip(&q.w)
                .map(|(&z2, &w2)| w2 * hj.h(rho0 * z1 + s * z2))
                .sum()
        };
        total += w1 * a * inner;
    }
    total
}

/// The Nataf ρ₀ for a target ρ, or Err((min, max)) with the attainable range.
fn nataf_rho0(
    q: &GaussHermite,
    di: &Distribution,
    dj: &Distribution,
    rho: f64,
) -> std::result::Result<f64, (f64, f64)> {
    let (hi, hj) = (Normalised::new(q, di), Normalised::new(q, dj));
    let (min, max) = (nataf_rho(q, &hi, &hj, -1.0), nataf_rho(q, &hi, &hj, 1.0));
    if rho <= min || rho >= max {
        return Err((min, max));
    }
    let (mut lo, mut hi_r) = (-1.0_f64, 1.0_f64);
    // ρ(ρ₀) is increasing; 60 halvings of [−1, 1] reach below 1e−17.
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi_r);
        if nataf_rho(q, &hi, &hj, mid) < rho {
            lo = mid;
        } else {
            hi_r = mid;
        }
        if hi_r - lo < 1e-15 {
            break;
        }
    }
    Ok(0.5 * (lo + hi_r))
}
