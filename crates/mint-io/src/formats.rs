//! The one table from a [`Format`] to the code that reads and writes it.
//!
//! Each format module implements the contract in [`crate::backend`]
//! (`info`, `open`, a writer's `create`) and depends on nothing else of the
//! crate's front end; [`backend`] names them here, once, so that
//! `reader.rs` and `writer.rs` dispatch without listing the formats, and
//! adding a format means one module and one row (see ARCHITECTURE.md).

use crate::backend::{FormatWriter, MeshInfo, Opened, WriteOptions};
use crate::error::Error;
use crate::format::Format;
use crate::mapped::Mapped;
use crate::{gltf, mesh, obj, off, ply, raw, stl, three_ds, tiles, vrml};
use std::path::Path;
use std::sync::Arc;

/// How one format is read and written.
pub(crate) struct Backend {
    /// What the file says about itself (header, or one counting pass).
    pub(crate) info: fn(&Path, &[u8]) -> Result<MeshInfo, Error>,
    /// Opens the file for streaming (positions made index-addressable).
    pub(crate) open: fn(&Path, Arc<Mapped>, &Path) -> Result<Opened, Error>,
    /// Starts writing the format.
    pub(crate) create: fn(&Path, &WriteOptions) -> Result<Box<dyn FormatWriter>, Error>,
    /// The format stores positions as f32 whatever `--double` asks.
    pub(crate) f32_only: bool,
    /// It stores them relative to an origin it carries in f64 (glTF: the
    /// node's translation), so f32 need hold only the model's extent.
    pub(crate) origin: bool,
    /// It holds per-vertex colour (PLY, OBJ).
    pub(crate) colour: bool,
}

fn boxed<W: FormatWriter + 'static>(w: Result<W, Error>) -> Result<Box<dyn FormatWriter>, Error> {
    w.map(|w| Box::new(w) as Box<dyn FormatWriter>)
}

/// The backend of `format`: the only list of the formats' code.
pub(crate) fn backend(format: Format) -> Backend {
    match format {
        Format::Ply => Backend {
            info: |path, data| Ok(ply::read::info_from_header(&ply::header::parse(data, path)?)),
            open: ply::read::open,
            create: |path, o| boxed(ply::write::PlyWriter::create(path, o)),
            f32_only: false,
            origin: false,
            colour: true,
        },
        Format::Obj => Backend { info: obj::info, open: obj::open, create: |path, o| boxed(obj::writer(path, o)), f32_only: false, origin: false, colour: true },
        Format::Stl => Backend { info: stl::info, open: stl::open, create: |path, o| boxed(stl::StlWriter::create(path, o)), f32_only: true, origin: false, colour: false },
        Format::Off => Backend { info: off::info, open: off::open, create: |path, o| boxed(off::writer(path, o)), f32_only: false, origin: false, colour: false },
        Format::Mesh => Backend { info: mesh::info, open: mesh::open, create: |path, o| boxed(mesh::writer(path, o)), f32_only: false, origin: false, colour: false },
        Format::Raw => Backend { info: raw::info, open: raw::open, create: |path, o| boxed(raw::RawWriter::create(path, o)), f32_only: false, origin: false, colour: false },
        Format::Vrml => Backend { info: vrml::info, open: vrml::open, create: |path, o| boxed(vrml::VrmlWriter::create(path, o)), f32_only: false, origin: false, colour: false },
        Format::Gltf => Backend { info: gltf::info, open: gltf::open, create: |path, o| boxed(gltf::GltfWriter::create(path, o)), f32_only: true, origin: true, colour: true },
        Format::Tiles => Backend {
            info: tiles::info,
            open: tiles::open,
            create: |path, _| Err(Error::unsupported(path, "mint does not write 3D Tiles; write .glb (or .gltf, .ply) and tile it with a 3D Tiles tool")),
            f32_only: true,
            origin: true,
            colour: false,
        },
        Format::ThreeDs => {
            Backend { info: three_ds::info, open: three_ds::open, create: |path, o| boxed(three_ds::ThreeDsWriter::create(path, o)), f32_only: true, origin: false, colour: false }
        }
    }
}
