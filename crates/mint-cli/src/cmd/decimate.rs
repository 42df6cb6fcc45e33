//! `mint decimate`: a mesh of any size down to a target face count, by an
//! out-of-core resampling to an intermediate mesh and an in-core quadric
//! simplification. Calls `mint_decimate::decimate`.

use crate::alloc;
use crate::jobs::{JsonArg, MemArg, QuietArg};
use crate::preview::{preview_path, write_before_after};
use crate::progress::Bars;
use crate::units::human_bytes;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct DecimateArgs {
    /// Input meshes (any format mint reads, any size), one surface: several
    /// files (tiles), a directory of them, or @LIST (one path a line).
    #[arg(required = true, num_args = 1.., value_name = "IN")]
    pub inputs: Vec<PathBuf>,
    /// Output mesh; the format follows the extension.
    #[arg(value_name = "OUT")]
    pub output: PathBuf,
    /// Faces of the output.
    #[arg(long)]
    pub faces: u64,
    /// Faces of the intermediate resampling [default: 4 × --faces, at least 200,000 and at most the input's; more costs time, rarely error].
    #[arg(long, value_name = "M")]
    pub intermediate: Option<u64>,
    /// Largest simplification error, as a fraction of the mesh's extent
    /// [default: 1, i.e. the face target decides].
    #[arg(long, value_name = "E", default_value_t = 1.0)]
    pub error: f32,
    /// The budget of the out-of-core stage.
    #[command(flatten)]
    pub mem: MemArg,
    /// Worker threads [default: all cores].
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Keep the resampling's stages here, to resume after a crash [default: temporary].
    #[arg(long, value_name = "DIR")]
    pub work: Option<PathBuf>,
    /// Directory for temporary files [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Write geometry only. By default a PLY, OBJ or glTF output carries
    /// the input's colour (per vertex, per face or textures): resampling
    /// carries it to the intermediate, and each output vertex takes the
    /// intermediate's colour at its nearest point.
    #[arg(long)]
    pub no_color: bool,
    /// How the in-core stage is reached. auto: a clean, oriented
    /// 2-manifold (closed, or open along simple boundary loops) of at most
    /// 4 x the intermediate's faces that fits --mem is simplified itself
    /// (sharp edges, thin parts and boundaries as they are); anything else
    /// (non-manifold, flipped, duplicated, larger) is resampled first,
    /// which also closes holes. The summary says which ran and why.
    #[arg(long, value_enum, default_value = "auto")]
    pub route: RouteArg,
    /// How much colour weighs in the collapse: a full-range colour
    /// difference across a face costs what a distance of W times the
    /// mesh's extent does. Larger keeps colour borders sharper at some cost
    /// in shape; 0 ignores colour (the kept vertices then take white).
    #[arg(long, value_name = "W", default_value_t = mint_decimate::COLOUR_WEIGHT)]
    pub color_weight: f64,
    /// Samples per direction of the error the summary reports (the sampled
    /// two-sided distance between the output and the input, as `mint
    /// distance` measures it); 0 leaves it out, saving about 0.1 s on a
    /// 270k-face mesh and 1 s against a 4M-face intermediate.
    #[arg(long, value_name = "N", default_value_t = mint_decimate::ERROR_SAMPLES)]
    pub error_samples: usize,
    /// Also write OUT.png beside the output: input and output side by side.
    #[arg(long)]
    pub preview: bool,
    #[command(flatten)]
    pub preview_up: crate::preview::PreviewUp,
    #[command(flatten)]
    pub quiet: QuietArg,
    #[command(flatten)]
    pub json: JsonArg,
}

/// `--route`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum RouteArg {
    Auto,
    Direct,
    Resample,
}

pub(crate) fn cmd_decimate(a: DecimateArgs) -> Result<()> {
    let files = crate::jobs::surface_files(&a.inputs)?;
    let refs: Vec<&std::path::Path> = files.iter().map(|p| p.as_path()).collect();
    crate::paths::check_output(&a.output, &refs)?;
    if a.preview {
        crate::paths::check_output(&preview_path(&a.output), &refs)?;
    }
    let mem = a.mem.bytes();
    let o = mint_decimate::DecimateOptions {
        target_faces: a.faces,
        intermediate_faces: a.intermediate,
        max_error: a.error,
        write: mint_pipeline::WriteSpec { no_colour: a.no_color, ..Default::default() },
        colour_weight: a.color_weight,
        error_samples: a.error_samples,
        route: match a.route {
            RouteArg::Auto => mint_decimate::Route::Auto,
            RouteArg::Direct => mint_decimate::Route::Direct,
            RouteArg::Resample => mint_decimate::Route::Resample,
        },
        tuning: mint_pipeline::Tuning { mem_bytes: mem, threads: a.threads, tmp_dir: a.tmp.clone(), work_dir: a.work.clone(), ..Default::default() },
    };
    let bars = Bars::new(a.quiet.quiet || a.json.json);
    let s = mint_decimate::decimate(&files, &a.output, &o, &bars)?;
    crate::summary::print_removed(&s.removed_dead);
    if a.preview {
        write_before_after(&files, &a.output, a.preview_up.up, a.quiet.quiet || a.json.json, &bars)?;
    }
    // The resampling's warnings (an open input read as a sheet, …).
    let mut warnings = match &s.resample {
        Some(r) => {
            let mut w = crate::summary::summary_warnings_with(r, "`mint resample --signs union`");
            if r.input_coloured_files > 0 && !s.colour && !a.no_color {
                w.insert(0, format!("{}: {} of the input files have colour, which {} cannot hold: the output is geometry only (write .ply, .obj, .gltf or .glb to keep it)", r.input, r.input_coloured_files, s.output));
            }
            w
        }
        None => Vec::new(),
    };
    if s.resample.is_none() && !s.colour && !a.no_color && files.iter().any(|f| mint_io::has_vertex_colour(f).unwrap_or(false)) {
        warnings.insert(0, format!("{}: the input has colour, which {} cannot hold: the output is geometry only (write .ply or .obj to keep it)", s.input, s.output));
    }
    for w in &warnings {
        crate::out::warn(w);
    }
    if a.json.json {
        let mut v = serde_json::to_value(&s)?;
        v["warnings"] = warnings.into();
        v["mem_budget_bytes"] = mem.into();
        v["peak_heap_bytes"] = alloc::peak_heap().into();
        crate::out::json(&v)?;
    } else if !a.quiet.quiet {
        eprintln!("decimated {} -> {}", s.input, s.output);
        eprintln!("  input        {} faces, area {:.6}", s.input_faces, s.input_area);
        if s.needles_ignored > 0 {
            eprintln!(
                "  needles      {} triangles many cells long and narrower than one ({:.1}% of the area) left out of the cell size: they vanish in the resampling",
                s.needles_ignored,
                100.0 * s.needle_area / s.input_area
            );
        }
        eprintln!("  route        {}: {}", s.route, s.route_reason);
        match &s.resample {
            Some(r) => eprintln!("  resampled    {} faces (asked {}), cells of {:.6}, {}", s.intermediate_faces, s.intermediate_faces_asked, s.cell_size, if s.intermediate_watertight {
                "watertight"
            } else if r.sign_rule == "sheet" {
                "an open sheet (the input is open)"
            } else {
                "NOT watertight"
            }),
            None => eprintln!("  welded       {} faces, {}", s.intermediate_faces, if s.intermediate_watertight { "watertight" } else { "NOT watertight" }),
        }
        eprintln!(
            "  simplified   {} faces (target {}), {} vertices, error {:.2e} of the extent; coordinates {}{}",
            s.output_faces,
            s.target_faces,
            s.output_vertices,
            s.simplify_error,
            s.output_precision,
            if s.colour { "; colour by colour-aware quadrics" } else { "" }
        );
        eprintln!("{}", crate::summary::surface_error_line(&s.error));
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
        crate::out::warn(if s.resample.is_some() { "the output is less clean than the resampling (see the summary)" } else { "the output is less clean than the input (see the summary)" });
    }
    Ok(())
}
