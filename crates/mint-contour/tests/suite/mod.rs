//! The integration suite: polygon triangulation on random simple polygons
//! (`triangulation`), analytic stacks reconstructed by both methods
//! (`stacks`), holes and branching (`branching`), exact degenerate
//! placements and windows (`mc_grid`), the optimizer (`optimizer`), profile
//! files and the file drivers (`files`), real data (`real_data`), and DICOM
//! RT structure sets read directly (`rtstruct`).
pub mod util;
mod branching;
mod branching_cases;
mod files;
mod mc_grid;
mod optimizer;
mod real_data;
mod rtstruct;
mod stacks;
mod triangulation;
