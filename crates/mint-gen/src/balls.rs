//! Many small closed components: [`components()`] streams `count` small UV
//! spheres ([`BallLattice::RINGS`] × [`BallLattice::SEGMENTS`], 120 faces
//! and 62 vertices each) centred on the points of a cubic lattice of
//! spacing 1, filled x fastest, then y, then z, `side = ⌈∛count⌉` per axis.
//! Ball `i` has a radius drawn from `[0.25, 0.4)` by its own seeded stream,
//! so balls never touch (gaps of at least 0.2). The exact surface is the
//! union of the spheres, [`BallLattice`], with an exact signed distance.
//! Memory is one trig table; vertices of ball `i` are `62·i .. 62·(i+1)`.

use crate::error::GenError;
use crate::rng::SplitMix64;
use crate::sphere::{SphereGrid, TrigTables};
use crate::surface::{norm, sub, ExactSurface};
use crate::{check_vertex_count, Generated};
use mint_core::MeshSink;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

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
                        let d = norm(sub(p, self.center(i))) - self.radius(i);
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

/// Streams about `target_faces` faces of small disjoint closed spheres
/// (see the module docs and [`BallLattice::for_faces`] for the count);
/// `Generated::components` says how many. Deterministic from `seed`, which
/// only sets the radii.
pub fn components(
    target_faces: u64,
    seed: u64,
    sink: &mut dyn MeshSink,
) -> Result<Generated, GenError> {
    let lattice = BallLattice::for_faces(target_faces, seed);
    let vertices = lattice.count * BallLattice::VERTICES_PER_BALL;
    check_vertex_count(vertices)?;
    let grid = SphereGrid {
        rings: BallLattice::RINGS,
        segments: BallLattice::SEGMENTS,
    };
    let tables = TrigTables::new(&grid);
    for i in 0..lattice.count {
        grid.emit_vertices(&tables, lattice.center(i), lattice.radius(i), sink)?;
    }
    for i in 0..lattice.count {
        grid.emit_faces((i * BallLattice::VERTICES_PER_BALL) as u32, sink)?;
    }
    Ok(Generated {
        vertices,
        faces: lattice.count * BallLattice::FACES_PER_BALL,
        components: lattice.count,
        genus: 0,
        surface: ExactSurface::Balls(lattice),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_side_is_the_ceiling_cube_root() {
        for (t, count, side) in [
            (0, 1, 1),
            (120, 1, 1),
            (1200, 10, 3),
            (120 * 27, 27, 3),
            (120 * 28, 28, 4),
        ] {
            let l = BallLattice::for_faces(t, 0);
            assert_eq!((l.count, l.side), (count, side), "target {t}");
        }
    }

    #[test]
    fn signed_distance_matches_brute_force() {
        let l = BallLattice::for_faces(120 * 30, 5); // 30 balls: a partial top layer
        let mut r = SplitMix64::new(1);
        for _ in 0..2000 {
            let p: [f64; 3] = std::array::from_fn(|_| r.next_f64() * 6.0 - 1.5);
            let brute = (0..l.count)
                .map(|i| norm(sub(p, l.center(i))) - l.radius(i))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(l.signed_distance(p), brute, "{p:?}");
        }
    }
}
