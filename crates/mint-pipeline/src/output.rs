//! The ordered output of a run: slab results arrive in slab order; their
//! vertices go straight to the output writer, their faces (renumbered to
//! global ids) to an anonymous spill file, because every vertex must precede
//! every face in the output. [`OrderedOutput::finish`] appends the faces and
//! renames the output into place. Shared by `resample` and `csg`.

use crate::progress::{Phase, Progress};
use crate::resample::{check_cancel, PipelineError};
use mint_core::reconstruct::SlabResult;
use mint_io::{Format, MeshWriter, WriteOptions};
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, Write};
use std::path::{Path, PathBuf};

/// Vertices to the output, faces to a spill file, in slab order.
pub(crate) struct OrderedOutput {
    writer: MeshWriter,
    spill: BufWriter<File>,
    spill_name: PathBuf,
    /// Vertices written so far (the id offset of the next slab).
    pub vertices: u64,
    /// Faces spilled so far.
    pub faces: u64,
}

impl OrderedOutput {
    /// Opens the output (a temporary file beside `path`) and a spill file in `tmp_root`.
    pub fn create(path: &Path, format: Format, write: WriteOptions, tmp_root: &Path) -> Result<OrderedOutput, PipelineError> {
        let writer = MeshWriter::create(path, format, write)?;
        let spill_name = tmp_root.join("(face spill)");
        let file = tempfile::tempfile_in(tmp_root).map_err(|source| PipelineError::Temp {
            path: spill_name.clone(),
            op: "creating the face spill file",
            source,
        })?;
        Ok(OrderedOutput { writer, spill: BufWriter::with_capacity(1 << 20, file), spill_name, vertices: 0, faces: 0 })
    }

    fn temp(&self, op: &'static str) -> impl FnOnce(std::io::Error) -> PipelineError + '_ {
        move |source| PipelineError::Temp { path: self.spill_name.clone(), op, source }
    }

    /// Writes the next slab's vertices and spills its faces with global ids.
    pub fn push(&mut self, res: &SlabResult) -> Result<(), PipelineError> {
        for v in &res.vertices {
            self.writer.write_vertex(*v)?;
        }
        for f in &res.faces {
            let mut b = [0u8; 12];
            for (k, x) in f.iter().enumerate() {
                b[4 * k..4 * k + 4].copy_from_slice(&((*x as u64 + self.vertices) as u32).to_le_bytes());
            }
            if let Err(e) = self.spill.write_all(&b) {
                return Err(self.temp("writing the face spill file")(e));
            }
        }
        self.vertices += res.vertices.len() as u64;
        self.faces += res.faces.len() as u64;
        Ok(())
    }

    /// Appends the spilled faces after the vertices and renames the output into place.
    pub fn finish(self, progress: &dyn Progress) -> Result<(), PipelineError> {
        let OrderedOutput { mut writer, spill, spill_name, faces, .. } = self;
        let temp = |op: &'static str| {
            let path = spill_name.clone();
            move |source: std::io::Error| PipelineError::Temp { path, op, source }
        };
        let mut file = spill.into_inner().map_err(|e| temp("writing the face spill file")(e.into_error()))?;
        file.rewind().map_err(temp("rewinding the face spill file"))?;
        let mut rd = BufReader::with_capacity(1 << 20, file);
        progress.start(Phase::Write, faces);
        let mut b = [0u8; 12];
        for i in 0..faces {
            rd.read_exact(&mut b).map_err(temp("reading the face spill file"))?;
            writer.write_face([0, 1, 2].map(|k| u32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap())))?;
            if i % (1 << 16) == 0 {
                progress.advance(1 << 16);
                check_cancel(progress)?;
            }
        }
        writer.finish()?;
        progress.finish();
        Ok(())
    }
}
