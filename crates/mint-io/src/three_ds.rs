//! Autodesk 3D Studio (`.3ds`), binary chunks: the triangle meshes of all
//! named objects.
//!
//! A chunk is a little-endian `u16` id, a `u32` length (header included) and
//! a body. The reader walks `0x4D4D` (main) → `0x3D3D` (editor) → `0x4000`
//! (named object: a NUL-terminated name, then chunks) → `0x4100` (triangle
//! mesh) → `0x4110` (points: `u16` count, `f32` x y z each) and `0x4120`
//! (faces: `u16` count, then `u16` a b c and `u16` flags each). Every other
//! chunk is skipped by its length. Objects are read in file order, any
//! number of them; object k's vertices follow object k−1's, and its face
//! indices are offset accordingly. The local axis chunk (`0x4160`) is
//! ignored: 3DS stores points in world coordinates already. Faces keep
//! their vertex order (counter-clockwise seen from outside).
//!
//! Writing: the format's counts are 16-bit, so the mesh is cut into objects
//! of at most 65,535 vertices and 65,535 faces, `mint0000`, `mint0001`, ...
//! Faces are taken in order; an object ends when the next face would need a
//! 65,536th vertex or face. A mesh of at most 65,535 vertices starts with
//! one object holding all of them in input order (so a mesh that fits one
//! object round-trips exactly); later objects number their vertices in
//! order of first use, repeating vertices shared across objects. Vertices
//! no object holds go into trailing face-less objects, so every vertex is
//! kept. Points are `f32`. The `0x4D4D` and
//! `0x3D3D` lengths are patched at `finish`; a file over 4 GiB is refused.
//!
//! Memory: the writer spills vertex positions (faces need them) and holds
//! one object (at most 65,535 faces) and a bit per vertex.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{Error, ErrorKind};
use crate::mapped::{Mapped, SpillFile};
use crate::positions::not_finite;
use crate::positions::{Emit, Positions, Reject};
use crate::backend::{ElementInfo, FaceStream, MeshInfo, Opened, ReadStats};
use crate::backend::{FormatWriter, OutFile, WriteOptions};
use crate::Format;

const MAIN: u16 = 0x4D4D;
const VERSION: u16 = 0x0002;
const EDITOR: u16 = 0x3D3D;
const MESH_VERSION: u16 = 0x3D3E;
const OBJECT: u16 = 0x4000;
const TRIMESH: u16 = 0x4100;
const POINTS: u16 = 0x4110;
const FACES: u16 = 0x4120;

/// Most vertices (and faces) per object.
pub(crate) const MAX_PER_OBJECT: usize = 65_535;

/// One object's mesh as found in the file.
#[derive(Debug, Clone)]
struct Obj {
    name: String,
    /// Offset of the first point (after the count) and the count.
    points: (usize, u32),
    /// Offset of the first face record and the count.
    faces: (usize, u32),
}

fn u16_at(d: &[u8], o: usize) -> u16 {
    u16::from_le_bytes([d[o], d[o + 1]])
}
fn u32_at(d: &[u8], o: usize) -> u32 {
    u32::from_le_bytes(d[o..o + 4].try_into().unwrap())
}

/// Walks the chunks of `[start, end)`, calling `f(id, body_start, end)`.
fn chunks(path: &Path, d: &[u8], start: usize, end: usize, f: &mut dyn FnMut(u16, usize, usize) -> Result<(), Error>) -> Result<(), Error> {
    let mut o = start;
    while o + 6 <= end {
        let id = u16_at(d, o);
        let len = u32_at(d, o + 2) as usize;
        if len < 6 || o + len > end {
            return Err(Error::format(path, format!("chunk 0x{id:04X} of {len} bytes runs past its parent (truncated file?)")).at_byte(o as u64));
        }
        f(id, o + 6, o + len)?;
        o += len;
    }
    Ok(())
}

/// Finds every object's mesh.
fn scan(path: &Path, d: &[u8]) -> Result<Vec<Obj>, Error> {
    if !crate::format::sniff_3ds(d, d.len() as u64) {
        return Err(Error::format(path, "not a 3DS file: no main chunk 0x4D4D at the start").at_byte(0));
    }
    let main_end = u32_at(d, 2) as usize;
    let mut objs = Vec::new();
    chunks(path, d, 6, main_end, &mut |id, s, e| {
        if id != EDITOR {
            return Ok(());
        }
        chunks(path, d, s, e, &mut |id, s, e| {
            if id != OBJECT {
                return Ok(());
            }
            let nul = d[s..e].iter().position(|&b| b == 0).ok_or_else(|| Error::format(path, "object name without its NUL terminator").at_byte(s as u64))?;
            let name = String::from_utf8_lossy(&d[s..s + nul]).into_owned();
            chunks(path, d, s + nul + 1, e, &mut |id, s, e| {
                if id != TRIMESH {
                    return Ok(());
                }
                let mut obj = Obj { name: name.clone(), points: (0, 0), faces: (0, 0) };
                let mut have_points = false;
                chunks(path, d, s, e, &mut |id, s, e| {
                    match id {
                        POINTS if !have_points => {
                            if s + 2 > e {
                                return Err(Error::format(path, "point list without its count").at_byte(s as u64));
                            }
                            let n = u16_at(d, s) as usize;
                            if s + 2 + 12 * n > e {
                                return Err(Error::format(path, format!("point list of {n} points does not fit its chunk")).at_byte(s as u64));
                            }
                            obj.points = (s + 2, n as u32);
                            have_points = true;
                        }
                        FACES if obj.faces.1 == 0 => {
                            if s + 2 > e {
                                return Err(Error::format(path, "face list without its count").at_byte(s as u64));
                            }
                            let n = u16_at(d, s) as usize;
                            if s + 2 + 8 * n > e {
                                return Err(Error::format(path, format!("face list of {n} faces does not fit its chunk")).at_byte(s as u64));
                            }
                            obj.faces = (s + 2, n as u32);
                        }
                        _ => {}
                    }
                    Ok(())
                })?;
                objs.push(obj);
                Ok(())
            })
        })
    })?;
    Ok(objs)
}

fn make_info(objs: &[Obj]) -> MeshInfo {
    let nv: u64 = objs.iter().map(|o| o.points.1 as u64).sum();
    let nf: u64 = objs.iter().map(|o| o.faces.1 as u64).sum();
    MeshInfo {
        format: Format::ThreeDs,
        encoding: "binary".into(),
        vertex_count: nv,
        face_count: Some(nf),
        elements: objs
            .iter()
            .map(|o| ElementInfo {
                name: format!("object {}", o.name),
                count: o.faces.1 as u64,
                properties: vec![format!("{} points", o.points.1), format!("{} faces", o.faces.1)],
            })
            .collect(),
        comments: Vec::new(),
        obj_info: Vec::new(),
    }
}

/// Object names and counts (a walk over the chunk headers).
pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    Ok(make_info(&scan(path, data)?))
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let d = map.bytes();
    let objs = scan(path, d)?;
    let mut spill = SpillFile::new(spill_dir, path)?;
    let mut nv = 0u64;
    let mut bases = Vec::with_capacity(objs.len());
    for o in &objs {
        bases.push(nv as u32);
        for k in 0..o.points.1 as usize {
            let p = o.points.0 + 12 * k;
            spill.write_point([0, 4, 8].map(|c| f32::from_le_bytes(d[p + c..p + c + 4].try_into().unwrap()) as f64))?;
        }
        nv += o.points.1 as u64;
        if nv > u32::MAX as u64 {
            return Err(Error::unsupported(path, format!("more than {} points (32-bit indices)", u32::MAX)));
        }
    }
    let positions = Positions::spilled(Arc::new(spill.into_mapped()?), nv as u32);
    let body = Body { path: path.to_path_buf(), map: map.clone(), objs: objs.clone(), bases, obj: 0, face: 0, total: d.len() as u64 };
    Ok(Opened { info: make_info(&objs), positions, body: Box::new(body), range_grid: None, spilled_vertices: nv, colours: None, face_colours: None, texturing: None })
}

/// Streams the objects' faces from the map.
struct Body {
    path: PathBuf,
    map: Arc<Mapped>,
    objs: Vec<Obj>,
    bases: Vec<u32>,
    obj: usize,
    face: u32,
    total: u64,
}

impl FaceStream for Body {
    fn fill(&mut self, out: &mut Emit, _stats: &mut ReadStats) -> Result<bool, Error> {
        let d = self.map.bytes();
        while self.obj < self.objs.len() {
            let o = &self.objs[self.obj];
            while self.face < o.faces.1 {
                if !out.room() {
                    return Ok(true);
                }
                let at = o.faces.0 + 8 * self.face as usize;
                let t = [0, 2, 4].map(|c| u16_at(d, at + c) as u32);
                if let Some(&bad) = t.iter().find(|&&i| i >= o.points.1) {
                    return Err(Error::new(
                        ErrorKind::Index,
                        &self.path,
                        format!("face of object '{}' uses point {bad}, but the object has {} points", o.name, o.points.1),
                    )
                    .at_element("face")
                    .at_record(self.face as u64)
                    .at_byte(at as u64));
                }
                let g = t.map(|i| i + self.bases[self.obj]);
                if let Err(Reject::NotFinite(v)) = out.tri_checked(g) {
                    return Err(not_finite(&self.path, v, out.pos).at_element("face").at_byte(at as u64));
                }
                self.face += 1;
            }
            self.obj += 1;
            self.face = 0;
        }
        Ok(false)
    }

    fn bytes_done(&self) -> u64 {
        match self.objs.get(self.obj) {
            Some(o) => (o.faces.0 + 8 * self.face as usize) as u64,
            None => self.total,
        }
    }
}

/// Writes objects of at most 65,535 vertices and faces.
pub(crate) struct ThreeDsWriter {
    out: OutFile,
    spill: Option<SpillFile>,
    positions: Option<Positions>,
    /// Current object: global → local vertex ids, its vertices, its faces.
    local: HashMap<u32, u16>,
    order: Vec<u32>,
    faces: Vec<[u16; 3]>,
    objects: u32,
    /// A bit per vertex: written in some object.
    written: Vec<u64>,
    /// The current object holds every vertex in input order.
    whole: bool,
}

impl ThreeDsWriter {
    pub(crate) fn create(path: &Path, opts: &WriteOptions) -> Result<ThreeDsWriter, Error> {
        let spill_dir = opts.spill_dir.clone().unwrap_or_else(std::env::temp_dir);
        let spill = SpillFile::new(&spill_dir, path)?;
        let mut out = OutFile::create(path)?;
        let mut h = Vec::new();
        h.extend_from_slice(&MAIN.to_le_bytes());
        h.extend_from_slice(&0u32.to_le_bytes()); // patched
        h.extend_from_slice(&VERSION.to_le_bytes());
        h.extend_from_slice(&10u32.to_le_bytes());
        h.extend_from_slice(&3u32.to_le_bytes());
        h.extend_from_slice(&EDITOR.to_le_bytes());
        h.extend_from_slice(&0u32.to_le_bytes()); // patched
        h.extend_from_slice(&MESH_VERSION.to_le_bytes());
        h.extend_from_slice(&10u32.to_le_bytes());
        h.extend_from_slice(&3u32.to_le_bytes());
        out.put(&h)?;
        Ok(ThreeDsWriter {
            out,
            spill: Some(spill),
            positions: None,
            local: HashMap::new(),
            order: Vec::new(),
            faces: Vec::new(),
            objects: 0,
            written: Vec::new(),
            whole: false,
        })
    }

    /// Maps the spilled positions once all vertices are in; a mesh that
    /// fits one object starts it with every vertex in input order.
    fn positions(&mut self) -> Result<&Positions, Error> {
        if self.positions.is_none() {
            let spill = self.spill.take().expect("spill before positions");
            let n = (spill.len() / 24) as u32;
            self.positions = Some(Positions::spilled(Arc::new(spill.into_mapped()?), n));
            self.written = vec![0u64; (n as usize).div_ceil(64)];
            if n as usize <= MAX_PER_OBJECT {
                self.whole = true;
                self.order = (0..n).collect();
                self.local = (0..n).map(|v| (v, v as u16)).collect();
            }
        }
        Ok(self.positions.as_ref().unwrap())
    }

    /// Writes the current object (vertices `order`, faces `faces`).
    fn flush(&mut self) -> Result<(), Error> {
        self.whole = false;
        if self.order.is_empty() && self.faces.is_empty() {
            return Ok(());
        }
        let name = format!("mint{:04}", self.objects);
        self.objects += 1;
        let pos = self.positions()?.clone();
        let points_len = 6 + 2 + 12 * self.order.len();
        let faces_len = if self.faces.is_empty() { 0 } else { 6 + 2 + 8 * self.faces.len() };
        let mesh_len = 6 + points_len + faces_len;
        let obj_len = 6 + name.len() + 1 + mesh_len;
        let mut b = Vec::with_capacity(obj_len);
        b.extend_from_slice(&OBJECT.to_le_bytes());
        b.extend_from_slice(&(obj_len as u32).to_le_bytes());
        b.extend_from_slice(name.as_bytes());
        b.push(0);
        b.extend_from_slice(&TRIMESH.to_le_bytes());
        b.extend_from_slice(&(mesh_len as u32).to_le_bytes());
        b.extend_from_slice(&POINTS.to_le_bytes());
        b.extend_from_slice(&(points_len as u32).to_le_bytes());
        b.extend_from_slice(&(self.order.len() as u16).to_le_bytes());
        for &v in &self.order {
            self.written[v as usize / 64] |= 1 << (v % 64);
            for c in pos.get(v) {
                b.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        if !self.faces.is_empty() {
            b.extend_from_slice(&FACES.to_le_bytes());
            b.extend_from_slice(&(faces_len as u32).to_le_bytes());
            b.extend_from_slice(&(self.faces.len() as u16).to_le_bytes());
            for f in &self.faces {
                for i in f {
                    b.extend_from_slice(&i.to_le_bytes());
                }
                b.extend_from_slice(&7u16.to_le_bytes());
            }
        }
        self.out.put(&b)?;
        self.local.clear();
        self.order.clear();
        self.faces.clear();
        Ok(())
    }
}

impl FormatWriter for ThreeDsWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        self.spill.as_mut().expect("vertices before faces").write_point(p)
    }

    fn face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        self.positions()?;
        if self.whole && self.faces.len() < MAX_PER_OBJECT {
            self.faces.push(f.map(|v| v as u16));
            return Ok(());
        }
        let new = f.iter().enumerate().filter(|&(k, v)| !self.local.contains_key(v) && !f[..k].contains(v)).count();
        if self.whole || self.order.len() + new > MAX_PER_OBJECT || self.faces.len() == MAX_PER_OBJECT {
            self.flush()?;
        }
        let mut l = [0u16; 3];
        for (k, &v) in f.iter().enumerate() {
            l[k] = match self.local.get(&v) {
                Some(&id) => id,
                None => {
                    let id = self.order.len() as u16;
                    self.local.insert(v, id);
                    self.order.push(v);
                    id
                }
            };
        }
        self.faces.push(l);
        Ok(())
    }

    fn finish(mut self: Box<Self>, vertices: u64, _faces: u64) -> Result<u64, Error> {
        let n = self.positions()?.count() as usize;
        debug_assert_eq!(n as u64, vertices);
        self.flush()?;
        // Vertices that no object holds yet, in face-less objects.
        for v in 0..n as u32 {
            if self.written[v as usize / 64] & (1 << (v % 64)) == 0 {
                if self.order.len() == MAX_PER_OBJECT {
                    self.flush()?;
                }
                self.order.push(v);
            }
        }
        self.flush()?;
        let len = self.out.len();
        if len > u32::MAX as u64 {
            return Err(Error::unsupported(self.out.target(), "the 3DS file would exceed 4 GiB (its lengths are 32-bit)"));
        }
        self.out.patch(2, &(len as u32).to_le_bytes())?;
        self.out.patch(16 + 2, &((len - 16) as u32).to_le_bytes())?;
        self.out.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncated_chunks_are_format_errors() {
        let mut d = Vec::new();
        d.extend_from_slice(&MAIN.to_le_bytes());
        d.extend_from_slice(&30u32.to_le_bytes());
        d.extend_from_slice(&EDITOR.to_le_bytes());
        d.extend_from_slice(&100u32.to_le_bytes());
        d.resize(30, 0);
        let e = scan(Path::new("a.3ds"), &d).err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Format);
        assert!(e.to_string().contains("chunk 0x3D3D"), "{e}");
        assert!(scan(Path::new("a.3ds"), b"hello world").is_err());
        assert!(crate::format::sniff_3ds(&d, 30) && !crate::format::sniff_3ds(&d, 20));
    }
}
