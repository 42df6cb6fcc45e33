//! `mint render` and the `--preview` pictures of the other commands.

use crate::jobs::*;
use crate::progress::Bars;
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The meshes to draw, then the PNG to write.
    #[arg(required = true, num_args = 2.., value_name = "MESH... OUT.png")]
    pub files: Vec<PathBuf>,
    /// Size of each view, WIDTHxHEIGHT pixels.
    #[arg(long, default_value = "1200x900", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Where the camera looks from.
    #[arg(long, value_enum, default_value_t = ViewArg::Iso)]
    pub view: ViewArg,
    /// A reference mesh for `--color distance` (read in memory).
    #[arg(long = "ref", value_name = "REF")]
    pub reference: Option<PathBuf>,
    /// shading: flat shading (back faces orange). distance: the distance
    /// of each visible point to --ref, blue (0) to red (the largest), with
    /// a colour bar: where a resampling or decimation lost detail.
    #[arg(long, value_enum, default_value_t = ColorArg::Shading)]
    pub color: ColorArg,
    /// Worker threads [default: all cores]. The picture is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorArg {
    Shading,
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
    let refs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
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
        (ColorArg::Shading, Some(_)) => bail!("--ref is used with --color distance"),
        (ColorArg::Shading, None) => None,
    };
    if let Some(r) = &distance_to {
        crate::paths::check_not_input(output, &[r.as_path()])?;
    }
    let threads = if a.threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { a.threads };
    let o = mint_render::RenderOptions { width: a.size.0, height: a.size.1, view, threads, distance_to };
    let bars = Bars::new(a.quiet || a.json);
    let s = mint_render::render_files(&refs, output, &o, &bars)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else if !a.quiet {
        eprintln!("rendered {} triangles -> {} ({}x{}, {} pixels covered) in {:.2}s", s.triangles, s.output, s.width, s.height, s.covered_pixels, s.seconds);
        if let (Some(max), Some(mean)) = (s.distance_max, s.distance_mean) {
            eprintln!("  distance to the reference over the visible surface: mean {mean:.3e}, max {max:.3e} (the colour bar's top)");
        }
    }
    Ok(())
}

/// `--preview`: `OUT.png` beside `output`, the meshes side by side.
pub(crate) fn write_preview(meshes: &[&std::path::Path], output: &std::path::Path, quiet: bool, bars: &Bars) -> Result<()> {
    let png = preview_path(output);
    let o = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
    mint_render::render_files(meshes, &png, &o, bars)?;
    if !quiet {
        eprintln!("preview: {} ({})", png.display(), meshes.iter().map(|m| m.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned())).collect::<Vec<_>>().join(", "));
    }
    Ok(())
}
