//! One hook for progress and cancellation, polled between stages, per chunk
//! of faces and per slab. The default methods do nothing, so [`NoProgress`]
//! is the null hook.

/// The long phases of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Reading vertex positions to find the bounding box (units: vertices).
    Bounds,
    /// Streaming faces and discretizing them (units: faces).
    Discretize,
    /// Reconstructing slabs (units: layers).
    Reconstruct,
    /// Copying the faces into the output after its vertices (units: faces).
    Write,
}

impl Phase {
    pub fn name(self) -> &'static str {
        match self {
            Phase::Bounds => "bounds",
            Phase::Discretize => "discretize",
            Phase::Reconstruct => "reconstruct",
            Phase::Write => "write",
        }
    }
}

/// Receives progress and may ask the pipeline to stop.
pub trait Progress: Sync {
    /// A phase starts with `total` units of work (0 when unknown).
    fn start(&self, _phase: Phase, _total: u64) {}
    /// `n` more units of the current phase are done.
    fn advance(&self, _n: u64) {}
    /// The current phase is over.
    fn finish(&self) {}
    /// True when the user asked to stop (Ctrl-C); the pipeline then cleans
    /// up and returns [`PipelineError::Cancelled`](crate::PipelineError::Cancelled).
    fn cancelled(&self) -> bool {
        false
    }
}

/// The null hook.
pub struct NoProgress;
impl Progress for NoProgress {}
