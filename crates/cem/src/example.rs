//! A built-in example topology, embedded in the binary so that `kappe cem solve --example`
//! runs on a fresh machine without any file.

use crate::error::CemError;
use crate::json::{TopologyFile, read_topology};

/// `kappe.cem.topology` text of a 16-node compression arch in the XZ plane: two 7-edge
/// trails (λ = −0.5) from a crown deviation edge (μ = −3), unit loads along −Z on every
/// node except the two supports.
pub const EXAMPLE_ARCH_JSON: &str = include_str!("example_arch.json");

/// The parsed example arch.
pub fn example_arch() -> Result<TopologyFile, CemError> {
    read_topology(EXAMPLE_ARCH_JSON)
}
