//! `mint align` as a library call: [`align_file`] reads a scan set, aligns
//! it and writes the refined set; [`align`] checks the options, builds
//! what pairing needs (a BVH and surface normals per scan, the pairing
//! distances), then registers the scans by multiview ([`crate::multiview`],
//! the default) or by the sequential strategies of [`crate::icp`]
//! (`global: false`), and reports how far each scan moved. Both build on
//! the pairwise ICP of [`crate::icp`]; this module sits above them.

use crate::agreement::{measure, Agreement};
use crate::error::RangeError;
use crate::geom::Rigid;
use crate::icp::{distance_levels, register_sequential, AlignOptions, ScanReport, Status, Targets};
use crate::multiview::{register, PairReport};
use crate::scan_mesh::{face_normal, load_set, MeshOptions, ScanMesh};
use crate::scanset::{ScanEntry, ScanSet, SetFormat};
use std::path::Path;
use mint_core::progress::{NoProgress, Progress};
use mint_mesh::TriangleBvh;
use glam::DVec3;

/// The result of [`align`]: a pose per scan (failed scans keep their
/// initial pose) and a report per scan.
#[derive(Debug, Clone)]
pub struct AlignResult {
    pub poses: Vec<Rigid>,
    pub reports: Vec<ScanReport>,
    /// The final and starting pairing distances used.
    pub distance: f64,
    pub start_distance: f64,
    /// Multiview only: every pairwise alignment tried in the last round,
    /// and the rounds run.
    pub pairs: Vec<PairReport>,
    pub rounds: usize,
    /// How well the registered scans agree under the final poses, within
    /// the final pairing distance ([`crate::agreement`]).
    pub agreement: Agreement,
}

/// Registers `scans` from the `initial` poses; see the module docs and
/// [`crate::icp`]. Errors: mismatched lengths, an anchor out of range, bad
/// distances.
pub fn align(scans: &[ScanMesh], initial: &[Rigid], opts: &AlignOptions) -> Result<AlignResult, RangeError> {
    align_with(scans, initial, opts, &NoProgress)
}

/// [`align`], reporting each registration of a scan (phase
/// [`crate::phases::REGISTER`]; the refine passes count too) and stopping with
/// [`RangeError::Cancelled`] between them when asked.
pub fn align_with(scans: &[ScanMesh], initial: &[Rigid], opts: &AlignOptions, progress: &dyn Progress) -> Result<AlignResult, RangeError> {
    if scans.len() != initial.len() {
        return Err(RangeError::option("initial", format!("{} poses for {} scans", initial.len(), scans.len())));
    }
    if opts.anchor >= scans.len() {
        return Err(RangeError::option("anchor", format!("scan {} does not exist ({} scans)", opts.anchor, scans.len())));
    }
    let d = final_distance(scans, opts);
    let d0 = opts.start_distance.unwrap_or(8.0 * d);
    if !(d.is_finite() && d > 0.0 && d0.is_finite() && d0 >= d) {
        return Err(RangeError::option("distance", format!("need 0 < distance ({d}) <= start distance ({d0})")));
    }
    let dists = distance_levels(d0, d);
    let (bvhs, face_normals) = surfaces(scans, opts.global)?;
    let targets = Targets::new(scans, opts.symmetric, opts.max_samples, &bvhs, &face_normals);
    if opts.global {
        let mut r = register(&targets, initial, &dists, opts, progress)?;
        moved(scans, initial, &r.poses, &mut r.reports);
        progress.start(crate::phases::AGREEMENT, 1);
        let agreement = measure(&targets, &r.poses, &registered(&r.reports), d, opts.min_overlap);
        progress.advance(1);
        progress.finish();
        return Ok(AlignResult { poses: r.poses, reports: r.reports, distance: d, start_distance: d0, pairs: r.pairs, rounds: r.rounds, agreement });
    }
    let (poses, mut reports) = register_sequential(&targets, initial, &dists, opts, progress)?;
    moved(scans, initial, &poses, &mut reports);
    let agreement = evaluate(scans, &poses, &registered(&reports), opts)?;
    Ok(AlignResult { poses, reports, distance: d, start_distance: d0, pairs: Vec::new(), rounds: 0, agreement })
}

/// A BVH and a unit normal per face of every scan. `smooth`: the normal
/// for point-to-plane steps and the agreement is the mean of the corners'
/// vertex normals. A face's own normal carries the depth noise of its three
/// corners; on the synthetic scene (noise 4% of the sample spacing) it
/// biased the point-to-plane minimum of a pair by 0.1–0.3°, and the
/// point-to-point finish, flat there, does not undo it.
fn surfaces(scans: &[ScanMesh], smooth: bool) -> Result<(Vec<TriangleBvh>, Vec<Vec<DVec3>>), RangeError> {
    let bvhs: Vec<TriangleBvh> = scans
        .iter()
        .map(|s| TriangleBvh::new(&s.positions, &s.faces).map_err(|e| RangeError::Mesh { what: s.name.clone(), source: e }))
        .collect::<Result<_, _>>()?;
    let face_normals: Vec<Vec<DVec3>> = scans
        .iter()
        .map(|s| {
            if smooth {
                s.faces.iter().map(|f| (s.normals[f[0] as usize] + s.normals[f[1] as usize] + s.normals[f[2] as usize]).normalize_or_zero()).collect()
            } else {
                s.faces.iter().map(|&f| face_normal(&s.positions, f).normalize_or_zero()).collect()
            }
        })
        .collect();
    Ok((bvhs, face_normals))
}

/// The pairing distance `opts` asks for, or its default: twice the largest
/// sampling distance of `scans`.
fn final_distance(scans: &[ScanMesh], opts: &AlignOptions) -> f64 {
    opts.distance.unwrap_or(2.0 * scans.iter().map(|s| s.sampling).fold(0.0, f64::max))
}

/// How well `scans` agree at `poses` ([`crate::agreement`]): within the
/// final pairing distance of `opts` (default: twice the largest sampling
/// distance), over pairs overlapping by at least `opts.min_overlap`, at
/// most `opts.max_samples` samples per scan and direction. Scans with
/// `include[i]` false are left out.
pub fn evaluate(scans: &[ScanMesh], poses: &[Rigid], include: &[bool], opts: &AlignOptions) -> Result<Agreement, RangeError> {
    if scans.len() != poses.len() || scans.len() != include.len() {
        return Err(RangeError::option("poses", format!("{} poses for {} scans", poses.len(), scans.len())));
    }
    let d = final_distance(scans, opts);
    if !(d.is_finite() && d > 0.0) {
        return Err(RangeError::option("distance", format!("need 0 < distance ({d})")));
    }
    let (bvhs, face_normals) = surfaces(scans, true)?;
    let t = Targets::new(scans, true, opts.max_samples, &bvhs, &face_normals);
    Ok(measure(&t, poses, include, d, opts.min_overlap))
}

/// The scans that did not fail.
fn registered(reports: &[ScanReport]) -> Vec<bool> {
    reports.iter().map(|r| !matches!(r.status, Status::Failed(_))).collect()
}

/// Fills in how far each scan moved from its initial pose.
fn moved(scans: &[ScanMesh], initial: &[Rigid], poses: &[Rigid], reports: &mut [ScanReport]) {
    for (i, r) in reports.iter_mut().enumerate() {
        let (deg, shift) = crate::geom::pose_error(&initial[i], &poses[i], &scans[i].bbox_corners());
        r.moved_deg = deg;
        r.moved = shift;
    }
}

/// What [`evaluate_file`] measured.
#[derive(Debug, Clone)]
pub struct EvaluateFileSummary {
    pub agreement: Agreement,
    pub scans: usize,
    /// Scans flagged as failed in the set, left out of the measure.
    pub flagged: Vec<String>,
    pub seconds: f64,
}

/// Reads the scan set `set_path` and measures how well its scans agree at
/// the set's own poses ([`evaluate`]), leaving out scans the set flags as
/// failed. Writes nothing.
pub fn evaluate_file(set_path: &Path, opts: &AlignOptions, progress: &dyn Progress) -> Result<EvaluateFileSummary, RangeError> {
    let t = std::time::Instant::now();
    let set = ScanSet::read(set_path)?;
    let scans = load_set(&set, set_path, &MeshOptions::default())?;
    let poses: Vec<Rigid> = set.entries.iter().map(|e| e.pose).collect();
    let include: Vec<bool> = set.entries.iter().map(|e| e.failed.is_none()).collect();
    let flagged = set.entries.iter().zip(&scans).filter(|(e, _)| e.failed.is_some()).map(|(_, s)| s.name.clone()).collect();
    progress.start(crate::phases::AGREEMENT, 1);
    let agreement = evaluate(&scans, &poses, &include, opts)?;
    progress.advance(1);
    progress.finish();
    Ok(EvaluateFileSummary { agreement, scans: scans.len(), flagged, seconds: t.elapsed().as_secs_f64() })
}

/// What [`align_file`] did.
#[derive(Debug, Clone)]
pub struct AlignFileSummary {
    pub result: AlignResult,
    pub scans: usize,
    /// Seconds in all, and in registration alone.
    pub seconds: f64,
    pub register_seconds: f64,
}

/// Reads the scan set `set_path` (`.conf` or `.aln`), registers its scans
/// from their poses ([`align_with`]) and writes the registered ones, with
/// their refined poses, to `out_set` in the convention its extension names
/// (`.aln`: MeshLab's; anything else: Stanford's `.conf`). Every scan is
/// written: one that failed keeps its initial pose and is flagged with the
/// reason ([`ScanEntry::failed`]), so that no scan is lost. Scan files are named as in the input when
/// `out_set` is in the same directory, else by their absolute paths, so
/// the written set always finds them. Fails (and writes nothing) when no
/// scan could be registered to the anchor.
pub fn align_file(set_path: &Path, out_set: &Path, opts: &AlignOptions, progress: &dyn Progress) -> Result<AlignFileSummary, RangeError> {
    let t = std::time::Instant::now();
    let set = ScanSet::read(set_path)?;
    let scans = load_set(&set, set_path, &MeshOptions::default())?;
    let initial: Vec<Rigid> = set.entries.iter().map(|e| e.pose).collect();
    let t_register = std::time::Instant::now();
    let result = align_with(&scans, &initial, opts, progress)?;
    let register_seconds = t_register.elapsed().as_secs_f64();
    let mut out = set.clone();
    out.entries.clear();
    let dir_of = |p: &Path| p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new(".")).canonicalize().ok();
    let same_dir = dir_of(set_path).is_some() && dir_of(set_path) == dir_of(out_set);
    for (i, e) in set.entries.iter().enumerate() {
        let file = if same_dir { e.file.clone() } else { e.path.canonicalize().unwrap_or_else(|_| e.path.clone()).display().to_string() };
        let failed = match &result.reports[i].status {
            Status::Failed(why) => Some(why.clone()),
            _ => None,
        };
        out.entries.push(ScanEntry { pose: result.poses[i], file, failed, ..e.clone() });
    }
    if scans.len() > 1 && out.entries.iter().filter(|e| e.failed.is_none()).count() < 2 {
        return Err(RangeError::Output { path: set_path.to_path_buf(), message: "no scan could be registered to the anchor".into() });
    }
    out.write(out_set, SetFormat::from_path(out_set))?;
    Ok(AlignFileSummary { result, scans: scans.len(), seconds: t.elapsed().as_secs_f64(), register_seconds })
}
