//! Range images: a [`RangeImage`] is a `cols × rows` grid of cells, each
//! empty or holding one sample point (in the scan's own frame), as a range
//! scanner delivers them. It comes from a PLY file with a `range_grid`
//! element ([`RangeImage::read`], through mint-io) and goes back to one
//! ([`RangeImage::write_ply`], binary little-endian, the layout of the
//! Stanford scans: `obj_info num_cols/num_rows`, `element vertex` with float
//! `x y z`, `element range_grid` with `list uchar int vertex_indices`, one
//! record per cell, row-major, list length 0 or 1).
//!
//! [`RangeImage::triangulate`] turns it into triangles (Turk and Levoy 1994,
//! §3.3): for each 2×2 block of cells, split along the shorter of the two
//! 3D diagonals and keep each of the two triangles only if all its edges
//! are shorter than `max_edge` (mint's default: 4·s, s from
//! [`RangeImage::sampling_distance`]); a block with three samples gives at
//! most one triangle. The edge test is what keeps depth discontinuities
//! from being bridged: across a silhouette, neighbouring cells are close in
//! the image but far apart in depth. All triangles are wound the same way
//! in the image (counter-clockwise in (column, row)), so the mesh is
//! consistently oriented; [`crate::scan_mesh`] flips it to face the scanner.
//!
//! Source: G. Turk and M. Levoy, "Zippered Polygon Meshes from Range
//! Images", SIGGRAPH 1994, §3.3.

use crate::error::RangeError;
use glam::DVec3;
use std::io::Write;
use std::path::Path;

/// A grid of range samples; see the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeImage {
    /// Cells per row.
    pub cols: u32,
    /// Rows.
    pub rows: u32,
    /// `cols × rows` cells, row-major: index into `points`, if sampled.
    pub cells: Vec<Option<u32>>,
    /// Sample points, in the scan's own frame.
    pub points: Vec<[f64; 3]>,
}

impl RangeImage {
    /// The sample at (`col`, `row`), if any.
    #[inline]
    pub fn at(&self, col: u32, row: u32) -> Option<u32> {
        self.cells[row as usize * self.cols as usize + col as usize]
    }

    /// Reads a PLY range image. Errors: anything mint-io reports (with file
    /// and position), and [`RangeError::EmptyScan`] when the file has no
    /// `range_grid` element or no samples.
    pub fn read(path: &Path) -> Result<RangeImage, RangeError> {
        let reader = mint_io::MeshReader::open(path, mint_io::ReadOptions { resolve_positions: false, ..Default::default() })?;
        let grid = reader
            .range_grid()
            .ok_or_else(|| RangeError::empty(path, "not a range image (no range_grid element)"))?;
        let points: Vec<[f64; 3]> = (0..reader.vertex_count()).map(|i| reader.vertex(i)).collect();
        if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(RangeError::empty(path, format!("vertex {i} has a non-finite coordinate")));
        }
        if grid.filled() == 0 {
            return Err(RangeError::empty(path, "the range grid has no samples"));
        }
        Ok(RangeImage { cols: grid.cols, rows: grid.rows, cells: grid.cells, points })
    }

    /// Writes the image as a binary little-endian PLY range image (see the
    /// module docs), atomically. Only sampled points are written, in cell
    /// order. `comment` lines go into the header.
    pub fn write_ply(&self, path: &Path, comments: &[String]) -> Result<(), RangeError> {
        let io_err = |e: std::io::Error| RangeError::File { path: path.to_path_buf(), what: "cannot write the range image", source: e };
        let mut order = Vec::new();
        let mut renum = vec![u32::MAX; self.points.len()];
        for &c in self.cells.iter().flatten() {
            if renum[c as usize] == u32::MAX {
                renum[c as usize] = order.len() as u32;
                order.push(c);
            }
        }
        let mut buf = Vec::with_capacity(64 + order.len() * 12 + self.cells.len() * 5);
        write!(buf, "ply\nformat binary_little_endian 1.0\n").map_err(io_err)?;
        for c in comments {
            writeln!(buf, "comment {}", c.replace(['\n', '\r'], " ")).map_err(io_err)?;
        }
        write!(
            buf,
            "obj_info num_cols {}\nobj_info num_rows {}\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
element range_grid {}\nproperty list uchar int vertex_indices\nend_header\n",
            self.cols,
            self.rows,
            order.len(),
            self.cells.len()
        )
        .map_err(io_err)?;
        for &i in &order {
            for c in self.points[i as usize] {
                buf.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        for c in &self.cells {
            match c {
                Some(i) => {
                    buf.push(1);
                    buf.extend_from_slice(&(renum[*i as usize] as i32).to_le_bytes());
                }
                None => buf.push(0),
            }
        }
        let mut f = mint_io::AtomicFile::create(path)?;
        f.as_file_mut().write_all(&buf).map_err(io_err)?;
        f.commit()?;
        Ok(())
    }

    /// The sampling distance s of Turk and Levoy: the distance between
    /// neighbouring samples once the image is flattened (depth, the
    /// component along `toward_scanner`, ignored). mint takes the median
    /// over horizontal neighbours and over vertical neighbours, and the
    /// larger of the two, so that a few pairs across silhouettes do not
    /// decide it. 0 if no two neighbouring cells are sampled.
    pub fn sampling_distance(&self, toward_scanner: DVec3) -> f64 {
        let flat = |a: u32, b: u32| {
            let d = DVec3::from(self.points[b as usize]) - DVec3::from(self.points[a as usize]);
            let d = d - toward_scanner * d.dot(toward_scanner);
            d.length()
        };
        let mut h = Vec::new();
        let mut v = Vec::new();
        for r in 0..self.rows {
            for c in 0..self.cols {
                if let Some(a) = self.at(c, r) {
                    if c + 1 < self.cols {
                        if let Some(b) = self.at(c + 1, r) {
                            h.push(flat(a, b));
                        }
                    }
                    if r + 1 < self.rows {
                        if let Some(b) = self.at(c, r + 1) {
                            v.push(flat(a, b));
                        }
                    }
                }
            }
        }
        median(&mut h).max(median(&mut v))
    }

    /// Triangles of the image (see the module docs), as indices into
    /// `points`, counter-clockwise in (column, row).
    pub fn triangulate(&self, max_edge: f64) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        let ok = |t: [u32; 3]| {
            let p = t.map(|i| DVec3::from(self.points[i as usize]));
            p[0].distance(p[1]) < max_edge && p[1].distance(p[2]) < max_edge && p[2].distance(p[0]) < max_edge
        };
        for r in 0..self.rows.saturating_sub(1) {
            for c in 0..self.cols.saturating_sub(1) {
                let (a, b, cc, d) = (self.at(c, r), self.at(c + 1, r), self.at(c, r + 1), self.at(c + 1, r + 1));
                let tris: [Option<[u32; 3]>; 2] = match (a, b, cc, d) {
                    (Some(a), Some(b), Some(cc), Some(d)) => {
                        let pa = DVec3::from(self.points[a as usize]);
                        let pb = DVec3::from(self.points[b as usize]);
                        let pc = DVec3::from(self.points[cc as usize]);
                        let pd = DVec3::from(self.points[d as usize]);
                        if pa.distance(pd) <= pb.distance(pc) {
                            [Some([a, b, d]), Some([a, d, cc])]
                        } else {
                            [Some([a, b, cc]), Some([b, d, cc])]
                        }
                    }
                    (None, Some(b), Some(cc), Some(d)) => [Some([b, d, cc]), None],
                    (Some(a), None, Some(cc), Some(d)) => [Some([a, d, cc]), None],
                    (Some(a), Some(b), None, Some(d)) => [Some([a, b, d]), None],
                    (Some(a), Some(b), Some(cc), None) => [Some([a, b, cc]), None],
                    _ => [None, None],
                };
                for t in tris.into_iter().flatten() {
                    if ok(t) {
                        out.push(t);
                    }
                }
            }
        }
        out
    }

    /// Every `step`-th row and column (`step ≥ 1`): the coarser images of
    /// the registration hierarchy. Points are shared, not copied.
    pub fn subsample(&self, step: u32) -> RangeImage {
        let step = step.max(1);
        let cols = self.cols.div_ceil(step);
        let rows = self.rows.div_ceil(step);
        let mut cells = Vec::with_capacity(cols as usize * rows as usize);
        for r in 0..rows {
            for c in 0..cols {
                cells.push(self.at(c * step, r * step));
            }
        }
        RangeImage { cols, rows, cells, points: self.points.clone() }
    }
}

/// The median of `v` (0 for an empty slice); reorders `v`.
pub(crate) fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let m = v.len() / 2;
    *v.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×3 image of a flat plane z = 0 with unit spacing, with cells
    /// removed as given, and an optional depth step.
    fn image(missing: &[(u32, u32)], step_at_col: Option<u32>) -> RangeImage {
        let (cols, rows) = (4u32, 3u32);
        let mut cells = Vec::new();
        let mut points = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                if missing.contains(&(c, r)) {
                    cells.push(None);
                    continue;
                }
                let z = match step_at_col {
                    Some(s) if c >= s => -10.0,
                    _ => 0.0,
                };
                cells.push(Some(points.len() as u32));
                points.push([c as f64, -(r as f64), z]);
            }
        }
        RangeImage { cols, rows, cells, points }
    }

    #[test]
    fn a_full_grid_gives_two_triangles_per_block() {
        let im = image(&[], None);
        assert_eq!(im.sampling_distance(DVec3::Z), 1.0);
        let t = im.triangulate(4.0);
        // 3 × 2 blocks, two triangles each.
        assert_eq!(t.len(), 12);
        // Equal diagonals: the a–d split is taken.
        assert_eq!(t[0], [0, 1, 5]);
        assert_eq!(t[1], [0, 5, 4]);
        // Counter-clockwise in (col, row) means clockwise seen from +z here
        // (rows go down in y): every normal points to -z.
        for f in &t {
            let [a, b, c] = f.map(|i| DVec3::from(im.points[i as usize]));
            assert!((b - a).cross(c - a).z < 0.0);
        }
    }

    #[test]
    fn missing_samples_leave_single_triangles_and_holes() {
        // Cell (1,1) missing: the four blocks around it keep one triangle
        // each (three samples), the other two blocks two each.
        let im = image(&[(1, 1)], None);
        assert_eq!(im.triangulate(4.0).len(), 4 + 4);
    }

    #[test]
    fn depth_discontinuities_are_not_bridged() {
        // Columns 2..4 sit 10 units behind: the blocks between columns 1 and
        // 2 have edges of length ≥ 10 > 4s and are dropped.
        let im = image(&[], Some(2));
        let t = im.triangulate(4.0 * im.sampling_distance(DVec3::Z));
        assert_eq!(t.len(), 8);
        for f in &t {
            let zs: Vec<f64> = f.iter().map(|&i| im.points[i as usize][2]).collect();
            assert!(zs.iter().all(|&z| z == zs[0]));
        }
    }

    #[test]
    fn the_shorter_diagonal_is_chosen() {
        let mut im = image(&[], None);
        // Pull sample (1,0) towards (0,1): the b–c diagonal of block (0,0) becomes shorter.
        im.points[1] = [0.6, -0.4, 0.0];
        let t = im.triangulate(4.0);
        assert_eq!(t[0], [0, 1, 4]);
        assert_eq!(t[1], [1, 5, 4]);
    }

    #[test]
    fn ply_round_trip_through_mint_io() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.ply");
        let im = image(&[(0, 0), (3, 2)], None);
        im.write_ply(&p, &["test".into()]).unwrap();
        let back = RangeImage::read(&p).unwrap();
        assert_eq!(back, im);
        let sub = im.subsample(2);
        assert_eq!((sub.cols, sub.rows), (2, 2));
        assert_eq!(sub.cells, vec![None, im.at(2, 0), im.at(0, 2), im.at(2, 2)]);
    }
}
