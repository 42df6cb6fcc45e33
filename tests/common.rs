//! Helpers for the integration tests: write generated meshes to files, run
//! the pipeline, load results back.

use mint_core::{MeshSink, TriMesh};
use mint_io::{Format, MeshReader, MeshWriter, ReadOptions, TriangleChunk, WriteOptions};
use std::path::{Path, PathBuf};

/// Writes a mesh produced by `f` into `dir/name`.
pub fn write_mesh(dir: &Path, name: &str, f: impl FnOnce(&mut dyn MeshSink)) -> PathBuf {
    let path = dir.join(name);
    let mut w = MeshWriter::create(&path, Format::from_path(&path).unwrap(), WriteOptions::default()).unwrap();
    f(&mut w);
    w.finish().unwrap();
    path
}

/// Writes an in-memory mesh.
pub fn write_trimesh(dir: &Path, name: &str, m: &TriMesh) -> PathBuf {
    write_mesh(dir, name, |s| {
        for p in &m.positions {
            s.vertex(*p).unwrap();
        }
        for f in &m.faces {
            s.face(*f).unwrap();
        }
    })
}

/// Reads a mesh file fully into memory.
pub fn load(path: &Path) -> TriMesh {
    let mut r = MeshReader::open(path, ReadOptions { resolve_positions: false, ..Default::default() }).unwrap();
    let positions = (0..r.vertex_count()).map(|i| r.vertex(i)).collect();
    let mut faces = Vec::new();
    let mut chunk = TriangleChunk::default();
    while r.next_chunk(&mut chunk).unwrap() {
        faces.extend_from_slice(&chunk.indices);
    }
    TriMesh { positions, faces }
}

/// An axis-aligned box with 12 outward triangles.
pub fn box_mesh(lo: [f64; 3], hi: [f64; 3]) -> TriMesh {
    let v = |i: usize| [if i & 1 == 0 { lo[0] } else { hi[0] }, if i & 2 == 0 { lo[1] } else { hi[1] }, if i & 4 == 0 { lo[2] } else { hi[2] }];
    let quads = [[0u32, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    TriMesh {
        positions: (0..8).map(v).collect(),
        faces: quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect(),
    }
}

/// Appends `b` to `a` (disjoint union).
pub fn union(a: &mut TriMesh, b: &TriMesh) {
    let off = a.positions.len() as u32;
    a.positions.extend_from_slice(&b.positions);
    a.faces.extend(b.faces.iter().map(|f| f.map(|i| i + off)));
}

/// A test's run: the spec's settings (its job and output come with each
/// call) and the tuning, changed field by field with [`Opts::with`].
#[derive(Debug, Clone)]
pub struct Opts {
    pub spec: mint_pipeline::RunSpec,
    pub tuning: mint_pipeline::Tuning,
}

impl Opts {
    /// Defaults on a grid of `size`.
    pub fn new(size: mint_core::GridSize) -> Opts {
        Opts { spec: mint_pipeline::RunSpec::resample("", "", size), tuning: Default::default() }
    }

    /// A copy changed by `f`.
    pub fn with(&self, f: impl FnOnce(&mut Opts)) -> Opts {
        let mut o = self.clone();
        f(&mut o);
        o
    }

    /// The spec of `job` into `output` with these settings.
    pub fn spec(&self, job: mint_pipeline::Job, output: &Path) -> mint_pipeline::RunSpec {
        mint_pipeline::RunSpec { job, output: output.to_path_buf(), ..self.spec.clone() }.normalized()
    }
}

/// Resamples `input` into `output` with `o`.
pub fn resample(input: &Path, output: &Path, o: &Opts, p: &dyn mint_pipeline::Progress) -> Result<mint_pipeline::ResampleSummary, mint_pipeline::PipelineError> {
    mint_pipeline::run(&o.spec(mint_pipeline::Job::Resample { inputs: vec![input.to_path_buf()] }, output), &o.tuning, p)
}

/// `a op b` into `output` with `o`.
pub fn boolean(op: mint_core::expr::BoolOp, a: &Path, b: &Path, output: &Path, o: &Opts, p: &dyn mint_pipeline::Progress) -> Result<mint_pipeline::ResampleSummary, mint_pipeline::PipelineError> {
    mint_pipeline::run(&o.spec(mint_pipeline::Job::Bool { op, a: vec![a.to_path_buf()], b: vec![b.to_path_buf()], iso_a: None, iso_b: None }, output), &o.tuning, p)
}

/// The scene `scene` (read from `scene_name`) into `output` with `o`.
pub fn csg(scene: &mint_pipeline::Scene, scene_name: &str, output: &Path, o: &Opts, p: &dyn mint_pipeline::Progress) -> Result<mint_pipeline::ResampleSummary, mint_pipeline::PipelineError> {
    mint_pipeline::run_scene(&o.spec(mint_pipeline::Job::Csg { scene: scene_name.into() }, output), scene, &o.tuning, p)
}

/// A PNG's pixels as RGB rows: (width, height, pixels row by row).
pub fn png_rgb(path: &Path) -> (usize, usize, Vec<[u8; 3]>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).unwrap();
    let (w, h) = (info.width as usize, info.height as usize);
    let ch = info.line_size / w;
    let px = (0..h).flat_map(|y| (0..w).map(move |x| (y, x))).map(|(y, x)| {
        let p = &buf[y * info.line_size + x * ch..][..3];
        [p[0], p[1], p[2]]
    });
    (w, h, px.collect())
}
