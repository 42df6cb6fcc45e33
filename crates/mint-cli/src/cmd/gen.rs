//! `mint gen`: a synthetic test mesh (sphere, torus, genus-n plate, many
//! components, or a scan-like surface with a defect list beside it),
//! streamed to disk at any size, in order or shuffled. Calls the generators
//! of `mint_gen` (`sphere`, `torus`, `genus`, `components`, `scan_like`,
//! `torus_shuffled`, `shuffle_mesh`); `mint demo` runs it through `cmd_gen`.

use crate::jobs::{JsonArg};
use crate::units::human_bytes;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use mint_io::WriteOptions;
use std::path::PathBuf;

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
    /// A voxel volume (write .nrrd, .nhdr, .mha, .mhd, .nii or .raw): a
    /// smooth field with a ball, a thin torus and a sheet 1.5 voxels thick;
    /// its surface is --iso 1000. Any size, streamed slice by slice.
    Volume,
    /// A label map volume: three touching solids labelled 1, 2, 3 on 0.
    Labels,
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
    /// Give every vertex a colour (PLY, OBJ, glTF): smooth gradients with sharp
    /// borders on the planes x, y, z = k/4, a function of the position
    /// (`mint_gen::colour::colour_at`), for colour tests and benchmarks.
    #[arg(long)]
    pub color: bool,
    /// Order of the vertices and faces in the file: as generated (spatially
    /// coherent), or shuffled, as real scans often come (the same surface
    /// and triangles; the torus is shuffled as it streams, at any size; other
    /// shapes are shuffled in memory, up to 50M faces).
    #[arg(long, value_enum, default_value_t = OrderArg::InOrder)]
    pub order: OrderArg,
    /// Volumes: dimensions X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", default_value = "128,128,128")]
    pub dims: String,
    /// Volumes: sample type (u8, i8, u16, i16, u32, i32, f32, f64) [default: u16, labels u8].
    #[arg(long = "type", value_name = "T")]
    pub sample: Option<String>,
    /// Volumes: voxel spacing [default: 1,1,1].
    #[arg(long, value_name = "SX,SY,SZ", default_value = "1,1,1")]
    pub spacing: String,
    #[command(flatten)]
    pub json: JsonArg,
}

/// `mint gen volume|labels`: slice by slice through `mint_volume::VolumeWriter`.
fn gen_volume(a: &GenArgs) -> Result<()> {
    let nums = |s: &str, what: &str| -> Result<Vec<f64>> {
        let v: Vec<f64> = s.split(',').map(|t| t.trim().parse::<f64>()).collect::<Result<_, _>>().with_context(|| format!("--{what} {s}: expected three numbers"))?;
        if v.len() != 3 || v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            bail!("--{what} {s}: expected three positive numbers");
        }
        Ok(v)
    };
    let d = nums(&a.dims, "dims")?;
    if d.iter().any(|x| x.fract() != 0.0) {
        bail!("--dims {}: whole numbers", a.dims);
    }
    let dims = [d[0] as u64, d[1] as u64, d[2] as u64];
    let sp = nums(&a.spacing, "spacing")?;
    let kind = if a.shape == Shape::Labels { mint_gen::volume::VolumeKind::Labels } else { mint_gen::volume::VolumeKind::Field };
    let name = a.sample.clone().unwrap_or_else(|| if kind == mint_gen::volume::VolumeKind::Labels { "u8".into() } else { "u16".into() });
    let sample = mint_volume::Sample::parse(&name).with_context(|| format!("--type {name}: one of u8, i8, u16, i16, u32, i32, u64, i64, f32, f64"))?;
    let m = [[sp[0], 0.0, 0.0, 0.0], [0.0, sp[1], 0.0, 0.0], [0.0, 0.0, sp[2], 0.0]];
    let mut w = mint_volume::VolumeWriter::create(&a.output, dims, sample, m, mint_volume::Frame::Scanner)?;
    let slice = dims[0].checked_mul(dims[1]).filter(|&n| n <= 1 << 32).with_context(|| format!("--dims {}: one slice is too large", a.dims))? as usize;
    let mut buf = vec![0f32; slice];
    let bar = crate::progress::Bars::new(a.json.json);
    mint_pipeline::Progress::start(&bar, mint_pipeline::progress::WRITE, dims[2]);
    for k in 0..dims[2] {
        mint_gen::volume::volume_slice(kind, dims, k, &mut buf);
        w.write_slice(&buf)?;
        mint_pipeline::Progress::advance(&bar, 1);
        if crate::progress::interrupted() {
            bail!("interrupted; no output written");
        }
    }
    let files = w.finish()?;
    mint_pipeline::Progress::finish(&bar);
    let bytes = dims.iter().product::<u64>() * sample.size() as u64;
    if a.json.json {
        crate::out::json(&serde_json::json!({ "dims": dims, "sample": sample.name(), "bytes": bytes, "files": files }))?;
    } else {
        eprintln!("generated {:?}: {}x{}x{} {} -> {} ({} of samples){}", a.shape, dims[0], dims[1], dims[2], sample.name(), a.output.display(), human_bytes(bytes), if kind == mint_gen::volume::VolumeKind::Field { "; its surface: --iso 1000" } else { "; labels 1, 2, 3" });
    }
    Ok(())
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OrderArg {
    InOrder,
    Shuffled,
}

/// Generates `a.shape` into `w`: what was generated, and the scan's defects.
pub(crate) fn cmd_gen_into(a: &GenArgs, w: &mut dyn mint_core::MeshSink) -> Result<(serde_json::Value, Option<mint_gen::ScanDefects>)> {
    Ok(match a.shape {
        Shape::Sphere => (serde_json::to_value(mint_gen::sphere([0.0; 3], 1.0, a.faces, w)?)?, None),
        Shape::Torus => (serde_json::to_value(mint_gen::torus([0.0; 3], 1.0, 0.35, a.faces, w)?)?, None),
        Shape::Genus => (serde_json::to_value(mint_gen::genus(a.genus, a.faces, w)?)?, None),
        Shape::Components => (serde_json::to_value(mint_gen::components(a.faces, a.seed, w)?)?, None),
        Shape::Volume | Shape::Labels => bail!("{}: `mint gen volume` and `mint gen labels` write volumes, not meshes", a.output.display()),
        Shape::Scan => {
            let d = mint_gen::scan_like(a.faces, a.seed, &mint_gen::ScanOptions::default(), w)?;
            (serde_json::to_value(&d.counts)?, Some(d))
        }
    })
}

/// Writes each vertex with the colour field's colour at it.
struct Coloured<'w>(&'w mut mint_io::MeshWriter);

impl mint_core::MeshSink for Coloured<'_> {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), mint_core::SinkError> {
        Ok(self.0.write_vertex_rgba(p, mint_gen::colour::colour_at(p))?)
    }
    fn face(&mut self, f: [u32; 3]) -> Result<(), mint_core::SinkError> {
        Ok(self.0.write_face(f)?)
    }
}

pub(crate) fn cmd_gen(a: GenArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[])?;
    if matches!(a.shape, Shape::Volume | Shape::Labels) {
        return gen_volume(&a);
    }
    let format = mint_io::Format::from_path(&a.output)?;
    if a.color && !mint_io::MeshWriter::holds_colour(format) {
        bail!("{}: --color needs a format that holds per-vertex colour (.ply, .obj, .glb or .gltf)", a.output.display());
    }
    let mut w = mint_io::MeshWriter::create(&a.output, format, WriteOptions { ascii: a.ascii, colours: a.color, ..Default::default() })?;
    let (generated, defects) = {
        let mut coloured = Coloured(&mut w);
        let sink: &mut dyn mint_core::MeshSink = if a.color { &mut coloured } else { coloured.0 };
        match (a.order, a.shape) {
            (OrderArg::Shuffled, Shape::Torus) => (serde_json::to_value(mint_gen::torus_shuffled([0.0; 3], 1.0, 0.35, a.faces, a.seed, sink)?)?, None),
            (OrderArg::Shuffled, _) => {
                if a.faces > 50_000_000 {
                    bail!("--order shuffled: only the torus is shuffled as it streams; other shapes are shuffled in memory, up to 50,000,000 faces");
                }
                let mut m = mint_core::TriMesh::default();
                let g = cmd_gen_into(&a, &mut m)?;
                mint_gen::shuffle_mesh(&m, a.seed, sink)?;
                g
            }
            (OrderArg::InOrder, _) => cmd_gen_into(&a, sink)?,
        }
    };
    let written = w.finish()?;
    if let Some(d) = &defects {
        let side = sidecar_path(&a.output);
        let tmp = side.with_extension("json.mint-tmp");
        std::fs::write(&tmp, serde_json::to_string_pretty(d)?).with_context(|| format!("{}: writing the defect list", tmp.display()))?;
        std::fs::rename(&tmp, &side).with_context(|| format!("{}: renaming the defect list", side.display()))?;
    }
    if a.json.json {
        crate::out::json(&generated)?;
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
