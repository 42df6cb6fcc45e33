//! The progress and cancellation hook of the pipelines: defined in
//! mint-core ([`mint_core::progress`]) so that every crate's long work
//! (resampling here, range-scan merging in mint-range) reports through the
//! same trait.

pub use mint_core::progress::{NoProgress, Phase, Progress};
