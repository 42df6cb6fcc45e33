//! Typed errors for bad input to the mesh tools. [`MeshError`] is returned by
//! the `try_*` entry points ([`crate::try_check`], [`crate::try_distance`],
//! [`crate::TriangleBvh::new`]); the plain entry points panic with the same
//! message. Each variant says how to fix the input.

/// Why a mesh could not be analysed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MeshError {
    /// A face refers to a vertex that does not exist. Fix the face list (or
    /// pass the positions that belong with it); faces index positions from 0.
    #[error("face {face} refers to vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// Index of the offending face in the face list.
        face: usize,
        /// The out-of-range vertex index it holds.
        index: u32,
        /// Number of positions given.
        vertices: usize,
    },
    /// More vertices than a `u32` index can address (`u32::MAX` is kept as a
    /// sentinel). Split the mesh or process it out of core.
    #[error("{vertices} vertices: at most {max} are supported in core", max = u32::MAX)]
    TooManyVertices {
        /// Number of positions given.
        vertices: usize,
    },
    /// More faces than the in-core tables support (for [`crate::check()`] the
    /// 3 corners of every face must fit in a `u32`). Split the mesh or
    /// process it out of core.
    #[error("{faces} faces: at most {max} are supported in core")]
    TooManyFaces {
        /// Number of faces given.
        faces: usize,
        /// The limit of the operation that refused them.
        max: usize,
    },
    /// The operation needs a surface and got none. For a distance, mesh A
    /// must have positive total area (something to sample) and mesh B at
    /// least one face (something to measure to).
    #[error("{what}")]
    Empty {
        /// What was missing.
        what: &'static str,
    },
    /// The caller asked to stop (Ctrl-C).
    #[error("cancelled")]
    Cancelled,
}

impl MeshError {
    /// Checks an indexed mesh before an in-core operation: at most
    /// `u32::MAX` vertices and `max_faces` faces, and every index in range
    /// (the first bad face is reported).
    pub fn validate(positions: &[[f64; 3]], faces: &[[u32; 3]], max_faces: usize) -> Result<(), MeshError> {
        use rayon::prelude::*;
        if positions.len() > u32::MAX as usize {
            return Err(MeshError::TooManyVertices { vertices: positions.len() });
        }
        if faces.len() > max_faces {
            return Err(MeshError::TooManyFaces { faces: faces.len(), max: max_faces });
        }
        let nv = positions.len() as u32;
        if let Some(face) = faces.par_iter().position_first(|f| f.iter().any(|&i| i >= nv)) {
            let index = *faces[face].iter().find(|&&i| i >= nv).expect("found above");
            return Err(MeshError::IndexOutOfRange { face, index, vertices: positions.len() });
        }
        Ok(())
    }
}
