//! Joining the shards of one study (`kappe study merge`): they must come from the same study
//! (same fingerprint and design list), hold every design at most once and, unless allowed,
//! together hold every design. The merged result's files equal those of an unsharded run.

use std::collections::BTreeMap;

use super::{RESULT_FORMAT, Record, StudyError, StudyResult};

/// A merged study: the result, and for every row the shard it came from (an index into the
/// `parts` given to [`merge`]), to copy its `designs/<name>/` from.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The merged result (`shard` is `None`).
    pub result: StudyResult,
    /// Per row of `result.rows`, the index of its shard in `parts`.
    pub sources: Vec<usize>,
}

/// Merges `parts` (a label for messages, e.g. the directory, and the shard's result).
///
/// # Errors
/// No parts, parts of different studies, a design in two parts, a design whose index another
/// design has, or missing designs without `allow_incomplete`.
pub fn merge(
    parts: &[(String, StudyResult)],
    allow_incomplete: bool,
) -> Result<Merged, StudyError> {
    let bail = |m: String| Err(StudyError::Merge(m));
    let Some((first_label, first)) = parts.first() else {
        return bail("give at least one shard directory".into());
    };
    let mut rows: BTreeMap<usize, (&Record, usize)> = BTreeMap::new();
    for (k, (label, r)) in parts.iter().enumerate() {
        if r.fingerprint != first.fingerprint || r.designs != first.designs {
            return bail(format!(
                "{first_label} and {label} are results of different studies (fingerprints {} and {})",
                first.fingerprint, r.fingerprint
            ));
        }
        for row in &r.rows {
            if first.designs.get(row.index) != Some(&row.name) {
                return bail(format!(
                    "{label}: design `{}` has index {}, which the study gives to another design",
                    row.name, row.index
                ));
            }
            if let Some((_, other)) = rows.insert(row.index, (row, k)) {
                return bail(format!(
                    "design `{}` is in both {} and {label}; give every shard once",
                    row.name, parts[other].0
                ));
            }
        }
    }
    let missing: Vec<&str> = first
        .designs
        .iter()
        .enumerate()
        .filter(|(i, _)| !rows.contains_key(i))
        .map(|(_, n)| n.as_str())
        .collect();
    if !missing.is_empty() && !allow_incomplete {
        let shown: Vec<&str> = missing.iter().take(10).copied().collect();
        return bail(format!(
            "{} of {} designs are missing from the shards given (e.g. {}); pass every shard, \
             or --allow-incomplete",
            missing.len(),
            first.designs.len(),
            shown.join(", ")
        ));
    }
    Ok(Merged {
        result: StudyResult {
            format: RESULT_FORMAT.into(),
            version: 1,
            title: first.title.clone(),
            fingerprint: first.fingerprint.clone(),
            designs: first.designs.clone(),
            shard: None,
            parameters: first.parameters.clone(),
            rows: rows.values().map(|(r, _)| (*r).clone()).collect(),
        },
        sources: rows.values().map(|(_, k)| *k).collect(),
    })
}
