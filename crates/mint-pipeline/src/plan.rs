//! The plan of a staged run (`DIR/plan.json`): what to evaluate (a
//! [`Job`]: one mesh, a boolean of two, or a CSG scene), on which grid
//! options, split into how many parts and slabs, the fingerprints of every
//! input file, and the stages in order with their task counts. Every task
//! count is known here, before any work, so that a whole run can be
//! submitted to a scheduler at once.
//!
//! The grid itself is not in the plan: it follows from the input's bounds,
//! which the first stage computes in parallel; every later task reduces the
//! bounds stage's small per-task files to the same grid. Likewise the slabs
//! are a fixed number of layer ranges, drawn from the discretize stage's
//! per-plane counts by one deterministic rule (equal shares of records).
//!
//! A plan from another mint version, or one whose inputs or options differ
//! from the command's, is refused with one line.

use crate::error::PipelineError;
use crate::options::ResampleOptions;
use crate::scene::{parse_scene, Operand, Scene};
use crate::workdir::{read_checked_json, PLAN_FILE};
use mint_core::grid::GridSize;
use mint_core::expr::{BoolOp, Expr};
use mint_core::signs::SignRule;
use mint_io::{MeshReader, ReadOptions};
use serde::{Deserialize, Serialize};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// The plan format's version; a plan of another version is refused.
pub const PLAN_VERSION: u32 = 1;
const PLAN_FORMAT: &str = "mint stage plan";

/// What a run evaluates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Job {
    /// Resample one mesh.
    Resample { input: PathBuf },
    /// `a op b` for two meshes; `op` is union, intersection or difference.
    Bool { op: String, a: PathBuf, b: PathBuf },
    /// A CSG scene file.
    Csg { scene: PathBuf },
}

impl Job {
    /// The scene this job evaluates.
    pub fn scene(&self) -> Result<Scene, PipelineError> {
        let mesh = |p: &Path| Operand::Mesh { path: p.to_path_buf(), transform: Default::default() };
        Ok(match self {
            Job::Resample { input } => Scene { expr: Expr::Operand(0), operands: vec![mesh(input)] },
            Job::Bool { op, a, b } => {
                let op = bool_op(op).ok_or_else(|| PipelineError::stage(a, format!("unknown boolean '{op}'")))?;
                Scene { expr: Expr::Op(op, vec![Expr::Operand(0), Expr::Operand(1)]), operands: vec![mesh(a), mesh(b)] }
            }
            Job::Csg { scene } => {
                let text = std::fs::read_to_string(scene)
                    .map_err(|source| PipelineError::Temp { path: scene.clone(), op: "reading the scene", source })?;
                parse_scene(&text, scene)?
            }
        })
    }

    /// How the summary names the input.
    pub fn name(&self) -> String {
        match self {
            Job::Resample { input } => input.display().to_string(),
            Job::Bool { op, a, b } => format!("{} {op} {}", a.display(), b.display()),
            Job::Csg { scene } => scene.display().to_string(),
        }
    }

    /// The file errors about the whole job are reported against.
    pub fn path(&self) -> PathBuf {
        match self {
            Job::Resample { input } => input.clone(),
            Job::Bool { a, .. } => a.clone(),
            Job::Csg { scene } => scene.clone(),
        }
    }
}

/// `union`, `intersection` or `difference`.
pub fn bool_op(name: &str) -> Option<BoolOp> {
    match name {
        "union" => Some(BoolOp::Union),
        "intersection" => Some(BoolOp::Intersection),
        "difference" => Some(BoolOp::Difference),
        _ => None,
    }
}

/// The name of a boolean operation, as [`bool_op`] reads it.
pub fn bool_op_name(op: BoolOp) -> &'static str {
    match op {
        BoolOp::Union => "union",
        BoolOp::Intersection => "intersection",
        BoolOp::Difference => "difference",
    }
}

/// The options that decide the output bytes (a resumed run must match).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanOptions {
    pub cells: Option<u64>,
    pub cell_size: Option<f64>,
    /// Slab axis 0, 1, 2 (x, y, z), or `None` for the longest.
    pub axis: Option<usize>,
    pub grid_offset: [f64; 3],
    /// auto, orient, union or parity.
    pub signs: String,
    pub max_hole: Option<u32>,
    pub ascii: bool,
    pub double: bool,
    pub max_listed: usize,
}

impl PlanOptions {
    pub(crate) fn from_options(o: &ResampleOptions) -> PlanOptions {
        let (cells, cell_size) = match o.size {
            GridSize::Cells(n) => (Some(n), None),
            GridSize::CellSize(h) => (None, Some(h)),
        };
        PlanOptions {
            cells,
            cell_size,
            axis: o.axis,
            grid_offset: o.grid_offset,
            signs: format!("{:?}", o.signs).to_lowercase(),
            max_hole: o.max_hole,
            ascii: o.write.ascii,
            double: o.write.double,
            max_listed: o.max_listed,
        }
    }

    pub fn size(&self) -> GridSize {
        match (self.cells, self.cell_size) {
            (Some(n), _) => GridSize::Cells(n),
            (None, Some(h)) => GridSize::CellSize(h),
            (None, None) => GridSize::Cells(1_000_000),
        }
    }

    pub fn sign_rule(&self) -> SignRule {
        match self.signs.as_str() {
            "orient" => SignRule::Orient,
            "union" => SignRule::Union,
            "parity" => SignRule::Parity,
            _ => SignRule::Auto,
        }
    }
}

/// Settings that do not change the output (a resumed run may change them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tuning {
    /// Default heap budget of a task, in bytes.
    pub mem_bytes: u64,
    /// Sub-slab thickness forced on slab tasks (`--slab`).
    pub slab_layers: Option<u32>,
}

/// What identifies an input file: path, size, modification time, and a
/// CRC-32 of its first 64 KiB, its last 4 KiB and eight 4 KiB blocks spread
/// over the rest.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fingerprint {
    pub path: PathBuf,
    pub size: u64,
    pub mtime_ns: u128,
    pub sample_crc32: u32,
}

impl Fingerprint {
    pub fn of(path: &Path) -> Result<Fingerprint, PipelineError> {
        let err = |op| move |source| PipelineError::Temp { path: path.to_path_buf(), op, source };
        let mut f = std::fs::File::open(path).map_err(err("opening an input"))?;
        let meta = f.metadata().map_err(err("reading an input's metadata"))?;
        let size = meta.len();
        let mtime_ns = meta.modified().ok().and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok()).map_or(0, |d| d.as_nanos());
        let mut crc = crc32fast::Hasher::new();
        let mut blocks: Vec<(u64, u64)> = vec![(0, 64 << 10)];
        for i in 1..=8u64 {
            blocks.push((size / 9 * i, 4 << 10));
        }
        blocks.push((size.saturating_sub(4 << 10), 4 << 10));
        let mut buf = vec![0u8; 64 << 10];
        for (at, len) in blocks {
            let len = len.min(size.saturating_sub(at)) as usize;
            f.seek(SeekFrom::Start(at)).map_err(err("reading an input"))?;
            f.read_exact(&mut buf[..len]).map_err(err("reading an input"))?;
            crc.update(&buf[..len]);
        }
        Ok(Fingerprint { path: path.to_path_buf(), size, mtime_ns, sample_crc32: crc.finalize() })
    }
}

/// What the plan knows of one operand of the scene.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OperandPlan {
    /// A mesh file: its vertex count, and its face-record count when its
    /// faces can be read in ranges (binary PLY, binary STL). Other files
    /// are read whole by part 0.
    Mesh { path: PathBuf, vertices: u64, split_faces: Option<u64> },
    /// An analytic primitive (computed on demand; nothing to read).
    Primitive,
}

/// One stage and its task count.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StagePlan {
    pub name: String,
    pub tasks: u32,
}

/// The stage names, in the order they run.
pub const STAGES: [&str; 6] = ["bounds", "discretize", "census", "reconstruct", "reopen", "write"];

/// A staged run's plan; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub format: String,
    pub version: u32,
    pub mint_version: String,
    pub job: Job,
    pub output: PathBuf,
    pub options: PlanOptions,
    pub parts: u32,
    pub slabs: u32,
    pub inputs: Vec<Fingerprint>,
    pub operands: Vec<OperandPlan>,
    pub stages: Vec<StagePlan>,
    pub tuning: Tuning,
}

/// An absolute path, without resolving links (so that the plan names what
/// the user named, from any machine that mounts it at the same place).
pub fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

impl Plan {
    /// Plans `job` (whose scene is `scene`) into `output`.
    pub fn new(job: Job, scene: &Scene, output: &Path, opts: &ResampleOptions) -> Result<Plan, PipelineError> {
        let parts = opts.parts.max(1);
        let slabs = opts.slabs.max(1);
        let mut operands = Vec::new();
        let mut files: Vec<PathBuf> = Vec::new();
        if let Job::Csg { scene } = &job {
            if scene.is_file() {
                files.push(scene.clone());
            }
        }
        for op in &scene.operands {
            operands.push(match op {
                Operand::Primitive(_) => OperandPlan::Primitive,
                Operand::Mesh { path, .. } => {
                    let r = MeshReader::open(path, ReadOptions { chunk_triangles: 1, spill_dir: Some(std::env::temp_dir()), resolve_positions: false })?;
                    if !files.contains(path) {
                        files.push(path.clone());
                    }
                    OperandPlan::Mesh { path: path.clone(), vertices: r.vertex_count() as u64, split_faces: r.splittable_records() }
                }
            });
        }
        let inputs = files.iter().map(|f| Fingerprint::of(f)).collect::<Result<Vec<_>, _>>()?;
        let options = PlanOptions::from_options(opts);
        let strict = matches!(job, Job::Resample { .. }) && options.sign_rule() == SignRule::Orient;
        let has_mesh = operands.iter().any(|o| matches!(o, OperandPlan::Mesh { .. }));
        let mut stages = vec![StagePlan { name: "bounds".into(), tasks: parts }, StagePlan { name: "discretize".into(), tasks: parts }];
        if has_mesh && !strict {
            stages.push(StagePlan { name: "census".into(), tasks: slabs });
        }
        stages.push(StagePlan { name: "reconstruct".into(), tasks: slabs });
        if !strict && options.max_hole.is_some() {
            stages.push(StagePlan { name: "reopen".into(), tasks: slabs });
        }
        stages.push(StagePlan { name: "write".into(), tasks: 1 });
        Ok(Plan {
            format: PLAN_FORMAT.into(),
            version: PLAN_VERSION,
            mint_version: env!("CARGO_PKG_VERSION").into(),
            job,
            output: absolute(output),
            options,
            parts,
            slabs,
            inputs,
            operands,
            stages,
            tuning: Tuning { mem_bytes: opts.mem_bytes, slab_layers: opts.slab_layers },
        })
    }

    /// Tasks of `stage` (0 when the plan has no such stage).
    pub fn tasks(&self, stage: &str) -> u32 {
        self.stages.iter().find(|s| s.name == stage).map_or(0, |s| s.tasks)
    }

    pub fn has_stage(&self, stage: &str) -> bool {
        self.stages.iter().any(|s| s.name == stage)
    }

    /// True for a strict `--signs orient` resampling (the paper's rule).
    pub fn strict(&self) -> bool {
        matches!(self.job, Job::Resample { .. }) && self.options.sign_rule() == SignRule::Orient
    }

    /// Reads `DIR/plan.json`, refusing a plan of another version.
    pub fn load(dir: &Path) -> Result<Plan, PipelineError> {
        let path = dir.join(PLAN_FILE);
        if !path.is_file() {
            return Err(PipelineError::stage(dir, "no plan.json: not a work directory (make one with `mint stage plan`)"));
        }
        let v: serde_json::Value = read_checked_json(&path)?;
        let (format, version, by) = (v["format"].as_str(), v["version"].as_u64(), v["mint_version"].as_str().unwrap_or("?"));
        if format != Some(PLAN_FORMAT) || version != Some(PLAN_VERSION as u64) || by != env!("CARGO_PKG_VERSION") {
            return Err(PipelineError::stage(
                &path,
                format!(
                    "a plan of format {} written by mint {by}; this is mint {} (plan format {PLAN_VERSION}): finish the run with that version, or plan it again in a new directory",
                    version.map_or("?".to_string(), |v| v.to_string()),
                    env!("CARGO_PKG_VERSION")
                ),
            ));
        }
        serde_json::from_value(v).map_err(|e| PipelineError::stage(&path, format!("unreadable plan ({e})")))
    }

    /// Checks that this (freshly made) plan describes the same run as the
    /// stored `other`: same job, output, options, split and input files.
    pub fn check_same_run(&self, other: &Plan, dir: &Path) -> Result<(), PipelineError> {
        let what = if self.inputs != other.inputs {
            let changed = self.inputs.iter().zip(&other.inputs).find(|(a, b)| a != b).map(|(a, _)| a.path.display().to_string());
            match changed {
                Some(p) => format!("the input {p} is not the file this run was planned for (size, time or content changed)"),
                None => "the run was planned for other input files".to_string(),
            }
        } else if self.job != other.job || self.operands != other.operands {
            "the run was planned for another job (inputs or scene)".to_string()
        } else if self.output != other.output {
            format!("the run was planned to write {}", other.output.display())
        } else if self.options != other.options {
            let a = serde_json::to_value(&self.options).unwrap();
            let b = serde_json::to_value(&other.options).unwrap();
            let key = a.as_object().unwrap().iter().find(|(k, v)| b.get(k.as_str()) != Some(v)).map(|(k, _)| k.clone()).unwrap_or_default();
            format!("the run was planned with other options ({key}: {} there, {} here)", b[&key], a[&key])
        } else if (self.parts, self.slabs) != (other.parts, other.slabs) {
            format!("the run was planned with {} parts and {} slabs", other.parts, other.slabs)
        } else {
            return Ok(());
        };
        Err(PipelineError::stage(
            dir.join(PLAN_FILE),
            format!("{what}; use another work directory, or remove this one to start over"),
        ))
    }
}
