//! Ladder-graph search (Descartes-style, robot.md §3.2, §3.6): rungs are path frames, vertices
//! are the valid joint configurations of a frame, edges join consecutive rungs when the step is
//! feasible. Hand-written because the graph is a layered DAG whose edges are generated on the fly;
//! one forward pass `dist[k+1][j] = min_i dist[k][i] + c(i, j)` is exact and needs no graph crate.
//!
//! - [`solve_optimal`]: exact minimum total cost; ties break by the lowest vertex index.
//! - [`solve_random`]: the paper's method (random choice of compatible segments, best of N trials,
//!   seeded), with backward-reachability pruning so that walks do not dead-end.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A path through the ladder: one vertex index per rung and its total cost.
#[derive(Clone, Debug, PartialEq)]
pub struct LadderPath {
    pub vertices: Vec<usize>,
    pub cost: f64,
}

/// Why no path exists.
#[derive(Clone, Debug, PartialEq)]
pub enum LadderFailure {
    /// Rung `rung` has no vertex at all.
    EmptyRung { rung: usize },
    /// No vertex of rung `rung` can be reached from rung `rung − 1`.
    NoEdge { rung: usize },
}

/// Exact shortest path from any vertex of rung 0 to any vertex of the last rung.
///
/// `sizes[k]` is the number of vertices of rung k; `edge(k, i, j)` is the cost of going from
/// vertex i of rung k to vertex j of rung k + 1, or `None` when not allowed.
pub fn solve_optimal(
    sizes: &[usize],
    edge: impl Fn(usize, usize, usize) -> Option<f64> + Sync,
) -> Result<LadderPath, LadderFailure> {
    if sizes.is_empty() {
        return Ok(LadderPath {
            vertices: Vec::new(),
            cost: 0.0,
        });
    }
    if let Some(k) = sizes.iter().position(|&n| n == 0) {
        return Err(LadderFailure::EmptyRung { rung: k });
    }
    let mut dist: Vec<f64> = vec![0.0; sizes[0]];
    let mut pred: Vec<Vec<u32>> = Vec::with_capacity(sizes.len());
    pred.push(vec![u32::MAX; sizes[0]]);
    for k in 0..sizes.len() - 1 {
        let n1 = sizes[k + 1];
        let mut nd = vec![f64::INFINITY; n1];
        let mut np = vec![u32::MAX; n1];
        for (j, (ndj, npj)) in nd.iter_mut().zip(np.iter_mut()).enumerate() {
            for (i, &di) in dist.iter().enumerate() {
                if !di.is_finite() {
                    continue;
                }
                if let Some(c) = edge(k, i, j) {
                    let v = di + c;
                    if v < *ndj {
                        *ndj = v;
                        *npj = i as u32;
                    }
                }
            }
        }
        if nd.iter().all(|v| !v.is_finite()) {
            return Err(LadderFailure::NoEdge { rung: k + 1 });
        }
        dist = nd;
        pred.push(np);
    }
    let (mut best, mut cost) = (0usize, f64::INFINITY);
    for (j, &d) in dist.iter().enumerate() {
        if d < cost {
            cost = d;
            best = j;
        }
    }
    let mut vertices = vec![0usize; sizes.len()];
    let mut v = best;
    for k in (0..sizes.len()).rev() {
        vertices[k] = v;
        if k > 0 {
            v = pred[k][v] as usize;
        }
    }
    Ok(LadderPath { vertices, cost })
}

/// The paper's planner: `trials` random walks of compatible edges, each starting at a random
/// rung-0 vertex and picking a uniformly random allowed successor; the cheapest walk is kept.
/// Vertices that cannot reach the last rung are pruned first (a backward pass), so every walk
/// completes whenever any path exists. Deterministic for a given `seed`.
pub fn solve_random(
    sizes: &[usize],
    edge: impl Fn(usize, usize, usize) -> Option<f64>,
    trials: usize,
    seed: u64,
) -> Result<LadderPath, LadderFailure> {
    if sizes.is_empty() {
        return Ok(LadderPath {
            vertices: Vec::new(),
            cost: 0.0,
        });
    }
    if let Some(k) = sizes.iter().position(|&n| n == 0) {
        return Err(LadderFailure::EmptyRung { rung: k });
    }
    let last = sizes.len() - 1;
    // alive[k][i]: vertex i of rung k reaches the last rung.
    let mut alive: Vec<Vec<bool>> = sizes.iter().map(|&n| vec![false; n]).collect();
    alive[last].iter_mut().for_each(|a| *a = true);
    for k in (0..last).rev() {
        let (head, tail) = alive.split_at_mut(k + 1);
        let next = &tail[0];
        for (i, a) in head[k].iter_mut().enumerate() {
            *a = next
                .iter()
                .enumerate()
                .any(|(j, &nj)| nj && edge(k, i, j).is_some());
        }
        if !head[k].iter().any(|&a| a) {
            return Err(LadderFailure::NoEdge { rung: k + 1 });
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut best: Option<LadderPath> = None;
    let starts: Vec<usize> = (0..sizes[0]).filter(|&i| alive[0][i]).collect();
    for _ in 0..trials.max(1) {
        let mut v = starts[rng.random_range(0..starts.len())];
        let mut path = vec![v];
        let mut cost = 0.0;
        for k in 0..last {
            let options: Vec<(usize, f64)> = (0..sizes[k + 1])
                .filter(|&j| alive[k + 1][j])
                .filter_map(|j| edge(k, v, j).map(|c| (j, c)))
                .collect();
            // `alive` guarantees at least one option.
            let Some(&(j, c)) = options.get(rng.random_range(0..options.len().max(1))) else {
                break;
            };
            v = j;
            cost += c;
            path.push(v);
        }
        if path.len() == sizes.len() && best.as_ref().is_none_or(|b| cost < b.cost) {
            best = Some(LadderPath {
                vertices: path,
                cost,
            });
        }
    }
    best.ok_or(LadderFailure::NoEdge { rung: 1 })
}
