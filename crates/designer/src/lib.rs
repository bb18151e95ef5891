//! # kappe-designer: the designer in the browser
//!
//! The kappe library compiled to WebAssembly (wasm-bindgen) for `kappe designer --out DIR`
//! (issue 25). Nothing here computes structure: every number comes from the functions
//! `kappe design` calls.
//!
//! * [`Session`] (the page's main thread): the design as TOML text (what "Download design.toml"
//!   saves), [`kappe::Design::from_toml_str`] (parse and validate), [`kappe::design_cap`]
//!   (form-finding, every print state's forces), [`kappe::run::evaluate`] (stresses,
//!   overhangs, the constraint report and the verdict, from the buckling results handed in so
//!   far).
//! * [`Worker`] (one per Web Worker): [`kappe::analysis::state_fe`], the buckling
//!   analysis of one print state, over the runs of [`kappe::analysis::fe_runs`].
//!
//! The results cross between workers as JSON ([`FeWire`]: the fields of
//! [`kappe::analysis::StateFe`], losslessly: serde_json's `float_roundtrip`).
//!
//! The designer plans no robot: its analysis runs on the schedule without a plan
//! ([`kappe::schedule::cap_schedule`]: path length / print speed and the `[schedule]` waits),
//! the schedule of `kappe design --no-robot`. With a constant material (the default design) the
//! layers' ages do not enter the analysis, so every number equals `kappe design`'s.

pub mod page;

use std::collections::{BTreeMap, HashMap};

use kappe::analysis::{BucklingStatus, ModeGuess, StateBuckling};
use kappe::analysis::{Increment, WorstElement};
use kappe::analysis::{RefineBatch, RefineSolves};
use kappe::analysis::{StateFe, analysis_green, fe_runs, state_fe, state_fe_refine};
use kappe::{Cap, Design, DesignError};
use kappe_fe::{ConvergedFactor, MeshLevel};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use wasm_bindgen::prelude::*;

/// The default design file (`kappe init`'s).
#[wasm_bindgen]
pub fn default_toml() -> String {
    kappe::input::EXAMPLE_TOML.to_string()
}

/// One problem with a design: the dotted field it names (empty for a syntax error or a
/// problem of the whole design) and the message of `kappe design`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldError {
    /// Dotted field, e.g. `cap.rise`.
    pub field: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl FieldError {
    fn of(e: &DesignError) -> FieldError {
        let field = match e {
            DesignError::Parse { path, .. } => path.clone(),
            DesignError::Invalid { field, .. } => (*field).to_string(),
            DesignError::Uncertainty { field, .. } => field.clone(),
            _ => String::new(),
        };
        FieldError {
            field,
            message: e.to_string(),
        }
    }
}

/// [`StateFe`] as it crosses from a worker to the page (JSON).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeWire {
    /// [`StateFe::state`].
    pub state: usize,
    /// [`StateBuckling::status`].
    pub status: BucklingStatus,
    /// [`StateBuckling::factors`].
    pub factors: Vec<f64>,
    /// [`StateBuckling::location`].
    pub location: Option<(i32, [f64; 3])>,
    /// [`StateBuckling::mechanism`].
    pub mechanism: Option<String>,
    /// [`StateBuckling::shell_nodes`].
    pub shell_nodes: usize,
    /// [`StateFe::green`]: (strength, sliding) worst elements.
    pub green: Option<(Option<WorstWire>, Option<WorstWire>)>,
    /// The `blf_max_split` the state was solved with: 1 for the first pass (print-layer mesh),
    /// more for a solve of the mesh-error pass ([`kappe::analysis::RefineBatch`]).
    #[serde(default = "first_pass")]
    pub max_split: usize,
    /// [`StateBuckling::convergence`] (a solve of the mesh-error pass; `None` in the first pass).
    #[serde(default)]
    pub convergence: Option<ConvergedWire>,
    /// The state's as-printed increment, solved inside its first-pass buckling solve
    /// ([`kappe::analysis::FeRequest::extra`]) so that the page's last evaluation does not
    /// factorize every state again on its single thread (`None`: not solved there).
    #[serde(default)]
    pub printed: Option<IncrementWire>,
}

/// [`Increment`] on the wire, flat: per node its key (layer id, index in the layer), its design
/// position and Δu (three numbers each). JSON numbers round-trip f64 exactly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IncrementWire {
    residual: f64,
    layers: Vec<i32>,
    indices: Vec<usize>,
    x: Vec<f64>,
    du: Vec<f64>,
}

impl From<&Increment> for IncrementWire {
    fn from(i: &Increment) -> Self {
        IncrementWire {
            residual: i.residual,
            layers: i.nodes.iter().map(|n| n.0.0).collect(),
            indices: i.nodes.iter().map(|n| n.0.1).collect(),
            x: i.nodes.iter().flat_map(|n| n.1).collect(),
            du: i.nodes.iter().flat_map(|n| n.2).collect(),
        }
    }
}

impl From<IncrementWire> for Increment {
    fn from(w: IncrementWire) -> Self {
        let three = |v: &[f64]| [v[0], v[1], v[2]];
        Increment {
            nodes: w
                .layers
                .iter()
                .zip(&w.indices)
                .zip(w.x.chunks_exact(3).zip(w.du.chunks_exact(3)))
                .map(|((&l, &i), (x, d))| ((l, i), three(x), three(d)))
                .collect(),
            residual: w.residual,
        }
    }
}

fn first_pass() -> usize {
    1
}

/// [`ConvergedFactor`] on the wire: JSON has no infinity, so an unbounded error is `null`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvergedWire {
    levels: Vec<(usize, f64, usize, usize)>,
    extrapolated: f64,
    upper: f64,
    error: Option<f64>,
    converged: bool,
}

impl From<&ConvergedFactor> for ConvergedWire {
    fn from(c: &ConvergedFactor) -> Self {
        ConvergedWire {
            levels: c
                .levels
                .iter()
                .map(|l| (l.split, l.factor, l.n_free_dofs, l.steps))
                .collect(),
            extrapolated: c.extrapolated,
            upper: c.upper,
            error: c.error.is_finite().then_some(c.error),
            converged: c.converged,
        }
    }
}

impl From<ConvergedWire> for ConvergedFactor {
    fn from(w: ConvergedWire) -> Self {
        ConvergedFactor {
            levels: w
                .levels
                .into_iter()
                .map(|(split, factor, n_free_dofs, steps)| MeshLevel {
                    split,
                    factor,
                    n_free_dofs,
                    steps,
                })
                .collect(),
            extrapolated: w.extrapolated,
            upper: w.upper,
            error: w.error.unwrap_or(f64::INFINITY),
            converged: w.converged,
        }
    }
}

/// [`WorstElement`] on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WorstWire {
    utilisation: f64,
    element: usize,
    layer: usize,
    age_s: f64,
    stresses: [f64; 2],
}

impl From<&WorstElement> for WorstWire {
    fn from(w: &WorstElement) -> Self {
        WorstWire {
            utilisation: w.utilisation,
            element: w.element,
            layer: w.layer,
            age_s: w.age_s,
            stresses: w.stresses,
        }
    }
}

impl From<WorstWire> for WorstElement {
    fn from(w: WorstWire) -> Self {
        WorstElement {
            utilisation: w.utilisation,
            element: w.element,
            layer: w.layer,
            age_s: w.age_s,
            stresses: w.stresses,
        }
    }
}

impl FeWire {
    /// `f` solved with `blf_max_split = max_split`, with its as-printed increment if solved.
    fn of(f: &StateFe, max_split: usize, printed: Option<&Increment>) -> Self {
        FeWire {
            state: f.state,
            status: f.buckling.status,
            factors: f.buckling.factors.clone(),
            location: f.buckling.location,
            mechanism: f.buckling.mechanism.clone(),
            shell_nodes: f.buckling.shell_nodes,
            green: f.green.as_ref().map(|(s, l)| {
                (
                    s.as_ref().map(WorstWire::from),
                    l.as_ref().map(WorstWire::from),
                )
            }),
            max_split,
            convergence: f.buckling.convergence.as_ref().map(ConvergedWire::from),
            printed: printed.map(IncrementWire::from),
        }
    }
}

impl From<FeWire> for StateFe {
    fn from(w: FeWire) -> Self {
        StateFe {
            state: w.state,
            buckling: StateBuckling {
                status: w.status,
                factors: w.factors,
                location: w.location,
                mechanism: w.mechanism,
                shell_nodes: w.shell_nodes,
                // A first-pass result has none: the mesh error is estimated afterwards over all
                // states (`converge_fe`, in `kappe::analysis::analyze` with the results given),
                // from the mesh-error solves the workers make when it asks for them.
                convergence: w.convergence.map(ConvergedFactor::from),
            },
            // The mode shape is not drawn by the designer (it is large); it enters no check.
            mode: Vec::new(),
            green: w
                .green
                .map(|(s, l)| (s.map(WorstElement::from), l.map(WorstElement::from))),
            seconds: 0.0,
        }
    }
}

/// Set `field` (dotted, e.g. `cap.rise`) of the TOML `text` to `value` (`null`: remove it, so it
/// takes its default); the new text. Tables on the way are created.
///
/// # Errors
/// `text` is not TOML, `field` is empty or runs through a value that is not a table, or `value`
/// cannot be held by TOML.
pub fn set_field(text: &str, field: &str, value: &Value) -> Result<String, FieldError> {
    let err = |message: String| FieldError {
        field: field.to_string(),
        message,
    };
    let mut doc: toml::Table = text.parse().map_err(|e: toml::de::Error| FieldError {
        field: String::new(),
        message: format!("the design is not valid TOML: {e}"),
    })?;
    let parts: Vec<&str> = field.split('.').collect();
    let Some((last, tables)) = parts.split_last() else {
        return Err(err("empty field name".into()));
    };
    if parts.iter().any(|p| p.is_empty()) {
        return Err(err("a field name is dotted words, e.g. cap.rise".into()));
    }
    let new = (!value.is_null())
        .then(|| to_toml(value))
        .map(|v| v.ok_or(()));
    let new = new.transpose().map_err(|()| {
        err(format!(
            "{value} is not a value a design field can take (a number, true/false or text)"
        ))
    })?;
    let mut table = &mut doc;
    for t in tables {
        let entry = table
            .entry((*t).to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        table = match entry {
            toml::Value::Table(t) => t,
            _ => return Err(err(format!("`{t}` is not a table"))),
        };
    }
    match new {
        Some(v) => table.insert((*last).to_string(), v),
        None => table.remove(*last),
    };
    toml::to_string(&doc).map_err(|e| err(format!("cannot write the design as TOML: {e}")))
}

fn to_toml(v: &Value) -> Option<toml::Value> {
    Some(match v {
        Value::Bool(b) => toml::Value::Boolean(*b),
        Value::Number(n) => match n.as_i64() {
            Some(i) => toml::Value::Integer(i),
            None => toml::Value::Float(n.as_f64().filter(|x| x.is_finite())?),
        },
        Value::String(s) => toml::Value::String(s.clone()),
        Value::Array(a) => toml::Value::Array(a.iter().map(to_toml).collect::<Option<_>>()?),
        Value::Object(o) => toml::Value::Table(
            o.iter()
                .map(|(k, v)| Some((k.clone(), to_toml(v)?)))
                .collect::<Option<_>>()?,
        ),
        Value::Null => return None,
    })
}

/// Read `field` (dotted) of a TOML text as JSON (`null` when absent or not TOML).
pub fn get_field(text: &str, field: &str) -> Value {
    let Ok(doc) = text.parse::<toml::Table>() else {
        return Value::Null;
    };
    let mut v = toml::Value::Table(doc);
    for p in field.split('.') {
        match v {
            toml::Value::Table(mut t) => match t.remove(p) {
                Some(x) => v = x,
                None => return Value::Null,
            },
            _ => return Value::Null,
        }
    }
    serde_json::to_value(&v).unwrap_or(Value::Null)
}

/// The page's design: its text, the designed cap, the buckling results so far.
pub struct SessionCore {
    text: String,
    cap: Option<Cap>,
    runs: Vec<Vec<usize>>,
    fe: BTreeMap<usize, StateFe>,
    /// The mesh-error pass's solves so far (the workers make them when the pass asks).
    refined: RefineSolves,
    /// The first pass's as-printed increments so far, by state.
    printed: HashMap<usize, Increment>,
    generation: u64,
}

impl Default for SessionCore {
    fn default() -> Self {
        Self::new()
    }
}

impl SessionCore {
    /// No design yet.
    pub fn new() -> SessionCore {
        SessionCore {
            text: String::new(),
            cap: None,
            runs: Vec::new(),
            fe: BTreeMap::new(),
            refined: RefineSolves::new(),
            printed: HashMap::new(),
            generation: 0,
        }
    }

    /// The design file as text (what "Download design.toml" saves).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Take `text` as the design: parse, validate and form-find it (every print state's forces)
    /// and analyse stresses and overhangs; the buckling results start empty. On an error the
    /// session keeps its last good design.
    ///
    /// # Errors
    /// The design's first problem, with the field it names.
    pub fn load(&mut self, text: &str) -> Result<Value, FieldError> {
        let design = Design::from_toml_str(text).map_err(|e| FieldError::of(&e))?;
        let cap = kappe::design_cap(&design, kappe::Context::default())
            .map_err(|e| FieldError::of(&e))?;
        let runs = fe_runs(&design.analysis, cap.states.len());
        // The quick pass must succeed before the design is taken (e.g. a bad [schedule]).
        let outcome = evaluate(&cap, &BTreeMap::new(), &RefineSolves::new(), HashMap::new())
            .map_err(|e| FieldError::of(&e))?;
        self.text = text.to_string();
        self.runs = runs;
        self.fe.clear();
        self.refined.clear();
        self.printed.clear();
        self.generation += 1;
        let view = view(&cap);
        let report = report(&outcome, &self.runs);
        self.cap = Some(cap);
        Ok(json!({
            "ok": true,
            "generation": self.generation,
            "text": self.text,
            "runs": self.runs,
            "view": view,
            "report": report,
        }))
    }

    /// [`Self::load`] of the current text with `field` set to `value`.
    ///
    /// # Errors
    /// As [`set_field`] and [`Self::load`]; the design is unchanged.
    pub fn set(&mut self, field: &str, value: &Value) -> Result<Value, FieldError> {
        let text = set_field(&self.text, field, value)?;
        self.load(&text)
    }

    /// Take a worker's results (JSON list of [`FeWire`]) for design `generation`; the report
    /// with every result so far. Results of an older generation are ignored.
    ///
    /// # Errors
    /// No design, or results that are not [`FeWire`] JSON.
    pub fn add_fe(&mut self, generation: u64, results: &str) -> Result<Value, FieldError> {
        let cap = self.cap.as_ref().ok_or_else(|| FieldError {
            field: String::new(),
            message: "no design loaded".into(),
        })?;
        if generation == self.generation {
            let wires: Vec<FeWire> = serde_json::from_str(results).map_err(|e| FieldError {
                field: String::new(),
                message: format!("worker results: {e}"),
            })?;
            for mut w in wires {
                if let Some(p) = w.printed.take() {
                    self.printed.insert(w.state, Increment::from(p));
                }
                match w.max_split {
                    0 | 1 => {
                        self.fe.insert(w.state, StateFe::from(w));
                    }
                    split => {
                        self.refined.insert((w.state, split), StateFe::from(w));
                    }
                }
            }
        }
        // The increments are used only once every state is in (the as-printed pass runs on a
        // complete analysis), so they are cloned only then.
        let all_in = self.fe.len() >= self.runs.iter().map(Vec::len).sum::<usize>();
        let printed = if all_in {
            self.printed.clone()
        } else {
            HashMap::new()
        };
        let outcome =
            evaluate(cap, &self.fe, &self.refined, printed).map_err(|e| FieldError::of(&e))?;
        Ok(report(&outcome, &self.runs))
    }
}

/// The verdict of `cap` with the buckling results so far (`fe`: first pass, `refined`: the
/// mesh-error pass's solves, `printed`: the first pass's as-printed increments):
/// [`kappe::run::evaluate`] with the design's own analysis options and no robot plan.
fn evaluate(
    cap: &Cap,
    fe: &BTreeMap<usize, StateFe>,
    refined: &RefineSolves,
    printed: HashMap<usize, Increment>,
) -> Result<kappe::Outcome, DesignError> {
    let options = kappe::Options {
        analysis: Some(cap.design.analysis.clone()),
        robot: false,
        allow_fail: false,
    };
    kappe::run::evaluate(
        cap.clone(),
        &options,
        Some(kappe::Given {
            fe: fe.values().cloned().collect(),
            refined: refined.clone(),
            increments: printed,
        }),
        &kappe::no_progress,
    )
}

/// The report of an outcome for the page: per state the stresses, overhang and BLF, the
/// constraint table, the verdict (`ok` only once every selected state is analysed).
fn report(outcome: &kappe::Outcome, runs: &[Vec<usize>]) -> Value {
    let total: usize = runs.iter().map(Vec::len).sum();
    let Some(a) = &outcome.analysis else {
        return json!({ "ok": null });
    };
    let done = a
        .states
        .iter()
        .filter(|s| s.buckling != BucklingStatus::Skipped)
        .count();
    let states: Vec<Value> = a
        .states
        .iter()
        .map(|s| {
            json!({
                "index": s.index,
                "top_layer": s.top_layer,
                "blf": s.blf,
                "compression_pa": s.max_compression_stress_pa,
                "tension_pa": s.max_tension_stress_pa,
                "overhang_m": s.max_overhang_m,
                "ok": s.ok,
            })
        })
        .collect();
    // Every first-pass factor in and the mesh-error pass done (`refine`: the solves it asks
    // for next, which the page hands to its workers).
    let refine: Option<&RefineBatch> = a.refine_pending.as_ref();
    let complete = done >= total && refine.is_none();
    json!({
        "complete": complete,
        "ok": if complete { Value::Bool(outcome.verdict.ok) } else { Value::Null },
        "ok_so_far": outcome.verdict.ok,
        "min_blf": outcome.min_blf(),
        "states_done": done,
        "states_total": total,
        "refine": refine,
        "states": states,
        "constraints": a.constraints,
        "failures": outcome.verdict.failures.iter().map(|f| f.to_string()).collect::<Vec<_>>(),
    })
}

/// The cap for the 3D view: the final state's network (node positions) and its members with
/// their stress ([`kappe::analysis::element_stresses`]), each node's layer overhang and the
/// limit `overhang_max`.
///
/// Flat arrays (`members`: the two node indices of member k at 2k and 2k + 1; `stress`: its
/// stress): the page reads nothing else of the view, and one JSON number per entry instead of a
/// three-element array per member makes the text the page parses on every change shorter and
/// its building here cheaper (no nested array per member).
fn view(cap: &Cap) -> Value {
    let net = &cap.final_state.network;
    // Drawing data only, so on a decimal grid (positions to 0.1 mm, stresses to 0.1 Pa): the
    // shortest decimals make the JSON the page parses on every change a third as long. The
    // numbers the verdict uses stay in `report`.
    let on_grid = |x: f64, per_unit: f64| (x * per_unit).round() / per_unit;
    let xyz: Vec<f64> = net
        .nodes
        .iter()
        .flat_map(|n| [n.xyz.x, n.xyz.y, n.xyz.z])
        .map(|x| on_grid(x, 1e4))
        .collect();
    let es = kappe::analysis::element_stresses(&cap.final_state, cap.areas()).unwrap_or_default();
    let (mut members, mut stress) = (Vec::new(), Vec::new());
    for e in es {
        members.extend(e.nodes);
        stress.push(on_grid(e.stress, 10.0));
    }
    // Each node's layer overhang (`Cap::overhangs`, in print order) for the overhang colouring,
    // and the limit it is judged against.
    let overhang: Vec<f64> = net
        .nodes
        .iter()
        .map(|n| {
            cap.sections
                .print_index(n.layer)
                .and_then(|k| cap.overhangs.get(k))
                .map_or(0.0, |&o| on_grid(o, 1e4))
        })
        .collect();
    json!({
        "xyz": xyz,
        "members": members,
        "stress": stress,
        "overhang": overhang,
        "overhang_max": cap.design.overhang_max(),
    })
}

/// A Web Worker's share of the buckling analysis: the cap of the design it was given, the warm
/// start within the current run, and the first-pass factor and mode of every state it solved,
/// from which it solves those states' mesh-error levels as `kappe design` does
/// ([`state_fe_refine`]: no second print-layer solve, the split's eigen-solve warm-started).
pub struct WorkerCore {
    text: String,
    cap: Option<Cap>,
    green: Option<kappe::analysis::CapGreen>,
    guess: Option<ModeGuess>,
    first: BTreeMap<usize, (f64, ModeGuess)>,
}

impl Default for WorkerCore {
    fn default() -> Self {
        Self::new()
    }
}

impl WorkerCore {
    /// No design yet.
    pub fn new() -> WorkerCore {
        WorkerCore {
            text: String::new(),
            cap: None,
            green: None,
            guess: None,
            first: BTreeMap::new(),
        }
    }

    /// Analyse `run` (state indices of one [`fe_runs`] run, in order) of the design `text` with
    /// `blf_max_split = max_split` (1: the first pass, warm-started along the run; more: single
    /// states of a [`RefineBatch`], each from the first pass's factor and mode if this worker
    /// solved it, as [`kappe::analysis::analyze`] does, else from a cold start); `on_state`
    /// hears each state's result as JSON ([`FeWire`]) as it finishes.
    ///
    /// # Errors
    /// The design's problem (the page checked it first) or a state that cannot be solved.
    pub fn run(
        &mut self,
        text: &str,
        run: &[usize],
        max_split: usize,
        on_state: &mut dyn FnMut(String),
    ) -> Result<(), FieldError> {
        if self.cap.is_none() || self.text != text {
            let design = Design::from_toml_str(text).map_err(|e| FieldError::of(&e))?;
            let cap = kappe::design_cap(&design, kappe::Context::default())
                .map_err(|e| FieldError::of(&e))?;
            let schedule = kappe::schedule::cap_schedule(&cap).map_err(|e| FieldError::of(&e))?;
            self.green = analysis_green(&cap, Some(&schedule)).map_err(|e| FieldError::of(&e))?;
            self.cap = Some(cap);
            self.text = text.to_string();
            self.first.clear();
        }
        let Some(cap) = &self.cap else {
            return Ok(());
        };
        self.guess = None;
        let max_split = max_split.max(1);
        // The first pass: the print-layer mesh alone (the mesh error is estimated over all
        // states together when every worker is done). A mesh-error solve: the options the pass
        // asked for (`converge_fe` solves with `blf_max_split` 2, or the design's own).
        let options = kappe::analysis::AnalysisOptions {
            blf_max_split: max_split,
            ..cap.design.analysis.clone()
        };
        for &i in run {
            let request = kappe::analysis::FeRequest {
                green: self.green.as_ref(),
                // The first pass also solves the state's as-printed increment on its factor of
                // K, as `kappe design` does.
                extra: max_split == 1,
            };
            let mut printed = None;
            let fe = match (max_split, self.first.get(&i)) {
                (1, _) => {
                    let solved = state_fe(cap, &options, i, &mut self.guess, &request)
                        .map_err(|e| FieldError::of(&e))?;
                    printed = solved.increment;
                    let fe = solved.fe;
                    // What `analyze` keeps for its mesh-error pass (without a green-state
                    // model, whose path starts cold).
                    if let (None, Some(g), Some(&f1)) =
                        (&self.green, &self.guess, fe.buckling.factors.first())
                    {
                        self.first.insert(i, (f1, g.clone()));
                    }
                    fe
                }
                (_, Some((f1, mode))) => {
                    state_fe_refine(cap, &options, i, *f1, mode).map_err(|e| FieldError::of(&e))?
                }
                (_, None) => {
                    state_fe(cap, &options, i, &mut None, &request)
                        .map_err(|e| FieldError::of(&e))?
                        .fe
                }
            };
            let wire = FeWire::of(&fe, max_split, printed.as_ref());
            on_state(serde_json::to_string(&[wire]).unwrap_or_default());
        }
        Ok(())
    }
}

fn js_err(e: FieldError) -> JsValue {
    JsValue::from_str(&serde_json::to_string(&e).unwrap_or_else(|_| e.message.clone()))
}

fn js_ok(v: &Value) -> Result<String, JsValue> {
    serde_json::to_string(v).map_err(|e| JsValue::from_str(&e.to_string()))
}

/// [`SessionCore`] for JavaScript: results as JSON text; errors as JSON `{field, message}`.
#[wasm_bindgen]
#[derive(Default)]
pub struct Session(SessionCore);

#[wasm_bindgen]
impl Session {
    /// No design yet.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Session {
        Session(SessionCore::new())
    }

    /// [`SessionCore::load`].
    ///
    /// # Errors
    /// `{field, message}` as JSON.
    pub fn load(&mut self, text: &str) -> Result<String, JsValue> {
        self.0.load(text).map_err(js_err).and_then(|v| js_ok(&v))
    }

    /// [`SessionCore::set`] with the value as JSON text.
    ///
    /// # Errors
    /// `{field, message}` as JSON.
    pub fn set(&mut self, field: &str, value_json: &str) -> Result<String, JsValue> {
        let value: Value = serde_json::from_str(value_json).map_err(|e| {
            js_err(FieldError {
                field: field.to_string(),
                message: format!("not a value: {e}"),
            })
        })?;
        self.0
            .set(field, &value)
            .map_err(js_err)
            .and_then(|v| js_ok(&v))
    }

    /// [`SessionCore::add_fe`].
    ///
    /// # Errors
    /// `{field, message}` as JSON.
    pub fn add_fe(&mut self, generation: u32, results: &str) -> Result<String, JsValue> {
        self.0
            .add_fe(u64::from(generation), results)
            .map_err(js_err)
            .and_then(|v| js_ok(&v))
    }

    /// The design file's text.
    pub fn text(&self) -> String {
        self.0.text().to_string()
    }

    /// [`get_field`] of the current design, as JSON text.
    pub fn get(&self, field: &str) -> String {
        get_field(self.0.text(), field).to_string()
    }
}

/// [`WorkerCore`] for JavaScript.
#[wasm_bindgen]
#[derive(Default)]
pub struct Worker(WorkerCore);

#[wasm_bindgen]
impl Worker {
    /// No design yet.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Worker {
        Worker(WorkerCore::new())
    }

    /// [`WorkerCore::run`]; `on_state` is called with each state's JSON.
    ///
    /// # Errors
    /// `{field, message}` as JSON.
    pub fn run(
        &mut self,
        text: &str,
        run: Vec<u32>,
        max_split: u32,
        on_state: &js_sys_fn::Function,
    ) -> Result<(), JsValue> {
        let run: Vec<usize> = run.into_iter().map(|i| i as usize).collect();
        let mut call = |s: String| {
            let _ = on_state.call1(&JsValue::NULL, &JsValue::from_str(&s));
        };
        self.0
            .run(text, &run, max_split as usize, &mut call)
            .map_err(js_err)
    }
}

/// The one JavaScript type the worker binding needs, declared here (no js-sys dependency).
mod js_sys_fn {
    use wasm_bindgen::prelude::*;

    #[wasm_bindgen]
    extern "C" {
        /// A JavaScript function.
        pub type Function;

        /// `f.call(this, a)`.
        #[wasm_bindgen(method, catch, js_name = call)]
        pub fn call1(this: &Function, ctx: &JsValue, a: &JsValue) -> Result<JsValue, JsValue>;
    }
}
