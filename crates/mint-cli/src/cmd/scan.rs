//! `mint scan`: casts range images of a mesh from N viewpoints, as an
//! orthographic range scanner would, and writes them with their true (and,
//! on request, perturbed) poses in a Stanford .conf. Calls
//! `mint_range::scan_file::scan_file`.

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use mint_range::depth_grid::GridEncoding;
use mint_range::synth::SynthOptions;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ScanArgs {
    /// The mesh to scan (any format mint reads), ideally closed.
    pub mesh: PathBuf,
    /// Directory for the output (created if missing): view_NN.ply range
    /// images, view_NN.mesh.ply their triangle meshes (in each view's own
    /// frame), scans.conf with the true poses.
    pub out_dir: PathBuf,
    /// Number of viewpoints, spread evenly over the sphere.
    #[arg(long, default_value_t = 8)]
    pub views: usize,
    /// Standard deviation of the depth noise, in model units.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Seed of the noise and of the perturbation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Samples across each view (each image has RES x RES cells).
    #[arg(long, default_value_t = 200)]
    pub resolution: u32,
    /// Samples seen at more than this angle (degrees) from the surface normal are lost.
    #[arg(long, default_value_t = 80.0)]
    pub max_angle: f64,
    /// Also write scans-perturbed.conf: every view but the first moved by a
    /// random rotation of up to this many degrees about the mesh centre...
    #[arg(long, default_value_t = 0.0)]
    pub perturb_deg: f64,
    /// ...and a random translation of up to this fraction of the bounding-box diagonal.
    #[arg(long, default_value_t = 0.0)]
    pub perturb_frac: f64,
    /// File format of the range images.
    #[arg(long, value_enum, default_value_t = ImageFormat::Ply)]
    pub image_format: ImageFormat,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// PLY range image (the Stanford scans' layout): view_NN.ply.
    Ply,
    /// mint's depth grid, binary: view_NN.rgrid (docs/FORMATS.md).
    Rgrid,
    /// mint's depth grid, text: view_NN.rgrid.
    RgridAscii,
}

pub fn cmd_scan(a: ScanArgs) -> Result<()> {
    let (positions, faces) = crate::jobs::load_mesh(&a.mesh)?;
    let format = match a.image_format {
        ImageFormat::Ply => mint_range::scan_file::ImageFormat::Ply,
        ImageFormat::Rgrid => mint_range::scan_file::ImageFormat::Grid(GridEncoding::BinaryLittleEndian),
        ImageFormat::RgridAscii => mint_range::scan_file::ImageFormat::Grid(GridEncoding::Ascii),
    };
    let opts = mint_range::scan_file::ScanFileOptions {
        synth: SynthOptions { views: a.views, resolution: a.resolution, noise: a.noise, seed: a.seed, max_angle_deg: a.max_angle },
        format,
        perturb_deg: a.perturb_deg,
        perturb_frac: a.perturb_frac,
    };
    // Nothing is written where it would overwrite the input.
    let not_input = |p: &std::path::Path| crate::paths::check_not_input(p, &[&a.mesh]).map_err(|e| e.to_string().trim_start_matches(&format!("{}: ", p.display())).to_string());
    let s = mint_range::scan_file::scan_file(&a.mesh, &positions, &faces, &a.out_dir, &opts, &not_input).with_context(|| format!("scanning {}", a.mesh.display()))?;
    eprintln!(
        "scanned {} from {} views: {} samples -> {} (scans.conf{})",
        a.mesh.display(),
        s.views,
        s.samples,
        a.out_dir.display(),
        if s.perturbed { ", scans-perturbed.conf" } else { "" }
    );
    Ok(())
}
