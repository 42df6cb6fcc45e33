//! What mint's line-based mesh formats (OBJ, OFF, Medit-like `mesh`) share,
//! written once: the face loop of their readers ([`fill_faces`]: emit the
//! current polygon's triangles, stop when the chunk is full, else read the
//! next face line), and their writer ([`TextWriter`]: a header, a line per
//! vertex, a line per face, and OFF's counts patched in at the end). Each
//! format says only what differs ([`FaceLines`], [`TextStyle`]).

use std::borrow::Cow;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::backend::{write_point, FaceStream, FormatWriter, OutFile, PolygonFan, ReadStats, WriteOptions};
use crate::error::Error;
use crate::mapped::Mapped;
use crate::positions::{not_finite, Emit};
use crate::text::Lines;

/// What every line-based body streams through: its file and map, where the
/// next unread line starts, and the polygon being emitted.
pub(crate) struct Section {
    pub(crate) path: PathBuf,
    pub(crate) map: Arc<Mapped>,
    pub(crate) pos: usize,
    pub(crate) fan: PolygonFan,
}

impl Section {
    /// The face section of `path` (mapped as `map`), from byte `pos`.
    pub(crate) fn new(path: &Path, map: Arc<Mapped>, pos: usize) -> Section {
        Section { path: path.to_path_buf(), map, pos, fan: PolygonFan::default() }
    }
}

/// A line-based format's face section, as [`fill_faces`] reads it.
pub(crate) trait FaceLines: Send {
    /// The body's [`Section`].
    fn section(&self) -> &Section;
    fn section_mut(&mut self) -> &mut Section;
    /// Where in the file the current polygon is, added to an error about it.
    fn locate(&self, e: Error, data: &[u8]) -> Error;
    /// The next line of the face section, or `None` where it ends (an
    /// error where it may not end yet).
    fn next_line<'d>(&mut self, lines: &mut Lines<'d>, data: &'d [u8]) -> Result<Option<(usize, Cow<'d, [u8]>)>, Error>;
    /// Reads the line at byte `at` into the polygon (counting it); `false`
    /// when it is not a face line.
    fn face(&mut self, data: &[u8], at: usize, line: &[u8], nv: u32) -> Result<bool, Error>;
}

/// Every line-based format's face stream is [`fill_faces`].
impl<B: FaceLines> FaceStream for B {
    fn fill(&mut self, out: &mut Emit, stats: &mut ReadStats) -> Result<bool, Error> {
        fill_faces(self, out, stats)
    }

    fn bytes_done(&self) -> u64 {
        self.section().pos as u64
    }
}

/// Fills `out` with the next triangles of `body` (see the module docs).
/// Returns `false` once the faces are exhausted.
fn fill_faces<B: FaceLines>(body: &mut B, out: &mut Emit, stats: &mut ReadStats) -> Result<bool, Error> {
    let map = body.section().map.clone();
    let data = map.bytes();
    let nv = out.pos.count();
    let mut lines = Lines::new(data, body.section().pos);
    loop {
        match body.section_mut().fan.emit(out) {
            Ok(true) => {}
            Ok(false) => {
                body.section_mut().pos = lines.pos;
                return Ok(true);
            }
            Err(v) => return Err(body.locate(not_finite(&body.section().path, v, out.pos), data)),
        }
        let Some((at, line)) = body.next_line(&mut lines, data)? else {
            body.section_mut().pos = data.len();
            return Ok(false);
        };
        if body.face(data, at, &line, nv)? {
            body.section_mut().fan.ready(stats);
        }
    }
}

/// How a line-based format writes.
pub(crate) struct TextStyle {
    /// The first bytes of the file.
    pub(crate) header: &'static [u8],
    /// What starts a vertex line.
    pub(crate) vertex: &'static [u8],
    /// What starts a face line (before the corner count, for OFF).
    pub(crate) face: &'static str,
    /// The index of the first vertex (OBJ: 1).
    pub(crate) base: u64,
    /// OFF: a counts line of fixed width after the header, patched at the
    /// end with the vertex and face counts.
    pub(crate) counts: Option<fn(u64, u64) -> String>,
    /// OBJ: vertex colour as `v x y z r g b` (channels in [0, 1]).
    pub(crate) colour: bool,
}

/// The one writer of the line-based formats.
pub(crate) struct TextWriter {
    out: OutFile,
    double: bool,
    style: TextStyle,
}

impl TextWriter {
    pub(crate) fn create(path: &Path, opts: &WriteOptions, style: TextStyle) -> Result<TextWriter, Error> {
        let mut out = OutFile::create(path)?;
        out.put(style.header)?;
        if let Some(counts) = style.counts {
            out.put(counts(0, 0).as_bytes())?;
        }
        Ok(TextWriter { out, double: opts.double, style })
    }
}

impl FormatWriter for TextWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        write_point(self.out.text(), self.style.vertex, p, self.double, b"\n");
        self.out.maybe_flush()
    }

    fn vertex_rgba(&mut self, p: [f64; 3], c: [u8; 4]) -> Result<(), Error> {
        if !self.style.colour {
            return self.vertex(p);
        }
        let t = self.out.text();
        write_point(t, self.style.vertex, p, self.double, b"");
        // The shortest f32 decimal of c/255 reads back as the same byte.
        let _ = writeln!(t, " {} {} {}", c[0] as f32 / 255.0, c[1] as f32 / 255.0, c[2] as f32 / 255.0);
        self.out.maybe_flush()
    }

    fn face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        let b = self.style.base;
        let _ = writeln!(self.out.text(), "{}{} {} {}", self.style.face, f[0] as u64 + b, f[1] as u64 + b, f[2] as u64 + b);
        self.out.maybe_flush()
    }

    fn finish(mut self: Box<Self>, vertices: u64, faces: u64) -> Result<u64, Error> {
        if let Some(counts) = self.style.counts {
            self.out.patch(self.style.header.len() as u64, counts(vertices, faces).as_bytes())?;
        }
        self.out.commit()
    }
}
