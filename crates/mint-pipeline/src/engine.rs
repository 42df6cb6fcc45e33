//! The staged engine's drivers: one engine for `resample`, `bool` and
//! `csg` (a [`RunSpec`]), run either whole in one process ([`run`],
//! [`run_scene`]: every stage's tasks in order, in a work directory that is
//! temporary or kept with `Tuning::work_dir` for resuming), or one task at a time
//! by separate processes on any machines sharing the work directory
//! ([`plan_run`], then [`run_task`] per task, [`status`] to watch; see the
//! `slurm` module for a scheduler).
//!
//! Both paths run the same task code (`stages`), so their output bytes are
//! the same. A resumed run (same work directory) checks that the inputs'
//! fingerprints and the spec match the plan, keeps every finished task
//! and runs the rest.

use crate::error::PipelineError;
use crate::summary::{ResampleSummary, MAX_LISTED};
use crate::progress::check_cancel;
use crate::plan::{Fingerprint, OperandPlan, Plan, Stage};
use crate::progress::Progress;
use crate::scene::{Operand, Scene};
use crate::spec::{Job, RunSpec, Tuning};
use crate::stages::{run_stage_task, Ctx, DiscretizeResult};
use crate::workdir::{disk_bytes, is_done, task_dir, temp_tasks, Owner, TaskBuild, PLAN_FILE};
use mint_core::signs::SignRule;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The name of a temporary work directory (`.mint-work-XXXXXX`).
pub const WORK_PREFIX: &str = ".mint-work-";

/// Runs `spec` whole in this process, in `tuning.work_dir` (kept, and
/// resumed when it holds the same run) or a temporary directory.
pub fn run(spec: &RunSpec, tuning: &Tuning, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    run_job(spec, None, tuning, progress)
}

/// Runs a CSG `spec` whose scene is already parsed (`scene`), so that the
/// scene file is not read again.
pub fn run_scene(spec: &RunSpec, scene: &Scene, tuning: &Tuning, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    run_job(spec, Some(scene.clone()), tuning, progress)
}

/// Writes the plan of `spec` into `dir` (created if needed). A directory
/// that already holds the same run's plan is kept as it is (its finished
/// tasks stay); one that holds another run's is refused.
pub fn plan_run(spec: &RunSpec, scene: Option<Scene>, tuning: &Tuning, dir: &Path) -> Result<Plan, PipelineError> {
    spec.validate()?;
    let scene = match scene {
        Some(s) => s,
        None => spec.job.scene()?,
    };
    let plan = Plan::new(spec, &scene, tuning)?;
    std::fs::create_dir_all(dir).map_err(|source| PipelineError::Temp { path: dir.to_path_buf(), op: "creating the work directory", source })?;
    if dir.join(PLAN_FILE).exists() {
        let stored = Plan::load(dir)?;
        plan.check_same_run(&stored, dir)?;
        return Ok(stored);
    }
    plan.save(dir)?;
    Ok(plan)
}

/// What [`run_task`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TaskOutcome {
    Ran,
    AlreadyDone,
}

/// What one task's process changes of the plan's [`Tuning`] (`None`:
/// the plan's). None of it changes the output.
#[derive(Debug, Clone, Default)]
pub struct TaskOptions {
    /// Worker threads; 0: all cores.
    pub threads: Option<usize>,
    /// Heap budget.
    pub mem_bytes: Option<u64>,
    /// How discretize tasks dereference faces.
    pub deref: Option<crate::deref::Deref>,
}

impl TaskOptions {
    /// The plan's tuning with these changes.
    pub fn apply(&self, plan: &Tuning) -> Tuning {
        Tuning {
            threads: self.threads.unwrap_or(plan.threads),
            mem_bytes: self.mem_bytes.unwrap_or(plan.mem_bytes),
            deref: self.deref.unwrap_or(plan.deref),
            ..plan.clone()
        }
    }
}

/// Runs task `task` of `stage` of the plan in `dir`, in this process. A
/// finished task is a no-op. Fails with one line when the plan is of
/// another version, an input changed, or a stage before is incomplete.
pub fn run_task(dir: &Path, stage: Stage, task: u32, topts: &TaskOptions, progress: &dyn Progress) -> Result<TaskOutcome, PipelineError> {
    let plan = Plan::load(dir)?;
    let Some(pos) = plan.stages.iter().position(|s| s.name == stage) else {
        let names: Vec<&str> = plan.stages.iter().map(|s| s.name.dir_name()).collect();
        return Err(PipelineError::stage(dir, format!("this plan has no stage '{stage}' (its stages: {})", names.join(", "))));
    };
    let n = plan.stages[pos].tasks;
    if task >= n {
        return Err(PipelineError::stage(dir, format!("stage '{stage}' has tasks 0 to {} (asked for {task})", n - 1)));
    }
    if is_done(dir, stage, task) {
        return Ok(TaskOutcome::AlreadyDone);
    }
    for before in &plan.stages[..pos] {
        let missing: Vec<u32> = (0..before.tasks).filter(|&t| !is_done(dir, before.name, t)).collect();
        if !missing.is_empty() {
            let list: Vec<String> = missing.iter().take(8).map(|t| t.to_string()).collect();
            return Err(PipelineError::stage(
                dir,
                format!(
                    "stage '{}' is not complete: task{} {}{} of {} not done; run {} first",
                    before.name,
                    if missing.len() > 1 { "s" } else { "" },
                    list.join(", "),
                    if missing.len() > 8 { ", …" } else { "" },
                    before.tasks,
                    if missing.len() > 1 { "them" } else { "it" }
                ),
            ));
        }
    }
    verify_inputs(&plan)?;
    let scene = plan.spec.job.scene()?;
    let tuning = topts.apply(&plan.tuning);
    plan.check_scene(&scene, &dir.join(crate::workdir::PLAN_FILE))?;
    let ctx = Ctx::new(dir, plan, scene, &tuning, progress);
    run_one(&ctx, stage, task)?;
    Ok(TaskOutcome::Ran)
}

/// Checks every input against its fingerprint in the plan.
fn verify_inputs(plan: &Plan) -> Result<(), PipelineError> {
    for f in &plan.inputs {
        let now = Fingerprint::of(&f.path)?;
        if &now != f {
            return Err(PipelineError::stage(
                &f.path,
                "this input changed since the run was planned (size, modification time or content); plan the run again in a new work directory",
            ));
        }
    }
    Ok(())
}

/// Runs one task and commits it. Cancellation is checked before the task
/// starts (and inside it, by its loops); a task whose work is complete is
/// committed even if a cancel arrives meanwhile, so that a write task that
/// has put the output in place never reports "no output written".
fn run_one(ctx: &Ctx, stage: Stage, task: u32) -> Result<(), PipelineError> {
    check_cancel(ctx.progress)?;
    let build = TaskBuild::begin(&ctx.dir, stage, task)?;
    let result = run_stage_task(ctx, stage, task, &build)?;
    build.commit(&result)
}

/// Forwards progress and cancellation of tasks run side by side; the phase
/// is started once for all of them (its total unknown).
struct Shared<'a>(&'a dyn Progress);

impl Progress for Shared<'_> {
    fn advance(&self, n: u64) {
        self.0.advance(n)
    }
    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

/// Runs `tasks` of `stage` on `workers` threads, each task with its share of
/// the threads and of the memory budget, taking tasks in order. Every
/// running task finishes; the error reported is that of the first task in
/// task order that failed, as running them one by one would report.
fn run_concurrently(ctx: &Ctx, tuning: &Tuning, stage: Stage, tasks: &[u32], workers: usize) -> Result<(), PipelineError> {
    let mut t = tuning.clone();
    t.threads = (ctx.threads / workers).max(1);
    t.mem_bytes = (tuning.mem_bytes / workers as u64).max(1);
    let shared = Shared(ctx.progress);
    let phase = match stage {
        Stage::Bounds => crate::progress::BOUNDS,
        _ => crate::progress::DISCRETIZE,
    };
    ctx.progress.start(phase, 0);
    // Each worker keeps the errors of its tasks; the pool stops handing out
    // tasks at the first one, and the running ones finish.
    let (_, errors, ()) = mint_core::pool::run(
        workers,
        tasks.len() as u64,
        |_| (Ctx::new(&ctx.dir, ctx.plan.clone(), ctx.scene.clone(), &t, &shared), Vec::new()),
        |(wctx, errs): &mut (Ctx, Vec<(u32, PipelineError)>), i| {
            let task = tasks[i as usize];
            run_one(wctx, stage, task).map_err(|e| errs.push((task, e)))
        },
        |(_, errs)| errs,
        |_| (),
    );
    ctx.progress.finish();
    let mut errors: Vec<(u32, PipelineError)> = errors.into_iter().flatten().collect();
    errors.sort_by_key(|e| e.0);
    match errors.into_iter().next() {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

/// Runs a whole job in this process; see the module docs.
fn run_job(spec: &RunSpec, scene: Option<Scene>, tuning: &Tuning, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let t_start = Instant::now();
    spec.validate()?;
    let output = &spec.output;
    let tmp_root = match &tuning.tmp_dir {
        Some(d) => d.clone(),
        None => output.parent().filter(|p| !p.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
    };
    let (_temp, _owner);
    let mut removed_dead = Vec::new();
    let dir = match &tuning.work_dir {
        Some(d) => d.clone(),
        None => {
            // Work directories that killed runs left here go first.
            removed_dead = crate::workdir::remove_dead(&tmp_root, WORK_PREFIX);
            let t = tempfile::Builder::new().prefix(WORK_PREFIX).tempdir_in(&tmp_root).map_err(|source| PipelineError::Temp {
                path: tmp_root.clone(),
                op: "creating the work directory",
                source,
            })?;
            let p = t.path().to_path_buf();
            crate::workdir::mark_temporary(&p)?;
            _owner = crate::workdir::OwnerLock::of_dir(&p)?;
            _temp = t;
            p
        }
    };
    let scene = match scene {
        Some(s) => s,
        None => spec.job.scene()?,
    };
    let plan = plan_run(spec, Some(scene.clone()), tuning, &dir)?;
    // Task directories abandoned by a process that died.
    for stage in &plan.stages {
        for (t, owner) in temp_tasks(&dir, stage.name) {
            if owner == Owner::Dead {
                let _ = std::fs::remove_dir_all(t);
            }
        }
    }
    // The output was removed after a finished run: write it again.
    if is_done(&dir, Stage::Write, 0) && !plan.spec.output.exists() {
        let _ = std::fs::remove_dir_all(task_dir(&dir, Stage::Write, 0));
    }
    let stages = plan.stages.clone();
    plan.check_scene(&scene, &dir.join(crate::workdir::PLAN_FILE))?;
    let ctx = Ctx::new(&dir, plan, scene, tuning, progress);
    let (mut ran, mut resumed) = (0u64, 0u64);
    let mut seconds = std::collections::HashMap::new();
    for stage in &stages {
        let t = Instant::now();
        let pending: Vec<u32> = (0..stage.tasks).filter(|&task| !is_done(&dir, stage.name, task)).collect();
        resumed += (stage.tasks as usize - pending.len()) as u64;
        // Parts of text files (OBJ, ASCII PLY…) run side by side, since one
        // such file is parsed on one thread; parts of binary files run one
        // after the other, each on every thread (records read in place).
        let text = ctx.plan.operands.iter().any(|o| matches!(o, OperandPlan::Mesh { files } if files.iter().any(|f| f.split_faces.is_none())));
        let workers = if text && matches!(stage.name, Stage::Bounds | Stage::Discretize) { ctx.threads.min(pending.len()) } else { 1 };
        if workers > 1 {
            run_concurrently(&ctx, tuning, stage.name, &pending, workers)?;
        } else {
            for &task in &pending {
                run_one(&ctx, stage.name, task)?;
            }
        }
        ran += pending.len() as u64;
        seconds.insert(stage.name, t.elapsed().as_secs_f64());
    }
    let mut s = summarize(&ctx)?;
    set_stage_seconds(&mut s, &seconds);
    s.output = output.display().to_string();
    s.seconds_total = t_start.elapsed().as_secs_f64();
    s.work_dir = tuning.work_dir.as_ref().map(|d| d.display().to_string());
    s.tasks_run = ran;
    s.tasks_resumed = resumed;
    s.removed_dead = removed_dead.iter().map(|p| p.display().to_string()).collect();
    Ok(s)
}

/// The summary's seconds per phase, from seconds per stage.
fn set_stage_seconds(s: &mut ResampleSummary, seconds: &std::collections::HashMap<Stage, f64>) {
    let sec = |n: Stage| seconds.get(&n).copied().unwrap_or(0.0);
    s.seconds_bounds = sec(Stage::Bounds);
    s.seconds_discretize = sec(Stage::Discretize);
    s.seconds_census = sec(Stage::Census);
    s.seconds_reconstruct = sec(Stage::Reconstruct) + sec(Stage::Reopen);
    s.seconds_write = sec(Stage::Write);
}

/// The summary of a finished run, from its tasks' results.
pub fn summarize(ctx: &Ctx) -> Result<ResampleSummary, PipelineError> {
    let plan = &ctx.plan;
    let grid = ctx.grid()?;
    let mut s = ResampleSummary {
        input: plan.spec.job.name(),
        output: plan.spec.output.display().to_string(),
        threads: ctx.threads,
        grid_cells: grid.dims,
        cell_size: grid.cell,
        grid_origin: grid.origin,
        slab_axis: ['x', 'y', 'z'][grid.slab_axis],
        ..Default::default()
    };
    s.colour = plan.coloured();
    s.no_colour = plan.spec.write.no_colour;
    let parts: &[DiscretizeResult] = ctx.parts()?;
    let mut mesh_ops = Vec::new();
    for (j, op) in plan.operands.iter().enumerate() {
        if let OperandPlan::Mesh { files } = op {
            s.input_files += files.len() as u64;
            s.input_vertices += ctx.vertices_read(j)?;
            s.input_tiles += files.iter().map(|f| f.tiles).sum::<u64>();
            s.input_coloured_files += files.iter().filter(|f| f.colour).count() as u64;
            s.input_faces += ctx.faces_and_volume(j)?.0;
            mesh_ops.push(j);
        }
    }
    let mut derefs: Vec<String> = Vec::new();
    for m in parts.iter().flat_map(|p| p.shards.iter().flatten()) {
        s.intercepts_found += m.records();
        s.shard_bytes += m.bytes();
    }
    for m in parts.iter().flat_map(|p| p.operands.iter().flatten()) {
        if let Some(d) = &m.deref {
            let line = format!("{}: {}", if d.sort { "sort" } else { "mmap" }, d.reason);
            if !derefs.contains(&line) {
                derefs.push(line);
            }
        }
        s.deref_spilled_bytes += m.sort.map_or(0, |st| st.bytes_spilled);
        for w in &m.warnings {
            if !s.input_warnings.contains(w) {
                s.input_warnings.push(w.clone());
            }
        }
    }
    s.deref = derefs.join("; ");
    let (rules, census) = ctx.rules()?;
    if let Job::Resample { .. } = plan.spec.job {
        let vol = ctx.faces_and_volume(0)?.1;
        s.input_signed_volume = vol * grid.cell.powi(3);
        s.orientation_inverted = ctx.inverted(0)?;
        s.orientation_from = if rules[0] == SignRule::Sheet { "faces" } else { "volume" }.to_string();
        s.sign_rule = rules[0].to_string();
        (s.census_lines, s.census_winding_valid, s.census_odd) = (census[0].lines, census[0].winding_valid, census[0].odd);
    } else {
        let names: Vec<String> = ctx
            .scene
            .operands
            .iter()
            .zip(rules)
            .map(|(op, r)| match op {
                Operand::Primitive(_) => "exact".to_string(),
                Operand::Mesh { .. } | Operand::Volume(_) => r.to_string(),
            })
            .collect();
        s.sign_rule = names.join(",");
    }
    if let Some((job, info)) = ctx.volume()? {
        let mut st = crate::volume::VolumeStats::default();
        for p in parts {
            if let Some(Some(v)) = p.volumes.first() {
                st.merge(v);
            }
        }
        let surface = match job.surface {
            crate::spec::VolumeSurface::Iso(v) => format!("iso {v}"),
            crate::spec::VolumeSurface::Label(v) => format!("label {v}"),
        };
        let name = job.input.display();
        if st.nan > 0 {
            s.input_warnings.push(format!("{name}: {} of {} samples are NaN; they count as outside", st.nan, st.samples));
        }
        match (st.range, job.surface) {
            (None, _) => s.input_warnings.push(format!("{name}: no sample is a finite number; the result is empty")),
            (Some([lo, hi]), crate::spec::VolumeSurface::Iso(v)) if v > hi => {
                s.input_warnings.push(format!("{name}: iso {v} is above every value ({lo} .. {hi}): nothing is inside, the result is empty"))
            }
            (Some([lo, hi]), crate::spec::VolumeSurface::Iso(v)) if v <= lo => {
                s.input_warnings.push(format!("{name}: iso {v} is at or below every value ({lo} .. {hi}): everything is inside, the result is the volume's box"))
            }
            _ => {}
        }
        s.input_files = info.files.len() as u64;
        s.volume = Some(crate::summary::VolumeSummary {
            format: info.format.to_string(),
            dims: info.dims,
            sample: info.sample.name().to_string(),
            slope: info.slope,
            intercept: info.intercept,
            spacing: std::array::from_fn(|d| info.spacing(d)),
            frame: info.frame.name().to_string(),
            surface,
            own_grid: job.own_grid,
            open_border: job.open_border,
            border_faces_removed: 0,
            border_vertices_split: 0,
            slices_read: st.slices,
            samples_read: st.samples,
            nan_samples: st.nan,
            value_range: st.range,
        });
    }
    let (open, holes) = ctx.open_cells()?;
    s.holes_closed = holes.closed;
    s.holes_left_open = holes.left_open;
    s.open_cells = open.as_ref().map_or(0, |o| o.len() as u64);
    let (mut kept, mut removed) = (0, 0);
    let mut loose: Vec<(u32, u32)> = Vec::new();
    for t in 0..plan.tasks(Stage::Reconstruct) {
        let (stage, r) = ctx.final_slab(t)?;
        if let Some(sum) = r.loose_file {
            let offset = s.output_vertices;
            let path = crate::workdir::task_dir(&ctx.dir, stage, t).join("loose.bin");
            crate::workdir::read_records::<8>(&path, sum, |b| {
                let a = u32::from_le_bytes(b[..4].try_into().unwrap()) as u64 + offset;
                let c = u32::from_le_bytes(b[4..].try_into().unwrap()) as u64 + offset;
                loose.push((a as u32, c as u32));
                Ok(())
            })?;
        }
        s.slabs += r.sub_slabs;
        s.planned_slab_bytes = s.planned_slab_bytes.max(r.planned_slab_bytes);
        s.output_vertices += r.vertices;
        s.output_faces += r.faces;
        s.active_cells += r.active_cells;
        s.non_canonical_cells += r.non_canonical_cells;
        let room = MAX_LISTED.saturating_sub(s.non_canonical_list.len());
        s.non_canonical_list.extend(r.non_canonical_list.iter().take(room));
        kept += r.filter_kept;
        removed += r.filter_removed;
        s.inconsistent_lines += r.repair.inconsistent_lines;
        s.synthesized_vertices += r.repair.synthesized_vertices;
        s.merged_edges += r.repair.merged_edges;
        s.dropped_intercepts += r.repair.dropped_intercepts;
    }
    (s.output_boundary_edges, s.output_boundary_loops) = crate::stages::boundary_of(&loose);
    if let Ok(w) = crate::workdir::read_result::<crate::stages::WriteResult>(&ctx.dir, Stage::Write, 0) {
        s.output_precision = w.precision;
        // --open-border: the write stage left the cap out; its counts stand.
        if let (Some(o), Some(v)) = (w.open_border, s.volume.as_mut()) {
            v.border_faces_removed = o.faces_removed;
            v.border_vertices_split = o.vertices_split;
            s.output_vertices = w.vertices;
            s.output_faces = w.faces;
            (s.output_boundary_edges, s.output_boundary_loops) = (o.boundary_edges, o.boundary_loops);
        }
    }
    if plan.strict() || rules.first() == Some(&SignRule::Orient) {
        s.intercepts_kept = kept;
        s.intercepts_removed = removed;
    } else {
        // Counted, not subtracted: each output vertex not synthesized is a
        // kept crossing (drops are counted per visit, and a plane shared by
        // two sub-slabs is visited twice, so found - dropped could wrap).
        s.intercepts_kept = s.output_vertices.saturating_sub(s.synthesized_vertices).min(s.intercepts_found);
        s.intercepts_removed = s.intercepts_found - s.intercepts_kept;
    }
    Ok(s)
}

/// The summary of a finished staged run in `dir` (for `mint stage run`'s
/// last task and `mint slurm --wait`), with wall times per stage measured
/// from the plan's writing to each stage's last task.
pub fn summarize_dir(dir: &Path, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let plan = Plan::load(dir)?;
    let scene = plan.spec.job.scene()?;
    let tuning = Tuning { threads: 1, ..plan.tuning.clone() };
    let stages = plan.stages.clone();
    plan.check_scene(&scene, &dir.join(crate::workdir::PLAN_FILE))?;
    let ctx = Ctx::new(dir, plan, scene, &tuning, progress);
    let mut s = summarize(&ctx)?;
    // Wall times of a run whose tasks ran elsewhere: from the plan's
    // writing to each stage's last finished task (directory times).
    let mtime = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if let Some(start) = mtime(&dir.join(PLAN_FILE)) {
        let mut prev = start;
        let mut secs = std::collections::HashMap::new();
        for st in &stages {
            let end = (0..st.tasks).filter_map(|t| mtime(&task_dir(dir, st.name, t))).max().unwrap_or(prev).max(prev);
            secs.insert(st.name, end.duration_since(prev).map_or(0.0, |d| d.as_secs_f64()));
            prev = end;
        }
        set_stage_seconds(&mut s, &secs);
        s.seconds_total = prev.duration_since(start).map_or(0.0, |d| d.as_secs_f64());
    }
    s.work_dir = Some(dir.display().to_string());
    s.distributed = true;
    Ok(s)
}

/// One stage's progress in a work directory.
#[derive(Debug, Clone, Serialize)]
pub struct StageStatus {
    pub name: Stage,
    pub tasks: u32,
    pub done: u32,
    /// Task directories being written by a live process (or by one whose
    /// liveness cannot be told).
    pub running: u32,
    /// Task directories abandoned by a process that died (no live process
    /// holds their lock); the next run of the task removes them.
    pub stale: u32,
    pub left: u32,
    /// Bytes on disk of the stage's results.
    pub bytes: u64,
}

/// A work directory's progress.
#[derive(Debug, Clone, Serialize)]
pub struct RunStatus {
    pub dir: String,
    pub job: String,
    pub output: String,
    pub parts: u32,
    pub slabs: u32,
    pub stages: Vec<StageStatus>,
    /// Every task of every stage is done (the output is written).
    pub complete: bool,
    pub bytes: u64,
}

/// What is done, running and left in the work directory `dir`.
pub fn status(dir: &Path) -> Result<RunStatus, PipelineError> {
    let plan = Plan::load(dir)?;
    let mut stages = Vec::new();
    for st in &plan.stages {
        let done = (0..st.tasks).filter(|&t| is_done(dir, st.name, t)).count() as u32;
        let temps = temp_tasks(dir, st.name);
        let stale = temps.iter().filter(|(_, o)| *o == Owner::Dead).count() as u32;
        let running = temps.len() as u32 - stale;
        stages.push(StageStatus {
            name: st.name,
            tasks: st.tasks,
            done,
            running,
            stale,
            left: st.tasks - done,
            bytes: disk_bytes(&dir.join(st.name.dir_name())),
        });
    }
    Ok(RunStatus {
        dir: dir.display().to_string(),
        job: plan.spec.job.name(),
        output: plan.spec.output.display().to_string(),
        parts: plan.parts,
        slabs: plan.slabs,
        complete: stages.iter().all(|s| s.left == 0),
        bytes: stages.iter().map(|s| s.bytes).sum(),
        stages,
    })
}
