//! `mint zipper` as a library call: [`merge_file`] reads a scan set (`.conf`
//! or `.aln`), opens its scans within a memory budget, merges them by
//! zippering or on a grid, writes the mesh (temporary file beside it,
//! renamed at the end) and judges it. Scans the set flags as failed (`mint
//! align` could not register them) are left out unless the options include
//! them. The CLI only parses, calls and prints.

use crate::error::RangeError;
use crate::grid_merge::{grid_merge_with, GridMergeOptions, GridMergeReport};
use crate::scan_mesh::MeshOptions;
use crate::scanset::ScanSet;
use crate::source::ScanFiles;
use crate::zipper::{zipper_with, ZipperOptions, ZipperReport};
use mint_core::progress::Progress;
use serde::Serialize;
use std::path::Path;

/// How to merge.
#[derive(Debug, Clone)]
pub enum MergeMethod {
    /// Zippering and consensus geometry (Turk & Levoy 1994).
    Zipper(ZipperOptions),
    /// Votes along the lines of a grid, then the robust reconstruction.
    Grid(GridMergeOptions),
}

/// Options of [`merge_file`].
#[derive(Debug, Clone)]
pub struct MergeFileOptions {
    pub method: MergeMethod,
    /// Bytes of scans held at once; scans beyond it are read again when
    /// needed (the output is the same).
    pub scan_mem: usize,
    /// How the output is encoded.
    pub write: mint_io::WriteOptions,
    /// Merge scans the set flags as failed ([`crate::ScanEntry::failed`])
    /// too, at their poses; by default they are left out.
    pub include_failed: bool,
}

/// The report of either method.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum MergeReport {
    Zipper(ZipperReport),
    Grid(GridMergeReport),
}

impl MergeReport {
    /// `"zipper"` or `"grid"`.
    pub fn method(&self) -> &'static str {
        match self {
            MergeReport::Zipper(_) => "zipper",
            MergeReport::Grid(_) => "grid",
        }
    }
}

/// What [`merge_file`] did.
#[derive(Debug, Clone, Serialize)]
pub struct MergeSummary {
    /// Scans merged.
    pub scans: usize,
    /// Scans left out because the set flags them as failed (their file
    /// names as the set writes them).
    pub skipped_failed: Vec<String>,
    pub report: MergeReport,
    /// The output judged as `mint check` judges it.
    pub check: mint_mesh::CheckReport,
    /// Scan files read (more than the scans when `scan_mem` is short), and
    /// the most bytes of scans held at once.
    pub scan_reads: usize,
    pub peak_scan_bytes: usize,
    pub seconds: f64,
}

/// Merges the scans of the set in `set_path` into the mesh `output`; see
/// the module docs.
pub fn merge_file(set_path: &Path, output: &Path, opts: &MergeFileOptions, progress: &dyn Progress) -> Result<MergeSummary, RangeError> {
    let t = std::time::Instant::now();
    let mut set = ScanSet::read(set_path)?;
    let mut skipped_failed = Vec::new();
    if !opts.include_failed {
        let (kept, flagged) = set.split_failed();
        skipped_failed = flagged.into_iter().map(|e| e.file).collect();
        set = kept;
        if set.entries.is_empty() {
            return Err(RangeError::Output { path: set_path.to_path_buf(), message: format!("every scan of the set is flagged as failed ({}); nothing to merge (--include-failed merges them anyway)", skipped_failed.len()) });
        }
    }
    let scans = ScanFiles::open_with(&set, set_path, &MeshOptions::default(), opts.scan_mem, progress)?;
    let poses: Vec<_> = set.entries.iter().map(|e| e.pose).collect();
    let (positions, faces, report) = match &opts.method {
        MergeMethod::Zipper(o) => {
            let (p, f, r) = zipper_with(&scans, &poses, o, progress)?;
            (p, f, MergeReport::Zipper(r))
        }
        MergeMethod::Grid(o) => {
            let (p, f, r) = grid_merge_with(&scans, &poses, o, progress)?;
            (p, f, MergeReport::Grid(r))
        }
    };
    let format = mint_io::Format::from_path(output)?;
    let mut w = mint_io::MeshWriter::create(output, format, opts.write.clone())?;
    for p in &positions {
        w.write_vertex(*p)?;
    }
    for f in &faces {
        w.write_face(*f)?;
    }
    w.finish()?;
    let check = mint_mesh::check(&positions, &faces);
    let (scan_reads, peak_scan_bytes) = scans.loads();
    Ok(MergeSummary { scans: set.entries.len(), skipped_failed, report, check, scan_reads, peak_scan_bytes, seconds: t.elapsed().as_secs_f64() })
}
