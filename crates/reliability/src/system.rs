//! Series systems: the probability that any of many limit states fails (every state × every
//! check of a print), from their FORM results.
//!
//! Each component i is linearised at its design point: failure ⇔ αᵢᵀu ≥ βᵢ, with u the common
//! standard normal vector (the components must share one u-space: the same variables in the same
//! order — states whose variables differ only by drift factors do, see [`crate::drift`]). The
//! component correlation is ρᵢⱼ = αᵢᵀαⱼ and
//!
//! P_f,sys = P(∪ᵢ {αᵢᵀu ≥ βᵢ}) = 1 − Φₘ(β; R),  β_sys = −Φ⁻¹(P_f,sys).
//!
//! # Multinormal probability: seeded importance sampling of the union (ALOE)
//!
//! We chose the estimator of Owen, Maximov & Chertkov (2019, "Importance sampling the union of
//! rare events with an application to power systems analysis", Electron. J. Statist. 13) over the
//! Genz algorithm: it works directly in the n-dimensional u-space, so R may be singular (more
//! components than variables, the normal case for a print), and its relative error stays bounded
//! however small P_f is. With pᵢ = Φ(−βᵢ) and P̄ = Σpᵢ: pick component i with probability pᵢ/P̄,
//! draw u ~ N(0, I) conditioned on αᵢᵀu ≥ βᵢ (the component along αᵢ from the truncated normal,
//! t = −Φ⁻¹(V·Φ(−βᵢ)), V ~ U(0, 1); the orthogonal part free), count the failing components
//! N(u) ≥ 1 and score P̄/N(u). The mean of the scores is unbiased for P_f,sys; since every score
//! lies in [P̄/m, P̄] its coefficient of variation is small. Seeded with ChaCha8.
//!
//! # Bounds
//!
//! Uni-modal: maxᵢ pᵢ ≤ P_f,sys ≤ min(1, Σpᵢ). Ditlevsen (1979) bi-modal bounds with the
//! components ordered by decreasing pᵢ and pᵢⱼ = Φ₂(−βᵢ, −βⱼ; ρᵢⱼ):
//!
//! p₁ + Σᵢ₌₂ max(0, pᵢ − Σⱼ<ᵢ pᵢⱼ) ≤ P_f,sys ≤ Σᵢ pᵢ − Σᵢ₌₂ maxⱼ<ᵢ pᵢⱼ.

use crate::error::{Error, Result};
use crate::form::FormResult;
use crate::rng;
use crate::stdnormal;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

/// One linearised component: failure ⇔ αᵀu ≥ β.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Component {
    /// Reliability index β.
    pub beta: f64,
    /// Unit vector α (towards failure) in the shared u-space.
    pub alpha: Vec<f64>,
}

impl From<&FormResult> for Component {
    fn from(r: &FormResult) -> Self {
        Self {
            beta: r.beta,
            alpha: r.alpha.clone(),
        }
    }
}

/// Series-system settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SystemOptions {
    /// Importance samples (default 20 000).
    pub samples: u64,
    /// Seed of ChaCha8Rng::seed_from_u64 (default 0).
    pub seed: u64,
    /// Compute the Ditlevsen bounds (m² bivariate normal probabilities; default true).
    pub ditlevsen: bool,
}

impl Default for SystemOptions {
    fn default() -> Self {
        Self {
            samples: 20_000,
            seed: 0,
            ditlevsen: true,
        }
    }
}

/// The failure probability of a series system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SystemResult {
    /// P_f,sys (importance-sampling estimate of the linearised union).
    pub pf: f64,
    /// β_sys = −Φ⁻¹(P_f,sys).
    pub beta: f64,
    /// Coefficient of variation of the estimate (standard error / P_f).
    pub cov: f64,
    /// 95 % interval of P_f,sys (P_f ± 1.96 standard errors, clamped at 0).
    pub interval: [f64; 2],
    /// Samples used.
    pub samples: u64,
    /// Uni-modal bounds [maxᵢ pᵢ, min(1, Σpᵢ)].
    pub unimodal_bounds: [f64; 2],
    /// Ditlevsen bounds [lower, upper], when asked for.
    pub ditlevsen_bounds: Option<[f64; 2]>,
    /// Index of the component with the largest pᵢ.
    pub governing: usize,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// P_f of the series system; see the module docs.
pub fn series_system(components: &[Component], options: &SystemOptions) -> Result<SystemResult> {
    let m = components.len();
    if m == 0 {
        return Err(Error::NoComponents);
    }
    if options.samples < 2 {
        return Err(Error::InvalidOption {
            field: "samples",
            value: options.samples as f64,
            allowed: "at least 2",
        });
    }
    let n = components[0].alpha.len();
    for (index, c) in components.iter().enumerate() {
        if c.alpha.len() != n {
            return Err(Error::DimensionMismatch {
                what: "system component α",
                expected: n,
                got: c.alpha.len(),
            });
        }
        let norm = dot(&c.alpha, &c.alpha).sqrt();
        // FORM's α is normalised to round-off; 1e−6 leaves room for α read back from text.
        if (norm - 1.0).abs() > 1e-6 || norm.is_nan() || !c.beta.is_finite() {
            return Err(Error::ComponentAlpha { index, norm });
        }
    }
    let p: Vec<f64> = components.iter().map(|c| stdnormal::cdf(-c.beta)).collect();
    let total: f64 = p.iter().sum();
    let governing = (0..m).max_by(|&a, &b| p[a].total_cmp(&p[b])).unwrap_or(0);
    let unimodal_bounds = [p[governing], total.min(1.0)];
    if total == 0.0 {
        // Every pᵢ underflows (all βᵢ > ~38): nothing to sample. β_sys ≤ minᵢ βᵢ always, and
        // that bound is reported as β.
        let beta = components
            .iter()
            .map(|c| c.beta)
            .fold(f64::INFINITY, f64::min);
        return Ok(SystemResult {
            pf: 0.0,
            beta,
            cov: 0.0,
            interval: [0.0, 0.0],
            samples: 0,
            unimodal_bounds,
            ditlevsen_bounds: options.ditlevsen.then_some([0.0, 0.0]),
            governing,
        });
    }
    let mut cumulative = Vec::with_capacity(m);
    let mut acc = 0.0;
    for pi in &p {
        acc += pi / total;
        cumulative.push(acc);
    }

    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut u = vec![0.0; n];
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..options.samples {
        let pick = rng::open01(&mut rng);
        let i = cumulative.partition_point(|&c| c < pick).min(m - 1);
        for v in u.iter_mut() {
            *v = rng::std_normal(&mut rng);
        }
        let a = &components[i].alpha;
        let t = -stdnormal::inv_cdf(rng::open01(&mut rng) * p[i]);
        let shift = t - dot(a, &u);
        for (v, ai) in u.iter_mut().zip(a) {
            *v += shift * ai;
        }
        let failing = components
            .iter()
            .enumerate()
            // A component touching the sampled point within round-off fails with it: identical
            // components (the same check in two states without drift) then count twice, exactly.
            .filter(|(j, c)| *j == i || dot(&c.alpha, &u) >= c.beta - 1e-12 * c.beta.abs().max(1.0))
            .count();
        let w = total / failing as f64;
        sum += w;
        sum2 += w * w;
    }
    let ns = options.samples as f64;
    let pf = (sum / ns).min(1.0);
    let var = ((sum2 / ns - (sum / ns).powi(2)) * ns / (ns - 1.0)).max(0.0);
    let se = (var / ns).sqrt();
    let ditlevsen_bounds = options.ditlevsen.then(|| ditlevsen(components, &p));
    Ok(SystemResult {
        pf,
        beta: stdnormal::beta_of(pf),
        cov: se / pf,
        interval: [(pf - 1.96 * se).max(0.0), (pf + 1.96 * se).min(1.0)],
        samples: options.samples,
        unimodal_bounds,
        ditlevsen_bounds,
        governing,
    })
}

/// Ditlevsen bounds [lower, upper]; see the module docs.
fn ditlevsen(components: &[Component], p: &[f64]) -> [f64; 2] {
    let mut order: Vec<usize> = (0..components.len()).collect();
    order.sort_by(|&a, &b| p[b].total_cmp(&p[a]));
    let mut lower = 0.0;
    let mut upper = 0.0;
    for (k, &i) in order.iter().enumerate() {
        let (mut sum_joint, mut max_joint) = (0.0, 0.0_f64);
        for &j in &order[..k] {
            let rho = dot(&components[i].alpha, &components[j].alpha);
            let pij = stdnormal::bivariate_cdf(-components[i].beta, -components[j].beta, rho);
            sum_joint += pij;
            max_joint = max_joint.max(pij);
        }
        lower += (p[i] - sum_joint).max(0.0);
        upper += p[i] - max_joint;
    }
    [lower.min(1.0), upper.min(1.0)]
}
