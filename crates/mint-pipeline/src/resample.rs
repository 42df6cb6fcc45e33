//! `resample`: out-of-core Marching Intersections (Rocchini et al. 2001).
//!
//! Data flow:
//! 1. **Bounds.** Vertex positions are read from the reader's memory map to
//!    find the bounding box; the [`Grid`] is chosen around it.
//! 2. **Discretize.** The reader thread streams chunks of triangles with
//!    positions resolved; worker threads map them to local grid coordinates
//!    and discretize them ([`discretize_triangle`]); a writer thread appends
//!    the [`Intercept`] records to the [`ShardStore`], one shard per group of
//!    slab-axis planes. Nothing here grows with the input but the shards.
//! 3. **Plan.** The store's per-plane counts decide the slabs: consecutive
//!    layers whose records fit the memory budget (or `--slab K` layers).
//! 4. **Reconstruct.** Worker threads take slabs in order, read their planes
//!    back, sort and filter them, and reconstruct them
//!    ([`reconstruct_slab`]). Results carry their slab number; the main
//!    thread writes them strictly in order (vertices to the output, faces to
//!    a spill file), and a window keeps at most `threads + 1` slabs in memory.
//! 5. **Write.** Faces are appended after the vertices and the output is
//!    renamed into place.
//!
//! Vertex ids depend only on the grid and the input (see
//! `mint_core::reconstruct`), so the output bytes are the same for any
//! thread count, memory budget or slab size.

use crate::progress::{Phase, Progress};
use mint_core::grid::{Axis, Grid, GridError, GridSize};
use mint_core::primitives::Transform;
use mint_core::intercept::filter_plane;
use mint_core::reconstruct::{crossing_to_intercept, reconstruct_slab, SlabResult};
use mint_core::holes::{open_cells, OpenCells};
use mint_core::robust::{census_plane, reconstruct_slab_solids, Expr};
use mint_core::signs::{LineCensus, RepairStats, SignRule};
use mint_core::{discretize_triangle, FilterStats, Intercept};
use mint_io::{Format, MeshReader, MeshWriter, ReadOptions, TriangleChunk, WriteOptions};
use crate::output::OrderedOutput;
use mint_store::{ShardStore, StoreError};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Instant;

/// Triangles per chunk handed from the reader to the workers.
const CHUNK_TRIANGLES: usize = 64 * 1024;
/// Estimated heap bytes per stored record while its slab is reconstructed:
/// the record, its vertex, about two faces, active-cell ids, and slack.
pub const BYTES_PER_RECORD_IN_SLAB: u64 = 128;
/// Heap kept aside for channels, chunk buffers and shard write buffers.
const FIXED_RESERVE: u64 = 48 << 20;

/// Options of a resampling run. `Default` gives the documented defaults.
#[derive(Debug, Clone)]
pub struct ResampleOptions {
    /// Grid size (no default: the CLI requires `--cells` or `--cell-size`).
    pub size: GridSize,
    /// Heap budget in bytes; decides slab thickness. Default: 2 GiB.
    pub mem_bytes: u64,
    /// Worker threads; 0 means all cores. Default 0.
    pub threads: usize,
    /// Directory for temporary files. Default: the output's directory.
    pub tmp_dir: Option<PathBuf>,
    /// Slab axis; `None` picks the longest grid axis. Default `None`.
    pub axis: Option<Axis>,
    /// Force slabs of this many layers (tests, tuning). Default: budget decides.
    pub slab_layers: Option<u32>,
    /// Grid shift in fractions of a cell. Default zero.
    pub grid_offset: [f64; 3],
    /// How the output is encoded. Default: binary PLY, f32.
    pub write: WriteOptions,
    /// How many non-canonical cells to list in the summary. Default 100.
    pub max_listed: usize,
    /// How intercept signs become inside/outside states (see
    /// `mint_core::signs`). Default `Auto`: robust, state-first
    /// reconstruction whose output is always closed; `Orient` is the paper's
    /// strict rule, which leaves non-canonical cells open.
    pub signs: SignRule,
    /// Robust rules: holes whose capping cells span more than this many
    /// cells along some axis are left open (a clean boundary loop); `None`
    /// closes every hole. Default `Some(16)`.
    pub max_hole: Option<u32>,
}

impl Default for ResampleOptions {
    fn default() -> Self {
        ResampleOptions {
            size: GridSize::Cells(1_000_000),
            mem_bytes: 2 << 30,
            threads: 0,
            tmp_dir: None,
            axis: None,
            slab_layers: None,
            grid_offset: [0.0; 3],
            write: WriteOptions::default(),
            max_listed: 100,
            signs: SignRule::Auto,
            max_hole: Some(16),
        }
    }
}

/// Everything a run measured; printed by the CLI and as JSON.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ResampleSummary {
    pub input: String,
    pub output: String,
    pub input_vertices: u64,
    pub input_faces: u64,
    /// Signed volume enclosed by the input (negative: inside-out).
    pub input_signed_volume: f64,
    /// True when the input was inside-out and its signs were reversed.
    pub orientation_inverted: bool,
    pub grid_cells: [u32; 3],
    pub cell_size: f64,
    pub grid_origin: [f64; 3],
    pub slab_axis: char,
    pub slabs: u64,
    pub threads: usize,
    pub intercepts_found: u64,
    pub intercepts_removed: u64,
    pub intercepts_kept: u64,
    pub shard_bytes: u64,
    pub active_cells: u64,
    pub output_vertices: u64,
    pub output_faces: u64,
    pub non_canonical_cells: u64,
    /// Up to `max_listed` non-canonical cells, as (x, y, z) cell indices.
    pub non_canonical_list: Vec<[u32; 3]>,
    /// Seconds per phase.
    pub seconds_bounds: f64,
    pub seconds_discretize: f64,
    pub seconds_reconstruct: f64,
    pub seconds_write: f64,
    pub seconds_total: f64,
    /// Largest planned slab, in estimated heap bytes.
    pub planned_slab_bytes: u64,
    /// The sign rule used (`auto` resolved to `union` or `parity`).
    pub sign_rule: String,
    /// A and B lines with intercepts, winding-valid ones, odd ones (auto's census).
    pub census_lines: u64,
    pub census_winding_valid: u64,
    pub census_odd: u64,
    /// Lines through holes whose nodes took states from elsewhere.
    pub inconsistent_lines: u64,
    /// Vertices made at edge midpoints where states change but no intercept
    /// exists (hole closing).
    pub synthesized_vertices: u64,
    /// Edges whose several same-sign intercepts were merged (overlapping layers).
    pub merged_edges: u64,
    /// Intercepts on edges without a state change, dropped.
    pub dropped_intercepts: u64,
    pub seconds_census: f64,
    /// Holes (groups of capping cells) closed, and left open by `max_hole`.
    pub holes_closed: u64,
    pub holes_left_open: u64,
    /// Cells left open around those holes.
    pub open_cells: u64,
}

impl ResampleSummary {
    /// Records what reconstruction did (repair counters, output counts,
    /// the phase's time since `t`); shared by resample and csg.
    pub(crate) fn record_reconstruction(&mut self, repair: &RepairStats, out: &OrderedOutput, t: Instant) {
        self.inconsistent_lines = repair.inconsistent_lines;
        self.synthesized_vertices = repair.synthesized_vertices;
        self.merged_edges = repair.merged_edges;
        self.dropped_intercepts = repair.dropped_intercepts;
        self.output_vertices = out.vertices;
        self.output_faces = out.faces;
        self.seconds_reconstruct = t.elapsed().as_secs_f64();
    }

    /// Appends the faces after the vertices and renames the output into
    /// place, recording the write time and the total since `t_start`.
    pub(crate) fn finish_output(&mut self, out: OrderedOutput, progress: &dyn Progress, t_start: Instant) -> Result<(), PipelineError> {
        let t = Instant::now();
        out.finish(progress)?;
        self.seconds_write = t.elapsed().as_secs_f64();
        self.seconds_total = t_start.elapsed().as_secs_f64();
        Ok(())
    }
}

/// Why a run failed. Each variant's text is one line naming the file.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Reading the input or writing the output failed (bad input, full disk…).
    #[error(transparent)]
    Io(#[from] mint_io::Error),
    /// The temporary shard store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The grid cannot be built; the message says which option to change.
    #[error("{path}: {source}")]
    Grid { path: PathBuf, source: GridError },
    /// A vertex position is NaN or infinite.
    #[error("{path}: vertex {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinite { path: PathBuf, index: u64, x: f64, y: f64, z: f64 },
    /// The input has no triangles.
    #[error("{path}: the mesh has no triangles to resample")]
    Empty { path: PathBuf },
    /// A temporary file outside the store failed.
    #[error("{path}: {op}: {source}")]
    Temp { path: PathBuf, op: &'static str, source: std::io::Error },
    /// A CSG scene whose result is unbounded (e.g. a lone half-space).
    #[error("{path}: the scene is unbounded (intersect half-spaces with a bounded solid)")]
    Unbounded { path: PathBuf },
    /// A range image could not be turned into a mesh.
    #[error("{path}: {message}")]
    Range { path: PathBuf, message: String },
    /// The user interrupted the run; temporary files were removed.
    #[error("interrupted; no output written")]
    Cancelled,
}

/// Resamples `input` into `output` on the grid `opts.size`.
pub fn resample(input: &Path, output: &Path, opts: &ResampleOptions, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let t_start = Instant::now();
    let threads = if opts.threads == 0 {
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    } else {
        opts.threads
    };
    let tmp_root = match &opts.tmp_dir {
        Some(d) => d.clone(),
        None => output.parent().filter(|p| !p.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
    };
    let out_format = Format::from_path(output)?;
    let read_opts = ReadOptions { chunk_triangles: CHUNK_TRIANGLES, spill_dir: Some(tmp_root.clone()), resolve_positions: false };
    let mut reader = MeshReader::open(input, read_opts.clone())?;
    // A PLY range image (a grid of samples, no faces) is triangulated first,
    // as one scan is (mint-range: shorter diagonal, no bridging of depth
    // jumps), into a temporary mesh removed when the run ends.
    let _range_mesh;
    if reader.range_grid().is_some() && reader.info().face_count.unwrap_or(0) == 0 {
        let scan = mint_range::load_scan(input, &mint_range::MeshOptions::default())
            .map_err(|e| PipelineError::Range { path: input.to_path_buf(), message: e.to_string() })?;
        let tmp = tempfile::Builder::new().prefix(".mint-range-").suffix(".ply").tempfile_in(&tmp_root).map_err(|source| PipelineError::Temp {
            path: tmp_root.clone(),
            op: "creating the range-image mesh",
            source,
        })?;
        let mut w = MeshWriter::create(tmp.path(), Format::Ply, WriteOptions { double: true, ..Default::default() })?;
        for p in &scan.positions {
            w.write_vertex(*p)?;
        }
        for f in &scan.faces {
            w.write_face(*f)?;
        }
        w.finish()?;
        reader = MeshReader::open(tmp.path(), read_opts)?;
        _range_mesh = tmp;
    }
    let mut summary = ResampleSummary {
        input: input.display().to_string(),
        output: output.display().to_string(),
        input_vertices: reader.vertex_count() as u64,
        threads,
        ..Default::default()
    };

    // 1. Bounds and grid.
    let t = Instant::now();
    let (lo, hi) = bounds(&reader, input, threads, progress, None)?;
    let grid = Grid::around(lo, hi, opts.size, opts.grid_offset, opts.axis)
        .map_err(|source| PipelineError::Grid { path: input.to_path_buf(), source })?;
    summary.seconds_bounds = t.elapsed().as_secs_f64();
    summary.grid_cells = grid.dims;
    summary.cell_size = grid.cell;
    summary.grid_origin = grid.origin;
    summary.slab_axis = ['x', 'y', 'z'][grid.slab_axis];
    check_cancel(progress)?;

    // 2. Discretize into the shard store.
    let t = Instant::now();
    let [_, _, ns] = grid.local_dims();
    let mut store = ShardStore::create(&tmp_root, ns + 1)?;
    let (faces, volume) = discretize_all(&mut reader, &grid, &mut store, threads, progress, None)?;
    summary.input_faces = faces;
    summary.input_signed_volume = volume * grid.cell.powi(3);
    // An inside-out input (negative volume) has every sign reversed: read it
    // as the solid it encloses, so the output faces outward.
    let invert = volume < 0.0;
    summary.orientation_inverted = invert;
    if summary.input_faces == 0 {
        return Err(PipelineError::Empty { path: input.to_path_buf() });
    }
    store.finish_writing()?;
    drop(reader);
    summary.intercepts_found = store.plane_counts().iter().sum();
    summary.shard_bytes = store.bytes_written();
    summary.seconds_discretize = t.elapsed().as_secs_f64();
    check_cancel(progress)?;

    // 3. Plan slabs.
    let slab_budget = opts.mem_bytes.saturating_sub(FIXED_RESERVE) / (threads as u64 + 2);
    let slabs = plan_slabs(store.plane_counts(), ns, opts.slab_layers, slab_budget);
    summary.slabs = slabs.len() as u64;
    summary.planned_slab_bytes = slabs
        .iter()
        .map(|&(k0, k1)| store.plane_counts()[k0 as usize..=k1 as usize].iter().sum::<u64>() * BYTES_PER_RECORD_IN_SLAB)
        .max()
        .unwrap_or(0);

    // 3b. Resolve the sign rule (auto: a census of all A/B lines).
    let t = Instant::now();
    let rule = match opts.signs {
        SignRule::Auto => {
            let mut census = LineCensus::default();
            for &(k0, k1) in &slabs {
                let mut planes = store.read_planes(k0, k1 - 1, false)?;
                for p in &mut planes {
                    if invert {
                        for r in p.iter_mut() {
                            r.signed_value = -r.signed_value;
                        }
                    }
                    census += census_plane(p);
                }
                check_cancel(progress)?;
            }
            summary.census_lines = census.lines;
            summary.census_winding_valid = census.winding_valid;
            summary.census_odd = census.odd;
            census.resolve()
        }
        r => r,
    };
    summary.sign_rule = format!("{rule:?}").to_lowercase();
    summary.seconds_census = t.elapsed().as_secs_f64();

    // 4. Reconstruct slabs in parallel, write in order.
    let t = Instant::now();
    let mut out = OrderedOutput::create(output, out_format, opts.write.clone(), &tmp_root)?;
    progress.start(Phase::Reconstruct, ns as u64);
    let mut removed = FilterStats::default();
    let mut repair = RepairStats::default();
    let mut emit = |res: SlabResult, filter: FilterStats, rep: RepairStats, layers: u64| -> Result<(), PipelineError> {
        removed += filter;
        repair += rep;
        out.push(&res)?;
        summary.active_cells += res.stats.active_cells;
        summary.non_canonical_cells += res.stats.non_canonical_cells;
        let room = opts.max_listed.saturating_sub(summary.non_canonical_list.len());
        summary.non_canonical_list.extend(res.non_canonical.iter().take(room));
        progress.advance(layers);
        Ok(())
    };
    let max_listed = opts.max_listed;
    let store_ref = &store;
    let grid_ref = &grid;
    // Holes to leave open: a first robust pass only collects hole cells.
    let open: Option<OpenCells> = match (rule, opts.max_hole) {
        (SignRule::Union | SignRule::Parity, Some(k)) => {
            let mut holes: Vec<u64> = Vec::new();
            let collect = |k0: u32, k1: u32| -> Result<Done, PipelineError> {
                let mut planes = store_ref.read_planes(k0, k1, true)?;
                if invert {
                    planes.iter_mut().flatten().for_each(|r| r.signed_value = -r.signed_value);
                }
                let (mut res, rep) = reconstruct_slab_solids(grid_ref, k0, vec![planes], &[rule], &Expr::Operand(0), None);
                res.vertices = Vec::new();
                res.faces = Vec::new();
                Ok((res, FilterStats::default(), rep))
            };
            reconstruct_ordered(&slabs, threads, &collect, &mint_pipeline_null_progress(progress), &mut |res, _, _, _| {
                holes.extend_from_slice(&res.hole_cells);
                Ok(())
            })?;
            let [na, nb, ns] = grid.local_dims();
            let (set, hs) = open_cells(&mut holes, [na, nb, ns], k);
            summary.holes_closed = hs.closed;
            summary.holes_left_open = hs.left_open;
            summary.open_cells = set.len() as u64;
            (!set.is_empty()).then_some(set)
        }
        _ => None,
    };
    let open_ref = open.as_ref();
    let compute = move |k0: u32, k1: u32| -> Result<Done, PipelineError> {
        let mut planes = store_ref.read_planes(k0, k1, true)?;
        if invert {
            for p in planes.iter_mut() {
                for r in p.iter_mut() {
                    r.signed_value = -r.signed_value;
                }
            }
        }
        if rule != SignRule::Orient {
            let (res, rep) = reconstruct_slab_solids(grid_ref, k0, vec![planes], &[rule], &Expr::Operand(0), open_ref);
            return Ok((res, FilterStats::default(), rep));
        }
        let mut stats = FilterStats::default();
        let owned = planes.len() - 1;
        for (n, p) in planes.iter_mut().enumerate() {
            let f = filter_plane(p);
            if n < owned {
                stats += f;
            }
        }
        Ok((reconstruct_slab(grid_ref, k0, &planes, max_listed), stats, RepairStats::default()))
    };
    reconstruct_ordered(&slabs, threads, &compute, progress, &mut emit)?;
    drop(emit);
    progress.finish();
    drop(store); // removes the shard directory before the final copy
    if rule == SignRule::Orient {
        summary.intercepts_removed = removed.removed;
        summary.intercepts_kept = removed.kept;
    } else {
        summary.intercepts_kept = summary.intercepts_found - repair.dropped_intercepts;
        summary.intercepts_removed = repair.dropped_intercepts;
    }
    summary.record_reconstruction(&repair, &out, t);
    check_cancel(progress)?;

    // 5. Faces after vertices, then rename into place.
    summary.finish_output(out, progress, t_start)?;
    Ok(summary)
}

pub(crate) fn check_cancel(progress: &dyn Progress) -> Result<(), PipelineError> {
    if progress.cancelled() {
        Err(PipelineError::Cancelled)
    } else {
        Ok(())
    }
}

/// The bounding box of all vertices, read from the map in parallel. Also
/// the check that every vertex is finite, so that workers resolving indices
/// later need not check again.
pub(crate) fn bounds(reader: &MeshReader, path: &Path, threads: usize, progress: &dyn Progress, xf: Option<&Transform>) -> Result<([f64; 3], [f64; 3]), PipelineError> {
    let positions = reader.positions();
    let n = positions.len() as u64;
    progress.start(Phase::Bounds, n);
    let per = n.div_ceil(threads as u64).max(1);
    let parts: Vec<Result<([f64; 3], [f64; 3]), PipelineError>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads as u64)
            .map(|t| {
                let positions = &positions;
                s.spawn(move || {
                    let mut lo = [f64::INFINITY; 3];
                    let mut hi = [f64::NEG_INFINITY; 3];
                    let (a, b) = ((t * per).min(n), ((t + 1) * per).min(n));
                    for i in a..b {
                        let p = positions.get(i as u32);
                        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
                            return Err(PipelineError::NonFinite { path: path.to_path_buf(), index: i, x: p[0], y: p[1], z: p[2] });
                        }
                        let p = match xf {
                            Some(t) => t.apply_point(p),
                            None => p,
                        };
                        for d in 0..3 {
                            lo[d] = lo[d].min(p[d]);
                            hi[d] = hi[d].max(p[d]);
                        }
                        if (i - a) % (1 << 20) == (1 << 20) - 1 {
                            progress.advance(1 << 20);
                        }
                    }
                    Ok((lo, hi))
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("bounds worker panicked")).collect()
    });
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for part in parts {
        let (l, h) = part?;
        for d in 0..3 {
            lo[d] = lo[d].min(l[d]);
            hi[d] = hi[d].max(h[d]);
        }
    }
    progress.finish();
    Ok((lo, hi))
}

/// Streams every triangle through the workers into the store. Returns the
/// number of triangles read and the input's signed volume (in grid units),
/// summed per chunk in chunk order so that it does not depend on threads.
pub(crate) fn discretize_all(
    reader: &mut MeshReader,
    grid: &Grid,
    store: &mut ShardStore,
    threads: usize,
    progress: &dyn Progress,
    xf: Option<&Transform>,
) -> Result<(u64, f64), PipelineError> {
    use crossbeam_channel::bounded;
    let [_, nb, _] = grid.local_dims();
    let positions = reader.positions();
    let positions = &positions;
    let (chunk_tx, chunk_rx) = bounded::<(usize, TriangleChunk)>(threads * 2);
    let (free_tx, free_rx) = bounded::<TriangleChunk>(threads * 3 + 2);
    let (rec_tx, rec_rx) = bounded::<(usize, Vec<Intercept>, f64)>(threads * 2);
    progress.start(Phase::Discretize, reader.info().face_count.unwrap_or(0));
    let mut faces = 0u64;
    let mut volumes: Vec<f64> = Vec::new();
    let result: Result<(), PipelineError> = std::thread::scope(|s| {
        for _ in 0..threads {
            let (chunk_rx, free_tx, rec_tx) = (chunk_rx.clone(), free_tx.clone(), rec_tx.clone());
            s.spawn(move || {
                for (seq, chunk) in chunk_rx {
                    let mut recs = Vec::with_capacity(chunk.indices.len() / 4 + 16);
                    let mut volume = 0.0;
                    for tri in &chunk.indices {
                        // Indices were range-checked by the reader; positions
                        // were checked finite by the bounds pass.
                        let at = |i: u32| {
                            let p = positions.get(i);
                            grid.to_local(match xf {
                                Some(t) => t.apply_point(p),
                                None => p,
                            })
                        };
                        let local = [at(tri[0]), at(tri[1]), at(tri[2])];
                        volume += signed_volume6(&local);
                        discretize_triangle(&local, |c| recs.push(crossing_to_intercept(&c, nb)));
                    }
                    let _ = free_tx.try_send(chunk);
                    if rec_tx.send((seq, recs, volume)).is_err() {
                        return; // the writer stopped on an error
                    }
                }
            });
        }
        drop((chunk_rx, free_tx, rec_tx));
        let volumes = &mut volumes;
        let writer = s.spawn(move || -> Result<(), StoreError> {
            for (seq, recs, volume) in rec_rx {
                if volumes.len() <= seq {
                    volumes.resize(seq + 1, 0.0);
                }
                volumes[seq] = volume;
                store.append(&recs)?;
            }
            Ok(())
        });
        let read: Result<(), PipelineError> = (|| {
            let mut seq = 0usize;
            loop {
                check_cancel(progress)?;
                let mut chunk = free_rx.try_recv().unwrap_or_default();
                if !reader.next_chunk(&mut chunk)? {
                    return Ok(());
                }
                let n = chunk.indices.len() as u64;
                faces += n;
                if chunk_tx.send((seq, chunk)).is_err() {
                    return Ok(()); // workers gone: the writer failed; its error follows
                }
                seq += 1;
                progress.advance(n);
            }
        })();
        drop(chunk_tx);
        let written = writer.join().expect("shard writer panicked");
        read?;
        written?;
        Ok(())
    });
    result?;
    progress.finish();
    Ok((faces, volumes.iter().sum::<f64>() / 6.0))
}

/// Six times the signed volume of the tetrahedron (origin, a, b, c).
#[inline]
fn signed_volume6(t: &[[f64; 3]; 3]) -> f64 {
    let [a, b, c] = t;
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// Splits layers `0 .. ns` into slabs `(k0, k1)`: layers `k0 .. k1`, reading
/// planes `k0 ..= k1`. With `fixed`, every slab has that many layers;
/// otherwise slabs grow while their planes' records fit `budget` bytes.
pub fn plan_slabs(counts: &[u64], ns: u32, fixed: Option<u32>, budget: u64) -> Vec<(u32, u32)> {
    let mut slabs = Vec::new();
    let mut k0 = 0u32;
    while k0 < ns {
        let mut k1 = k0 + 1;
        match fixed {
            Some(n) => k1 = (k0 + n.max(1)).min(ns),
            None => {
                let bytes = |k: u32| counts.get(k as usize).copied().unwrap_or(0) * BYTES_PER_RECORD_IN_SLAB;
                let mut used = bytes(k0) + bytes(k1);
                while k1 < ns && used + bytes(k1 + 1) <= budget {
                    k1 += 1;
                    used += bytes(k1);
                }
            }
        }
        slabs.push((k0, k1));
        k0 = k1;
    }
    slabs
}

/// A progress hook that only forwards cancellation (for hidden passes).
fn mint_pipeline_null_progress(p: &dyn Progress) -> impl Progress + '_ {
    struct CancelOnly<'a>(&'a dyn Progress);
    impl Progress for CancelOnly<'_> {
        fn cancelled(&self) -> bool {
            self.0.cancelled()
        }
    }
    CancelOnly(p)
}

/// What one slab's reconstruction returns.
pub(crate) type Done = (SlabResult, FilterStats, RepairStats);

/// Reconstructs `slabs` on `threads` workers and hands results to `emit`
/// strictly in slab order. At most `threads + 1` slabs are held at once.
pub(crate) fn reconstruct_ordered(
    slabs: &[(u32, u32)],
    threads: usize,
    compute: &(dyn Fn(u32, u32) -> Result<Done, PipelineError> + Sync),
    progress: &dyn Progress,
    emit: &mut dyn FnMut(SlabResult, FilterStats, RepairStats, u64) -> Result<(), PipelineError>,
) -> Result<(), PipelineError> {
    let window = threads as u64 + 1;
    let next = AtomicU64::new(0);
    let written = (Mutex::new(0u64), Condvar::new());
    let stop = std::sync::atomic::AtomicBool::new(false);
    let (tx, rx) = crossbeam_channel::unbounded::<(u64, Result<Done, PipelineError>)>();
    std::thread::scope(|s| {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, written, stop) = (&next, &written, &stop);
            s.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= slabs.len() as u64 || stop.load(Ordering::SeqCst) {
                    return;
                }
                {
                    let (lock, cv) = written;
                    let mut w = lock.lock().unwrap();
                    while i >= *w + window && !stop.load(Ordering::SeqCst) {
                        w = cv.wait(w).unwrap();
                    }
                }
                let (k0, k1) = slabs[i as usize];
                let r = compute(k0, k1);
                if tx.send((i, r)).is_err() {
                    return;
                }
            });
        }
        drop(tx);
        let mut pending = std::collections::BTreeMap::new();
        let mut want = 0u64;
        let mut outcome = Ok(());
        for (i, r) in rx.iter() {
            pending.insert(i, r);
            while let Some(r) = pending.remove(&want) {
                let step = r.and_then(|(res, f, rep)| {
                    let (k0, k1) = slabs[want as usize];
                    emit(res, f, rep, (k1 - k0) as u64)
                });
                let step = step.and_then(|_| check_cancel(progress));
                if let Err(e) = step {
                    outcome = Err(e);
                    stop.store(true, Ordering::SeqCst);
                }
                want += 1;
                let (lock, cv) = &written;
                *lock.lock().unwrap() = want;
                cv.notify_all();
                if outcome.is_err() {
                    break;
                }
            }
            if outcome.is_err() {
                break;
            }
        }
        if outcome.is_err() {
            stop.store(true, Ordering::SeqCst);
            let (lock, cv) = &written;
            *lock.lock().unwrap() = u64::MAX / 2;
            cv.notify_all();
        }
        outcome
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_slabs_cover_every_layer_once() {
        let counts = vec![5u64; 11];
        assert_eq!(plan_slabs(&counts, 10, Some(3), 0), vec![(0, 3), (3, 6), (6, 9), (9, 10)]);
        assert_eq!(plan_slabs(&counts, 10, Some(1), 0).len(), 10);
    }

    #[test]
    fn budget_slabs_grow_until_full_but_never_below_one_layer() {
        let counts = vec![10u64; 11];
        let per = 10 * BYTES_PER_RECORD_IN_SLAB;
        assert_eq!(plan_slabs(&counts, 10, None, 0).len(), 10);
        // Room for 4 planes = 3 layers.
        let s = plan_slabs(&counts, 10, None, 4 * per);
        assert_eq!(s[0], (0, 3));
        assert_eq!(s.last().unwrap().1, 10);
        assert_eq!(plan_slabs(&counts, 10, None, u64::MAX), vec![(0, 10)]);
    }
}
