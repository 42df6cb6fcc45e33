//! `mint gen` and `mint demo`: synthetic meshes, and the main job end to end on one.

use crate::jobs::*;
use crate::progress::Bars;
use crate::units::human_bytes;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use mint_io::WriteOptions;
use std::path::PathBuf;
use crate::cmd::decimate::resample_and_report;
use crate::cmd::check::print_check;

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// UV sphere of radius 1 around the origin (genus 0).
    Sphere,
    /// Torus around the z axis, radii 1 and 0.35 (genus 1).
    Torus,
    /// Thick plate with --genus square holes.
    Genus,
    /// Many small disjoint spheres on a lattice.
    Components,
    /// Noisy sphere with holes, flipped faces, overlapping patches and
    /// non-manifold slivers; writes OUT.defects.json listing them.
    Scan,
}

#[derive(Args, Debug)]
pub struct GenArgs {
    /// Shape to generate.
    #[arg(value_enum)]
    pub shape: Shape,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// About this many faces.
    #[arg(long, default_value_t = 100_000)]
    pub faces: u64,
    /// Seed for shapes with randomness (components, scan).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of holes of the genus shape.
    #[arg(long, default_value_t = 3)]
    pub genus: u32,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Order of the vertices and faces in the file: as generated (spatially
    /// coherent), or shuffled, as real scans often come (the same surface
    /// and triangles; the torus is shuffled as it streams, at any size; other
    /// shapes are shuffled in memory, up to 50M faces).
    #[arg(long, value_enum, default_value_t = OrderArg::InOrder)]
    pub order: OrderArg,
    /// Print what was generated as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OrderArg {
    InOrder,
    Shuffled,
}

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Faces of the generated input.
    #[arg(long, default_value_t = 2_000_000)]
    pub faces: u64,
    /// Grid cells of the resampling.
    #[arg(long, default_value_t = 1_000_000)]
    pub cells: u64,
    /// Keep the input and output in this directory [default: a temporary
    /// directory, removed at the end].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Where to write the before/after picture [default: mint-demo.png in
    /// the --out directory, else in the current directory].
    #[arg(long, value_name = "PNG")]
    pub picture: Option<PathBuf>,
}

/// Generates `a.shape` into `w`: what was generated, and the scan's defects.
pub(crate) fn cmd_gen_into(a: &GenArgs, w: &mut dyn mint_core::MeshSink) -> Result<(serde_json::Value, Option<mint_gen::ScanDefects>)> {
    Ok(match a.shape {
        Shape::Sphere => (serde_json::to_value(mint_gen::sphere([0.0; 3], 1.0, a.faces, w)?)?, None),
        Shape::Torus => (serde_json::to_value(mint_gen::torus([0.0; 3], 1.0, 0.35, a.faces, w)?)?, None),
        Shape::Genus => (serde_json::to_value(mint_gen::genus(a.genus, a.faces, w)?)?, None),
        Shape::Components => (serde_json::to_value(mint_gen::components(a.faces, a.seed, w)?)?, None),
        Shape::Scan => {
            let d = mint_gen::scan_like(a.faces, a.seed, &mint_gen::ScanOptions::default(), w)?;
            (serde_json::to_value(&d.counts)?, Some(d))
        }
    })
}

pub(crate) fn cmd_gen(a: GenArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[])?;
    let format = mint_io::Format::from_path(&a.output)?;
    let mut w = mint_io::MeshWriter::create(&a.output, format, WriteOptions { ascii: a.ascii, ..Default::default() })?;
    let (generated, defects) = match (a.order, a.shape) {
        (OrderArg::Shuffled, Shape::Torus) => (serde_json::to_value(mint_gen::torus_shuffled([0.0; 3], 1.0, 0.35, a.faces, a.seed, &mut w)?)?, None),
        (OrderArg::Shuffled, _) => {
            if a.faces > 50_000_000 {
                bail!("--order shuffled: only the torus is shuffled as it streams; other shapes are shuffled in memory, up to 50,000,000 faces");
            }
            let mut m = mint_core::TriMesh::default();
            let g = cmd_gen_into(&a, &mut m)?;
            mint_gen::shuffle_mesh(&m, a.seed, &mut w)?;
            g
        }
        (OrderArg::InOrder, _) => cmd_gen_into(&a, &mut w)?,
    };
    let written = w.finish()?;
    if let Some(d) = &defects {
        let side = sidecar_path(&a.output);
        let tmp = side.with_extension("json.mint-tmp");
        std::fs::write(&tmp, serde_json::to_string_pretty(d)?).with_context(|| format!("{}: writing the defect list", tmp.display()))?;
        std::fs::rename(&tmp, &side).with_context(|| format!("{}: renaming the defect list", side.display()))?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&generated)?);
    } else {
        eprintln!(
            "generated {:?}: {} vertices, {} faces -> {} ({})",
            a.shape,
            written.vertices,
            written.faces,
            a.output.display(),
            human_bytes(written.bytes)
        );
        if defects.is_some() {
            eprintln!("defects listed in {}", sidecar_path(&a.output).display());
        }
    }
    Ok(())
}

/// `out.ply` -> `out.defects.json`.
pub(crate) fn sidecar_path(out: &std::path::Path) -> PathBuf {
    out.with_extension("defects.json")
}

pub(crate) fn cmd_demo(a: DemoArgs) -> Result<()> {
    let tmp;
    let dir = match &a.out {
        Some(d) => {
            std::fs::create_dir_all(d).with_context(|| format!("{}: creating the output directory", d.display()))?;
            d.clone()
        }
        None => {
            tmp = tempfile_dir()?;
            tmp.path().to_path_buf()
        }
    };
    let input = dir.join("demo-genus3.ply");
    let output = dir.join("demo-genus3-resampled.ply");
    eprintln!("1/3 generating a genus-3 solid with about {} faces: {}", a.faces, input.display());
    cmd_gen(GenArgs { shape: Shape::Genus, output: input.clone(), faces: a.faces, seed: 1, genus: 3, ascii: false, order: OrderArg::InOrder, json: false })?;
    eprintln!("2/3 resampling it on about {} cells", a.cells);
    let s = resample_and_report(ResampleArgs {
        input: input.clone(),
        output: output.clone(),
        cells: Some(a.cells),
        cell_size: None,
        mem: None,
        threads: 0,
        tmp: None,
        axis: AxisArg::Auto,
        slab: None,
        staged: StagedArgs::default(),
        signs: SignsArg::Auto,
        max_hole: 16,
        close_all: false,
        grid_offset: None,
        ascii: false,
        double: false,
        quiet: false,
        json: false,
        preview: false,
    })?;
    eprintln!("3/3 checking the output");
    let (positions, faces) = load_mesh(&output)?;
    let r = mint_mesh::try_check(&positions, &faces)?;
    print_check(&output.display().to_string(), &r);
    if !(r.watertight && r.genus_total == 3 && s.non_canonical_cells == 0) {
        bail!("demo output is not a watertight genus-3 surface: this is a bug, please report it");
    }
    let png = a.picture.clone().unwrap_or_else(|| a.out.as_ref().map_or_else(|| PathBuf::from("mint-demo.png"), |d| d.join("mint-demo.png")));
    let o = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
    mint_render::render_files(&[input.as_path(), output.as_path()], &png, &o, &Bars::new(true))?;
    println!("demo ok: {} faces -> {} faces, watertight, genus 3", s.input_faces, s.output_faces);
    println!("picture: {} (input left, resampled right)", png.display());
    Ok(())
}

struct TempDir(PathBuf);
impl TempDir {
    fn path(&self) -> &std::path::Path {
        &self.0
    }
}
impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
fn tempfile_dir() -> Result<TempDir> {
    let base = std::env::temp_dir().join(format!("mint-demo-{}", std::process::id()));
    std::fs::create_dir_all(&base).with_context(|| format!("{}: creating a temporary directory", base.display()))?;
    Ok(TempDir(base))
}
