//! Reading a study file: the base design, the `[grid]` or `[[design]]` entries, names and the
//! fingerprint (see the [module docs](super)).

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::{Study, StudyError, Variation};

/// Results of this module: a [`StudyError::File`] (or [`StudyError::Shard`]) naming the entry.
type Result<T, E = StudyError> = std::result::Result<T, E>;

/// `bail!` of the study file: returns a [`StudyError::File`].
macro_rules! bail {
    ($($t:tt)*) => {
        return Err(StudyError::File(format!($($t)*)))
    };
}

/// Prefixes an error's message with where it happened (what `anyhow::Context` did in the CLI).
trait Context<T> {
    fn context(self, what: &str) -> Result<T>;
    fn with_context(self, what: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: std::fmt::Display> Context<T> for std::result::Result<T, E> {
    fn context(self, what: &str) -> Result<T> {
        self.map_err(|e| StudyError::File(format!("{what}: {e}")))
    }
    fn with_context(self, what: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| StudyError::File(format!("{}: {e}", what())))
    }
}

/// Flattens nested tables into dotted paths, so that `"cap.span" = 1` and `cap.span = 1` (or
/// `[cap] span = 1`) are the same override.
fn flatten(prefix: &str, table: &toml::Table, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in table {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(t) => flatten(&path, t, out),
            other => out.push((path, other.clone())),
        }
    }
}

/// Sets `path` (dotted; a key containing a dot is split) in `table`.
fn set_path(table: &mut toml::Table, path: &str, value: toml::Value) -> Result<()> {
    let parts: Vec<&str> = path.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        bail!("`{path}` is not a parameter path (expected e.g. `cap.span`)");
    }
    let Some((leaf, parents)) = parts.split_last() else {
        bail!("empty parameter path");
    };
    let mut cur = table;
    for (i, part) in parents.iter().enumerate() {
        let entry = cur
            .entry((*part).to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => bail!(
                "`{path}`: `{}` is a value, not a section of the design file",
                parts[..=i].join(".")
            ),
        };
    }
    cur.insert((*leaf).to_string(), value);
    Ok(())
}

/// Looks a dotted path up in a table.
pub fn get_path<'a>(table: &'a toml::Table, path: &str) -> Option<&'a toml::Value> {
    let mut parts = path.split('.');
    let mut cur = table.get(parts.next()?)?;
    for part in parts {
        cur = cur.as_table()?.get(part)?;
    }
    Some(cur)
}

/// A value as the user reads it: strings without quotes.
pub fn show(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Design names become directory names and links: keep them to a portable character set.
fn check_name(name: &str) -> std::result::Result<(), String> {
    let ok_char = |c: char| c.is_ascii_alphanumeric() || "._+=-".contains(c);
    if name.is_empty() {
        return Err("the name is empty".into());
    }
    if name.len() > 120 {
        return Err(format!(
            "the name has {} characters; at most 120",
            name.len()
        ));
    }
    if name.starts_with('.') || !name.chars().all(ok_char) {
        return Err(format!(
            "`{name}` is not a portable directory name: use letters, digits and . _ + = - \
             (not starting with a dot)"
        ));
    }
    Ok(())
}

/// The part of a grid value that goes into a design name.
fn name_part(value: &toml::Value) -> String {
    show(value)
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._+-".contains(c) {
                c
            } else {
                '-'
            }
        })
        .collect()
}

/// FNV-1a, 64 bit (see the module docs for why not std's hasher).
fn fnv1a(bytes: &[u8], mut hash: u64) -> u64 {
    for b in bytes {
        hash ^= u64::from(*b);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

/// Parses a design table: `Ok(Ok(design))`, `Ok(Err(reason))` for a value out of range (the
/// design fails, the study goes on), `Err` for a schema error (unknown field, wrong type: the
/// study file is wrong).
fn parse_design(table: &toml::Table) -> Result<std::result::Result<crate::Design, String>> {
    let text = toml::to_string(table).context("cannot write the design as TOML")?;
    match crate::Design::from_toml_str(&text) {
        Ok(d) => Ok(Ok(d)),
        Err(e @ crate::DesignError::Parse { .. }) => Err(StudyError::File(e.to_string())),
        Err(e) => Ok(Err(e.to_string())),
    }
}

/// Reads the base design table.
fn base_table(doc: &toml::Table, study_dir: &Path) -> Result<toml::Table> {
    let table = match doc.get("base") {
        None => toml::Table::new(),
        Some(toml::Value::Table(t)) => t.clone(),
        Some(toml::Value::String(file)) => {
            let path = study_dir.join(file);
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("cannot read the base design {}", path.display()))?;
            text.parse::<toml::Table>()
                .with_context(|| format!("the base design {} is not valid TOML", path.display()))?
        }
        Some(other) => bail!(
            "`base` must be a design file name or a [base] table, not a {}",
            other.type_str()
        ),
    };
    // Only schema errors matter here: a base out of range may be made valid by the overrides.
    // No base at all means the defaults (a design file that sets nothing is an error, a study
    // without a base is not).
    if !table.is_empty() {
        let _range_checked_per_design = parse_design(&table)
            .context("the base design does not match the design file schema")?;
    }
    Ok(table)
}

/// Parses and validates a study file's text (`source` names it in messages and is the default
/// title; `study_dir` resolves `base = "file"`).
pub fn parse(text: &str, source: &str, study_dir: &Path) -> Result<Study> {
    let doc: toml::Table = text.parse().context("the study file is not valid TOML")?;
    for key in doc.keys() {
        if !["title", "base", "grid", "design", "analysis"].contains(&key.as_str()) {
            bail!(
                "unknown key `{key}` in the study file; allowed: title, base, grid (a table), \
                 design (a [[design]] list), analysis (a table)"
            );
        }
    }
    let title = match doc.get("title") {
        None => source.to_string(),
        Some(toml::Value::String(s)) => s.clone(),
        Some(other) => bail!("`title` must be a string, not a {}", other.type_str()),
    };
    let mut base = base_table(&doc, study_dir)?;
    let analysis = match doc.get("analysis") {
        None => None,
        Some(v) => {
            let o: crate::analysis::AnalysisOptions =
                v.clone().try_into().map_err(|e: toml::de::Error| {
                    StudyError::File(format!("[analysis]: {}", e.message()))
                })?;
            o.validate().context("[analysis]")?;
            // Every design carries the study's analysis (it replaces a base's own), so its
            // `design.toml` run alone by `kappe design` is analysed, and judged, the same way.
            base.insert("analysis".into(), v.clone());
            Some(o)
        }
    };

    // (name, overrides) in study order, and the parameter columns.
    let (parameters, entries): Entries = match (doc.get("grid"), doc.get("design")) {
        (Some(_), Some(_)) => {
            bail!("the study file has both [grid] and [[design]]; give one of them")
        }
        (None, None) => {
            bail!("the study file has neither a [grid] table nor a [[design]] list: nothing to run")
        }
        (Some(grid), None) => grid_entries(grid, &base)?,
        (None, Some(list)) => list_entries(list, &base)?,
    };

    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (i, (name, _)) in entries.iter().enumerate() {
        check_name(name)
            .map_err(|e| StudyError::File(format!("design #{} (`{name}`): {e}", i + 1)))?;
        if let Some(first) = seen.insert(name.as_str(), i) {
            bail!(
                "duplicate design name `{name}` (designs #{} and #{}); design names must be unique",
                first + 1,
                i + 1
            );
        }
    }

    let mut hash = 0xcbf2_9ce4_8422_2325_u64;
    let options = serde_json::to_string(&analysis).unwrap_or_default();
    hash = fnv1a(options.as_bytes(), hash);
    let mut variations = Vec::with_capacity(entries.len());
    for (index, (name, overrides)) in entries.into_iter().enumerate() {
        let mut table = base.clone();
        for (path, value) in overrides {
            set_path(&mut table, &path, value)
                .with_context(|| format!("design `{name}`: cannot apply `{path}`"))?;
        }
        table.insert("name".into(), toml::Value::String(name.clone()));
        let design = parse_design(&table)
            .with_context(|| format!("design `{name}`: unknown parameter or wrong type"))?;
        let text = toml::to_string(&table).unwrap_or_default();
        hash = fnv1a(text.as_bytes(), fnv1a(name.as_bytes(), hash));
        variations.push(Variation {
            index,
            name,
            table,
            design,
        });
    }
    Ok(Study {
        title,
        parameters,
        variations,
        fingerprint: format!("{hash:016x}"),
        analysis,
    })
}

/// Checks one override path against the design schema: applied alone to the base, it must
/// parse (a range error is fine here: other overrides may make the design valid).
fn check_override(base: &toml::Table, path: &str, value: &toml::Value) -> Result<()> {
    if path == "name" || path == "base" {
        bail!("`{path}` is set by the study, not a design parameter");
    }
    let mut table = base.clone();
    set_path(&mut table, path, value.clone())?;
    parse_design(&table).map(|_| ())
}

type Entries = (Vec<String>, Vec<(String, Vec<(String, toml::Value)>)>);

fn grid_entries(grid: &toml::Value, base: &toml::Table) -> Result<Entries> {
    let toml::Value::Table(grid) = grid else {
        bail!("`grid` must be a table of parameter = [values]");
    };
    let mut axes = Vec::new();
    flatten("", grid, &mut axes);
    if axes.is_empty() {
        bail!(
            "the [grid] table is empty: give at least one parameter with a list of values, e.g. \"cap.span\" = [0.6, 0.8]"
        );
    }
    // Alphabetical by path, whatever the TOML map's order, so the study order is defined.
    axes.sort_by(|a, b| a.0.cmp(&b.0));
    let mut lists: Vec<(String, Vec<toml::Value>)> = Vec::new();
    for (path, value) in axes {
        let toml::Value::Array(values) = value else {
            bail!(
                "grid entry `{path}`: expected a list of values, e.g. [0.6, 0.8], got a {}",
                value.type_str()
            );
        };
        if values.is_empty() {
            bail!("grid entry `{path}` is an empty list: give at least one value");
        }
        let mut shown = HashSet::new();
        for v in &values {
            if !shown.insert(name_part(v)) {
                bail!("grid entry `{path}` lists the value {} twice", show(v));
            }
            check_override(base, &path, v)
                .with_context(|| format!("grid entry `{path}` = {}", show(v)))?;
        }
        lists.push((path, values));
    }
    // Name parts: the last path segment, unless two axes share it.
    let last = |p: &str| p.rsplit('.').next().unwrap_or(p).to_string();
    let lasts: Vec<String> = lists.iter().map(|(p, _)| last(p)).collect();
    let labels: Vec<String> = lists
        .iter()
        .map(|(p, _)| {
            if lasts.iter().filter(|l| **l == last(p)).count() > 1 {
                p.clone()
            } else {
                last(p)
            }
        })
        .collect();
    let total: usize = lists.iter().map(|(_, v)| v.len()).product();
    const MAX_DESIGNS: usize = 1_000_000;
    if total > MAX_DESIGNS {
        bail!(
            "the grid has {total} designs; at most {MAX_DESIGNS} (split it into several studies)"
        );
    }
    let mut entries = Vec::with_capacity(total);
    for k in 0..total {
        // Mixed radix, last axis fastest.
        let mut rest = k;
        let mut picks = vec![0usize; lists.len()];
        for (a, (_, values)) in lists.iter().enumerate().rev() {
            picks[a] = rest % values.len();
            rest /= values.len();
        }
        let mut overrides = Vec::with_capacity(lists.len());
        let mut name_parts = Vec::with_capacity(lists.len());
        for (a, (path, values)) in lists.iter().enumerate() {
            let v = &values[picks[a]];
            name_parts.push(format!("{}={}", labels[a], name_part(v)));
            overrides.push((path.clone(), v.clone()));
        }
        entries.push((name_parts.join("_"), overrides));
    }
    Ok((lists.into_iter().map(|(p, _)| p).collect(), entries))
}

fn list_entries(list: &toml::Value, base: &toml::Table) -> Result<Entries> {
    let toml::Value::Array(list) = list else {
        bail!("`design` must be a [[design]] list of tables");
    };
    if list.is_empty() {
        bail!("the [[design]] list is empty: nothing to run");
    }
    let mut parameters: Vec<String> = Vec::new();
    let mut entries = Vec::with_capacity(list.len());
    for (i, item) in list.iter().enumerate() {
        let toml::Value::Table(t) = item else {
            bail!("[[design]] #{}: expected a table", i + 1);
        };
        let name = match t.get("name") {
            Some(toml::Value::String(s)) => s.clone(),
            Some(other) => bail!(
                "[[design]] #{}: `name` must be a string, not a {}",
                i + 1,
                other.type_str()
            ),
            None => bail!("[[design]] #{}: every design needs a `name`", i + 1),
        };
        let mut rest = t.clone();
        rest.remove("name");
        let mut overrides = Vec::new();
        flatten("", &rest, &mut overrides);
        for (path, value) in &overrides {
            check_override(base, path, value)
                .with_context(|| format!("[[design]] #{} (`{name}`): `{path}`", i + 1))?;
            if !parameters.contains(path) {
                parameters.push(path.clone());
            }
        }
        entries.push((name, overrides));
    }
    Ok((parameters, entries))
}

/// `i/n` with 0 ≤ i < n.
pub fn parse_shard(spec: &str) -> Result<(usize, usize)> {
    let bad = || {
        StudyError::Shard(format!(
            "--shard `{spec}`: expected i/n with whole numbers 0 ≤ i < n (0-based shard i of n), \
             e.g. 0/4"
        ))
    };
    let (i, n) = spec.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if n == 0 {
        return Err(StudyError::Shard(format!(
            "--shard `{spec}`: the shard count n must be at least 1"
        )));
    }
    if i >= n {
        return Err(StudyError::Shard(format!(
            "--shard `{spec}`: the shard index must be below the count (0-based: 0..={})",
            n - 1
        )));
    }
    Ok((i, n))
}

/// The shard of this task of a Slurm job array (`kappe study --shard` without `i/n`):
/// i = `SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN` (0 when unset), n =
/// `SLURM_ARRAY_TASK_COUNT`. `var` reads a variable (`std::env::var(..).ok()` in the
/// command; a map in tests).
pub fn slurm_shard(var: impl Fn(&str) -> Option<String>) -> Result<(usize, usize)> {
    let number = |k: &str| -> Result<Option<usize>> {
        match var(k) {
            None => Ok(None),
            Some(v) => v.trim().parse().map(Some).map_err(|_| {
                StudyError::Shard(format!("--shard: {k}={v:?} is not a whole number"))
            }),
        }
    };
    let (Some(id), Some(count)) = (
        number("SLURM_ARRAY_TASK_ID")?,
        number("SLURM_ARRAY_TASK_COUNT")?,
    ) else {
        return Err(StudyError::Shard(
            "--shard without i/n needs SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT (a Slurm job \
             array); give --shard i/n otherwise"
                .into(),
        ));
    };
    let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
    let Some(i) = id.checked_sub(min) else {
        return Err(StudyError::Shard(format!(
            "--shard: SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}"
        )));
    };
    if count > 0 && i >= count {
        return Err(StudyError::Shard(format!(
            "--shard: SLURM_ARRAY_TASK_ID={id} − SLURM_ARRAY_TASK_MIN={min} = {i} is not below \
             SLURM_ARRAY_TASK_COUNT={count} (an array of {count} tasks has the shards 0..={})",
            count - 1
        )));
    }
    parse_shard(&format!("{i}/{count}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            vars.iter()
                .find(|(name, _)| *name == k)
                .map(|(_, v)| (*v).to_string())
        }
    }

    #[test]
    fn slurm_shard_is_id_minus_min_of_count() {
        let id_min_count = [
            ("SLURM_ARRAY_TASK_ID", "7"),
            ("SLURM_ARRAY_TASK_MIN", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert_eq!(slurm_shard(env(&id_min_count)).ok(), Some((2, 4)));
        let no_min = [
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert_eq!(slurm_shard(env(&no_min)).ok(), Some((3, 4)));
        // The last task of `--array=5-8` is shard 3 of 4; one more is outside the array.
        let last = [
            ("SLURM_ARRAY_TASK_ID", "8"),
            ("SLURM_ARRAY_TASK_MIN", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert_eq!(slurm_shard(env(&last)).ok(), Some((3, 4)));
        for bad in [
            &[
                ("SLURM_ARRAY_TASK_ID", "9"),
                ("SLURM_ARRAY_TASK_MIN", "5"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ][..],
            &[
                ("SLURM_ARRAY_TASK_ID", "4"),
                ("SLURM_ARRAY_TASK_MIN", "5"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ][..],
            &[
                ("SLURM_ARRAY_TASK_ID", "-1"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ][..],
            &[("SLURM_ARRAY_TASK_COUNT", "4")][..],
            &[][..],
        ] {
            assert!(
                matches!(slurm_shard(env(bad)), Err(StudyError::Shard(_))),
                "{bad:?}"
            );
        }
    }
}
