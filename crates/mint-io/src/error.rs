//! The one error type of mint-io. An [`Error`] carries an [`ErrorKind`] that
//! keeps I/O failures, malformed files, bad indices, bad values and
//! unsupported features apart, the path of the file concerned, a short
//! message, and a [`Position`] (element, record, line, byte offset) wherever
//! the reader knows it. Its `Display` is always exactly one line:
//!
//! ```text
//! /data/scan.ply: face list runs past the end of the file (element 'face', record 1234, byte offset 5678)
//! ```
//!
//! Records are counted from 0 within their element (record `k` of element
//! `vertex` is vertex index `k`); lines are counted from 1; byte offsets are
//! from the start of the file.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// What went wrong, coarsely; use it to decide what to tell the user.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// The operating system refused an operation (open, read, write, rename,
    /// a full disk). Fix: check the path, permissions and free space.
    Io,
    /// The file is malformed: a bad header, a token that is not a number, a
    /// truncated body, or counts that do not match the body (too few records,
    /// trailing data). Fix: the file is damaged or was written by a broken
    /// exporter; re-export it.
    Format,
    /// A face refers to a vertex that does not exist (negative, zero in OBJ,
    /// or not below the vertex count). Fix: the file is inconsistent; repair
    /// or re-export it.
    Index,
    /// A coordinate that a face uses is NaN or infinite (or a writer was
    /// handed one). Fix: clean the input; mint cannot place such a triangle.
    Value,
    /// The file is valid but uses something mint-io does not read or write
    /// (an unknown format, 64-bit types, more than 2^32 - 1 vertices, ...).
    Unsupported,
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ErrorKind::Io => "I/O error",
            ErrorKind::Format => "format error",
            ErrorKind::Index => "index error",
            ErrorKind::Value => "value error",
            ErrorKind::Unsupported => "unsupported",
        })
    }
}

/// Where in a file an error was found; each part is known or not.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Position {
    /// The element (PLY element name, `v`/`f` for OBJ, `facet` for STL,
    /// `vertex`/`face` for OFF, `header` for headers).
    pub element: Option<String>,
    /// 0-based record index within the element.
    pub record: Option<u64>,
    /// 1-based line number (text files only).
    pub line: Option<u64>,
    /// Byte offset from the start of the file.
    pub byte_offset: Option<u64>,
}

impl Position {
    fn is_empty(&self) -> bool {
        self.element.is_none() && self.record.is_none() && self.line.is_none() && self.byte_offset.is_none()
    }
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return Ok(());
        }
        let mut parts: Vec<String> = Vec::with_capacity(4);
        if let Some(e) = &self.element {
            parts.push(format!("element '{}'", one_line(e)));
        }
        if let Some(r) = self.record {
            parts.push(format!("record {r}"));
        }
        if let Some(l) = self.line {
            parts.push(format!("line {l}"));
        }
        if let Some(b) = self.byte_offset {
            parts.push(format!("byte offset {b}"));
        }
        write!(f, " ({})", parts.join(", "))
    }
}

/// A mint-io error: kind, file, message and position. See the module docs
/// for the one-line `Display` format. The details live behind one box, so
/// `Result<(), Error>` stays a pointer wide on hot paths.
///
/// For [`ErrorKind::Io`] the operating system's message is part of the
/// `Display` text, and the original [`io::Error`] is available through
/// [`Error::io_error`]; it is deliberately not also reported as `source()`,
/// so that error chains do not print it twice.
#[derive(Debug, thiserror::Error)]
#[error("{}: {}{}", .inner.path.display(), .inner.message, .inner.position)]
pub struct Error {
    inner: Box<Inner>,
}

#[derive(Debug)]
struct Inner {
    kind: ErrorKind,
    path: PathBuf,
    message: String,
    position: Position,
    io: Option<io::Error>,
}

impl Error {
    /// An error of `kind` about `path`. The message is made single-line.
    pub fn new(kind: ErrorKind, path: &Path, message: impl Into<String>) -> Error {
        Error {
            inner: Box::new(Inner {
                kind,
                path: path.to_path_buf(),
                message: one_line(&message.into()),
                position: Position::default(),
                io: None,
            }),
        }
    }

    /// An [`ErrorKind::Io`] error: `what` was being done when `err` happened.
    pub fn io(path: &Path, what: &str, err: io::Error) -> Error {
        let mut e = Error::new(ErrorKind::Io, path, format!("{what}: {err}"));
        e.inner.io = Some(err);
        e
    }

    pub(crate) fn format(path: &Path, message: impl Into<String>) -> Error {
        Error::new(ErrorKind::Format, path, message)
    }

    pub(crate) fn unsupported(path: &Path, message: impl Into<String>) -> Error {
        Error::new(ErrorKind::Unsupported, path, message)
    }

    /// Sets the element name.
    pub fn at_element(mut self, element: &str) -> Error {
        self.inner.position.element = Some(element.to_string());
        self
    }

    /// Sets the 0-based record index.
    pub fn at_record(mut self, record: u64) -> Error {
        self.inner.position.record = Some(record);
        self
    }

    /// Sets the 1-based line number.
    pub fn at_line(mut self, line: u64) -> Error {
        self.inner.position.line = Some(line);
        self
    }

    /// Sets the byte offset from the start of the file.
    pub fn at_byte(mut self, offset: u64) -> Error {
        self.inner.position.byte_offset = Some(offset);
        self
    }

    /// What kind of failure this is.
    pub fn kind(&self) -> ErrorKind {
        self.inner.kind
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        &self.inner.path
    }

    /// The message without path and position.
    pub fn message(&self) -> &str {
        &self.inner.message
    }

    /// Where in the file, as far as known.
    pub fn position(&self) -> &Position {
        &self.inner.position
    }

    /// The underlying operating-system error of an [`ErrorKind::Io`] error.
    pub fn io_error(&self) -> Option<&io::Error> {
        self.inner.io.as_ref()
    }
}

/// Replaces line breaks and other control characters so that a message taken
/// partly from file contents stays on one line.
pub(crate) fn one_line(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    s.chars()
        .map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() })
        .collect()
}

/// Shows a token taken from a file in a message: quoted, at most 40
/// characters, non-UTF-8 and control bytes escaped.
pub(crate) fn show_token(tok: &[u8]) -> String {
    let mut s = String::with_capacity(tok.len().min(48) + 2);
    s.push('\'');
    for (n, &b) in tok.iter().enumerate() {
        if n == 40 {
            s.push_str("...");
            break;
        }
        if b.is_ascii_graphic() || b == b' ' {
            s.push(b as char);
        } else {
            s.push_str(&format!("\\x{b:02x}"));
        }
    }
    s.push('\'');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_is_one_line_with_position() {
        let e = Error::format(Path::new("/d/a.ply"), "bad\nthing")
            .at_element("face")
            .at_record(1234)
            .at_byte(5678);
        assert_eq!(
            e.to_string(),
            "/d/a.ply: bad\\nthing (element 'face', record 1234, byte offset 5678)"
        );
        assert_eq!(e.kind(), ErrorKind::Format);
        assert_eq!(e.position().record, Some(1234));
        assert_eq!(std::mem::size_of::<Result<(), Error>>(), std::mem::size_of::<usize>());
        let e = Error::io(Path::new("x"), "cannot open", io::Error::from(io::ErrorKind::NotFound));
        assert_eq!(e.to_string().lines().count(), 1);
        assert!(e.to_string().starts_with("x: cannot open: "));
    }

    #[test]
    fn tokens_are_escaped() {
        assert_eq!(show_token(b"ab\n\xff"), "'ab\\x0a\\xff'");
    }
}
