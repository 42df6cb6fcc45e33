//! The UV sphere: [`SphereGrid`] picks a resolution for a face budget and
//! streams the mesh; [`sphere()`] is the one-call generator. The same grid
//! carries the small spheres of [`crate::components`] and the noisy sphere
//! of [`crate::scan_like`], which is why its numbering is public.
//!
//! Numbering, with `R = rings` latitude bands and `S = segments`
//! longitudes: vertex 0 is the north pole `(0, 0, +r)`; ring `i` in
//! `1..R` (polar angle `θ_i = π i / R`) holds vertices
//! `1 + (i-1)·S + j` for `j` in `0..S` (azimuth `φ_j = 2π j / S`); the
//! south pole is last. Faces, in order: the north fan
//! `(0, v(1,j), v(1,j+1))`, then for each band `i` in `1..R-1` and each `j`
//! the quad `a = v(i,j)`, `b = v(i,j+1)`, `c = v(i+1,j)`, `d = v(i+1,j+1)`
//! split along `a–d` into `(a,c,d)` and `(a,d,b)`, then the south fan
//! `(s, v(R-1,j+1), v(R-1,j))`:
//!
//! ```text
//!   a ----- b      ring i      (θ smaller, nearer the north pole)
//!   | \     |
//!   |   \   |      (a,c,d) lower-left, (a,d,b) upper-right,
//!   |     \ |      both counter-clockwise seen from outside
//!   c ----- d      ring i+1
//!  φ_j    φ_j+1
//! ```
//!
//! `V = 2 + (R-1)·S`, `F = 2·S·(R-1)`; memory is two trig tables of
//! `O(R + S) = O(√F)` entries.

use crate::error::GenError;
use crate::surface::{ExactSurface, SphereSurface};
use crate::{check_vertex_count, finite3, positive, Generated};
use mint_core::{MeshSink, SinkError};
use std::f64::consts::PI;

/// Resolution of a UV sphere: `rings` latitude bands (at least 2) and
/// `segments` longitudes (at least 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SphereGrid {
    pub rings: u32,
    pub segments: u32,
}

impl SphereGrid {
    /// The resolution whose face count `2·S·(R-1)` is nearest to
    /// `target_faces`, among grids with `S/R` between 1.5 and 2.5 (near
    /// square quads at the equator). `|faces - target| ≤ 0.7·√target` for
    /// targets of 100 or more, often 0; below 12 faces the result is the
    /// 6-face bipyramid (`R = 2, S = 3`) or a 2-band one.
    pub fn for_faces(target_faces: u64) -> Self {
        // Beyond 2³⁶ faces the vertices overflow u32 anyway; clamping keeps
        // the search short.
        let t = target_faces.clamp(6, 1 << 36) as f64;
        let m0 = (t / 4.0).sqrt(); // F ≈ 4 m² with m = R - 1, S ≈ 2m
        let lo = ((m0 * 0.75).floor() as u64).max(1);
        let hi = (m0 * 1.3).ceil() as u64 + 2;
        // Key: out of the aspect range last, then face-count error, then
        // distance from the ideal aspect 2.
        let mut best: Option<((bool, u64, f64), SphereGrid)> = None;
        for m in lo..=hi {
            let s = ((t / (2.0 * m as f64)).round() as u64).max(3);
            let (Ok(rings), Ok(segments)) = (u32::try_from(m + 1), u32::try_from(s)) else {
                continue;
            };
            let aspect = s as f64 / (m + 1) as f64;
            let key = (
                !(1.5..=2.5).contains(&aspect),
                (2 * s * m).abs_diff(t as u64),
                (aspect - 2.0).abs(),
            );
            if best.as_ref().is_none_or(|(k, _)| key < *k) {
                best = Some((key, SphereGrid { rings, segments }));
            }
        }
        best.map_or(
            SphereGrid {
                rings: 2,
                segments: 3,
            },
            |b| b.1,
        )
    }

    /// `2·segments·(rings - 1)`.
    pub fn faces(&self) -> u64 {
        2 * u64::from(self.segments) * u64::from(self.rings - 1)
    }

    /// `2 + (rings - 1)·segments`.
    pub fn vertices(&self) -> u64 {
        2 + u64::from(self.rings - 1) * u64::from(self.segments)
    }

    /// Index of ring vertex `(i, j)` for `i` in `1..rings` (`j` taken modulo
    /// `segments`).
    #[inline]
    pub fn vertex(&self, i: u32, j: u32) -> u32 {
        1 + (i - 1) * self.segments + j % self.segments
    }

    /// Unit direction of ring vertex `(i, j)` (and of the poles for
    /// `i = 0` and `i = rings`).
    pub fn direction(&self, i: u32, j: u32) -> [f64; 3] {
        let t = PI * f64::from(i) / f64::from(self.rings);
        let p = 2.0 * PI * f64::from(j % self.segments) / f64::from(self.segments);
        [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()]
    }

    /// Checks the ranges and that the vertices fit `u32` indices.
    pub fn validate(&self) -> Result<(), GenError> {
        if self.rings < 2 || self.segments < 3 {
            return Err(GenError::InvalidParameter {
                name: "grid",
                reason: format!("{self:?}: need rings >= 2 and segments >= 3"),
            });
        }
        check_vertex_count(self.vertices())
    }

    /// Streams the vertices of the sphere of `radius` around `center`, in
    /// the numbering of the module docs. Multi-sphere generators call this
    /// for every sphere, then [`emit_faces`](Self::emit_faces) with each
    /// sphere's first vertex index.
    pub(crate) fn emit_vertices(
        &self,
        tables: &TrigTables,
        center: [f64; 3],
        radius: f64,
        sink: &mut dyn MeshSink,
    ) -> Result<(), SinkError> {
        let [cx, cy, cz] = center;
        sink.vertex([cx, cy, cz + radius])?;
        for &(st, ct) in &tables.rings {
            let (rs, z) = (radius * st, cz + radius * ct);
            for &(cp, sp) in &tables.segments {
                sink.vertex([cx + rs * cp, cy + rs * sp, z])?;
            }
        }
        sink.vertex([cx, cy, cz - radius])
    }

    /// Streams the faces, vertex indices offset by `base`.
    pub(crate) fn emit_faces(&self, base: u32, sink: &mut dyn MeshSink) -> Result<(), SinkError> {
        let (r, s) = (self.rings, self.segments);
        let south = base + 1 + (r - 1) * s;
        for j in 0..s {
            let jn = if j + 1 == s { 0 } else { j + 1 };
            sink.face([base, base + 1 + j, base + 1 + jn])?;
        }
        for i in 1..r - 1 {
            let top = base + 1 + (i - 1) * s;
            let bot = top + s;
            for j in 0..s {
                let jn = if j + 1 == s { 0 } else { j + 1 };
                let (a, b, c, d) = (top + j, top + jn, bot + j, bot + jn);
                sink.face([a, c, d])?;
                sink.face([a, d, b])?;
            }
        }
        let last = base + 1 + (r - 2) * s;
        for j in 0..s {
            let jn = if j + 1 == s { 0 } else { j + 1 };
            sink.face([south, last + jn, last + j])?;
        }
        Ok(())
    }
}

/// `(sin θ_i, cos θ_i)` for rings `1..R` and `(cos φ_j, sin φ_j)` for
/// segments `0..S`: the only per-grid memory.
pub(crate) struct TrigTables {
    pub rings: Vec<(f64, f64)>,
    pub segments: Vec<(f64, f64)>,
}

impl TrigTables {
    pub fn new(g: &SphereGrid) -> Self {
        let rings = (1..g.rings)
            .map(|i| {
                let t = PI * f64::from(i) / f64::from(g.rings);
                (t.sin(), t.cos())
            })
            .collect();
        let segments = (0..g.segments)
            .map(|j| {
                let p = 2.0 * PI * f64::from(j) / f64::from(g.segments);
                (p.cos(), p.sin())
            })
            .collect();
        Self { rings, segments }
    }
}

/// Streams a UV sphere of `radius` around `center` with about
/// `target_faces` faces (resolution from [`SphereGrid::for_faces`]): a
/// closed genus-0 surface, outward oriented, every vertex on the sphere up
/// to rounding. The exact surface is [`SphereSurface`].
pub fn sphere(
    center: [f64; 3],
    radius: f64,
    target_faces: u64,
    sink: &mut dyn MeshSink,
) -> Result<Generated, GenError> {
    positive("radius", radius)?;
    finite3("center", center)?;
    let grid = SphereGrid::for_faces(target_faces);
    grid.validate()?;
    let tables = TrigTables::new(&grid);
    grid.emit_vertices(&tables, center, radius, sink)?;
    grid.emit_faces(0, sink)?;
    Ok(Generated {
        vertices: grid.vertices(),
        faces: grid.faces(),
        components: 1,
        genus: 0,
        surface: ExactSurface::Sphere(SphereSurface { center, radius }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_counts_are_close_to_target() {
        for t in (100..20_000)
            .step_by(37)
            .chain([1_000_000, 5_000_000, 100_000_000])
        {
            let g = SphereGrid::for_faces(t);
            let err = g.faces().abs_diff(t) as f64;
            assert!(
                err <= 0.7 * (t as f64).sqrt(),
                "target {t}: {g:?} gives {}",
                g.faces()
            );
            let aspect = f64::from(g.segments) / f64::from(g.rings);
            assert!((1.5..=2.5).contains(&aspect), "target {t}: {g:?}");
        }
        assert_eq!(
            SphereGrid::for_faces(0),
            SphereGrid {
                rings: 2,
                segments: 3
            }
        );
        assert_eq!(SphereGrid::for_faces(6).faces(), 6);
    }

    #[test]
    fn tiny_sphere_counts() {
        let mut m = mint_core::TriMesh::default();
        let g = sphere([1.0, 2.0, 3.0], 2.0, 6, &mut m).unwrap();
        assert_eq!((g.vertices, g.faces), (5, 6));
        assert_eq!((m.positions.len(), m.faces.len()), (5, 6));
    }
}
