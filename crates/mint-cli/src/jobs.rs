//! The argument groups and option builders that several commands share:
//! the job arguments of `resample`, `bool` and `csg` (also parsed by
//! `mint stage plan` and `mint slurm`, as a `JobCommand`), their translation
//! into library options and into a staged run's plan, and the in-memory
//! mesh loader of the in-core commands. Command modules import from here;
//! this module imports no command module.

use crate::units::parse_bytes;
use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use mint_core::GridSize;
use mint_io::WriteOptions;
use mint_pipeline::{Job, Plan, ResampleOptions};
use std::path::{Path, PathBuf};

#[derive(Args, Debug, Clone)]
pub struct ResampleArgs {
    /// Input mesh (PLY, OBJ, STL or OFF).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension. Written to a temporary
    /// file beside it and renamed at the end, so it never exists half-written.
    pub output: PathBuf,
    /// About this many cubic cells over the input's bounding box
    /// (the output has very roughly 2-6 faces per surface cell).
    #[arg(long, conflicts_with = "cell_size", required_unless_present = "cell_size")]
    pub cells: Option<u64>,
    /// Cell edge length in input units (alternative to --cells).
    #[arg(long)]
    pub cell_size: Option<f64>,
    /// Heap budget, e.g. 512M or 2G; it decides slab thickness, never the
    /// input size [default: a quarter of RAM].
    #[arg(long, value_parser = parse_bytes)]
    pub mem: Option<u64>,
    /// Worker threads [default: all cores]. The output is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Directory for temporary shards and spill files [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Axis along which the grid is cut into slabs.
    #[arg(long, value_enum, default_value_t = AxisArg::Auto)]
    pub axis: AxisArg,
    /// Force slabs of K cell layers (for tests and tuning); without it, --mem decides.
    #[arg(long, value_name = "K")]
    pub slab: Option<u32>,
    #[command(flatten)]
    pub staged: StagedArgs,
    /// How crossing signs become inside/outside. auto: robust; picks union
    /// (orientation kept, overlapping scans merge) or parity (orientation
    /// ignored, for flipped faces) from a census of all grid lines, and
    /// always gives a closed surface, closing holes. orient: the original
    /// paper's rule; cells that disagree are left open and counted.
    #[arg(long, value_enum, default_value_t = SignsArg::Auto)]
    pub signs: SignsArg,
    /// Holes wider than K cells are left open, with a clean boundary loop
    /// (robust sign rules only); smaller holes are closed.
    #[arg(long, value_name = "K", default_value_t = 16)]
    pub max_hole: u32,
    /// Close every hole, whatever its size (for watertight output, e.g. 3D printing).
    #[arg(long)]
    pub close_all: bool,
    /// Shift the grid by fractions of a cell, e.g. 0.5,0,0 [default: 0,0,0].
    #[arg(long, value_parser = parse_triple, hide = true)]
    pub grid_offset: Option<[f64; 3]>,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 instead of f32.
    #[arg(long)]
    pub double: bool,
    /// No progress bars and no summary (errors are still printed).
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Also write OUT.png beside the output: the input and the output side
    /// by side, under the same camera (see `mint render`).
    #[arg(long)]
    pub preview: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoolOpArg {
    Union,
    Intersection,
    Difference,
}

/// Grid, memory and output options shared by `bool` and `csg`.
#[derive(Args, Debug, Clone)]
pub struct GridArgs {
    /// About this many cubic cells over the result's bounding box.
    #[arg(long, conflicts_with = "cell_size", required_unless_present = "cell_size")]
    pub cells: Option<u64>,
    /// Cell edge length (alternative to --cells).
    #[arg(long)]
    pub cell_size: Option<f64>,
    /// Heap budget, e.g. 512M or 2G [default: a quarter of RAM].
    #[arg(long, value_parser = parse_bytes)]
    pub mem: Option<u64>,
    /// Worker threads [default: all cores]. The output is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Directory for temporary files [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Force slabs of K cell layers; without it, --mem decides.
    #[arg(long, value_name = "K")]
    pub slab: Option<u32>,
    #[command(flatten)]
    pub staged: StagedArgs,
    /// Shift the grid by fractions of a cell, e.g. 0.5,0,0 [default: 0,0,0].
    #[arg(long, value_parser = parse_triple, hide = true)]
    pub grid_offset: Option<[f64; 3]>,
    /// Also write OUT.png beside the output: the input meshes and the
    /// result side by side, under the same camera (see `mint render`).
    #[arg(long)]
    pub preview: bool,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug, Clone)]
pub struct BoolArgs {
    /// union, intersection or difference (A minus B).
    #[arg(value_enum)]
    pub op: BoolOpArg,
    /// First mesh (closed).
    pub a: PathBuf,
    /// Second mesh (closed).
    pub b: PathBuf,
    /// Output mesh.
    pub output: PathBuf,
    #[command(flatten)]
    pub grid: GridArgs,
}

#[derive(Args, Debug, Clone)]
pub struct CsgArgs {
    /// Scene file (JSON).
    pub scene: PathBuf,
    /// Output mesh.
    pub output: PathBuf,
    #[command(flatten)]
    pub grid: GridArgs,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SignsArg {
    Auto,
    Orient,
    Union,
    Parity,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisArg {
    Auto,
    X,
    Y,
    Z,
}

fn parse_triple(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("'{s}': {e}"))?;
    if v.len() != 3 {
        return Err(format!("'{s}': expected three comma-separated numbers"));
    }
    Ok([v[0], v[1], v[2]])
}

/// The library options of `mint resample`'s arguments.
pub(crate) fn resample_options(a: &ResampleArgs) -> Result<ResampleOptions> {
    let size = match (a.cells, a.cell_size) {
        (Some(n), None) => {
            if n == 0 {
                bail!("--cells must be at least 1");
            }
            GridSize::Cells(n)
        }
        (None, Some(h)) => GridSize::CellSize(h),
        _ => bail!("give exactly one of --cells N or --cell-size H"),
    };
    Ok(ResampleOptions {
        size,
        mem_bytes: a.mem.unwrap_or_else(default_mem),
        threads: a.threads,
        tmp_dir: a.tmp.clone(),
        axis: match a.axis {
            AxisArg::Auto => None,
            AxisArg::X => Some(0),
            AxisArg::Y => Some(1),
            AxisArg::Z => Some(2),
        },
        slab_layers: a.slab,
        grid_offset: a.grid_offset.unwrap_or([0.0; 3]),
        write: WriteOptions { ascii: a.ascii, double: a.double, ..Default::default() },
        max_listed: 100,
        signs: match a.signs {
            SignsArg::Auto => mint_core::signs::SignRule::Auto,
            SignsArg::Orient => mint_core::signs::SignRule::Orient,
            SignsArg::Union => mint_core::signs::SignRule::Union,
            SignsArg::Parity => mint_core::signs::SignRule::Parity,
        },
        max_hole: if a.close_all { None } else { Some(a.max_hole) },
        work_dir: a.staged.work.clone(),
        parts: a.staged.parts,
        slabs: a.staged.slabs,
        deref: a.staged.deref.to_deref(),
    })
}

/// The default heap budget: a quarter of RAM (2 GiB when RAM is unknown).
pub(crate) fn default_mem() -> u64 {
    mint_pipeline::default_mem_bytes()
}

/// The mesh `mint resample` reads: the input itself, or, for a PLY range
/// image, its triangulation (mint-range owns range images; the engine sees
/// a mesh). With a work directory the triangulation is kept there, so that
/// a resumed run finds the same file; otherwise it is a temporary file.
pub(crate) fn resample_input(input: &std::path::Path, work: Option<&std::path::Path>, tmp: &std::path::Path) -> Result<(PathBuf, Option<tempfile::NamedTempFile>)> {
    if let Some(dir) = work {
        let kept = dir.join("range-image-mesh.ply");
        if kept.is_file() {
            return Ok((kept, None));
        }
        std::fs::create_dir_all(dir).with_context(|| format!("{}: creating the work directory", dir.display()))?;
        return Ok(match mint_range::range_image_as_mesh(input, dir)? {
            Some(t) => {
                t.persist(&kept).map_err(|e| anyhow::anyhow!("{}: {}", kept.display(), e.error))?;
                (kept, None)
            }
            None => (input.to_path_buf(), None),
        });
    }
    Ok(match mint_range::range_image_as_mesh(input, tmp)? {
        Some(t) => (t.path().to_path_buf(), Some(t)),
        None => (input.to_path_buf(), None),
    })
}

/// Reads a whole mesh into memory (`mint_io::read_mesh_with`): positions
/// as stored (non-finite ones included, for `check` to count), reader
/// warnings on stderr, Ctrl-C honoured between chunks.
pub fn load_mesh(path: &std::path::Path) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>)> {
    let opts = mint_io::ReadOptions { resolve_positions: false, ..Default::default() };
    let whole = mint_io::read_mesh_with(path, opts, || !crate::progress::interrupted())?;
    if !whole.complete {
        bail!("interrupted");
    }
    for w in &whole.warnings {
        eprintln!("mint: warning: {w}");
    }
    Ok((whole.positions, whole.faces))
}

pub(crate) fn grid_options(g: &GridArgs) -> Result<ResampleOptions> {
    let size = match (g.cells, g.cell_size) {
        (Some(n), None) if n > 0 => GridSize::Cells(n),
        (None, Some(h)) => GridSize::CellSize(h),
        _ => bail!("give exactly one of --cells N (N >= 1) or --cell-size H"),
    };
    Ok(ResampleOptions {
        size,
        mem_bytes: g.mem.unwrap_or_else(default_mem),
        threads: g.threads,
        tmp_dir: g.tmp.clone(),
        slab_layers: g.slab,
        grid_offset: g.grid_offset.unwrap_or([0.0; 3]),
        work_dir: g.staged.work.clone(),
        parts: g.staged.parts,
        slabs: g.staged.slabs,
        deref: g.staged.deref.to_deref(),
        max_hole: None,
        ..Default::default()
    })
}

/// The files a scene reads: the scene file and its meshes.
pub(crate) fn scene_inputs<'a>(path: &'a std::path::Path, scene: &'a mint_pipeline::Scene) -> Vec<&'a std::path::Path> {
    let mut v = vec![path];
    for op in &scene.operands {
        if let mint_pipeline::scene::Operand::Mesh { path, .. } = op {
            v.push(path.as_path());
        }
    }
    v
}

/// How a run is staged: the work directory that makes it resumable, and its
/// split into parts and slabs (shared by resample, bool, csg, stage, slurm).
#[derive(Args, Debug, Clone, Default)]
pub struct StagedArgs {
    /// Keep the run's stages in DIR: a run killed at any moment (crash,
    /// kill -9, reboot) resumes where it stopped when run again with the same
    /// DIR, after checking that the inputs and options are the same. DIR is
    /// kept at the end (remove it yourself). [default: a temporary directory,
    /// removed at the end]
    #[arg(long, value_name = "DIR")]
    pub work: Option<PathBuf>,
    /// Split the reading of the input's faces into P parts (one task each;
    /// binary PLY and binary STL split, other formats are read whole by the
    /// first part). The output is the same for any P.
    #[arg(long, value_name = "P", default_value_t = 1)]
    pub parts: u32,
    /// Split the grid into S slabs (one reconstruction task each). The
    /// output is the same for any S.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub slabs: u32,
    /// How each face's vertex indices become positions. mmap: fetch them
    /// from the mapped vertex array (fast when neighbouring faces use
    /// neighbouring vertices). sort: Lindstrom-Silva dereferencing, which
    /// sorts corners by vertex and joins them with the vertex array in one
    /// sequential pass, spilling to disk beyond --mem (for meshes whose
    /// vertices are in no spatial order and larger than memory). auto: sort
    /// when a sample of the faces shows poor locality and the positions will
    /// not stay in memory (larger than 3/4 of MemAvailable or of the cgroup's
    /// limit); the summary says which ran and why. The output is the same for
    /// every choice.
    #[arg(long, value_enum, default_value_t = DerefArg::Auto)]
    pub deref: DerefArg,
}

/// `--deref`.
#[derive(ValueEnum, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum DerefArg {
    #[default]
    Auto,
    Mmap,
    Sort,
}

impl DerefArg {
    pub(crate) fn to_deref(self) -> mint_pipeline::Deref {
        match self {
            DerefArg::Auto => mint_pipeline::Deref::Auto,
            DerefArg::Mmap => mint_pipeline::Deref::Mmap,
            DerefArg::Sort => mint_pipeline::Deref::Sort,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            DerefArg::Auto => "auto",
            DerefArg::Mmap => "mmap",
            DerefArg::Sort => "sort",
        }
    }
}

/// The job of a staged run, with the options of the one-process command.
#[derive(Subcommand, Debug)]
pub enum JobCommand {
    /// Resample a mesh (every `mint resample` option).
    Resample(ResampleArgs),
    /// A boolean of two meshes (every `mint bool` option).
    #[command(name = "bool")]
    Bool(BoolArgs),
    /// A CSG scene (every `mint csg` option).
    Csg(CsgArgs),
}

/// The job, its options and its output, from a job command's arguments.
/// Range images are triangulated into the work directory first.
pub(crate) fn job_of(c: &JobCommand) -> Result<(Job, ResampleOptions, PathBuf, bool, bool)> {
    Ok(match c {
        JobCommand::Resample(a) => {
            let opts = resample_options(a)?;
            let Some(work) = &a.staged.work else { bail!("a staged run needs --work DIR (a directory every task can reach)") };
            crate::paths::check_output(&a.output, &[&a.input])?;
            let (input, _) = resample_input(&a.input, Some(work), work)?;
            (Job::Resample { input: abs(&input) }, opts, a.output.clone(), a.json, a.quiet)
        }
        JobCommand::Bool(a) => {
            let op = match a.op {
                BoolOpArg::Union => "union",
                BoolOpArg::Intersection => "intersection",
                BoolOpArg::Difference => "difference",
            };
            crate::paths::check_output(&a.output, &[&a.a, &a.b])?;
            (Job::Bool { op: op.into(), a: abs(&a.a), b: abs(&a.b) }, grid_options(&a.grid)?, a.output.clone(), a.grid.json, a.grid.quiet)
        }
        JobCommand::Csg(a) => {
            let text = std::fs::read_to_string(&a.scene).with_context(|| format!("{}: cannot read the scene", a.scene.display()))?;
            let scene = mint_pipeline::parse_scene(&text, &a.scene)?;
            crate::paths::check_output(&a.output, &scene_inputs(&a.scene, &scene))?;
            (Job::Csg { scene: abs(&a.scene) }, grid_options(&a.grid)?, a.output.clone(), a.grid.json, a.grid.quiet)
        }
    })
}

/// `p` made absolute: tasks may run in another directory, on another machine.
pub(crate) fn abs(p: &Path) -> PathBuf {
    mint_pipeline::plan::absolute(p)
}

/// The plan of a staged run of the job (written into its --work DIR), the
/// directory, and the job's --json and --quiet.
pub(crate) fn plan_of(c: &JobCommand) -> Result<(Plan, PathBuf, bool, bool)> {
    let (job, opts, output, json, quiet) = job_of(c)?;
    let Some(dir) = opts.work_dir.clone() else { bail!("a staged run needs --work DIR (a directory every task can reach)") };
    let plan = mint_pipeline::plan_run(job, None, &output, &opts, &dir)?;
    Ok((plan, dir, json, quiet))
}
