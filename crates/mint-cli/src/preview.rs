//! The `--preview` pictures: OUT.png beside a command's output, the meshes
//! side by side under one camera (800x600, iso view), drawn by
//! `mint_render::render_files`. Used by resample, decimate, bool, csg,
//! contours and zipper.

use crate::progress::Bars;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// `--up`: the world axis drawn upwards in pictures.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum UpArg {
    X,
    #[default]
    Y,
    Z,
}

/// `--up` of a command that writes a preview (y by default).
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub struct PreviewUp {
    /// The axis drawn upwards in the preview (and `mint render --up`): y
    /// for glTF, most OBJ exporters, MeshLab and the Stanford scans; z for
    /// CAD, terrain and medical stacks.
    #[arg(long, value_enum, default_value_t = UpArg::Y)]
    pub up: UpArg,
}

impl UpArg {
    pub(crate) fn axis(self) -> mint_render::Up {
        match self {
            UpArg::X => mint_render::Up::X,
            UpArg::Y => mint_render::Up::Y,
            UpArg::Z => mint_render::Up::Z,
        }
    }
}

/// `OUT.png` beside `output` (its extension replaced).
pub(crate) fn preview_path(output: &Path) -> PathBuf {
    output.with_extension("png")
}

/// Draws `meshes` (each one or more files) side by side into the preview
/// picture of `output`, and returns its path.
fn draw_preview(meshes: &[Vec<PathBuf>], output: &Path, up: UpArg, bars: &Bars) -> Result<PathBuf> {
    let png = preview_path(output);
    let o = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, up: up.axis(), ..Default::default() };
    mint_render::render_surfaces(meshes, &png, &o, bars)?;
    Ok(png)
}

/// How a preview line names a surface: its file, or its first file and
/// how many more.
fn surface_name(files: &[PathBuf]) -> String {
    let name = |p: &PathBuf| p.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    match files {
        [one] => name(one),
        [first, rest @ ..] => format!("{} and {} more", name(first), rest.len()),
        [] => String::new(),
    }
}

/// `--preview`: `OUT.png` beside `output`, the meshes side by side.
pub(crate) fn write_preview(meshes: &[Vec<PathBuf>], output: &Path, up: UpArg, quiet: bool, bars: &Bars) -> Result<()> {
    let png = draw_preview(meshes, output, up, bars)?;
    if !quiet {
        eprintln!("preview: {} ({})", png.display(), meshes.iter().map(|m| surface_name(m)).collect::<Vec<_>>().join(", "));
    }
    Ok(())
}

/// `--preview` of resample and decimate: the input left (all its files),
/// the output right.
pub(crate) fn write_before_after(inputs: &[PathBuf], output: &Path, up: UpArg, quiet: bool, bars: &Bars) -> Result<()> {
    let png = draw_preview(&[inputs.to_vec(), vec![output.to_path_buf()]], output, up, bars)?;
    if !quiet {
        eprintln!("preview: {} (input left, output right)", png.display());
    }
    Ok(())
}
