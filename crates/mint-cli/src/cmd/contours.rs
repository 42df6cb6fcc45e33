//! `mint contours`: rebuilds a surface from a stack of planar contours, by
//! the angle criterion or by marching cubes; the stack is a profile (.pro)
//! or an ROI of a DICOM RT structure set (`--roi`, `--all-rois`,
//! `--list-rois`). Calls `mint_contour::run::reconstruct_file` (profiles)
//! or `mint_contour::run::reconstruct_sections` on the stacks of
//! `mint_contour::rtstruct` (DICOM).

use crate::jobs::{QuietArg, JsonArg};
use crate::alloc;
use crate::contour_report::{report, status, write_options, write_stats};
use crate::units::human_bytes;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use mint_contour::angle::AngleOptions;
use mint_contour::mc::McOptions;
use mint_contour::rtstruct;
use mint_contour::run::{self, Method, MethodStats, RunStats};
use std::path::{Path, PathBuf};

/// A reconstruction method.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// Cross-section triangulation with the angle criterion: triangles join
    /// the contour vertices of consecutive sections; few triangles, exact
    /// contours; branching by splitting contours.
    Angle,
    /// Marching cubes on a grid of --cubes across the stack: watertight with
    /// --caps, handles holes and any branching; more triangles.
    Mc,
}

/// Where the angle method's end caps sit.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum CapAt {
    /// In the end sections' planes (the 1998 method).
    Sections,
    /// Half a section spacing beyond the end sections, where marching
    /// cubes puts its caps: each section stands for a slab one spacing
    /// thick, as in the planimetric volume.
    HalfSpacing,
}

#[derive(Args, Debug)]
pub struct ContoursArgs {
    /// Input: a profile (.pro) of planar contour sections, or a DICOM RT
    /// structure set (recognised by content, or by a .dcm name), which
    /// needs --roi, --all-rois or --list-rois.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension (.ply, .obj, .stl,
    /// .off, .mesh, .raw, .wrl, .3ds). Not with --all-rois or --list-rois.
    #[arg(required_unless_present_any = ["all_rois", "list_rois"])]
    pub output: Option<PathBuf>,
    /// Reconstruction method.
    #[arg(long, value_enum, required_unless_present = "list_rois")]
    pub method: Option<MethodArg>,
    /// DICOM RT structure set: rebuild this ROI, by name (exact, else
    /// ignoring case with '_' for ' ') or by ROI number.
    #[arg(long, value_name = "NAME", conflicts_with_all = ["all_rois", "list_rois"])]
    pub roi: Option<String>,
    /// DICOM RT structure set: rebuild every ROI into OUTDIR/NAME.ply (the
    /// ROI name with characters other than letters, digits, '-', '_' and
    /// '.' replaced by '_'; '-NUMBER' added when two names clash). ROIs
    /// with no closed contours are skipped with a warning; an ROI that
    /// fails is reported and the others go on (exit status 1 at the end).
    #[arg(long, value_name = "OUTDIR", conflicts_with_all = ["output", "list_rois"])]
    pub all_rois: Option<PathBuf>,
    /// DICOM RT structure set: list its ROIs (number, name, contours,
    /// closed contours, slices, points) on stdout and exit.
    #[arg(long)]
    pub list_rois: bool,
    /// mc: cubes across the larger side of the stack's bounding box in the
    /// section planes; the spacing along the stack is that of the sections
    /// [default: 64].
    #[arg(long)]
    pub cubes: Option<u32>,
    /// angle: direction threshold t, a cosine in [-1, 1]; the next vertex
    /// follows the edge whose direction agrees (cos > t) with the other
    /// contour's [default: 0.5, i.e. 60 degrees].
    #[arg(long)]
    pub threshold: Option<f64>,
    /// angle: contours are open polylines, not closed polygons.
    #[arg(long)]
    pub open: bool,
    /// Close the surface: triangulate the first and last sections (and, for
    /// angle, every contour that starts or ends inside the stack; for mc,
    /// caps half a section spacing beyond the end sections).
    #[arg(long)]
    pub caps: bool,
    /// angle with --caps: where the end caps sit [default: half-spacing for
    /// RT structure sets, whose contours each stand for one slice
    /// thickness; sections for profiles].
    #[arg(long, value_enum)]
    pub cap_at: Option<CapAt>,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 instead of f32.
    #[arg(long)]
    pub double: bool,
    /// Also write OUT.png beside the output: a picture of the surface (see
    /// `mint render`); with --all-rois, OUTDIR/rois.png of all of them.
    #[arg(long)]
    pub preview: bool,
    /// The axis drawn upwards in the preview. Contour stacks are slices
    /// along z (DICOM's patient z is superior), so z by default.
    #[arg(long, value_enum, default_value_t = crate::preview::UpArg::Z)]
    pub up: crate::preview::UpArg,
    /// Write the status file (time, counts, parameters) as JSON here; with
    /// --all-rois, {"rois": [one status per ROI]}.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    pub quiet: QuietArg,
    #[command(flatten)]
    pub json: JsonArg,
}

/// Is `path` a DICOM file: by content, or by a `.dcm` name (so that a
/// non-DICOM file named so gets the DICOM reader's "not a DICOM file")?
fn is_dicom(path: &Path) -> Result<bool> {
    let by_name = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("dcm"));
    Ok(by_name || rtstruct::sniff(path)?.is_some())
}

/// The method from the arguments; `dicom` picks the default of --cap-at.
fn contour_method(a: &ContoursArgs, dicom: bool) -> Result<Method> {
    let Some(method) = a.method else { bail!("--method is required (angle or mc)") };
    Ok(match method {
        MethodArg::Mc => {
            if a.threshold.is_some() || a.open || a.cap_at.is_some() {
                bail!("--threshold, --open and --cap-at apply to --method angle only");
            }
            let cubes = a.cubes.unwrap_or(McOptions::default().cubes);
            if cubes == 0 {
                bail!("--cubes must be at least 1");
            }
            Method::Mc(McOptions { cubes, caps: a.caps, ..McOptions::default() })
        }
        MethodArg::Angle => {
            if a.cubes.is_some() {
                bail!("--cubes applies to --method mc only");
            }
            let threshold = a.threshold.unwrap_or(AngleOptions::default().threshold);
            if !(-1.0..=1.0).contains(&threshold) {
                bail!("--threshold {threshold} is not a cosine in [-1, 1]");
            }
            if a.open && a.caps {
                bail!("--caps needs closed contours; it cannot be used with --open");
            }
            if a.cap_at.is_some() && !a.caps {
                bail!("--cap-at places the caps: it needs --caps");
            }
            if a.open && dicom {
                bail!("--open does not apply to RT structure sets: their contours are closed");
            }
            let default = if dicom { CapAt::HalfSpacing } else { CapAt::Sections };
            let extend_ends = a.caps && a.cap_at.unwrap_or(default) == CapAt::HalfSpacing;
            Method::Angle(AngleOptions { threshold, open: a.open, caps: a.caps, extend_ends })
        }
    })
}

/// The summary line of one reconstruction.
fn contours_line(s: &RunStats, input: &str, output: &Path) -> String {
    let extra = match &s.details {
        MethodStats::Mc(d) => format!(
            "grid {}x{}x{} cells of {:.6}, {} non-canonical cells",
            d.grid_cells[0], d.grid_cells[1], d.grid_cells[2], d.cube_size, d.non_canonical_cells
        ),
        MethodStats::Angle(d) => {
            let f = &d.fallback_slabs;
            format!(
                "{} tubes ({} by the paper's march, {} from another start pair, {} by minimum area), {} splits, {} bridged groups, {} paired, {} capped apart, {} caps\n  section pairs using each fallback: restart {}, minimum area {}, split {}, bridge {}, pairs {}, apart {}",
                d.tubes, d.tiled.march, d.tiled.restart, d.tiled.min_area, d.splits, d.bridged, d.paired, d.apart, d.caps, f.restart, f.min_area, f.split, f.bridge, f.pairs, f.apart
            )
        }
        _ => String::new(),
    };
    let mut line = format!(
        "reconstructed {input} ({} sections, {} contour vertices) -> {}: {} vertices, {} faces; {extra}",
        s.input_faces_or_sections,
        s.input_vertices,
        output.display(),
        s.vertices,
        s.faces
    );
    if let Some(v) = &s.volume {
        let diff = v.relative_difference.map_or("n/a".to_string(), |d| format!("{:+.2}%", 100.0 * d));
        line += &format!("\n  volume: mesh {:.6e}, planimetric {:.6e} (contour areas x section spacing), difference {diff}", v.mesh, v.planimetric);
    }
    line
}

pub fn cmd_contours(a: ContoursArgs) -> Result<()> {
    let dicom = is_dicom(&a.input)?;
    let dicom_only = a.roi.is_some() || a.all_rois.is_some() || a.list_rois;
    if !dicom && dicom_only {
        bail!("{}: --roi, --all-rois and --list-rois apply to DICOM RT structure sets; this file is not DICOM", a.input.display());
    }
    if dicom {
        return cmd_contours_dicom(a);
    }
    let output = a.output.clone().expect("clap requires the output");
    crate::paths::check_output(&output, &[&a.input])?;
    if a.preview {
        crate::paths::check_output(&crate::preview::preview_path(&output), &[&a.input])?;
    }
    if let Some(st) = &a.stats {
        crate::paths::check_output(st, &[&a.input, &output])?;
    }
    let method = contour_method(&a, false)?;
    let s = run::reconstruct_file(&a.input, &output, method, write_options(a.ascii, a.double), &crate::progress::Bars::new(a.quiet.quiet || a.json.json))?;
    let line = contours_line(&s, &a.input.display().to_string(), &output);
    if a.preview {
        crate::preview::write_preview(&[vec![output.clone()]], &output, a.up, a.quiet.quiet || a.json.json, &crate::progress::Bars::new(a.quiet.quiet || a.json.json))?;
    }
    report(&s, &a.stats, a.quiet.quiet, a.json.json, line)
}

/// `mint contours` on a DICOM RT structure set: --list-rois, --roi or
/// --all-rois.
fn cmd_contours_dicom(a: ContoursArgs) -> Result<()> {
    let set = rtstruct::StructureSet::read(&a.input)?;
    let sopts = rtstruct::StackOptions::default();
    if a.list_rois {
        return list_rois(&set, sopts, a.json.json);
    }
    let method = contour_method(&a, true)?;
    let quiet = a.quiet.quiet || a.json.json;
    if let Some(name) = &a.roi {
        let output = a.output.clone().expect("clap requires the output");
        crate::paths::check_output(&output, &[&a.input])?;
        if a.preview {
            crate::paths::check_output(&crate::preview::preview_path(&output), &[&a.input])?;
        }
        if let Some(st) = &a.stats {
            crate::paths::check_output(st, &[&a.input, &output])?;
        }
        let roi = set.find(name)?;
        let s = rebuild_roi(&a, &set, roi, sopts, method, &output)?;
        let line = contours_line(&s, &format!("{} {}", a.input.display(), roi.label()), &output);
        if a.preview {
            crate::preview::write_preview(&[vec![output.clone()]], &output, a.up, quiet, &crate::progress::Bars::new(quiet))?;
        }
        return report(&s, &a.stats, a.quiet.quiet, a.json.json, line);
    }
    let Some(dir) = &a.all_rois else {
        bail!(
            "{}: a DICOM RT structure set: choose the ROI with --roi NAME, or rebuild them all with --all-rois OUTDIR (--list-rois lists them)",
            a.input.display()
        );
    };
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create the output directory", dir.display()))?;
    if let Some(st) = &a.stats {
        crate::paths::check_output(st, &[&a.input])?;
    }
    let names = roi_file_names(&set.rois);
    let (mut runs, mut written, mut failed) = (Vec::new(), Vec::new(), 0usize);
    for (roi, name) in set.rois.iter().zip(&names) {
        if !roi.has_closed_contours() {
            crate::out::warn(&format!("{}: {} has no closed contours ({} contours in all); skipped", a.input.display(), roi.label(), roi.contours.len()));
            continue;
        }
        let output = dir.join(format!("{name}.ply"));
        crate::paths::check_not_input(&output, &[&a.input])?;
        match rebuild_roi(&a, &set, roi, sopts, method, &output) {
            Ok(s) => {
                if !quiet {
                    eprintln!("{}", contours_line(&s, &roi.label(), &output));
                }
                runs.push(status(&s)?);
                written.push(output);
            }
            Err(e) => {
                if crate::progress::interrupted() {
                    return Err(e);
                }
                eprintln!("mint: error: {e}");
                failed += 1;
            }
        }
    }
    let v = serde_json::json!({ "input": a.input.display().to_string(), "rois": runs, "peak_heap_bytes": alloc::peak_heap() });
    if let Some(p) = &a.stats {
        write_stats(p, &v)?;
    }
    if a.json.json {
        crate::out::json(&v)?;
    }
    if a.preview && !written.is_empty() {
        let paths: Vec<Vec<std::path::PathBuf>> = written.iter().map(|p| vec![p.clone()]).collect();
        crate::preview::write_preview(&paths, &dir.join("rois.ply"), a.up, quiet, &crate::progress::Bars::new(quiet))?;
    }
    if !quiet {
        eprintln!("{} ROIs written to {}, peak heap {}", written.len(), dir.display(), human_bytes(alloc::peak_heap()));
    }
    if failed > 0 {
        bail!("{}: {failed} of {} ROIs with closed contours failed (see above)", a.input.display(), failed + written.len());
    }
    Ok(())
}

/// One ROI into `output`; the ROI goes into the run's parameters.
fn rebuild_roi(a: &ContoursArgs, set: &rtstruct::StructureSet, roi: &rtstruct::Roi, sopts: rtstruct::StackOptions, method: Method, output: &Path) -> Result<RunStats> {
    let (frame, sections) = roi.stack(&set.path, sopts)?;
    let bars = crate::progress::Bars::new(a.quiet.quiet || a.json.json);
    let mut s = run::reconstruct_sections(&a.input, frame, &sections, output, method, write_options(a.ascii, a.double), &bars)?;
    s.parameters.insert("roi".into(), run::Value::Text(roi.name.clone()));
    s.parameters.insert("roi_number".into(), run::Value::Int(roi.number.max(0) as u64));
    Ok(s)
}

/// `--list-rois`: a table on stdout (or JSON). A closed pipe (`| head`)
/// ends the listing quietly.
fn list_rois(set: &rtstruct::StructureSet, sopts: rtstruct::StackOptions, json: bool) -> Result<()> {
    use std::io::Write;
    let rows: Vec<rtstruct::RoiSummary> = set.rois.iter().map(|r| r.summary(sopts)).collect();
    let mut text = String::new();
    if json {
        let v = serde_json::json!({ "input": set.path.display().to_string(), "label": set.label, "rois": rows });
        text = serde_json::to_string_pretty(&v)? + "\n";
    } else {
        use std::fmt::Write as _;
        let label = set.label.as_ref().map_or(String::new(), |l| format!(" '{l}'"));
        let _ = writeln!(text, "{}: RT structure set{label}, {} ROIs", set.path.display(), rows.len());
        let w = rows.iter().map(|r| r.name.chars().count()).max().unwrap_or(4).max(4);
        let _ = writeln!(text, "{:>6}  {:<w$}  {:>8}  {:>6}  {:>6}  {:>8}", "number", "name", "contours", "closed", "slices", "points");
        for r in &rows {
            let _ = writeln!(text, "{:>6}  {:<w$}  {:>8}  {:>6}  {:>6}  {:>8}", r.number, r.name, r.contours, r.closed, r.slices, r.points);
        }
    }
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(anyhow::Error::new(e).context("writing the ROI list")),
        _ => Ok(()),
    }
}

/// File names for ROIs: letters, digits, '-', '_' and '.' kept, anything
/// else '_', no leading '.'; `roiN` if nothing is left; '-NUMBER' appended
/// to every name that clashes (ignoring case) with another.
fn roi_file_names(rois: &[rtstruct::Roi]) -> Vec<String> {
    let clean: Vec<String> = rois
        .iter()
        .map(|r| {
            let s: String = r.name.chars().map(|c| if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '_' }).collect();
            let s = s.trim_start_matches('.').to_string();
            if s.is_empty() {
                format!("roi{}", r.number)
            } else {
                s
            }
        })
        .collect();
    clean
        .iter()
        .zip(rois)
        .map(|(s, r)| {
            let clash = clean.iter().filter(|t| t.eq_ignore_ascii_case(s)).count() > 1;
            if clash {
                format!("{s}-{}", r.number)
            } else {
                s.clone()
            }
        })
        .collect()
}
