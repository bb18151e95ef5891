//! The bending part of a corrugated print state (issue 26, docs/corrugation.md "State
//! equilibrium").
//!
//! A corrugated cap's printed geometry is fixed, and it is not funicular for the loads of every
//! print state: a column that changes slope from one bed joint to the next needs a transverse
//! force that depends on how many layers stand above it. The state's loads are therefore split
//! ([`crate::form::forces::split_state_forces`]): the network carries `q_n − s_n` axially, in
//! exact equilibrium (its residual is round-off), and the shell of the state
//! ([`crate::analysis::shell`], the same mesh, supports and element as the buckling analysis)
//! carries the unbalanced forces `s_n` as nodal loads by bending and membrane action, solved by
//! linear statics. The two are equilibrium states of the same structure under loads that sum to
//! the state's own, so their stresses superpose: every network element's normal stress along its
//! direction is `N/A` plus the shell's surface stress along that direction, on either face.
//!
//! Hand-written: it is Kappe's own split of its own network; the solver is `kappe_fe`'s.

use std::collections::HashMap;

use serde::Serialize;

use crate::analysis::shell::{ShellMaterial, StateShell, state_shell};
use crate::form::forces::{Sections2D, split_state_forces};
use crate::form::frame::V3;
use crate::form::states::State;
use crate::form::stresses::{ElementStress, element_stresses};
use crate::input::error::DesignError;

/// What the shell carries of one state, and how well.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BendingSummary {
    /// Largest node force handed from the network to the shell, |s_n|, N.
    pub out_of_funicular_n: f64,
    /// Sum of the handed-over forces, |Σ s_n|, N.
    pub load_sum_n: f64,
    /// The shell statics' global equilibrium, |Σ s_n + Σ reactions|, N.
    pub equilibrium_residual_n: f64,
    /// Largest |σ| the bending part adds to any network element, Pa.
    pub max_stress_pa: f64,
}

/// The element stresses of a corrugated state with its bending part: every element of
/// [`element_stresses`] twice, once with the shell's stress along it on each face (the lower and
/// the higher of the two, so the extremes see both), and the summary of the shell's part.
/// Without unbalanced forces (or without a shell, a single layer on the bed) the network's own
/// stresses and `None`. The analysis solves the shell's part inside each state's buckling solve
/// instead ([`crate::analysis::buckling`]'s `bending` request: the same loads on the same factor
/// of K, so the same numbers, for one triangular solve instead of a factorization).
///
/// # Errors
/// A state whose network or shell cannot be solved.
pub fn corrugated_stresses(
    state: &State,
    areas: Sections2D,
    material: &ShellMaterial,
) -> Result<(Vec<ElementStress>, Option<BendingSummary>), DesignError> {
    let unbalanced = Unbalanced::of(state, areas)?;
    if !unbalanced.any() {
        return Ok(unbalanced.network_only());
    }
    let Ok(shell) = state_shell(state, material, 1) else {
        return Ok(unbalanced.network_only());
    };
    let case = unbalanced.load_case(&shell);
    let mut model = shell.model.clone();
    model.gravity = [0.0; 3];
    model.nodal_loads.clone_from(&case.nodal_loads);
    let st = kappe_fe::linear_static(&model).map_err(|e| unbalanced.failed(state, e))?;
    Ok(unbalanced.stresses(state, &shell, &case, &st))
}

/// A corrugated state's network stresses and the unbalanced forces its shell carries
/// ([`split_state_forces`]).
pub(crate) struct Unbalanced {
    network: Vec<ElementStress>,
    forces: Vec<V3>,
    max: f64,
}

impl Unbalanced {
    /// The split of `state`'s loads.
    pub(crate) fn of(state: &State, areas: Sections2D) -> Result<Self, DesignError> {
        let network = element_stresses(state, areas)?;
        let (_, _, _, forces) = split_state_forces(state, areas)?;
        let max = forces.iter().fold(0.0_f64, |m, s| m.max(s.norm()));
        Ok(Self {
            network,
            forces,
            max,
        })
    }

    /// Whether the shell carries anything.
    pub(crate) fn any(&self) -> bool {
        self.max != 0.0
    }

    /// The network's own stresses, no bending part.
    pub(crate) fn network_only(self) -> (Vec<ElementStress>, Option<BendingSummary>) {
        (self.network, None)
    }

    /// The error of a failed shell solve.
    pub(crate) fn failed(&self, state: &State, e: kappe_fe::FeError) -> DesignError {
        DesignError::State {
            state: state.index,
            message: format!("the shell statics of the corrugation's bending part failed: {e}"),
        }
    }

    /// The unbalanced forces as nodal loads on `shell` (the state's own shell, row stride 1),
    /// without self-weight.
    pub(crate) fn load_case(&self, shell: &StateShell) -> kappe_fe::LoadCase {
        kappe_fe::LoadCase {
            weight: Vec::new(),
            nodal_loads: shell
                .network_node
                .iter()
                .enumerate()
                .filter_map(|(k, &ni)| {
                    let s = self.forces.get(ni)?;
                    (s.norm() > 0.0).then_some(kappe_fe::NodalLoad {
                        node: k,
                        force: [s.x, s.y, s.z],
                        moment: [0.0; 3],
                    })
                })
                .collect(),
        }
    }

    /// The element stresses with the shell's part `st` (the static solution of `case`, this
    /// split's [`Unbalanced::load_case`] on `shell`) and its summary.
    pub(crate) fn stresses(
        self,
        state: &State,
        shell: &StateShell,
        case: &kappe_fe::LoadCase,
        st: &kappe_fe::StaticResult,
    ) -> (Vec<ElementStress>, Option<BendingSummary>) {
        let handed: V3 = case
            .nodal_loads
            .iter()
            .fold(V3::zeros(), |a, l| a + V3::from(l.force));
        let equilibrium_residual_n = (V3::from(st.load_sum) + V3::from(st.reactions_sum)).norm();
        let model = &shell.model;
        // Facets around every network node.
        let mut shell_of: HashMap<usize, usize> = HashMap::new();
        for (k, &ni) in shell.network_node.iter().enumerate() {
            shell_of.insert(ni, k);
        }
        let mut facets_of: Vec<Vec<usize>> = vec![Vec::new(); model.nodes.len()];
        for (e, t) in model.triangles.iter().enumerate() {
            for &n in t {
                facets_of[n].push(e);
            }
        }
        let pos = state.network.positions();
        let mut out = Vec::with_capacity(2 * self.network.len());
        let mut max_stress_pa: f64 = 0.0;
        for s in self.network {
            let [u, v] = s.nodes;
            let d = pos[v] - pos[u];
            let (su, sv) = (shell_of.get(&u).copied(), shell_of.get(&v).copied());
            let around = |n: Option<usize>| n.map_or(&[][..], |n| &facets_of[n][..]);
            // The facets the element runs in (both ends), else those at either end.
            let mut facets: Vec<usize> = around(su)
                .iter()
                .copied()
                .filter(|e| around(sv).contains(e))
                .collect();
            if facets.is_empty() {
                facets = around(su).iter().chain(around(sv)).copied().collect();
            }
            let (mut lo, mut hi) = (0.0_f64, 0.0_f64);
            for e in facets {
                let Some(r) = st.elements.get(e) else {
                    continue;
                };
                let [e1, e2, _] = r.frame.map(V3::from);
                let (a, b) = (d.dot(&e1), d.dot(&e2));
                let l2 = a * a + b * b;
                if l2 <= 0.0 {
                    continue;
                }
                for top in [true, false] {
                    let [sx, sy, sxy] = r.surface_stress(top);
                    let sd = (sx * a * a + sy * b * b + 2.0 * sxy * a * b) / l2;
                    lo = lo.min(sd);
                    hi = hi.max(sd);
                }
            }
            max_stress_pa = max_stress_pa.max(lo.abs()).max(hi.abs());
            out.push(ElementStress {
                stress: s.stress + lo,
                ..s
            });
            out.push(ElementStress {
                stress: s.stress + hi,
                ..s
            });
        }
        (
            out,
            Some(BendingSummary {
                out_of_funicular_n: self.max,
                load_sum_n: handed.norm(),
                equilibrium_residual_n,
                max_stress_pa,
            }),
        )
    }
}
