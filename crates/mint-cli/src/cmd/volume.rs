//! `mint volume`: a voxel volume (CT, MRI, micro-CT: NRRD, MetaImage,
//! NIfTI, DICOM series, TIFF stacks, raw) to a closed, oriented 2-manifold
//! surface by Marching Intersections, out of core: the slices stream
//! through the staged engine (`mint_pipeline::run` of a
//! `Job::Volume`). With `--labels`, one run per label value.

use crate::jobs::VolumeArgs;
use crate::progress::Bars;
use crate::summary::{print_removed, summary_warnings};
use crate::units::human_bytes;
use anyhow::{bail, Result};
use mint_pipeline::{ResampleSummary, VolumeSurface};
use std::path::{Path, PathBuf};

/// The most distinct values `--labels all` accepts (more: not a label map).
const MAX_LABELS: usize = 4096;

pub(crate) fn cmd_volume(a: VolumeArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[a.input.as_path()])?;
    let bars = Bars::new(a.report.silent());
    let tuning = a.tuning();
    if let Some(iso) = a.iso {
        let s = mint_pipeline::run(&a.spec(VolumeSurface::Iso(iso), &a.output)?, &tuning, &bars)?;
        return print(&a, &[s]);
    }
    let labels = labels(&a)?;
    if labels.is_empty() {
        bail!("{}: no label value other than 0 in the volume", a.input.display());
    }
    let mut summaries = Vec::new();
    let mut files: Vec<PathBuf> = Vec::new();
    // One file per label, or per-label files beside OUT joined at the end.
    let tmp = if a.one_file {
        let dir = a.output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        Some(tempfile::Builder::new().prefix(".mint-labels-").tempdir_in(dir)?)
    } else {
        None
    };
    for &v in &labels {
        let out = match &tmp {
            Some(d) => d.path().join(format!("label-{v}.ply")),
            None => label_path(&a.output, v),
        };
        crate::paths::check_output(&out, &[a.input.as_path()])?;
        let mut t = tuning.clone();
        if let Some(w) = &t.work_dir {
            t.work_dir = Some(w.join(format!("label-{v}")));
        }
        let mut s = mint_pipeline::run(&a.spec(VolumeSurface::Label(v), &out)?, &t, &bars)?;
        if a.one_file {
            s.output = a.output.display().to_string();
        }
        files.push(out);
        summaries.push(s);
    }
    if a.one_file {
        let format = mint_io::Format::from_path(&a.output)?;
        let write = mint_io::WriteOptions { ascii: a.ascii, double: a.double, spill_dir: None, colours: false };
        mint_io::concatenate(&files, &a.output, format, write, &crate::progress::interrupted)?;
    }
    print(&a, &summaries)
}

/// `OUT` with `.label-V` before its extension.
fn label_path(out: &Path, v: f32) -> PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let name = match out.extension() {
        Some(e) => format!("{stem}.label-{v}.{}", e.to_string_lossy()),
        None => format!("{stem}.label-{v}"),
    };
    out.with_file_name(name)
}

/// The label values: the list given, or every distinct value but 0 (one
/// pass over the slices).
fn labels(a: &VolumeArgs) -> Result<Vec<f32>> {
    let list = a.labels.as_deref().unwrap_or("all");
    if list != "all" {
        let mut v = Vec::new();
        for t in list.split(',') {
            match t.trim().parse::<f32>() {
                Ok(x) if x.is_finite() => v.push(x),
                _ => bail!("--labels {list}: `{t}` is not a number (give `all` or a list such as 1,2,5)"),
            }
        }
        v.sort_by(f32::total_cmp);
        v.dedup();
        return Ok(v);
    }
    let mut vol = a.job(VolumeSurface::Iso(0.0)).open()?;
    let info = vol.info().clone();
    let mut seen = std::collections::BTreeSet::new();
    let mut slice = vec![0f32; info.slice_len()];
    for k in 0..info.dims[2] {
        vol.read_slices(k, 1, &mut slice)?;
        for &x in &slice {
            if x != 0.0 && x.is_finite() {
                seen.insert(x.to_bits());
            }
        }
        if seen.len() > MAX_LABELS {
            bail!("{}: more than {MAX_LABELS} distinct values: not a label map (use --iso V, or --labels LIST)", a.input.display());
        }
        if crate::progress::interrupted() {
            bail!("interrupted; no output written");
        }
    }
    let mut v: Vec<f32> = seen.into_iter().map(f32::from_bits).collect();
    v.sort_by(f32::total_cmp);
    Ok(v)
}

fn print(a: &VolumeArgs, summaries: &[ResampleSummary]) -> Result<()> {
    let mut all_warnings = Vec::new();
    for s in summaries {
        print_removed(&s.removed_dead);
        let w = summary_warnings(s);
        for line in &w {
            crate::out::warn(line);
        }
        all_warnings.push(w);
    }
    if a.report.json() {
        let mut out = Vec::new();
        for (s, w) in summaries.iter().zip(all_warnings) {
            let mut v = serde_json::to_value(s)?;
            v["warnings"] = w.into();
            out.push(v);
        }
        let mut v = if out.len() == 1 && a.iso.is_some() { out.pop().unwrap() } else { serde_json::json!({ "labels": out }) };
        v["peak_heap_bytes"] = crate::alloc::peak_heap().into();
        v["peak_rss_bytes"] = crate::alloc::peak_rss().into();
        crate::out::json(&v)?;
    } else if !a.report.quiet() {
        for s in summaries {
            let Some(v) = &s.volume else { continue };
            eprintln!("meshed {} ({}) -> {}", s.input, v.surface, s.output);
            let range = v.value_range.map_or("none finite".to_string(), |[lo, hi]| format!("{lo} .. {hi}"));
            eprintln!(
                "  volume       {} {}x{}x{} {} (values {range}{}), voxels {:.4} x {:.4} x {:.4}",
                v.format, v.dims[0], v.dims[1], v.dims[2], v.sample,
                if v.slope != 1.0 || v.intercept != 0.0 { format!(", rescaled x{} {:+}", v.slope, v.intercept) } else { String::new() },
                v.spacing[0], v.spacing[1], v.spacing[2]
            );
            eprintln!("  frame        {} (the output's coordinates)", v.frame);
            let grid = if v.own_grid { "the volume's own: one node per voxel centre".to_string() } else { format!("cubic cells of {:.6}, sampled trilinearly", s.cell_size) };
            let border = if v.open_border {
                format!(
                    "left open on the volume's border ({} faces of the cap there left out, {} vertices split where it touched the rest at a point; {} boundary edges in {} loops)",
                    v.border_faces_removed, v.border_vertices_split, s.output_boundary_edges, s.output_boundary_loops
                )
            } else {
                "the border counts as outside (closed on it)".to_string()
            };
            eprintln!("  grid         {}x{}x{} cells, {grid}; {border}", s.grid_cells[0], s.grid_cells[1], s.grid_cells[2]);
            eprintln!("  intercepts   {} found ({} of shards), {} slices read", s.intercepts_found, human_bytes(s.shard_bytes), v.slices_read);
            eprintln!("  output       {} vertices, {} faces, coordinates {}", s.output_vertices, s.output_faces, s.output_precision);
            eprintln!("  time         {:.2}s; peak heap {}", s.seconds_total, human_bytes(crate::alloc::peak_heap()));
        }
    }
    Ok(())
}
