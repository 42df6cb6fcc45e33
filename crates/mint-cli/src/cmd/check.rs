//! `mint info`, `convert`, `validate`, `check` and `distance`: reading, converting and judging mesh files.

use crate::jobs::*;
use crate::progress::Bars;
use crate::units::human_bytes;
use anyhow::{bail, Context, Result};
use clap::Args;
use mint_io::WriteOptions;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Mesh file.
    pub file: PathBuf,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Exit with code 3 when the mesh is not watertight (for scripts).
    #[arg(long)]
    pub strict: bool,
    /// Also count the pairs of faces that intersect (exact predicates;
    /// faces sharing a vertex or an edge count only if they overlap beyond
    /// it), with a few examples. In memory: about 100 bytes per face.
    #[arg(long)]
    pub self_intersections: bool,
    /// Judge the indices as written. By default vertices at identical
    /// positions are merged first, as MeshLab and trimesh do on import: STL
    /// stores each triangle's corners separately and OBJ splits vertices at
    /// texture seams, which would otherwise read as boundaries everywhere.
    #[arg(long)]
    pub no_weld: bool,
    /// Heap budget, e.g. 512M or 2G [default: a quarter of RAM]. The check
    /// keeps a few bytes per vertex in memory and sends each face's corners
    /// to buckets that spill to disk past this budget, so a mesh of any size
    /// can be checked (--self-intersections is in memory, though).
    #[arg(long, value_parser = crate::units::parse_bytes)]
    pub mem: Option<u64>,
    /// Directory for spill files [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Worker threads [default: all cores]. The report is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Args, Debug)]
pub struct DistanceArgs {
    /// The mesh sampled first (A → B, then B → A).
    pub a: PathBuf,
    /// The other mesh.
    pub b: PathBuf,
    /// Area-uniform samples per direction.
    #[arg(long, default_value_t = 1_000_000)]
    pub samples: usize,
    /// Seed of the sample positions.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// Mesh file.
    pub file: PathBuf,
    /// Directory for temporary spill files (ASCII input) [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
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

pub(crate) fn cmd_info(a: InfoArgs) -> Result<()> {
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

pub(crate) fn cmd_convert(a: ConvertArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    let bars = Bars::new(a.quiet);
    use mint_pipeline::{Phase, Progress};
    bars.start(Phase::named("convert"), 0);
    let read = mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() };
    let write = WriteOptions { ascii: a.ascii, double: a.double, ..Default::default() };
    let mut last = 0u64;
    let summary = mint_io::convert_cancellable(&a.input, &a.output, read, write, &mut |done, _total| {
        bars.advance(done.saturating_sub(last));
        last = last.max(done);
        !crate::progress::interrupted()
    })
    .with_context(|| format!("converting {} to {}", a.input.display(), a.output.display()))?;
    bars.finish();
    if !a.quiet {
        eprintln!(
            "converted {} ({:?}) -> {} ({:?}): {} vertices, {} triangles, {}",
            a.input.display(),
            summary.input_format,
            a.output.display(),
            summary.output_format,
            summary.vertices_written,
            summary.triangles,
            human_bytes(summary.bytes_written)
        );
    }
    Ok(())
}


pub(crate) fn cmd_validate(a: ValidateArgs) -> Result<()> {
    use mint_pipeline::{Phase, Progress};
    let t = std::time::Instant::now();
    let mut reader = mint_io::MeshReader::open(&a.file, mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() })?;
    let bars = Bars::new(a.quiet || a.json);
    bars.start(Phase::named("validate"), reader.info().face_count.unwrap_or(0));
    let mut chunk = mint_io::TriangleChunk::default();
    let mut triangles = 0u64;
    // A checksum over positions keeps the read from being optimized away and
    // lets two runs be compared.
    let mut checksum = 0.0f64;
    while reader.next_chunk(&mut chunk)? {
        triangles += chunk.positions.len() as u64;
        for t in &chunk.positions {
            checksum += t[0][0] + t[1][1] + t[2][2];
        }
        bars.advance(chunk.positions.len() as u64);
        if crate::progress::interrupted() {
            bail!("interrupted");
        }
    }
    bars.finish();
    for w in reader.warnings() {
        eprintln!("mint: warning: {w}");
    }
    let secs = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&a.file).map(|m| m.len()).unwrap_or(0);
    let tps = triangles as f64 / secs.max(1e-9);
    let mbs = bytes as f64 / 1e6 / secs.max(1e-9);
    if a.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(), "vertices": reader.vertex_count(), "triangles": triangles,
            "seconds": secs, "triangles_per_second": tps, "mb_per_second": mbs, "checksum": checksum,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "{}: ok, {} vertices, {} triangles in {:.3}s ({:.1} M triangles/s, {:.0} MB/s)",
            a.file.display(),
            reader.vertex_count(),
            triangles,
            secs,
            tps / 1e6,
            mbs
        );
    }
    Ok(())
}

pub(crate) fn cmd_check(a: CheckArgs) -> Result<()> {
    let threads = if a.threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { a.threads };
    let opts = mint_pipeline::CheckOptions { mem_bytes: a.mem.unwrap_or_else(default_mem), weld: !a.no_weld, tmp_dir: a.tmp.clone(), threads, list_boundary: 0 };
    let (r, stats) = mint_pipeline::check_file(&a.file, &opts, &Bars::new(a.quiet || a.json))?;
    let sx = if a.self_intersections {
        let (mut positions, mut faces) = load_mesh(&a.file)?;
        if !a.no_weld {
            mint_mesh::weld(&mut positions, &mut faces);
        }
        Some(mint_mesh::self_intersections(&positions, &faces, 5))
    } else {
        None
    };
    if !a.json && !a.quiet && stats.bytes_spilled > 0 {
        eprintln!("  ({} of corners spilled to disk to stay within --mem)", human_bytes(stats.bytes_spilled));
    }
    if a.json {
        let mut v = serde_json::to_value(&r)?;
        v["file"] = a.file.display().to_string().into();
        v["spilled_bytes"] = stats.bytes_spilled.into();
        if let Some(x) = &sx {
            v["self_intersections"] = serde_json::to_value(x)?;
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print_check(&a.file.display().to_string(), &r);
        if let Some(x) = &sx {
            let ex: Vec<String> = x.examples.iter().map(|[i, j]| format!("{i}-{j}")).collect();
            println!(
                "  self-intersections {} pairs of faces{}",
                x.pairs,
                if ex.is_empty() { String::new() } else { format!(" (e.g. faces {})", ex.join(", ")) }
            );
        }
    }
    if a.strict && !r.watertight {
        std::process::exit(3);
    }
    Ok(())
}

pub(crate) fn print_check(name: &str, r: &mint_mesh::CheckReport) {
    println!("{name}: {}", if r.watertight { "watertight (closed, 2-manifold, consistently oriented)" } else { "NOT watertight" });
    println!("  vertices {} ({} unreferenced), faces {}", r.vertices, r.unreferenced_vertices, r.faces);
    if r.welded_vertices > 0 {
        println!("  welded {} vertices at identical positions into earlier ones (--no-weld judges the indices as written)", r.welded_vertices);
    }
    if let (Some(lo), Some(hi)) = (r.bbox_min, r.bbox_max) {
        println!("  bbox [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    }
    println!("  components {} ({} closed), genus of closed ones {:?} (total {})", r.components, r.closed_components, r.genera, r.genus_total);
    println!("  edges {}, boundary edges {} in {} loops ({} on non-simple boundaries)", r.edges, r.boundary_edges, r.boundary_loops, r.non_simple_boundary_edges);
    println!("  non-manifold edges {}, non-manifold vertices {}", r.non_manifold_edges, r.non_manifold_vertices);
    println!("  inconsistently oriented edges {}", r.inconsistently_oriented_edges);
    println!("  degenerate faces {} ({} with a repeated index), duplicate faces {}", r.degenerate_faces, r.collapsed_faces, r.duplicate_faces);
    println!("  Euler characteristic {}, signed volume {:.9}, area {:.9}", r.euler_characteristic, r.signed_volume, r.surface_area);
}

pub(crate) fn cmd_distance(a: DistanceArgs) -> Result<()> {
    let ma = load_mesh(&a.a)?;
    let mb = load_mesh(&a.b)?;
    let (ab, ba) = mint_mesh::try_symmetric_distance((&ma.0, &ma.1), (&mb.0, &mb.1), a.samples, a.seed)
        .with_context(|| format!("distance between {} and {}", a.a.display(), a.b.display()))?;
    if a.json {
        let v = serde_json::json!({ "a": a.a.display().to_string(), "b": a.b.display().to_string(), "a_to_b": ab, "b_to_a": ba });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        for (name, r) in [(format!("{} -> {}", a.a.display(), a.b.display()), &ab), (format!("{} -> {}", a.b.display(), a.a.display()), &ba)] {
            println!("{name} ({} samples)", r.samples);
            println!("  mean {:.6e} ({:.3e} of diagonal)", r.mean, r.mean_rel);
            println!("  rms  {:.6e} ({:.3e} of diagonal)", r.rms, r.rms_rel);
            println!("  max  {:.6e} ({:.3e} of diagonal) at {:?}", r.max, r.max_rel, r.max_point);
        }
    }
    Ok(())
}
