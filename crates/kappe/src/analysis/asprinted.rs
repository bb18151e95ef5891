//! The as-printed shape (issue 23 item 4, docs/as-printed.md): the print states in sequence,
//! each new layer laid at its programmed position onto the deformed earlier layers, each layer
//! with its own age in every state.
//!
//! The increment of state k is Δu_k = K_k⁻¹ f_k,new: K_k is state k's linear stiffness with
//! every layer's modulus at its age in state k, f_k,new the self-weight of what state k adds
//! (the strip between the previous top layer and the new one). Loads already carried stay
//! locked in: a layer that stiffens later does not un-deflect. A node's deviation from the
//! design after state k is the sum of the increments of the states from the one it was laid in
//! up to k; a node laid at its programmed position starts at zero deviation even though the
//! layer below it has sagged. Linear per increment, small rotations (docs/as-printed.md).
//!
//! Nodes are matched between states by (layer id, index of the node in its layer): the keys the
//! buckling warm start uses too ([`crate::analysis::buckling::ModeGuess`]), since network node
//! indices change from state to state (the network stores the layers top-down).

use std::collections::HashMap;

use kappe_fe::{FeError, ShellModel};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::analysis::buckling::state_material;
use crate::analysis::graded::AnalysedState;
use crate::analysis::shell::{NoShell, StateShell, state_shell};
use crate::form::cap::Cap;
use crate::input::analysis::AnalysisOptions;
use crate::input::error::DesignError;

/// A material point of the print: (layer id, index of the node in its layer).
pub type NodeKey = (i32, usize);

/// One print state's displacement increment.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Increment {
    /// Per node of the state: its key, its design position (m) and its increment Δu (m).
    pub nodes: Vec<(NodeKey, [f64; 3], [f64; 3])>,
    /// |Σ reactions + Σ loads| / |Σ loads| of the increment's static solve (0 when nothing
    /// was loaded).
    pub residual: f64,
}

/// The accumulated deviation from the design after one print state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct StateDeviation {
    /// State index (top print index).
    pub state: usize,
    /// Crown sag, m: the largest downward vertical deviation at the crown (the highest design
    /// node) of any printed layer (0 if no crown has sunk).
    pub crown_sag_m: f64,
    /// Layer whose crown sags most (None: no crown has sunk).
    pub crown_sag_layer: Option<i32>,
    /// The largest deviation |u| of any printed node from its design position, m.
    pub deviation_m: f64,
    /// Layer of that node.
    pub deviation_layer: Option<i32>,
    /// Design position of that node, m.
    pub deviation_at_m: Option<[f64; 3]>,
    /// Relative equilibrium residual of this state's increment.
    pub residual: f64,
}

/// The as-printed shape over the whole print.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct AsPrinted {
    /// The largest deviation over the print, m.
    pub deviation_m: f64,
    /// State where it occurs.
    pub state: Option<usize>,
    /// Layer of that node.
    pub layer: Option<i32>,
    /// Design position of that node, m.
    pub at_m: Option<[f64; 3]>,
    /// The largest crown sag over the print, m.
    pub crown_sag_m: f64,
    /// State of the largest crown sag.
    pub crown_sag_state: Option<usize>,
    /// The largest relative equilibrium residual of any increment.
    pub max_residual: f64,
    /// Per state, in print order.
    pub states: Vec<StateDeviation>,
}

/// The increment of one state: `model` carries only the weight added in this state (the
/// caller zeroes the unit weight of the older elements); `keys` names every model node (None:
/// a node not tracked).
///
/// # Errors
/// The static solve fails (e.g. the model is a mechanism).
pub fn increment(model: &ShellModel, keys: &[Option<NodeKey>]) -> Result<Increment, FeError> {
    Ok(increment_of(
        &model.nodes,
        keys,
        &kappe_fe::linear_static(model)?,
    ))
}

/// The increment from the static solution `r` of a state's new weight on the model with nodes
/// `nodes` (`keys` as in [`increment`]): e.g. the second load case of the state's buckling solve
/// (`kappe_fe::BucklingSolver::buckling_with_weight_case`), which reuses its factor of K.
pub fn increment_of(
    nodes: &[[f64; 3]],
    keys: &[Option<NodeKey>],
    r: &kappe_fe::StaticResult,
) -> Increment {
    let load = norm(r.load_sum);
    let sum = [0, 1, 2].map(|c| r.reactions_sum[c] + r.load_sum[c]);
    let nodes = keys
        .iter()
        .zip(nodes)
        .zip(&r.displacements)
        .filter_map(|((k, x), d)| k.map(|k| (k, *x, [d[0], d[1], d[2]])))
        .collect();
    Increment {
        nodes,
        residual: if load > 0.0 { norm(sum) / load } else { 0.0 },
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The deviation of every node after every state: the running sum of the increments, in print
/// order (a node's sum starts in the state it first appears in).
pub fn accumulate(increments: &[Increment]) -> AsPrinted {
    let mut dev: HashMap<NodeKey, ([f64; 3], [f64; 3])> = HashMap::new();
    let mut states = Vec::with_capacity(increments.len());
    for (k, inc) in increments.iter().enumerate() {
        for (key, x, du) in &inc.nodes {
            let e = dev.entry(*key).or_insert((*x, [0.0; 3]));
            for (sum, d) in e.1.iter_mut().zip(du) {
                *sum += d;
            }
        }
        // Crown of each layer: its highest design node (of two at the same height, the one
        // earlier in the layer, so the answer does not depend on the hash order).
        let mut crowns: HashMap<i32, (f64, usize, f64)> = HashMap::new();
        let mut worst: Option<(f64, NodeKey, [f64; 3])> = None;
        for (key, (x, u)) in &dev {
            let c = crowns
                .entry(key.0)
                .or_insert((f64::NEG_INFINITY, usize::MAX, 0.0));
            if x[2] > c.0 || (x[2] == c.0 && key.1 < c.1) {
                *c = (x[2], key.1, -u[2]);
            }
            let m = norm(*u);
            // Ties broken by key, so the answer does not depend on the hash order.
            if worst
                .as_ref()
                .is_none_or(|w| m > w.0 || (m == w.0 && *key < w.1))
            {
                worst = Some((m, *key, *x));
            }
        }
        let crown = crowns
            .iter()
            .filter(|(_, c)| c.2 > 0.0)
            .max_by(|a, b| a.1.2.total_cmp(&b.1.2).then(b.0.cmp(a.0)));
        states.push(StateDeviation {
            state: k,
            crown_sag_m: crown.map_or(0.0, |c| c.1.2),
            crown_sag_layer: crown.map(|c| *c.0),
            deviation_m: worst.as_ref().map_or(0.0, |w| w.0),
            deviation_layer: worst.as_ref().map(|w| w.1.0),
            deviation_at_m: worst.as_ref().map(|w| w.2),
            residual: inc.residual,
        });
    }
    let top = states
        .iter()
        .filter(|s| s.deviation_m > 0.0)
        .max_by(|a, b| {
            a.deviation_m
                .total_cmp(&b.deviation_m)
                .then(b.state.cmp(&a.state))
        });
    let sag = states
        .iter()
        .filter(|s| s.crown_sag_m > 0.0)
        .max_by(|a, b| {
            a.crown_sag_m
                .total_cmp(&b.crown_sag_m)
                .then(b.state.cmp(&a.state))
        });
    AsPrinted {
        deviation_m: top.map_or(0.0, |s| s.deviation_m),
        state: top.map(|s| s.state),
        layer: top.and_then(|s| s.deviation_layer),
        at_m: top.and_then(|s| s.deviation_at_m),
        crown_sag_m: sag.map_or(0.0, |s| s.crown_sag_m),
        crown_sag_state: sag.map(|s| s.state),
        max_residual: states.iter().fold(0.0, |m, s| m.max(s.residual)),
        states,
    }
}

/// The increment of print state `top` of `cap` on the mesh the buckling check meshes it with
/// (every layer a row, or with `[analysis.grading]` the graded rows, the dropped nodes filled in
/// by [`fill_graded`]; layer moduli at their ages in state `top` from `green`).
///
/// # Errors
/// A state that cannot be built, or whose shell is a mechanism.
pub fn cap_increment(
    cap: &Cap,
    options: &AnalysisOptions,
    green: Option<&crate::analysis::green::CapGreen>,
    top: usize,
) -> Result<Increment, DesignError> {
    let state = cap.state(top)?;
    let mat = state_material(cap, options, top, green);
    // `row_stride` > 1 thins the buckling mesh without filling in; the pass then keeps the full
    // print-layer mesh (`shares_mesh`).
    let grading = options.grading.as_ref().filter(|_| shares_mesh(options));
    let analysed = AnalysedState::new(&state, grading);
    let shell = match state_shell(analysed.state(), &mat, 1) {
        Ok(s) => s,
        // A single layer lies on the bed: every node is supported, nothing moves.
        Err(NoShell::SingleLayer) => return Ok(Increment::default()),
    };
    let keys = node_keys_of(&state, &analysed, &shell);
    let mut model = shell.model;
    let n_el = model.triangles.len();
    model.materials = (0..n_el)
        .map(|e| {
            let mut m = model.material_of(e);
            // Only the strip that ends in the new top layer is new weight.
            if shell
                .element_layers
                .get(e)
                .is_none_or(|l| l.1 != state.top_layer)
            {
                m.unit_weight = 0.0;
            }
            m
        })
        .collect();
    let inc = increment(&model, &keys).map_err(|e| DesignError::State {
        state: top,
        message: format!("as-printed increment failed: {e}"),
    })?;
    Ok(on_state(&state, &analysed, inc))
}

/// An increment solved on the shell of `analysed` as one on every node of `state`: itself on
/// the state's own mesh, filled in over the dropped nodes ([`fill_graded`]) on a graded one.
pub fn on_state(
    state: &crate::form::states::State,
    analysed: &AnalysedState<'_>,
    inc: Increment,
) -> Increment {
    match analysed {
        AnalysedState::Graded(..) => fill_graded(state, &inc),
        AnalysedState::Full(_) => inc,
    }
}

/// The key of every node of a state's shell (None: a node not tracked, e.g. a column end).
pub fn node_keys(state: &crate::form::states::State, shell: &StateShell) -> Vec<Option<NodeKey>> {
    node_keys_of(state, &AnalysedState::Full(state), shell)
}

/// [`node_keys`] of a shell meshed from `analysed` (the state itself or its graded reduction):
/// the keys name the nodes of `state`'s own network.
pub fn node_keys_of(
    state: &crate::form::states::State,
    analysed: &AnalysedState<'_>,
    shell: &StateShell,
) -> Vec<Option<NodeKey>> {
    let starts = state.network.layer_starts();
    shell
        .network_node
        .iter()
        .map(|&k| {
            let i = analysed.full_index(k)?;
            let layer = state.network.nodes.get(i)?.layer;
            Some((layer, i.checked_sub(starts.get(layer)?)?))
        })
        .collect()
}

/// An increment solved on a graded mesh (`crate::analysis::graded`) extended to every node of
/// `state`: a thinned row's dropped nodes take the linear interpolation, by their index along
/// the layer, between the kept nodes on either side; a dropped row takes the linear
/// interpolation, by print index, between the nearest kept rows below and above, each read at
/// the same fraction t = j/(m − 1) of its own length (node j of a row of m nodes). Row 0 and the
/// top row are always kept, and every kept row keeps both feet, so every dropped node lies
/// between kept ones. The increment's field is smooth with depth where the grading thins it
/// (the newest `fine` layers, where the new weight acts, are all rows), the premise of the
/// graded buckling mesh; docs/as-printed.md §6 measures what the filling costs in accuracy.
pub fn fill_graded(state: &crate::form::states::State, inc: &Increment) -> Increment {
    let known: HashMap<NodeKey, [f64; 3]> = inc.nodes.iter().map(|(k, _, d)| (*k, *d)).collect();
    let net = &state.network;
    let starts = net.layer_starts();
    // Every row bottom-up: its nodes' keys and design positions.
    let rows: Vec<Vec<(NodeKey, [f64; 3])>> = crate::analysis::shell::layer_rows(net)
        .into_iter()
        .map(|(layer, nodes)| {
            let f = starts.get(layer).unwrap_or(0);
            nodes
                .into_iter()
                .filter_map(|i| {
                    let x = net.nodes.get(i)?.xyz;
                    Some(((layer, i.saturating_sub(f)), [x.x, x.y, x.z]))
                })
                .collect()
        })
        .collect();
    // Along each row that kept any node: every node's value, the dropped ones interpolated.
    let along: Vec<Option<Vec<[f64; 3]>>> = rows
        .iter()
        .map(|row| {
            let vals: Vec<Option<[f64; 3]>> =
                row.iter().map(|(k, _)| known.get(k).copied()).collect();
            let kept: Vec<usize> = (0..vals.len()).filter(|&j| vals[j].is_some()).collect();
            (!kept.is_empty()).then(|| {
                (0..vals.len())
                    .map(|j| between(&kept, j, |a| vals[a].unwrap_or_default()))
                    .collect()
            })
        })
        .collect();
    let kept_rows: Vec<usize> = (0..rows.len()).filter(|&q| along[q].is_some()).collect();
    // The value of kept row `q` at the fraction `t` of its length.
    let at = |q: usize, t: f64| -> [f64; 3] {
        let Some(Some(v)) = along.get(q) else {
            return [0.0; 3];
        };
        if v.len() < 2 {
            return v.first().copied().unwrap_or_default();
        }
        let p = t * (v.len() - 1) as f64;
        let a = (p.floor() as usize).min(v.len() - 2);
        lerp(v[a], v[a + 1], p - a as f64)
    };
    let mut nodes = Vec::with_capacity(rows.iter().map(Vec::len).sum());
    for (q, row) in rows.iter().enumerate() {
        let m = row.len();
        for (j, (key, x)) in row.iter().enumerate() {
            let du = match &along[q] {
                Some(v) => v[j],
                None => {
                    let t = if m > 1 {
                        j as f64 / (m - 1) as f64
                    } else {
                        0.0
                    };
                    between(&kept_rows, q, |a| at(a, t))
                }
            };
            nodes.push((*key, *x, du));
        }
    }
    Increment {
        nodes,
        residual: inc.residual,
    }
}

/// The value at position `j` of a sequence known at the sorted positions `kept` (`value(a)` for
/// `a` in `kept`): itself where kept, else linear between the kept neighbours on either side (the
/// nearest one where only one side has any).
fn between(kept: &[usize], j: usize, value: impl Fn(usize) -> [f64; 3]) -> [f64; 3] {
    let b = kept.partition_point(|&k| k < j);
    match (b.checked_sub(1).map(|a| kept[a]), kept.get(b)) {
        (_, Some(&c)) if c == j => value(c),
        (Some(a), Some(&c)) => lerp(value(a), value(c), (j - a) as f64 / (c - a) as f64),
        (Some(a), None) => value(a),
        (None, Some(&c)) => value(c),
        (None, None) => [0.0; 3],
    }
}

/// (1 − w)·a + w·b.
fn lerp(a: [f64; 3], b: [f64; 3], w: f64) -> [f64; 3] {
    [0, 1, 2].map(|c| (1.0 - w) * a[c] + w * b[c])
}

/// The as-printed shape of `cap` over every print state (increments in parallel, summed in
/// print order); `cancelled` is polled between states.
///
/// # Errors
/// A state that cannot be built or solved, or a cancellation.
pub fn cap_as_printed(
    cap: &Cap,
    options: &AnalysisOptions,
    green: Option<&crate::analysis::green::CapGreen>,
    cancelled: &(dyn Fn() -> Result<(), DesignError> + Sync),
) -> Result<AsPrinted, DesignError> {
    cap_as_printed_given(cap, options, green, HashMap::new(), cancelled)
}

/// [`cap_as_printed`] with the increments of some states already solved (`known`, by state
/// index: the buckling pass solves a state's increment inside its own factorization of K,
/// `crate::analysis::check`); only the others are solved here ([`cap_increment`]). A known
/// increment must be [`cap_increment`]'s of the same state, options and `green`.
///
/// # Errors
/// As [`cap_as_printed`].
pub fn cap_as_printed_given(
    cap: &Cap,
    options: &AnalysisOptions,
    green: Option<&crate::analysis::green::CapGreen>,
    mut known: HashMap<usize, Increment>,
    cancelled: &(dyn Fn() -> Result<(), DesignError> + Sync),
) -> Result<AsPrinted, DesignError> {
    let todo: Vec<usize> = (0..cap.states.len())
        .filter(|top| !known.contains_key(top))
        .collect();
    let solved = todo
        .into_par_iter()
        .map(|top| {
            cancelled()?;
            cap_increment(cap, options, green, top).map(|i| (top, i))
        })
        .collect::<Result<Vec<_>, DesignError>>()?;
    known.extend(solved);
    let increments: Vec<Increment> = (0..cap.states.len())
        .map(|top| known.remove(&top).unwrap_or_default())
        .collect();
    Ok(accumulate(&increments))
}

/// Whether the buckling pass's mesh of a state is the as-printed pass's own mesh (every layer a
/// row, or graded: [`cap_increment`] solves on the graded rows and fills in the rest), so its
/// factor of K can solve the state's increment. Not with `row_stride` > 1, a thinning of the
/// buckling mesh alone.
pub fn shares_mesh(options: &AnalysisOptions) -> bool {
    options.row_stride <= 1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Linear interpolation reproduces a field linear in the row (print index) and in the
    /// fraction along the layer exactly: so the filling of a graded increment adds no error of
    /// its own where the field is linear, and every dropped node is reached (row 0 and the top
    /// row kept, both feet of every kept row kept). Tolerance 1e-12: round-off of the weights.
    #[test]
    fn filling_a_graded_increment_reproduces_a_linear_field() {
        let design = crate::Design::from_toml_str("[cap]\nlength = 0.2\n").expect("design");
        let cap = crate::design_cap(&design, crate::Context::default()).expect("cap");
        let top = cap.states.len() - 1;
        let state = cap.state(top).expect("state");
        // A grading that drops rows and thins them on this short cap.
        let g = crate::input::analysis::Grading {
            fine: 2,
            zone_rows: 1,
            max_stride: 8,
            transverse: 2,
            start_stride: 4,
            ..Default::default()
        };
        let rows = crate::analysis::shell::layer_rows(&state.network);
        let field = |q: usize, j: usize, m: usize| -> [f64; 3] {
            let t = if m > 1 {
                j as f64 / (m - 1) as f64
            } else {
                0.0
            };
            [q as f64, t, 2.0 * q as f64 - 3.0 * t + 1.0]
        };
        // Keys of the reduced network's nodes, each with the field at its full node.
        let (_, map) = crate::analysis::graded::graded_state_map(&state, &g);
        let starts = state.network.layer_starts();
        let first = |layer: i32| starts.get(layer).expect("layer");
        let mut at: HashMap<usize, (usize, usize, usize)> = HashMap::new();
        for (q, (_, nodes)) in rows.iter().enumerate() {
            for (j, &i) in nodes.iter().enumerate() {
                at.insert(i, (q, j, nodes.len()));
            }
        }
        let kept: Vec<(NodeKey, [f64; 3], [f64; 3])> = map
            .iter()
            .map(|&i| {
                let n = &state.network.nodes[i];
                let (q, j, m) = at[&i];
                ((n.layer, i - first(n.layer)), [0.0; 3], field(q, j, m))
            })
            .collect();
        let total: usize = rows.iter().map(|r| r.1.len()).sum();
        assert!(kept.len() < total, "the grading drops nothing: {total}");
        let filled = fill_graded(
            &state,
            &Increment {
                nodes: kept,
                residual: 0.0,
            },
        );
        assert_eq!(filled.nodes.len(), total);
        for (q, (layer, nodes)) in rows.iter().enumerate() {
            for (j, &i) in nodes.iter().enumerate() {
                let key = (*layer, i - first(*layer));
                let got = filled
                    .nodes
                    .iter()
                    .find(|n| n.0 == key)
                    .map(|n| n.2)
                    .expect("every node filled");
                let want = field(q, j, nodes.len());
                for c in 0..3 {
                    assert!(
                        (got[c] - want[c]).abs() < 1e-12,
                        "{key:?}: {got:?} vs {want:?}"
                    );
                }
            }
        }
    }
}
