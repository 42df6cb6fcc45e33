//! The CSG scene format of `mint csg`: a JSON document describing a tree of
//! primitives and meshes combined by booleans, with transforms. A small
//! parser of our own keeps the line of every value, so that every error
//! names the line and the key ("scene.json:7: key 'radius': must be > 0").
//!
//! ```json
//! { "defs": { "hole": { "cylinder": { "radius": 0.3, "height": 3 } } },
//!   "scene": { "difference": [
//!       { "box": { "size": [2, 2, 2] }, "rotate": [0, 0, 30] },
//!       { "sphere": { "radius": 1.2 }, "translate": [0.5, 0, 0] },
//!       { "ref": "hole" },
//!       { "mesh": "part.ply", "scale": 0.5 } ] } }
//! ```
//! A node is an object with exactly one shape or operator key:
//! - `union`, `intersection`, `difference`: an array of nodes (n-ary;
//!   difference is the first minus all the others);
//! - `sphere {radius}`, `box {size: [x,y,z]}` (centred), `cylinder {radius,
//!   height}` (around z, centred), `cone {radius, height}` (base at z = 0, apex
//!   at z = height), `torus {major, minor}` (around z), `halfspace {normal,
//!   offset}` (the points p with normal·p <= offset);
//! - `mesh`: a path to a closed mesh file, relative to the scene file;
//! - `volume {file, iso}` (or `{file, label}`): a voxel volume's iso-surface
//!   (or a label's boundary), placed by its own header in its world frame
//!   (axis-aligned volumes only; no transform), sampled trilinearly on the
//!   scene's grid;
//! - `ref`: the name of an entry of the top-level `defs` (cycles are errors).
//! Optional keys on any node, applied in this order: `scale` (a number or
//! three), `rotate` (degrees about x, then y, then z), `translate`.
//! The top level is either a node or an object with `scene` (and `defs`).

use mint_core::primitives::{Primitive, Shape, Transform};
use mint_core::expr::{BoolOp, Expr};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A parsed scene: an expression over numbered operands.
#[derive(Debug, Clone)]
pub struct Scene {
    pub expr: Expr,
    pub operands: Vec<Operand>,
}

/// One leaf of a scene.
#[derive(Debug, Clone)]
pub enum Operand {
    Primitive(Primitive),
    /// One surface, given as one or more files (in the engine's order).
    Mesh { paths: Vec<PathBuf>, transform: Transform },
    /// A voxel volume's iso-surface (`mint volume`), in the volume's own
    /// frame (see `crate::volume`).
    Volume(Box<VolumeJob>),
}

/// A scene error: `file:line: message`.
#[derive(Debug, thiserror::Error)]
#[error("{path}:{line}: {}", one_line(message))]
pub struct SceneError {
    pub path: PathBuf,
    pub line: usize,
    pub message: String,
}

/// `s` with control characters escaped (`\n`, `\r`, `\u{0}`), so that an
/// error quoting the scene's text stays one line.
fn one_line(s: &str) -> String {
    s.chars().map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() }).collect()
}

#[derive(Debug, Clone)]
enum Value {
    Null,
    Bool,
    Num(f64),
    Str(String),
    Arr(Vec<(usize, Value)>),
    Obj(Vec<(String, usize, Value)>),
}

/// The deepest nesting of nodes a scene may have (operators, transforms'
/// nodes and `ref`s followed, counted from the root): deeper scenes are
/// refused with one line naming the limit and the line, instead of
/// overflowing the stack.
pub const MAX_SCENE_DEPTH: usize = 256;

/// The deepest nesting of JSON values (objects and arrays) the scene parser
/// reads: room for [`MAX_SCENE_DEPTH`] nodes (an operator's node and its
/// array are two levels each).
pub const MAX_JSON_DEPTH: usize = 2 * MAX_SCENE_DEPTH + 8;

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    line: usize,
    depth: usize,
}

impl Parser<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() {
            match self.s[self.i] {
                b'\n' => {
                    self.line += 1;
                    self.i += 1
                }
                b' ' | b'\t' | b'\r' => self.i += 1,
                _ => break,
            }
        }
    }
    fn err<T>(&self, m: impl Into<String>) -> Result<T, (usize, String)> {
        Err((self.line, m.into()))
    }
    fn value(&mut self) -> Result<(usize, Value), (usize, String)> {
        if self.depth >= MAX_JSON_DEPTH {
            self.ws();
            return self.err(format!("the scene nests JSON values deeper than {MAX_JSON_DEPTH} levels (mint's limit: at most {MAX_SCENE_DEPTH} nested nodes)"));
        }
        self.depth += 1;
        let v = self.value_inner();
        self.depth -= 1;
        v
    }
    fn value_inner(&mut self) -> Result<(usize, Value), (usize, String)> {
        self.ws();
        let line = self.line;
        let Some(&c) = self.s.get(self.i) else { return self.err("unexpected end of file") };
        let v = match c {
            b'{' => {
                self.i += 1;
                let mut items = Vec::new();
                self.ws();
                if self.s.get(self.i) == Some(&b'}') {
                    self.i += 1;
                } else {
                    loop {
                        self.ws();
                        let kl = self.line;
                        let Value::Str(k) = self.value()?.1 else { return Err((kl, "expected a key in quotes".into())) };
                        self.ws();
                        if self.s.get(self.i) != Some(&b':') {
                            return self.err(format!("expected ':' after key '{k}'"));
                        }
                        self.i += 1;
                        let (vl, v) = self.value()?;
                        items.push((k, vl, v));
                        self.ws();
                        match self.s.get(self.i) {
                            Some(b',') => self.i += 1,
                            Some(b'}') => {
                                self.i += 1;
                                break;
                            }
                            _ => return self.err("expected ',' or '}'"),
                        }
                    }
                }
                Value::Obj(items)
            }
            b'[' => {
                self.i += 1;
                let mut items = Vec::new();
                self.ws();
                if self.s.get(self.i) == Some(&b']') {
                    self.i += 1;
                } else {
                    loop {
                        items.push(self.value()?);
                        self.ws();
                        match self.s.get(self.i) {
                            Some(b',') => self.i += 1,
                            Some(b']') => {
                                self.i += 1;
                                break;
                            }
                            _ => return self.err("expected ',' or ']'"),
                        }
                    }
                }
                Value::Arr(items)
            }
            b'"' => {
                self.i += 1;
                let start = self.i;
                while self.i < self.s.len() && self.s[self.i] != b'"' {
                    if self.s[self.i] == b'\n' {
                        return self.err("newline inside a string");
                    }
                    self.i += 1;
                }
                if self.i >= self.s.len() {
                    return self.err("unterminated string");
                }
                let v = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                self.i += 1;
                Value::Str(v)
            }
            b't' if self.s[self.i..].starts_with(b"true") => {
                self.i += 4;
                Value::Bool
            }
            b'f' if self.s[self.i..].starts_with(b"false") => {
                self.i += 5;
                Value::Bool
            }
            b'n' if self.s[self.i..].starts_with(b"null") => {
                self.i += 4;
                Value::Null
            }
            _ => {
                let start = self.i;
                while self.i < self.s.len() && matches!(self.s[self.i], b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E') {
                    self.i += 1;
                }
                let t = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
                match t.parse::<f64>() {
                    Ok(x) if x.is_finite() => Value::Num(x),
                    _ => return self.err(format!("unexpected '{}'", &String::from_utf8_lossy(&self.s[start..(start + 12).min(self.s.len())]))),
                }
            }
        };
        Ok((line, v))
    }
}

struct Builder<'a> {
    path: &'a Path,
    base: PathBuf,
    defs: Vec<(String, usize, Value)>,
    operands: Vec<Operand>,
    stack: Vec<String>,
    depth: usize,
}

impl Builder<'_> {
    fn err<T>(&self, line: usize, m: impl Into<String>) -> Result<T, SceneError> {
        Err(SceneError { path: self.path.to_path_buf(), line, message: m.into() })
    }
    fn num(&self, line: usize, key: &str, v: &Value) -> Result<f64, SceneError> {
        match v {
            Value::Num(x) => Ok(*x),
            _ => self.err(line, format!("key '{key}': expected a number")),
        }
    }
    fn positive(&self, line: usize, key: &str, v: &Value) -> Result<f64, SceneError> {
        let x = self.num(line, key, v)?;
        if x > 0.0 {
            Ok(x)
        } else {
            self.err(line, format!("key '{key}': must be > 0, got {x}"))
        }
    }
    fn vec3(&self, line: usize, key: &str, v: &Value) -> Result<[f64; 3], SceneError> {
        match v {
            Value::Arr(a) if a.len() == 3 => {
                let mut out = [0.0; 3];
                for (k, (l, x)) in a.iter().enumerate() {
                    out[k] = self.num(*l, key, x)?;
                }
                Ok(out)
            }
            Value::Num(x) if key == "scale" => Ok([*x; 3]),
            _ => self.err(line, format!("key '{key}': expected three numbers")),
        }
    }
    fn field<'v>(&self, line: usize, shape: &str, obj: &'v Value, key: &str) -> Result<(usize, &'v Value), SceneError> {
        if let Value::Obj(items) = obj {
            for (k, l, v) in items {
                if k == key {
                    return Ok((*l, v));
                }
            }
            for (k, l, _) in items {
                if !["radius", "size", "height", "major", "minor", "normal", "offset"].contains(&k.as_str()) {
                    return self.err(*l, format!("key '{k}': unknown parameter of {shape}"));
                }
            }
            return self.err(line, format!("{shape}: missing key '{key}'"));
        }
        self.err(line, format!("key '{shape}': expected an object of parameters"))
    }

    fn node(&mut self, line: usize, v: &Value, outer: &Transform) -> Result<Expr, SceneError> {
        if self.depth >= MAX_SCENE_DEPTH {
            return self.err(line, format!("the scene nests nodes deeper than {MAX_SCENE_DEPTH} levels (mint's limit; refs count as they are followed)"));
        }
        self.depth += 1;
        let e = self.node_inner(line, v, outer);
        self.depth -= 1;
        e
    }

    fn node_inner(&mut self, line: usize, v: &Value, outer: &Transform) -> Result<Expr, SceneError> {
        let Value::Obj(items) = v else { return self.err(line, "expected a node (an object)") };
        // Transform of this node: scale, then rotate x, y, z, then translate.
        let mut local = Transform::default();
        let mut kind: Option<(&str, usize, &Value)> = None;
        for (k, l, x) in items {
            match k.as_str() {
                "scale" => {
                    let s = self.vec3(*l, k, x)?;
                    local = Transform::scale(s).ok_or(()).or_else(|_| self.err(*l, format!("key 'scale': factors must be non-zero and their product within f64's range, got {s:?}")))?.after(&local);
                }
                "rotate" => {
                    let r = self.vec3(*l, k, x)?;
                    for (axis, deg) in r.iter().enumerate() {
                        local = Transform::rotation(axis, *deg).after(&local);
                    }
                }
                "translate" => {
                    let t = self.vec3(*l, k, x)?;
                    local = Transform::translate(t).after(&local);
                }
                "union" | "intersection" | "difference" | "sphere" | "box" | "cylinder" | "cone" | "torus" | "halfspace" | "mesh" | "volume" | "ref" => {
                    if let Some((other, _, _)) = kind {
                        return self.err(*l, format!("key '{k}': a node has one shape or operator, already '{other}'"));
                    }
                    kind = Some((k.as_str(), *l, x));
                }
                _ => return self.err(*l, format!("key '{k}': unknown primitive, operator or option")),
            }
        }
        let Some((k, l, x)) = kind else { return self.err(line, "node has no shape or operator") };
        let xf = outer.after(&local);
        let prim = |shape: Shape| Primitive::new(shape, xf);
        let leaf = match k {
            "union" | "intersection" | "difference" => {
                let Value::Arr(children) = x else { return self.err(l, format!("key '{k}': expected an array of nodes")) };
                if children.is_empty() {
                    return self.err(l, format!("key '{k}': needs at least one node"));
                }
                let op = match k {
                    "union" => BoolOp::Union,
                    "intersection" => BoolOp::Intersection,
                    _ => BoolOp::Difference,
                };
                let mut c = Vec::new();
                for (cl, cv) in children {
                    c.push(self.node(*cl, cv, &xf)?);
                }
                return Ok(Expr::Op(op, c));
            }
            "ref" => {
                let Value::Str(name) = x else { return self.err(l, "key 'ref': expected a name") };
                if self.stack.contains(name) {
                    return self.err(l, format!("key 'ref': '{name}' refers to itself (a cycle: {} -> {name})", self.stack.join(" -> ")));
                }
                let Some((_, dl, dv)) = self.defs.iter().find(|(n, _, _)| n == name).cloned() else {
                    return self.err(l, format!("key 'ref': no definition named '{name}' in 'defs'"));
                };
                self.stack.push(name.clone());
                let e = self.node(dl, &dv, &xf)?;
                self.stack.pop();
                return Ok(e);
            }
            "mesh" => {
                let Value::Str(p) = x else { return self.err(l, "key 'mesh': expected a file path") };
                let path = self.base.join(p);
                if !path.is_file() {
                    return self.err(l, format!("key 'mesh': no such file {}", path.display()));
                }
                Operand::Mesh { paths: vec![path], transform: xf }
            }
            "volume" => {
                let Value::Obj(items) = x else { return self.err(l, "key 'volume': expected an object such as {\"file\": \"ct.nii.gz\", \"iso\": 300}") };
                let (mut file, mut surface, mut dicom_series) = (None, None, None);
                for (k, kl, v) in items {
                    match (k.as_str(), v) {
                        ("file", Value::Str(p)) => file = Some((*kl, self.base.join(p))),
                        ("dicom_series", Value::Str(s)) => dicom_series = Some(s.clone()),
                        ("dicom_series", Value::Num(n)) if *n >= 1.0 && n.fract() == 0.0 && *n <= u32::MAX as f64 => dicom_series = Some(format!("{}", *n as u64)),
                        ("dicom_series", _) => return self.err(*kl, "key 'dicom_series': expected a SeriesInstanceUID (a string) or a series number from 1"),
                        ("file", _) => return self.err(*kl, "key 'file': expected a path to a volume (a file, or a DICOM or TIFF folder)"),
                        ("iso" | "label", v) => {
                            if surface.is_some() {
                                return self.err(*kl, "volume: give one of 'iso' and 'label'");
                            }
                            let x = self.num(*kl, k, v)?;
                            if !(x.abs() <= f32::MAX as f64) {
                                return self.err(*kl, format!("key '{k}': {x} is not a 32-bit float"));
                            }
                            surface = Some(if k == "iso" { VolumeSurface::Iso(x as f32) } else { VolumeSurface::Label(x as f32) });
                        }
                        _ => return self.err(*kl, format!("key '{k}': unknown parameter of volume (file, iso, label, dicom_series)")),
                    }
                }
                let Some((fl, input)) = file else { return self.err(l, "volume: missing key 'file'") };
                let Some(surface) = surface else { return self.err(l, "volume: missing key 'iso' (or 'label')") };
                if !input.exists() {
                    return self.err(fl, format!("key 'file': no such file or folder {}", input.display()));
                }
                if xf != Transform::default() {
                    return self.err(l, "volume: a volume is placed by its own header; 'scale', 'rotate' and 'translate' on it (or on a node above it) are not supported");
                }
                Operand::Volume(Box::new(VolumeJob { input, raw: None, surface, own_grid: false, open_border: false, dicom_series }))
            }
            "sphere" => Operand::Primitive(prim(Shape::Sphere { radius: { let (fl, f) = self.field(l, k, x, "radius")?; self.positive(fl, "radius", f)? } })),
            "box" => {
                let (fl, f) = self.field(l, k, x, "size")?;
                let s = self.vec3(fl, "size", f)?;
                if s.iter().any(|&v| v <= 0.0) {
                    return self.err(fl, "key 'size': every side must be > 0");
                }
                Operand::Primitive(prim(Shape::Box { half: s.map(|v| 0.5 * v) }))
            }
            "cylinder" => {
                let (rl, r) = self.field(l, k, x, "radius")?;
                let (hl, h) = self.field(l, k, x, "height")?;
                Operand::Primitive(prim(Shape::Cylinder { radius: self.positive(rl, "radius", r)?, half_height: 0.5 * self.positive(hl, "height", h)? }))
            }
            "cone" => {
                let (rl, r) = self.field(l, k, x, "radius")?;
                let (hl, h) = self.field(l, k, x, "height")?;
                Operand::Primitive(prim(Shape::Cone { radius: self.positive(rl, "radius", r)?, height: self.positive(hl, "height", h)? }))
            }
            "torus" => {
                let (ml, m) = self.field(l, k, x, "major")?;
                let (nl, n) = self.field(l, k, x, "minor")?;
                let (major, minor) = (self.positive(ml, "major", m)?, self.positive(nl, "minor", n)?);
                if minor >= major {
                    return self.err(nl, "key 'minor': must be smaller than 'major'");
                }
                Operand::Primitive(prim(Shape::Torus { major, minor }))
            }
            "halfspace" => {
                let (nl, n) = self.field(l, k, x, "normal")?;
                let (ol, o) = self.field(l, k, x, "offset")?;
                let n = self.vec3(nl, "normal", n)?;
                let d = self.num(ol, "offset", o)?;
                // Scaled by its largest component first, so that no square
                // overflows or underflows (a normal of [1e200, 0, 0] is +x).
                let big = n.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if !(big > 0.0) {
                    return self.err(nl, "key 'normal': must not be zero");
                }
                let n = n.map(|v| v / big);
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                // n·p <= d with |n| = big·len: the plane is at distance d / (big·len).
                let dist = d / big / len;
                if !dist.is_finite() {
                    return self.err(ol, format!("key 'offset': {d} over a normal of length {:e} is not a finite distance", big * len));
                }
                let w = n.map(|v| v / len);
                // An orthonormal frame (u, v, w): local z maps to the normal.
                let helper = if w[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
                let cross = |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
                let u = cross(helper, w);
                let ul = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
                let u = u.map(|x| x / ul);
                let v = cross(w, u);
                let m = [[u[0], v[0], w[0]], [u[1], v[1], w[1]], [u[2], v[2], w[2]]];
                let Some(frame) = Transform::new(m, w.map(|x| x * dist)) else {
                    return self.err(nl, format!("key 'normal': no orthonormal frame for {n:?}"));
                };
                Operand::Primitive(Primitive::new(Shape::HalfSpace, xf.after(&frame)))
            }
            _ => unreachable!(),
        };
        self.operands.push(leaf);
        Ok(Expr::Operand(self.operands.len() - 1))
    }
}

/// Parses a scene file's text. `path` names the file in errors; mesh paths
/// are relative to its directory.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let mut p = Parser { s: text.as_bytes(), i: 0, line: 1, depth: 0 };
    let (line, root) = p.value().map_err(|(line, message)| SceneError { path: path.to_path_buf(), line, message })?;
    p.ws();
    if p.i < p.s.len() {
        return Err(SceneError { path: path.to_path_buf(), line: p.line, message: "unexpected text after the scene".into() });
    }
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut b = Builder { path, base, defs: Vec::new(), operands: Vec::new(), stack: Vec::new(), depth: 0 };
    let (node_line, node) = match &root {
        Value::Obj(items) if items.iter().any(|(k, _, _)| k == "scene") => {
            let mut scene = None;
            for (k, l, v) in items {
                match k.as_str() {
                    "scene" => scene = Some((*l, v.clone())),
                    "defs" => match v {
                        Value::Obj(d) => b.defs = d.clone(),
                        _ => return b.err(*l, "key 'defs': expected an object of named nodes"),
                    },
                    _ => return b.err(*l, format!("key '{k}': expected only 'scene' and 'defs' at the top level")),
                }
            }
            scene.unwrap()
        }
        _ => (line, root.clone()),
    };
    let expr = b.node(node_line, &node, &Transform::default())?;
    Ok(Scene { expr, operands: b.operands })
}

/// A voxel volume read as a surface (`mint volume`): which file, which
/// surface, and on which grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeJob {
    /// A header file, a DICOM or TIFF folder, or raw samples (`raw`).
    pub input: PathBuf,
    /// The raw layout, for a file without a header.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw: Option<RawLayout>,
    pub surface: VolumeSurface,
    /// `true`: the grid is the volume's own (a node on every voxel centre,
    /// in index units; the run's grid size is ignored). `false`: cubic
    /// cells of the run's grid size in the volume's physical axes (index ×
    /// spacing), samples interpolated trilinearly.
    pub own_grid: bool,
    /// `--open-border`: leave the surface open where it meets the volume's
    /// border (the faces of the cap on the border are left out) instead of
    /// closing it there.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub open_border: bool,
    /// `--dicom-series`: of a DICOM folder holding several series, the one
    /// to read (its SeriesInstanceUID, or its number from 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dicom_series: Option<String>,
}

/// Which surface of a volume.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum VolumeSurface {
    /// Where the values cross `iso` (values `>= iso` inside).
    Iso(f32),
    /// The boundary of the voxels whose value is this label.
    Label(f32),
}

impl VolumeSurface {
    /// The core's field.
    pub fn field(self) -> mint_core::volume::Field {
        match self {
            VolumeSurface::Iso(v) => mint_core::volume::Field::Iso(v),
            VolumeSurface::Label(v) => mint_core::volume::Field::Label(v),
        }
    }
}

/// A raw volume's layout (`--raw-dims`, `--raw-type`, …).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLayout {
    pub dims: [u64; 3],
    /// `u8`, `i16`, `f32`, …
    pub sample: String,
    #[serde(default)]
    pub big_endian: bool,
    pub spacing: [f64; 3],
    #[serde(default)]
    pub header_bytes: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Scene, SceneError> {
        parse_scene(s, Path::new("scene.json"))
    }

    /// Found by fuzzing: errors quoting the scene's text (a bad value, a
    /// key) kept its newlines and control characters, so they took more
    /// than one line.
    #[test]
    fn errors_quoting_the_text_stay_one_line() {
        for text in ["{ \"sphere\": \u{0}\u{0} },\n  { \"", "{ \"translat\re\": [0, 0, 0] }", "{ \"union\": K\n [] }"] {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.starts_with("scene.json:1: ") && !e.contains(['\n', '\r', '\0']), "{e:?}");
        }
    }

    #[test]
    fn a_nested_scene_parses() {
        let s = parse(r#"{ "defs": { "h": { "cylinder": { "radius": 0.3, "height": 3 } } },
            "scene": { "difference": [ { "box": { "size": [2, 2, 2] }, "rotate": [0, 0, 30] },
                                        { "union": [ { "sphere": { "radius": 1.2 } }, { "ref": "h" } ] } ] } }"#)
        .unwrap();
        assert_eq!(s.operands.len(), 3);
        assert_eq!(s.expr, Expr::Op(BoolOp::Difference, vec![Expr::Operand(0), Expr::Op(BoolOp::Union, vec![Expr::Operand(1), Expr::Operand(2)])]));
    }

    #[test]
    fn bad_scenes_name_the_line_and_the_key() {
        let e = parse("{\n \"union\": [\n  { \"sphere\": { \"radius\": -1 } }\n ]\n}").unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.to_string().contains("'radius'"), "{e}");
        let e = parse("{\n \"blob\": {}\n}").unwrap_err();
        assert_eq!((e.line, e.to_string().contains("unknown primitive")), (2, true), "{e}");
        let e = parse("{ \"scene\": { \"ref\": \"a\" },\n \"defs\": { \"a\": { \"union\": [\n { \"ref\": \"a\" } ] } } }").unwrap_err();
        assert!(e.to_string().contains("cycle"), "{e}");
        let e = parse("{ \"mesh\": \"nope.ply\" }").unwrap_err();
        assert!(e.to_string().contains("no such file"), "{e}");
        let e = parse("{ \"sphere\": { \"radius\": 1 }, }").unwrap_err();
        assert!(e.to_string().starts_with("scene.json:1:"), "{e}");
    }

    /// A half-space normal of [1e200, 0, 0] is +x (it used to panic on a
    /// non-invertible frame); a tiny one too.
    #[test]
    fn huge_and_tiny_halfspace_normals_are_normalized_safely() {
        for (n, d) in [(1e200, 2e200), (1e-200, 2e-200), (3.0, 6.0)] {
            let s = parse(&format!("{{ \"halfspace\": {{ \"normal\": [{n:e}, 0, 0], \"offset\": {d:e} }} }}")).unwrap();
            let Operand::Primitive(p) = &s.operands[0] else { panic!() };
            // The plane x = 2: its frame's origin maps to (2, 0, 0), local z to +x.
            let o = p.transform.apply_point([0.0; 3]);
            let z = p.transform.apply_point([0.0, 0.0, 1.0]);
            assert!((o[0] - 2.0).abs() < 1e-12 && o[1].abs() < 1e-12 && o[2].abs() < 1e-12, "{n}: {o:?}");
            assert!((z[0] - 3.0).abs() < 1e-12, "{n}: {z:?}");
        }
        let e = parse("{ \"halfspace\": { \"normal\": [1e-300, 0, 0],\n \"offset\": 1e300 } }").unwrap_err();
        assert_eq!(e.line, 2, "{e}");
    }

    /// 10,000 nested unions, a deeply nested JSON array, and a chain of
    /// 300 refs are refused naming the limit and the line (they used to
    /// overflow the stack). Run on a thread with the main thread's stack.
    #[test]
    fn deep_nesting_is_refused_naming_the_limit() {
        std::thread::Builder::new()
            .stack_size(8 << 20)
            .spawn(|| {
                let n = 10_000;
                let deep = "{ \"union\": [\n".repeat(n) + "{ \"sphere\": { \"radius\": 1 } }" + &" ] }".repeat(n);
                let e = parse(&deep).unwrap_err();
                assert!(e.to_string().contains(&MAX_SCENE_DEPTH.to_string()), "{e}");
                assert!(e.line > 1, "{e}");
                let e = parse(&("[".repeat(100_000) + &"]".repeat(100_000))).unwrap_err();
                assert!(e.to_string().contains(&MAX_JSON_DEPTH.to_string()), "{e}");
                let mut defs: Vec<String> = (0..300).map(|i| format!("\"d{i}\": {{ \"ref\": \"d{}\" }}", i + 1)).collect();
                defs.push("\"d300\": { \"sphere\": { \"radius\": 1 } }".into());
                let e = parse(&format!("{{ \"defs\": {{ {} }}, \"scene\": {{ \"ref\": \"d0\" }} }}", defs.join(",\n"))).unwrap_err();
                assert!(e.to_string().contains(&MAX_SCENE_DEPTH.to_string()), "{e}");
                // Just within the limit: parses.
                let k = MAX_SCENE_DEPTH - 1;
                let ok = "{ \"union\": [\n".repeat(k) + "{ \"sphere\": { \"radius\": 1 } }" + &" ] }".repeat(k);
                parse(&ok).unwrap();
            })
            .unwrap()
            .join()
            .unwrap();
    }
}
