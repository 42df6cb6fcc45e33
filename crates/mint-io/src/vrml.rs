//! VRML 2.0 (VRML97, ISO/IEC 14772-1): the triangles of every
//! `IndexedFaceSet` inside a `Shape`, under any nesting of `Transform`,
//! `Group`-like nodes, `Switch` and `LOD`.
//!
//! Reading: the file must start with `#VRML V2.0` (VRML 1.0 is refused as
//! unsupported). A recursive-descent parser walks the scene graph with the
//! current transform (`T · C · R · SR · S · SR⁻¹ · C⁻¹`, per the standard,
//! composed down the `Transform` nesting); each `Coordinate`'s points are
//! transformed and spilled, each `coordIndex` polygon is fan-triangulated
//! (reversed when `ccw FALSE`) and its triangles spilled too. `DEF`/`USE`
//! re-parse the named node where it is used (so a `USE`d `Coordinate` or
//! `Transform` gets the transform of its use). `Group`, `Anchor`,
//! `Collision` and `Billboard` read their `children`; `Switch` its
//! `whichChoice` child; `LOD` its first `level`. Other nodes, other
//! geometry (`Box`, `Sphere`, `IndexedLineSet`, ...), `PROTO`,
//! `EXTERNPROTO` and `ROUTE` are skipped. Fields may come in any order: a
//! node's fields are located first, then read in the order needed.
//! Commas are whitespace; `#` starts a comment.
//!
//! Writing: one `Shape` with one `IndexedFaceSet` (`coord Coordinate {
//! point [...] }` then `coordIndex [...]`), streamed.
//!
//! Memory: positions and triangles go to spill files; the parser holds the
//! `DEF` table (names and offsets) and the transform stack.

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{show_token, Error, ErrorKind};
use crate::mapped::{Mapped, SpillFile};
use crate::positions::not_finite;
use crate::positions::{Emit, Positions, Reject};
use crate::backend::{ElementInfo, FaceStream, MeshInfo, Opened, ReadStats};
use crate::text::{line_of, parse_f64, parse_i64};
use crate::backend::{write_point, FormatWriter, OutFile, WriteOptions};
use crate::Format;

/// An affine transform: 3 rows of `[a b c t]`.
type Affine = [[f64; 4]; 3];

const IDENTITY: Affine = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];

fn mul(a: &Affine, b: &Affine) -> Affine {
    let mut r = [[0.0; 4]; 3];
    for i in 0..3 {
        for j in 0..4 {
            let mut s = if j == 3 { a[i][3] } else { 0.0 };
            for k in 0..3 {
                s += a[i][k] * b[k][j];
            }
            r[i][j] = s;
        }
    }
    r
}

fn apply(m: &Affine, p: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3])
}

fn translation(t: [f64; 3]) -> Affine {
    [[1.0, 0.0, 0.0, t[0]], [0.0, 1.0, 0.0, t[1]], [0.0, 0.0, 1.0, t[2]]]
}

fn scaling(s: [f64; 3]) -> Affine {
    [[s[0], 0.0, 0.0, 0.0], [0.0, s[1], 0.0, 0.0], [0.0, 0.0, s[2], 0.0]]
}

/// Rotation by `r[3]` radians about the axis `r[0..3]` (Rodrigues).
fn rotation(r: [f64; 4]) -> Affine {
    let l = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    if l == 0.0 || r[3] == 0.0 {
        return IDENTITY;
    }
    let (x, y, z) = (r[0] / l, r[1] / l, r[2] / l);
    let (s, c) = r[3].sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0.0],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0.0],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0.0],
    ]
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok<'a> {
    Open,
    Close,
    LBrack,
    RBrack,
    Str,
    Word(&'a [u8]),
}

#[derive(Clone)]
struct Lexer<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Lexer<'a> {
    fn skip_space(&mut self) {
        let d = self.data;
        while self.pos < d.len() {
            match d[self.pos] {
                b' ' | b'\t' | b'\r' | b'\n' | b',' | 0x0b | 0x0c => self.pos += 1,
                b'#' => {
                    while self.pos < d.len() && d[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    /// The next token and its offset.
    fn next(&mut self) -> Option<(usize, Tok<'a>)> {
        self.skip_space();
        let d = self.data;
        let at = self.pos;
        let b = *d.get(at)?;
        self.pos += 1;
        let t = match b {
            b'{' => Tok::Open,
            b'}' => Tok::Close,
            b'[' => Tok::LBrack,
            b']' => Tok::RBrack,
            b'"' => {
                while self.pos < d.len() && d[self.pos] != b'"' {
                    if d[self.pos] == b'\\' {
                        self.pos += 1;
                    }
                    self.pos += 1;
                }
                self.pos = (self.pos + 1).min(d.len());
                Tok::Str
            }
            _ => {
                while self.pos < d.len() && !matches!(d[self.pos], b' ' | b'\t' | b'\r' | b'\n' | b',' | b'{' | b'}' | b'[' | b']' | b'"' | b'#' | 0x0b | 0x0c) {
                    self.pos += 1;
                }
                Tok::Word(&d[at..self.pos])
            }
        };
        Some((at, t))
    }

    fn peek(&self) -> Option<(usize, Tok<'a>)> {
        self.clone().next()
    }
}

fn numeric(w: &[u8]) -> bool {
    w.first().is_some_and(|b| b"+-.0123456789".contains(b))
}

/// Where parsed geometry goes: counting (for `info`) or spilling.
trait Out {
    fn point(&mut self, p: [f64; 3]) -> Result<(), Error>;
    fn tri(&mut self, t: [u32; 3]) -> Result<(), Error>;
}

struct Count {
    points: u64,
    tris: u64,
}

impl Out for Count {
    fn point(&mut self, _p: [f64; 3]) -> Result<(), Error> {
        self.points += 1;
        Ok(())
    }
    fn tri(&mut self, _t: [u32; 3]) -> Result<(), Error> {
        self.tris += 1;
        Ok(())
    }
}

struct Spill {
    points: SpillFile,
    tris: SpillFile,
    np: u64,
    nt: u64,
}

impl Out for Spill {
    fn point(&mut self, p: [f64; 3]) -> Result<(), Error> {
        self.np += 1;
        self.points.write_point(p)
    }
    fn tri(&mut self, t: [u32; 3]) -> Result<(), Error> {
        self.nt += 1;
        let mut b = [0u8; 12];
        for k in 0..3 {
            b[4 * k..4 * k + 4].copy_from_slice(&t[k].to_le_bytes());
        }
        self.tris.write_bytes(&b)
    }
}

/// Counters shown in the info's comments.
#[derive(Default)]
struct Seen {
    shapes: u64,
    face_sets: u64,
    skipped_geometry: HashMap<String, u64>,
    short_polygons: u64,
}

struct Parser<'a, 'o> {
    path: &'a Path,
    data: &'a [u8],
    lx: Lexer<'a>,
    defs: HashMap<&'a [u8], usize>,
    out: &'o mut dyn Out,
    points: u64,
    depth: u32,
    seen: Seen,
}

impl<'a> Parser<'a, '_> {
    fn err(&self, at: usize, msg: impl Into<String>) -> Error {
        Error::format(self.path, msg).at_line(line_of(self.data, at)).at_byte(at as u64)
    }

    fn next(&mut self, what: &str) -> Result<(usize, Tok<'a>), Error> {
        self.lx.next().ok_or_else(|| self.err(self.data.len(), format!("unexpected end of file, expected {what} (truncated file?)")))
    }

    fn expect(&mut self, t: Tok<'static>, what: &str) -> Result<usize, Error> {
        let (at, got) = self.next(what)?;
        if got != t {
            return Err(self.err(at, format!("expected {what}, found {}", self.show(at, got))));
        }
        Ok(at)
    }

    fn show(&self, _at: usize, t: Tok) -> String {
        match t {
            Tok::Open => "'{'".into(),
            Tok::Close => "'}'".into(),
            Tok::LBrack => "'['".into(),
            Tok::RBrack => "']'".into(),
            Tok::Str => "a string".into(),
            Tok::Word(w) => show_token(w),
        }
    }

    fn word(&mut self, what: &str) -> Result<(usize, &'a [u8]), Error> {
        match self.next(what)? {
            (at, Tok::Word(w)) => Ok((at, w)),
            (at, t) => Err(self.err(at, format!("expected {what}, found {}", self.show(at, t)))),
        }
    }

    fn number(&mut self) -> Result<f64, Error> {
        let (at, w) = self.word("a number")?;
        parse_f64(w).ok_or_else(|| self.err(at, format!("expected a number, found {}", show_token(w))))
    }

    /// Skips to the matching close of an already consumed `{` or `[`.
    fn skip_balanced(&mut self, open_at: usize) -> Result<(), Error> {
        let mut depth = 1u32;
        while depth > 0 {
            match self.lx.next() {
                None => return Err(self.err(open_at, "unbalanced brackets: this one is never closed (truncated file?)")),
                Some((_, Tok::Open | Tok::LBrack)) => depth += 1,
                Some((_, Tok::Close | Tok::RBrack)) => depth -= 1,
                _ => {}
            }
        }
        Ok(())
    }

    /// Skips one field value of any type.
    fn skip_value(&mut self) -> Result<(), Error> {
        match self.next("a field value")? {
            (at, Tok::LBrack) => self.skip_balanced(at),
            (_, Tok::Str) => {
                while matches!(self.lx.peek(), Some((_, Tok::Str))) {
                    self.lx.next();
                }
                Ok(())
            }
            (_, Tok::Word(b"DEF")) => {
                self.word("a name")?;
                self.skip_value()
            }
            (_, Tok::Word(b"USE" | b"IS")) => self.word("a name").map(|_| ()),
            (_, Tok::Word(b"NULL")) => Ok(()),
            (_, Tok::Word(w)) if numeric(w) || w == b"TRUE" || w == b"FALSE" => {
                while let Some((_, Tok::Word(x))) = self.lx.peek() {
                    if numeric(x) || x == b"TRUE" || x == b"FALSE" {
                        self.lx.next();
                    } else {
                        break;
                    }
                }
                Ok(())
            }
            (_, Tok::Word(_)) => {
                // A node type: its body follows.
                let at = self.expect(Tok::Open, "'{'")?;
                self.skip_balanced(at)
            }
            (at, t) => Err(self.err(at, format!("expected a field value, found {}", self.show(at, t)))),
        }
    }

    /// The fields of a node body (after its `{`): name and value offset;
    /// leaves the lexer after the closing `}`.
    fn fields(&mut self) -> Result<Vec<(&'a [u8], usize)>, Error> {
        let mut out = Vec::new();
        loop {
            match self.next("a field name or '}'")? {
                (_, Tok::Close) => return Ok(out),
                (_, Tok::Word(w)) => {
                    self.lx.skip_space();
                    out.push((w, self.lx.pos));
                    self.skip_value()?;
                }
                (at, t) => return Err(self.err(at, format!("expected a field name or '}}', found {}", self.show(at, t)))),
            }
        }
    }

    /// Runs `f` with the lexer at `pos`, then restores it.
    fn at<T>(&mut self, pos: usize, f: impl FnOnce(&mut Self) -> Result<T, Error>) -> Result<T, Error> {
        let saved = self.lx.pos;
        self.lx.pos = pos;
        let r = f(self);
        self.lx.pos = saved;
        r
    }

    fn floats<const N: usize>(&mut self) -> Result<[f64; N], Error> {
        let mut v = [0.0; N];
        for x in v.iter_mut() {
            *x = self.number()?;
        }
        Ok(v)
    }

    /// A statement at the top level or in a `children` list.
    fn statement(&mut self, m: &Affine) -> Result<(), Error> {
        match self.lx.peek() {
            Some((_, Tok::Word(b"PROTO"))) => {
                self.lx.next();
                self.word("a PROTO name")?;
                let at = self.expect(Tok::LBrack, "'['")?;
                self.skip_balanced(at)?;
                let at = self.expect(Tok::Open, "'{'")?;
                self.skip_balanced(at)
            }
            Some((_, Tok::Word(b"EXTERNPROTO"))) => {
                self.lx.next();
                self.word("an EXTERNPROTO name")?;
                let at = self.expect(Tok::LBrack, "'['")?;
                self.skip_balanced(at)?;
                self.skip_value()
            }
            Some((_, Tok::Word(b"ROUTE"))) => {
                self.lx.next();
                for _ in 0..3 {
                    self.word("a ROUTE part")?;
                }
                Ok(())
            }
            _ => self.node(m),
        }
    }

    /// A node value (with `DEF`, `USE` or `NULL`).
    fn node(&mut self, m: &Affine) -> Result<(), Error> {
        let (at, ty) = self.word("a node")?;
        match ty {
            b"NULL" => Ok(()),
            b"DEF" => {
                let (_, name) = self.word("a DEF name")?;
                self.lx.skip_space();
                self.defs.insert(name, self.lx.pos);
                self.node(m)
            }
            b"USE" => {
                let (nat, name) = self.word("a USE name")?;
                let Some(&pos) = self.defs.get(name) else {
                    return Err(self.err(nat, format!("USE of {} before its DEF", show_token(name))));
                };
                self.depth += 1;
                if self.depth > 64 {
                    return Err(self.err(nat, "USE nesting deeper than 64 (a node that uses itself?)"));
                }
                let r = self.at(pos, |p| p.node(m));
                self.depth -= 1;
                r
            }
            _ => {
                self.expect(Tok::Open, "'{'")?;
                let fields = self.fields()?;
                let get = |name: &[u8]| fields.iter().rev().find(|f| f.0 == name).map(|f| f.1);
                match ty {
                    b"Transform" => {
                        let mut t = [0.0; 3];
                        let mut c = [0.0; 3];
                        let mut s = [1.0; 3];
                        let mut r = [0.0, 0.0, 1.0, 0.0];
                        let mut so = [0.0, 0.0, 1.0, 0.0];
                        if let Some(p) = get(b"translation") {
                            t = self.at(p, |p| p.floats::<3>())?;
                        }
                        if let Some(p) = get(b"center") {
                            c = self.at(p, |p| p.floats::<3>())?;
                        }
                        if let Some(p) = get(b"scale") {
                            s = self.at(p, |p| p.floats::<3>())?;
                        }
                        if let Some(p) = get(b"rotation") {
                            r = self.at(p, |p| p.floats::<4>())?;
                        }
                        if let Some(p) = get(b"scaleOrientation") {
                            so = self.at(p, |p| p.floats::<4>())?;
                        }
                        let neg = |v: [f64; 3]| [-v[0], -v[1], -v[2]];
                        let local = [
                            translation(t),
                            translation(c),
                            rotation(r),
                            rotation(so),
                            scaling(s),
                            rotation([so[0], so[1], so[2], -so[3]]),
                            translation(neg(c)),
                        ]
                        .iter()
                        .fold(IDENTITY, |acc, x| mul(&acc, x));
                        let m2 = mul(m, &local);
                        if let Some(p) = get(b"children") {
                            self.at(p, |p| p.children(&m2))?;
                        }
                        Ok(())
                    }
                    b"Group" | b"Anchor" | b"Collision" | b"Billboard" => {
                        if let Some(p) = get(b"children") {
                            self.at(p, |p| p.children(m))?;
                        }
                        Ok(())
                    }
                    b"Switch" => {
                        let which = match get(b"whichChoice") {
                            Some(p) => self.at(p, |p| p.number())? as i64,
                            None => -1,
                        };
                        if let (Some(p), true) = (get(b"choice"), which >= 0) {
                            self.at(p, |p| p.nth_child(which as usize, m))?;
                        }
                        Ok(())
                    }
                    b"LOD" => {
                        if let Some(p) = get(b"level") {
                            self.at(p, |p| p.nth_child(0, m))?;
                        }
                        Ok(())
                    }
                    b"Shape" => {
                        self.seen.shapes += 1;
                        if let Some(p) = get(b"geometry") {
                            self.at(p, |p| p.geometry(m))?;
                        }
                        Ok(())
                    }
                    _ => {
                        let _ = at;
                        Ok(())
                    }
                }
            }
        }
    }

    /// A `children` value: one node or a list of statements.
    fn children(&mut self, m: &Affine) -> Result<(), Error> {
        if let Some((_, Tok::LBrack)) = self.lx.peek() {
            self.lx.next();
            loop {
                if let Some((_, Tok::RBrack)) = self.lx.peek() {
                    self.lx.next();
                    return Ok(());
                }
                if self.lx.peek().is_none() {
                    return Err(self.err(self.data.len(), "unexpected end of file in a children list (truncated file?)"));
                }
                self.statement(m)?;
            }
        }
        self.node(m)
    }

    /// Reads only the `n`-th node of a list (or the single node).
    fn nth_child(&mut self, n: usize, m: &Affine) -> Result<(), Error> {
        if let Some((_, Tok::LBrack)) = self.lx.peek() {
            self.lx.next();
            let mut k = 0;
            loop {
                match self.lx.peek() {
                    Some((_, Tok::RBrack)) | None => return Ok(()),
                    _ => {
                        if k == n {
                            return self.node(m);
                        }
                        self.skip_value()?;
                        k += 1;
                    }
                }
            }
        }
        if n == 0 {
            self.node(m)
        } else {
            Ok(())
        }
    }

    /// A `geometry` value: only `IndexedFaceSet` is read.
    fn geometry(&mut self, m: &Affine) -> Result<(), Error> {
        let (at, ty) = match self.lx.peek() {
            Some((at, Tok::Word(w))) => (at, w),
            _ => return self.skip_value(),
        };
        match ty {
            b"DEF" => {
                self.lx.next();
                let (_, name) = self.word("a DEF name")?;
                self.lx.skip_space();
                self.defs.insert(name, self.lx.pos);
                self.geometry(m)
            }
            b"USE" => {
                self.lx.next();
                let (nat, name) = self.word("a USE name")?;
                let Some(&pos) = self.defs.get(name) else {
                    return Err(self.err(nat, format!("USE of {} before its DEF", show_token(name))));
                };
                self.at(pos, |p| p.geometry(m))
            }
            b"NULL" => {
                self.lx.next();
                Ok(())
            }
            b"IndexedFaceSet" => {
                self.lx.next();
                self.expect(Tok::Open, "'{'")?;
                let fields = self.fields()?;
                let get = |name: &[u8]| fields.iter().rev().find(|f| f.0 == name).map(|f| f.1);
                self.seen.face_sets += 1;
                let ccw = match get(b"ccw") {
                    Some(p) => self.at(p, |p| p.word("TRUE or FALSE"))?.1 != b"FALSE",
                    None => true,
                };
                let Some(ci) = get(b"coordIndex") else { return Ok(()) };
                let Some(cp) = get(b"coord") else {
                    return Err(self.err(at, "an IndexedFaceSet with coordIndex but no coord"));
                };
                let base = self.points;
                let count = self.at(cp, |p| p.coordinate(m))?;
                self.at(ci, |p| p.coord_index(base, count, ccw))
            }
            _ => {
                *self.seen.skipped_geometry.entry(String::from_utf8_lossy(ty).into_owned()).or_default() += 1;
                let _ = at;
                self.skip_value()
            }
        }
    }

    /// A `coord` value: a `Coordinate` node; returns its point count.
    fn coordinate(&mut self, m: &Affine) -> Result<u64, Error> {
        let (at, ty) = self.word("a Coordinate node")?;
        match ty {
            b"DEF" => {
                let (_, name) = self.word("a DEF name")?;
                self.lx.skip_space();
                self.defs.insert(name, self.lx.pos);
                self.coordinate(m)
            }
            b"USE" => {
                let (nat, name) = self.word("a USE name")?;
                let Some(&pos) = self.defs.get(name) else {
                    return Err(self.err(nat, format!("USE of {} before its DEF", show_token(name))));
                };
                self.at(pos, |p| p.coordinate(m))
            }
            b"Coordinate" => {
                self.expect(Tok::Open, "'{'")?;
                let fields = self.fields()?;
                let Some(pp) = fields.iter().rev().find(|f| f.0 == b"point").map(|f| f.1) else { return Ok(0) };
                self.at(pp, |p| {
                    let mut n = 0u64;
                    let list = matches!(p.lx.peek(), Some((_, Tok::LBrack)));
                    if list {
                        p.lx.next();
                    }
                    loop {
                        if list {
                            match p.lx.peek() {
                                Some((_, Tok::RBrack)) => break,
                                None => return Err(p.err(p.data.len(), "unexpected end of file in a point list (truncated file?)")),
                                _ => {}
                            }
                        }
                        let q = p.floats::<3>()?;
                        p.out.point(apply(m, q))?;
                        p.points += 1;
                        n += 1;
                        if !list {
                            break;
                        }
                    }
                    Ok(n)
                })
            }
            _ => Err(self.err(at, format!("expected a Coordinate node, found {}", show_token(ty)))),
        }
    }

    /// A `coordIndex` list: polygons separated by -1, fan-triangulated.
    fn coord_index(&mut self, base: u64, count: u64, ccw: bool) -> Result<(), Error> {
        let list = matches!(self.lx.peek(), Some((_, Tok::LBrack)));
        if list {
            self.lx.next();
        }
        let mut poly: Vec<u32> = Vec::new();
        let flush = |p: &mut Self, poly: &mut Vec<u32>| -> Result<(), Error> {
            if poly.len() < 3 {
                if !poly.is_empty() {
                    p.seen.short_polygons += 1;
                }
            } else {
                for k in 1..poly.len() - 1 {
                    let t = [poly[0], poly[k], poly[k + 1]];
                    p.out.tri(if ccw { t } else { [t[0], t[2], t[1]] })?;
                }
            }
            poly.clear();
            Ok(())
        };
        loop {
            match self.lx.peek() {
                Some((_, Tok::RBrack)) if list => {
                    self.lx.next();
                    break;
                }
                None if list => return Err(self.err(self.data.len(), "unexpected end of file in coordIndex (truncated file?)")),
                Some((_, Tok::Word(w))) if numeric(w) => {
                    let (at, _) = self.lx.next().unwrap();
                    let i = parse_i64(w).ok_or_else(|| self.err(at, format!("expected an index, found {}", show_token(w))))?;
                    if i == -1 {
                        flush(self, &mut poly)?;
                    } else if i < 0 || i as u64 >= count {
                        return Err(Error::new(ErrorKind::Index, self.path, format!("coordIndex {i} is out of range (the Coordinate has {count} points)"))
                            .at_line(line_of(self.data, at))
                            .at_byte(at as u64));
                    } else {
                        let g = base + i as u64;
                        if g > u32::MAX as u64 {
                            return Err(Error::unsupported(self.path, format!("more than {} points (32-bit indices)", u32::MAX)));
                        }
                        poly.push(g as u32);
                    }
                    if !list {
                        break;
                    }
                }
                _ if !list => break,
                Some((at, t)) => return Err(self.err(at, format!("expected an index, found {}", self.show(at, t)))),
                None => break,
            }
        }
        flush(self, &mut poly)
    }
}

/// Checks the header and parses the whole file into `out`.
fn parse(path: &Path, data: &[u8], out: &mut dyn Out) -> Result<Seen, Error> {
    if data.starts_with(b"#VRML V1.0") {
        return Err(Error::unsupported(path, "VRML 1.0 is not supported (only VRML 2.0)").at_line(1));
    }
    if !data.starts_with(b"#VRML V2.0") {
        return Err(Error::format(path, "not a VRML 2.0 file: the first line must start with '#VRML V2.0'").at_element("header").at_line(1));
    }
    let mut p = Parser { path, data, lx: Lexer { data, pos: 0 }, defs: HashMap::new(), out, points: 0, depth: 0, seen: Seen::default() };
    while p.lx.peek().is_some() {
        p.statement(&IDENTITY)?;
    }
    Ok(p.seen)
}

fn make_info(points: u64, tris: u64, seen: &Seen) -> MeshInfo {
    let mut comments = vec![format!("{} Shape nodes, {} IndexedFaceSet nodes read", seen.shapes, seen.face_sets)];
    let mut skipped: Vec<_> = seen.skipped_geometry.iter().collect();
    skipped.sort();
    for (k, n) in skipped {
        comments.push(format!("{n} {k} geometry nodes skipped"));
    }
    if seen.short_polygons > 0 {
        comments.push(format!("{} polygons with fewer than 3 indices skipped", seen.short_polygons));
    }
    MeshInfo {
        format: Format::Vrml,
        encoding: "ascii".into(),
        vertex_count: points,
        face_count: Some(tris),
        elements: vec![
            ElementInfo { name: "point".into(), count: points, properties: vec!["x".into(), "y".into(), "z".into()] },
            ElementInfo { name: "triangle".into(), count: tris, properties: vec!["vertex_indices".into()] },
        ],
        comments,
        obj_info: Vec::new(),
    }
}

/// Parses the whole file, counting.
pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    let mut c = Count { points: 0, tris: 0 };
    let seen = parse(path, data, &mut c)?;
    Ok(make_info(c.points, c.tris, &seen))
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let data = map.bytes();
    map.advise_sequential(0, data.len());
    let mut s = Spill { points: SpillFile::new(spill_dir, path)?, tris: SpillFile::new(spill_dir, path)?, np: 0, nt: 0 };
    let seen = parse(path, data, &mut s)?;
    if s.np > u32::MAX as u64 {
        return Err(Error::unsupported(path, format!("{} points; mint reads at most {} (32-bit indices)", s.np, u32::MAX)));
    }
    let info = make_info(s.np, s.nt, &seen);
    let positions = Positions::spilled(Arc::new(s.points.into_mapped()?), s.np as u32);
    let tris = Arc::new(s.tris.into_mapped()?);
    let body = VrmlBody { path: path.to_path_buf(), tris, count: s.nt, next: 0, total: data.len() as u64 };
    Ok(Opened { info, positions, body: Box::new(body), range_grid: None, spilled_vertices: s.np, colours: None, face_colours: None, texturing: None })
}

/// Streams the spilled triangles.
struct VrmlBody {
    path: PathBuf,
    tris: Arc<Mapped>,
    count: u64,
    next: u64,
    total: u64,
}

impl FaceStream for VrmlBody {
    fn fill(&mut self, out: &mut Emit, _stats: &mut ReadStats) -> Result<bool, Error> {
        let b = self.tris.bytes();
        while self.next < self.count && out.room() {
            let o = 12 * self.next as usize;
            let t = [0, 1, 2].map(|k| u32::from_le_bytes(b[o + 4 * k..o + 4 * k + 4].try_into().unwrap()));
            if let Err(Reject::NotFinite(v)) = out.tri_checked(t) {
                return Err(not_finite(&self.path, v, out.pos).at_element("triangle").at_record(self.next));
            }
            self.next += 1;
        }
        Ok(self.next < self.count)
    }

    fn bytes_done(&self) -> u64 {
        if self.count == 0 {
            self.total
        } else {
            (self.total as f64 * self.next as f64 / self.count as f64) as u64
        }
    }
}

/// Writes one `Shape` with one `IndexedFaceSet`, streamed.
pub(crate) struct VrmlWriter {
    out: OutFile,
    double: bool,
    in_faces: bool,
}

const HEAD: &[u8] = b"#VRML V2.0 utf8\n# written by mint-io\nShape {\n  geometry IndexedFaceSet {\n    solid FALSE\n    coord Coordinate {\n      point [\n";
const MIDDLE: &[u8] = b"      ]\n    }\n    coordIndex [\n";
const TAIL: &[u8] = b"    ]\n  }\n}\n";

impl VrmlWriter {
    pub(crate) fn create(path: &Path, opts: &WriteOptions) -> Result<VrmlWriter, Error> {
        let mut out = OutFile::create(path)?;
        out.put(HEAD)?;
        Ok(VrmlWriter { out, double: opts.double, in_faces: false })
    }
}

impl FormatWriter for VrmlWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        write_point(self.out.text(), b"        ", p, self.double, b",\n");
        self.out.maybe_flush()
    }

    fn face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        if !self.in_faces {
            self.in_faces = true;
            self.out.put(MIDDLE)?;
        }
        let _ = writeln!(self.out.text(), "      {} {} {} -1,", f[0], f[1], f[2]);
        self.out.maybe_flush()
    }

    fn finish(mut self: Box<Self>, _vertices: u64, _faces: u64) -> Result<u64, Error> {
        if !self.in_faces {
            self.out.put(MIDDLE)?;
        }
        self.out.put(TAIL)?;
        self.out.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(text: &str) -> Result<(u64, u64), Error> {
        let mut c = Count { points: 0, tris: 0 };
        parse(Path::new("a.wrl"), text.as_bytes(), &mut c)?;
        Ok((c.points, c.tris))
    }

    #[test]
    fn transforms_compose_and_fields_come_in_any_order() {
        struct Keep(Vec<[f64; 3]>, Vec<[u32; 3]>);
        impl Out for Keep {
            fn point(&mut self, p: [f64; 3]) -> Result<(), Error> {
                self.0.push(p);
                Ok(())
            }
            fn tri(&mut self, t: [u32; 3]) -> Result<(), Error> {
                self.1.push(t);
                Ok(())
            }
        }
        let text = "#VRML V2.0 utf8\n\
            Transform { translation 10 0 0 children [\n\
              Transform { children Shape { geometry IndexedFaceSet {\n\
                  coordIndex [ 0 1 2 3 -1 ] ccw FALSE\n\
                  coord DEF C Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0 1 0 ] } } }\n\
                scale 2 2 2 }\n\
              Shape { appearance Appearance { material Material { diffuseColor 1 0 0 } } geometry Box { size 1 1 1 } }\n\
            ] }\n\
            Shape { geometry IndexedFaceSet { coord USE C coordIndex [ 0 1 2 ] } }\n\
            ROUTE a.b TO c.d\n";
        let mut k = Keep(Vec::new(), Vec::new());
        let seen = parse(Path::new("a.wrl"), text.as_bytes(), &mut k).unwrap();
        assert_eq!(k.0[2], [12.0, 2.0, 0.0]);
        assert_eq!(k.0[6], [1.0, 1.0, 0.0]);
        // ccw FALSE reverses the fan; the USEd coordinates are new points.
        assert_eq!(k.1, vec![[0, 2, 1], [0, 3, 2], [4, 5, 6]]);
        assert_eq!((seen.shapes, seen.face_sets), (3, 2));
        assert_eq!(seen.skipped_geometry.get("Box"), Some(&1));
    }

    #[test]
    fn rotation_about_z_by_a_quarter_turn() {
        let m = rotation([0.0, 0.0, 1.0, std::f64::consts::FRAC_PI_2]);
        let p = apply(&m, [1.0, 0.0, 0.0]);
        assert!((p[0]).abs() < 1e-15 && (p[1] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn bad_files_name_the_line() {
        assert_eq!(count("#VRML V1.0 ascii\n").err().unwrap().kind(), ErrorKind::Unsupported);
        assert!(count("hello").is_err());
        let e = count("#VRML V2.0 utf8\nShape { geometry IndexedFaceSet {\ncoord Coordinate { point [ 0 0 0 ] }\ncoordIndex [ 0 0 5 ] } }\n").err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Index);
        assert!(e.to_string().contains("line 4"), "{e}");
        let e = count("#VRML V2.0 utf8\nShape { geometry IndexedFaceSet { coord Coordinate { point [ 0 0 ").err().unwrap();
        assert!(e.to_string().contains("never closed (truncated file?) (line 2"), "{e}");
        assert_eq!(count("#VRML V2.0 utf8\n# nothing\n").unwrap(), (0, 0));
    }
}
