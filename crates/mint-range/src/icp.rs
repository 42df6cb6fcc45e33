//! Constrained ICP (`mint align`): registers scans to each other, after
//! Turk and Levoy 1994, §4.
//!
//! Sources: P. Besl and N. McKay, "A Method for Registration of 3-D
//! Shapes", IEEE PAMI 14(2), 1992 (the iteration); B. K. P. Horn,
//! "Closed-form solution of absolute orientation using unit quaternions",
//! JOSA A 4(4), 1987 (the best rigid motion: the eigenvector of the largest
//! eigenvalue of a 4×4 symmetric matrix built from the weighted
//! cross-covariance; solved with nalgebra's symmetric eigen-decomposition);
//! Y. Chen and G. Medioni, "Object modelling by registration of multiple
//! range images", 1992 (the point-to-plane option, linearized in the
//! rotation and solved as a 6×6 system); G. Turk and M. Levoy 1994, §4.1–4.4
//! (the constraints).
//!
//! One iteration for a source scan against a set of target scans:
//! 1. each sample vertex of the source (the current hierarchy level; not on
//!    the source's boundary, confidence > 0) is moved to the world by the
//!    source's current pose, and its nearest point **on the surface** of
//!    each target (a [`mint_mesh::TriangleBvh`] per scan, built once in the
//!    scan's own frame) is looked for within the distance `d`
//!    (`nearest_within`); the nearest over all targets wins. With
//!    [`AlignOptions::symmetric`] (the default, mint's addition) the
//!    targets' samples are also paired with the source's surface: scan
//!    vertices lie on the surface and scan triangles are its chords, so a
//!    one-way vertex-to-surface distance is biased by the chord error and
//!    the two directions' biases cancel (on the synthetic test scene this
//!    took the worst view from 0.34° to 0.10°);
//! 2. the pair is dropped when the target point lies on a triangle with a
//!    boundary corner (the boundary constraint: boundary matches drag
//!    meshes apart);
//! 3. the pair's weight is the product of the two confidences (source
//!    vertex, mean of the target triangle's corners);
//! 4. pairs farther apart than [`AlignOptions::reject`] × the median pair
//!    distance are dropped (mint's addition);
//! 5. the weighted best rigid motion (Horn, or point-to-plane; by default
//!    point-to-plane on the coarse levels and Horn on the last,
//!    [`Metric::PlaneThenPoint`]) moves the source, combined with the last
//!    steps by Anderson acceleration (guarded by the energy); repeat until it moves less than [`AlignOptions::tolerance`] times the
//!    sampling distance, or [`AlignOptions::max_iterations`].
//!
//! The hierarchy: levels of the source's samples (every 8th, 4th, 2nd row
//! and column, then all; [`crate::ScanMesh::levels`]), from the coarsest,
//! with `d` halving from [`AlignOptions::start_distance`] down to
//! [`AlignOptions::distance`]. The targets stay at full resolution: the
//! closest point is on their surface anyway.
//!
//! Which targets: by default ([`AlignOptions::global`]) the registration
//! is multiview ([`crate::multiview`]): judged pairwise alignments along
//! the overlap graph, then one solve of all poses; this module provides
//! the pairwise ICP it runs. With `global: false`, the strategies below
//! (mint's registration before issue 17). With
//! [`Strategy::Growing`] (the default) the anchor scan
//! is fixed and the others join one at a time, each time the one with the
//! most pairs against the scans already registered, and registers against
//! all of them; then [`AlignOptions::refine_passes`] passes re-register
//! every scan against all others at the final distance and the finest
//! level. With
//! [`Strategy::Anchor`] every scan registers against the anchor alone. A
//! scan with fewer than [`AlignOptions::min_pairs`] pairs is reported as
//! failed and left out; the run continues.

use crate::error::RangeError;
use crate::geom::Rigid;
use glam::DVec3;

use crate::scan_mesh::ScanMesh;
use mint_core::progress::Progress;
use mint_mesh::TriangleBvh;
use rayon::prelude::*;
use serde::Serialize;

/// The error metric minimized at each iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Metric {
    /// Σ w·|R·b + t − a|², solved in closed form by Horn's quaternion method.
    PointToPoint,
    /// Σ w·((R·b + t − a)·n_a)², linearized in the rotation (Chen–Medioni).
    PointToPlane,
    /// Point-to-plane on every distance level but the last, then Horn's
    /// point-to-point on the last level and in the refine passes.
    /// Point-to-point alone crawls when the scans must slide along each
    /// other (each step only removes a fraction of the tangential offset,
    /// so hundreds of iterations end a degree short); point-to-plane gets
    /// into the basin in tens of iterations but its minimum is biased by
    /// the noise in the target's face normals. Together: the speed of the
    /// one and the accuracy of the other (measured in
    /// `crates/mint-range/tests/range.rs`).
    PlaneThenPoint,
}

/// How the residuals of one iteration are weighed (mint's addition; see
/// [`AlignOptions::reject`] for the scale `c`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Kernel {
    /// Pairs farther apart than `c` are dropped, the rest keep their
    /// weight (trimming).
    Trim,
    /// Tukey's biweight: a pair at distance `r < c` keeps `(1 − (r/c)²)²`
    /// of its weight, farther ones are dropped. Softer than trimming: a
    /// pair near the cut-off counts little, so the set of pairs can change
    /// without the step jumping. The judge's retry uses it.
    Tukey,
}

/// Which scans each scan registers against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Strategy {
    /// To the growing model of all scans registered so far, then refined
    /// against all others.
    Growing,
    /// Every scan to the anchor scan only.
    Anchor,
}

/// Options of [`align`]; every field has a documented default.
#[derive(Debug, Clone, PartialEq)]
pub struct AlignOptions {
    /// Final pairing distance d. Default `None`: 2·s with s the largest
    /// sampling distance of the scans (Turk and Levoy: "twice the spacing").
    pub distance: Option<f64>,
    /// Pairing distance of the coarsest level; halved per level down to
    /// `distance`. Default `None`: 8·`distance` (four levels). Raise it when
    /// the initial poses are off by more than about half of it.
    pub start_distance: Option<f64>,
    /// Iterations per level at most. Default 50.
    pub max_iterations: usize,
    /// Convergence: an iteration moving the source's bounding box corners
    /// by less than this fraction of its sampling distance ends the level.
    /// Default 1e-2 (a hundredth of the sample spacing: 1e-3 took six
    /// times as many iterations on the bunny for no measurable gain).
    pub tolerance: f64,
    /// Default [`Metric::PlaneThenPoint`].
    pub metric: Metric,
    /// Default [`Strategy::Growing`]. Used only with `global: false`.
    pub strategy: Strategy,
    /// Multiview registration ([`crate::multiview`]): pairwise alignments
    /// judged one by one, along a maximum spanning tree of the overlap
    /// graph, then between all overlapping pairs, then every pose solved
    /// at once. Default true; false runs `strategy` (mint's registration
    /// before issue 17).
    pub global: bool,
    /// Multiview: two scans are partners when each has at least this
    /// fraction of its samples within the pairing distance of the other
    /// (at the start distance from the initial poses, at the final distance
    /// after registration). Default 0.05.
    pub min_overlap: f64,
    /// Multiview: a pairwise alignment whose RMS is more than this many
    /// times the median RMS of the accepted alignments (both relative to
    /// the scans' sampling distance) fails. Default 2.5.
    pub rms_factor: f64,
    /// Multiview: rounds of (pairwise alignments, global solve) at most;
    /// the rounds stop earlier when no scan moves by more than a quarter of
    /// its sampling distance. Default 4.
    pub global_rounds: usize,
    /// Default [`Kernel::Trim`].
    pub kernel: Kernel,
    /// The scan that stays fixed. Default 0 (the first of the set).
    pub anchor: usize,
    /// Fewest pairs for a registration to count. Default 100.
    pub min_pairs: usize,
    /// Passes re-registering every scan against all others at the final
    /// distance (growing model only). Default 3.
    pub refine_passes: usize,
    /// Robust rejection (mint's addition, after Zhang, "Iterative point
    /// matching for registration of free-form curves and surfaces", IJCV
    /// 1994): at each iteration pairs farther apart than `reject` times the
    /// median pair distance are dropped. Large distances at the coarse
    /// levels otherwise match surfaces one scan saw to different surfaces
    /// of the other and drag it off. Default 3; `f64::INFINITY` turns it off.
    pub reject: f64,
    /// Anderson acceleration of the iteration (see [`align`]'s loop).
    /// Default true.
    pub accelerate: bool,
    /// Pair both ways: the source's samples with the targets' surfaces and
    /// the targets' samples with the source's surface. Cancels the bias of
    /// vertex-to-chord distances on curved surfaces. Default true.
    pub symmetric: bool,
    /// At most this many samples of a scan are paired per iteration (a
    /// regular stride through the level's samples), in each direction.
    /// Tens of thousands of well-spread pairs pin a rigid motion; more
    /// only cost time. Default 8192; `usize::MAX` uses every sample.
    pub max_samples: usize,
}

impl Default for AlignOptions {
    fn default() -> Self {
        AlignOptions {
            distance: None,
            start_distance: None,
            max_iterations: 50,
            tolerance: 1e-2,
            metric: Metric::PlaneThenPoint,
            strategy: Strategy::Growing,
            global: true,
            min_overlap: 0.05,
            rms_factor: 2.5,
            global_rounds: 4,
            kernel: Kernel::Trim,
            anchor: 0,
            min_pairs: 100,
            refine_passes: 3,
            reject: 3.0,
            accelerate: true,
            symmetric: true,
            max_samples: 8192,
        }
    }
}

/// What happened to one scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Status {
    /// The fixed scan.
    Anchor,
    /// Registered.
    Registered,
    /// Not registered (the reason); kept at its initial pose and flagged in
    /// the output set.
    Failed(String),
}

/// Per-scan registration report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanReport {
    pub name: String,
    pub status: Status,
    /// Pairs at the final distance in the last iteration.
    pub pairs: usize,
    /// RMS distance of those pairs (unweighted), model units.
    pub rms: f64,
    /// RMS divided by the scan's sampling distance: comparable across scans
    /// and scanners.
    pub rms_rel: f64,
    /// Iterations over all levels and passes.
    pub iterations: usize,
    /// Every registration of the scan ended below the tolerance (none hit
    /// [`AlignOptions::max_iterations`] on a level).
    pub converged: bool,
    /// The scans whose pairwise alignment with this one was accepted
    /// (multiview; the scans registered against otherwise).
    pub partners: Vec<String>,
    /// How far registration moved the scan: rotation in degrees and the
    /// largest displacement of its bounding-box corners.
    pub moved_deg: f64,
    pub moved: f64,
    /// Multiview: registrations tried again after the scan first failed (0:
    /// it did not fail), and the start that succeeded.
    pub retries: usize,
    pub retried_from: Option<String>,
}

impl ScanReport {
    /// A scan not (yet) reached.
    pub(crate) fn new(name: &str) -> ScanReport {
        ScanReport { name: name.to_string(), status: Status::Failed("not reached".into()), pairs: 0, rms: 0.0, rms_rel: 0.0, iterations: 0, converged: true, partners: Vec::new(), moved_deg: 0.0, moved: 0.0, retries: 0, retried_from: None }
    }
}

/// One correspondence, in world coordinates.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pair {
    /// On the source scan's surface or a source sample.
    pub(crate) src: DVec3,
    /// On a target's surface or a target sample.
    pub(crate) dst: DVec3,
    /// The unit normal of the triangle the closest point lies on, world.
    pub(crate) normal: DVec3,
    pub(crate) w: f64,
}

/// The scans with what pairing needs of them: a BVH and face normals per
/// scan, built once.
pub(crate) struct Targets<'a> {
    pub(crate) scans: &'a [ScanMesh],
    /// Pair both ways ([`AlignOptions::symmetric`]).
    symmetric: bool,
    /// [`AlignOptions::max_samples`].
    max_samples: usize,
    bvhs: &'a [TriangleBvh],
    face_normals: &'a [Vec<DVec3>],
}

impl<'a> Targets<'a> {
    /// Scans with their BVHs and face normals (built by the caller).
    pub(crate) fn new(scans: &'a [ScanMesh], symmetric: bool, max_samples: usize, bvhs: &'a [TriangleBvh], face_normals: &'a [Vec<DVec3>]) -> Targets<'a> {
        Targets { scans, symmetric, max_samples, bvhs, face_normals }
    }

    /// Samples paired per direction at most.
    pub(crate) fn max_samples(&self) -> usize {
        self.max_samples
    }

    /// The same scans, pairing at most `max_samples` per direction.
    pub(crate) fn with_max_samples(&self, max_samples: usize) -> Targets<'_> {
        Targets { scans: self.scans, symmetric: self.symmetric, max_samples, bvhs: self.bvhs, face_normals: self.face_normals }
    }
}

/// The registration of mint before multiview (`--global off`): the
/// strategies of the module docs, on `targets` from the `initial` poses with
/// pairing distances `dists`. Returns the poses (failed scans keep their
/// initial one) and a report per scan.
pub(crate) fn register_sequential(targets: &Targets, initial: &[Rigid], dists: &[f64], opts: &AlignOptions, progress: &dyn Progress) -> Result<(Vec<Rigid>, Vec<ScanReport>), RangeError> {
    let scans = targets.scans;
    let dists = dists.to_vec();
    let mut poses = initial.to_vec();
    let mut reports: Vec<ScanReport> = scans.iter().map(|s| ScanReport::new(&s.name)).collect();
    reports[opts.anchor].status = Status::Anchor;
    let mut registered = vec![opts.anchor];
    let mut pending: Vec<usize> = (0..scans.len()).filter(|&i| i != opts.anchor).collect();
    let passes = match opts.strategy {
        Strategy::Anchor => 1,
        Strategy::Growing => 1 + opts.refine_passes,
    };
    progress.start(crate::phases::REGISTER, (passes * pending.len()) as u64);
    let step = || crate::error::advance(progress);
    match opts.strategy {
        Strategy::Anchor => {
            for &i in &pending {
                if !register_one(targets, i, &[opts.anchor], &mut poses, &dists, opts, &mut reports[i]) {
                    poses[i] = initial[i];
                }
                step()?;
            }
        }
        Strategy::Growing => {
            while !pending.is_empty() {
                // The pending scan that overlaps the model most joins next.
                let counts: Vec<usize> = pending.iter().map(|&i| pairs_with(targets, i, 0, &registered, &poses, dists[0], false).len()).collect();
                let (k, &best) = counts.iter().enumerate().max_by_key(|&(k, &c)| (c, usize::MAX - k)).expect("pending is not empty");
                if best < required(&scans[pending[k]], 0, opts.min_pairs, opts.max_samples) {
                    for &i in &pending {
                        reports[i].status = Status::Failed(format!(
                            "no overlap: {} pairs within {:.4e} of the registered scans at the coarsest level (need {})",
                            counts[pending.iter().position(|&j| j == i).unwrap()],
                            dists[0],
                            required(&scans[i], 0, opts.min_pairs, opts.max_samples)
                        ));
                    }
                    break;
                }
                let i = pending.remove(k);
                if register_one(targets, i, &registered, &mut poses, &dists, opts, &mut reports[i]) {
                    registered.push(i);
                } else {
                    poses[i] = initial[i];
                }
                step()?;
            }
            let fine = &dists[dists.len() - 1..];
            for _ in 0..opts.refine_passes {
                let all = registered.clone();
                for &i in &all {
                    if i == opts.anchor {
                        continue;
                    }
                    let others: Vec<usize> = all.iter().copied().filter(|&j| j != i).collect();
                    let keep = poses[i];
                    let mut r = reports[i].clone();
                    let ok = register_one(targets, i, &others, &mut poses, fine, opts, &mut r);
                    step()?;
                    if !ok {
                        poses[i] = keep;
                        continue;
                    }
                    r.iterations += reports[i].iterations;
                    r.converged &= reports[i].converged;
                    reports[i] = r;
                }
            }
        }
    }
    progress.finish();
    Ok((poses, reports))
}

/// Pairs needed at a hierarchy level: `min_pairs` scaled by the level's
/// share of the (thinned) samples, at least 6 unless `min_pairs` is
/// smaller, and never more than `min_pairs`.
pub(crate) fn required(scan: &ScanMesh, level: usize, min_pairs: usize, cap: usize) -> usize {
    let used = |n: usize| n.div_ceil(stride(n, cap));
    let finest = used(scan.levels.last().map_or(1, Vec::len)).max(1);
    (min_pairs * used(scan.levels[level].len()) / finest).max(6).min(min_pairs)
}

/// The step through a level's samples so that at most `cap` are used.
pub(crate) fn stride(n: usize, cap: usize) -> usize {
    n.div_ceil(cap.max(1)).max(1)
}

/// `d0, d0/2, ...` down to `d` (the last one is exactly `d`).
pub(crate) fn distance_levels(d0: f64, d: f64) -> Vec<f64> {
    let mut v = vec![d0];
    while *v.last().unwrap() > d * 1.0001 {
        let next = (v.last().unwrap() * 0.5).max(d);
        v.push(next);
    }
    v
}

/// Registers scan `i` against `targets_idx` through the distance levels;
/// updates its pose and report; false (and the report says why) if too
/// few pairs remain.
pub(crate) fn register_one(t: &Targets, i: usize, targets_idx: &[usize], poses: &mut [Rigid], dists: &[f64], opts: &AlignOptions, report: &mut ScanReport) -> bool {
    let scan = &t.scans[i];
    let corners = scan.bbox_corners();
    let nl = scan.levels.len();
    let k = dists.len();
    let mut iterations = 0;
    let (lo, hi) = crate::scan_mesh::bbox(corners.iter().copied());
    let (lo, hi) = (DVec3::from(lo), DVec3::from(hi));
    let centre_local = (lo + hi) * 0.5;
    let radius = 0.5 * lo.distance(hi);
    let mut converged = true;
    for (j, &d) in dists.iter().enumerate() {
        let level = (nl + j).saturating_sub(k).min(nl - 1);
        let metric = match opts.metric {
            Metric::PlaneThenPoint if j + 1 < k => Metric::PointToPlane,
            Metric::PlaneThenPoint => Metric::PointToPoint,
            m => m,
        };
        // Poses of this level as 6-vectors: the motion from the level's
        // starting pose, about the scan's centre there.
        let base = poses[i];
        let c = base.apply(centre_local);
        let to_vec = |p: &Rigid| motion_vector(&p.after(&base.inverse()), c, radius);
        let from_vec = |v: [f64; 6]| motion_from_vector(v, c, radius).after(&base);
        let mut anderson = Anderson::new(ANDERSON_DEPTH);
        // The last plain ICP step (fallback when an accelerated one raises
        // the energy) and the energy of the pose it was taken from.
        let mut fallback: Option<(Rigid, f64)> = None;
        let mut settled = false;
        // The energies of the level's iterations, for the plateau test.
        let mut energies: Vec<f64> = Vec::new();
        for _ in 0..opts.max_iterations {
            let p = weighed(pairs(t, i, level, targets_idx, poses, d), opts.reject, opts.kernel);
            let need = required(scan, level, opts.min_pairs, opts.max_samples);
            if p.len() < need {
                report.status = Status::Failed(format!("no overlap: {} pairs within {d:.4e} (need {need})", p.len()));
                report.pairs = p.len();
                report.iterations = iterations;
                return false;
            }
            let energy = weighted_mean_square(&p);
            energies.push(energy);
            if let Some((plain, e_prev)) = fallback {
                if anderson.accelerated && energy > e_prev {
                    // The extrapolation overshot: take the plain step
                    // instead and start the history again.
                    poses[i] = plain;
                    anderson.reset();
                    fallback = None;
                    continue;
                }
            }
            let delta = match metric {
                Metric::PointToPlane => point_to_plane(&p),
                _ => horn(&p),
            };
            iterations += 1;
            let Some(delta) = delta else {
                settled = true;
                break;
            };
            let plain = delta.after(&poses[i]).orthonormalized();
            let moved = corners.iter().map(|&cn| poses[i].apply(DVec3::from(cn)).distance(plain.apply(DVec3::from(cn)))).fold(0.0, f64::max);
            if moved < opts.tolerance * scan.sampling {
                poses[i] = plain;
                settled = true;
                break;
            }
            poses[i] = if opts.accelerate { from_vec(anderson.next(to_vec(&poses[i]), to_vec(&plain))).orthonormalized() } else { plain };
            fallback = Some((plain, energy));
        }
        // The last level decides convergence (the coarser ones only bring
        // the scan into its basin, and may hand over unfinished). If it
        // used up its iterations it did not converge, unless its energy had
        // stopped falling: then the scan was only creeping along a
        // direction the overlap does not determine (a surface of
        // revolution, a plane), at no gain.
        if j + 1 == k {
            converged = settled || plateau(&energies);
        }
    }
    report.converged = converged;
    // Final statistics at the finest level and distance.
    let p = pairs(t, i, nl - 1, targets_idx, poses, *dists.last().unwrap());
    if p.len() < opts.min_pairs {
        report.status = Status::Failed(format!("no overlap: {} pairs within {:.4e} after registration (need {})", p.len(), dists.last().unwrap(), opts.min_pairs));
        report.pairs = p.len();
        report.iterations = iterations;
        return false;
    }
    report.status = Status::Registered;
    report.pairs = p.len();
    report.rms = (p.iter().map(|q| q.src.distance_squared(q.dst)).sum::<f64>() / p.len() as f64).sqrt();
    report.rms_rel = report.rms / scan.sampling;
    report.iterations = iterations;
    true
}

/// Iterations over which [`plateau`] looks.
const PLATEAU: usize = 10;

/// Whether the energy of a level has stopped falling: the median of its
/// last [`PLATEAU`] iterations is not 5% below the median of the
/// [`PLATEAU`] before (medians, because the pairs change between
/// iterations and the energy of noise-free scans jumps by tens of percent
/// at its floor). The objective has then converged, whatever the pose
/// still does.
fn plateau(energies: &[f64]) -> bool {
    if energies.len() < 2 * PLATEAU {
        return false;
    }
    let n = energies.len();
    let last = crate::range_image::median(&mut energies[n - PLATEAU..].to_vec());
    let before = crate::range_image::median(&mut energies[n - 2 * PLATEAU..n - PLATEAU].to_vec());
    last >= 0.95 * before
}

/// Weighted mean squared pair distance and pair count of scan `i` (finest
/// level) against `targets_idx` at the poses given, within `d`, after the
/// same trimming as registration: the objective ICP minimizes.
pub fn objective(scans: &[ScanMesh], poses: &[Rigid], i: usize, targets_idx: &[usize], d: f64, reject: f64) -> Result<(f64, usize), RangeError> {
    let bvhs: Vec<TriangleBvh> = scans
        .iter()
        .map(|s| TriangleBvh::new(&s.positions, &s.faces).map_err(|e| RangeError::Mesh { what: s.name.clone(), source: e }))
        .collect::<Result<_, _>>()?;
    let face_normals = vec![Vec::new(); scans.len()];
    let t = Targets { scans, symmetric: false, max_samples: usize::MAX, bvhs: &bvhs, face_normals: &face_normals };
    let p = trimmed(pairs(&t, i, scans[i].levels.len() - 1, targets_idx, poses, d), reject);
    Ok((weighted_mean_square(&p), p.len()))
}

/// Iterates remembered by [`Anderson`].
const ANDERSON_DEPTH: usize = 5;

/// Anderson acceleration of the fixed-point map `x ↦ G(x)` that one ICP
/// step is (D. G. Anderson, "Iterative procedures for nonlinear integral
/// equations", J. ACM 1965; applied to ICP by Pavlov, Ovchinnikov,
/// Shmatko and Korbut, "AA-ICP", 2018): the next iterate combines the
/// last `depth` steps so as to cancel their residuals `G(x) − x` in the
/// least-squares sense. Point-to-point ICP converges linearly and slowly
/// when the scans must slide along each other; this turns hundreds of
/// crawling iterations into tens. The caller guards it with the energy
/// (an accelerated step that raises it is replaced by the plain step).
struct Anderson {
    depth: usize,
    /// (x, G(x)) of the last iterations, oldest first.
    history: Vec<([f64; 6], [f64; 6])>,
    /// Whether the last [`Anderson::next`] extrapolated.
    accelerated: bool,
}

impl Anderson {
    fn new(depth: usize) -> Anderson {
        Anderson { depth, history: Vec::new(), accelerated: false }
    }

    fn reset(&mut self) {
        self.history.clear();
        self.accelerated = false;
    }

    /// The next iterate from `x` and its plain step `g = G(x)`.
    fn next(&mut self, x: [f64; 6], g: [f64; 6]) -> [f64; 6] {
        self.history.push((x, g));
        if self.history.len() > self.depth + 1 {
            self.history.remove(0);
        }
        let m = self.history.len() - 1;
        self.accelerated = false;
        if m == 0 {
            return g;
        }
        let f = |h: &([f64; 6], [f64; 6])| -> nalgebra::Vector6<f64> { nalgebra::Vector6::from_fn(|r, _| h.1[r] - h.0[r]) };
        let fk = f(&self.history[m]);
        // Columns: differences of residuals and of steps.
        let df = nalgebra::DMatrix::from_fn(6, m, |r, c| fk[r] - f(&self.history[m - 1 - c])[r]);
        let dg = nalgebra::DMatrix::from_fn(6, m, |r, c| g[r] - self.history[m - 1 - c].1[r]);
        let Ok(svd) = nalgebra::SVD::try_new(df, true, true, f64::EPSILON, 100).ok_or(()) else { return g };
        // Singular values below 1e-10 of the largest are treated as zero:
        // a cut-off relative to the data, not to the scan's units.
        let cutoff = 1e-10 * svd.singular_values.max();
        let Ok(theta) = svd.solve(&nalgebra::DVector::from_column_slice(fk.as_slice()), cutoff) else { return g };
        let next = nalgebra::DVector::from_column_slice(&g) - dg * theta;
        if next.iter().any(|v| !v.is_finite()) {
            return g;
        }
        self.accelerated = true;
        std::array::from_fn(|r| next[r])
    }
}

/// Σ w·|src − dst|² / Σ w: the energy point-to-point ICP lowers.
fn weighted_mean_square(p: &[Pair]) -> f64 {
    let w: f64 = p.iter().map(|q| q.w).sum();
    p.iter().map(|q| q.w * q.src.distance_squared(q.dst)).sum::<f64>() / w.max(f64::MIN_POSITIVE)
}

/// A motion as `[ω·radius, t]` about the point `c`: `p ↦ R(ω)(p − c) + c + t`.
fn motion_vector(m: &Rigid, c: DVec3, radius: f64) -> [f64; 6] {
    let q = m.quat();
    let s = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
    let angle = 2.0 * s.atan2(q[3]);
    let w = if s > 0.0 { DVec3::new(q[0], q[1], q[2]) * (angle / s) } else { DVec3::ZERO };
    let t = m.apply(c) - c;
    [w[0] * radius, w[1] * radius, w[2] * radius, t[0], t[1], t[2]]
}

/// The inverse of [`motion_vector`].
fn motion_from_vector(v: [f64; 6], c: DVec3, radius: f64) -> Rigid {
    let rot = Rigid::from_rotation_vector(DVec3::new(v[0] / radius, v[1] / radius, v[2] / radius), [0.0; 3]);
    Rigid { r: rot.r, t: (c - rot.rotate(c) + DVec3::new(v[3], v[4], v[5])).to_array() }
}

/// The pairs as [`Kernel`] weighs them, with `c = reject` × the median
/// pair distance.
pub(crate) fn weighed(p: Vec<Pair>, reject: f64, kernel: Kernel) -> Vec<Pair> {
    match kernel {
        Kernel::Trim => trimmed(p, reject),
        Kernel::Tukey => {
            if !reject.is_finite() || p.is_empty() {
                return p;
            }
            let mut d: Vec<f64> = p.iter().map(|q| q.src.distance(q.dst)).collect();
            let c = reject * crate::range_image::median(&mut d);
            p.into_iter()
                .filter_map(|mut q| {
                    let u = q.src.distance(q.dst) / c;
                    if u >= 1.0 {
                        return None;
                    }
                    q.w *= (1.0 - u * u) * (1.0 - u * u);
                    Some(q)
                })
                .collect()
        }
    }
}

/// Drops pairs farther apart than `reject` × the median pair distance.
pub(crate) fn trimmed(mut p: Vec<Pair>, reject: f64) -> Vec<Pair> {
    if !reject.is_finite() || p.is_empty() {
        return p;
    }
    let mut d: Vec<f64> = p.iter().map(|q| q.src.distance(q.dst)).collect();
    let limit = reject * crate::range_image::median(&mut d);
    p.retain(|q| q.src.distance(q.dst) <= limit);
    p
}

/// The pairs of scan `i`'s level-`level` samples with the targets.
pub(crate) fn pairs(t: &Targets, i: usize, level: usize, targets_idx: &[usize], poses: &[Rigid], d: f64) -> Vec<Pair> {
    pairs_with(t, i, level, targets_idx, poses, d, t.symmetric)
}

/// Samples of a level (every `stride`-th) are paired in fixed chunks of
/// this many, each chunk in order, carrying the last triangle found per
/// target as the next search's hint; the answer does not depend on the
/// thread count.
const CHUNK: usize = 64;

/// [`pairs`], both ways or only forward.
pub(crate) fn pairs_with(t: &Targets, i: usize, level: usize, targets_idx: &[usize], poses: &[Rigid], d: f64, symmetric: bool) -> Vec<Pair> {
    let scan = &t.scans[i];
    let pose = poses[i];
    let tinfo: Vec<(usize, Rigid, [f64; 3], [f64; 3])> = targets_idx
        .iter()
        .map(|&j| {
            let (wlo, whi) = world_bounds(&t.bvhs[j], &poses[j]);
            (j, poses[j].inverse(), wlo, whi)
        })
        .collect();
    let lv = &scan.levels[level];
    let samples: Vec<u32> = lv.iter().copied().step_by(stride(lv.len(), t.max_samples)).collect();
    let forward: Vec<Pair> = in_chunks(&samples, tinfo.len(), |hints, v| {
            let v = v as usize;
            if scan.boundary[v] || scan.confidence[v] <= 0.0 {
                return None;
            }
            let w = pose.apply(scan.positions[v]);
            let mut best: Option<(f64, usize, [f64; 3], u32)> = None;
            for (k_t, &(j, inv, lo, hi)) in tinfo.iter().enumerate() {
                if (0..3).any(|k| w[k] < lo[k] - d || w[k] > hi[k] + d) {
                    continue;
                }
                let limit = best.map_or(d, |b| b.0);
                if let Some((dd, cp, f)) = t.bvhs[j].nearest_within_hinted(inv.apply(w), limit, &mut hints[k_t]) {
                    best = Some((dd, j, cp, f));
                }
            }
            let (_, j, cp, f) = best?;
            let ts = &t.scans[j];
            if ts.face_on_boundary[f as usize] {
                return None;
            }
            let wt = scan.confidence[v] * ts.face_confidence[f as usize];
            if wt <= 0.0 {
                return None;
            }
            Some(Pair { src: DVec3::from(w), dst: poses[j].apply(DVec3::from(cp)), normal: t.face_normals[j].get(f as usize).map_or(DVec3::ZERO, |&n| poses[j].rotate(n)), w: wt })
        });
    if !symmetric {
        return forward;
    }
    // The reverse pairs: the targets' samples against scan i's surface.
    // Scan vertices lie on the surface and scan triangles are chords of
    // it, so a vertex-to-surface distance is biased by the chord error
    // (outwards on convex parts); pairing both ways makes the two biases
    // pull in opposite directions and cancel.
    let inv_i = pose.inverse();
    let (lo_i, hi_i) = world_bounds(&t.bvhs[i], &pose);
    // Target samples over scan i's box, all targets together, thinned
    // to at most `max_samples`.
    let mut candidates: Vec<(u32, u32)> = Vec::new();
    for (slot, &j) in targets_idx.iter().enumerate() {
        let ts = &t.scans[j];
        let pj = poses[j];
        for &v in &ts.levels[level.min(ts.levels.len() - 1)] {
            let w = pj.apply(ts.positions[v as usize]);
            if (0..3).all(|k| w[k] >= lo_i[k] - d && w[k] <= hi_i[k] + d) {
                candidates.push((slot as u32, v));
            }
        }
    }
    let step = stride(candidates.len(), t.max_samples);
    let thinned: Vec<u32> = (0..candidates.len()).step_by(step).map(|k| k as u32).collect();
    let reverse = in_chunks(&thinned, targets_idx.len(), |hints, k| {
        let (slot, v) = candidates[k as usize];
        let j = targets_idx[slot as usize];
        let ts = &t.scans[j];
        let v = v as usize;
        if ts.boundary[v] || ts.confidence[v] <= 0.0 {
            return None;
        }
        let w = poses[j].apply(ts.positions[v]);
        let (_, cp, f) = t.bvhs[i].nearest_within_hinted(inv_i.apply(w), d, &mut hints[slot as usize])?;
        if scan.face_on_boundary[f as usize] {
            return None;
        }
        let wt = ts.confidence[v] * scan.face_confidence[f as usize];
        if wt <= 0.0 {
            return None;
        }
        Some(Pair { src: pose.apply(DVec3::from(cp)), dst: DVec3::from(w), normal: t.face_normals[i].get(f as usize).map_or(DVec3::ZERO, |&n| pose.rotate(n)), w: wt })
    });
    let mut all = forward;
    all.extend(reverse);
    all
}

/// The fraction of scan `i`'s usable samples at `level` (not on its
/// boundary, confidence > 0; thinned as for pairing) that pair, one way,
/// with a surface of `targets_idx` within `d`: how much of scan `i` the
/// targets cover.
pub(crate) fn coverage(t: &Targets, i: usize, level: usize, targets_idx: &[usize], poses: &[Rigid], d: f64) -> f64 {
    let scan = &t.scans[i];
    let lv = &scan.levels[level];
    let usable = lv.iter().step_by(stride(lv.len(), t.max_samples)).filter(|&&v| !scan.boundary[v as usize] && scan.confidence[v as usize] > 0.0).count();
    pairs_with(t, i, level, targets_idx, poses, d, false).len() as f64 / usable.max(1) as f64
}

/// `pair` over `samples` in parallel, in fixed chunks of [`CHUNK`], each
/// with its own `hint_slots` search hints; results in sample order.
fn in_chunks<F>(samples: &[u32], hint_slots: usize, pair: F) -> Vec<Pair>
where
    F: Fn(&mut [Option<u32>], u32) -> Option<Pair> + Sync,
{
    samples
        .par_chunks(CHUNK)
        .flat_map_iter(|c| {
            let mut hints = vec![None; hint_slots];
            c.iter().filter_map(|&v| pair(&mut hints, v)).collect::<Vec<_>>()
        })
        .collect()
}

/// The world box around a scan's BVH box moved by `pose`.
fn world_bounds(bvh: &TriangleBvh, pose: &Rigid) -> ([f64; 3], [f64; 3]) {
    let (lo, hi) = bvh.bounds();
    crate::scan_mesh::bbox((0..8).map(|k| pose.apply([if k & 1 == 0 { lo[0] } else { hi[0] }, if k & 2 == 0 { lo[1] } else { hi[1] }, if k & 4 == 0 { lo[2] } else { hi[2] }])))
}

/// Horn's weighted closed form: the motion taking `src` onto `dst`.
fn horn(p: &[Pair]) -> Option<Rigid> {
    let wsum: f64 = p.iter().map(|q| q.w).sum();
    if wsum <= 0.0 {
        return None;
    }
    let cs = p.iter().fold(DVec3::ZERO, |a, q| a + q.src * q.w) * (1.0 / wsum);
    let cd = p.iter().fold(DVec3::ZERO, |a, q| a + q.dst * q.w) * (1.0 / wsum);
    let mut s = [[0.0; 3]; 3];
    for q in p {
        let b = q.src - cs;
        let a = q.dst - cd;
        for r in 0..3 {
            for c in 0..3 {
                s[r][c] += q.w * b[r] * a[c];
            }
        }
    }
    let (sxx, sxy, sxz) = (s[0][0], s[0][1], s[0][2]);
    let (syx, syy, syz) = (s[1][0], s[1][1], s[1][2]);
    let (szx, szy, szz) = (s[2][0], s[2][1], s[2][2]);
    let n = nalgebra::Matrix4::new(
        sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,
        syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,
        szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,
        sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz,
    );
    let eig = nalgebra::SymmetricEigen::new(n);
    let (k, _) = eig.eigenvalues.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let v = eig.eigenvectors.column(k);
    // Horn's quaternion is (w, x, y, z).
    let rot = Rigid::from_quat([v[1], v[2], v[3], v[0]], [0.0; 3]);
    let t = cd - rot.rotate(cs);
    Some(Rigid { r: rot.r, t: t.to_array() })
}

/// Point-to-plane, linearized: solve for a small rotation vector ω and a
/// translation about the source centroid, then make the rotation exact.
fn point_to_plane(p: &[Pair]) -> Option<Rigid> {
    let wsum: f64 = p.iter().map(|q| q.w).sum();
    if wsum <= 0.0 {
        return None;
    }
    let c = p.iter().fold(DVec3::ZERO, |a, q| a + q.src * q.w) * (1.0 / wsum);
    let mut ata = nalgebra::Matrix6::<f64>::zeros();
    let mut atb = nalgebra::Vector6::<f64>::zeros();
    for q in p {
        let b = q.src - c;
        let n = q.normal;
        let j = b.cross(n);
        let row = nalgebra::Vector6::new(j.x, j.y, j.z, n.x, n.y, n.z);
        let r = (q.src - q.dst).dot(n);
        ata += q.w * row * row.transpose();
        atb -= q.w * r * row;
    }
    let x = ata.cholesky()?.solve(&atb);
    let rot = Rigid::from_rotation_vector(DVec3::new(x[0], x[1], x[2]), [0.0; 3]);
    // p ↦ R(p − c) + c + t
    let t = c - rot.rotate(c) + DVec3::new(x[3], x[4], x[5]);
    Some(Rigid { r: rot.r, t: t.to_array() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horn_recovers_a_known_motion_exactly() {
        let truth = Rigid::from_quat([0.1, -0.3, 0.2, 0.9], [0.5, -1.0, 2.0]);
        let pts: Vec<[f64; 3]> = (0..20).map(|i| [(i as f64 * 0.7).sin(), (i as f64 * 1.3).cos(), i as f64 * 0.1]).collect();
        let pairs: Vec<Pair> = pts.iter().enumerate().map(|(i, &p)| Pair { src: DVec3::from(p), dst: truth.apply(DVec3::from(p)), normal: DVec3::Z, w: 1.0 + i as f64 }).collect();
        let m = horn(&pairs).unwrap();
        let (deg, shift) = crate::geom::pose_error(&m, &truth, &pts);
        assert!(deg < 1e-9 && shift < 1e-12, "{deg} {shift}");
    }

    #[test]
    fn distance_levels_halve_down_to_the_final_distance() {
        assert_eq!(distance_levels(8.0, 1.0), vec![8.0, 4.0, 2.0, 1.0]);
        assert_eq!(distance_levels(5.0, 1.0), vec![5.0, 2.5, 1.25, 1.0]);
        assert_eq!(distance_levels(1.0, 1.0), vec![1.0]);
    }
}
