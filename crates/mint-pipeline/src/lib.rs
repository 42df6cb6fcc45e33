//! mint's out-of-core pipelines. Entry points read like a script: check the
//! contract, then run named stages; each stage reports to a [`Progress`]
//! hook that can also cancel the run.
//!
//! - [`resample`]: Marching Intersections resampling of a mesh file
//!   (stream faces → discretize → shard store → plan slabs → reconstruct
//!   slabs in parallel → write in order);
//! - [`csg`]: booleans and CSG trees of meshes and analytic primitives
//!   ([`scene`] parses the scene files), on the same machinery.

pub mod csg;
mod output;
pub mod progress;
pub mod resample;
pub mod scene;

pub use progress::{NoProgress, Phase, Progress};
pub use csg::{boolean, csg};
pub use resample::{resample, PipelineError, ResampleOptions, ResampleSummary};
pub use scene::{parse_scene, Scene, SceneError};
