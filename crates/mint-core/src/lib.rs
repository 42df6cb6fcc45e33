//! mint's geometry core. It does no I/O: everything here works on values in
//! memory and pushes results into sinks.
//!
//! Data flows through it in this order:
//! - [`grid`]: the [`Grid`] and the local frame; world points become grid coordinates;
//! - [`predicates`]: exact orientation tests with the grid's symbolic tie-break;
//! - [`discretize`]: one triangle → its signed [`Crossing`]s with grid lines;
//! - [`intercept`]: the 16-byte [`Intercept`] record, per-line sorting and the removal filter;
//! - [`colour`]: the colour of a crossing and of each output vertex (coloured inputs);
//! - [`mc_table`]: the generated marching-cubes table;
//! - [`cells`]: slab results and the one walk over a slab's cells, numbering vertices;
//! - [`reconstruct`]: a slab of cells → vertices and triangles (the paper's strict rule);
//! - [`signs`]: sign rules for dirty scans, node states and the census that picks a rule;
//! - [`expr`]: CSG expressions over solids and where their value changes along an edge;
//! - [`holes`]: which hole-capping cells stay open under `--max-hole`;
//! - [`robust`]: the state-first reconstruction of one solid or a CSG expression, closing holes;
//! - [`primitives`]: analytic solids that intersect grid lines exactly (for CSG);
//! - [`volume`]: voxel volumes on the grid: node values from slices, the iso-surface's crossings;
//! - [`in_core`]: the whole resampling in memory (strict, robust, hole protocol), for tests and small inputs;
//! - [`rng`]: SplitMix64, the seeded generator shared by samplers and generators;
//! - [`sink`]: the [`MeshSink`] trait through which meshes leave algorithms;
//! - [`pool`]: the one worker pool of the parallel passes (numbered items, first error wins);
//! - [`choice`]: closed sets of named values (sign rule, boolean operator…), named once for the command line and for plans.

pub mod cells;
pub mod choice;
pub mod colour;
pub mod discretize;
pub mod expr;
pub mod grid;
pub mod holes;
pub mod in_core;
pub mod intercept;
pub mod mc_table;
pub mod pool;
pub mod predicates;
pub mod primitives;
pub mod progress;
pub mod reconstruct;
pub mod rng;
pub mod robust;
pub mod signs;
pub mod sink;
pub mod volume;

pub use discretize::{discretize_triangle, Crossing, MARGIN};
pub use grid::{Grid, GridError, GridSize};
pub use intercept::{filter_plane, FilterStats, Intercept, PlaneLines};
pub use sink::{CountingSink, MeshSink, SinkError, TriMesh};
