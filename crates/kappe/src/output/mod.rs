//! Writing what Kappe produces: the files of a run ([`OutputFile`], [`Outcome::files`]) and
//! the safe writer that puts them on disk ([`prepare_dir`], [`write_user_file`]).
//!
//! Both live in the library, not in the binary, so the CLI and the Python package write the
//! same files under the same rule: Kappe never deletes or overwrites what it did not write
//! (see [`dir`]).
//!
//! [`Outcome::files`]: crate::Outcome::files

pub(crate) mod dir;
mod files;
pub(crate) mod network;
pub(crate) mod report_input;
pub(crate) mod schedule_report;
pub(crate) mod summary;

pub use dir::{
    MANIFEST, PreparedDir, check_user_file, prepare_dir, write_file_atomic, write_user_file,
};
pub use files::{OutputFile, moving_plan_files, plan_files};

/// Why an output could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The location is refused: writing there could lose something Kappe did not write (the
    /// working directory, a foreign non-empty directory, an existing file without `--force`,
    /// a symbolic link, ...). Nothing was changed.
    #[error("{0}")]
    Refused(String),
    /// The file system failed (no write access, a full disk, `/proc`, ...).
    #[error("{0}")]
    Io(String),
    /// Producing a file's contents failed (a program that fails the URScript check, a report
    /// that cannot be rendered): a bug in Kappe rather than in the input.
    #[error("{0}")]
    Produce(String),
}

/// Results of this module.
pub type Result<T> = std::result::Result<T, OutputError>;

// The items users outside the crate need (the CLI, Python, the designer, the tests).
pub use network::network_json;
pub use summary::{Summary, summary_schema};
