//! What a run of the engine reports ([`ResampleSummary`]), for `resample`,
//! `bool` and `csg` alike. What a run is asked to do is `spec`.

use serde::Serialize;

pub use crate::spec::defaults::MAX_LISTED;

/// Everything a run measured; printed by the CLI and as JSON.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ResampleSummary {
    pub input: String,
    pub output: String,
    /// Files read, over every mesh operand (tiles count one each).
    pub input_files: u64,
    /// Tiles read from 3D Tiles tilesets (their finest level), 0 without.
    pub input_tiles: u64,
    /// Input files with per-vertex colour.
    pub input_coloured_files: u64,
    /// The output carries per-vertex colour (see `mint_core::colour`).
    pub colour: bool,
    /// `--no-color` was given.
    pub no_colour: bool,
    pub input_vertices: u64,
    pub input_faces: u64,
    /// Signed volume enclosed by the input (negative: inside-out).
    pub input_signed_volume: f64,
    /// True when the input was inside-out and its signs were reversed.
    pub orientation_inverted: bool,
    /// What decided the output's orientation: "volume" (a closed input: the
    /// sign of its volume; reversed when negative) or "faces" (an open
    /// input, which encloses no volume: its faces' own orientation).
    pub orientation_from: String,
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
    /// The output's coordinates: "f32", or "f64" with the reason.
    pub output_precision: String,
    pub non_canonical_cells: u64,
    /// Up to [`MAX_LISTED`] non-canonical cells, as (x, y, z) cell indices.
    pub non_canonical_list: Vec<[u32; 3]>,
    /// Seconds per phase.
    pub seconds_bounds: f64,
    pub seconds_discretize: f64,
    pub seconds_reconstruct: f64,
    pub seconds_write: f64,
    pub seconds_total: f64,
    /// Largest planned slab, in estimated heap bytes.
    pub planned_slab_bytes: u64,
    /// The sign rule used (`auto` resolved to `union`, `parity` or `sheet`).
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
    /// Temporary work directories that killed runs had left beside this
    /// one's, removed.
    pub removed_dead: Vec<String>,
    /// What the readers accepted but a user should know, one line each
    /// naming the file (undeclared values skipped, bytes after the body).
    #[serde(default)]
    pub input_warnings: Vec<String>,
    /// The tasks ran in other processes (`mint stage run`, Slurm): times
    /// are wall times between stage completions, and this process's memory
    /// says nothing of theirs.
    pub distributed: bool,
    /// The volume of a `mint volume` run (`None` for meshes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<VolumeSummary>,
}

/// What a `mint volume` run read, and in which frame it wrote.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct VolumeSummary {
    /// "NRRD", "MetaImage", "NIfTI-1", "DICOM series" (with the compression, e.g. "DICOM series (JPEG Lossless)"), "TIFF stack", "raw".
    pub format: String,
    pub dims: [u64; 3],
    /// Stored sample type (`u16`, `f32`, …) and rescale.
    pub sample: String,
    pub slope: f64,
    pub intercept: f64,
    /// World length of a voxel step along i, j, k.
    pub spacing: [f64; 3],
    /// The frame the output's coordinates are in (the file's).
    pub frame: String,
    /// `iso V` or `label V`.
    pub surface: String,
    /// True: one grid node per voxel centre (the volume's own resolution).
    pub own_grid: bool,
    /// `--open-border`: the surface is left open on the volume's border;
    /// the faces of the cap there that were left out.
    #[serde(default)]
    pub open_border: bool,
    #[serde(default)]
    pub border_faces_removed: u64,
    /// Border vertices split in two or more where the cap touched the rest
    /// of the surface at a vertex only (so that it stays a 2-manifold).
    #[serde(default)]
    pub border_vertices_split: u64,
    /// Slices and samples read (over all parts; neighbouring parts share
    /// slices), NaN samples, and the finite samples' range.
    pub slices_read: u64,
    pub samples_read: u64,
    pub nan_samples: u64,
    pub value_range: Option<[f32; 2]>,
}

impl ResampleSummary {
    /// Why the output is empty, or `None` when it has faces.
    pub fn empty_reason(&self) -> Option<&'static str> {
        if self.output_faces > 0 {
            return None;
        }
        Some(if self.intercepts_found == 0 {
            "no grid line crosses the surface (it is flat between grid lines or smaller than a cell; use smaller cells)"
        } else if self.intercepts_kept == 0 {
            "every crossing cancelled (the surface is thinner than a cell, or not closed)"
        } else {
            "no cell changes from outside to inside (the surface is thinner than a cell, not closed, or its holes were left open)"
        })
    }
}
