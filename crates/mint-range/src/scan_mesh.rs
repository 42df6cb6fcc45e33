//! One scan as a mesh with everything the later steps weigh it by. A
//! [`ScanMesh`] holds, in the scan's own frame: positions, triangles facing
//! the scanner, per-vertex normals, boundary flags, **confidence**, the
//! sampling distance s, and the vertex subsets of the registration
//! hierarchy. It is built from a [`RangeImage`]
//! ([`ScanMesh::from_range_image`]) or from a triangle mesh of one view
//! ([`ScanMesh::from_triangles`]); [`load_scan`] picks by content.
//!
//! Confidence (Turk and Levoy 1994, §4.3): `max(0, n·L)` with `n` the
//! vertex normal (area-weighted mean of the incident face normals) and `L`
//! the direction to the scanner ([`MeshOptions::toward_scanner`]; the view
//! direction, since the light direction of the scanners used here is not
//! recorded), times a ramp that lowers it near the mesh boundary, where
//! structured-light scanners extend and curl surfaces: a vertex `h` edges
//! away from the boundary keeps `min(1, (h + 1) / (ramp + 1))` of it
//! ([`MeshOptions::boundary_ramp`], default 4). Vertices used by no
//! triangle have confidence 0.
//!
//! Orientation: triangles are flipped, all together, so that their
//! area-weighted mean normal points towards the scanner: a scanner sees the
//! outside of an object, so its mesh faces outward.

use crate::error::RangeError;
use glam::DVec3;
use crate::range_image::{median, RangeImage};
use std::path::Path;

/// How scans become meshes. Every field has a documented default.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshOptions {
    /// Triangles with an edge of `edge_factor · s` or longer are dropped.
    /// Default 4 (Turk and Levoy's "typically 4s").
    pub edge_factor: f64,
    /// Unit direction from the scan to the scanner, in the scan's own frame.
    /// Default `[0, 0, 1]`: the Cyberware convention of the Stanford scans
    /// (depth along z, the scanner on the +z side), which `mint scan` writes
    /// too.
    pub toward_scanner: DVec3,
    /// Edges over which confidence ramps up from the boundary. Default 4.
    pub boundary_ramp: u32,
    /// Levels of the registration hierarchy (each level has a quarter of the
    /// samples of the next finer one). Default 4.
    pub levels: u32,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions { edge_factor: 4.0, toward_scanner: DVec3::Z, boundary_ramp: 4, levels: 4 }
    }
}

/// A scan as a mesh; see the module docs.
#[derive(Debug, Clone)]
pub struct ScanMesh {
    /// A name for reports (the file name).
    pub name: String,
    /// Positions in the scan's own frame.
    pub positions: Vec<[f64; 3]>,
    /// Triangles, facing the scanner.
    pub faces: Vec<[u32; 3]>,
    /// Unit vertex normals (zero for unused vertices).
    pub normals: Vec<DVec3>,
    /// Per-vertex confidence in `[0, 1]`.
    pub confidence: Vec<f64>,
    /// Vertex lies on a boundary edge (an edge of one triangle).
    pub boundary: Vec<bool>,
    /// Per-face: a corner is a boundary vertex.
    pub face_on_boundary: Vec<bool>,
    /// Per-face mean confidence of the corners.
    pub face_confidence: Vec<f64>,
    /// Direction to the scanner, own frame.
    pub toward_scanner: DVec3,
    /// The sampling distance s.
    pub sampling: f64,
    /// Longest edge allowed in the triangulation (`edge_factor · s`).
    pub max_edge: f64,
    /// Vertex subsets of the hierarchy, coarsest first; the last level holds
    /// every used vertex.
    pub levels: Vec<Vec<u32>>,
}

/// Reads one scan: a PLY range image (triangulated here) or any mesh file
/// mint-io reads (taken as the mesh of one view). `name` defaults to the
/// file name.
pub fn load_scan(path: &Path, opts: &MeshOptions) -> Result<ScanMesh, RangeError> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    if crate::depth_grid::is_depth_grid(path) {
        let im = crate::depth_grid::read_depth_grid(path)?;
        return ScanMesh::from_range_image(&name, &im, opts).map_err(|e| with_path(e, path));
    }
    let read = mint_io::ReadOptions { resolve_positions: false, ..Default::default() };
    if mint_io::MeshReader::open(path, read.clone())?.range_grid().is_some() {
        let im = RangeImage::read(path)?;
        return ScanMesh::from_range_image(&name, &im, opts).map_err(|e| with_path(e, path));
    }
    let whole = mint_io::read_mesh_with(path, read, || true)?;
    ScanMesh::from_triangles(&name, whole.positions, whole.faces, opts).map_err(|e| with_path(e, path))
}

/// Loads every scan of a set. A scan file that does not exist or cannot
/// be opened gives [`RangeError::MissingScan`] naming the set file and the
/// line that lists it.
pub fn load_set(set: &crate::ScanSet, set_path: &Path, opts: &MeshOptions) -> Result<Vec<ScanMesh>, RangeError> {
    set.entries
        .iter()
        .map(|e| {
            if let Err(source) = std::fs::File::open(&e.path) {
                return Err(RangeError::MissingScan { set: set_path.to_path_buf(), line: e.line, scan: e.path.clone(), source });
            }
            load_scan(&e.path, opts)
        })
        .collect()
}

fn with_path(e: RangeError, path: &Path) -> RangeError {
    match e {
        RangeError::EmptyScan { message, .. } => RangeError::empty(path, message),
        e => e,
    }
}

impl ScanMesh {
    /// Triangulates a range image (see [`crate::range_image`]) and computes
    /// normals, boundary, confidence and the hierarchy (every `2^k`-th row
    /// and column).
    pub fn from_range_image(name: &str, im: &RangeImage, opts: &MeshOptions) -> Result<ScanMesh, RangeError> {
        check_options(opts)?;
        let toward = opts.toward_scanner.normalize_or_zero();
        let s = im.sampling_distance(toward);
        if s <= 0.0 {
            return Err(RangeError::empty(Path::new(name), "no two neighbouring cells are sampled"));
        }
        let max_edge = opts.edge_factor * s;
        let faces = im.triangulate(max_edge);
        let mut m = ScanMesh::assemble(name, im.points.clone(), faces, toward, s, max_edge, opts)?;
        let mut levels = Vec::new();
        for l in (0..opts.levels).rev() {
            let step = 1u32 << l;
            let mut v = Vec::new();
            for r in (0..im.rows).step_by(step as usize) {
                for c in (0..im.cols).step_by(step as usize) {
                    if let Some(i) = im.at(c, r) {
                        v.push(i);
                    }
                }
            }
            v.retain(|&i| m.normals[i as usize] != DVec3::ZERO);
            levels.push(v);
        }
        m.levels = levels;
        Ok(m)
    }

    /// A mesh of one view: s is the median edge length, and the hierarchy
    /// takes every `4^k`-th used vertex.
    pub fn from_triangles(name: &str, positions: Vec<[f64; 3]>, faces: Vec<[u32; 3]>, opts: &MeshOptions) -> Result<ScanMesh, RangeError> {
        check_options(opts)?;
        let n = positions.len() as u32;
        if let Some(f) = faces.iter().find(|f| f.iter().any(|&i| i >= n)) {
            return Err(RangeError::empty(Path::new(name), format!("face {f:?} refers past the {n} vertices")));
        }
        let mut lens: Vec<f64> = faces.iter().map(|f| DVec3::from(positions[f[0] as usize]).distance(DVec3::from(positions[f[1] as usize]))).collect();
        let s = median(&mut lens);
        let toward = opts.toward_scanner.normalize_or_zero();
        let mut m = ScanMesh::assemble(name, positions, faces, toward, s, f64::INFINITY, opts)?;
        let used: Vec<u32> = (0..n).filter(|&i| m.normals[i as usize] != DVec3::ZERO).collect();
        m.levels = (0..opts.levels).rev().map(|l| used.iter().copied().step_by(1 << (2 * l)).collect()).collect();
        Ok(m)
    }

    fn assemble(name: &str, positions: Vec<[f64; 3]>, mut faces: Vec<[u32; 3]>, toward: DVec3, s: f64, max_edge: f64, opts: &MeshOptions) -> Result<ScanMesh, RangeError> {
        if faces.is_empty() {
            return Err(RangeError::empty(Path::new(name), "no triangle survives the edge-length cutoff"));
        }
        // Face the scanner.
        let mut sum = DVec3::ZERO;
        for f in &faces {
            sum += face_normal(&positions, *f);
        }
        if sum.dot(toward) < 0.0 {
            for f in &mut faces {
                f.swap(1, 2);
            }
        }
        let normals = vertex_normals(&positions, &faces);
        let boundary = boundary_vertices(positions.len(), &faces);
        let hops = hops_from(&boundary, &faces, opts.boundary_ramp + 1);
        let ramp = opts.boundary_ramp as f64;
        let confidence: Vec<f64> = (0..positions.len())
            .map(|i| {
                let c = normals[i].dot(toward).max(0.0);
                c * ((hops[i] as f64 + 1.0) / (ramp + 1.0)).min(1.0)
            })
            .collect();
        let face_on_boundary = faces.iter().map(|f| f.iter().any(|&i| boundary[i as usize])).collect();
        let face_confidence = faces.iter().map(|f| f.iter().map(|&i| confidence[i as usize]).sum::<f64>() / 3.0).collect();
        Ok(ScanMesh {
            name: name.to_string(),
            positions,
            faces,
            normals,
            confidence,
            boundary,
            face_on_boundary,
            face_confidence,
            toward_scanner: toward,
            sampling: s,
            max_edge,
            levels: Vec::new(),
        })
    }

    /// The corners of the bounding box of the used vertices (for pose
    /// error reports).
    pub fn bbox_corners(&self) -> Vec<[f64; 3]> {
        let (lo, hi) = bbox(self.faces.iter().flatten().map(|&i| self.positions[i as usize]));
        (0..8).map(|k| [if k & 1 == 0 { lo[0] } else { hi[0] }, if k & 2 == 0 { lo[1] } else { hi[1] }, if k & 4 == 0 { lo[2] } else { hi[2] }]).collect()
    }
}

fn check_options(opts: &MeshOptions) -> Result<(), RangeError> {
    if !(opts.edge_factor.is_finite() && opts.edge_factor > 0.0) {
        return Err(RangeError::option("edge_factor", format!("{} is not a positive number", opts.edge_factor)));
    }
    if opts.toward_scanner.length() == 0.0 || !opts.toward_scanner.is_finite() {
        return Err(RangeError::option("toward_scanner", "must be a non-zero finite vector"));
    }
    if opts.levels == 0 || opts.levels > 8 {
        return Err(RangeError::option("levels", format!("{} is not in 1..=8", opts.levels)));
    }
    Ok(())
}

/// The bounding box of some points.
pub fn bbox(points: impl IntoIterator<Item = [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Twice the area vector of face `f` (right-hand normal, length = 2·area).
#[inline]
pub fn face_normal(positions: &[[f64; 3]], f: [u32; 3]) -> DVec3 {
    let [a, b, c] = f.map(|i| DVec3::from(positions[i as usize]));
    (b - a).cross(c - a)
}

/// Unit area-weighted vertex normals (zero for unused vertices).
pub use mint_mesh::normals::vertex_normals;

/// Vertices on an edge used by exactly one face (or by more than two).
pub fn boundary_vertices(n: usize, faces: &[[u32; 3]]) -> Vec<bool> {
    let mut edges: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k].min(f[(k + 1) % 3]), f[k].max(f[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    let mut b = vec![false; n];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j] == edges[i] {
            j += 1;
        }
        if j - i != 2 {
            b[edges[i].0 as usize] = true;
            b[edges[i].1 as usize] = true;
        }
        i = j;
    }
    b
}

/// Edge hops from the nearest `true` vertex, capped at `cap`.
fn hops_from(seed: &[bool], faces: &[[u32; 3]], cap: u32) -> Vec<u32> {
    let mut h: Vec<u32> = seed.iter().map(|&b| if b { 0 } else { cap }).collect();
    for round in 0..cap {
        let mut changed = false;
        for f in faces {
            for k in 0..3 {
                let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
                if h[a] == round && h[b] > round + 1 {
                    h[b] = round + 1;
                    changed = true;
                }
                if h[b] == round && h[a] > round + 1 {
                    h[a] = round + 1;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n×n flat grid at z = 0 seen from +z.
    fn flat(n: u32) -> RangeImage {
        let mut cells = Vec::new();
        let mut points = Vec::new();
        for r in 0..n {
            for c in 0..n {
                cells.push(Some(points.len() as u32));
                points.push([c as f64, -(r as f64), 0.0]);
            }
        }
        RangeImage { cols: n, rows: n, cells, points }
    }

    #[test]
    fn a_flat_view_faces_the_scanner_with_boundary_ramped_confidence() {
        let m = ScanMesh::from_range_image("flat", &flat(12), &MeshOptions::default()).unwrap();
        assert_eq!(m.faces.len(), 2 * 11 * 11);
        assert_eq!(m.sampling, 1.0);
        assert_eq!(m.max_edge, 4.0);
        for f in &m.faces {
            assert!(face_normal(&m.positions, *f).z > 0.0);
        }
        // Row 0 is the boundary (0.2), row k keeps (k+1)/5 up to 1.
        let at = |c: usize, r: usize| m.confidence[r * 12 + c];
        assert!((at(5, 0) - 0.2).abs() < 1e-12);
        assert!((at(5, 1) - 0.4).abs() < 1e-12);
        assert!((at(5, 3) - 0.8).abs() < 1e-12);
        assert!((at(5, 5) - 1.0).abs() < 1e-12);
        assert_eq!(m.boundary.iter().filter(|&&b| b).count(), 44);
        // Levels: every 8th, 4th, 2nd row/col, then all.
        assert_eq!(m.levels.iter().map(Vec::len).collect::<Vec<_>>(), vec![4, 9, 36, 144]);
    }

    #[test]
    fn a_tilted_view_has_cosine_confidence() {
        let mut im = flat(12);
        // Tilt by 60° about the x axis: n·z = cos 60° = 0.5.
        let (s, c) = 60f64.to_radians().sin_cos();
        for p in &mut im.points {
            *p = [p[0], p[1] * c, p[1] * s];
        }
        let m = ScanMesh::from_range_image("tilted", &im, &MeshOptions::default()).unwrap();
        assert!((m.confidence[6 * 12 + 6] - 0.5).abs() < 1e-12);
    }
}

/// When `path` is a PLY range image (a `range_grid` of samples and no
/// faces), triangulates it as one scan is (shorter diagonal, no bridging of
/// depth jumps) into a temporary binary PLY in `dir`, removed when the
/// returned file is dropped; `None` for any other file. This is how
/// `mint resample` takes a range image: the engine sees a mesh.
pub fn range_image_as_mesh(path: &Path, dir: &Path) -> Result<Option<tempfile::NamedTempFile>, RangeError> {
    let reader = mint_io::MeshReader::open(path, mint_io::ReadOptions { chunk_triangles: 1, spill_dir: Some(dir.to_path_buf()), resolve_positions: false })?;
    if reader.range_grid().is_none() || reader.info().face_count.unwrap_or(0) != 0 {
        return Ok(None);
    }
    drop(reader);
    let scan = load_scan(path, &MeshOptions::default())?;
    let tmp = tempfile::Builder::new()
        .prefix(".mint-range-")
        .suffix(".ply")
        .tempfile_in(dir)
        .map_err(|source| RangeError::File { path: dir.to_path_buf(), what: "creating the range-image mesh", source })?;
    let mut w = mint_io::MeshWriter::create(tmp.path(), mint_io::Format::Ply, mint_io::WriteOptions { double: true, ..Default::default() })?;
    for p in &scan.positions {
        w.write_vertex(*p)?;
    }
    for f in &scan.faces {
        w.write_face(*f)?;
    }
    w.finish()?;
    Ok(Some(tmp))
}
