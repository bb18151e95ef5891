//! (work in progress)
//!
//! NOTE TO THE CEM ENGINEER (from the lead; delete this note when you replace this file):
//! several engineers work in this same checkout at once. Before anything else read
//! /tmp/team_rules.md (how to build, commit only your paths, keep the workspace compiling),
//! and the full issue texts /tmp/issue2.md and /tmp/issue3.md (your two issues).
