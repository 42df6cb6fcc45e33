//! mint's synthetic test meshes. Every generator streams an indexed triangle
//! mesh into a [`MeshSink`] (all vertices, then all faces, outward
//! orientation, as the sink contract says) and computes each vertex and
//! face from its index by formula, so memory stays `O(√faces)` (trig tables
//! and per-row tables; plus `O(defects)` for the scan) and hundreds of
//! millions of faces can go straight to a file writer. No
//! generator does I/O.
//!
//! - [`sphere()`] ([`sphere`](mod@sphere)): a UV sphere with poles.
//! - [`torus()`] ([`torus`](mod@torus)): a torus around the z axis (genus 1).
//! - [`genus()`] ([`plate`]): a thick plate with `n` square holes (genus `n`).
//! - [`components()`] ([`balls`]): many small disjoint spheres on a lattice.
//! - [`torus_shuffled()`] and [`shuffle_mesh()`] ([`shuffle`]): the same
//!   meshes with vertices and faces in a pseudo-random order, as scans come.
//! - [`volume`]: synthetic voxel volumes (a smooth field with thin
//!   features, a label map), one slice at a time, for `mint gen volume`.
//! - [`scan_like()`] ([`scan`]): a noisy sphere with holes, flipped faces,
//!   duplicated patches and non-manifold slivers at known sites, returning
//!   [`ScanDefects`], which states the exact counts `mint_mesh::check`
//!   must report.
//!
//! Each returns, besides the mesh, the analytic surface it approximates
//! ([`ExactSurface`], in [`surface`]) with a signed distance, volume and area,
//! so tests can measure the mesh against the truth. Each takes a target face
//! count and documents how close it gets. Randomness (only in
//! [`components()`] and [`scan_like()`]) comes from a seed through a
//! self-contained SplitMix64 ([`rng`]); the others are fully determined by
//! their parameters.

pub mod balls;
pub mod colour;
pub mod error;
pub mod plate;
pub mod rng;
pub mod scan;
pub mod shuffle;
pub mod sphere;
pub mod surface;
pub mod torus;
pub mod volume;

pub use balls::components;
pub use error::GenError;
pub use mint_core::{CountingSink, MeshSink, SinkError, TriMesh};
pub use plate::{genus, Plate};
pub use scan::{scan_like, ExpectedCheck, ScanDefects, ScanOptions};
pub use shuffle::{shuffle_mesh, torus_shuffled, Permutation};
pub use sphere::{sphere, SphereGrid};
pub use surface::{BallLattice, ExactSurface, PlateSurface, ScanSurface, SphereSurface, TorusSurface};
pub use torus::{torus, TorusGrid};

use serde::{Deserialize, Serialize};

/// What a generator produced: sizes, topology and the exact surface.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Generated {
    /// Vertices pushed into the sink.
    pub vertices: u64,
    /// Faces pushed into the sink.
    pub faces: u64,
    /// Connected components (all closed 2-manifolds).
    pub components: u64,
    /// Genus of each component (all components have the same genus).
    pub genus: u64,
    /// The analytic surface the mesh approximates.
    pub surface: ExactSurface,
}

/// Checks that a vertex count can be addressed by `u32` face indices.
pub(crate) fn check_vertex_count(vertices: u64) -> Result<(), GenError> {
    if vertices > u64::from(u32::MAX) {
        return Err(GenError::TooManyVertices { vertices });
    }
    Ok(())
}

/// Rejects a parameter that is not a finite positive number.
pub(crate) fn positive(name: &'static str, x: f64) -> Result<(), GenError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(GenError::InvalidParameter {
            name,
            reason: format!("{x} is not a finite positive number"),
        })
    }
}

pub(crate) fn finite3(name: &'static str, p: [f64; 3]) -> Result<(), GenError> {
    if p.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(GenError::InvalidParameter {
            name,
            reason: format!("{p:?} is not finite"),
        })
    }
}
