//! 3D Tiles (1.0 and 1.1): a `tileset.json` read as one surface, and a
//! single `.b3dm` tile.
//!
//! A tileset is a tree of tiles, each with an optional `transform` (a
//! column-major 4×4 matrix, relative to its parent), `content` (1.0, also
//! `url`) or `contents` (1.1), `children`, and a `refine` mode inherited
//! from its parent. The surface at the finest level is what is read: the
//! contents of the leaf tiles, and, where refinement is `ADD`, of every tile
//! on the way (their children add detail rather than replace it). Content
//! may be `.glb`/`.gltf`, `.b3dm` (a feature table, a batch table and a
//! GLB: its `RTC_CENTER` is applied) or another tileset (an external
//! tileset, read in place of the tile). glTF content is y-up and is turned
//! z-up, as 3D Tiles requires (`asset.gltfUpAxis` of old tilesets is
//! honoured). So a vertex lands at
//! `tile transforms × RTC_CENTER × y-up-to-z-up × glTF node transforms × p`,
//! all in f64, and an ECEF tileset keeps its world coordinates.
//!
//! Every content's triangles go through the glTF reader's code
//! ([`crate::gltf::append`]) into one pair of spill files, ids running on
//! across tiles. Points (`.pnts`), instances (`.i3dm`), composites
//! (`.cmpt`), implicit tiling and remote URIs are refused with one line
//! naming the tile; so are cycles of external tilesets, trees deeper than
//! [`MAX_DEPTH`] and more than [`MAX_TILES`] tiles.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde_json::Value;

use crate::backend::{ElementInfo, MeshInfo, Opened};
use crate::error::Error;
use crate::format::Format;
use crate::gltf::{append, mul, percent_decode, spilled_body, Counts, Mat, Textures, IDENTITY};
use crate::mapped::{Mapped, SpillFile};
use crate::positions::Positions;

/// Tiles nested deeper than this (tree depth plus external tilesets) are
/// refused: a cycle, or a hostile file.
pub const MAX_DEPTH: usize = 64;
/// Tiles in all, over external tilesets.
pub const MAX_TILES: usize = 1 << 20;

/// glTF's y-up to 3D Tiles' z-up: (x, y, z) → (x, −z, y).
const Y_UP_TO_Z_UP: Mat = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
/// x-up to z-up (old tilesets' `gltfUpAxis: "X"`): (x, y, z) → (−z, y, x).
const X_UP_TO_Z_UP: Mat = [[0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

fn translation(t: [f64; 3]) -> Mat {
    let mut m = IDENTITY;
    for i in 0..3 {
        m[i][3] = t[i];
    }
    m
}

fn bad(path: &Path, at: &str, msg: impl std::fmt::Display) -> Error {
    Error::format(path, format!("{at}: {msg}"))
}

/// True for a file that is a `b3dm` tile (by its magic).
pub(crate) fn is_b3dm(head: &[u8]) -> bool {
    head.starts_with(b"b3dm")
}

/// The tiles read, and what they held.
#[derive(Default)]
struct Walk {
    counts: Counts,
    /// Content files read (leaf tiles, and tiles refined by ADD).
    tiles: u64,
    /// Tiles visited, over external tilesets.
    visited: usize,
    /// External tilesets open on the current path (cycle check).
    open: HashSet<PathBuf>,
}

/// A tileset or tile being read: its spill files when reading for real.
struct Reader<'s> {
    spill_dir: PathBuf,
    spill: Option<(&'s mut SpillFile, &'s mut SpillFile)>,
    /// The tiles' materials and texture records, when reading for real.
    textures: Option<Textures>,
    walk: Walk,
}

impl Reader<'_> {
    /// Reads the tileset at `path` under `parent` (the transform of the
    /// tile whose content it is), inheriting `refine`.
    fn tileset(&mut self, path: &Path, parent: &Mat, refine: Refine, depth: usize) -> Result<(), Error> {
        let key = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if !self.walk.open.insert(key.clone()) {
            return Err(Error::format(path, "an external tileset that contains itself (a cycle of tilesets)"));
        }
        let map = Mapped::open(path, &self.spill_dir)?;
        let json: Value = serde_json::from_slice(map.bytes()).map_err(|e| Error::format(path, format!("not a 3D Tiles tileset: not JSON ({e})")))?;
        let version = json.get("asset").and_then(|a| a.get("version")).and_then(Value::as_str);
        let Some(version) = version else {
            return Err(Error::format(path, "not a 3D Tiles tileset: no asset.version"));
        };
        if !(version.starts_with("1.") || version == "0.0") {
            return Err(Error::unsupported(path, format!("3D Tiles asset version {version:?} (mint reads 1.0 and 1.1)")));
        }
        for (i, e) in json.get("extensionsRequired").and_then(Value::as_array).map_or(&[][..], Vec::as_slice).iter().enumerate() {
            return Err(Error::unsupported(path, format!("extensionsRequired[{i}]: the tileset requires extension {e}, which mint does not implement")));
        }
        let up = match json.get("asset").and_then(|a| a.get("gltfUpAxis")).and_then(Value::as_str) {
            None | Some("Y") | Some("y") => Y_UP_TO_Z_UP,
            Some("Z") | Some("z") => IDENTITY,
            Some("X") | Some("x") => X_UP_TO_Z_UP,
            Some(o) => return Err(bad(path, "asset.gltfUpAxis", format!("{o:?} is not X, Y or Z"))),
        };
        let root = json.get("root").filter(|r| r.is_object()).ok_or_else(|| Error::format(path, "not a 3D Tiles tileset: no root tile"))?;
        self.tile(path, root, "root", parent, refine, &up, depth)?;
        self.walk.open.remove(&key);
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn tile(&mut self, path: &Path, tile: &Value, at: &str, parent: &Mat, refine: Refine, up: &Mat, depth: usize) -> Result<(), Error> {
        if depth > MAX_DEPTH {
            return Err(bad(path, at, format!("tiles nested deeper than {MAX_DEPTH}")));
        }
        self.walk.visited += 1;
        if self.walk.visited > MAX_TILES {
            return Err(bad(path, at, format!("more than {MAX_TILES} tiles")));
        }
        if !tile.is_object() {
            return Err(bad(path, at, "a tile that is not a JSON object"));
        }
        if tile.get("implicitTiling").is_some() {
            return Err(Error::unsupported(path, format!("{at}: implicit tiling (subtree files) is not read; export explicit tiles")));
        }
        let world = match tile.get("transform") {
            None => *parent,
            Some(t) => {
                let v: Vec<f64> = t.as_array().filter(|a| a.len() == 16).map(|a| a.iter().filter_map(Value::as_f64).collect()).unwrap_or_default();
                if v.len() != 16 || v.iter().any(|x| !x.is_finite()) {
                    return Err(bad(path, &format!("{at}.transform"), "not 16 finite numbers"));
                }
                // Column-major: element (row r, column c) is v[4c + r].
                let mut m = [[0.0; 4]; 4];
                for (r, row) in m.iter_mut().enumerate() {
                    for (c, x) in row.iter_mut().enumerate() {
                        *x = v[4 * c + r];
                    }
                }
                mul(parent, &m)
            }
        };
        let refine = match tile.get("refine").and_then(Value::as_str) {
            None => refine,
            Some(s) if s.eq_ignore_ascii_case("ADD") => Refine::Add,
            Some(s) if s.eq_ignore_ascii_case("REPLACE") => Refine::Replace,
            Some(s) => return Err(bad(path, &format!("{at}.refine"), format!("{s:?} is neither ADD nor REPLACE"))),
        };
        let children = match tile.get("children") {
            None => &[][..],
            Some(Value::Array(c)) => c.as_slice(),
            Some(_) => return Err(bad(path, &format!("{at}.children"), "not an array")),
        };
        // The finest level: leaves, and every tile that its children only add to.
        if children.is_empty() || refine == Refine::Add {
            let mut contents: Vec<(String, &Value)> = Vec::new();
            if let Some(c) = tile.get("content") {
                contents.push((format!("{at}.content"), c));
            }
            if let Some(cs) = tile.get("contents").and_then(Value::as_array) {
                contents.extend(cs.iter().enumerate().map(|(i, c)| (format!("{at}.contents[{i}]"), c)));
            }
            for (cat, c) in contents {
                let uri = c.get("uri").or_else(|| c.get("url")).and_then(Value::as_str).ok_or_else(|| bad(path, &cat, "a content without a uri"))?;
                self.content(path, &cat, uri, &world, refine, up, depth)?;
            }
        }
        for (i, child) in children.iter().enumerate() {
            self.tile(path, child, &format!("{at}.children[{i}]"), &world, refine, up, depth + 1)?;
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn content(&mut self, tileset: &Path, at: &str, uri: &str, world: &Mat, refine: Refine, up: &Mat, depth: usize) -> Result<(), Error> {
        let rel = uri.split(['?', '#']).next().unwrap_or("");
        if rel.contains("://") || rel.starts_with("data:") {
            return Err(bad(tileset, at, format!("content {uri:?}: only files beside the tileset are read")));
        }
        let file = tileset.parent().unwrap_or(Path::new(".")).join(percent_decode(rel));
        let ext = file.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        match ext.as_str() {
            "json" => return self.tileset(&file, world, refine, depth + 1).map_err(|e| within(tileset, at, e)),
            "pnts" | "i3dm" | "cmpt" | "vctr" | "geom" | "subtree" => {
                return Err(Error::unsupported(tileset, format!("{at}: content {uri:?} is a .{ext} tile, which mint does not read (it reads glb, gltf, b3dm and external tilesets)")));
            }
            _ => {}
        }
        let map = Arc::new(Mapped::open(&file, &self.spill_dir).map_err(|e| within(tileset, at, e))?);
        self.walk.tiles += 1;
        self.model(&file, &map, world, up).map_err(|e| within(tileset, at, e))
    }

    /// One model file: a b3dm, or a glTF/GLB, drawn under `world`.
    fn model(&mut self, file: &Path, map: &Arc<Mapped>, world: &Mat, up: &Mat) -> Result<(), Error> {
        let data = map.bytes();
        let (range, rtc) = if is_b3dm(data) { b3dm(file, data)? } else { ((0, data.len()), [0.0; 3]) };
        let prefix = mul(&mul(world, &translation(rtc)), up);
        let spill = self.spill.as_mut().map(|(v, f)| (&mut **v, &mut **f));
        append(file, map, range, &prefix, &self.spill_dir, &mut self.walk.counts, spill, self.textures.as_mut())
    }
}

/// An error inside a tile's content, with the tile it came from.
fn within(tileset: &Path, at: &str, e: Error) -> Error {
    Error::format(tileset, format!("{at}: {e}"))
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Refine {
    Add,
    Replace,
}

/// The GLB inside a b3dm and its RTC_CENTER.
fn b3dm(path: &Path, data: &[u8]) -> Result<((usize, usize), [f64; 3]), Error> {
    if data.len() < 28 {
        return Err(Error::format(path, format!("a b3dm of {} bytes, shorter than its 28-byte header", data.len())));
    }
    let u32_at = |o: usize| u32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]) as usize;
    let version = u32_at(4);
    if version != 1 {
        return Err(Error::unsupported(path, format!("b3dm version {version} (mint reads 1)")));
    }
    let total = u32_at(8);
    if total > data.len() {
        return Err(Error::format(path, format!("the b3dm header says {total} bytes, the file holds {}", data.len())));
    }
    let (ftj, ftb, btj, btb) = (u32_at(12), u32_at(16), u32_at(20), u32_at(24));
    // Old headers (before 1.0) put the batch length where the feature
    // table's JSON length is: their GLB starts at byte 20 or 24.
    if ftj >= 0x2200_0000 || ftb >= 0x2200_0000 {
        return Err(Error::unsupported(path, "a b3dm with a legacy header (before 3D Tiles 1.0); upgrade it first (e.g. 3d-tiles-tools upgrade)"));
    }
    let glb = [28usize, ftj, ftb, btj, btb].iter().try_fold(0usize, |a, &b| a.checked_add(b)).filter(|&g| g <= total).ok_or_else(|| {
        Error::format(path, format!("the b3dm's tables ({ftj} + {ftb} + {btj} + {btb} bytes) run past its length ({total} bytes)"))
    })?;
    let mut rtc = [0.0; 3];
    if ftj > 0 {
        let table: Value = serde_json::from_slice(&data[28..28 + ftj]).map_err(|e| Error::format(path, format!("the b3dm's feature table is not JSON ({e})")))?;
        match table.get("RTC_CENTER") {
            None => {}
            Some(Value::Array(a)) if a.len() == 3 && a.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)) => {
                for k in 0..3 {
                    rtc[k] = a[k].as_f64().unwrap_or(0.0);
                }
            }
            Some(v) if v.get("byteOffset").is_some() => {
                let off = v["byteOffset"].as_u64().filter(|&o| o % 4 == 0 && o + 24 <= ftb as u64).ok_or_else(|| {
                    Error::format(path, "the b3dm's RTC_CENTER byteOffset is not inside its feature table's binary body")
                })? as usize;
                let at = 28 + ftj + off;
                for k in 0..3 {
                    let b: [u8; 8] = data[at + 8 * k..at + 8 * k + 8].try_into().unwrap_or([0; 8]);
                    rtc[k] = f64::from_le_bytes(b);
                }
                if rtc.iter().any(|x| !x.is_finite()) {
                    return Err(Error::format(path, "the b3dm's RTC_CENTER is not finite"));
                }
            }
            Some(_) => return Err(Error::format(path, "the b3dm's RTC_CENTER is neither three numbers nor a byteOffset")),
        }
    }
    if glb + 20 > total || &data[glb..glb + 4] != b"glTF" {
        return Err(Error::format(path, format!("the b3dm holds no GLB at byte {glb}")));
    }
    Ok(((glb, total), rtc))
}

fn read(path: &Path, b3dm_file: bool, spill_dir: &Path, spill: Option<(&mut SpillFile, &mut SpillFile)>) -> Result<(Walk, Option<Textures>), Error> {
    let textures = spill.is_some().then(|| Textures::new(path));
    let mut r = Reader { spill_dir: spill_dir.to_path_buf(), spill, textures, walk: Walk::default() };
    if b3dm_file {
        // A lone b3dm: one tile, z-up, its RTC_CENTER applied.
        let map = Arc::new(Mapped::open(path, spill_dir)?);
        r.walk.tiles = 1;
        r.model(path, &map, &IDENTITY, &Y_UP_TO_Z_UP)?;
    } else {
        r.tileset(path, &IDENTITY, Refine::Replace, 0)?;
    }
    Ok((r.walk, r.textures))
}

fn make_info(w: &Walk) -> MeshInfo {
    let c = &w.counts;
    MeshInfo {
        format: Format::Tiles,
        encoding: "3D Tiles".into(),
        vertex_count: c.vertices,
        face_count: Some(c.triangles),
        elements: vec![
            ElementInfo { name: "tiles".into(), count: w.tiles, properties: vec![format!("content files read at the finest level, of {} tiles", w.visited)] },
            ElementInfo { name: "POSITION".into(), count: c.vertices, properties: vec!["float[3] x y z (tile, RTC and node transforms applied, z-up)".into()] },
            ElementInfo { name: "triangles".into(), count: c.triangles, properties: vec![] },
        ],
        comments: Vec::new(),
        obj_info: Vec::new(),
    }
}

pub(crate) fn info(path: &Path, data: &[u8]) -> Result<MeshInfo, Error> {
    Ok(make_info(&read(path, is_b3dm(data), &std::env::temp_dir(), None)?.0))
}

pub(crate) fn open(path: &Path, map: Arc<Mapped>, spill_dir: &Path) -> Result<Opened, Error> {
    let (mut vs, mut fs) = (SpillFile::new(spill_dir, path)?, SpillFile::new(spill_dir, path)?);
    let (w, textures) = read(path, is_b3dm(map.bytes()), spill_dir, Some((&mut vs, &mut fs)))?;
    // The tiles' vertex colours, or their materials and textures
    // (photogrammetry tiles are textured), numbered over all tiles.
    let (colours, texturing) = match textures {
        Some(t) => t.finish(w.counts.vertices)?,
        None => (None, None),
    };
    let c = w.counts;
    let info = make_info(&w);
    let positions = Positions::spilled(Arc::new(vs.into_mapped()?), c.vertices as u32);
    let faces = Arc::new(fs.into_mapped()?);
    let body = spilled_body(path, faces, c.triangles, map.bytes().len() as u64);
    Ok(Opened { info, positions, body, range_grid: None, spilled_vertices: c.vertices, colours, face_colours: None, texturing })
}
