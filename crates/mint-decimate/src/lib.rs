//! `decimate`: a giant mesh to a target face count, in two stages.
//!
//! 1. **Out of core.** Marching Intersections resampling (the staged engine)
//!    to an intermediate mesh of about `M` faces (default `4 N`, at least
//!    [`INTERMEDIATE_FLOOR`], at most the input's faces). The cell
//!    size comes from the target: one streaming pass sums the triangles'
//!    area `A`, and MI gives about `K · A / h²` faces for cells of size `h`
//!    (`K` = [`FACES_PER_AREA_CELL`], measured), so `h = √(K·A/M)`. Overlapping
//!    or noisy scans have more triangle area than surface, so `M` then
//!    comes out smaller than asked; the summary reports both.
//! 2. **In core.** quadric edge collapse in f64 to `N` faces
//!    (`mint_mesh::simplify`), which judges its result with `check` and
//!    relaxes the target rather than hand over a mesh less clean than the
//!    resampling (which is closed and 2-manifold by construction).
//!
//! Memory: stage 1 is bounded by `--mem`; stage 2 holds the intermediate
//! mesh and the simplifier's tables (measured in docs/PERFORMANCE.md).

use mint_core::grid::GridSize;
use mint_io::{Format, MeshReader, MeshWriter, TriangleChunk, WriteOptions};
use mint_pipeline::discretize::CHUNK_TRIANGLES;
use mint_pipeline::progress::{check_cancel, Progress, BOUNDS};
use mint_pipeline::{run, PipelineError, ResampleSummary, RunSpec, Tuning, WriteSpec};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;


/// The least default intermediate size. Small targets need an intermediate
/// finer than `4 N` for the simplifier to choose the shape: measured on
/// the horse at 100 faces, mean error 2.69e-2 with 800 intermediate faces
/// and 8.9e-3 with the whole 97k (MeshLab: 8.8e-3); the in-core stage
/// costs about 0.3 s and 15 MB at this size.
pub const INTERMEDIATE_FLOOR: u64 = 200_000;

/// The default intermediate size per output face. Measured on the 22M-face
/// sphere to 220k faces (mean error relative to the diagonal, MeshLab
/// 2.35e-6): 2N 4.4e-6, 4N 3.3e-6, 8N 2.8e-6, the in-core stage taking
/// 1.0, 1.3 and 2.9 s; and 100M faces to 1M: 4N 11 s in all, 8N 25 s.
/// 4N keeps within 1.5× of MeshLab's error and the 15 s target.
pub const INTERMEDIATE_FACTOR: u64 = 4;

/// MI output faces per `area / cell²`: measured 3.0 on spheres, 2.9 on tori
/// and 2.0 on the genus-3 plate (large axis-aligned flats), from 10⁴ to 10⁶
/// output faces. Flats therefore give fewer intermediate faces than asked;
/// the default `M = 4 N` leaves room for that.
pub const FACES_PER_AREA_CELL: f64 = 3.0;

/// Options of [`decimate`].
#[derive(Debug, Clone)]
pub struct DecimateOptions {
    /// Faces of the output.
    pub target_faces: u64,
    /// Faces of the intermediate resampling (default `4 × target`, at least
    /// [`INTERMEDIATE_FLOOR`], at most the input's: measured, see docs/PERFORMANCE.md).
    pub intermediate_faces: Option<u64>,
    /// Largest error the simplifier may reach, relative to the extent
    /// (default 1: the face target decides).
    pub max_error: f32,
    /// How the output is written.
    pub write: WriteSpec,
    /// The resampling's tuning (memory, threads, work directory, parts…).
    /// With a work directory the intermediate mesh is kept there too
    /// (`intermediate.ply`), so that the same command resumes.
    pub tuning: Tuning,
}

/// What a decimation did.
#[derive(Debug, Clone, Serialize)]
pub struct DecimateSummary {
    pub input: String,
    pub output: String,
    /// The output's coordinates: "f32", or "f64" and why.
    pub output_precision: String,
    pub input_faces: u64,
    pub input_area: f64,
    pub cell_size: f64,
    pub intermediate_faces_asked: u64,
    pub intermediate_faces: u64,
    pub output_faces: u64,
    pub output_vertices: u64,
    pub target_faces: u64,
    /// The simplifier's largest collapse error (an area-weighted RMS
    /// distance), relative to the mesh extent.
    pub simplify_error: f32,
    pub intermediate_watertight: bool,
    pub output_watertight: bool,
    /// Times the simplifier's target was relaxed to keep the output clean.
    pub relaxed: u32,
    /// Folded face pairs removed from the simplifier's result.
    pub folded_pairs_removed: u64,
    pub seconds_area: f64,
    pub seconds_resample: f64,
    pub seconds_simplify: f64,
    pub seconds_write: f64,
    pub seconds_total: f64,
    /// Temporary files and directories that killed runs had left, removed.
    pub removed_dead: Vec<String>,
    pub resample: ResampleSummary,
}

/// Decimates `input` into `output`; see the module docs.
pub fn decimate(input: &Path, output: &Path, o: &DecimateOptions, progress: &dyn Progress) -> Result<DecimateSummary, PipelineError> {
    let t0 = Instant::now();
    let format = Format::from_path(output)?;
    if o.target_faces < 4 {
        return Err(PipelineError::stage(output, format!("--faces {}: a closed surface needs at least 4 faces", o.target_faces)));
    }
    let threads = o.tuning.thread_count();
    // 1. Area, then the cell size for the intermediate target.
    let t = Instant::now();
    let (faces, area) = surface_area(input, threads, progress)?;
    if faces == 0 || !(area > 0.0) || !area.is_finite() {
        return Err(PipelineError::Empty { path: input.to_path_buf() });
    }
    let seconds_area = t.elapsed().as_secs_f64();
    // Never finer than the input itself: that adds no information.
    let m = o.intermediate_faces.unwrap_or((INTERMEDIATE_FACTOR * o.target_faces).max(INTERMEDIATE_FLOOR).min(faces)).max(o.target_faces);
    let h = (FACES_PER_AREA_CELL * area / m as f64).sqrt();
    // 2. Resample into a temporary file beside the output (or in tmp).
    let t = Instant::now();
    let (mut removed_dead, mut owner) = (Vec::new(), None);
    let (mid_path, mid) = match &o.tuning.work_dir {
        // Kept beside the resampling's stages: the same command resumes.
        Some(w) => (w.join("intermediate.ply"), None),
        None => {
            let dir = o.tuning.tmp_dir.clone().unwrap_or_else(|| output.parent().filter(|p| !p.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")));
            // Intermediates that killed runs left here go first.
            removed_dead = mint_pipeline::workdir::remove_dead(&dir, ".mint-decimate-");
            // A directory of its own, locked by this run while it lives
            // (the intermediate itself is replaced by an atomic rename).
            let mid = tempfile::Builder::new().prefix(".mint-decimate-").tempdir_in(&dir).map_err(|source| PipelineError::Temp {
                path: dir.clone(),
                op: "creating the intermediate mesh's directory",
                source,
            })?;
            owner = Some(mint_pipeline::workdir::OwnerLock::of_dir(mid.path())?);
            (mid.path().join("intermediate.ply"), Some(mid))
        }
    };
    let mut spec = RunSpec::resample(input, &mid_path, GridSize::CellSize(h));
    spec.write.double = true;
    let rs = run(&spec, &o.tuning, progress)?;
    let seconds_resample = t.elapsed().as_secs_f64();
    // 3. In core: simplify and judge; 4. write.
    let t = Instant::now();
    let (positions, tris) = mint_io::read_mesh(&mid_path)?;
    drop((owner, mid));
    let so = mint_mesh::SimplifyOptions { target_faces: o.target_faces, max_error: o.max_error };
    let tolerance = h * mint_pipeline::spec::defaults::F32_TOLERANCE_CELLS;
    let (sr, output_precision, _, seconds_write) = simplify_and_write(input, output, format, &o.write.options(None), tolerance, positions, tris, &so, progress)?;
    // Reading the intermediate counts as simplifying.
    let seconds_simplify = t.elapsed().as_secs_f64() - seconds_write;
    Ok(DecimateSummary {
        input: input.display().to_string(),
        output: output.display().to_string(),
        output_precision,
        input_faces: faces,
        input_area: area,
        cell_size: h,
        intermediate_faces_asked: m,
        intermediate_faces: rs.output_faces,
        output_faces: sr.output_faces,
        output_vertices: sr.output_vertices,
        target_faces: o.target_faces,
        simplify_error: sr.error,
        intermediate_watertight: sr.input_watertight,
        output_watertight: sr.output_watertight,
        relaxed: sr.relaxed,
        folded_pairs_removed: sr.folded_pairs_removed,
        seconds_area,
        seconds_resample,
        seconds_simplify,
        seconds_write,
        seconds_total: t0.elapsed().as_secs_f64(),
        removed_dead: removed_dead.iter().map(|p| p.display().to_string()).chain(rs.removed_dead.iter().cloned()).collect(),
        resample: rs,
    })
}

/// Simplifies a mesh held in memory and writes it: the in-core stage of
/// [`decimate`] and all of [`simplify_file`]. Returns the simplifier's
/// report, the output's precision ("f32", or "f64" and why) and the
/// seconds spent simplifying and writing. Coordinates are written in f32
/// only where it places them within `tolerance` (`mint_io::precision`).
#[allow(clippy::too_many_arguments)]
fn simplify_and_write(
    input: &Path,
    output: &Path,
    format: Format,
    write: &WriteOptions,
    tolerance: f64,
    positions: Vec<[f64; 3]>,
    tris: Vec<[u32; 3]>,
    so: &mint_mesh::SimplifyOptions,
    progress: &dyn Progress,
) -> Result<(mint_mesh::SimplifyReport, String, f64, f64), PipelineError> {
    let t = Instant::now();
    let (p, f, sr) = mint_mesh::simplify_with(&positions, &tris, so, &|| progress.cancelled()).map_err(|e| match e {
        mint_mesh::MeshError::Cancelled => PipelineError::Cancelled,
        e => PipelineError::stage(input, format!("simplifying: {e}")),
    })?;
    drop((positions, tris));
    let seconds_simplify = t.elapsed().as_secs_f64();
    check_cancel(progress)?;
    let t = Instant::now();
    let (lo, hi) = bbox(&p);
    let (double, precision) = mint_io::precision::choose(output, format, write.double, lo, hi, tolerance)?;
    let mut w = MeshWriter::create(output, format, WriteOptions { double, ..write.clone() })?;
    for v in &p {
        w.write_vertex(*v)?;
    }
    for t in &f {
        w.write_face(*t)?;
    }
    w.finish()?;
    Ok((sr, precision, seconds_simplify, t.elapsed().as_secs_f64()))
}

/// The box of `p` (a zero box at the origin when empty).
fn bbox(p: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    if p.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in p {
        for d in 0..3 {
            lo[d] = lo[d].min(v[d]);
            hi[d] = hi[d].max(v[d]);
        }
    }
    (lo, hi)
}

/// `simplify`'s tolerance without a grid: a millionth of the box's
/// diagonal (f32 keeps a mesh near the origin; a geo-referenced one gets f64).
fn tolerance_of(p: &[[f64; 3]]) -> f64 {
    let (lo, hi) = bbox(p);
    1e-6 * (0..3).map(|d| (hi[d] - lo[d]).powi(2)).sum::<f64>().sqrt()
}

/// Options of [`simplify_file`].
#[derive(Debug, Clone)]
pub struct SimplifyFileOptions {
    /// Faces of the output.
    pub target_faces: u64,
    /// Largest error, relative to the extent (1: the face target decides).
    pub max_error: f32,
    /// Weld vertices at identical positions first (STL stores every
    /// triangle alone: without welding nothing could collapse).
    pub weld: bool,
    pub write: WriteOptions,
}

/// What [`simplify_file`] did.
#[derive(Debug, Clone, Serialize)]
pub struct SimplifySummary {
    pub input: String,
    pub output: String,
    /// The output's coordinates: "f32", or "f64" and why.
    pub output_precision: String,
    pub input_faces: u64,
    pub input_vertices: u64,
    pub welded_vertices: u64,
    pub target_faces: u64,
    pub output_faces: u64,
    pub output_vertices: u64,
    /// The simplifier's largest collapse error, relative to the extent.
    pub simplify_error: f32,
    pub input_watertight: bool,
    pub output_watertight: bool,
    pub relaxed: u32,
    pub folded_pairs_removed: u64,
    pub seconds_read: f64,
    pub seconds_simplify: f64,
    pub seconds_write: f64,
    pub seconds_total: f64,
}

/// `mint simplify`: the in-core stage alone, for a mesh that fits in
/// memory: read it whole, weld it (optionally), simplify it to the target
/// and write it. A closed, 2-manifold, oriented input gives one too.
pub fn simplify_file(input: &Path, output: &Path, o: &SimplifyFileOptions, progress: &dyn Progress) -> Result<SimplifySummary, PipelineError> {
    let t0 = Instant::now();
    let format = Format::from_path(output)?;
    if o.target_faces < 4 {
        return Err(PipelineError::stage(output, format!("--faces {}: a closed surface needs at least 4 faces", o.target_faces)));
    }
    let (mut positions, mut tris) = mint_io::read_mesh(input)?;
    if tris.is_empty() {
        return Err(PipelineError::Empty { path: input.to_path_buf() });
    }
    let (input_faces, input_vertices) = (tris.len() as u64, positions.len() as u64);
    let welded = if o.weld { mint_mesh::weld(&mut positions, &mut tris) } else { 0 };
    let seconds_read = t0.elapsed().as_secs_f64();
    check_cancel(progress)?;
    let so = mint_mesh::SimplifyOptions { target_faces: o.target_faces, max_error: o.max_error };
    let tolerance = tolerance_of(&positions);
    let (sr, output_precision, seconds_simplify, seconds_write) = simplify_and_write(input, output, format, &o.write, tolerance, positions, tris, &so, progress)?;
    Ok(SimplifySummary {
        input: input.display().to_string(),
        output: output.display().to_string(),
        output_precision,
        input_faces,
        input_vertices,
        welded_vertices: welded,
        target_faces: o.target_faces,
        output_faces: sr.output_faces,
        output_vertices: sr.output_vertices,
        simplify_error: sr.error,
        input_watertight: sr.input_watertight,
        output_watertight: sr.output_watertight,
        relaxed: sr.relaxed,
        folded_pairs_removed: sr.folded_pairs_removed,
        seconds_read,
        seconds_simplify,
        seconds_write,
        seconds_total: t0.elapsed().as_secs_f64(),
    })
}

/// The total area of `path`'s triangles and their count, in one streaming
/// pass (workers over fixed-size records when the file has them, else the
/// reader), summed per chunk in chunk order (the same for any thread count).
fn surface_area(path: &Path, threads: usize, progress: &dyn Progress) -> Result<(u64, f64), PipelineError> {
    let read = mint_io::ReadOptions { chunk_triangles: CHUNK_TRIANGLES, spill_dir: None, resolve_positions: true };
    let mut reader = MeshReader::open(path, read)?;
    let area = |p: &[[f64; 3]; 3]| {
        let (u, v) = ([p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]], [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]]);
        let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
    };
    if let Some(records) = reader.triangle_records()? {
        let n = records.len();
        let chunks = n.div_ceil(CHUNK_TRIANGLES as u64);
        progress.start(BOUNDS, n);
        let sums = Mutex::new(vec![0.0f64; chunks as usize]);
        mint_core::pool::for_each(threads, chunks, |_| (), |_, c| {
            if progress.cancelled() {
                return Err(PipelineError::Cancelled);
            }
            let (a, b) = (c * CHUNK_TRIANGLES as u64, ((c + 1) * CHUNK_TRIANGLES as u64).min(n));
            let mut sum = 0.0;
            records.visit(a, b, &mut |p: &[[f64; 3]; 3]| sum += area(p))?;
            sums.lock().unwrap()[c as usize] = sum;
            progress.advance(b - a);
            Ok(())
        })?;
        check_cancel(progress)?;
        progress.finish();
        return Ok((n, sums.into_inner().unwrap().iter().sum()));
    }
    progress.start(BOUNDS, reader.info().face_count.unwrap_or(0));
    let (mut faces, mut total) = (0u64, 0.0f64);
    let mut chunk = TriangleChunk::new();
    while reader.next_chunk(&mut chunk)? {
        check_cancel(progress)?;
        total += chunk.positions.iter().map(area).sum::<f64>();
        faces += chunk.len() as u64;
        progress.advance(chunk.len() as u64);
    }
    progress.finish();
    Ok((faces, total))
}
