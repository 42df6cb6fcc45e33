//! glTF 2.0, as `.gltf` (JSON, with `.bin` buffers or `data:` URIs) and
//! `.glb` (binary container): triangle geometry in and out.
//!
//! **Reading.** Every triangle primitive (modes TRIANGLES, TRIANGLE_STRIP,
//! TRIANGLE_FAN; points and lines are skipped and counted) of the default
//! scene, or of every scene when none is default, or of every root node
//! when the file has no scene, with the node transforms applied in f64 —
//! the `matrix`, or `translation`/`rotation`/`scale` — so that a
//! geo-referenced model whose vertices are f32 offsets from a large node
//! translation keeps its world coordinates. (The `gltf` crate stores
//! transforms as f32, which puts a UTM translation on a half-metre lattice;
//! hence this reader over serde_json: see docs/DEPENDENCIES.md.) Positions:
//! FLOAT VEC3, any byte stride, sparse accessors; indices: UNSIGNED_BYTE,
//! _SHORT and _INT, any stride, sparse, or none (sequential). Positions go
//! to a spill file in world coordinates, triangles to another; both are
//! streamed from there. Every offset, count and index is checked; an error
//! is one line naming the file and the JSON path (`accessors[3]: …`).
//!
//! **Writing.** Positions as f32 relative to an origin carried by the
//! node's `translation` (f64 in the JSON): the centre of the box when the
//! model is far from the origin, else none. So a building at 5·10⁶ m keeps
//! micrometres, where absolute f32 would keep half metres. Indices as
//! UNSIGNED_INT. `.glb` is refused when it would pass the format's 4 GiB
//! limit, naming `.gltf` or `.ply` instead; `.gltf` writes `NAME.bin`
//! beside it. Both are written beside the target and renamed.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde_json::Value;

use crate::backend::{ElementInfo, FaceStream, FormatWriter, MeshInfo, Opened, OutFile, ReadStats, WriteOptions};
use crate::error::Error;
use crate::format::{is_glb, Format};
use crate::coords::origin_for;
use crate::mapped::{Mapped, SpillFile};
use crate::textures::{ImageSource, Material, TextureInfo, Texturing, TexturingBuilder, Wrap, NONE};
use crate::positions::{not_finite, Emit, Layout, Positions, Reject, Scalar};

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
/// Nested nodes deeper than this are refused (a cycle, or a hostile file).
const MAX_DEPTH: usize = 256;

pub(crate) type Mat = [[f64; 4]; 4];
pub(crate) const IDENTITY: Mat = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

pub(crate) fn mul(a: &Mat, b: &Mat) -> Mat {
    let mut m = [[0.0; 4]; 4];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn apply(m: &Mat, p: [f64; 3]) -> [f64; 3] {
    // Translation added last, so that a large offset meets the small,
    // already transformed coordinates once (exactly when the rest is identity).
    let r = |i: usize| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2];
    [r(0) + m[0][3], r(1) + m[1][3], r(2) + m[2][3]]
}

/// The parsed document and its buffers.
struct Doc<'a> {
    path: &'a Path,
    json: Value,
    buffers: Vec<Buf>,
    /// The file's bytes and its buffers': what bounds the output (see
    /// [`MAX_EXPANSION`]).
    bytes: u64,
}

/// Vertices plus triangles a glTF may expand to, per byte of the file and
/// its buffers, beyond [`EXPANSION_FLOOR`]. Only instancing (a mesh drawn
/// by many nodes) expands a file; a hostile hierarchy must not turn a few
/// kilobytes into a spill of a hundred gigabytes.
const MAX_EXPANSION: u64 = 64;
const EXPANSION_FLOOR: u64 = 1 << 24;
/// Elements an accessor without a bufferView (zeros, with sparse
/// substitutions) may have: it costs nothing in the file.
const MAX_ZERO_ELEMENTS: usize = 1 << 20;

/// A buffer's bytes: a range of the mapped GLB, a mapped external file, or
/// decoded `data:` bytes.
enum Buf {
    Map(Arc<Mapped>, usize, usize),
    Bytes(Vec<u8>),
}

impl Buf {
    fn bytes(&self) -> &[u8] {
        match self {
            Buf::Map(m, a, b) => &m.bytes()[*a..*b],
            Buf::Bytes(v) => v,
        }
    }
}

fn bad(path: &Path, at: &str, msg: impl std::fmt::Display) -> Error {
    Error::format(path, format!("{at}: {msg}"))
}

/// Splits a GLB into its JSON and the byte range of its BIN chunk.
fn glb_chunks<'d>(path: &Path, data: &'d [u8]) -> Result<(&'d [u8], Option<(usize, usize)>), Error> {
    let u32_at = |o: usize| u32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]);
    if data.len() < 20 {
        return Err(Error::format(path, "a GLB shorter than its 12-byte header and first chunk header"));
    }
    let version = u32_at(4);
    if version != 2 {
        return Err(Error::unsupported(path, format!("GLB version {version} (mint reads glTF 2.0)")));
    }
    let total = (u32_at(8) as usize).min(data.len());
    let (mut at, mut json, mut bin) = (12usize, None, None);
    while at + 8 <= total {
        let (len, kind) = (u32_at(at) as usize, u32_at(at + 4));
        let (a, b) = (at + 8, (at + 8).checked_add(len).filter(|&b| b <= total).ok_or_else(|| {
            Error::format(path, format!("a GLB chunk of {len} bytes at byte {at} runs past the end of the file ({total} bytes)"))
        })?);
        match kind {
            CHUNK_JSON if json.is_none() => json = Some(&data[a..b]),
            CHUNK_BIN if bin.is_none() => bin = Some((a, b)),
            _ => {}
        }
        at = b + (4 - len % 4) % 4;
    }
    let json = json.ok_or_else(|| Error::format(path, "a GLB without a JSON chunk"))?;
    Ok((json, bin))
}

fn base64(path: &Path, at: &str, s: &str) -> Result<Vec<u8>, Error> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for &c in s.as_bytes() {
        if c == b'=' {
            break;
        }
        let v = val(c).ok_or_else(|| bad(path, at, format!("a data URI with the character {:?}, not base64", c as char)))?;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

fn arr<'v>(v: &'v Value, key: &str) -> &'v [Value] {
    v.get(key).and_then(Value::as_array).map_or(&[], |a| a.as_slice())
}

/// `v[key]` as an index below `len`.
fn index(path: &Path, at: &str, v: &Value, key: &str, len: usize) -> Result<Option<usize>, Error> {
    match v.get(key) {
        None => Ok(None),
        Some(x) => match x.as_u64() {
            Some(i) if (i as usize) < len => Ok(Some(i as usize)),
            _ => Err(bad(path, at, format!("'{key}' is {x}, not an index below {len}"))),
        },
    }
}

fn uint(path: &Path, at: &str, v: &Value, key: &str, default: u64) -> Result<u64, Error> {
    match v.get(key) {
        None => Ok(default),
        Some(x) => x.as_u64().ok_or_else(|| bad(path, at, format!("'{key}' is {x}, not a non-negative integer"))),
    }
}

impl<'a> Doc<'a> {
    fn parse(path: &'a Path, map: &Arc<Mapped>, spill_dir: &Path) -> Result<Doc<'a>, Error> {
        Doc::parse_range(path, map, (0, map.bytes().len()), spill_dir)
    }

    /// Parses the glTF at bytes `range` of `map` (a whole file, or the GLB
    /// inside a 3D Tiles `b3dm`).
    fn parse_range(path: &'a Path, map: &Arc<Mapped>, range: (usize, usize), spill_dir: &Path) -> Result<Doc<'a>, Error> {
        let data = &map.bytes()[range.0..range.1];
        let (json_bytes, bin) = if is_glb(data) { glb_chunks(path, data)? } else { (data, None) };
        let bin = bin.map(|(a, e)| (a + range.0, e + range.0));
        let json: Value = serde_json::from_slice(json_bytes).map_err(|e| Error::format(path, format!("not glTF JSON ({e})")))?;
        if !json.is_object() {
            return Err(Error::format(path, "not glTF: the JSON is not an object"));
        }
        let version = json.get("asset").and_then(|a| a.get("version")).and_then(Value::as_str).unwrap_or("");
        if !version.starts_with("2.") {
            return Err(Error::unsupported(path, format!("glTF asset version {version:?} (mint reads 2.x)")));
        }
        // A required extension changes what the file means; those that only
        // touch materials, lights or image codecs leave the geometry alone.
        for (i, e) in arr(&json, "extensionsRequired").iter().enumerate() {
            let name = e.as_str().unwrap_or("");
            let harmless = name.starts_with("KHR_materials_")
                || matches!(name, "KHR_texture_transform" | "KHR_lights_punctual" | "KHR_texture_basisu" | "EXT_texture_webp" | "EXT_texture_avif");
            if !harmless {
                let what = match name {
                    "KHR_draco_mesh_compression" => " (Draco-compressed geometry; decompress it first, e.g. gltf-transform decompress)",
                    "EXT_meshopt_compression" | "KHR_meshopt_compression" => " (meshopt-compressed buffers; decompress them first, e.g. gltf-transform decompress)",
                    "KHR_mesh_quantization" => " (quantized positions; dequantize them first, e.g. gltf-transform dequantize)",
                    _ => "",
                };
                return Err(Error::unsupported(path, format!("extensionsRequired[{i}]: the file requires extension {name:?}, which mint does not implement{what}")));
            }
        }
        let mut buffers = Vec::new();
        for (i, b) in arr(&json, "buffers").iter().enumerate() {
            let at = format!("buffers[{i}]");
            let len = uint(path, &at, b, "byteLength", 0)? as usize;
            let buf = match b.get("uri").and_then(Value::as_str) {
                None => match bin {
                    Some((a, e)) if i == 0 => Buf::Map(map.clone(), a, e),
                    _ => return Err(bad(path, &at, "a buffer without a URI outside a GLB's first buffer")),
                },
                Some(uri) if uri.starts_with("data:") => {
                    let comma = uri.find(',').ok_or_else(|| bad(path, &at, "a data URI without a comma"))?;
                    if !uri[..comma].ends_with(";base64") {
                        return Err(bad(path, &at, "a data URI that is not base64"));
                    }
                    Buf::Bytes(base64(path, &at, &uri[comma + 1..])?)
                }
                Some(uri) => {
                    let rel = percent_decode(uri);
                    if rel.contains("://") {
                        return Err(bad(path, &at, format!("buffer URI {uri:?}: only files beside the .gltf are read")));
                    }
                    let file = path.parent().unwrap_or(Path::new(".")).join(&rel);
                    let m = Mapped::open(&file, spill_dir).map_err(|e| bad(path, &at, format!("buffer {}: {e}", file.display())))?;
                    let n = m.bytes().len();
                    Buf::Map(Arc::new(m), 0, n)
                }
            };
            if buf.bytes().len() < len {
                return Err(bad(path, &at, format!("byteLength {len}, but the buffer holds {} bytes", buf.bytes().len())));
            }
            buffers.push(buf);
        }
        let bytes = data.len() as u64 + buffers.iter().map(|b| b.bytes().len() as u64).sum::<u64>();
        Ok(Doc { path, json, buffers, bytes })
    }

    /// The root nodes to draw and why.
    fn roots(&self) -> Result<Vec<usize>, Error> {
        let (path, nodes) = (self.path, arr(&self.json, "nodes"));
        let scenes = arr(&self.json, "scenes");
        let scene_nodes = |s: usize| -> Result<Vec<usize>, Error> {
            let at = format!("scenes[{s}]");
            arr(&scenes[s], "nodes").iter().map(|n| match n.as_u64() {
                Some(i) if (i as usize) < nodes.len() => Ok(i as usize),
                _ => Err(bad(path, &at, format!("node {n} is not an index below {}", nodes.len()))),
            }).collect()
        };
        if let Some(s) = index(path, "scene", &self.json, "scene", scenes.len())? {
            return scene_nodes(s);
        }
        if !scenes.is_empty() {
            let mut all = Vec::new();
            for s in 0..scenes.len() {
                all.extend(scene_nodes(s)?);
            }
            return Ok(all);
        }
        // No scene: every node that is no other node's child.
        let mut child = vec![false; nodes.len()];
        for n in nodes {
            for c in arr(n, "children") {
                if let Some(i) = c.as_u64().filter(|&i| (i as usize) < nodes.len()) {
                    child[i as usize] = true;
                }
            }
        }
        Ok((0..nodes.len()).filter(|&i| !child[i]).collect())
    }

    fn local(&self, n: usize) -> Result<Mat, Error> {
        let node = &arr(&self.json, "nodes")[n];
        let at = format!("nodes[{n}]");
        let nums = |key: &str, len: usize| -> Result<Option<Vec<f64>>, Error> {
            match node.get(key) {
                None => Ok(None),
                Some(v) => {
                    let xs: Option<Vec<f64>> = v.as_array().map(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>()).flatten();
                    match xs {
                        Some(xs) if xs.len() == len && xs.iter().all(|x| x.is_finite()) => Ok(Some(xs)),
                        _ => Err(bad(self.path, &at, format!("'{key}' is not {len} finite numbers"))),
                    }
                }
            }
        };
        if let Some(m) = nums("matrix", 16)? {
            // Column-major.
            let mut r = [[0.0; 4]; 4];
            for c in 0..4 {
                for (row, x) in r.iter_mut().enumerate() {
                    x[c] = m[4 * c + row];
                }
            }
            return Ok(r);
        }
        let t = nums("translation", 3)?.unwrap_or(vec![0.0; 3]);
        let q = nums("rotation", 4)?.unwrap_or(vec![0.0, 0.0, 0.0, 1.0]);
        let s = nums("scale", 3)?.unwrap_or(vec![1.0; 3]);
        let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
        let rot = [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ];
        let mut m = IDENTITY;
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = rot[i][j] * s[j];
            }
            m[i][3] = t[i];
        }
        Ok(m)
    }

    /// Every (mesh, world transform) to draw, in traversal order.
    fn instances(&self) -> Result<Vec<(usize, Mat)>, Error> {
        let nodes = arr(&self.json, "nodes");
        let meshes = arr(&self.json, "meshes").len();
        let mut out = Vec::new();
        let mut stack: Vec<(usize, Mat, usize)> = self.roots()?.into_iter().rev().map(|n| (n, IDENTITY, 0)).collect();
        // A node hierarchy is a forest: each node is drawn once. A root
        // listed again (by another scene) is skipped; a node reached twice
        // through children (two parents, or a cycle) is refused.
        let mut seen: HashSet<usize> = HashSet::new();
        while let Some((n, parent, depth)) = stack.pop() {
            let at = format!("nodes[{n}]");
            if depth > MAX_DEPTH {
                return Err(bad(self.path, &at, "nodes nested deeper than 256"));
            }
            if !seen.insert(n) {
                if depth == 0 {
                    continue;
                }
                return Err(bad(self.path, &at, "a node with two parents, or a cycle in the node hierarchy"));
            }
            let world = mul(&parent, &self.local(n)?);
            if let Some(m) = index(self.path, &at, &nodes[n], "mesh", meshes)? {
                out.push((m, world));
            }
            let children = arr(&nodes[n], "children");
            for c in children.iter().rev() {
                match c.as_u64() {
                    Some(i) if (i as usize) < nodes.len() => stack.push((i as usize, world, depth + 1)),
                    _ => return Err(bad(self.path, &at, format!("child {c} is not an index below {}", nodes.len()))),
                }
            }
        }
        Ok(out)
    }
}

/// Decodes `%XX` escapes of a relative URI.
pub(crate) fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// One accessor, resolved: where its elements are and how to read them.
struct Accessor<'d> {
    at: String,
    count: usize,
    /// (bytes, stride) of the bufferView part; None: all zeros.
    data: Option<(&'d [u8], usize)>,
    comp: u32,
    /// Sparse substitutions: (element index, bytes of its value).
    sparse: Vec<(usize, &'d [u8])>,
}

fn comp_size(path: &Path, at: &str, comp: u32) -> Result<usize, Error> {
    match comp {
        5120 | 5121 => Ok(1),
        5122 | 5123 => Ok(2),
        5125 | 5126 => Ok(4),
        c => Err(bad(path, at, format!("componentType {c} is not a glTF component type"))),
    }
}

impl<'d> Accessor<'d> {
    fn new(doc: &'d Doc, i: usize, want_type: &str) -> Result<Accessor<'d>, Error> {
        let path = doc.path;
        let accs = arr(&doc.json, "accessors");
        let at = format!("accessors[{i}]");
        let a = accs.get(i).ok_or_else(|| bad(path, "accessors", format!("accessor {i} does not exist ({} accessors)", accs.len())))?;
        let ty = a.get("type").and_then(Value::as_str).unwrap_or("");
        if !want_type.split('|').any(|t| t == ty) {
            return Err(bad(path, &at, format!("type {ty:?}, {want_type:?} expected")));
        }
        let comps = match ty {
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 1,
        };
        let comp = uint(path, &at, a, "componentType", 0)? as u32;
        let size = comp_size(path, &at, comp)?;
        let count = uint(path, &at, a, "count", 0)?;
        // No accessor can hold more elements than bytes in the file or 2^32.
        if count > u32::MAX as u64 {
            return Err(bad(path, &at, format!("count {count} is past 32-bit indices")));
        }
        let count = count as usize;
        let elem = size * comps;
        let view = |vi: usize, offset: usize, at: &str| -> Result<(&'d [u8], usize), Error> {
            let views = arr(&doc.json, "bufferViews");
            let v = views.get(vi).ok_or_else(|| bad(path, at, format!("bufferView {vi} does not exist ({} views)", views.len())))?;
            let vat = format!("bufferViews[{vi}]");
            let b = index(path, &vat, v, "buffer", doc.buffers.len())?.ok_or_else(|| bad(path, &vat, "no buffer"))?;
            let (off, len) = (uint(path, &vat, v, "byteOffset", 0)? as usize, uint(path, &vat, v, "byteLength", 0)? as usize);
            let bytes = doc.buffers[b].bytes();
            let range = off.checked_add(len).filter(|&e| e <= bytes.len()).ok_or_else(|| {
                bad(path, &vat, format!("bytes {off}..{} past the end of buffer {b} ({} bytes)", off as u128 + len as u128, bytes.len()))
            })?;
            let stride = uint(path, &vat, v, "byteStride", 0)? as usize;
            let view = &bytes[off..range];
            let view = view.get(offset..).ok_or_else(|| bad(path, at, format!("byteOffset {offset} past its view of {len} bytes")))?;
            Ok((view, stride))
        };
        let data = match index(path, &at, a, "bufferView", usize::MAX)? {
            None => None,
            Some(vi) => {
                let (bytes, stride) = view(vi, uint(path, &at, a, "byteOffset", 0)? as usize, &at)?;
                let stride = if stride == 0 { elem } else { stride };
                if stride < elem {
                    return Err(bad(path, &at, format!("byteStride {stride} is shorter than an element ({elem} bytes)")));
                }
                if count > 0 && (count - 1) as u128 * stride as u128 + elem as u128 > bytes.len() as u128 {
                    return Err(bad(path, &at, format!("{count} elements of stride {stride} need more than the {} bytes of its view", bytes.len())));
                }
                Some((bytes, stride))
            }
        };
        if data.is_none() && count > MAX_ZERO_ELEMENTS {
            return Err(bad(path, &at, format!("{count} elements without a bufferView (zeros): mint reads at most {MAX_ZERO_ELEMENTS} such elements")));
        }
        let mut sparse = Vec::new();
        if let Some(sp) = a.get("sparse") {
            let sat = format!("{at}.sparse");
            let n = uint(path, &sat, sp, "count", 0)? as usize;
            if n > count {
                return Err(bad(path, &sat, format!("count {n} is more than the accessor's {count}")));
            }
            let (idx, vals) = (sp.get("indices").unwrap_or(&Value::Null), sp.get("values").unwrap_or(&Value::Null));
            let icomp = uint(path, &sat, idx, "componentType", 0)? as u32;
            let isize = comp_size(path, &sat, icomp)?;
            let iv = index(path, &sat, idx, "bufferView", usize::MAX)?.ok_or_else(|| bad(path, &sat, "indices without a bufferView"))?;
            let vv = index(path, &sat, vals, "bufferView", usize::MAX)?.ok_or_else(|| bad(path, &sat, "values without a bufferView"))?;
            let (ib, _) = view(iv, uint(path, &sat, idx, "byteOffset", 0)? as usize, &sat)?;
            let (vb, _) = view(vv, uint(path, &sat, vals, "byteOffset", 0)? as usize, &sat)?;
            if ib.len() < n * isize || vb.len() < n * elem {
                return Err(bad(path, &sat, format!("{n} substitutions need more bytes than its views hold")));
            }
            for k in 0..n {
                let e = read_uint(&ib[k * isize..], icomp) as usize;
                if e >= count {
                    return Err(bad(path, &sat, format!("substitution {k} names element {e} of {count}")));
                }
                sparse.push((e, &vb[k * elem..(k + 1) * elem]));
            }
        }
        Ok(Accessor { at, count, data, comp, sparse })
    }

    /// Element `i`'s bytes (before sparse substitution).
    fn raw(&self, i: usize) -> Option<&'d [u8]> {
        self.data.map(|(b, stride)| &b[i * stride..])
    }
}

fn read_uint(b: &[u8], comp: u32) -> u64 {
    match comp {
        5120 | 5121 => b[0] as u64,
        5122 | 5123 => u16::from_le_bytes([b[0], b[1]]) as u64,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64,
    }
}

fn read_vec3(b: &[u8]) -> [f64; 3] {
    let f = |o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as f64;
    [f(0), f(4), f(8)]
}

/// What a pass over the document found.
#[derive(Default, Debug, Clone, Copy)]
pub(crate) struct Counts {
    pub(crate) vertices: u64,
    pub(crate) triangles: u64,
    primitives: u64,
    /// Primitives of points or lines, skipped.
    skipped: u64,
}

/// Walks every drawn primitive; with spills, writes world positions and
/// triangles (0-based over all primitives).
fn walk(doc: &Doc, spill: Option<(&mut SpillFile, &mut SpillFile)>, colours: Option<&mut SpillFile>, uvs: Option<&mut TexturingBuilder>) -> Result<Counts, Error> {
    let mut c = Counts::default();
    walk_into(doc, &IDENTITY, &mut c, spill, colours, uvs.map(|u| (u, 0)))?;
    Ok(c)
}

/// True when some primitive names a material (its base colour, its
/// texture).
fn has_material(doc: &Doc) -> bool {
    arr(&doc.json, "meshes").iter().any(|m| arr(m, "primitives").iter().any(|p| p.get("material").is_some()))
}

/// A `TEXCOORD_0` element: FLOAT, or normalized UNSIGNED_BYTE or
/// UNSIGNED_SHORT.
fn read_uv(b: &[u8], comp: u32) -> [f32; 2] {
    match comp {
        5121 => [b[0] as f32 / 255.0, b[1] as f32 / 255.0],
        5123 => [u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0, u16::from_le_bytes([b[2], b[3]]) as f32 / 65535.0],
        _ => [f32::from_le_bytes([b[0], b[1], b[2], b[3]]), f32::from_le_bytes([b[4], b[5], b[6], b[7]])],
    }
}

/// The document's materials (base colour factor and texture, with the
/// sampler's wrap modes) and the textures' images, sized from their
/// headers. Images that are neither PNG nor JPEG, or missing, leave their
/// materials untextured, with a warning.
fn materials(doc: &Doc, map: &Arc<Mapped>) -> Result<(Vec<Material>, Vec<TextureInfo>, Vec<String>), Error> {
    let path = doc.path;
    let mut warnings = Vec::new();
    let mut textures: Vec<TextureInfo> = Vec::new();
    let mut by_image: Vec<(usize, usize)> = Vec::new();
    let mut out = Vec::new();
    for (i, m) in arr(&doc.json, "materials").iter().enumerate() {
        let at = format!("materials[{i}]");
        let name = m.get("name").and_then(Value::as_str).unwrap_or("").to_string();
        let mut mat = Material { name, colour: [1.0; 4], texture: None, wrap: [Wrap::Repeat; 2], v_up: false };
        let pbr = m.get("pbrMetallicRoughness").unwrap_or(&Value::Null);
        if let Some(f) = pbr.get("baseColorFactor").and_then(Value::as_array) {
            for (k, v) in f.iter().take(4).enumerate() {
                mat.colour[k] = v.as_f64().unwrap_or(1.0).clamp(0.0, 1.0) as f32;
            }
        }
        if let Some(t) = pbr.get("baseColorTexture") {
            let tat = format!("{at}.pbrMetallicRoughness.baseColorTexture");
            let ti = index(path, &tat, t, "index", arr(&doc.json, "textures").len())?.ok_or_else(|| bad(path, &tat, "no index"))?;
            if uint(path, &tat, t, "texCoord", 0)? != 0 {
                warnings.push(format!("{}: {tat} uses TEXCOORD_{}: mint reads TEXCOORD_0; the material keeps its base colour", path.display(), uint(path, &tat, t, "texCoord", 0)?));
            } else {
                let tex = &arr(&doc.json, "textures")[ti];
                let xat = format!("textures[{ti}]");
                if let Some(si) = index(path, &xat, tex, "sampler", arr(&doc.json, "samplers").len())? {
                    let smp = &arr(&doc.json, "samplers")[si];
                    let wrap = |k: &str| match smp.get(k).and_then(Value::as_u64) {
                        Some(33071) => Wrap::Clamp,
                        Some(33648) => Wrap::Mirror,
                        _ => Wrap::Repeat,
                    };
                    mat.wrap = [wrap("wrapS"), wrap("wrapT")];
                }
                match index(path, &xat, tex, "source", arr(&doc.json, "images").len())? {
                    None => warnings.push(format!("{}: {xat} has no source image (an extension's only?): its material keeps its base colour", path.display())),
                    Some(ii) => match by_image.iter().find(|(img, _)| *img == ii) {
                        Some(&(_, t)) => mat.texture = Some(t),
                        None => {
                            if let Some(source) = image_source(doc, map, ii, &mut warnings)? {
                                let (width, height) = crate::textures::image_size(&source, path)?;
                                textures.push(TextureInfo { source, width, height });
                                by_image.push((ii, textures.len() - 1));
                                mat.texture = Some(textures.len() - 1);
                            }
                        }
                    },
                }
            }
        }
        out.push(mat);
    }
    Ok((out, textures, warnings))
}

/// Where image `i`'s bytes are: a buffer view (in the GLB's map, or a
/// buffer's decoded bytes), a `data:` URI, or a file beside the glTF.
fn image_source(doc: &Doc, map: &Arc<Mapped>, i: usize, warnings: &mut Vec<String>) -> Result<Option<ImageSource>, Error> {
    let path = doc.path;
    let img = &arr(&doc.json, "images")[i];
    let at = format!("images[{i}]");
    if let Some(vi) = index(path, &at, img, "bufferView", arr(&doc.json, "bufferViews").len())? {
        let v = &arr(&doc.json, "bufferViews")[vi];
        let vat = format!("bufferViews[{vi}]");
        let b = index(path, &vat, v, "buffer", doc.buffers.len())?.ok_or_else(|| bad(path, &vat, "no buffer"))?;
        let (off, len) = (uint(path, &vat, v, "byteOffset", 0)? as usize, uint(path, &vat, v, "byteLength", 0)? as usize);
        let buf = &doc.buffers[b];
        let end = off.checked_add(len).filter(|&e| e <= buf.bytes().len()).ok_or_else(|| bad(path, &vat, "past the end of its buffer"))?;
        let name = format!("{}: {at}", path.display());
        return Ok(Some(match buf {
            Buf::Map(m, a, _) if Arc::ptr_eq(m, map) => ImageSource::embedded(m.clone(), (a + off, a + end), name),
            _ => ImageSource::bytes(buf.bytes()[off..end].to_vec(), name),
        }));
    }
    let Some(uri) = img.get("uri").and_then(Value::as_str) else {
        return Err(bad(path, &at, "neither a bufferView nor a uri"));
    };
    if uri.starts_with("data:") {
        let comma = uri.find(',').ok_or_else(|| bad(path, &at, "a data URI without a comma"))?;
        if !uri[..comma].ends_with(";base64") {
            return Err(bad(path, &at, "a data URI that is not base64"));
        }
        return Ok(Some(ImageSource::bytes(base64(path, &at, &uri[comma + 1..])?, format!("{}: {at}", path.display()))));
    }
    let rel = percent_decode(uri);
    if rel.contains("://") {
        return Err(bad(path, &at, format!("image URI {uri:?}: only files beside the .gltf are read")));
    }
    let file = path.parent().unwrap_or(Path::new(".")).join(&rel);
    if !file.is_file() {
        warnings.push(format!("{}: texture '{}' ({at}) not found: its materials keep their base colour", path.display(), file.display()));
        return Ok(None);
    }
    Ok(Some(ImageSource::file(file)))
}

/// True when some primitive of the document has a `COLOR_0` attribute.
fn has_colour(doc: &Doc) -> bool {
    arr(&doc.json, "meshes").iter().any(|m| arr(m, "primitives").iter().any(|p| p.get("attributes").and_then(|a| a.get("COLOR_0")).is_some()))
}

/// A `COLOR_0` element as RGBA bytes: FLOAT, or normalized UNSIGNED_BYTE
/// or UNSIGNED_SHORT, VEC3 (alpha 255) or VEC4.
fn read_colour(b: &[u8], comp: u32, comps: usize) -> [u8; 4] {
    let mut c = [255u8; 4];
    for (k, ch) in c.iter_mut().enumerate().take(comps) {
        *ch = match comp {
            5121 => b[k],
            5123 => b[2 * k + 1],
            _ => crate::colours::unit_to_u8(f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]) as f64),
        };
    }
    c
}

/// [`walk`] with `prefix` applied after the node transforms, appending to
/// the counts (and spills) of earlier documents: vertex ids go on from
/// `c.vertices`.
fn walk_into(
    doc: &Doc,
    prefix: &Mat,
    c: &mut Counts,
    mut spill: Option<(&mut SpillFile, &mut SpillFile)>,
    mut colours: Option<&mut SpillFile>,
    mut uvs: Option<(&mut TexturingBuilder, u32)>,
) -> Result<(), Error> {
    let path = doc.path;
    let meshes = arr(&doc.json, "meshes");
    let start = *c;
    for (m, world) in doc.instances()? {
        let world = mul(prefix, &world);
        for (p, prim) in arr(&meshes[m], "primitives").iter().enumerate() {
            let at = format!("meshes[{m}].primitives[{p}]");
            let mode = uint(path, &at, prim, "mode", 4)?;
            if mode < 4 {
                c.skipped += 1;
                continue;
            }
            if mode > 6 {
                return Err(bad(path, &at, format!("mode {mode} is not a glTF primitive mode")));
            }
            let attrs = prim.get("attributes").unwrap_or(&Value::Null);
            let pos_i = index(path, &at, attrs, "POSITION", usize::MAX)?.ok_or_else(|| bad(path, &at, "no POSITION attribute"))?;
            let pos = Accessor::new(doc, pos_i, "VEC3")?;
            if pos.comp != 5126 {
                return Err(Error::unsupported(path, format!("{}: POSITION of componentType {} (quantized positions, KHR_mesh_quantization, are not read; FLOAT is)", pos.at, pos.comp)));
            }
            let base = c.vertices;
            if base + pos.count as u64 > u32::MAX as u64 {
                return Err(bad(path, &at, format!("more than {} vertices in all (32-bit indices)", u32::MAX)));
            }
            let idx = match index(path, &at, prim, "indices", usize::MAX)? {
                Some(i) => {
                    let a = Accessor::new(doc, i, "SCALAR")?;
                    if !matches!(a.comp, 5121 | 5123 | 5125) {
                        return Err(bad(path, &a.at, format!("indices of componentType {}, not an unsigned integer type", a.comp)));
                    }
                    Some(a)
                }
                None => None,
            };
            let n = idx.as_ref().map_or(pos.count, |a| a.count);
            let tris = match mode {
                4 => n / 3,
                _ => n.saturating_sub(2),
            } as u64;
            c.vertices += pos.count as u64;
            c.triangles += tris;
            c.primitives += 1;
            let limit = EXPANSION_FLOOR + MAX_EXPANSION * doc.bytes;
            if (c.vertices - start.vertices) + (c.triangles - start.triangles) > limit {
                return Err(bad(
                    path,
                    &at,
                    format!("its node instances expand to more than {limit} vertices and triangles, over {MAX_EXPANSION} per byte of the file: refused as a broken or hostile hierarchy (flatten the instances first)"),
                ));
            }
            let Some((vs, fs)) = spill.as_mut() else { continue };
            // Colours, one per position (white where a primitive has none).
            if let Some(cs) = colours.as_mut() {
                match index(path, &at, attrs, "COLOR_0", usize::MAX)? {
                    None => {
                        for _ in 0..pos.count {
                            cs.write_bytes(&[255; 4])?;
                        }
                    }
                    Some(ci) => {
                        let a = Accessor::new(doc, ci, "VEC3|VEC4")?;
                        if !matches!(a.comp, 5121 | 5123 | 5126) {
                            return Err(bad(path, &a.at, format!("COLOR_0 of componentType {} (FLOAT, UNSIGNED_BYTE or UNSIGNED_SHORT expected)", a.comp)));
                        }
                        if a.count != pos.count {
                            return Err(bad(path, &a.at, format!("COLOR_0 has {} elements, POSITION {}", a.count, pos.count)));
                        }
                        let comps = if arr(&doc.json, "accessors")[ci].get("type").and_then(Value::as_str) == Some("VEC4") { 4 } else { 3 };
                        let mut sub: Vec<(usize, &[u8])> = a.sparse.clone();
                        sub.sort_by_key(|s| s.0);
                        let mut next = 0;
                        for i in 0..a.count {
                            let mut col = a.raw(i).map_or([0, 0, 0, 255], |b| read_colour(b, a.comp, comps));
                            while next < sub.len() && sub[next].0 <= i {
                                if sub[next].0 == i {
                                    col = read_colour(sub[next].1, a.comp, comps);
                                }
                                next += 1;
                            }
                            cs.write_bytes(&col)?;
                        }
                    }
                }
            }
            // Texture coordinates, one pair per position (none where a
            // primitive has none: its triangles take their material's colour).
            let mut textured = false;
            if let Some((ub, _)) = uvs.as_mut() {
                let uv = match index(path, &at, attrs, "TEXCOORD_0", usize::MAX)? {
                    None => None,
                    Some(ti) => {
                        let a = Accessor::new(doc, ti, "VEC2")?;
                        if !matches!(a.comp, 5121 | 5123 | 5126) {
                            return Err(bad(path, &a.at, format!("TEXCOORD_0 of componentType {} (FLOAT, UNSIGNED_BYTE or UNSIGNED_SHORT expected)", a.comp)));
                        }
                        if a.count != pos.count {
                            return Err(bad(path, &a.at, format!("TEXCOORD_0 has {} elements, POSITION {}", a.count, pos.count)));
                        }
                        Some(a)
                    }
                };
                textured = uv.is_some();
                let mut sub: Vec<(usize, &[u8])> = uv.as_ref().map_or(Vec::new(), |a| a.sparse.clone());
                sub.sort_by_key(|s| s.0);
                let mut next = 0;
                for i in 0..pos.count {
                    let mut q = uv.as_ref().and_then(|a| a.raw(i).map(|b| read_uv(b, a.comp))).unwrap_or([0.0; 2]);
                    while next < sub.len() && sub[next].0 <= i {
                        if sub[next].0 == i {
                            q = read_uv(sub[next].1, uv.as_ref().unwrap().comp);
                        }
                        next += 1;
                    }
                    ub.uv(q)?;
                }
            }
            // Materials are numbered after those of earlier documents.
            let material = match (index(path, &at, prim, "material", arr(&doc.json, "materials").len())?, uvs.as_ref()) {
                (Some(m), Some((_, base))) => base + m as u32,
                _ => NONE,
            };
            // Positions, sparse values substituted, in world coordinates.
            let mut sub: Vec<(usize, &[u8])> = pos.sparse.clone();
            sub.sort_by_key(|s| s.0);
            let mut next = 0;
            for i in 0..pos.count {
                let mut q = pos.raw(i).map_or([0.0; 3], read_vec3);
                while next < sub.len() && sub[next].0 <= i {
                    if sub[next].0 == i {
                        q = read_vec3(sub[next].1);
                    }
                    next += 1;
                }
                vs.write_point(apply(&world, q))?;
            }
            // Indices, sparse substituted (rare: materialized).
            let index_of = |k: usize| -> u64 {
                match &idx {
                    None => k as u64,
                    Some(a) => a.raw(k).map_or(0, |b| read_uint(b, a.comp)),
                }
            };
            let patched: Option<std::collections::HashMap<usize, u64>> =
                idx.as_ref().filter(|a| !a.sparse.is_empty()).map(|a| a.sparse.iter().map(|&(e, b)| (e, read_uint(b, a.comp))).collect());
            let get = |k: usize| -> Result<u32, Error> {
                let v = patched.as_ref().and_then(|p| p.get(&k).copied()).unwrap_or_else(|| index_of(k));
                if v >= pos.count as u64 {
                    return Err(bad(path, &at, format!("index {v} (element {k}) is out of range ({} positions)", pos.count)));
                }
                Ok((base + v) as u32)
            };
            for t in 0..tris as usize {
                let tri = match mode {
                    4 => [get(3 * t)?, get(3 * t + 1)?, get(3 * t + 2)?],
                    5 if t % 2 == 0 => [get(t)?, get(t + 1)?, get(t + 2)?],
                    5 => [get(t + 1)?, get(t)?, get(t + 2)?],
                    _ => [get(0)?, get(t + 1)?, get(t + 2)?],
                };
                let mut b = [0u8; 12];
                for (k, v) in tri.iter().enumerate() {
                    b[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
                }
                fs.write_bytes(&b)?;
                if let Some((ub, _)) = uvs.as_mut() {
                    // The pairs are numbered as the vertices are.
                    ub.triangle(material, if textured { tri } else { [NONE; 3] })?;
                }
            }
        }
    }
    Ok(())
}

/// Appends the glTF at bytes `range` of `map` (named `path` in errors),
/// drawn with `prefix` (row-major, translation in the last column) after
/// its node transforms, to the counts and, when given, the spills: for
/// readers of containers of glTF (3D Tiles).
#[allow(clippy::too_many_arguments)]
pub(crate) fn append(
    path: &Path,
    map: &Arc<Mapped>,
    range: (usize, usize),
    prefix: &[[f64; 4]; 4],
    spill_dir: &Path,
    c: &mut Counts,
    spill: Option<(&mut SpillFile, &mut SpillFile)>,
    textures: Option<&mut Textures>,
) -> Result<(), Error> {
    let doc = Doc::parse_range(path, map, range, spill_dir)?;
    let Some(t) = textures else { return walk_into(&doc, prefix, c, spill, None, None) };
    // The first document with `COLOR_0` starts the colour spill: the
    // vertices before it are white.
    if t.colours.is_none() && has_colour(&doc) {
        let mut cs = SpillFile::new(spill_dir, &t.about)?;
        for _ in 0..c.vertices {
            cs.write_bytes(&[255; 4])?;
        }
        t.colours = Some(cs);
    }
    // The first document with a material starts the texture records; the
    // triangles and vertices before it have none.
    if t.builder.is_none() && has_material(&doc) {
        let mut b = TexturingBuilder::new(spill_dir, &t.about)?;
        for _ in 0..c.vertices {
            b.uv([0.0; 2])?;
        }
        for _ in 0..c.triangles {
            b.triangle(NONE, [NONE; 3])?;
        }
        t.builder = Some(b);
    }
    let base = t.materials.len() as u32;
    walk_into(&doc, prefix, c, spill, t.colours.as_mut(), t.builder.as_mut().map(|b| (b, base)))?;
    if t.builder.is_some() {
        let (mats, texs, warnings) = materials(&doc, map)?;
        let first = t.textures.len();
        t.materials.extend(mats.into_iter().map(|mut m| {
            m.texture = m.texture.map(|i| i + first);
            m
        }));
        t.textures.extend(texs);
        t.warnings.extend(warnings);
    }
    Ok(())
}

/// The materials and texture records of several glTF documents read as one
/// surface (the tiles of a tileset).
pub(crate) struct Textures {
    about: PathBuf,
    /// `COLOR_0` of every vertex, once a document has it.
    colours: Option<SpillFile>,
    builder: Option<TexturingBuilder>,
    materials: Vec<Material>,
    textures: Vec<TextureInfo>,
    warnings: Vec<String>,
}

impl Textures {
    /// None yet, for the surface read from `about`.
    pub(crate) fn new(about: &Path) -> Textures {
        Textures { about: about.to_path_buf(), colours: None, builder: None, materials: Vec::new(), textures: Vec::new(), warnings: Vec::new() }
    }

    /// The vertex colours of all `vertices`, if some document had
    /// `COLOR_0` (they win, as in one glTF file); else the texturing, if
    /// some document had a material.
    pub(crate) fn finish(self, vertices: u64) -> Result<(Option<crate::colours::VertexColours>, Option<Texturing>), Error> {
        if let Some(cs) = self.colours {
            return Ok((Some(crate::colours::VertexColours::spilled(Arc::new(cs.into_mapped()?), vertices as u32)), None));
        }
        match self.builder {
            Some(b) => Ok((None, Some(b.finish(self.materials, self.textures, self.warnings)?))),
            None => Ok((None, None)),
        }
    }
}

/// Streams triangles spilled as three little-endian u32 ids each: the body
/// of the glTF and 3D Tiles readers.
pub(crate) fn spilled_body(path: &Path, faces: Arc<Mapped>, tris: u64, total: u64) -> Box<dyn FaceStream> {
    Box::new(GltfBody { path: path.to_path_buf(), faces, tris, next: 0, total })
}

fn make_info(doc: &Doc, glb: bool, c: &Counts) -> MeshInfo {
    let generator = doc.json.get("asset").and_then(|a| a.get("generator")).and_then(Value::as_str).map(str::to_string);
    MeshInfo {
        format: Format::Gltf,
        encoding: if glb { "glb" } else { "gltf" }.into(),
        vertex_count: c.vertices,
        face_count: Some(c.triangles),
        elements: vec![
            ElementInfo { name: "POSITION".into(), count: c.vertices, properties: vec!["float[3] x y z (node transforms applied)".into()] },
            ElementInfo { name: "triangles".into(), count: c.triangles, properties: vec![format!("from {} primitives ({} of points or lines skipped)", c.primitives, c.skipped)] },
        ]
        .into_iter()
        .chain(has_colour(doc).then(|| ElementInfo { name: "COLOR_0".into(), count: c.vertices, properties: vec!["RGBA per vertex (white where a primitive has none)".into()] }))
        .collect(),
        comments: generator.into_iter().map(|g| format!("generator: {g}")).collect(),
        obj_info: Vec::new(),
    }
}

/// Counts the drawn vertices and triangles (reads the JSON and checks every
/// accessor; no spill).
pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    // The buffers are mapped again for the check: `info` has only the bytes.
    let map = Arc::new(Mapped::open(path, &std::env::temp_dir())?);
    let doc = Doc::parse(path, &map, &std::env::temp_dir())?;
    let c = walk(&doc, None, None, None)?;
    Ok(make_info(&doc, is_glb(data), &c))
}

/// The byte offset of `b` within `map`, when `b` lies in it.
fn offset_in(map: &Mapped, b: &[u8]) -> Option<usize> {
    let (m, p) = (map.bytes().as_ptr() as usize, b.as_ptr() as usize);
    (p >= m && p + b.len() <= m + map.bytes().len()).then(|| p - m)
}

/// Opens the common case in place, as the PLY reader does: one drawn
/// instance, with no transform, of one TRIANGLES primitive whose FLOAT
/// positions and indices (if any) lie in the GLB's own BIN chunk, without
/// sparse substitution. Positions are then read from the mapping and
/// indices streamed from it; nothing is spilled. `None`: anything else.
fn open_in_place(doc: &Doc, map: &Arc<Mapped>) -> Result<Option<Opened>, Error> {
    let path = doc.path;
    let inst = doc.instances()?;
    let [(m, world)] = inst.as_slice() else { return Ok(None) };
    if *world != IDENTITY {
        return Ok(None);
    }
    let prims = arr(&arr(&doc.json, "meshes")[*m], "primitives");
    let [prim] = prims else { return Ok(None) };
    let at = format!("meshes[{m}].primitives[0]");
    if uint(path, &at, prim, "mode", 4)? != 4 {
        return Ok(None);
    }
    let attrs = prim.get("attributes").unwrap_or(&Value::Null);
    let Some(pos_i) = index(path, &at, attrs, "POSITION", usize::MAX)? else { return Ok(None) };
    let pos = Accessor::new(doc, pos_i, "VEC3")?;
    let Some((pos_bytes, pos_stride)) = pos.data else { return Ok(None) };
    let Some(pos_off) = offset_in(map, pos_bytes) else { return Ok(None) };
    if pos.comp != 5126 || !pos.sparse.is_empty() {
        return Ok(None);
    }
    let indices = match index(path, &at, prim, "indices", usize::MAX)? {
        None => None,
        Some(i) => {
            let a = Accessor::new(doc, i, "SCALAR")?;
            let Some((bytes, stride)) = a.data else { return Ok(None) };
            let Some(off) = offset_in(map, bytes) else { return Ok(None) };
            if !matches!(a.comp, 5121 | 5123 | 5125) || !a.sparse.is_empty() {
                return Ok(None);
            }
            Some((off, stride, a.comp, a.count, a.at))
        }
    };
    let n = indices.as_ref().map_or(pos.count, |i| i.3);
    let c = Counts { vertices: pos.count as u64, triangles: (n / 3) as u64, primitives: 1, skipped: 0 };
    let positions = Positions::new(
        map.clone(),
        pos.count as u32,
        Layout { base: pos_off, stride: pos_stride, group: 1, inner: 0, off: [0, 4, 8], ty: [Scalar::F32; 3], be: false },
    );
    let body = InPlaceBody {
        path: path.to_path_buf(),
        map: map.clone(),
        indices: indices.map(|(off, stride, comp, _, at)| (off, stride, comp, at)),
        vertices: pos.count as u64,
        tris: c.triangles,
        next: 0,
        total: c.triangles,
    };
    Ok(Some(Opened { info: make_info(doc, is_glb(map.bytes()), &c), positions, body: Box::new(body), range_grid: None, spilled_vertices: 0, colours: None, face_colours: None, texturing: None }))
}

/// Triangles streamed from an index accessor in the mapped GLB (or, without
/// one, vertex `3t, 3t+1, 3t+2`).
struct InPlaceBody {
    path: PathBuf,
    map: Arc<Mapped>,
    /// Byte offset, stride, component type and JSON path of the indices.
    indices: Option<(usize, usize, u32, String)>,
    vertices: u64,
    tris: u64,
    next: u64,
    /// Triangles in the file (`tris` is where a restricted range ends).
    total: u64,
}

impl FaceStream for InPlaceBody {
    fn fill(&mut self, out: &mut Emit, _stats: &mut ReadStats) -> Result<bool, Error> {
        let b = self.map.bytes();
        // Tightly packed u32 indices, the usual case: three at a time.
        if let Some((off, 4, 5125, at)) = &self.indices {
            while self.next < self.tris && out.room() {
                let o = off + 12 * self.next as usize;
                let r = &b[o..o + 12];
                let tri = [0, 4, 8].map(|k| u32::from_le_bytes([r[k], r[k + 1], r[k + 2], r[k + 3]]));
                if let Some(k) = (0..3).find(|&k| tri[k] as u64 >= self.vertices) {
                    return Err(bad(&self.path, at, format!("index {} (element {}) is out of range ({} positions)", tri[k], 3 * self.next + k as u64, self.vertices)));
                }
                if let Err(Reject::NotFinite(x)) = out.tri_checked(tri) {
                    return Err(not_finite(&self.path, x, out.pos).at_element("triangle").at_record(self.next));
                }
                self.next += 1;
            }
            return Ok(self.next < self.tris);
        }
        while self.next < self.tris && out.room() {
            let t = self.next as usize;
            let mut tri = [3 * t as u64, 3 * t as u64 + 1, 3 * t as u64 + 2];
            if let Some((off, stride, comp, at)) = &self.indices {
                for (k, v) in tri.iter_mut().enumerate() {
                    let e = 3 * t + k;
                    *v = read_uint(&b[off + e * stride..], *comp);
                    if *v >= self.vertices {
                        return Err(bad(&self.path, at, format!("index {v} (element {e}) is out of range ({} positions)", self.vertices)));
                    }
                }
            }
            let tri = tri.map(|v| v as u32);
            if let Err(Reject::NotFinite(x)) = out.tri_checked(tri) {
                return Err(not_finite(&self.path, x, out.pos).at_element("triangle").at_record(self.next));
            }
            self.next += 1;
        }
        Ok(self.next < self.tris)
    }

    fn bytes_done(&self) -> u64 {
        crate::backend::share_done(self.map.bytes().len() as u64, self.next, self.tris)
    }

    // Fixed-size triangles in place: parts read ranges of them, and the
    // engine visits them on every thread, as binary PLY's.
    fn splittable_records(&self) -> Option<u64> {
        Some(self.total)
    }

    fn restrict(&mut self, first: u64, end: u64) -> Result<(), Error> {
        (self.next, self.tris) = (first, end);
        Ok(())
    }

    fn fixed_faces(&self) -> Result<Option<crate::visit::FixedFaces>, Error> {
        let (start, stride, ity, element) = match &self.indices {
            None => (0, 0, None, "POSITION".to_string()),
            Some((off, stride, comp, at)) => {
                let ity = match comp {
                    5121 => Scalar::U8,
                    5123 => Scalar::U16,
                    _ => Scalar::U32,
                };
                (*off, *stride, Some(ity), at.clone())
            }
        };
        Ok(Some(crate::visit::FixedFaces::Indexed { map: self.map.clone(), element, start, stride, ity, count: self.total }))
    }
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let doc = Doc::parse(path, &map, spill_dir)?;
    let coloured = has_colour(&doc);
    // Vertex colour wins over materials.
    let textured = !coloured && has_material(&doc);
    if !coloured && !textured {
        if let Some(opened) = open_in_place(&doc, &map)? {
            return Ok(opened);
        }
    }
    let (mut vs, mut fs) = (SpillFile::new(spill_dir, path)?, SpillFile::new(spill_dir, path)?);
    let mut cs = if coloured { Some(SpillFile::new(spill_dir, path)?) } else { None };
    let mut ub = if textured { Some(TexturingBuilder::new(spill_dir, path)?) } else { None };
    let c = walk(&doc, Some((&mut vs, &mut fs)), cs.as_mut(), ub.as_mut())?;
    let texturing = match ub {
        Some(ub) => {
            let (mats, textures, warnings) = materials(&doc, &map)?;
            Some(ub.finish(mats, textures, warnings)?)
        }
        None => None,
    };
    let colours = match cs {
        Some(cs) => Some(crate::colours::VertexColours::spilled(Arc::new(cs.into_mapped()?), c.vertices as u32)),
        None => None,
    };
    let info = make_info(&doc, is_glb(map.bytes()), &c);
    let positions = Positions::spilled(Arc::new(vs.into_mapped()?), c.vertices as u32);
    let faces = Arc::new(fs.into_mapped()?);
    let body = GltfBody { path: path.to_path_buf(), faces, tris: c.triangles, next: 0, total: map.bytes().len() as u64 };
    Ok(Opened { info, positions, body: Box::new(body), range_grid: None, spilled_vertices: c.vertices, colours, face_colours: None, texturing })
}

struct GltfBody {
    path: PathBuf,
    faces: Arc<Mapped>,
    tris: u64,
    next: u64,
    total: u64,
}

impl FaceStream for GltfBody {
    fn fill(&mut self, out: &mut Emit, _stats: &mut ReadStats) -> Result<bool, Error> {
        let b = self.faces.bytes();
        while self.next < self.tris && out.room() {
            let o = 12 * self.next as usize;
            let v = |k: usize| u32::from_le_bytes([b[o + 4 * k], b[o + 4 * k + 1], b[o + 4 * k + 2], b[o + 4 * k + 3]]);
            if let Err(Reject::NotFinite(x)) = out.tri_checked([v(0), v(1), v(2)]) {
                return Err(not_finite(&self.path, x, out.pos).at_element("triangle").at_record(self.next));
            }
            self.next += 1;
        }
        Ok(self.next < self.tris)
    }

    fn bytes_done(&self) -> u64 {
        crate::backend::share_done(self.total, self.next, self.tris)
    }
}

// ---------------------------------------------------------------- writing

/// The GLB container's limit: its length field is 32 bits.
pub const GLB_MAX_BYTES: u64 = u32::MAX as u64;

/// Streams vertices and triangles into spill files, then writes the glTF.
pub(crate) struct GltfWriter {
    path: PathBuf,
    glb: bool,
    vs: SpillFile,
    fs: SpillFile,
    /// RGBA per vertex, when writing colour (`COLOR_0`).
    cs: Option<SpillFile>,
    lo: [f64; 3],
    hi: [f64; 3],
}

impl GltfWriter {
    pub(crate) fn create(path: &Path, opts: &WriteOptions) -> Result<GltfWriter, Error> {
        let glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
        let dir = opts.spill_dir.clone().unwrap_or_else(|| path.parent().filter(|p| !p.as_os_str().is_empty()).map_or_else(|| PathBuf::from("."), Path::to_path_buf));
        Ok(GltfWriter {
            path: path.to_path_buf(),
            glb,
            vs: SpillFile::new(&dir, path)?,
            fs: SpillFile::new(&dir, path)?,
            cs: if opts.colours { Some(SpillFile::new(&dir, path)?) } else { None },
            lo: [f64::INFINITY; 3],
            hi: [f64::NEG_INFINITY; 3],
        })
    }

    fn limit(&self, vertices: u64, faces: u64) -> Result<(), Error> {
        let per_vertex = if self.cs.is_some() { 16 } else { 12 };
        if self.glb && per_vertex * vertices + 12 * faces + (1 << 12) > GLB_MAX_BYTES {
            return Err(Error::unsupported(
                &self.path,
                format!("{vertices} vertices and {faces} triangles pass GLB's 4 GiB limit: write .gltf (its buffer goes to a .bin beside it, no limit) or .ply"),
            ));
        }
        Ok(())
    }
}

impl FormatWriter for GltfWriter {
    fn vertex_rgba(&mut self, p: [f64; 3], c: [u8; 4]) -> Result<(), Error> {
        if let Some(cs) = self.cs.as_mut() {
            cs.write_bytes(&c)?;
        }
        self.vertex(p)
    }

    fn vertex(&mut self, p: [f64; 3]) -> Result<(), Error> {
        for d in 0..3 {
            self.lo[d] = self.lo[d].min(p[d]);
            self.hi[d] = self.hi[d].max(p[d]);
        }
        self.vs.write_point(p)?;
        self.limit(self.vs.len() / 24, self.fs.len() / 12)
    }

    fn face(&mut self, f: [u32; 3]) -> Result<(), Error> {
        let mut b = [0u8; 12];
        for (k, v) in f.iter().enumerate() {
            b[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
        self.fs.write_bytes(&b)?;
        if self.fs.len() % (12 << 16) == 0 {
            self.limit(self.vs.len() / 24, self.fs.len() / 12)?;
        }
        Ok(())
    }

    fn finish(self: Box<Self>, vertices: u64, faces: u64) -> Result<u64, Error> {
        self.limit(vertices, faces)?;
        let me = *self;
        let origin = origin_for(me.lo, me.hi);
        let vmap = me.vs.into_mapped()?;
        let fmap = me.fs.into_mapped()?;
        let cmap = match me.cs {
            Some(cs) => Some(cs.into_mapped()?),
            None => None,
        };
        let (vb, fb) = (vmap.bytes(), fmap.bytes());
        let rel = |i: usize| -> [f32; 3] {
            let o = 24 * i;
            let c = |k: usize| f64::from_le_bytes(vb[o + 8 * k..o + 8 * k + 8].try_into().unwrap());
            [0, 1, 2].map(|d| (c(d) - origin[d]) as f32)
        };
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for i in 0..vertices as usize {
            let q = rel(i);
            for d in 0..3 {
                lo[d] = lo[d].min(q[d]);
                hi[d] = hi[d].max(q[d]);
            }
        }
        let (pos_len, idx_len) = (12 * vertices, 12 * faces);
        let col_len = if cmap.is_some() { 4 * vertices } else { 0 };
        let bin_len = pos_len + idx_len + col_len;
        let bin_name = format!("{}.bin", me.path.file_stem().map_or("mesh".into(), |s| s.to_string_lossy()));
        let mut node = serde_json::json!({ "name": "mint" });
        if origin != [0.0; 3] {
            node["translation"] = serde_json::json!(origin);
        }
        let mut doc = serde_json::json!({
            "asset": { "version": "2.0", "generator": "mint" },
            "scene": 0,
            "scenes": [{ "nodes": [0] }],
            "nodes": [node],
        });
        if faces > 0 {
            doc["nodes"][0]["mesh"] = 0.into();
            doc["meshes"] = serde_json::json!([{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "mode": 4 }] }]);
            doc["accessors"] = serde_json::json!([
                { "bufferView": 0, "componentType": 5126, "count": vertices, "type": "VEC3", "min": lo, "max": hi },
                { "bufferView": 1, "componentType": 5125, "count": 3 * faces, "type": "SCALAR" },
            ]);
            doc["bufferViews"] = serde_json::json!([
                { "buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962 },
                { "buffer": 0, "byteOffset": pos_len, "byteLength": idx_len, "target": 34963 },
            ]);
            if col_len > 0 {
                doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 2.into();
                doc["accessors"].as_array_mut().expect("accessors").push(serde_json::json!({ "bufferView": 2, "componentType": 5121, "normalized": true, "count": vertices, "type": "VEC4" }));
                doc["bufferViews"].as_array_mut().expect("views").push(serde_json::json!({ "buffer": 0, "byteOffset": pos_len + idx_len, "byteLength": col_len, "target": 34962 }));
            }
            let mut buffer = serde_json::json!({ "byteLength": bin_len });
            if !me.glb {
                buffer["uri"] = Value::String(bin_name.clone());
            }
            doc["buffers"] = serde_json::json!([buffer]);
        }
        let write_bin = |out: &mut OutFile| -> Result<(), Error> {
            if faces == 0 {
                return Ok(());
            }
            for i in 0..vertices as usize {
                let q = rel(i);
                let mut b = [0u8; 12];
                for d in 0..3 {
                    b[4 * d..4 * d + 4].copy_from_slice(&q[d].to_le_bytes());
                }
                out.put(&b)?;
            }
            out.put(&fb[..idx_len as usize])?;
            match &cmap {
                Some(c) => out.put(&c.bytes()[..col_len as usize]),
                None => Ok(()),
            }
        };
        let mut json = serde_json::to_vec(&doc).expect("a glTF document serializes");
        if me.glb {
            while json.len() % 4 != 0 {
                json.push(b' ');
            }
            let bin_padded = if faces == 0 { 0 } else { bin_len.div_ceil(4) * 4 };
            let total = 12 + 8 + json.len() as u64 + if faces == 0 { 0 } else { 8 + bin_padded };
            let mut out = OutFile::create(&me.path)?;
            out.put(GLB_MAGIC)?;
            out.put(&2u32.to_le_bytes())?;
            out.put(&(total as u32).to_le_bytes())?;
            out.put(&(json.len() as u32).to_le_bytes())?;
            out.put(&CHUNK_JSON.to_le_bytes())?;
            out.put(&json)?;
            if faces > 0 {
                out.put(&(bin_padded as u32).to_le_bytes())?;
                out.put(&CHUNK_BIN.to_le_bytes())?;
                write_bin(&mut out)?;
                out.put(&vec![0u8; (bin_padded - bin_len) as usize])?;
            }
            out.commit()
        } else {
            let mut n = 0;
            if faces > 0 {
                let bin_path = me.path.with_file_name(&bin_name);
                let mut out = OutFile::create(&bin_path)?;
                write_bin(&mut out)?;
                n += out.commit()?;
            }
            let mut out = OutFile::create(&me.path)?;
            out.put(&json)?;
            Ok(n + out.commit()?)
        }
    }
}
