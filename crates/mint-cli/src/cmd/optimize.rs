//! `mint optimize`: reduces an over-tessellated mesh by merging
//! near-coplanar triangles into regions and re-triangulating each from its
//! boundary (Dangl's normal optimizer); no vertex moves. Calls
//! `mint_contour::run::optimize_file`.

use crate::jobs::{QuietArg, JsonArg};
use crate::contour_report::{report, write_options};
use anyhow::Result;
use clap::Args;
use mint_contour::run::{self, MethodStats};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct OptimizeArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Normal angle threshold in degrees: triangles merge into a region when
    /// all their normals lie within this angle of one another; 0 merges only
    /// exactly coplanar triangles.
    #[arg(long)]
    pub angle: f64,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 instead of f32.
    #[arg(long)]
    pub double: bool,
    /// Write the status file (time, counts, parameters) as JSON here.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    pub quiet: QuietArg,
    #[command(flatten)]
    pub json: JsonArg,
}

pub fn cmd_optimize(a: OptimizeArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    if let Some(st) = &a.stats {
        crate::paths::check_output(st, &[&a.input, &a.output])?;
    }
    let s = run::optimize_file(&a.input, &a.output, a.angle, write_options(a.ascii, a.double))?;
    let MethodStats::Optimize(d) = &s.details else { unreachable!() };
    let line = format!(
        "optimized {} -> {}: {} -> {} faces ({:.1}% fewer), {} -> {} vertices; {} regions, {} re-triangulated, {} kept, {} collinear vertices dropped",
        a.input.display(),
        a.output.display(),
        d.faces_in,
        d.faces_out,
        100.0 * (1.0 - d.faces_out as f64 / (d.faces_in.max(1)) as f64),
        d.vertices_in,
        d.vertices_out,
        d.regions,
        d.regions_optimized,
        d.regions_kept,
        d.collinear_dropped
    );
    report(&s, &a.stats, a.quiet.quiet, a.json.json, line)
}
