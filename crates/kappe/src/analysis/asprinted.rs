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
use crate::analysis::shell::{NoShell, StateShell, state_shell};
use crate::form::cap::Cap;
use crate::form::states::Role;
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

/// The increment of print state `top` of `cap` (the full print-layer mesh, every layer a row;
/// layer moduli at their ages in state `top` from `green`).
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
    let shell = match state_shell(&state, &mat, 1) {
        Ok(s) => s,
        // A single layer lies on the bed: every node is supported, nothing moves.
        Err(NoShell::SingleLayer) => return Ok(Increment::default()),
    };
    let keys = node_keys(&state, &shell);
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
    increment(&model, &keys).map_err(|e| DesignError::State {
        state: top,
        message: format!("as-printed increment failed: {e}"),
    })
}

/// The key of every node of a state's shell (None: a node not tracked, e.g. a column end).
pub fn node_keys(state: &crate::form::states::State, shell: &StateShell) -> Vec<Option<NodeKey>> {
    let mut first: HashMap<i32, usize> = HashMap::new();
    for (i, n) in state.network.nodes.iter().enumerate() {
        if n.role != Role::ColumnEnd {
            first.entry(n.layer).or_insert(i);
        }
    }
    shell
        .network_node
        .iter()
        .map(|&i| {
            let layer = state.network.nodes.get(i)?.layer;
            Some((layer, i.checked_sub(*first.get(&layer)?)?))
        })
        .collect()
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

/// Whether the buckling pass's print-layer mesh of a state is the as-printed pass's own mesh
/// (every layer a row, no grading), so its factor of K can solve the state's increment.
pub fn shares_mesh(options: &AnalysisOptions) -> bool {
    options.row_stride <= 1 && options.grading.is_none()
}
