//! Meshes in scan order: real scans often list vertices and faces in an
//! order unrelated to space, which makes every triangle's corners land far
//! apart in the vertex array. [`Permutation`] is a pseudo-random bijection
//! of `0..n` computable both ways in O(1) with no table (a four-round Feistel
//! network on the next even power of two, cycle-walking back into range), so
//! a generator can write vertex `π⁻¹(j)` at position `j` and face `σ⁻¹(k)`
//! at position `k`, both sequentially, for any size. [`torus_shuffled`] is
//! the torus so permuted; [`shuffle_mesh`] permutes a mesh held in memory.

use crate::error::GenError;
use crate::rng::SplitMix64;
use crate::torus::TorusMesh;
use crate::Generated;
use mint_core::{MeshSink, TriMesh};

/// A pseudo-random permutation of `0..n`; see the module docs.
#[derive(Debug, Clone)]
pub struct Permutation {
    n: u64,
    half: u32,
    keys: [u64; 4],
}

impl Permutation {
    /// The permutation of `0..n` drawn from `seed`.
    pub fn new(n: u64, seed: u64) -> Permutation {
        let bits = 64 - n.saturating_sub(1).leading_zeros();
        let half = bits.div_ceil(2).max(1);
        let mut r = SplitMix64::new(seed);
        Permutation { n, half, keys: [r.next_u64(), r.next_u64(), r.next_u64(), r.next_u64()] }
    }

    fn round(&self, x: u64, k: u64) -> u64 {
        let mut z = (x ^ k).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        (z ^ (z >> 32)) & ((1u64 << self.half) - 1)
    }

    fn feistel(&self, x: u64, inverse: bool) -> u64 {
        let mask = (1u64 << self.half) - 1;
        let (mut l, mut r) = (x >> self.half, x & mask);
        if !inverse {
            for &k in &self.keys {
                (l, r) = (r, l ^ self.round(r, k));
            }
        } else {
            for &k in self.keys.iter().rev() {
                (l, r) = (r ^ self.round(l, k), l);
            }
        }
        (l << self.half) | r
    }

    /// `π(i)`, for `i < n`.
    pub fn apply(&self, i: u64) -> u64 {
        debug_assert!(i < self.n);
        let mut x = self.feistel(i, false);
        while x >= self.n {
            x = self.feistel(x, false);
        }
        x
    }

    /// `π⁻¹(j)`, for `j < n`.
    pub fn invert(&self, j: u64) -> u64 {
        debug_assert!(j < self.n);
        let mut x = self.feistel(j, true);
        while x >= self.n {
            x = self.feistel(x, true);
        }
        x
    }
}

/// The torus of [`crate::torus()`] with its vertices and its faces each in a
/// pseudo-random order drawn from `seed` (the same surface, the same
/// triangles with the same corner order). Memory `O(√faces)`.
pub fn torus_shuffled(center: [f64; 3], major: f64, minor: f64, target_faces: u64, seed: u64, sink: &mut dyn MeshSink) -> Result<Generated, GenError> {
    let t = TorusMesh::new(center, major, minor, target_faces)?;
    let (nv, nf) = (t.grid.vertices(), t.grid.faces());
    let pv = Permutation::new(nv, seed);
    let pf = Permutation::new(nf, seed ^ 0x5151_5151);
    for j in 0..nv {
        sink.vertex(t.vertex(pv.invert(j) as u32))?;
    }
    for k in 0..nf {
        let f = t.face(pf.invert(k));
        sink.face(f.map(|i| pv.apply(i as u64) as u32))?;
    }
    Ok(t.generated())
}

/// Writes `m` with its vertices and faces each in a pseudo-random order.
pub fn shuffle_mesh(m: &TriMesh, seed: u64, sink: &mut dyn MeshSink) -> Result<(), GenError> {
    let pv = Permutation::new(m.positions.len() as u64, seed);
    let pf = Permutation::new(m.faces.len() as u64, seed ^ 0x5151_5151);
    for j in 0..m.positions.len() as u64 {
        sink.vertex(m.positions[pv.invert(j) as usize])?;
    }
    for k in 0..m.faces.len() as u64 {
        let f = m.faces[pf.invert(k) as usize];
        sink.face(f.map(|i| pv.apply(i as u64) as u32))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutations_are_bijections_both_ways() {
        for n in [1u64, 2, 3, 7, 64, 100, 1000, 4097] {
            let p = Permutation::new(n, n * 31 + 1);
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let j = p.apply(i);
                assert!(j < n && !seen[j as usize], "n {n}: {i} -> {j}");
                seen[j as usize] = true;
                assert_eq!(p.invert(j), i);
            }
        }
    }

    #[test]
    fn neighbours_land_far_apart() {
        let n = 1_000_000;
        let p = Permutation::new(n, 5);
        let far = (0..1000).filter(|&i| p.apply(i).abs_diff(p.apply(i + 1)) > n / 100).count();
        assert!(far > 900, "{far}");
    }

    #[test]
    fn the_shuffled_torus_is_the_torus() {
        let mut a = TriMesh::default();
        crate::torus([0.0; 3], 1.0, 0.35, 5000, &mut a).unwrap();
        let mut b = TriMesh::default();
        torus_shuffled([0.0; 3], 1.0, 0.35, 5000, 9, &mut b).unwrap();
        assert_eq!((a.positions.len(), a.faces.len()), (b.positions.len(), b.faces.len()));
        assert_ne!(a.positions, b.positions);
        let tri = |m: &TriMesh| {
            let mut v: Vec<[[u64; 3]; 3]> = m.faces.iter().map(|f| f.map(|i| m.positions[i as usize].map(f64::to_bits))).collect();
            v.sort();
            v
        };
        assert_eq!(tri(&a), tri(&b), "the same triangles, corner order kept");
        let mut c = TriMesh::default();
        shuffle_mesh(&a, 3, &mut c).unwrap();
        assert_eq!(tri(&a), tri(&c));
    }
}
