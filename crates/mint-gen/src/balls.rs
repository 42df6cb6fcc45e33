//! Many small closed components: [`components()`] streams `count` small UV
//! spheres ([`BallLattice::RINGS`] × [`BallLattice::SEGMENTS`], 120 faces
//! and 62 vertices each) centred on the points of a cubic lattice of
//! spacing 1, filled x fastest, then y, then z, `side = ⌈∛count⌉` per axis.
//! Ball `i` has a radius drawn from `[0.25, 0.4)` by its own seeded stream,
//! so balls never touch (gaps of at least 0.2). The exact surface is the
//! union of the spheres, [`BallLattice`] (in `surface`), with an exact signed distance.
//! Memory is one trig table; vertices of ball `i` are `62·i .. 62·(i+1)`.

use crate::error::GenError;
use crate::sphere::{SphereGrid, TrigTables};
use crate::surface::{BallLattice, ExactSurface};
use crate::{check_vertex_count, Generated};
use mint_core::MeshSink;

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
    use crate::rng::SplitMix64;
    use crate::surface::distance;

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
                .map(|i| distance(p, l.center(i)) - l.radius(i))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(l.signed_distance(p), brute, "{p:?}");
        }
    }
}
