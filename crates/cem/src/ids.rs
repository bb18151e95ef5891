//! The node id, on the floor below both the topology and the errors that name nodes.

/// A node id: any non-negative integer, unique within a topology.
pub type NodeId = u64;
