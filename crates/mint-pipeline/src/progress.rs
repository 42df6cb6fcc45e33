//! The progress and cancellation hook of the pipelines: defined in
//! mint-core ([`mint_core::progress`]) so that every crate's long work
//! (resampling here, range-scan merging in mint-range) reports through the
//! same trait.

pub use mint_core::progress::{NoProgress, Phase, Progress};

/// Reading vertex positions to find the bounding box (units: vertices).
pub const BOUNDS: Phase = Phase::named("bounds");
/// Streaming faces and discretizing them (units: faces).
pub const DISCRETIZE: Phase = Phase::named("discretize");
/// Reconstructing slabs (units: layers).
pub const RECONSTRUCT: Phase = Phase::named("reconstruct");
/// Copying the slabs into the output (units: faces).
pub const WRITE: Phase = Phase::named("write");

/// `Err(Cancelled)` once the run is cancelled (Ctrl-C, SIGTERM).
pub fn check_cancel(progress: &dyn Progress) -> Result<(), crate::error::PipelineError> {
    if progress.cancelled() {
        Err(crate::error::PipelineError::Cancelled)
    } else {
        Ok(())
    }
}
