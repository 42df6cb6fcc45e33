//! Consensus geometry (Turk and Levoy 1994, §6): after zippering, each
//! vertex of the merged mesh moves **along its normal only** to the
//! confidence-weighted average of where that normal line meets every
//! original scan near the vertex.
//!
//! For a vertex V: the normal N is the confidence-weighted mean of the
//! normals of all scan vertices within [`ConsensusOptions::radius`]·s of V
//! (through a hash grid of all scan vertices in world coordinates; the
//! merged mesh's own vertex normal where none is that close). The line
//! `V + t·N`, `|t| ≤ reach·s`, is intersected with each scan (a
//! [`RayBvh`] per scan, in the scan's own frame); each scan contributes its
//! hit nearest to V, weighted by the confidence interpolated at the hit
//! (barycentric weights of the triangle's corners). V moves to `V + t̄·N`
//! with `t̄` the weighted mean. All new positions are computed from the old
//! ones, then written (the result does not depend on vertex order).

use crate::error::RangeError;
use crate::geom::{add, dot, normalize, scale, Rigid, V3};
use crate::raycast::RayBvh;
use crate::scan_mesh::{vertex_normals, ScanMesh};
use rayon::prelude::*;
use serde::Serialize;
use rustc_hash::FxHashMap as HashMap;

/// Options of [`consensus`]; every field has a documented default.
#[derive(Debug, Clone, PartialEq)]
pub struct ConsensusOptions {
    /// Radius of the sphere whose scan normals are averaged, in multiples
    /// of s (the largest sampling distance). Default 2.
    pub radius: f64,
    /// How far along the normal intersections count, in multiples of s.
    /// Default 3 (the zipper's redundancy tolerance).
    pub reach: f64,
}

impl Default for ConsensusOptions {
    fn default() -> Self {
        ConsensusOptions { radius: 2.0, reach: 3.0 }
    }
}

/// What consensus geometry did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ConsensusReport {
    /// Vertices moved (at least one intersection found).
    pub moved: usize,
    /// Mean and largest |t̄|.
    pub mean_move: f64,
    pub max_move: f64,
    /// Mean number of scans met per moved vertex.
    pub mean_scans: f64,
}

/// Moves `positions` (a mesh with `faces`) to the consensus of the scans at
/// their poses; see the module docs.
pub fn consensus(positions: &mut [V3], faces: &[[u32; 3]], scans: &[ScanMesh], poses: &[Rigid], opts: &ConsensusOptions) -> Result<ConsensusReport, RangeError> {
    if !(opts.radius > 0.0 && opts.reach > 0.0 && opts.radius.is_finite() && opts.reach.is_finite()) {
        return Err(RangeError::option("consensus", "radius and reach must be positive"));
    }
    let s = scans.iter().map(|m| m.sampling).fold(0.0, f64::max);
    let radius = opts.radius * s;
    let reach = opts.reach * s;
    let own = vertex_normals(positions, faces);
    // Scan vertices and normals in the world, hashed by cells of `radius`.
    let ckey = |p: V3| [0, 1, 2].map(|k| (p[k] / radius).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<(V3, V3, f64)>> = HashMap::default();
    for (m, pose) in scans.iter().zip(poses) {
        for i in 0..m.positions.len() {
            if m.confidence[i] > 0.0 {
                let p = pose.apply(m.positions[i]);
                grid.entry(ckey(p)).or_default().push((p, pose.rotate(m.normals[i]), m.confidence[i]));
            }
        }
    }
    let trees: Vec<(RayBvh, Rigid)> = scans.iter().zip(poses).map(|(m, p)| (RayBvh::new(&m.positions, &m.faces), p.inverse())).collect();
    let moves: Vec<Option<(f64, usize, V3)>> = positions
        .par_iter()
        .enumerate()
        .map(|(i, &v)| {
            let c = ckey(v);
            let mut n = [0.0; 3];
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                            for &(p, nn, w) in list {
                                if crate::geom::dist(p, v) <= radius {
                                    n = add(n, scale(nn, w));
                                }
                            }
                        }
                    }
                }
            }
            let mut n = normalize(n);
            if n == [0.0; 3] || dot(n, own[i]) < 0.0 && own[i] != [0.0; 3] {
                n = own[i];
            }
            if n == [0.0; 3] {
                return None;
            }
            let (mut tw, mut ws, mut met) = (0.0, 0.0, 0);
            for ((tree, inv), m) in trees.iter().zip(scans) {
                let o = inv.apply(v);
                let dir = inv.rotate(n);
                let mut best: Option<(f64, f64)> = None;
                tree.segment_hits(o, dir, -reach, reach, |h| {
                    let f = m.faces[h.face as usize];
                    let w: f64 = (0..3).map(|k| h.bary[k] * m.confidence[f[k] as usize]).sum();
                    if best.is_none_or(|b| h.t.abs() < b.0.abs()) {
                        best = Some((h.t, w));
                    }
                });
                if let Some((t, w)) = best {
                    if w > 0.0 {
                        tw += t * w;
                        ws += w;
                        met += 1;
                    }
                }
            }
            if ws <= 0.0 {
                return None;
            }
            Some((tw / ws, met, n))
        })
        .collect();
    let mut r = ConsensusReport::default();
    let mut scans_met = 0;
    for (p, m) in positions.iter_mut().zip(&moves) {
        if let Some((t, met, n)) = *m {
            *p = add(*p, scale(n, t));
            r.moved += 1;
            r.mean_move += t.abs();
            r.max_move = r.max_move.max(t.abs());
            scans_met += met;
        }
    }
    if r.moved > 0 {
        r.mean_move /= r.moved as f64;
        r.mean_scans = scans_met as f64 / r.moved as f64;
    }
    Ok(r)
}
