//! `mint slice`: cuts a mesh by N parallel planes into a stack of closed
//! planar contours (a .pro profile): test data for `mint contours`, and
//! cross-sections for users. Calls `mint_contour::run::slice_file`.

use crate::jobs::{QuietArg, JsonArg};
use crate::contour_report::report;
use anyhow::Result;
use clap::{Args, ValueEnum};
use mint_contour::run::{self, MethodStats};
use std::path::PathBuf;

/// An axis of the input mesh.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SliceAxis {
    X,
    Y,
    Z,
}

#[derive(Args, Debug)]
pub struct SliceArgs {
    /// Input mesh (any format mint reads).
    pub input: PathBuf,
    /// Output profile (.pro), written to a temporary file and renamed at the end.
    pub output: PathBuf,
    /// Number of cutting planes, evenly spaced across the mesh's extent along
    /// the axis (plane k at min + (k + 1/2) * extent / N).
    #[arg(long)]
    pub sections: u32,
    /// Axis the planes are orthogonal to.
    #[arg(long, value_enum, default_value_t = SliceAxis::Z)]
    pub axis: SliceAxis,
    /// Write the status file (time, counts, parameters) as JSON here.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    pub quiet: QuietArg,
    #[command(flatten)]
    pub json: JsonArg,
}

pub fn cmd_slice(a: SliceArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    if let Some(st) = &a.stats {
        crate::paths::check_output(st, &[&a.input, &a.output])?;
    }
    let axis = a.axis as usize;
    let s = run::slice_file(&a.input, &a.output, a.sections, axis, &crate::progress::Bars::new(a.quiet.quiet || a.json.json))?;
    let MethodStats::Slice(d) = &s.details else { unreachable!() };
    let line = format!(
        "sliced {} -> {}: {} of {} planes met the mesh, {} contours, {} vertices ({} open chains closed, {} contours dropped)",
        a.input.display(),
        a.output.display(),
        d.sections,
        d.planes,
        d.contours,
        d.vertices,
        d.chains_closed,
        d.contours_dropped
    );
    report(&s, &a.stats, a.quiet.quiet, a.json.json, line)
}
