//! The profile format (`.pro`): a stack of planar cross-sections, each a set
//! of closed polygons (Dangl 1998, appendix A.3). [`ProfileReader`] streams
//! it one [`Section`] at a time and checks the contract as it goes;
//! [`ProfileWriter`] writes it. [`StackFrame`] is the right-handed frame
//! `(u, v, n)` whose third axis is the sections' common normal, oriented so
//! that sections come in increasing order along it; every algorithm works on
//! the projected `(u, v)` coordinates and the offset along `n`.
//!
//! # The format
//! ```text
//! pro                      # header: the first token of the file
//! section                  # a cross-section; its first contour follows
//! 0 0 0   1 0 0   1 1 0    # vertices: three coordinates each
//! contour                  # another polygon in the same section
//! 0.2 0.2 0  0.4 0.2 0  0.3 0.4 0
//! section
//! ...
//! ```
//! - Tokens are separated by any whitespace; a vertex may span lines, and
//!   a line may hold several vertices. `#` starts a comment that runs to the
//!   end of the line, anywhere after the header.
//! - Numbers are decimal with an optional sign, fraction and exponent
//!   (`-1.5e-3`, `+2`, `.5`): a superset of the 1998 grammar, which had
//!   unsigned plain decimals only. `inf` and `nan` are refused.
//! - Contours are closed implicitly: a last vertex equal to the first one is
//!   dropped, as are consecutive duplicates (DICOM RT structure sets repeat
//!   points). Orientation (clockwise or not) does not matter; nesting gives
//!   holes (even-odd).
//!
//! # The contract, checked on read
//! Each contour has at least 3 distinct vertices; all vertices of a section
//! lie in one plane (within [`ProfileOptions::planarity`] times the section's
//! bounding-box diagonal); every section's plane is parallel to the first
//! one's; contours are simple and pairwise disjoint (exact test on the
//! projected coordinates); and sections are strictly ordered along the
//! normal (either direction, fixed by the first two sections). A violation
//! is a [`ProfileError`] naming the line. Non-goal: rotational scans
//! (sections through a common axis); they are refused as not parallel.
//!
//! Memory: the reader holds at most two sections (the first one is held
//! until the second fixes the direction of the stack axis).

use crate::error::{ProfileError, ProfileErrorKind as K};
use crate::geom2d::{first_crossing, P2};
use glam::DVec3;
use std::collections::VecDeque;
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

/// Options of [`ProfileReader`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileOptions {
    /// Planarity tolerance, relative to each section's bounding-box
    /// diagonal. Default `1e-6`.
    pub planarity: f64,
    /// Check that contours are simple and disjoint. Default true; the check
    /// costs O(n log n) per section.
    pub check_intersections: bool,
}

impl Default for ProfileOptions {
    fn default() -> Self {
        ProfileOptions { planarity: 1e-6, check_intersections: true }
    }
}

/// One closed polygon of a section.
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    /// World positions, duplicates removed, in file order.
    pub points: Vec<[f64; 3]>,
    /// The same points in the stack frame's `(u, v)` coordinates.
    pub uv: Vec<P2>,
    /// Line of the `section` or `contour` keyword that starts it (from a
    /// DICOM RT structure set: its item number in the ROI's Contour
    /// Sequence, 1-based).
    pub line: u64,
}

/// One cross-section: its contours and its offset along the stack normal.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// 0-based position in the stack.
    pub index: usize,
    /// Line of the `section` keyword (from DICOM: its first contour's
    /// item number).
    pub line: u64,
    /// Position of the section's plane along [`StackFrame::n`].
    pub offset: f64,
    /// Its contours, in file order.
    pub contours: Vec<Contour>,
}

impl Section {
    /// Total number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.contours.iter().map(|c| c.points.len()).sum()
    }

    /// The same contours in the parallel plane at `offset` along
    /// `frame.n` (the frame the section was read in): same `(u, v)`, points
    /// moved along the normal (exactly for axis-aligned frames).
    pub fn moved(&self, frame: &StackFrame, offset: f64) -> Section {
        let contours = self
            .contours
            .iter()
            .map(|c| Contour { points: c.uv.iter().map(|&q| frame.unproject(q, offset)).collect(), uv: c.uv.clone(), line: c.line })
            .collect();
        Section { index: self.index, line: self.line, offset, contours }
    }

    /// The area of the section's solid: each contour's area counts with its
    /// nesting depth (even-odd: outer boundaries add, holes subtract,
    /// islands in holes add again). Contours are disjoint, so one vertex
    /// decides what contains what.
    pub fn solid_area(&self) -> f64 {
        let cs = &self.contours;
        (0..cs.len())
            .map(|i| {
                let depth = (0..cs.len()).filter(|&j| j != i && crate::geom2d::inside(&cs[j].uv, cs[i].uv[0])).count();
                let a = crate::geom2d::signed_area(&cs[i].uv).abs();
                if depth % 2 == 0 {
                    a
                } else {
                    -a
                }
            })
            .sum()
    }
}

/// The planimetric volume of a stack, section by section: the sum of each
/// section's [`solid_area`](Section::solid_area) times its thickness, the
/// clinical convention. A section's thickness is half the distance to the
/// previous section plus half the distance to the next one; an end section
/// counts its one neighbour's distance in full. For evenly spaced sections
/// this is the sum of the areas times the spacing. A one-section stack has
/// no thickness (volume 0).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Planimeter {
    /// The previous section's offset and area, and its distance to the one
    /// before it.
    prev: Option<(f64, f64, Option<f64>)>,
    sum: f64,
}

impl Planimeter {
    /// Adds the next section (in stack order).
    pub fn add(&mut self, s: &Section) {
        let area = s.solid_area();
        if let Some((po, pa, before)) = self.prev {
            let gap = (s.offset - po).abs();
            self.sum += pa * 0.5 * (before.unwrap_or(gap) + gap);
            self.prev = Some((s.offset, area, Some(gap)));
        } else {
            self.prev = Some((s.offset, area, None));
        }
    }

    /// The volume of the sections added.
    pub fn volume(&self) -> f64 {
        match self.prev {
            Some((_, pa, Some(gap))) => self.sum + pa * gap,
            _ => self.sum,
        }
    }
}

/// A right-handed orthonormal frame `(u, v, n)`; `n` is the stack axis.
/// Axis-aligned stacks use exact coordinate copies (no rounding).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StackFrame {
    /// First in-plane axis.
    pub u: [f64; 3],
    /// Second in-plane axis, `n × u`.
    pub v: [f64; 3],
    /// The stack axis; sections come in increasing order along it.
    pub n: [f64; 3],
    /// For axis-aligned stacks: world axes of `u`, `v`, `n` and the sign of `n`.
    axes: Option<(usize, usize, usize, f64)>,
}

impl StackFrame {
    /// The frame whose normal is `+axis` (`sign > 0`) or `-axis`.
    pub fn axis(axis: usize, sign: f64) -> StackFrame {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let (iu, iv) = if sign > 0.0 { (a, b) } else { (b, a) };
        let e = |i: usize| {
            let mut x = [0.0; 3];
            x[i] = 1.0;
            x
        };
        let mut n = e(axis);
        n[axis] = sign.signum();
        StackFrame { u: e(iu), v: e(iv), n, axes: Some((iu, iv, axis, sign.signum())) }
    }

    /// A frame around the unit normal `n` (any direction).
    pub fn around(n: [f64; 3]) -> StackFrame {
        // Unit vectors by dividing by the length (not glam's normalize,
        // which multiplies by the reciprocal and rounds differently).
        let n = DVec3::from(n);
        let n = n / n.length();
        let k = (0..3).min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs())).unwrap();
        let mut e = DVec3::ZERO;
        e[k] = 1.0;
        let u = n.cross(e);
        let u = u / u.length();
        let v = n.cross(u);
        StackFrame { u: u.to_array(), v: v.to_array(), n: n.to_array(), axes: None }
    }

    /// The same planes with the normal reversed: `(v, u, -n)`.
    pub fn flipped(&self) -> StackFrame {
        StackFrame {
            u: self.v,
            v: self.u,
            n: (-DVec3::from(self.n)).to_array(),
            axes: self.axes.map(|(iu, iv, d, s)| (iv, iu, d, -s)),
        }
    }

    /// `(u, v)` coordinates and offset along `n` of a world point.
    #[inline]
    pub fn project(&self, p: [f64; 3]) -> (P2, f64) {
        match self.axes {
            Some((iu, iv, d, s)) => ([p[iu], p[iv]], if s > 0.0 { p[d] } else { -p[d] }),
            None => {
                let p = DVec3::from(p);
                ([p.dot(self.u.into()), p.dot(self.v.into())], p.dot(self.n.into()))
            }
        }
    }

    /// The world point at `(u, v)` and offset `s`.
    #[inline]
    pub fn unproject(&self, uv: P2, s: f64) -> [f64; 3] {
        match self.axes {
            Some((iu, iv, d, sg)) => {
                let mut p = [0.0; 3];
                p[iu] = uv[0];
                p[iv] = uv[1];
                p[d] = if sg > 0.0 { s } else { -s };
                p
            }
            None => (uv[0] * DVec3::from(self.u) + uv[1] * DVec3::from(self.v) + s * DVec3::from(self.n)).to_array(),
        }
    }
}

/// Newell's normal of a closed polygon (twice its vector area).
pub fn newell(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len();
    let mut s = [0.0; 3];
    let o = DVec3::from(points[0]);
    for i in 0..n {
        let (p, q) = (DVec3::from(points[i]) - o, DVec3::from(points[(i + 1) % n]) - o);
        s[0] += (p[1] - q[1]) * (p[2] + q[2]);
        s[1] += (p[2] - q[2]) * (p[0] + q[0]);
        s[2] += (p[0] - q[0]) * (p[1] + q[1]);
    }
    s
}

/// Counters of a read.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct ReadStats {
    /// Sections returned.
    pub sections: u64,
    /// Contours returned.
    pub contours: u64,
    /// Vertices returned (after removing duplicates).
    pub vertices: u64,
    /// Repeated vertices dropped (closing repeats and consecutive duplicates).
    pub duplicates_removed: u64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok {
    Section,
    Contour,
    Num(f64),
}

struct RawContour {
    line: u64,
    points: Vec<[f64; 3]>,
    lines: Vec<u64>,
}

/// Streams a profile one validated [`Section`] at a time; see the module docs.
pub struct ProfileReader<R: BufRead> {
    src: R,
    path: PathBuf,
    opts: ProfileOptions,
    /// Current line number (1-based) and its text, comments removed.
    line: u64,
    text: String,
    raw: Vec<u8>,
    tokens: Vec<(usize, usize)>,
    cursor: usize,
    header: bool,
    /// Line of a `section` keyword already consumed.
    pending: Option<u64>,
    raw_sections: usize,
    frame: Option<StackFrame>,
    /// Sections validated but not yet returned.
    ready: VecDeque<Section>,
    last_offset: Option<f64>,
    stats: ReadStats,
}

impl<R: BufRead> ProfileReader<R> {
    /// A reader over `src`; `path` names the file in errors.
    pub fn new(src: R, path: &Path, opts: ProfileOptions) -> ProfileReader<R> {
        ProfileReader {
            src,
            path: path.to_path_buf(),
            opts,
            line: 0,
            text: String::new(),
            raw: Vec::new(),
            tokens: Vec::new(),
            cursor: 0,
            header: false,
            pending: None,
            raw_sections: 0,
            frame: None,
            ready: VecDeque::new(),
            last_offset: None,
            stats: ReadStats::default(),
        }
    }

    /// The stack frame, once the first section has been read.
    pub fn frame(&self) -> Option<StackFrame> {
        self.frame
    }

    /// Counters so far.
    pub fn stats(&self) -> ReadStats {
        self.stats
    }

    fn err(&self, kind: K, line: u64, msg: impl Into<String>) -> ProfileError {
        ProfileError::new(kind, &self.path, line, msg)
    }

    /// The next token, reading lines as needed; `None` at the end.
    fn next_tok(&mut self) -> Result<Option<Tok>, crate::ContourError> {
        loop {
            if self.cursor < self.tokens.len() {
                let (a, b) = self.tokens[self.cursor];
                self.cursor += 1;
                let tok = &self.text[a..b];
                if !self.header {
                    if tok != "pro" {
                        return Err(self.err(K::Syntax, self.line, format!("not a profile file: expected the header 'pro', found '{}'", show(tok))).into());
                    }
                    self.header = true;
                    // Comments are allowed from here on: drop this line's rest after '#'.
                    let rest_start = b;
                    if let Some(h) = self.text[rest_start..].find('#') {
                        let cut = rest_start + h;
                        self.tokens.retain(|&(s, _)| s < cut);
                    }
                    continue;
                }
                return match tok {
                    "section" => Ok(Some(Tok::Section)),
                    "contour" => Ok(Some(Tok::Contour)),
                    "pro" => Err(self.err(K::Syntax, self.line, "unexpected 'pro': the header appears once, at the start").into()),
                    _ => match tok.parse::<f64>() {
                        Ok(x) if x.is_finite() => Ok(Some(Tok::Num(x))),
                        Ok(_) => Err(self.err(K::Syntax, self.line, format!("coordinate '{}' is not a finite number", show(tok))).into()),
                        Err(_) => Err(self
                            .err(K::Syntax, self.line, format!("expected a number, 'section' or 'contour', found '{}'", show(tok)))
                            .into()),
                    },
                };
            }
            self.raw.clear();
            let n = self.src.read_until(b'\n', &mut self.raw).map_err(|e| crate::ContourError::io(&self.path, "cannot read", e))?;
            if n == 0 {
                return Ok(None);
            }
            self.line += 1;
            self.text.clear();
            match std::str::from_utf8(&self.raw) {
                Ok(s) => self.text.push_str(s),
                Err(_) => return Err(self.err(K::Syntax, self.line, "the line is not valid UTF-8 text").into()),
            }
            let body = if self.header {
                match self.text.find('#') {
                    Some(h) => h,
                    None => self.text.len(),
                }
            } else {
                self.text.len()
            };
            self.tokens.clear();
            self.cursor = 0;
            let bytes = self.text.as_bytes();
            let mut i = 0;
            while i < body {
                while i < body && bytes[i].is_ascii_whitespace() {
                    i += 1;
                }
                let s = i;
                while i < body && !bytes[i].is_ascii_whitespace() {
                    i += 1;
                }
                if i > s {
                    self.tokens.push((s, i));
                }
            }
        }
    }

    /// Parses the next section's raw contours, or `None` at the end.
    fn read_raw(&mut self) -> Result<Option<(u64, Vec<RawContour>)>, crate::ContourError> {
        let line = match self.pending.take() {
            Some(l) => l,
            None => match self.next_tok()? {
                None => {
                    if self.raw_sections == 0 {
                        let what = if self.header { "the profile has no sections" } else { "empty file: expected the header 'pro'" };
                        return Err(self.err(K::Syntax, self.line.max(1), what).into());
                    }
                    return Ok(None);
                }
                Some(Tok::Section) => self.line,
                Some(Tok::Contour) => return Err(self.err(K::Syntax, self.line, "'contour' before the first 'section'").into()),
                Some(Tok::Num(_)) => return Err(self.err(K::Syntax, self.line, "a vertex before the first 'section'").into()),
            },
        };
        self.raw_sections += 1;
        let mut contours = vec![RawContour { line, points: Vec::new(), lines: Vec::new() }];
        let mut xyz = [0.0; 3];
        let mut have = 0;
        let mut vline = 0;
        loop {
            let tok = self.next_tok()?;
            if have != 0 && !matches!(tok, Some(Tok::Num(_))) {
                return Err(self.err(K::Syntax, vline, format!("a vertex needs 3 coordinates, found {have}")).into());
            }
            match tok {
                None => break,
                Some(Tok::Num(x)) => {
                    if have == 0 {
                        vline = self.line;
                    }
                    xyz[have] = x;
                    have += 1;
                    if have == 3 {
                        let c = contours.last_mut().unwrap();
                        c.points.push(xyz);
                        c.lines.push(vline);
                        have = 0;
                    }
                }
                Some(Tok::Contour) => contours.push(RawContour { line: self.line, points: Vec::new(), lines: Vec::new() }),
                Some(Tok::Section) => {
                    self.pending = Some(self.line);
                    break;
                }
            }
        }
        Ok(Some((line, contours)))
    }

    /// The next validated section, or `None` after the last one.
    pub fn next_section(&mut self) -> Result<Option<Section>, crate::ContourError> {
        loop {
            if let Some(s) = self.ready.pop_front() {
                self.stats.sections += 1;
                self.stats.contours += s.contours.len() as u64;
                self.stats.vertices += s.vertex_count() as u64;
                return Ok(Some(s));
            }
            let Some((line, raw)) = self.read_raw()? else {
                return Ok(None);
            };
            let index = self.raw_sections - 1;
            let section = self.validate(index, line, raw)?;
            match index {
                0 => {
                    // Hold it: peek the next section first.
                    let first = section;
                    match self.read_raw()? {
                        None => {
                            self.last_offset = Some(first.offset);
                            self.ready.push_back(first);
                        }
                        Some((l2, raw2)) => {
                            let mut second = self.validate(1, l2, raw2)?;
                            let mut first = first;
                            if second.offset == first.offset {
                                return Err(self
                                    .err(K::OutOfOrder, l2, "section lies in the same plane as the previous one (sections must be ordered along the stack axis)")
                                    .into());
                            }
                            if second.offset < first.offset {
                                // Sections come in decreasing order: reverse the normal.
                                let f = self.frame.unwrap().flipped();
                                self.frame = Some(f);
                                for s in [&mut first, &mut second] {
                                    s.offset = -s.offset;
                                    for c in &mut s.contours {
                                        for q in &mut c.uv {
                                            *q = [q[1], q[0]];
                                        }
                                    }
                                }
                            }
                            self.last_offset = Some(second.offset);
                            self.ready.push_back(first);
                            self.ready.push_back(second);
                        }
                    }
                }
                _ => {
                    let last = self.last_offset.unwrap();
                    if section.offset <= last {
                        let why = if section.offset == last { "lies in the same plane as the previous one" } else { "comes before the previous one" };
                        return Err(self
                            .err(
                                K::OutOfOrder,
                                line,
                                format!("section {} {why} along the stack axis (offset {} after {}): sections must be ordered", index, section.offset, last),
                            )
                            .into());
                    }
                    self.last_offset = Some(section.offset);
                    self.ready.push_back(section);
                }
            }
        }
    }

    /// Checks one raw section and projects it.
    fn validate(&mut self, index: usize, line: u64, raw: Vec<RawContour>) -> Result<Section, crate::ContourError> {
        // Drop repeated vertices; at least 3 must remain.
        let mut contours: Vec<RawContour> = Vec::with_capacity(raw.len());
        for mut c in raw {
            let before = c.points.len();
            let mut k = 0;
            for i in 0..c.points.len() {
                if k > 0 && c.points[i] == c.points[k - 1] {
                    continue;
                }
                c.points[k] = c.points[i];
                c.lines[k] = c.lines[i];
                k += 1;
            }
            while k > 1 && c.points[k - 1] == c.points[0] {
                k -= 1;
            }
            c.points.truncate(k);
            c.lines.truncate(k);
            self.stats.duplicates_removed += (before - k) as u64;
            if k < 3 {
                return Err(self
                    .err(K::TooFewVertices, c.line, format!("a contour needs at least 3 distinct vertices, this one has {k}"))
                    .into());
            }
            contours.push(c);
        }
        // The frame comes from the first section.
        let frame = match self.frame {
            Some(f) => f,
            None => {
                let p0 = contours[0].points[0];
                let axis = (0..3).find(|&d| contours.iter().all(|c| c.points.iter().all(|p| p[d] == p0[d])));
                let f = match axis {
                    Some(d) => StackFrame::axis(d, 1.0),
                    None => {
                        let n = contours
                            .iter()
                            .map(|c| newell(&c.points))
                            .max_by(|&a, &b| DVec3::from(a).length_squared().total_cmp(&DVec3::from(b).length_squared()))
                            .unwrap();
                        if !(DVec3::from(n).length_squared() > 0.0) {
                            return Err(self
                                .err(K::NonPlanar, contours[0].line, "the first section's contours have no area (their vertices are collinear)")
                                .into());
                        }
                        StackFrame::around(n)
                    }
                };
                self.frame = Some(f);
                f
            }
        };
        // Project; check planarity against the section's mid plane.
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for c in &contours {
            for p in &c.points {
                for d in 0..3 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
        }
        let diag = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
        let tol = self.opts.planarity * diag;
        let mut out = Section { index, line, offset: 0.0, contours: Vec::with_capacity(contours.len()) };
        let mut offs: Vec<Vec<f64>> = Vec::with_capacity(contours.len());
        let (mut smin, mut smax) = (f64::INFINITY, f64::NEG_INFINITY);
        for c in &contours {
            let mut uv = Vec::with_capacity(c.points.len());
            let mut o = Vec::with_capacity(c.points.len());
            for (k, &p) in c.points.iter().enumerate() {
                let (q, s) = frame.project(p);
                if !(q[0].is_finite() && q[1].is_finite() && s.is_finite()) {
                    let l = c.lines.get(k).copied().unwrap_or(c.line);
                    return Err(self.err(K::Syntax, l, format!("vertex ({}, {}, {}) is too large: its coordinates along the stack's axes overflow", p[0], p[1], p[2])).into());
                }
                uv.push(q);
                o.push(s);
                smin = smin.min(s);
                smax = smax.max(s);
            }
            offs.push(o);
            out.contours.push(Contour { points: c.points.clone(), uv, line: c.line });
        }
        let mid = 0.5 * (smin + smax);
        if smax - smin > 2.0 * tol {
            // Find the culprit: a tilted planar contour, a bent one, or a
            // contour in another plane than the first one.
            for (ci, c) in contours.iter().enumerate() {
                let (cmin, cmax) = offs[ci].iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &s| (a.min(s), b.max(s)));
                if cmax - cmin <= 2.0 * tol {
                    continue;
                }
                let own = DVec3::from(newell(&c.points));
                let ln = own.length();
                let centre = c.points.iter().fold(DVec3::ZERO, |s, &p| s + DVec3::from(p)) / c.points.len() as f64;
                let own_planar = ln > 0.0 && c.points.iter().all(|&p| ((DVec3::from(p) - centre).dot(own) / ln).abs() <= tol);
                if own_planar && index > 0 {
                    let cosang = (own.dot(DVec3::from(frame.n)) / ln).abs().min(1.0);
                    return Err(self
                        .err(
                            K::NotParallel,
                            c.line,
                            format!(
                                "contour is planar but not parallel to the first section (tilted by {:.3} degrees): sections must be cut by parallel planes",
                                cosang.acos().to_degrees()
                            ),
                        )
                        .into());
                }
                // The vertex farthest from the median plane is the odd one out.
                let mut sorted = offs[ci].clone();
                sorted.sort_by(f64::total_cmp);
                let median = sorted[sorted.len() / 2];
                let (k, dev) = offs[ci].iter().enumerate().map(|(k, &s)| (k, (s - median).abs())).fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
                return Err(self
                    .err(
                        K::NonPlanar,
                        c.line,
                        format!(
                            "contour is not planar: its vertex at line {} is {dev:.6e} away from the plane of the others (tolerance {tol:.3e})",
                            c.lines[k]
                        ),
                    )
                    .into());
            }
            // Each contour is flat, but not all in one plane.
            let first = 0.5 * offs[0].iter().fold(f64::INFINITY, |a, &b| a.min(b)) + 0.5 * offs[0].iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
            let (ci, dev) = offs
                .iter()
                .enumerate()
                .map(|(ci, o)| (ci, (o[0] - first).abs()))
                .fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
            return Err(self
                .err(
                    K::NonPlanar,
                    contours[ci].line,
                    format!("contour lies {dev:.6e} away from the plane of its section's first contour (tolerance {tol:.3e}): a section is one plane"),
                )
                .into());
        }
        out.offset = mid;
        if self.opts.check_intersections {
            let polys: Vec<&[P2]> = out.contours.iter().map(|c| c.uv.as_slice()).collect();
            if let Some(((c1, e1), (c2, e2))) = first_crossing(&polys) {
                let (l1, l2) = (contours[c1].lines[e1], contours[c2].lines[e2]);
                let e = if c1 == c2 {
                    self.err(
                        K::SelfIntersecting,
                        contours[c1].line,
                        format!("contour is self-intersecting: its edges starting at lines {l1} and {l2} cross or touch"),
                    )
                } else {
                    self.err(
                        K::SelfIntersecting,
                        contours[c2].line,
                        format!(
                            "contours starting at lines {} and {} cross or touch (edges from lines {l1} and {l2}): contours of a section must be disjoint",
                            contours[c1].line, contours[c2].line
                        ),
                    )
                };
                return Err(e.into());
            }
        }
        Ok(out)
    }
}

fn show(tok: &str) -> String {
    let t: String = tok.chars().take(40).collect();
    if t.len() < tok.len() {
        format!("{t}...")
    } else {
        t
    }
}

/// Writes a profile: header, optional comment lines, then sections.
pub struct ProfileWriter<W: Write> {
    out: W,
    sections: u64,
}

impl<W: Write> ProfileWriter<W> {
    /// Writes the header and one `# ` line per comment.
    pub fn new(mut out: W, comments: &[String]) -> std::io::Result<ProfileWriter<W>> {
        out.write_all(b"pro\n")?;
        for c in comments {
            writeln!(out, "# {}", c.replace(['\n', '\r'], " "))?;
        }
        Ok(ProfileWriter { out, sections: 0 })
    }

    /// Writes one section (at least one contour, each of 3+ vertices).
    pub fn section(&mut self, contours: &[Vec<[f64; 3]>]) -> std::io::Result<()> {
        let mut buf = String::with_capacity(64 * contours.iter().map(|c| c.len()).sum::<usize>() + 32);
        for (i, c) in contours.iter().enumerate() {
            buf.push_str(if i == 0 { "section\n" } else { "contour\n" });
            for p in c {
                push_num(&mut buf, p[0]);
                buf.push(' ');
                push_num(&mut buf, p[1]);
                buf.push(' ');
                push_num(&mut buf, p[2]);
                buf.push('\n');
            }
        }
        self.sections += 1;
        self.out.write_all(buf.as_bytes())
    }

    /// Sections written.
    pub fn sections(&self) -> u64 {
        self.sections
    }

    /// Flushes and returns the inner writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// The shortest decimal that reads back as the same f64; exponent notation
/// for very large or small magnitudes.
fn push_num(buf: &mut String, x: f64) {
    use std::fmt::Write as _;
    let a = x.abs();
    if a == 0.0 || (1e-5..1e16).contains(&a) {
        let _ = write!(buf, "{x}");
    } else {
        let _ = write!(buf, "{x:e}");
    }
}

/// Reads a whole profile into memory (tests and small stacks).
pub fn read_all(text: &[u8], path: &Path, opts: ProfileOptions) -> Result<(StackFrame, Vec<Section>), crate::ContourError> {
    let mut r = ProfileReader::new(text, path, opts);
    let mut v = Vec::new();
    while let Some(s) = r.next_section()? {
        v.push(s);
    }
    Ok((r.frame().expect("a profile with sections has a frame"), v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ContourError;

    fn read(s: &str) -> Result<Vec<Section>, ContourError> {
        read_all(s.as_bytes(), Path::new("t.pro"), ProfileOptions::default()).map(|r| r.1)
    }

    fn err(s: &str) -> ProfileError {
        match read(s) {
            Err(ContourError::Profile(e)) => e,
            other => panic!("expected a profile error, got {other:?}"),
        }
    }

    /// Found by fuzzing: a vertex whose coordinates overflow in the stack
    /// frame gave non-finite (u, v); now a one-line error naming its line.
    #[test]
    fn vertices_overflowing_the_stack_frame_are_refused() {
        let e = err("pro\nsection\n4 2\n9e216 0. 2 1 1 -2 2");
        assert_eq!(e.kind, K::Syntax);
        assert!(e.to_string().contains("too large"), "{e}");
    }

    #[test]
    fn a_two_section_stack_with_a_hole_reads_back() {
        let s = read("pro # header comment\nsection\n0 0 0 4 0 0 4 4 0 0 4 0\ncontour # hole\n1 1 0\n2 1 0\n2 2 0\n\nsection\n0 0 +1e0 4 0 1 4 4 1 0 4 1 0 0 1\n").unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].contours.len(), 2);
        assert_eq!(s[0].contours[1].line, 4);
        assert_eq!((s[0].offset, s[1].offset), (0.0, 1.0));
        // The closing repeat was dropped.
        assert_eq!(s[1].contours[0].points.len(), 4);
        assert_eq!(s[0].contours[0].uv[2], [4.0, 4.0]);
    }

    #[test]
    fn decreasing_sections_flip_the_frame_and_keep_handedness() {
        let (f, s) = read_all(b"pro\nsection 0 0 5 1 0 5 0 1 5\nsection 0 0 2 1 0 2 0 1 2\nsection 0 0 -1 1 0 -1 0 1 -1", Path::new("t.pro"), ProfileOptions::default()).unwrap();
        assert_eq!(f.n, [0.0, 0.0, -1.0]);
        assert_eq!(DVec3::from(f.u).cross(DVec3::from(f.v)).to_array(), f.n);
        assert_eq!(s.iter().map(|s| s.offset).collect::<Vec<_>>(), vec![-5.0, -2.0, 1.0]);
        assert_eq!(s[0].contours[0].uv[1], [0.0, 1.0]);
        assert_eq!(f.unproject(s[0].contours[0].uv[1], s[0].offset), [1.0, 0.0, 5.0]);
    }

    #[test]
    fn tilted_stacks_use_a_general_frame() {
        // Planes x + z = c.
        let (f, s) = read_all(b"pro\nsection 0 0 0 1 0 -1 0 1 0\nsection 0 0 1 1 0 0 0 1 1", Path::new("t.pro"), ProfileOptions::default()).unwrap();
        assert!((f.n[0] - f.n[2]).abs() < 1e-15 && f.n[0] > 0.0);
        assert!(s[1].offset > s[0].offset);
        let back = f.unproject(s[1].contours[0].uv[2], s[1].offset);
        assert!((back[0]).abs() < 1e-12 && (back[1] - 1.0).abs() < 1e-12 && (back[2] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_profiles_name_the_line() {
        let e = err("prx\nsection 0 0 0");
        assert_eq!((e.kind, e.line), (K::Syntax, 1));
        assert_eq!(e.to_string(), "t.pro: not a profile file: expected the header 'pro', found 'prx' (line 1)");
        let e = err("pro\n");
        assert_eq!(e.to_string(), "t.pro: the profile has no sections (line 1)");
        let e = err("pro\nsection\n0 0 0\n1 0 0\n1 x 0\n");
        assert_eq!(e.to_string(), "t.pro: expected a number, 'section' or 'contour', found 'x' (line 5)");
        let e = err("pro\nsection\n0 0 0 1 0 0 1 1\ncontour 0 0 0");
        assert_eq!(e.to_string(), "t.pro: a vertex needs 3 coordinates, found 2 (line 3)");
        let e = err("pro\n1 2 3\n");
        assert_eq!((e.kind, e.line), (K::Syntax, 2));
        let e = err("pro\nsection 0 0 0 1 0 0 1 1 0\ncontour\n5 5 0 6 5 0\n");
        assert_eq!((e.kind, e.line), (K::TooFewVertices, 3));
        assert_eq!(e.message, "a contour needs at least 3 distinct vertices, this one has 2");
        let e = err("pro\nsection 0 0 0 1 0 0 1 0 0 0 0 0\n");
        assert_eq!((e.kind, e.line), (K::TooFewVertices, 2));
        let e = err("pro\nsection\n0 0 0\n2 0 0\n2 2 0\n1 3 0.5\n0 2 0\n");
        assert_eq!((e.kind, e.line), (K::NonPlanar, 2));
        assert!(e.message.starts_with("contour is not planar: its vertex at line "), "{}", e.message);
        // Along an axis-aligned stack the odd vertex is named exactly.
        let e = err("pro\nsection 0 0 0 1 0 0 0 1 0\nsection\n0 0 1\n2 0 1\n2 2 1\n1 3 1.5\n0 2 1\n");
        assert_eq!((e.kind, e.line), (K::NonPlanar, 3));
        assert!(e.message.starts_with("contour is not planar: its vertex at line 7 is 5.0"), "{}", e.message);
        let e = err("pro\nsection\n0 0 0\n2 0 0\n0 2 0\n2 2 0\n");
        assert_eq!((e.kind, e.line), (K::SelfIntersecting, 2));
        assert!(e.message.contains("lines 4 and 6"), "{}", e.message);
        let e = err("pro\nsection 0 0 0 4 0 0 0 4 0\ncontour\n1 1 0 5 1 0 1 5 0\n");
        assert_eq!((e.kind, e.line), (K::SelfIntersecting, 3));
        let e = err("pro\nsection 0 0 0 1 0 0 0 1 0\nsection 0 0 2 1 0 2 0 1 2\nsection 0 0 1 1 0 1 0 1 1\n");
        assert_eq!((e.kind, e.line), (K::OutOfOrder, 4));
        let e = err("pro\nsection 0 0 0 1 0 0 0 1 0\nsection 0 0 0 1 0 0 0 1 0\n");
        assert_eq!((e.kind, e.line), (K::OutOfOrder, 3));
        let e = err("pro\nsection 0 0 0 1 0 0 0 1 0\nsection 0 0 1 1 0 1.5 0 1 1\n");
        assert_eq!((e.kind, e.line), (K::NotParallel, 3));
        let e = err("pro\nsection 0 0 0 1 0 0 0 1 0\ncontour 5 5 1 6 5 1 5 6 1\n");
        assert_eq!((e.kind, e.line), (K::NonPlanar, 3));
        let e = err("pro\nsection 0 0 0 1 0 0 0 1 inf\n");
        assert_eq!(e.message, "coordinate 'inf' is not a finite number");
        let e = err("# comment first\npro\n");
        assert_eq!((e.kind, e.line), (K::Syntax, 1));
    }

    #[test]
    fn writer_output_reads_back_exactly() {
        let c1 = vec![[0.1, 0.2, 1e-7], [1.0 / 3.0, 0.0, 1e-7], [0.0, 2e20, 1e-7]];
        let mut w = ProfileWriter::new(Vec::new(), &["made in a test".into()]).unwrap();
        w.section(std::slice::from_ref(&c1)).unwrap();
        let text = w.finish().unwrap();
        let s = read(std::str::from_utf8(&text).unwrap()).unwrap();
        assert_eq!(s[0].contours[0].points, c1);
    }
}
