//! mint-contour: surfaces from stacks of planar contours, after M. Dangl,
//! "Three-Dimensional Object Reconstruction from Layered Spatial Data"
//! (PRIP-TR-50, TU Vienna, 1998), and the normal-angle mesh optimizer.
pub mod geom2d;
pub mod triangulate;
pub mod error;
pub mod profile;

pub use error::{ContourError, ProfileError, ProfileErrorKind};
pub mod mc;
pub mod angle;
pub mod slice;
pub mod optimize;
pub mod run;
