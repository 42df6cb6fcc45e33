//! The errors of mint-contour. [`ContourError`] keeps bad profiles
//! ([`ProfileError`], with a [`ProfileErrorKind`] and the 1-based line),
//! unreadable or unwritable files, unusable parameters and failing output
//! sinks apart. Every `Display` is one line that names the file and, for
//! profiles, the line:
//!
//! ```text
//! stack.pro: contour is self-intersecting: its edges from lines 14 and 20 touch (line 12)
//! ```
//!
//! DICOM RT structure sets have no lines: their errors ([`DicomError`],
//! with a [`DicomErrorKind`]) name the file, and the ROI and contour where
//! there is one:
//!
//! ```text
//! rtstruct.dcm: ROI 2 'Isocenter 1': contour 1 is POINT: only CLOSED_PLANAR contours bound a solid
//! ```

use std::path::{Path, PathBuf};

/// What is wrong with a profile file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ProfileErrorKind {
    /// Not the profile grammar: no `pro` header, a token that is neither a
    /// number nor a keyword, a vertex with fewer than 3 coordinates, a
    /// non-finite coordinate, no sections. Fix the file's syntax.
    Syntax,
    /// A contour has fewer than 3 distinct vertices. Remove it or add points.
    TooFewVertices,
    /// A contour's vertices do not lie in one plane, or the contours of one
    /// section lie in different planes. Cross-sections must be planar.
    NonPlanar,
    /// A contour is planar but not parallel to the first section: all
    /// sections must be cut by parallel planes.
    NotParallel,
    /// A contour crosses or touches itself, or two contours of one section
    /// cross or touch. Contours must be simple and disjoint (nesting is fine).
    SelfIntersecting,
    /// A section does not come after the previous one along the stack axis
    /// (or repeats its plane). Sections must be ordered along the scan path.
    OutOfOrder,
}

/// A bad profile: kind, file, 1-based line and a one-line message.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: {message} (line {line})", path.display())]
pub struct ProfileError {
    /// What kind of problem this is.
    pub kind: ProfileErrorKind,
    /// The profile file.
    pub path: PathBuf,
    /// 1-based line where the problem was found.
    pub line: u64,
    /// What is wrong, in one line.
    pub message: String,
}

impl ProfileError {
    pub(crate) fn new(kind: ProfileErrorKind, path: &Path, line: u64, message: impl Into<String>) -> ProfileError {
        ProfileError { kind, path: path.to_path_buf(), line, message: message.into().replace(['\n', '\r'], " ") }
    }
}

/// What is wrong with a DICOM input (`mint contours rtss.dcm`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DicomErrorKind {
    /// Not DICOM: no `DICM` marker after a 128-byte preamble, none at the
    /// start, and no data set at the start either. Give a DICOM file.
    NotDicom,
    /// DICOM, but the parser stopped: the file is truncated or corrupted,
    /// or uses a transfer syntax mint does not read (deflate, big endian
    /// retired). Export the structure set again.
    Corrupt,
    /// A readable DICOM file that is not an RT structure set: its Modality
    /// is not RTSTRUCT, or it has no ROI Contour Sequence. Give the RTSTRUCT
    /// file of the series, not an image.
    NotRtStruct,
    /// No ROI of that name (or several share it); `--list-rois` lists them.
    NoSuchRoi,
    /// The ROI has no contours: nothing to reconstruct.
    Empty,
    /// A contour of the ROI is POINT, OPEN_PLANAR or OPEN_NONPLANAR: it
    /// bounds no area. Only CLOSED_PLANAR contours make a solid.
    NotClosed,
    /// A contour's data is malformed: its point count is not Number of
    /// Contour Points, a coordinate is not a finite number, or it has fewer
    /// than 3 distinct points.
    BadContour,
    /// A contour is not planar, or the contours do not lie in parallel
    /// planes: a stack is cut by parallel planes.
    NotParallel,
    /// A contour crosses or touches itself, or two contours of one plane
    /// cross or touch. Contours of a plane must be simple and disjoint
    /// (nesting is fine).
    SelfIntersecting,
}

/// A bad DICOM input: kind, file and a one-line message (which names the
/// ROI and the contour where there is one).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct DicomError {
    /// What kind of problem this is.
    pub kind: DicomErrorKind,
    /// The DICOM file.
    pub path: PathBuf,
    /// What is wrong, in one line.
    pub message: String,
}

impl DicomError {
    pub(crate) fn new(kind: DicomErrorKind, path: &Path, message: impl Into<String>) -> DicomError {
        DicomError { kind, path: path.to_path_buf(), message: message.into().replace(['\n', '\r'], " ") }
    }
}

/// Any failure of a contour command.
#[derive(Debug, thiserror::Error)]
pub enum ContourError {
    /// The profile is malformed or breaks the contract (see [`ProfileErrorKind`]).
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// The DICOM RT structure set is unreadable or unusable (see
    /// [`DicomErrorKind`]).
    #[error(transparent)]
    Dicom(#[from] DicomError),
    /// Reading or writing a mesh failed (mint-io names the file and position).
    #[error(transparent)]
    Mesh(#[from] mint_io::Error),
    /// A file operation failed: `op` on `path`.
    #[error("{}: {op}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// What was being done.
        op: &'static str,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The input cannot be used as asked (an empty mesh, a grid too fine, a
    /// stack with nothing to reconstruct); the message says what to change.
    #[error("{}: {message}", path.display())]
    Input {
        /// The input file.
        path: PathBuf,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// An output sink refused data (a full disk, usually).
    #[error("writing the output: {0}")]
    Sink(mint_core::SinkError),
    /// The user interrupted the run; no output was left behind.
    #[error("interrupted; no output written")]
    Cancelled,
}

impl ContourError {
    pub(crate) fn io(path: &Path, op: &'static str, source: std::io::Error) -> ContourError {
        ContourError::Io { path: path.to_path_buf(), op, source }
    }

    pub(crate) fn input(path: &Path, message: impl Into<String>) -> ContourError {
        ContourError::Input { path: path.to_path_buf(), message: message.into() }
    }
}

impl From<mint_core::SinkError> for ContourError {
    fn from(e: mint_core::SinkError) -> ContourError {
        // A mint-io error travelling through a sink keeps its own message.
        match e.downcast::<mint_io::Error>() {
            Ok(io) => ContourError::Mesh(*io),
            Err(e) => ContourError::Sink(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_errors_are_one_line_with_file_and_line() {
        let e = ProfileError::new(ProfileErrorKind::Syntax, Path::new("a.pro"), 7, "bad\ntoken");
        assert_eq!(e.to_string(), "a.pro: bad token (line 7)");
        let c: ContourError = e.into();
        assert_eq!(c.to_string(), "a.pro: bad token (line 7)");
    }
}
