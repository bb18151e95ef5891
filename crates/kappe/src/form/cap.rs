//! The whole cap pipeline as one plain function: design → arch → sections → states → forces →
//! path → mesh. States are independent and solved in parallel (rayon); their order is kept.

use rayon::prelude::*;

use crate::form::arch::{Arch, ArchSpec, Catenary, form_find_layer, form_find_layer_with_segments};
use crate::form::beads::{TriMesh, bead_mesh};
use crate::form::forces::{Sections2D, StateForces, split_state_forces, state_pass};
use crate::form::frame::LayerFrame;
use crate::form::overhang::{layer_overhangs, measured_overhangs};
use crate::form::path::{PrintPath, print_path};
use crate::form::section::{Sections, build_corrugated_sections, build_sections_with_end};
use crate::form::states::{State, build_state};
use crate::form::stresses::{StressExtremes, element_stresses_of};
use crate::input::context::Context;
use crate::input::design::Design;
use crate::input::error::DesignError;

/// Summary of one print state.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StateSummary {
    /// State index (0 = first layer printed).
    pub index: usize,
    /// Print progress Pp in (0, 1].
    pub progress: f64,
    /// Layers printed so far.
    pub layers_printed: usize,
    /// Id of the top layer.
    pub top_layer: i32,
    /// Nodes in the state network.
    pub nodes: usize,
    /// Layer factor d of every printed layer, in print order (1 for centre layers).
    #[serde(skip)]
    pub factors: Vec<f64>,
    /// Forces, stresses, residual and reactions.
    #[serde(flatten)]
    pub forces: StateForces,
    /// The extremes of the element stresses of the network (σ = N/A) of a prismatic cap, from the
    /// same force pass; `None` for a corrugated cap, whose stresses include the shell's bending
    /// (`crate::analysis::bending`).
    #[serde(skip)]
    pub stresses: Option<StressExtremes>,
}

/// A designed cap: every intermediate product of the pipeline.
#[derive(Debug, Clone)]
pub struct Cap {
    /// The validated design.
    pub design: Design,
    /// The layer frame.
    pub frame: LayerFrame,
    /// Layer 0.
    pub arch: Arch,
    /// The arch of every centre layer of a corrugated cap (`[cap.corrugation]`), layer 0 first;
    /// empty for the prismatic cap, whose centre layers are all translates of [`Cap::arch`].
    pub centre_arches: Vec<Arch>,
    /// The catenary limit of layer 0 (closed form).
    pub catenary: Catenary,
    /// All layers in print order.
    pub sections: Sections,
    /// Overhang of every layer over the previous one, in print order, m.
    pub overhangs: Vec<f64>,
    /// One summary per state, in print order.
    pub states: Vec<StateSummary>,
    /// The final state (100 %) with its network.
    pub final_state: State,
    /// Its CEM topology.
    pub final_topology: kappe_cem::Topology,
    /// Its CEM force-pass result.
    pub final_forces: kappe_cem::fixed_geometry::ForcePass,
    /// The print path.
    pub path: PrintPath,
    /// The printed beads.
    pub mesh: TriMesh,
}

impl Cap {
    /// The print state whose top layer has print index `top`, built as form-finding built it
    /// (the cap's sections, frame and `print.start_arch_fraction`).
    ///
    /// # Errors
    /// `top` is not a printed layer.
    pub fn state(&self, top: usize) -> Result<State, DesignError> {
        build_state(
            &self.sections,
            &self.frame,
            self.design.print.start_arch_fraction,
            top,
        )
    }

    /// Cross-section areas for stresses.
    pub fn areas(&self) -> Sections2D {
        areas(&self.design, &self.arch, &self.centre_arches)
    }
}

/// The bed-joint area takes the shortest segment of any layer (a corrugated cap's layers have
/// their own segment lengths; the shortest gives the largest bed-joint stress).
fn areas(design: &Design, arch: &Arch, centre: &[Arch]) -> Sections2D {
    let lw = design.print.layer_width;
    let s = centre
        .iter()
        .map(|a| a.segment_length)
        .fold(arch.segment_length, f64::min);
    Sections2D {
        along_layer: lw * design.print.layer_height,
        bed_joint: lw * s,
    }
}

/// Form-find every centre layer of a corrugated cap in its own plane to its own rise
/// (`CorrugationSpec::layer_rise`), with layer 0's segment count so the columns run through.
/// Layer 0 is `arch` itself. An arch that cannot be found, or that is not in compression
/// everywhere, is an error naming the layer and its rise.
fn corrugated_arches(
    design: &Design,
    spec: &ArchSpec,
    arch: &Arch,
    n_centre: usize,
) -> Result<Vec<Arch>, DesignError> {
    let Some(w) = design.corrugation() else {
        return Ok(Vec::new());
    };
    let step = design.print.layer_height / spec.tilt.cos();
    let segments = arch.segments();
    (0..n_centre)
        .into_par_iter()
        .map(|k| {
            if k == 0 {
                return Ok(arch.clone());
            }
            let rise = w.layer_rise(spec.rise, step, k);
            let layer_spec = ArchSpec { rise, ..*spec };
            let a = form_find_layer_with_segments(&layer_spec, segments).map_err(|e| {
                DesignError::FormFinding(format!(
                    "corrugated centre layer {k} (rise {:.1} mm from amplitude {} m, wavelength \
                     {} m): {e}",
                    rise * 1e3,
                    w.amplitude,
                    w.wavelength
                ))
            })?;
            if let Some((i, f)) = a
                .segment_forces
                .iter()
                .enumerate()
                .find(|(_, f)| f.is_nan() || **f >= 0.0)
            {
                return Err(DesignError::FormFinding(format!(
                    "corrugated centre layer {k} (rise {:.1} mm): segment {i} carries {f:.3e} N, \
                     not compression; lower cap.corrugation.amplitude",
                    rise * 1e3
                )));
            }
            Ok(a)
        })
        .collect()
}

/// Form-find the layer, build the sections and states, and solve the forces of every state.
/// `context` hears once per solved state (for a progress bar), with the state count, and is
/// checked for a stop before every state.
///
/// # Errors
/// An invalid design, a layer without an equilibrium form, a state that cannot be solved, or
/// [`DesignError::Cancelled`].
pub fn design_cap(design: &Design, context: Context<'_>) -> Result<Cap, DesignError> {
    design.validate()?;
    let tilt = design.tilt();
    let frame = LayerFrame::new(tilt);
    let spec = ArchSpec {
        span: design.cap.span,
        rise: design.cap.rise,
        tilt,
        specific_weight: design.material.specific_weight,
        layer_width: design.print.layer_width,
        layer_height: design.print.layer_height,
        path_sampling: design.print.path_sampling,
    };
    let arch = form_find_layer(&spec)?;
    let catenary = Catenary::new(spec.span, spec.rise, tilt, spec.specific_weight);
    let bead_weight_per_m =
        design.material.specific_weight * design.print.layer_width * design.print.layer_height;
    let (sections, centre_arches) = if design.corrugation().is_some() {
        let n_centre = crate::form::section::centre_layer_count(
            design.cap.length,
            &frame,
            design.print.layer_height,
        );
        let centre = corrugated_arches(design, &spec, &arch, n_centre)?;
        let sections = build_corrugated_sections(
            &arch,
            &centre,
            &frame,
            design.cap.length,
            design.print.layer_height,
            design.print.start_arch_fraction,
            |chord| 0.5 * chord * bead_weight_per_m,
            design.cap.end,
        )?;
        (sections, centre)
    } else {
        let sections = build_sections_with_end(
            &arch,
            &frame,
            design.cap.length,
            design.print.layer_height,
            design.print.start_arch_fraction,
            |chord| 0.5 * chord * bead_weight_per_m,
            design.cap.end,
        )?;
        (sections, Vec::new())
    };
    let overhangs = if centre_arches.is_empty() {
        layer_overhangs(&sections, &frame)
    } else {
        measured_overhangs(&sections, &frame)
    };
    let phi = design.print.start_arch_fraction;
    let area = areas(design, &arch, &centre_arches);
    let total = sections.layers.len();
    let corrugated = !centre_arches.is_empty();
    let solve = |top: usize| {
        context.check()?;
        let state = build_state(&sections, &frame, phi, top)?;
        // A corrugated state is not funicular for its loads: the network carries their
        // funicular part exactly, the shell the rest (`split_state_forces`). Only the final
        // state keeps a topology (`Cap::final_topology`): the others' passes run on the model
        // built from their trails (`state_pass`).
        let (topology, pass, forces) = if corrugated {
            let (t, p, f, _) = split_state_forces(&state, area)?;
            (Some(t), p, f)
        } else {
            let (p, f) = state_pass(&state, area)?;
            (None, p, f)
        };
        context.step(total);
        let stresses =
            (!corrugated).then(|| StressExtremes::of(element_stresses_of(&state, &pass, area)));
        let summary = StateSummary {
            index: state.index,
            progress: state.progress,
            layers_printed: state.layers_printed,
            top_layer: state.top_layer,
            nodes: state.network.nodes.len(),
            factors: state.factors.clone(),
            forces,
            stresses,
        };
        Ok::<_, DesignError>((state, topology, pass, summary))
    };
    // Every state but the last keeps only its summary; the final one keeps its network too.
    let mut summaries: Vec<StateSummary> = (0..total - 1)
        .into_par_iter()
        .map(|top| solve(top).map(|(_, _, _, summary)| summary))
        .collect::<Result<_, DesignError>>()?;
    let (final_state, final_topology, final_forces, final_summary) = solve(total - 1)?;
    let final_topology = final_topology.unwrap_or_else(|| {
        final_state
            .network
            .to_topology(&format!("state {}", final_state.index))
    });
    summaries.push(final_summary);
    let path = print_path(
        &sections,
        &frame,
        design.print.layer_height,
        design.print.layer_width,
        design.material.specific_weight,
        design.print.print_speed,
    );
    let mesh = bead_mesh(
        &sections,
        &frame,
        design.print.layer_width,
        design.print.layer_height,
    );
    Ok(Cap {
        design: design.clone(),
        frame,
        arch,
        centre_arches,
        catenary,
        sections,
        overhangs,
        states: summaries,
        final_state,
        final_topology,
        final_forces,
        path,
        mesh,
    })
}
