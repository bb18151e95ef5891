//! Sampling estimates of P_f: crude Monte Carlo and importance sampling around the design point,
//! seeded and splittable into batches whose merged result equals a single run bit for bit.
//!
//! # Estimators
//!
//! Crude Monte Carlo: uₖ ~ N(0, I), P̂_f = N_fail/N, standard error √(P̂(1 − P̂)/N); the 95 %
//! interval is Wilson's score interval (it stays inside [0, 1] and is not empty when no sample fails).
//!
//! Importance sampling (Melchers 1989; Der Kiureghian 2022, §7): uₖ = c + yₖ, yₖ ~ N(0, I),
//! c = the design point u*, with weight wₖ = φₙ(uₖ)/φₙ(uₖ − c) = exp(−cᵀuₖ + ½‖c‖²);
//! P̂_f = (1/N)Σ 1[g(xₖ) ≤ 0] wₖ, sample variance s² of the scores, standard error s/√N, 95 %
//! interval P̂ ± 1.96 s/√N (normal approximation of the mean).
//! Coefficient of variation: standard error / P̂ (∞ when P̂ = 0).
//!
//! # Batches (how Dask workers run it)
//!
//! The N samples are cut into blocks of `block_size` (the last may be shorter). Block b draws from
//! its own derived stream: `ChaCha8Rng::seed_from_u64(seed)` with `set_stream(b)` (ChaCha's 64-bit
//! stream id; streams are independent keystreams of the same key). Each normal number takes one
//! 64-bit word (inverse transform, no rejection), so a block's samples depend only on (seed, b). Batch i of n takes
//! the blocks ⌊i·B/n⌋ … ⌊(i+1)·B/n⌋ − 1 (B blocks in all) and returns per-block sums (failures,
//! Σw, Σw²). [`merge`] sorts the blocks and adds them in block order; a single run is the merge
//! of batch 0 of 1, so every split gives the same floating-point sums — the same result, bit for bit.

use crate::error::{Error, EvalError, Result};
use crate::limit_state::{Fallible, LimitState};
use crate::model::Model;
use crate::rng;
use crate::stdnormal;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which estimator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum SamplingMethod {
    /// Crude Monte Carlo.
    MonteCarlo,
    /// Importance sampling with N(center, I) in u-space (center = the FORM design point u*).
    ImportanceSampling { center: Vec<f64> },
}

/// Sample count, seed and block size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SamplingOptions {
    /// Total samples N (≥ 2).
    pub samples: u64,
    /// Seed of ChaCha8Rng::seed_from_u64.
    pub seed: u64,
    /// Samples per block (default 1000); the unit of batch splitting.
    pub block_size: u64,
}

impl SamplingOptions {
    /// N samples with this seed and blocks of 1000.
    pub fn new(samples: u64, seed: u64) -> Self {
        Self {
            samples,
            seed,
            block_size: 1000,
        }
    }

    fn blocks(&self) -> u64 {
        self.samples.div_ceil(self.block_size)
    }
}

/// Which share of the run a worker does: batch `index` of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Batch {
    /// 0 ≤ index < count.
    pub index: u64,
    /// Number of batches (≥ 1).
    pub count: u64,
}

/// Sums of one block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlockSums {
    /// Block index.
    pub block: u64,
    /// Samples in the block.
    pub samples: u64,
    /// Failing samples.
    pub failures: u64,
    /// Σ of the scores 1[g ≤ 0]·w.
    pub sum_w: f64,
    /// Σ of the squared scores.
    pub sum_w2: f64,
}

/// What one batch returns (serialisable: a Dask worker sends it back as JSON).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SamplingBatch {
    /// The estimator.
    pub method: SamplingMethod,
    /// The run's options.
    pub options: SamplingOptions,
    /// This batch's blocks, in order.
    pub blocks: Vec<BlockSums>,
}

/// A sampling estimate of P_f.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SamplingResult {
    /// The estimator.
    pub method: SamplingMethod,
    /// P̂_f.
    pub pf: f64,
    /// β = −Φ⁻¹(P̂_f).
    pub beta: f64,
    /// Coefficient of variation of P̂_f.
    pub cov: f64,
    /// 95 % interval of P_f.
    pub interval: [f64; 2],
    /// Samples N (= limit-state evaluations).
    pub samples: u64,
    /// Failing samples.
    pub failures: u64,
}

fn check(
    model: &Model,
    method: &SamplingMethod,
    options: &SamplingOptions,
    batch: Batch,
) -> Result<()> {
    let bad = |field, value: f64, allowed| {
        Err(Error::InvalidOption {
            field,
            value,
            allowed,
        })
    };
    if options.samples < 2 {
        return bad("samples", options.samples as f64, "at least 2");
    }
    if options.block_size == 0 {
        return bad("block_size", 0.0, "at least 1");
    }
    if batch.count == 0 || batch.index >= batch.count {
        return bad(
            "batch.index",
            batch.index as f64,
            "0 ≤ index < count, count ≥ 1",
        );
    }
    if let SamplingMethod::ImportanceSampling { center } = method {
        if center.len() != model.len() {
            return Err(Error::DimensionMismatch {
                what: "importance-sampling center",
                expected: model.len(),
                got: center.len(),
            });
        }
        if let Some(v) = center.iter().find(|v| !v.is_finite()) {
            return bad("center", *v, "finite coordinates");
        }
    }
    Ok(())
}

/// Runs batch `batch` of a sampling run; see the module docs.
pub fn sample_batch<L: LimitState + ?Sized>(
    model: &Model,
    limit_state: &mut L,
    method: &SamplingMethod,
    options: &SamplingOptions,
    batch: Batch,
) -> Result<SamplingBatch> {
    check(model, method, options, batch)?;
    let (first, last) = block_range(options, batch);
    let center = center_of(method);
    let blocks = (first..last)
        .map(|b| run_block(model, limit_state, center, options, b))
        .collect::<Result<Vec<_>>>()?;
    Ok(SamplingBatch {
        method: method.clone(),
        options: options.clone(),
        blocks,
    })
}

/// Batch `batch` with its blocks run in parallel (rayon), for a limit state that can be shared
/// between threads. Each block is still summed sequentially and the blocks are kept in order, so
/// the result equals [`sample_batch`]'s bit for bit.
pub fn sample_batch_parallel<F>(
    model: &Model,
    limit_state: &F,
    method: &SamplingMethod,
    options: &SamplingOptions,
    batch: Batch,
) -> Result<SamplingBatch>
where
    F: Fn(&[f64]) -> Result<f64, EvalError> + Sync,
{
    check(model, method, options, batch)?;
    let (first, last) = block_range(options, batch);
    let center = center_of(method);
    let blocks = (first..last)
        .into_par_iter()
        .map(|b| {
            run_block(
                model,
                &mut Fallible(|x: &[f64]| limit_state(x)),
                center,
                options,
                b,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(SamplingBatch {
        method: method.clone(),
        options: options.clone(),
        blocks,
    })
}

fn block_range(options: &SamplingOptions, batch: Batch) -> (u64, u64) {
    let total = options.blocks();
    (
        batch.index * total / batch.count,
        (batch.index + 1) * total / batch.count,
    )
}

fn center_of(method: &SamplingMethod) -> Option<&[f64]> {
    match method {
        SamplingMethod::MonteCarlo => None,
        SamplingMethod::ImportanceSampling { center } => Some(center.as_slice()),
    }
}

/// Block `b`'s random stream (the seed's stream number `b`, so every block draws the same numbers
/// whichever batch or thread runs it) and its sample count (the last block may be short).
fn block_stream(options: &SamplingOptions, b: u64) -> (ChaCha8Rng, u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    rng.set_stream(b);
    let count = options
        .block_size
        .min(options.samples - b * options.block_size);
    (rng, count)
}

/// The sums of block `b`: its own ChaCha8 stream, samples in order.
fn run_block<L: LimitState + ?Sized>(
    model: &Model,
    limit_state: &mut L,
    center: Option<&[f64]>,
    options: &SamplingOptions,
    b: u64,
) -> Result<BlockSums> {
    let half_c2 = center.map_or(0.0, |c| 0.5 * c.iter().map(|v| v * v).sum::<f64>());
    let mut u = vec![0.0; model.len()];
    let (mut rng, count) = block_stream(options, b);
    let mut sums = BlockSums {
        block: b,
        samples: count,
        failures: 0,
        sum_w: 0.0,
        sum_w2: 0.0,
    };
    for _ in 0..count {
        for v in u.iter_mut() {
            *v = rng::std_normal(&mut rng);
        }
        let mut w = 1.0;
        if let Some(c) = center {
            for (v, ci) in u.iter_mut().zip(c) {
                *v += ci;
            }
            let cu: f64 = c.iter().zip(&u).map(|(a, b)| a * b).sum();
            w = (half_c2 - cu).exp();
        }
        let x = model.x_from_u(&u);
        let g = limit_state.value(&x).map_err(|source| Error::LimitState {
            x: x.clone(),
            source,
        })?;
        if g.is_nan() {
            return Err(Error::NonFiniteLimitState {
                what: "value",
                value: g,
                x,
            });
        }
        if g <= 0.0 {
            sums.failures += 1;
            sums.sum_w += w;
            sums.sum_w2 += w * w;
        }
    }
    Ok(sums)
}

/// Merges the batches of one run (in any order) into its estimate; errors when they belong to
/// different runs, overlap or leave blocks out.
pub fn merge(batches: &[SamplingBatch]) -> Result<SamplingResult> {
    let first = batches.first().ok_or_else(|| Error::BatchMerge {
        reason: "no batches".to_owned(),
    })?;
    if let Some(other) = batches
        .iter()
        .find(|b| b.method != first.method || b.options != first.options)
    {
        return Err(Error::BatchMerge {
            reason: format!(
                "batches of different runs ({:?} {:?} vs {:?} {:?})",
                first.method, first.options, other.method, other.options
            ),
        });
    }
    let options = &first.options;
    let mut blocks: Vec<&BlockSums> = batches.iter().flat_map(|b| &b.blocks).collect();
    blocks.sort_by_key(|b| b.block);
    let expected = options.blocks();
    if blocks.len() as u64 != expected
        || blocks.iter().enumerate().any(|(k, b)| b.block != k as u64)
    {
        let have: Vec<u64> = blocks.iter().map(|b| b.block).collect();
        return Err(Error::BatchMerge {
            reason: format!(
                "the run has blocks 0..{expected}, the batches hold {have:?} (missing or duplicate blocks)"
            ),
        });
    }
    let (mut samples, mut failures, mut sum_w, mut sum_w2) = (0u64, 0u64, 0.0, 0.0);
    for b in &blocks {
        samples += b.samples;
        failures += b.failures;
        sum_w += b.sum_w;
        sum_w2 += b.sum_w2;
    }
    if samples != options.samples {
        return Err(Error::BatchMerge {
            reason: format!(
                "the blocks hold {samples} samples, the run has {}",
                options.samples
            ),
        });
    }
    let ns = samples as f64;
    let z = 1.959_963_984_540_054; // Φ⁻¹(0.975)
    let (pf, se, interval) = match first.method {
        SamplingMethod::MonteCarlo => {
            let p = failures as f64 / ns;
            let se = (p * (1.0 - p) / ns).sqrt();
            let denom = 1.0 + z * z / ns;
            let centre = (p + z * z / (2.0 * ns)) / denom;
            let half = z * (p * (1.0 - p) / ns + z * z / (4.0 * ns * ns)).sqrt() / denom;
            (p, se, [(centre - half).max(0.0), (centre + half).min(1.0)])
        }
        SamplingMethod::ImportanceSampling { .. } => {
            let p = sum_w / ns;
            let var = ((sum_w2 / ns - p * p) * ns / (ns - 1.0)).max(0.0);
            let se = (var / ns).sqrt();
            (p, se, [(p - z * se).max(0.0), (p + z * se).min(1.0)])
        }
    };
    Ok(SamplingResult {
        method: first.method.clone(),
        pf,
        beta: stdnormal::beta_of(pf),
        cov: if pf > 0.0 { se / pf } else { f64::INFINITY },
        interval,
        samples,
        failures,
    })
}

/// Crude Monte Carlo in one run (= the merge of batch 0 of 1).
pub fn monte_carlo<L: LimitState + ?Sized>(
    model: &Model,
    limit_state: &mut L,
    options: &SamplingOptions,
) -> Result<SamplingResult> {
    let batch = sample_batch(
        model,
        limit_state,
        &SamplingMethod::MonteCarlo,
        options,
        Batch { index: 0, count: 1 },
    )?;
    merge(&[batch])
}

/// Importance sampling around `center` (u-space; pass the FORM `u_star`) in one run.
pub fn importance_sampling<L: LimitState + ?Sized>(
    model: &Model,
    limit_state: &mut L,
    center: &[f64],
    options: &SamplingOptions,
) -> Result<SamplingResult> {
    let method = SamplingMethod::ImportanceSampling {
        center: center.to_vec(),
    };
    let batch = sample_batch(
        model,
        limit_state,
        &method,
        options,
        Batch { index: 0, count: 1 },
    )?;
    merge(&[batch])
}

/// Counts of several failure events in one block (see [`sample_events`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EventBlock {
    /// Block index.
    pub block: u64,
    /// Samples in the block.
    pub samples: u64,
    /// Per event, the samples in which it occurred.
    pub counts: Vec<u64>,
}

/// What one batch of [`sample_events`] returns (serialisable for a Dask worker).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EventBatch {
    /// The run's options.
    pub options: SamplingOptions,
    /// Number of events.
    pub events: usize,
    /// This batch's blocks, in order.
    pub blocks: Vec<EventBlock>,
}

/// Crude Monte Carlo of `events` failure events at once on the same samples (e.g. "state n
/// fails" for every state of a print): `indicator(u, x, hits)` sets `hits[k]` when event k occurs
/// at the sample (u in standard normal space, x = the model's physical values; a caller with
/// drifted models maps u itself). Blocks draw exactly the numbers of [`monte_carlo`] with the
/// same options (the same stream per block, one word per normal), run in parallel (rayon) and
/// are kept in order, so batches merge ([`merge_events`]) into the single run bit for bit.
///
/// # Errors
/// Invalid options or a failing indicator.
pub fn sample_events<F>(
    model: &Model,
    events: usize,
    indicator: &F,
    options: &SamplingOptions,
    batch: Batch,
) -> Result<EventBatch>
where
    F: Fn(&[f64], &[f64], &mut [bool]) -> Result<(), EvalError> + Sync,
{
    check(model, &SamplingMethod::MonteCarlo, options, batch)?;
    let (first, last) = block_range(options, batch);
    let blocks = (first..last)
        .into_par_iter()
        .map(|b| {
            let mut u = vec![0.0; model.len()];
            let (mut rng, count) = block_stream(options, b);
            let mut counts = vec![0u64; events];
            let mut hits = vec![false; events];
            for _ in 0..count {
                for v in u.iter_mut() {
                    *v = rng::std_normal(&mut rng);
                }
                let x = model.x_from_u(&u);
                hits.iter_mut().for_each(|h| *h = false);
                indicator(&u, &x, &mut hits).map_err(|source| Error::LimitState {
                    x: x.clone(),
                    source,
                })?;
                for (c, h) in counts.iter_mut().zip(&hits) {
                    *c += u64::from(*h);
                }
            }
            Ok(EventBlock {
                block: b,
                samples: count,
                counts,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(EventBatch {
        options: options.clone(),
        events,
        blocks,
    })
}

/// Merges the batches of one [`sample_events`] run into a crude Monte Carlo estimate per event
/// (the same estimator and interval as [`merge`]).
///
/// # Errors
/// Batches of different runs, or missing or duplicate blocks.
pub fn merge_events(batches: &[EventBatch]) -> Result<Vec<SamplingResult>> {
    let first = batches.first().ok_or_else(|| Error::BatchMerge {
        reason: "no batches".to_owned(),
    })?;
    if batches
        .iter()
        .any(|b| b.options != first.options || b.events != first.events)
    {
        return Err(Error::BatchMerge {
            reason: "batches of different runs (options or event counts differ)".to_owned(),
        });
    }
    // Each event as a one-event SamplingBatch: the same merge (checks, sums and interval).
    (0..first.events)
        .map(|k| {
            let as_batches: Vec<SamplingBatch> = batches
                .iter()
                .map(|b| SamplingBatch {
                    method: SamplingMethod::MonteCarlo,
                    options: b.options.clone(),
                    blocks: b
                        .blocks
                        .iter()
                        .map(|e| {
                            let f = e.counts.get(k).copied().unwrap_or(0);
                            BlockSums {
                                block: e.block,
                                samples: e.samples,
                                failures: f,
                                sum_w: f as f64,
                                sum_w2: f as f64,
                            }
                        })
                        .collect(),
                })
                .collect();
            merge(&as_batches)
        })
        .collect()
}
