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

use std::path::{Path, PathBuf};

use mint_core::{MeshSink, SinkError};

use crate::error::{Error, ErrorKind};
use crate::format::Format;
pub use crate::backend::WriteOptions;
use crate::backend::FormatWriter;

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

/// A streaming mesh file writer; see the module docs. Implements
/// [`MeshSink`], so algorithms can write straight to disk.
pub struct MeshWriter {
    path: PathBuf,
    format: Format,
    inner: Box<dyn FormatWriter>,
    /// Coordinates are stored as f32 (checked to fit).
    f32_out: bool,
    /// Per-vertex colour is written (asked for, and the format holds it).
    colours: bool,
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
        let backend = crate::formats::backend(format);
        let inner = (backend.create)(path, &opts)?;
        let f32_out = !opts.double || backend.f32_only;
        let colours = opts.colours && backend.colour;
        Ok(MeshWriter { path: path.to_path_buf(), format, inner, f32_out, colours, vertices: 0, faces: 0 })
    }

    /// True when `format` can hold per-vertex colour (PLY, OBJ).
    pub fn holds_colour(format: Format) -> bool {
        crate::formats::backend(format).colour
    }

    /// True when this writer writes per-vertex colour.
    pub fn writes_colour(&self) -> bool {
        self.colours
    }

    /// Appends a vertex with its colour (RGBA bytes). The colour is written
    /// when the writer writes colour ([`MeshWriter::writes_colour`]), else
    /// dropped; otherwise as [`MeshWriter::write_vertex`].
    pub fn write_vertex_rgba(&mut self, p: [f64; 3], c: [u8; 4]) -> Result<(), Error> {
        self.check_vertex(p)?;
        if self.colours {
            self.inner.vertex_rgba(p, c)?;
        } else {
            self.inner.vertex(p)?;
        }
        self.vertices += 1;
        Ok(())
    }

    /// Appends a vertex. All vertices come before the first face; the
    /// coordinates must be finite. A writer that writes colour gives it
    /// white.
    pub fn write_vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        if self.colours {
            return self.write_vertex_rgba(p, [255; 4]);
        }
        self.check_vertex(p)?;
        self.inner.vertex(p)?;
        self.vertices += 1;
        Ok(())
    }

    /// What every vertex must be, with the error naming it.
    fn check_vertex(&self, p: [f64; 3]) -> Result<(), Error> {
        self.check_vertex_at(p, self.vertices)
    }

    /// [`MeshWriter::check_vertex`] of the vertex that will be number `record`.
    fn check_vertex_at(&self, p: [f64; 3], record: u64) -> Result<(), Error> {
        if self.faces > 0 {
            return Err(Error::unsupported(&self.path, "a vertex after the first face (streaming writers need all vertices first)")
                .at_element("vertex")
                .at_record(record));
        }
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::new(
                ErrorKind::Value,
                &self.path,
                format!("non-finite vertex coordinate ({}, {}, {})", p[0], p[1], p[2]),
            )
            .at_element("vertex")
            .at_record(record));
        }
        if self.f32_out && !p.iter().all(|&c| (c as f32).is_finite()) {
            return Err(Error::new(
                ErrorKind::Value,
                &self.path,
                format!("vertex ({}, {}, {}) does not fit in 32-bit floats (write with double coordinates)", p[0], p[1], p[2]),
            )
            .at_element("vertex")
            .at_record(record));
        }
        if record >= u32::MAX as u64 {
            return Err(Error::unsupported(&self.path, format!("more than {} vertices (32-bit indices)", u32::MAX)).at_element("vertex"));
        }
        Ok(())
    }

    /// Appends a triangle of 0-based vertex indices, each below the number
    /// of vertices written.
    pub fn write_face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        self.check_face_at(f, self.faces)?;
        self.inner.face(f)?;
        self.faces += 1;
        Ok(())
    }

    /// What every face must be: indices of vertices written.
    fn check_face_at(&self, f: [u32; 3], record: u64) -> Result<(), Error> {
        match f.iter().find(|&&i| i as u64 >= self.vertices) {
            Some(&bad) => Err(Error::new(ErrorKind::Index, &self.path, format!("vertex index {bad} is out of range ({} vertices written)", self.vertices))
                .at_element("face")
                .at_record(record)),
            None => Ok(()),
        }
    }

    /// Appends many vertices: the same file as [`MeshWriter::write_vertex`]
    /// on each, faster (binary PLY builds its records in bulk). Checked
    /// first, as a whole: nothing is appended when one is refused.
    pub fn write_vertices(&mut self, ps: &[[f64; 3]]) -> Result<(), Error> {
        if self.colours {
            return ps.iter().try_for_each(|&p| self.write_vertex(p));
        }
        for (k, &p) in ps.iter().enumerate() {
            self.check_vertex_at(p, self.vertices + k as u64)?;
        }
        self.inner.vertices(ps)?;
        self.vertices += ps.len() as u64;
        Ok(())
    }

    /// Appends many triangles: the same file as [`MeshWriter::write_face`]
    /// on each, faster. Checked first, as a whole.
    pub fn write_faces(&mut self, fs: &[[u32; 3]]) -> Result<(), Error> {
        for (k, f) in fs.iter().enumerate() {
            self.check_face_at(*f, self.faces + k as u64)?;
        }
        self.inner.faces(fs)?;
        self.faces += fs.len() as u64;
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
    fn vertex_rgba(&mut self, p: [f64; 3], c: [u8; 4]) -> Result<(), SinkError> {
        Ok(self.write_vertex_rgba(p, c)?)
    }
    fn face(&mut self, f: [u32; 3]) -> Result<(), SinkError> {
        Ok(self.write_face(f)?)
    }
}
