//! Wavefront OBJ, geometry only.
//!
//! Reading takes two passes over the mapped file. [`open`] makes the first:
//! every `v x y z [w] [r g b]` line becomes an f64 triple in a spill file
//! (w and colours are ignored), and `f` lines are counted. [`ObjBody`] makes
//! the second, streaming `f` lines: each corner is `i`, `i/t`, `i//n` or
//! `i/t/n`; negative indices count back from the vertices defined so far;
//! polygons are fan-triangulated (v0, vi, vi+1) from a small reused buffer;
//! faces with fewer than three corners are skipped and counted. All other
//! lines (`vt`, `vn`, `g`, `o`, `s`, `usemtl`, `mtllib`, `l`, comments)
//! are ignored. Errors name element `v` or `f`, the record (0-based among
//! lines of that kind), the line and byte offset.
//!
//! Writing: `v` lines, then `f` lines with 1-based indices.

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
use crate::textures::{ImageSource, Material, TextureInfo, Texturing, TexturingBuilder, Wrap, NONE};
use crate::Format;
use std::path::PathBuf;

/// The kind of an OBJ line we care about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Vertex,
    Face,
    Comment,
    Other,
}

/// Classifies a line by its first word; returns the kind and the rest of
/// the line after the keyword (comments after `#` removed).
#[inline]
fn classify(line: &[u8]) -> (Kind, &[u8]) {
    let mut i = 0;
    while i < line.len() && (line[i] == b' ' || line[i] == b'\t') {
        i += 1;
    }
    let l = &line[i..];
    let kind = match l {
        [b'v'] | [b'v', b' ' | b'\t', ..] => Kind::Vertex,
        [b'f'] | [b'f', b' ' | b'\t', ..] => Kind::Face,
        [b'#', ..] => return (Kind::Comment, &l[1..]),
        _ => return (Kind::Other, l),
    };
    let rest = l.get(2..).unwrap_or(&[]);
    let rest = match rest.iter().position(|&b| b == b'#') {
        Some(n) => &rest[..n],
        None => rest,
    };
    (kind, rest)
}

fn err_at(e: Error, data: &[u8], element: &str, record: u64, at: usize) -> Error {
    e.at_element(element).at_record(record).at_line(line_of(data, at)).at_byte(at as u64)
}

/// Parses the three coordinates of a `v` line.
fn parse_vertex(path: &Path, data: &[u8], rest: &[u8], record: u64, at: usize) -> Result<([f64; 3], Option<[u8; 4]>), Error> {
    let mut p = [0.0; 3];
    let mut w = words(rest);
    for (k, c) in p.iter_mut().enumerate() {
        let tok = w.next().ok_or_else(|| {
            err_at(Error::format(path, format!("a 'v' line needs 3 coordinates, found {k}")), data, "v", record, at)
        })?;
        *c = parse_f64(tok).ok_or_else(|| {
            err_at(Error::format(path, format!("expected a number, found {}", show_token(tok))), data, "v", record, at)
        })?;
    }
    // `v x y z r g b [a]`, the common extension (channels in [0, 1]);
    // `v x y z [w]` has none.
    let more: Vec<&[u8]> = w.take_while(|t| !t.starts_with(b"#")).take(5).collect();
    if more.len() < 3 {
        return Ok((p, None));
    }
    let mut c = [255u8; 4];
    for (k, tok) in more.iter().take(4).enumerate() {
        let v = parse_f64(tok).ok_or_else(|| {
            err_at(Error::format(path, format!("expected a colour channel, found {}", show_token(tok))), data, "v", record, at)
        })?;
        c[k] = crate::colours::unit_to_u8(v);
    }
    Ok((p, Some(c)))
}

/// Whether the file will come with colour, reading only up to its first
/// `v` line (planning asks this of text files it does not scan): that line
/// has a colour, or an `mtllib` line comes before it (materials and
/// textures; exporters write it first).
pub(crate) fn first_vertex_coloured(data: &[u8]) -> bool {
    let mut lines = Lines::new(data, 0);
    let mut materials = false;
    while let Some((_, line)) = lines.next_joined() {
        match classify(&line[..]) {
            (Kind::Vertex, rest) => return materials || words(rest).take_while(|t| !t.starts_with(b"#")).count() >= 6,
            (Kind::Other, rest) if rest.starts_with(b"mtllib") => materials = true,
            _ => {}
        }
    }
    false
}

/// Counts `v` and `f` lines and collects the leading comment block; says
/// whether the first `v` line has a colour (`v x y z r g b`).
fn scan(data: &[u8]) -> (u64, u64, Vec<String>, bool) {
    let mut colour = false;
    let (mut nv, mut nf) = (0u64, 0u64);
    let mut comments = Vec::new();
    let mut leading = true;
    let mut lines = Lines::new(data, 0);
    while let Some((_, line)) = lines.next_joined() {
        let line = &line[..];
        let (kind, rest) = classify(line);
        match kind {
            Kind::Vertex => {
                if nv == 0 {
                    colour = words(rest).take_while(|t| !t.starts_with(b"#")).count() >= 6;
                }
                nv += 1
            }
            Kind::Face => nf += 1,
            Kind::Comment if leading => comments.push(String::from_utf8_lossy(rest).trim().to_string()),
            _ => {}
        }
        if leading && kind != Kind::Comment && !line.iter().all(|b| b.is_ascii_whitespace()) {
            leading = false;
        }
    }
    (nv, nf, comments, colour)
}

fn make_info(nv: u64, nf: u64, comments: Vec<String>, colour: bool) -> MeshInfo {
    MeshInfo {
        format: Format::Obj,
        encoding: "ascii".into(),
        vertex_count: nv,
        face_count: Some(nf),
        elements: vec![
            ElementInfo { name: "v".into(), count: nv, properties: if colour { vec!["x".into(), "y".into(), "z".into(), "r".into(), "g".into(), "b".into()] } else { vec!["x".into(), "y".into(), "z".into()] } },
            ElementInfo { name: "f".into(), count: nf, properties: vec!["vertex_indices".into()] },
        ],
        comments,
        obj_info: Vec::new(),
    }
}

/// Header information of an OBJ file: a full scan counting lines.
pub(crate) fn info(_path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    let (nv, nf, comments, colour) = scan(data);
    Ok(make_info(nv, nf, comments, colour))
}

/// First pass: spills vertex positions; returns the reader parts.
pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let data = map.bytes();
    map.advise_sequential(0, data.len());
    let mut spill = SpillFile::new(spill_dir, path)?;
    // Colour spill, once the first `v` line says the file has colour.
    let mut cspill: Option<SpillFile> = None;
    let (mut nv, mut nf) = (0u64, 0u64);
    let mut comments = Vec::new();
    let mut leading = true;
    let mut tex = ObjTexturing::default();
    let mut lines = Lines::new(data, 0);
    while let Some((at, line)) = lines.next_joined() {
        let line = &line[..];
        let (kind, rest) = classify(line);
        match kind {
            Kind::Other => tex.line(rest, data, at, spill_dir, path)?,
            Kind::Face if tex.builder.is_some() => {
                tex.face(rest)?;
                nf += 1;
            }
            Kind::Vertex => {
                let (p, c) = parse_vertex(path, data, rest, nv, at)?;
                match (c, cspill.as_mut()) {
                    (Some(c), Some(cs)) => cs.write_bytes(&c)?,
                    (Some(c), None) if nv == 0 => {
                        let mut cs = SpillFile::new(spill_dir, path)?;
                        cs.write_bytes(&c)?;
                        cspill = Some(cs);
                    }
                    (None, None) => {}
                    _ => {
                        let what = if cspill.is_some() { "the first vertex has a colour (x y z r g b), this one none" } else { "the first vertex has no colour, this one has (x y z r g b)" };
                        return Err(err_at(Error::format(path, format!("'v' lines mix 3 and 6 numbers: {what}")), data, "v", nv, at));
                    }
                }
                spill.write_point(p)?;
                nv += 1;
            }
            Kind::Face => nf += 1,
            Kind::Comment if leading => comments.push(String::from_utf8_lossy(rest).trim().to_string()),
            _ => {}
        }
        if kind != Kind::Comment && !line.iter().all(|b| b.is_ascii_whitespace()) {
            leading = false;
        }
    }
    if nv > u32::MAX as u64 {
        return Err(Error::unsupported(path, format!("{nv} vertices; mint reads at most {} (32-bit indices)", u32::MAX)).at_element("v"));
    }
    let positions = Positions::spilled(Arc::new(spill.into_mapped()?), nv as u32);
    let colours = match cspill {
        Some(cs) => Some(crate::colours::VertexColours::spilled(Arc::new(cs.into_mapped()?), nv as u32)),
        None => None,
    };
    // Vertex colour wins over materials.
    let texturing = if colours.is_none() { tex.finish(path)? } else { None };
    let body = ObjBody { sec: Section::new(path, map, 0), v_seen: 0, f_rec: 0, rec_at: 0 };
    Ok(Opened { info: make_info(nv, nf, comments, colours.is_some()), positions, body: Box::new(body), range_grid: None, spilled_vertices: nv, colours, face_colours: None, texturing })
}

/// What the first pass gathers of an OBJ's materials: `vt` pairs,
/// `mtllib` files, the `usemtl` in force, and per triangle (once the file
/// has shown any of these) its material and corner `vt` indices, fanned as
/// the faces are.
#[derive(Default)]
struct ObjTexturing {
    builder: Option<TexturingBuilder>,
    libraries: Vec<String>,
    names: Vec<String>,
    current: Option<u32>,
    corners: Vec<u32>,
}

impl ObjTexturing {
    /// A line of another kind than `v`, `f` and comments.
    fn line(&mut self, l: &[u8], data: &[u8], at: usize, spill_dir: &Path, path: &Path) -> Result<(), Error> {
        let (key, rest) = match l.iter().position(|&b| b == b' ' || b == b'\t') {
            Some(n) => (&l[..n], &l[n + 1..]),
            None => (l, &l[l.len()..]),
        };
        if !matches!(key, b"vt" | b"usemtl" | b"mtllib") {
            return Ok(());
        }
        let rest = String::from_utf8_lossy(rest.split(|&b| b == b'#').next().unwrap_or(&[])).trim().to_string();
        if self.builder.is_none() {
            let mut b = TexturingBuilder::new(spill_dir, path)?;
            // Triangles of faces seen before: no material.
            for _ in 0..count_triangles(&data[..at]) {
                b.triangle(NONE, [NONE; 3])?;
            }
            self.builder = Some(b);
        }
        let b = self.builder.as_mut().unwrap();
        match key {
            b"vt" => {
                let mut w = rest.split_ascii_whitespace().map(|t| parse_f64(t.as_bytes()).unwrap_or(0.0) as f32);
                let uv = [w.next().unwrap_or(0.0), w.next().unwrap_or(0.0)];
                b.uv(uv)?;
            }
            b"usemtl" => {
                let i = match self.names.iter().position(|n| *n == rest) {
                    Some(i) => i,
                    None => {
                        self.names.push(rest);
                        self.names.len() - 1
                    }
                };
                self.current = Some(i as u32);
            }
            _ => self.libraries.push(rest),
        }
        Ok(())
    }

    /// An `f` line: its triangles' records.
    fn face(&mut self, rest: &[u8]) -> Result<(), Error> {
        let b = self.builder.as_mut().unwrap();
        let seen = b.uv_count() as i64;
        self.corners.clear();
        for tok in words(rest) {
            let mut parts = tok.split(|&c| c == b'/');
            parts.next();
            let t = parts.next().and_then(parse_i64).map_or(NONE, |t| match t {
                t if t > 0 => (t - 1).min(NONE as i64 - 1) as u32,
                t if t < 0 && seen + t >= 0 => (seen + t) as u32,
                _ => NONE,
            });
            self.corners.push(t);
        }
        let m = self.current.unwrap_or(NONE);
        for i in 1..self.corners.len().saturating_sub(1) {
            b.triangle(m, [self.corners[0], self.corners[i], self.corners[i + 1]])?;
        }
        Ok(())
    }

    /// The materials from the `mtllib` files (beside the OBJ), their
    /// textures' sizes; `None` when the file named no material and no `vt`.
    fn finish(self, path: &Path) -> Result<Option<Texturing>, Error> {
        let Some(b) = self.builder else { return Ok(None) };
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut warnings = Vec::new();
        let mut found: Vec<(Material, Option<PathBuf>)> = Vec::new();
        for lib in &self.libraries {
            let mtl = dir.join(lib.replace('\\', "/"));
            match std::fs::read(&mtl) {
                Ok(text) => found.extend(parse_mtl(&text, mtl.parent().unwrap_or(dir))),
                Err(_) => warnings.push(format!("{}: material library '{}' not found: its materials are white", path.display(), mtl.display())),
            }
        }
        let mut textures: Vec<TextureInfo> = Vec::new();
        let mut materials = Vec::with_capacity(self.names.len());
        for name in &self.names {
            let Some((m, file)) = found.iter().find(|(m, _)| m.name == *name) else {
                if !self.libraries.is_empty() {
                    warnings.push(format!("{}: material '{name}' is in no material library: white", path.display()));
                }
                materials.push(Material::white(name));
                continue;
            };
            let mut m = m.clone();
            if let Some(file) = file {
                match textures.iter().position(|t| t.source.name() == file.display().to_string()) {
                    Some(i) => m.texture = Some(i),
                    None if file.is_file() => {
                        let source = ImageSource::file(file.clone());
                        let (width, height) = crate::textures::image_size(&source, path)?;
                        textures.push(TextureInfo { source, width, height });
                        m.texture = Some(textures.len() - 1);
                    }
                    None => warnings.push(format!("{}: texture '{}' of material '{name}' not found: its faces take the material's colour", path.display(), file.display())),
                }
            }
            // A texture replaces Kd (exporters write Kd 0.6 or 0.8 beside
            // map_Kd, and viewers show the texture as it is); without its
            // texture the material shows Kd.
            if m.texture.is_some() {
                m.colour = [1.0; 4];
            }
            materials.push(m);
        }
        Ok(Some(b.finish(materials, textures, warnings)?))
    }
}

/// Triangles of the `f` lines in `data` (corners − 2 each).
fn count_triangles(data: &[u8]) -> u64 {
    let mut n = 0;
    let mut lines = Lines::new(data, 0);
    while let Some((_, line)) = lines.next_joined() {
        if let (Kind::Face, rest) = classify(&line[..]) {
            n += (words(rest).count() as u64).saturating_sub(2);
        }
    }
    n
}

/// The materials of an MTL file: `newmtl`, `Kd` and `map_Kd` (its options
/// skipped, `-clamp on` kept); texture paths relative to `dir`.
fn parse_mtl(text: &[u8], dir: &Path) -> Vec<(Material, Option<PathBuf>)> {
    let mut out: Vec<(Material, Option<PathBuf>)> = Vec::new();
    for line in String::from_utf8_lossy(text).lines() {
        let line = line.trim();
        let (key, rest) = line.split_once(char::is_whitespace).map_or((line, ""), |(k, r)| (k, r.trim()));
        match key {
            "newmtl" => out.push((Material::white(rest), None)),
            "Kd" => {
                if let Some((m, _)) = out.last_mut() {
                    let c: Vec<f32> = rest.split_whitespace().filter_map(|t| t.parse().ok()).collect();
                    if c.len() >= 3 {
                        m.colour = [c[0].clamp(0.0, 1.0), c[1].clamp(0.0, 1.0), c[2].clamp(0.0, 1.0), 1.0];
                    }
                }
            }
            "map_Kd" => {
                if let Some((m, file)) = out.last_mut() {
                    // Options take a fixed number of arguments; the rest is the file name.
                    let words: Vec<&str> = rest.split_whitespace().collect();
                    let mut i = 0;
                    while i < words.len() && words[i].starts_with('-') {
                        let n = match words[i] {
                            "-o" | "-s" | "-t" => 3,
                            "-mm" => 2,
                            _ => 1,
                        };
                        if words[i] == "-clamp" && words.get(i + 1) == Some(&"on") {
                            m.wrap = [Wrap::Clamp; 2];
                        }
                        i += 1 + n;
                    }
                    if i < words.len() {
                        *file = Some(dir.join(words[i..].join(" ").replace('\\', "/")));
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// Second pass: streams the faces (see the module docs).
struct ObjBody {
    sec: Section,
    /// `v` lines before the section's position (for negative indices).
    v_seen: u64,
    /// `f` lines before it.
    f_rec: u64,
    /// Where the current polygon's line starts.
    rec_at: usize,
}

impl ObjBody {
    /// Parses the corners of an `f` line into `self.sec.fan`.
    fn parse_face(&mut self, data: &[u8], rest: &[u8], nv: u32, at: usize) -> Result<(), Error> {
        self.sec.fan.clear();
        let record = self.f_rec;
        for tok in words(rest) {
            let num = match tok.iter().position(|&b| b == b'/') {
                Some(n) => &tok[..n],
                None => tok,
            };
            let bad = |kind, msg: String| err_at(Error::new(kind, &self.sec.path, msg), data, "f", record, at);
            let i = parse_i64(num).ok_or_else(|| bad(ErrorKind::Format, format!("expected a vertex index, found {}", show_token(tok))))?;
            let abs = match i {
                0 => return Err(bad(ErrorKind::Index, "vertex index 0 (OBJ indices start at 1)".into())),
                i if i > 0 => i - 1,
                i => self.v_seen as i64 + i,
            };
            if abs < 0 || abs >= nv as i64 {
                return Err(bad(
                    ErrorKind::Index,
                    format!("vertex index {i} is out of range ({} vertices in the file, {} defined before this line)", nv, self.v_seen),
                ));
            }
            self.sec.fan.push(abs as u32);
        }
        Ok(())
    }
}

impl FaceLines for ObjBody {
    fn section(&self) -> &Section {
        &self.sec
    }

    fn section_mut(&mut self) -> &mut Section {
        &mut self.sec
    }

    fn locate(&self, e: Error, data: &[u8]) -> Error {
        err_at(e, data, "f", self.f_rec - 1, self.rec_at)
    }

    fn next_line<'d>(&mut self, lines: &mut Lines<'d>, _data: &'d [u8]) -> Result<Option<(usize, Cow<'d, [u8]>)>, Error> {
        Ok(lines.next_joined())
    }

    fn face(&mut self, data: &[u8], at: usize, line: &[u8], nv: u32) -> Result<bool, Error> {
        match classify(line) {
            (Kind::Vertex, _) => self.v_seen += 1,
            (Kind::Face, rest) => {
                self.parse_face(data, rest, nv, at)?;
                self.f_rec += 1;
                self.rec_at = at;
                return Ok(true);
            }
            _ => {}
        }
        Ok(false)
    }
}

/// OBJ as mint writes it: `v` then `f` lines, indices from 1.
pub(crate) fn writer(path: &Path, opts: &WriteOptions) -> Result<TextWriter, Error> {
    TextWriter::create(path, opts, TextStyle { header: b"# written by mint-io\n", vertex: b"v ", face: "f ", base: 1, counts: None, colour: true })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classify_lines() {
        assert_eq!(classify(b"  v 1 2 3 # c").0, Kind::Vertex);
        assert_eq!(classify(b"v 1 2 3 # c").1, b"1 2 3 ");
        assert_eq!(classify(b"vt 1 2").0, Kind::Other);
        assert_eq!(classify(b"f\t1 2 3").0, Kind::Face);
        assert_eq!(classify(b"# hi").0, Kind::Comment);
        assert_eq!(classify(b"v").0, Kind::Vertex);
        assert_eq!(classify(b"vp 1").0, Kind::Other);
    }
}
