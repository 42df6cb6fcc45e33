//! Why a run or a task failed: [`PipelineError`]. Each variant's text is one
//! line naming the file (input, work directory or output) and what to do.

use mint_core::grid::GridError;
use mint_store::StoreError;
use std::path::PathBuf;

/// Why a run failed. Each variant's text is one line naming the file.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Reading the input or writing the output failed (bad input, full disk…).
    #[error(transparent)]
    Io(#[from] mint_io::Error),
    /// A volume's header or data is bad, or reading it failed.
    #[error(transparent)]
    Volume(#[from] mint_volume::VolumeError),
    /// The shard store failed, or a shard is damaged.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The grid cannot be built; the message says which option to change.
    #[error("{path}: {source}")]
    Grid { path: PathBuf, source: GridError },
    /// A vertex position is NaN or infinite.
    #[error("{path}: vertex {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinite { path: PathBuf, index: u64, x: f64, y: f64, z: f64 },
    /// A computed output vertex is NaN or infinite: arithmetic on the
    /// input's coordinates overflowed. Names the input, not the output.
    #[error("{path}: an output vertex came out non-finite ({x}, {y}, {z}): the input's coordinates are too large for the grid's arithmetic; scale or translate the input towards the origin")]
    NonFiniteResult { path: PathBuf, x: f64, y: f64, z: f64 },
    /// A mesh vertex moved by the scene's transforms is NaN or infinite.
    #[error("{path}: vertex {index} moved by the scene's transforms is non-finite ({x}, {y}, {z}): the scale or translation is too large")]
    TransformOverflow { path: PathBuf, index: u64, x: f64, y: f64, z: f64 },
    /// The input has no triangles.
    #[error("{path}: the mesh has no triangles to resample")]
    Empty { path: PathBuf },
    /// A temporary or work file failed.
    #[error("{path}: {op}: {source}")]
    Temp { path: PathBuf, op: &'static str, source: std::io::Error },
    /// A CSG scene whose result is unbounded (e.g. a lone half-space).
    #[error("{path}: the scene is unbounded (intersect half-spaces with a bounded solid)")]
    Unbounded { path: PathBuf },
    /// A staged run's work directory, plan or task results are not what
    /// the command needs: another input or options, a missing or damaged
    /// task result, a plan of another version. The message says which and
    /// what to do.
    #[error("{path}: {message}")]
    Stage { path: PathBuf, message: String },
    /// The memory budget (`--mem`) is too small for the job; the message
    /// says how much would do, or which option to change.
    #[error("{path}: {message}")]
    Budget { path: PathBuf, message: String },
    /// A scene file could not be read or parsed.
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// One of a surface's several files failed: which one of the list.
    #[error("input {} of {count}: {source}", .index + 1)]
    InFile { index: usize, count: usize, source: Box<PipelineError> },
    /// The user interrupted the run; temporary files were removed.
    #[error("interrupted; no output written")]
    Cancelled,
}

impl PipelineError {
    /// A [`PipelineError::Stage`] error.
    pub fn stage(path: impl Into<PathBuf>, message: impl Into<String>) -> PipelineError {
        PipelineError::Stage { path: path.into(), message: message.into() }
    }

    /// A [`PipelineError::Budget`] error.
    pub fn budget(path: impl Into<PathBuf>, message: impl Into<String>) -> PipelineError {
        PipelineError::Budget { path: path.into(), message: message.into() }
    }
}

/// `e`, saying which of a surface's `count` files it concerns when there
/// are several (a tile that fails to read is named with its position).
pub fn in_file_list(e: PipelineError, index: usize, count: usize) -> PipelineError {
    match e {
        PipelineError::Cancelled | PipelineError::InFile { .. } => e,
        _ if count <= 1 => e,
        _ => PipelineError::InFile { index, count, source: Box::new(e) },
    }
}
