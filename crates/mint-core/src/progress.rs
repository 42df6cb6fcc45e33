//! One hook for progress and cancellation, polled between stages, per chunk
//! of faces, per slab and per scan. The default methods do nothing, so
//! [`NoProgress`] is the null hook. (A trait and a name only: mint-core
//! still does no I/O; the CLI draws the bars.)

/// A long phase of some work, by name ("discretize", "zipper"…). Each
/// crate names its own phases (`mint_pipeline::progress::DISCRETIZE`,
/// `mint_range::phases::ZIPPER`…); the core keeps only this type and the
/// trait.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Phase(&'static str);

impl Phase {
    /// A phase called `name` (lower case, a few words: shown beside its bar).
    pub const fn named(name: &'static str) -> Phase {
        Phase(name)
    }

    pub fn name(self) -> &'static str {
        self.0
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
    /// up and returns its `Cancelled` error (mint-pipeline's `PipelineError`,
    /// mint-range's `RangeError`).
    fn cancelled(&self) -> bool {
        false
    }
}

/// The null hook.
pub struct NoProgress;
impl Progress for NoProgress {}
