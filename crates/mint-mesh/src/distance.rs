//! Metro-style surface distances: [`distance()`] draws area-uniform random
//! points on mesh A, finds each one's nearest point on mesh B with a
//! [`TriangleBvh`], and summarises the distances in a [`DistanceReport`]
//! (mean, RMS, max, absolute and relative to B's bounding-box diagonal).
//! [`symmetric_distance()`] does both directions.
//!
//! Source: Cignoni, Rocchi and Scopigno, "Metro: measuring error on
//! simplified surfaces", Computer Graphics Forum 17(2), 1998. Metro samples
//! A's surface and measures to B; the one-sided Hausdorff distance is the
//! maximum of those distances. Here sampling is plain Monte Carlo: a face is
//! drawn with probability proportional to its area (binary search in the
//! prefix sums of face areas), then a point uniformly inside it
//! (`s = √r1`, barycentrics `(1 - s, s(1 - r2), s·r2)`; Osada et al.,
//! "Shape distributions", 2002, §4.2). The maximum is therefore a lower
//! bound of the true one-sided Hausdorff distance that tightens as
//! `samples` grows.
//!
//! Determinism: sample `i` draws from its own generator,
//! `SplitMix64::for_stream(seed, i)`, and distances are reduced in fixed
//! blocks of samples combined in block order, so a report depends on the
//! inputs, `samples` and `seed` only, never on the thread count. Within a
//! block the queries run in Morton order of the sample points, each one
//! seeded with the previous answer ([`TriangleBvh`]'s hint), which keeps
//! the tree's hot paths in cache; that order too is fixed by the block's
//! contents.

use crate::bvh::TriangleBvh;
use crate::check::is_collapsed;
use glam::DVec3;
use crate::error::MeshError;
use crate::rng::SplitMix64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Samples per reduction block; fixes the summation order.
const SAMPLE_BLOCK: usize = 1 << 14;

/// Borrowed mesh: `(positions, faces)`.
pub type MeshRef<'a> = (&'a [[f64; 3]], &'a [[u32; 3]]);

/// Distances from sampled points of mesh A to the surface of mesh B.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DistanceReport {
    /// Number of sample points drawn on A.
    pub samples: u64,
    /// Mean distance, in model units.
    pub mean: f64,
    /// Root mean square distance.
    pub rms: f64,
    /// Largest sampled distance: a lower bound of the one-sided Hausdorff
    /// distance from A to B.
    pub max: f64,
    /// The sample point of A where `max` was reached (first one on ties).
    pub max_point: [f64; 3],
    /// Diagonal of the bounding box of B's triangles; the `*_rel` fields are
    /// the absolute ones divided by it (0 if the diagonal is 0).
    pub bbox_diagonal: f64,
    pub mean_rel: f64,
    pub rms_rel: f64,
    pub max_rel: f64,
    /// Total area of A (what was sampled).
    pub area_sampled: f64,
}

/// Distance from A to B: `samples` area-uniform points on A, nearest points
/// on B. See the [module docs](self).
///
/// # Panics
/// On invalid input (out-of-range indices, A without area, B without faces,
/// `samples == 0`); [`try_distance`] returns a [`MeshError`] instead.
pub fn distance(a: MeshRef, b: MeshRef, samples: usize, seed: u64) -> DistanceReport {
    try_distance(a, b, samples, seed).unwrap_or_else(|e| panic!("mint_mesh::distance: {e}"))
}

/// [`distance()`] returning errors instead of panicking.
pub fn try_distance(
    a: MeshRef,
    b: MeshRef,
    samples: usize,
    seed: u64,
) -> Result<DistanceReport, MeshError> {
    let bvh = TriangleBvh::new(b.0, b.1)?;
    distance_to_bvh(a, &bvh, samples, seed)
}

/// Distances in both directions, `(A→B, B→A)`, each with `samples` points
/// and the same `seed`. The symmetric Hausdorff estimate is the larger
/// `max` of the two.
///
/// # Panics
/// As [`distance()`]; [`try_symmetric_distance`] returns errors instead.
pub fn symmetric_distance(
    a: MeshRef,
    b: MeshRef,
    samples: usize,
    seed: u64,
) -> (DistanceReport, DistanceReport) {
    try_symmetric_distance(a, b, samples, seed)
        .unwrap_or_else(|e| panic!("mint_mesh::symmetric_distance: {e}"))
}

/// [`symmetric_distance()`] returning errors instead of panicking.
pub fn try_symmetric_distance(
    a: MeshRef,
    b: MeshRef,
    samples: usize,
    seed: u64,
) -> Result<(DistanceReport, DistanceReport), MeshError> {
    Ok((
        try_distance(a, b, samples, seed)?,
        try_distance(b, a, samples, seed)?,
    ))
}

/// Distance from A to the surface already indexed in `bvh` (build the tree
/// once to measure several meshes against the same reference).
pub fn distance_to_bvh(
    a: MeshRef,
    bvh: &TriangleBvh,
    samples: usize,
    seed: u64,
) -> Result<DistanceReport, MeshError> {
    if samples == 0 {
        return Err(MeshError::Empty {
            what: "a distance needs at least one sample",
        });
    }
    let sampler = AreaSampler::new(a.0, a.1)?;
    let (lo, hi) = bvh.bounds();
    let blocks = samples.div_ceil(SAMPLE_BLOCK);
    let parts: Vec<Block> = (0..blocks)
        .into_par_iter()
        .map(|blk| {
            // Draw the block's samples, then query them in Morton order of
            // position, each starting from the previous answer: nearby
            // queries share cache lines and prune at once.
            let end = ((blk + 1) * SAMPLE_BLOCK).min(samples);
            let mut pts: Vec<(u64, u64, [f64; 3])> = (blk * SAMPLE_BLOCK..end)
                .map(|i| {
                    let p = sampler.sample(seed, i as u64);
                    (morton(p, lo, hi), i as u64, p)
                })
                .collect();
            pts.sort_unstable_by_key(|&(key, i, _)| (key, i));
            let mut acc = Block::new();
            let mut hint = None;
            for &(_, i, p) in &pts {
                let (d2, _, t) = bvh
                    .search(p, f64::INFINITY, hint)
                    .unwrap_or((f64::NAN, p, 0));
                hint = Some(t);
                let d = d2.sqrt();
                acc.sum += d;
                acc.sum2 += d2;
                if d > acc.max || (d == acc.max && i < acc.max_index) {
                    acc.max = d;
                    acc.max_index = i;
                    acc.max_point = p;
                }
            }
            acc
        })
        .collect();
    let mut total = Block::new();
    for b in &parts {
        total.sum += b.sum;
        total.sum2 += b.sum2;
        if b.max > total.max {
            total.max = b.max;
            total.max_point = b.max_point;
        }
    }
    let n = samples as f64;
    let diag = DVec3::from(hi).distance(DVec3::from(lo));
    let rel = |x: f64| if diag > 0.0 { x / diag } else { 0.0 };
    let (mean, rms) = (total.sum / n, (total.sum2 / n).sqrt());
    Ok(DistanceReport {
        samples: samples as u64,
        mean,
        rms,
        max: total.max,
        max_point: total.max_point,
        bbox_diagonal: diag,
        mean_rel: rel(mean),
        rms_rel: rel(rms),
        max_rel: rel(total.max),
        area_sampled: sampler.total,
    })
}

struct Block {
    sum: f64,
    sum2: f64,
    max: f64,
    max_index: u64,
    max_point: [f64; 3],
}

impl Block {
    fn new() -> Self {
        Block {
            sum: 0.0,
            sum2: 0.0,
            max: -1.0,
            max_index: u64::MAX,
            max_point: [0.0; 3],
        }
    }
}

/// 63-bit Morton code of `p` in the box `[lo, hi]` (clamped), 21 bits a
/// coordinate.
fn morton(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> u64 {
    let spread = |x: f64, l: f64, h: f64| -> u64 {
        let t = if h > l {
            ((x - l) / (h - l)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut v = (t * f64::from((1u32 << 21) - 1)) as u64;
        v = (v | v << 32) & 0x001F_0000_0000_FFFF;
        v = (v | v << 16) & 0x001F_0000_FF00_00FF;
        v = (v | v << 8) & 0x100F_00F0_0F00_F00F;
        v = (v | v << 4) & 0x10C3_0C30_C30C_30C3;
        v = (v | v << 2) & 0x1249_2492_4924_9249;
        v
    };
    spread(p[0], lo[0], hi[0]) | spread(p[1], lo[1], hi[1]) << 1 | spread(p[2], lo[2], hi[2]) << 2
}

/// Area-weighted point sampler over a mesh's faces.
struct AreaSampler<'a> {
    positions: &'a [[f64; 3]],
    faces: &'a [[u32; 3]],
    /// `cum[i]` = total area of faces `0..=i`.
    cum: Vec<f64>,
    total: f64,
    /// Last face with positive area (the one to fall back on at the top end).
    last: usize,
}

impl<'a> AreaSampler<'a> {
    fn new(positions: &'a [[f64; 3]], faces: &'a [[u32; 3]]) -> Result<Self, MeshError> {
        let nv = positions.len();
        if let Some(face) = faces
            .par_iter()
            .position_first(|f| f.iter().any(|&i| i as usize >= nv))
        {
            let index = *faces[face]
                .iter()
                .find(|&&i| i as usize >= nv)
                .expect("found above");
            return Err(MeshError::IndexOutOfRange {
                face,
                index,
                vertices: nv,
            });
        }
        let areas: Vec<f64> = faces
            .par_iter()
            .map(|f| {
                if is_collapsed(f) {
                    return 0.0;
                }
                let [a, b, c] = f.map(|i| positions[i as usize]);
                let (a, b, c) = (DVec3::from(a), DVec3::from(b), DVec3::from(c));
                0.5 * (b - a).cross(c - a).length()
            })
            .collect();
        let mut cum = Vec::with_capacity(areas.len());
        let mut total = 0.0;
        let mut last = None;
        for (i, &ar) in areas.iter().enumerate() {
            if ar > 0.0 && ar.is_finite() {
                total += ar;
                last = Some(i);
            }
            cum.push(total);
        }
        let Some(last) = last else {
            return Err(MeshError::Empty {
                what: "mesh A has no face with positive area to sample",
            });
        };
        Ok(Self {
            positions,
            faces,
            cum,
            total,
            last,
        })
    }

    /// Sample `i` of the run seeded with `seed`.
    fn sample(&self, seed: u64, i: u64) -> [f64; 3] {
        let mut rng = SplitMix64::for_stream(seed, i);
        let t = rng.next_f64() * self.total;
        let fi = self.cum.partition_point(|&c| c <= t).min(self.last);
        let [a, b, c] = self.faces[fi].map(|k| self.positions[k as usize]);
        let s = rng.next_f64().sqrt();
        let r2 = rng.next_f64();
        let (wa, wb, wc) = (1.0 - s, s * (1.0 - r2), s * r2);
        std::array::from_fn(|k| wa * a[k] + wb * b[k] + wc * c[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square(z: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        (
            vec![[0.0, 0.0, z], [1.0, 0.0, z], [1.0, 1.0, z], [0.0, 1.0, z]],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn parallel_planes_are_their_gap_apart() {
        let (pa, fa) = unit_square(0.0);
        let (pb, fb) = unit_square(0.25);
        let r = distance((&pa, &fa), (&pb, &fb), 1000, 1);
        assert_eq!(r.samples, 1000);
        assert!((r.mean - 0.25).abs() < 1e-12);
        assert!((r.rms - 0.25).abs() < 1e-12);
        assert!((r.max - 0.25).abs() < 1e-12);
        assert!((r.bbox_diagonal - 2f64.sqrt()).abs() < 1e-12);
        assert!((r.area_sampled - 1.0).abs() < 1e-12);
    }

    #[test]
    fn samples_stay_on_their_faces_and_cover_them_by_area() {
        // Face 0 has area 1/2, face 1 (a larger triangle) area 2.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [10.0, 0.0, 0.0],
            [12.0, 0.0, 0.0],
            [10.0, 2.0, 0.0],
        ];
        let f = [[0, 1, 2], [3, 4, 5]];
        let s = AreaSampler::new(&p, &f).unwrap();
        let n = 20_000;
        let mut on_big = 0;
        for i in 0..n {
            let q = s.sample(9, i);
            assert_eq!(q[2], 0.0);
            if q[0] >= 10.0 {
                on_big += 1;
                assert!(q[0] - 10.0 + q[1] <= 2.0 + 1e-12 && q[1] >= 0.0);
            } else {
                assert!(q[0] + q[1] <= 1.0 + 1e-12 && q[0] >= 0.0 && q[1] >= 0.0);
            }
        }
        let frac = on_big as f64 / n as f64;
        assert!((frac - 0.8).abs() < 0.02, "fraction on the big face {frac}");
    }

    #[test]
    fn errors_are_typed() {
        let (p, f) = unit_square(0.0);
        let flat = [[0.0; 3]; 3];
        assert!(matches!(
            try_distance((&flat, &[[0, 1, 2]]), (&p, &f), 10, 0),
            Err(MeshError::Empty { .. })
        ));
        assert!(matches!(
            try_distance((&p, &f), (&p, &[]), 10, 0),
            Err(MeshError::Empty { .. })
        ));
        assert!(matches!(
            try_distance((&p, &f), (&p, &f), 0, 0),
            Err(MeshError::Empty { .. })
        ));
        assert!(matches!(
            try_distance((&p, &[[0, 1, 9]]), (&p, &f), 10, 0),
            Err(MeshError::IndexOutOfRange {
                face: 0,
                index: 9,
                vertices: 4
            })
        ));
    }
}
