//! The PLY reader: locates every element in the body, gives vertex positions
//! an index-addressable home, and streams triangles out of `face` and
//! `tristrips` elements.
//!
//! Data flow. [`open`] parses the header, then walks the elements in file
//! order up to the last one it needs before streaming (`vertex`,
//! `range_grid`): the vertex element becomes [`Positions`] (read in place
//! from the map when the file is binary with a fixed-size vertex record,
//! otherwise parsed once into a spill file of f64 triples), a range grid is
//! parsed into a [`RangeGrid`], and face elements met on the way (faces
//! stored before vertices) are skipped and remembered. [`PlyBody`] then
//! streams the remembered face elements and continues the walk, skipping
//! unknown elements, and finally checks that the body ends exactly where
//! the header says (no trailing bytes or tokens).
//!
//! Records are read through the [`Src`] trait, implemented for binary
//! little/big-endian ([`Bin`]) and ascii ([`Ascii`], a tokenizer over the
//! map), so one generic record walker serves all three encodings. Binary
//! little-endian faces declared `list uchar int` (or `uint`) and holding
//! exactly three indices take [`fast_le_triangles`], a loop that reads 13
//! bytes per triangle straight from the map.
//!
//! Polygons are fan-triangulated (v0, vi, vi+1); records with fewer than
//! three indices are skipped and counted. Strips are unrolled with
//! alternating winding, `-1` restarts a strip, and triangles with a repeated
//! index (the usual degenerate joins) are dropped and counted.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::header::{parse, Element, Encoding, PlyHeader, PropType, Property};
use crate::error::{show_token, Error, ErrorKind};
use crate::mapped::{Mapped, SpillFile};
use crate::colours::{FaceColours, VertexColours};
use crate::textures::{ImageSource, Material, TextureInfo, Texturing, TexturingBuilder, NONE};
use crate::positions::{check_finite, not_finite, Emit, Layout, PosKind, Positions, Reject, Scalar};
use crate::backend::{ElementInfo, FaceStream, MeshInfo, Opened, RangeGrid, ReadStats};
use crate::text::{line_of, parse_f64, parse_int, Tokens};
use crate::Format;

/// What an element is to the reader.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    /// Positions, and colour properties (red, green, blue, alpha; alpha
    /// when the last is `Some`).
    Vertex { xyz: [usize; 3], rgb: Option<[usize; 3]>, alpha: Option<usize> },
    /// Faces (or triangle strips), with their colour properties when the
    /// element has them (faces only).
    Faces { list: usize, strip: bool, rgb: Option<[usize; 3]>, alpha: Option<usize>, texcoord: Option<usize>, texnumber: Option<usize> },
    RangeGrid { list: usize },
    Other,
}

/// The header summary of a PLY file.
pub(crate) fn info_from_header(h: &PlyHeader) -> MeshInfo {
    let vertex_count = h.elements.iter().find(|e| e.name == "vertex").map_or(0, |e| e.count);
    let faces: Vec<u64> = h
        .elements
        .iter()
        .filter(|e| e.name == "face" || e.name == "tristrips")
        .map(|e| e.count)
        .collect();
    MeshInfo {
        format: Format::Ply,
        encoding: h.encoding.name().to_string(),
        vertex_count,
        face_count: if faces.is_empty() { None } else { Some(faces.iter().sum()) },
        elements: h
            .elements
            .iter()
            .map(|e| ElementInfo {
                name: e.name.clone(),
                count: e.count,
                properties: e.props.iter().map(|p| p.decl.clone()).collect(),
            })
            .collect(),
        comments: h.comments.clone(),
        obj_info: h.obj_info.clone(),
    }
}

/// Reads the header of the mapped file `map` and prepares streaming.
pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let header = parse(map.bytes(), path)?;
    let roles = roles(&header, path)?;
    let info = info_from_header(&header);
    let mut body = PlyBody {
        path: path.to_path_buf(),
        map: map.clone(),
        header,
        roles,
        pending: VecDeque::new(),
        next_elem: 0,
        next_offset: 0,
        cur: None,
        finished: false,
        bytes_done: 0,
        range_only: false,
        trailing: 0,
        extra: Vec::new(),
    };
    body.extra = vec![Default::default(); body.header.elements.len()];
    body.next_offset = body.header.body;
    let mut positions = Positions::empty();
    let mut colours = None;
    let mut spilled = 0;
    let mut grid = None;
    // Walk up to the last element needed before streaming.
    let last_needed = body.roles.iter().rposition(|r| matches!(r, Role::Vertex { .. } | Role::RangeGrid { .. }));
    if let Some(last) = last_needed {
        for e in 0..=last {
            let start = body.next_offset;
            let end = match body.roles[e] {
                Role::Vertex { xyz, rgb, alpha } => {
                    let (p, c, end, s) = body.read_vertices(e, xyz, rgb.map(|c| (c, alpha)), start, spill_dir)?;
                    positions = p;
                    colours = c;
                    spilled = s;
                    end
                }
                Role::RangeGrid { list } => {
                    let (g, end) = body.read_range_grid(e, list, start, positions.count())?;
                    grid = Some(g);
                    end
                }
                Role::Faces { .. } => {
                    body.pending.push_back((e, start));
                    body.skip_element(e, start)?
                }
                Role::Other => body.skip_element(e, start)?,
            };
            body.next_offset = end;
        }
        body.next_elem = last + 1;
    }
    // Per-face colour, when the vertices have none: one pass over the
    // first face element (pending, or next) spills a colour per triangle.
    // Else textures (MeshLab's `comment TextureFile NAME` and face
    // `texcoord` lists), by the same kind of pass.
    let mut face_colours = None;
    let mut texturing = None;
    if colours.is_none() {
        let first_faces = body.roles.iter().position(|r| matches!(r, Role::Faces { .. }));
        if let Some(e) = first_faces {
            let start = body.pending.iter().find(|p| p.0 == e).map(|p| p.1).or((e == body.next_elem).then_some(body.next_offset));
            match (body.roles[e], start) {
                (Role::Faces { list, rgb: Some(rgb), alpha, .. }, Some(start)) => face_colours = Some(body.read_face_colours(e, list, rgb, alpha, start, spill_dir)?),
                (Role::Faces { list, texcoord: Some(tc), texnumber, .. }, Some(start)) => texturing = body.read_texcoords(e, list, tc, texnumber, start, spill_dir)?,
                _ => {}
            }
        }
    }
    // Madvise: positions are fetched at random, faces read front to back.
    let (pstart, plen) = positions.byte_range();
    if !std::ptr::eq(positions.mapped(), &*map) {
        // Positions live in a spill file; the input is read sequentially.
        map.advise_sequential(body.header.body, map.bytes().len());
    } else if plen > 0 {
        map.advise_willneed(pstart, plen.min(1 << 30));
        map.advise_sequential(pstart + plen, map.bytes().len());
    }
    body.bytes_done = body.next_offset as u64;
    // A file without faces is checked to the end right away.
    if body.pending.is_empty() && !body.roles[body.next_elem..].iter().any(|r| matches!(r, Role::Faces { .. })) {
        body.walk_to_end()?;
    }
    Ok(Opened { info, positions, body: Box::new(body), range_grid: grid, spilled_vertices: spilled, colours, face_colours, texturing })
}

/// Checks that property `i` of `el` may hold a colour channel.
fn colour_type(el: &crate::ply::header::Element, i: usize, name: &str) -> Result<(), String> {
    match el.props[i].ty {
        PropType::Scalar(t) if crate::colours::colour_scalar(t) => Ok(()),
        PropType::Scalar(_) => Err(format!("colour property '{name}' of an odd type (mint reads uchar, ushort, float and double colours)")),
        PropType::List { .. } => Err(format!("colour property '{name}' is a list, expected a number")),
    }
}

/// Classifies the elements and checks that the ones mint reads have the
/// properties it needs.
fn roles(h: &PlyHeader, path: &Path) -> Result<Vec<Role>, Error> {
    let mut roles = Vec::with_capacity(h.elements.len());
    let mut have_vertex = false;
    for el in &h.elements {
        let err = |kind, msg: String| Error::new(kind, path, msg).at_element(&el.name);
        let role = match el.name.as_str() {
            "vertex" if !have_vertex => {
                have_vertex = true;
                if el.count > u32::MAX as u64 {
                    return Err(err(
                        ErrorKind::Unsupported,
                        format!("{} vertices; mint reads at most {} (32-bit indices)", el.count, u32::MAX),
                    ));
                }
                let mut xyz = [0; 3];
                for (k, name) in ["x", "y", "z"].iter().enumerate() {
                    match el.prop(name) {
                        Some(i) if matches!(el.props[i].ty, PropType::Scalar(_)) => xyz[k] = i,
                        Some(_) => return Err(err(ErrorKind::Format, format!("property '{name}' is a list, expected a number"))),
                        None if el.count == 0 => {}
                        None => return Err(err(ErrorKind::Format, format!("the vertex element has no property '{name}'"))),
                    }
                }
                let (rgb, alpha) = colour_props(el).map_err(|m| err(ErrorKind::Unsupported, m))?;
                Role::Vertex { xyz, rgb, alpha }
            }
            "vertex" => return Err(err(ErrorKind::Unsupported, "more than one 'vertex' element".into())),
            "face" | "tristrips" | "range_grid" => {
                let list = index_list(el).ok_or_else(|| {
                    err(ErrorKind::Unsupported, "no 'vertex_indices' list property (or more than one unnamed list)".into())
                })?;
                let PropType::List { item, .. } = el.props[list].ty else { unreachable!() };
                if item.is_float() {
                    return Err(err(ErrorKind::Unsupported, "vertex indices of a floating-point type".into()));
                }
                match el.name.as_str() {
                    "range_grid" => Role::RangeGrid { list },
                    "face" => {
                        let (rgb, alpha) = colour_props(el).map_err(|m| err(ErrorKind::Unsupported, m))?;
                        // MeshLab's per-corner texture coordinates.
                        let texcoord = el.props.iter().position(|p| p.name == "texcoord" && matches!(p.ty, PropType::List { .. }));
                        let texnumber = el.props.iter().position(|p| p.name == "texnumber" && matches!(p.ty, PropType::Scalar(_)));
                        Role::Faces { list, strip: false, rgb, alpha, texcoord, texnumber }
                    }
                    _ => Role::Faces { list, strip: true, rgb: None, alpha: None, texcoord: None, texnumber: None },
                }
            }
            _ => Role::Other,
        };
        roles.push(role);
    }
    Ok(roles)
}

/// The colour properties of an element: `red green blue [alpha]` (MeshLab,
/// Open3D), or `diffuse_red …` (older scanners' exports); all three or no
/// colour (a lone 'red' is some other property, skipped).
#[allow(clippy::type_complexity)]
fn colour_props(el: &Element) -> Result<(Option<[usize; 3]>, Option<usize>), String> {
    for prefix in ["", "diffuse_"] {
        let idx = ["red", "green", "blue"].map(|c| el.prop(&format!("{prefix}{c}")));
        let [Some(r), Some(g), Some(b)] = idx else { continue };
        let found = [r, g, b];
        for (k, &i) in found.iter().enumerate() {
            colour_type(el, i, &format!("{prefix}{}", ["red", "green", "blue"][k]))?;
        }
        let mut alpha = None;
        if let Some(a) = el.prop(&format!("{prefix}alpha")) {
            colour_type(el, a, &format!("{prefix}alpha"))?;
            alpha = Some(a);
        }
        return Ok((Some(found), alpha));
    }
    Ok((None, None))
}

/// The list property holding vertex indices: `vertex_indices`,
/// `vertex_index`, or the only list of the element.
fn index_list(el: &Element) -> Option<usize> {
    let is_list = |p: &Property| matches!(p.ty, PropType::List { .. });
    for name in ["vertex_indices", "vertex_index"] {
        if let Some(i) = el.props.iter().position(|p| p.name == name && is_list(p)) {
            return Some(i);
        }
    }
    let mut lists = el.props.iter().enumerate().filter(|(_, p)| is_list(p));
    match (lists.next(), lists.next()) {
        (Some((i, _)), None) => Some(i),
        _ => None,
    }
}

// ---------------------------------------------------------------------------
// Record sources

/// Why a value could not be read.
#[derive(Debug, Clone, Copy)]
enum SrcErr {
    /// The data ended.
    Eof,
    /// The token at this offset is not a number.
    NotNumber(usize),
    /// A list length that is negative, at this offset.
    BadLen(i64, usize),
}

/// A cursor over the values of a PLY body.
trait Src {
    /// Current offset (for binary: of the next value; for ascii: just past
    /// the last token).
    fn pos(&self) -> usize;
    /// Offset where the next record starts (ascii: skips whitespace).
    fn mark(&mut self) -> usize;
    fn int(&mut self, ty: Scalar) -> Result<i64, SrcErr>;
    fn float(&mut self, ty: Scalar) -> Result<f64, SrcErr>;
    fn skip_n(&mut self, ty: Scalar, n: u64) -> Result<(), SrcErr>;

    /// Ends a record whose declared values have all been read. Ascii: a
    /// record is a line (as the format says, and as trimesh and numpy read
    /// it), so values left on the line are skipped; returns the offset of
    /// the first one. Binary: nothing to do.
    #[inline]
    fn end_record(&mut self) -> Option<usize> {
        None
    }

    /// Reads a list length.
    #[inline]
    fn list_len(&mut self, ty: Scalar) -> Result<u64, SrcErr> {
        let at = self.mark();
        let n = self.int(ty)?;
        if n < 0 {
            return Err(SrcErr::BadLen(n, at));
        }
        Ok(n as u64)
    }

    /// Skips a list; returns its length.
    #[inline]
    fn skip_list(&mut self, count: Scalar, item: Scalar) -> Result<u64, SrcErr> {
        let n = self.list_len(count)?;
        self.skip_n(item, n)?;
        Ok(n)
    }

    /// Skips the given properties of one record.
    #[inline]
    fn skip_props(&mut self, props: &[Property]) -> Result<(), SrcErr> {
        for p in props {
            match p.ty {
                PropType::Scalar(t) => self.skip_n(t, 1)?,
                PropType::List { count, item } => {
                    let n = self.list_len(count)?;
                    self.skip_n(item, n)?;
                }
            }
        }
        Ok(())
    }
}

/// Binary values; `BE` selects big-endian.
struct Bin<'a, const BE: bool> {
    d: &'a [u8],
    pos: usize,
}

impl<const BE: bool> Src for Bin<'_, BE> {
    #[inline]
    fn pos(&self) -> usize {
        self.pos
    }
    #[inline]
    fn mark(&mut self) -> usize {
        self.pos
    }
    #[inline]
    fn int(&mut self, ty: Scalar) -> Result<i64, SrcErr> {
        let s = ty.size();
        if self.d.len() - self.pos < s {
            return Err(SrcErr::Eof);
        }
        let v = ty.read_i64(&self.d[self.pos..], BE);
        self.pos += s;
        Ok(v)
    }
    #[inline]
    fn float(&mut self, ty: Scalar) -> Result<f64, SrcErr> {
        let s = ty.size();
        if self.d.len() - self.pos < s {
            return Err(SrcErr::Eof);
        }
        let v = ty.read_f64(&self.d[self.pos..], BE);
        self.pos += s;
        Ok(v)
    }
    #[inline]
    fn skip_n(&mut self, ty: Scalar, n: u64) -> Result<(), SrcErr> {
        let left = (self.d.len() - self.pos) as u64;
        match (ty.size() as u64).checked_mul(n) {
            Some(b) if b <= left => {
                self.pos += b as usize;
                Ok(())
            }
            _ => Err(SrcErr::Eof),
        }
    }
}

/// Ascii values: whitespace-separated tokens.
struct Ascii<'a> {
    t: Tokens<'a>,
}

impl Src for Ascii<'_> {
    #[inline]
    fn pos(&self) -> usize {
        self.t.pos
    }
    #[inline]
    fn mark(&mut self) -> usize {
        self.t.skip_space()
    }
    #[inline]
    fn int(&mut self, _ty: Scalar) -> Result<i64, SrcErr> {
        let (at, tok) = self.t.next_tok().ok_or(SrcErr::Eof)?;
        parse_int(tok).ok_or(SrcErr::NotNumber(at))
    }
    /// The decimal is rounded to the declared type, so that ascii and
    /// binary encodings of one file give the same values.
    #[inline]
    fn float(&mut self, ty: Scalar) -> Result<f64, SrcErr> {
        let (at, tok) = self.t.next_tok().ok_or(SrcErr::Eof)?;
        let v = parse_f64(tok).ok_or(SrcErr::NotNumber(at))?;
        Ok(if ty == Scalar::F32 { v as f32 as f64 } else { v })
    }
    #[inline]
    fn skip_n(&mut self, _ty: Scalar, n: u64) -> Result<(), SrcErr> {
        for _ in 0..n {
            self.t.next_tok().ok_or(SrcErr::Eof)?;
        }
        Ok(())
    }
    /// A line ends at `\n` or `\r` (CRLF and old Mac files alike).
    #[inline]
    fn end_record(&mut self) -> Option<usize> {
        let d = self.t.data;
        let mut i = self.t.pos;
        while i < d.len() && matches!(d[i], b' ' | b'\t' | 0x0b | 0x0c) {
            i += 1;
        }
        self.t.pos = i;
        if i >= d.len() || matches!(d[i], b'\n' | b'\r') {
            return None;
        }
        let first = i;
        while i < d.len() && !matches!(d[i], b'\n' | b'\r') {
            i += 1;
        }
        self.t.pos = i;
        Some(first)
    }
}

/// Records whose line held values beyond the declared ones (ascii), per
/// element: the first such value's offset and how many lines.
#[derive(Debug, Clone, Copy, Default)]
struct Extra {
    first: Option<usize>,
    lines: u64,
}

impl Extra {
    #[inline]
    fn note(&mut self, at: Option<usize>) {
        if let Some(at) = at {
            self.first.get_or_insert(at);
            self.lines += 1;
        }
    }
    /// The same element read twice (skipped, then streamed) counts once.
    fn merge(self, o: Extra) -> Extra {
        Extra {
            first: match (self.first, o.first) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            },
            lines: self.lines.max(o.lines),
        }
    }
}

/// Runs `$body` with `$s` bound to a [`Src`] of the right encoding over
/// `$data` starting at `$pos`.
macro_rules! with_src {
    ($enc:expr, $data:expr, $pos:expr, |$s:ident| $body:expr) => {
        match $enc {
            Encoding::Ascii => {
                let mut $s = Ascii { t: Tokens::new($data, $pos) };
                $body
            }
            Encoding::BinaryLe => {
                let mut $s = Bin::<false> { d: $data, pos: $pos };
                $body
            }
            Encoding::BinaryBe => {
                let mut $s = Bin::<true> { d: $data, pos: $pos };
                $body
            }
        }
    };
}

/// Error context: the file, its bytes and the element being read.
struct Ctx<'a> {
    path: &'a Path,
    data: &'a [u8],
    ascii: bool,
    elem: &'a str,
    count: u64,
}

impl Ctx<'_> {
    fn at(&self, e: Error, record: u64, byte: usize) -> Error {
        let e = e.at_element(self.elem).at_record(record);
        let e = if self.ascii { e.at_line(line_of(self.data, byte)) } else { e };
        e.at_byte(byte as u64)
    }

    #[cold]
    fn src(&self, e: SrcErr, record: u64, rec_start: usize) -> Error {
        match e {
            SrcErr::Eof => self.at(
                Error::format(
                    self.path,
                    format!(
                        "unexpected end of file inside this record ({} records declared; truncated file, or the header counts are too large)",
                        self.count
                    ),
                ),
                record,
                rec_start,
            ),
            SrcErr::NotNumber(at) => {
                let tok = Tokens::new(self.data, at).next_tok().map(|t| t.1).unwrap_or(b"");
                self.at(Error::format(self.path, format!("expected a number, found {}", show_token(tok))), record, at)
            }
            SrcErr::BadLen(n, at) => self.at(Error::format(self.path, format!("negative list length {n}")), record, at),
        }
    }

    #[cold]
    fn reject(&self, r: Reject, pos: &Positions, record: u64, rec_start: usize) -> Error {
        let e = match r {
            Reject::Index(v) => Error::new(
                ErrorKind::Index,
                self.path,
                format!("vertex index {v} is out of range (the file has {} vertices)", pos.count()),
            ),
            Reject::NotFinite(v) => not_finite(self.path, v, pos),
        };
        self.at(e, record, rec_start)
    }
}

// ---------------------------------------------------------------------------
// Streaming

/// Where streaming of one face element stands.
#[derive(Debug, Clone)]
struct Cursor {
    elem: usize,
    list: usize,
    strip: bool,
    count: u64,
    record: u64,
    pos: usize,
    rec_start: usize,
    /// Set while paused inside the index list of `record`.
    ls: Option<ListState>,
    /// True if the element was reached by the walk (its end continues it).
    walked: bool,
    /// Reading a range of records (`MeshReader::open_range`): every record
    /// must be a triangle, so that records have one size.
    tri_only: bool,
    /// Lines with values beyond the declared ones, so far.
    extra: Extra,
}

/// Progress through one index list.
#[derive(Debug, Clone, Copy)]
struct ListState {
    left: u64,
    len: u64,
    seen: u64,
    a: i64,
    b: i64,
    odd: bool,
}

/// Streams the triangles of a PLY body (see the module docs).
pub(crate) struct PlyBody {
    path: PathBuf,
    map: Arc<Mapped>,
    header: PlyHeader,
    roles: Vec<Role>,
    /// Face elements located before streaming: (element, start offset).
    pending: VecDeque<(usize, usize)>,
    /// The walk: next element and its start offset.
    next_elem: usize,
    next_offset: usize,
    cur: Option<Cursor>,
    finished: bool,
    bytes_done: u64,
    /// Only a range of one face element's records is read (see `restrict`).
    range_only: bool,
    /// Bytes after the last element, ignored.
    trailing: u64,
    /// Per element: lines with undeclared values, skipped (ascii).
    extra: Vec<std::cell::Cell<Extra>>,
}

impl PlyBody {
    fn note_extra(&self, e: usize, x: Extra) {
        let c = &self.extra[e];
        c.set(c.get().merge(x));
    }

    fn ctx<'a>(&'a self, data: &'a [u8], e: usize) -> Ctx<'a> {
        let el = &self.header.elements[e];
        Ctx { path: &self.path, data, ascii: self.header.encoding == Encoding::Ascii, elem: &el.name, count: el.count }
    }

    /// Skips element `e` starting at `start`; returns its end offset.
    fn skip_element(&self, e: usize, start: usize) -> Result<usize, Error> {
        let data = self.map.bytes();
        let el = &self.header.elements[e];
        let ctx = self.ctx(data, e);
        if self.header.encoding != Encoding::Ascii {
            if let Some(size) = el.fixed_size() {
                return fixed_end(&ctx, start, size, el.count);
            }
        }
        let mut extra = Extra::default();
        let end = with_src!(self.header.encoding, data, start, |s| {
            for r in 0..el.count {
                let at = s.mark();
                s.skip_props(&el.props).map_err(|err| ctx.src(err, r, at))?;
                extra.note(s.end_record());
            }
            s.pos()
        });
        self.note_extra(e, extra);
        Ok(end)
    }

    /// Makes the vertex element `e` index-addressable: in place for binary
    /// fixed-size records, else spilled. Returns (positions, end offset,
    /// spilled vertex count).
    #[allow(clippy::type_complexity)]
    fn read_vertices(&self, e: usize, xyz: [usize; 3], rgba: Option<([usize; 3], Option<usize>)>, start: usize, spill_dir: &Path) -> Result<(Positions, Option<VertexColours>, usize, u64), Error> {
        let data = self.map.bytes();
        let el = &self.header.elements[e];
        let ctx = self.ctx(data, e);
        let count = el.count as u32;
        if count == 0 {
            return Ok((Positions::empty(), None, start, 0));
        }
        let offset_of = |i: usize| -> usize { el.props[..i].iter().map(|p| if let PropType::Scalar(s) = p.ty { s.size() } else { 0 }).sum() };
        let scalar_of = |i: usize| -> Scalar {
            let PropType::Scalar(t) = el.props[i].ty else { unreachable!("checked by roles") };
            t
        };
        if self.header.encoding != Encoding::Ascii {
            if let Some(size) = el.fixed_size() {
                let end = fixed_end(&ctx, start, size, el.count)?;
                let mut off = [0; 3];
                let mut ty = [Scalar::F32; 3];
                for k in 0..3 {
                    off[k] = el.props[..xyz[k]].iter().map(|p| match p.ty {
                        PropType::Scalar(s) => s.size(),
                        PropType::List { .. } => unreachable!(),
                    }).sum();
                    let PropType::Scalar(t) = el.props[xyz[k]].ty else { unreachable!() };
                    ty[k] = t;
                }
                let be = self.header.encoding == Encoding::BinaryBe;
                let layout = Layout { base: start, stride: size, group: 1, inner: 0, off, ty, be };
                let colours = rgba.map(|(rgb, alpha)| {
                    let a = alpha.unwrap_or(rgb[0]);
                    let chans = [rgb[0], rgb[1], rgb[2], a];
                    VertexColours::new(self.map.clone(), count, start, size, chans.map(offset_of), chans.map(scalar_of), alpha.is_some(), be)
                });
                return Ok((Positions::new(self.map.clone(), count, layout), colours, end, 0));
            }
        }
        // Spill: parse every record once into f64 triples (and RGBA bytes).
        let mut extra = Extra::default();
        let mut spill = SpillFile::new(spill_dir, &self.path)?;
        let mut cspill = match rgba {
            Some(_) => Some(SpillFile::new(spill_dir, &self.path)?),
            None => None,
        };
        // Role of each property: 1..=3 a coordinate, 4..=7 a colour channel.
        let role: Vec<u8> = (0..el.props.len())
            .map(|i| match xyz.iter().position(|&k| k == i) {
                Some(k) => k as u8 + 1,
                None => rgba.and_then(|(rgb, a)| [Some(rgb[0]), Some(rgb[1]), Some(rgb[2]), a].iter().position(|&k| k == Some(i))).map_or(0, |k| k as u8 + 4),
            })
            .collect();
        let end = with_src!(self.header.encoding, data, start, |s| {
            for r in 0..el.count {
                let at = s.mark();
                let mut p = [0.0f64; 3];
                let mut c = [255u8; 4];
                for (prop, &role) in el.props.iter().zip(&role) {
                    let res = match prop.ty {
                        PropType::Scalar(t) if (1..=3).contains(&role) => s.float(t).map(|v| p[role as usize - 1] = v),
                        PropType::Scalar(t) if role >= 4 => s.float(t).map(|v| {
                            c[role as usize - 4] = match t {
                                Scalar::U8 => v as u8,
                                Scalar::U16 => ((v as u64) >> 8) as u8,
                                _ => crate::colours::unit_to_u8(v),
                            }
                        }),
                        PropType::Scalar(t) => s.skip_n(t, 1),
                        PropType::List { count, item } => s.list_len(count).and_then(|n| s.skip_n(item, n)),
                    };
                    res.map_err(|err| ctx.src(err, r, at))?;
                }
                extra.note(s.end_record());
                spill.write_point(p)?;
                if let Some(cs) = cspill.as_mut() {
                    cs.write_bytes(&c)?;
                }
            }
            s.pos()
        });
        self.note_extra(e, extra);
        let map = Arc::new(spill.into_mapped()?);
        let colours = match cspill {
            Some(cs) => Some(VertexColours::spilled(Arc::new(cs.into_mapped()?), count)),
            None => None,
        };
        Ok((Positions::spilled(map, count), colours, end, el.count))
    }

    /// One pass over face element `e` (from `start`): the colour of each
    /// record, written once per triangle it gives (n − 2 for n corners).
    fn read_face_colours(&self, e: usize, list: usize, rgb: [usize; 3], alpha: Option<usize>, start: usize, spill_dir: &Path) -> Result<FaceColours, Error> {
        let data = self.map.bytes();
        let el = &self.header.elements[e];
        let ctx = self.ctx(data, e);
        let mut spill = SpillFile::new(spill_dir, &self.path)?;
        let chans = [Some(rgb[0]), Some(rgb[1]), Some(rgb[2]), alpha];
        with_src!(self.header.encoding, data, start, |s| {
            for r in 0..el.count {
                let at = s.mark();
                let mut c = [255u8; 4];
                let mut corners = 0u64;
                for (i, prop) in el.props.iter().enumerate() {
                    let res = match prop.ty {
                        PropType::Scalar(t) => match chans.iter().position(|&k| k == Some(i)) {
                            Some(k) => s.float(t).map(|v| {
                                c[k] = match t {
                                    Scalar::U8 => v as u8,
                                    Scalar::U16 => ((v as u64) >> 8) as u8,
                                    _ => crate::colours::unit_to_u8(v),
                                }
                            }),
                            None => s.skip_n(t, 1),
                        },
                        PropType::List { count, item } => s.skip_list(count, item).map(|n| {
                            if i == list {
                                corners = n;
                            }
                        }),
                    };
                    res.map_err(|err| ctx.src(err, r, at))?;
                }
                s.end_record();
                for _ in 0..corners.saturating_sub(2) {
                    spill.write_bytes(&c)?;
                }
            }
        });
        Ok(FaceColours::spilled(Arc::new(spill.into_mapped()?)))
    }

    /// One pass over face element `e` (from `start`) for MeshLab's texture
    /// convention: per face a `texcoord` list of (u, v) per corner and
    /// optionally a `texnumber` (which `comment TextureFile NAME` of the
    /// header, in order; 0 without). Triangles are fanned as the faces are;
    /// a face whose list is not two numbers per corner has none. `None`
    /// when the header names no texture file.
    #[allow(clippy::too_many_arguments)]
    fn read_texcoords(&self, e: usize, list: usize, tc: usize, texnumber: Option<usize>, start: usize, spill_dir: &Path) -> Result<Option<Texturing>, Error> {
        let files: Vec<String> = self.header.comments.iter().filter_map(|c| c.strip_prefix("TextureFile").map(|f| f.trim().to_string())).filter(|f| !f.is_empty()).collect();
        if files.is_empty() {
            return Ok(None);
        }
        let data = self.map.bytes();
        let el = &self.header.elements[e];
        let ctx = self.ctx(data, e);
        let mut b = TexturingBuilder::new(spill_dir, &self.path)?;
        let mut uv: Vec<f32> = Vec::new();
        with_src!(self.header.encoding, data, start, |s| {
            for r in 0..el.count {
                let at = s.mark();
                let mut corners = 0u64;
                let mut tex = 0u32;
                uv.clear();
                for (i, prop) in el.props.iter().enumerate() {
                    let res = match prop.ty {
                        PropType::Scalar(t) if Some(i) == texnumber => s.float(t).map(|v| tex = if v >= 0.0 && v < NONE as f64 { v as u32 } else { NONE }),
                        PropType::Scalar(t) => s.skip_n(t, 1),
                        PropType::List { count, item } if i == tc => s.list_len(count).and_then(|n| {
                            for _ in 0..n {
                                let v = s.float(item)?;
                                if uv.len() < 1 << 16 {
                                    uv.push(v as f32);
                                }
                            }
                            Ok(())
                        }),
                        PropType::List { count, item } => s.skip_list(count, item).map(|n| {
                            if i == list {
                                corners = n;
                            }
                        }),
                    };
                    res.map_err(|err| ctx.src(err, r, at))?;
                }
                s.end_record();
                let ids: Vec<u32> = if uv.len() as u64 == 2 * corners {
                    let mut ids = Vec::with_capacity(corners as usize);
                    for k in 0..corners as usize {
                        ids.push(b.uv([uv[2 * k], uv[2 * k + 1]])?);
                    }
                    ids
                } else {
                    vec![NONE; corners as usize]
                };
                for k in 1..ids.len().saturating_sub(1) {
                    b.triangle(tex, [ids[0], ids[k], ids[k + 1]])?;
                }
            }
        });
        let dir = self.path.parent().unwrap_or(Path::new("."));
        let mut warnings = Vec::new();
        let mut materials = Vec::new();
        let mut textures = Vec::new();
        for f in &files {
            let file = dir.join(f.replace('\\', "/"));
            let mut m = Material::white(f);
            if file.is_file() {
                let source = ImageSource::file(file);
                let (width, height) = crate::textures::image_size(&source, &self.path)?;
                textures.push(TextureInfo { source, width, height });
                m.texture = Some(textures.len() - 1);
            } else {
                warnings.push(format!("{}: texture '{}' not found: its faces are white", self.path.display(), file.display()));
            }
            materials.push(m);
        }
        Ok(Some(b.finish(materials, textures, warnings)?))
    }

    /// Parses a `range_grid` element; `nv` is the vertex count.
    fn read_range_grid(&self, e: usize, list: usize, start: usize, nv: u32) -> Result<(RangeGrid, usize), Error> {
        let data = self.map.bytes();
        let el = &self.header.elements[e];
        let ctx = self.ctx(data, e);
        let (cols, rows) = (self.header.obj_info_u64("num_cols"), self.header.obj_info_u64("num_rows"));
        let (cols, rows) = match (cols, rows) {
            (Some(c), Some(r)) if c.checked_mul(r) == Some(el.count) && c <= u32::MAX as u64 && r <= u32::MAX as u64 => {
                (c as u32, r as u32)
            }
            _ => {
                return Err(Error::format(
                    &self.path,
                    format!(
                        "a range_grid of {} cells needs 'obj_info num_cols N' and 'obj_info num_rows M' with N*M = {} (found {:?} x {:?})",
                        el.count, el.count, cols, rows
                    ),
                )
                .at_element(&el.name))
            }
        };
        let PropType::List { count: cty, item: ity } = el.props[list].ty else { unreachable!() };
        let mut cells = Vec::with_capacity((el.count as usize).min(data.len()));
        let mut extra = Extra::default();
        let end = with_src!(self.header.encoding, data, start, |s| {
            for r in 0..el.count {
                let at = s.mark();
                s.skip_props(&el.props[..list]).map_err(|err| ctx.src(err, r, at))?;
                let n = s.list_len(cty).map_err(|err| ctx.src(err, r, at))?;
                let cell = match n {
                    0 => None,
                    1 => {
                        let v = s.int(ity).map_err(|err| ctx.src(err, r, at))?;
                        if v < 0 || v >= nv as i64 {
                            return Err(ctx.at(
                                Error::new(ErrorKind::Index, &self.path, format!("vertex index {v} is out of range (the file has {nv} vertices)")),
                                r,
                                at,
                            ));
                        }
                        Some(v as u32)
                    }
                    n => {
                        return Err(ctx.at(
                            Error::format(&self.path, format!("a range_grid cell lists {n} vertices (expected 0 or 1)")),
                            r,
                            at,
                        ))
                    }
                };
                cells.push(cell);
                s.skip_props(&el.props[list + 1..]).map_err(|err| ctx.src(err, r, at))?;
                extra.note(s.end_record());
            }
            s.pos()
        });
        self.note_extra(e, extra);
        Ok((RangeGrid { cols, rows, cells }, end))
    }

    /// Continues the walk past non-face elements to the end of the body and
    /// checks that nothing follows the last element.
    fn walk_to_end(&mut self) -> Result<(), Error> {
        while self.next_elem < self.header.elements.len() {
            self.next_offset = self.skip_element(self.next_elem, self.next_offset)?;
            self.next_elem += 1;
        }
        self.finished = true;
        self.bytes_done = self.map.bytes().len() as u64;
        self.trailing = self.trailing_bytes(self.next_offset);
        Ok(())
    }

    /// Bytes after `end` that are data (for ascii: from the first token
    /// on), which readers ignore as MeshLab and trimesh do; the reader
    /// reports them as a warning.
    fn trailing_bytes(&self, end: usize) -> u64 {
        let data = self.map.bytes();
        if self.header.encoding == Encoding::Ascii {
            let mut t = Tokens::new(data, end);
            t.next_tok().map_or(0, |(at, _)| (data.len() - at) as u64)
        } else {
            data.len().saturating_sub(end) as u64
        }
    }

    /// Picks the next face element to stream, or finishes the walk.
    fn start_next(&mut self) -> Result<(), Error> {
        let (elem, start, walked) = if let Some((e, start)) = self.pending.pop_front() {
            (e, start, false)
        } else {
            loop {
                if self.next_elem >= self.header.elements.len() {
                    return self.walk_to_end();
                }
                let e = self.next_elem;
                if let Role::Faces { .. } = self.roles[e] {
                    break (e, self.next_offset, true);
                }
                self.next_offset = self.skip_element(e, self.next_offset)?;
                self.next_elem += 1;
            }
        };
        let Role::Faces { list, strip, .. } = self.roles[elem] else { unreachable!() };
        let count = self.header.elements[elem].count;
        self.cur = Some(Cursor { elem, list, strip, count, record: 0, pos: start, rec_start: start, ls: None, walked, tri_only: false, extra: Extra::default() });
        Ok(())
    }

    /// Streams from the current face element until `out` is full or the
    /// element ends; returns true when it ended.
    fn stream(&mut self, out: &mut Emit, stats: &mut ReadStats) -> Result<bool, Error> {
        let map = self.map.clone();
        let data = map.bytes();
        let mut cur = self.cur.take().expect("a current face element");
        let el = &self.header.elements[cur.elem];
        let ctx = self.ctx(data, cur.elem);
        let PropType::List { count: cty, item: ity } = el.props[cur.list].ty else { unreachable!() };
        let fast = self.header.encoding == Encoding::BinaryLe
            && !cur.strip
            && el.props.len() == 1
            && cty == Scalar::U8
            && (ity == Scalar::U32 || (ity == Scalar::I32 && out.pos.count() <= i32::MAX as u32));
        let done = if fast {
            loop {
                if cur.ls.is_none() {
                    fast_le_triangles(data, &mut cur, out).map_err(|(r, rec, at)| ctx.reject(r, out.pos, rec, at))?;
                }
                if cur.record >= cur.count || !out.room() {
                    break cur.record >= cur.count && cur.ls.is_none();
                }
                // A record the fast loop declined: handle it generically.
                let mut s = Bin::<false> { d: data, pos: cur.pos };
                let ended = stream_records(&mut s, &mut cur, el, cty, ity, &ctx, out, stats, 1)?;
                if ended {
                    break true;
                }
            }
        } else {
            with_src!(self.header.encoding, data, cur.pos, |s| stream_records(&mut s, &mut cur, el, cty, ity, &ctx, out, stats, u64::MAX)?)
        };
        self.bytes_done = cur.pos as u64;
        if done {
            self.note_extra(cur.elem, cur.extra);
            if cur.walked {
                self.next_offset = cur.pos;
                self.next_elem = cur.elem + 1;
            }
        } else {
            self.cur = Some(cur);
        }
        Ok(done)
    }
}

/// The end of `count` fixed-size records from `start`, or a truncation
/// error naming the first incomplete record.
fn fixed_end(ctx: &Ctx, start: usize, size: usize, count: u64) -> Result<usize, Error> {
    let left = (ctx.data.len() - start) as u64;
    match (size as u64).checked_mul(count) {
        Some(n) if n <= left => Ok(start + n as usize),
        _ => {
            let complete = if size == 0 { 0 } else { left / size as u64 };
            Err(ctx.at(
                Error::format(
                    ctx.path,
                    format!(
                        "unexpected end of file: {count} records of {size} bytes declared, the file holds only {complete} (truncated file, or the header counts are too large)"
                    ),
                ),
                complete,
                start + (complete * size as u64) as usize,
            ))
        }
    }
}

/// The triangle fast path: binary little-endian records that are exactly
/// `uchar 3` followed by three 32-bit indices below the vertex count. Stops
/// at the first record that is anything else (the generic walker handles
/// it, including any error), when the chunk is full, or at the end.
#[inline]
fn fast_le_triangles(data: &[u8], cur: &mut Cursor, out: &mut Emit) -> Result<(), (Reject, u64, usize)> {
    let n = (cur.count - cur.record).min((out.max - out.len()) as u64) as usize;
    let nv = out.pos.count();
    let resolve = out.resolve;
    let pos = out.pos;
    match (resolve, pos.kind()) {
        (false, _) => fast_loop(data, cur, n, nv, out, |_| [0.0; 3], false),
        (true, PosKind::F32Le) => fast_loop(data, cur, n, nv, out, |i| pos.get_f32le(i), true),
        (true, PosKind::F64Le) => fast_loop(data, cur, n, nv, out, |i| pos.get_f64le(i), true),
        (true, PosKind::Other) => fast_loop(data, cur, n, nv, out, |i| pos.get_other(i), true),
    }
}

#[inline(always)]
fn fast_loop<F: Fn(u32) -> [f64; 3]>(
    data: &[u8],
    cur: &mut Cursor,
    n: usize,
    nv: u32,
    out: &mut Emit,
    fetch: F,
    resolve: bool,
) -> Result<(), (Reject, u64, usize)> {
    let mut pos = cur.pos;
    let mut k = 0;
    // Records that fit entirely: no per-record length check needed below.
    let fit = (data.len().saturating_sub(pos) / 13).min(n);
    while k < fit {
        let r: &[u8; 13] = data[pos..pos + 13].try_into().unwrap();
        if r[0] != 3 {
            break;
        }
        let a = u32::from_le_bytes([r[1], r[2], r[3], r[4]]);
        let b = u32::from_le_bytes([r[5], r[6], r[7], r[8]]);
        let c = u32::from_le_bytes([r[9], r[10], r[11], r[12]]);
        if a >= nv || b >= nv || c >= nv {
            break;
        }
        out.indices.push([a, b, c]);
        if resolve {
            let p = [fetch(a), fetch(b), fetch(c)];
            if let Err(rej) = check_finite(&p, &[a, b, c]) {
                out.indices.pop();
                let rec = cur.record + k as u64;
                cur.pos = pos;
                cur.record = rec;
                return Err((rej, rec, pos));
            }
            out.positions.push(p);
        }
        pos += 13;
        k += 1;
    }
    cur.pos = pos;
    cur.record += k as u64;
    cur.rec_start = pos;
    Ok(())
}

/// The generic record walker for face elements: streams until `out` is
/// full, the element ends, or `budget` records have been completed.
/// Returns true when the element ended.
#[allow(clippy::too_many_arguments)]
#[inline]
fn stream_records<S: Src>(
    s: &mut S,
    cur: &mut Cursor,
    el: &Element,
    cty: Scalar,
    ity: Scalar,
    ctx: &Ctx,
    out: &mut Emit,
    stats: &mut ReadStats,
    budget: u64,
) -> Result<bool, Error> {
    let nv = out.pos.count() as i64;
    let mut completed = 0u64;
    loop {
        if let Some(mut ls) = cur.ls.take() {
            while ls.left > 0 {
                if !out.room() {
                    cur.ls = Some(ls);
                    cur.pos = s.pos();
                    return Ok(false);
                }
                let v = s.int(ity).map_err(|e| ctx.src(e, cur.record, cur.rec_start))?;
                ls.left -= 1;
                if cur.strip && v == -1 {
                    ls.seen = 0;
                    ls.odd = false;
                    continue;
                }
                if v < 0 || v >= nv {
                    return Err(ctx.reject(Reject::Index(v), out.pos, cur.record, cur.rec_start));
                }
                match ls.seen {
                    0 => ls.a = v,
                    1 => ls.b = v,
                    _ if cur.strip => {
                        let (p, q) = if ls.odd { (ls.b, ls.a) } else { (ls.a, ls.b) };
                        if p == q || p == v || q == v {
                            stats.degenerate_strip_triangles += 1;
                        } else {
                            out.tri_checked([p as u32, q as u32, v as u32])
                                .map_err(|r| ctx.reject(r, out.pos, cur.record, cur.rec_start))?;
                        }
                        ls.a = ls.b;
                        ls.b = v;
                        ls.odd = !ls.odd;
                    }
                    _ => {
                        out.tri_checked([ls.a as u32, ls.b as u32, v as u32])
                            .map_err(|r| ctx.reject(r, out.pos, cur.record, cur.rec_start))?;
                        ls.b = v;
                    }
                }
                ls.seen += 1;
            }
            if !cur.strip && ls.len < 3 {
                stats.short_faces += 1;
            }
            s.skip_props(&el.props[cur.list + 1..]).map_err(|e| ctx.src(e, cur.record, cur.rec_start))?;
            cur.extra.note(s.end_record());
            cur.record += 1;
            completed += 1;
            if completed >= budget {
                cur.pos = s.pos();
                return Ok(cur.record >= cur.count);
            }
        }
        if cur.record >= cur.count {
            cur.pos = s.pos();
            return Ok(true);
        }
        if !out.room() {
            cur.pos = s.pos();
            return Ok(false);
        }
        cur.rec_start = s.mark();
        s.skip_props(&el.props[..cur.list]).map_err(|e| ctx.src(e, cur.record, cur.rec_start))?;
        let n = s.list_len(cty).map_err(|e| ctx.src(e, cur.record, cur.rec_start))?;
        if cur.tri_only && n != 3 {
            let e = Error::unsupported(
                ctx.path,
                format!("a face with {n} corners: a file read in parts must hold only triangles (run it as one part, --parts 1)"),
            );
            return Err(ctx.at(e, cur.record, cur.rec_start));
        }
        cur.ls = Some(ListState { left: n, len: n, seen: 0, a: 0, b: 0, odd: false });
    }
}

impl FaceStream for PlyBody {
    fn splittable_records(&self) -> Option<u64> {
        if self.header.encoding == Encoding::Ascii {
            return None;
        }
        let mut faces = self.roles.iter().enumerate().filter(|(_, r)| matches!(r, Role::Faces { .. }));
        let (e, Role::Faces { list, strip: false, .. }) = faces.next()? else { return None };
        if faces.next().is_some() || self.range_only {
            return None;
        }
        let el = &self.header.elements[e];
        let others_fixed = el.props.iter().enumerate().all(|(i, p)| i == *list || matches!(p.ty, PropType::Scalar(_)));
        others_fixed.then_some(el.count)
    }

    fn fixed_faces(&self) -> Result<Option<crate::visit::FixedFaces>, Error> {
        let Some(count) = self.splittable_records() else { return Ok(None) };
        // The face element's start: located already, or found by walking.
        let (elem, start) = match self.pending.front() {
            Some(&(e, start)) => (e, start),
            None => {
                let (mut e, mut at) = (self.next_elem, self.next_offset);
                while !matches!(self.roles.get(e), Some(Role::Faces { .. })) {
                    if e >= self.roles.len() {
                        return Ok(None);
                    }
                    at = self.skip_element(e, at)?;
                    e += 1;
                }
                (e, at)
            }
        };
        let el = &self.header.elements[elem];
        let Role::Faces { list, .. } = self.roles[elem] else { unreachable!() };
        let PropType::List { count: cty, item: ity } = el.props[list].ty else { unreachable!() };
        let size = |ps: &[Property]| -> usize { ps.iter().map(|p| if let PropType::Scalar(s) = p.ty { s.size() } else { 0 }).sum() };
        let pre = size(&el.props[..list]);
        let stride = pre + cty.size() + 3 * ity.size() + size(&el.props[list + 1..]);
        let map = self.map.clone();
        // Too short for `count` triangles: polygons with fewer corners, or a
        // truncated file. Either way the stream decides (and a truncated
        // file is reported there, at the record where it ends).
        if fixed_end(&self.ctx(map.bytes(), elem), start, stride, count).is_err() {
            return Ok(None);
        }
        Ok(Some(crate::visit::FixedFaces::Ply {
            map,
            element: el.name.clone(),
            start,
            stride,
            pre,
            cty,
            ity,
            be: self.header.encoding == Encoding::BinaryBe,
            count,
        }))
    }

    fn restrict(&mut self, first: u64, end: u64) -> Result<(), Error> {
        self.start_next()?;
        let Some((elem, list, start)) = self.cur.as_ref().map(|c| (c.elem, c.list, c.pos)) else { return Ok(()) };
        let el = &self.header.elements[elem];
        let PropType::List { count: cty, item: ity } = el.props[list].ty else { unreachable!() };
        let others: usize = el.props.iter().map(|p| if let PropType::Scalar(s) = p.ty { s.size() } else { 0 }).sum();
        let stride = others + cty.size() + 3 * ity.size();
        let map = self.map.clone();
        fixed_end(&self.ctx(map.bytes(), elem), start, stride, end)?;
        let Some(cur) = self.cur.as_mut() else { unreachable!() };
        cur.pos = start + first as usize * stride;
        cur.rec_start = cur.pos;
        cur.record = first;
        cur.count = end;
        cur.walked = false;
        cur.tri_only = true;
        self.bytes_done = cur.pos as u64;
        self.range_only = true;
        Ok(())
    }

    fn fill(&mut self, out: &mut Emit, stats: &mut ReadStats) -> Result<bool, Error> {
        while !self.finished {
            if self.cur.is_none() {
                self.start_next()?;
                continue;
            }
            let ended = self.stream(out, stats)?;
            if ended && self.range_only {
                self.finished = true;
                break;
            }
            if !ended && !out.room() {
                return Ok(true);
            }
        }
        Ok(false)
    }

    fn bytes_done(&self) -> u64 {
        self.bytes_done
    }

    fn ignored_trailing_bytes(&self) -> u64 {
        self.trailing
    }

    fn warnings(&self) -> Vec<String> {
        let data = self.map.bytes();
        let mut w = Vec::new();
        for (el, x) in self.header.elements.iter().zip(&self.extra) {
            let x = x.get();
            if let Some(at) = x.first {
                w.push(format!(
                    "{}: line {}: element '{}' has more values on its line than the {} propert{} its header declares; the declared ones were read and the rest ignored ({} line{} like this)",
                    self.path.display(),
                    line_of(data, at),
                    el.name,
                    el.props.len(),
                    if el.props.len() == 1 { "y" } else { "ies" },
                    x.lines,
                    if x.lines == 1 { "" } else { "s" }
                ));
            }
        }
        w
    }
}
