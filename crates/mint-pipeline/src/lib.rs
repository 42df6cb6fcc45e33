//! mint's out-of-core engine: one staged evaluation of solids on the grid
//! for `resample` (one mesh), `bool` (two), `csg` (meshes and analytic
//! primitives under an expression) and `volume` (a voxel volume's
//! iso-surface). Entry points read like a script: check
//! the contract, then run named stages; each stage reports to a
//! [`Progress`] hook that can also cancel the run.
//!
//! - [`engine`]: the drivers: a whole run in one process ([`run`],
//!   [`run_scene`]), or one task at a time ([`plan_run`],
//!   [`run_task`], [`status`]) for resuming and for clusters;
//! - [`spec`]: the one description of a run: what decides the output
//!   ([`RunSpec`]) and what does not ([`Tuning`]), with every default;
//! - [`plan`]: a staged run in its work directory (spec, fingerprints, stages);
//! - [`stages`]: the tasks of each stage and the reduces between stages;
//! - the parallel passes inside a task, one file each: [`bounds`],
//!   [`discretize`] (with the per-triangle [`kernels`]), [`slabs`] (slab
//!   planning and ordered reconstruction);
//! - [`deref`]: how faces' vertex indices become positions (memory map,
//!   or Lindstrom–Silva dereferencing by distribution sort);
//! - [`workdir`]: task directories, atomic commits, checksums;
//! - [`slurm`]: submitting a plan to a Slurm cluster;
//! - [`scene`]: the CSG scene format;
//! - [`volume`]: voxel volumes as operands (`mint volume`): their frames,
//!   grid, and the discretize pass that samples slices into shards.
//!
//! Above the engine: `mint-decimate` (the engine to an intermediate mesh,
//! then quadric edge collapse). Beside it: `mint-check` (`mint check`
//! within a memory budget). The memory budget's shares are
//! `mint_store::Budget`; the worker pool is `mint_core::pool`.

pub mod bounds;
pub mod deref;
pub mod discretize;
pub mod engine;
pub mod error;
pub mod kernels;
pub mod plan;
pub mod progress;
pub mod scene;
pub mod slabs;
pub mod slurm;
pub mod spec;
pub mod stages;
pub mod summary;
pub mod volume;
pub mod workdir;

pub use mint_store::budget::{self, default_mem_bytes, Budget};
pub use engine::{plan_run, run, run_scene, run_task, status, summarize_dir, RunStatus, StageStatus, TaskOptions, TaskOutcome};
pub use deref::Deref;
pub use error::PipelineError;
pub use plan::{Plan, Stage};
pub use spec::{GridSpec, Job, RawLayout, RunSpec, SlabAxis, Tuning, VolumeJob, VolumeSurface, WriteSpec};
pub use summary::ResampleSummary;
pub use progress::{NoProgress, Phase, Progress};
pub use scene::{parse_scene, Scene, SceneError};
