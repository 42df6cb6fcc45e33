//! The contract between the reader and writer and the format modules: what
//! a format hands back from opening a file ([`Opened`]: the [`MeshInfo`],
//! the positions, an optional [`RangeGrid`] and a [`FaceStream`]), the
//! counters readers keep ([`ReadStats`]), and what a format writer is
//! ([`FormatWriter`], appending to an [`OutFile`], with the shared text
//! helpers [`write_coord`] and [`write_point`]). Formats depend only on this
//! module (and the low-level ones: positions, text, mapped, errors), never
//! on `reader` or `writer`, which dispatch to them.

use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::atomic::AtomicFile;
use crate::error::Error;
use crate::format::Format;
use crate::positions::{Emit, Positions, Reject};

/// What a file says about itself, from its header (see [`read_info`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshInfo {
    /// The file format.
    pub format: Format,
    /// `"ascii"`, `"binary_little_endian"`, `"binary_big_endian"`, or
    /// `"binary"` for binary STL.
    pub encoding: String,
    /// Vertices as stored (for STL: 3 per facet, a soup).
    pub vertex_count: u64,
    /// Face records (polygons, strips or facets) when the file says; `None`
    /// when the file has no face element at all (a PLY point cloud or range
    /// scan).
    pub face_count: Option<u64>,
    /// The elements in file order.
    pub elements: Vec<ElementInfo>,
    /// Header comments (PLY `comment`, leading `#` lines of OBJ/OFF, the
    /// binary STL header text or the ascii STL solid name).
    pub comments: Vec<String>,
    /// PLY `obj_info` lines, without the keyword.
    pub obj_info: Vec<String>,
}

/// One element of a file: PLY elements as declared; `v`/`f` for OBJ,
/// `vertex`/`face` for OFF, `facet` for STL.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ElementInfo {
    /// Element name as in the file.
    pub name: String,
    /// Number of records.
    pub count: u64,
    /// Property declarations as written, e.g. `"float x"`,
    /// `"list uchar int vertex_indices"`.
    pub properties: Vec<String>,
}

/// The sample grid of a range scan (PLY `range_grid` element): `cols` x
/// `rows` cells in row-major order, each the index of the vertex sampled
/// there, or `None`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RangeGrid {
    /// Cells per row (`obj_info num_cols`).
    pub cols: u32,
    /// Rows (`obj_info num_rows`).
    pub rows: u32,
    /// `cols * rows` cells, row-major: the vertex sampled there, if any.
    pub cells: Vec<Option<u32>>,
}

impl RangeGrid {
    /// The vertex at (`col`, `row`), if any. Panics outside the grid.
    pub fn cell(&self, col: u32, row: u32) -> Option<u32> {
        assert!(col < self.cols && row < self.rows, "cell ({col}, {row}) outside a {}x{} grid", self.cols, self.rows);
        self.cells[row as usize * self.cols as usize + col as usize]
    }

    /// Number of cells that hold a vertex.
    pub fn filled(&self) -> usize {
        self.cells.iter().filter(|c| c.is_some()).count()
    }
}

/// Counters of what a reader met so far.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct ReadStats {
    /// Triangles delivered.
    pub triangles: u64,
    /// Face records with fewer than 3 indices, skipped (PLY faces, OBJ `f`
    /// lines, OFF faces).
    pub short_faces: u64,
    /// Strip triangles with a repeated index, dropped (PLY `tristrips`).
    pub degenerate_strip_triangles: u64,
    /// Vertex positions written to a spill file (0 when they are read in
    /// place from a binary file).
    pub spilled_vertices: u64,
    /// Bytes after the last declared PLY element, ignored as MeshLab and
    /// trimesh ignore them (see [`MeshReader::warnings`]). Known once the
    /// faces have been read.
    pub ignored_trailing_bytes: u64,
}

/// The format-specific part of a reader: produces triangles into an
/// `Emit` until it is full or the faces end.
pub(crate) trait FaceStream: Send {
    /// Fills `out`; returns false when no triangles remain after this call.
    fn fill(&mut self, out: &mut Emit, stats: &mut ReadStats) -> Result<bool, Error>;
    /// Bytes of the input consumed so far.
    fn bytes_done(&self) -> u64;
    /// Bytes after the last declared element, ignored (PLY).
    fn ignored_trailing_bytes(&self) -> u64 {
        0
    }
    /// What the format accepted but a user should know, one line each
    /// naming the file (see [`crate::MeshReader::warnings`]).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// The number of face records, when every record has the same size if
    /// it is a triangle, so that records `first .. end` can be read alone
    /// (binary PLY with one face element, binary STL). `None` otherwise.
    fn splittable_records(&self) -> Option<u64> {
        None
    }
    /// Restricts the stream to face records `first .. end`, each of which
    /// must be a triangle (checked while reading). Only called when
    /// [`FaceStream::splittable_records`] is `Some`.
    fn restrict(&mut self, _first: u64, _end: u64) -> Result<(), Error> {
        unreachable!("restrict called on a stream that cannot be split")
    }
    /// Where the fixed-size face records are, for direct parallel access
    /// ([`crate::visit::TriangleRecords`]); `None` unless splittable.
    fn fixed_faces(&self) -> Result<Option<crate::visit::FixedFaces>, Error> {
        Ok(None)
    }
}

/// The polygon a text format's [`FaceStream`] is emitting as a fan of
/// triangles `(c0, c(i-1), ci)`, kept across `fill` calls: parse a face
/// record's corners with [`PolygonFan::clear`] and [`PolygonFan::push`],
/// call [`PolygonFan::ready`], then [`PolygonFan::emit`] until it is done.
#[derive(Debug, Default)]
pub(crate) struct PolygonFan {
    /// Corners (0-based, range-checked by the format).
    corners: Vec<u32>,
    /// The next triangle to emit: `(c0, c(next-1), c(next))`.
    next: usize,
}

impl PolygonFan {
    /// Starts a new face record.
    pub(crate) fn clear(&mut self) {
        self.corners.clear();
        self.next = 0;
    }
    /// Adds the record's next corner.
    pub(crate) fn push(&mut self, corner: u32) {
        self.corners.push(corner);
    }
    /// The record is read: a face of fewer than three corners is dropped
    /// and counted in `stats.short_faces`.
    pub(crate) fn ready(&mut self, stats: &mut ReadStats) {
        if self.corners.len() < 3 {
            stats.short_faces += 1;
            self.corners.clear();
        }
        self.next = 2;
    }
    /// Emits the pending triangles while `out` has room. `Ok(true)`: the
    /// polygon is done; `Ok(false)`: `out` is full; `Err(v)`: vertex `v` of
    /// a triangle is not finite.
    #[inline]
    pub(crate) fn emit(&mut self, out: &mut Emit) -> Result<bool, u32> {
        while self.next < self.corners.len() {
            if !out.room() {
                return Ok(false);
            }
            let c = &self.corners;
            if let Err(Reject::NotFinite(v)) = out.tri_checked([c[0], c[self.next - 1], c[self.next]]) {
                return Err(v);
            }
            self.next += 1;
        }
        Ok(true)
    }
}

/// What a format module hands back from opening a file.
pub(crate) struct Opened {
    pub(crate) info: MeshInfo,
    pub(crate) positions: Positions,
    pub(crate) body: Box<dyn FaceStream>,
    pub(crate) range_grid: Option<RangeGrid>,
    pub(crate) spilled_vertices: u64,
    /// Per-vertex colour, when the file has it.
    pub(crate) colours: Option<crate::colours::VertexColours>,
    /// Per-face colour, when the file has it (and no per-vertex colour).
    pub(crate) face_colours: Option<crate::colours::FaceColours>,
    /// Texture coordinates and materials, when the file has them.
    pub(crate) texturing: Option<crate::textures::Texturing>,
}

/// Options of [`MeshWriter::create`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct WriteOptions {
    /// Write text: ascii PLY or ascii STL. Default false (binary
    /// little-endian PLY, binary STL). OBJ and OFF are always text.
    pub ascii: bool,
    /// Store vertex coordinates as f64. Default false: f32 (PLY `float`;
    /// in OBJ, OFF, mesh, raw and VRML the shortest decimal that reads back
    /// as the same f32 (as f64 it reads back as that decimal, e.g. `0.1`));
    /// coordinates beyond the f32 range are then refused with a `Value`
    /// error. STL and 3DS always store f32.
    pub double: bool,
    /// Where the STL writer spills vertex positions. Default `None`: the
    /// system temporary directory, [`std::env::temp_dir`].
    pub spill_dir: Option<PathBuf>,
    /// Write per-vertex colour (given by [`crate::MeshWriter::write_vertex_rgba`])
    /// where the format holds it: PLY `uchar red green blue alpha`, OBJ
    /// `v x y z r g b`. Default false.
    pub colours: bool,
}

/// A buffered writer over an [`AtomicFile`], with in-place patching.
pub(crate) struct OutFile {
    file: AtomicFile,
    buf: Vec<u8>,
    flushed: u64,
}

const FLUSH_AT: usize = 4 << 20;
/// Flushes end at multiples of this file offset (see [`OutFile::maybe_flush`]).
const FLUSH_ALIGN: u64 = 2 << 20;

impl OutFile {
    pub(crate) fn create(path: &Path) -> Result<OutFile, Error> {
        Ok(OutFile { file: AtomicFile::create(path)?, buf: Vec::with_capacity(FLUSH_AT + 4096), flushed: 0 })
    }

    /// The target path (for error messages).
    pub(crate) fn target(&self) -> &Path {
        self.file.path()
    }

    /// An I/O error about the target.
    #[cold]
    pub(crate) fn err(&self, e: io::Error) -> Error {
        Error::io(self.file.path(), "cannot write", e)
    }

    /// Appends bytes.
    #[inline]
    pub(crate) fn put(&mut self, b: &[u8]) -> Result<(), Error> {
        self.buf.extend_from_slice(b);
        self.maybe_flush()
    }

    /// The buffer, for `write!`; call [`OutFile::maybe_flush`] after.
    #[inline]
    pub(crate) fn text(&mut self) -> &mut Vec<u8> {
        &mut self.buf
    }

    #[inline]
    pub(crate) fn maybe_flush(&mut self) -> Result<(), Error> {
        if self.buf.len() >= FLUSH_AT {
            self.flush_aligned()?;
        }
        Ok(())
    }

    /// Writes the buffer up to the last multiple of [`FLUSH_ALIGN`] in the
    /// file and keeps the rest. Writes of whole, aligned 2 MiB ranges let
    /// the kernel cache the file in 2 MiB pages, which whoever maps the
    /// output next (mint itself, reading it back) can map with one
    /// page-table entry each instead of 512.
    #[cold]
    fn flush_aligned(&mut self) -> Result<(), Error> {
        let end = (self.flushed + self.buf.len() as u64) / FLUSH_ALIGN * FLUSH_ALIGN;
        let n = (end - self.flushed) as usize;
        if n == 0 {
            return self.flush_buf();
        }
        if let Err(e) = self.file.write_all(&self.buf[..n]) {
            return Err(self.err(e));
        }
        self.flushed += n as u64;
        self.buf.drain(..n);
        Ok(())
    }

    fn flush_buf(&mut self) -> Result<(), Error> {
        if let Err(e) = self.file.write_all(&self.buf) {
            return Err(self.err(e));
        }
        self.flushed += self.buf.len() as u64;
        self.buf.clear();
        Ok(())
    }

    /// Bytes written so far (flushed and buffered).
    pub(crate) fn len(&self) -> u64 {
        self.flushed + self.buf.len() as u64
    }

    /// Overwrites bytes at `offset` (which must already be written).
    pub(crate) fn patch(&mut self, offset: u64, bytes: &[u8]) -> Result<(), Error> {
        self.flush_buf()?;
        let r = (|| {
            self.file.seek(SeekFrom::Start(offset))?;
            self.file.write_all(bytes)?;
            self.file.seek(SeekFrom::End(0))?;
            Ok(())
        })();
        r.map_err(|e| self.err(e))
    }

    /// Flushes, syncs and renames onto the target; returns the file size.
    pub(crate) fn commit(mut self) -> Result<u64, Error> {
        self.flush_buf()?;
        let len = self.flushed;
        self.file.commit()?;
        Ok(len)
    }
}

/// The format-specific part of a writer. [`MeshWriter`] has already checked
/// order, finiteness and index ranges.
pub(crate) trait FormatWriter: Send {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error>;
    /// A vertex and its colour; only called when the writer was created
    /// with [`WriteOptions::colours`] and its backend holds colour.
    fn vertex_rgba(&mut self, p: [f64; 3], _c: [u8; 4]) -> Result<(), Error> {
        self.vertex(p)
    }
    fn face(&mut self, f: [u32; 3]) -> Result<(), Error>;
    /// Many vertices at once (checked by the caller); the same bytes as
    /// one [`FormatWriter::vertex`] each.
    fn vertices(&mut self, ps: &[[f64; 3]]) -> Result<(), Error> {
        ps.iter().try_for_each(|&p| self.vertex(p))
    }
    /// Many faces at once (checked by the caller); the same bytes as one
    /// [`FormatWriter::face`] each.
    fn faces(&mut self, fs: &[[u32; 3]]) -> Result<(), Error> {
        fs.iter().try_for_each(|&f| self.face(f))
    }
    /// Patches counts, syncs and renames; returns the file size.
    fn finish(self: Box<Self>, vertices: u64, faces: u64) -> Result<u64, Error>;
}

/// Appends a coordinate in text: the shortest decimal that reads back as
/// the same f32 (or f64 when `double`).
/// Plain notation for moderate magnitudes, exponent notation otherwise (so
/// 1e300 does not become 301 digits).
#[inline]
pub(crate) fn write_coord(out: &mut Vec<u8>, c: f64, double: bool) {
    let a = c.abs();
    let plain = a == 0.0 || (1e-5..1e16).contains(&a);
    let _ = match (double, plain) {
        (true, true) => write!(out, "{c}"),
        (true, false) => write!(out, "{c:e}"),
        (false, true) => write!(out, "{}", c as f32),
        (false, false) => write!(out, "{:e}", c as f32),
    };
}

/// Appends `prefix`, the three coordinates separated by spaces, and
/// `suffix`: one vertex line of a text format.
#[inline]
pub(crate) fn write_point(out: &mut Vec<u8>, prefix: &[u8], p: [f64; 3], double: bool, suffix: &[u8]) {
    out.extend_from_slice(prefix);
    write_coord(out, p[0], double);
    out.push(b' ');
    write_coord(out, p[1], double);
    out.push(b' ');
    write_coord(out, p[2], double);
    out.extend_from_slice(suffix);
}

/// Progress through a file of `total` bytes read as `count` equal items,
/// `done` of them read (all of it when there are none).
pub(crate) fn share_done(total: u64, done: u64, count: u64) -> u64 {
    if count == 0 {
        total
    } else {
        (total as f64 * done as f64 / count as f64) as u64
    }
}
