//! What `kappe cem solve` and `kappe cem optimize` read, print and write, as library functions
//! so that the command line and the Python package (`kappe.cem`) share one implementation:
//! reading a topology file, the equilibrium document, the one-screen summary of a solve, and
//! the optimization report with its JSON block.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::json::{TopologyFile, equilibrium_to_json, read_topology};
use crate::{CemError, Equilibrium, OptimizeOptions, OptimizeResult, Problem, SolverOptions};

/// A topology file that could not be read or is not a valid topology.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is not a valid `kappe.cem.topology` document.
    #[error("invalid topology in {}", path.display())]
    Invalid {
        path: PathBuf,
        #[source]
        source: CemError,
    },
}

/// Reads and checks a `kappe.cem.topology` v1 JSON file.
pub fn read_topology_file(path: &Path) -> Result<TopologyFile, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|source| LoadError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    read_topology(&text).map_err(|source| LoadError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}

/// The problem of a topology's `optimization` block; `None` if it has none.
pub fn optimization_problem(
    file: &TopologyFile,
) -> Result<Option<(Problem, OptimizeOptions)>, CemError> {
    file.optimization
        .as_ref()
        .map(Problem::from_json)
        .transpose()
}

/// Pretty JSON with a final newline, as the command writes its documents.
fn pretty(doc: &Value) -> Result<String, serde_json::Error> {
    let mut text = serde_json::to_string_pretty(doc)?;
    text.push('\n');
    Ok(text)
}

/// The equilibrium document of `kappe cem solve` (a `kappe.cem.expected`-shaped result).
pub fn solve_document(
    eq: &Equilibrium,
    solver: &SolverOptions,
    force_polygons: bool,
) -> Result<String, serde_json::Error> {
    pretty(&equilibrium_to_json(eq, solver, force_polygons))
}

/// The short human-readable summary of a solve (`kappe cem solve --summary`); `source` names
/// the input.
pub fn summary(eq: &Equilibrium, solver: &SolverOptions, source: &str) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let indirect = eq.deviation_edges.iter().filter(|e| !e.direct).count();
    let _ = writeln!(s, "CEM equilibrium of {source} ({})", eq.name);
    let _ = writeln!(
        s,
        "  nodes {}  trails {}  trail edges {}  deviation edges {} ({indirect} indirect)  auxiliary trails {}",
        eq.nodes.len(),
        eq.trails.len(),
        eq.trail_edges.len(),
        eq.deviation_edges.len(),
        eq.auxiliary_trails.len()
    );
    let _ = writeln!(
        s,
        "  sweeps {} (tmax {}, eta {:e}, residual distance {:.3e})",
        eq.iterations.sweeps, solver.tmax, solver.eta, eq.iterations.residual_distance
    );
    let (fmin, fmax) = eq
        .trail_edges
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), e| {
            (a.min(e.force), b.max(e.force))
        });
    if fmin.is_finite() {
        let _ = writeln!(s, "  trail forces  min {fmin:.6}  max {fmax:.6}");
    }
    let _ = writeln!(
        s,
        "  max node residual {:.3e}  |Σq + ΣR| {:.3e}",
        eq.checks.max_node_residual,
        (eq.checks.sum_loads + eq.checks.sum_reactions).norm()
    );
    let _ = writeln!(
        s,
        "  {:>8}  {:>14} {:>14} {:>14}",
        "support", "Rx", "Ry", "Rz"
    );
    for n in eq.nodes.iter().filter(|n| n.support) {
        let r = n.reaction;
        let _ = writeln!(
            s,
            "  {:>8}  {:>14.6} {:>14.6} {:>14.6}",
            n.id, r.x, r.y, r.z
        );
    }
    s
}

/// The report of an optimization (`kappe cem optimize` prints it on stderr): status,
/// iterations, objective, the parameters and every goal's error.
pub fn optimization_report(r: &OptimizeResult) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "status {} ({}), {} iterations, {} evaluations, objective {:.3e} -> {:.3e}",
        r.status.name(),
        if r.converged {
            "converged"
        } else {
            "NOT converged"
        },
        r.iterations,
        r.evaluations,
        r.objective_at_x0,
        r.objective_at_x_opt
    );
    let _ = writeln!(s, "  x0    {:?}", r.x0);
    let _ = writeln!(s, "  x_opt {:?}", r.x_opt);
    let _ = writeln!(
        s,
        "  {:<32} {:>8} {:>14} {:>14}",
        "goal", "weight", "error", "w*e^2"
    );
    for g in &r.goals {
        let _ = writeln!(
            s,
            "  {:<32} {:>8.3} {:>14.3e} {:>14.3e}",
            g.goal, g.weight, g.error, g.weighted_squared_error
        );
    }
    s
}

/// The `optimization` block of the optimize document.
pub fn optimization_json(r: &OptimizeResult) -> Value {
    json!({
        "x0": r.x0,
        "bounds_low": r.bounds_low,
        "bounds_up": r.bounds_up,
        "objective_at_x0": r.objective_at_x0,
        "gradient_at_x0": r.gradient_at_x0,
        "x_opt": r.x_opt,
        "objective_at_x_opt": r.objective_at_x_opt,
        "gradient_at_x_opt": r.gradient_at_x_opt,
        "status": r.status.name(),
        "converged": r.converged,
        "iterations": r.iterations,
        "evaluations": r.evaluations,
        "goals": r.goals.iter().map(|g| json!({
            "goal": g.goal,
            "weight": g.weight,
            "error": g.error,
            "weighted_squared_error": g.weighted_squared_error,
        })).collect::<Vec<_>>(),
    })
}

/// The document of `kappe cem optimize`: the final equilibrium plus the `optimization` block.
pub fn optimize_value(r: &OptimizeResult, solver: &SolverOptions) -> Value {
    let mut doc = equilibrium_to_json(&r.equilibrium, solver, false);
    if let Value::Object(m) = &mut doc {
        m.insert("optimization".into(), optimization_json(r));
    }
    doc
}

/// [`optimize_value`] as the text the command writes.
pub fn optimize_document(
    r: &OptimizeResult,
    solver: &SolverOptions,
) -> Result<String, serde_json::Error> {
    pretty(&optimize_value(r, solver))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_has_a_row_per_support() {
        let file = crate::example::example_arch().expect("the built-in example");
        let eq = crate::solve(&file.topology, &file.solver).expect("it solves");
        let s = summary(&eq, &file.solver, "built-in example");
        let supports = eq.nodes.iter().filter(|n| n.support).count();
        assert!(supports >= 1);
        // Title, counts, sweeps, trail forces, residuals, the table header, one row per support.
        assert_eq!(s.lines().count(), 6 + supports, "{s}");
        assert!(s.starts_with(&format!(
            "CEM equilibrium of built-in example ({})",
            eq.name
        )));
        // The document: pretty JSON of the `kappe.cem.expected` shape with a final newline.
        let doc = solve_document(&eq, &file.solver, false).expect("serializes");
        assert!(doc.starts_with("{\n") && doc.ends_with("}\n"));
        assert!(doc.contains("\"format\": \"kappe.cem.expected\""));
    }

    #[test]
    fn a_missing_file_and_a_missing_optimization_block_are_told_apart() {
        let e = read_topology_file(Path::new("/nonexistent/kappe-topology.json"))
            .expect_err("missing file");
        assert_eq!(
            e.to_string(),
            "cannot read /nonexistent/kappe-topology.json"
        );
        let file = crate::example::example_arch().expect("the built-in example");
        assert!(matches!(optimization_problem(&file), Ok(None)));
    }
}
