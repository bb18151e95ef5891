//! Output directories and single files, written without ever losing a user's files.
//!
//! Two rules hold for every command:
//!
//! 1. **Kappe deletes or replaces only what Kappe wrote.** An output directory is marked with a
//!    manifest ([`MANIFEST`]) listing the files Kappe put there. A later run replaces such a
//!    directory only if it still holds nothing but those files. Anything else (the working
//!    directory, one of its ancestors, a non-empty directory without a manifest, a Kappe output
//!    the user has added files to, a symbolic link, a regular file) is refused before any work is
//!    done; `--force` moves a foreign directory aside to `NAME.old-N` (nothing is deleted).
//!    A single output file (`-o FILE`, `kappe init`) is never written over an existing file
//!    without `--force`.
//! 2. **At every moment either the complete old or the complete new output is in place.** The new
//!    output is written into a staging directory beside the target; only when it is complete is it
//!    swapped in with one `renameat2(RENAME_EXCHANGE)` (two renames where the file system lacks
//!    it), and only then is the old one removed. A run killed while writing leaves the old output
//!    untouched and a hidden staging directory `.kappe-out-*`, which the next run removes once its
//!    process is gone.
//!
//! The staging directory is created by [`prepare_dir`] *before* any computing, so an output that
//! cannot be written (read-only directory, `/proc/...`, a regular file) fails at once. Files and
//! directories are created with the ordinary `open`/`mkdir` calls, so they get the usual
//! permissions (0666/0777 less the umask); `tempfile`'s private 0600/0700 modes are not used for
//! anything the user keeps.

use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::{OutputError, Result};

/// The file that marks a directory as a Kappe output and lists what Kappe wrote into it.
pub const MANIFEST: &str = ".kappe-output.json";
/// Marker inside a staging directory (holds the writer's process id).
const STAGING_MARKER: &str = ".kappe-staging";
const STAGING_PREFIX: &str = ".kappe-out-";

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Write `bytes` to `path` through a temporary sibling and a rename, so a failure never leaves
/// a partial file. Used for files inside a staging directory and, through [`write_user_file`],
/// for single-file outputs.
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = parent_or_dot(path);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(
        ".{name}.kappe-tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| -> std::io::Result<()> {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(err) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::Io(format!(
            "cannot write {}: {err}",
            path.display()
        )));
    }
    test_write_delay();
    Ok(())
}

/// `KAPPE_TEST_WRITE_DELAY_MS`: sleep after each file, so the tests can kill a run in the
/// middle of writing its output and check that the old output survives.
fn test_write_delay() {
    if let Some(ms) = std::env::var("KAPPE_TEST_WRITE_DELAY_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}

/// Write a single output file the user named (`-o FILE`, `kappe init PATH`): refused if `path`
/// exists, unless `force`.
pub fn write_user_file(path: &Path, bytes: &[u8], force: bool) -> Result<()> {
    check_user_file(path, force)?;
    write_file_atomic(path, bytes)
}

/// The early check of [`write_user_file`]: call it before computing. Fails if `path` exists
/// (unless `force`), is a directory, or its directory does not exist or cannot be written.
pub fn check_user_file(path: &Path, force: bool) -> Result<()> {
    if path.is_dir() {
        return Err(OutputError::Refused(format!(
            "{} is a directory, not a file",
            path.display()
        )));
    }
    if path.symlink_metadata().is_ok() && !force {
        return Err(OutputError::Refused(format!(
            "{} exists; Kappe does not overwrite files it may not have written (pass --force to replace it)",
            path.display()
        )));
    }
    let dir = parent_or_dot(path);
    if !dir.is_dir() {
        return Err(OutputError::Refused(format!(
            "the directory {} does not exist",
            dir.display()
        )));
    }
    // Probe that the directory takes a new file, so the failure comes before the computing.
    let probe = dir.join(format!(
        ".kappe-probe-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(err) => Err(OutputError::Io(format!(
            "cannot write into {}: {err}",
            dir.display()
        ))),
    }
}

/// What is at the target path before the run.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Previous {
    /// Nothing: the staging directory is renamed into place.
    Nothing,
    /// An empty directory: replaced by the rename (POSIX replaces an empty directory).
    EmptyDir,
    /// A Kappe output holding only what its manifest lists: swapped out, then removed.
    Kappe,
    /// Not Kappe's, and `--force` was given: moved aside to this path, never deleted.
    MoveAside(PathBuf),
}

/// An output directory being written: [`PreparedDir::path`] is the staging directory to fill,
/// [`PreparedDir::commit`] puts it in place. Dropped without commit, it removes the staging
/// directory and any parent directories it created, leaving everything as it was.
#[derive(Debug)]
pub struct PreparedDir {
    target: PathBuf,
    staging: PathBuf,
    created_parents: Vec<PathBuf>,
    previous: Previous,
    command: String,
    committed: bool,
}

/// Check the output directory `dir` and create its staging directory beside it. Call this
/// before computing anything: every refusal and every unwritable location fails here.
pub fn prepare_dir(dir: &Path, force: bool, command: &str) -> Result<PreparedDir> {
    if dir.as_os_str().is_empty() {
        return Err(OutputError::Refused(
            "the output directory is empty (give --out DIR)".into(),
        ));
    }
    let cwd = std::env::current_dir()
        .map_err(|e| OutputError::Io(format!("cannot read the working directory: {e}")))?
        .canonicalize()
        .map_err(|e| OutputError::Io(format!("cannot resolve the working directory: {e}")))?;
    let target = normalize(&cwd.join(dir));
    let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return Err(OutputError::Refused(format!(
            "--out {} is the file-system root; give a directory of its own",
            dir.display()
        )));
    };

    let previous = match target.symlink_metadata() {
        Err(_) => Previous::Nothing,
        Ok(meta) if meta.file_type().is_symlink() => {
            return Err(OutputError::Refused(format!(
                "--out {} is a symbolic link; give the directory it points to, or a new path",
                dir.display()
            )));
        }
        Ok(meta) if !meta.is_dir() => {
            return Err(OutputError::Refused(format!(
                "--out {} exists and is not a directory",
                dir.display()
            )));
        }
        Ok(_) => {
            let canonical = target.canonicalize().map_err(|e| {
                OutputError::Io(format!("cannot resolve {}: {e}", target.display()))
            })?;
            if cwd.starts_with(&canonical) {
                return Err(OutputError::Refused(format!(
                    "--out {} is the working directory or one of its ancestors; Kappe replaces \
                     its output directory as a whole, so give a new or empty directory (e.g. --out out)",
                    dir.display()
                )));
            }
            classify_existing(&target, force)?
        }
    };

    // Create the missing parents (remembered, to be removed again if the run fails), then the
    // staging directory: this is the early proof that the location can be written.
    let parent = target
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("/"));
    let mut created_parents = Vec::new();
    let mut missing = Vec::new();
    let mut p = parent.as_path();
    while p.symlink_metadata().is_err() {
        missing.push(p.to_path_buf());
        match p.parent() {
            Some(up) => p = up,
            None => break,
        }
    }
    for d in missing.iter().rev() {
        if let Err(err) = std::fs::create_dir(d) {
            cleanup_parents(&created_parents);
            return Err(OutputError::Io(format!(
                "cannot create the output directory {}: {err}",
                d.display()
            )));
        }
        created_parents.push(d.clone());
    }
    if !parent.is_dir() {
        cleanup_parents(&created_parents);
        return Err(OutputError::Refused(format!(
            "{} is not a directory",
            parent.display()
        )));
    }
    remove_stale_staging(&parent);
    let staging = parent.join(format!(
        "{STAGING_PREFIX}{name}-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let made = std::fs::create_dir(&staging).and_then(|()| {
        std::fs::write(staging.join(STAGING_MARKER), std::process::id().to_string())
    });
    if let Err(err) = made {
        let _ = std::fs::remove_dir_all(&staging);
        cleanup_parents(&created_parents);
        return Err(OutputError::Io(format!(
            "cannot write the output {} (no write access to {}: {err})",
            dir.display(),
            parent.display()
        )));
    }
    Ok(PreparedDir {
        target,
        staging,
        created_parents,
        previous,
        command: command.to_string(),
        committed: false,
    })
}

impl PreparedDir {
    /// The staging directory to write the outputs into.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Write `files` into the staging directory (creating their subdirectories).
    ///
    /// # Errors
    /// [`OutputError::Io`] when a file cannot be written.
    pub fn write(&self, files: &[super::OutputFile]) -> Result<()> {
        for f in files {
            let path = self.staging.join(&f.name);
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).map_err(|e| {
                    OutputError::Io(format!("cannot create {}: {e}", dir.display()))
                })?;
            }
            write_file_atomic(&path, &f.bytes)?;
        }
        Ok(())
    }

    /// Write the manifest and put the complete output in place of the old one (see the module
    /// docs). Returns a notice when a foreign directory was moved aside.
    pub fn commit(mut self) -> Result<Option<String>> {
        std::fs::remove_file(self.staging.join(STAGING_MARKER)).ok();
        let files = list_files(&self.staging)
            .map_err(|e| OutputError::Io(format!("cannot list {}: {e}", self.staging.display())))?;
        let manifest = serde_json::json!({
            "format": "kappe.output",
            "version": 1,
            "kappe": env!("CARGO_PKG_VERSION"),
            "command": self.command,
            "files": files,
        });
        let text = serde_json::to_string_pretty(&manifest)
            .map_err(|e| OutputError::Io(format!("cannot write the manifest: {e}")))?
            + "\n";
        write_file_atomic(&self.staging.join(MANIFEST), text.as_bytes())?;
        let io = |what: &str, err: std::io::Error| -> OutputError {
            OutputError::Io(format!("{what} {}: {err}", self.target.display()))
        };
        let mut notice = None;
        match &self.previous {
            Previous::Nothing | Previous::EmptyDir => {
                std::fs::rename(&self.staging, &self.target).map_err(|e| {
                    // Checked empty or absent before the run: someone else wrote it meanwhile.
                    if self.target.symlink_metadata().is_ok() && !list_entries_empty(&self.target) {
                        OutputError::Refused(format!(
                            "{} was filled by another run (or another program) while this one \
                             ran; this run's output was not put in place and the other was left \
                             as it is. Run one Kappe command per output directory at a time, and \
                             run this one again",
                            self.target.display()
                        ))
                    } else {
                        io("cannot move the output into place at", e)
                    }
                })?;
            }
            Previous::Kappe => {
                // Outputs of other commands nested inside (`kappe robot resume` writes
                // DIR/resume_from_layer_K/) belong to the previous output's plan: moved aside
                // with a notice, never deleted with it (issue 28).
                notice = move_nested_aside(&self.target)?;
                match exchange(&self.staging, &self.target) {
                    Ok(()) => {}
                    Err(_) => {
                        // No atomic exchange on this file system: two renames, old kept until
                        // the new one is in place.
                        let old = self.staging.with_extension("old");
                        std::fs::rename(&self.target, &old)
                            .map_err(|e| io("cannot move the previous output aside at", e))?;
                        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
                            let _ = std::fs::rename(&old, &self.target);
                            return Err(io("cannot move the output into place at", e));
                        }
                        std::fs::rename(&old, &self.staging).ok();
                    }
                }
                // The staging path now holds the previous output, which Kappe wrote.
                self.committed = true;
                let _ = std::fs::remove_dir_all(&self.staging);
            }
            Previous::MoveAside(aside) => {
                std::fs::rename(&self.target, aside)
                    .map_err(|e| io("cannot move the existing directory aside at", e))?;
                if let Err(e) = std::fs::rename(&self.staging, &self.target) {
                    let _ = std::fs::rename(aside, &self.target);
                    return Err(io("cannot move the output into place at", e));
                }
                notice = Some(format!(
                    "moved the previous contents of {} aside to {} (--force)",
                    self.target.display(),
                    aside.display()
                ));
            }
        }
        self.committed = true;
        Ok(notice)
    }
}

impl Drop for PreparedDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
            cleanup_parents(&self.created_parents);
        }
    }
}

/// Decide what may be done with an existing directory at `target`.
fn classify_existing(target: &Path, force: bool) -> Result<Previous> {
    let present = list_files(target)
        .map_err(|e| OutputError::Io(format!("cannot read {}: {e}", target.display())))?;
    if present.is_empty() && list_entries_empty(target) {
        return Ok(Previous::EmptyDir);
    }
    let manifest_files: Option<BTreeSet<String>> = std::fs::read(target.join(MANIFEST))
        .ok()
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .filter(|v| v.get("format").and_then(|f| f.as_str()) == Some("kappe.output"))
        .and_then(|v| {
            v.get("files")?
                .as_array()?
                .iter()
                .map(|f| f.as_str().map(String::from))
                .collect()
        });
    let foreign: Vec<String> = match &manifest_files {
        Some(listed) => present
            .iter()
            .filter(|f| f.as_str() != MANIFEST && !listed.contains(*f))
            .filter(|f| !in_nested_output(target, f))
            .cloned()
            .collect(),
        None => present.clone(),
    };
    if manifest_files.is_some() && foreign.is_empty() {
        return Ok(Previous::Kappe);
    }
    if force {
        return Ok(Previous::MoveAside(free_aside_name(target)));
    }
    let shown: Vec<&str> = foreign.iter().take(5).map(String::as_str).collect();
    let more = if foreign.len() > 5 {
        format!(" and {} more", foreign.len() - 5)
    } else {
        String::new()
    };
    let why = if manifest_files.is_some() {
        "is a Kappe output, but holds files Kappe did not write"
    } else {
        "is not empty and is not a Kappe output"
    };
    Err(OutputError::Refused(format!(
        "--out {} {why} ({}{more}); nothing was changed. Choose another --out, or pass --force \
         to move it aside to {} (nothing is deleted)",
        target.display(),
        shown.join(", "),
        free_aside_name(target).display()
    )))
}

/// Whether the relative file `rel` lies inside a nested Kappe output below `root` (e.g.
/// `kappe robot resume` writes `resume_from_layer_K/` into a design's output) whose own manifest
/// lists it.
fn in_nested_output(root: &Path, rel: &str) -> bool {
    let parts: Vec<&str> = rel.split('/').collect();
    (1..parts.len()).any(|depth| {
        let sub = root.join(parts[..depth].join("/"));
        let inner = parts[depth..].join("/");
        std::fs::read(sub.join(MANIFEST))
            .ok()
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
            .and_then(|v| {
                v.get("files")?.as_array().map(|a| {
                    inner == MANIFEST || a.iter().any(|f| f.as_str() == Some(inner.as_str()))
                })
            })
            .unwrap_or(false)
    })
}

fn list_entries_empty(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut it| it.next().is_none())
}

/// Every file (and symbolic link) below `dir`, as `/`-separated relative paths, sorted.
fn list_files(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for entry in std::fs::read_dir(dir.join(&rel))? {
            let entry = entry?;
            let rel_path = rel.join(entry.file_name());
            if entry.file_type()?.is_dir() {
                stack.push(rel_path);
            } else {
                let parts: Vec<String> = rel_path
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.push(parts.join("/"));
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Move the Kappe outputs nested in the output `target` (a subdirectory with its own
/// manifest) to `TARGET.old-N/<same path>`; a notice naming them, or `None` when there are none.
fn move_nested_aside(target: &Path) -> Result<Option<String>> {
    let files = list_files(target)
        .map_err(|e| OutputError::Io(format!("cannot read {}: {e}", target.display())))?;
    let suffix = format!("/{MANIFEST}");
    let mut roots: Vec<String> = Vec::new();
    for f in &files {
        if let Some(dir) = f.strip_suffix(&suffix)
            && !roots.iter().any(|r| dir.starts_with(&format!("{r}/")))
        {
            roots.push(dir.to_string());
        }
    }
    if roots.is_empty() {
        return Ok(None);
    }
    let aside = free_aside_name(target);
    let mut moved = Vec::new();
    for r in &roots {
        let to = aside.join(r);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|e| OutputError::Io(format!("cannot create {}: {e}", parent.display())))?;
        }
        std::fs::rename(target.join(r), &to).map_err(|e| {
            OutputError::Io(format!(
                "cannot move {} aside to {}: {e}",
                target.join(r).display(),
                to.display()
            ))
        })?;
        moved.push(format!("{r}/"));
    }
    Ok(Some(format!(
        "kept {} (written by another Kappe command from the previous output, e.g. \
         `kappe robot resume`) by moving it aside to {}",
        moved.join(", "),
        aside.display()
    )))
}

fn free_aside_name(target: &Path) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    (1..)
        .map(|n| target.with_file_name(format!("{name}.old-{n}")))
        .find(|p| p.symlink_metadata().is_err())
        .unwrap_or_else(|| target.with_file_name(format!("{name}.old")))
}

/// Remove staging directories of earlier runs whose process is gone (killed mid-write). Only
/// directories carrying Kappe's staging marker are touched.
fn remove_stale_staging(parent: &Path) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !name.starts_with(STAGING_PREFIX) {
            continue;
        }
        let path = entry.path();
        let Ok(pid) = std::fs::read_to_string(path.join(STAGING_MARKER)) else {
            continue;
        };
        let alive = Path::new("/proc").join(pid.trim()).exists();
        if !alive && pid.trim().parse::<u32>().is_ok() {
            let _ = std::fs::remove_dir_all(&path);
        }
    }
}

fn cleanup_parents(created: &[PathBuf]) {
    for d in created.iter().rev() {
        let _ = std::fs::remove_dir(d);
    }
}

fn parent_or_dot(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Lexical normalization (`.` dropped, `..` pops), for an absolute path.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

/// Swap two paths atomically (Linux `renameat2(RENAME_EXCHANGE)`).
#[cfg(not(target_arch = "wasm32"))]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    rustix::fs::renameat_with(
        rustix::fs::CWD,
        a,
        rustix::fs::CWD,
        b,
        rustix::fs::RenameFlags::EXCHANGE,
    )
    .map_err(std::io::Error::from)
}

/// No file system on wasm32 (the designer in the browser writes nothing): the caller's
/// two-rename fallback.
#[cfg(target_arch = "wasm32")]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::ErrorKind::Unsupported.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalize_resolves_dots() {
        assert_eq!(
            normalize(Path::new("/a/b/../c/./d")),
            PathBuf::from("/a/c/d")
        );
        assert_eq!(normalize(Path::new("/a/..")), PathBuf::from("/"));
    }
}
