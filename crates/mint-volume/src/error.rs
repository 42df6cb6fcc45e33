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

/// One line: `<file>: <where>: <what>`. Control characters in the file's
/// name or in the text an error quotes from a header (a `\r`, a NUL) are
/// shown escaped, so that the error stays one line.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", one_line(&path.display().to_string()))]
pub struct VolumeError {
    kind: VolumeErrorKind,
    path: PathBuf,
    message: String,
}

/// `s` with its control characters escaped (`\r`, `\n`, `\t`, `\u{0}`).
fn one_line(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    s.chars().map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() }).collect()
}

impl VolumeError {
    /// A new error about `path`.
    pub fn new(kind: VolumeErrorKind, path: &Path, message: impl Into<String>) -> VolumeError {
        VolumeError { kind, path: path.to_path_buf(), message: one_line(&message.into()) }
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
        VolumeError { kind, path: path.to_path_buf(), message: one_line(&msg) }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Found by fuzzing: a header line with a carriage return and NULs,
    /// quoted in the error, made it two lines.
    #[test]
    fn quoted_control_characters_keep_the_error_on_one_line() {
        let e = VolumeError::format(Path::new("a\nb.nrrd"), "line 4: `dim\r\0\0 3` is not a `field: value` line");
        let s = e.to_string();
        assert!(!s.contains('\n') && !s.contains('\r') && !s.contains('\0'), "{s:?}");
        assert_eq!(s, "a\\nb.nrrd: line 4: `dim\\r\\u{0}\\u{0} 3` is not a `field: value` line");
    }
}
