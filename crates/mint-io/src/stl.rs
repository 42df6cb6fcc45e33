//! STL, binary and ascii. STL is a triangle soup: each facet stores its
//! three corner positions, so the reader reports `3 * facets` vertices and
//! triangle `k` is `(3k, 3k + 1, 3k + 2)`; [`convert`](crate::convert) welds
//! equal positions when writing an indexed format.
//!
//! Binary vs ascii: a file is ascii when it starts with `solid` and its
//! first 512 bytes are text mentioning `facet` or `endsolid`; otherwise it
//! is binary (80-byte header, u32 facet count, 50-byte records), whose size
//! must be exactly `84 + 50 * count`. Many binary files start with "solid",
//! which is why the word alone decides nothing.
//!
//! Binary positions are read in place from the map (three vertices per
//! record); ascii facets are parsed once at open into a spill file. The
//! writer spills vertex positions too, because a facet needs the positions
//! of its indices; it computes facet normals from the corners and patches
//! the binary facet count at `finish`.

use glam::DVec3;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{show_token, Error, ErrorKind};
use crate::format::stl_looks_ascii;
use crate::mapped::{Mapped, SpillFile};
use crate::positions::not_finite;
use crate::positions::{Emit, Layout, Positions, Reject, Scalar};
use crate::backend::{ElementInfo, FaceStream, MeshInfo, Opened, ReadStats};
use crate::text::{line_of, parse_f64, Tokens};
use crate::backend::{write_coord, FormatWriter, OutFile, WriteOptions};
use crate::Format;

fn is_ascii(data: &[u8]) -> bool {
    stl_looks_ascii(&data[..data.len().min(4096)])
}

fn make_info(encoding: &str, facets: u64, comments: Vec<String>) -> MeshInfo {
    MeshInfo {
        format: Format::Stl,
        encoding: encoding.into(),
        vertex_count: 3 * facets,
        face_count: Some(facets),
        elements: vec![ElementInfo {
            name: "facet".into(),
            count: facets,
            properties: ["float[3] normal", "float[3] vertex1", "float[3] vertex2", "float[3] vertex3"]
                .iter()
                .map(|s| s.to_string())
                .chain(if encoding == "binary" { Some("ushort attribute".to_string()) } else { None })
                .collect(),
        }],
        comments,
        obj_info: Vec::new(),
    }
}

/// The printable text of a binary STL header.
fn header_text(data: &[u8]) -> Vec<String> {
    let h = &data[..data.len().min(80)];
    let s: String = h.iter().map(|&b| if b.is_ascii_graphic() || b == b' ' { b as char } else { ' ' }).collect();
    let s = s.trim();
    if s.is_empty() {
        Vec::new()
    } else {
        vec![s.to_string()]
    }
}

/// Checks a binary STL's size; returns the facet count.
fn binary_count(path: &Path, data: &[u8]) -> Result<u64, Error> {
    if data.len() < 84 {
        return Err(Error::format(
            path,
            format!("not an STL file: too short for a binary STL header (84 bytes) and not ascii STL ('solid ... facet ...'); {} bytes", data.len()),
        )
        .at_element("header")
        .at_byte(data.len() as u64));
    }
    let count = u32::from_le_bytes(data[80..84].try_into().unwrap()) as u64;
    let expected = 84 + 50 * count;
    let len = data.len() as u64;
    if len != expected {
        let complete = ((len - 84) / 50).min(count);
        let what = if len < expected { "the file is truncated" } else { "trailing data after the last facet" };
        return Err(Error::format(
            path,
            format!("binary STL says {count} facets, which take {expected} bytes, but the file has {len} bytes ({what})"),
        )
        .at_element("facet")
        .at_record(complete)
        .at_byte(84 + 50 * complete));
    }
    Ok(count)
}

/// Header information: binary from the header; ascii by counting `facet`
/// keywords in a full scan.
pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    if is_ascii(data) {
        let mut t = Tokens::new(data, 0);
        let mut n = 0;
        while let Some((_, tok)) = t.next_tok() {
            n += (tok == b"facet") as u64;
        }
        Ok(make_info("ascii", n, solid_name(data)))
    } else {
        let count = binary_count(path, data)?;
        Ok(make_info("binary", count, header_text(data)))
    }
}

/// The name after the first `solid`, as a comment.
fn solid_name(data: &[u8]) -> Vec<String> {
    let line_end = data.iter().position(|&b| b == b'\n').unwrap_or(data.len());
    let line = String::from_utf8_lossy(&data[..line_end]);
    let name = line.trim().strip_prefix("solid").unwrap_or("").trim();
    if name.is_empty() {
        Vec::new()
    } else {
        vec![name.to_string()]
    }
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let data = map.bytes();
    let too_many = |n: u64| {
        Error::unsupported(path, format!("{n} facets need {} vertices; mint reads at most {} (32-bit indices)", 3 * n, u32::MAX))
            .at_element("facet")
    };
    if is_ascii(data) {
        map.advise_sequential(0, data.len());
        let mut spill = SpillFile::new(spill_dir, path)?;
        let facets = parse_ascii(path, data, &mut spill)?;
        if 3 * facets > u32::MAX as u64 {
            return Err(too_many(facets));
        }
        let positions = Positions::spilled(Arc::new(spill.into_mapped()?), 3 * facets as u32);
        let body = StlBody { path: path.to_path_buf(), facets, next: 0, total_bytes: data.len() as u64, binary: false };
        Ok(Opened {
            info: make_info("ascii", facets, solid_name(data)),
            positions,
            body: Box::new(body),
            range_grid: None,
            spilled_vertices: 3 * facets,
            colours: None,
            face_colours: None,
            texturing: None,
        })
    } else {
        let facets = binary_count(path, data)?;
        if 3 * facets > u32::MAX as u64 {
            return Err(too_many(facets));
        }
        map.advise_sequential(0, data.len());
        let layout = Layout { base: 84 + 12, stride: 50, group: 3, inner: 12, off: [0, 4, 8], ty: [Scalar::F32; 3], be: false };
        let positions = Positions::new(map.clone(), 3 * facets as u32, layout);
        let body = StlBody { path: path.to_path_buf(), facets, next: 0, total_bytes: data.len() as u64, binary: true };
        Ok(Opened { info: make_info("binary", facets, header_text(data)), positions, body: Box::new(body), range_grid: None, spilled_vertices: 0, colours: None, face_colours: None, texturing: None })
    }
}

/// Parses an ascii STL (one or more `solid ... endsolid` blocks) into the
/// spill; returns the facet count.
fn parse_ascii(path: &Path, data: &[u8], spill: &mut SpillFile) -> Result<u64, Error> {
    let mut t = Tokens::new(data, 0);
    let mut facets = 0u64;
    let fail = |msg: String, facets: u64, at: usize| {
        Error::format(path, msg).at_element("facet").at_record(facets).at_line(line_of(data, at)).at_byte(at as u64)
    };
    // `next`, `expect` and `number` report errors against the current facet.
    macro_rules! next {
        ($what:expr) => {
            match t.next_tok() {
                Some(x) => x,
                None => return Err(fail(format!("unexpected end of file, expected {} (truncated file?)", $what), facets, data.len())),
            }
        };
    }
    macro_rules! expect {
        ($word:expr) => {{
            let (at, tok) = next!(concat!("'", $word, "'"));
            if tok != $word.as_bytes() {
                return Err(fail(format!("expected '{}', found {}", $word, show_token(tok)), facets, at));
            }
        }};
    }
    macro_rules! number {
        () => {{
            let (at, tok) = next!("a number");
            match parse_f64(tok) {
                Some(v) => v,
                None => return Err(fail(format!("expected a number, found {}", show_token(tok)), facets, at)),
            }
        }};
    }
    let skip_line = |t: &mut Tokens| {
        while t.pos < data.len() && data[t.pos] != b'\n' {
            t.pos += 1;
        }
    };
    expect!("solid");
    skip_line(&mut t);
    loop {
        let (at, tok) = next!("'facet' or 'endsolid'");
        match tok {
            b"facet" => {
                expect!("normal");
                for _ in 0..3 {
                    number!();
                }
                expect!("outer");
                expect!("loop");
                for _ in 0..3 {
                    expect!("vertex");
                    let p = [number!(), number!(), number!()];
                    spill.write_point(p)?;
                }
                expect!("endloop");
                expect!("endfacet");
                facets += 1;
            }
            b"endsolid" => {
                skip_line(&mut t);
                match t.next_tok() {
                    None => return Ok(facets),
                    Some((_, b"solid")) => skip_line(&mut t),
                    Some((at, tok)) => {
                        return Err(fail(format!("unexpected data after 'endsolid': {}", show_token(tok)), facets, at))
                    }
                }
            }
            _ => {
                return Err(fail(format!("expected 'facet' or 'endsolid', found {}", show_token(tok)), facets, at));
            }
        }
    }
}

/// Streams the facets as triangles (3k, 3k + 1, 3k + 2).
struct StlBody {
    path: PathBuf,
    facets: u64,
    next: u64,
    total_bytes: u64,
    binary: bool,
}

impl FaceStream for StlBody {
    fn splittable_records(&self) -> Option<u64> {
        self.binary.then_some(self.facets)
    }

    fn restrict(&mut self, first: u64, end: u64) -> Result<(), Error> {
        self.next = first;
        self.facets = end;
        Ok(())
    }

    fn fixed_faces(&self) -> Result<Option<crate::visit::FixedFaces>, Error> {
        Ok(self.binary.then_some(crate::visit::FixedFaces::Soup { count: self.facets }))
    }

    fn fill(&mut self, out: &mut Emit, _stats: &mut ReadStats) -> Result<bool, Error> {
        while self.next < self.facets && out.room() {
            let k = self.next as u32 * 3;
            if let Err(Reject::NotFinite(v)) = out.tri_checked([k, k + 1, k + 2]) {
                let e = not_finite(&self.path, v, out.pos).at_element("facet").at_record(self.next);
                return Err(if self.binary { e.at_byte(84 + 50 * self.next) } else { e });
            }
            self.next += 1;
        }
        Ok(self.next < self.facets)
    }

    fn bytes_done(&self) -> u64 {
        if self.binary {
            84 + 50 * self.next
        } else if self.facets == 0 {
            self.total_bytes
        } else {
            (self.total_bytes as f64 * self.next as f64 / self.facets as f64) as u64
        }
    }
}

/// Writes binary (default) or ascii STL; see the module docs.
pub(crate) struct StlWriter {
    out: OutFile,
    ascii: bool,
    spill: Option<SpillFile>,
    positions: Option<Positions>,
}

const BINARY_HEADER: &[u8] = b"binary STL written by mint-io";

impl StlWriter {
    pub(crate) fn create(path: &Path, opts: &WriteOptions) -> Result<StlWriter, Error> {
        let spill_dir = opts.spill_dir.clone().unwrap_or_else(std::env::temp_dir);
        let spill = SpillFile::new(&spill_dir, path)?;
        let mut out = OutFile::create(path)?;
        if opts.ascii {
            out.put(b"solid mint\n")?;
        } else {
            let mut h = [b' '; 84];
            h[..BINARY_HEADER.len()].copy_from_slice(BINARY_HEADER);
            h[80..84].copy_from_slice(&0u32.to_le_bytes());
            out.put(&h)?;
        }
        Ok(StlWriter { out, ascii: opts.ascii, spill: Some(spill), positions: None })
    }

    fn positions(&mut self) -> Result<&Positions, Error> {
        if self.positions.is_none() {
            let spill = self.spill.take().expect("spill before positions");
            let n = (spill.len() / 24) as u32;
            self.positions = Some(Positions::spilled(Arc::new(spill.into_mapped()?), n));
        }
        Ok(self.positions.as_ref().unwrap())
    }
}

/// The unit normal of triangle (a, b, c) by the right-hand rule, or zero
/// for a degenerate triangle. It divides by the length: glam's `normalize`
/// multiplies by the reciprocal, which rounds differently and would change
/// the normals written.
fn normal(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let [a, b, c] = [a, b, c].map(DVec3::from);
    let n = (b - a).cross(c - a);
    let len = n.length();
    if len > 0.0 && len.is_finite() {
        (n / len).to_array()
    } else {
        [0.0; 3]
    }
}

impl FormatWriter for StlWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        self.spill.as_mut().expect("vertices before faces").write_point(p)
    }

    fn face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        let pos = self.positions()?;
        let (a, b, c) = (pos.get(f[0]), pos.get(f[1]), pos.get(f[2]));
        let n = normal(a, b, c);
        if self.ascii {
            let t = self.out.text();
            t.extend_from_slice(b"  facet normal ");
            for (k, x) in n.iter().enumerate() {
                if k > 0 {
                    t.push(b' ');
                }
                write_coord(t, *x, false);
            }
            t.extend_from_slice(b"\n    outer loop\n");
            for p in [a, b, c] {
                t.extend_from_slice(b"      vertex ");
                write_coord(t, p[0], false);
                t.push(b' ');
                write_coord(t, p[1], false);
                t.push(b' ');
                write_coord(t, p[2], false);
                t.push(b'\n');
            }
            t.extend_from_slice(b"    endloop\n  endfacet\n");
            self.out.maybe_flush()
        } else {
            let mut r = [0u8; 50];
            for (k, v) in [n, a, b, c].iter().enumerate() {
                for (j, x) in v.iter().enumerate() {
                    let at = 12 * k + 4 * j;
                    r[at..at + 4].copy_from_slice(&(*x as f32).to_le_bytes());
                }
            }
            self.out.put(&r)
        }
    }

    fn finish(mut self: Box<Self>, _vertices: u64, faces: u64) -> Result<u64, Error> {
        if self.ascii {
            let _ = writeln!(self.out.text(), "endsolid mint");
        } else {
            let count = u32::try_from(faces).map_err(|_| {
                Error::new(ErrorKind::Unsupported, self.out.target(), format!("{faces} facets do not fit a binary STL's 32-bit count"))
            })?;
            self.out.patch(80, &count.to_le_bytes())?;
        }
        self.out.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_of_ccw_triangle_points_up() {
        assert_eq!(normal([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(normal([0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]), [0.0; 3]);
    }

    #[test]
    fn ascii_parse_counts_and_errors() {
        let dir = std::env::temp_dir();
        let ok = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let mut s = SpillFile::new(&dir, Path::new("t.stl")).unwrap();
        assert_eq!(parse_ascii(Path::new("t.stl"), ok, &mut s).unwrap(), 1);
        assert_eq!(s.len(), 72);
        let bad = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 x 0\n";
        let mut s = SpillFile::new(&dir, Path::new("t.stl")).unwrap();
        let e = parse_ascii(Path::new("t.stl"), bad, &mut s).unwrap_err();
        assert_eq!(e.to_string(), "t.stl: expected a number, found 'x' (element 'facet', record 0, line 5, byte offset 60)");
    }
}
