//! `mint bool`: the union, intersection or difference of two meshes,
//! computed on the intersection lists of one grid: out of core, watertight.
//! Calls `mint_pipeline::run`; the arguments (`BoolArgs`, shared with
//! `mint stage plan bool` and `mint slurm bool`) live in `jobs`.

use crate::jobs::{surface_files, BoolArgs};
use crate::preview::write_preview;
use crate::progress::Bars;
use crate::summary::report;
use anyhow::Result;
use mint_pipeline::Job;

pub(crate) fn cmd_bool(a: BoolArgs) -> Result<()> {
    let (fa, fb) = (surface_files(std::slice::from_ref(&a.a))?, surface_files(std::slice::from_ref(&a.b))?);
    crate::paths::check_output(&a.output, &fa.iter().chain(&fb).map(|p| p.as_path()).collect::<Vec<_>>())?;
    let spec = a.run.spec(Job::Bool { op: a.op, a: fa.clone(), b: fb.clone() }, &a.output, None)?;
    let bars = Bars::new(a.run.report.silent());
    let s = mint_pipeline::run(&spec, &a.run.tuning(), &bars)?;
    if a.run.preview {
        write_preview(&[fa, fb, vec![a.output.clone()]], &a.output, a.run.preview_up.up, a.run.report.silent(), &bars)?;
    }
    report(&a.run.report, &s)
}
