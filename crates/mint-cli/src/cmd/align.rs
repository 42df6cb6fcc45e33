//! `mint align`: registers range scans to each other by constrained ICP
//! (multiview by default) and writes the refined poses in the output set's
//! convention (Stanford .conf or MeshLab .aln, by extension; scan paths are
//! relative to the set file), then reports how well the registered scans
//! agree. `--evaluate` measures that agreement for a set's own poses and
//! writes nothing. Calls `mint_range::align::{align_file, evaluate_file}`.

use crate::jobs::{JsonArg};
use anyhow::Result;
use clap::{Args, ValueEnum};
use mint_range::agreement::Agreement;
use mint_range::align::{align_file, evaluate_file};
use mint_range::icp::{AlignOptions, Metric, Status, Strategy};
use mint_range::ScanSet;
use std::path::PathBuf;

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MetricArg {
    /// Point to plane on the coarse levels (fast into the basin), then
    /// point to point by Horn's method on the last level (unbiased by
    /// noisy normals).
    PlaneThenPoint,
    /// Point to point, Horn's closed-form quaternion (Turk and Levoy's
    /// choice) at every level. Crawls when scans must slide along each
    /// other: from a few degrees off it can stop short by tenths of a degree.
    Point,
    /// Point to plane (Chen and Medioni), linearized.
    Plane,
}

#[derive(Args, Debug)]
pub struct AlignArgs {
    /// Scan set with initial poses (.conf or .aln).
    pub set: PathBuf,
    /// Output scan set with the refined poses, in the convention its
    /// extension names: .aln is MeshLab's (it opens as a project), anything
    /// else a Stanford .conf. Scan files keep their names when it is in the
    /// input's directory, else are written as absolute paths. A scan that
    /// could not be registered is still written, at its initial pose, with
    /// a `# mint: failed: REASON` line before it; `mint zipper` and
    /// `mint merge` leave flagged scans out unless --include-failed.
    #[arg(required_unless_present = "evaluate")]
    pub out_set: Option<PathBuf>,
    /// Register nothing: measure how well the set's scans agree at its own
    /// poses (RMS point-to-plane distance of every overlapping pair, within
    /// the final pairing distance) and write nothing. Compares two pose
    /// sets of the same scans, e.g. a published .conf and mint's output.
    #[arg(long, conflicts_with = "out_set")]
    pub evaluate: bool,
    /// Final pairing distance d [default: 2 x the largest sampling distance].
    #[arg(long)]
    pub distance: Option<f64>,
    /// Pairing distance of the coarsest level, halved per level down to d
    /// [default: 8 d]. Raise it when the initial poses are far off.
    #[arg(long)]
    pub start_distance: Option<f64>,
    /// Error metric.
    #[arg(long, value_enum, default_value_t = MetricArg::PlaneThenPoint)]
    pub metric: MetricArg,
    /// Index (0-based, in set order) of the scan that stays fixed.
    #[arg(long, default_value_t = 0)]
    pub anchor: usize,
    /// With --global off: register every scan to the anchor alone instead
    /// of to the growing model of all registered scans.
    #[arg(long)]
    pub anchor_only: bool,
    /// Pair one way only (source samples to target surfaces), as Turk and
    /// Levoy did. By default pairs go both ways, which cancels the bias of
    /// vertex-to-chord distances on curved surfaces.
    #[arg(long)]
    pub one_way: bool,
    /// Convergence: a level ends when an iteration moves the scan's
    /// bounding-box corners by less than this fraction of its sampling
    /// distance.
    #[arg(long, default_value_t = AlignOptions::default().tolerance)]
    pub tolerance: f64,
    /// Samples paired per iteration at most, in each direction (a regular
    /// thinning of the scan's samples).
    #[arg(long, default_value_t = AlignOptions::default().max_samples)]
    pub max_samples: usize,
    /// With --global off: passes re-registering every scan against all
    /// others at the final distance, after the growing model is complete.
    #[arg(long, default_value_t = AlignOptions::default().refine_passes)]
    pub refine_passes: usize,
    /// Multiview registration: every pairwise alignment judged (converged,
    /// overlap, RMS against its peers'; failures retried, then reported),
    /// scans joined along the largest overlaps, then all overlapping pairs
    /// aligned and every pose solved at once, which closes rings of scans.
    /// `off`: the growing model in one pass plus --refine-passes (mint's
    /// registration before; --anchor-only applies only here).
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    pub global: OnOff,
    /// Multiview: two scans are partners when each has at least this
    /// fraction of its samples within the pairing distance of the other.
    #[arg(long, default_value_t = AlignOptions::default().min_overlap)]
    pub min_overlap: f64,
    /// Multiview: a pairwise alignment fails when its RMS (relative to the
    /// sampling distance) is more than this many times the median of its
    /// peers'.
    #[arg(long, default_value_t = AlignOptions::default().rms_factor)]
    pub rms_factor: f64,
    /// Multiview: rounds of (all pairwise alignments, global solve) at most;
    /// they stop earlier once the poses stop moving.
    #[arg(long, default_value_t = AlignOptions::default().global_rounds)]
    pub global_rounds: usize,
    #[command(flatten)]
    pub json: JsonArg,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnOff {
    On,
    Off,
}

pub fn cmd_align(a: AlignArgs) -> Result<()> {
    let opts = AlignOptions {
        distance: a.distance,
        start_distance: a.start_distance,
        metric: match a.metric {
            MetricArg::PlaneThenPoint => Metric::PlaneThenPoint,
            MetricArg::Point => Metric::PointToPoint,
            MetricArg::Plane => Metric::PointToPlane,
        },
        strategy: if a.anchor_only { Strategy::Anchor } else { Strategy::Growing },
        anchor: a.anchor,
        symmetric: !a.one_way,
        tolerance: a.tolerance,
        max_samples: a.max_samples,
        refine_passes: a.refine_passes,
        global: a.global == OnOff::On,
        min_overlap: a.min_overlap,
        rms_factor: a.rms_factor,
        global_rounds: a.global_rounds,
        ..Default::default()
    };
    let bars = crate::progress::Bars::new(a.json.json);
    let Some(out_set) = &a.out_set else {
        let e = evaluate_file(&a.set, &opts, &bars)?;
        if a.json.json {
            let v = serde_json::json!({ "set": a.set.display().to_string(), "scans": e.scans, "flagged_failed": e.flagged, "seconds": e.seconds, "agreement": e.agreement });
            crate::out::json(&v)?;
        } else {
            eprintln!("evaluated {} scans of {} in {:.2}s (poses as given)", e.scans, a.set.display(), e.seconds);
            if !e.flagged.is_empty() {
                eprintln!("  left out, flagged as failed in the set: {}", e.flagged.join(" "));
            }
            print_agreement(&e.agreement, true);
        }
        return Ok(());
    };
    let set = ScanSet::read(&a.set)?;
    let mut inputs: Vec<&std::path::Path> = vec![&a.set];
    inputs.extend(set.entries.iter().map(|e| e.path.as_path()));
    crate::paths::check_output(out_set, &inputs)?;
    let s = align_file(&a.set, out_set, &opts, &bars)?;
    let (r, secs, register_secs) = (&s.result, s.seconds, s.register_seconds);
    let failed: Vec<&str> = r.reports.iter().filter(|s| matches!(s.status, Status::Failed(_))).map(|s| s.name.as_str()).collect();
    if a.json.json {
        let v = serde_json::json!({ "set": a.set.display().to_string(), "out_set": out_set.display().to_string(), "global": opts.global, "distance": r.distance, "start_distance": r.start_distance, "seconds": secs, "register_seconds": register_secs, "peak_heap_bytes": crate::alloc::peak_heap(), "rounds": r.rounds, "scans": r.reports, "pairs": r.pairs, "failed": failed, "agreement": r.agreement });
        crate::out::json(&v)?;
    } else {
        let how = if opts.global { format!("multiview, {} rounds", r.rounds) } else { "growing model".to_string() };
        eprintln!("aligned {} scans of {} ({how}; d = {:.4e}, start {:.4e}) in {secs:.2}s -> {}", s.scans, a.set.display(), r.distance, r.start_distance, out_set.display());
        eprintln!("  {:<24} {:<10} {:>10} {:>6} {:>8} {:>6} {:>9}  partners", "scan", "status", "rms", "rms/s", "pairs", "iters", "moved deg");
        for s in &r.reports {
            match &s.status {
                Status::Failed(why) => eprintln!(
                    "  {:<24} FAILED{}, kept its initial pose and flagged in the output set: {why}",
                    s.name,
                    if s.retries > 0 { format!(" after {} retries", s.retries) } else { String::new() }
                ),
                st => eprintln!(
                    "  {:<24} {:<10} {:>10.4e} {:>6.3} {:>8} {:>6} {:>9.3}  {}{}{}",
                    s.name,
                    format!("{st:?}"),
                    s.rms,
                    s.rms_rel,
                    s.pairs,
                    s.iterations,
                    s.moved_deg,
                    s.partners.join(" "),
                    if s.converged { "" } else { " (hit the iteration cap)" },
                    match &s.retried_from {
                        Some(from) => format!(" (registered on retry {} of its start: {from})", s.retries),
                        None => String::new(),
                    }
                ),
            }
        }
        let rejected: Vec<String> = r
            .pairs
            .iter()
            .filter_map(|p| match &p.status {
                mint_range::multiview::PairStatus::Accepted => None,
                mint_range::multiview::PairStatus::Failed(why) => Some(format!("  pair {} / {}: failed: {why}", p.a, p.b)),
                mint_range::multiview::PairStatus::Inconsistent => Some(format!("  pair {} / {}: left out, inconsistent with the others (mates {:.3e} apart after the global solve)", p.a, p.b, p.residual)),
            })
            .collect();
        if !r.pairs.is_empty() {
            eprintln!("  {} pairwise alignments, {} accepted", r.pairs.len(), r.pairs.len() - rejected.len());
        }
        for l in rejected {
            eprintln!("{l}");
        }
        print_agreement(&r.agreement, false);
        if !failed.is_empty() {
            eprintln!("warning: {} of {} scans could not be registered ({}); they are flagged in {} and left out of zipper and merge unless --include-failed", failed.len(), r.reports.len(), failed.join(" "), out_set.display());
        }
    }
    Ok(())
}

/// The agreement lines of the text summary; `all_pairs` lists every pair.
fn print_agreement(g: &Agreement, all_pairs: bool) {
    if g.pairs.is_empty() {
        eprintln!("  agreement: no pair of scans overlaps by {:.0}% within d = {:.4e}", 100.0 * g.min_overlap, g.distance);
        return;
    }
    eprintln!("  agreement: rms {:.4e} over {} overlapping pairs (median pair rms {:.4e}; point to plane within d = {:.4e})", g.rms, g.pairs.len(), g.median_rms, g.distance);
    if all_pairs {
        for p in &g.pairs {
            eprintln!("    {:<24} {:<24} overlap {:>5.1}%  {:>8} pairs  rms {:.4e}", p.a, p.b, 100.0 * p.overlap, p.pairs, p.rms);
        }
    }
}
