//! Geomview OFF (ascii).
//!
//! Layout: a keyword line `OFF` (prefixes `ST`, `C`, `N` accepted: the
//! extra per-vertex values are ignored; `4OFF`, `nOFF` and `OFF BINARY` are
//! refused as unsupported), a counts line `vertices faces [edges]` (which
//! may also follow the keyword on its line), one vertex per line (the first
//! three numbers are x y z), then one face per line: `n i j k ...`, extra
//! values after the indices (a face colour) ignored. `#` starts a comment;
//! blank lines are skipped. The format is read line by line: one record per
//! line, as all common OFF writers produce.
//!
//! [`open`] spills the vertices; [`OffBody`] streams the faces,
//! fan-triangulating polygons, and checks that only blank or comment lines
//! follow the last face. The writer reserves the counts line with space
//! padding and rewrites it at `finish`.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

use crate::error::{show_token, Error, ErrorKind};
use crate::format::off_keyword;
use crate::mapped::{Mapped, SpillFile};
use crate::positions::Positions;
use crate::backend::{ElementInfo, MeshInfo, Opened};
use crate::text::{line_of, parse_f64, parse_i64, words, Lines};
use crate::backend::WriteOptions;
use crate::line_formats::{FaceLines, Section, TextStyle, TextWriter};
use crate::Format;

/// The next line with content, `#` comments removed: (start, content).
fn content_line<'a>(lines: &mut Lines<'a>) -> Option<(usize, &'a [u8])> {
    while let Some((at, line)) = lines.next_line() {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(n) => &line[..n],
            None => line,
        };
        if words(line).next().is_some() {
            return Some((at, line));
        }
    }
    None
}

/// The parsed header: counts, comments, and where the vertices start.
struct Header {
    nv: u64,
    nf: u64,
    comments: Vec<String>,
    body: usize,
}

fn at(e: Error, data: &[u8], element: &str, record: Option<u64>, off: usize) -> Error {
    let e = e.at_element(element);
    let e = match record {
        Some(r) => e.at_record(r),
        None => e,
    };
    e.at_line(line_of(data, off)).at_byte(off as u64)
}

fn parse_header(path: &Path, data: &[u8]) -> Result<Header, Error> {
    let mut comments = Vec::new();
    let mut lines = Lines::new(data, 0);
    // Leading comments.
    let (kat, kline) = loop {
        let Some((a, line)) = lines.next_line() else {
            return Err(at(Error::format(path, "empty OFF file: no 'OFF' keyword"), data, "header", None, data.len()));
        };
        let trimmed = line.trim_ascii();
        if let Some(c) = trimmed.strip_prefix(b"#") {
            comments.push(String::from_utf8_lossy(c).trim().to_string());
            continue;
        }
        if trimmed.is_empty() {
            continue;
        }
        break (a, line);
    };
    let kline = match kline.iter().position(|&b| b == b'#') {
        Some(n) => &kline[..n],
        None => kline,
    };
    let mut w = words(kline);
    let tok = w.next().unwrap_or(b"");
    // `OFF8 6 12`: the keyword and the first count run together (files
    // written so exist among public test meshes).
    let (kw, glued): (&[u8], Option<&[u8]>) = match tok.windows(3).position(|x| x == b"OFF") {
        Some(i) if off_keyword(tok).is_none() && i + 3 < tok.len() && tok[i + 3..].iter().all(u8::is_ascii_digit) => (&tok[..i + 3], Some(&tok[i + 3..])),
        _ => (tok, None),
    };
    let Some(prefix) = off_keyword(kw) else {
        return Err(at(Error::format(path, format!("not an OFF file: expected 'OFF', found {}", show_token(kw))), data, "header", None, kat));
    };
    if prefix.contains(&b'4') || prefix.contains(&b'n') {
        return Err(at(
            Error::unsupported(path, format!("{} (vertices of other than 3 dimensions) is not supported", show_token(kw))),
            data,
            "header",
            None,
            kat,
        ));
    }
    let rest: Vec<&[u8]> = glued.into_iter().chain(w).collect();
    if rest.first() == Some(&&b"BINARY"[..]) {
        return Err(at(Error::unsupported(path, "binary OFF is not supported"), data, "header", None, kat));
    }
    let (cat, counts) = if rest.is_empty() {
        content_line(&mut lines).ok_or_else(|| at(Error::format(path, "no counts line after 'OFF'"), data, "header", None, data.len()))?
    } else {
        (kat, kline)
    };
    let nums: Vec<&[u8]> = if rest.is_empty() { words(counts).filter(|t| off_keyword(t).is_none()).collect() } else { rest.clone() };
    let parse = |t: Option<&&[u8]>| t.and_then(|t| parse_i64(t)).filter(|&n| n >= 0).map(|n| n as u64);
    let (Some(nv), Some(nf)) = (parse(nums.first()), parse(nums.get(1))) else {
        return Err(at(
            Error::format(path, format!("expected a counts line 'vertices faces edges', found {}", show_token(counts))),
            data,
            "header",
            None,
            cat,
        ));
    };
    Ok(Header { nv, nf, comments, body: lines.pos.min(data.len()) })
}

fn make_info(h: &Header) -> MeshInfo {
    MeshInfo {
        format: Format::Off,
        encoding: "ascii".into(),
        vertex_count: h.nv,
        face_count: Some(h.nf),
        elements: vec![
            ElementInfo { name: "vertex".into(), count: h.nv, properties: vec!["x".into(), "y".into(), "z".into()] },
            ElementInfo { name: "face".into(), count: h.nf, properties: vec!["vertex_indices".into()] },
        ],
        comments: h.comments.clone(),
        obj_info: Vec::new(),
    }
}

/// Header information (keyword and counts only).
pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    Ok(make_info(&parse_header(path, data)?))
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let data = map.bytes();
    map.advise_sequential(0, data.len());
    let h = parse_header(path, data)?;
    if h.nv > u32::MAX as u64 {
        return Err(Error::unsupported(path, format!("{} vertices; mint reads at most {} (32-bit indices)", h.nv, u32::MAX)).at_element("vertex"));
    }
    let mut spill = SpillFile::new(spill_dir, path)?;
    let mut lines = Lines::new(data, h.body);
    for r in 0..h.nv {
        let Some((a, line)) = content_line(&mut lines) else {
            return Err(at(
                Error::format(path, format!("unexpected end of file: {} vertices declared, {r} found (truncated file?)", h.nv)),
                data,
                "vertex",
                Some(r),
                data.len(),
            ));
        };
        let mut p = [0.0; 3];
        let mut w = words(line);
        for (k, c) in p.iter_mut().enumerate() {
            let tok = w.next().ok_or_else(|| {
                at(Error::format(path, format!("a vertex line needs 3 coordinates, found {k}")), data, "vertex", Some(r), a)
            })?;
            *c = parse_f64(tok).ok_or_else(|| {
                at(Error::format(path, format!("expected a number, found {}", show_token(tok))), data, "vertex", Some(r), a)
            })?;
        }
        spill.write_point(p)?;
    }
    let positions = Positions::spilled(Arc::new(spill.into_mapped()?), h.nv as u32);
    let body = OffBody { sec: Section::new(path, map.clone(), lines.pos.min(data.len())), nf: h.nf, rec: 0, rec_at: 0 };
    Ok(Opened { info: make_info(&h), positions, body: Box::new(body), range_grid: None, spilled_vertices: h.nv, colours: None, face_colours: None, texturing: None })
}

/// Streams OFF faces (see the module docs).
struct OffBody {
    sec: Section,
    nf: u64,
    /// Face lines read.
    rec: u64,
    rec_at: usize,
}

impl OffBody {
    fn parse_face(&mut self, data: &[u8], line: &[u8], a: usize, nv: u32) -> Result<(), Error> {
        self.sec.fan.clear();
        let r = self.rec;
        let err = |kind, msg: String| at(Error::new(kind, &self.sec.path, msg), data, "face", Some(r), a);
        let mut w = words(line);
        let first = w.next().unwrap_or(b"");
        let n = parse_i64(first)
            .filter(|&n| n >= 0)
            .ok_or_else(|| err(ErrorKind::Format, format!("expected a corner count, found {}", show_token(first))))?;
        for k in 0..n {
            let tok = w.next().ok_or_else(|| err(ErrorKind::Format, format!("a face of {n} corners lists only {k} indices")))?;
            let i = parse_i64(tok).ok_or_else(|| err(ErrorKind::Format, format!("expected a vertex index, found {}", show_token(tok))))?;
            if i < 0 || i >= nv as i64 {
                return Err(err(ErrorKind::Index, format!("vertex index {i} is out of range (the file has {nv} vertices)")));
            }
            self.sec.fan.push(i as u32);
        }
        Ok(())
    }
}

impl FaceLines for OffBody {
    fn section(&self) -> &Section {
        &self.sec
    }

    fn section_mut(&mut self) -> &mut Section {
        &mut self.sec
    }

    fn locate(&self, e: Error, data: &[u8]) -> Error {
        at(e, data, "face", Some(self.rec - 1), self.rec_at)
    }

    fn next_line<'d>(&mut self, lines: &mut Lines<'d>, data: &'d [u8]) -> Result<Option<(usize, Cow<'d, [u8]>)>, Error> {
        if self.rec == self.nf {
            // Only blank lines and comments may follow.
            if let Some((a, line)) = content_line(lines) {
                let tok = words(line).next().unwrap_or(b"");
                return Err(at(
                    Error::format(&self.sec.path, format!("unexpected data after the last face: {} (the counts line does not match the body)", show_token(tok))),
                    data,
                    "face",
                    Some(self.nf),
                    a,
                ));
            }
            return Ok(None);
        }
        match content_line(lines) {
            Some((a, line)) => Ok(Some((a, Cow::Borrowed(line)))),
            None => Err(at(
                Error::format(&self.sec.path, format!("unexpected end of file: {} faces declared, {} found (truncated file?)", self.nf, self.rec)),
                data,
                "face",
                Some(self.rec),
                data.len(),
            )),
        }
    }

    fn face(&mut self, data: &[u8], a: usize, line: &[u8], nv: u32) -> Result<bool, Error> {
        self.parse_face(data, line, a, nv)?;
        self.rec += 1;
        self.rec_at = a;
        Ok(true)
    }
}

/// Width of the reserved counts line, without its newline: two 20-digit
/// counts, a 1-digit edge count and separators.
const COUNTS_WIDTH: usize = 43;

fn counts_line(v: u64, f: u64) -> String {
    format!("{:<width$}\n", format!("{v} {f} 0"), width = COUNTS_WIDTH)
}

/// OFF as mint writes it: the counts line reserved after `OFF` and
/// patched at the end, vertex lines, `3 a b c` face lines.
pub(crate) fn writer(path: &Path, opts: &WriteOptions) -> Result<TextWriter, Error> {
    TextWriter::create(path, opts, TextStyle { header: b"OFF\n", vertex: b"", face: "3 ", base: 0, counts: Some(counts_line), colour: false })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_line_has_fixed_width() {
        assert_eq!(counts_line(0, 0).len(), COUNTS_WIDTH + 1);
        assert_eq!(counts_line(u64::MAX, u64::MAX).len(), COUNTS_WIDTH + 1);
    }

    #[test]
    fn header_forms() {
        let h = parse_header(Path::new("a.off"), b"# hi\nOFF 4 2 0\n0 0 0\n").unwrap();
        assert_eq!((h.nv, h.nf, h.comments.clone()), (4, 2, vec!["hi".to_string()]));
        let h = parse_header(Path::new("a.off"), b"COFF\n\n# c\n3 1 3\n").unwrap();
        assert_eq!((h.nv, h.nf), (3, 1));
        let h = parse_header(Path::new("a.off"), b"OFF8 6 12\n").unwrap();
        assert_eq!((h.nv, h.nf), (8, 6));
        let e = parse_header(Path::new("a.off"), b"4OFF\n1 0 0\n").err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Unsupported);
        let e = parse_header(Path::new("a.off"), b"OFF\nx y\n").err().unwrap();
        assert_eq!(e.to_string(), "a.off: expected a counts line 'vertices faces edges', found 'x y' (element 'header', line 2, byte offset 4)");
    }
}
