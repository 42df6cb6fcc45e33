//! `mint render`: a PNG picture of one or more meshes of any size, by a
//! streaming z-buffer rasterizer (shading, or the distance to a reference;
//! wireframe, boundary edges). Calls `mint_render::render_files` (and
//! `mint_check::check_file` for `--show-boundary`).

use crate::jobs::{QuietArg, JsonArg, MemArg};
use crate::progress::Bars;
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The meshes to draw, one column each, then the PNG to write. A
    /// directory of tiles or @LIST (one path a line) is one surface, drawn
    /// in one column.
    #[arg(required = true, num_args = 2.., value_name = "MESH... OUT.png")]
    pub files: Vec<PathBuf>,
    /// Size of each view, WIDTHxHEIGHT pixels.
    #[arg(long, default_value = "1200x900", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Where the camera looks from: front, back, left, right, top and
    /// bottom as the model sees them with --up pointing up.
    #[arg(long, value_enum, default_value_t = ViewArg::Iso)]
    pub view: ViewArg,
    /// The world axis drawn upwards: y (glTF, most OBJ exporters, MeshLab,
    /// the Stanford scans; the front faces +z) or z (CAD, terrain, medical
    /// stacks; the front faces −y), or x.
    #[arg(long, value_enum, default_value_t = crate::preview::UpArg::Y)]
    pub up: crate::preview::UpArg,
    /// A reference mesh for `--color distance` (read in memory).
    #[arg(long = "ref", value_name = "REF")]
    pub reference: Option<PathBuf>,
    /// vertex (the default): a file's per-vertex colours where it has them
    /// (PLY red green blue, OBJ v x y z r g b), else shading. shading: flat
    /// shading (back faces orange), colours ignored. distance: the distance
    /// of each visible point to --ref, blue (0) to red (the largest), with
    /// a colour bar: where a resampling or decimation lost detail.
    #[arg(long, value_enum, default_value_t = ColorArg::Vertex)]
    pub color: ColorArg,
    /// Draw every triangle's edges in dark grey (edges hidden by the surface
    /// stay hidden). On a mesh with more triangles than pixels this turns
    /// the surface grey: use it on small meshes or zoomed views.
    #[arg(long)]
    pub wireframe: bool,
    /// Draw the boundary edges (edges used by one face, after welding
    /// vertices at identical positions) thick and red, so that holes show.
    /// Finds them as `mint check` does, within --mem; draws at most the
    /// first 10 million per mesh.
    #[arg(long)]
    pub show_boundary: bool,
    /// The budget of --show-boundary's check.
    #[command(flatten)]
    pub mem: MemArg,
    /// Worker threads [default: all cores]. The picture is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    #[command(flatten)]
    pub quiet: QuietArg,
    #[command(flatten)]
    pub json: JsonArg,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorArg {
    /// The files' colours where they have them (per vertex, per face, or
    /// textures sampled per pixel), else shading.
    Vertex,
    /// Shading only, whatever colours the files have.
    Shading,
    /// Distance to --ref, with a colour bar.
    Distance,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewArg {
    Iso,
    Front,
    Back,
    Left,
    Right,
    Top,
    Bottom,
    All,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 1200x900"))?;
    let n = |t: &str| t.trim().parse::<u32>().map_err(|e| format!("'{s}': {e}"));
    Ok((n(w)?, n(h)?))
}

pub(crate) fn cmd_render(a: RenderArgs) -> Result<()> {
    let (output, inputs) = a.files.split_last().expect("clap requires two files");
    if output.extension().is_none_or(|e| !e.eq_ignore_ascii_case("png")) {
        bail!("{}: the picture is written as PNG; name it OUT.png", output.display());
    }
    let columns: Vec<Vec<PathBuf>> = inputs.iter().map(|i| crate::jobs::surface_files(std::slice::from_ref(i))).collect::<Result<_>>()?;
    let refs: Vec<&std::path::Path> = columns.iter().flatten().map(PathBuf::as_path).collect();
    crate::paths::check_output(output, &refs)?;
    let view = match a.view {
        ViewArg::Iso => mint_render::View::Iso,
        ViewArg::Front => mint_render::View::Front,
        ViewArg::Back => mint_render::View::Back,
        ViewArg::Left => mint_render::View::Left,
        ViewArg::Right => mint_render::View::Right,
        ViewArg::Top => mint_render::View::Top,
        ViewArg::Bottom => mint_render::View::Bottom,
        ViewArg::All => mint_render::View::All,
    };
    let distance_to = match (a.color, &a.reference) {
        (ColorArg::Distance, Some(r)) => Some(r.clone()),
        (ColorArg::Distance, None) => bail!("--color distance needs --ref REF, the mesh to measure against"),
        (ColorArg::Shading | ColorArg::Vertex, Some(_)) => bail!("--ref is used with --color distance"),
        (ColorArg::Shading | ColorArg::Vertex, None) => None,
    };
    if let Some(r) = &distance_to {
        crate::paths::check_not_input(output, &[r.as_path()])?;
    }
    let threads = if a.threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { a.threads };
    let bars = Bars::new(a.quiet.quiet || a.json.json);
    let mut marks = Vec::new();
    let mut boundary_edges = Vec::new();
    if a.show_boundary {
        const MOST: usize = 10_000_000;
        for files in &columns {
            let [input] = files.as_slice() else {
                bail!("{}: --show-boundary draws one file a column, not yet a surface of {} files (check them with `mint check`)", mint_pipeline::spec::files_name(files), files.len());
            };
            let opts = mint_check::CheckOptions { mem_bytes: a.mem.bytes(), weld: true, tmp_dir: None, threads, list_boundary: MOST };
            let (report, stats) = mint_check::check_file(input, &opts, &bars)?;
            let positions = mint_io::MeshReader::open(input, mint_io::ReadOptions::default())?.positions();
            marks.push(stats.boundary.iter().map(|&[v, w]| [positions.get(v), positions.get(w)]).collect::<Vec<_>>());
            if report.boundary_edges as usize > MOST && !a.quiet.quiet {
                eprintln!("warning: {}: {} boundary edges; drawing the first {MOST}", input.display(), report.boundary_edges);
            }
            boundary_edges.push(report.boundary_edges);
        }
    }
    let o = mint_render::RenderOptions {
        width: a.size.0,
        height: a.size.1,
        view,
        threads,
        distance_to,
        wireframe: a.wireframe,
        marks,
        up: a.up.axis(),
        vertex_colours: a.color == ColorArg::Vertex,
    };
    let s = mint_render::render_surfaces(&columns, output, &o, &bars)?;
    if a.json.json {
        let mut v = serde_json::to_value(&s)?;
        if a.show_boundary {
            v["boundary_edges"] = boundary_edges.clone().into();
        }
        crate::out::json(&v)?;
    } else if !a.quiet.quiet {
        eprintln!("rendered {} triangles -> {} ({}x{}, {} pixels covered) in {:.2}s", s.triangles, s.output, s.width, s.height, s.covered_pixels, s.seconds);
        if s.coloured_files > 0 {
            eprintln!("  drawn in their colours (per vertex, per face or textures): {} of the files (--color shading to ignore them)", s.coloured_files);
        }
        if a.show_boundary {
            let list: Vec<String> = boundary_edges.iter().map(u64::to_string).collect();
            eprintln!("  boundary edges (red): {}", list.join(", "));
        }
        if let (Some(max), Some(mean)) = (s.distance_max, s.distance_mean) {
            eprintln!("  distance to the reference over the visible surface: mean {mean:.3e}, max {max:.3e} (the colour bar's top)");
        }
    }
    Ok(())
}
