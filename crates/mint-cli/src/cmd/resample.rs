//! `mint resample`: Marching Intersections resampling of a mesh of any size
//! into a watertight 2-manifold mesh, out of core, with bounded memory.
//! Calls `mint_pipeline::resample` (a PLY range image is triangulated first,
//! see `jobs::resample_input`); `mint demo` runs it through
//! `resample_and_report`.

use crate::jobs::{resample_input, resample_options, ResampleArgs};
use crate::preview::write_before_after;
use crate::progress::Bars;
use crate::summary::print_resample_summary;
use anyhow::Result;
use mint_pipeline::resample;
use std::path::PathBuf;

pub(crate) fn cmd_resample(a: ResampleArgs) -> Result<()> {
    resample_and_report(a).map(|_| ())
}

pub(crate) fn resample_and_report(a: ResampleArgs) -> Result<mint_pipeline::ResampleSummary> {
    let opts = resample_options(&a)?;
    crate::paths::check_output(&a.output, &[&a.input])?;
    let mem = opts.mem_bytes;
    let tmp_root = a.tmp.clone().unwrap_or_else(|| a.output.parent().filter(|p| !p.as_os_str().is_empty()).map(PathBuf::from).unwrap_or_else(|| PathBuf::from(".")));
    let (input, _range_mesh) = resample_input(&a.input, a.staged.work.as_deref(), &tmp_root)?;
    let bars = Bars::new(a.quiet || a.json);
    let mut summary = resample(&input, &a.output, &opts, &bars)?;
    summary.input = a.input.display().to_string();
    if a.preview {
        write_before_after(&input, &a.output, a.quiet || a.json, &bars)?;
    }
    print_resample_summary(&summary, a.json, a.quiet, mem)?;
    Ok(summary)
}
