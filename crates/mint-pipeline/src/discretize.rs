//! The discretize passes: every triangle of a mesh (a stream from the
//! reader, or fixed-size records straight from the map) to its intercept
//! records in a shard store, through the worker pool and the one shard
//! writer ([`write_chunks`]), with six times the signed volume of each
//! chunk, in chunk order. The per-triangle work is in `kernels`.

use crate::error::{in_file_list, PipelineError};
use crate::kernels::{signed_volume6, visit_chunk, visit_chunk_marked, ChunkJob, LocalMap};
use crate::progress::{check_cancel, Progress};
use mint_core::grid::Grid;
use mint_core::primitives::Transform;
use mint_core::colour::{barycentric, crossing_colour, crossing_of, Rgba};
use mint_core::{discretize_triangle, Crossing, Intercept};
use mint_io::textures::{Image, Texturing};
use mint_io::{FaceColours, MeshReader, TriangleChunk, TriangleRecords, VertexColours, VertexPositions};
use mint_store::{ShardWriter, StoreError};
use crossbeam_channel::Sender;
use std::sync::atomic::Ordering;

/// Triangles per chunk handed from the reader to the workers. Parts of a
/// split input start at multiples of it, so that the per-chunk volumes (and
/// their sum) do not depend on the split.
pub const CHUNK_TRIANGLES: usize = 64 * 1024;
/// How many chunks ahead of the workers the direct path asks the kernel to
/// read (about 40 MB of common PLY faces): far enough that a cold file's
/// reads overlap the work, small beside any page cache.
const READ_AHEAD: u64 = 48;

/// The outcome of one worker's chunk of faces: the visit's own error
/// first, then the sink's, then a pending Ctrl-C.
pub(crate) fn chunk_outcome(visited: Result<(), mint_io::Error>, sink: Option<StoreError>, progress: &dyn Progress) -> Option<PipelineError> {
    match (visited, sink) {
        (Err(e), _) => Some(PipelineError::from(e)),
        (_, Some(e)) => Some(e.into()),
        _ if progress.cancelled() => Some(PipelineError::Cancelled),
        _ => None,
    }
}

/// Streams every triangle of `reader` through the workers into `store`
/// (with each crossing's colour when the store is coloured and the file
/// has colour).
/// Returns the number of triangles read and six times the signed volume of
/// each chunk (in grid units), in chunk order, so that their sum does not
/// depend on threads or on how the input was split into parts.
/// `first_triangle`: the place of the reader's first triangle in the file
/// (a part of a split file), for per-face colours.
#[allow(clippy::too_many_arguments)]
pub(crate) fn discretize_all(
    reader: &mut MeshReader,
    grid: &Grid,
    store: &mut ShardWriter,
    threads: usize,
    progress: &dyn Progress,
    xf: Option<&Transform>,
    expected_faces: u64,
    first_triangle: u64,
    colours: Option<&CornerColours>,
) -> Result<(u64, Vec<f64>), PipelineError> {
    use crossbeam_channel::bounded;
    let [_, nb, _] = grid.local_dims();
    let positions = reader.positions();
    let positions = &positions;
    // Each crossing's colour, when the store keeps colour and the file has it.

    let (chunk_tx, chunk_rx) = bounded::<(usize, u64, TriangleChunk)>(threads * 2);
    let (free_tx, free_rx) = bounded::<TriangleChunk>(threads * 3 + 2);
    let (rec_tx, rec_rx) = bounded::<(usize, Vec<Intercept>, Vec<Rgba>, f64)>(threads * 2);
    progress.start(crate::progress::DISCRETIZE, expected_faces);
    let mut faces = 0u64;
    let mut volumes: Vec<f64> = Vec::new();
    let result: Result<(), PipelineError> = std::thread::scope(|s| {
        for _ in 0..threads {
            let (chunk_rx, free_tx, rec_tx) = (chunk_rx.clone(), free_tx.clone(), rec_tx.clone());
            s.spawn(move || {
                for (seq, first, chunk) in chunk_rx {
                    let mut recs = Vec::with_capacity(chunk.indices.len() / 4 + 16);
                    let mut tints = Vec::new();
                    let mut volume = 0.0;
                    for (n, tri) in chunk.indices.iter().enumerate() {
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
                        match colours {
                            Some(cs) => {
                                let mut corners = None;
                                discretize_triangle(&local, |c| {
                                    recs.push(c.intercept(nb));
                                    tints.push(cs.crossing(first + n as u64, *tri, &local, &c, &mut corners));
                                });
                            }
                            None => discretize_triangle(&local, |c| recs.push(c.intercept(nb))),
                        }
                    }
                    let _ = free_tx.try_send(chunk);
                    if rec_tx.send((seq, recs, tints, volume)).is_err() {
                        return; // the writer stopped on an error
                    }
                }
            });
        }
        drop((chunk_rx, free_tx, rec_tx));
        let volumes = &mut volumes;
        let writer = s.spawn(move || -> Result<(), StoreError> {
            for (seq, recs, tints, volume) in rec_rx {
                if volumes.len() <= seq {
                    volumes.resize(seq + 1, 0.0);
                }
                volumes[seq] = volume;
                if tints.is_empty() {
                    store.append(&recs)?;
                } else {
                    store.append_coloured(&recs, &tints)?;
                }
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
                let first = first_triangle + faces;
                faces += n;
                if chunk_tx.send((seq, first, chunk)).is_err() {
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
    Ok((faces, volumes))
}

/// Discretizes face records `first .. end` of a file read directly
/// ([`TriangleRecords`]): `threads` workers take whole chunks of
/// [`CHUNK_TRIANGLES`] records in turn and visit them straight from the map
/// (no reader thread, no chunk buffers); one writer appends their records
/// to `store`. Returns what [`discretize_all`] returns, chunk for chunk the
/// same (`first` is a multiple of the chunk size, or 0).
pub(crate) fn discretize_direct(
    records: &TriangleRecords,
    range: (u64, u64),
    grid: &Grid,
    store: &mut ShardWriter,
    threads: usize,
    progress: &dyn Progress,
    xf: Option<&Transform>,
) -> Result<(u64, Vec<f64>), PipelineError> {
    let mut out = discretize_direct_many(&[DirectPiece { records, range, file: 0 }], 1, grid, store, threads, progress, xf)?;
    Ok(out.remove(0))
}

/// One file's records for [`discretize_direct_many`]: faces `range` of
/// it, and its place among `files` (for errors).
pub(crate) struct DirectPiece<'r> {
    pub records: &'r TriangleRecords,
    pub range: (u64, u64),
    pub file: usize,
}

/// [`discretize_direct`] over several files (tiles) at once: their chunks
/// form one queue for the workers, so a part that reads many small files
/// keeps every thread busy to the end instead of idling at the tail of
/// each file. Each file's chunks are its own (they start at its `range`),
/// so its volumes are those [`discretize_direct`] gives; returns them per
/// piece. An error names its file among `files` ([`in_file_list`]), except
/// a record that is not a triangle ([`mint_io::ErrorKind::Unsupported`]),
/// returned as is for the caller to stream that file instead.
pub(crate) fn discretize_direct_many(
    pieces: &[DirectPiece],
    files: usize,
    grid: &Grid,
    store: &mut ShardWriter,
    threads: usize,
    progress: &dyn Progress,
    xf: Option<&Transform>,
) -> Result<Vec<(u64, Vec<f64>)>, PipelineError> {
    let [_, nb, _] = grid.local_dims();
    let local = LocalMap::new(grid);
    let chunk = CHUNK_TRIANGLES as u64;
    let faces: Vec<u64> = pieces.iter().map(|p| p.range.1.saturating_sub(p.range.0)).collect();
    // Where each piece's chunks start in the one queue.
    let mut starts = Vec::with_capacity(pieces.len() + 1);
    starts.push(0u64);
    for f in &faces {
        starts.push(starts.last().unwrap() + f.div_ceil(chunk));
    }
    let chunks = *starts.last().unwrap();
    progress.start(crate::progress::DISCRETIZE, faces.iter().sum());
    let local = &local;
    let starts = &starts;
    let volumes = discretize_on_pool(threads, chunks, chunks as usize, store, progress, |_| (), |_, tx, g| {
        if progress.cancelled() {
            return Err(PipelineError::Cancelled);
        }
        let p = starts.partition_point(|&s| s <= g) - 1;
        let DirectPiece { records, range: (first, end), file } = pieces[p];
        let c = g - starts[p];
        let (a, b) = (first + c * chunk, (first + (c + 1) * chunk).min(end));
        // Keep the disk busy READ_AHEAD chunks ahead of the workers
        // (each worker asks for the chunk that far past its own).
        let ahead = a + READ_AHEAD * chunk;
        records.read_ahead(ahead, (ahead + chunk).min(end));
        let mut recs = Vec::with_capacity(1024);
        let mut volume = 0.0;
        let visited = match (grid.slab_axis, xf) {
            (0, None) => visit_chunk::<0>(&ChunkJob { records, a, b, local, xf: None, nb, progress }, &mut recs, &mut volume),
            (1, None) => visit_chunk::<1>(&ChunkJob { records, a, b, local, xf: None, nb, progress }, &mut recs, &mut volume),
            (_, None) => visit_chunk::<2>(&ChunkJob { records, a, b, local, xf: None, nb, progress }, &mut recs, &mut volume),
            (_, Some(t)) => visit_chunk::<3>(&ChunkJob { records, a, b, local, xf: Some(t), nb, progress }, &mut recs, &mut volume),
        };
        match visited {
            Ok(true) => {}
            Ok(false) => return Err(PipelineError::Cancelled),
            Err(e) if e.kind() == mint_io::ErrorKind::Unsupported => return Err(e.into()),
            Err(e) => return Err(in_file_list(e.into(), file, files)),
        }
        progress.advance(b - a);
        // A closed channel: the writer stopped on an error and raised `stop`.
        let _ = tx.send((g as usize, recs, Vec::new(), volume));
        Ok(())
    })?;
    Ok((0..pieces.len()).map(|p| (faces[p], volumes[starts[p] as usize..starts[p + 1] as usize].to_vec())).collect())
}

/// Where a coloured file's colours come from: its vertices, its faces (by
/// the triangle's place in the file's stream of triangles, which is the
/// face record's index in files read directly), or its textures (decoded).
pub(crate) enum CornerColours {
    Vertex(VertexColours),
    Face(FaceColours),
    Texture(Texturing, Vec<Image>),
}

impl CornerColours {
    /// The colours `reader` gives (per vertex first), textures decoded if
    /// they fit in `budget` bytes.
    pub(crate) fn of(reader: &MeshReader, budget: u64) -> Result<Option<CornerColours>, PipelineError> {
        if let Some(c) = reader.colours() {
            return Ok(Some(CornerColours::Vertex(c)));
        }
        if let Some(c) = reader.face_colours() {
            return Ok(Some(CornerColours::Face(c)));
        }
        let Some(t) = reader.texturing() else { return Ok(None) };
        let need = t.decoded_bytes();
        if need > budget {
            let mib = |b: u64| b.div_ceil(1 << 20);
            return Err(PipelineError::budget(
                reader.path(),
                format!(
                    "its {} textures take {} MiB decoded, more than the {} MiB the memory budget leaves them; give --mem {}M or more (or --no-color)",
                    t.textures.len(),
                    mib(need),
                    mib(budget),
                    mib(need * 2) + 64
                ),
            ));
        }
        let images = t.decode(reader.path())?;
        Ok(Some(CornerColours::Texture(t, images)))
    }

    /// The colour of crossing `c` of triangle `t` (vertex indices `tri`,
    /// grid coordinates `local`); `corners` caches the triangle's corner
    /// colours across its crossings.
    #[inline]
    fn crossing(&self, t: u64, tri: [u32; 3], local: &[[f64; 3]; 3], c: &Crossing, corners: &mut Option<[Rgba; 3]>) -> Rgba {
        match self {
            CornerColours::Vertex(v) => crossing_colour(local, corners.get_or_insert_with(|| tri.map(|i| v.get(i))), c),
            CornerColours::Face(f) => *corners.get_or_insert_with(|| [f.get(t); 3]).first().unwrap(),
            CornerColours::Texture(tex, images) => tex.colour(images, t, barycentric(local, c)),
        }
    }
}

/// [`discretize_direct`] for a coloured file in a coloured store: the
/// workers run the direct path's kernel on each chunk (the same records and
/// volume), noting which records crossed a line, and colour only those
/// triangles' crossings: their vertex indices read from the record
/// ([`TriangleRecords::visit_indices`]), their corners from the positions
/// (the arithmetic of [`Grid::to_local`]), each crossing's colour there.
#[allow(clippy::too_many_arguments)]
pub(crate) fn discretize_direct_coloured(
    records: &TriangleRecords,
    positions: &VertexPositions,
    colours: &CornerColours,
    (first, end): (u64, u64),
    grid: &Grid,
    store: &mut ShardWriter,
    threads: usize,
    progress: &dyn Progress,
    xf: Option<&Transform>,
) -> Result<(u64, Vec<f64>), PipelineError> {
    let [_, nb, _] = grid.local_dims();
    let local = LocalMap::new(grid);
    let local = &local;
    let chunk = CHUNK_TRIANGLES as u64;
    let end = end.min(records.len());
    let faces = end.saturating_sub(first);
    let chunks = faces.div_ceil(chunk);
    progress.start(crate::progress::DISCRETIZE, faces);
    let volumes = discretize_on_pool(threads, chunks, chunks as usize, store, progress, |_| (), |_, tx, g| {
        if progress.cancelled() {
            return Err(PipelineError::Cancelled);
        }
        let (a, b) = (first + g * chunk, (first + (g + 1) * chunk).min(end));
        let ahead = a + READ_AHEAD * chunk;
        records.read_ahead(ahead, (ahead + chunk).min(end));
        let (mut recs, mut volume, mut marks) = (Vec::with_capacity(1024), 0.0, Vec::new());
        let job = ChunkJob { records, a, b, local, xf, nb, progress };
        let visited = match (grid.slab_axis, xf) {
            (0, None) => visit_chunk_marked::<0, true>(&job, &mut recs, &mut volume, &mut marks),
            (1, None) => visit_chunk_marked::<1, true>(&job, &mut recs, &mut volume, &mut marks),
            (_, None) => visit_chunk_marked::<2, true>(&job, &mut recs, &mut volume, &mut marks),
            (_, Some(_)) => visit_chunk_marked::<3, true>(&job, &mut recs, &mut volume, &mut marks),
        };
        if !visited? {
            return Err(PipelineError::Cancelled);
        }
        let mut tints = vec![[0u8; 4]; recs.len()];
        for (i, &(k, start)) in marks.iter().enumerate() {
            let stop = marks.get(i + 1).map_or(recs.len(), |m| m.1 as usize);
            let mut tri = [0u32; 3];
            records.visit_indices(k, k + 1, |_, t| tri = t)?;
            let l = tri.map(|v| {
                let p = positions.get(v);
                grid.to_local(xf.map_or(p, |t| t.apply_point(p)))
            });
            let mut corners = None;
            for r in start as usize..stop {
                tints[r] = colours.crossing(k, tri, &l, &crossing_of(&recs[r], nb), &mut corners);
            }
        }
        progress.advance(b - a);
        let _ = tx.send((g as usize, recs, tints, volume));
        Ok(())
    })?;
    Ok((faces, volumes))
}

/// A chunk of records on its way to the shard writer: its number, its
/// records, their colours (empty when none), six times its signed volume.
pub(crate) type ChunkOut = (usize, Vec<Intercept>, Vec<Rgba>, f64);

/// The parallel discretize passes' one shape (direct and sorted): `work`
/// runs over `items` on the worker pool, each worker with its own state from
/// `make` and a sender of [`ChunkOut`]s; beside them the one shard writer
/// appends each chunk's records to `store` as they come (order does not
/// matter: readers sort) and files each chunk's volume under its number
/// (`chunks` of them). A store error stops the workers; the first error of
/// either side is returned. Returns the volumes, in chunk order.
pub(crate) fn discretize_on_pool<W: Send>(
    threads: usize,
    items: u64,
    chunks: usize,
    store: &mut ShardWriter,
    progress: &dyn Progress,
    make: impl FnMut(usize) -> W,
    work: impl Fn(&mut W, &Sender<ChunkOut>, u64) -> Result<(), PipelineError> + Sync,
) -> Result<Vec<f64>, PipelineError> {
    let (tx, rx) = crossbeam_channel::bounded::<ChunkOut>(threads * 2);
    let mut volumes = vec![0.0f64; chunks];
    let mut make = make;
    let (failed, _, written) = mint_core::pool::run(
        threads,
        items,
        move |w| (tx.clone(), make(w)),
        |(tx, state), i| work(state, tx, i),
        drop,
        |stop| -> Result<(), StoreError> {
            for (seq, recs, tints, volume) in rx {
                volumes[seq] = volume;
                let appended = if tints.is_empty() { store.append(&recs) } else { store.append_coloured(&recs, &tints) };
                if let Err(e) = appended {
                    stop.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
            Ok(())
        },
    );
    if let Some(e) = failed {
        return Err(e);
    }
    written?;
    progress.finish();
    Ok(volumes)
}
