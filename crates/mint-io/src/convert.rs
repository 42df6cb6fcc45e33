//! [`convert`]: stream a mesh from one file format into another.
//!
//! The stages: pick the output format from the output file name, open the
//! reader (so a bad input fails before any output exists), create the
//! writer (a temporary file beside the target), copy the vertices, stream
//! the triangles chunk by chunk, and finish (patch counts, sync, rename).
//! An error at any stage drops the writer, which deletes its temporary
//! file: the target is created complete or not at all.
//!
//! STL and raw input converted to an indexed format is welded: corners with exactly
//! equal coordinates (bit for bit, with -0.0 taken as 0.0) become one
//! vertex. Welding keeps a hash map over the distinct positions, about 40
//! bytes per output vertex, so its memory grows with the vertex count of
//! the result (not with the face count); that is accepted for now.
//! Converting between STL and raw keeps the soup layout.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{Error, ErrorKind};
use crate::format::Format;
use crate::reader::{MeshReader, ReadOptions, ReadStats, TriangleChunk};
use crate::writer::{MeshWriter, WriteOptions};

/// What [`convert`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConvertSummary {
    /// Format of the input (detected).
    pub input_format: Format,
    /// The output's coordinates: "f32", or "f64" and why.
    pub precision: String,
    /// Format of the output (from its extension).
    pub output_format: Format,
    /// Vertices in the input (for STL: 3 per facet).
    pub vertices_read: u64,
    /// Vertices written (fewer than read after STL welding).
    pub vertices_written: u64,
    /// Triangles written.
    pub triangles: u64,
    /// The reader's counters (skipped short faces, dropped strip triangles,
    /// spilled vertices).
    pub read_stats: ReadStats,
    /// Size of the output file.
    pub bytes_written: u64,
    /// Per-vertex colour: `None` when the input has none (or colour was
    /// not asked for), `Some(true)` kept, `Some(false)` dropped because the
    /// output format cannot hold it.
    pub colour_kept: Option<bool>,
}

/// Converts `input` into `output` (format by the output's extension),
/// streaming. `progress(bytes_done, bytes_total)` is called after each
/// chunk with input byte counts.
///
/// Every input vertex is copied, used or not, and must be finite (a `Value`
/// error naming the input otherwise). With
/// [`ReadOptions::resolve_positions`] set (the default), triangles are also
/// checked as they are read.
pub fn convert(
    input: &Path,
    output: &Path,
    read: ReadOptions,
    write: WriteOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<ConvertSummary, Error> {
    convert_cancellable(input, output, read, write, &mut |done, total| {
        progress(done, total);
        true
    })
}

/// [`convert`], stopping when `progress` returns `false` (polled after each
/// chunk of triangles and every 2^20 vertices): the temporary output is
/// removed and the error says "interrupted", naming the output.
pub fn convert_cancellable(
    input: &Path,
    output: &Path,
    read: ReadOptions,
    write: WriteOptions,
    progress: &mut dyn FnMut(u64, u64) -> bool,
) -> Result<ConvertSummary, Error> {
    let interrupted = || Error::new(ErrorKind::Io, output, "interrupted; no output written");
    // Output format from the name: refuse before touching anything.
    let output_format = Format::from_extension(output).ok_or_else(|| {
        Error::unsupported(output, "unknown output format: the file name must end in .ply, .obj, .stl, .off, .mesh, .raw, .wrl or .3ds")
    })?;
    // Open the input; a bad input fails here, before any output exists.
    let mut reader = MeshReader::open(input, read)?;
    let input_format = reader.info().format;
    let soup = |f: Format| matches!(f, Format::Stl | Format::Raw);
    let weld = soup(input_format) && !soup(output_format);
    let total = reader.bytes_total();
    // Coordinates the input stores as f64 stay f64 where f32 would move them
    // by more than a millionth of the box's diagonal (geo-referenced
    // models); an f32 input loses nothing in f32.
    let positions = reader.positions();
    let (double, precision) = match (write.double || positions.exact_in_f32(), positions.bounds(0, positions.len())) {
        (false, Ok(Some((lo, hi)))) => {
            let diag = (0..3).map(|d| (hi[d] - lo[d]).powi(2)).sum::<f64>().sqrt();
            crate::precision::choose(output, output_format, false, lo, hi, 1e-6 * diag)?
        }
        _ => (write.double, if write.double { "f64 (asked)".to_string() } else { "f32".to_string() }),
    };
    // Colour goes along when asked for and the output format holds it.
    let colours = if write.colours { reader.colours() } else { None };
    let keep = colours.is_some() && MeshWriter::holds_colour(output_format);
    let colour_kept = colours.as_ref().map(|_| keep);
    let colours = colours.filter(|_| keep);
    // The writer's temporary file lives beside the target until `finish`.
    let mut writer = MeshWriter::create(output, output_format, WriteOptions { double, colours: keep, ..write })?;
    // Vertices: copied, or welded for STL input.
    let nv = reader.vertex_count();
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    for i in 0..nv {
        if i % (1 << 20) == 0 && !progress(0, total) {
            return Err(interrupted());
        }
        let p = reader.vertex(i);
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::new(
                ErrorKind::Value,
                input,
                format!("vertex {i} has a non-finite coordinate ({}, {}, {}); it cannot be converted", p[0], p[1], p[2]),
            )
            .at_element("vertex")
            .at_record(i as u64));
        }
        if weld {
            let next = welded.len() as u32;
            if *welded.entry(weld_key(p)).or_insert(next) == next {
                writer.write_vertex(p)?;
            }
        } else {
            match &colours {
                Some(c) => writer.write_vertex_rgba(p, c.get(i))?,
                None => writer.write_vertex(p)?,
            }
        }
    }
    // Triangles, chunk by chunk.
    let mut chunk = TriangleChunk::new();
    while reader.next_chunk(&mut chunk)? {
        for t in &chunk.indices {
            let t = if weld { t.map(|i| welded[&weld_key(reader.vertex(i))]) } else { *t };
            writer.write_face(t)?;
        }
        if !progress(reader.bytes_done(), total) {
            return Err(interrupted());
        }
    }
    if !progress(total, total) {
        return Err(interrupted());
    }
    // Finish: counts, sync, rename.
    let vertices_written = writer.vertices();
    let summary = writer.finish()?;
    Ok(ConvertSummary {
        precision,
        input_format,
        output_format,
        vertices_read: nv as u64,
        vertices_written,
        triangles: summary.faces,
        read_stats: reader.stats(),
        bytes_written: summary.bytes,
        colour_kept,
    })
}

/// The exact bits of a position, with -0.0 folded into 0.0.
fn weld_key(p: [f64; 3]) -> [u64; 3] {
    p.map(|c| if c == 0.0 { 0u64 } else { c.to_bits() })
}

/// Writes the files of one surface into `output` as one mesh in `format`
/// (`write.double` keeps every coordinate as read): every file's vertices
/// in file order, then every file's triangles with its vertices' offset.
/// Streams (positions through each file's map), so memory does not grow
/// with the files. `cancelled` is polled between chunks. Returns the
/// vertices and triangles written. Errors name the file that failed.
pub fn concatenate(inputs: &[std::path::PathBuf], output: &Path, format: Format, write: WriteOptions, cancelled: &dyn Fn() -> bool) -> Result<(u64, u64), Error> {
    let read = ReadOptions { chunk_triangles: 1 << 16, spill_dir: write.spill_dir.clone(), resolve_positions: false };
    let mut counts = Vec::with_capacity(inputs.len());
    let mut w = MeshWriter::create(output, format, write)?;
    let mut total = 0u64;
    for p in inputs {
        let r = MeshReader::open(p, read.clone())?;
        let pos = r.positions();
        for i in 0..pos.len() {
            if i % (1 << 16) == 0 && cancelled() {
                return Err(Error::new(ErrorKind::Io, output, "interrupted"));
            }
            w.write_vertex(pos.get(i))?;
        }
        counts.push(pos.len() as u64);
        total += pos.len() as u64;
        if total > u32::MAX as u64 {
            return Err(Error::new(ErrorKind::Format, p, format!("the files hold more than {} vertices together (u32 indices)", u32::MAX)));
        }
    }
    let (mut base, mut faces) = (0u32, 0u64);
    let mut chunk = TriangleChunk::new();
    for (p, n) in inputs.iter().zip(counts) {
        let mut r = MeshReader::open(p, read.clone())?;
        while r.next_chunk(&mut chunk)? {
            if cancelled() {
                return Err(Error::new(ErrorKind::Io, output, "interrupted"));
            }
            for t in &chunk.indices {
                w.write_face([t[0] + base, t[1] + base, t[2] + base])?;
            }
            faces += chunk.indices.len() as u64;
        }
        base += n as u32;
    }
    w.finish()?;
    Ok((total, faces))
}
