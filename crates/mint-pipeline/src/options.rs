//! What a run is asked to do ([`ResampleOptions`]) and what it reports
//! ([`ResampleSummary`]), for `resample`, `bool` and `csg` alike.

use mint_core::grid::{Axis, GridSize};
use mint_core::signs::SignRule;
use mint_io::WriteOptions;
use serde::Serialize;
use std::path::PathBuf;

/// Options of a resampling run. `Default` gives the documented defaults.
#[derive(Debug, Clone)]
pub struct ResampleOptions {
    /// Grid size (no default: the CLI requires `--cells` or `--cell-size`).
    pub size: GridSize,
    /// Heap budget in bytes; decides slab thickness. Default:
    /// [`default_mem_bytes`], a quarter of the machine's memory.
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
    /// closes every hole. Default `Some(16)`. (Booleans and CSG close every
    /// hole.)
    pub max_hole: Option<u32>,
    /// Keep the stages' results in this directory, so that a run killed at
    /// any moment resumes where it stopped when run again with the same
    /// directory. Default `None`: a temporary directory beside the output
    /// (or in `tmp_dir`), removed at the end.
    pub work_dir: Option<PathBuf>,
    /// Parts the input's faces are split into (one discretize task each).
    /// Default 1. More parts only split the work; the output is the same.
    pub parts: u32,
    /// Slabs the grid is split into (one reconstruct task each). Default 1.
    /// Each slab task still cuts its own work to fit `mem_bytes`.
    pub slabs: u32,
    /// How face corners are resolved to positions. Default `Auto`. Does
    /// not change the output.
    pub deref: crate::deref::Deref,
}

/// The default heap budget of every command: a quarter of the machine's
/// memory (`MemTotal` of /proc/meminfo), or 2 GiB where that is unknown.
pub fn default_mem_bytes() -> u64 {
    let total = || -> Option<u64> {
        let s = std::fs::read_to_string("/proc/meminfo").ok()?;
        let kb: u64 = s.lines().find(|l| l.starts_with("MemTotal:"))?.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb * 1024)
    };
    total().map_or(2 << 30, |r| r / 4)
}

impl Default for ResampleOptions {
    fn default() -> Self {
        ResampleOptions {
            size: GridSize::Cells(1_000_000),
            mem_bytes: default_mem_bytes(),
            threads: 0,
            tmp_dir: None,
            axis: None,
            slab_layers: None,
            grid_offset: [0.0; 3],
            write: WriteOptions::default(),
            max_listed: 100,
            signs: SignRule::Auto,
            max_hole: Some(16),
            work_dir: None,
            parts: 1,
            slabs: 1,
            deref: crate::deref::Deref::Auto,
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
    /// The output's own boundary: edges used by one face, and the loops
    /// they form (what `mint check` counts on the output).
    pub output_boundary_edges: u64,
    pub output_boundary_loops: u64,
    /// How faces were dereferenced (`mmap` or `sort`) and why, per part
    /// when parts decided differently; bytes the sort spilled to disk.
    pub deref: String,
    pub deref_spilled_bytes: u64,
    /// The work directory of a staged run (`None`: a temporary one).
    pub work_dir: Option<String>,
    /// Tasks run by this process, and tasks found already done (resumed).
    pub tasks_run: u64,
    pub tasks_resumed: u64,
    /// The tasks ran in other processes (`mint stage run`, Slurm): times
    /// are wall times between stage completions, and this process's memory
    /// says nothing of theirs.
    pub distributed: bool,
}
