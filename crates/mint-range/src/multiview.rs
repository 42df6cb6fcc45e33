//! Multiview registration (`mint align`, the default): every pairwise
//! alignment is judged, scans join along the overlaps they share most, and
//! all poses are solved at once so that a ring of scans closes.
//!
//! Sources: K. Pulli, "Multiview Registration for Large Data Sets", 3DIM
//! 1999 (pairwise alignments between all overlapping scans, each kept as
//! "virtual mates" — points of the overlap expressed in both scans' frames
//! at the pairwise optimum — then all poses moved at once to bring the
//! mates together; scanalyze and MeshLab's global alignment work this
//! way); R. Prim, "Shortest connection networks", 1957 (the spanning tree,
//! here by largest overlap).
//!
//! The stages, on the [`Targets`] of [`crate::icp`]:
//! 1. **Overlap graph.** For every two scans at their initial poses, the
//!    fraction of each one's coarsest samples within the start distance of
//!    the other's surface ([`crate::icp::coverage`]); the smaller of the two
//!    is the pair's overlap. Pairs under [`AlignOptions::min_overlap`] are
//!    not partners.
//! 2. **Tree.** From the anchor, Prim's order on the overlap: the pending
//!    scan with the largest overlap with a placed scan registers against
//!    that scan alone (pairwise ICP through the whole hierarchy, from its
//!    initial pose). The registration is **judged** ([`judge`]): it must
//!    converge on every level, cover at least `min_overlap` of the scan at
//!    the final distance, and have an RMS (relative to the sampling
//!    distance) at most [`AlignOptions::rms_factor`] times the median of
//!    the registrations accepted so far (once there are three). A failure
//!    is retried with a coarser start, four times the samples and Tukey's
//!    kernel; then against every placed partner. A scan that still fails
//!    keeps its initial pose, is reported, and no other scan joins through
//!    it.
//! 3. **Rounds** of, at most [`AlignOptions::global_rounds`]:
//!    - pairwise ICP between **all** partners (overlap recomputed at the
//!      current poses), in parallel, each judged as above against the
//!      median of the round (failures retried once with the robust
//!      settings); a scan left with no accepted pair fails;
//!    - the **global solve**: all poses but the anchor's, by Gauss–Newton
//!      on Σ w·|P_a·y − P_b·x|² over every accepted pair's mates (x in
//!      scan b's frame, y in scan a's); then the pair whose mates stay
//!      farthest apart is dropped as inconsistent if its RMS exceeds
//!      three times the median and the pair is not the last link of a
//!      scan to the anchor, and the solve repeats;
//!    - the rounds stop when no scan moves by more than a quarter of its
//!      sampling distance ([`STILL`]).
//! 4. **Retries.** Every scan still failed is registered again against the
//!    placed scans at their refined poses ([`retry`]): from the pose its
//!    best-covered registered neighbours predict (their correction applied
//!    to it, right when scans started off by about the same motion), then
//!    from its own initial pose; each with the defaults, the robust
//!    settings and a coarser search; at most 12 tries. A retry is judged
//!    like any registration; one that passes joins the last round's
//!    solution and the rounds of stage 3 run again from there. A scan no
//!    retry brings back keeps its initial pose and is reported (with its
//!    tries); `mint align` writes it flagged, so no scan is lost.
//!
//! The result does not depend on the thread count: pairs are aligned in
//! parallel but each alignment is deterministic, and everything is
//! gathered in a fixed order.

use crate::error::RangeError;
use crate::geom::Rigid;
use glam::DVec3;
use crate::icp::{coverage, distance_levels, pairs, register_one, weighed, AlignOptions, Kernel, ScanReport, Status, Targets};
use mint_core::progress::Progress;
use rayon::prelude::*;
use serde::Serialize;

/// Mates kept per pairwise alignment at most (a regular thinning; the
/// weights of the kept ones are scaled up to stand for the rest).
const MATES: usize = 1000;

/// The rounds stop when no scan moved by more than this many of its
/// sampling distances in the last one (on the dragon stand the second
/// round moves scans by about 0.12 s and the third by 0.01–0.04 s, which
/// changes no pose by more than 0.01°).
const STILL: f64 = 0.25;

/// The judge's verdict on one pairwise alignment.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum PairStatus {
    /// Used by the global solve.
    Accepted,
    /// Failed the judge (the reason).
    Failed(String),
    /// Passed the judge, but the global solve could not agree with it (its
    /// mates stayed far apart); left out.
    Inconsistent,
}

/// One pairwise alignment of the last round: scan `b` registered against
/// scan `a`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairReport {
    pub a: String,
    pub b: String,
    /// Overlap (the smaller coverage of the two) before and after.
    pub overlap_before: f64,
    pub overlap: f64,
    /// Pairs at the final distance after the alignment, their RMS (model
    /// units) and the RMS over the moving scan's sampling distance.
    pub pairs: usize,
    pub rms: f64,
    pub rms_rel: f64,
    pub iterations: usize,
    pub converged: bool,
    /// Settings tried (1: the defaults; 2: also the robust retry).
    pub attempts: usize,
    /// After the global solve: RMS distance of the pair's mates, model
    /// units (how far the global poses are from this pair's own optimum).
    pub residual: f64,
    pub status: PairStatus,
}

/// What one pairwise registration gave.
#[derive(Debug, Clone)]
struct Fit {
    pose: Rigid,
    report: ScanReport,
    ok: bool,
    overlap: f64,
    attempts: usize,
}

/// One accepted pair's virtual mates: `x` in scan `b`'s frame and `y` in
/// scan `a`'s, the same world point at the pair's optimum, and `n` the
/// surface normal there in scan `a`'s frame.
#[derive(Debug, Clone)]
struct Mates {
    a: usize,
    b: usize,
    x: Vec<DVec3>,
    y: Vec<DVec3>,
    n: Vec<DVec3>,
    w: Vec<f64>,
}

/// Weight of the mates' distance along the surface against their distance
/// across it in the global solve (see [`solve`]).
const TANGENTIAL: f64 = 0.1;

/// What [`register`] gives: the poses (failed scans keep their initial
/// pose), a report per scan, the last round's pair reports and the number
/// of rounds.
pub(crate) struct Registration {
    pub(crate) poses: Vec<Rigid>,
    pub(crate) reports: Vec<ScanReport>,
    pub(crate) pairs: Vec<PairReport>,
    pub(crate) rounds: usize,
}

/// Multiview registration; see the module docs.
pub(crate) fn register(t: &Targets, initial: &[Rigid], dists: &[f64], opts: &AlignOptions, progress: &dyn Progress) -> Result<Registration, RangeError> {
    let scans = t.scans;
    let n = scans.len();
    let anchor = opts.anchor;
    let d0 = dists[0];
    let d = *dists.last().expect("at least one distance");
    let mut reports: Vec<ScanReport> = scans.iter().map(|s| ScanReport::new(&s.name)).collect();
    reports[anchor].status = Status::Anchor;
    let mut poses = initial.to_vec();

    // 1. Overlap graph at the initial poses.
    let overlap0 = overlaps(t, initial, 0, d0, &(0..n).collect::<Vec<_>>());

    // 2. The tree, in Prim's order by overlap.
    progress.start(crate::phases::REGISTER, (n - 1) as u64);
    let mut placed = vec![false; n];
    placed[anchor] = true;
    let mut done = vec![false; n];
    done[anchor] = true;
    let mut accepted_rms: Vec<f64> = Vec::new();
    loop {
        let mut best: Option<(f64, usize, usize)> = None;
        for k in (0..n).filter(|&k| !done[k]) {
            for p in (0..n).filter(|&p| placed[p]) {
                let o = overlap0[k][p];
                if o >= opts.min_overlap && best.is_none_or(|b| o > b.0) {
                    best = Some((o, k, p));
                }
            }
        }
        let Some((_, k, parent)) = best else { break };
        done[k] = true;
        let reference = median(&accepted_rms);
        let partners: Vec<usize> = (0..n).filter(|&p| placed[p] && overlap0[k][p] >= opts.min_overlap).collect();
        let tries: [(&[usize], bool); 3] = [(&[parent], false), (&[parent], true), (&partners, true)];
        let mut last_reason = String::new();
        let mut fitted = None;
        for (attempt, &(against, robust)) in tries.iter().enumerate() {
            if attempt == 2 && partners.len() < 2 {
                break;
            }
            let f = fit(t, k, against, &poses, initial[k], dists, opts, robust, attempt + 1);
            match judge(&f, opts, reference, d) {
                Ok(()) => {
                    fitted = Some(f);
                    break;
                }
                Err(why) => last_reason = why,
            }
        }
        match fitted {
            Some(f) => {
                poses[k] = f.pose;
                placed[k] = true;
                accepted_rms.push(f.report.rms_rel);
                reports[k].iterations += f.report.iterations;
                reports[k].converged &= f.report.converged;
                reports[k].status = Status::Registered;
            }
            None => {
                reports[k].status = Status::Failed(format!("registration against {} failed: {last_reason}", scans[parent].name));
            }
        }
        crate::error::advance(progress)?;
    }
    progress.finish();
    for k in (0..n).filter(|&k| !done[k]) {
        let (o, p) = (0..n).filter(|&p| placed[p]).map(|p| (overlap0[k][p], p)).fold((0.0, k), |a, b| if b.0 > a.0 { b } else { a });
        let through: Vec<String> = (0..n).filter(|&q| q != k && !placed[q] && overlap0[k][q] >= opts.min_overlap).map(|q| format!("{} ({:.0}%)", scans[q].name, 100.0 * overlap0[k][q])).collect();
        reports[k].status = Status::Failed(format!(
            "no overlap: at most {:.1}% of it within {d0:.4e} of a registered scan{} at the initial poses (need {:.1}%){}",
            100.0 * o,
            if p != k { format!(" ({})", scans[p].name) } else { String::new() },
            100.0 * opts.min_overlap,
            if through.is_empty() { String::new() } else { format!("; it overlaps only scans not registered: {}", through.join(", ")) }
        ));
    }

    // 3. Rounds of pairwise alignments between all partners and the
    //    global solve.
    let mut state = State { poses, placed, reports };
    let (mut pair_reports, mut rounds) = run_rounds(t, initial, &mut state, d0, d, opts, progress)?;

    // 4. Retries of the scans that failed, from where their registered
    //    neighbours say they are; then the rounds again with the ones that
    //    came back.
    let failed: Vec<usize> = (0..n).filter(|&k| !state.placed[k]).collect();
    if !failed.is_empty() {
        let reference = median(&pair_reports.iter().filter(|p| p.status == PairStatus::Accepted).map(|p| p.rms_rel).collect::<Vec<_>>());
        progress.start(crate::phases::RETRY, failed.len() as u64);
        let mut back = Vec::new();
        for &k in &failed {
            let (outcome, tries) = retry(t, k, initial, &state, dists, opts, reference);
            state.reports[k].retries = tries;
            match outcome {
                Ok((f, from)) => back.push((k, f, from)),
                Err(why) => {
                    if let Status::Failed(first) = &mut state.reports[k].status {
                        first.push_str(&format!("; retried from {tries} starts, none accepted ({why})"));
                    }
                }
            }
            crate::error::advance(progress)?;
        }
        progress.finish();
        if !back.is_empty() {
            for (k, f, from) in back {
                state.poses[k] = f.pose;
                state.placed[k] = true;
                let r = &mut state.reports[k];
                r.iterations += f.report.iterations;
                r.status = Status::Registered;
                r.retried_from = Some(from);
            }
            let (p, more) = run_rounds(t, initial, &mut state, d0, d, opts, progress)?;
            pair_reports = p;
            rounds += more;
            for r in state.reports.iter_mut().filter(|r| matches!(r.status, Status::Failed(_))) {
                r.retried_from = None;
            }
        }
    }
    let State { mut poses, placed, mut reports } = state;

    // Final statistics of each registered scan against its partners.
    let names: Vec<&str> = scans.iter().map(|s| s.name.as_str()).collect();
    let finals: Vec<Option<(usize, f64)>> = (0..n)
        .into_par_iter()
        .map(|k| {
            if !placed[k] {
                return None;
            }
            let partners: Vec<usize> = reports[k].partners.iter().filter_map(|p| names.iter().position(|q| q == p)).collect();
            let p = weighed(pairs(t, k, scans[k].levels.len() - 1, &partners, &poses, d), opts.reject, opts.kernel);
            let rms = (p.iter().map(|q| q.src.distance_squared(q.dst)).sum::<f64>() / p.len().max(1) as f64).sqrt();
            Some((p.len(), rms))
        })
        .collect();
    for (k, f) in finals.into_iter().enumerate() {
        if let Some((np, rms)) = f {
            reports[k].pairs = np;
            reports[k].rms = rms;
            reports[k].rms_rel = rms / scans[k].sampling;
        } else {
            poses[k] = initial[k];
        }
    }
    Ok(Registration { poses, reports, pairs: pair_reports, rounds })
}

/// What the rounds change: the poses, which scans are placed (registered),
/// and the scans' reports.
struct State {
    poses: Vec<Rigid>,
    placed: Vec<bool>,
    reports: Vec<ScanReport>,
}

/// Stage 3 of the module docs on the placed scans of `state`: rounds of
/// pairwise alignments between all partners and the global solve, until
/// the poses stop moving. A scan left with no accepted pair goes back to
/// its `initial` pose and fails. Returns the last round's pair reports and
/// the rounds run.
#[allow(clippy::too_many_arguments)]
fn run_rounds(t: &Targets, initial: &[Rigid], state: &mut State, d0: f64, d: f64, opts: &AlignOptions, progress: &dyn Progress) -> Result<(Vec<PairReport>, usize), RangeError> {
    let scans = t.scans;
    let n = scans.len();
    let anchor = opts.anchor;
    let State { poses, placed, reports } = state;
    let center = model_center(scans, poses, placed);
    // Pairing distances of the rounds: from the tree's poses the pairs are
    // within a few sampling distances of their optimum; from a solved pose
    // within one.
    let first = distance_levels(d0.min(4.0 * d), d);
    let later = distance_levels(d0.min(2.0 * d), d);
    let mut pair_reports = Vec::new();
    let mut rounds = 0;
    for round in 0..opts.global_rounds {
        rounds = round + 1;
        let active: Vec<usize> = (0..n).filter(|&k| placed[k]).collect();
        let ov = overlaps(t, &poses, scans[0].levels.len().saturating_sub(2), 2.0 * d, &active);
        let edges: Vec<(usize, usize)> = active.iter().flat_map(|&a| active.iter().filter(move |&&b| b > a).map(move |&b| (a, b))).filter(|&(a, b)| ov[a][b] >= opts.min_overlap).collect();
        let levels = if round == 0 { &first[..] } else { &later[..] };
        progress.start(crate::phases::REFINE, edges.len() as u64);
        let fits: Vec<Fit> = edges
            .par_iter()
            .map(|&(a, b)| {
                let f = fit(t, b, &[a], &poses, poses[b], levels, opts, false, 1);
                progress.advance(1);
                f
            })
            .collect();
        progress.finish();
        if progress.cancelled() {
            return Err(RangeError::Cancelled);
        }
        // Judge against the round's median; retry the failures robustly.
        let reference = median(&fits.iter().filter(|f| f.ok && f.report.converged).map(|f| f.report.rms_rel).collect::<Vec<_>>());
        let fits: Vec<Fit> = fits
            .into_par_iter()
            .zip(edges.par_iter())
            .map(|(f, &(a, b))| if judge(&f, opts, reference, d).is_ok() { f } else { fit(t, b, &[a], &poses, poses[b], levels, opts, true, 2) })
            .collect();
        let mut reps: Vec<PairReport> = Vec::with_capacity(edges.len());
        let mut mates: Vec<Mates> = Vec::new();
        // The pair (index into `edges` and `reps`) of each `mates`.
        let mut of_edge: Vec<usize> = Vec::new();
        for (e, (f, &(a, b))) in fits.iter().zip(&edges).enumerate() {
            let verdict = judge(f, opts, reference, d);
            reps.push(PairReport {
                a: scans[a].name.clone(),
                b: scans[b].name.clone(),
                overlap_before: ov[a][b],
                overlap: f.overlap,
                pairs: f.report.pairs,
                rms: f.report.rms,
                rms_rel: f.report.rms_rel,
                iterations: f.report.iterations,
                converged: f.report.converged,
                attempts: f.attempts,
                residual: 0.0,
                status: match &verdict {
                    Ok(()) => PairStatus::Accepted,
                    Err(why) => PairStatus::Failed(why.clone()),
                },
            });
            if verdict.is_ok() {
                let mut p = poses.clone();
                p[b] = f.pose;
                mates.push(virtual_mates(t, a, b, &p, d, opts));
                of_edge.push(e);
            }
        }
        // A scan with no accepted pair, or cut off from the anchor, fails.
        let mut index: Vec<usize> = (0..mates.len()).collect();
        let reached = reachable(n, anchor, &mates, &index);
        for &k in &active {
            if k != anchor && !reached[k] {
                let why: Vec<String> = edges
                    .iter()
                    .zip(&reps)
                    .filter(|(&(a, b), _)| a == k || b == k)
                    .filter_map(|(&(a, b), r)| match &r.status {
                        PairStatus::Failed(w) => Some(format!("with {}: {w}", scans[if a == k { b } else { a }].name)),
                        _ => None,
                    })
                    .collect();
                reports[k].status = Status::Failed(if why.is_empty() { "no partner overlaps it after registration".to_string() } else { format!("no pairwise alignment accepted ({})", why.join("; ")) });
                placed[k] = false;
                poses[k] = initial[k];
            }
        }
        index.retain(|&e| placed[mates[e].a] && placed[mates[e].b]);
        // The global solve, dropping inconsistent pairs one at a time.
        let mut solved;
        loop {
            solved = poses.clone();
            solve(&mut solved, &mates, &index, anchor, &placed, center, 1e-4 * d, TANGENTIAL);
            let res: Vec<f64> = index.iter().map(|&e| residual(&solved, &mates[e], TANGENTIAL)).collect();
            let m = median(&res).unwrap_or(0.0);
            let worst = index
                .iter()
                .zip(&res)
                .filter(|&(_, &r)| r > 3.0 * m && r > 0.25 * d)
                .filter(|&(&e, _)| {
                    let rest: Vec<usize> = index.iter().copied().filter(|&f| f != e).collect();
                    let r = reachable(n, anchor, &mates, &rest);
                    r[mates[e].a] && r[mates[e].b]
                })
                .max_by(|a, b| a.1.total_cmp(b.1));
            match worst {
                Some((&e, _)) => index.retain(|&f| f != e),
                None => break,
            }
        }
        for (e, m) in mates.iter().enumerate() {
            let r = &mut reps[of_edge[e]];
            r.residual = residual(&solved, m, TANGENTIAL);
            if !index.contains(&e) && placed[m.a] && placed[m.b] {
                r.status = PairStatus::Inconsistent;
            }
        }
        let moved = (0..n).filter(|&k| placed[k]).map(|k| crate::geom::pose_error(&poses[k], &solved[k], &scans[k].bbox_corners()).1 / scans[k].sampling).fold(0.0, f64::max);
        *poses = solved;
        for r in reports.iter_mut() {
            r.partners.clear();
        }
        for &e in &index {
            let (a, b) = (mates[e].a, mates[e].b);
            reports[a].partners.push(scans[b].name.clone());
            reports[b].partners.push(scans[a].name.clone());
        }
        for (f, &(_, b)) in fits.iter().zip(&edges) {
            reports[b].iterations += f.report.iterations;
        }
        pair_reports = reps;
        if moved < STILL {
            break;
        }
    }

    Ok((pair_reports, rounds))
}

/// Neighbours whose prediction a retry starts from, at most.
const RETRY_NEIGHBOURS: usize = 3;

/// Stage 4: failed scan `k` registered again against the placed scans of
/// `state`, from each start in turn until one passes the judge (against
/// `reference`, the median RMS of the last round's accepted pairs):
/// - the poses its registered neighbours predict: neighbour `p`'s
///   correction applied to `k`, `poses[p] · initial[p]⁻¹ · initial[k]`
///   (right when the two started off by about the same motion, as scans
///   of one turntable sweep or one tracker do), best covered first, at
///   most [`RETRY_NEIGHBOURS`] distinct ones;
/// - its initial pose, now against every placed partner at its refined
///   pose;
///
/// each with the defaults, then the robust settings, then a coarser
/// search (the robust settings from four times the start distance). The
/// partners of a start are the placed scans that cover at least
/// `min_overlap` of it at the start distance (else the best one).
/// Returns the accepted fit and a description of its start, or why the
/// last try failed; and the number of registrations tried.
fn retry(t: &Targets, k: usize, initial: &[Rigid], state: &State, dists: &[f64], opts: &AlignOptions, reference: Option<f64>) -> (Result<(Fit, String), String>, usize) {
    let scans = t.scans;
    let n = scans.len();
    let d0 = dists[0];
    let d = *dists.last().expect("at least one distance");
    let placed: Vec<usize> = (0..n).filter(|&p| p != k && state.placed[p]).collect();
    let corners = scans[k].bbox_corners();
    let same = |a: &Rigid, b: &Rigid| {
        let (deg, shift) = crate::geom::pose_error(a, b, &corners);
        deg < 0.1 && shift < 0.25 * d
    };
    // The starts, with how well the placed scans cover each.
    let at = |start: Rigid| {
        let mut p = state.poses.clone();
        p[k] = start;
        p
    };
    let cover = |start: Rigid| coverage(t, k, 0, &placed, &at(start), d0);
    let mut predicted: Vec<(f64, Rigid, String)> = placed
        .iter()
        .map(|&p| {
            let s = state.poses[p].after(&initial[p].inverse()).after(&initial[k]).orthonormalized();
            (cover(s), s, format!("the pose {} predicts", scans[p].name))
        })
        .collect();
    predicted.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut starts: Vec<(Rigid, String)> = Vec::new();
    for (_, s, why) in predicted {
        if starts.len() < RETRY_NEIGHBOURS && !starts.iter().any(|(q, _)| same(q, &s)) {
            starts.push((s, why));
        }
    }
    if !starts.iter().any(|(q, _)| same(q, &initial[k])) {
        starts.push((initial[k], "its initial pose".to_string()));
    }
    let coarse = distance_levels(2.0 * d0, d);
    let mut tries = 0;
    let mut last = "no start overlaps a registered scan".to_string();
    for (start, from) in starts {
        let poses = at(start);
        let cov: Vec<(f64, usize)> = placed.iter().map(|&p| (coverage(t, k, 0, &[p], &poses, d0), p)).collect();
        let mut against: Vec<usize> = cov.iter().filter(|c| c.0 >= opts.min_overlap).map(|c| c.1).collect();
        if against.is_empty() {
            match cov.iter().filter(|c| c.0 > 0.0).max_by(|a, b| a.0.total_cmp(&b.0)) {
                Some(&(_, p)) => against.push(p),
                None => continue,
            }
        }
        for (how, levels, robust) in [("", dists, false), (", robust", dists, true), (", coarse search", &coarse[..], true)] {
            tries += 1;
            let f = fit(t, k, &against, &poses, start, levels, opts, robust, tries);
            match judge(&f, opts, reference, d) {
                Ok(()) => return (Ok((f, format!("{from}{how}"))), tries),
                Err(why) => last = format!("from {from}{how}: {why}"),
            }
        }
    }
    (Err(last), tries)
}

/// Registers scan `k` against `against` from `start` (the others at
/// `poses`); `robust`: the retry's settings (start distance doubled, four
/// times the samples, Tukey's kernel).
#[allow(clippy::too_many_arguments)]
fn fit(t: &Targets, k: usize, against: &[usize], poses: &[Rigid], start: Rigid, dists: &[f64], opts: &AlignOptions, robust: bool, attempts: usize) -> Fit {
    let mut p = poses.to_vec();
    p[k] = start;
    let mut report = ScanReport::new(&t.scans[k].name);
    let ok = if robust {
        let o = AlignOptions { kernel: Kernel::Tukey, max_samples: opts.max_samples.saturating_mul(4), ..opts.clone() };
        let wide = distance_levels(2.0 * dists[0], *dists.last().unwrap());
        let tw = t.with_max_samples(o.max_samples);
        register_one(&tw, k, against, &mut p, &wide, &o, &mut report)
    } else {
        register_one(t, k, against, &mut p, dists, opts, &mut report)
    };
    let d = *dists.last().unwrap();
    let nl = t.scans[k].levels.len();
    let overlap = if ok {
        let forward = coverage(t, k, nl - 1, against, &p, d);
        let back = against.iter().map(|&a| coverage(t, a, t.scans[a].levels.len() - 1, &[k], &p, d)).fold(0.0, f64::max);
        forward.min(back)
    } else {
        0.0
    };
    Fit { pose: p[k], report, ok, overlap, attempts }
}

/// The judge: `Err(why)` when the registration hit the iteration cap, left
/// too little overlap, or has an RMS above `rms_factor` × `reference`
/// (the median RMS of its peers, relative to the sampling distance).
fn judge(f: &Fit, opts: &AlignOptions, reference: Option<f64>, d: f64) -> Result<(), String> {
    if !f.ok {
        return Err(match &f.report.status {
            Status::Failed(why) => why.clone(),
            _ => "failed".into(),
        });
    }
    let mut why = Vec::new();
    if !f.report.converged {
        why.push(format!("hit the iteration cap ({} iterations)", f.report.iterations));
    }
    if f.overlap < opts.min_overlap {
        why.push(format!("overlap {:.1}% within {d:.3e} (need {:.1}%)", 100.0 * f.overlap, 100.0 * opts.min_overlap));
    }
    if let Some(r) = reference {
        if f.report.rms_rel > opts.rms_factor * r {
            why.push(format!("RMS {:.3} sampling distances, over {} x the median {r:.3}", f.report.rms_rel, opts.rms_factor));
        }
    }
    if why.is_empty() {
        Ok(())
    } else {
        Err(why.join(", "))
    }
}

/// The median, or `None` for fewer than three values (too few to judge by).
fn median(v: &[f64]) -> Option<f64> {
    if v.len() < 3 {
        return None;
    }
    let mut v = v.to_vec();
    Some(crate::range_image::median(&mut v))
}

/// The overlap of every two scans of `among` at `poses` (the smaller of the
/// two coverages at `level` within `r`); 0 elsewhere.
fn overlaps(t: &Targets, poses: &[Rigid], level: usize, r: f64, among: &[usize]) -> Vec<Vec<f64>> {
    let n = t.scans.len();
    let pairs: Vec<(usize, usize)> = among.iter().flat_map(|&a| among.iter().filter(move |&&b| b != a).map(move |&b| (a, b))).collect();
    let cov: Vec<f64> = pairs.par_iter().map(|&(a, b)| coverage(t, a, level.min(t.scans[a].levels.len() - 1), &[b], poses, r)).collect();
    let mut one_way = vec![vec![0.0; n]; n];
    for (&(a, b), &c) in pairs.iter().zip(&cov) {
        one_way[a][b] = c;
    }
    (0..n).map(|a| (0..n).map(|b| one_way[a][b].min(one_way[b][a])).collect()).collect()
}

/// Scan `b`'s pairs with scan `a` at `poses` (the pair's optimum) as
/// mates in both frames, thinned to [`MATES`].
fn virtual_mates(t: &Targets, a: usize, b: usize, poses: &[Rigid], d: f64, opts: &AlignOptions) -> Mates {
    let p = weighed(pairs(t, b, t.scans[b].levels.len() - 1, &[a], poses, d), opts.reject, opts.kernel);
    let step = p.len().div_ceil(MATES).max(1);
    let (ia, ib) = (poses[a].inverse(), poses[b].inverse());
    let mut m = Mates { a, b, x: Vec::new(), y: Vec::new(), n: Vec::new(), w: Vec::new() };
    for q in p.iter().step_by(step) {
        // The midpoint of the pair: the same world point in both frames.
        let w = (q.src + q.dst) * 0.5;
        m.x.push(ib.apply(w));
        m.y.push(ia.apply(w));
        m.n.push(ia.rotate(q.normal));
        m.w.push(q.w * step as f64);
    }
    m
}

/// RMS of a pair's mates at `poses` in [`solve`]'s metric (mostly the
/// distance across the surface, and `tangential` of the distance along it).
fn residual(poses: &[Rigid], m: &Mates, tangential: f64) -> f64 {
    let (mut s, mut w) = (0.0, 0.0);
    for k in 0..m.x.len() {
        let r = poses[m.a].apply(m.y[k]) - poses[m.b].apply(m.x[k]);
        let across = r.dot(poses[m.a].rotate(m.n[k]));
        s += m.w[k] * ((1.0 - tangential) * across * across + tangential * r.dot(r));
        w += m.w[k];
    }
    (s / w.max(f64::MIN_POSITIVE)).sqrt()
}

/// Which scans the pairs `index` of `mates` connect to `anchor`.
fn reachable(n: usize, anchor: usize, mates: &[Mates], index: &[usize]) -> Vec<bool> {
    let mut seen = vec![false; n];
    seen[anchor] = true;
    let mut stack = vec![anchor];
    while let Some(k) = stack.pop() {
        for &e in index {
            let (a, b) = (mates[e].a, mates[e].b);
            let other = if a == k { b } else if b == k { a } else { continue };
            if !seen[other] {
                seen[other] = true;
                stack.push(other);
            }
        }
    }
    seen
}

/// The centre of the placed scans' world boxes (the global solve rotates
/// about it, which keeps its normal equations well scaled).
fn model_center(scans: &[crate::ScanMesh], poses: &[Rigid], placed: &[bool]) -> DVec3 {
    let (lo, hi) = crate::scan_mesh::bbox(scans.iter().zip(poses).zip(placed).filter(|(_, &p)| p).flat_map(|((s, p), _)| s.bbox_corners().into_iter().map(move |c| p.apply(c))));
    (DVec3::from(lo) + DVec3::from(hi)) * 0.5
}

/// The global solve: Gauss–Newton on
/// Σ w·((1 − τ)·(n·(P_a·y − P_b·x))² + τ·|P_a·y − P_b·x|²) over the mates
/// of the pairs `index` (τ = [`TANGENTIAL`]), every placed scan but
/// `anchor` free. Mostly the distance across the surface, as in
/// point-to-plane ICP: a pair of scans that could slide along each other
/// (a narrow overlap, a smooth patch) holds the solve little in that
/// direction, and the other pairs decide it; with point-to-point mates a
/// pair pins its own optimum in every direction, however poorly its
/// overlap determines it. Each pose is updated as
/// `p ↦ R(ω)(p − c) + c + t` on the left.
/// Stops when no mate moves by more than `tol` in an iteration.
#[allow(clippy::too_many_arguments)]
fn solve(poses: &mut [Rigid], mates: &[Mates], index: &[usize], anchor: usize, placed: &[bool], c: DVec3, tol: f64, tangential: f64) {
    let n = poses.len();
    let mut var = vec![usize::MAX; n];
    let mut nv = 0;
    for k in 0..n {
        if placed[k] && k != anchor {
            var[k] = nv;
            nv += 1;
        }
    }
    if nv == 0 {
        return;
    }
    let m = 6 * nv;
    // The farthest mate from the centre: a rotation ω moves it by |ω|·radius.
    let mut radius: f64 = 0.0;
    for &e in index {
        let pa = poses[mates[e].a];
        radius = mates[e].y.iter().fold(radius, |r, &y| r.max(pa.apply(y).distance(c)));
    }
    for _ in 0..20 {
        let mut h = nalgebra::DMatrix::<f64>::zeros(m, m);
        let mut g = nalgebra::DVector::<f64>::zeros(m);
        for &e in index {
            let mt = &mates[e];
            let (va, vb) = (var[mt.a], var[mt.b]);
            let mut hb = nalgebra::SMatrix::<f64, 12, 12>::zeros();
            let mut gb = nalgebra::SVector::<f64, 12>::zeros();
            for k in 0..mt.x.len() {
                let pa = poses[mt.a].apply(mt.y[k]) - c;
                let pb = poses[mt.b].apply(mt.x[k]) - c;
                let r = pa - pb;
                let n = poses[mt.a].rotate(mt.n[k]);
                // d r / d(ω_a, t_a, ω_b, t_b), one row per coordinate, and
                // the row of the distance across the surface, n · r (n
                // held fixed within the iteration).
                let mut jn = nalgebra::SVector::<f64, 12>::zeros();
                for (row, e_axis) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
                    // ∂(ω × p)_row / ∂ω = p × e_row.
                    let ja = pa.cross(e_axis);
                    let jb = pb.cross(e_axis);
                    let mut j = nalgebra::SVector::<f64, 12>::zeros();
                    for q in 0..3 {
                        j[q] = ja[q];
                        j[6 + q] = -jb[q];
                    }
                    j[3 + row] = 1.0;
                    j[9 + row] = -1.0;
                    hb += (tangential * mt.w[k]) * j * j.transpose();
                    gb += (tangential * mt.w[k] * r[row]) * j;
                    jn += n[row] * j;
                }
                let w = (1.0 - tangential) * mt.w[k];
                hb += w * jn * jn.transpose();
                gb += (w * n.dot(r)) * jn;
            }
            for (bi, vi) in [(0, va), (6, vb)] {
                if vi == usize::MAX {
                    continue;
                }
                for r in 0..6 {
                    g[6 * vi + r] += gb[bi + r];
                    for (bj, vj) in [(0, va), (6, vb)] {
                        if vj == usize::MAX {
                            continue;
                        }
                        for s in 0..6 {
                            h[(6 * vi + r, 6 * vj + s)] += hb[(bi + r, bj + s)];
                        }
                    }
                }
            }
        }
        // A scan held by no pair (cannot happen once unreachable scans are
        // dropped) keeps its pose: a unit diagonal makes the system regular.
        for k in 0..m {
            if h[(k, k)] == 0.0 {
                h[(k, k)] = 1.0;
            }
        }
        let Some(ch) = h.cholesky() else { return };
        let x = ch.solve(&(-g));
        let mut step: f64 = 0.0;
        for k in 0..n {
            let v = var[k];
            if v == usize::MAX {
                continue;
            }
            let w = DVec3::new(x[6 * v], x[6 * v + 1], x[6 * v + 2]);
            let tr = DVec3::new(x[6 * v + 3], x[6 * v + 4], x[6 * v + 5]);
            let rot = Rigid::from_rotation_vector(w, [0.0; 3]);
            let delta = Rigid { r: rot.r, t: (c - rot.rotate(c) + tr).to_array() };
            poses[k] = delta.after(&poses[k]).orthonormalized();
            step = step.max(tr.length() + w.length() * radius);
        }
        if step < tol {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mates of a pair whose scans sit at `pa` and `pb`: points on a
    /// curved patch (so that no direction slides), with normals.
    fn mates(a: usize, b: usize, pa: &Rigid, pb: &Rigid, seed: f64) -> Mates {
        let mut m = Mates { a, b, x: Vec::new(), y: Vec::new(), n: Vec::new(), w: Vec::new() };
        for i in 0..200 {
            let u = (i as f64 * 0.37 + seed).sin();
            let v = (i as f64 * 0.73 + seed).cos();
            let w = DVec3::new(u, v, 0.3 * (u * u - v * v) + 0.5 * u * v);
            let normal = DVec3::new(-0.6 * u - 0.5 * v, 0.6 * v - 0.5 * u, 1.0).normalize_or_zero();
            m.x.push(pb.inverse().apply(w));
            m.y.push(pa.inverse().apply(w));
            m.n.push(pa.inverse().rotate(normal));
            m.w.push(1.0);
        }
        m
    }

    /// Three scans in a loop with exact mates: from poses a few degrees
    /// off, the solve returns every pose exactly, with the anchor fixed.
    #[test]
    fn the_global_solve_closes_a_loop_of_exact_mates() {
        let truth = [Rigid::IDENTITY, Rigid::from_quat([0.1, 0.2, -0.1, 0.97], [0.3, -0.2, 0.1]), Rigid::from_quat([-0.2, 0.05, 0.1, 0.97], [-0.1, 0.4, 0.2])];
        let all = vec![mates(0, 1, &truth[0], &truth[1], 0.0), mates(1, 2, &truth[1], &truth[2], 1.0), mates(0, 2, &truth[0], &truth[2], 2.0)];
        let mut poses = truth;
        poses[1] = Rigid::from_axis_angle(DVec3::new(1.0, 1.0, 0.0), 0.05).after(&poses[1]);
        poses[2] = Rigid { t: (DVec3::from(poses[2].t) + DVec3::new(0.02, -0.01, 0.03)).to_array(), ..Rigid::from_axis_angle(DVec3::new(0.0, 1.0, 1.0), -0.04).after(&poses[2]) };
        solve(&mut poses, &all, &[0, 1, 2], 0, &[true; 3], DVec3::ZERO, 1e-12, TANGENTIAL);
        assert_eq!(poses[0], Rigid::IDENTITY);
        for k in 1..3 {
            let (deg, shift) = crate::geom::pose_error(&truth[k], &poses[k], &[[1.0, 1.0, 1.0], [-1.0, 0.0, 0.5]]);
            assert!(deg < 1e-9 && shift < 1e-9, "scan {k}: {deg}° {shift}");
        }
        assert!(all.iter().all(|m| residual(&poses, m, TANGENTIAL) < 1e-9));
    }

    #[test]
    fn reachable_follows_only_the_pairs_given() {
        let id = Rigid::IDENTITY;
        let m = vec![mates(0, 1, &id, &id, 0.0), mates(1, 2, &id, &id, 0.0), mates(3, 4, &id, &id, 0.0)];
        assert_eq!(reachable(5, 0, &m, &[0, 1, 2]), vec![true, true, true, false, false]);
        assert_eq!(reachable(5, 0, &m, &[1, 2]), vec![true, false, false, false, false]);
        assert_eq!(reachable(5, 4, &m, &[2]), vec![false, false, false, true, true]);
    }

    #[test]
    fn the_median_needs_three_peers() {
        assert_eq!(median(&[1.0, 2.0]), None);
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
    }
}
