//! The layered-reconstruction subcommands: `mint slice` (mesh → contour
//! stack), `mint contours` (contour stack → mesh, by the angle criterion or
//! marching cubes) and `mint optimize` (the normal-angle optimizer). Each
//! handler checks its arguments, calls one driver of `mint_contour::run`,
//! prints a one-paragraph summary (or `--json`) and writes the `--stats`
//! status file: time, counts, every parameter used (defaults included) and
//! the method's own counters, plus the peak heap.

use crate::alloc;
use crate::units::human_bytes;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use mint_contour::angle::AngleOptions;
use mint_contour::mc::McOptions;
use mint_contour::run::{self, Method, MethodStats, RunStats};
use mint_io::WriteOptions;
use std::path::{Path, PathBuf};

/// An axis of the input mesh.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SliceAxis {
    X,
    Y,
    Z,
}

#[derive(Args, Debug)]
pub struct SliceArgs {
    /// Input mesh (any format mint reads).
    pub input: PathBuf,
    /// Output profile (.pro), written to a temporary file and renamed at the end.
    pub output: PathBuf,
    /// Number of cutting planes, evenly spaced across the mesh's extent along
    /// the axis (plane k at min + (k + 1/2) * extent / N).
    #[arg(long)]
    pub sections: u32,
    /// Axis the planes are orthogonal to.
    #[arg(long, value_enum, default_value_t = SliceAxis::Z)]
    pub axis: SliceAxis,
    /// Write the status file (time, counts, parameters) as JSON here.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// No summary (errors are still printed).
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// A reconstruction method.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// Cross-section triangulation with the angle criterion: triangles join
    /// the contour vertices of consecutive sections; few triangles, exact
    /// contours; branching by splitting contours.
    Angle,
    /// Marching cubes on a grid of --cubes across the stack: watertight with
    /// --caps, handles holes and any branching; more triangles.
    Mc,
}

#[derive(Args, Debug)]
pub struct ContoursArgs {
    /// Input profile (.pro): sections of planar contours.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension (.ply, .obj, .stl,
    /// .off, .mesh, .raw, .wrl, .3ds).
    pub output: PathBuf,
    /// Reconstruction method.
    #[arg(long, value_enum)]
    pub method: MethodArg,
    /// mc: cubes across the larger side of the stack's bounding box in the
    /// section planes; the spacing along the stack is that of the sections
    /// [default: 64].
    #[arg(long)]
    pub cubes: Option<u32>,
    /// angle: direction threshold t, a cosine in [-1, 1]; the next vertex
    /// follows the edge whose direction agrees (cos > t) with the other
    /// contour's [default: 0.5, i.e. 60 degrees].
    #[arg(long)]
    pub threshold: Option<f64>,
    /// angle: contours are open polylines, not closed polygons.
    #[arg(long)]
    pub open: bool,
    /// Close the surface: triangulate the first and last sections (and, for
    /// angle, every contour that starts or ends inside the stack; for mc,
    /// caps half a section spacing beyond the end sections).
    #[arg(long)]
    pub caps: bool,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 instead of f32.
    #[arg(long)]
    pub double: bool,
    /// Also write OUT.png beside the output: a picture of the surface (see
    /// `mint render`).
    #[arg(long)]
    pub preview: bool,
    /// Write the status file (time, counts, parameters) as JSON here.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// No summary (errors are still printed).
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

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
    /// No summary (errors are still printed).
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// The status JSON: the run's stats plus the peak heap.
fn status(s: &RunStats) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(s)?;
    v["peak_heap_bytes"] = alloc::peak_heap().into();
    Ok(v)
}

/// Writes the status file atomically (temporary name, then rename).
fn write_stats(path: &Path, v: &serde_json::Value) -> Result<()> {
    let tmp = path.with_extension("json.mint-tmp");
    std::fs::write(&tmp, serde_json::to_string_pretty(v)? + "\n").with_context(|| format!("{}: writing the status file", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("{}: renaming the status file", path.display()))?;
    Ok(())
}

/// Prints and records a finished run.
fn report(s: &RunStats, stats: &Option<PathBuf>, quiet: bool, json: bool, line: String) -> Result<()> {
    let v = status(s)?;
    if let Some(p) = stats {
        write_stats(p, &v)?;
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else if !quiet {
        eprintln!("{line}");
        eprintln!("  time {:.3}s, peak heap {}", s.seconds, human_bytes(alloc::peak_heap()));
    }
    Ok(())
}

fn write_options(ascii: bool, double: bool) -> WriteOptions {
    WriteOptions { ascii, double, ..Default::default() }
}

pub fn cmd_slice(a: SliceArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    if let Some(st) = &a.stats {
        crate::paths::check_output(st, &[&a.input, &a.output])?;
    }
    let axis = a.axis as usize;
    let s = run::slice_file(&a.input, &a.output, a.sections, axis, &crate::progress::Bars::new(a.quiet || a.json))?;
    let MethodStats::Slice(d) = &s.details else { unreachable!() };
    let line = format!(
        "sliced {} -> {}: {} of {} planes met the mesh, {} contours, {} vertices ({} open chains closed, {} contours dropped)",
        a.input.display(),
        a.output.display(),
        d.sections,
        d.planes,
        d.contours,
        d.vertices,
        d.chains_closed,
        d.contours_dropped
    );
    report(&s, &a.stats, a.quiet, a.json, line)
}

pub fn cmd_contours(a: ContoursArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    if a.preview {
        crate::paths::check_output(&crate::jobs::preview_path(&a.output), &[&a.input])?;
    }
    if let Some(st) = &a.stats {
        crate::paths::check_output(st, &[&a.input, &a.output])?;
    }
    let method = match a.method {
        MethodArg::Mc => {
            if a.threshold.is_some() || a.open {
                bail!("--threshold and --open apply to --method angle only");
            }
            let cubes = a.cubes.unwrap_or(McOptions::default().cubes);
            if cubes == 0 {
                bail!("--cubes must be at least 1");
            }
            Method::Mc(McOptions { cubes, caps: a.caps, ..McOptions::default() })
        }
        MethodArg::Angle => {
            if a.cubes.is_some() {
                bail!("--cubes applies to --method mc only");
            }
            let threshold = a.threshold.unwrap_or(AngleOptions::default().threshold);
            if !(-1.0..=1.0).contains(&threshold) {
                bail!("--threshold {threshold} is not a cosine in [-1, 1]");
            }
            if a.open && a.caps {
                bail!("--caps needs closed contours; it cannot be used with --open");
            }
            Method::Angle(AngleOptions { threshold, open: a.open, caps: a.caps, extend_ends: false })
        }
    };
    let s = run::reconstruct_file(&a.input, &a.output, method, write_options(a.ascii, a.double), &crate::progress::Bars::new(a.quiet || a.json))?;
    let extra = match &s.details {
        MethodStats::Mc(d) => format!(
            "grid {}x{}x{} cells of {:.6}, {} non-canonical cells",
            d.grid_cells[0], d.grid_cells[1], d.grid_cells[2], d.cube_size, d.non_canonical_cells
        ),
        MethodStats::Angle(d) => {
            let f = &d.fallback_slabs;
            format!(
                "{} tubes ({} by the paper's march, {} from another start pair, {} by minimum area), {} splits, {} bridged groups, {} paired, {} capped apart, {} caps\n  section pairs using each fallback: restart {}, minimum area {}, split {}, bridge {}, pairs {}, apart {}",
                d.tubes, d.tiled.march, d.tiled.restart, d.tiled.min_area, d.splits, d.bridged, d.paired, d.apart, d.caps, f.restart, f.min_area, f.split, f.bridge, f.pairs, f.apart
            )
        }
        _ => String::new(),
    };
    let mut line = format!(
        "reconstructed {} ({} sections, {} contour vertices) -> {}: {} vertices, {} faces; {extra}",
        a.input.display(),
        s.input_faces_or_sections,
        s.input_vertices,
        a.output.display(),
        s.vertices,
        s.faces
    );
    if let Some(v) = &s.volume {
        let diff = v.relative_difference.map_or("n/a".to_string(), |d| format!("{:+.2}%", 100.0 * d));
        line += &format!("\n  volume: mesh {:.6e}, planimetric {:.6e} (contour areas x section spacing), difference {diff}", v.mesh, v.planimetric);
    }
    if a.preview {
        crate::picture_cmds::write_preview(&[a.output.as_path()], &a.output, a.quiet || a.json, &crate::progress::Bars::new(a.quiet || a.json))?;
    }
    report(&s, &a.stats, a.quiet, a.json, line)
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
    report(&s, &a.stats, a.quiet, a.json, line)
}
