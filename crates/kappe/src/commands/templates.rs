//! The commented example files `kappe init --kind K` writes, one per input format. Each is
//! reproduced verbatim in its page under `docs/formats/` and run by the CLI tests, so the
//! examples, the docs and the readers cannot drift apart.

/// The kinds of example file, with the text `kappe init --kind` writes.
pub const KINDS: [(&str, &str); 8] = [
    ("design", crate::input::design::EXAMPLE_TOML),
    ("study", STUDY_TOML),
    ("prototypes", PROTOTYPES_TOML),
    ("optimize", OPTIMIZE_TOML),
    ("buildability", crate::commands::buildability::EXAMPLE_TOML),
    ("ceiling", crate::commands::ceiling::EXAMPLE_TOML),
    ("moving", MOVING_TOML),
    ("corrugated", CORRUGATED_TOML),
];

/// A design study (`kappe study`): a 2 × 2 grid of short caps.
pub const STUDY_TOML: &str = include_str!("templates/study.toml");
/// Printed prototypes for `kappe calibrate`.
pub const PROTOTYPES_TOML: &str = include_str!("templates/prototypes.toml");
/// The design loop (`kappe optimize`).
pub const OPTIMIZE_TOML: &str = include_str!("templates/optimize.toml");

/// A design printed in one take while the base moves (issue 27): a 1.5 m × 4 m bay.
pub const MOVING_TOML: &str = include_str!("templates/moving.toml");

/// The default cap with a corrugated centre section (issue 26, `docs/corrugation.md`).
pub const CORRUGATED_TOML: &str = include_str!("templates/corrugated.toml");

/// The example text of `kind`, if it is one of [`KINDS`].
///
/// ```
/// assert!(kappe::commands::templates::example("study").unwrap().contains("[grid]"));
/// assert!(kappe::commands::templates::example("nonsense").is_none());
/// ```
pub fn example(kind: &str) -> Option<&'static str> {
    KINDS.iter().find(|(k, _)| *k == kind).map(|(_, t)| *t)
}
