//! The analytic surfaces the generators approximate, as plain data
//! ([`ExactSurface`] and one struct per shape) with signed distances,
//! volumes and areas, so a test can measure a mesh against the truth: a
//! generated vertex lies on its surface up to rounding, a point of a face
//! within the tessellation's sagitta. Signed distances are negative inside
//! the solid and exact (the true Euclidean distance to the surface) for
//! every shape except [`ScanSurface`], whose radial offset is only an upper
//! bound of the distance's magnitude.

use glam::DVec3;
use crate::rng::SplitMix64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// One of the generators' analytic surfaces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum ExactSurface {
    Sphere(SphereSurface),
    Torus(TorusSurface),
    Plate(PlateSurface),
    Balls(BallLattice),
    Scan(ScanSurface),
}

impl ExactSurface {
    /// Signed distance from `p` to the surface (negative inside). Exact for
    /// all shapes but [`ExactSurface::Scan`], where it is the radial offset
    /// (see [`ScanSurface::radial_offset`]).
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        match self {
            ExactSurface::Sphere(s) => s.signed_distance(p),
            ExactSurface::Torus(t) => t.signed_distance(p),
            ExactSurface::Plate(s) => s.signed_distance(p),
            ExactSurface::Balls(b) => b.signed_distance(p),
            ExactSurface::Scan(s) => s.radial_offset(p),
        }
    }

    /// Enclosed volume, where a closed form exists (not for the scan).
    pub fn volume(&self) -> Option<f64> {
        match self {
            ExactSurface::Sphere(s) => Some(s.volume()),
            ExactSurface::Torus(t) => Some(t.volume()),
            ExactSurface::Plate(s) => Some(s.volume()),
            ExactSurface::Balls(b) => Some(b.volume()),
            ExactSurface::Scan(_) => None,
        }
    }

    /// Surface area, where a closed form exists (not for the scan).
    pub fn area(&self) -> Option<f64> {
        match self {
            ExactSurface::Sphere(s) => Some(s.area()),
            ExactSurface::Torus(t) => Some(t.area()),
            ExactSurface::Plate(s) => Some(s.area()),
            ExactSurface::Balls(b) => Some(b.area()),
            ExactSurface::Scan(_) => None,
        }
    }
}

/// `|a - b|`.
#[inline]
pub(crate) fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    DVec3::from(a).distance(DVec3::from(b))
}

/// The sphere `|p - center| = radius`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SphereSurface {
    pub center: [f64; 3],
    pub radius: f64,
}

impl SphereSurface {
    /// `|p - center| - radius`.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        distance(p, self.center) - self.radius
    }
    /// `4/3 π r³`.
    pub fn volume(&self) -> f64 {
        4.0 / 3.0 * PI * self.radius.powi(3)
    }
    /// `4 π r²`.
    pub fn area(&self) -> f64 {
        4.0 * PI * self.radius.powi(2)
    }
}

/// The torus around the axis through `center` parallel to z: points at
/// distance `minor` from the circle of radius `major` in the plane
/// `z = center.z`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TorusSurface {
    pub center: [f64; 3],
    pub major: f64,
    pub minor: f64,
}

impl TorusSurface {
    /// `|(ρ - major, z)| - minor` with `ρ` the distance to the axis.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        let q = (DVec3::from(p) - DVec3::from(self.center)).to_array();
        let rho = (q[0] * q[0] + q[1] * q[1]).sqrt();
        ((rho - self.major).powi(2) + q[2] * q[2]).sqrt() - self.minor
    }
    /// `2 π² R r²`.
    pub fn volume(&self) -> f64 {
        2.0 * PI * PI * self.major * self.minor * self.minor
    }
    /// `4 π² R r`.
    pub fn area(&self) -> f64 {
        4.0 * PI * PI * self.major * self.minor
    }
}

/// The genus-`holes` plate: the box `[0, 3·blocks·cell] × [0, 3·cell] ×
/// [0, thickness]` (`blocks = max(holes, 1)`) minus the square prisms
/// `(3b+1, 3b+2)·cell × (1, 2)·cell × ℝ` for `b < holes`: a row of square
/// frames, each a 3×3 block of cells with its middle cell open.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlateSurface {
    pub holes: u32,
    pub cell: f64,
    pub thickness: f64,
}

impl PlateSurface {
    /// Number of 3×3 blocks along x (1 for a plate without holes).
    pub fn blocks(&self) -> u32 {
        self.holes.max(1)
    }

    /// Exact signed distance: the distance to the union of the top and
    /// bottom faces (a rectangle with square holes), the outer side walls and
    /// the nearest hole's walls, negative inside the solid.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        let (c, t) = (self.cell, self.thickness);
        let (w, h) = (3.0 * f64::from(self.blocks()) * c, 3.0 * c);
        let [x, y, z] = p;
        // Distance in the plane to the outer rectangle (0 inside) and to its
        // boundary.
        let out2 = |x: f64, y: f64, x0: f64, x1: f64, y0: f64, y1: f64| {
            let dx = (x0 - x).max(0.0).max(x - x1);
            let dy = (y0 - y).max(0.0).max(y - y1);
            (dx * dx + dy * dy).sqrt()
        };
        let to_boundary = |x: f64, y: f64, x0: f64, x1: f64, y0: f64, y1: f64| {
            let o = out2(x, y, x0, x1, y0, y1);
            if o > 0.0 {
                o
            } else {
                (x - x0).min(x1 - x).min(y - y0).min(y1 - y)
            }
        };
        let rect_out = out2(x, y, 0.0, w, 0.0, h);
        let rect_edge = to_boundary(x, y, 0.0, w, 0.0, h);
        // The nearest hole (they are identical and in a row along x).
        let (mut hole_edge, mut in_hole) = (f64::INFINITY, false);
        if self.holes > 0 {
            let guess = ((x / c - 1.5) / 3.0).round();
            for b in [guess - 1.0, guess, guess + 1.0] {
                if b < 0.0 || b >= f64::from(self.holes) {
                    continue;
                }
                let x0 = (3.0 * b + 1.0) * c;
                let (x1, y0, y1) = (x0 + c, c, 2.0 * c);
                hole_edge = hole_edge.min(to_boundary(x, y, x0, x1, y0, y1));
                in_hole |= x > x0 && x < x1 && y > y0 && y < y1;
            }
        }
        // Planar distance to the region (rectangle minus holes).
        let region = if rect_out > 0.0 {
            rect_out
        } else if in_hole {
            hole_edge
        } else {
            0.0
        };
        let dz_wall = (-z).max(0.0).max(z - t);
        let d = [
            region.hypot(z - t),
            region.hypot(z),
            rect_edge.hypot(dz_wall),
            hole_edge.hypot(dz_wall),
        ]
        .into_iter()
        .fold(f64::INFINITY, f64::min);
        let inside = region == 0.0 && (0.0..=t).contains(&z);
        if inside {
            -d
        } else {
            d
        }
    }

    /// `(9·blocks - holes)·cell²·thickness`.
    pub fn volume(&self) -> f64 {
        f64::from(9 * self.blocks() - self.holes) * self.cell * self.cell * self.thickness
    }

    /// Top and bottom faces plus outer and hole walls.
    pub fn area(&self) -> f64 {
        let c = self.cell;
        let faces = 2.0 * f64::from(9 * self.blocks() - self.holes) * c * c;
        let perimeter =
            2.0 * (3.0 * f64::from(self.blocks()) * c + 3.0 * c) + 4.0 * f64::from(self.holes) * c;
        faces + perimeter * self.thickness
    }
}

/// One smooth bump field term: `sin(k·u + phase)` for a unit direction `u`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wave {
    pub k: [f64; 3],
    pub phase: f64,
}

/// The star-shaped noisy sphere of [`crate::scan_like`]: in unit direction
/// `u` from `center` the surface is at radius
/// `radius · (1 + amplitude · n(u))`, with
/// `n(u) = (1/W) Σ_w sin(k_w·u + phase_w)` over the `W` waves, so
/// `|n| ≤ 1`. The waves' frequencies `|k_w|` lie in `[2, 5)`: a few gentle
/// bumps around the sphere.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScanSurface {
    pub center: [f64; 3],
    pub radius: f64,
    pub amplitude: f64,
    pub waves: Vec<Wave>,
}

impl ScanSurface {
    /// The bump field `n(u)` in `[-1, 1]` for a unit vector `u`.
    #[inline]
    pub fn noise(&self, u: [f64; 3]) -> f64 {
        if self.waves.is_empty() {
            return 0.0;
        }
        let s: f64 = self
            .waves
            .iter()
            .map(|w| (w.k[0] * u[0] + w.k[1] * u[1] + w.k[2] * u[2] + w.phase).sin())
            .sum();
        s / self.waves.len() as f64
    }

    /// Surface radius in unit direction `u`.
    #[inline]
    pub fn radius_at(&self, u: [f64; 3]) -> f64 {
        self.radius * (1.0 + self.amplitude * self.noise(u))
    }

    /// `|p - center| - radius_at(direction of p)`: the signed offset along
    /// the ray from the centre. Zero exactly on the surface and negative
    /// inside; its magnitude bounds the true distance from above (and is
    /// close to it while the amplitude is small).
    pub fn radial_offset(&self, p: [f64; 3]) -> f64 {
        let q = (DVec3::from(p) - DVec3::from(self.center)).to_array();
        let r = DVec3::from(q).length();
        if r == 0.0 {
            return -self.radius_at([0.0, 0.0, 1.0]);
        }
        r - self.radius_at(q.map(|x| x / r))
    }
}

/// The union of `count` disjoint spheres on a cubic lattice: ball `i` is
/// centred at `(i mod side, ⌊i/side⌋ mod side, ⌊i/side²⌋) · spacing` with
/// radius `min_radius + (max_radius - min_radius)·u_i`, `u_i` the first
/// draw of `SplitMix64::for_stream(seed, i)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BallLattice {
    pub count: u64,
    pub side: u64,
    pub spacing: f64,
    pub min_radius: f64,
    pub max_radius: f64,
    pub seed: u64,
}

impl BallLattice {
    /// Latitude bands of each ball.
    pub const RINGS: u32 = 6;
    /// Longitudes of each ball.
    pub const SEGMENTS: u32 = 12;
    /// Faces of each ball: `2·12·5`.
    pub const FACES_PER_BALL: u64 = 120;
    /// Vertices of each ball: `2 + 5·12`.
    pub const VERTICES_PER_BALL: u64 = 62;

    /// The lattice for about `target_faces` faces: `max(1, round(target /
    /// 120))` balls, so within 60 faces of the target (at least 120).
    pub fn for_faces(target_faces: u64, seed: u64) -> Self {
        let count =
            (target_faces.saturating_add(Self::FACES_PER_BALL / 2) / Self::FACES_PER_BALL).max(1);
        let mut side = (count as f64).cbrt().round() as u64;
        while side.pow(3) < count {
            side += 1;
        }
        while side > 1 && (side - 1).pow(3) >= count {
            side -= 1;
        }
        Self {
            count,
            side,
            spacing: 1.0,
            min_radius: 0.25,
            max_radius: 0.4,
            seed,
        }
    }

    /// Centre of ball `i`.
    pub fn center(&self, i: u64) -> [f64; 3] {
        let s = self.side;
        [(i % s) as f64, (i / s % s) as f64, (i / (s * s)) as f64].map(|x| x * self.spacing)
    }

    /// Radius of ball `i`.
    pub fn radius(&self, i: u64) -> f64 {
        let u = SplitMix64::for_stream(self.seed, i).next_f64();
        self.min_radius + (self.max_radius - self.min_radius) * u
    }

    /// Exact signed distance to the union of the balls (negative inside
    /// one): searches lattice cells in growing shells around `p`'s nearest
    /// cell until no farther ball can be nearer.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        let s = self.side as i64;
        let layers = (self.count.div_ceil(self.side * self.side)) as i64;
        let cell = |x: f64, hi: i64| ((x / self.spacing).round() as i64).clamp(0, hi - 1);
        let c0 = [cell(p[0], s), cell(p[1], s), cell(p[2], layers)];
        let mut best = f64::INFINITY;
        for shell in 0i64.. {
            // Any ball in this shell is at least (shell - 1/2)·spacing away
            // from p in one coordinate (clamping only moves p towards it).
            if (shell as f64 - 0.5) * self.spacing - self.max_radius > best {
                break;
            }
            if shell > s.max(layers) {
                break;
            }
            for dz in -shell..=shell {
                for dy in -shell..=shell {
                    for dx in -shell..=shell {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != shell {
                            continue;
                        }
                        let c = [c0[0] + dx, c0[1] + dy, c0[2] + dz];
                        if c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= s || c[1] >= s {
                            continue;
                        }
                        let i = (c[2] * s * s + c[1] * s + c[0]) as u64;
                        if i >= self.count {
                            continue;
                        }
                        let d = distance(p, self.center(i)) - self.radius(i);
                        best = best.min(d);
                    }
                }
            }
        }
        best
    }

    /// `Σ 4/3 π r_i³`.
    pub fn volume(&self) -> f64 {
        (0..self.count)
            .map(|i| 4.0 / 3.0 * PI * self.radius(i).powi(3))
            .sum()
    }

    /// `Σ 4 π r_i²`.
    pub fn area(&self) -> f64 {
        (0..self.count)
            .map(|i| 4.0 * PI * self.radius(i).powi(2))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plate_distance_at_known_points() {
        let s = PlateSurface {
            holes: 2,
            cell: 1.0,
            thickness: 0.5,
        };
        // Centre of the solid between the holes: 0.25 below the top.
        assert_eq!(s.signed_distance([3.0, 1.5, 0.25]), -0.25);
        // Centre of hole 0 at mid-thickness: half a cell to its walls.
        assert_eq!(s.signed_distance([1.5, 1.5, 0.25]), 0.5);
        // Above a hole's centre: to its top rim, diagonally.
        assert!((s.signed_distance([1.5, 1.5, 1.5]) - 0.5f64.hypot(1.0)).abs() < 1e-15);
        // Outside the outer wall.
        assert_eq!(s.signed_distance([-2.0, 1.5, 0.25]), 2.0);
        // Above the solid.
        assert_eq!(s.signed_distance([0.5, 0.5, 3.0]), 2.5);
        // Near a corner of the box, inside.
        assert_eq!(s.signed_distance([0.1, 0.2, 0.25]), -0.1);
        // On the surface.
        assert_eq!(s.signed_distance([4.0, 1.5, 0.1]), 0.0);
        assert_eq!(s.volume(), 16.0 * 0.5);
    }

    #[test]
    fn torus_and_sphere_distances() {
        let t = TorusSurface {
            center: [1.0, 0.0, 0.0],
            major: 2.0,
            minor: 0.5,
        };
        assert_eq!(t.signed_distance([3.0, 0.0, 0.0]), -0.5);
        assert_eq!(t.signed_distance([1.0, 0.0, 0.0]), 1.5);
        let s = SphereSurface {
            center: [0.0; 3],
            radius: 2.0,
        };
        assert_eq!(s.signed_distance([0.0, 3.0, 0.0]), 1.0);
    }

    #[test]
    fn serializes_with_a_shape_tag() {
        let e = ExactSurface::Sphere(SphereSurface {
            center: [0.0; 3],
            radius: 1.0,
        });
        let j = serde_json::to_value(&e).unwrap();
        assert_eq!(j["shape"], "sphere");
        assert_eq!(serde_json::from_value::<ExactSurface>(j).unwrap(), e);
    }
}
