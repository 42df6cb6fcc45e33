//! mint-contour: surfaces from stacks of planar contours, after M. Dangl,
//! "Three-Dimensional Object Reconstruction from Layered Spatial Data"
//! (PRIP-TR-50, TU Vienna, 1998), and the normal-angle mesh optimizer.
//!
//! Data flows through it in this order:
//! - [`profile`]: the `.pro` format; [`ProfileReader`](profile::ProfileReader)
//!   streams validated [`Section`](profile::Section)s (planar, parallel,
//!   ordered, simple and disjoint contours, else a [`ProfileError`] naming
//!   the line) in a right-handed [`StackFrame`](profile::StackFrame);
//! - [`mc`]: marching cubes over the stack: contour crossings with grid
//!   lines become mint-core intercepts, reconstructed window by window with
//!   `mint_core::reconstruct::reconstruct_slab` (watertight with caps);
//! - [`angle`]: the angle-criterion strips between consecutive sections,
//!   with branching by splitting and bridging contours and caps by
//!   [`triangulate`]; each strip is a [`tiling`] (the paper's march, or the
//!   minimum-area tiling as a fallback) accepted only if the exact
//!   [`slabcheck`] finds no crossing;
//! - [`triangulate`]: smallest-inner-angle-first ear clipping, holes joined
//!   by bridges; also used by [`optimize`];
//! - [`optimize`]: the normal optimizer (regions of near-coplanar faces
//!   re-triangulated from their boundaries);
//! - [`rtstruct`]: DICOM RT structure sets (dicom-rs): an ROI's contours
//!   become the same validated [`Section`](profile::Section)s, grouped and
//!   ordered along the normal of their planes;
//! - [`slice`](mod@slice): a mesh cut by parallel planes into contours (test data);
//! - [`run`]: the file-to-file drivers of `mint slice`, `mint contours` and
//!   `mint optimize`, with their status counters ([`run::RunStats`]); with
//!   [`rtstruct`], the only modules that touch files.
//!
//! Meshes leave the algorithms through [`mint_core::MeshSink`]; the
//! reconstructions send faces as soon as their vertices are out, so file
//! output goes through [`run::SpillSink`]. Planar topology decisions are
//! exact ([`geom2d`] wraps Shewchuk's `orient2d`); errors are
//! [`ContourError`]. Design notes: `crates/mint-contour/README.md`.

pub mod angle;
pub mod error;
pub mod geom2d;
pub mod mc;
pub mod optimize;
pub mod profile;
pub mod rtstruct;
pub mod run;
pub mod slabcheck;
pub mod slice;
pub mod tiling;
pub mod triangulate;

pub use error::{ContourError, DicomError, DicomErrorKind, ProfileError, ProfileErrorKind};

/// The phases this crate reports through `mint_core::progress::Progress`.
pub mod phases {
    /// Reading the sections of a contour stack (units: sections).
    pub const SECTIONS: mint_core::progress::Phase = mint_core::progress::Phase::named("sections");
    /// Reconstructing a surface from contour sections (units: sections).
    pub const CONTOURS: mint_core::progress::Phase = mint_core::progress::Phase::named("contours");
    /// Cutting a mesh into sections (units: bytes of the input).
    pub const SLICE: mint_core::progress::Phase = mint_core::progress::Phase::named("slice");
}
