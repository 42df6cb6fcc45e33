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
    #[command(flatten)]
    pub json: JsonArg,
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
