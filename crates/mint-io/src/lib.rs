//! mint-io: streaming readers and writers for triangle meshes (PLY, OBJ,
//! STL, OFF, and the formats of layered reconstruction: `mesh`, raw,
//! VRML 2.0, 3DS) whose memory does not grow with the face count.
//!
//! Reading: [`MeshReader::open`] detects the [`Format`], memory-maps the
//! file, parses the header into a [`MeshInfo`] and makes vertex positions
//! addressable by index through a map (in place for binary PLY and STL,
//! through an anonymous spill file of f64 triples for text formats). Faces
//! are then pulled with [`MeshReader::next_chunk`] into a reusable
//! [`TriangleChunk`]: 0-based indices and, optionally, resolved corner
//! positions. PLY range scans expose their sample grid as a [`RangeGrid`].
//!
//! Writing: [`MeshWriter`] (a [`mint_core::MeshSink`]) streams vertices then
//! faces into a temporary file beside the target, patches the counts at
//! [`MeshWriter::finish`] and renames the file into place with
//! [`AtomicFile`]; on error or drop nothing is left behind.
//! [`convert()`] chains the two.
//!
//! Errors are one [`Error`] type with an [`ErrorKind`] and a one-line
//! `Display` naming the file, the element and the record/byte position.
//!
//! Modules: [`format`](mod@format) (detection), [`reader`], [`writer`], [`atomic`],
//! [`convert`](mod@convert), [`error`]; the format modules `ply`, `obj`,
//! `stl`, `off`, `mesh`, `raw`, `vrml`, `three_ds`; `mapped` (the only place that maps files), `positions`
//! (index-addressed vertex fetches and the triangle emitter), `text`
//! (tokenizing).

#![warn(missing_docs)]

pub mod atomic;
mod backend;
pub mod convert;
mod coords;
pub mod error;
pub mod format;
mod formats;
pub mod colours;
pub mod gltf;
pub mod tiles;
pub mod textures;
pub mod inputs;
mod line_formats;
mod mapped;
mod mesh;
mod obj;
mod off;
mod ply;
mod positions;
pub mod precision;
mod raw;
pub mod reader;
mod stl;
mod text;
mod three_ds;
pub mod visit;
mod vrml;
pub mod writer;

pub use atomic::AtomicFile;
pub use colours::{FaceColours, VertexColours};
pub use convert::{concatenate, convert, convert_cancellable, ConvertSummary};
pub use error::{Error, ErrorKind, Position};
pub use format::Format;
pub use inputs::expand_inputs;
pub use reader::{has_vertex_colour, read_info, read_mesh, read_mesh_with, read_vertex_colours, ElementInfo, MeshInfo, MeshReader, RangeGrid, ReadOptions, ReadStats, TriangleChunk, VertexPositions, WholeMesh};
pub use reader::PREFETCH_PAGES_PER_FACE;
pub use visit::{f32le_corners, TriangleRecords, TriangleVisitor};
#[cfg(target_arch = "x86_64")]
pub use visit::use_avx2;
pub use writer::{MeshWriter, WriteOptions, WriteSummary};

#[cfg(test)]
mod layered_tests;

#[cfg(test)]
mod tests {
    /// Readers and writers move between pipeline threads.
    #[test]
    fn readers_and_writers_are_send() {
        fn send<T: Send>() {}
        send::<crate::MeshReader>();
        send::<crate::MeshWriter>();
        send::<crate::AtomicFile>();
        send::<crate::Error>();
        fn sync<T: Sync>() {}
        sync::<crate::Error>();
    }
}
