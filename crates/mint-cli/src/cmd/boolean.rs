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
    let job = a.job()?;
    let spec = a.run.spec(job.clone(), &a.output, None)?;
    let bars = Bars::new(a.run.report.silent());
    let s = mint_pipeline::run(&spec, &a.run.tuning(), &bars)?;
    if a.run.preview {
        // The meshes and the result (a volume operand has no mesh to show).
        let Job::Bool { a: fa, b: fb, iso_a, iso_b, .. } = job else { unreachable!() };
        let shown: Vec<Vec<std::path::PathBuf>> = [(fa, iso_a), (fb, iso_b)].into_iter().filter(|(_, iso)| iso.is_none()).map(|(f, _)| f).chain([vec![a.output.clone()]]).collect();
        write_preview(&shown, &a.output, a.run.preview_up.up, a.run.report.silent(), &bars)?;
    }
    report(&a.run.report, &s)
}
