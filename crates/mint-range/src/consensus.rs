//! Consensus geometry (Turk and Levoy 1994, §6): after zippering, each
//! vertex of the merged mesh moves **along its normal only** to the
//! confidence-weighted average of where that normal line meets every
//! original scan near the vertex.
//!
//! For a vertex V: the normal N is the confidence-weighted mean of the
//! normals of all scan vertices within [`ConsensusOptions::radius`]·s of V
//! (each scan's vertices looked up in a hash grid of the merged mesh's
//! vertices; the merged mesh's own vertex normal where none is that
//! close). The line
//! `V + t·N`, `|t| ≤ reach·s`, is intersected with each scan (a
//! [`RayBvh`] per scan, in the scan's own frame); each scan contributes its
//! hit nearest to V, weighted by the confidence interpolated at the hit
//! (barycentric weights of the triangle's corners). V moves to `V + t̄·N`
//! with `t̄` the weighted mean. All new positions are computed from the old
//! ones, then written (the result does not depend on vertex order). Scans
//! are visited one at a time ([`ScanSource`]), so only one scan and its
//! ray tree are in memory with the mesh.

use crate::error::RangeError;
use crate::geom::Rigid;
use crate::raycast::RayBvh;
use crate::scan_mesh::vertex_normals;
use crate::source::ScanSource;
use glam::DVec3;
use mint_core::progress::{NoProgress, Progress};
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
/// their poses; see the module docs. The scans are visited one at a time,
/// twice (normals, then intersections).
pub fn consensus<S: ScanSource + ?Sized>(positions: &mut [[f64; 3]], faces: &[[u32; 3]], scans: &S, poses: &[Rigid], opts: &ConsensusOptions) -> Result<ConsensusReport, RangeError> {
    consensus_with(positions, faces, scans, poses, opts, &NoProgress)
}

/// [`consensus`], reporting each scan visited ([`crate::phases::CONSENSUS`], two
/// passes) and stopping with [`RangeError::Cancelled`] when asked (the
/// positions are then unchanged).
pub fn consensus_with<S: ScanSource + ?Sized>(positions: &mut [[f64; 3]], faces: &[[u32; 3]], scans: &S, poses: &[Rigid], opts: &ConsensusOptions, progress: &dyn Progress) -> Result<ConsensusReport, RangeError> {
    if !(opts.radius > 0.0 && opts.reach > 0.0 && opts.radius.is_finite() && opts.reach.is_finite()) {
        return Err(RangeError::option("consensus", "radius and reach must be positive"));
    }
    if scans.len() != poses.len() {
        return Err(RangeError::option("poses", format!("{} poses for {} scans", poses.len(), scans.len())));
    }
    let s = scans.max_sampling();
    let radius = opts.radius * s;
    let reach = opts.reach * s;
    let own = vertex_normals(positions, faces);
    // 1. Normals: every scan vertex adds its weighted normal to the merged
    // mesh's vertices within `radius` (found through a hash grid of the
    // merged vertices, cells of `radius`), scan after scan.
    let ckey = |p: [f64; 3]| [0, 1, 2].map(|k| (p[k] / radius).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::default();
    for (i, &p) in positions.iter().enumerate() {
        grid.entry(ckey(p)).or_default().push(i as u32);
    }
    let mut normal_sum = vec![DVec3::ZERO; positions.len()];
    progress.start(crate::phases::CONSENSUS, 2 * poses.len() as u64);
    let step = || crate::error::advance(progress);
    for (k, pose) in poses.iter().enumerate() {
        step()?;
        let m = scans.scan(k)?;
        for i in 0..m.positions.len() {
            if m.confidence[i] <= 0.0 {
                continue;
            }
            let p = pose.apply(m.positions[i]);
            let wn = pose.rotate(m.normals[i]) * m.confidence[i];
            let c = ckey(p);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                            for &v in list {
                                if DVec3::from(p).distance(DVec3::from(positions[v as usize])) <= radius {
                                    normal_sum[v as usize] += wn;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    drop(grid);
    let normals: Vec<DVec3> = normal_sum
        .iter()
        .zip(&own)
        .map(|(&ns, &o)| {
            let n = ns.normalize_or_zero();
            if n == DVec3::ZERO || n.dot(o) < 0.0 && o != DVec3::ZERO {
                o
            } else {
                n
            }
        })
        .collect();
    drop(normal_sum);
    // 2. Intersections: each scan in turn adds, to every vertex whose
    // normal line meets it within `reach`, its hit nearest to the vertex.
    // Per vertex: (Σ t·w, Σ w, scans met).
    let mut acc = vec![(0.0f64, 0.0f64, 0usize); positions.len()];
    for (k, pose) in poses.iter().enumerate() {
        step()?;
        let m = scans.scan(k)?;
        let tree = RayBvh::new(&m.positions, &m.faces);
        let inv = pose.inverse();
        let pos: &[[f64; 3]] = positions;
        acc.par_iter_mut().enumerate().for_each(|(i, a)| {
            let n = normals[i];
            if n == DVec3::ZERO {
                return;
            }
            let mut best: Option<(f64, f64)> = None;
            tree.segment_hits(inv.apply(DVec3::from(pos[i])), inv.rotate(n), -reach, reach, |h| {
                let f = m.faces[h.face as usize];
                let w: f64 = (0..3).map(|c| h.bary[c] * m.confidence[f[c] as usize]).sum();
                if best.is_none_or(|b| h.t.abs() < b.0.abs()) {
                    best = Some((h.t, w));
                }
            });
            if let Some((t, w)) = best {
                if w > 0.0 {
                    a.0 += t * w;
                    a.1 += w;
                    a.2 += 1;
                }
            }
        });
    }
    progress.finish();
    let mut r = ConsensusReport::default();
    let mut scans_met = 0;
    for ((p, &(tw, ws, met)), &n) in positions.iter_mut().zip(&acc).zip(&normals) {
        if ws <= 0.0 {
            continue;
        }
        let t = tw / ws;
        *p = (DVec3::from(*p) + n * t).to_array();
        r.moved += 1;
        r.mean_move += t.abs();
        r.max_move = r.max_move.max(t.abs());
        scans_met += met;
    }
    if r.moved > 0 {
        r.mean_move /= r.moved as f64;
        r.mean_scans = scans_met as f64 / r.moved as f64;
    }
    Ok(r)
}
