//! `mint simplify`: the in-core stage of `mint decimate` alone, for a mesh
//! that fits in memory: weld, quadric edge collapse (f64) to a face
//! target, check, write. Calls `mint_decimate::simplify_file`.

use crate::jobs::{QuietArg, JsonArg};
use crate::alloc;
use crate::progress::Bars;
use crate::units::human_bytes;
use anyhow::Result;
use clap::Args;
use mint_io::WriteOptions;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct SimplifyArgs {
    /// Input mesh (read whole into memory: about 200 bytes a face).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Faces of the output.
    #[arg(long)]
    pub faces: u64,
    /// Largest simplification error, as a fraction of the mesh's extent
    /// [default: 1, i.e. the face target decides].
    #[arg(long, value_name = "E", default_value_t = 1.0)]
    pub error: f32,
    /// Take the vertex indices as written instead of welding vertices at
    /// identical positions first (STL stores every triangle alone).
    #[arg(long)]
    pub no_weld: bool,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 instead of f32.
    #[arg(long)]
    pub double: bool,
    /// Write geometry only. By default a PLY, OBJ or glTF output carries
    /// the input's per-vertex colour, taken at each output vertex's
    /// nearest point of the input.
    #[arg(long)]
    pub no_color: bool,
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
    #[command(flatten)]
    pub quiet: QuietArg,
    #[command(flatten)]
    pub json: JsonArg,
}

pub(crate) fn cmd_simplify(a: SimplifyArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    let o = mint_decimate::SimplifyFileOptions {
        target_faces: a.faces,
        max_error: a.error,
        weld: !a.no_weld,
        write: WriteOptions { ascii: a.ascii, double: a.double, colours: !a.no_color, ..Default::default() },
        colour_weight: a.color_weight,
        error_samples: a.error_samples,
    };
    let bars = Bars::new(a.quiet.quiet || a.json.json);
    let s = mint_decimate::simplify_file(&a.input, &a.output, &o, &bars)?;
    if a.json.json {
        let mut v = serde_json::to_value(&s)?;
        v["peak_heap_bytes"] = alloc::peak_heap().into();
        crate::out::json(&v)?;
    } else if !a.quiet.quiet {
        eprintln!("simplified {} -> {}", s.input, s.output);
        eprintln!("  input        {} faces, {} vertices ({} welded), {}", s.input_faces, s.input_vertices, s.welded_vertices, if s.input_watertight { "watertight" } else { "not watertight" });
        eprintln!(
            "  output       {} faces (target {}), {} vertices, error {:.2e} of the extent; coordinates {}{}",
            s.output_faces,
            s.target_faces,
            s.output_vertices,
            s.simplify_error,
            s.output_precision,
            if s.colour { "; colour by colour-aware quadrics" } else { "" }
        );
        eprintln!("{}", crate::summary::surface_error_line(&s.error));
        eprintln!(
            "  judged       {}{}",
            if s.output_watertight { "watertight (closed, 2-manifold, consistently oriented)" } else { "NOT watertight" },
            if s.relaxed > 0 { format!("; target relaxed {} times to keep it so", s.relaxed) } else { String::new() }
        );
        eprintln!(
            "  time         {:.2}s (read {:.2}s, simplify {:.2}s, write {:.2}s), peak heap {}",
            s.seconds_total, s.seconds_read, s.seconds_simplify, s.seconds_write, human_bytes(alloc::peak_heap())
        );
    }
    if s.input_watertight && !s.output_watertight {
        crate::out::warn("the output is less clean than the input (see the summary)");
    }
    if s.output_faces > s.target_faces + s.target_faces / 50 {
        crate::out::warn(&format!("{} faces, more than the {} asked: the collapses that remained would have broken the surface", s.output_faces, s.target_faces));
    }
    Ok(())
}
