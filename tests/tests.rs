//! Cross-crate integration tests, built into one binary (ripgrep's layout).
//! Heavy cases are `#[ignore]`d and run by hand; see each module.

mod common;
mod colour;
pub mod cli;
mod contours_dicom;
mod check_bounded;
mod core_props;
mod fuzz_replay;
mod csg;
mod layout;
mod open;
mod world;
mod resample;
mod robustness;
mod same_bytes;
mod scans;
mod stages;
mod tiles;
mod volume;
