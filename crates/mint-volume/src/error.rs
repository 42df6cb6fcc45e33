//! The one error type of mint-volume: a [`VolumeError`] is a kind (what a
//! caller may act on: I/O, a bad header or data, an unsupported variant, a
//! bad argument) and one line naming the file and the place in it
//! (`quarter.nhdr: line 3 (sizes): …`, `1-07.dcm: (0028,0010) Rows: …`).

use std::path::{Path, PathBuf};

/// What went wrong, for a caller that maps errors to exit codes or
/// exception types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeErrorKind {
    /// The operating system failed to read or write a file.
    Io,
    /// The header or the data contradict themselves or each other (sizes,
    /// a truncated slice, a missing DICOM slice): fix or re-export the file.
    Format,
    /// A valid file that uses what mint does not read (a compressed
    /// transfer syntax without a decoder, 4-D data, colour samples).
    Unsupported,
    /// A bad request: slices out of range, raw dimensions that overflow.
    Value,
}

/// One line: `<file>: <where>: <what>`.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct VolumeError {
    kind: VolumeErrorKind,
    path: PathBuf,
    message: String,
}

impl VolumeError {
    /// A new error about `path`.
    pub fn new(kind: VolumeErrorKind, path: &Path, message: impl Into<String>) -> VolumeError {
        VolumeError { kind, path: path.to_path_buf(), message: message.into() }
    }

    /// A format error about `path`.
    pub fn format(path: &Path, message: impl Into<String>) -> VolumeError {
        VolumeError::new(VolumeErrorKind::Format, path, message)
    }

    /// An unsupported-variant error about `path`.
    pub fn unsupported(path: &Path, message: impl Into<String>) -> VolumeError {
        VolumeError::new(VolumeErrorKind::Unsupported, path, message)
    }

    /// An I/O error while doing `what` on `path`.
    pub fn io(path: &Path, what: &str, err: std::io::Error) -> VolumeError {
        let kind = if err.kind() == std::io::ErrorKind::UnexpectedEof { VolumeErrorKind::Format } else { VolumeErrorKind::Io };
        let msg = if kind == VolumeErrorKind::Format { format!("{what}: the file ends early (truncated)") } else { format!("{what}: {err}") };
        VolumeError { kind, path: path.to_path_buf(), message: msg }
    }

    /// The kind.
    pub fn kind(&self) -> VolumeErrorKind {
        self.kind
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        &self.path
    }
}
