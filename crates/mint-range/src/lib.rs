//! mint-range: merging range scans into one mesh, after Turk and Levoy,
//! "Zippered Polygon Meshes from Range Images" (SIGGRAPH 1994), or on the
//! Marching Intersections grid after Rocchini et al. ([`grid_merge`],
//! `mint zipper --method grid`).
//!
//! Data flows through the modules in this order:
//! - [`scanset`]: a [`ScanSet`] (Stanford `.conf` or MeshLab `.aln`) names
//!   the scans and their poses ([`Rigid`], scan frame → world);
//! - [`range_image`]: a [`RangeImage`] (PLY `range_grid`, or mint's own
//!   `.rgrid` depth grid of [`depth_grid`]) is triangulated without
//!   bridging depth discontinuities;
//! - [`scan_mesh`]: a [`ScanMesh`] adds normals, boundary, confidence and
//!   the registration hierarchy;
//! - [`synth`]: `mint scan` — range images ray-cast from a mesh, with true
//!   (and perturbed) poses, through the [`raycast`] BVH;
//! - [`icp`]: `mint align` — constrained ICP (closest points on surfaces
//!   within d, no boundary pairs, weighted Horn quaternion, hierarchy with d
//!   halving, anchor or growing model);
//! - [`multiview`]: `mint align`'s default — every pairwise alignment
//!   judged, scans joined along the largest overlaps, all overlapping
//!   pairs aligned and every pose solved at once (Pulli 1999);
//! - [`zipper`]: `mint zipper` — redundancy removal, trimming, stitching
//!   along the seams, small-triangle removal ([`mesh_ops`]), then
//!   [`consensus`] geometry;
//! - [`grid_merge`]: `mint zipper --method grid` — every posed scan
//!   discretized on one grid, crossings voted as signed distances along
//!   the grid lines, same-edge crossings merged by confidence, then the
//!   resampler's reconstruction: a closed 2-manifold.
//!
//! Everything works in memory on borrowed or owned arrays; only
//! [`scanset`], [`range_image`], [`depth_grid`] and [`scan_mesh::load_scan`] touch files,
//! through mint-io's atomic writers.

pub mod agreement;
pub mod align;
pub mod consensus;
pub mod depth_grid;
pub mod error;
pub mod geom;
pub mod grid_merge;
pub mod icp;
pub mod mesh_ops;
pub mod merge_file;
pub mod multiview;
pub mod range_image;
pub mod raycast;
pub mod scan_file;
pub mod scan_mesh;
pub mod scanset;
pub mod source;
pub mod synth;
pub mod zipper;

pub use error::RangeError;
pub use merge_file::{merge_file, MergeFileOptions, MergeMethod, MergeReport, MergeSummary};

/// A merged mesh: world positions, faces, and the method's report.
pub type Merged<R> = (Vec<[f64; 3]>, Vec<[u32; 3]>, R);
pub use geom::Rigid;
pub use range_image::RangeImage;
pub use scan_mesh::{load_scan, load_set, range_image_as_mesh, MeshOptions, ScanMesh};
pub use scanset::{ScanEntry, ScanSet, SetFormat};
pub use source::{ScanFiles, ScanSource};

/// The phases this crate reports through `mint_core::progress::Progress`.
pub mod phases {
    /// Reading range scans (units: scans).
    pub const LOAD_SCANS: mint_core::progress::Phase = mint_core::progress::Phase::named("load scans");
    /// Registering scans by ICP (units: scans).
    pub const REGISTER: mint_core::progress::Phase = mint_core::progress::Phase::named("register");
    /// Multiview refinement: pairwise alignments of one round (units: pairs).
    pub const REFINE: mint_core::progress::Phase = mint_core::progress::Phase::named("refine");
    /// Multiview: failed scans registered again from other starts (units:
    /// scans).
    pub const RETRY: mint_core::progress::Phase = mint_core::progress::Phase::named("retry");
    /// Measuring how well registered scans agree (units: pairs).
    pub const AGREEMENT: mint_core::progress::Phase = mint_core::progress::Phase::named("agreement");
    /// Zippering scans into the model (units: scans).
    pub const ZIPPER: mint_core::progress::Phase = mint_core::progress::Phase::named("zipper");
    /// Consensus geometry, two passes over the scans (units: scan passes).
    pub const CONSENSUS: mint_core::progress::Phase = mint_core::progress::Phase::named("consensus");
    /// Discretizing scans on the grid merge's grid (units: scans).
    pub const GRID_MERGE: mint_core::progress::Phase = mint_core::progress::Phase::named("grid merge");
}
