//! `mint demo`: mint's main job end to end on a built-in input: generates a
//! genus-3 solid (`mint gen`), resamples it (`mint resample`), checks the
//! result (`mint_mesh::try_check`) and draws a before/after picture
//! (`mint_render::render_files`), in a temporary directory unless `--out`.

use crate::cmd::gen::{cmd_gen, GenArgs, OrderArg, Shape};
use crate::cmd::resample::resample_and_report;
use crate::jobs::{load_mesh, ResampleArgs};
use crate::progress::Bars;
use crate::summary::print_check;
use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::PathBuf;

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

pub(crate) fn cmd_demo(a: DemoArgs) -> Result<()> {
    let tmp;
    let dir = match &a.out {
        Some(d) => {
            std::fs::create_dir_all(d).with_context(|| format!("{}: creating the output directory", d.display()))?;
            d.clone()
        }
        None => {
            tmp = tempfile::Builder::new().prefix("mint-demo-").tempdir().with_context(|| format!("{}: creating a temporary directory", std::env::temp_dir().display()))?;
            tmp.path().to_path_buf()
        }
    };
    let input = dir.join("demo-genus3.ply");
    let output = dir.join("demo-genus3-resampled.ply");
    eprintln!("1/3 generating a genus-3 solid with about {} faces: {}", a.faces, input.display());
    cmd_gen(GenArgs { shape: Shape::Genus, output: input.clone(), faces: a.faces, seed: 1, genus: 3, ascii: false, color: false, dims: "128,128,128".into(), sample: None, spacing: "1,1,1".into(), order: OrderArg::InOrder, json: Default::default() })?;
    eprintln!("2/3 resampling it on about {} cells", a.cells);
    // The very arguments `mint resample IN OUT --cells N` parses to.
    #[derive(clap::Parser)]
    struct Resample {
        #[command(flatten)]
        a: ResampleArgs,
    }
    let words = ["resample".into(), input.clone().into_os_string(), output.clone().into_os_string(), "--cells".into(), a.cells.to_string().into()];
    let r = <Resample as clap::Parser>::try_parse_from(words).context("the demo's resample arguments")?;
    let s = resample_and_report(&r.a)?;
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
