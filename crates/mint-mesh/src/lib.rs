//! mint's in-core mesh tools: the judges that tell whether a mesh is what it
//! should be. Everything works on borrowed flat arrays (`&[[f64; 3]]`
//! positions, `&[[u32; 3]]` faces, or a [`mint_core::TriMesh`]) and does no
//! I/O; the CLI crate reads and writes files around them.
//!
//! - [`check`](mod@check): [`check()`] reads a mesh once and returns a
//!   [`CheckReport`]: counts, bounding box, components, boundary edges and
//!   loops, non-manifold edges and vertices, orientation, degenerate and
//!   duplicate faces, Euler characteristic and genus per closed component,
//!   volume and area. Topology comes from a vertex→face incidence table
//!   (a counting sort), never from hash maps, so tens of millions of faces
//!   fit in a few GB.
//! - [`bvh`]: [`TriangleBvh`], an AABB tree over a mesh's triangles with an
//!   exact nearest-point query ([`closest_point_on_triangle`], Ericson's
//!   method), for any crate that needs point-to-mesh distances.
//! - [`distance`](mod@distance): [`distance()`] and [`symmetric_distance()`],
//!   Metro-style sampled surface distances ([`DistanceReport`]) that are
//!   deterministic for a seed whatever the thread count.
//! - [`normals`]: area-weighted unit vertex normals.
//! - [`rng`]: [`SplitMix64`], the tiny seeded generator the sampler uses.
//! - [`error`]: [`MeshError`], the typed errors for bad input.
//!
//! Parallel work uses rayon with fixed-size chunks whose partial results are
//! combined in chunk order, so every report is bit-identical under any
//! thread count.

pub mod bvh;
pub mod check;
pub mod distance;
mod edge_heap;
pub mod error;
pub mod normals;
pub mod qem;
pub mod rng;
pub mod selfx;
pub mod simplify;
pub mod weld;

pub use bvh::{closest_point_on_triangle, TriangleBvh};
pub use check::{check, check_mesh, try_check, CheckReport};
pub use distance::{
    distance, distance_to_bvh, symmetric_distance, try_distance, try_symmetric_distance,
    DistanceReport, MeshRef,
};
pub use error::MeshError;
pub use rng::SplitMix64;
pub use simplify::{simplify, simplify_coloured, simplify_with, SimplifyOptions, SimplifyReport};
pub use selfx::{faces_intersect, self_intersections, SelfIntersections};
pub use weld::weld;
