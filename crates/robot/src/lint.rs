//! An independent URScript checker (`kappe robot lint`): it parses a program file (blocks,
//! statements, calls, literals) without using anything of the writer, and rejects what a UR
//! e-Series controller would refuse or what would drive the arm outside its limits:
//!
//! - unbalanced blocks (`def`/`thread`/`if`/`while` … `end`), a `def` that is never called;
//! - calls of unknown functions, wrong argument counts, unknown keyword arguments (the table
//!   [`SIGNATURES`], from UR's "The URScript Programming Language", e-Series SW 5.x);
//! - non-finite or unparsable numbers;
//! - joint targets beyond UR's position limits (±360°, elbow ±180°), poses and joint lists that
//!   do not have six numbers;
//! - I/O numbers the controller lacks, analog values outside 0..1, negative sleeps;
//! - more motion targets than the limit;
//! - in a program that uses conveyor tracking (a moving base, [`crate::conveyor`]): a decoder
//!   set up before tracking, no joint target while tracking, tracking stopped before the end.
//!
//! Hand-written: no URScript parser exists as a crate. The grammar covered is the subset the
//! exporter and hand edits use (no operator precedence is needed to check literals and calls).

use std::collections::HashSet;

use serde::Serialize;

/// One function of the table: name, least and most arguments, keyword names (in order).
pub struct Signature {
    pub name: &'static str,
    pub min: usize,
    pub params: &'static [&'static str],
}

/// The functions the checker knows, with their parameters (UR Script Manual, e-Series).
pub const SIGNATURES: &[Signature] = &[
    Signature {
        name: "movej",
        min: 1,
        params: &["q", "a", "v", "t", "r"],
    },
    Signature {
        name: "movel",
        min: 1,
        params: &["pose", "a", "v", "t", "r"],
    },
    Signature {
        name: "movep",
        min: 1,
        params: &["pose", "a", "v", "r"],
    },
    Signature {
        name: "movec",
        min: 2,
        params: &["pose_via", "pose_to", "a", "v", "r", "mode"],
    },
    Signature {
        name: "servoj",
        min: 1,
        params: &["q", "a", "v", "t", "lookahead_time", "gain"],
    },
    Signature {
        name: "stopj",
        min: 1,
        params: &["a"],
    },
    Signature {
        name: "stopl",
        min: 1,
        params: &["a", "aRot"],
    },
    Signature {
        name: "set_tcp",
        min: 1,
        params: &["pose"],
    },
    Signature {
        name: "set_payload",
        min: 1,
        params: &["m", "cog"],
    },
    Signature {
        name: "set_target_payload",
        min: 2,
        params: &["m", "cog", "inertia", "transition_time"],
    },
    Signature {
        name: "set_analog_outputdomain",
        min: 2,
        params: &["port", "domain"],
    },
    Signature {
        name: "set_standard_analog_out",
        min: 2,
        params: &["n", "f"],
    },
    Signature {
        name: "set_standard_digital_out",
        min: 2,
        params: &["n", "b"],
    },
    Signature {
        name: "set_configurable_digital_out",
        min: 2,
        params: &["n", "b"],
    },
    Signature {
        name: "set_tool_digital_out",
        min: 2,
        params: &["n", "b"],
    },
    Signature {
        name: "sleep",
        min: 1,
        params: &["t"],
    },
    Signature {
        name: "sync",
        min: 0,
        params: &[],
    },
    Signature {
        name: "textmsg",
        min: 1,
        params: &["s1", "s2"],
    },
    Signature {
        name: "popup",
        min: 1,
        params: &["s", "title", "warning", "error", "blocking"],
    },
    Signature {
        name: "get_actual_joint_positions",
        min: 0,
        params: &[],
    },
    Signature {
        name: "get_actual_tcp_pose",
        min: 0,
        params: &[],
    },
    Signature {
        name: "pose_trans",
        min: 2,
        params: &["p_from", "p_from_to"],
    },
    Signature {
        name: "pose_inv",
        min: 1,
        params: &["p_from"],
    },
    // Conveyor tracking (a moving base's travel as the conveyor, `crate::conveyor`).
    Signature {
        name: "conveyor_pulse_decode",
        min: 3,
        params: &["type", "A", "B"],
    },
    Signature {
        name: "encoder_enable_pulse_decode",
        min: 4,
        params: &["encoder_index", "decoder_type", "A", "B"],
    },
    Signature {
        name: "track_conveyor_linear",
        min: 2,
        params: &["direction", "ticks_per_meter", "encoder_index"],
    },
    Signature {
        name: "stop_conveyor_tracking",
        min: 0,
        params: &["a"],
    },
    Signature {
        name: "end_conveyor_tracking",
        min: 0,
        params: &["a", "aRot"],
    },
    Signature {
        name: "get_standard_digital_in",
        min: 1,
        params: &["n"],
    },
];

/// Functions that command one motion target.
const MOTION: &[&str] = &["movej", "movel", "movep", "movec", "servoj"];

/// Result of linting one file.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LintReport {
    /// Motion targets (move commands).
    pub targets: usize,
    /// Calls checked.
    pub calls: usize,
    /// Problems, each "line N: …".
    pub problems: Vec<String>,
}

impl LintReport {
    pub fn ok(&self) -> bool {
        self.problems.is_empty()
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Num(f64, String),
    Str,
    Punct(char),
    /// `==`, `!=`, `<=`, `>=`
    Op2,
}

fn tokenize(line: &str) -> Result<Vec<Tok>, String> {
    let mut out = Vec::new();
    let c: Vec<char> = line.chars().collect();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch == '#' {
            break;
        }
        if ch.is_whitespace() {
            i += 1;
        } else if ch.is_ascii_alphabetic() || ch == '_' {
            let s = i;
            while i < c.len() && (c[i].is_ascii_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(c[s..i].iter().collect()));
        } else if ch.is_ascii_digit()
            || (ch == '.' && c.get(i + 1).is_some_and(char::is_ascii_digit))
        {
            let s = i;
            while i < c.len() && (c[i].is_ascii_digit() || c[i] == '.') {
                i += 1;
            }
            if i < c.len() && (c[i] == 'e' || c[i] == 'E') {
                i += 1;
                if i < c.len() && (c[i] == '+' || c[i] == '-') {
                    i += 1;
                }
                while i < c.len() && c[i].is_ascii_digit() {
                    i += 1;
                }
            }
            let text: String = c[s..i].iter().collect();
            let v: f64 = text
                .parse()
                .map_err(|_| format!("cannot read the number {text:?}"))?;
            out.push(Tok::Num(v, text));
        } else if ch == '"' || ch == '\'' {
            let q = ch;
            i += 1;
            while i < c.len() && c[i] != q {
                i += 1;
            }
            if i >= c.len() {
                return Err("unterminated string".into());
            }
            i += 1;
            out.push(Tok::Str);
        } else if "=!<>".contains(ch) && c.get(i + 1) == Some(&'=') {
            out.push(Tok::Op2);
            i += 2;
        } else if "()[],:=+-*/%<>".contains(ch) {
            out.push(Tok::Punct(ch));
            i += 1;
        } else {
            return Err(format!("unexpected character {ch:?}"));
        }
    }
    Ok(out)
}

/// A parsed expression (only what the checks need).
#[derive(Clone, Debug)]
enum Expr {
    Num(f64),
    List(Vec<Expr>),
    Pose(Vec<Expr>),
    Call,
    Other,
}

#[derive(Clone, Debug)]
struct Arg {
    name: Option<String>,
    value: Expr,
}

struct Parser<'a> {
    t: &'a [Tok],
    i: usize,
    calls: Vec<(String, Vec<Arg>)>,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.t.get(self.i)
    }
    fn punct(&self, c: char) -> bool {
        self.peek() == Some(&Tok::Punct(c))
    }
    fn expect(&mut self, c: char) -> Result<(), String> {
        if self.punct(c) {
            self.i += 1;
            Ok(())
        } else {
            Err(format!("expected {c:?}, found {:?}", self.peek()))
        }
    }

    /// expr := unary (binop unary)*
    fn expr(&mut self) -> Result<Expr, String> {
        let mut e = self.unary()?;
        loop {
            let bin = match self.peek() {
                Some(Tok::Punct(c)) if "+-*/%<>".contains(*c) => true,
                Some(Tok::Op2) => true,
                Some(Tok::Ident(k)) if k == "and" || k == "or" => true,
                _ => false,
            };
            if !bin {
                return Ok(e);
            }
            self.i += 1;
            self.unary()?;
            e = Expr::Other;
        }
    }

    fn unary(&mut self) -> Result<Expr, String> {
        match self.peek().cloned() {
            Some(Tok::Punct('-')) => {
                self.i += 1;
                Ok(match self.unary()? {
                    Expr::Num(v) => Expr::Num(-v),
                    _ => Expr::Other,
                })
            }
            Some(Tok::Punct('+')) => {
                self.i += 1;
                self.unary()
            }
            Some(Tok::Ident(k)) if k == "not" => {
                self.i += 1;
                self.unary()?;
                Ok(Expr::Other)
            }
            _ => self.atom(),
        }
    }

    fn list(&mut self, close: char) -> Result<Vec<Expr>, String> {
        let mut v = Vec::new();
        if self.punct(close) {
            self.i += 1;
            return Ok(v);
        }
        loop {
            v.push(self.expr()?);
            if self.punct(',') {
                self.i += 1;
                continue;
            }
            self.expect(close)?;
            return Ok(v);
        }
    }

    fn atom(&mut self) -> Result<Expr, String> {
        let Some(tok) = self.peek().cloned() else {
            return Err("expression expected at the end of the line".into());
        };
        self.i += 1;
        match tok {
            Tok::Num(v, text) => {
                if !v.is_finite() {
                    return Err(format!("the number {text} is not finite"));
                }
                Ok(Expr::Num(v))
            }
            Tok::Str => Ok(Expr::Other),
            Tok::Punct('(') => {
                let e = self.expr()?;
                self.expect(')')?;
                Ok(e)
            }
            Tok::Punct('[') => Ok(Expr::List(self.list(']')?)),
            Tok::Ident(name) => {
                if name == "p" && self.punct('[') {
                    self.i += 1;
                    return Ok(Expr::Pose(self.list(']')?));
                }
                if ["inf", "nan", "Infinity", "NaN"].contains(&name.as_str()) {
                    return Err(format!("{name} is not a finite number"));
                }
                let mut e = if self.punct('(') {
                    self.i += 1;
                    let args = self.args()?;
                    self.calls.push((name, args));
                    Expr::Call
                } else {
                    Expr::Other
                };
                // Indexing: x[i]
                while self.punct('[') {
                    self.i += 1;
                    self.expr()?;
                    self.expect(']')?;
                    e = Expr::Other;
                }
                Ok(e)
            }
            other => Err(format!("unexpected {other:?}")),
        }
    }

    fn args(&mut self) -> Result<Vec<Arg>, String> {
        let mut v = Vec::new();
        if self.punct(')') {
            self.i += 1;
            return Ok(v);
        }
        loop {
            let named = match (self.t.get(self.i), self.t.get(self.i + 1)) {
                (Some(Tok::Ident(n)), Some(Tok::Punct('='))) => Some(n.clone()),
                _ => None,
            };
            if named.is_some() {
                self.i += 2;
            }
            let value = self.expr()?;
            v.push(Arg { name: named, value });
            if self.punct(',') {
                self.i += 1;
                continue;
            }
            self.expect(')')?;
            return Ok(v);
        }
    }
}

fn numbers(e: &Expr) -> Option<Vec<f64>> {
    match e {
        Expr::List(v) | Expr::Pose(v) => v
            .iter()
            .map(|x| if let Expr::Num(n) = x { Some(*n) } else { None })
            .collect(),
        _ => None,
    }
}

/// Check one call against the table and the controller's ranges.
fn check_call(
    name: &str,
    args: &[Arg],
    defined: &HashSet<String>,
    problems: &mut Vec<String>,
    ln: usize,
    limits: &[[f64; 2]; 6],
) {
    let Some(sig) = SIGNATURES.iter().find(|s| s.name == name) else {
        if !defined.contains(name) {
            problems.push(format!("line {ln}: unknown function {name}()"));
        }
        return;
    };
    // Bind positional then keyword arguments to parameters.
    let mut bound: Vec<Option<&Expr>> = vec![None; sig.params.len()];
    let mut pos = 0usize;
    for a in args {
        match &a.name {
            None => {
                if pos >= sig.params.len() {
                    problems.push(format!(
                        "line {ln}: {name}() takes at most {} arguments, got {}",
                        sig.params.len(),
                        args.len()
                    ));
                    return;
                }
                bound[pos] = Some(&a.value);
                pos += 1;
            }
            Some(k) => match sig.params.iter().position(|p| p == k) {
                Some(i) if bound[i].is_none() => bound[i] = Some(&a.value),
                Some(_) => {
                    problems.push(format!("line {ln}: {name}(): argument {k} given twice"));
                    return;
                }
                None => {
                    problems.push(format!(
                        "line {ln}: {name}() has no parameter {k} (it takes {})",
                        sig.params.join(", ")
                    ));
                    return;
                }
            },
        }
    }
    if let Some(missing) = (0..sig.min).find(|&i| bound[i].is_none()) {
        problems.push(format!(
            "line {ln}: {name}() needs at least {} arguments ({} missing)",
            sig.min, sig.params[missing]
        ));
        return;
    }
    let num = |i: usize| match bound.get(i).copied().flatten() {
        Some(Expr::Num(v)) => Some(*v),
        _ => None,
    };
    match name {
        "movej" | "servoj" => {
            if let Some(e) = bound[0]
                && let Some(q) = numbers(e)
            {
                if q.len() != 6 {
                    problems.push(format!(
                        "line {ln}: {name}() joint target has {} values, expected 6",
                        q.len()
                    ));
                } else if matches!(e, Expr::List(_)) {
                    for j in 0..6 {
                        // 1e-9 rad: the writer's 9 decimals.
                        let [lo, hi] = limits[j];
                        if q[j] < lo - 1e-9 || q[j] > hi + 1e-9 {
                            problems.push(format!(
                                "line {ln}: {name}() joint {} = {:.6} rad is beyond its limits [{lo:.4}, {hi:.4}]",
                                j + 1,
                                q[j]
                            ));
                        }
                    }
                }
            }
        }
        "movel" | "movep" | "set_tcp" => {
            if let Some(e @ (Expr::Pose(_) | Expr::List(_))) = bound[0]
                && let Some(p) = numbers(e)
                && p.len() != 6
            {
                problems.push(format!(
                    "line {ln}: {name}() pose has {} values, expected 6",
                    p.len()
                ));
            }
        }
        "set_standard_analog_out" | "set_analog_outputdomain" => {
            if let Some(n) = num(0)
                && !(n == 0.0 || n == 1.0)
            {
                problems.push(format!(
                    "line {ln}: {name}(): analog output {n} does not exist (the controller has 0 and 1)"
                ));
            }
            if name == "set_standard_analog_out"
                && let Some(f) = num(1)
                && !(0.0..=1.0).contains(&f)
            {
                problems.push(format!(
                    "line {ln}: {name}(): value {f} is outside 0..1 (a ratio of the output range)"
                ));
            }
            if name == "set_analog_outputdomain"
                && let Some(d) = num(1)
                && !(d == 0.0 || d == 1.0)
            {
                problems.push(format!(
                    "line {ln}: {name}(): domain {d} (0 = current, 1 = voltage)"
                ));
            }
        }
        "set_standard_digital_out" | "set_configurable_digital_out" | "set_tool_digital_out" => {
            let max = if name == "set_tool_digital_out" {
                1.0
            } else {
                7.0
            };
            if let Some(n) = num(0)
                && !(n >= 0.0 && n <= max && n.fract() == 0.0)
            {
                problems.push(format!(
                    "line {ln}: {name}(): output {n} does not exist (0..={max})"
                ));
            }
        }
        "conveyor_pulse_decode" => {
            if let Some(t) = num(0)
                && !(t.fract() == 0.0 && (0.0..=4.0).contains(&t))
            {
                problems.push(format!(
                    "line {ln}: conveyor_pulse_decode(): type {t} (0 off, 1 quadrature, 2–4 single-input edges)"
                ));
            }
            for i in [1, 2] {
                if let Some(n) = num(i)
                    && !(n.fract() == 0.0 && (0.0..=3.0).contains(&n))
                {
                    problems.push(format!(
                        "line {ln}: conveyor_pulse_decode(): encoder input {n} does not exist (digital inputs 0–3)"
                    ));
                }
            }
        }
        "track_conveyor_linear" => {
            if let Some(e) = bound[0]
                && let Some(p) = numbers(e)
            {
                let len = if p.len() == 6 {
                    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
                } else {
                    0.0
                };
                // 1e-6: the writer's 9 decimals on a unit vector.
                if p.len() != 6 || (len - 1.0).abs() > 1e-6 || p[3..].iter().any(|v| *v != 0.0) {
                    problems.push(format!(
                        "line {ln}: track_conveyor_linear(): direction {p:?} must be p[x, y, z, 0, 0, 0] with a unit (x, y, z)"
                    ));
                }
            }
            if let Some(t) = num(1)
                && t <= 0.0
            {
                problems.push(format!(
                    "line {ln}: track_conveyor_linear(): ticks_per_meter {t} must be > 0"
                ));
            }
        }
        "get_standard_digital_in" => {
            if let Some(n) = num(0)
                && !(n.fract() == 0.0 && (0.0..=7.0).contains(&n))
            {
                problems.push(format!(
                    "line {ln}: get_standard_digital_in(): input {n} does not exist (0..=7)"
                ));
            }
        }
        "sleep" => {
            if let Some(t) = num(0)
                && t < 0.0
            {
                problems.push(format!("line {ln}: sleep({t}) is negative"));
            }
        }
        _ => {}
    }
    // Speeds, accelerations, blend radii and times must be ≥ 0 where given as numbers.
    for (i, p) in sig.params.iter().enumerate() {
        if ["a", "v", "r", "t"].contains(p)
            && let Some(v) = num(i)
            && v < 0.0
        {
            problems.push(format!("line {ln}: {name}(): {p} = {v} is negative"));
        }
    }
}

/// Lint a URScript program against the UR10e joint limits; `max_targets` is the per-file
/// motion target limit.
pub fn lint(text: &str, max_targets: usize) -> LintReport {
    lint_with_limits(
        text,
        max_targets,
        &crate::setup::JointLimitOptions::default().position(),
    )
}

/// [`lint`] with joint position limits `limits` (rad, `[min, max]` per joint): `movej` and
/// `servoj` joint targets outside them are rejected.
pub fn lint_with_limits(text: &str, max_targets: usize, limits: &[[f64; 2]; 6]) -> LintReport {
    let mut rep = LintReport::default();
    let mut problems = Vec::new();
    // Pass 1: the functions the file defines.
    let mut defined = HashSet::new();
    for line in text.lines() {
        if let Ok(t) = tokenize(line)
            && let [Tok::Ident(k), Tok::Ident(name), ..] = t.as_slice()
            && (k == "def" || k == "thread")
        {
            defined.insert(name.clone());
        }
    }
    let mut stack: Vec<(&str, usize)> = Vec::new();
    let mut called_top = HashSet::new();
    let mut called_any = HashSet::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let toks = match tokenize(line) {
            Ok(t) => t,
            Err(e) => {
                problems.push(format!("line {ln}: {e}"));
                continue;
            }
        };
        let Some(first) = toks.first() else { continue };
        let kw = if let Tok::Ident(k) = first {
            k.as_str()
        } else {
            ""
        };
        let mut p = Parser {
            t: &toks,
            i: 0,
            calls: Vec::new(),
        };
        let res: Result<(), String> = (|| {
            match kw {
                "def" | "thread" => {
                    p.i = 1;
                    match p.peek() {
                        Some(Tok::Ident(_)) => p.i += 1,
                        _ => return Err(format!("{kw} needs a name")),
                    }
                    p.expect('(')?;
                    while !p.punct(')') {
                        if p.peek().is_none() {
                            return Err("unterminated parameter list".into());
                        }
                        p.i += 1;
                    }
                    p.i += 1;
                    p.expect(':')?;
                    stack.push((if kw == "def" { "def" } else { "thread" }, ln));
                }
                "if" | "while" | "elif" => {
                    p.i = 1;
                    p.expr()?;
                    p.expect(':')?;
                    if kw == "elif" {
                        if stack.last().map(|s| s.0) != Some("if") {
                            return Err("elif without if".into());
                        }
                    } else {
                        stack.push((if kw == "if" { "if" } else { "while" }, ln));
                    }
                }
                "else" => {
                    p.i = 1;
                    p.expect(':')?;
                    if stack.last().map(|s| s.0) != Some("if") {
                        return Err("else without if".into());
                    }
                }
                "end" => {
                    p.i = 1;
                    if stack.pop().is_none() {
                        return Err("end without an open block".into());
                    }
                }
                "halt" | "break" | "continue" => p.i = 1,
                "return" => {
                    p.i = 1;
                    if p.peek().is_some() {
                        p.expr()?;
                    }
                }
                _ => {
                    if matches!(kw, "global" | "local") {
                        p.i = 1;
                    }
                    // assignment `x = expr`, `x[i] = expr`, or an expression statement
                    if matches!(p.t.get(p.i), Some(Tok::Ident(_))) {
                        // `name =` or `name[…] =` is an assignment target.
                        let mut j = p.i + 1;
                        if toks.get(j) == Some(&Tok::Punct('[')) {
                            let mut depth = 0i32;
                            while let Some(t) = toks.get(j) {
                                match t {
                                    Tok::Punct('[') => depth += 1,
                                    Tok::Punct(']') => depth -= 1,
                                    _ => {}
                                }
                                j += 1;
                                if depth == 0 {
                                    break;
                                }
                            }
                        }
                        if toks.get(j) == Some(&Tok::Punct('=')) {
                            p.i = j + 1;
                        }
                    }
                    p.expr()?;
                    if stack.is_empty()
                        && let Tok::Ident(n) = &toks[0]
                    {
                        called_top.insert(n.clone());
                    }
                }
            }
            if p.i != toks.len() {
                return Err(format!("unexpected {:?} after the statement", toks[p.i]));
            }
            Ok(())
        })();
        if let Err(e) = res {
            problems.push(format!("line {ln}: {e}"));
        }
        for (name, args) in &p.calls {
            called_any.insert(name.clone());
            rep.calls += 1;
            if MOTION.contains(&name.as_str()) {
                rep.targets += 1;
            }
            check_call(name, args, &defined, &mut problems, ln, limits);
        }
    }
    for (kind, ln) in &stack {
        problems.push(format!("line {ln}: {kind} block is never closed with end"));
    }
    if !text.lines().any(|l| l.trim_start().starts_with("def ")) {
        problems.push("the file defines no program (def name(): … end)".into());
    }
    for name in &defined {
        let is_thread = text
            .lines()
            .any(|l| l.trim_start().starts_with(&format!("thread {name}")));
        if !is_thread && !called_any.contains(name) {
            problems.push(format!("{name} is defined but never called"));
        }
    }
    if !defined.iter().any(|n| called_top.contains(n)) {
        problems.push(
            "no defined program is called at the top level (the controller would run nothing)"
                .into(),
        );
    }
    if rep.targets > max_targets {
        problems.push(format!(
            "{} motion targets, more than the limit {max_targets}",
            rep.targets
        ));
    }
    // A moving-base program (conveyor tracking) has its own form (`crate::conveyor`).
    if uses_tracking(text) {
        problems.extend(tracking_form_problems(text));
    }
    crate::error::shorten(&mut problems, 50);
    rep.problems = problems;
    rep
}

// The conveyor-tracking form: the writer of those programs is `crate::conveyor`, which stands
// above the checker (the checker uses nothing of the writer).

/// `name(` called on line `l` (not part of a longer identifier), outside comments.
fn calls(l: &str, name: &str) -> bool {
    let code = l.split('#').next().unwrap_or("");
    code.match_indices(name).any(|(i, _)| {
        let before = code[..i].chars().last();
        let after = code[i + name.len()..].trim_start().chars().next();
        !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') && after == Some('(')
    })
}

const TRACKING_CALLS: &[&str] = &[
    "conveyor_pulse_decode",
    "encoder_enable_pulse_decode",
    "track_conveyor_linear",
    "stop_conveyor_tracking",
    "end_conveyor_tracking",
];

/// Whether a program uses conveyor tracking at all (then [`lint_with_limits`] applies
/// [`tracking_form_problems`]).
pub fn uses_tracking(text: &str) -> bool {
    text.lines()
        .any(|l| TRACKING_CALLS.iter().any(|n| calls(l, n)))
}

/// The tracking form of a program (see [`lint_tracking`]), as problems.
pub fn tracking_form_problems(text: &str) -> Vec<String> {
    let mut problems = Vec::new();
    let mut decoder = false;
    let mut tracking: Option<usize> = None;
    let mut tracked_moves = 0usize;
    for (i, l) in text.lines().enumerate() {
        let ln = i + 1;
        if calls(l, "conveyor_pulse_decode") || calls(l, "encoder_enable_pulse_decode") {
            decoder = true;
        }
        if calls(l, "track_conveyor_linear") {
            if !decoder {
                problems.push(format!(
                    "line {ln}: track_conveyor_linear() before the encoder is set up (conveyor_pulse_decode)"
                ));
            }
            if let Some(s) = tracking {
                problems.push(format!(
                    "line {ln}: track_conveyor_linear() while already tracking (since line {s})"
                ));
            }
            tracking = Some(ln);
        }
        if tracking.is_some() && (calls(l, "movej") || calls(l, "servoj")) {
            problems.push(format!(
                "line {ln}: a joint target while tracking the base (joint targets hold only at the base pose they were planned for)"
            ));
        }
        if tracking.is_some() && (calls(l, "movep") || calls(l, "movel") || calls(l, "movec")) {
            tracked_moves += 1;
        }
        if calls(l, "stop_conveyor_tracking") || calls(l, "end_conveyor_tracking") {
            if tracking.is_none() {
                problems.push(format!("line {ln}: tracking stopped but never started"));
            }
            tracking = None;
        }
    }
    if let Some(s) = tracking {
        problems.push(format!(
            "tracking started on line {s} is never stopped (stop_conveyor_tracking) before the program ends"
        ));
    }
    if tracked_moves == 0 {
        problems.push(
            "no motion target while tracking the base: not a conveyor-tracking program".into(),
        );
    }
    problems
}

/// Lint a conveyor-tracking program: [`lint_with_limits`] (which knows the conveyor
/// functions' signatures and ranges, and applies the tracking form below to any program that
/// uses tracking) plus: the program must track. The tracking form:
///
/// - `track_conveyor_linear` only after a decoder is set up (`conveyor_pulse_decode` or
///   `encoder_enable_pulse_decode`) and never while already tracking;
/// - no joint target (`movej`, `servoj`) while tracking: a joint target is valid only at the
///   base pose it was planned for;
/// - tracking stopped (`stop_conveyor_tracking` / `end_conveyor_tracking`) before the program
///   ends, and never stopped when not tracking;
/// - at least one tracked motion target.
pub fn lint_tracking(text: &str, max_targets: usize, limits: &[[f64; 2]; 6]) -> LintReport {
    let mut rep = lint_with_limits(text, max_targets, limits);
    if !uses_tracking(text) {
        rep.problems.extend(tracking_form_problems(text));
    }
    rep
}
