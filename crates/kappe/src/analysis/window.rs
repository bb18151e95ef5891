//! Buckling analysis that scales with the bay length (issue 15): a **graded shell mesh** along
//! the print direction.
//!
//! Consecutive print states differ by one layer. The shell of a state is a continuum (thickness
//! lw, weight γ·lw per unit area); the print layers are only its discretisation along y. The
//! lowest buckling mode of a tilted-layer cap is **not** local to the newest layers: measured
//! with `examples/mode_profile.rs`, mode 1 of the final state rises almost linearly from the start
//! section to the top (amplitude 0.15 at layer 0 of the default, 0.26 at layer 0 of a 1.2 m cap),
//! a sway of the whole stack about the feet on the beams. So cutting a window of the newest
//! layers (clamped at the cut; [`window_shell`], kept for the record) is 23–34 % off on the
//! default cap. What the mode *is* is smooth in depth: so the mesh keeps every layer as a row
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
//! mode ([`crate::analysis::buckling::state_buckling_warm`]), about 30 % fewer CPU seconds.
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

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use kappe_fe::Support;

use crate::analysis::AnalysisOptions;
use crate::analysis::buckling::{BucklingStatus, StateBuckling, shell_buckling};
use crate::analysis::shell::{NoShell, ShellMaterial, StateShell, state_shell};
use crate::form::states::State;
use crate::input::error::DesignError;

/// Settings of the window experiment (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindowOptions {
    /// Rows (layers) in the window, not counting the clamped cut row; 0 = analyse every state
    /// whole.
    pub layers: usize,
    /// Largest allowed mode-1 amplitude next to the cut, relative to its peak.
    pub decay: f64,
    /// Rows above the cut whose amplitude is checked.
    pub guard: usize,
}

impl Default for WindowOptions {
    fn default() -> Self {
        WindowOptions {
            layers: 40,
            decay: 0.02,
            guard: 3,
        }
    }
}

/// The windowed buckling result of one state (the window experiment, see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct WindowedBuckling {
    /// The buckling result (its `shell_nodes` are the window's).
    pub buckling: StateBuckling,
    /// Rows analysed (the whole state when it is not longer than the window).
    pub rows: usize,
    /// Rows of the whole state.
    pub state_rows: usize,
    /// Mode-1 amplitude on the guard rows over its peak (0 for a whole state).
    pub edge_ratio: f64,
}

/// The sub-model of `shell` made of its last `rows` rows plus the row below them, clamped.
/// `None` when the shell has no more than `rows + 1` rows (then the whole shell is the window).
pub fn window_shell(shell: &StateShell, rows: usize) -> Option<StateShell> {
    let n_rows = shell.rows.len();
    if rows == 0 || n_rows <= rows + 1 {
        return None;
    }
    let k0 = n_rows - rows - 1;
    let mut map: HashMap<usize, usize> = HashMap::new();
    let mut nodes = Vec::new();
    let mut node_layer = Vec::new();
    let mut network_node = Vec::new();
    let mut new_rows = Vec::with_capacity(rows + 1);
    for (id, row) in &shell.rows[k0..] {
        let mut r = Vec::with_capacity(row.len());
        for &i in row {
            let j = nodes.len();
            map.insert(i, j);
            nodes.push(*shell.model.nodes.get(i)?);
            node_layer.push(*shell.node_layer.get(i)?);
            network_node.push(*shell.network_node.get(i)?);
            r.push(j);
        }
        new_rows.push((*id, r));
    }
    let m = &shell.model;
    let per_tri = |v: usize| v > 1;
    let mut triangles = Vec::new();
    let mut thickness = Vec::new();
    let mut materials = Vec::new();
    let mut element_layers = Vec::new();
    for (t, tri) in m.triangles.iter().enumerate() {
        let (Some(&a), Some(&b), Some(&c)) = (map.get(&tri[0]), map.get(&tri[1]), map.get(&tri[2]))
        else {
            continue;
        };
        triangles.push([a, b, c]);
        if per_tri(m.thickness.len()) {
            thickness.push(*m.thickness.get(t)?);
        }
        if per_tri(m.materials.len()) {
            materials.push(*m.materials.get(t)?);
        }
        element_layers.push(*shell.element_layers.get(t)?);
    }
    let mut model = m.clone();
    model.nodes = nodes;
    model.triangles = triangles;
    if per_tri(m.thickness.len()) {
        model.thickness = thickness;
    }
    if per_tri(m.materials.len()) {
        model.materials = materials;
    }
    let cut: Vec<usize> = new_rows.first().map(|r| r.1.clone()).unwrap_or_default();
    let mut supports: Vec<Support> = m
        .supports
        .iter()
        .filter_map(|s| {
            map.get(&s.node).map(|&j| Support {
                node: j,
                fixed: s.fixed,
            })
        })
        .collect();
    supports.extend(cut.iter().map(|&j| Support::clamped(j)));
    model.supports = supports;
    model.nodal_loads = m
        .nodal_loads
        .iter()
        .filter_map(|l| {
            map.get(&l.node).map(|&j| {
                let mut l = *l;
                l.node = j;
                l
            })
        })
        .collect();
    Some(StateShell {
        model,
        node_layer,
        network_node,
        element_layers,
        rows: new_rows,
        merged_feet: shell.merged_feet,
    })
}

/// Mode-1 amplitude on rows `1..=guard` of the window (row 0 is the clamped cut) over its peak.
fn edge_ratio(shell: &StateShell, mode: &[[f64; 6]], guard: usize) -> f64 {
    let amp = |i: usize| {
        mode.get(i)
            .map_or(0.0, |d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
    };
    let peak = (0..mode.len()).map(amp).fold(0.0_f64, f64::max);
    if peak <= 0.0 {
        return 0.0;
    }
    let edge = shell
        .rows
        .iter()
        .skip(1)
        .take(guard)
        .flat_map(|(_, r)| r.iter().map(|&i| amp(i)))
        .fold(0.0_f64, f64::max);
    edge / peak
}

/// Buckling of `state` on a window of its newest layers clamped at the cut, grown until the mode
/// decays before the cut or the window is the whole state. Kept for the record: the mode of a cap
/// is global, so this is not accurate (module docs); use [`graded_state`].
pub fn windowed_buckling(
    state: &State,
    material: &ShellMaterial,
    options: &AnalysisOptions,
    window: &WindowOptions,
) -> Result<WindowedBuckling, DesignError> {
    let full = match state_shell(state, material, options.row_stride) {
        Ok(s) => s,
        Err(NoShell::SingleLayer) => {
            return Ok(WindowedBuckling {
                buckling: StateBuckling {
                    status: BucklingStatus::SingleLayer,
                    factors: Vec::new(),
                    location: None,
                    mechanism: None,
                    shell_nodes: 0,
                },
                rows: 1,
                state_rows: 1,
                edge_ratio: 0.0,
            });
        }
    };
    let state_rows = full.rows.len();
    let mut rows = window.layers;
    loop {
        let Some(sub) = window_shell(&full, rows) else {
            let buckling = shell_buckling(&full, state.index, options)?;
            return Ok(WindowedBuckling {
                buckling,
                rows: state_rows,
                state_rows,
                edge_ratio: 0.0,
            });
        };
        let (buckling, modes) = shell_buckling_modes(&sub, state.index, options)?;
        let ratio = modes
            .first()
            .map_or(0.0, |m| edge_ratio(&sub, m, window.guard));
        if buckling.status == BucklingStatus::Analysed && ratio <= window.decay {
            return Ok(WindowedBuckling {
                buckling,
                rows: rows + 1,
                state_rows,
                edge_ratio: ratio,
            });
        }
        // The mode reaches the cut (or the window is a mechanism): grow it.
        rows *= 2;
    }
}

/// [`shell_buckling`] plus the mode shapes (for the decay check).
/// Mode shapes: per mode, the six displacements of every shell node.
type Modes = Vec<Vec<[f64; 6]>>;

fn shell_buckling_modes(
    shell: &StateShell,
    state: usize,
    options: &AnalysisOptions,
) -> Result<(StateBuckling, Modes), DesignError> {
    let fe_opts = kappe_fe::BucklingOptions {
        modes: options.modes,
        tolerance: 1e-8,
        sturm_check: options.sturm_check,
        ..Default::default()
    };
    match kappe_fe::buckling(&shell.model, &fe_opts) {
        Ok(r) => {
            let b = shell_buckling_from(shell, &r);
            Ok((b, r.modes))
        }
        // Mechanisms and errors: let the standard path report them.
        Err(_) => Ok((shell_buckling(shell, state, options)?, Vec::new())),
    }
}

fn shell_buckling_from(shell: &StateShell, r: &kappe_fe::BucklingResult) -> StateBuckling {
    let location = r.modes.first().and_then(|m| {
        let (i, _) = m
            .iter()
            .enumerate()
            .map(|(i, d)| (i, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        Some((*shell.node_layer.get(i)?, *shell.model.nodes.get(i)?))
    });
    StateBuckling {
        status: if r.factors.is_empty() {
            BucklingStatus::NoPositiveFactor
        } else {
            BucklingStatus::Analysed
        },
        factors: r.factors.clone(),
        location,
        mechanism: None,
        shell_nodes: shell.model.nodes.len(),
    }
}

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
    let nodes = map
        .iter()
        .filter_map(|&i| net.nodes.get(i).cloned())
        .collect();
    let reduced = State {
        index: state.index,
        layers_printed: state.layers_printed,
        top_layer: state.top_layer,
        progress: state.progress,
        factors: state.factors.clone(),
        column_force_per_weight: state.column_force_per_weight.clone(),
        network: crate::form::states::Network {
            nodes,
            trails: Vec::new(),
            deviation_edges: Vec::new(),
        },
    };
    (reduced, map)
}
