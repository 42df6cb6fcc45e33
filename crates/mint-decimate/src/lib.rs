//! `decimate`: a giant mesh to a target face count, in two stages.
//!
//! 1. **Out of core.** Marching Intersections resampling (the staged engine)
//!    to an intermediate mesh of about `M` faces (default `4 N`, at least
//!    [`INTERMEDIATE_FLOOR`], at most the input's faces). The cell
//!    size comes from the target: one streaming pass sums the triangles'
//!    area `A`, and MI gives about `K · A / h²` faces for cells of size `h`
//!    (`K` = [`FACES_PER_AREA_CELL`], measured), so `h = √(K·A/M)`. Overlapping
//!    or noisy scans have more triangle area than surface, so `M` then
//!    comes out smaller than asked; the summary reports both. Needles (a
//!    spike or a stray vertex: triangles many cells long and narrower
//!    than one) vanish in the resampling however large their area, so when
//!    the largest of them hold most of `A` they are left out of it (see
//!    [`LARGEST`]); a grid those needles would make too large is refused
//!    up front, and so is a resampling that comes out empty.
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

/// The largest triangles the area pass keeps (with their longest edges),
/// to tell needles from surface when choosing the cell size.
/// (A spike's fan is a vertex's valence, a few to a few hundred triangles.)
pub const LARGEST: usize = 1024;

/// A needle is at least this many cells long (and narrower than a cell):
/// ordinary triangles about a cell in size are not needles.
pub const NEEDLE_CELLS: f64 = 8.0;

/// Needles are left out of the area only when they hold more than this
/// share of it (the cell size then changes by more than a factor 2), so
/// that a few long slivers in an ordinary scan change nothing.
pub const NEEDLE_SHARE: f64 = 0.75;

/// How [`decimate`] reaches the in-core stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Route {
    /// Directly when the input is a clean solid that fits (see
    /// [`DIRECT_FACTOR`]), else by resampling.
    #[default]
    Auto,
    /// Simplify the input itself (read whole, welded).
    Direct,
    /// Resample to an intermediate first, whatever the input.
    Resample,
}

/// `Route::Auto` simplifies the input directly when it is a clean,
/// oriented 2-manifold (closed, or open along simple boundary loops, which
/// the collapse keeps) and has at most this many times the faces of the
/// intermediate it would resample to. The quadric collapse then sees
/// the input's own triangles: sharp edges stay sharp (a resampling rounds
/// them to the cell) and thin parts keep the shape the input gives them;
/// measured on the shared meshes and thin shapes (docs/PERFORMANCE.md,
/// `scripts/bench/thin.sh`). Larger inputs go through the resampling,
/// which bounds the in-core stage's time and memory.
pub const DIRECT_FACTOR: u64 = 4;

/// The heap a direct simplification needs per input face (the in-core
/// stage's tables, about 196 bytes per face measured on a 3.85M-face
/// intermediate since the edge lists of the indexed heap (185 before), 227
/// on the 97k-face horse, and the welding):
/// the input goes directly only when its faces fit `--mem` at this rate.
pub const DIRECT_BYTES_PER_FACE: u64 = 256;

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
    /// How much colour weighs in the collapse ([`COLOUR_WEIGHT`]).
    pub colour_weight: f64,
    /// Samples per direction of the summary's error ([`ERROR_SAMPLES`]; 0:
    /// not measured).
    pub error_samples: usize,
    /// Directly, by resampling, or chosen ([`Route`]).
    pub route: Route,
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
    /// "direct" (the input simplified itself) or "resample" (through an
    /// intermediate resampling), and why.
    pub route: &'static str,
    pub route_reason: String,
    /// The output carries per-vertex colour: the intermediate's, through
    /// colour-aware quadrics (`mint_mesh::qem::collapse_coloured`).
    pub colour: bool,
    /// The output's coordinates: "f32", or "f64" and why.
    pub output_precision: String,
    pub input_faces: u64,
    pub input_area: f64,
    /// Needle triangles (many cells long, narrower than one) left out of
    /// the area that sizes the cells, and the area they hold.
    pub needles_ignored: u64,
    pub needle_area: f64,
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
    /// The output's sampled distance to the input (or, for inputs much
    /// larger than the intermediate, to the intermediate).
    pub error: Option<SurfaceError>,
    pub seconds_area: f64,
    pub seconds_resample: f64,
    pub seconds_simplify: f64,
    pub seconds_write: f64,
    pub seconds_total: f64,
    /// Temporary files and directories that killed runs had left, removed.
    pub removed_dead: Vec<String>,
    /// The resampling's summary (none on the direct route).
    pub resample: Option<ResampleSummary>,
}

/// Decimates `inputs` (one surface, one or more files) into `output`; see
/// the module docs.
pub fn decimate(inputs: &[PathBuf], output: &Path, o: &DecimateOptions, progress: &dyn Progress) -> Result<DecimateSummary, PipelineError> {
    let Some(input) = inputs.first() else { return Err(PipelineError::stage(output, "no input file")) };
    let input = input.as_path();
    let t0 = Instant::now();
    let format = Format::from_path(output)?;
    if o.target_faces < 4 {
        return Err(PipelineError::stage(output, format!("--faces {}: a closed surface needs at least 4 faces", o.target_faces)));
    }
    let threads = o.tuning.thread_count();
    // 1. Area, then the cell size for the intermediate target.
    let t = Instant::now();
    let pass = surface_area_of(inputs, threads, progress)?;
    let (faces, area) = (pass.faces, pass.total);
    if faces == 0 || !(area > 0.0) {
        return Err(PipelineError::Empty { path: input.to_path_buf() });
    }
    if !area.is_finite() {
        return Err(PipelineError::stage(input, "the triangles' area overflows f64 (coordinates near 1e154 or beyond); scale the input down"));
    }
    let seconds_area = t.elapsed().as_secs_f64();
    // Never finer than the input itself: that adds no information.
    let m = o.intermediate_faces.unwrap_or((INTERMEDIATE_FACTOR * o.target_faces).max(INTERMEDIATE_FLOOR).min(faces)).max(o.target_faces);
    let (h, needles) = cell_size(&pass, m);
    let needle_area: f64 = needles.iter().map(|b| b.area).sum();
    // The direct route: a clean solid of a size the in-core stage takes.
    let fits = faces.saturating_mul(DIRECT_BYTES_PER_FACE) <= o.tuning.mem_bytes;
    let mut why_not = match o.route {
        Route::Resample => "asked (--route resample)".to_string(),
        Route::Direct | Route::Auto if inputs.len() > 1 => format!("{} files (the direct route reads one)", inputs.len()),
        Route::Direct => String::new(),
        Route::Auto if o.intermediate_faces.is_some() => "an intermediate size was given".to_string(),
        Route::Auto if faces > DIRECT_FACTOR * m => format!("{faces} faces, more than {DIRECT_FACTOR} x the {m} of the intermediate"),
        Route::Auto if !fits => format!("{faces} faces need about {} MiB in memory, more than --mem", faces * DIRECT_BYTES_PER_FACE >> 20),
        Route::Auto => String::new(),
    };
    if why_not.is_empty() {
        let want_colour = !o.write.no_colour && MeshWriter::holds_colour(format);
        let w = read_welded(input, true, want_colour)?;
        check_cancel(progress)?;
        let judged = mint_mesh::try_check(&w.positions, &w.tris).map_err(|e| PipelineError::stage(input, format!("judging the input: {e}")))?;
        // Clean: a 2-manifold, consistently oriented, without degenerate or
        // duplicate faces; closed, or open along simple boundary loops
        // (the collapse keeps those loops, as MeshLab does; the resampling
        // would cap them).
        let clean = judged.non_manifold_edges == 0
            && judged.non_manifold_vertices == 0
            && judged.inconsistently_oriented_edges == 0
            && judged.non_simple_boundary_edges == 0
            && judged.duplicate_faces == 0
            && judged.collapsed_faces == 0;
        if clean || o.route == Route::Direct {
            let reason = if o.route == Route::Direct {
                "asked (--route direct)".to_string()
            } else if judged.watertight {
                format!("the input is closed, 2-manifold and oriented, and its {faces} faces fit in memory: its own triangles are simplified")
            } else {
                format!(
                    "the input is a 2-manifold, oriented, open along {} boundary loop{}, and its {faces} faces fit in memory: its own triangles are simplified and its boundaries kept (--route resample closes them)",
                    judged.boundary_loops,
                    if judged.boundary_loops == 1 { "" } else { "s" }
                )
            };
            return decimate_directly(inputs, output, format, o, w, faces, area, reason, seconds_area, t0, progress);
        }
        why_not = format!(
            "the input is not a clean 2-manifold ({} non-manifold edges, {} non-manifold vertices, {} inconsistently oriented edges, {} duplicate and {} collapsed faces): the resampling repairs it",
            judged.non_manifold_edges, judged.non_manifold_vertices, judged.inconsistently_oriented_edges, judged.duplicate_faces, judged.collapsed_faces
        );
    }
    check_grid(input, &pass, h, m, &needles)?;
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
    let mut spec = RunSpec::new(mint_pipeline::Job::Resample { inputs: inputs.to_vec() }, &mid_path, GridSize::CellSize(h));
    spec.write.double = true;
    // The intermediate carries colour when the output can hold it.
    spec.write.no_colour = o.write.no_colour || !MeshWriter::holds_colour(format);
    let rs = run(&spec, &o.tuning, progress)?;
    let seconds_resample = t.elapsed().as_secs_f64();
    if let Some(why) = rs.empty_reason() {
        return Err(PipelineError::stage(input, format!("resampled at cells of {h:.3e}, the surface is empty: {why}; nothing written")));
    }
    // 3. In core: simplify and judge; 4. write.
    let t = Instant::now();
    let (positions, tris) = mint_io::read_mesh(&mid_path)?;
    let colours = vertex_colours(&mid_path)?;
    drop((owner, mid));
    // The intermediate's vertices lie on the input and its faces are chords
    // of it: its quadrics take the lifted planes.
    let so = mint_mesh::SimplifyOptions { target_faces: o.target_faces, max_error: o.max_error, planes: mint_mesh::qem::Planes::Lifted };
    let tolerance = h * mint_pipeline::spec::defaults::F32_TOLERANCE_CELLS;
    let colour = colours.is_some();
    // The error against the input itself when it is not much larger than
    // the intermediate, else against the intermediate.
    let reference = if faces as usize <= ERROR_INPUT_FACTOR * tris.len().max(1) { Reference::Files(inputs) } else { Reference::Own("intermediate") };
    let (sr, output_precision, _, seconds_write, error) = simplify_and_write(input, output, format, &o.write.options(None, colour), tolerance, positions, tris, colours, o.colour_weight, &so, reference, o.error_samples, progress)?;
    // Reading the intermediate counts as simplifying.
    let seconds_simplify = t.elapsed().as_secs_f64() - seconds_write;
    let base = summary_of(inputs, output, o, ("resample", why_not), (faces, area, colour), (sr, output_precision, seconds_simplify, seconds_write, error), seconds_area, t0);
    Ok(DecimateSummary {
        needles_ignored: needles.len() as u64,
        needle_area,
        cell_size: h,
        intermediate_faces_asked: m,
        intermediate_faces: rs.output_faces,
        seconds_resample,
        removed_dead: removed_dead.iter().map(|p| p.display().to_string()).chain(rs.removed_dead.iter().cloned()).collect(),
        resample: Some(rs),
        ..base
    })
}

/// The summary of a decimation whose in-core stage reported `done`, on
/// the direct route (the resampling's fields empty; the resample route
/// fills them in).
#[allow(clippy::type_complexity)]
fn summary_of(
    inputs: &[PathBuf],
    output: &Path,
    o: &DecimateOptions,
    (route, route_reason): (&'static str, String),
    (input_faces, input_area, colour): (u64, f64, bool),
    (sr, output_precision, seconds_simplify, seconds_write, error): (mint_mesh::SimplifyReport, String, f64, f64, Option<SurfaceError>),
    seconds_area: f64,
    t0: Instant,
) -> DecimateSummary {
    DecimateSummary {
        input: mint_pipeline::spec::files_name(inputs),
        output: output.display().to_string(),
        route,
        route_reason,
        output_precision,
        input_faces,
        input_area,
        needles_ignored: 0,
        needle_area: 0.0,
        cell_size: 0.0,
        intermediate_faces_asked: 0,
        intermediate_faces: sr.input_faces,
        output_faces: sr.output_faces,
        output_vertices: sr.output_vertices,
        colour,
        target_faces: o.target_faces,
        simplify_error: sr.error,
        intermediate_watertight: sr.input_watertight,
        output_watertight: sr.output_watertight,
        relaxed: sr.relaxed,
        folded_pairs_removed: sr.folded_pairs_removed,
        error,
        seconds_area,
        seconds_resample: 0.0,
        seconds_simplify,
        seconds_write,
        seconds_total: t0.elapsed().as_secs_f64(),
        removed_dead: Vec::new(),
        resample: None,
    }
}

/// The direct route of [`decimate`]: the input (read whole and welded,
/// `w`) simplified itself.
#[allow(clippy::too_many_arguments)]
fn decimate_directly(
    inputs: &[PathBuf],
    output: &Path,
    format: Format,
    o: &DecimateOptions,
    w: Welded,
    faces: u64,
    area: f64,
    route_reason: String,
    seconds_area: f64,
    t0: Instant,
    progress: &dyn Progress,
) -> Result<DecimateSummary, PipelineError> {
    let input = inputs[0].as_path();
    let so = mint_mesh::SimplifyOptions { target_faces: o.target_faces, max_error: o.max_error, ..Default::default() };
    let tolerance = tolerance_of(&w.positions);
    let colour = w.colours.is_some();
    let t = Instant::now();
    let (sr, output_precision, _, seconds_write, error) =
        simplify_and_write(input, output, format, &o.write.options(None, colour), tolerance, w.positions, w.tris, w.colours, o.colour_weight, &so, Reference::Own("input"), o.error_samples, progress)?;
    let seconds_simplify = t.elapsed().as_secs_f64() - seconds_write;
    Ok(summary_of(inputs, output, o, ("direct", route_reason), (faces, area, colour), (sr, output_precision, seconds_simplify, seconds_write, error), seconds_area, t0))
}

/// A mesh file read whole for the in-core stage: welded (optionally),
/// with its per-vertex colours when wanted and present.
struct Welded {
    positions: Vec<[f64; 3]>,
    tris: Vec<[u32; 3]>,
    colours: Option<Vec<[u8; 4]>>,
    welded: u64,
}

/// Reads `input` whole and welds vertices at identical positions (`weld`);
/// each welded vertex keeps one of its copies' colours (the output's come
/// from the colour quadrics anyway).
fn read_welded(input: &Path, weld: bool, want_colour: bool) -> Result<Welded, PipelineError> {
    let (mut positions, mut tris) = mint_io::read_mesh(input)?;
    if tris.is_empty() {
        return Err(PipelineError::Empty { path: input.to_path_buf() });
    }
    let mut colours = if want_colour { vertex_colours(input)? } else { None };
    let welded = if weld {
        let before = positions.clone();
        let n = mint_mesh::weld(&mut positions, &mut tris);
        if let Some(c) = colours.as_mut() {
            *c = rekey_colours(&before, &positions, c);
        }
        n
    } else {
        0
    };
    Ok(Welded { positions, tris, colours, welded })
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
    colours: Option<Vec<[u8; 4]>>,
    colour_weight: f64,
    so: &mint_mesh::SimplifyOptions,
    reference: Reference,
    error_samples: usize,
    progress: &dyn Progress,
) -> Result<(mint_mesh::SimplifyReport, String, f64, f64, Option<SurfaceError>), PipelineError> {
    let t = Instant::now();
    let err = |e| match e {
        mint_mesh::MeshError::Cancelled => PipelineError::Cancelled,
        e => PipelineError::stage(input, format!("simplifying: {e}")),
    };
    let stop = || progress.cancelled();
    let (p, f, out_colours, sr) = match &colours {
        // Colour-aware quadrics: they place each kept vertex and give its
        // colour.
        Some(c) => {
            let (p, f, qc, sr) = mint_mesh::simplify_coloured(&positions, &tris, c, colour_weight, so, &stop).map_err(err)?;
            (p, f, Some(qc), sr)
        }
        None => {
            let (p, f, sr) = mint_mesh::simplify_with(&positions, &tris, so, &stop).map_err(err)?;
            (p, f, None, sr)
        }
    };
    drop(colours);
    let seconds_simplify = t.elapsed().as_secs_f64();
    check_cancel(progress)?;
    let error = match reference {
        _ if error_samples == 0 => None,
        Reference::Own(name) => Some(surface_error(input, name, (&positions, &tris), (&p, &f), error_samples)?),
        Reference::Files(files) => {
            drop((positions, tris));
            let (rp, rf) = read_whole(files)?;
            Some(surface_error(input, "input", (&rp, &rf), (&p, &f), error_samples)?)
        }
    };
    check_cancel(progress)?;
    let t = Instant::now();
    let (lo, hi) = bbox(&p);
    let (double, precision) = mint_io::precision::choose(output, format, write.double, lo, hi, tolerance)?;
    let mut w = MeshWriter::create(output, format, WriteOptions { double, ..write.clone() })?;
    match &out_colours {
        Some(c) => {
            for (v, c) in p.iter().zip(c) {
                w.write_vertex_rgba(*v, *c)?;
            }
        }
        None => {
            for v in &p {
                w.write_vertex(*v)?;
            }
        }
    }
    for t in &f {
        w.write_face(*t)?;
    }
    w.finish()?;
    Ok((sr, precision, seconds_simplify, t.elapsed().as_secs_f64(), error))
}

/// How much colour weighs in the collapse by default: a full-range colour
/// difference across a face costs what a distance of this fraction of the
/// extent does. Measured (docs/PERFORMANCE.md) on two colour scans and a
/// 2M-face sphere with sharp colour borders every quarter unit, at 10% and
/// 1% of the faces: from 0.0003 to 0.03 the colour error is below
/// MeshLab's everywhere; at 0.0003 the geometric error stays within 5% of
/// the colourless collapse's (0.001: up to +19%, 0.01: up to +100% on the
/// sphere, whose borders then hold vertices the shape needs).
pub const COLOUR_WEIGHT: f64 = 0.0003;

/// Samples per direction of the error in the summaries (the default of
/// `--error-samples`): the mean to about
/// 1%, the max a lower bound that finds deviations covering 1/50,000 of
/// the area. Measured on Igea (268k faces to 27k): 2 × 50k samples with
/// both trees cost 0.1 s.
pub const ERROR_SAMPLES: usize = 50_000;

/// An input read whole for the error may have at most this many times the
/// faces of the mesh the in-core stage already holds (else the error is
/// measured against that mesh, the intermediate, and says so).
pub const ERROR_INPUT_FACTOR: usize = 2;

/// The output's sampled distance to a reference surface, both ways
/// (Metro, `mint_mesh::symmetric_distance`): what a target costs, without
/// running `mint distance`.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceError {
    /// What the output is measured against: "input", or "intermediate"
    /// (the resampled mesh, when the input is too large to read whole).
    pub reference: &'static str,
    /// Samples per direction.
    pub samples: u64,
    /// The larger of the two directions' mean distances, and the largest
    /// sampled distance (a lower bound of the Hausdorff distance).
    pub mean: f64,
    pub max: f64,
    /// `mean` and `max` relative to the reference's bounding-box diagonal.
    pub mean_rel: f64,
    pub max_rel: f64,
    pub seconds: f64,
}

/// The sampled two-sided distance between `out` and `reference`.
fn surface_error(input: &Path, name: &'static str, reference: mint_mesh::MeshRef, out: mint_mesh::MeshRef, samples: usize) -> Result<SurfaceError, PipelineError> {
    let t = Instant::now();
    let (ab, ba) = mint_mesh::try_symmetric_distance(reference, out, samples, 1).map_err(|e| PipelineError::stage(input, format!("measuring the error: {e}")))?;
    let diagonal = ab.bbox_diagonal.max(ba.bbox_diagonal);
    let (mean, max) = (ab.mean.max(ba.mean), ab.max.max(ba.max));
    let rel = |x: f64| if diagonal > 0.0 { x / diagonal } else { 0.0 };
    Ok(SurfaceError { reference: name, samples: samples as u64, mean, max, mean_rel: rel(mean), max_rel: rel(max), seconds: t.elapsed().as_secs_f64() })
}

/// The surface the output is measured against: the in-core stage's own
/// input, or files read whole after the collapse.
enum Reference<'a> {
    Own(&'static str),
    Files(&'a [PathBuf]),
}

/// Several files of one surface read whole, as one mesh.
fn read_whole(files: &[PathBuf]) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>), PipelineError> {
    let (mut p, mut f) = (Vec::new(), Vec::new());
    for file in files {
        let (fp, ff) = mint_io::read_mesh(file)?;
        let base = p.len() as u32;
        f.extend(ff.iter().map(|t| t.map(|i| i + base)));
        p.extend(fp);
    }
    Ok((p, f))
}

/// A mesh file's per-vertex colours, if it has them.
fn vertex_colours(path: &Path) -> Result<Option<Vec<[u8; 4]>>, PipelineError> {
    Ok(mint_io::read_vertex_colours(path)?)
}

/// The colours of welded vertices: `after[i]` takes the colour of the
/// first vertex of `before` at its exact position.
fn rekey_colours(before: &[[f64; 3]], after: &[[f64; 3]], colours: &[[u8; 4]]) -> Vec<[u8; 4]> {
    use mint_mesh::weld::position_key;
    let mut first: std::collections::HashMap<[u64; 3], usize> = std::collections::HashMap::with_capacity(before.len());
    for (i, p) in before.iter().enumerate() {
        first.entry(position_key(p)).or_insert(i);
    }
    after.iter().map(|p| first.get(&position_key(p)).map_or([255; 4], |&i| colours[i])).collect()
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
    /// How much colour weighs in the collapse ([`COLOUR_WEIGHT`]).
    pub colour_weight: f64,
    /// Samples per direction of the summary's error ([`ERROR_SAMPLES`]; 0:
    /// not measured).
    pub error_samples: usize,
}

/// What [`simplify_file`] did.
#[derive(Debug, Clone, Serialize)]
pub struct SimplifySummary {
    pub input: String,
    pub output: String,
    /// The output carries per-vertex colour (the input's, through
    /// colour-aware quadrics).
    pub colour: bool,
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
    /// The output's sampled distance to the input (as welded).
    pub error: Option<SurfaceError>,
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
    let want_colour = o.write.colours && MeshWriter::holds_colour(format);
    let Welded { positions, tris, colours, welded } = read_welded(input, o.weld, want_colour)?;
    let (input_faces, input_vertices) = (tris.len() as u64, positions.len() as u64 + welded);
    let seconds_read = t0.elapsed().as_secs_f64();
    check_cancel(progress)?;
    let so = mint_mesh::SimplifyOptions { target_faces: o.target_faces, max_error: o.max_error, ..Default::default() };
    let tolerance = tolerance_of(&positions);
    let colour = colours.is_some();
    let write = WriteOptions { colours: colour, ..o.write.clone() };
    let (sr, output_precision, seconds_simplify, seconds_write, error) = simplify_and_write(input, output, format, &write, tolerance, positions, tris, colours, o.colour_weight, &so, Reference::Own("input"), o.error_samples, progress)?;
    Ok(SimplifySummary {
        input: input.display().to_string(),
        output: output.display().to_string(),
        colour,
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
        error,
        seconds_read,
        seconds_simplify,
        seconds_write,
        seconds_total: t0.elapsed().as_secs_f64(),
    })
}

/// Refuses, before any resampling, a grid of cells of `h` around the input
/// that the engine could not hold; names the needles that stretch it.
fn check_grid(input: &Path, pass: &AreaPass, h: f64, m: u64, needles: &[Big]) -> Result<(), PipelineError> {
    let Err(e) = mint_core::grid::Grid::around(pass.min, pass.max, GridSize::CellSize(h), [0.0; 3], None) else { return Ok(()) };
    let far: Vec<&Big> = if needles.is_empty() { pass.largest.iter().filter(|b| b.is_needle(h)).collect() } else { needles.iter().collect() };
    let e = match e {
        mint_core::grid::GridError::TooManyCells { dims, .. } => format!("the box would be {}x{}x{} cells, more than the engine addresses", dims[0], dims[1], dims[2]),
        e => e.to_string(),
    };
    let why = match far.first() {
        Some(b) => format!(
            "; {} needle triangle{} (many cells long, narrower than one) stretch{} the box: the largest, face {}, is {:.3e} long and {:.3e} wide (a spike or a stray vertex?); remove {} and run again",
            far.len(),
            if far.len() == 1 { "" } else { "s" },
            if far.len() == 1 { "es" } else { "" },
            b.face,
            b.longest_edge,
            b.width(),
            if far.len() == 1 { "it" } else { "them" }
        ),
        None => "; pass --intermediate with fewer faces for larger cells".to_string(),
    };
    Err(PipelineError::stage(input, format!("cells of {h:.3e} (for about {m} intermediate faces) do not fit its bounding box: {e}{why}")))
}

/// One of the largest triangles of the input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Big {
    pub area: f64,
    /// Its index among the input's triangles (polygons count as their fans).
    pub face: u64,
    pub longest_edge: f64,
}

impl Big {
    /// Twice the area over the longest edge: the triangle's narrowest width.
    pub fn width(&self) -> f64 {
        if self.longest_edge > 0.0 { 2.0 * self.area / self.longest_edge } else { 0.0 }
    }

    /// At least [`NEEDLE_CELLS`] cells of `h` long and narrower than one:
    /// it vanishes in the resampling, whatever its area.
    pub fn is_needle(&self, h: f64) -> bool {
        self.longest_edge > NEEDLE_CELLS * h && self.width() < h
    }
}

/// What the area pass learns of the input.
#[derive(Debug, Clone)]
pub struct AreaPass {
    pub faces: u64,
    pub total: f64,
    pub min: [f64; 3],
    pub max: [f64; 3],
    /// The [`LARGEST`] largest triangles, largest first (ties: lower index first).
    pub largest: Vec<Big>,
}

/// Per chunk: the sum, the box and the largest triangles.
struct ChunkArea {
    sum: f64,
    min: [f64; 3],
    max: [f64; 3],
    /// Candidates for the largest triangles (unsorted; every triangle
    /// among the chunk's [`LARGEST`] largest so far is in).
    largest: Vec<Big>,
    /// The area a triangle must exceed to be a candidate: the
    /// [`LARGEST`]-th largest at the last pruning (a later triangle of the
    /// same area ranks after it).
    threshold: f64,
}

impl ChunkArea {
    fn new() -> ChunkArea {
        ChunkArea { sum: 0.0, min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3], largest: Vec::new(), threshold: f64::NEG_INFINITY }
    }
    #[inline]
    fn add(&mut self, face: u64, p: &[[f64; 3]; 3]) {
        let (u, v) = ([p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]], [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]]);
        let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let area = 0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        self.sum += area;
        for q in p {
            for d in 0..3 {
                self.min[d] = self.min[d].min(q[d]);
                self.max[d] = self.max[d].max(q[d]);
            }
        }
        // (Pruned by selection every 8 x LARGEST candidates, not sorted
        // every LARGEST: on a 100M-face generated torus the sorts were 11%
        // of the area pass's samples; two runs each: 2.30
        // and 2.66 s against 2.70 and 2.83 s, the same output.)
        if area > self.threshold || self.largest.len() < LARGEST {
            let len = |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            let longest_edge = len(p[0], p[1]).max(len(p[1], p[2])).max(len(p[2], p[0]));
            self.largest.push(Big { area, face, longest_edge });
            if self.largest.len() >= 8 * LARGEST {
                self.largest.select_nth_unstable_by(LARGEST - 1, rank);
                self.largest.truncate(LARGEST);
                self.threshold = self.largest[LARGEST - 1].area;
            }
        }
    }
}

/// Sorts largest first (ties by index, so the result does not depend on the
/// order chunks are merged in) and keeps [`LARGEST`].
fn keep_largest(v: &mut Vec<Big>) {
    v.sort_by(rank);
    v.truncate(LARGEST);
}

/// Largest first, ties by index.
fn rank(a: &Big, b: &Big) -> std::cmp::Ordering {
    b.area.total_cmp(&a.area).then(a.face.cmp(&b.face))
}

/// The area pass over the files of one surface, merged in file order (a
/// triangle's index counts on through the files).
pub fn surface_area_of(paths: &[PathBuf], threads: usize, progress: &dyn Progress) -> Result<AreaPass, PipelineError> {
    let mut all = AreaPass { faces: 0, total: 0.0, min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3], largest: Vec::new() };
    for (k, p) in paths.iter().enumerate() {
        let pass = surface_area(p, threads, progress).map_err(|e| mint_pipeline::error::in_file_list(e, k, paths.len()))?;
        all.total += pass.total;
        for d in 0..3 {
            all.min[d] = all.min[d].min(pass.min[d]);
            all.max[d] = all.max[d].max(pass.max[d]);
        }
        all.largest.extend(pass.largest.iter().map(|b| Big { face: b.face + all.faces, ..*b }));
        keep_largest(&mut all.largest);
        all.faces += pass.faces;
    }
    Ok(all)
}

/// The area pass over `path`: the triangles' count, total area (summed per
/// chunk in chunk order: the same for any thread count), box and largest
/// triangles, in one streaming pass (workers over fixed-size records when
/// the file has them, else the reader).
pub fn surface_area(path: &Path, threads: usize, progress: &dyn Progress) -> Result<AreaPass, PipelineError> {
    let read = mint_io::ReadOptions { chunk_triangles: CHUNK_TRIANGLES, spill_dir: None, resolve_positions: true };
    let mut reader = MeshReader::open(path, read)?;
    // Sums in chunk order; the largest triangles merged as chunks end (their
    // order is total, so the merge order does not matter).
    let largest = Mutex::new(Vec::new());
    let add = |pass: &mut AreaPass, c: ChunkArea| {
        pass.total += c.sum;
        for d in 0..3 {
            pass.min[d] = pass.min[d].min(c.min[d]);
            pass.max[d] = pass.max[d].max(c.max[d]);
        }
    };
    let take_largest = |mut c: ChunkArea| {
        let mut l = largest.lock().unwrap();
        l.append(&mut c.largest);
        keep_largest(&mut l);
        c
    };
    let mut pass = AreaPass { faces: 0, total: 0.0, min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3], largest: Vec::new() };
    if let Some(records) = reader.triangle_records()? {
        let n = records.len();
        let chunks = n.div_ceil(CHUNK_TRIANGLES as u64);
        progress.start(BOUNDS, n);
        let sums: Mutex<Vec<Option<ChunkArea>>> = Mutex::new((0..chunks).map(|_| None).collect());
        mint_core::pool::for_each(threads, chunks, |_| (), |_, c| {
            if progress.cancelled() {
                return Err(PipelineError::Cancelled);
            }
            let (a, b) = (c * CHUNK_TRIANGLES as u64, ((c + 1) * CHUNK_TRIANGLES as u64).min(n));
            let mut acc = ChunkArea::new();
            let mut face = a;
            records.visit(a, b, &mut |p: &[[f64; 3]; 3]| {
                acc.add(face, p);
                face += 1;
            })?;
            let acc = take_largest(acc);
            sums.lock().unwrap()[c as usize] = Some(acc);
            progress.advance(b - a);
            Ok(())
        })?;
        check_cancel(progress)?;
        progress.finish();
        for c in sums.into_inner().unwrap().into_iter().flatten() {
            add(&mut pass, c);
        }
        pass.faces = n;
        pass.largest = largest.into_inner().unwrap();
        return Ok(pass);
    }
    progress.start(BOUNDS, reader.info().face_count.unwrap_or(0));
    let mut faces = 0u64;
    let mut chunk = TriangleChunk::new();
    while reader.next_chunk(&mut chunk)? {
        check_cancel(progress)?;
        let mut acc = ChunkArea::new();
        for (i, p) in chunk.positions.iter().enumerate() {
            acc.add(faces + i as u64, p);
        }
        let acc = take_largest(acc);
        add(&mut pass, acc);
        faces += chunk.len() as u64;
        progress.advance(chunk.len() as u64);
    }
    progress.finish();
    pass.faces = faces;
    pass.largest = largest.into_inner().unwrap();
    Ok(pass)
}

/// The cell size for about `m` intermediate faces: `h = √(K·A/m)`, with the
/// needles among the largest triangles ([`Big::is_needle`]: they vanish in
/// the resampling) left out of `A` when they hold more
/// than [`NEEDLE_SHARE`] of it. Returns `h` and the needles left out.
pub fn cell_size(pass: &AreaPass, m: u64) -> (f64, Vec<Big>) {
    let of = |area: f64| (FACES_PER_AREA_CELL * area / m as f64).sqrt();
    let h0 = of(pass.total);
    let (mut h, mut needles) = (h0, Vec::new());
    // Needles at h; h from the rest; again, until the set settles.
    for _ in 0..16 {
        let now: Vec<Big> = pass.largest.iter().filter(|b| b.is_needle(h)).copied().collect();
        let held: f64 = now.iter().map(|b| b.area).sum();
        let rest = pass.total - held;
        if !(held > NEEDLE_SHARE * pass.total) || !(rest > 0.0) {
            // Not (or no longer) needles holding most of the area: keep the
            // last size at which they did, or the plain one.
            return if needles.is_empty() { (h0, Vec::new()) } else { (h, needles) };
        }
        let next = of(rest);
        let settled = now == needles && next == h;
        (h, needles) = (next, now);
        if settled {
            break;
        }
    }
    (h, needles)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The area pass's largest triangles are the [`LARGEST`] largest by
    /// (area, then index), whatever the prunings: areas with many ties,
    /// rising along the file as a generated mesh's do.
    #[test]
    fn the_largest_triangles_survive_the_prunings() {
        let mut acc = ChunkArea::new();
        let mut all = Vec::new();
        let mut x: u64 = 12345;
        for face in 0..40_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let s = ((x >> 40) % 64) as f64 / 8.0 + face as f64 * 1e-4 * ((x >> 20) % 2) as f64;
            let p = [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, 2.0, 0.0]];
            acc.add(face, &p);
            all.push(Big { area: s, face, longest_edge: 0.0 });
        }
        let mut got = acc.largest;
        keep_largest(&mut got);
        keep_largest(&mut all);
        let key = |v: &[Big]| v.iter().map(|b| (b.area.to_bits(), b.face)).collect::<Vec<_>>();
        assert_eq!(key(&got), key(&all));
    }
}
