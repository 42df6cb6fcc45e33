//! The one description of a run of the engine, in two halves:
//!
//! - [`RunSpec`]: everything that decides the output bytes (the job and
//!   its inputs, the output, the grid, the sign rule, the hole limit, how
//!   the output is written). A resumed run must match it exactly; the plan
//!   (`DIR/plan.json`) embeds it as it is, and every task reads it back.
//! - [`Tuning`]: everything that does not (memory, threads, dereferencing,
//!   temporary directory, slab thickness, the work directory and its split
//!   into parts and slabs). Any of it may change between a plan and its
//!   tasks, or between a run and its resumption, without changing a byte.
//!
//! The defaults of both are stated once, here ([`defaults`]), and the
//! command line shows them from here. Adding an option that changes the
//! output is a field of [`RunSpec`] (or of one of its parts) and a flag of
//! the CLI's one argument group that builds it; see docs/ARCHITECTURE.md.

use crate::deref::Deref;
use crate::error::PipelineError;
use crate::scene::{parse_scene, Operand, Scene};
pub use crate::scene::{RawLayout, VolumeJob, VolumeSurface};
use mint_core::expr::{BoolOp, Expr};
use mint_core::grid::{Axis, GridSize};
use mint_core::signs::SignRule;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Every default of a run, stated once.
pub mod defaults {
    use mint_core::signs::SignRule;
    /// `--signs`.
    pub const SIGNS: SignRule = SignRule::Auto;
    /// `--max-hole`: holes wider than this many cells stay open (resample).
    pub const MAX_HOLE: u32 = 16;
    /// `--parts` and `--slabs`.
    pub const PARTS: u32 = 1;
    pub const SLABS: u32 = 1;
    /// Non-canonical cells listed in a summary.
    pub const MAX_LISTED: usize = 100;
    /// Outputs are written in f32 only when f32 places every vertex within
    /// this fraction of a cell (else f64; `--double` forces f64).
    pub const F32_TOLERANCE_CELLS: f64 = 1e-3;
}

mint_core::choice! {
    /// The axis along which the grid is cut into slabs (`--axis`); `auto`
    /// picks the grid's longest.
    pub enum SlabAxis {
        Auto => "auto",
        X => "x",
        Y => "y",
        Z => "z",
    }
}

impl SlabAxis {
    /// The axis index, `None` for `auto`.
    pub fn index(self) -> Option<Axis> {
        match self {
            SlabAxis::Auto => None,
            SlabAxis::X => Some(0),
            SlabAxis::Y => Some(1),
            SlabAxis::Z => Some(2),
        }
    }
}

/// What a run evaluates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Job {
    /// Resample one surface, given as one or more files.
    Resample { inputs: Vec<PathBuf> },
    /// `a op b` for two surfaces, each one or more files, or a voxel
    /// volume's iso-surface at `iso_a` / `iso_b` (one file or folder).
    Bool {
        op: BoolOp,
        a: Vec<PathBuf>,
        b: Vec<PathBuf>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        iso_a: Option<f32>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        iso_b: Option<f32>,
    },
    /// A CSG scene file.
    Csg { scene: PathBuf },
    /// The iso-surface (or a label's boundary) of a voxel volume.
    Volume(VolumeJob),
}

impl Job {
    /// The scene this job evaluates.
    pub fn scene(&self) -> Result<Scene, PipelineError> {
        let mesh = |p: &[PathBuf]| Operand::Mesh { paths: p.to_vec(), transform: Default::default() };
        Ok(match self {
            Job::Resample { inputs } => Scene { expr: Expr::Operand(0), operands: vec![mesh(inputs)] },
            Job::Bool { op, a, b, iso_a, iso_b } => {
                let side = |p: &[PathBuf], iso: Option<f32>| match (iso, p) {
                    (Some(v), [input]) => Operand::Volume(Box::new(VolumeJob { input: input.clone(), raw: None, surface: crate::scene::VolumeSurface::Iso(v), own_grid: false, open_border: false, dicom_series: None })),
                    _ => mesh(p),
                };
                Scene { expr: Expr::Op(*op, vec![Expr::Operand(0), Expr::Operand(1)]), operands: vec![side(a, *iso_a), side(b, *iso_b)] }
            }
            Job::Csg { scene } => {
                let text = std::fs::read_to_string(scene)
                    .map_err(|source| PipelineError::Temp { path: scene.clone(), op: "reading the scene", source })?;
                parse_scene(&text, scene)?
            }
            Job::Volume(v) => Scene { expr: Expr::Operand(0), operands: vec![Operand::Volume(Box::new(v.clone()))] },
        })
    }

    /// How the summary names the input.
    pub fn name(&self) -> String {
        match self {
            Job::Resample { inputs } => files_name(inputs),
            Job::Bool { op, a, b, .. } => format!("{} {op} {}", files_name(a), files_name(b)),
            Job::Csg { scene } => scene.display().to_string(),
            Job::Volume(v) => v.input.display().to_string(),
        }
    }

    /// The file errors about the whole job are reported against.
    pub fn path(&self) -> PathBuf {
        match self {
            Job::Resample { inputs } => first(inputs),
            Job::Bool { a, .. } => first(a),
            Job::Csg { scene } => scene.clone(),
            Job::Volume(v) => v.input.clone(),
        }
    }

    /// The same job with every path made absolute (tasks may run in another
    /// directory, on another machine).
    pub fn absolute(&self) -> Job {
        let all = |v: &[PathBuf]| v.iter().map(|p| absolute(p)).collect::<Vec<_>>();
        match self {
            Job::Resample { inputs } => Job::Resample { inputs: all(inputs) },
            Job::Bool { op, a, b, iso_a, iso_b } => Job::Bool { op: *op, a: all(a), b: all(b), iso_a: *iso_a, iso_b: *iso_b },
            Job::Csg { scene } => Job::Csg { scene: absolute(scene) },
            Job::Volume(v) => Job::Volume(VolumeJob { input: absolute(&v.input), ..v.clone() }),
        }
    }
}

fn first(v: &[PathBuf]) -> PathBuf {
    v.first().cloned().unwrap_or_default()
}

/// How a summary names the files of one surface.
pub fn files_name(v: &[PathBuf]) -> String {
    match v {
        [] => String::new(),
        [one] => one.display().to_string(),
        [a, rest @ ..] => format!("{} and {} more file{}", a.display(), rest.len(), if rest.len() == 1 { "" } else { "s" }),
    }
}

/// An absolute path, without resolving links (so that a plan names what
/// the user named, from any machine that mounts it at the same place).
pub fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// The grid: its size, slab axis, and shift.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// About N cubic cells over the bounding box, or cells of size H.
    pub size: GridSize,
    /// Axis along which the grid is cut into slabs.
    pub axis: SlabAxis,
    /// Grid shift in fractions of a cell.
    pub offset: [f64; 3],
}

impl GridSpec {
    /// A grid of `size`, other fields at their defaults.
    pub fn of(size: GridSize) -> GridSpec {
        GridSpec { size, axis: SlabAxis::Auto, offset: [0.0; 3] }
    }
}

/// How the output is encoded (its format follows the output's extension).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WriteSpec {
    /// Text PLY or STL instead of binary.
    pub ascii: bool,
    /// Coordinates as f64 even where f32 would place them within
    /// [`defaults::F32_TOLERANCE_CELLS`] of a cell (elsewhere f64 is chosen
    /// anyway).
    pub double: bool,
    /// Geometry only, even when the input has colour and the output's
    /// format holds it (`--no-color`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub no_colour: bool,
}

impl WriteSpec {
    /// The writer's options, spilling into `spill_dir`; `colours` when the
    /// run carries colour.
    pub fn options(&self, spill_dir: Option<PathBuf>, colours: bool) -> mint_io::WriteOptions {
        mint_io::WriteOptions { ascii: self.ascii, double: self.double, spill_dir, colours }
    }
}

/// Everything that decides a run's output bytes; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    pub job: Job,
    pub output: PathBuf,
    pub grid: GridSpec,
    /// How crossing signs become inside/outside (see `mint_core::signs`).
    /// For `bool` and `csg` it applies to each mesh operand.
    pub signs: SignRule,
    /// Holes whose capping cells span more than this many cells stay open
    /// (robust rules); `None` closes every hole. Booleans and CSG close
    /// every hole.
    pub max_hole: Option<u32>,
    pub write: WriteSpec,
}

impl RunSpec {
    /// A run of `job` into `output` on a grid of `size`, every other field
    /// at its default (booleans and CSG close every hole).
    pub fn new(job: Job, output: impl Into<PathBuf>, size: GridSize) -> RunSpec {
        let max_hole = match job {
            Job::Resample { .. } => Some(defaults::MAX_HOLE),
            _ => None,
        };
        RunSpec { job, output: output.into(), grid: GridSpec::of(size), signs: defaults::SIGNS, max_hole, write: WriteSpec::default() }
    }

    /// Resampling `input` into `output`.
    pub fn resample(input: impl Into<PathBuf>, output: impl Into<PathBuf>, size: GridSize) -> RunSpec {
        RunSpec::new(Job::Resample { inputs: vec![input.into()] }, output, size)
    }

    /// `a op b` into `output`.
    pub fn boolean(op: BoolOp, a: impl Into<PathBuf>, b: impl Into<PathBuf>, output: impl Into<PathBuf>, size: GridSize) -> RunSpec {
        RunSpec::new(Job::Bool { op, a: vec![a.into()], b: vec![b.into()], iso_a: None, iso_b: None }, output, size)
    }

    /// The scene file `scene` into `output`.
    pub fn csg(scene: impl Into<PathBuf>, output: impl Into<PathBuf>, size: GridSize) -> RunSpec {
        RunSpec::new(Job::Csg { scene: scene.into() }, output, size)
    }

    /// The spec as the engine runs it: booleans and CSG close every hole.
    pub fn normalized(&self) -> RunSpec {
        let mut s = self.clone();
        if !matches!(s.job, Job::Resample { .. }) {
            s.max_hole = None;
        }
        s
    }

    /// True for a strict `--signs orient` resampling (the paper's rule).
    pub fn strict(&self) -> bool {
        matches!(self.job, Job::Resample { .. }) && self.signs == SignRule::Orient
    }

    /// Checks what can be checked before any work: the grid size, and that
    /// the output's format is known.
    pub fn validate(&self) -> Result<(), PipelineError> {
        match self.grid.size {
            GridSize::Cells(0) => return Err(PipelineError::stage(&self.output, "--cells must be at least 1")),
            GridSize::CellSize(h) if !(h > 0.0 && h.is_finite()) => {
                return Err(PipelineError::stage(&self.output, format!("--cell-size {h}: must be a positive number")))
            }
            _ => {}
        }
        if self.grid.offset.iter().any(|o| !o.is_finite()) {
            return Err(PipelineError::stage(&self.output, "--grid-offset: must be three finite numbers"));
        }
        mint_io::Format::from_path(&self.output)?;
        let empty = match &self.job {
            Job::Resample { inputs } => inputs.is_empty(),
            Job::Bool { a, b, .. } => a.is_empty() || b.is_empty(),
            Job::Csg { .. } => false,
            Job::Volume(v) => v.input.as_os_str().is_empty(),
        };
        if let Job::Volume(v) = &self.job {
            let (VolumeSurface::Iso(x) | VolumeSurface::Label(x)) = v.surface;
            if !x.is_finite() {
                return Err(PipelineError::stage(&v.input, format!("--iso {x}: must be a finite number")));
            }
        }
        if empty {
            return Err(PipelineError::stage(&self.output, "a surface of the run names no input file"));
        }
        Ok(())
    }
}

/// Everything that does not change the output bytes; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tuning {
    /// Heap budget in bytes (see [`mint_store::Budget`]). Default:
    /// [`mint_store::default_mem_bytes`], a quarter of RAM.
    pub mem_bytes: u64,
    /// Worker threads; 0: all cores. Default 0.
    pub threads: usize,
    /// How face corners become positions. Default `auto`.
    pub deref: Deref,
    /// Directory for temporary files. Default: the output's directory.
    pub tmp_dir: Option<PathBuf>,
    /// Force sub-slabs of this many layers (tests, tuning). Default: the
    /// budget decides.
    pub slab_layers: Option<u32>,
    /// Keep the stages here, so that a run killed at any moment resumes
    /// when run again with the same directory. Default `None`: a temporary
    /// directory, removed at the end.
    pub work_dir: Option<PathBuf>,
    /// Parts the input's faces are split into (one discretize task each).
    pub parts: u32,
    /// Slabs the grid is split into (one reconstruct task each).
    pub slabs: u32,
}

impl Default for Tuning {
    fn default() -> Self {
        Tuning {
            mem_bytes: mint_store::default_mem_bytes(),
            threads: 0,
            deref: Deref::Auto,
            tmp_dir: None,
            slab_layers: None,
            work_dir: None,
            parts: defaults::PARTS,
            slabs: defaults::SLABS,
        }
    }
}

impl Tuning {
    /// The worker threads this process runs (0: all cores).
    pub fn thread_count(&self) -> usize {
        threads_of(self.threads)
    }
}

/// `n` worker threads, 0 meaning all cores.
pub fn threads_of(n: usize) -> usize {
    if n == 0 {
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    } else {
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mint_core::choice::Choice;

    #[test]
    fn a_spec_survives_json() {
        let mut s = RunSpec::boolean(BoolOp::Difference, "/a.ply", "/b.ply", "/o.ply", GridSize::CellSize(0.25));
        s.grid.axis = SlabAxis::Y;
        s.signs = SignRule::Parity;
        let text = serde_json::to_string(&s).unwrap();
        assert!(text.contains(r#""op":"difference""#) && text.contains(r#""signs":"parity""#) && text.contains(r#""cell_size":0.25"#), "{text}");
        assert_eq!(serde_json::from_str::<RunSpec>(&text).unwrap(), s);
    }

    #[test]
    fn unknown_values_are_refused_by_name() {
        let text = serde_json::to_string(&RunSpec::resample("/a.ply", "/o.ply", GridSize::Cells(10))).unwrap();
        let bad = text.replace(r#""signs":"auto""#, r#""signs":"sideways""#);
        let e = serde_json::from_str::<RunSpec>(&bad).unwrap_err().to_string();
        assert!(e.contains("unknown value 'sideways'") && e.contains("auto, orient, union, parity"), "{e}");
        for &a in SlabAxis::ALL {
            assert_eq!(SlabAxis::parse(a.name()), Ok(a));
        }
    }

    #[test]
    fn booleans_close_every_hole() {
        assert_eq!(RunSpec::resample("a", "o.ply", GridSize::Cells(1)).max_hole, Some(defaults::MAX_HOLE));
        assert_eq!(RunSpec::csg("s.json", "o.ply", GridSize::Cells(1)).max_hole, None);
        let mut b = RunSpec::boolean(BoolOp::Union, "a", "b", "o.ply", GridSize::Cells(1));
        b.max_hole = Some(3);
        assert_eq!(b.normalized().max_hole, None);
    }
}
