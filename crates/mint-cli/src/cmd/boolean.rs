//! `mint bool`: the union, intersection or difference of two meshes,
//! computed on the intersection lists of one grid: out of core, watertight.
//! Calls `mint_pipeline::boolean`; the arguments (`BoolArgs`, shared with
//! `mint stage plan bool` and `mint slurm bool`) live in `jobs`.

use crate::jobs::{grid_options, BoolArgs, BoolOpArg};
use crate::preview::write_preview;
use crate::progress::Bars;
use crate::summary::report;
use anyhow::Result;

pub(crate) fn cmd_bool(a: BoolArgs) -> Result<()> {
    let opts = grid_options(&a.grid)?;
    crate::paths::check_output(&a.output, &[&a.a, &a.b])?;
    let op = match a.op {
        BoolOpArg::Union => mint_core::expr::BoolOp::Union,
        BoolOpArg::Intersection => mint_core::expr::BoolOp::Intersection,
        BoolOpArg::Difference => mint_core::expr::BoolOp::Difference,
    };
    let bars = Bars::new(a.grid.quiet || a.grid.json);
    let s = mint_pipeline::boolean(op, &a.a, &a.b, &a.output, &opts, &bars)?;
    if a.grid.preview {
        write_preview(&[a.a.as_path(), a.b.as_path(), a.output.as_path()], &a.output, a.grid.quiet || a.grid.json, &bars)?;
    }
    report(&a.grid, &s)
}
