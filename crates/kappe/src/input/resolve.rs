//! The one "inline table or relative path" of the input files: a prototype's design, an
//! optimize file's start design, a print calibration's buildability spec (and, as a TOML
//! table, a study's base design) are each given inline or as a path relative to the file that
//! names them.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// A `T` given inline or by a path relative to the naming file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Source<T> {
    /// Path of the file, relative to the naming file's directory.
    Path(String),
    /// The value inline.
    Inline(Box<T>),
}

/// Why a [`Source`] could not be had.
#[derive(Debug, thiserror::Error)]
pub enum ResolveError<E: std::error::Error + 'static> {
    /// The file cannot be read.
    #[error("cannot read {}", path.display())]
    Read {
        /// The file, joined to the naming file's directory.
        path: PathBuf,
        /// What reading it said.
        #[source]
        source: std::io::Error,
    },
    /// The file (`path` set) or the inline value (`path` None) is not valid.
    #[error("{}", path.as_ref().map_or("the inline table is not valid".to_string(), |p| format!("{} is not valid", p.display())))]
    Invalid {
        /// The file, when the value came from one.
        path: Option<PathBuf>,
        /// What is wrong.
        #[source]
        source: E,
    },
}

impl<T: Clone> Source<T> {
    /// The value: the inline one checked by `check`, or the file at `base/path` parsed by
    /// `parse`.
    ///
    /// # Errors
    /// [`ResolveError::Read`] for an unreadable file, [`ResolveError::Invalid`] for what
    /// `check` or `parse` rejects.
    pub fn resolve<E: std::error::Error + 'static>(
        &self,
        base: &Path,
        check: impl FnOnce(&T) -> Result<(), E>,
        parse: impl FnOnce(&str) -> Result<T, E>,
    ) -> Result<T, ResolveError<E>> {
        match self {
            Source::Inline(v) => {
                check(v).map_err(|source| ResolveError::Invalid { path: None, source })?;
                Ok((**v).clone())
            }
            Source::Path(rel) => {
                let path = base.join(rel);
                let text = std::fs::read_to_string(&path).map_err(|source| ResolveError::Read {
                    path: path.clone(),
                    source,
                })?;
                parse(&text).map_err(|source| ResolveError::Invalid {
                    path: Some(path),
                    source,
                })
            }
        }
    }
}
