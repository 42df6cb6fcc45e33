//! The streaming writer. [`MeshWriter`] checks the sink contract (all
//! vertices before any face, finite coordinates, indices in range), counts,
//! and hands each vertex and face to a format writer (PLY, OBJ, STL, OFF,
//! mesh, raw, VRML, 3DS)
//! that appends bytes to an `OutFile`: a 1 MiB buffer over an
//! [`AtomicFile`]. Counts that a format stores before the data (PLY header,
//! OFF counts line, binary STL facet count) are written as placeholders of
//! fixed size and patched in place by `finish`, which then syncs and renames
//! the temporary file onto the target. Any error, or dropping the writer
//! without `finish`, removes the temporary file and leaves the target as it
//! was.
//!
//! Memory: the buffer, plus for STL, raw and 3DS output a spill file of
//! vertex positions (f64 triples, mapped), since those store positions per
//! facet or per object.

use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use mint_core::{MeshSink, SinkError};

use crate::atomic::AtomicFile;
use crate::error::{Error, ErrorKind};
use crate::format::Format;
use crate::{mesh, obj, off, ply, raw, stl, three_ds, vrml};

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
}

/// What [`MeshWriter::finish`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WriteSummary {
    /// The target path, now complete.
    pub path: PathBuf,
    /// The format written.
    pub format: Format,
    /// Vertices written.
    pub vertices: u64,
    /// Faces (triangles) written.
    pub faces: u64,
    /// Size of the written file.
    pub bytes: u64,
}

/// A buffered writer over an [`AtomicFile`], with in-place patching.
pub(crate) struct OutFile {
    file: AtomicFile,
    buf: Vec<u8>,
    flushed: u64,
}

const FLUSH_AT: usize = 1 << 20;

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
            self.flush_buf()?;
        }
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
    fn face(&mut self, f: [u32; 3]) -> Result<(), Error>;
    /// Patches counts, syncs and renames; returns the file size.
    fn finish(self: Box<Self>, vertices: u64, faces: u64) -> Result<u64, Error>;
}

/// A streaming mesh file writer; see the module docs. Implements
/// [`MeshSink`], so algorithms can write straight to disk.
pub struct MeshWriter {
    path: PathBuf,
    format: Format,
    inner: Box<dyn FormatWriter>,
    /// Coordinates are stored as f32 (checked to fit).
    f32_out: bool,
    vertices: u64,
    faces: u64,
}

impl std::fmt::Debug for MeshWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshWriter")
            .field("path", &self.path)
            .field("format", &self.format)
            .field("vertices", &self.vertices)
            .field("faces", &self.faces)
            .finish_non_exhaustive()
    }
}

impl MeshWriter {
    /// Starts writing `path` in `format`: creates a temporary file beside
    /// it (the target appears only at [`finish`](MeshWriter::finish)).
    pub fn create(path: &Path, format: Format, opts: WriteOptions) -> Result<MeshWriter, Error> {
        let inner: Box<dyn FormatWriter> = match format {
            Format::Ply => Box::new(ply::write::PlyWriter::create(path, &opts)?),
            Format::Obj => Box::new(obj::ObjWriter::create(path, &opts)?),
            Format::Stl => Box::new(stl::StlWriter::create(path, &opts)?),
            Format::Off => Box::new(off::OffWriter::create(path, &opts)?),
            Format::Mesh => Box::new(mesh::MeshFmtWriter::create(path, &opts)?),
            Format::Raw => Box::new(raw::RawWriter::create(path, &opts)?),
            Format::Vrml => Box::new(vrml::VrmlWriter::create(path, &opts)?),
            Format::ThreeDs => Box::new(three_ds::ThreeDsWriter::create(path, &opts)?),
        };
        let f32_out = !opts.double || matches!(format, Format::Stl | Format::ThreeDs);
        Ok(MeshWriter { path: path.to_path_buf(), format, inner, f32_out, vertices: 0, faces: 0 })
    }

    /// Appends a vertex. All vertices come before the first face; the
    /// coordinates must be finite.
    pub fn write_vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        if self.faces > 0 {
            return Err(Error::unsupported(&self.path, "a vertex after the first face (streaming writers need all vertices first)")
                .at_element("vertex")
                .at_record(self.vertices));
        }
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::new(
                ErrorKind::Value,
                &self.path,
                format!("non-finite vertex coordinate ({}, {}, {})", p[0], p[1], p[2]),
            )
            .at_element("vertex")
            .at_record(self.vertices));
        }
        if self.f32_out && !p.iter().all(|&c| (c as f32).is_finite()) {
            return Err(Error::new(
                ErrorKind::Value,
                &self.path,
                format!("vertex ({}, {}, {}) does not fit in 32-bit floats (write with double coordinates)", p[0], p[1], p[2]),
            )
            .at_element("vertex")
            .at_record(self.vertices));
        }
        if self.vertices >= u32::MAX as u64 {
            return Err(Error::unsupported(&self.path, format!("more than {} vertices (32-bit indices)", u32::MAX)).at_element("vertex"));
        }
        self.inner.vertex(p)?;
        self.vertices += 1;
        Ok(())
    }

    /// Appends a triangle of 0-based vertex indices, each below the number
    /// of vertices written.
    pub fn write_face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        if let Some(&bad) = f.iter().find(|&&i| i as u64 >= self.vertices) {
            return Err(Error::new(
                ErrorKind::Index,
                &self.path,
                format!("vertex index {bad} is out of range ({} vertices written)", self.vertices),
            )
            .at_element("face")
            .at_record(self.faces));
        }
        self.inner.face(f)?;
        self.faces += 1;
        Ok(())
    }

    /// Vertices written so far.
    pub fn vertices(&self) -> u64 {
        self.vertices
    }

    /// Faces written so far.
    pub fn faces(&self) -> u64 {
        self.faces
    }

    /// Fills in the counts, flushes, syncs and renames the file onto the
    /// target path.
    pub fn finish(self) -> Result<WriteSummary, Error> {
        let bytes = self.inner.finish(self.vertices, self.faces)?;
        Ok(WriteSummary { path: self.path, format: self.format, vertices: self.vertices, faces: self.faces, bytes })
    }
}

impl MeshSink for MeshWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), SinkError> {
        Ok(self.write_vertex(p)?)
    }
    fn face(&mut self, f: [u32; 3]) -> Result<(), SinkError> {
        Ok(self.write_face(f)?)
    }
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
