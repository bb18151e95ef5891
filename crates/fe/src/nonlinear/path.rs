//! Path following: load-controlled Newton–Raphson and Crisfield's cylindrical arc length
//! (formulas in the module docs of [`crate::nonlinear`]).

use crate::clock::Instant;
use std::ops::ControlFlow;

use faer::Mat;

use super::{Problem, State, Tangent};
use crate::error::FeError;
use crate::factor::Ldlt;
use crate::model::ShellModel;

/// How the load factor is controlled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PathControl {
    /// Crisfield's cylindrical arc length: passes limit points and snap-backs.
    #[default]
    ArcLength,
    /// Fixed load-factor increments (adaptive size): stops near a limit point, where the
    /// tangent turns singular; exact load levels for curves without one.
    Load,
}

/// Options of [`nonlinear_path`].
#[derive(Debug, Clone, PartialEq)]
pub struct PathOptions {
    /// Load or arc-length control (default arc length).
    pub control: PathControl,
    /// Load-factor increment of the first step, > 0 (default 0.1). The first arc length is
    /// this increment times the W-norm of the tangent displacement under the reference load.
    pub initial_increment: f64,
    /// Smallest step (arc length or Δλ) relative to the first; below it the path stops with
    /// [`StopReason::StepTooSmall`] (default 1e-4).
    pub min_step_ratio: f64,
    /// Largest load-factor increment of a step (arc length: of its predictor) relative to
    /// the first (default 10).
    pub max_step_ratio: f64,
    /// Largest arc length (m; W-norm of a step's displacement increment). `None` (default):
    /// 5 % of the model's bounding-box diagonal. The first arc length follows from
    /// `initial_increment` and is usually far smaller: a stiff pre-buckling state moves
    /// little, the post-buckling path a lot; steps grow by up to 2× per step.
    pub max_arc_length: Option<f64>,
    /// Iterations per step the step-size control aims at (default 4).
    pub target_iterations: usize,
    /// Iterations before a step is cut (default 20).
    pub max_iterations: usize,
    /// Largest number of converged steps (default 200).
    pub max_steps: usize,
    /// The path ends at this load factor (default 10); the last step is cut to reach it.
    pub lambda_max: f64,
    /// Equilibrium tolerance: `‖λ q − f_int‖ ≤ tol · ‖q‖ · max(|λ|, initial_increment)`
    /// over the free DOFs (default 1e-6).
    pub tolerance: f64,
    /// Stop once a limit point (load maximum or bifurcation) has been passed (default true:
    /// the collapse factor is known then).
    pub stop_at_limit: bool,
    /// Start each step's corrections as modified Newton (the factor of the step's starting
    /// tangent, internal force only), switching to full Newton when the residual is not
    /// halved by an iteration or after 8 of them (default false). Without applied moments
    /// only; a modified iteration costs a force evaluation and a triangular solve. Saves
    /// 15–30 % of the tangent assemblies on the collapse paths of `bench_nonlinear`; off by
    /// default because it is less proven (with it, the load-controlled cantilever of the
    /// tests takes more than 200 steps).
    pub modified_newton: bool,
    /// Arc length: predict each step after the first along the previous converged step's
    /// increment (Δu, Δλ) scaled to the new arc length (the secant predictor) instead of the
    /// tangent's solution under the reference load (default false). The secant follows the
    /// path's curvature of the last step, so the corrector starts closer to the path and
    /// passes a load maximum without the tangent's sign test; it also saves the predictor's
    /// solve.
    pub secant_predictor: bool,
    /// Locate a critical point that a rising step crosses (the tangent's inertia changes)
    /// from the tangent's eigenvalue nearest zero, μ, instead of cutting the step until the
    /// crossing is bracketed within 10⁻³ in λ (default false). μ is computed at every
    /// converged step (inverse iteration with the step's factor, warm-started from the last
    /// step's vector); a crossing step is accepted when the zero of μ(λ) interpolated
    /// linearly between the two steps around it and the zero of the parabola through the
    /// last three steps agree within 10⁻³ in λ, and the lower of the two is the critical λ
    /// (docs/nonlinear.md, "Locating a critical point"). Otherwise the step is cut as
    /// without it. Load maxima (λ falls) are bracketed as before.
    pub locate_by_eigenvalue: bool,
    /// Keep the factor of a step's last full-Newton iteration as the converged point's
    /// (its inertia, μ and the next step's modified-Newton factor) instead of factorizing the
    /// tangent at the converged point again, when the step's last correction was a full-Newton
    /// one (default false). That tangent is one converging correction away from the
    /// converged point (the residual then was already small), so its inertia and μ differ
    /// from the converged tangent's only within a step of the critical point that
    /// `locate_by_eigenvalue` resolves anyway; it saves one LDLᵀ per step (a third of a
    /// cap state's). Without applied moments the residual after such a correction is then
    /// checked with the internal force alone, and the converged point keeps that iteration's
    /// tangent with its factor: the tangent is assembled again only when another correction
    /// is needed (a cap state's path: 25 → 18 assemblies).
    pub reuse_iteration_factor: bool,
    /// Length ℓ weighting rotations in the arc-length norm (rotation·ℓ ≈ a translation);
    /// `None` (default): the mean edge length of the mesh.
    pub rotation_length: Option<f64>,
    /// Give each facet its own initial-stress (von Kármán) terms in its co-rotated frame, so
    /// that the tangent at the reference state carries the linear buckling solver's K_G
    /// (docs/nonlinear.md, "Local initial-stress terms"). Default true; false is the plain
    /// small-strain EICR facet (kept for comparison).
    pub local_geometric: bool,
}

impl Default for PathOptions {
    fn default() -> Self {
        Self {
            control: PathControl::ArcLength,
            initial_increment: 0.1,
            min_step_ratio: 1e-4,
            max_step_ratio: 10.0,
            max_arc_length: None,
            target_iterations: 4,
            max_iterations: 20,
            max_steps: 200,
            lambda_max: 10.0,
            tolerance: 1e-6,
            stop_at_limit: true,
            modified_newton: false,
            secant_predictor: false,
            locate_by_eigenvalue: false,
            reuse_iteration_factor: false,
            rotation_length: None,
            local_geometric: true,
        }
    }
}

impl PathOptions {
    fn validate(&self) -> Result<(), FeError> {
        let pos = |field: &'static str, v: f64, allowed: &'static str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(FeError::BadOption {
                    field,
                    value: v,
                    allowed,
                })
            }
        };
        pos("initial_increment", self.initial_increment, "> 0")?;
        pos("min_step_ratio", self.min_step_ratio, "> 0 and ≤ 1")?;
        pos("max_step_ratio", self.max_step_ratio, "≥ 1")?;
        pos("lambda_max", self.lambda_max, "> 0")?;
        pos("tolerance", self.tolerance, "> 0 and < 1")?;
        if self.min_step_ratio > 1.0 {
            return Err(FeError::BadOption {
                field: "min_step_ratio",
                value: self.min_step_ratio,
                allowed: "> 0 and ≤ 1",
            });
        }
        if self.max_step_ratio < 1.0 {
            return Err(FeError::BadOption {
                field: "max_step_ratio",
                value: self.max_step_ratio,
                allowed: "≥ 1",
            });
        }
        if self.tolerance >= 1.0 {
            return Err(FeError::BadOption {
                field: "tolerance",
                value: self.tolerance,
                allowed: "> 0 and < 1",
            });
        }
        for (field, v) in [
            ("target_iterations", self.target_iterations),
            ("max_iterations", self.max_iterations),
            ("max_steps", self.max_steps),
        ] {
            if v == 0 {
                return Err(FeError::BadOption {
                    field,
                    value: 0.0,
                    allowed: "≥ 1",
                });
            }
        }
        if let Some(l) = self.max_arc_length {
            pos("max_arc_length", l, "> 0 m")?;
        }
        if let Some(l) = self.rotation_length {
            pos("rotation_length", l, "> 0 m")?;
        }
        Ok(())
    }
}

/// One converged point of the path.
#[derive(Debug, Clone, PartialEq)]
pub struct PathStep {
    /// Step number (1-based; 0 is the unloaded state, not reported).
    pub step: usize,
    /// Load factor λ (multiplies the model's reference load).
    pub lambda: f64,
    /// Per node `[ux, uy, uz, rx, ry, rz]`: translations (m) and the total rotation as a
    /// rotation vector (rad, |θ| ≤ π).
    pub displacements: Vec<[f64; 6]>,
    /// Equilibrium residual `‖λ q − f_int‖ / (‖q‖ · max(|λ|, initial_increment))`.
    pub residual: f64,
    /// Newton iterations of this step (0: the predictor was already in equilibrium).
    pub iterations: usize,
    /// Negative pivots of the LDLᵀ of the tangent here (= its negative eigenvalues).
    pub negative_pivots: usize,
    /// The path's first limit point (load maximum or bifurcation, [`Path::limit`]) lies
    /// between the previous step and this one.
    pub limit_passed: bool,
    /// Arc length of this step (W-norm of the displacement increment, m).
    pub arc_length: f64,
}

impl PathStep {
    /// Translation of `node` (m).
    pub fn translation(&self, node: usize) -> Option<[f64; 3]> {
        self.displacements.get(node).map(|d| [d[0], d[1], d[2]])
    }
}

/// Why the path ended.
#[derive(Debug, Clone, PartialEq)]
pub enum StopReason {
    /// λ reached [`PathOptions::lambda_max`].
    LambdaMax,
    /// A limit point was passed and [`PathOptions::stop_at_limit`] is set.
    LimitPoint,
    /// [`PathOptions::max_steps`] converged steps.
    MaxSteps,
    /// Steps were cut below [`PathOptions::min_step_ratio`] without converging (e.g. load
    /// control at a limit point).
    StepTooSmall {
        /// Load factor of the last converged step.
        lambda: f64,
    },
    /// The caller's callback stopped the path (e.g. material failure), with its reason.
    Caller(String),
}

/// Kind of a limit point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitKind {
    /// The load factor passed a maximum (snap-through or collapse).
    LoadMaximum,
    /// The tangent's negative-pivot count rose while λ kept rising: a bifurcation.
    Bifurcation,
}

/// The first limit point of the path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimitPoint {
    /// Load factor: for a maximum the vertex of the parabola through the three steps
    /// around it (in arc length); for a bifurcation the λ interpolated linearly to the zero
    /// of the tangent's eigenvalue that changed sign, estimated by inverse iteration.
    pub lambda: f64,
    /// Index into [`Path::steps`] of the step after which it was detected.
    pub step: usize,
    /// What kind.
    pub kind: LimitKind,
}

/// Counters and timings.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathStats {
    /// Free DOFs.
    pub n_free_dofs: usize,
    /// Assemblies of internal force + tangent.
    pub assemblies: usize,
    /// Evaluations of the internal force alone (modified-Newton iterations).
    pub force_evaluations: usize,
    /// Numeric LDLᵀ factorizations.
    pub factorizations: usize,
    /// Rejected (cut) step attempts.
    pub cut_steps: usize,
    /// Seconds: setup (pattern, symbolic factorization, element matrices).
    pub t_setup: f64,
    /// Seconds: internal force and tangent assembly.
    pub t_assembly: f64,
    /// Seconds: numeric factorizations and solves.
    pub t_factor: f64,
    /// Seconds in total.
    pub t_total: f64,
}

/// A traced equilibrium path.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    /// The converged steps, in order.
    pub steps: Vec<PathStep>,
    /// Why it ended.
    pub stop: StopReason,
    /// The first limit point, if one was passed.
    pub limit: Option<LimitPoint>,
    /// Counters and timings.
    pub stats: PathStats,
}

impl Path {
    /// Largest load factor reached before the first limit point, or over the whole path.
    pub fn max_lambda(&self) -> f64 {
        let end = self.limit.map_or(self.steps.len(), |l| l.step + 1);
        self.steps[..end.min(self.steps.len())]
            .iter()
            .map(|s| s.lambda)
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

fn dot_w(w: &[f64], a: &[f64], b: &[f64]) -> f64 {
    w.iter().zip(a).zip(b).map(|((w, a), b)| w * a * b).sum()
}

fn norm(a: &[f64]) -> f64 {
    a.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Solve `(K_s + K_k) x = b` by GMRES (Saad & Schultz 1986), right-preconditioned with the
/// LDLᵀ of the symmetric part `K_s`. Without a skew part the first Krylov step is exact;
/// at equilibrium the skew part is of low rank (the nodes carrying moments), so a few steps
/// suffice. Stops at a relative residual of 1e-9 or after 40 steps; the flag tells whether
/// 1e-6 was reached.
fn solve_t(
    f: &Ldlt<'_>,
    k: &Tangent,
    p: &Problem<'_>,
    b: &[f64],
) -> Result<(Vec<f64>, bool), FeError> {
    const M: usize = 40;
    let n = b.len();
    let bn = norm(b);
    if bn == 0.0 {
        return Ok((vec![0.0; n], true));
    }
    let mut v: Vec<Vec<f64>> = vec![b.iter().map(|x| x / bn).collect()];
    let mut z: Vec<Vec<f64>> = Vec::new();
    let mut h: Vec<Vec<f64>> = Vec::new(); // columns of the Hessenberg matrix
    let (mut cs, mut sn): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut g = vec![bn];
    let mut w = vec![0.0; n];
    for j in 0..M {
        let zj = solve(f, &v[j])?;
        k.matvec(&p.pattern, &zj, &mut w);
        z.push(zj);
        let mut col = Vec::with_capacity(j + 2);
        for vi in &v {
            let hij: f64 = vi.iter().zip(&w).map(|(a, b)| a * b).sum();
            w.iter_mut().zip(vi).for_each(|(a, b)| *a -= hij * b);
            col.push(hij);
        }
        let hn = norm(&w);
        col.push(hn);
        for i in 0..j {
            let (a, b2) = (col[i], col[i + 1]);
            col[i] = cs[i] * a + sn[i] * b2;
            col[i + 1] = -sn[i] * a + cs[i] * b2;
        }
        let (a, b2) = (col[j], col[j + 1]);
        let r = a.hypot(b2);
        let (c, s) = if r == 0.0 {
            (1.0, 0.0)
        } else {
            (a / r, b2 / r)
        };
        cs.push(c);
        sn.push(s);
        col[j] = r;
        col[j + 1] = 0.0;
        g.push(-s * g[j]);
        g[j] *= c;
        h.push(col);
        let done = g[j + 1].abs() <= 1e-9 * bn || hn == 0.0;
        if done || j + 1 == M {
            break;
        }
        v.push(w.iter().map(|x| x / hn).collect());
    }
    // Back substitution H y = g.
    let m = h.len();
    let mut y = vec![0.0; m];
    for i in (0..m).rev() {
        let mut acc = g[i];
        for jj in i + 1..m {
            acc -= h[jj][i] * y[jj];
        }
        y[i] = if h[i][i] != 0.0 { acc / h[i][i] } else { 0.0 };
    }
    let mut x = vec![0.0; n];
    for (yj, zj) in y.iter().zip(&z) {
        x.iter_mut().zip(zj).for_each(|(a, b)| *a += yj * b);
    }
    let ok = g.get(m).is_some_and(|r| r.abs() <= 1e-6 * bn) && x.iter().all(|v| v.is_finite());
    Ok((x, ok))
}

/// Solve with the symmetric part only, for two right-hand sides in one pass.
fn solve2(f: &Ldlt<'_>, a: &[f64], b: &[f64]) -> Result<(Vec<f64>, Vec<f64>), FeError> {
    let n = a.len();
    let mut m = Mat::<f64>::from_fn(n, 2, |i, j| if j == 0 { a[i] } else { b[i] });
    f.solve_in_place(m.as_mut())?;
    Ok((
        (0..n).map(|i| m[(i, 0)]).collect(),
        (0..n).map(|i| m[(i, 1)]).collect(),
    ))
}

fn solve(f: &Ldlt<'_>, rhs: &[f64]) -> Result<Vec<f64>, FeError> {
    let mut m = Mat::<f64>::from_fn(rhs.len(), 1, |i, _| rhs[i]);
    f.solve_in_place(m.as_mut())?;
    Ok((0..rhs.len()).map(|i| m[(i, 0)]).collect())
}

/// Eigenvalue of the tangent closest to zero, by a few steps of inverse iteration with its
/// factor (Rayleigh quotient of the last iterate).
fn eig_near_zero(f: &Ldlt<'_>, kv: &Tangent, p: &Problem<'_>) -> Result<f64, FeError> {
    Ok(eig_near_zero_from(f, kv, p, None, 8)?.0)
}

/// As [`eig_near_zero`], warm-started from `start` (the previous step's vector; `None`: the
/// fixed start, 8 iterations) with `iterations` steps; returns μ and the vector.
fn eig_near_zero_from(
    f: &Ldlt<'_>,
    kv: &Tangent,
    p: &Problem<'_>,
    start: Option<&[f64]>,
    iterations: usize,
) -> Result<(f64, Vec<f64>), FeError> {
    let n = p.q.len();
    let mut x: Vec<f64> = match start {
        Some(v) if v.len() == n => v.to_vec(),
        _ => (0..n)
            .map(|i| 1.0 + ((i * 7919) % 101) as f64 / 101.0)
            .collect(),
    };
    let mut y = vec![0.0; n];
    for _ in 0..iterations {
        let nx = norm(&x);
        x.iter_mut().for_each(|v| *v /= nx);
        x = solve(f, &x)?;
    }
    let nx = norm(&x);
    x.iter_mut().for_each(|v| *v /= nx);
    p.pattern.sym_matvec(&kv.sym, &x, &mut y);
    Ok((x.iter().zip(&y).map(|(a, b)| a * b).sum(), x))
}

/// The zero of μ(λ) in a step (λ0, μ0 > 0) → (λ1, μ1 < 0) that crossed it, when the linear
/// interpolation and the parabola through `before` (the step ahead of λ0) and the two agree
/// within `tol` in λ: the lower of the two (for a μ concave in λ, as it is approaching a
/// critical point, the chord's zero is the lower one).
fn crossing_zero(
    before: Option<(f64, f64)>,
    l0: f64,
    m0: f64,
    l1: f64,
    m1: f64,
    tol: f64,
) -> Option<f64> {
    if !(m0 > 0.0 && m1 < 0.0 && l1 > l0) {
        return None;
    }
    let lin = l0 + (l1 - l0) * m0 / (m0 - m1);
    let (la, ma) = before?;
    if la >= l0 || la.is_nan() {
        return None;
    }
    // Newton form through (la, ma), (l0, m0), (l1, m1); its root in [l0, l1].
    let d0 = (m0 - ma) / (l0 - la);
    let d1 = (m1 - m0) / (l1 - l0);
    let c = (d1 - d0) / (l1 - la);
    let (a, b, cc) = (c, d1 - c * (l0 + l1), m1 - d1 * l1 + c * l0 * l1);
    let quad = if a.abs() <= 1e-12 * b.abs() {
        -cc / b
    } else {
        let disc = b * b - 4.0 * a * cc;
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let q = -0.5 * (b + b.signum() * sq);
        [q / a, cc / q]
            .into_iter()
            .filter(|r| r.is_finite() && *r >= l0 && *r <= l1)
            .fold(f64::NAN, f64::min)
    };
    (quad.is_finite() && (quad - lin).abs() <= tol).then_some(lin.min(quad))
}

struct Converged<'a> {
    state: State,
    lambda: f64,
    du: Vec<f64>,
    factor: Ldlt<'a>,
    kvals: Tangent,
    residual: f64,
    iterations: usize,
    /// Full-Newton iterations plus a third of the modified ones (for the step control).
    cost: f64,
}

struct Solver<'a, 'm> {
    p: &'a Problem<'m>,
    opt: &'a PathOptions,
    qnorm: f64,
    stats: PathStats,
}

impl<'a, 'm> Solver<'a, 'm> {
    fn factor(&mut self, kv: &Tangent) -> Result<Option<Ldlt<'a>>, FeError> {
        let t = Instant::now();
        let f = self
            .p
            .symbolic
            .ldlt_with(&self.p.pattern, &kv.sym, Some(&self.p.buffers))?;
        self.stats.factorizations += 1;
        self.stats.t_factor += t.elapsed().as_secs_f64();
        Ok(f)
    }

    fn evaluate(&mut self, st: &State) -> Result<(Vec<f64>, Tangent), FeError> {
        let t = Instant::now();
        let (f, k) = self.p.evaluate(st, true)?;
        self.stats.assemblies += 1;
        self.stats.t_assembly += t.elapsed().as_secs_f64();
        let k = k.ok_or(FeError::Numerical {
            stage: "tangent assembly",
            detail: "no tangent".into(),
        })?;
        Ok((f, k))
    }

    fn force(&mut self, st: &State) -> Result<Vec<f64>, FeError> {
        let t = Instant::now();
        let (f, _) = self.p.evaluate(st, false)?;
        self.stats.force_evaluations += 1;
        self.stats.t_assembly += t.elapsed().as_secs_f64();
        Ok(f)
    }

    fn residual(&self, lambda: f64, fint: &[f64]) -> (Vec<f64>, f64) {
        let r: Vec<f64> = self
            .p
            .q
            .iter()
            .zip(fint)
            .map(|(q, f)| lambda * q - f)
            .collect();
        let rel = norm(&r) / (self.qnorm * lambda.abs().max(self.opt.initial_increment));
        (r, rel)
    }

    /// One step from a converged state. `arc`: `Some(Δl)` for arc length (with the previous
    /// increment for the predictor's sign), `None` with `dlambda` for load control.
    /// `Ok(None)`: no convergence (cut the step).
    fn step(
        &mut self,
        from: &State,
        lambda0: f64,
        factor0: &Ldlt<'_>,
        k0: &Tangent,
        control: StepControl<'_>,
    ) -> Result<Option<Converged<'a>>, FeError> {
        let p = self.p;
        let mut st = from.clone();
        let mut lambda = lambda0;
        let mut du_step: Vec<f64>;
        let mut arc_eff = 0.0;
        let secant = match control {
            StepControl::Arc {
                prev: Some(prev),
                prev_dlambda: Some(pdl),
                ..
            } if self.opt.secant_predictor => {
                let np = dot_w(&p.weight, prev, prev).sqrt();
                (np > 0.0 && np.is_finite()).then_some((prev, pdl, np))
            }
            _ => None,
        };
        match control {
            StepControl::Load(dl) => {
                let ut = solve_t(factor0, k0, p, &p.q)?.0;
                du_step = ut.iter().map(|v| v * dl).collect();
                lambda += dl;
            }
            StepControl::Arc { dl, dlam_max, .. } if secant.is_some() => {
                let Some((prev, pdl, np)) = secant else {
                    return Ok(None);
                };
                // The previous increment scaled to the new arc length, its Δλ capped as the
                // tangent predictor's is.
                let mut s = dl / np;
                if (pdl * s).abs() > dlam_max {
                    s = dlam_max / pdl.abs();
                }
                arc_eff = s * np;
                du_step = prev.iter().map(|v| v * s).collect();
                lambda += pdl * s;
            }
            StepControl::Arc {
                dl, prev, dlam_max, ..
            } => {
                let ut = solve_t(factor0, k0, p, &p.q)?.0;
                let nut = dot_w(&p.weight, &ut, &ut).sqrt();
                // Cap the predicted load increment (stiff pre-buckling states).
                let dl = dl.min(dlam_max * nut);
                arc_eff = dl;
                let sign = match prev {
                    Some(prev) if dot_w(&p.weight, &ut, prev) < 0.0 => -1.0,
                    _ => 1.0,
                };
                let dlam = sign * dl / nut;
                du_step = ut.iter().map(|v| v * dlam).collect();
                lambda += dlam;
            }
        }
        p.apply(&mut st, &du_step);
        // Modified Newton first (the step's starting factor, internal force only), full
        // Newton once it stalls (residual not halved) or after MODIFIED_MAX iterations.
        let mut full = !self.opt.modified_newton || p.has_moments;
        let mut own: Option<(Ldlt<'a>, Tangent)> = None;
        // The last correction used a factor computed in its own iteration.
        let mut own_fresh = false;
        let mut prev_rel = f64::INFINITY;
        let (mut n_full, mut n_mod) = (0usize, 0usize);
        for it in 0..=self.opt.max_iterations {
            // After a full-Newton correction with its own factor, whose factor and tangent
            // the converged point would keep anyway, the next residual is checked with the
            // internal force alone: the tangent is assembled only if another correction is
            // needed (a force evaluation costs about a third of an assembly).
            let check_only = full && own_fresh && self.opt.reuse_iteration_factor && !p.has_moments;
            let (fint, mut kv_now) = if full && !check_only {
                let (f, k) = self.evaluate(&st)?;
                (f, Some(k))
            } else {
                (self.force(&st)?, None)
            };
            let (r, rel) = self.residual(lambda, &fint);
            if !rel.is_finite() {
                return Ok(None);
            }
            if rel <= self.opt.tolerance {
                let reuse = if self.opt.reuse_iteration_factor && own_fresh {
                    own.take()
                } else {
                    None
                };
                let (factor, kv) = match reuse {
                    // The last iteration's factor with its own tangent, or with the
                    // converged tangent when a correction's check assembled it.
                    Some((f, k)) => (f, kv_now.unwrap_or(k)),
                    None => {
                        let kv = match kv_now {
                            Some(k) => k,
                            None => self.evaluate(&st)?.1,
                        };
                        let Some(factor) = self.factor(&kv)? else {
                            return Ok(None);
                        };
                        (factor, kv)
                    }
                };
                return Ok(Some(Converged {
                    state: st,
                    lambda,
                    du: du_step,
                    factor,
                    kvals: kv,
                    residual: rel,
                    iterations: it,
                    cost: n_full as f64 + n_mod as f64 / 3.0,
                }));
            }
            if it == self.opt.max_iterations {
                break;
            }
            if check_only || (!full && (n_mod >= MODIFIED_MAX || rel > 0.5 * prev_rel)) {
                full = true;
                kv_now = Some(self.evaluate(&st)?.1);
            }
            prev_rel = rel;
            if let Some(kv) = kv_now {
                let Some(f) = self.factor(&kv)? else {
                    return Ok(None);
                };
                own = Some((f, kv));
                own_fresh = true;
                n_full += 1;
            } else {
                own_fresh = false;
                n_mod += 1;
            }
            let (factor, kv): (&Ldlt<'_>, &Tangent) = match own.as_ref() {
                Some((f, k)) => (f, k),
                None => (factor0, k0),
            };
            let t = Instant::now();
            let arc = matches!(control, StepControl::Arc { .. });
            let (dur, dut) = if p.has_moments {
                let dur = solve_t(factor, kv, p, &r)?.0;
                let dut = if arc {
                    solve_t(factor, kv, p, &p.q)?.0
                } else {
                    Vec::new()
                };
                (dur, dut)
            } else if arc {
                // Without applied moments the skew part vanishes at equilibrium: Newton with
                // the symmetric part keeps its local convergence, at one solve per RHS.
                solve2(factor, &r, &p.q)?
            } else {
                (solve(factor, &r)?, Vec::new())
            };
            let sol = Some((dur, dut));
            let Some((dur, dut)) = sol else {
                return Ok(None);
            };
            let du = match control {
                StepControl::Load(_) => dur,
                StepControl::Arc { .. } => {
                    let dl = arc_eff;
                    let w = &p.weight;
                    let base: Vec<f64> = du_step.iter().zip(&dur).map(|(a, b)| a + b).collect();
                    let a = dot_w(w, &dut, &dut);
                    let b = 2.0 * dot_w(w, &base, &dut);
                    let c = dot_w(w, &base, &base) - dl * dl;
                    let disc = b * b - 4.0 * a * c;
                    if disc < 0.0 || a <= 0.0 {
                        return Ok(None);
                    }
                    let sq = disc.sqrt();
                    // Numerically stable roots.
                    let qq = -0.5 * (b + b.signum() * sq);
                    let (r1, r2) = if qq != 0.0 {
                        (qq / a, c / qq)
                    } else {
                        (0.0, 0.0)
                    };
                    // The root keeping the step closest in direction to the step so far.
                    let score = |dlam: f64| -> f64 {
                        let mut s = 0.0;
                        for i in 0..base.len() {
                            s += w[i] * (base[i] + dlam * dut[i]) * du_step[i];
                        }
                        s
                    };
                    let dlam = if score(r1) >= score(r2) { r1 } else { r2 };
                    lambda += dlam;
                    base.iter()
                        .zip(&du_step)
                        .zip(&dut)
                        .map(|((bb, s), t)| bb - s + dlam * t)
                        .collect()
                }
            };
            self.stats.t_factor += t.elapsed().as_secs_f64();
            if du.iter().any(|v| !v.is_finite()) {
                return Ok(None);
            }
            p.apply(&mut st, &du);
            du_step.iter_mut().zip(&du).for_each(|(a, b)| *a += b);
        }
        Ok(None)
    }
}

#[derive(Clone, Copy)]
enum StepControl<'v> {
    Load(f64),
    Arc {
        dl: f64,
        prev: Option<&'v [f64]>,
        /// Δλ of the previous converged step (the secant predictor's).
        prev_dlambda: Option<f64>,
        dlam_max: f64,
    },
}

/// Modified-Newton iterations before a step switches to full Newton.
const MODIFIED_MAX: usize = 8;

/// Relative λ-width to which a step crossing a change of the tangent's inertia is shortened.
const LOCATE: f64 = 1e-3;

/// Trace the equilibrium path of `model` under `λ ×` its reference load (self-weight ·
/// gravity + nodal loads), geometrically nonlinear (co-rotational, small strains), from
/// λ = 0 until [`PathOptions::lambda_max`], a limit point (with `stop_at_limit`),
/// `max_steps`, a step below `min_step_ratio`, or `on_step` returning
/// `ControlFlow::Break(reason)`. `on_step` sees every converged step (λ, displacements,
/// residual, iterations, inertia) before the next begins, e.g. to check the material with
/// [`super::deformed_resultants`]; the collapse factor is then the smaller of
/// [`Path::limit`]'s λ and the λ at which it stopped the path.
///
/// Loads are dead loads (fixed direction); applied moments are fixed global vectors.
pub fn nonlinear_path(
    model: &ShellModel,
    options: &PathOptions,
    on_step: &mut dyn FnMut(&PathStep) -> ControlFlow<StopReason>,
) -> Result<Path, FeError> {
    options.validate()?;
    let t_all = Instant::now();
    let problem = Problem::new(model, options.rotation_length, options.local_geometric)?;
    let mut solver = Solver {
        p: &problem,
        opt: options,
        qnorm: norm(&problem.q),
        stats: PathStats {
            n_free_dofs: problem.dofs.n_free(),
            t_setup: t_all.elapsed().as_secs_f64(),
            ..Default::default()
        },
    };
    let mut state = State::initial(model);
    let (_, kv0) = solver.evaluate(&state)?;
    let mut factor = match solver.factor(&kv0)? {
        Some(f) => f,
        None => {
            return Err(FeError::Numerical {
                stage: "initial tangent",
                detail: "singular stiffness at λ = 0 (a mechanism: check the supports)".into(),
            });
        }
    };
    let mut kvals = kv0;
    let mut neg = factor.negative;
    let mut lambda = 0.0;
    let ut0 = solve_t(&factor, &kvals, &problem, &problem.q)?.0;
    let arc = options.control == PathControl::ArcLength;
    let step0 = if arc {
        options.initial_increment * dot_w(&problem.weight, &ut0, &ut0).sqrt()
    } else {
        options.initial_increment
    };
    let smin = step0 * options.min_step_ratio;
    let smax = if arc {
        options
            .max_arc_length
            .unwrap_or(0.05 * bbox_diagonal(model))
    } else {
        step0 * options.max_step_ratio
    }
    .max(step0);
    let mut size = step0;
    let mut prev: Option<Vec<f64>> = None;
    let mut prev_dlambda: Option<f64> = None;
    let mut steps: Vec<PathStep> = Vec::new();
    let mut limit: Option<LimitPoint> = None;
    let mut s_cum = vec![0.0];
    let mut rising = true;
    // (λ, μ) of the converged steps (from λ = 0) and the last eigenvector, with
    // `locate_by_eigenvalue`.
    // μ at λ = 0 is computed when first needed, from λ = 0's factor (still at hand then): a
    // path that the caller ends at its first step needs none, and every μ is the same as
    // computed up front (the same start, the same factor, the same order).
    let mut mu_hist: Vec<(f64, f64)> = Vec::new();
    let mut mu_vec: Option<Vec<f64>> = None;
    let mu_at_zero = |factor: &Ldlt<'_>, kvals: &Tangent| -> Result<_, FeError> {
        let (m, v) = eig_near_zero_from(factor, kvals, &problem, None, 8)?;
        Ok(((0.0, m), v))
    };
    let stop;
    loop {
        if steps.len() >= options.max_steps {
            stop = StopReason::MaxSteps;
            break;
        }
        // Attempt a step, cutting on failure.
        let mut to_max = false;
        // μ at the accepted step and the critical λ located from it.
        let mut located: Option<(f64, Vec<f64>, Option<f64>)> = None;
        let conv = loop {
            let ctrl = if arc && !to_max {
                StepControl::Arc {
                    dl: size,
                    prev: prev.as_deref(),
                    prev_dlambda,
                    dlam_max: options.max_step_ratio * options.initial_increment,
                }
            } else if to_max {
                StepControl::Load(options.lambda_max - lambda)
            } else {
                StepControl::Load(size.min(options.lambda_max - lambda))
            };
            match solver.step(&state, lambda, &factor, &kvals, ctrl)? {
                Some(c) if arc && !to_max && c.lambda > options.lambda_max => {
                    // Overshot λ_max: redo the step load-controlled to λ_max exactly.
                    to_max = true;
                }
                Some(c)
                    if options.locate_by_eigenvalue
                        && arc
                        && c.factor.negative == neg + 1
                        && c.lambda > lambda
                        && mu_hist.len() >= 2 =>
                {
                    let (m1, v1) =
                        eig_near_zero_from(&c.factor, &c.kvals, &problem, mu_vec.as_deref(), 4)?;
                    let (l0, m0) = mu_hist[mu_hist.len() - 1];
                    let before = mu_hist.get(mu_hist.len() - 2).copied();
                    let tol = LOCATE * lambda.abs().max(options.initial_increment);
                    match crossing_zero(before, l0, m0, c.lambda, m1, tol) {
                        Some(z) => {
                            located = Some((m1, v1, Some(z)));
                            break Some(c);
                        }
                        None if (c.lambda - lambda).abs() > tol && 0.5 * size >= smin => {
                            solver.stats.cut_steps += 1;
                            size *= 0.5;
                        }
                        None => {
                            located = Some((m1, v1, None));
                            break Some(c);
                        }
                    }
                }
                Some(c)
                    if arc
                        && c.factor.negative != neg
                        && (c.lambda - lambda).abs()
                            > LOCATE * lambda.abs().max(options.initial_increment)
                        && 0.5 * size >= smin =>
                {
                    // The tangent's inertia changed within a long step: shorten it until the
                    // critical point is bracketed within LOCATE in λ.
                    solver.stats.cut_steps += 1;
                    size *= 0.5;
                }
                Some(c) => break Some(c),
                None => {
                    solver.stats.cut_steps += 1;
                    if to_max {
                        to_max = false;
                    }
                    size *= 0.5;
                    if size < smin {
                        break None;
                    }
                }
            }
        };
        let Some(c) = conv else {
            stop = StopReason::StepTooSmall { lambda };
            break;
        };
        let arc_len = dot_w(&problem.weight, &c.du, &c.du).sqrt();
        let new_neg = c.factor.negative;
        let mut passed = false;
        let idx = steps.len();
        s_cum.push(s_cum[idx] + arc_len);
        // Load maximum: λ falls after rising.
        if limit.is_none() {
            if rising && c.lambda < lambda && lambda > 0.0 {
                passed = true;
                let lam_lim = if idx >= 1 {
                    let (s0, s1, s2) = (s_cum[idx - 1], s_cum[idx], s_cum[idx + 1]);
                    let (l0, l1, l2) = (steps[idx - 1].lambda, lambda, c.lambda);
                    parabola_max(s0, s1, s2, l0, l1, l2).unwrap_or(l1)
                } else {
                    lambda
                };
                limit = Some(LimitPoint {
                    lambda: lam_lim,
                    step: idx,
                    kind: LimitKind::LoadMaximum,
                });
            } else if new_neg > neg && c.lambda >= lambda {
                passed = true;
                // The eigenvalue that crossed zero: interpolate between its estimates.
                let (e0, e1) = match (&located, mu_hist.last()) {
                    (Some((m1, _, _)), Some(&(_, m0))) => (m0, *m1),
                    _ => (
                        eig_near_zero(&factor, &kvals, &problem)?,
                        eig_near_zero(&c.factor, &c.kvals, &problem)?,
                    ),
                };
                let lam = if let Some((_, _, Some(z))) = &located {
                    *z
                } else if e0 > 0.0 && e1 < 0.0 {
                    lambda + (c.lambda - lambda) * e0 / (e0 - e1)
                } else {
                    c.lambda
                };
                limit = Some(LimitPoint {
                    lambda: lam,
                    step: idx,
                    kind: LimitKind::Bifurcation,
                });
            }
        }
        if c.lambda > lambda {
            rising = true;
        } else if c.lambda < lambda {
            rising = false;
        }
        let ps = PathStep {
            step: idx + 1,
            lambda: c.lambda,
            displacements: c.state.displacements(model),
            residual: c.residual,
            iterations: c.iterations,
            negative_pivots: new_neg,
            limit_passed: passed,
            arc_length: arc_len,
        };
        let flow = on_step(&ps);
        steps.push(ps);
        // The path ends at this step: μ would serve only the steps after it (a stopped state
        // of the collapse rule ends after one or two steps, so this is a fair share of its
        // solves).
        let last = flow.is_break()
            || (passed && options.stop_at_limit)
            || c.lambda >= options.lambda_max * (1.0 - 1e-12);
        if options.locate_by_eigenvalue && !last {
            if mu_hist.is_empty() {
                let (h, v) = mu_at_zero(&factor, &kvals)?;
                mu_hist.push(h);
                mu_vec = Some(v);
            }
            let (m, v) = match located {
                Some((m, v, _)) => (m, v),
                None => eig_near_zero_from(&c.factor, &c.kvals, &problem, mu_vec.as_deref(), 4)?,
            };
            mu_hist.push((c.lambda, m));
            mu_vec = Some(v);
        }
        // Next step size.
        let ratio = (options.target_iterations as f64 / c.cost.max(1.0)).sqrt();
        size = (size * ratio.clamp(0.5, 2.0)).clamp(smin, smax);
        let lambda_before = lambda;
        lambda = c.lambda;
        state = c.state;
        factor = c.factor;
        kvals = c.kvals;
        neg = new_neg;
        prev = Some(c.du);
        prev_dlambda = Some(c.lambda - lambda_before);
        if let ControlFlow::Break(reason) = flow {
            stop = reason;
            break;
        }
        if passed && options.stop_at_limit {
            stop = StopReason::LimitPoint;
            break;
        }
        if lambda >= options.lambda_max * (1.0 - 1e-12) {
            stop = StopReason::LambdaMax;
            break;
        }
    }
    solver.stats.t_total = t_all.elapsed().as_secs_f64();
    Ok(Path {
        steps,
        stop,
        limit,
        stats: solver.stats,
    })
}

fn bbox_diagonal(model: &ShellModel) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &model.nodes {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt()
}

/// Maximum of the parabola through (s_i, l_i), if it is concave and its vertex lies within
/// [s0, s2].
fn parabola_max(s0: f64, s1: f64, s2: f64, l0: f64, l1: f64, l2: f64) -> Option<f64> {
    let d01 = (l1 - l0) / (s1 - s0);
    let d12 = (l2 - l1) / (s2 - s1);
    let a = (d12 - d01) / (s2 - s0);
    if a.is_nan() || a >= 0.0 {
        return None;
    }
    let b = d01 - a * (s0 + s1);
    let sv = -b / (2.0 * a);
    if !(sv >= s0 && sv <= s2) {
        return None;
    }
    Some(l0 + d01 * (sv - s0) + a * (sv - s0) * (sv - s1))
}
