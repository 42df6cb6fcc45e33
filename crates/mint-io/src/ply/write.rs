//! The PLY writer: binary little-endian (default) or ascii, vertices
//! `float x y z` (or `double`), faces `list uchar int vertex_indices`
//! (`uint` when there are more than 2^31 - 1 vertices).
//!
//! The header is written first with zero counts and padded to a fixed size
//! by trailing spaces on its `comment written by mint-io` line; `finish` rewrites it with the real counts, padded to
//! the same size, so the vertex section never moves.

use std::io::Write;
use std::path::Path;

use crate::error::Error;
use crate::ply::header::Encoding;
use crate::backend::{write_coord, FormatWriter, OutFile, WriteOptions};

/// Records per bulk chunk ([`FormatWriter::vertices`], [`FormatWriter::faces`]).
const BULK: usize = 1 << 16;

pub(crate) struct PlyWriter {
    out: OutFile,
    encoding: Encoding,
    double: bool,
    /// Index type decided at the first face (all vertices are known then).
    uint: Option<bool>,
    /// Vertices carry `uchar red green blue alpha`.
    colours: bool,
    vertices: u64,
    reserved: usize,
}

/// The header text for the given counts, padded to `size` bytes if given.
fn header(encoding: Encoding, double: bool, colours: bool, uint: bool, v: u64, f: u64, size: Option<usize>) -> String {
    let coord = if double { "double" } else { "float" };
    let index = if uint { "uint" } else { "int" };
    let head = format!("ply\nformat {} 1.0\n", encoding.name());
    let rgba = if colours { "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n" } else { "" };
    let tail = format!(
        "element vertex {v}\nproperty {coord} x\nproperty {coord} y\nproperty {coord} z\n{rgba}\
         element face {f}\nproperty list uchar {index} vertex_indices\nend_header\n"
    );
    // The comment after the format line is padded with spaces.
    const COMMENT: &str = "comment written by mint-io";
    let base = head.len() + tail.len() + COMMENT.len() + 1;
    let pad = size.map_or(0, |s| s.saturating_sub(base));
    format!("{head}{COMMENT}{}\n{tail}", " ".repeat(pad))
}

impl PlyWriter {
    pub(crate) fn create(path: &Path, opts: &WriteOptions) -> Result<PlyWriter, Error> {
        let encoding = if opts.ascii { Encoding::Ascii } else { Encoding::BinaryLe };
        let reserved = header(encoding, opts.double, opts.colours, true, u64::MAX, u64::MAX, None).len();
        let mut out = OutFile::create(path)?;
        let h = header(encoding, opts.double, opts.colours, false, 0, 0, Some(reserved));
        debug_assert_eq!(h.len(), reserved);
        out.put(h.as_bytes())?;
        Ok(PlyWriter { out, encoding, double: opts.double, uint: None, colours: opts.colours, vertices: 0, reserved })
    }
}

impl FormatWriter for PlyWriter {
    fn vertex_rgba(&mut self, p: [f64; 3], c: [u8; 4]) -> Result<(), Error> {
        if self.encoding == Encoding::Ascii {
            self.vertices += 1;
            let t = self.out.text();
            for k in 0..3 {
                write_coord(t, p[k], self.double);
                t.push(b' ');
            }
            let _ = writeln!(t, "{} {} {} {}", c[0], c[1], c[2], c[3]);
            return self.out.maybe_flush();
        }
        self.vertex(p)?;
        self.out.put(&c)
    }

    #[inline]
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        self.vertices += 1;
        match (self.encoding, self.double) {
            (Encoding::Ascii, _) => {
                let t = self.out.text();
                write_coord(t, p[0], self.double);
                t.push(b' ');
                write_coord(t, p[1], self.double);
                t.push(b' ');
                write_coord(t, p[2], self.double);
                t.push(b'\n');
                self.out.maybe_flush()
            }
            (_, false) => {
                let mut b = [0u8; 12];
                for k in 0..3 {
                    b[4 * k..4 * k + 4].copy_from_slice(&(p[k] as f32).to_le_bytes());
                }
                self.out.put(&b)
            }
            (_, true) => {
                let mut b = [0u8; 24];
                for k in 0..3 {
                    b[8 * k..8 * k + 8].copy_from_slice(&p[k].to_le_bytes());
                }
                self.out.put(&b)
            }
        }
    }

    #[inline]
    fn face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        let vertices = self.vertices;
        self.uint.get_or_insert(vertices > i32::MAX as u64);
        if self.encoding == Encoding::Ascii {
            let _ = writeln!(self.out.text(), "3 {} {} {}", f[0], f[1], f[2]);
            return self.out.maybe_flush();
        }
        let mut b = [3u8; 13];
        b[1..5].copy_from_slice(&f[0].to_le_bytes());
        b[5..9].copy_from_slice(&f[1].to_le_bytes());
        b[9..13].copy_from_slice(&f[2].to_le_bytes());
        self.out.put(&b)
    }

    fn vertices(&mut self, ps: &[[f64; 3]]) -> Result<(), Error> {
        if self.encoding == Encoding::Ascii {
            return ps.iter().try_for_each(|&p| self.vertex(p));
        }
        // Binary: a chunk's records built at once, one copy into the buffer.
        let mut buf = Vec::with_capacity(ps.len().min(BULK) * 24);
        for chunk in ps.chunks(BULK) {
            buf.clear();
            for p in chunk {
                for c in p {
                    if self.double {
                        buf.extend_from_slice(&c.to_le_bytes());
                    } else {
                        buf.extend_from_slice(&(*c as f32).to_le_bytes());
                    }
                }
            }
            self.out.put(&buf)?;
        }
        self.vertices += ps.len() as u64;
        Ok(())
    }

    fn faces(&mut self, fs: &[[u32; 3]]) -> Result<(), Error> {
        if self.encoding == Encoding::Ascii || fs.is_empty() {
            return fs.iter().try_for_each(|&f| self.face(f));
        }
        let vertices = self.vertices;
        self.uint.get_or_insert(vertices > i32::MAX as u64);
        let mut buf = Vec::with_capacity(fs.len().min(BULK) * 13);
        for chunk in fs.chunks(BULK) {
            buf.clear();
            for f in chunk {
                buf.push(3);
                for i in f {
                    buf.extend_from_slice(&i.to_le_bytes());
                }
            }
            self.out.put(&buf)?;
        }
        Ok(())
    }

    fn finish(mut self: Box<Self>, vertices: u64, faces: u64) -> Result<u64, Error> {
        let uint = self.uint.unwrap_or(vertices > i32::MAX as u64);
        let h = header(self.encoding, self.double, self.colours, uint, vertices, faces, Some(self.reserved));
        debug_assert_eq!(h.len(), self.reserved);
        self.out.patch(0, h.as_bytes())?;
        self.out.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_size_is_fixed() {
        let r = header(Encoding::BinaryLe, false, false, true, u64::MAX, u64::MAX, None).len();
        for (v, f, u) in [(0, 0, false), (12345, 7, false), (u64::MAX, u64::MAX, true)] {
            let h = header(Encoding::BinaryLe, false, false, u, v, f, Some(r));
            assert_eq!(h.len(), r);
            assert!(h.contains(&format!("element vertex {v}\n")));
        }
    }
}
