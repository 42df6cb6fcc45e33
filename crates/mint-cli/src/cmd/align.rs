//! The range-scan subcommands `mint scan`, `mint align` and `mint zipper`:
//! argument definitions (clap derive, with help that teaches) and the glue
//! to mint-range. Set files are Stanford `.conf` or MeshLab `.aln`, by
//! extension; scan paths inside them are relative to the set file.

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use mint_range::align::align_file;
use mint_range::icp::{AlignOptions, Metric, Status, Strategy};
use mint_range::synth::SynthOptions;
use mint_range::depth_grid::GridEncoding;
use mint_range::grid_merge::GridMergeOptions;
use mint_range::zipper::ZipperOptions;
use mint_range::ScanSet;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ScanArgs {
    /// The mesh to scan (any format mint reads), ideally closed.
    pub mesh: PathBuf,
    /// Directory for the output (created if missing): view_NN.ply range
    /// images, view_NN.mesh.ply their triangle meshes (in each view's own
    /// frame), scans.conf with the true poses.
    pub out_dir: PathBuf,
    /// Number of viewpoints, spread evenly over the sphere.
    #[arg(long, default_value_t = 8)]
    pub views: usize,
    /// Standard deviation of the depth noise, in model units.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Seed of the noise and of the perturbation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Samples across each view (each image has RES x RES cells).
    #[arg(long, default_value_t = 200)]
    pub resolution: u32,
    /// Samples seen at more than this angle (degrees) from the surface normal are lost.
    #[arg(long, default_value_t = 80.0)]
    pub max_angle: f64,
    /// Also write scans-perturbed.conf: every view but the first moved by a
    /// random rotation of up to this many degrees about the mesh centre...
    #[arg(long, default_value_t = 0.0)]
    pub perturb_deg: f64,
    /// ...and a random translation of up to this fraction of the bounding-box diagonal.
    #[arg(long, default_value_t = 0.0)]
    pub perturb_frac: f64,
    /// File format of the range images.
    #[arg(long, value_enum, default_value_t = ImageFormat::Ply)]
    pub image_format: ImageFormat,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// PLY range image (the Stanford scans' layout): view_NN.ply.
    Ply,
    /// mint's depth grid, binary: view_NN.rgrid (docs/FORMATS.md).
    Rgrid,
    /// mint's depth grid, text: view_NN.rgrid.
    RgridAscii,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MetricArg {
    /// Point to plane on the coarse levels (fast into the basin), then
    /// point to point by Horn's method on the last level (unbiased by
    /// noisy normals).
    PlaneThenPoint,
    /// Point to point, Horn's closed-form quaternion (Turk and Levoy's
    /// choice) at every level. Crawls when scans must slide along each
    /// other: from a few degrees off it can stop short by tenths of a degree.
    Point,
    /// Point to plane (Chen and Medioni), linearized.
    Plane,
}

#[derive(Args, Debug)]
pub struct AlignArgs {
    /// Scan set with initial poses (.conf or .aln).
    pub set: PathBuf,
    /// Output scan set with the refined poses, written in the convention of
    /// the input set. Scans that could not be registered are left out (and
    /// reported).
    pub out_set: PathBuf,
    /// Final pairing distance d [default: 2 x the largest sampling distance].
    #[arg(long)]
    pub distance: Option<f64>,
    /// Pairing distance of the coarsest level, halved per level down to d
    /// [default: 8 d]. Raise it when the initial poses are far off.
    #[arg(long)]
    pub start_distance: Option<f64>,
    /// Error metric.
    #[arg(long, value_enum, default_value_t = MetricArg::PlaneThenPoint)]
    pub metric: MetricArg,
    /// Index (0-based, in set order) of the scan that stays fixed.
    #[arg(long, default_value_t = 0)]
    pub anchor: usize,
    /// With --global off: register every scan to the anchor alone instead
    /// of to the growing model of all registered scans.
    #[arg(long)]
    pub anchor_only: bool,
    /// Pair one way only (source samples to target surfaces), as Turk and
    /// Levoy did. By default pairs go both ways, which cancels the bias of
    /// vertex-to-chord distances on curved surfaces.
    #[arg(long)]
    pub one_way: bool,
    /// Convergence: a level ends when an iteration moves the scan's
    /// bounding-box corners by less than this fraction of its sampling
    /// distance.
    #[arg(long, default_value_t = AlignOptions::default().tolerance)]
    pub tolerance: f64,
    /// Samples paired per iteration at most, in each direction (a regular
    /// thinning of the scan's samples).
    #[arg(long, default_value_t = AlignOptions::default().max_samples)]
    pub max_samples: usize,
    /// With --global off: passes re-registering every scan against all
    /// others at the final distance, after the growing model is complete.
    #[arg(long, default_value_t = AlignOptions::default().refine_passes)]
    pub refine_passes: usize,
    /// Multiview registration: every pairwise alignment judged (converged,
    /// overlap, RMS against its peers'; failures retried, then reported),
    /// scans joined along the largest overlaps, then all overlapping pairs
    /// aligned and every pose solved at once, which closes rings of scans.
    /// `off`: the growing model in one pass plus --refine-passes (mint's
    /// registration before; --anchor-only applies only here).
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    pub global: OnOff,
    /// Multiview: two scans are partners when each has at least this
    /// fraction of its samples within the pairing distance of the other.
    #[arg(long, default_value_t = AlignOptions::default().min_overlap)]
    pub min_overlap: f64,
    /// Multiview: a pairwise alignment fails when its RMS (relative to the
    /// sampling distance) is more than this many times the median of its
    /// peers'.
    #[arg(long, default_value_t = AlignOptions::default().rms_factor)]
    pub rms_factor: f64,
    /// Multiview: rounds of (all pairwise alignments, global solve) at most;
    /// they stop earlier once the poses stop moving.
    #[arg(long, default_value_t = AlignOptions::default().global_rounds)]
    pub global_rounds: usize,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnOff {
    On,
    Off,
}

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
    /// Memory for scans held at once, e.g. 256M or 2G. Scans are read
    /// from their files when needed and the most recently used kept within
    /// this; with less than the whole set, scans are read more than once
    /// (the output is the same). The model and the grid come on top.
    #[arg(long, value_parser = crate::units::parse_bytes, default_value = "1G")]
    pub mem: u64,
    /// Grid method: half-width of a crossing's vote along its grid line, in
    /// scan units [default: the larger of 1.5 cells and 3 sampling distances].
    #[arg(long)]
    pub band: Option<f64>,
    /// Also write OUT.png beside the output: a picture of the merged surface
    /// (see `mint render`).
    #[arg(long)]
    pub preview: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn cmd_scan(a: ScanArgs) -> Result<()> {
    let (positions, faces) = crate::jobs::load_mesh(&a.mesh)?;
    let format = match a.image_format {
        ImageFormat::Ply => mint_range::scan_file::ImageFormat::Ply,
        ImageFormat::Rgrid => mint_range::scan_file::ImageFormat::Grid(GridEncoding::BinaryLittleEndian),
        ImageFormat::RgridAscii => mint_range::scan_file::ImageFormat::Grid(GridEncoding::Ascii),
    };
    let opts = mint_range::scan_file::ScanFileOptions {
        synth: SynthOptions { views: a.views, resolution: a.resolution, noise: a.noise, seed: a.seed, max_angle_deg: a.max_angle },
        format,
        perturb_deg: a.perturb_deg,
        perturb_frac: a.perturb_frac,
    };
    // Nothing is written where it would overwrite the input.
    let not_input = |p: &std::path::Path| crate::paths::check_not_input(p, &[&a.mesh]).map_err(|e| e.to_string().trim_start_matches(&format!("{}: ", p.display())).to_string());
    let s = mint_range::scan_file::scan_file(&a.mesh, &positions, &faces, &a.out_dir, &opts, &not_input).with_context(|| format!("scanning {}", a.mesh.display()))?;
    eprintln!(
        "scanned {} from {} views: {} samples -> {} (scans.conf{})",
        a.mesh.display(),
        s.views,
        s.samples,
        a.out_dir.display(),
        if s.perturbed { ", scans-perturbed.conf" } else { "" }
    );
    Ok(())
}

pub fn cmd_align(a: AlignArgs) -> Result<()> {
    let set = ScanSet::read(&a.set)?;
    let mut inputs: Vec<&std::path::Path> = vec![&a.set];
    inputs.extend(set.entries.iter().map(|e| e.path.as_path()));
    crate::paths::check_output(&a.out_set, &inputs)?;
    let opts = AlignOptions {
        distance: a.distance,
        start_distance: a.start_distance,
        metric: match a.metric {
            MetricArg::PlaneThenPoint => Metric::PlaneThenPoint,
            MetricArg::Point => Metric::PointToPoint,
            MetricArg::Plane => Metric::PointToPlane,
        },
        strategy: if a.anchor_only { Strategy::Anchor } else { Strategy::Growing },
        anchor: a.anchor,
        symmetric: !a.one_way,
        tolerance: a.tolerance,
        max_samples: a.max_samples,
        refine_passes: a.refine_passes,
        global: a.global == OnOff::On,
        min_overlap: a.min_overlap,
        rms_factor: a.rms_factor,
        global_rounds: a.global_rounds,
        ..Default::default()
    };
    let s = align_file(&a.set, &a.out_set, &opts, &crate::progress::Bars::new(a.json))?;
    let (r, secs, register_secs) = (&s.result, s.seconds, s.register_seconds);
    if a.json {
        let v = serde_json::json!({ "set": a.set.display().to_string(), "out_set": a.out_set.display().to_string(), "global": opts.global, "distance": r.distance, "start_distance": r.start_distance, "seconds": secs, "register_seconds": register_secs, "peak_heap_bytes": crate::alloc::peak_heap(), "rounds": r.rounds, "scans": r.reports, "pairs": r.pairs });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let how = if opts.global { format!("multiview, {} rounds", r.rounds) } else { "growing model".to_string() };
        eprintln!("aligned {} scans of {} ({how}; d = {:.4e}, start {:.4e}) in {secs:.2}s -> {}", s.scans, a.set.display(), r.distance, r.start_distance, a.out_set.display());
        eprintln!("  {:<24} {:<10} {:>10} {:>6} {:>8} {:>6} {:>9}  partners", "scan", "status", "rms", "rms/s", "pairs", "iters", "moved deg");
        for s in &r.reports {
            match &s.status {
                Status::Failed(why) => eprintln!("  {:<24} FAILED, kept its initial pose and left out: {why}", s.name),
                st => eprintln!(
                    "  {:<24} {:<10} {:>10.4e} {:>6.3} {:>8} {:>6} {:>9.3}  {}{}",
                    s.name,
                    format!("{st:?}"),
                    s.rms,
                    s.rms_rel,
                    s.pairs,
                    s.iterations,
                    s.moved_deg,
                    s.partners.join(" "),
                    if s.converged { "" } else { " (hit the iteration cap)" }
                ),
            }
        }
        let rejected: Vec<String> = r
            .pairs
            .iter()
            .filter_map(|p| match &p.status {
                mint_range::multiview::PairStatus::Accepted => None,
                mint_range::multiview::PairStatus::Failed(why) => Some(format!("  pair {} / {}: failed: {why}", p.a, p.b)),
                mint_range::multiview::PairStatus::Inconsistent => Some(format!("  pair {} / {}: left out, inconsistent with the others (mates {:.3e} apart after the global solve)", p.a, p.b, p.residual)),
            })
            .collect();
        if !r.pairs.is_empty() {
            eprintln!("  {} pairwise alignments, {} accepted", r.pairs.len(), r.pairs.len() - rejected.len());
        }
        for l in rejected {
            eprintln!("{l}");
        }
    }
    Ok(())
}

pub fn cmd_zipper(a: ZipperArgs) -> Result<()> {
    let set = ScanSet::read(&a.set)?;
    let mut inputs: Vec<&std::path::Path> = vec![&a.set];
    inputs.extend(set.entries.iter().map(|e| e.path.as_path()));
    crate::paths::check_output(&a.output, &inputs)?;
    if a.preview {
        crate::paths::check_output(&crate::jobs::preview_path(&a.output), &inputs)?;
    }
    let bars = crate::progress::Bars::new(a.json);
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
    let opts = mint_range::MergeFileOptions { method, scan_mem: a.mem as usize, write: Default::default() };
    let s = mint_range::merge_file(&a.set, &a.output, &opts, &bars)?;
    let (report, check, secs) = (&s.report, &s.check, s.seconds);
    if a.preview {
        crate::cmd::render::write_preview(&[a.output.as_path()], &a.output, a.json, &bars)?;
    }
    if a.json {
        let key = report.method();
        let v = serde_json::json!({ "set": a.set.display().to_string(), "output": a.output.display().to_string(), "seconds": secs, key: report, "check": check, "scan_reads": s.scan_reads, "peak_scan_bytes": s.peak_scan_bytes, "peak_heap_bytes": crate::alloc::peak_heap() });
        println!("{}", serde_json::to_string_pretty(&v)?);
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
    eprintln!("  scans read {} times for {} scans (at most {:.1} MiB of scans held at once, budget --mem {:.0} MiB)", s.scan_reads, s.scans, s.peak_scan_bytes as f64 / 1048576.0, a.mem as f64 / 1048576.0);
    Ok(())
}

