//! One module per `mint` subcommand: its clap arguments (and value enums)
//! and its `cmd_…` function, which checks the arguments, calls one library
//! entry point and prints a summary (or `--json`). `crate::cli` dispatches
//! to them. What several commands share lives outside: argument groups and
//! option builders in `crate::jobs`, printing in `crate::summary`,
//! `crate::preview` and `crate::contour_report`.

pub mod align;
pub mod boolean;
pub mod check;
pub mod contours;
pub mod convert;
pub mod csg;
pub mod decimate;
pub mod demo;
pub mod distance;
pub mod gen;
pub mod info;
pub mod optimize;
pub mod render;
pub mod resample;
pub mod scan;
pub mod simplify;
pub mod slice;
pub mod slurm;
pub mod stage;
pub mod validate;
pub mod volume;
pub mod zipper;
