//! The `mesh` format of Dangl 1998 (appendix A.4): a header line `mesh`,
//! then `v x y z` lines, then `f i j k` lines; `#` starts a comment
//! anywhere after the header.
//!
//! Indices: mint writes them **0-based** (the 1998 grammar allows 0 and says
//! nothing more). On read the base is detected from the whole file: 0-based
//! if any index is 0; else 1-based if the largest index equals the vertex
//! count (so it is out of range for 0-based); else 0-based. The result is
//! shown in [`MeshInfo`]'s face element as `vertex_indices (0-based)` or
//! `(1-based)`.
//!
//! A superset of the 1998 grammar is read: signed numbers and exponents,
//! `v` and `f` lines in any order, and faces of more than three corners
//! (fan-triangulated; fewer than three are skipped and counted as short
//! faces). Any other keyword is a format error naming the line.
//!
//! Reading takes two passes over the mapped file, like OBJ: [`open`] spills
//! the vertices and finds the index base; [`MeshBody`] streams the faces.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

use crate::error::{show_token, Error, ErrorKind};
use crate::mapped::{Mapped, SpillFile};
use crate::positions::Positions;
use crate::backend::{ElementInfo, MeshInfo, Opened};
use crate::text::{line_of, parse_f64, parse_i64, words, Lines};
use crate::backend::WriteOptions;
use crate::line_formats::{FaceLines, Section, TextStyle, TextWriter};
use crate::Format;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Vertex,
    Face,
    Blank,
}

/// Classifies a content line (comment removed) and returns the rest after
/// the keyword, or a format error for an unknown keyword.
fn classify<'a>(path: &Path, data: &[u8], line: &'a [u8], at: usize) -> Result<(Kind, &'a [u8]), Error> {
    let line = match line.iter().position(|&b| b == b'#') {
        Some(n) => &line[..n],
        None => line,
    };
    let mut w = words(line);
    let Some(first) = w.next() else { return Ok((Kind::Blank, line)) };
    let start = first.as_ptr() as usize - line.as_ptr() as usize + first.len();
    let rest = &line[start..];
    match first {
        b"v" => Ok((Kind::Vertex, rest)),
        b"f" => Ok((Kind::Face, rest)),
        _ => Err(Error::format(path, format!("expected 'v' or 'f', found {}", show_token(first)))
            .at_line(line_of(data, at))
            .at_byte(at as u64)),
    }
}

/// Finds the header; returns the offset after its line.
fn header(path: &Path, data: &[u8]) -> Result<usize, Error> {
    let mut lines = Lines::new(data, 0);
    while let Some((at, line)) = lines.next_line() {
        let mut w = words(line);
        match w.next() {
            None => continue,
            Some(b"mesh") => {
                let rest: Vec<&[u8]> = w.collect();
                if rest.first().is_some_and(|t| !t.starts_with(b"#")) {
                    return Err(Error::format(path, format!("unexpected {} after the 'mesh' header", show_token(rest[0])))
                        .at_element("header")
                        .at_line(line_of(data, at))
                        .at_byte(at as u64));
                }
                return Ok(lines.pos.min(data.len()));
            }
            Some(t) => {
                return Err(Error::format(path, format!("not a mesh file: expected the header 'mesh', found {}", show_token(t)))
                    .at_element("header")
                    .at_line(line_of(data, at))
                    .at_byte(at as u64))
            }
        }
    }
    Err(Error::format(path, "empty file: expected the header 'mesh'").at_element("header"))
}

/// First pass: counts, index range and (when `spill` is given) positions.
struct Scan {
    nv: u64,
    nf: u64,
    min_index: i64,
    max_index: i64,
    comments: Vec<String>,
    body: usize,
}

fn scan(path: &Path, data: &[u8], mut spill: Option<&mut SpillFile>) -> Result<Scan, Error> {
    let body = header(path, data)?;
    let mut s = Scan { nv: 0, nf: 0, min_index: i64::MAX, max_index: i64::MIN, comments: Vec::new(), body };
    let mut leading = true;
    let mut lines = Lines::new(data, body);
    while let Some((at, line)) = lines.next_line() {
        let trimmed = line.trim_ascii();
        if leading {
            if let Some(c) = trimmed.strip_prefix(b"#") {
                s.comments.push(String::from_utf8_lossy(c).trim().to_string());
                continue;
            }
        }
        let (kind, rest) = classify(path, data, line, at)?;
        match kind {
            Kind::Blank => {}
            Kind::Vertex => {
                leading = false;
                let mut p = [0.0; 3];
                let mut w = words(rest);
                for (k, c) in p.iter_mut().enumerate() {
                    let bad = |msg: String| Error::format(path, msg).at_element("v").at_record(s.nv).at_line(line_of(data, at)).at_byte(at as u64);
                    let tok = w.next().ok_or_else(|| bad(format!("a 'v' line needs 3 coordinates, found {k}")))?;
                    *c = parse_f64(tok).ok_or_else(|| bad(format!("expected a number, found {}", show_token(tok))))?;
                }
                if let Some(sp) = spill.as_deref_mut() {
                    sp.write_point(p)?;
                }
                s.nv += 1;
            }
            Kind::Face => {
                leading = false;
                for tok in words(rest) {
                    let i = parse_i64(tok).ok_or_else(|| {
                        Error::format(path, format!("expected a vertex index, found {}", show_token(tok)))
                            .at_element("f")
                            .at_record(s.nf)
                            .at_line(line_of(data, at))
                            .at_byte(at as u64)
                    })?;
                    s.min_index = s.min_index.min(i);
                    s.max_index = s.max_index.max(i);
                }
                s.nf += 1;
            }
        }
    }
    Ok(s)
}

impl Scan {
    /// 1 for 1-based files, else 0 (module docs).
    fn base(&self) -> i64 {
        if self.min_index != 0 && self.max_index == self.nv as i64 {
            1
        } else {
            0
        }
    }
}

fn make_info(s: &Scan) -> MeshInfo {
    let base = if s.base() == 1 { "vertex_indices (1-based)" } else { "vertex_indices (0-based)" };
    MeshInfo {
        format: Format::Mesh,
        encoding: "ascii".into(),
        vertex_count: s.nv,
        face_count: Some(s.nf),
        elements: vec![
            ElementInfo { name: "v".into(), count: s.nv, properties: vec!["x".into(), "y".into(), "z".into()] },
            ElementInfo { name: "f".into(), count: s.nf, properties: vec![base.into()] },
        ],
        comments: s.comments.clone(),
        obj_info: Vec::new(),
    }
}

/// Header information: a full scan (the format has no counts).
pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    Ok(make_info(&scan(path, data, None)?))
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let data = map.bytes();
    map.advise_sequential(0, data.len());
    let mut spill = SpillFile::new(spill_dir, path)?;
    let s = scan(path, data, Some(&mut spill))?;
    if s.nv > u32::MAX as u64 {
        return Err(Error::unsupported(path, format!("{} vertices; mint reads at most {} (32-bit indices)", s.nv, u32::MAX)).at_element("v"));
    }
    let positions = Positions::spilled(Arc::new(spill.into_mapped()?), s.nv as u32);
    let body = MeshBody { sec: Section::new(path, map.clone(), s.body), base: s.base(), f_rec: 0, rec_at: 0 };
    Ok(Opened { info: make_info(&s), positions, body: Box::new(body), range_grid: None, spilled_vertices: s.nv, colours: None, face_colours: None, texturing: None })
}

/// Second pass: streams the `f` lines.
struct MeshBody {
    sec: Section,
    base: i64,
    f_rec: u64,
    rec_at: usize,
}

impl FaceLines for MeshBody {
    fn section(&self) -> &Section {
        &self.sec
    }

    fn section_mut(&mut self) -> &mut Section {
        &mut self.sec
    }

    fn locate(&self, e: Error, data: &[u8]) -> Error {
        e.at_element("f").at_record(self.f_rec - 1).at_line(line_of(data, self.rec_at))
    }

    fn next_line<'d>(&mut self, lines: &mut Lines<'d>, _data: &'d [u8]) -> Result<Option<(usize, Cow<'d, [u8]>)>, Error> {
        Ok(lines.next_line().map(|(a, l)| (a, Cow::Borrowed(l))))
    }

    fn face(&mut self, data: &[u8], at: usize, line: &[u8], nv: u32) -> Result<bool, Error> {
        let (kind, rest) = classify(&self.sec.path, data, line, at)?;
        if kind != Kind::Face {
            return Ok(false);
        }
        self.sec.fan.clear();
        for tok in words(rest) {
            let i = parse_i64(tok).unwrap_or(-1) - self.base;
            if i < 0 || i >= nv as i64 {
                return Err(Error::new(
                    ErrorKind::Index,
                    &self.sec.path,
                    format!(
                        "vertex index {} is out of range ({} vertices, indices read as {}-based)",
                        i + self.base,
                        nv,
                        self.base
                    ),
                )
                .at_element("f")
                .at_record(self.f_rec)
                .at_line(line_of(data, at))
                .at_byte(at as u64));
            }
            self.sec.fan.push(i as u32);
        }
        self.f_rec += 1;
        self.rec_at = at;
        Ok(true)
    }
}

/// `mesh` as mint writes it: its header, `v` lines, `f` lines with
/// 0-based indices.
pub(crate) fn writer(path: &Path, opts: &WriteOptions) -> Result<TextWriter, Error> {
    TextWriter::create(path, opts, TextStyle { header: b"mesh\n# written by mint-io; face indices start at 0\n", vertex: b"v ", face: "f ", base: 0, counts: None, colour: false })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan_of(text: &str) -> Result<Scan, Error> {
        scan(Path::new("a.mesh"), text.as_bytes(), None)
    }

    #[test]
    fn index_base_is_detected() {
        let zero = scan_of("mesh\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap();
        assert_eq!(zero.base(), 0);
        let one = scan_of("mesh # c\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(one.base(), 1);
        // Indices 1..2 of 4 vertices: valid both ways, read as 0-based.
        let amb = scan_of("mesh\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 1\n").unwrap();
        assert_eq!(amb.base(), 0);
    }

    #[test]
    fn bad_lines_name_the_line() {
        let e = scan_of("mesh\nv 0 0 0\nvt 1 2\n").err().unwrap();
        assert_eq!(e.to_string(), "a.mesh: expected 'v' or 'f', found 'vt' (line 3, byte offset 13)");
        let e = scan_of("hello\n").err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Format);
        assert!(e.to_string().contains("expected the header 'mesh'"));
        let e = scan_of("mesh\nv 0 0\n").err().unwrap();
        assert!(e.to_string().contains("needs 3 coordinates, found 2"), "{e}");
    }
}
