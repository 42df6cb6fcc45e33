//! Voxel volumes as operands of the engine (`mint volume`). A volume is
//! discretized like a mesh: each discretize task takes a run of the grid's
//! node planes along the slab axis (z, the volume's slice axis, so that a
//! task reads a contiguous range of slices), samples them
//! (`mint_core::volume::PlaneSampler`), and writes the crossings of their
//! grid lines into the task's shard store. Census, slabs, budget,
//! reconstruction, resumption and Slurm are then the mesh path's.
//!
//! Frames: the engine runs in the volume's *engine frame*, index × `scale`
//! per axis: `scale` = 1 on the volume's own grid (a node on every voxel
//! centre, cells of one voxel), the voxel spacing otherwise (cubic cells
//! in physical units). The write stage maps vertices to the frame the file
//! declares by [`OutputMap`] (index-to-world ∘ engine-to-index), flipping
//! faces when that map mirrors.
//!
//! Memory: a task holds the slices its batch of planes reads (at least
//! two), two node planes, and the crossings of one group of bands of a
//! plane ([`discretize_planes`]); the batch shrinks to the budget.

use crate::error::PipelineError;
use crate::progress::{check_cancel, Progress};
use crate::scene::VolumeJob;
use mint_core::grid::{Grid, GridSize};
use mint_core::volume::{band_capacity, band_crossings, band_rows, inside_rows, Placement, PlaneSampler};
use mint_core::Intercept;
use mint_store::ShardWriter;
use mint_volume::{SampleStats, Volume, VolumeInfo};
use serde::{Deserialize, Serialize};

impl VolumeJob {
    /// Opens the volume (header only).
    pub fn open(&self) -> Result<mint_volume::Volume, PipelineError> {
        let raw = match &self.raw {
            Some(r) => {
                let sample = mint_volume::Sample::parse(&r.sample)
                    .ok_or_else(|| PipelineError::stage(&self.input, format!("--raw-type {}: one of u8, i8, u16, i16, u32, i32, u64, i64, f32, f64", r.sample)))?;
                Some(mint_volume::RawSpec { dims: r.dims, sample, big_endian: r.big_endian, spacing: r.spacing, header_bytes: r.header_bytes })
            }
            None => None,
        };
        Ok(mint_volume::Volume::open(&self.input, &mint_volume::OpenOptions { raw, dicom_series: self.dicom_series.clone() })?)
    }
}


/// What one discretize task saw of the volume.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct VolumeStats {
    /// Slices read.
    pub slices: u64,
    /// Samples read, NaN among them, and the finite ones' range (after
    /// the rescale; `None` when no sample was finite).
    pub samples: u64,
    pub nan: u64,
    pub range: Option<[f32; 2]>,
    /// Crossings written.
    pub records: u64,
}

impl VolumeStats {
    /// Both tasks' statistics together.
    pub fn merge(&mut self, o: &VolumeStats) {
        self.slices += o.slices;
        self.samples += o.samples;
        self.records += o.records;
        self.add_seen(&SampleStats { nan: o.nan, range: o.range });
    }

    /// Adds what a read saw of the samples (NaN count and range, merged by
    /// their owner, mint-volume's `SampleStats`).
    pub fn add_seen(&mut self, seen: &SampleStats) {
        let mut s = SampleStats { nan: self.nan, range: self.range };
        s.merge(seen);
        (self.nan, self.range) = (s.nan, s.range);
    }
}

/// The engine frame's scale per axis (see the module docs).
pub fn scale(job: &VolumeJob, info: &VolumeInfo) -> [f64; 3] {
    if job.own_grid {
        [1.0; 3]
    } else {
        std::array::from_fn(|d| info.spacing(d))
    }
}

/// The box the grid is built around, in the engine frame: the voxel
/// centres on the own grid (so that nodes land on them), the voxels'
/// extent otherwise.
pub fn bounds(job: &VolumeJob, info: &VolumeInfo) -> ([f64; 3], [f64; 3]) {
    let s = scale(job, info);
    if job.own_grid {
        ([0.0; 3], std::array::from_fn(|d| (info.dims[d] - 1) as f64))
    } else {
        (std::array::from_fn(|d| -0.5 * s[d]), std::array::from_fn(|d| (info.dims[d] as f64 - 0.5) * s[d]))
    }
}

/// The grid of a volume job: around [`bounds`], slabs along z (the slices);
/// on the own grid cells of one voxel and no shift.
pub fn grid(job: &VolumeJob, info: &VolumeInfo, size: GridSize, offset: [f64; 3]) -> Result<Grid, mint_core::grid::GridError> {
    let (lo, hi) = bounds(job, info);
    if job.own_grid {
        Grid::around(lo, hi, GridSize::CellSize(1.0), [0.0; 3], Some(2))
    } else {
        Grid::around(lo, hi, size, offset, Some(2))
    }
}

/// Where the grid's nodes sit on the volume.
pub fn placement(job: &VolumeJob, info: &VolumeInfo, grid: &Grid) -> Placement {
    let s = scale(job, info);
    let [na, nb, ns] = grid.local_dims();
    Placement {
        axis: [0, 1, 2],
        start: std::array::from_fn(|d| grid.origin[d] / s[d]),
        step: std::array::from_fn(|d| grid.cell / s[d]),
        dims: info.dims,
        nodes: [na + 1, nb + 1, ns + 1],
    }
}

/// Engine coordinates to the file's world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputMap {
    /// world = m · (x, y, z, 1).
    pub m: [[f64; 4]; 3],
    /// The map mirrors (negative determinant): faces are written reversed
    /// so that they still face out.
    pub flip: bool,
    /// The shortest world length of a cell edge (the precision the output
    /// needs is a fraction of it).
    pub cell: f64,
}

impl OutputMap {
    pub fn new(job: &VolumeJob, info: &VolumeInfo, grid: &Grid) -> OutputMap {
        let s = scale(job, info);
        let a = &info.index_to_world;
        let mut m = [[0.0; 4]; 3];
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] = a[r][c] / s[c];
            }
            m[r][3] = a[r][3];
        }
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        let cell = (0..3).map(|c| grid.cell * (m[0][c].powi(2) + m[1][c].powi(2) + m[2][c].powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
        OutputMap { m, flip: det < 0.0, cell }
    }

    #[inline]
    pub fn apply(&self, v: [f64; 3]) -> [f64; 3] {
        let m = &self.m;
        std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2] + m[r][3])
    }

    /// The world box of the engine box `[lo, hi]` (its eight corners').
    pub fn bounds(&self, lo: [f64; 3], hi: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for c in 0..8 {
            let p = self.apply(std::array::from_fn(|d| if c >> d & 1 == 1 { hi[d] } else { lo[d] }));
            for d in 0..3 {
                a[d] = a[d].min(p[d]);
                b[d] = b[d].max(p[d]);
            }
        }
        (a, b)
    }
}

/// The domain of the field in the engine frame, per axis: the voxels'
/// extent, half a voxel beyond the outer centres (see `mint_core::volume`).
pub fn domain(job: &VolumeJob, info: &VolumeInfo) -> [(f64, f64); 3] {
    let s = scale(job, info);
    std::array::from_fn(|d| (-0.5 * s[d], (info.dims[d] as f64 - 0.5) * s[d]))
}

/// `--open-border`: which output faces and vertices the write stage keeps
/// when the cap on the volume's border is left out, and which border
/// vertices it splits so that the open surface stays a 2-manifold
/// (`mint_core::volume::fan_splits`). Built in two passes over the slabs'
/// results (each slab: its `vertices.bin`, `faces.bin`, their sums and its
/// vertex count); holds 1.25 bytes per vertex and a few words per face
/// that touches the border.
pub struct BorderCut {
    masks: Vec<u8>,
    used: Vec<u64>,
    /// Vertices kept before each word of `used`.
    rank: Vec<u64>,
    /// `(v, a, b)` of a face around border vertex `v` (`a < b` its other
    /// vertices, ids before the cut) → the id of the copy of `v` it uses.
    split: std::collections::HashMap<(u32, u32, u32), u64>,
    /// The copies, written after the kept vertices: the vertex each copies,
    /// in order.
    pub copies: Vec<u64>,
    /// Kept vertices, copies included.
    pub kept_vertices: u64,
    pub counts: OpenBorder,
}

/// The write stage's `--open-border` counts.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct OpenBorder {
    pub faces_removed: u64,
    pub vertices_removed: u64,
    /// Border vertices split where the cap touched the rest at a vertex
    /// only (copies added).
    #[serde(default)]
    pub vertices_split: u64,
    pub boundary_edges: u64,
    pub boundary_loops: u64,
}

/// One slab's result files, for [`BorderCut::new`].
pub struct SlabFiles {
    pub vertices: std::path::PathBuf,
    pub vertices_sum: crate::workdir::FileSum,
    pub faces: std::path::PathBuf,
    pub faces_sum: crate::workdir::FileSum,
    pub count: u64,
}

#[inline]
fn sorted(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl BorderCut {
    /// Reads the slabs' results; `boundary` turns the kept faces' edges
    /// along the border (new ids) into the output's boundary counts
    /// (edges, loops).
    pub fn new(
        slabs: &[SlabFiles],
        vertex_bytes: usize,
        domain: [(f64, f64); 3],
        cell: f64,
        budget: u64,
        name: &std::path::Path,
        boundary: impl Fn(&[(u32, u32)]) -> (u64, u64),
    ) -> Result<BorderCut, PipelineError> {
        use crate::workdir::read_records;
        let total: u64 = slabs.iter().map(|s| s.count).sum();
        if total > u32::MAX as u64 {
            return Err(PipelineError::stage(name, format!("{total} output vertices do not fit 32-bit indices; use a coarser grid")));
        }
        let need = total + total.div_ceil(64) * 16;
        if need > budget {
            return Err(PipelineError::budget(name, format!("--open-border needs {} MiB for {total} output vertices, more than the memory budget ({} MiB): use more --mem or larger cells", need >> 20, budget >> 20)));
        }
        let mut masks = Vec::with_capacity(total as usize);
        for s in slabs {
            let mut each = |b: &[u8]| {
                let c = |d: usize| f64::from_le_bytes(b[8 * d..8 * d + 8].try_into().unwrap());
                masks.push(mint_core::volume::border_mask([c(0), c(1), c(2)], domain, cell));
                Ok(())
            };
            match vertex_bytes {
                24 => read_records::<24>(&s.vertices, s.vertices_sum, |b| each(b))?,
                _ => read_records::<28>(&s.vertices, s.vertices_sum, |b| each(b))?,
            }
        }
        let mut used = vec![0u64; total.div_ceil(64) as usize];
        // Kept faces at the border: (v, a, b) per border vertex, and their
        // edges along the border (u, w, the face's third vertex).
        let mut incident: Vec<(u32, u32, u32)> = Vec::new();
        let mut edges: Vec<(u32, u32, u32)> = Vec::new();
        let mut counts = OpenBorder::default();
        let mut offset = 0u64;
        for s in slabs {
            read_records::<12>(&s.faces, s.faces_sum, |b| {
                let f: [u64; 3] = std::array::from_fn(|d| u32::from_le_bytes(b[4 * d..4 * d + 4].try_into().unwrap()) as u64 + offset);
                if f.iter().any(|&v| v >= total) {
                    return Err(PipelineError::stage(&s.faces, format!("damaged slab result: a face names vertex {} of {total}; remove its task directory and run the task again", f.iter().max().unwrap())));
                }
                let m = f.map(|v| masks[v as usize]);
                if mint_core::volume::on_border(m) {
                    counts.faces_removed += 1;
                    return Ok(());
                }
                let f = f.map(|v| v as u32);
                for k in 0..3 {
                    used[(f[k] / 64) as usize] |= 1 << (f[k] % 64);
                    let (a, b) = (f[(k + 1) % 3], f[(k + 2) % 3]);
                    if m[k] != 0 {
                        let (lo, hi) = sorted(a, b);
                        incident.push((f[k], lo, hi));
                        // The edges the cap may have shared: both ends on the border.
                        if m[(k + 1) % 3] != 0 {
                            edges.push((f[k], a, b));
                        }
                    }
                }
                Ok(())
            })?;
            offset += s.count;
        }
        let mut rank = Vec::with_capacity(used.len());
        let mut n = 0u64;
        for w in &used {
            rank.push(n);
            n += w.count_ones() as u64;
        }
        counts.vertices_removed = total - n;
        let mut cut = BorderCut { masks, used, rank, split: Default::default(), copies: Vec::new(), kept_vertices: n, counts };
        // Copies of split vertices, after the kept ones, by vertex and fan.
        let mut last: Option<(u32, u32)> = None;
        for (v, a, b, k) in mint_core::volume::fan_splits(incident) {
            if last != Some((v, k)) {
                cut.copies.push(v as u64);
                if last.map(|l| l.0) != Some(v) {
                    cut.counts.vertices_split += 1;
                }
                last = Some((v, k));
            }
            cut.split.insert((v, a, b), n + cut.copies.len() as u64 - 1);
        }
        cut.kept_vertices = n + cut.copies.len() as u64;
        let renamed: Vec<(u32, u32)> = edges.iter().map(|&(u, w, x)| (cut.id_in_face(u, w, x) as u32, cut.id_in_face(w, u, x) as u32)).collect();
        (cut.counts.boundary_edges, cut.counts.boundary_loops) = boundary(&renamed);
        Ok(cut)
    }

    /// Whether output vertex `v` (a global id before the cut) is kept.
    #[inline]
    pub fn keeps(&self, v: u64) -> bool {
        self.used[(v / 64) as usize] >> (v % 64) & 1 == 1
    }

    /// The new id of vertex `v` in a face whose other vertices are `a`, `b`.
    #[inline]
    fn id_in_face(&self, v: u32, a: u32, b: u32) -> u64 {
        if !self.split.is_empty() && self.masks[v as usize] != 0 {
            let (lo, hi) = sorted(a, b);
            if let Some(&c) = self.split.get(&(v, lo, hi)) {
                return c;
            }
        }
        let (w, bit) = ((v / 64) as usize, v % 64);
        self.rank[w] + (self.used[w] & ((1u64 << bit) - 1)).count_ones() as u64
    }

    /// A face's new ids, or `None` when the face is part of the cap.
    #[inline]
    pub fn face(&self, f: [u64; 3]) -> Option<[u64; 3]> {
        if mint_core::volume::on_border(f.map(|v| self.masks[v as usize])) {
            return None;
        }
        let f = f.map(|v| v as u32);
        Some(std::array::from_fn(|k| self.id_in_face(f[k], f[(k + 1) % 3], f[(k + 2) % 3])))
    }
}

/// A volume as an operand of a scene (`mint csg`, `mint bool`), in the
/// world frame its header declares: which index axis runs along each world
/// axis, and the signed length of one index step there. Only axis-aligned
/// volumes (direction cosines a signed permutation, within 1e-6) are placed
/// so; an oblique one is refused with the reason.
pub fn world_axes(info: &VolumeInfo) -> Result<[(usize, f64); 3], String> {
    let m = &info.index_to_world;
    let mut out = [(0usize, 0.0f64); 3];
    let mut used = [false; 3];
    for (w, o) in out.iter_mut().enumerate() {
        let big = (0..3).fold(0.0f64, |a, v| a.max(m[w][v].abs()));
        let along: Vec<usize> = (0..3).filter(|&v| m[w][v].abs() > 1e-6 * big).collect();
        if big == 0.0 || along.len() != 1 || used[along[0]] {
            return Err("its direction cosines are oblique (not along the world axes); as a scene operand only axis-aligned volumes are placed: mesh it alone with `mint volume` and use that mesh".into());
        }
        used[along[0]] = true;
        *o = (along[0], m[w][along[0]]);
    }
    Ok(out)
}

/// The world box of an axis-aligned volume's domain (the voxels' extent).
pub fn world_box(info: &VolumeInfo) -> Result<([f64; 3], [f64; 3]), String> {
    let ax = world_axes(info)?;
    let m = &info.index_to_world;
    let mut lo = [0.0; 3];
    let mut hi = [0.0; 3];
    for w in 0..3 {
        let (v, step) = ax[w];
        let (a, b) = (m[w][3] - 0.5 * step, m[w][3] + (info.dims[v] as f64 - 0.5) * step);
        (lo[w], hi[w]) = (a.min(b), a.max(b));
    }
    Ok((lo, hi))
}

/// The world axis that the volume's slices stack along (its index k).
pub fn world_slice_axis(info: &VolumeInfo) -> Result<usize, String> {
    Ok(world_axes(info)?.iter().position(|&(v, _)| v == 2).unwrap())
}

/// Where the nodes of a world-frame `grid` sit on an axis-aligned volume
/// whose slices stack along the grid's slab axis.
pub fn world_placement(info: &VolumeInfo, grid: &Grid) -> Result<Placement, String> {
    let ax = world_axes(info)?;
    let m = &info.index_to_world;
    let local = grid.local_axes();
    let [na, nb, ns] = grid.local_dims();
    let axis: [usize; 3] = std::array::from_fn(|d| ax[local[d]].0);
    if axis[2] != 2 {
        return Err(format!("its slices stack along world axis {}, not the grid's slab axis {}", "xyz".as_bytes()[world_slice_axis(info)?] as char, "xyz".as_bytes()[local[2]] as char));
    }
    Ok(Placement {
        axis,
        start: std::array::from_fn(|d| (grid.origin[local[d]] - m[local[d]][3]) / ax[local[d]].1),
        step: std::array::from_fn(|d| grid.cell / ax[local[d]].1),
        dims: info.dims,
        nodes: [na + 1, nb + 1, ns + 1],
    })
}

/// The node planes `[k0, k1)` that discretize task `task` of `parts` takes.
pub fn task_planes(grid: &Grid, parts: u32, task: u32) -> (u32, u32) {
    let planes = grid.local_dims()[2] as u64 + 1;
    let (a, b) = crate::plan::part_range(planes, parts.max(1), task, 1);
    (a as u32, b as u32)
}

/// Writes the crossings of node planes `[k0, k1)` (each with the S lines
/// to the plane after it) into `writer`, reading the slices they need from
/// `volume` placed by `p` on `grid` (its own engine frame, [`placement`],
/// or the world frame of a scene, [`world_placement`]), on `threads`
/// threads within `budget` bytes.
///
/// Planes are worked one after the other, each by every thread: a plane's
/// rows are cut into bands ([`band_rows`], set by the grid alone), bands
/// are sampled and crossed in parallel, a group of them at a time, and
/// written in band order. Memory is the slices of a batch of planes, two
/// node planes and their inside bits, and one group of bands' worst-case
/// crossings, whatever the volume holds; the records' order depends on the
/// grid only, never on threads or budget.
#[allow(clippy::too_many_arguments)]
pub fn discretize_planes(
    job: &VolumeJob,
    volume: &mut Volume,
    p: &Placement,
    grid: &Grid,
    (k0, k1): (u32, u32),
    writer: &mut ShardWriter,
    threads: usize,
    budget: u64,
    progress: &dyn Progress,
) -> Result<VolumeStats, PipelineError> {
    use rayon::prelude::*;
    let info = volume.info().clone();
    let p = *p;
    let field = job.surface.field();
    let iso = field.iso();
    let sampler = PlaneSampler::new(p);
    let ns = grid.local_dims()[2];
    let [na1, nb1, _] = p.nodes.map(|n| n as usize);
    let words = na1.div_ceil(64);
    let rows = band_rows(na1);
    let bands = nb1.div_ceil(rows);
    let slice_len = info.slice_len();
    let slice_bytes = slice_len as u64 * 4;
    let threads = threads.max(1);
    // Two node planes with their bits, two slices, one band per thread,
    // a slice of stored bytes for each extra reader of the slices, and
    // the read-ahead's buffer.
    let planes_bytes = 2 * (na1 * nb1 * 4 + nb1 * words * 8) as u64 + (threads.max(1) - 1) as u64 * volume.reader_bytes() + Volume::READ_AHEAD_BYTES;
    let band_bytes = (band_capacity(na1, rows) * std::mem::size_of::<Intercept>()) as u64;
    let least_group = threads.min(bands);
    let least = planes_bytes + 2 * slice_bytes + least_group as u64 * band_bytes;
    if least > budget {
        return Err(PipelineError::budget(
            &job.input,
            format!(
                "one slice of {} x {} samples needs {} MiB, and a task two of them, two planes of {} x {} nodes and {} bands of crossings: {} MiB, more than the memory budget ({} MiB); use more --mem or fewer threads",
                info.dims[0],
                info.dims[1],
                slice_bytes >> 20,
                na1,
                nb1,
                least_group,
                least.div_ceil(1 << 20),
                budget >> 20
            ),
        ));
    }
    // Up to four bands per thread in a group, then the rest for slices.
    let spare = budget - least;
    let group = (least_group + (spare / 2 / band_bytes) as usize).min(4 * threads).min(bands);
    let room = (budget - planes_bytes - group as u64 * band_bytes) / slice_bytes.max(1);
    // Planes per batch: as many as the slices in memory allow (a plane
    // reads at most two slices, neighbours share them), at most 64.
    let per_plane = p.step[2].abs().max(1.0);
    let batch = (((room - 2) as f64 / per_plane).floor() as u32 + 1).clamp(1, 64);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("mint-volume-{i}"))
        .build()
        .map_err(|e| PipelineError::stage(&job.input, format!("starting {threads} volume threads: {e}")))?;
    let mut stats = VolumeStats::default();
    let mut slices: Vec<f32> = Vec::new();
    let mut have: (u64, u64) = (0, 0);
    let (mut cur, mut nxt) = (vec![0f32; na1 * nb1], vec![0f32; na1 * nb1]);
    let (mut cur_bits, mut nxt_bits) = (vec![0u64; nb1 * words], vec![0u64; nb1 * words]);
    let mut outs: Vec<Vec<Intercept>> = (0..group).map(|_| Vec::with_capacity(band_capacity(na1, rows))).collect();
    // Planes sampled: k0 ..= last (the one after k1 - 1 for its S lines,
    // unless k1 - 1 is the last plane of the grid).
    let last = k1.min(ns);
    let mut q = k0;
    progress.start(crate::progress::DISCRETIZE, (k1 - k0) as u64);
    while q <= last {
        let end = (q + batch - 1).min(last);
        let (z0, z1) = p.slice_range(q, end);
        if z1 > z0 && (z0, z1) != have {
            // Keep the slices this batch shares with the last one (moved to
            // the front of the one buffer, which is reused, never zeroed again).
            let mut from = z0;
            if have.0 <= z0 && z0 < have.1 {
                let keep = (have.1.min(z1) - z0) as usize * slice_len;
                let at = (z0 - have.0) as usize * slice_len;
                slices.copy_within(at..at + keep, 0);
                from = have.1.min(z1);
            }
            slices.resize(((z1 - z0) as usize) * slice_len, 0.0);
            if from < z1 {
                let at = (from - z0) as usize * slice_len;
                let seen = volume.read_slices_on(from, z1 - from, &mut slices[at..], threads)?;
                stats.add_seen(&seen);
                stats.slices += z1 - from;
                stats.samples += (z1 - from) * slice_len as u64;
                // The next batch's new slices are read ahead on a thread
                // while this batch is worked: a volume larger than memory
                // then costs about its reading or its work, not both.
                if end < last {
                    let (n0, n1) = p.slice_range(end + 1, (end + batch).min(last));
                    let n0 = n0.max(z1);
                    if n1 > n0 {
                        volume.read_ahead(n0, n1 - n0);
                    }
                }
            }
            have = (z0, z1);
        }
        let slice_of = |z: u64| -> &[f32] {
            let i = (z - have.0) as usize;
            &slices[i * slice_len..(i + 1) * slice_len]
        };
        for q in q..=end {
            // Plane q's nodes and bits, band by band.
            let at = p.slices_of_plane(q).map(|(z, w)| (slice_of(z), if w > 0.0 { slice_of(z + 1) } else { slice_of(z) }, w));
            pool.install(|| {
                nxt.par_chunks_mut(rows * na1).zip(nxt_bits.par_chunks_mut(rows * words)).enumerate().for_each(|(b, (v, bits))| {
                    sampler.sample_rows(field, at, b * rows, v);
                    inside_rows(v, na1, iso, bits);
                })
            });
            std::mem::swap(&mut cur, &mut nxt);
            std::mem::swap(&mut cur_bits, &mut nxt_bits);
            // Now `cur` is plane q and `nxt` plane q - 1: cross q - 1 with q,
            // and the grid's last plane k1 - 1 = ns with nothing.
            let mut cross = |k: u32, planes: ((&[f32], &[u64]), Option<(&[f32], &[u64])>)| -> Result<(), PipelineError> {
                for g in (0..bands).step_by(group) {
                    let n = group.min(bands - g);
                    pool.install(|| {
                        outs[..n].par_iter_mut().enumerate().for_each(|(i, out)| {
                            out.clear();
                            let b = g + i;
                            band_crossings(&p, field, k, b * rows..((b + 1) * rows).min(nb1), planes.0, planes.1, out);
                        })
                    });
                    for out in &outs[..n] {
                        stats.records += out.len() as u64;
                        writer.append(out)?;
                    }
                }
                progress.advance(1);
                check_cancel(progress)
            };
            if q > k0 {
                cross(q - 1, ((&nxt, &nxt_bits), Some((&cur, &cur_bits))))?;
            }
            if q == ns && q < k1 {
                cross(q, ((&cur, &cur_bits), None))?;
            }
        }
        q = end + 1;
    }
    progress.finish();
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::VolumeSurface;

    fn job(own: bool) -> VolumeJob {
        VolumeJob { input: "v.nrrd".into(), raw: None, surface: VolumeSurface::Iso(0.5), own_grid: own, open_border: false, dicom_series: None }
    }

    fn info(dims: [u64; 3], m: [[f64; 4]; 3]) -> VolumeInfo {
        VolumeInfo {
            dims,
            sample: mint_volume::Sample::U8,
            index_to_world: m,
            frame: mint_volume::Frame::Lps,
            slope: 1.0,
            intercept: 0.0,
            format: "test",
            files: vec![],
            sequential_only: false,
        }
    }

    #[test]
    fn the_own_grid_puts_nodes_on_voxel_centres() {
        let i = info([5, 4, 3], [[2.0, 0.0, 0.0, 0.0], [0.0, 3.0, 0.0, 0.0], [0.0, 0.0, 4.0, 0.0]]);
        let g = grid(&job(true), &i, GridSize::Cells(10), [0.3; 3]).unwrap();
        assert_eq!(g.cell, 1.0);
        let p = placement(&job(true), &i, &g);
        assert!(p.on_voxels(), "{p:?}");
        assert_eq!(p.start, [-1.0; 3]);
    }

    #[test]
    fn the_output_map_mirrors_and_scales() {
        // LPS with i running to the right (-x): a mirror.
        let i = info([4, 4, 4], [[-0.5, 0.0, 0.0, 10.0], [0.0, 0.5, 0.0, 0.0], [0.0, 0.0, 2.0, -3.0]]);
        let g = grid(&job(false), &i, GridSize::CellSize(1.0), [0.0; 3]).unwrap();
        let m = OutputMap::new(&job(false), &i, &g);
        assert!(m.flip);
        // Engine point (index × spacing) (1, 1, 4) is index (2, 2, 2).
        assert_eq!(m.apply([1.0, 1.0, 4.0]), [9.0, 1.0, 1.0]);
        assert_eq!(m.cell, 1.0);
        let own = OutputMap::new(&job(true), &i, &grid(&job(true), &i, GridSize::Cells(1), [0.0; 3]).unwrap());
        assert_eq!(own.apply([2.0, 2.0, 2.0]), [9.0, 1.0, 1.0]);
        assert_eq!(own.cell, 0.5);
    }
}
