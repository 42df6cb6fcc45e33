//! `mint bool`: the union, intersection or difference of two meshes,
//! computed on the intersection lists of one grid: out of core, watertight.
//! Calls `mint_pipeline::run`; the arguments (`BoolArgs`, shared with
//! `mint stage plan bool` and `mint slurm bool`) live in `jobs`.

use crate::jobs::BoolArgs;
use crate::preview::write_preview;
use crate::progress::Bars;
use crate::summary::report;
use anyhow::Result;
use mint_pipeline::Job;

pub(crate) fn cmd_bool(a: BoolArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.a, &a.b])?;
    let spec = a.run.spec(Job::Bool { op: a.op, a: a.a.clone(), b: a.b.clone() }, &a.output, None)?;
    let bars = Bars::new(a.run.report.silent());
    let s = mint_pipeline::run(&spec, &a.run.tuning(), &bars)?;
    if a.run.preview {
        write_preview(&[a.a.as_path(), a.b.as_path(), a.output.as_path()], &a.output, a.run.report.silent(), &bars)?;
    }
    report(&a.run.report, &s)
}
