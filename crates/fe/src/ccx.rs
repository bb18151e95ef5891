//! CalculiX (`ccx`) input decks and results, for cross-checking a buckling factor against an
//! independent solver (buckling.md §8). Used by the comparison examples (`ccx_compare`,
//! `accuracy_vs_time`, kappe's `ccx_state`); never by the solver itself.
//!
//! Hand-written because no crate writes Abaqus/CalculiX input: the format is a few keyword
//! blocks (`*NODE`, `*ELEMENT`, `*NSET`, `*BOUNDARY`, `*MATERIAL`, `*SHELL SECTION`, `*STEP`
//! with `*BUCKLE` and a `GRAV` load) described in the CalculiX 2.20 user's manual.
//!
//! ccx's ARPACK shift-invert finds the factors nearest its shift and skips lower ones far
//! below 1, so a factor is found in two passes ([`two_pass`]): pass A with the load scaled by
//! 0.01 locates λ₁, pass B scales the load so that λ₁ ≈ 2, and the factors are unscaled.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// Gravity used in the decks, m/s² (ccx takes a mass density and an acceleration).
pub const GRAVITY: f64 = 9.81;

/// Append a `*NODE` block (1-based ids in slice order).
pub fn write_nodes(s: &mut String, nodes: &[[f64; 3]]) {
    s.push_str("*NODE\n");
    for (i, p) in nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {:.12e}, {:.12e}, {:.12e}", i + 1, p[0], p[1], p[2]);
    }
}

/// Append an `*ELEMENT` block of `kind` (e.g. `S3`, `S6`, `S8R`) in element set `EALL`;
/// `elements` hold 1-based node ids.
pub fn write_elements(s: &mut String, kind: &str, elements: impl IntoIterator<Item = Vec<usize>>) {
    let _ = writeln!(s, "*ELEMENT, TYPE={kind}, ELSET=EALL");
    for (k, e) in elements.into_iter().enumerate() {
        let ids: Vec<String> = e.iter().map(usize::to_string).collect();
        let _ = writeln!(s, "{}, {}", k + 1, ids.join(", "));
    }
}

/// Append the node set `SUP` (1-based ids), ten per line as ccx reads them.
pub fn write_supports(s: &mut String, ids: impl IntoIterator<Item = usize>) {
    s.push_str("*NSET, NSET=SUP\n");
    let ids: Vec<String> = ids.into_iter().map(|n| n.to_string()).collect();
    for chunk in ids.chunks(10) {
        let _ = writeln!(s, "{}", chunk.join(", "));
    }
}

/// The material and load of a self-weight buckling step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuckleStep {
    /// Young's modulus, Pa.
    pub youngs_modulus: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
    /// Unit weight γ, N/m³ (written as the density γ/g).
    pub unit_weight: f64,
    /// Shell thickness, m.
    pub thickness: f64,
    /// Number of buckling factors asked for.
    pub modes: usize,
}

impl BuckleStep {
    /// The material and thickness of `model`'s first element, `modes` factors.
    pub fn of(model: &crate::ShellModel, modes: usize) -> Self {
        let mat = model.materials.first().copied().unwrap_or(crate::Material {
            youngs_modulus: f64::NAN,
            poisson_ratio: f64::NAN,
            unit_weight: f64::NAN,
        });
        Self {
            youngs_modulus: mat.youngs_modulus,
            poisson_ratio: mat.poisson_ratio,
            unit_weight: mat.unit_weight,
            thickness: model.thickness.first().copied().unwrap_or(f64::NAN),
            modes,
        }
    }
}

/// Append the pinned supports (`SUP`, DOFs 1–3), the material, the shell section of `EALL` and
/// a `*BUCKLE` step under self-weight scaled by `scale`.
pub fn write_buckle_step(s: &mut String, step: &BuckleStep, scale: f64) {
    let _ = write!(
        s,
        "*BOUNDARY\nSUP, 1, 3\n*MATERIAL, NAME=M\n*ELASTIC\n{:e}, {}\n*DENSITY\n{:e}\n\
         *SHELL SECTION, ELSET=EALL, MATERIAL=M\n{}\n*STEP\n*BUCKLE\n{}, 1e-6\n\
         *DLOAD\nEALL, GRAV, {:.8e}, 0., 0., -1.\n*END STEP\n",
        step.youngs_modulus,
        step.poisson_ratio,
        step.unit_weight / GRAVITY,
        step.thickness,
        step.modes,
        GRAVITY * scale
    );
}

/// The buckling factors of a ccx `.dat` file's text, in order (empty when there are none).
pub fn buckling_factors(dat: &str) -> Vec<f64> {
    let mut out = Vec::new();
    let mut on = false;
    for line in dat.lines() {
        if line.contains("B U C K L I N G") {
            on = true;
            continue;
        }
        if on {
            let w: Vec<&str> = line.split_whitespace().collect();
            if let [a, b] = w.as_slice()
                && let (Ok(_), Ok(f)) = (a.parse::<usize>(), b.parse::<f64>())
            {
                out.push(f);
            }
        }
    }
    out
}

/// One ccx run: wall time, s; the (unscaled) factors; whether ccx exited with success.
pub type Run = (f64, Vec<f64>, bool);

/// One `ccx` run of `deck` as job `job` in `dir` (2 threads): wall time, the factors times
/// `scale` (undoing the load scaling), and whether ccx exited with success.
///
/// # Errors
/// The deck cannot be written or `ccx` cannot be started (not on PATH).
pub fn run(dir: &Path, job: &str, deck: &str, scale: f64) -> std::io::Result<Run> {
    std::fs::write(dir.join(format!("{job}.inp")), deck)?;
    let t = Instant::now();
    let status = Command::new("ccx")
        .arg(job)
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "2")
        .env("CCX_NPROC_EQUATION_SOLVER", "2")
        .stdout(std::process::Stdio::null())
        .status()?;
    let wall = t.elapsed().as_secs_f64();
    let dat = std::fs::read_to_string(dir.join(format!("{job}.dat"))).unwrap_or_default();
    let factors = buckling_factors(&dat)
        .into_iter()
        .map(|x| x * scale)
        .collect();
    Ok((wall, factors, status.success()))
}

/// A two-pass ccx buckling run (module docs): `deck(scale)` writes the deck with the load
/// scaled by `scale`. Returns pass A's and pass B's `(wall s, factors, success)`; pass B is
/// `None` when pass A found no factor.
///
/// # Errors
/// As [`run`].
pub fn two_pass(
    dir: &Path,
    job: &str,
    deck: impl Fn(f64) -> String,
) -> std::io::Result<(Run, Option<Run>)> {
    let a = run(dir, job, &deck(0.01), 0.01)?;
    let b = match a.1.first() {
        Some(&l1) => Some(run(dir, job, &deck(l1 / 2.0), l1 / 2.0)?),
        None => None,
    };
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_are_read_after_the_buckling_header_only() {
        // The layout of a ccx 2.20 .dat file; the line before the header must not count.
        let dat = "  1   9.9\n\n     B U C K L I N G   F A C T O R   O U T P U T\n\n \
                   MODE NO       BUCKLING\n                FACTOR\n\n      1   0.6897044E-01\n      \
                   2   0.7512000E-01\n";
        assert_eq!(buckling_factors(dat), vec![0.06897044, 0.07512]);
    }

    #[test]
    fn a_deck_names_every_node_and_support() {
        let mut s = String::from("*HEADING\nt\n");
        write_nodes(&mut s, &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        write_elements(&mut s, "S3", [vec![1, 2, 3]]);
        write_supports(&mut s, 1..=12);
        let step = BuckleStep {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            unit_weight: 2e4,
            thickness: 0.02,
            modes: 2,
        };
        write_buckle_step(&mut s, &step, 0.5);
        assert!(s.contains("3, 0.000000000000e0, 1.000000000000e0, 0.000000000000e0\n"));
        assert!(s.contains("*ELEMENT, TYPE=S3, ELSET=EALL\n1, 1, 2, 3\n"));
        // Twelve supports: a line of ten, then a line of two.
        assert!(s.contains("1, 2, 3, 4, 5, 6, 7, 8, 9, 10\n11, 12\n"));
        assert!(s.contains("*BUCKLE\n2, 1e-6\n"));
        // Density γ/g and the gravity scaled by 0.5.
        assert!(s.contains(&format!("*DENSITY\n{:e}\n", 2e4 / GRAVITY)));
        assert!(s.contains(&format!("GRAV, {:.8e}, 0., 0., -1.", GRAVITY * 0.5)));
    }
}
