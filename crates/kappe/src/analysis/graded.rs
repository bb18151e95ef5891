//! Buckling analysis that scales with the bay length (issue 15): a **graded shell mesh** along
//! the print direction.
//!
//! Consecutive print states differ by one layer. The shell of a state is a continuum (thickness
//! lw, weight γ·lw per unit area); the print layers are only its discretisation along y. The
//! lowest buckling mode of a tilted-layer cap is **not** local to the newest layers: measured
//! with `examples/mode_profile.rs`, mode 1 of the final state rises almost linearly from the start
//! section to the top (amplitude 0.15 at layer 0 of the default, 0.26 at layer 0 of a 1.2 m cap),
//! a sway of the whole stack about the feet on the beams. So cutting a window of the newest
//! layers (clamped at the cut; an experiment removed in issue 22, see the git history) is
//! 23–34 % off on the default cap. What the mode *is* is smooth in depth: so the mesh keeps every layer as a row
//! near the top, where the mode and the stresses change fastest, and thins the rows out with
//! depth ([`graded_rows`]: the newest `fine` layers at stride 1, then `zone_rows` rows at each of
//! the strides 2, 4, … up to `max_stride` layers per row, which goes on to the bed). Deep rows are
//! also thinned along the layer ([`Grading::transverse`]: every c-th node, c the largest power of
//! two keeping the facets about square, at most `transverse`). The shell's DOFs then grow like
//! `fine + zone_rows·log2(max_stride) + depth/max_stride` rows instead of `depth`.
//!
//! **The supports set the grading, not the depth.** A start layer's feet stand on the base
//! plane, each pinned: a coarse row in the start section leaves that support line pinned only
//! every few layers. That, not the depth, is where coarse gradings lost their accuracy: on the
//! 1.2 m cap, zone rows 4 are 1.8 % off with the start section graded like the rest and 0.15 %
//! with every start layer a row ([`Grading::start_stride`] 1); on an end-wall cap (no start
//! section) zone rows 4 are 0.15–0.51 % off. The start section has a fixed number of layers, so
//! keeping it whole costs the same at every length, while four zone rows instead of twelve make
//! the per-state mesh stop growing early (issue 15's cost exponent, `examples/scaling.rs`).
//!
//! Rows are anchored at print index 0 (a row is kept when its index is a multiple of its stride),
//! so the mesh of a state is the previous state's mesh less a few rows plus the new top layer:
//! [`crate::analysis::analyze`] starts each state's Lanczos iteration from the previous state's
//! mode ([`crate::analysis::buckling::BucklingRequest::guess`]), about 30 % fewer CPU seconds.
//! (`kappe_fe` blends the start with seeded noise: the previous mode alone once made a 4.8 m
//! cap's state converge to its second mode, 2 % high.)
//!
//! **Checked against the full mesh** (`examples/graded_check.rs`, the analysis as `kappe design`
//! runs it, release) with the default grading (fine 32, zone rows 4 at each stride 2 … 64, then
//! stride 128; transverse 2; start stride 1), largest BLF difference and where, the governing
//! state the same in each:
//!
//! | cap | states checked | largest difference | governing state, BLF graded / full | FE s, graded / full |
//! |---|---|---|---|---|
//! | default (0.6 m, start section) | all 113 | 0.085 % (state 108) | 112, 3.6028 / 3.6052 | 6.8 / 8.0 |
//! | 1.2 m, start section | all 197 | 0.15 % (state 160) | 196, 2.3969 / 2.3970 | 13.1 / 28.4 |
//! | 1.2 m, end wall | all 136 | 0.15 % (state 64) | 135, 3.3740 / 3.3739 | 4.3 / 15.2 |
//! | 4.8 m, end wall | every 4th of 544 | 0.41 % (state 392) | 543, 1.5524 / 1.5481 | 5.3 / 72.9 |
//! | 9.6 m, end wall | every 16th of 1,088 | 0.40 % (state 400) | 1087, 1.4682 / 1.4644 | 2.8 / – |
//!
//! The previous default (zone rows 12, max stride 32, transverse 4, the start section graded)
//! was 0.22 %, 0.56 %, 0.16 % and 0.40 % on the first four. Max stride 32 instead of 128 gives
//! 0.26 % at 4.8 m and 0.29 % at 9.6 m, but a row per 32 layers below the zones, so the mesh
//! keeps growing with the depth; with 128 the 9.6 m cap's states 100 … 1087 have 2,045 … 2,445
//! shell nodes at the same cost (`examples/analysis_bench.rs profile`).
//! `tests/scale.rs` repeats the check on every 8th state of the default cap, every 24th of the
//! 1.2 m cap and every 24th of the 1.2 m end-wall cap.
//!
//! Independent of the element: the graded state is the state's network reduced to the kept rows,
//! meshed by [`crate::analysis::shell::state_shell`] with whatever element it uses. Hand-written: the row
//! bookkeeping of print layers is Kappe's own.

use crate::form::states::State;

pub use crate::input::analysis::Grading;

/// Which of `n` rows (print order, the last is the newest; the first `start_rows` are the start
/// section's) a graded mesh keeps: a row `d` layers below the top is kept when its print index is
/// a multiple of [`Grading::row_stride`]; the first row (on the bed or the wall) and the top row
/// always.
/// The rows are anchored at print index 0, not at the top, so the kept rows of a state are the
/// kept rows of the previous state less a few and plus the new top layer (strides only grow with
/// depth and are powers of two): the previous state's mode is a good start for this one.
pub fn graded_rows(n: usize, start_rows: usize, g: &Grading) -> Vec<bool> {
    (0..n)
        .map(|q| q == 0 || q.is_multiple_of(g.row_stride(n - 1 - q, q < start_rows)))
        .collect()
}

/// The state's network reduced to the rows a graded mesh keeps (nodes only: the shell is built
/// from the layer rows, [`crate::analysis::shell::layer_rows`]). Column ends are dropped (the shell does not
/// use them).
pub fn graded_state(state: &State, g: &Grading) -> State {
    graded_state_map(state, g).0
}

/// The network a state's shell analysis meshes: the state itself, or with a grading its graded
/// reduction ([`graded_state_map`]) together with the way back to the state's own nodes, so the
/// buckling and the green-state checks report modes and places on the state's network.
pub enum AnalysedState<'a> {
    /// Every layer is a mesh row.
    Full(&'a State),
    /// The kept rows, and for each of their nodes its index in the state's network.
    Graded(State, Vec<usize>),
}

impl<'a> AnalysedState<'a> {
    /// `state` as the analysis with `grading` meshes it.
    pub fn new(state: &'a State, grading: Option<&Grading>) -> Self {
        match grading {
            Some(g) => {
                let (reduced, map) = graded_state_map(state, g);
                AnalysedState::Graded(reduced, map)
            }
            None => AnalysedState::Full(state),
        }
    }

    /// The network to mesh.
    pub fn state(&self) -> &State {
        match self {
            AnalysedState::Full(s) => s,
            AnalysedState::Graded(s, _) => s,
        }
    }

    /// The index in the state's own network of node `k` of [`Self::state`].
    pub fn full_index(&self, k: usize) -> Option<usize> {
        match self {
            AnalysedState::Full(_) => Some(k),
            AnalysedState::Graded(_, map) => map.get(k).copied(),
        }
    }
}

/// Indices `0 = i_0 < … < i_m = len − 1` of the nodes a row of `len` nodes keeps when thinned by
/// `c`: m = ⌈(len − 1)/c⌉ nearly equal steps (so no sliver at the far foot).
fn thinned(len: usize, c: usize) -> Vec<usize> {
    if c <= 1 || len <= 2 {
        return (0..len).collect();
    }
    let m = (len - 1).div_ceil(c).max(1);
    (0..=m).map(|j| (j * (len - 1) + m / 2) / m).collect()
}

/// Fewest segments a transversally thinned row keeps (the arch needs a few facets to bend).
const MIN_ROW_SEGMENTS: usize = 8;

/// [`graded_state`] and, for every node of the reduced network, its index in `state`'s network.
pub fn graded_state_map(state: &State, g: &Grading) -> (State, Vec<usize>) {
    let net = &state.network;
    let rows = crate::analysis::shell::layer_rows(net);
    let n = rows.len();
    let start_rows = rows.iter().take_while(|(id, _)| *id < 0).count();
    let keep = graded_rows(n, start_rows, g);
    // Δs and the layer pitch at the top (both are uniform along the cap).
    let pitch_ratio = match (rows.last(), n.checked_sub(2).and_then(|k| rows.get(k))) {
        (Some((_, top)), Some((_, below))) if top.len() >= 2 && top.len() == below.len() => {
            let mid = top.len() / 2;
            let d = |a: usize, b: usize| {
                let (Some(p), Some(q)) = (net.nodes.get(a), net.nodes.get(b)) else {
                    return 0.0;
                };
                (p.xyz - q.xyz).norm()
            };
            let seg = d(top[mid - 1], top[mid]);
            if seg > 0.0 {
                d(top[mid], below[mid]) / seg
            } else {
                0.0
            }
        }
        _ => 0.0,
    };
    let mut map = Vec::new();
    for (q, ((_, row), k)) in rows.iter().zip(&keep).enumerate() {
        if !*k {
            continue;
        }
        let stride = g.row_stride(n - 1 - q, q < start_rows);
        let mut c = 1usize;
        while 2 * c <= g.transverse.max(1)
            && (2 * c) as f64 <= stride as f64 * pitch_ratio
            && (row.len().saturating_sub(1)) / (2 * c) >= MIN_ROW_SEGMENTS
        {
            c *= 2;
        }
        map.extend(thinned(row.len(), c).into_iter().filter_map(|j| row.get(j)));
    }
    // The network stores the layers top-down; keep that order.
    map.sort_unstable();
    (with_nodes(state, &map), map)
}

/// `state` with only the network nodes `map` (sorted indices into its nodes), for the shell
/// mesh alone (no trails or deviation edges).
fn with_nodes(state: &State, map: &[usize]) -> State {
    let net = &state.network;
    State {
        index: state.index,
        layers_printed: state.layers_printed,
        top_layer: state.top_layer,
        progress: state.progress,
        factors: state.factors.clone(),
        column_force_per_weight: state.column_force_per_weight.clone(),
        network: crate::form::states::Network {
            nodes: map
                .iter()
                .filter_map(|&i| net.nodes.get(i).cloned())
                .collect(),
            trails: Vec::new(),
            deviation_edges: Vec::new(),
        },
    }
}

/// The state's network on a coarser mesh (issue 25, the coarse-mesh screen of
/// docs/convergence.md): every `row_stride`-th layer row (anchored at print index 0, the first
/// and the top row always, as [`crate::analysis::shell::state_shell`]'s `row_stride`) and every
/// `node_stride`-th node along each kept row (both feet kept, [`thinned`]'s nearly equal steps).
/// Strides 1 and 1 give the state's shell nodes (column ends are dropped: the shell does not
/// use them); 2 and 2 the mesh 2h.
pub fn coarsened_state(state: &State, row_stride: usize, node_stride: usize) -> State {
    let (rs, ns) = (row_stride.max(1), node_stride.max(1));
    let net = &state.network;
    let rows = crate::analysis::shell::layer_rows(net);
    let top = rows.len().saturating_sub(1);
    let mut map: Vec<usize> = rows
        .iter()
        .enumerate()
        .filter(|(q, _)| q % rs == 0 || *q == top)
        .flat_map(|(_, (_, row))| {
            thinned(row.len(), ns)
                .into_iter()
                .filter_map(|j| row.get(j).copied())
        })
        .collect();
    map.sort_unstable();
    with_nodes(state, &map)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 2h network of a default-cap state: the rows at even print index and the top row,
    /// each with both feet and every other node between them (⌈(len − 1)/2⌉ steps), in the
    /// network's own top-down order; strides 1 keep every shell node.
    #[test]
    fn coarsened_state_keeps_every_other_row_and_node_and_the_feet() {
        let cap = crate::design_cap(&crate::Design::default(), crate::Context::default())
            .expect("the default design is valid");
        let state = cap.state(21).expect("state 21 exists");
        let rows = crate::analysis::shell::layer_rows(&state.network);
        let shell_nodes: Vec<_> = state
            .network
            .nodes
            .iter()
            .filter(|n| n.role != crate::form::states::Role::ColumnEnd)
            .cloned()
            .collect();
        assert_eq!(coarsened_state(&state, 1, 1).network.nodes, shell_nodes);
        let coarse = coarsened_state(&state, 2, 2);
        let coarse_rows = crate::analysis::shell::layer_rows(&coarse.network);
        let kept: Vec<&(i32, Vec<usize>)> = rows
            .iter()
            .enumerate()
            .filter(|(q, _)| q % 2 == 0 || *q == rows.len() - 1)
            .map(|(_, r)| r)
            .collect();
        assert_eq!(coarse_rows.len(), kept.len());
        for ((id, full), (cid, thin)) in kept.iter().map(|r| (&r.0, &r.1)).zip(&coarse_rows) {
            assert_eq!(id, cid);
            assert_eq!(thin.len(), (full.len() - 1).div_ceil(2) + 1, "layer {id}");
            let (Some(&f0), Some(&f1), Some(&c0), Some(&c1)) =
                (full.first(), full.last(), thin.first(), thin.last())
            else {
                panic!("empty row {id}");
            };
            assert_eq!(coarse.network.nodes[c0].xyz, state.network.nodes[f0].xyz);
            assert_eq!(coarse.network.nodes[c1].xyz, state.network.nodes[f1].xyz);
        }
    }
}
