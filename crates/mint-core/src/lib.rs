//! mint's geometry core. It does no I/O: everything here works on values in
//! memory and pushes results into sinks.
//!
//! Data flows through it in this order:
//! - [`grid`]: the [`Grid`] and the local frame; world points become grid coordinates;
//! - [`predicates`]: exact orientation tests with the grid's symbolic tie-break;
//! - [`discretize`]: one triangle → its signed [`Crossing`]s with grid lines;
//! - [`intercept`]: the 16-byte [`Intercept`] record, per-line sorting and the removal filter;
//! - [`mc_table`]: the generated marching-cubes table;
//! - [`reconstruct`]: one layer of cells → vertices and triangles (the paper's strict rule);
//! - [`primitives`]: analytic solids that intersect grid lines exactly (for CSG);
//! - [`holes`]: which hole-capping cells stay open under `--max-hole`;
//! - [`signs`], [`robust`]: sign rules for dirty scans and the state-first reconstruction;
//! - [`expr`]: CSG expressions over solids and where their value changes along an edge;
//! - [`rng`]: SplitMix64, the seeded generator shared by samplers and generators;
//! - [`sink`]: the [`MeshSink`] trait through which meshes leave algorithms.

pub mod discretize;
pub mod expr;
pub mod grid;
pub mod holes;
pub mod intercept;
pub mod mc_table;
pub mod predicates;
pub mod primitives;
pub mod progress;
pub mod reconstruct;
pub mod rng;
pub mod robust;
pub mod signs;
pub mod sink;

pub use discretize::{discretize_triangle, Crossing, MARGIN};
pub use grid::{Grid, GridError, GridSize};
pub use intercept::{filter_plane, FilterStats, Intercept, PlaneLines};
pub use sink::{CountingSink, MeshSink, SinkError, TriMesh};
