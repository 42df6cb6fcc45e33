//! The subcommands: argument definitions (clap derive, with help text that
//! teaches) and the glue from arguments to library calls.

use crate::alloc;
use crate::progress::Bars;
use crate::units::{human_bytes, parse_bytes};
use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use mint_io::WriteOptions;
use mint_pipeline::{resample, ResampleOptions};
use std::path::PathBuf;

pub(crate) use crate::jobs::*;

#[derive(Parser, Debug)]
#[command(
    name = "mint",
    version,
    about = "Turn huge 3D scans into clean meshes.",
    long_about = "mint turns huge scanned meshes into clean, watertight meshes with bounded memory.\n\n\
Its main job is out-of-core Marching Intersections resampling: the input's faces are streamed, \
only their signed intersections with the lines of a regular grid are kept (on disk, in shards), \
detail smaller than a cell is dropped, and a watertight 2-manifold mesh is rebuilt slab by slab.\n\n\
Formats: PLY (ascii, binary little/big endian, triangle strips, range grids), OBJ, STL (ascii/binary), OFF, \
mesh (Medit), raw triangles, VRML 2.0 and 3DS, chosen by file extension (or sniffed).\n\n\
Start with:  mint demo            (generate a mesh, resample it, check the result)\n\
Then:        mint resample IN.ply OUT.ply --cells 1000000"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Resample a mesh on a regular grid into a watertight 2-manifold mesh (out of core).
    #[command(long_about = "Resample a mesh on a regular grid into a watertight, 2-manifold, outward-oriented mesh.\n\n\
How it works (Marching Intersections): the input's faces are streamed once; for every grid line \
parallel to x, y or z, the points where the surface crosses it are kept, with a sign (entering or \
leaving the solid), in temporary shard files. Two crossings of one cell edge with opposite signs \
cancel: that is how detail smaller than a cell disappears. Each slab of the grid is then read back \
and turned into triangles whose vertices are the crossings themselves, so every output vertex lies \
on the input surface.\n\n\
Choosing the grid: --cells N spreads about N cubic cells over the bounding box; the output has \
roughly 2-6 faces per cell that the surface passes through (a sphere at --cells 1000000 gives about \
90,000 faces). Features thinner than a cell may vanish or merge.\n\n\
Memory: --mem bounds the heap; slabs are sized to fit it. The input may be far larger than RAM: \
its vertices are memory-mapped and its faces streamed. The output is identical for any --mem, \
--threads or --slab.\n\n\
Examples:\n  mint resample scan.ply clean.ply --cells 10000000\n  \
mint resample huge.ply out.ply --cell-size 0.5 --mem 1G --tmp /scratch --json")]
    Resample(ResampleArgs),
    /// Decimate a mesh of any size to a target face count: resample out of
    /// core, then simplify in core; watertight when the input is closed.
    #[command(long_about = "Decimate a mesh of any size to about --faces N faces.\n\n\
Two stages. Out of core: Marching Intersections resampling to an intermediate mesh of about \
--intermediate M faces (default 8 N), with the cell size chosen from the input's surface area (one \
streaming pass); this drops detail smaller than a cell and closes holes, within --mem. In core: \
meshoptimizer's quadric edge-collapse simplifier to N faces. The result is checked: when the \
resampling is closed and 2-manifold, so is the output (the simplifier's target is relaxed rather than \
hand over a worse mesh, and the summary says so).\n\n\
Examples:\n  mint decimate scan.ply small.ply --faces 1000000\n  mint decimate huge.ply lod.ply --faces 50000 --intermediate 400000 --mem 2G --json")]
    Decimate(DecimateArgs),
    /// Boolean of two meshes on one grid (union, intersection, difference),
    /// computed on the grid's intersection lists: out of core, watertight.
    #[command(name = "bool")]
    Bool(BoolArgs),
    /// Mesh a CSG scene (JSON) of primitives and meshes with transforms.
    #[command(long_about = "Mesh a CSG scene: a JSON tree of analytic primitives (sphere, box, cylinder, cone, \
torus, halfspace) and meshes, combined by union, intersection and difference, with scale/rotate/translate \
on any node. Primitives are intersected with the grid lines exactly; nothing is tessellated first.\n\n\
Example scene:\n  { \"difference\": [ { \"box\": { \"size\": [2, 2, 2] }, \"rotate\": [0, 0, 30] },\n                   { \"sphere\": { \"radius\": 1.2 } },\n                   { \"mesh\": \"part.ply\", \"scale\": 0.5 } ] }\n\n\
See crates/mint-pipeline/src/scene.rs for the whole format (defs and refs, halfspace normal/offset).")]
    Csg(CsgArgs),
    /// Show a mesh file's format, counts and properties without reading its body.
    Info(InfoArgs),
    /// Convert between mesh formats (PLY, OBJ, STL, OFF), streaming.
    Convert(ConvertArgs),
    /// Stream every triangle of a file with positions resolved: validates
    /// indices and coordinates and reports the read speed.
    Validate(ValidateArgs),
    /// Judge a mesh: counts, components, boundary and non-manifold edges,
    /// orientation, degenerate and duplicate faces, genus, volume, and one
    /// verdict: watertight or not. Exit code 0 either way; read the verdict.
    Check(CheckArgs),
    /// Metro-style surface distance between two meshes, both directions.
    Distance(DistanceArgs),
    /// Draw a picture of one or more meshes of any size (PNG), streaming.
    #[command(long_about = "Draw a picture of one or more meshes of any size, as PNG.\n\n\
A streaming z-buffer rasterizer: every triangle is projected and drawn on its own, so memory is the \
picture (about 7 bytes per pixel), whatever the mesh size. Orthographic views fitted to the meshes' \
joint bounding box; flat shading from each face's normal with a fixed light; faces seen from behind \
(inside-out parts, the inside seen through a hole) in orange. Several meshes are drawn side by side \
under the same camera; --view all draws seven views (iso, front, right, top, back, left, bottom), one \
row each. The bytes are the same on any machine.\n\n\
Examples:\n  mint render scan.ply scan.png\n  mint render scan.ply resampled.ply compare.png --view all --size 600x450")]
    Render(RenderArgs),
    /// Generate a synthetic test mesh, streamed to disk (any size).
    Gen(GenArgs),
    /// Generate a genus-3 solid, resample it, and check the result: mint's
    /// main job on a built-in input, end to end.
    Demo(DemoArgs),
    /// Cut a mesh by N parallel planes into a stack of contours (a .pro
    /// profile): test data for `mint contours`, and cross-sections for users.
    #[command(long_about = "Cut a mesh by N parallel planes into a profile (.pro): a stack of sections, \
each a set of closed planar contours.\n\n\
Plane k lies at min + (k + 1/2) * extent / N along --axis (default z), so no plane touches the mesh's extremes. \
A vertex exactly on a plane counts as above it, so every crossing is decided exactly; holes in the mesh \
leave open chains, which are closed to the nearest chain start. Contours that are degenerate or cross \
another are dropped (and counted), so the output is always a valid profile.\n\n\
Example:\n  mint slice bunny.ply bunny.pro --sections 100 --axis y")]
    Slice(crate::contour_cmds::SliceArgs),
    /// Rebuild a surface from a stack of planar contours (.pro) by the angle
    /// criterion or by marching cubes.
    #[command(long_about = "Rebuild a surface from a profile (.pro): sections of planar contours, holes by nesting.\n\n\
--method angle (Dangl 1998, 2.2) joins the contour vertices of consecutive sections by strips of \
triangles: from a start pair (the vertex farthest from its centroid and its best match above), it \
advances on the side with the shorter new diagonal unless the edge directions disagree beyond \
--threshold (a cosine, default 0.5). Exact contours and few triangles; one contour facing several is \
split along chords (branching); --open for open polylines.\n\n\
--method mc puts the stack on a grid of --cubes cubes (default 64) across its larger side, one layer \
per section spacing, and runs mint's exact marching machinery: in-plane vertices where the contours \
really cross the grid lines, between-section vertices interpolated from the distances to the contours. \
Any holes and branching; watertight with --caps.\n\n\
--caps closes the ends: triangulated end sections (angle), caps half a spacing beyond them (mc).\n\n\
Examples:\n  mint contours organ.pro organ.ply --method mc --cubes 256 --caps --stats run.json\n  \
mint contours vase.pro vase.wrl --method angle --threshold 0.7 --caps")]
    Contours(crate::contour_cmds::ContoursArgs),
    /// Reduce an over-tessellated mesh by merging near-coplanar triangles
    /// (normals within --angle degrees) and re-triangulating each region.
    #[command(long_about = "Reduce an over-tessellated mesh with the normal optimizer (Dangl 1998, 3).\n\n\
Edge-connected triangles whose normals all lie within --angle degrees of one another form regions \
(--angle 0: exactly coplanar ones only). Each region that is a disk (with holes) and projects without \
folding on the plane of its Newell normal is re-triangulated from its boundary, smallest inner angle \
first; boundary vertices collinear with their neighbours in every region around them are dropped. \
Other regions stay as they are. No vertex moves: planar regions stay planar, and the topology and \
boundary are kept.\n\n\
Example:\n  mint optimize marching-cubed.ply clean.ply --angle 5 --stats opt.json")]
    Optimize(crate::contour_cmds::OptimizeArgs),
    /// Cast range images of a mesh from N viewpoints: test scans with true
    /// (and, on request, perturbed) poses in a .conf.
    #[command(long_about = "Cast range images of a mesh from N viewpoints, as an orthographic range scanner would.\n\n\
Writes, in OUT_DIR: view_NN.ply (a PLY range image: a grid of samples in the view's own frame, \
the layout of the Stanford scans; with --image-format rgrid or rgrid-ascii, view_NN.rgrid, \
mint's depth grid of docs/FORMATS.md), view_NN.mesh.ply (its triangle mesh), and scans.conf (Stanford \
convention) with the true pose of every view. With --perturb-deg/--perturb-frac it also writes \
scans-perturbed.conf, every view but the first moved at random: ground truth for `mint align`.\n\n\
Example:\n  mint scan bunny.ply scans/ --views 8 --noise 0.0005 --perturb-deg 5 --perturb-frac 0.05")]
    Scan(crate::range_cmds::ScanArgs),
    /// Register range scans to each other (constrained ICP) and write the refined poses.
    #[command(long_about = "Register range scans to each other with constrained ICP (Turk and Levoy 1994).\n\n\
Reads a scan set (Stanford .conf or MeshLab .aln; scans are PLY range images or meshes) with \
rough initial poses. Each scan's vertices are paired with the nearest points on the surfaces of \
the other scans within a distance d (and their vertices with its surface: --one-way turns that \
off), pairs on a mesh boundary are dropped, and the weighted best rigid motion is applied until \
convergence, over a hierarchy of subsampled scans with d halving per level: point-to-plane on \
the coarse levels, Horn's point-to-point quaternion on the last (--metric). Scans join a growing model, the best-overlapping first; a scan \
that cannot be registered is reported and left out of OUT_SET.\n\n\
Example:\n  mint align bun.conf bun-aligned.conf")]
    Align(crate::range_cmds::AlignArgs),
    /// Merge registered range scans into one mesh: zippering + consensus, or on a grid.
    #[command(long_about = "Merge registered range scans into one mesh.\n\n\
--method zipper (default; Turk and Levoy 1994): scans are added one at a time: overlapping \
boundary triangles are removed (the more confident surface stays), the meshes are trimmed to \
meet and stitched along their seams, small triangles are removed, and finally every vertex \
moves along its normal to the confidence-weighted average of the scans there (consensus \
geometry). The result is a 2-manifold at the scans' resolution; its boundary loops are where no \
scan saw the surface.\n\n\
--method grid (after Rocchini et al.'s Marching Intersections merge): every scan is cut by the \
lines of one grid (--cells / --cell-size); each crossing votes a signed distance to the grid \
nodes near it along its line, crossings of different scans on the same cell edge are merged by \
confidence, and the resampler rebuilds the surface. The result is always closed (watertight, \
2-manifold, oriented); unseen regions are closed where the surrounding inside and outside \
meet.\n\n\
Examples:\n  mint zipper bun-aligned.conf bunny.ply\n  mint zipper bun-aligned.conf bunny-closed.ply --method grid --cells 2000000")]
    Zipper(crate::range_cmds::ZipperArgs),
    /// Run resample, bool or csg as separate tasks: plan, run one task,
    /// watch (for resuming, and for clusters and schedulers).
    #[command(subcommand, long_about = "Run resample, bool or csg as stages of separate tasks, for schedulers and clusters.\n\n\
A staged run lives in a work directory DIR shared by every machine (NFS or the like). `mint stage plan` \
writes DIR/plan.json: the inputs' fingerprints, the options, and the stages in order with their task \
counts (bounds and discretize: one task per part of the input's faces; census, reconstruct and reopen: \
one per slab of the grid; write: one). `mint stage run DIR STAGE TASK` runs one task; tasks of one stage \
may run in any order, at the same time, on any machine, once the stages before are complete. A task's \
result is written atomically with a checksum; running a finished task again does nothing. The last \
stage writes the output. The output bytes are the same as one `mint resample` run.\n\n\
Example:\n  mint stage plan resample scan.ply out.ply --cells 100000000 --work /shared/run --parts 16 --slabs 16\n  \
mint stage run /shared/run bounds 0     # ... every task of every stage, in stage order\n  \
mint stage status /shared/run\n\n\
`mint slurm` does all of this on a Slurm cluster; docs/SCALE.md has the recipe for other schedulers.")]
    Stage(crate::stage_cmds::StageCommand),
    /// Run resample, bool or csg on a Slurm cluster: one job array per stage.
    #[command(long_about = "Run resample, bool or csg on a Slurm cluster.\n\n\
Writes the plan into --work DIR (which every node must see at the same path), writes one sbatch \
script per stage into DIR/slurm/, and submits them as job arrays (one array task per stage task), \
each depending on the one before (afterok, --kill-on-invalid-dep=yes), with `sbatch --parsable`. \
Prints the job ids. --dry-run writes the scripts and submits nothing; --wait follows the run with \
squeue and exits with its status. Extra sbatch options (partition, account, time, memory) go in \
--sbatch \"...\".\n\n\
Example:\n  mint slurm resample scan.ply out.ply --cells 100000000 --work /shared/run --parts 32 --slabs 32 \\\n      --sbatch \"--partition=batch --time=2:00:00\" --wait")]
    Slurm(crate::stage_cmds::SlurmArgs),
}

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Mesh file.
    pub file: PathBuf,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Exit with code 3 when the mesh is not watertight (for scripts).
    #[arg(long)]
    pub strict: bool,
    /// Also count the pairs of faces that intersect (exact predicates;
    /// faces sharing a vertex or an edge count only if they overlap beyond
    /// it), with a few examples. In memory: about 100 bytes per face.
    #[arg(long)]
    pub self_intersections: bool,
    /// Judge the indices as written. By default vertices at identical
    /// positions are merged first, as MeshLab and trimesh do on import: STL
    /// stores each triangle's corners separately and OBJ splits vertices at
    /// texture seams, which would otherwise read as boundaries everywhere.
    #[arg(long)]
    pub no_weld: bool,
}

#[derive(Args, Debug)]
pub struct DecimateArgs {
    /// Input mesh (any format mint reads, any size).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Faces of the output.
    #[arg(long)]
    pub faces: u64,
    /// Faces of the intermediate resampling [default: 8 × --faces; more costs time, rarely error].
    #[arg(long, value_name = "M")]
    pub intermediate: Option<u64>,
    /// Largest simplification error, as a fraction of the mesh's extent
    /// [default: 1, i.e. the face target decides].
    #[arg(long, value_name = "E", default_value_t = 1.0)]
    pub error: f32,
    /// Heap budget of the out-of-core stage, e.g. 2G [default: a quarter of RAM].
    #[arg(long, value_parser = parse_bytes)]
    pub mem: Option<u64>,
    /// Worker threads [default: all cores].
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Keep the resampling's stages here, to resume after a crash [default: temporary].
    #[arg(long, value_name = "DIR")]
    pub work: Option<PathBuf>,
    /// Directory for temporary files [default: the output's directory].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// Also write OUT.png beside the output: input and output side by side.
    #[arg(long)]
    pub preview: bool,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The meshes to draw, then the PNG to write.
    #[arg(required = true, num_args = 2.., value_name = "MESH... OUT.png")]
    pub files: Vec<PathBuf>,
    /// Size of each view, WIDTHxHEIGHT pixels.
    #[arg(long, default_value = "1200x900", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Where the camera looks from.
    #[arg(long, value_enum, default_value_t = ViewArg::Iso)]
    pub view: ViewArg,
    /// A reference mesh for `--color distance` (read in memory).
    #[arg(long = "ref", value_name = "REF")]
    pub reference: Option<PathBuf>,
    /// shading: flat shading (back faces orange). distance: the distance
    /// of each visible point to --ref, blue (0) to red (the largest), with
    /// a colour bar: where a resampling or decimation lost detail.
    #[arg(long, value_enum, default_value_t = ColorArg::Shading)]
    pub color: ColorArg,
    /// Worker threads [default: all cores]. The picture is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorArg {
    Shading,
    Distance,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewArg {
    Iso,
    Front,
    Back,
    Left,
    Right,
    Top,
    Bottom,
    All,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 1200x900"))?;
    let n = |t: &str| t.trim().parse::<u32>().map_err(|e| format!("'{s}': {e}"));
    Ok((n(w)?, n(h)?))
}

#[derive(Args, Debug)]
pub struct DistanceArgs {
    /// The mesh sampled first (A → B, then B → A).
    pub a: PathBuf,
    /// The other mesh.
    pub b: PathBuf,
    /// Area-uniform samples per direction.
    #[arg(long, default_value_t = 1_000_000)]
    pub samples: usize,
    /// Seed of the sample positions.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// UV sphere of radius 1 around the origin (genus 0).
    Sphere,
    /// Torus around the z axis, radii 1 and 0.35 (genus 1).
    Torus,
    /// Thick plate with --genus square holes.
    Genus,
    /// Many small disjoint spheres on a lattice.
    Components,
    /// Noisy sphere with holes, flipped faces, overlapping patches and
    /// non-manifold slivers; writes OUT.defects.json listing them.
    Scan,
}

#[derive(Args, Debug)]
pub struct GenArgs {
    /// Shape to generate.
    #[arg(value_enum)]
    pub shape: Shape,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// About this many faces.
    #[arg(long, default_value_t = 100_000)]
    pub faces: u64,
    /// Seed for shapes with randomness (components, scan).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of holes of the genus shape.
    #[arg(long, default_value_t = 3)]
    pub genus: u32,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Order of the vertices and faces in the file: as generated (spatially
    /// coherent), or shuffled, as real scans often come (the same surface
    /// and triangles; the torus is shuffled as it streams, at any size; other
    /// shapes are shuffled in memory, up to 50M faces).
    #[arg(long, value_enum, default_value_t = OrderArg::InOrder)]
    pub order: OrderArg,
    /// Print what was generated as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OrderArg {
    InOrder,
    Shuffled,
}

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Faces of the generated input.
    #[arg(long, default_value_t = 2_000_000)]
    pub faces: u64,
    /// Grid cells of the resampling.
    #[arg(long, default_value_t = 1_000_000)]
    pub cells: u64,
    /// Keep the input and output in this directory [default: a temporary
    /// directory, removed at the end].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Where to write the before/after picture [default: mint-demo.png in
    /// the --out directory, else in the current directory].
    #[arg(long, value_name = "PNG")]
    pub picture: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// Mesh file.
    pub file: PathBuf,
    /// Directory for temporary spill files (ASCII input) [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Mesh file.
    pub file: PathBuf,
    /// Print as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub output: PathBuf,
    /// Write ASCII instead of binary (PLY/STL).
    #[arg(long)]
    pub ascii: bool,
    /// Write vertex coordinates as f64 (PLY).
    #[arg(long)]
    pub double: bool,
    /// Directory for temporary spill files [default: the system temp dir].
    #[arg(long)]
    pub tmp: Option<PathBuf>,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Resample(a) => cmd_resample(a),
        Command::Bool(a) => cmd_bool(a),
        Command::Csg(a) => cmd_csg(a),
        Command::Info(a) => cmd_info(a),
        Command::Convert(a) => cmd_convert(a),
        Command::Validate(a) => cmd_validate(a),
        Command::Check(a) => cmd_check(a),
        Command::Distance(a) => cmd_distance(a),
        Command::Render(a) => cmd_render(a),
        Command::Decimate(a) => cmd_decimate(a),
        Command::Gen(a) => cmd_gen(a),
        Command::Demo(a) => cmd_demo(a),
        Command::Slice(a) => crate::contour_cmds::cmd_slice(a),
        Command::Contours(a) => crate::contour_cmds::cmd_contours(a),
        Command::Optimize(a) => crate::contour_cmds::cmd_optimize(a),
        Command::Scan(a) => crate::range_cmds::cmd_scan(a),
        Command::Align(a) => crate::range_cmds::cmd_align(a),
        Command::Zipper(a) => crate::range_cmds::cmd_zipper(a),
        Command::Stage(c) => crate::stage_cmds::cmd_stage(c),
        Command::Slurm(a) => crate::stage_cmds::cmd_slurm(a),
    }
}

fn cmd_resample(a: ResampleArgs) -> Result<()> {
    resample_and_report(a).map(|_| ())
}

pub(crate) fn resample_and_report(a: ResampleArgs) -> Result<mint_pipeline::ResampleSummary> {
    let opts = resample_options(&a)?;
    crate::paths::check_output(&a.output, &[&a.input])?;
    let mem = opts.mem_bytes;
    let tmp_root = a.tmp.clone().unwrap_or_else(|| a.output.parent().filter(|p| !p.as_os_str().is_empty()).map(PathBuf::from).unwrap_or_else(|| PathBuf::from(".")));
    let (input, _range_mesh) = resample_input(&a.input, a.work.as_deref(), &tmp_root)?;
    let bars = Bars::new(a.quiet || a.json);
    let mut summary = resample(&input, &a.output, &opts, &bars)?;
    summary.input = a.input.display().to_string();
    if a.preview {
        let png = preview_path(&a.output);
        let o = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
        mint_render::render_files(&[input.as_path(), a.output.as_path()], &png, &o, &bars)?;
        if !a.quiet && !a.json {
            eprintln!("preview: {} (input left, output right)", png.display());
        }
    }
    print_resample_summary(&summary, a.json, a.quiet, mem)?;
    Ok(summary)
}

fn cmd_info(a: InfoArgs) -> Result<()> {
    let info = mint_io::read_info(&a.file)?;
    if a.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(),
            "format": format!("{:?}", info.format),
            "encoding": info.encoding,
            "vertices": info.vertex_count,
            "faces": info.face_count,
            "elements": info.elements.iter().map(|e| serde_json::json!({
                "name": e.name, "count": e.count, "properties": e.properties
            })).collect::<Vec<_>>(),
            "comments": info.comments,
            "obj_info": info.obj_info,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("{}: {:?} ({})", a.file.display(), info.format, info.encoding);
        println!("  vertices  {}", info.vertex_count);
        match info.face_count {
            Some(n) => println!("  faces     {n}"),
            None => println!("  faces     (not stated in the header)"),
        }
        for e in &info.elements {
            println!("  element {} {}", e.name, e.count);
            for p in &e.properties {
                println!("    {p}");
            }
        }
        for c in &info.comments {
            println!("  comment {c}");
        }
        for c in &info.obj_info {
            println!("  obj_info {c}");
        }
    }
    Ok(())
}

fn cmd_convert(a: ConvertArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    let bars = Bars::new(a.quiet);
    use mint_pipeline::{Phase, Progress};
    bars.start(Phase::named("convert"), 0);
    let read = mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() };
    let write = WriteOptions { ascii: a.ascii, double: a.double, ..Default::default() };
    let mut last = 0u64;
    let summary = mint_io::convert_cancellable(&a.input, &a.output, read, write, &mut |done, _total| {
        bars.advance(done.saturating_sub(last));
        last = last.max(done);
        !crate::progress::interrupted()
    })
    .with_context(|| format!("converting {} to {}", a.input.display(), a.output.display()))?;
    bars.finish();
    if !a.quiet {
        eprintln!(
            "converted {} ({:?}) -> {} ({:?}): {} vertices, {} triangles, {}",
            a.input.display(),
            summary.input_format,
            a.output.display(),
            summary.output_format,
            summary.vertices_written,
            summary.triangles,
            human_bytes(summary.bytes_written)
        );
    }
    Ok(())
}


fn cmd_validate(a: ValidateArgs) -> Result<()> {
    use mint_pipeline::{Phase, Progress};
    let t = std::time::Instant::now();
    let mut reader = mint_io::MeshReader::open(&a.file, mint_io::ReadOptions { spill_dir: a.tmp.clone(), ..Default::default() })?;
    let bars = Bars::new(a.quiet || a.json);
    bars.start(Phase::named("validate"), reader.info().face_count.unwrap_or(0));
    let mut chunk = mint_io::TriangleChunk::default();
    let mut triangles = 0u64;
    // A checksum over positions keeps the read from being optimized away and
    // lets two runs be compared.
    let mut checksum = 0.0f64;
    while reader.next_chunk(&mut chunk)? {
        triangles += chunk.positions.len() as u64;
        for t in &chunk.positions {
            checksum += t[0][0] + t[1][1] + t[2][2];
        }
        bars.advance(chunk.positions.len() as u64);
        if crate::progress::interrupted() {
            bail!("interrupted");
        }
    }
    bars.finish();
    for w in reader.warnings() {
        eprintln!("mint: warning: {w}");
    }
    let secs = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&a.file).map(|m| m.len()).unwrap_or(0);
    let tps = triangles as f64 / secs.max(1e-9);
    let mbs = bytes as f64 / 1e6 / secs.max(1e-9);
    if a.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(), "vertices": reader.vertex_count(), "triangles": triangles,
            "seconds": secs, "triangles_per_second": tps, "mb_per_second": mbs, "checksum": checksum,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "{}: ok, {} vertices, {} triangles in {:.3}s ({:.1} M triangles/s, {:.0} MB/s)",
            a.file.display(),
            reader.vertex_count(),
            triangles,
            secs,
            tps / 1e6,
            mbs
        );
    }
    Ok(())
}

fn cmd_check(a: CheckArgs) -> Result<()> {
    let (mut positions, mut faces) = load_mesh(&a.file)?;
    let welded = if a.no_weld { 0 } else { mint_mesh::weld(&mut positions, &mut faces) };
    let mut r = mint_mesh::try_check(&positions, &faces).with_context(|| format!("{}", a.file.display()))?;
    r.welded_vertices = welded;
    let sx = a.self_intersections.then(|| mint_mesh::self_intersections(&positions, &faces, 5));
    if a.json {
        let mut v = serde_json::to_value(&r)?;
        v["file"] = a.file.display().to_string().into();
        if let Some(x) = &sx {
            v["self_intersections"] = serde_json::to_value(x)?;
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print_check(&a.file.display().to_string(), &r);
        if let Some(x) = &sx {
            let ex: Vec<String> = x.examples.iter().map(|[i, j]| format!("{i}-{j}")).collect();
            println!(
                "  self-intersections {} pairs of faces{}",
                x.pairs,
                if ex.is_empty() { String::new() } else { format!(" (e.g. faces {})", ex.join(", ")) }
            );
        }
    }
    if a.strict && !r.watertight {
        std::process::exit(3);
    }
    Ok(())
}

fn print_check(name: &str, r: &mint_mesh::CheckReport) {
    println!("{name}: {}", if r.watertight { "watertight (closed, 2-manifold, consistently oriented)" } else { "NOT watertight" });
    println!("  vertices {} ({} unreferenced), faces {}", r.vertices, r.unreferenced_vertices, r.faces);
    if r.welded_vertices > 0 {
        println!("  welded {} vertices at identical positions into earlier ones (--no-weld judges the indices as written)", r.welded_vertices);
    }
    if let (Some(lo), Some(hi)) = (r.bbox_min, r.bbox_max) {
        println!("  bbox [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    }
    println!("  components {} ({} closed), genus of closed ones {:?} (total {})", r.components, r.closed_components, r.genera, r.genus_total);
    println!("  edges {}, boundary edges {} in {} loops ({} on non-simple boundaries)", r.edges, r.boundary_edges, r.boundary_loops, r.non_simple_boundary_edges);
    println!("  non-manifold edges {}, non-manifold vertices {}", r.non_manifold_edges, r.non_manifold_vertices);
    println!("  inconsistently oriented edges {}", r.inconsistently_oriented_edges);
    println!("  degenerate faces {} ({} with a repeated index), duplicate faces {}", r.degenerate_faces, r.collapsed_faces, r.duplicate_faces);
    println!("  Euler characteristic {}, signed volume {:.9}, area {:.9}", r.euler_characteristic, r.signed_volume, r.surface_area);
}

fn cmd_decimate(a: DecimateArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[&a.input])?;
    if a.preview {
        crate::paths::check_output(&preview_path(&a.output), &[&a.input])?;
    }
    let mem = a.mem.unwrap_or_else(default_mem);
    let o = mint_pipeline::DecimateOptions {
        target_faces: a.faces,
        intermediate_faces: a.intermediate,
        max_error: a.error,
        resample: ResampleOptions { mem_bytes: mem, threads: a.threads, tmp_dir: a.tmp.clone(), work_dir: a.work.clone(), ..Default::default() },
    };
    let bars = Bars::new(a.quiet || a.json);
    let s = mint_pipeline::decimate(&a.input, &a.output, &o, &bars)?;
    if a.preview {
        let png = preview_path(&a.output);
        let ro = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
        mint_render::render_files(&[a.input.as_path(), a.output.as_path()], &png, &ro, &bars)?;
        if !a.quiet && !a.json {
            eprintln!("preview: {} (input left, output right)", png.display());
        }
    }
    if a.json {
        let mut v = serde_json::to_value(&s)?;
        v["mem_budget_bytes"] = mem.into();
        v["peak_heap_bytes"] = alloc::peak_heap().into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else if !a.quiet {
        eprintln!("decimated {} -> {}", s.input, s.output);
        eprintln!("  input        {} faces, area {:.6}", s.input_faces, s.input_area);
        eprintln!("  resampled    {} faces (asked {}), cells of {:.6}, {}", s.intermediate_faces, s.intermediate_faces_asked, s.cell_size, if s.intermediate_watertight { "watertight" } else { "NOT watertight" });
        eprintln!("  simplified   {} faces (target {}), {} vertices, error {:.2e} of the extent", s.output_faces, s.target_faces, s.output_vertices, s.simplify_error);
        eprintln!(
            "  output       {}{}",
            if s.output_watertight { "watertight (closed, 2-manifold, consistently oriented)" } else { "NOT watertight" },
            if s.relaxed > 0 { format!("; target relaxed {} times to keep it so", s.relaxed) } else { String::new() }
        );
        eprintln!(
            "  time         {:.2}s (area {:.2}s, resample {:.2}s, simplify {:.2}s, write {:.2}s), peak heap {}",
            s.seconds_total, s.seconds_area, s.seconds_resample, s.seconds_simplify, s.seconds_write, human_bytes(alloc::peak_heap())
        );
    }
    if s.intermediate_watertight && !s.output_watertight {
        eprintln!("mint: warning: the output is less clean than the resampling (see the summary)");
    }
    Ok(())
}

fn cmd_render(a: RenderArgs) -> Result<()> {
    let (output, inputs) = a.files.split_last().expect("clap requires two files");
    if output.extension().is_none_or(|e| !e.eq_ignore_ascii_case("png")) {
        bail!("{}: the picture is written as PNG; name it OUT.png", output.display());
    }
    let refs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
    crate::paths::check_output(output, &refs)?;
    let view = match a.view {
        ViewArg::Iso => mint_render::View::Iso,
        ViewArg::Front => mint_render::View::Front,
        ViewArg::Back => mint_render::View::Back,
        ViewArg::Left => mint_render::View::Left,
        ViewArg::Right => mint_render::View::Right,
        ViewArg::Top => mint_render::View::Top,
        ViewArg::Bottom => mint_render::View::Bottom,
        ViewArg::All => mint_render::View::All,
    };
    let distance_to = match (a.color, &a.reference) {
        (ColorArg::Distance, Some(r)) => Some(r.clone()),
        (ColorArg::Distance, None) => bail!("--color distance needs --ref REF, the mesh to measure against"),
        (ColorArg::Shading, Some(_)) => bail!("--ref is used with --color distance"),
        (ColorArg::Shading, None) => None,
    };
    if let Some(r) = &distance_to {
        crate::paths::check_not_input(output, &[r.as_path()])?;
    }
    let threads = if a.threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { a.threads };
    let o = mint_render::RenderOptions { width: a.size.0, height: a.size.1, view, threads, distance_to };
    let bars = Bars::new(a.quiet || a.json);
    let s = mint_render::render_files(&refs, output, &o, &bars)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else if !a.quiet {
        eprintln!("rendered {} triangles -> {} ({}x{}, {} pixels covered) in {:.2}s", s.triangles, s.output, s.width, s.height, s.covered_pixels, s.seconds);
        if let (Some(max), Some(mean)) = (s.distance_max, s.distance_mean) {
            eprintln!("  distance to the reference over the visible surface: mean {mean:.3e}, max {max:.3e} (the colour bar's top)");
        }
    }
    Ok(())
}

fn cmd_distance(a: DistanceArgs) -> Result<()> {
    let ma = load_mesh(&a.a)?;
    let mb = load_mesh(&a.b)?;
    let (ab, ba) = mint_mesh::try_symmetric_distance((&ma.0, &ma.1), (&mb.0, &mb.1), a.samples, a.seed)
        .with_context(|| format!("distance between {} and {}", a.a.display(), a.b.display()))?;
    if a.json {
        let v = serde_json::json!({ "a": a.a.display().to_string(), "b": a.b.display().to_string(), "a_to_b": ab, "b_to_a": ba });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        for (name, r) in [(format!("{} -> {}", a.a.display(), a.b.display()), &ab), (format!("{} -> {}", a.b.display(), a.a.display()), &ba)] {
            println!("{name} ({} samples)", r.samples);
            println!("  mean {:.6e} ({:.3e} of diagonal)", r.mean, r.mean_rel);
            println!("  rms  {:.6e} ({:.3e} of diagonal)", r.rms, r.rms_rel);
            println!("  max  {:.6e} ({:.3e} of diagonal) at {:?}", r.max, r.max_rel, r.max_point);
        }
    }
    Ok(())
}

/// Generates `a.shape` into `w`: what was generated, and the scan's defects.
fn cmd_gen_into(a: &GenArgs, w: &mut dyn mint_core::MeshSink) -> Result<(serde_json::Value, Option<mint_gen::ScanDefects>)> {
    Ok(match a.shape {
        Shape::Sphere => (serde_json::to_value(mint_gen::sphere([0.0; 3], 1.0, a.faces, w)?)?, None),
        Shape::Torus => (serde_json::to_value(mint_gen::torus([0.0; 3], 1.0, 0.35, a.faces, w)?)?, None),
        Shape::Genus => (serde_json::to_value(mint_gen::genus(a.genus, a.faces, w)?)?, None),
        Shape::Components => (serde_json::to_value(mint_gen::components(a.faces, a.seed, w)?)?, None),
        Shape::Scan => {
            let d = mint_gen::scan_like(a.faces, a.seed, &mint_gen::ScanOptions::default(), w)?;
            (serde_json::to_value(&d.counts)?, Some(d))
        }
    })
}

fn cmd_gen(a: GenArgs) -> Result<()> {
    crate::paths::check_output(&a.output, &[])?;
    let format = mint_io::Format::from_path(&a.output)?;
    let mut w = mint_io::MeshWriter::create(&a.output, format, WriteOptions { ascii: a.ascii, ..Default::default() })?;
    let (generated, defects) = match (a.order, a.shape) {
        (OrderArg::Shuffled, Shape::Torus) => (serde_json::to_value(mint_gen::torus_shuffled([0.0; 3], 1.0, 0.35, a.faces, a.seed, &mut w)?)?, None),
        (OrderArg::Shuffled, _) => {
            if a.faces > 50_000_000 {
                bail!("--order shuffled: only the torus is shuffled as it streams; other shapes are shuffled in memory, up to 50,000,000 faces");
            }
            let mut m = mint_core::TriMesh::default();
            let g = cmd_gen_into(&a, &mut m)?;
            mint_gen::shuffle_mesh(&m, a.seed, &mut w)?;
            g
        }
        (OrderArg::InOrder, _) => cmd_gen_into(&a, &mut w)?,
    };
    let written = w.finish()?;
    if let Some(d) = &defects {
        let side = sidecar_path(&a.output);
        let tmp = side.with_extension("json.mint-tmp");
        std::fs::write(&tmp, serde_json::to_string_pretty(d)?).with_context(|| format!("{}: writing the defect list", tmp.display()))?;
        std::fs::rename(&tmp, &side).with_context(|| format!("{}: renaming the defect list", side.display()))?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&generated)?);
    } else {
        eprintln!(
            "generated {:?}: {} vertices, {} faces -> {} ({})",
            a.shape,
            written.vertices,
            written.faces,
            a.output.display(),
            human_bytes(written.bytes)
        );
        if defects.is_some() {
            eprintln!("defects listed in {}", sidecar_path(&a.output).display());
        }
    }
    Ok(())
}

/// `out.ply` -> `out.defects.json`.
pub fn sidecar_path(out: &std::path::Path) -> PathBuf {
    out.with_extension("defects.json")
}

fn cmd_demo(a: DemoArgs) -> Result<()> {
    let tmp;
    let dir = match &a.out {
        Some(d) => {
            std::fs::create_dir_all(d).with_context(|| format!("{}: creating the output directory", d.display()))?;
            d.clone()
        }
        None => {
            tmp = tempfile_dir()?;
            tmp.path().to_path_buf()
        }
    };
    let input = dir.join("demo-genus3.ply");
    let output = dir.join("demo-genus3-resampled.ply");
    eprintln!("1/3 generating a genus-3 solid with about {} faces: {}", a.faces, input.display());
    cmd_gen(GenArgs { shape: Shape::Genus, output: input.clone(), faces: a.faces, seed: 1, genus: 3, ascii: false, order: OrderArg::InOrder, json: false })?;
    eprintln!("2/3 resampling it on about {} cells", a.cells);
    let s = resample_and_report(ResampleArgs {
        input: input.clone(),
        output: output.clone(),
        cells: Some(a.cells),
        cell_size: None,
        mem: None,
        threads: 0,
        tmp: None,
        axis: AxisArg::Auto,
        slab: None,
        work: None,
        parts: 1,
        slabs: 1,
        signs: SignsArg::Auto,
        max_hole: 16,
        close_all: false,
        grid_offset: None,
        ascii: false,
        double: false,
        quiet: false,
        json: false,
        preview: false,
    })?;
    eprintln!("3/3 checking the output");
    let (positions, faces) = load_mesh(&output)?;
    let r = mint_mesh::try_check(&positions, &faces)?;
    print_check(&output.display().to_string(), &r);
    if !(r.watertight && r.genus_total == 3 && s.non_canonical_cells == 0) {
        bail!("demo output is not a watertight genus-3 surface: this is a bug, please report it");
    }
    let png = a.picture.clone().unwrap_or_else(|| a.out.as_ref().map_or_else(|| PathBuf::from("mint-demo.png"), |d| d.join("mint-demo.png")));
    let o = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
    mint_render::render_files(&[input.as_path(), output.as_path()], &png, &o, &Bars::new(true))?;
    println!("demo ok: {} faces -> {} faces, watertight, genus 3", s.input_faces, s.output_faces);
    println!("picture: {} (input left, resampled right)", png.display());
    Ok(())
}

struct TempDir(PathBuf);
impl TempDir {
    fn path(&self) -> &std::path::Path {
        &self.0
    }
}
impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
fn tempfile_dir() -> Result<TempDir> {
    let base = std::env::temp_dir().join(format!("mint-demo-{}", std::process::id()));
    std::fs::create_dir_all(&base).with_context(|| format!("{}: creating a temporary directory", base.display()))?;
    Ok(TempDir(base))
}

fn cmd_bool(a: BoolArgs) -> Result<()> {
    let opts = grid_options(&a.grid)?;
    crate::paths::check_output(&a.output, &[&a.a, &a.b])?;
    let op = match a.op {
        BoolOpArg::Union => mint_core::robust::BoolOp::Union,
        BoolOpArg::Intersection => mint_core::robust::BoolOp::Intersection,
        BoolOpArg::Difference => mint_core::robust::BoolOp::Difference,
    };
    let bars = Bars::new(a.grid.quiet || a.grid.json);
    let s = mint_pipeline::boolean(op, &a.a, &a.b, &a.output, &opts, &bars)?;
    if a.grid.preview {
        write_preview(&[a.a.as_path(), a.b.as_path(), a.output.as_path()], &a.output, a.grid.quiet || a.grid.json, &bars)?;
    }
    report(&a.grid, &s)
}

/// `--preview`: `OUT.png` beside `output`, the meshes side by side.
fn write_preview(meshes: &[&std::path::Path], output: &std::path::Path, quiet: bool, bars: &Bars) -> Result<()> {
    let png = preview_path(output);
    let o = mint_render::RenderOptions { width: 800, height: 600, view: mint_render::View::Iso, ..Default::default() };
    mint_render::render_files(meshes, &png, &o, bars)?;
    if !quiet {
        eprintln!("preview: {} ({})", png.display(), meshes.iter().map(|m| m.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned())).collect::<Vec<_>>().join(", "));
    }
    Ok(())
}

fn cmd_csg(a: CsgArgs) -> Result<()> {
    let opts = grid_options(&a.grid)?;
    crate::paths::check_output(&a.output, &[&a.scene])?;
    let text = std::fs::read_to_string(&a.scene).with_context(|| format!("{}: cannot read the scene", a.scene.display()))?;
    let scene = mint_pipeline::parse_scene(&text, &a.scene)?;
    crate::paths::check_output(&a.output, &scene_inputs(&a.scene, &scene))?;
    let bars = Bars::new(a.grid.quiet || a.grid.json);
    let s = mint_pipeline::csg(&scene, &a.scene.display().to_string(), &a.output, &opts, &bars)?;
    if a.grid.preview {
        let mut meshes: Vec<&std::path::Path> = scene.operands.iter().filter_map(|o| match o {
            mint_pipeline::scene::Operand::Mesh { path, .. } => Some(path.as_path()),
            _ => None,
        }).collect();
        meshes.push(a.output.as_path());
        write_preview(&meshes, &a.output, a.grid.quiet || a.grid.json, &bars)?;
    }
    report(&a.grid, &s)
}
