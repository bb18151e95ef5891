//! Typed errors of the shell solver. Every variant names the node, element or field at fault,
//! the offending value and what is allowed, so a caller can point the user at the input.

use thiserror::Error;

/// Names of the six nodal degrees of freedom, in storage order.
pub const DOF_NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];

/// One degree of freedom of one node (used to report mechanisms).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeDof {
    /// Node index (0-based).
    pub node: usize,
    /// DOF index 0..6 (ux, uy, uz, rx, ry, rz).
    pub dof: usize,
}

impl std::fmt::Display for NodeDof {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = DOF_NAMES.get(self.dof).copied().unwrap_or("?");
        write!(f, "node {} {}", self.node, name)
    }
}

fn list_dofs(dofs: &[NodeDof]) -> String {
    const SHOWN: usize = 12;
    let mut s: Vec<String> = dofs.iter().take(SHOWN).map(ToString::to_string).collect();
    if dofs.len() > SHOWN {
        s.push(format!("… ({} more)", dofs.len() - SHOWN));
    }
    s.join(", ")
}

/// Everything that can go wrong when building, validating or solving a shell model.
#[derive(Debug, Error)]
pub enum FeError {
    /// The model has no nodes or no triangles.
    #[error("the model is empty: {what} (at least one triangle with three nodes is needed)")]
    Empty {
        /// What is missing.
        what: &'static str,
    },
    /// A coordinate, load or property is NaN or infinite.
    #[error("{field} is not a finite number ({value}); all inputs must be finite")]
    NotFinite {
        /// Field path, e.g. `nodes[3].z`.
        field: String,
        /// The value.
        value: f64,
    },
    /// A triangle refers to a node that does not exist.
    #[error("triangle {element} refers to node {node}, but there are only {n_nodes} nodes")]
    NodeOutOfRange {
        /// Element index.
        element: usize,
        /// Node index given.
        node: usize,
        /// Number of nodes.
        n_nodes: usize,
    },
    /// A support, load or other per-node item refers to a node that does not exist.
    #[error("{field} refers to node {node}, but there are only {n_nodes} nodes")]
    ItemNodeOutOfRange {
        /// Field path.
        field: String,
        /// Node index given.
        node: usize,
        /// Number of nodes.
        n_nodes: usize,
    },
    /// A triangle has zero area, repeated nodes, or a too small height relative to its edges.
    #[error(
        "triangle {element} (nodes {nodes:?}) is degenerate: area {area:e} m², aspect ratio {aspect:.3e} \
         (allowed: distinct nodes, positive area, longest edge / smallest height ≤ {max_aspect:e})"
    )]
    DegenerateTriangle {
        /// Element index.
        element: usize,
        /// Its nodes.
        nodes: [usize; 3],
        /// Its area.
        area: f64,
        /// Longest edge over smallest height.
        aspect: f64,
        /// The limit.
        max_aspect: f64,
    },
    /// A triangle's normal points against its neighbour's across a shared edge traversed the
    /// same way (a flipped, i.e. inverted, triangle in an otherwise consistently oriented mesh).
    #[error(
        "triangle {element} is inverted relative to triangle {neighbour}: both traverse edge \
         {a}→{b} in the same direction (orient all triangles consistently, or set allow_mixed_orientation / --allow-mixed-orientation: results are orientation-independent)"
    )]
    InvertedTriangle {
        /// Element index.
        element: usize,
        /// The neighbour it disagrees with.
        neighbour: usize,
        /// Shared edge start.
        a: usize,
        /// Shared edge end.
        b: usize,
    },
    /// A node is not used by any triangle.
    #[error("node {node} is not used by any triangle (remove it or connect it)")]
    UnreferencedNode {
        /// Node index.
        node: usize,
    },
    /// A per-element array has the wrong length.
    #[error("{field} has {len} entries; allowed: 1 (uniform) or {n_elements} (one per triangle)")]
    WrongLength {
        /// Field name.
        field: &'static str,
        /// Its length.
        len: usize,
        /// Number of triangles.
        n_elements: usize,
    },
    /// A property is outside its physical range.
    #[error("{field} = {value} is not allowed; allowed: {allowed}")]
    OutOfRange {
        /// Field path, e.g. `thickness[12]`.
        field: String,
        /// The value.
        value: f64,
        /// The allowed range.
        allowed: &'static str,
    },
    /// The stiffness matrix is singular: the supports do not prevent all rigid-body or
    /// zero-energy motions.
    #[error("structure is a mechanism: free DOFs without stiffness: {}", list_dofs(.free_dofs))]
    Mechanism {
        /// DOFs that take part in the zero-energy motion (largest amplitude first).
        free_dofs: Vec<NodeDof>,
    },
    /// Every DOF is fixed: nothing to solve.
    #[error("every degree of freedom is fixed by supports; nothing to solve")]
    NoFreeDofs,
    /// The cached solver was built for another mesh/support pattern.
    #[error("the solver's cached pattern does not match this model ({reason}); build a new solver")]
    PatternMismatch {
        /// What differs.
        reason: &'static str,
    },
    /// The Sturm count shows eigenvalues below the returned ones that the iteration missed
    /// even after deflated restarts.
    #[error(
        "Sturm check failed: K + {sigma:e}·K_G has {negative} negative pivots, but only {found} \
         buckling factors ≤ {sigma:e} were found"
    )]
    SturmMismatch {
        /// The shift.
        sigma: f64,
        /// Negative pivots counted.
        negative: usize,
        /// Factors found below the shift.
        found: usize,
    },
    /// The eigen solver did not converge.
    #[error(
        "the buckling eigen solver did not converge after {iterations} Lanczos steps ({detail})"
    )]
    NoConvergence {
        /// Steps taken.
        iterations: usize,
        /// What was missing.
        detail: String,
    },
    /// An invalid option.
    #[error("option {field} = {value} is not allowed; allowed: {allowed}")]
    BadOption {
        /// Option name.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Allowed range.
        allowed: &'static str,
    },
    /// A numerical library error (out of memory, factorization failure other than a mechanism).
    #[error("numerical failure in {stage}: {detail}")]
    Numerical {
        /// Which step.
        stage: &'static str,
        /// Library message.
        detail: String,
    },
    /// The mesh JSON could not be parsed.
    #[error("invalid mesh JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// The mesh JSON is valid JSON but not a valid mesh description.
    #[error("invalid mesh JSON: {field}: {detail}")]
    MeshFormat {
        /// Field path.
        field: String,
        /// What is wrong and what is allowed.
        detail: String,
    },
}
