//! Floor 1, **the form**: the layer arch form-found with constrained CEM ([`arch`]) in its
//! tilted frame ([`frame`]), the centre and start sections ([`section`]) and the ends
//! ([`ends`]), the network of every print state ([`states`]) and its forces ([`forces`]), the
//! layers' overhang ([`overhang`]), the print path ([`path`]) and the printed beads
//! ([`beads`]); [`cap`] ties them into a [`Cap`]. Imports only [`crate::input`].

pub mod arch;
pub mod beads;
pub mod cap;
pub mod ends;
pub mod forces;
pub mod frame;
pub mod overhang;
pub mod path;
pub mod section;
pub mod states;

pub use cap::{Cap, StateSummary, design_cap};
