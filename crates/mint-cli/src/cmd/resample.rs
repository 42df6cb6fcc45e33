//! `mint resample`: Marching Intersections resampling of a mesh of any size
//! into a watertight 2-manifold mesh, out of core, with bounded memory.
//! Builds the run's spec from the shared arguments (`jobs::RunArgs`) and
//! calls `mint_pipeline::run` (a PLY range image is triangulated first, see
//! `jobs::resample_input`); `mint demo` runs it through
//! `resample_and_report`.

use crate::jobs::{resample_inputs, surface_files, ResampleArgs};
use crate::preview::write_before_after;
use crate::progress::Bars;
use crate::summary::print_resample_summary;
use anyhow::Result;
use mint_pipeline::Job;
use std::path::PathBuf;

pub(crate) fn cmd_resample(a: ResampleArgs) -> Result<()> {
    resample_and_report(&a).map(|_| ())
}

pub(crate) fn resample_and_report(a: &ResampleArgs) -> Result<mint_pipeline::ResampleSummary> {
    let r = &a.run;
    let tuning = r.tuning();
    let tmp_root = r.tmp.clone().unwrap_or_else(|| a.output.parent().filter(|p| !p.as_os_str().is_empty()).map(PathBuf::from).unwrap_or_else(|| PathBuf::from(".")));
    let files = surface_files(&a.inputs)?;
    crate::paths::check_output(&a.output, &files.iter().map(|p| p.as_path()).collect::<Vec<_>>())?;
    let (inputs, _range_mesh) = resample_inputs(&files, r.staged.work.as_deref(), &tmp_root)?;
    let spec = r.spec(Job::Resample { inputs: inputs.clone() }, &a.output, Some(&a.holes))?;
    let bars = Bars::new(r.report.silent());
    let mut summary = mint_pipeline::run(&spec, &tuning, &bars)?;
    if let [one] = files.as_slice() {
        summary.input = one.display().to_string();
    }
    if r.preview {
        write_before_after(&inputs, &a.output, r.preview_up.up, r.report.silent(), &bars)?;
    }
    print_resample_summary(&summary, r.report.json(), r.report.quiet(), tuning.mem_bytes)?;
    Ok(summary)
}
