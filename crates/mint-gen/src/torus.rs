//! The torus around the z axis: [`TorusGrid`] picks a resolution for a face
//! budget, [`torus()`] streams it. Vertex `(i, j)`, `i` in `0..U` around
//! the axis (angle `u = 2π i / U`) and `j` in `0..W` around the tube
//! (`v = 2π j / W`), has index `i·W + j` and position
//! `center + ((R + r cos v) cos u, (R + r cos v) sin u, r sin v)`. Each grid
//! quad `a = (i,j)`, `b = (i+1,j)`, `c = (i+1,j+1)`, `d = (i,j+1)` (indices
//! wrapping) gives faces `(a,b,c)` and `(a,c,d)`, counter-clockwise seen
//! from outside since `∂p/∂u × ∂p/∂v` points away from the tube's core.
//! `V = U·W`, `F = 2·U·W`, genus 1; memory is two trig tables.

use crate::error::GenError;
use crate::surface::{ExactSurface, TorusSurface};
use crate::{check_vertex_count, finite3, positive, Generated};
use mint_core::MeshSink;
use std::f64::consts::PI;

/// Resolution of a torus: `around` steps around the axis (`U`, at least 3)
/// and `tube` steps around the tube (`W`, at least 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TorusGrid {
    pub around: u32,
    pub tube: u32,
}

impl TorusGrid {
    /// The resolution with `2·U·W` nearest to `target_faces` among grids
    /// whose quads are roughly square on the tube's centre circle
    /// (`U/W` within a factor 1.5 of `major/minor`, both at least 3). For a
    /// given `W`, `U` is rounded, so `|faces - target| ≤ W` with
    /// `W ≈ √(target·minor/(2·major))`: under 1% from 10³ faces for
    /// `major/minor ≥ 3`, often exact. At least 18 faces.
    pub fn for_faces(target_faces: u64, major: f64, minor: f64) -> Self {
        let k = (major / minor).max(1.0);
        // Beyond 2³⁶ faces the vertices overflow u32 anyway.
        let t = target_faces.clamp(18, 1 << 36) as f64;
        let w0 = (t / (2.0 * k)).sqrt();
        let lo = ((w0 * 0.6).floor() as u64).max(3);
        let hi = ((w0 * 1.5).ceil() as u64).max(3) + 2;
        let mut best: Option<((bool, u64, f64), TorusGrid)> = None;
        for w in lo..=hi {
            let u = ((t / (2.0 * w as f64)).round() as u64).max(3);
            let (Ok(around), Ok(tube)) = (u32::try_from(u), u32::try_from(w)) else {
                continue;
            };
            let ratio = (u as f64 / w as f64) / k;
            let key = (
                !(1.0 / 1.5..=1.5).contains(&ratio),
                (2 * u * w).abs_diff(t as u64),
                ratio.ln().abs(),
            );
            if best.as_ref().is_none_or(|(b, _)| key < *b) {
                best = Some((key, TorusGrid { around, tube }));
            }
        }
        best.map_or(TorusGrid { around: 3, tube: 3 }, |b| b.1)
    }

    /// `2·U·W`.
    pub fn faces(&self) -> u64 {
        2 * u64::from(self.around) * u64::from(self.tube)
    }

    /// `U·W`.
    pub fn vertices(&self) -> u64 {
        u64::from(self.around) * u64::from(self.tube)
    }
}

/// A torus whose vertices and faces are computed from their index (trig
/// tables of `O(U + W)`), for streaming in order ([`torus()`]) or in any
/// order (`shuffle::torus_shuffled`).
pub(crate) struct TorusMesh {
    pub(crate) grid: TorusGrid,
    center: [f64; 3],
    major: f64,
    minor: f64,
    /// Around the axis: (cos u, sin u) per `i`.
    around: Vec<(f64, f64)>,
    /// Around the tube: (ρ, z) = (R + r cos v, r sin v) per `j`.
    ring: Vec<(f64, f64)>,
}

impl TorusMesh {
    pub(crate) fn new(center: [f64; 3], major: f64, minor: f64, target_faces: u64) -> Result<TorusMesh, GenError> {
        positive("major", major)?;
        positive("minor", minor)?;
        finite3("center", center)?;
        if minor >= major {
            return Err(GenError::InvalidParameter {
                name: "minor",
                reason: format!("minor radius {minor} must be below the major radius {major}"),
            });
        }
        let grid = TorusGrid::for_faces(target_faces, major, minor);
        check_vertex_count(grid.vertices())?;
        let (nu, nw) = (grid.around, grid.tube);
        let ring = (0..nw)
            .map(|j| {
                let v = 2.0 * PI * f64::from(j) / f64::from(nw);
                (major + minor * v.cos(), minor * v.sin())
            })
            .collect();
        let around = (0..nu)
            .map(|i| {
                let u = 2.0 * PI * f64::from(i) / f64::from(nu);
                (u.cos(), u.sin())
            })
            .collect();
        Ok(TorusMesh { grid, center, major, minor, around, ring })
    }

    /// Vertex `i·W + j`.
    #[inline]
    pub(crate) fn vertex(&self, index: u32) -> [f64; 3] {
        let (i, j) = (index / self.grid.tube, index % self.grid.tube);
        let (cu, su) = self.around[i as usize];
        let (rho, z) = self.ring[j as usize];
        let c = self.center;
        [c[0] + rho * cu, c[1] + rho * su, c[2] + z]
    }

    /// Face `2·(i·W + j) + k`: `(a, b, c)` for `k = 0`, `(a, c, d)` for `k = 1`.
    #[inline]
    pub(crate) fn face(&self, f: u64) -> [u32; 3] {
        let (nu, nw) = (self.grid.around, self.grid.tube);
        let q = (f / 2) as u32;
        let (i, j) = (q / nw, q % nw);
        let row = i * nw;
        let next = if i + 1 == nu { 0 } else { row + nw };
        let jn = if j + 1 == nw { 0 } else { j + 1 };
        let (a, b, c, d) = (row + j, next + j, next + jn, row + jn);
        if f % 2 == 0 {
            [a, b, c]
        } else {
            [a, c, d]
        }
    }

    pub(crate) fn generated(&self) -> Generated {
        Generated {
            vertices: self.grid.vertices(),
            faces: self.grid.faces(),
            components: 1,
            genus: 1,
            surface: ExactSurface::Torus(TorusSurface { center: self.center, major: self.major, minor: self.minor }),
        }
    }
}

/// Streams a torus around the axis through `center` parallel to z, with
/// major radius `major`, minor radius `minor < major`, and about
/// `target_faces` faces (see [`TorusGrid::for_faces`]). Closed, genus 1,
/// outward oriented; vertices lie on [`TorusSurface`] up to rounding.
pub fn torus(
    center: [f64; 3],
    major: f64,
    minor: f64,
    target_faces: u64,
    sink: &mut dyn MeshSink,
) -> Result<Generated, GenError> {
    let t = TorusMesh::new(center, major, minor, target_faces)?;
    for i in 0..t.grid.vertices() as u32 {
        sink.vertex(t.vertex(i))?;
    }
    for f in 0..t.grid.faces() {
        sink.face(t.face(f))?;
    }
    Ok(t.generated())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_counts_are_close_to_target() {
        for t in [1_000u64, 10_000, 123_457, 1_000_000, 50_000_000] {
            let g = TorusGrid::for_faces(t, 3.0, 1.0);
            let rel = g.faces().abs_diff(t) as f64 / t as f64;
            assert!(rel < if t >= 10_000 { 0.01 } else { 0.05 }, "{t}: {g:?}");
        }
    }

    #[test]
    fn absurd_targets_fail_fast() {
        let mut s = mint_core::CountingSink::default();
        assert!(matches!(
            torus([0.0; 3], 2.0, 1.0, u64::MAX, &mut s),
            Err(GenError::TooManyVertices { .. })
        ));
        assert!(matches!(
            crate::sphere([0.0; 3], 1.0, u64::MAX, &mut s),
            Err(GenError::TooManyVertices { .. })
        ));
        assert!(matches!(
            crate::genus(2, u64::MAX, &mut s),
            Err(GenError::TooManyVertices { .. })
        ));
        assert!(matches!(
            crate::components(u64::MAX, 0, &mut s),
            Err(GenError::TooManyVertices { .. })
        ));
        assert_eq!(s.faces, 0);
    }

    #[test]
    fn rejects_a_self_intersecting_torus() {
        let mut s = mint_core::CountingSink::default();
        assert!(matches!(
            torus([0.0; 3], 1.0, 1.0, 100, &mut s),
            Err(GenError::InvalidParameter { name: "minor", .. })
        ));
    }
}
