//! Floor 1, **the form**: the layer arch form-found with constrained CEM ([`arch`]) in its
//! tilted frame ([`frame`]), the centre and start sections ([`section`]) and the ends
//! ([`ends`]), the network of every print state ([`states`]), its forces ([`forces`]) and element stresses
//! ([`stresses`]), the
//! layers' overhang ([`overhang`]), the print path ([`path`]) and the printed beads
//! ([`beads`]); [`cap`] ties them into a [`Cap`]. Imports only [`crate::input`].

pub(crate) mod arch;
pub(crate) mod beads;
pub(crate) mod cap;
pub(crate) mod ends;
pub(crate) mod forces;
pub(crate) mod frame;
pub(crate) mod overhang;
pub(crate) mod path;
pub(crate) mod section;
pub(crate) mod states;
pub(crate) mod stresses;

pub use cap::{Cap, StateSummary, design_cap};

// The items users outside the crate need (the CLI, Python, the designer, the tests).
pub use arch::{Arch, ArchSpec, Catenary, form_find_layer};
pub use ends::{EndKind, stack_thrust, wall_load};
pub use forces::{Sections2D, state_forces, state_pass};
pub use frame::{LayerFrame, V3};
pub use overhang::{layer_overhangs, measured_overhangs};
pub use section::{NodeKind, Sections, build_sections_with_end};
pub use states::{Role, State, build_state};
pub use stresses::{ElementKind, ElementStress, STRESS_REL_TOL, StressExtremes, element_stresses};
