//! `mint resample`, `bool`, `csg` and `decimate`: the jobs of the staged engine run in one process.

use crate::alloc;
use crate::jobs::*;
use crate::progress::Bars;
use crate::units::{human_bytes, parse_bytes};
use anyhow::{Context, Result};
use clap::Args;
use mint_pipeline::{resample, ResampleOptions};
use std::path::PathBuf;
use crate::cmd::render::write_preview;

#[derive(Args, Debug)]
pub struct DecimateArgs {
    /// Input mesh (any format mint reads, any size).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Faces of the output.
    #[arg(long)]
    pub faces: u64,
    /// Faces of the intermediate resampling [default: 8 × --faces, at least 200,000 and at most the input's; more costs time, rarely error].
    #[arg(long, value_name = "M")]
    pub intermediate: Option<u64>,
    /// Largest simplification error, as a fraction of the mesh's extent
    /// [default: 1, i.e. the face target decides].
    #[arg(long, value_name = "E", default_value_t = 1.0)]
    pub error: f32,
    /// Heap budget of the out-of-core stage, e.g. 2G [default: a quarter of RAM].
    #[arg(long, value_parser = parse_bytes)]
    pub mem: Option<u64>,
    /// Worker threads [default: all cores].
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Keep the resampling's stages here, to resume after a crash [default: temporary].
    #[arg(long, value_name = "DIR")]
    pub work: Option<PathBuf>,
    /// Directory for temporary files [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Also write OUT.png beside the output: input and output side by side.
    #[arg(long)]
    pub preview: bool,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

pub(crate) fn cmd_resample(a: ResampleArgs) -> Result<()> {
    resample_and_report(a).map(|_| ())
}

pub(crate) fn resample_and_report(a: ResampleArgs) -> Result<mint_pipeline::ResampleSummary> {
    let opts = resample_options(&a)?;
    crate::paths::check_output(&a.output, &[&a.input])?;
    let mem = opts.mem_bytes;
    let tmp_root = a.tmp.clone().unwrap_or_else(|| a.output.parent().filter(|p| !p.as_os_str().is_empty()).map(PathBuf::from).unwrap_or_else(|| PathBuf::from(".")));
    let (input, _range_mesh) = resample_input(&a.input, a.staged.work.as_deref(), &tmp_root)?;
    let bars = Bars::new(a.quiet || a.json);
    let mut summary = resample(&input, &a.output, &opts, &bars)?;
    summary.input = a.input.display().to_string();
    if a.preview {
        let png = preview_path(&a.output);
        let o = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
        mint_render::render_files(&[input.as_path(), a.output.as_path()], &png, &o, &bars)?;
        if !a.quiet && !a.json {
            eprintln!("preview: {} (input left, output right)", png.display());
        }
    }
    print_resample_summary(&summary, a.json, a.quiet, mem)?;
    Ok(summary)
}

pub(crate) fn cmd_decimate(a: DecimateArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    if a.preview {
        crate::paths::check_output(&preview_path(&a.output), &[&a.input])?;
    }
    let mem = a.mem.unwrap_or_else(default_mem);
    let o = mint_pipeline::DecimateOptions {
        target_faces: a.faces,
        intermediate_faces: a.intermediate,
        max_error: a.error,
        resample: ResampleOptions { mem_bytes: mem, threads: a.threads, tmp_dir: a.tmp.clone(), work_dir: a.work.clone(), ..Default::default() },
    };
    let bars = Bars::new(a.quiet || a.json);
    let s = mint_pipeline::decimate(&a.input, &a.output, &o, &bars)?;
    if a.preview {
        let png = preview_path(&a.output);
        let ro = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
        mint_render::render_files(&[a.input.as_path(), a.output.as_path()], &png, &ro, &bars)?;
        if !a.quiet && !a.json {
            eprintln!("preview: {} (input left, output right)", png.display());
        }
    }
    if a.json {
        let mut v = serde_json::to_value(&s)?;
        v["mem_budget_bytes"] = mem.into();
        v["peak_heap_bytes"] = alloc::peak_heap().into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else if !a.quiet {
        eprintln!("decimated {} -> {}", s.input, s.output);
        eprintln!("  input        {} faces, area {:.6}", s.input_faces, s.input_area);
        eprintln!("  resampled    {} faces (asked {}), cells of {:.6}, {}", s.intermediate_faces, s.intermediate_faces_asked, s.cell_size, if s.intermediate_watertight { "watertight" } else { "NOT watertight" });
        eprintln!("  simplified   {} faces (target {}), {} vertices, error {:.2e} of the extent", s.output_faces, s.target_faces, s.output_vertices, s.simplify_error);
        eprintln!(
            "  output       {}{}",
            if s.output_watertight { "watertight (closed, 2-manifold, consistently oriented)" } else { "NOT watertight" },
            if s.relaxed > 0 { format!("; target relaxed {} times to keep it so", s.relaxed) } else { String::new() }
        );
        eprintln!(
            "  time         {:.2}s (area {:.2}s, resample {:.2}s, simplify {:.2}s, write {:.2}s), peak heap {}",
            s.seconds_total, s.seconds_area, s.seconds_resample, s.seconds_simplify, s.seconds_write, human_bytes(alloc::peak_heap())
        );
    }
    if s.intermediate_watertight && !s.output_watertight {
        eprintln!("mint: warning: the output is less clean than the resampling (see the summary)");
    }
    Ok(())
}

pub(crate) fn cmd_bool(a: BoolArgs) -> Result<()> {
    let opts = grid_options(&a.grid)?;
    crate::paths::check_output(&a.output, &[&a.a, &a.b])?;
    let op = match a.op {
        BoolOpArg::Union => mint_core::expr::BoolOp::Union,
        BoolOpArg::Intersection => mint_core::expr::BoolOp::Intersection,
        BoolOpArg::Difference => mint_core::expr::BoolOp::Difference,
    };
    let bars = Bars::new(a.grid.quiet || a.grid.json);
    let s = mint_pipeline::boolean(op, &a.a, &a.b, &a.output, &opts, &bars)?;
    if a.grid.preview {
        write_preview(&[a.a.as_path(), a.b.as_path(), a.output.as_path()], &a.output, a.grid.quiet || a.grid.json, &bars)?;
    }
    report(&a.grid, &s)
}

pub(crate) fn cmd_csg(a: CsgArgs) -> Result<()> {
    let opts = grid_options(&a.grid)?;
    crate::paths::check_output(&a.output, &[&a.scene])?;
    let text = std::fs::read_to_string(&a.scene).with_context(|| format!("{}: cannot read the scene", a.scene.display()))?;
    let scene = mint_pipeline::parse_scene(&text, &a.scene)?;
    crate::paths::check_output(&a.output, &scene_inputs(&a.scene, &scene))?;
    let bars = Bars::new(a.grid.quiet || a.grid.json);
    let s = mint_pipeline::csg(&scene, &a.scene.display().to_string(), &a.output, &opts, &bars)?;
    if a.grid.preview {
        let mut meshes: Vec<&std::path::Path> = scene.operands.iter().filter_map(|o| match o {
            mint_pipeline::scene::Operand::Mesh { path, .. } => Some(path.as_path()),
            _ => None,
        }).collect();
        meshes.push(a.output.as_path());
        write_preview(&meshes, &a.output, a.grid.quiet || a.grid.json, &bars)?;
    }
    report(&a.grid, &s)
}
