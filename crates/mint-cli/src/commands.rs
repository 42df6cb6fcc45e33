//! The subcommands: argument definitions (clap derive, with help text that
//! teaches) and the glue from arguments to library calls.

use crate::alloc;
use crate::progress::Bars;
use crate::units::{human_bytes, parse_bytes};
use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use mint_core::GridSize;
use mint_io::WriteOptions;
use mint_pipeline::{resample, ResampleOptions};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "mint",
    version,
    about = "Turn huge 3D scans into clean meshes.",
    long_about = "mint turns huge scanned meshes into clean, watertight meshes with bounded memory.\n\n\
Its main job is out-of-core Marching Intersections resampling: the input's faces are streamed, \
only their signed intersections with the lines of a regular grid are kept (on disk, in shards), \
detail smaller than a cell is dropped, and a watertight 2-manifold mesh is rebuilt slab by slab.\n\n\
Formats: PLY (ascii, binary little/big endian), OBJ, STL (ascii/binary), OFF, chosen by file extension.\n\n\
Start with:  mint demo            (generate a mesh, resample it, check the result)\n\
Then:        mint resample IN.ply OUT.ply --cells 1000000"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Resample a mesh on a regular grid into a watertight 2-manifold mesh (out of core).
    Resample(ResampleArgs),
    /// Show a mesh file's format, counts and properties without reading its body.
    Info(InfoArgs),
    /// Convert between mesh formats (PLY, OBJ, STL, OFF), streaming.
    Convert(ConvertArgs),
}

#[derive(Args, Debug)]
pub struct ResampleArgs {
    /// Input mesh (PLY, OBJ, STL or OFF).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension. Written to a temporary
    /// file beside it and renamed at the end, so it never exists half-written.
    pub output: PathBuf,
    /// About this many cubic cells over the input's bounding box
    /// (the output has very roughly 2-6 faces per surface cell).
    #[arg(long, conflicts_with = "cell_size", required_unless_present = "cell_size")]
    pub cells: Option<u64>,
    /// Cell edge length in input units (alternative to --cells).
    #[arg(long)]
    pub cell_size: Option<f64>,
    /// Heap budget, e.g. 512M or 2G; it decides slab thickness, never the
    /// input size [default: a quarter of RAM].
    #[arg(long, value_parser = parse_bytes)]
    pub mem: Option<u64>,
    /// Worker threads [default: all cores]. The output is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Directory for temporary shards and spill files [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Axis along which the grid is cut into slabs.
    #[arg(long, value_enum, default_value_t = AxisArg::Auto)]
    pub axis: AxisArg,
    /// Force slabs of K cell layers (for tests and tuning); without it, --mem decides.
    #[arg(long, value_name = "K")]
    pub slab: Option<u32>,
    /// Shift the grid by fractions of a cell, e.g. 0.5,0,0 [default: 0,0,0].
    #[arg(long, value_parser = parse_triple, hide = true)]
    pub grid_offset: Option<[f64; 3]>,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 instead of f32.
    #[arg(long)]
    pub double: bool,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisArg {
    Auto,
    X,
    Y,
    Z,
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Mesh file.
    pub file: PathBuf,
    /// Print as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 (PLY).
    #[arg(long)]
    pub double: bool,
    /// Directory for temporary spill files [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
}

fn parse_triple(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("'{s}': {e}"))?;
    if v.len() != 3 {
        return Err(format!("'{s}': expected three comma-separated numbers"));
    }
    Ok([v[0], v[1], v[2]])
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Resample(a) => cmd_resample(a),
        Command::Info(a) => cmd_info(a),
        Command::Convert(a) => cmd_convert(a),
    }
}

fn cmd_resample(a: ResampleArgs) -> Result<()> {
    let size = match (a.cells, a.cell_size) {
        (Some(n), None) => {
            if n == 0 {
                bail!("--cells must be at least 1");
            }
            GridSize::Cells(n)
        }
        (None, Some(h)) => GridSize::CellSize(h),
        _ => bail!("give exactly one of --cells N or --cell-size H"),
    };
    let mem = a.mem.unwrap_or_else(|| alloc::total_ram().map(|r| r / 4).unwrap_or(2 << 30));
    let opts = ResampleOptions {
        size,
        mem_bytes: mem,
        threads: a.threads,
        tmp_dir: a.tmp.clone(),
        axis: match a.axis {
            AxisArg::Auto => None,
            AxisArg::X => Some(0),
            AxisArg::Y => Some(1),
            AxisArg::Z => Some(2),
        },
        slab_layers: a.slab,
        grid_offset: a.grid_offset.unwrap_or([0.0; 3]),
        write: WriteOptions { ascii: a.ascii, double: a.double },
        max_listed: 100,
    };
    let bars = Bars::new(a.quiet || a.json);
    let summary = resample(&a.input, &a.output, &opts, &bars)?;
    let peak_heap = alloc::peak_heap();
    let peak_rss = alloc::peak_rss();
    if a.json {
        let mut v = serde_json::to_value(&summary)?;
        v["mem_budget_bytes"] = mem.into();
        v["peak_heap_bytes"] = peak_heap.into();
        v["peak_rss_bytes"] = peak_rss.into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let s = &summary;
        eprintln!("resampled {} -> {}", s.input, s.output);
        eprintln!("  input        {} vertices, {} faces", s.input_vertices, s.input_faces);
        eprintln!(
            "  grid         {}x{}x{} cells of {:.6} (slabs along {}: {}, {} threads)",
            s.grid_cells[0], s.grid_cells[1], s.grid_cells[2], s.cell_size, s.slab_axis, s.slabs, s.threads
        );
        eprintln!(
            "  intercepts   {} found, {} removed, {} kept ({} of shards)",
            s.intercepts_found,
            s.intercepts_removed,
            s.intercepts_kept,
            human_bytes(s.shard_bytes)
        );
        eprintln!("  output       {} vertices, {} faces", s.output_vertices, s.output_faces);
        eprintln!("  non-canonical cells  {}", s.non_canonical_cells);
        eprintln!(
            "  time         {:.2}s (bounds {:.2}s, discretize {:.2}s, reconstruct {:.2}s, write {:.2}s)",
            s.seconds_total, s.seconds_bounds, s.seconds_discretize, s.seconds_reconstruct, s.seconds_write
        );
        eprintln!(
            "  memory       peak heap {}, peak RSS {}, budget {}",
            human_bytes(peak_heap),
            peak_rss.map(human_bytes).unwrap_or_else(|| "?".into()),
            human_bytes(mem)
        );
    }
    Ok(())
}

fn cmd_info(a: InfoArgs) -> Result<()> {
    let info = mint_io::read_info(&a.file)?;
    if a.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(),
            "format": format!("{:?}", info.format),
            "encoding": info.encoding,
            "vertices": info.vertex_count,
            "faces": info.face_count,
            "elements": info.elements.iter().map(|e| serde_json::json!({
                "name": e.name, "count": e.count, "properties": e.properties
            })).collect::<Vec<_>>(),
            "comments": info.comments,
            "obj_info": info.obj_info,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("{}: {:?} ({})", a.file.display(), info.format, info.encoding);
        println!("  vertices  {}", info.vertex_count);
        match info.face_count {
            Some(n) => println!("  faces     {n}"),
            None => println!("  faces     (not stated in the header)"),
        }
        for e in &info.elements {
            println!("  element {} {}", e.name, e.count);
            for p in &e.properties {
                println!("    {p}");
            }
        }
        for c in &info.comments {
            println!("  comment {c}");
        }
        for c in &info.obj_info {
            println!("  obj_info {c}");
        }
    }
    Ok(())
}

fn cmd_convert(a: ConvertArgs) -> Result<()> {
    let bars = Bars::new(a.quiet);
    use mint_pipeline::{Phase, Progress};
    bars.start(Phase::Write, 0);
    let read = mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() };
    let write = WriteOptions { ascii: a.ascii, double: a.double };
    let mut last = 0u64;
    let summary = mint_io::convert(&a.input, &a.output, read, write, &mut |done, _total| {
        bars.advance(done.saturating_sub(last));
        last = done;
    })
    .with_context(|| format!("converting {} to {}", a.input.display(), a.output.display()))?;
    bars.finish();
    if !a.quiet {
        eprintln!("converted {} -> {}: {:?}", a.input.display(), a.output.display(), summary);
    }
    Ok(())
}

