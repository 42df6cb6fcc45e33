//! `mint zipper`: merges registered range scans into one mesh, by
//! zippering and consensus geometry or by signed-distance voting on one
//! grid. Calls `mint_range::merge_file`.

use crate::jobs::{JsonArg, MemArg};
use anyhow::Result;
use clap::{Args, ValueEnum};
use mint_range::grid_merge::GridMergeOptions;
use mint_range::zipper::ZipperOptions;
use mint_range::ScanSet;
use std::path::PathBuf;

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeMethod {
    /// Zippering and consensus geometry (Turk and Levoy).
    Zipper,
    /// Signed-distance voting on the grid lines and MI reconstruction.
    Grid,
}

#[derive(Args, Debug)]
pub struct ZipperArgs {
    /// Scan set with registered poses (.conf or .aln).
    pub set: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Redundancy tolerance d as a multiple of the sampling distance s.
    #[arg(long, default_value_t = 3.0)]
    pub distance_factor: f64,
    /// Skip consensus geometry (vertices stay where their scan put them).
    #[arg(long)]
    pub no_consensus: bool,
    /// How to merge.
    #[arg(long, value_enum, default_value_t = MergeMethod::Zipper)]
    pub method: MergeMethod,
    /// Grid method: about this many cubic cells over the scans' bounding box.
    /// Detail below a cell is dropped, and parts thinner than about a cell
    /// can come apart (the bunny needs 2M cells to keep the back of its
    /// head in one piece); raise it for more detail.
    #[arg(long, conflicts_with = "cell_size", default_value_t = 1_000_000)]
    pub cells: u64,
    /// Grid method: cell edge length in scan units (instead of --cells).
    #[arg(long)]
    pub cell_size: Option<f64>,
    /// Scans are read from their files when needed and the most recently
    /// used kept within --mem; with less than the whole set, scans are read
    /// more than once (the output is the same). The model and the grid come
    /// on top.
    #[command(flatten)]
    pub mem: MemArg,
    /// Grid method: half-width of a crossing's vote along its grid line, in
    /// scan units [default: the larger of 1.5 cells and 3 sampling distances].
    #[arg(long)]
    pub band: Option<f64>,
    /// Also write OUT.png beside the output: a picture of the merged surface
    /// (see `mint render`).
    #[arg(long)]
    pub preview: bool,
    #[command(flatten)]
    pub preview_up: crate::preview::PreviewUp,
    /// Also merge scans the set flags as failed (`mint align` writes them at
    /// their initial pose with a `# mint: failed:` line); by default they
    /// are left out, with a warning naming them.
    #[arg(long)]
    pub include_failed: bool,
    #[command(flatten)]
    pub json: JsonArg,
}

pub fn cmd_zipper(a: ZipperArgs) -> Result<()> {
    let set = ScanSet::read(&a.set)?;
    let mut inputs: Vec<&std::path::Path> = vec![&a.set];
    inputs.extend(set.entries.iter().map(|e| e.path.as_path()));
    crate::paths::check_output(&a.output, &inputs)?;
    if a.preview {
        crate::paths::check_output(&crate::preview::preview_path(&a.output), &inputs)?;
    }
    let bars = crate::progress::Bars::new(a.json.json);
    let method = match a.method {
        MergeMethod::Zipper => mint_range::MergeMethod::Zipper(ZipperOptions { distance_factor: a.distance_factor, consensus: !a.no_consensus, ..Default::default() }),
        MergeMethod::Grid => {
            let size = match a.cell_size {
                Some(h) => mint_core::GridSize::CellSize(h),
                None => mint_core::GridSize::Cells(a.cells),
            };
            mint_range::MergeMethod::Grid(GridMergeOptions { size, band: a.band, ..Default::default() })
        }
    };
    let opts = mint_range::MergeFileOptions { method, scan_mem: a.mem.bytes() as usize, write: Default::default(), include_failed: a.include_failed };
    let s = mint_range::merge_file(&a.set, &a.output, &opts, &bars)?;
    let (report, check, secs) = (&s.report, &s.check, s.seconds);
    if a.preview {
        crate::preview::write_preview(&[vec![a.output.clone()]], &a.output, a.preview_up.up, a.json.json, &bars)?;
    }
    if !s.skipped_failed.is_empty() && !a.json.json {
        eprintln!("warning: left out {} scans the set flags as failed: {} (--include-failed merges them)", s.skipped_failed.len(), s.skipped_failed.join(" "));
    }
    if a.json.json {
        let key = report.method();
        let v = serde_json::json!({ "set": a.set.display().to_string(), "output": a.output.display().to_string(), "seconds": secs, key: report, "check": check, "skipped_failed": s.skipped_failed, "scan_reads": s.scan_reads, "peak_scan_bytes": s.peak_scan_bytes, "peak_heap_bytes": crate::alloc::peak_heap() });
        crate::out::json(&v)?;
        return Ok(());
    }
    match report {
        mint_range::MergeReport::Zipper(rep) => {
            eprintln!("zippered {} scans of {} in {secs:.2}s -> {}: {} vertices, {} faces", rep.scans, a.set.display(), a.output.display(), rep.vertices, rep.faces);
            eprintln!("  redundant {} , trimmed {}, stitched {}, holes filled {}, small-triangle vertices {}", rep.redundant, rep.trimmed, rep.stitched, rep.holes_filled, rep.small_triangle_vertices);
        }
        mint_range::MergeReport::Grid(rep) => {
            eprintln!("merged {} scans of {} on a {}x{}x{} grid (cell {:.4e}) in {secs:.2}s -> {}: {} vertices, {} faces", rep.scans, a.set.display(), rep.dims[0], rep.dims[1], rep.dims[2], rep.cell, a.output.display(), rep.vertices, rep.faces);
            eprintln!(
                "  {} crossings; nodes voted {}, filled {}; vertices from crossings {} ({} merged across scans), interpolated {}, midpoints {}",
                rep.crossings, rep.voted_nodes, rep.filled_nodes, rep.vertices_from_crossings, rep.vertices_merged, rep.vertices_interpolated, rep.vertices_midpoint
            );
        }
    }
    eprintln!(
        "  2-manifold: {} (non-manifold edges {}, vertices {}), boundary loops {}, components {}",
        check.non_manifold_edges == 0 && check.non_manifold_vertices == 0,
        check.non_manifold_edges,
        check.non_manifold_vertices,
        check.boundary_loops,
        check.components
    );
    if let mint_range::MergeReport::Zipper(rep) = report {
        if let Some(c) = &rep.consensus {
            eprintln!("  consensus: {} vertices moved, mean {:.3e}, max {:.3e}, {:.2} scans each", c.moved, c.mean_move, c.max_move, c.mean_scans);
        }
    }
    eprintln!("  scans read {} times for {} scans (at most {:.1} MiB of scans held at once, budget --mem {:.0} MiB)", s.scan_reads, s.scans, s.peak_scan_bytes as f64 / 1048576.0, a.mem.bytes() as f64 / 1048576.0);
    Ok(())
}
