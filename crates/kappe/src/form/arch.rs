//! One print layer (paper T1, method.md §4): the closed arch in the tilted plane, form-found with
//! constrained CEM so that its feet land on the springing lines and its crown at the rise.

use crate::form::frame::{LayerFrame, V3};
use crate::input::error::DesignError;

/// A form-found layer-0 arch: nodes from the left foot over the crown to the right foot.
#[derive(Debug, Clone, PartialEq)]
pub struct Arch {
    /// Node positions, foot (−Cs/2, 0, 0) → crown → foot (+Cs/2, 0, 0); `2·(n_t + 1)` nodes.
    pub points: Vec<V3>,
    /// Signed axial force of segment `i` (between points `i` and `i + 1`), N; compression < 0.
    pub segment_forces: Vec<f64>,
    /// Gravity load magnitude W of every node, N (feet: half a segment's bead).
    pub weights: Vec<f64>,
    /// Common segment length s, m.
    pub segment_length: f64,
    /// Crown thrust μ (signed force of the crown deviation edge), N.
    pub crown_force: f64,
    /// Fixed-point iterations of the tributary self-weight.
    pub weight_iterations: usize,
    /// Objective of the last constrained form-finding (squared foot error, m²).
    pub objective: f64,
}

impl Arch {
    /// Number of segments, `2·n_t + 1`.
    pub fn segments(&self) -> usize {
        self.segment_forces.len()
    }

    /// Indices of the interior nodes (every node but the two feet): the columns of the cap.
    pub fn columns(&self) -> std::ops::Range<usize> {
        1..self.points.len().saturating_sub(1)
    }
}

/// The closed-form limit of a layer (method.md §4): a catenary in the tilted plane under the
/// in-plane load `q' = γ·lw·lh / cos(am)` per unit arc length.
///
/// Its parameter `a` solves `a·(cosh(Cs / 2a) − 1) = R` with `R = Cr / cos(am)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Catenary {
    /// Catenary parameter a, m.
    pub a: f64,
    /// In-plane rise R = Cr / cos(am), m.
    pub in_plane_rise: f64,
    /// Crown stress magnitude γ·a / cos(am), Pa.
    pub crown_stress: f64,
    /// Springing stress magnitude γ·(a + R) / cos(am), Pa.
    pub springing_stress: f64,
}

impl Catenary {
    /// Solve for `a` by bisection (the left side falls monotonically in `a`).
    ///
    /// ```
    /// // method.md §4: defaults give a = 0.394642 m and 10.03 / 15.65 kPa.
    /// let c = kappe::form::Catenary::new(0.8, 0.2, 25f64.to_radians(), 23044.0);
    /// assert!((c.a - 0.394642).abs() < 1e-6);
    /// assert!((c.crown_stress / 1e3 - 10.03).abs() < 0.01);
    /// assert!((c.springing_stress / 1e3 - 15.65).abs() < 0.01);
    /// ```
    pub fn new(span: f64, rise: f64, tilt: f64, gamma: f64) -> Catenary {
        let r = rise / tilt.cos();
        let f = |a: f64| a * ((0.5 * span / a).cosh() - 1.0) - r;
        // f(a) → +∞ as a → 0 and → −R < 0 as a → ∞; bracket and bisect.
        let (mut lo, mut hi) = (1e-4 * span, 1e4 * span);
        while f(lo) <= 0.0 && lo > 1e-12 {
            lo *= 0.5;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let a = 0.5 * (lo + hi);
        Catenary {
            a,
            in_plane_rise: r,
            crown_stress: gamma * a / tilt.cos(),
            springing_stress: gamma * (a + r) / tilt.cos(),
        }
    }

    /// Arc length of the catenary from foot to foot, `2a·sinh(Cs / 2a)`.
    pub fn arc_length(&self, span: f64) -> f64 {
        2.0 * self.a * (0.5 * span / self.a).sinh()
    }

    /// Distance from `p` (a point of the tilted plane) to the catenary, sampled finely.
    pub fn distance_to(&self, p: &V3, span: f64, frame: &LayerFrame) -> f64 {
        let h = p.dot(&frame.u); // in-plane height
        let samples = 4000;
        let mut best = f64::INFINITY;
        for k in 0..=samples {
            let x = -0.5 * span + span * k as f64 / samples as f64;
            let y = self.in_plane_rise - self.a * ((x / self.a).cosh() - 1.0);
            let d = ((p.x - x).powi(2) + (h - y).powi(2)).sqrt();
            best = best.min(d);
        }
        best
    }
}

/// Inputs of the layer form-finding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArchSpec {
    /// Cs, m.
    pub span: f64,
    /// Cr, m.
    pub rise: f64,
    /// am, rad.
    pub tilt: f64,
    /// γ, N/m³.
    pub specific_weight: f64,
    /// lw, m.
    pub layer_width: f64,
    /// lh, m.
    pub layer_height: f64,
    /// Δs, m.
    pub path_sampling: f64,
}

/// The CEM topology of the layer arch for a given segment length `s` (which sets the loads and the
/// crown origins), trail length `len` and crown force `mu`.
///
/// Nodes `0..=nt` are the left trail from the crown origin (0) to the foot (`nt`, support),
/// nodes `nt+1..=2nt+1` the right trail. Every non-support node carries its tributary self-weight
/// `W = γ·lw·lh·s` down plus the horizontal auxiliary force `W·tan(am)·e_y` (method.md §4).
pub fn layer_topology(
    spec: &ArchSpec,
    nt: usize,
    s: f64,
    len: f64,
    mu: f64,
) -> kappe_cem::Topology {
    use kappe_cem::topology::{DeviationEdge, Node, Topology, TrailEdge};
    let w = spec.specific_weight * spec.layer_width * spec.layer_height * s;
    let load = V3::new(0.0, w * spec.tilt.tan(), -w);
    let crown_y = -spec.rise * spec.tilt.tan();
    let mut nodes = Vec::with_capacity(2 * nt + 2);
    let mut trail_edges = Vec::with_capacity(2 * nt);
    for side in 0..2u64 {
        let sign = if side == 0 { -1.0 } else { 1.0 };
        let first = side * (nt as u64 + 1);
        for k in 0..=nt as u64 {
            let support = k == nt as u64;
            // Starting guesses only; the solver overwrites every non-origin position.
            let frac = k as f64 / nt as f64;
            let xyz = V3::new(
                sign * (0.5 * s + frac * (0.5 * spec.span - 0.5 * s)),
                crown_y * (1.0 - frac),
                spec.rise * (1.0 - frac),
            );
            nodes.push(Node {
                id: first + k,
                xyz,
                load: if support { V3::zeros() } else { load },
                support,
                origin: None,
            });
            if k > 0 {
                trail_edges.push(TrailEdge {
                    u: first + k - 1,
                    v: first + k,
                    length: -len.abs(),
                    plane: None,
                });
            }
        }
    }
    Topology {
        name: "layer".into(),
        nodes,
        trail_edges,
        deviation_edges: vec![DeviationEdge {
            u: 0,
            v: nt as u64 + 1,
            force: mu,
        }],
        auxiliary_trails: None,
        trail_shifts: Vec::new(),
    }
}

/// Form-find layer 0 (paper T1, method.md §4): unknowns the crown thrust μ and one common segment
/// length s; goals the feet at (∓Cs/2, 0, 0); the crown origins at z = Cr, `s` apart. The loads
/// depend on s, so the constrained problem is solved inside a fixed-point loop on s.
///
/// Each constrained problem is `kappe_cem::optimize` (SLSQP, exact forward-mode gradients) with
/// two parameters, the crown force and one length shared by every trail edge (both kept in
/// compression), and two point goals, the feet.
pub fn form_find_layer(spec: &ArchSpec) -> Result<Arch, DesignError> {
    form_find(spec, None)
}

/// [`form_find_layer`] with a prescribed segment count `2·nt + 1` (`nt` = `(segments − 1) / 2`)
/// instead of the one Δs gives: the layers of a corrugated centre section (`crate::form::section`)
/// share the columns of layer 0, so every layer needs layer 0's node count whatever its rise.
pub fn form_find_layer_with_segments(
    spec: &ArchSpec,
    segments: usize,
) -> Result<Arch, DesignError> {
    if segments < 5 || segments.is_multiple_of(2) {
        return Err(DesignError::FormFinding(format!(
            "{segments} segments requested; allowed: an odd count ≥ 5"
        )));
    }
    form_find(spec, Some((segments - 1) / 2))
}

fn form_find(spec: &ArchSpec, fixed_nt: Option<usize>) -> Result<Arch, DesignError> {
    let cat = Catenary::new(spec.span, spec.rise, spec.tilt, spec.specific_weight);
    let arc = cat.arc_length(spec.span);
    // 2·nt + 1 = round(arc / Δs), rounded to an odd count of at least 5 segments.
    let mut nt = fixed_nt
        .unwrap_or_else(|| (((arc / spec.path_sampling) - 1.0) / 2.0).round().max(2.0) as usize);
    let gamma_a = spec.specific_weight * spec.layer_width * spec.layer_height;
    let mut s = arc / (2 * nt + 1) as f64;
    let mut mu = -gamma_a * cat.a / spec.tilt.cos();
    let opts = kappe_cem::SolverOptions::default();
    let mut iterations = 0;
    let mut objective = f64::INFINITY;
    for _ in 0..3 {
        // Fixed point on the load length s: loads and crown origins frozen at s, constrained CEM
        // for (μ, common trail length), repeat until s stops moving.
        for it in 0..60 {
            iterations += 1;
            let s_load = s;
            let (len, mu_new, obj) = constrained_layer(spec, nt, s_load, mu)?;
            objective = obj;
            mu = mu_new;
            s = len;
            if (s - s_load).abs() <= 1e-15 * s.max(1.0) && it > 0 {
                break;
            }
        }
        if fixed_nt.is_some() {
            break;
        }
        // Check the segment count against Δs; rebuild once if the rounding changed.
        let arc_now = (2 * nt + 1) as f64 * s;
        let nt_new = (((arc_now / spec.path_sampling) - 1.0) / 2.0)
            .round()
            .max(2.0) as usize;
        if nt_new == nt {
            break;
        }
        s = arc_now / (2 * nt_new + 1) as f64;
        nt = nt_new;
    }
    if objective.is_nan() || objective >= 1e-20 {
        return Err(DesignError::FormFinding(format!(
            "the feet did not reach the springing lines (squared error {objective:.3e} m²): no compression \
             arch of this span and rise"
        )));
    }
    let topo = layer_topology(spec, nt, s, s, mu);
    let eq = kappe_cem::solve(&topo, &opts)?;
    let pos = |id: u64| {
        eq.position(id)
            .ok_or_else(|| DesignError::FormFinding(format!("node {id} missing")))
    };
    let mut points = Vec::with_capacity(2 * nt + 2);
    for k in (0..=nt as u64).rev() {
        points.push(pos(k)?);
    }
    for k in 0..=nt as u64 {
        points.push(pos(nt as u64 + 1 + k)?);
    }
    let force = |a: u64, b: u64| -> Result<f64, DesignError> {
        eq.trail_edge(a, b)
            .map(|e| e.force)
            .ok_or_else(|| DesignError::FormFinding(format!("trail edge {a}-{b} missing")))
    };
    let mut segment_forces = Vec::with_capacity(2 * nt + 1);
    for k in (0..nt as u64).rev() {
        segment_forces.push(force(k, k + 1)?);
    }
    segment_forces.push(mu);
    for k in 0..nt as u64 {
        let first = nt as u64 + 1;
        segment_forces.push(force(first + k, first + k + 1)?);
    }
    let w = gamma_a * s;
    let mut weights = vec![w; points.len()];
    weights[0] = 0.5 * w;
    let last = weights.len() - 1;
    weights[last] = 0.5 * w;
    Ok(Arch {
        points,
        segment_forces,
        weights,
        segment_length: s,
        crown_force: mu,
        weight_iterations: iterations,
        objective,
    })
}

/// One constrained CEM solve of the layer: loads and origins frozen at `s_load`; returns the
/// common trail length, the crown force and the final objective.
fn constrained_layer(
    spec: &ArchSpec,
    nt: usize,
    s_load: f64,
    mu0: f64,
) -> Result<(f64, f64, f64), DesignError> {
    use kappe_cem::optimize::{
        Bounds, Goal, OptimizeOptions, Parameter, ParameterKind, Problem, WeightedGoal,
    };
    let topo = layer_topology(spec, nt, s_load, s_load, mu0);
    let edges: Vec<(u64, u64)> = topo.trail_edges.iter().map(|e| (e.u, e.v)).collect();
    let tiny = 1e-9 * s_load;
    let problem = Problem {
        parameters: vec![
            Parameter::new(
                ParameterKind::DeviationForce(0, nt as u64 + 1),
                Bounds::Absolute {
                    lower: f64::NEG_INFINITY,
                    upper: -1e-12 * mu0.abs(),
                },
            ),
            Parameter::new(
                ParameterKind::TrailLengths(edges),
                Bounds::Absolute {
                    lower: -10.0 * spec.span,
                    upper: -tiny,
                },
            ),
        ],
        goals: [(nt as u64, -1.0), (2 * nt as u64 + 1, 1.0)]
            .into_iter()
            .map(|(node, side)| WeightedGoal {
                goal: Goal::Point {
                    node,
                    target: V3::new(side * 0.5 * spec.span, 0.0, 0.0),
                },
                weight: 1.0,
            })
            .collect(),
    };
    let options = OptimizeOptions {
        max_evaluations: 400,
        stopval: 1e-30,
        ftol_abs: 1e-32,
        keep_states: true,
        ..Default::default()
    };
    let res = kappe_cem::optimize::optimize(&topo, &problem, &options)?;
    let (Some(&mu), Some(&len)) = (res.x_opt.first(), res.x_opt.get(1)) else {
        return Err(DesignError::FormFinding(
            "the optimizer returned no parameters".into(),
        ));
    };
    Ok((len.abs(), mu, res.objective_at_x_opt))
}
