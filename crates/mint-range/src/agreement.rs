//! How well posed scans agree with each other: for every pair of scans
//! that overlap under the given poses, the RMS point-to-plane distance of
//! their overlap, and the same pooled over all pairs. It needs no ground
//! truth and no peer tool, so two pose sets of the same scans (mint's and
//! a published `.conf`, or two runs) can be compared by it: lower is
//! tighter. `mint align` reports it for its result; `mint align
//! --evaluate` for a set's own poses.
//!
//! Per pair (a, b): a's finest-level samples (thinned to `max_samples`,
//! off the boundary, confidence > 0) are paired with the closest point on
//! b's surface within `d`, and b's with a's. The overlap is the smaller of
//! the two paired fractions; a pair counts when it is at least
//! `min_overlap`. Each paired sample contributes its distance along the
//! surface normal at the closest point (the mean of the triangle's corner
//! normals), unweighted and untrimmed: every sample within `d` is an
//! inlier, as in Open3D's `evaluate_registration` with threshold `d`.

use crate::geom::Rigid;
use crate::icp::{pairs_with, stride, Targets};
use serde::Serialize;

/// One overlapping pair under the poses.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairAgreement {
    pub a: String,
    pub b: String,
    /// The smaller fraction of either scan's samples within `d` of the other.
    pub overlap: f64,
    /// Paired samples, both ways.
    pub pairs: usize,
    /// RMS point-to-plane distance of those samples (model units).
    pub rms: f64,
}

/// The agreement of a pose set: every overlapping pair, the RMS pooled over
/// all their samples, and the median of the pairs' RMS.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Agreement {
    /// Pairing distance: samples farther from the other scan do not count.
    pub distance: f64,
    pub min_overlap: f64,
    pub pairs: Vec<PairAgreement>,
    pub rms: f64,
    pub median_rms: f64,
}

/// The agreement of the scans of `t` at `poses` within `d`, over the scans
/// with `include[i]` (failed scans are left out by the caller). Pairs are
/// in index order (a < b); the result does not depend on the thread count.
pub(crate) fn measure(t: &Targets, poses: &[Rigid], include: &[bool], d: f64, min_overlap: f64) -> Agreement {
    let n = t.scans.len();
    let level = |i: usize| t.scans[i].levels.len() - 1;
    let usable: Vec<usize> = (0..n)
        .map(|i| {
            let s = &t.scans[i];
            let lv = &s.levels[level(i)];
            lv.iter().step_by(stride(lv.len(), t.max_samples())).filter(|&&v| !s.boundary[v as usize] && s.confidence[v as usize] > 0.0).count().max(1)
        })
        .collect();
    let (mut pairs, mut sum_sq, mut count) = (Vec::new(), 0.0f64, 0usize);
    for a in (0..n).filter(|&i| include[i]) {
        for b in (a + 1..n).filter(|&j| include[j]) {
            // The same level for both directions: each scan's finest.
            let ab = pairs_with(t, a, level(a), &[b], poses, d, false);
            if (ab.len() as f64 / usable[a] as f64) < min_overlap {
                continue;
            }
            let ba = pairs_with(t, b, level(b), &[a], poses, d, false);
            let overlap = (ab.len() as f64 / usable[a] as f64).min(ba.len() as f64 / usable[b] as f64);
            if overlap < min_overlap {
                continue;
            }
            let sq: f64 = ab.iter().chain(&ba).map(|p| (p.src - p.dst).dot(p.normal).powi(2)).sum();
            let k = ab.len() + ba.len();
            sum_sq += sq;
            count += k;
            pairs.push(PairAgreement { a: t.scans[a].name.clone(), b: t.scans[b].name.clone(), overlap, pairs: k, rms: (sq / k.max(1) as f64).sqrt() });
        }
    }
    let mut r: Vec<f64> = pairs.iter().map(|p| p.rms).collect();
    let median_rms = if r.is_empty() { 0.0 } else { crate::range_image::median(&mut r) };
    Agreement { distance: d, min_overlap, pairs, rms: if count == 0 { 0.0 } else { (sum_sq / count as f64).sqrt() }, median_rms }
}
