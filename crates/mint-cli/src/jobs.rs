//! The one argument group of a run of the engine ([`RunArgs`], flattened
//! into `resample`, `bool` and `csg`, and so into `mint stage plan` and
//! `mint slurm` through [`JobCommand`]), the one builder of its
//! [`RunSpec`] and [`Tuning`] ([`RunArgs::spec`], [`RunArgs::tuning`]), the
//! report flags every command shares, the command line's view of the
//! library's named choices ([`choice`]), and the in-memory mesh loader of
//! the in-core commands. Command modules import from here; this module
//! imports no command module.

use crate::units::parse_bytes;
use anyhow::{bail, Context, Result};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, Subcommand};
use mint_core::choice::Choice;
use mint_core::expr::BoolOp;
use mint_core::signs::SignRule;
use mint_core::GridSize;
use mint_pipeline::budget::MEM_HELP;
use mint_pipeline::spec::defaults;
use mint_pipeline::{Deref, GridSpec, Job, Plan, RunSpec, SlabAxis, Tuning, WriteSpec};
use std::path::{Path, PathBuf};

/// The command line's parser of a library choice: its names (from the
/// library, never copied), listed by `--help` and in errors.
pub fn choice<T: Choice>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::NAMES).map(|s| T::parse(&s).expect("a listed name"))
}

/// `--quiet`, for every command that reports.
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct QuietArg {
    /// No progress bars and no summary (errors and warnings are still printed).
    #[arg(long, short)]
    pub quiet: bool,
}

/// `--json`, for every command that reports.
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct JsonArg {
    /// Print the summary as JSON on stdout (no progress bars).
    #[arg(long)]
    pub json: bool,
}

/// `--quiet` and `--json` together.
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct ReportArgs {
    #[command(flatten)]
    pub q: QuietArg,
    #[command(flatten)]
    pub j: JsonArg,
}

impl ReportArgs {
    pub fn quiet(&self) -> bool {
        self.q.quiet
    }
    pub fn json(&self) -> bool {
        self.j.json
    }
    /// No progress bars: quiet, or JSON on stdout.
    pub fn silent(&self) -> bool {
        self.q.quiet || self.j.json
    }
}

/// `--mem`, for every command with a memory budget.
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct MemArg {
    #[arg(long, value_parser = parse_bytes, help = MEM_HELP)]
    pub mem: Option<u64>,
}

impl MemArg {
    /// The budget in bytes: `--mem`, or the default of every command.
    pub fn bytes(&self) -> u64 {
        self.mem.unwrap_or_else(mint_pipeline::default_mem_bytes)
    }
}

/// Every option of a run of the engine: what decides the output (the
/// grid, the sign rule, the encoding: a [`RunSpec`]) and what does not
/// (memory, threads, staging: a [`Tuning`]).
#[derive(Args, Debug, Clone)]
pub struct RunArgs {
    /// About this many cubic cells over the bounding box
    /// (the output has very roughly 2-6 faces per surface cell).
    #[arg(long, conflicts_with = "cell_size", required_unless_present = "cell_size", value_parser = clap::value_parser!(u64).range(1..))]
    pub cells: Option<u64>,
    /// Cell edge length in input units (alternative to --cells).
    #[arg(long, value_name = "H", value_parser = parse_cell_size)]
    pub cell_size: Option<f64>,
    /// Axis along which the grid is cut into slabs (auto: the longest).
    #[arg(long, value_parser = choice::<SlabAxis>(), default_value_t = SlabAxis::Auto)]
    pub axis: SlabAxis,
    /// Shift the grid by fractions of a cell, e.g. 0.5,0,0 [default: 0,0,0].
    #[arg(long, value_parser = parse_triple, hide = true, allow_hyphen_values = true)]
    pub grid_offset: Option<[f64; 3]>,
    /// How crossing signs become inside/outside. auto: robust; from a census
    /// of all grid lines it picks sheet for an open input (more than a third
    /// of the lines cross it an odd number of times: a terrain tile, a single
    /// range scan, one-sided photogrammetry, loose triangles), else union
    /// (orientation kept, overlapping scans merge) or parity (orientation
    /// ignored, for flipped faces), which always give a closed surface,
    /// closing holes. sheet: the input resampled as an open surface with its
    /// faces' orientation; it encloses nothing, so nothing is closed. orient:
    /// the original paper's rule; cells that disagree are left open and
    /// counted (for bool and csg it applies to each mesh operand, and still
    /// closes; there auto never picks sheet: operands are solids).
    #[arg(long, value_parser = choice::<SignRule>(), default_value_t = defaults::SIGNS)]
    pub signs: SignRule,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 [default: f32 where it places every
    /// vertex within a thousandth of a cell, f64 elsewhere, e.g. for
    /// geo-referenced (UTM) or tiny models; the summary says which].
    #[arg(long)]
    pub double: bool,
    /// Write geometry only. By default the output carries the input's
    /// per-vertex colour (PLY, OBJ or glTF output; files without colour
    /// count as white): each vertex takes the colour of the input where its
    /// grid line crosses it.
    #[arg(long)]
    pub no_color: bool,
    #[command(flatten)]
    pub mem: MemArg,
    /// Worker threads [default: all cores]. The output is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Directory for temporary shards and spill files [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Force slabs of K cell layers (for tests and tuning); without it, --mem decides.
    #[arg(long, value_name = "K")]
    pub slab: Option<u32>,
    #[command(flatten)]
    pub staged: StagedArgs,
    /// Also write OUT.png beside the output: the inputs and the output
    /// side by side, under the same camera (see `mint render`).
    #[arg(long)]
    pub preview: bool,
    #[command(flatten)]
    pub preview_up: crate::preview::PreviewUp,
    #[command(flatten)]
    pub report: ReportArgs,
}

/// `--max-hole` and `--close-all` (resample only: booleans and CSG close
/// every hole).
#[derive(Args, Debug, Clone)]
pub struct HoleArgs {
    /// Holes wider than K cells are left open, with a clean boundary loop
    /// (robust sign rules only); smaller holes are closed.
    #[arg(long, value_name = "K", default_value_t = defaults::MAX_HOLE)]
    pub max_hole: u32,
    /// Close every hole, whatever its size (for watertight output, e.g. 3D printing).
    #[arg(long)]
    pub close_all: bool,
}

impl RunArgs {
    /// The run's spec: `job` into `output`, holes as `holes` says (booleans
    /// and CSG close every hole).
    pub fn spec(&self, job: Job, output: &Path, holes: Option<&HoleArgs>) -> Result<RunSpec> {
        let size = match (self.cells, self.cell_size) {
            (Some(n), None) => GridSize::Cells(n),
            (None, Some(h)) => GridSize::CellSize(h),
            _ => bail!("give exactly one of --cells N or --cell-size H"),
        };
        let mut spec = RunSpec::new(job, output, size);
        spec.grid = GridSpec { size, axis: self.axis, offset: self.grid_offset.unwrap_or([0.0; 3]) };
        spec.signs = self.signs;
        spec.write = WriteSpec { ascii: self.ascii, double: self.double, no_colour: self.no_color };
        if let Some(h) = holes {
            spec.max_hole = if h.close_all { None } else { Some(h.max_hole) };
        }
        Ok(spec.normalized())
    }

    /// The run's tuning.
    pub fn tuning(&self) -> Tuning {
        Tuning {
            mem_bytes: self.mem.bytes(),
            threads: self.threads,
            deref: self.staged.deref,
            tmp_dir: self.tmp.clone(),
            slab_layers: self.slab,
            work_dir: self.staged.work.clone(),
            parts: self.staged.parts,
            slabs: self.staged.slabs,
        }
    }
}

fn parse_cell_size(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(h) if h > 0.0 && h.is_finite() => Ok(h),
        Ok(_) => Err("must be a positive number".into()),
        Err(e) => Err(e.to_string()),
    }
}

fn parse_triple(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("'{s}': {e}"))?;
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        return Err(format!("'{s}': expected three comma-separated finite numbers"));
    }
    Ok([v[0], v[1], v[2]])
}

#[derive(Args, Debug, Clone)]
pub struct ResampleArgs {
    /// Input meshes (PLY, OBJ, STL, OFF, glTF/GLB, …), one surface: several
    /// files (tiles), a directory (its mesh files) or @LIST (a file naming
    /// one path a line) give the same output as one file holding all their
    /// triangles, in any order. A single PLY range image is triangulated first.
    #[arg(required = true, num_args = 1.., value_name = "IN")]
    pub inputs: Vec<PathBuf>,
    /// Output mesh; the format follows the extension. Written to a temporary
    /// file beside it and renamed at the end, so it never exists half-written.
    #[arg(value_name = "OUT")]
    pub output: PathBuf,
    #[command(flatten)]
    pub run: RunArgs,
    #[command(flatten)]
    pub holes: HoleArgs,
}

#[derive(Args, Debug, Clone)]
pub struct BoolArgs {
    /// union, intersection or difference (A minus B).
    #[arg(value_parser = choice::<BoolOp>())]
    pub op: BoolOp,
    /// First mesh (closed): a file, a directory of tiles or @LIST; or a
    /// voxel volume with --iso-a.
    pub a: PathBuf,
    /// Second mesh (closed): a file, a directory of tiles or @LIST; or a
    /// voxel volume with --iso-b.
    pub b: PathBuf,
    /// Output mesh.
    pub output: PathBuf,
    /// A is a voxel volume (any format `mint volume` reads), read as its
    /// iso-surface at V in the world frame its header declares (axis-aligned
    /// volumes), sampled trilinearly on the grid.
    #[arg(long, value_name = "V", allow_hyphen_values = true)]
    pub iso_a: Option<f32>,
    /// B is a voxel volume, read as its iso-surface at V (see --iso-a).
    #[arg(long, value_name = "V", allow_hyphen_values = true)]
    pub iso_b: Option<f32>,
    #[command(flatten)]
    pub run: RunArgs,
}

impl BoolArgs {
    /// The run's job: each side's files (a volume is one file or folder).
    pub fn job(&self) -> Result<Job> {
        let side = |p: &PathBuf, iso: Option<f32>| -> Result<Vec<PathBuf>> {
            match iso {
                Some(v) if !v.is_finite() => bail!("--iso-a/--iso-b {v}: not a finite number"),
                Some(_) => Ok(vec![p.clone()]),
                None => surface_files(std::slice::from_ref(p)),
            }
        };
        let (fa, fb) = (side(&self.a, self.iso_a)?, side(&self.b, self.iso_b)?);
        crate::paths::check_output(&self.output, &fa.iter().chain(&fb).map(|p| p.as_path()).collect::<Vec<_>>())?;
        Ok(Job::Bool { op: self.op, a: fa, b: fb, iso_a: self.iso_a, iso_b: self.iso_b })
    }
}

#[derive(Args, Debug, Clone)]
pub struct CsgArgs {
    /// Scene file (JSON).
    pub scene: PathBuf,
    /// Output mesh.
    pub output: PathBuf,
    #[command(flatten)]
    pub run: RunArgs,
}

/// `mint volume`'s arguments (shared with `mint stage plan volume` and
/// `mint slurm volume`).
#[derive(Args, Debug, Clone)]
pub struct VolumeArgs {
    /// The volume: a NRRD (.nrrd, .nhdr), MetaImage (.mhd, .mha) or NIfTI-1
    /// (.nii, .nii.gz, .hdr) file, a folder holding one DICOM series or a
    /// TIFF stack (or one of its files), a multi-page TIFF, or raw samples
    /// (give --raw-dims and --raw-type).
    #[arg(value_name = "IN")]
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    #[arg(value_name = "OUT")]
    pub output: PathBuf,
    /// The iso value: samples at or above it are inside (after the file's
    /// rescale, e.g. Hounsfield units for CT: 300 for bone, -500 for skin).
    #[arg(long, value_name = "V", allow_hyphen_values = true, required_unless_present = "labels", conflicts_with = "labels")]
    pub iso: Option<f32>,
    /// A label map: one closed surface per label value (`all`, the
    /// default when the flag has no value: every value but 0; or a list
    /// such as 1,2,5). Neighbouring labels share their boundary. Written
    /// one file per label (OUT's name with `.label-V` before the
    /// extension) unless --one-file.
    #[arg(long, value_name = "LIST", num_args = 0..=1, default_missing_value = "all")]
    pub labels: Option<String>,
    /// With --labels: every label's surface in OUT itself, one component
    /// set per label, in label order.
    #[arg(long, requires = "labels")]
    pub one_file: bool,
    /// About N cubic cells over the volume's extent, sampled trilinearly
    /// [default: the volume's own grid, one node per voxel centre, whose
    /// crossings are marching cubes' vertices].
    #[arg(long, conflicts_with = "cell_size", value_parser = clap::value_parser!(u64).range(1..))]
    pub cells: Option<u64>,
    /// Cubic cells of edge H in the volume's units (mm for medical formats).
    #[arg(long, value_name = "H", value_parser = parse_cell_size)]
    pub cell_size: Option<f64>,
    /// Leave the surface open where it meets the volume's border (its
    /// boundary then lies on the border), as marching cubes does, instead
    /// of closing it there [default: the border counts as outside, and a
    /// surface cut by it is closed on it].
    #[arg(long)]
    pub open_border: bool,
    /// Of a DICOM folder that holds several series (a CT with its scout
    /// and dose report, say), the one to mesh: its SeriesInstanceUID, or its
    /// number in the list that `mint volume FOLDER` prints without this
    /// option. Giving one of the series' .dcm files instead of the folder
    /// picks that file's series.
    #[arg(long, value_name = "UID|N")]
    pub dicom_series: Option<String>,
    /// Raw samples: dimensions X,Y,Z (X fastest in the file).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_dims, requires = "raw_type")]
    pub raw_dims: Option<[u64; 3]>,
    /// Raw samples: type (u8, i8, u16, i16, u32, i32, u64, i64, f32, f64).
    #[arg(long, value_name = "T", requires = "raw_dims")]
    pub raw_type: Option<String>,
    /// Raw samples: voxel spacing [default: 1,1,1].
    #[arg(long, value_name = "SX,SY,SZ", value_parser = parse_triple, requires = "raw_dims")]
    pub raw_spacing: Option<[f64; 3]>,
    /// Raw samples: big-endian [default: little].
    #[arg(long, requires = "raw_dims")]
    pub raw_big_endian: bool,
    /// Raw samples: bytes to skip before the first sample [default: 0].
    #[arg(long, value_name = "BYTES", default_value_t = 0, requires = "raw_dims")]
    pub raw_header: u64,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 [default: f32 where it places every
    /// vertex within a thousandth of a cell].
    #[arg(long)]
    pub double: bool,
    #[command(flatten)]
    pub mem: MemArg,
    /// Worker threads [default: all cores]. The output is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Directory for temporary shards [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Force slabs of K cell layers (for tests and tuning); without it, --mem decides.
    #[arg(long, value_name = "K")]
    pub slab: Option<u32>,
    #[command(flatten)]
    pub staged: StagedArgs,
    #[command(flatten)]
    pub report: ReportArgs,
}

impl VolumeArgs {
    /// The volume job of the surface `surface` (the iso value, or one label).
    pub fn job(&self, surface: mint_pipeline::VolumeSurface) -> mint_pipeline::VolumeJob {
        let raw = self.raw_dims.map(|dims| mint_pipeline::RawLayout {
            dims,
            sample: self.raw_type.clone().unwrap_or_default(),
            big_endian: self.raw_big_endian,
            spacing: self.raw_spacing.unwrap_or([1.0; 3]),
            header_bytes: self.raw_header,
        });
        mint_pipeline::VolumeJob {
            input: self.input.clone(),
            raw,
            surface,
            own_grid: self.cells.is_none() && self.cell_size.is_none(),
            open_border: self.open_border,
            dicom_series: self.dicom_series.clone(),
        }
    }

    /// The run's spec for `surface`, written to `output`.
    pub fn spec(&self, surface: mint_pipeline::VolumeSurface, output: &Path) -> Result<RunSpec> {
        let size = match (self.cells, self.cell_size) {
            (Some(n), _) => GridSize::Cells(n),
            (_, Some(h)) => GridSize::CellSize(h),
            // The own grid: cells of one voxel (the size is not used).
            _ => GridSize::CellSize(1.0),
        };
        let mut spec = RunSpec::new(Job::Volume(self.job(surface)), output, size);
        spec.grid = GridSpec { size, axis: SlabAxis::Z, offset: [0.0; 3] };
        spec.write = WriteSpec { ascii: self.ascii, double: self.double, no_colour: false };
        Ok(spec.normalized())
    }

    /// The run's tuning.
    pub fn tuning(&self) -> Tuning {
        Tuning {
            mem_bytes: self.mem.bytes(),
            threads: self.threads,
            deref: self.staged.deref,
            tmp_dir: self.tmp.clone(),
            slab_layers: self.slab,
            work_dir: self.staged.work.clone(),
            parts: self.staged.parts,
            slabs: self.staged.slabs,
        }
    }
}

fn parse_dims(s: &str) -> Result<[u64; 3], String> {
    let v: Vec<u64> = s.split(',').map(|x| x.trim().parse::<u64>()).collect::<Result<_, _>>().map_err(|e| format!("'{s}': {e}"))?;
    if v.len() != 3 || v.contains(&0) {
        return Err(format!("'{s}': expected three positive whole numbers X,Y,Z"));
    }
    Ok([v[0], v[1], v[2]])
}

/// The files of one surface, from its arguments (see
/// `mint_io::expand_inputs`).
pub(crate) fn surface_files(args: &[PathBuf]) -> Result<Vec<PathBuf>> {
    Ok(mint_io::expand_inputs(args)?)
}

/// The files `mint resample` reads, from the surface's `files`: those, or,
/// for a single PLY range image, its triangulation (see [`resample_input`]).
pub(crate) fn resample_inputs(files: &[PathBuf], work: Option<&std::path::Path>, tmp: &std::path::Path) -> Result<(Vec<PathBuf>, Option<tempfile::NamedTempFile>)> {
    if let [one] = files {
        let (f, t) = resample_input(one, work, tmp)?;
        return Ok((vec![f], t));
    }
    Ok((files.to_vec(), None))
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
        crate::out::warn(w);
    }
    Ok((whole.positions, whole.faces))
}

/// The files of one surface read into memory as one mesh (each file's
/// faces offset by the vertices before it).
pub fn load_meshes(paths: &[PathBuf]) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>)> {
    let (mut positions, mut faces) = (Vec::new(), Vec::new());
    for p in paths {
        let (ps, fs) = load_mesh(p)?;
        let base = u32::try_from(positions.len()).ok().filter(|b| (*b as u64) + ps.len() as u64 <= u32::MAX as u64);
        let Some(base) = base else { bail!("{}: the files hold more than {} vertices together", p.display(), u32::MAX) };
        positions.extend(ps);
        faces.extend(fs.into_iter().map(|f| [f[0] + base, f[1] + base, f[2] + base]));
    }
    Ok((positions, faces))
}

/// The files a scene reads: the scene file and its meshes.
pub(crate) fn scene_inputs<'a>(path: &'a std::path::Path, scene: &'a mint_pipeline::Scene) -> Vec<&'a std::path::Path> {
    let mut v = vec![path];
    for op in &scene.operands {
        if let mint_pipeline::scene::Operand::Mesh { paths, .. } = op {
            v.extend(paths.iter().map(|p| p.as_path()));
        }
    }
    v
}

/// How a run is staged: the work directory that makes it resumable, its
/// split into parts and slabs, and how faces are dereferenced (shared by
/// resample, bool, csg, stage, slurm). None of it changes the output.
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
    #[arg(long, value_name = "P", default_value_t = defaults::PARTS, value_parser = clap::value_parser!(u32).range(1..=mint_pipeline::plan::MAX_TASKS as i64))]
    pub parts: u32,
    /// Split the grid into S slabs (one reconstruction task each). The
    /// output is the same for any S.
    #[arg(long, value_name = "S", default_value_t = defaults::SLABS, value_parser = clap::value_parser!(u32).range(1..=mint_pipeline::plan::MAX_TASKS as i64))]
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
    #[arg(long, value_parser = choice::<Deref>(), default_value_t = Deref::Auto)]
    pub deref: Deref,
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
    /// A volume's iso-surface (every `mint volume` option but --labels).
    Volume(VolumeArgs),
}

impl JobCommand {
    /// The run's report flags.
    pub fn report(&self) -> &ReportArgs {
        match self {
            JobCommand::Resample(a) => &a.run.report,
            JobCommand::Bool(a) => &a.run.report,
            JobCommand::Csg(a) => &a.run.report,
            JobCommand::Volume(a) => &a.report,
        }
    }

    /// The spec and tuning of a staged run of this job (`--work` required).
    /// Range images are triangulated into the work directory first.
    pub fn staged(&self) -> Result<(RunSpec, Tuning, PathBuf)> {
        let r = match self {
            JobCommand::Resample(a) => &a.run,
            JobCommand::Bool(a) => &a.run,
            JobCommand::Csg(a) => &a.run,
            JobCommand::Volume(a) => {
                let Some(work) = a.staged.work.clone() else { bail!("a staged run needs --work DIR (a directory every task can reach)") };
                let Some(iso) = a.iso else { bail!("a staged volume run takes --iso V (run one label at a time with --iso on a label map's indicator, or use `mint volume --labels`)") };
                crate::paths::check_output(&a.output, &[a.input.as_path()])?;
                return Ok((a.spec(mint_pipeline::VolumeSurface::Iso(iso), &a.output)?, a.tuning(), work));
            }
        };
        let Some(work) = r.staged.work.clone() else { bail!("a staged run needs --work DIR (a directory every task can reach)") };
        let spec = match self {
            JobCommand::Resample(a) => {
                let files = surface_files(&a.inputs)?;
                crate::paths::check_output(&a.output, &files.iter().map(|p| p.as_path()).collect::<Vec<_>>())?;
                let (inputs, _) = resample_inputs(&files, Some(&work), &work)?;
                r.spec(Job::Resample { inputs }, &a.output, Some(&a.holes))?
            }
            JobCommand::Bool(a) => r.spec(a.job()?, &a.output, None)?,
            JobCommand::Volume(_) => unreachable!("returned above"),
            JobCommand::Csg(a) => {
                let text = std::fs::read_to_string(&a.scene).with_context(|| format!("{}: cannot read the scene", a.scene.display()))?;
                let scene = mint_pipeline::parse_scene(&text, &a.scene)?;
                crate::paths::check_output(&a.output, &scene_inputs(&a.scene, &scene))?;
                r.spec(Job::Csg { scene: a.scene.clone() }, &a.output, None)?
            }
        };
        Ok((spec, r.tuning(), work))
    }

    /// The plan of a staged run of the job, written into its --work DIR,
    /// and the directory.
    pub fn plan(&self) -> Result<(Plan, PathBuf)> {
        let (spec, tuning, dir) = self.staged()?;
        let plan = mint_pipeline::plan_run(&spec, None, &tuning, &dir)?;
        Ok((plan, dir))
    }
}

#[cfg(test)]
mod tests {
    use crate::cli::{Cli, Command};
    use clap::Parser;
    use mint_core::choice::Choice;
    use crate::cmd::stage::StageCommand;
    use proptest::prelude::*;
    use std::path::Path;

    /// A tetrahedron, as the input of every planned run.
    fn tetrahedron(dir: &Path, name: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n").unwrap();
        p
    }

    /// Command-line words of a run: one of each option that decides the output or tunes it.
    fn words() -> impl Strategy<Value = Vec<String>> {
        let size = prop_oneof![(1u64..10_000_000).prop_map(|n| vec!["--cells".to_string(), n.to_string()]), (1e-6f64..1e3).prop_map(|h| vec!["--cell-size".to_string(), h.to_string()])];
        let pick = |names: &'static [&'static str], flag: &'static str| proptest::option::of(proptest::sample::select(names)).prop_map(move |v| v.map_or(vec![], |v| vec![flag.to_string(), v.to_string()]));
        let offset = proptest::option::of((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0)).prop_map(|o| o.map_or(vec![], |(a, b, c)| vec!["--grid-offset".into(), format!("{a},{b},{c}")]));
        let flags = (any::<bool>(), any::<bool>(), proptest::option::of(0u32..100), any::<bool>(), proptest::option::of(1u64..1 << 40), proptest::option::of(0usize..9), 1u32..5, 1u32..5, proptest::option::of(1u32..9));
        (size, pick(mint_core::signs::SignRule::NAMES, "--signs"), pick(mint_pipeline::SlabAxis::NAMES, "--axis"), pick(mint_pipeline::Deref::NAMES, "--deref"), offset, flags).prop_map(
            |(size, signs, axis, deref, offset, (ascii, double, max_hole, close_all, mem, threads, parts, slabs, slab))| {
                let mut w: Vec<String> = [size, signs, axis, deref, offset].concat();
                w.extend(ascii.then(|| "--ascii".to_string()));
                w.extend(double.then(|| "--double".to_string()));
                if let Some(k) = max_hole {
                    w.extend(["--max-hole".to_string(), k.to_string()]);
                }
                w.extend(close_all.then(|| "--close-all".to_string()));
                if let Some(m) = mem {
                    w.extend(["--mem".to_string(), m.to_string()]);
                }
                if let Some(t) = threads {
                    w.extend(["--threads".to_string(), t.to_string()]);
                }
                w.extend(["--parts".to_string(), parts.to_string(), "--slabs".to_string(), slabs.to_string()]);
                if let Some(k) = slab {
                    w.extend(["--slab".to_string(), k.to_string()]);
                }
                w
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
        /// The spec and tuning the CLI builds reach a task as they were:
        /// command line -> plan.json -> `Plan::load`, which `mint stage run`
        /// and every Slurm task call.
        #[test]
        fn a_spec_survives_the_cli_the_plan_and_a_task(words in words(), op in proptest::sample::select(mint_core::expr::BoolOp::NAMES), job in 0..2u8) {
            let d = tempfile::tempdir().unwrap();
            let a = tetrahedron(d.path(), "a.ply");
            let b = tetrahedron(d.path(), "b.ply");
            let work = d.path().join("work");
            let mut argv: Vec<String> = vec!["mint".into(), "stage".into(), "plan".into()];
            match job {
                0 => argv.extend(["resample".into(), a.display().to_string()]),
                _ => argv.extend(["bool".into(), op.to_string(), a.display().to_string(), b.display().to_string()]),
            }
            let bool_job = job != 0;
            let words: Vec<String> = if bool_job {
                // Booleans take no hole options.
                let mut v = Vec::new();
                let mut it = words.into_iter();
                while let Some(w) = it.next() {
                    match w.as_str() {
                        "--close-all" => {}
                        "--max-hole" => { it.next(); }
                        _ => v.push(w),
                    }
                }
                v
            } else {
                words
            };
            argv.push(d.path().join("out.ply").display().to_string());
            argv.extend(words);
            argv.extend(["--work".into(), work.display().to_string(), "--quiet".into()]);
            let cli = Cli::try_parse_from(&argv).map_err(|e| TestCaseError::fail(format!("{argv:?}: {e}")))?;
            let Command::Stage(StageCommand::Plan(job)) = cli.command else { panic!("not a plan") };
            let (spec, tuning, dir) = job.staged().unwrap();
            let planned = mint_pipeline::plan_run(&spec, None, &tuning, &dir).unwrap();
            let task = mint_pipeline::Plan::load(&dir).unwrap();
            prop_assert_eq!(&task, &planned);
            // The spec arrives whole; its paths are made absolute for tasks elsewhere.
            let want = mint_pipeline::RunSpec { job: spec.job.absolute(), output: mint_pipeline::spec::absolute(&spec.output), ..spec.clone() };
            prop_assert_eq!(&task.spec, &want);
            prop_assert_eq!(task.spec.max_hole.is_none(), bool_job || argv.iter().any(|w| w == "--close-all"));
            // The tuning arrives whole, as the tasks' defaults.
            prop_assert_eq!(&task.tuning, &mint_pipeline::Tuning { work_dir: Some(mint_pipeline::spec::absolute(&work)), ..tuning.clone() });
            // And the same command plans the same run again.
            let again = mint_pipeline::plan_run(&spec, None, &tuning, &dir).unwrap();
            prop_assert_eq!(&again, &planned);
        }
    }
}
