//! [`GenError`]: why a generator stopped. Bad parameters, meshes too large
//! for `u32` indices and too small for the requested defects are the
//! caller's to fix; a sink failure (a full disk, a cancelled run) is passed
//! through untouched.

use mint_core::SinkError;

/// A generator's failure.
#[derive(Debug, thiserror::Error)]
pub enum GenError {
    /// The sink refused a vertex or face; the mesh is incomplete. The source
    /// is the sink's own error.
    #[error("the mesh sink failed")]
    Sink(#[source] SinkError),
    /// A parameter is out of its documented range; the message says which
    /// and why.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// What is wrong with its value.
        reason: String,
    },
    /// The mesh would need more vertices than `u32` face indices can
    /// address; ask for fewer faces (about 8.5 billion at most).
    #[error("the mesh would need {vertices} vertices, more than u32 indices address; ask for fewer faces")]
    TooManyVertices {
        /// Vertices the request would need.
        vertices: u64,
    },
    /// `scan_like` cannot keep the requested defects far enough apart on a
    /// mesh this small; ask for more faces, fewer defects or a smaller hole
    /// radius.
    #[error("{target_faces} faces leave room for {available} defect sites but {needed} were requested; ask for more faces, fewer defects or smaller holes")]
    TooSmallForDefects {
        /// The requested face count.
        target_faces: u64,
        /// Defect sites requested (holes + flips + patches + slivers).
        needed: u64,
        /// Sites that fit.
        available: u64,
    },
}

impl From<SinkError> for GenError {
    fn from(e: SinkError) -> Self {
        GenError::Sink(e)
    }
}
