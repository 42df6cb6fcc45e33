//! mint's out-of-core pipelines. Entry points read like a script: check the
//! contract, then run named stages; each stage reports to a [`Progress`]
//! hook that can also cancel the run.
//!
//! - [`resample`]: Marching Intersections resampling of a mesh file
//!   (stream faces → discretize → shard store → plan slabs → reconstruct
//!   slabs in parallel → write in order).

pub mod progress;
pub mod resample;

pub use progress::{NoProgress, Phase, Progress};
pub use resample::{resample, PipelineError, ResampleOptions, ResampleSummary};
