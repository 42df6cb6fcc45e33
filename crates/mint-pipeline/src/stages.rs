//! The stages of the engine, each a function of one task, and the small
//! reduce steps between them. A task reads the plan and the results of the
//! stages before it, and writes only into its own [`TaskBuild`].
//!
//! | stage         | tasks  | reads                         | writes                                   |
//! |---------------|--------|-------------------------------|------------------------------------------|
//! | `bounds`      | parts  | a range of each mesh's vertices | its box (JSON)                         |
//! | `discretize`  | parts  | a range of each mesh's faces  | shards per mesh, counts, chunk volumes   |
//! | `census`      | slabs  | the slab's planes (all parts) | line census per mesh (JSON)              |
//! | `reconstruct` | slabs  | the slab's planes             | `vertices.bin`, `faces.bin` (slab ids), hole-capping cells (`holes.bin`) |
//! | `reopen`      | slabs  | every slab's hole cells; the slab's planes when a hole stays open | nothing, or the slab again with the open holes left open |
//! | `write`       | 1      | every slab's vertices, faces  | the output, renamed into place           |
//!
//! `reopen` exists when holes wider than `--max-hole` stay open. The first
//! reconstruction closes every hole; only when the hole groups (a global
//! decision) leave some open is every slab reconstructed again with them
//! open, exactly as one process would; otherwise the first result stands.
//!
//! The reduces, each deterministic and cheap, run in whichever task needs
//! them: [`Ctx::grid`] (every bounds box → the grid), [`Ctx::inverted`]
//! (chunk volumes in chunk order → the inside-out sign), [`Ctx::slab_ranges`]
//! (per-plane counts → the slabs' layer ranges), [`Ctx::rules`] (line
//! census → each mesh's sign rule), [`Ctx::open_cells`] (hole cells → the
//! groups left open), [`Ctx::final_slab`] (which pass's result each slab keeps).
//!
//! Every vertex id depends only on the grid and the input
//! (`mint_core::reconstruct`), and the write stage concatenates slabs in
//! order, so the output bytes do not depend on parts, slabs, threads,
//! memory or task order.

use crate::error::PipelineError;
use crate::deref::{choose, discretize_sorted, Deref, DerefChoice, Faces, SortStats};
use mint_store::Budget;
use crate::bounds::bounds;
use crate::discretize::{discretize_all, discretize_direct, discretize_direct_coloured, CornerColours, discretize_direct_many, DirectPiece, CHUNK_TRIANGLES};
use crate::progress::check_cancel;
use crate::slabs::{bytes_per_plane, plan_slabs, reconstruct_ordered, Done, BYTES_PER_RECORD_IN_SLAB, COLOUR_BYTES_PER_RECORD_IN_SLAB};
use crate::plan::{part_range, MeshFile, OperandPlan, Plan, Stage};
use crate::error::in_file_list;
use crate::spec::{Job, Tuning};
use crate::progress::Progress;
use crate::scene::{Operand, Scene};
use crate::workdir::{read_records, read_result, FileSum, SumWriter, TaskBuild};
use mint_core::grid::Grid;
use mint_core::holes::{open_cells, HoleStats, OpenCells};
use mint_core::in_core::effective_max_hole;
use mint_core::intercept::filter_plane;
use mint_core::primitives::Transform;
use mint_core::reconstruct::reconstruct_slab;
use mint_core::expr::{BoolOp, Expr};
use mint_core::robust::{census_plane, reconstruct_slab_solids};
use mint_core::signs::{LineCensus, RepairStats, SignRule};
use mint_core::cells::SlabResult;
use mint_core::colour::{colour_vertices, sort_coloured, Tinted, WHITE};
use mint_core::{FilterStats, Intercept};
use mint_io::{Format, MeshReader, MeshWriter, ReadOptions};
use mint_store::{ShardManifest, ShardSet, ShardWriter};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock as OnceCell;
use std::path::{Path, PathBuf};

/// A bounds task's result: per operand, the box of its vertex range.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BoundsResult {
    pub operands: Vec<Option<[[f64; 3]; 2]>>,
    /// Per operand, the vertices this task read (summed over tasks: the
    /// surface's vertex count, which planning leaves to this stage for
    /// text files).
    #[serde(default)]
    pub vertices: Vec<u64>,
}

/// A discretize task's result for one piece (a file, or a range of its
/// faces) of a mesh operand. Its intercepts are in the task's shard store
/// of that operand, `op-J`, shared by every piece the task read.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MeshPart {
    /// The file of the operand (its index in the plan's `files`).
    pub file: u32,
    pub faces: u64,
    /// Six times the signed volume of each chunk of faces, in grid units.
    pub chunk_volumes6: Vec<f64>,
    /// How the faces were dereferenced, and what the sort did.
    #[serde(default)]
    pub deref: Option<DerefChoice>,
    #[serde(default)]
    pub sort: Option<SortStats>,
    /// What the reader accepted but a user should know (one line each).
    #[serde(default)]
    pub warnings: Vec<String>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DiscretizeResult {
    /// Per operand, the pieces this task read, in file order.
    pub operands: Vec<Vec<MeshPart>>,
    /// Per operand, the shard store (`op-J`) of all its pieces: one store
    /// per task, however many files the task read (`None`: no piece).
    pub shards: Vec<Option<ShardManifest>>,
    /// Per operand, what the task read of a volume (`None` for others).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub volumes: Vec<Option<crate::volume::VolumeStats>>,
}

/// A line census (see `mint_core::signs::LineCensus`).
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct Census {
    pub lines: u64,
    pub winding_valid: u64,
    pub odd: u64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CensusResult {
    pub operands: Vec<Option<Census>>,
}

/// What reconstruction repaired (see `mint_core::signs::RepairStats`).
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct Repair {
    pub inconsistent_lines: u64,
    pub synthesized_vertices: u64,
    pub merged_edges: u64,
    pub dropped_intercepts: u64,
}

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct ReconstructResult {
    pub layers: [u32; 2],
    pub sub_slabs: u64,
    pub planned_slab_bytes: u64,
    pub vertices: u64,
    pub faces: u64,
    pub vertices_file: Option<FileSum>,
    pub faces_file: Option<FileSum>,
    pub active_cells: u64,
    pub non_canonical_cells: u64,
    pub non_canonical_list: Vec<[u32; 3]>,
    pub filter_kept: u64,
    pub filter_removed: u64,
    pub repair: Repair,
    /// First pass: the slab's hole-capping cells (`holes.bin`).
    pub hole_cells: u64,
    pub holes_file: Option<FileSum>,
    /// `reopen`: no hole stays open, the first pass's result stands.
    pub reused: bool,
    /// `reopen` (holes left open): the directed edges used by one face of
    /// their sub-slab (`loose.bin`, u32 pairs, task-local ids): the
    /// output's boundary edges, and the seams between sub-slabs, which the
    /// summary pairs up across slabs.
    pub loose_edges: u64,
    pub loose_file: Option<FileSum>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WriteResult {
    pub output: PathBuf,
    pub vertices: u64,
    pub faces: u64,
    /// Coordinates written as f64, and why (or "f32").
    pub double: bool,
    pub precision: String,
    /// `--open-border` of a volume: what leaving the cap out did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open_border: Option<crate::volume::OpenBorder>,
}

/// Everything a task needs: the plan, its scene, this process's tuning
/// (threads, budget, dereferencing), and the reduces, each computed at most
/// once.
pub struct Ctx<'a> {
    pub dir: PathBuf,
    pub plan: Plan,
    pub scene: Scene,
    pub threads: usize,
    pub budget: Budget,
    /// How discretize tasks dereference faces (does not change the output).
    pub deref: Deref,
    /// Sub-slab thickness forced by `--slab` (does not change the output).
    pub slab_layers: Option<u32>,
    pub progress: &'a dyn Progress,
    grid: OnceCell<Grid>,
    parts: OnceCell<Vec<DiscretizeResult>>,
    rules: OnceCell<(Vec<SignRule>, Vec<Census>)>,
    open: OnceCell<(Option<OpenCells>, HoleStats)>,
    volume: OnceCell<Option<(crate::scene::VolumeJob, mint_volume::VolumeInfo)>>,
}

fn identity(t: &Transform) -> bool {
    t.m == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] && t.t == [0.0; 3]
}


/// The tasks `[s, e)` of `parts` that read file `i` of a surface: each
/// file gets a share of the tasks by its size, at least one, in file
/// order; many small files share a task, a large splittable one is split
/// over several (a single file gets them all).
pub fn file_tasks(files: &[MeshFile], parts: u32, i: usize) -> (u32, u32) {
    let w = |f: &MeshFile| f.bytes.max(1) as u128;
    let total: u128 = files.iter().map(w).sum();
    let before: u128 = files[..i].iter().map(w).sum();
    let p = parts.max(1) as u128;
    let s = ((p * before / total.max(1)) as u32).min(parts.max(1) - 1);
    let e = ((p * (before + w(&files[i])) / total.max(1)) as u32).clamp(s + 1, parts.max(1));
    (s, e)
}

/// The pieces of a surface's files that task `task` reads: `(file, range)`
/// with a range of vertices (`faces == false`) or of face records in whole
/// chunks (`faces == true`). A file whose faces cannot be read in ranges
/// is read whole by its first task (faces `(0, u64::MAX)`).
pub fn pieces(files: &[MeshFile], parts: u32, task: u32, faces: bool) -> Vec<(usize, (u64, u64))> {
    let mut v = Vec::new();
    for (i, f) in files.iter().enumerate() {
        let (s, e) = file_tasks(files, parts, i);
        if task < s || task >= e {
            continue;
        }
        let range = match (f.split_faces, faces) {
            (Some(n), true) => part_range(n, e - s, task - s, CHUNK_TRIANGLES as u64),
            (Some(_), false) => part_range(f.vertices.unwrap_or(0), e - s, task - s, 1),
            (None, _) if task != s => continue,
            (None, true) => (0, u64::MAX),
            (None, false) => (0, f.vertices.unwrap_or(u64::MAX)),
        };
        if range.0 < range.1 {
            v.push((i, range));
        }
    }
    v
}

impl<'a> Ctx<'a> {
    pub fn new(dir: &Path, plan: Plan, scene: Scene, tuning: &Tuning, progress: &'a dyn Progress) -> Ctx<'a> {
        let threads = tuning.thread_count().max(1);
        Ctx {
            dir: dir.to_path_buf(),
            plan,
            scene,
            threads,
            budget: Budget::new(tuning.mem_bytes, threads),
            deref: tuning.deref,
            slab_layers: tuning.slab_layers,
            progress,
            grid: OnceCell::new(),
            parts: OnceCell::new(),
            rules: OnceCell::new(),
            open: OnceCell::new(),
            volume: OnceCell::new(),
        }
    }

    /// The volume operand of a volume job and its header (read once).
    pub fn volume(&self) -> Result<Option<&(crate::scene::VolumeJob, mint_volume::VolumeInfo)>, PipelineError> {
        if let Some(v) = self.volume.get() {
            return Ok(v.as_ref());
        }
        let v = match self.scene.operands.as_slice() {
            [Operand::Volume(job)] => {
                let info = job.open()?.info().clone();
                Some(((**job).clone(), info))
            }
            // A volume among other operands is placed in the world frame
            // (`mesh_grid`, `discretize_task`): no engine frame to map from.
            _ => None,
        };
        Ok(self.volume.get_or_init(|| v).as_ref())
    }

    fn name(&self) -> PathBuf {
        self.plan.spec.job.path()
    }

    fn transform(&self, j: usize) -> Option<&Transform> {
        match &self.scene.operands[j] {
            Operand::Mesh { transform, .. } if !identity(transform) => Some(transform),
            _ => None,
        }
    }

    fn read_options(&self) -> ReadOptions {
        ReadOptions { chunk_triangles: CHUNK_TRIANGLES, spill_dir: Some(self.dir.clone()), resolve_positions: false }
    }

    // ----- reduces -----

    /// The grid, from every bounds task's boxes.
    /// Vertices of mesh operand `j`, as the bounds stage read them.
    pub fn vertices_read(&self, j: usize) -> Result<u64, PipelineError> {
        let mut n = 0;
        for t in 0..self.plan.tasks(Stage::Bounds) {
            let r: BoundsResult = read_result(&self.dir, Stage::Bounds, t)?;
            n += r.vertices.get(j).copied().unwrap_or(0);
        }
        Ok(n)
    }

    pub fn grid(&self) -> Result<&Grid, PipelineError> {
        if let Some(g) = self.grid.get() {
            return Ok(g);
        }
        let n = self.scene.operands.len();
        let mut leaf: Vec<Option<([f64; 3], [f64; 3])>> = vec![None; n];
        for t in 0..self.plan.tasks(Stage::Bounds) {
            let r: BoundsResult = read_result(&self.dir, Stage::Bounds, t)?;
            for (j, b) in r.operands.iter().enumerate().take(n) {
                if let Some([l, h]) = b {
                    let e = leaf[j].get_or_insert(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]));
                    for d in 0..3 {
                        e.0[d] = e.0[d].min(l[d]);
                        e.1[d] = e.1[d].max(h[d]);
                    }
                }
            }
        }
        let g = &self.plan.spec.grid;
        let grid = if let Some((job, info)) = self.volume()? {
            crate::volume::grid(job, info, g.size, g.offset).map_err(|source| PipelineError::Grid { path: self.name(), source })?
        } else {
            self.mesh_grid(&leaf)?
        };
        self.check_layers(&grid)?;
        Ok(self.grid.get_or_init(|| grid))
    }

    /// The grid around mesh and primitive operands.
    fn mesh_grid(&self, leaf: &[Option<([f64; 3], [f64; 3])>]) -> Result<Grid, PipelineError> {
        let mut boxes = Vec::with_capacity(leaf.len());
        for (j, op) in self.scene.operands.iter().enumerate() {
            boxes.push(match op {
                Operand::Primitive(p) => p.bounds(),
                Operand::Mesh { paths, .. } => leaf[j].ok_or_else(|| PipelineError::Empty { path: paths.first().cloned().unwrap_or_default() })?,
                Operand::Volume(v) => {
                    let info = v.open()?.info().clone();
                    crate::volume::world_box(&info).map_err(|m| PipelineError::stage(&v.input, format!("as an operand of a scene: {m}")))?
                }
            });
        }
        let (elo, ehi) = expr_bounds(&self.scene.expr, &boxes);
        if (0..3).any(|d| !(elo[d].is_finite() && ehi[d].is_finite())) {
            return Err(PipelineError::Unbounded { path: self.name() });
        }
        if (0..3).any(|d| elo[d] > ehi[d]) {
            return Err(PipelineError::Empty { path: self.name() });
        }
        // The grid holds every bounded operand whole (so that every line
        // starts and ends outside each of them), not only the result's box.
        let (mut lo, mut hi) = (elo, ehi);
        for (l, h) in &boxes {
            for d in 0..3 {
                if l[d].is_finite() && h[d].is_finite() {
                    lo[d] = lo[d].min(l[d]);
                    hi[d] = hi[d].max(h[d]);
                }
            }
        }
        let g = &self.plan.spec.grid;
        // Volume operands stream by slices: the slab axis is the world axis
        // their slices stack along (one for all of them).
        let mut axis = g.axis.index();
        for op in &self.scene.operands {
            if let Operand::Volume(v) = op {
                let info = v.open()?.info().clone();
                let a = crate::volume::world_slice_axis(&info).map_err(|m| PipelineError::stage(&v.input, format!("as an operand of a scene: {m}")))?;
                match axis {
                    Some(b) if b != a => {
                        let name = |x: usize| "xyz".as_bytes()[x] as char;
                        let why = if g.axis.index().is_some() { "--axis".to_string() } else { "another volume operand".to_string() };
                        return Err(PipelineError::stage(&v.input, format!("its slices stack along {}, but {why} asks for slabs along {}: volumes stream slice by slice, so the slab axis must be theirs", name(a), name(b))));
                    }
                    _ => axis = Some(a),
                }
            }
        }
        Grid::around(lo, hi, g.size, g.offset, axis).map_err(|source| PipelineError::Grid { path: self.name(), source })
    }

    /// Refuses a grid whose per-layer tables would not fit the budget.
    fn check_layers(&self, grid: &Grid) -> Result<(), PipelineError> {
        // Tables with an entry per layer (a count per plane in each part's
        // result, as a number in its JSON, and their sum) grow with the
        // layers, not the input: a needle 10^7 cells long must not exhaust
        // memory before any slab is planned.
        let layers = grid.local_dims()[2] as u64 + 1;
        // Pieces: at most a part per task and file of every mesh operand.
        let pieces: u64 = self.plan.operands.iter().map(|o| match o {
            OperandPlan::Mesh { files } => self.plan.parts as u64 + files.len() as u64,
            OperandPlan::Volume => self.plan.parts as u64,
            OperandPlan::Primitive => 0,
        }).sum();
        let need = layers * BYTES_PER_LAYER_ENTRY * (pieces + 1);
        if need > self.budget.layer_tables() {
            return Err(PipelineError::budget(
                self.name(),
                format!(
                    "the grid has {} layers along its slab axis ({}x{}x{} cells of {:.3e}); its per-layer tables need about {} MiB, more than half the memory budget ({} MiB): use larger cells, or more --mem",
                    layers - 1,
                    grid.dims[0],
                    grid.dims[1],
                    grid.dims[2],
                    grid.cell,
                    need >> 20,
                    self.budget.total() >> 20
                ),
            ));
        }
        Ok(())
    }

    /// Every discretize task's result, in part order.
    pub fn parts(&self) -> Result<&[DiscretizeResult], PipelineError> {
        if let Some(p) = self.parts.get() {
            return Ok(p);
        }
        let mut v = Vec::new();
        for t in 0..self.plan.tasks(Stage::Discretize) {
            v.push(read_result::<DiscretizeResult>(&self.dir, Stage::Discretize, t)?);
        }
        // What the results claim, checked before anything indexes by it.
        let planes = self.grid()?.local_dims()[2] + 1;
        for (t, r) in v.iter().enumerate() {
            let path = crate::workdir::task_dir(&self.dir, Stage::Discretize, t as u32).join(crate::workdir::RESULT_FILE);
            if r.operands.len() != self.scene.operands.len() {
                return Err(PipelineError::stage(&path, format!("damaged task result: {} operands, the plan has {}; remove its task directory and run the task again", r.operands.len(), self.scene.operands.len())));
            }
            for (j, ms) in r.operands.iter().enumerate() {
                let files = match &self.plan.operands[j] {
                    OperandPlan::Mesh { files } => files,
                    OperandPlan::Volume if ms.is_empty() => {
                        match r.shards.get(j) {
                            Some(Some(m)) => {
                                if let Err(what) = m.validate(planes) {
                                    return Err(PipelineError::stage(&path, format!("damaged task result: {what}; remove its task directory and run the task again")));
                                }
                            }
                            Some(None) => {}
                            None => return Err(PipelineError::stage(&path, format!("damaged task result: no shard entry for volume operand {j}; remove its task directory and run the task again"))),
                        }
                        continue;
                    }
                    OperandPlan::Primitive if ms.is_empty() => continue,
                    OperandPlan::Primitive | OperandPlan::Volume => {
                        return Err(PipelineError::stage(&path, format!("damaged task result: shards for operand {j}, which is not a mesh; remove its task directory and run the task again")))
                    }
                };
                let expected: Vec<usize> = pieces(files, self.plan.parts, t as u32, true).iter().map(|p| p.0).collect();
                let got: Vec<usize> = ms.iter().map(|m| m.file as usize).collect();
                // A piece may be missing (a file that turned out to hold no
                // triangle), never unplanned or out of order.
                if got.iter().any(|f| !expected.contains(f)) || got.windows(2).any(|w| w[0] >= w[1]) {
                    return Err(PipelineError::stage(&path, format!("damaged task result: operand {j} lists files {got:?}, the plan gives this task {expected:?}; remove its task directory and run the task again")));
                }
                match r.shards.get(j) {
                    Some(Some(m)) if !ms.is_empty() => {
                        if let Err(what) = m.validate(planes) {
                            return Err(PipelineError::stage(&path, format!("damaged task result: {what}; remove its task directory and run the task again")));
                        }
                    }
                    Some(None) if ms.is_empty() => {}
                    _ => return Err(PipelineError::stage(&path, format!("damaged task result: operand {j}'s shard store does not match its pieces; remove its task directory and run the task again"))),
                }
            }
        }
        for (j, op) in self.scene.operands.iter().enumerate() {
            if let Operand::Mesh { paths, .. } = op {
                if v.iter().flat_map(|r| r.operands[j].iter()).map(|m| m.faces).sum::<u64>() == 0 {
                    return Err(PipelineError::Empty { path: paths.first().cloned().unwrap_or_default() });
                }
            }
        }
        Ok(self.parts.get_or_init(|| v))
    }

    /// The shards of mesh operand `j`, over every part.
    pub fn shards(&self, j: usize) -> Result<ShardSet, PipelineError> {
        let mut set = ShardSet::new();
        for (t, r) in self.parts()?.iter().enumerate() {
            if let Some(Some(m)) = r.shards.get(j) {
                set.push(crate::workdir::task_dir(&self.dir, Stage::Discretize, t as u32).join(format!("op-{j}")), m.clone());
            }
        }
        Ok(set)
    }

    /// Faces, and the signed volume (grid units), of mesh operand `j`: the
    /// chunk volumes summed file by file in the order of the files' paths
    /// (not the order they were given in), each file's in chunk order, as
    /// one process would: the same sum for any split and any order.
    pub fn faces_and_volume(&self, j: usize) -> Result<(u64, f64), PipelineError> {
        let mut faces = 0;
        let OperandPlan::Mesh { files } = &self.plan.operands[j] else { return Ok((0, 0.0)) };
        // Tasks in order hold a file's pieces in chunk order.
        let mut pieces: Vec<(&Path, &[f64])> = Vec::new();
        for r in self.parts()? {
            for m in &r.operands[j] {
                faces += m.faces;
                pieces.push((files[m.file as usize].path.as_path(), &m.chunk_volumes6));
            }
        }
        pieces.sort_by(|a, b| a.0.cmp(b.0));
        let mut sum = 0.0f64;
        for (_, vs) in pieces {
            for v in vs {
                sum += v;
            }
        }
        Ok((faces, sum / 6.0))
    }

    /// True when mesh operand `j` encloses a negative volume, as an
    /// inside-out closed mesh does.
    fn negative_volume(&self, j: usize) -> Result<bool, PipelineError> {
        Ok(matches!(self.scene.operands[j], Operand::Mesh { .. }) && self.faces_and_volume(j)?.1 < 0.0)
    }

    /// True when mesh operand `j` is inside-out (negative volume) and read
    /// as a solid: its signs are reversed, so that it reads as the solid it
    /// encloses. An open input (the Sheet rule) encloses nothing, so its
    /// volume's sign says nothing: its faces' orientation is kept.
    pub fn inverted(&self, j: usize) -> Result<bool, PipelineError> {
        Ok(self.negative_volume(j)? && self.rules()?.0[j] != SignRule::Sheet)
    }

    /// Records per plane, over every mesh operand.
    fn plane_counts(&self) -> Result<Vec<u64>, PipelineError> {
        let [_, _, ns] = self.grid()?.local_dims();
        let mut c = vec![0u64; ns as usize + 1];
        for r in self.parts()? {
            for m in r.shards.iter().flatten() {
                for (a, b) in c.iter_mut().zip(&m.counts) {
                    *a += b;
                }
            }
        }
        Ok(c)
    }

    /// The layer ranges `[a, b)` of the plan's slabs: consecutive layers,
    /// cut where the running count of records passes each equal share.
    pub fn slab_ranges(&self) -> Result<Vec<(u32, u32)>, PipelineError> {
        let [_, _, ns] = self.grid()?.local_dims();
        let counts = self.plane_counts()?;
        Ok(slab_ranges(&counts[..ns as usize], self.plan.slabs))
    }

    /// Each operand's sign rule, and each mesh's census (summed over slabs).
    pub fn rules(&self) -> Result<&(Vec<SignRule>, Vec<Census>), PipelineError> {
        if let Some(r) = self.rules.get() {
            return Ok(r);
        }
        let n = self.scene.operands.len();
        let mut census = vec![Census::default(); n];
        if self.plan.has_stage(Stage::Census) {
            for t in 0..self.plan.tasks(Stage::Census) {
                let r: CensusResult = read_result(&self.dir, Stage::Census, t)?;
                for (j, c) in r.operands.iter().enumerate().take(n) {
                    if let Some(c) = c {
                        census[j].lines += c.lines;
                        census[j].winding_valid += c.winding_valid;
                        census[j].odd += c.odd;
                    }
                }
            }
        }
        let asked = self.plan.spec.signs;
        let strict = self.plan.strict();
        let resample = matches!(self.plan.spec.job, Job::Resample { .. });
        let rules = self
            .scene
            .operands
            .iter()
            .zip(&census)
            .map(|(op, c)| match op {
                Operand::Primitive(_) | Operand::Volume(_) => SignRule::Union,
                Operand::Mesh { .. } => {
                    let census = LineCensus { lines: c.lines, winding_valid: c.winding_valid, odd: c.odd };
                    match asked {
                        SignRule::Orient if strict => SignRule::Orient,
                        // Operands of a boolean are solids whatever their census.
                        SignRule::Auto | SignRule::Orient if !resample => census.resolve_closed(),
                        SignRule::Auto | SignRule::Orient => census.resolve(),
                        r => r,
                    }
                }
            })
            .collect();
        Ok(self.rules.get_or_init(|| (rules, census)))
    }

    /// The hole-capping cells left open (`None`: close every hole).
    pub fn open_cells(&self) -> Result<&(Option<OpenCells>, HoleStats), PipelineError> {
        if let Some(o) = self.open.get() {
            return Ok(o);
        }
        let result = match self.plan.spec.max_hole {
            Some(k) if self.plan.has_stage(Stage::Reopen) => {
                let mut cells: Vec<u64> = Vec::new();
                for t in 0..self.plan.tasks(Stage::Reconstruct) {
                    let r: ReconstructResult = read_result(&self.dir, Stage::Reconstruct, t)?;
                    let path = crate::workdir::task_dir(&self.dir, Stage::Reconstruct, t).join("holes.bin");
                    if let Some(sum) = r.holes_file {
                        read_records::<8>(&path, sum, |b| {
                            cells.push(u64::from_le_bytes(*b));
                            Ok(())
                        })?;
                    }
                }
                let k = effective_max_hole(self.rules()?.0[0], k);
                let (set, stats) = open_cells(&mut cells, self.grid()?.local_dims(), k);
                ((!set.is_empty()).then_some(set), stats)
            }
            _ => (None, HoleStats::default()),
        };
        Ok(self.open.get_or_init(|| result))
    }

    /// The stage whose result slab `t` keeps, and that result: `reopen`'s
    /// when it reconstructed the slab again, else `reconstruct`'s.
    pub fn final_slab(&self, t: u32) -> Result<(Stage, ReconstructResult), PipelineError> {
        if self.plan.has_stage(Stage::Reopen) {
            let r: ReconstructResult = read_result(&self.dir, Stage::Reopen, t)?;
            if !r.reused {
                return Ok((Stage::Reopen, r));
            }
        }
        Ok((Stage::Reconstruct, read_result(&self.dir, Stage::Reconstruct, t)?))
    }

    /// Every operand's raw intercepts for planes `k0 ..= k1` (the last one
    /// without its layer's S records, except under the Sheet rule), inside-out
    /// meshes reversed; and, per operand, its raw records of plane `k0 - 1`
    /// when the Sheet rule needs them (else empty).
    ///
    /// With `coloured`, also the coloured raw records of the owned planes
    /// `k0 .. k1`, every operand's together, sorted for
    /// [`colour_vertices`] (primitives are white).
    #[allow(clippy::type_complexity)]
    fn operand_planes(&self, k0: u32, k1: u32, coloured: bool) -> Result<(Vec<Vec<Vec<Intercept>>>, Vec<Vec<Intercept>>, Option<Vec<Vec<Tinted>>>), PipelineError> {
        let grid = self.grid()?;
        let rules = &self.rules()?.0;
        let mut operands = Vec::with_capacity(self.scene.operands.len());
        let mut below = Vec::with_capacity(self.scene.operands.len());
        let mut tinted: Option<Vec<Vec<Tinted>>> = coloured.then(|| vec![Vec::new(); (k1 - k0) as usize]);
        for (j, op) in self.scene.operands.iter().enumerate() {
            let sheet = rules[j] == SignRule::Sheet;
            operands.push(match op {
                Operand::Mesh { .. } | Operand::Volume(_) => {
                    let first = if sheet && k0 > 0 { k0 - 1 } else { k0 };
                    let mut planes = match tinted.as_mut() {
                        Some(t) => {
                            let read = self.shards(j)?.read_planes_coloured(first, k1, !sheet)?;
                            let planes = read.iter().map(|p| p.iter().map(|r| r.0).collect()).collect();
                            for (k, p) in read.into_iter().enumerate() {
                                let k = first + k as u32;
                                if k >= k0 && k < k1 {
                                    t[(k - k0) as usize].extend(p);
                                }
                            }
                            planes
                        }
                        None => self.shards(j)?.read_planes(first, k1, !sheet)?,
                    };
                    check_records(&planes, first, grid, &self.dir)?;
                    if self.inverted(j)? {
                        planes.iter_mut().flatten().for_each(|r| r.signed_value = -r.signed_value);
                    }
                    below.push(if first < k0 { planes.remove(0) } else { Vec::new() });
                    planes
                }
                Operand::Primitive(p) => {
                    below.push(Vec::new());
                    let planes: Vec<Vec<Intercept>> = (k0..=k1).map(|k| p.plane_intercepts(grid, k, k < k1)).collect();
                    if let Some(t) = tinted.as_mut() {
                        for (k, p) in planes[..(k1 - k0) as usize].iter().enumerate() {
                            t[k].extend(p.iter().map(|&r| (r, WHITE)));
                        }
                    }
                    planes
                }
            });
        }
        if let Some(t) = tinted.as_mut() {
            t.iter_mut().for_each(|p| sort_coloured(p));
        }
        Ok((operands, below, tinted))
    }

    /// Sub-slabs of layers `a .. b` that fit the budget, and (with more
    /// than one thread) small enough that every thread gets several: a
    /// slab's records are at most a quarter of one thread's share, but never
    /// below [`MIN_SUB_SLAB_BYTES`]. The output does not depend on the cut.
    fn sub_slabs(&self, a: u32, b: u32) -> Result<Vec<(u32, u32)>, PipelineError> {
        let counts = self.plane_counts()?;
        if a >= b {
            return Ok(Vec::new());
        }
        let [na, nb, _] = self.grid()?.local_dims();
        let plane_bytes = bytes_per_plane(na, nb);
        let mut budget = self.budget.slab_in_flight();
        if self.threads > 1 {
            let bytes = counts[a as usize..=b as usize].iter().sum::<u64>() * self.record_bytes_in_slab() + (b - a + 1) as u64 * plane_bytes;
            budget = budget.min((bytes / (4 * self.threads as u64)).max(MIN_SUB_SLAB_BYTES));
        }
        // plan_slabs counts geometry-only records: a coloured run's
        // budget shrinks by what colour adds per record.
        let budget = budget / self.record_bytes_in_slab() * BYTES_PER_RECORD_IN_SLAB;
        let subs = plan_slabs(&counts, a, b, self.slab_layers, budget, plane_bytes);
        if self.slab_layers.is_some() {
            return Ok(subs);
        }
        // At most MAX_SUB_SLAB_CELLS cells a sub-slab (a cancellation is
        // seen between sub-slabs), but never fewer layers than a shard
        // holds (each sub-slab streams the shards it overlaps).
        let ns = self.grid()?.local_dims()[2] as u64 + 1;
        let per_shard = ns.div_ceil(mint_store::MAX_SHARDS as u64);
        let most = (MAX_SUB_SLAB_CELLS / (na as u64 * nb as u64).max(1)).max(per_shard).max(1) as u32;
        Ok(subs
            .into_iter()
            .flat_map(|(k0, k1)| {
                let n = (k1 - k0).div_ceil(most).max(1);
                (0..n).map(move |i| (k0 + (k1 - k0) * i / n, k0 + (k1 - k0) * (i + 1) / n))
            })
            .collect())
    }

    /// Planned heap bytes per record of a slab in memory.
    fn record_bytes_in_slab(&self) -> u64 {
        BYTES_PER_RECORD_IN_SLAB + if self.plan.coloured() { COLOUR_BYTES_PER_RECORD_IN_SLAB } else { 0 }
    }

    /// Warms every reduce a slab task needs, so that worker threads only read.
    fn prepare_slab_task(&self) -> Result<(), PipelineError> {
        self.grid()?;
        self.parts()?;
        self.rules()?;
        Ok(())
    }
}

/// Heap bytes per layer per table of per-layer entries: the u64 count and
/// its decimal text in a task result (the parsed copy replaces the writer's).
const BYTES_PER_LAYER_ENTRY: u64 = 16;

/// The smallest sub-slab worth a thread of its own, in planned bytes.
const MIN_SUB_SLAB_BYTES: u64 = 1 << 20;

/// The most cells a sub-slab reconstructs: 16M, about 0.3 s of one thread
/// (a 400M-cell grid on a 2.8 GHz Xeon), so that Ctrl-C is answered within
/// a second (issue 29) however large the memory budget lets sub-slabs be.
const MAX_SUB_SLAB_CELLS: u64 = 1 << 24;

/// Splits layers `0 .. counts.len()` into `slabs` consecutive ranges, cut
/// where the running count passes each `i / slabs` share of the total (and
/// never inside a layer); empty ranges when there are fewer layers.
pub fn slab_ranges(counts: &[u64], slabs: u32) -> Vec<(u32, u32)> {
    let ns = counts.len() as u32;
    let total: u64 = counts.iter().sum();
    let mut cuts = vec![0u32];
    let (mut k, mut run) = (0u32, 0u64);
    for i in 1..slabs {
        let share = (total as u128 * i as u128 / slabs as u128) as u64;
        let last = *cuts.last().unwrap();
        // Leave at least one layer for each slab still to come, when there are enough.
        let max_k = ns.saturating_sub(slabs - i);
        while k < max_k && (run < share || k == last) {
            run += counts[k as usize];
            k += 1;
        }
        cuts.push(k);
    }
    cuts.push(ns);
    cuts.windows(2).map(|w| (w[0], w[1].max(w[0]))).collect()
}

/// The bounding box of an expression over its leaves' boxes.
fn expr_bounds(e: &Expr, leaf: &[([f64; 3], [f64; 3])]) -> ([f64; 3], [f64; 3]) {
    match e {
        Expr::Operand(i) => leaf[*i],
        Expr::Op(op, c) => {
            let bs: Vec<_> = c.iter().map(|x| expr_bounds(x, leaf)).collect();
            match op {
                BoolOp::Union => bs.iter().fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(l, h), (bl, bh)| {
                    ([0, 1, 2].map(|d| l[d].min(bl[d])), [0, 1, 2].map(|d| h[d].max(bh[d])))
                }),
                BoolOp::Intersection => bs.iter().fold(([f64::NEG_INFINITY; 3], [f64::INFINITY; 3]), |(l, h), (bl, bh)| {
                    ([0, 1, 2].map(|d| l[d].max(bl[d])), [0, 1, 2].map(|d| h[d].min(bh[d])))
                }),
                BoolOp::Difference => bs[0],
            }
        }
    }
}

/// Checks what every record read from shards claims against the grid: its
/// plane, family, line and position. Checksums catch accidents, not content:
/// a crafted or stale shard whose checksum is valid must be refused with one
/// line, never index past a line table.
fn check_records(planes: &[Vec<Intercept>], k0: u32, grid: &Grid, dir: &Path) -> Result<(), PipelineError> {
    use mint_core::intercept::{FAMILY_A, FAMILY_B, FAMILY_S};
    let [na, nb, ns] = grid.local_dims();
    for (i, plane) in planes.iter().enumerate() {
        let k = k0 + i as u32;
        for r in plane {
            let v = r.signed_value.abs();
            let (lines, span) = match r.family() {
                FAMILY_A => (nb as u64 + 1, na as f64),
                FAMILY_B => (na as u64 + 1, nb as f64),
                FAMILY_S => ((na as u64 + 1) * (nb as u64 + 1), ns as f64),
                _ => (0, 0.0),
            };
            if r.plane != k || (r.index() as u64) >= lines || !(v.is_finite() && v <= span + 1.0) {
                return Err(PipelineError::stage(
                    dir,
                    format!(
                        "a shard record claims plane {}, family {}, line {}, position {} in plane {k}, outside the {na}x{nb}x{ns}-cell grid: the work directory is damaged or not this run's; remove it and run again",
                        r.plane,
                        r.family(),
                        r.index(),
                        r.signed_value
                    ),
                ));
            }
        }
    }
    Ok(())
}

// ----- the stages -----

/// Runs task `task` of `stage` into `build`; returns the result to commit.
pub fn run_stage_task(ctx: &Ctx, stage: Stage, task: u32, build: &TaskBuild) -> Result<serde_json::Value, PipelineError> {
    let v = match stage {
        Stage::Bounds => serde_json::to_value(bounds_task(ctx, task)?),
        Stage::Discretize => serde_json::to_value(discretize_task(ctx, task, build.path())?),
        Stage::Census => serde_json::to_value(census_task(ctx, task)?),
        Stage::Reconstruct => serde_json::to_value(reconstruct_task(ctx, task, build.path(), false)?),
        Stage::Reopen => serde_json::to_value(reconstruct_task(ctx, task, build.path(), true)?),
        Stage::Write => serde_json::to_value(write_task(ctx)?),
    };
    Ok(v.expect("results serialize"))
}

fn bounds_task(ctx: &Ctx, task: u32) -> Result<BoundsResult, PipelineError> {
    let mut operands = Vec::new();
    let mut vertices = Vec::new();
    for (j, op) in ctx.scene.operands.iter().enumerate() {
        let (Operand::Mesh { .. }, OperandPlan::Mesh { files }) = (op, &ctx.plan.operands[j]) else {
            operands.push(None);
            vertices.push(0);
            continue;
        };
        let mut bx: Option<[[f64; 3]; 2]> = None;
        let mut read = 0u64;
        for (k, range) in pieces(files, ctx.plan.parts, task, false) {
            let path = &files[k].path;
            let b = (|| {
                let reader = MeshReader::open(path, ctx.read_options())?;
                // A text file's count is known once it is open.
                let range = (range.0, range.1.min(reader.vertex_count() as u64));
                read += range.1.saturating_sub(range.0);
                bounds(&reader.positions(), range, path, ctx.threads, ctx.progress, ctx.transform(j))
            })()
            .map_err(|e| in_file_list(e, k, files.len()))?;
            if let Some((l, h)) = b {
                let e = bx.get_or_insert([l, h]);
                for d in 0..3 {
                    e[0][d] = e[0][d].min(l[d]);
                    e[1][d] = e[1][d].max(h[d]);
                }
            }
            check_cancel(ctx.progress)?;
        }
        operands.push(bx);
        vertices.push(read);
    }
    Ok(BoundsResult { operands, vertices })
}

fn discretize_task(ctx: &Ctx, task: u32, out: &Path) -> Result<DiscretizeResult, PipelineError> {
    let mut operands = Vec::new();
    let mut shards = Vec::new();
    let mut volumes = Vec::new();
    if let Some((job, _)) = ctx.volume()? {
        let grid = ctx.grid()?;
        let planes = crate::volume::task_planes(grid, ctx.plan.parts, task);
        if planes.0 >= planes.1 {
            return Ok(DiscretizeResult { operands: vec![Vec::new()], shards: vec![None], volumes: vec![None] });
        }
        let mut volume = job.open()?;
        let dir = make_dir(&out.join("op-0"))?;
        let mut writer = ShardWriter::create(&dir, grid.local_dims()[2] + 1);
        let p = crate::volume::placement(job, volume.info(), grid);
        let stats = crate::volume::discretize_planes(job, &mut volume, &p, grid, planes, &mut writer, ctx.threads, ctx.budget.volume(), ctx.progress)?;
        return Ok(DiscretizeResult { operands: vec![Vec::new()], shards: vec![Some(writer.finish()?)], volumes: vec![Some(stats)] });
    }
    for (j, op) in ctx.scene.operands.iter().enumerate() {
        if let Operand::Volume(job) = op {
            // A volume among other operands: this task's node planes, on
            // the scene's world grid.
            let grid = ctx.grid()?;
            let planes = crate::volume::task_planes(grid, ctx.plan.parts, task);
            operands.push(Vec::new());
            volumes.resize(j, None);
            if planes.0 >= planes.1 {
                shards.push(None);
                volumes.push(None);
                continue;
            }
            let mut volume = job.open()?;
            let info = volume.info().clone();
            let p = crate::volume::world_placement(&info, grid).map_err(|m| PipelineError::stage(&job.input, format!("as an operand of a scene: {m}")))?;
            let dir = make_dir(&out.join(format!("op-{j}")))?;
            let mut writer = ShardWriter::create(&dir, grid.local_dims()[2] + 1);
            let stats = crate::volume::discretize_planes(job, &mut volume, &p, grid, planes, &mut writer, ctx.threads, ctx.budget.volume(), ctx.progress)?;
            shards.push(Some(writer.finish()?));
            volumes.push(Some(stats));
            continue;
        }
        let (Operand::Mesh { .. }, OperandPlan::Mesh { files }) = (op, &ctx.plan.operands[j]) else {
            operands.push(Vec::new());
            shards.push(None);
            continue;
        };
        let mine = pieces(files, ctx.plan.parts, task, true);
        if mine.is_empty() {
            operands.push(Vec::new());
            shards.push(None);
            continue;
        }
        // One store for every piece: many small files (tiles) cost one set
        // of shard files per task, not one per file.
        let [_, _, ns] = ctx.grid()?.local_dims();
        let dir = make_dir(&out.join(format!("op-{j}")))?;
        let mut writer = if ctx.plan.coloured() { ShardWriter::create_coloured(&dir, ns + 1) } else { ShardWriter::create(&dir, ns + 1) };
        let parts = match discretize_pieces_at_once(ctx, j, files, &mine, &mut writer)? {
            Some(parts) => parts,
            None => {
                let mut parts = Vec::new();
                for (k, range) in mine {
                    let part = discretize_piece(ctx, j, &files[k], k as u32, range, &mut writer).map_err(|e| in_file_list(e, k, files.len()))?;
                    parts.push(part);
                    check_cancel(ctx.progress)?;
                }
                parts
            }
        };
        operands.push(parts);
        shards.push(Some(writer.finish()?));
    }
    volumes.resize(operands.len(), None);
    Ok(DiscretizeResult { operands, shards, volumes })
}

/// Discretizes several pieces (tiles) of mesh operand `j` in one queue of
/// chunks ([`discretize_direct_many`]) when every one of them is read
/// directly from its map: the common case of many binary tiles. `None`
/// (nothing written) when one is not, or when one turns out to hold
/// polygons: the caller then reads them one by one.
fn discretize_pieces_at_once(ctx: &Ctx, j: usize, files: &[MeshFile], mine: &[(usize, (u64, u64))], writer: &mut ShardWriter) -> Result<Option<Vec<MeshPart>>, PipelineError> {
    // Coloured files stream through the reader (see `discretize_piece`).
    if mine.len() < 2 || (writer.coloured() && mine.iter().any(|&(k, _)| files[k].colour)) {
        return Ok(None);
    }
    let mut opened = Vec::with_capacity(mine.len());
    for &(k, range) in mine {
        let reader = MeshReader::open(&files[k].path, ctx.read_options()).map_err(|e| in_file_list(e.into(), k, files.len()))?;
        let Some(mut records) = (if files[k].split_faces.is_some() { reader.triangle_records().map_err(|e| in_file_list(e.into(), k, files.len()))? } else { None }) else {
            return Ok(None);
        };
        let positions = reader.positions();
        let on = records.prefetch_pays(&positions, range);
        records.set_prefetch(on);
        records.set_positions_known_finite(true);
        let choice = choose(ctx.deref, Some(&records), &positions, range);
        if choice.sort {
            return Ok(None);
        }
        opened.push((k, range, records, choice));
    }
    let direct: Vec<DirectPiece> = opened.iter().map(|(k, range, records, _)| DirectPiece { records, range: *range, file: *k }).collect();
    let checkpoint = writer.checkpoint();
    match discretize_direct_many(&direct, files.len(), ctx.grid()?, writer, ctx.threads, ctx.progress, ctx.transform(j)) {
        Ok(done) => Ok(Some(
            opened
                .into_iter()
                .zip(done)
                .map(|((k, _, _, choice), (faces, chunk_volumes6))| MeshPart { file: k as u32, faces, chunk_volumes6, deref: Some(choice), sort: None, warnings: Vec::new() })
                .collect(),
        )),
        Err(PipelineError::Io(e)) if e.kind() == mint_io::ErrorKind::Unsupported => {
            writer.rollback(checkpoint)?;
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// Discretizes faces `range` of `file` (file `k` of mesh operand `j`) into
/// the task's shard store of that operand.
fn discretize_piece(ctx: &Ctx, j: usize, file: &MeshFile, k: u32, range: (u64, u64), writer: &mut ShardWriter) -> Result<MeshPart, PipelineError> {
    let grid = ctx.grid()?;
    let (path, split_faces) = (&file.path, file.split_faces);
    // The whole file, read by this one task.
    let whole = range.0 == 0 && split_faces.is_none_or(|n| range.1 >= n);
    let reader = MeshReader::open(path, ctx.read_options())?;
    // Files with fixed-size records are read directly by every worker;
    // others (and, as one part, files that turn out to hold polygons)
    // stream through the reader.
    // A coloured file in a coloured run: its crossings take its colours
    // (read by vertex index; never by the sort, which carries positions only).
    // Textures may take half the task's budget.
    let colours = if writer.coloured() { CornerColours::of(&reader, ctx.budget.total() / 2)? } else { None };
    let mut direct = match split_faces {
        Some(_) => reader.triangle_records()?,
        None => None,
    };
    let positions = reader.positions();
    if let Some(records) = direct.as_mut() {
        let on = records.prefetch_pays(&positions, range);
        records.set_prefetch(on);
        // The bounds stage, complete before any discretize task (the
        // grid is made from its results), checked every vertex finite.
        records.set_positions_known_finite(true);
    }
    let mut choice = choose(ctx.deref, direct.as_ref(), &positions, range);
    if colours.is_some() {
        choice.sort = false;
    }
    let mut result = None;
    let mut sort_stats = None;
    let mut warnings = Vec::new();
    if let Some(records) = &direct {
        let checkpoint = writer.checkpoint();
        let run = if let Some(cs) = &colours {
            discretize_direct_coloured(records, &positions, cs, range, grid, writer, ctx.threads, ctx.progress, ctx.transform(j))
        } else if choice.sort {
            let faces = Faces::Records { records, first: range.0, end: range.1 };
            discretize_sorted(faces, &positions, grid, writer, ctx.threads, ctx.progress, ctx.transform(j), &ctx.dir, &ctx.budget).map(|(n, v, st)| {
                sort_stats = Some(st);
                (n, v)
            })
        } else {
            discretize_direct(records, range, grid, writer, ctx.threads, ctx.progress, ctx.transform(j))
        };
        match run {
            Ok(r) => result = Some(r),
            // Faces that turn out not to be triangles: what was written of
            // this file is taken back, and the file streamed instead.
            Err(PipelineError::Io(e)) if whole && e.kind() == mint_io::ErrorKind::Unsupported => writer.rollback(checkpoint)?,
            Err(e) => return Err(e),
        }
    }
    let (faces, chunk_volumes6) = match result {
        Some(r) => r,
        None => {
            let mut reader = if !whole && split_faces.is_some() { MeshReader::open_range(path, ctx.read_options(), range.0, range.1)? } else { reader };
            let expected = if range.1 == u64::MAX { reader.info().face_count.unwrap_or(0) } else { range.1 - range.0 };
            let r = if choice.sort {
                let positions = reader.positions();
                let (n, v, st) = discretize_sorted(Faces::Reader(&mut reader), &positions, grid, writer, ctx.threads, ctx.progress, ctx.transform(j), &ctx.dir, &ctx.budget)?;
                sort_stats = Some(st);
                (n, v)
            } else {
                let first = if !whole && split_faces.is_some() { range.0 } else { 0 };
                discretize_all(&mut reader, grid, writer, ctx.threads, ctx.progress, ctx.transform(j), expected, first, colours.as_ref())?
            };
            warnings = reader.warnings();
            r
        }
    };
    Ok(MeshPart { file: k, faces, chunk_volumes6, deref: Some(choice), sort: sort_stats, warnings })
}

fn make_dir(dir: &Path) -> Result<PathBuf, PipelineError> {
    std::fs::create_dir(dir).map_err(|source| PipelineError::Temp { path: dir.to_path_buf(), op: "creating a shard directory", source })?;
    Ok(dir.to_path_buf())
}

fn census_task(ctx: &Ctx, task: u32) -> Result<CensusResult, PipelineError> {
    let (a, b) = ctx.slab_ranges()?[task as usize];
    let mut operands = Vec::new();
    for (j, op) in ctx.scene.operands.iter().enumerate() {
        if !matches!(op, Operand::Mesh { .. }) {
            operands.push(None);
            continue;
        }
        let shards = ctx.shards(j)?;
        // Before the rules exist: the census's odd count does not depend on
        // the sign, and its winding count matters only for closed inputs.
        let invert = ctx.negative_volume(j)?;
        let mut c = LineCensus::default();
        for (k0, k1) in ctx.sub_slabs(a, b)? {
            let mut planes = shards.read_planes(k0, k1 - 1, false)?;
            check_records(&planes, k0, ctx.grid()?, &ctx.dir)?;
            for p in &mut planes {
                if invert {
                    p.iter_mut().for_each(|r| r.signed_value = -r.signed_value);
                }
                c += census_plane(p);
            }
            check_cancel(ctx.progress)?;
        }
        operands.push(Some(Census { lines: c.lines, winding_valid: c.winding_valid, odd: c.odd }));
    }
    Ok(CensusResult { operands })
}

/// Reconstructs slab `task`: the first pass (`reopen` false) closes every
/// hole and records the hole-capping cells; the second (`reopen` true) runs
/// only when some hole group stays open, and leaves those open.
fn reconstruct_task(ctx: &Ctx, task: u32, out: &Path, reopen: bool) -> Result<ReconstructResult, PipelineError> {
    ctx.prepare_slab_task()?;
    let (a, b) = ctx.slab_ranges()?[task as usize];
    let grid = ctx.grid()?;
    let (rules, _) = ctx.rules()?;
    let strict = ctx.plan.strict();
    let open = if reopen {
        match ctx.open_cells()?.0.as_ref() {
            Some(set) => Some(set),
            None => return Ok(ReconstructResult { layers: [a, b], reused: true, ..Default::default() }),
        }
    } else {
        None
    };
    let collect_holes = !reopen && ctx.plan.has_stage(Stage::Reopen);
    let mut holes = if collect_holes { Some(SumWriter::create(out.join("holes.bin"))?) } else { None };
    let mut hole_cells = 0u64;
    let max_listed = crate::summary::MAX_LISTED;
    let subs = ctx.sub_slabs(a, b)?;
    let counts = ctx.plane_counts()?;
    let mut r = ReconstructResult { layers: [a, b], sub_slabs: subs.len() as u64, ..Default::default() };
    let [na, nb, _] = grid.local_dims();
    r.planned_slab_bytes = subs
        .iter()
        .map(|&(k0, k1)| counts[k0 as usize..=k1 as usize].iter().sum::<u64>() * ctx.record_bytes_in_slab() + (k1 - k0 + 1) as u64 * bytes_per_plane(na, nb))
        .max()
        .unwrap_or(0);
    let coloured = ctx.plan.coloured();
    let compute = |k0: u32, k1: u32| -> Result<Done, PipelineError> {
        let (mut operands, below, tinted) = ctx.operand_planes(k0, k1, coloured)?;
        let colour = |res: &SlabResult| match &tinted {
            Some(t) => colour_vertices(grid, k0, &res.vertices, t),
            None => Vec::new(),
        };
        if !strict {
            let (res, rep) = reconstruct_slab_solids(grid, k0, operands, rules, &ctx.scene.expr, open, &below);
            let c = colour(&res);
            return Ok((res, c, FilterStats::default(), rep));
        }
        let mut planes = operands.swap_remove(0);
        let mut stats = FilterStats::default();
        let owned = planes.len() - 1;
        for (n, p) in planes.iter_mut().enumerate() {
            let f = filter_plane(p);
            if n < owned {
                stats += f;
            }
        }
        let res = reconstruct_slab(grid, k0, &planes, max_listed);
        let c = colour(&res);
        Ok((res, c, stats, RepairStats::default()))
    };
    let mut vfile = SumWriter::create(out.join("vertices.bin"))?;
    let mut ffile = SumWriter::create(out.join("faces.bin"))?;
    let mut loose = if reopen { Some(SumWriter::create(out.join("loose.bin"))?) } else { None };
    let mut loose_edges = 0u64;
    let mut filter = FilterStats::default();
    let mut repair = RepairStats::default();
    ctx.progress.start(crate::progress::RECONSTRUCT, (b - a) as u64);
    reconstruct_ordered(&subs, ctx.threads, &compute, ctx.progress, &mut |res, colours, f, rep, layers| {
        filter += f;
        repair += rep;
        if let Some(h) = holes.as_mut() {
            for c in &res.hole_cells {
                h.write(&c.to_le_bytes())?;
            }
            hole_cells += res.hole_cells.len() as u64;
        }
        for (i, v) in res.vertices.iter().enumerate() {
            let mut bytes = [0u8; VERTEX_BYTES + 4];
            for d in 0..3 {
                bytes[8 * d..8 * d + 8].copy_from_slice(&v[d].to_le_bytes());
            }
            match colours.get(i) {
                Some(c) => {
                    bytes[VERTEX_BYTES..].copy_from_slice(c);
                    vfile.write(&bytes)?;
                }
                None => vfile.write(&bytes[..VERTEX_BYTES])?,
            }
        }
        for f in &res.faces {
            let mut bytes = [0u8; 12];
            for d in 0..3 {
                let id = u32::try_from(f[d] as u64 + r.vertices).map_err(|_| PipelineError::stage(&ctx.plan.spec.output, "more than 2^32 output vertices in one slab; use more slabs"))?;
                bytes[4 * d..4 * d + 4].copy_from_slice(&id.to_le_bytes());
            }
            ffile.write(&bytes)?;
        }
        if let Some(l) = loose.as_mut() {
            for (a, b) in edges_used_once(&res.faces) {
                let (a, b) = ((a as u64 + r.vertices) as u32, (b as u64 + r.vertices) as u32);
                let mut bytes = [0u8; 8];
                bytes[..4].copy_from_slice(&a.to_le_bytes());
                bytes[4..].copy_from_slice(&b.to_le_bytes());
                l.write(&bytes)?;
                loose_edges += 1;
            }
        }
        r.vertices += res.vertices.len() as u64;
        r.faces += res.faces.len() as u64;
        r.active_cells += res.stats.active_cells;
        r.non_canonical_cells += res.stats.non_canonical_cells;
        let room = max_listed.saturating_sub(r.non_canonical_list.len());
        r.non_canonical_list.extend(res.non_canonical.iter().take(room));
        ctx.progress.advance(layers);
        Ok(())
    })?;
    ctx.progress.finish();
    r.vertices_file = Some(vfile.finish()?);
    r.hole_cells = hole_cells;
    r.holes_file = holes.map(|h| h.finish()).transpose()?;
    r.faces_file = Some(ffile.finish()?);
    r.loose_edges = loose_edges;
    r.loose_file = loose.map(|l| l.finish()).transpose()?;
    r.filter_kept = filter.kept;
    r.filter_removed = filter.removed;
    r.repair = Repair {
        inconsistent_lines: repair.inconsistent_lines,
        synthesized_vertices: repair.synthesized_vertices,
        merged_edges: repair.merged_edges,
        dropped_intercepts: repair.dropped_intercepts,
    };
    Ok(r)
}

/// The directed edges of `faces` that no other face of the list uses, in
/// face order.
fn edges_used_once(faces: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut count: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::with_capacity(faces.len() * 2);
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut out = Vec::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if count[&(a.min(b), a.max(b))] == 1 {
                out.push((a, b));
            }
        }
    }
    out
}

/// Boundary edges and loops of the whole output, from every slab's loose
/// edges (`ids` offset to global): an edge is a boundary edge when exactly
/// one face of the whole output uses it; a loop is a cycle of boundary
/// edges through vertices with exactly one boundary edge in and one out
/// (the definition `mint check` counts by).
pub fn boundary_of(loose: &[(u32, u32)]) -> (u64, u64) {
    use std::collections::HashMap;
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for &(a, b) in loose {
        *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
    }
    let boundary: Vec<(u32, u32)> = loose.iter().copied().filter(|&(a, b)| count[&(a.min(b), a.max(b))] == 1).collect();
    let mut outd: HashMap<u32, (u32, u32)> = HashMap::new();
    let mut ind: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in &boundary {
        let e = outd.entry(a).or_insert((0, b));
        e.0 += 1;
        *ind.entry(b).or_insert(0) += 1;
    }
    let simple = |v: u32| outd.get(&v).is_some_and(|o| o.0 == 1) && ind.get(&v) == Some(&1);
    let mut seen: std::collections::HashSet<u32> = std::collections::HashSet::new();
    let mut loops = 0;
    let mut starts: Vec<u32> = boundary.iter().map(|e| e.0).collect();
    starts.sort_unstable();
    starts.dedup();
    for s in starts {
        if seen.contains(&s) || !simple(s) {
            continue;
        }
        let mut v = s;
        let mut path = Vec::new();
        let closed = loop {
            if !simple(v) || !seen.insert(v) {
                break v == s && !path.is_empty();
            }
            path.push(v);
            v = outd[&v].1;
        };
        if closed {
            loops += 1;
        }
    }
    (boundary.len() as u64, loops)
}

/// Bytes of one vertex in a slab's `vertices.bin` (three f64), followed
/// in a coloured run by its RGBA.
const VERTEX_BYTES: usize = 24;

fn write_task(ctx: &Ctx) -> Result<WriteResult, PipelineError> {
    let output = &ctx.plan.spec.output;
    let format = Format::from_path(output)?;
    // f32 only where it places every vertex within a small fraction of a
    // cell (mint_io::precision): geo-referenced and tiny models get f64.
    let grid = ctx.grid()?;
    let hi: [f64; 3] = std::array::from_fn(|d| grid.origin[d] + grid.dims[d] as f64 * grid.cell);
    // A volume's vertices go from its engine frame to the frame its file declares.
    let map = ctx.volume()?.map(|(job, info)| crate::volume::OutputMap::new(job, info, grid));
    let ((lo, hi), cell) = match &map {
        Some(m) => (m.bounds(grid.origin, hi), m.cell),
        None => ((grid.origin, hi), grid.cell),
    };
    let tolerance = cell * crate::spec::defaults::F32_TOLERANCE_CELLS;
    let (double, precision) = mint_io::precision::choose(output, format, ctx.plan.spec.write.double, lo, hi, tolerance)?;
    let flip = map.is_some_and(|m| m.flip);
    let coloured = ctx.plan.coloured();
    let write = mint_io::WriteOptions { double, ..ctx.plan.spec.write.options(Some(ctx.dir.clone()), coloured) };
    let slabs: Vec<(Stage, ReconstructResult)> = (0..ctx.plan.tasks(Stage::Reconstruct)).map(|t| ctx.final_slab(t)).collect::<Result<_, _>>()?;
    let mut total_faces: u64 = slabs.iter().map(|(_, s)| s.faces).sum();
    let no_file = FileSum { len: 0, crc32: 0 };
    // --open-border: the cap on the volume's border is left out, and with
    // it the vertices only the cap used (two more passes over the slabs).
    let cut = match ctx.volume()? {
        Some((job, info)) if job.open_border => {
            let files: Vec<crate::volume::SlabFiles> = slabs
                .iter()
                .enumerate()
                .map(|(t, (stage, s))| {
                    let dir = crate::workdir::task_dir(&ctx.dir, *stage, t as u32);
                    crate::volume::SlabFiles { vertices: dir.join("vertices.bin"), vertices_sum: s.vertices_file.unwrap_or(no_file), faces: dir.join("faces.bin"), faces_sum: s.faces_file.unwrap_or(no_file), count: s.vertices }
                })
                .collect();
            let bytes = if coloured { VERTEX_BYTES + 4 } else { VERTEX_BYTES };
            let c = crate::volume::BorderCut::new(&files, bytes, crate::volume::domain(job, info), grid.cell, ctx.budget.total() / 2, &ctx.name(), boundary_of)?;
            total_faces -= c.counts.faces_removed;
            Some(c)
        }
        _ => None,
    };
    let mut writer = MeshWriter::create(output, format, write)?;
    let mut global = 0u64;
    // --open-border: the split vertices' copies, written after the rest.
    let mut copies: Vec<([f64; 3], Option<[u8; 4]>)> = Vec::new();
    let mut next_copy = 0usize;
    ctx.progress.start(crate::progress::WRITE, total_faces);
    for (t, (stage, s)) in slabs.iter().enumerate() {
        let path = crate::workdir::task_dir(&ctx.dir, *stage, t as u32).join("vertices.bin");
        let sum = s.vertices_file.unwrap_or(FileSum { len: 0, crc32: 0 });
        let mut vertex = |b: &[u8], rgba: Option<[u8; 4]>| -> Result<(), PipelineError> {
            let c = |d: usize| f64::from_le_bytes(b[8 * d..8 * d + 8].try_into().unwrap());
            global += 1;
            if cut.as_ref().is_some_and(|c| !c.keeps(global - 1)) {
                return Ok(());
            }
            let mut v = [c(0), c(1), c(2)];
            if let Some(m) = &map {
                v = m.apply(v);
            }
            if !v.iter().all(|x| x.is_finite()) {
                return Err(PipelineError::NonFiniteResult { path: ctx.name(), x: v[0], y: v[1], z: v[2] });
            }
            if let Some(c) = &cut {
                while c.copies.get(next_copy) == Some(&(global - 1)) {
                    copies.push((v, rgba));
                    next_copy += 1;
                }
            }
            match rgba {
                Some(c) => writer.write_vertex_rgba(v, c)?,
                None => writer.write_vertex(v)?,
            }
            Ok(())
        };
        if coloured {
            read_records::<{ VERTEX_BYTES + 4 }>(&path, sum, |b| vertex(b, Some(b[VERTEX_BYTES..].try_into().unwrap())))?;
        } else {
            read_records::<VERTEX_BYTES>(&path, sum, |b| vertex(b, None))?;
        }
        check_cancel(ctx.progress)?;
    }
    for (v, rgba) in copies {
        match rgba {
            Some(c) => writer.write_vertex_rgba(v, c)?,
            None => writer.write_vertex(v)?,
        }
    }
    let total_vertices: u64 = slabs.iter().map(|(_, s)| s.vertices).sum();
    let mut offset = 0u64;
    let mut written = 0u64;
    for (t, (stage, s)) in slabs.iter().enumerate() {
        let path = crate::workdir::task_dir(&ctx.dir, *stage, t as u32).join("faces.bin");
        read_records::<12>(&path, s.faces_file.unwrap_or(FileSum { len: 0, crc32: 0 }), |b| {
            let id = |d: usize| u32::from_le_bytes(b[4 * d..4 * d + 4].try_into().unwrap()) as u64 + offset;
            let mut f = if flip { [id(0), id(2), id(1)] } else { [id(0), id(1), id(2)] };
            // A damaged slab result is blamed on itself, before its
            // checksum (checked at its end) could say so: never on the output.
            if f.iter().any(|&v| v >= total_vertices) {
                return Err(PipelineError::stage(&path, format!("damaged slab result: a face names vertex {} of {total_vertices}; remove its task directory and run the task again", f.iter().max().unwrap())));
            }
            if let Some(c) = &cut {
                match c.face(f) {
                    Some(g) => f = g,
                    None => return Ok(()),
                }
            }
            writer.write_face(f.map(|v| v as u32))?;
            written += 1;
            if written % (1 << 16) == 0 {
                ctx.progress.advance(1 << 16);
                check_cancel(ctx.progress)?;
            }
            Ok(())
        })?;
        offset += s.vertices;
    }
    let vertices = cut.as_ref().map_or(offset, |c| c.kept_vertices);
    if vertices > u32::MAX as u64 + 1 {
        return Err(PipelineError::stage(output, format!("{vertices} output vertices do not fit 32-bit indices; use a coarser grid")));
    }
    writer.finish()?;
    ctx.progress.finish();
    Ok(WriteResult { output: output.clone(), vertices, faces: total_faces, double, precision, open_border: cut.map(|c| c.counts) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_cover_every_item_once_in_whole_chunks() {
        for (n, parts, chunk) in [(0u64, 3u32, 4u64), (10, 1, 4), (10, 3, 4), (1000, 7, 64), (5, 9, 1)] {
            let mut next = 0;
            for i in 0..parts {
                let (a, b) = part_range(n, parts, i, chunk);
                assert_eq!(a, next);
                assert!(a == n || a % chunk == 0);
                next = b;
            }
            assert_eq!(next, n);
        }
    }

    #[test]
    fn slab_ranges_tile_the_layers_and_balance_records() {
        let counts = vec![1u64, 1, 1, 100, 1, 1, 100, 1, 1, 1];
        let r = slab_ranges(&counts, 3);
        assert_eq!(r.len(), 3);
        assert_eq!(r[0].0, 0);
        assert_eq!(r[2].1, 10);
        assert!(r.windows(2).all(|w| w[0].1 == w[1].0));
        assert!(r.iter().all(|&(a, b)| b > a), "{r:?}");
        // More slabs than layers: every layer once, the rest empty.
        let r = slab_ranges(&[5, 5], 4);
        assert_eq!(r.len(), 4);
        assert_eq!(r.iter().map(|&(a, b)| b - a).sum::<u32>(), 2);
        assert_eq!(slab_ranges(&[3, 4, 5], 1), vec![(0, 3)]);
    }
}
