//! [`RangeError`], the one error type of mint-range. It keeps bad input
//! (a malformed set file, a scan without samples), I/O failures (passed
//! through from mint-io with their file and position) and impossible
//! requests (options out of range) apart. `Display` is always one line that
//! names the file and, where known, the line in it:
//!
//! ```text
//! scans/bun.conf:4: bmesh needs 8 fields (file tx ty tz qx qy qz qw), found 5
//! ```

use std::path::{Path, PathBuf};

/// Everything that can go wrong in mint-range.
#[derive(Debug, thiserror::Error)]
pub enum RangeError {
    /// A scan-set file (.conf or .aln) is malformed at `line` (1-based).
    /// Fix: correct that line; the message says what was expected.
    #[error("{}:{line}: {}", .path.display(), .message.chars().map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() }).collect::<String>())]
    SetSyntax { path: PathBuf, line: usize, message: String },
    /// A scan listed in a set file does not exist or cannot be read.
    /// Fix: check the name in the set file; paths are relative to the set
    /// file's directory.
    #[error("{}:{line}: scan '{}' cannot be opened: {source}", .set.display(), .scan.display())]
    MissingScan { set: PathBuf, line: usize, scan: PathBuf, source: std::io::Error },
    /// Reading or writing a mesh or range image failed (the message names the
    /// file and the position in it).
    #[error(transparent)]
    Io(#[from] mint_io::Error),
    /// A `.rgrid` range grid is malformed `at` a header line, a data row
    /// and column, or a byte offset.
    #[error("{}: {at}: {message}", .path.display())]
    GridSyntax { path: PathBuf, at: String, message: String },
    /// A plain file operation failed.
    #[error("{}: {what}: {source}", .path.display())]
    File { path: PathBuf, what: &'static str, source: std::io::Error },
    /// A scan has nothing usable: no samples, or no triangle survived the
    /// edge-length cutoff. Fix: check the file, or raise the cutoff factor.
    #[error("{}: {message}", .path.display())]
    EmptyScan { path: PathBuf, message: String },
    /// An option or argument is out of its range.
    #[error("invalid option {name}: {message}")]
    InvalidOption { name: &'static str, message: String },
    /// A mesh handed to the library is inconsistent (bad indices...).
    #[error("{what}: {source}")]
    Mesh { what: String, source: mint_mesh::MeshError },
    /// An output path that cannot be used: not a directory where one is
    /// needed, or refused by the caller (it is an input).
    #[error("{}: {message}", .path.display())]
    Output { path: PathBuf, message: String },
    /// The user asked to stop (Ctrl-C); nothing was written.
    #[error("interrupted")]
    Cancelled,
    /// The grid merge could not choose a grid.
    #[error("grid merge: {0}")]
    Grid(#[from] mint_core::GridError),
}

impl RangeError {
    pub(crate) fn syntax(path: &Path, line: usize, message: impl Into<String>) -> RangeError {
        RangeError::SetSyntax { path: path.to_path_buf(), line, message: message.into() }
    }
    pub(crate) fn empty(path: &Path, message: impl Into<String>) -> RangeError {
        RangeError::EmptyScan { path: path.to_path_buf(), message: message.into() }
    }
    pub(crate) fn option(name: &'static str, message: impl Into<String>) -> RangeError {
        RangeError::InvalidOption { name, message: message.into() }
    }
}

/// One unit of progress done; [`RangeError::Cancelled`] if the user asked
/// to stop.
pub(crate) fn advance(progress: &dyn mint_core::progress::Progress) -> Result<(), RangeError> {
    progress.advance(1);
    if progress.cancelled() {
        return Err(RangeError::Cancelled);
    }
    Ok(())
}
