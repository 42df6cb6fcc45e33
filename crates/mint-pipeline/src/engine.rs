//! The staged engine's drivers: one engine for `resample`, `bool` and
//! `csg`, run either whole in one process ([`resample`], [`boolean`],
//! [`csg`]: every stage's tasks in order, in a work directory that is
//! temporary or kept with `work_dir` for resuming), or one task at a time
//! by separate processes on any machines sharing the work directory
//! ([`plan_run`], then [`run_task`] per task, [`status`] to watch; see the
//! `slurm` module for a scheduler).
//!
//! Both paths run the same task code (`stages`), so their output bytes are
//! the same. A resumed run (same work directory) checks that the inputs'
//! fingerprints and the options match the plan, keeps every finished task
//! and runs the rest.

use crate::error::PipelineError;
use crate::options::{ResampleOptions, ResampleSummary};
use crate::passes::check_cancel;
use crate::plan::{bool_op_name, Fingerprint, Job, OperandPlan, Plan};
use crate::progress::Progress;
use crate::scene::{Operand, Scene};
use crate::stages::{run_stage_task, Ctx, DiscretizeResult};
use crate::workdir::{checked_json, disk_bytes, is_done, task_dir, temp_tasks, write_atomic, TaskBuild, PLAN_FILE};
use mint_core::expr::BoolOp;
use mint_core::signs::SignRule;
use mint_io::Format;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Resamples `input` into `output` on the grid `opts.size`.
pub fn resample(input: &Path, output: &Path, opts: &ResampleOptions, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    run_job(Job::Resample { input: input.to_path_buf() }, None, output, opts, progress)
}

/// `A op B` for two mesh files (`mint bool`).
pub fn boolean(op: BoolOp, a: &Path, b: &Path, output: &Path, opts: &ResampleOptions, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let job = Job::Bool { op: bool_op_name(op).into(), a: a.to_path_buf(), b: b.to_path_buf() };
    run_job(job, None, output, &ResampleOptions { max_hole: None, ..opts.clone() }, progress)
}

/// Evaluates `scene` (read from the file `scene_name`, when it is one) on
/// the grid `opts.size` into `output`.
pub fn csg(scene: &Scene, scene_name: &str, output: &Path, opts: &ResampleOptions, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let job = Job::Csg { scene: PathBuf::from(scene_name) };
    run_job(job, Some(scene.clone()), output, &ResampleOptions { max_hole: None, ..opts.clone() }, progress)
}

fn threads_of(n: usize) -> usize {
    if n == 0 {
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    } else {
        n
    }
}

/// Checks the options that can be checked before any work.
fn check_output(output: &Path) -> Result<(), PipelineError> {
    Format::from_path(output)?;
    Ok(())
}

/// Writes the plan of `job` into `dir` (created if needed). A directory
/// that already holds the same run's plan is kept as it is (its finished
/// tasks stay); one that holds another run's is refused.
pub fn plan_run(job: Job, scene: Option<Scene>, output: &Path, opts: &ResampleOptions, dir: &Path) -> Result<Plan, PipelineError> {
    check_output(output)?;
    let scene = match scene {
        Some(s) => s,
        None => job.scene()?,
    };
    let plan = Plan::new(job, &scene, output, opts)?;
    std::fs::create_dir_all(dir).map_err(|source| PipelineError::Temp { path: dir.to_path_buf(), op: "creating the work directory", source })?;
    if dir.join(PLAN_FILE).exists() {
        let stored = Plan::load(dir)?;
        plan.check_same_run(&stored, dir)?;
        return Ok(stored);
    }
    write_atomic(&dir.join(PLAN_FILE), &checked_json(&plan))?;
    Ok(plan)
}

/// What [`run_task`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TaskOutcome {
    Ran,
    AlreadyDone,
}

/// Options of one task's process.
#[derive(Debug, Clone, Default)]
pub struct TaskOptions {
    /// Worker threads; 0: all cores.
    pub threads: usize,
    /// Heap budget; `None`: the plan's.
    pub mem_bytes: Option<u64>,
    /// How discretize tasks dereference faces.
    pub deref: crate::deref::Deref,
}

/// Runs task `task` of `stage` of the plan in `dir`, in this process. A
/// finished task is a no-op. Fails with one line when the plan is of
/// another version, an input changed, or a stage before is incomplete.
pub fn run_task(dir: &Path, stage: &str, task: u32, topts: &TaskOptions, progress: &dyn Progress) -> Result<TaskOutcome, PipelineError> {
    let plan = Plan::load(dir)?;
    let Some(pos) = plan.stages.iter().position(|s| s.name == stage) else {
        let names: Vec<&str> = plan.stages.iter().map(|s| s.name.as_str()).collect();
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
        let missing: Vec<u32> = (0..before.tasks).filter(|&t| !is_done(dir, &before.name, t)).collect();
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
    let scene = plan.job.scene()?;
    let mem = topts.mem_bytes.unwrap_or(plan.tuning.mem_bytes);
    let mut ctx = Ctx::new(dir, plan, scene, threads_of(topts.threads), mem, progress);
    ctx.deref = topts.deref;
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

fn run_one(ctx: &Ctx, stage: &str, task: u32) -> Result<(), PipelineError> {
    let build = TaskBuild::begin(&ctx.dir, stage, task)?;
    let result = run_stage_task(ctx, stage, task, &build)?;
    check_cancel(ctx.progress)?;
    build.commit(&result)
}

/// Runs a whole job in this process; see the module docs.
fn run_job(job: Job, scene: Option<Scene>, output: &Path, opts: &ResampleOptions, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let t_start = Instant::now();
    check_output(output)?;
    let threads = threads_of(opts.threads);
    let tmp_root = match &opts.tmp_dir {
        Some(d) => d.clone(),
        None => output.parent().filter(|p| !p.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
    };
    let _temp;
    let dir = match &opts.work_dir {
        Some(d) => d.clone(),
        None => {
            let t = tempfile::Builder::new().prefix(".mint-work-").tempdir_in(&tmp_root).map_err(|source| PipelineError::Temp {
                path: tmp_root.clone(),
                op: "creating the work directory",
                source,
            })?;
            let p = t.path().to_path_buf();
            _temp = t;
            p
        }
    };
    let scene = match scene {
        Some(s) => s,
        None => job.scene()?,
    };
    let plan = plan_run(job, Some(scene.clone()), output, opts, &dir)?;
    // Task directories abandoned by a process that died.
    for stage in &plan.stages {
        for t in temp_tasks(&dir, &stage.name) {
            let _ = std::fs::remove_dir_all(t);
        }
    }
    // The output was removed after a finished run: write it again.
    if is_done(&dir, "write", 0) && !plan.output.exists() {
        let _ = std::fs::remove_dir_all(task_dir(&dir, "write", 0));
    }
    let stages = plan.stages.clone();
    let mut ctx = Ctx::new(&dir, plan, scene, threads, opts.mem_bytes, progress);
    ctx.deref = opts.deref;
    let (mut ran, mut resumed) = (0u64, 0u64);
    let mut seconds = std::collections::HashMap::new();
    for stage in &stages {
        let t = Instant::now();
        for task in 0..stage.tasks {
            if is_done(&dir, &stage.name, task) {
                resumed += 1;
                continue;
            }
            run_one(&ctx, &stage.name, task)?;
            ran += 1;
        }
        check_cancel(progress)?;
        seconds.insert(stage.name.clone(), t.elapsed().as_secs_f64());
    }
    let mut s = summarize(&ctx)?;
    let sec = |n: &str| seconds.get(n).copied().unwrap_or(0.0);
    s.output = output.display().to_string();
    s.seconds_bounds = sec("bounds");
    s.seconds_discretize = sec("discretize");
    s.seconds_census = sec("census");
    s.seconds_reconstruct = sec("reconstruct") + sec("reopen");
    s.seconds_write = sec("write");
    s.seconds_total = t_start.elapsed().as_secs_f64();
    s.work_dir = opts.work_dir.as_ref().map(|d| d.display().to_string());
    s.tasks_run = ran;
    s.tasks_resumed = resumed;
    Ok(s)
}

/// The summary of a finished run, from its tasks' results.
pub fn summarize(ctx: &Ctx) -> Result<ResampleSummary, PipelineError> {
    let plan = &ctx.plan;
    let grid = ctx.grid()?;
    let mut s = ResampleSummary {
        input: plan.job.name(),
        output: plan.output.display().to_string(),
        threads: ctx.threads,
        grid_cells: grid.dims,
        cell_size: grid.cell,
        grid_origin: grid.origin,
        slab_axis: ['x', 'y', 'z'][grid.slab_axis],
        ..Default::default()
    };
    let parts: &[DiscretizeResult] = ctx.parts()?;
    let mut mesh_ops = Vec::new();
    for (j, op) in plan.operands.iter().enumerate() {
        if let OperandPlan::Mesh { vertices, .. } = op {
            s.input_vertices += vertices;
            s.input_faces += ctx.faces_and_volume(j)?.0;
            mesh_ops.push(j);
        }
    }
    let mut derefs: Vec<String> = Vec::new();
    for m in parts.iter().flat_map(|p| p.operands.iter().flatten()) {
        s.intercepts_found += m.shards.records();
        s.shard_bytes += m.shards.bytes();
        if let Some(d) = &m.deref {
            let line = format!("{}: {}", if d.sort { "sort" } else { "mmap" }, d.reason);
            if !derefs.contains(&line) {
                derefs.push(line);
            }
        }
        s.deref_spilled_bytes += m.sort.map_or(0, |st| st.bytes_spilled);
    }
    s.deref = derefs.join("; ");
    let (rules, census) = ctx.rules()?;
    if let Job::Resample { .. } = plan.job {
        let vol = ctx.faces_and_volume(0)?.1;
        s.input_signed_volume = vol * grid.cell.powi(3);
        s.orientation_inverted = vol < 0.0;
        s.sign_rule = format!("{:?}", rules[0]).to_lowercase();
        (s.census_lines, s.census_winding_valid, s.census_odd) = (census[0].lines, census[0].winding_valid, census[0].odd);
    } else {
        let names: Vec<String> = ctx
            .scene
            .operands
            .iter()
            .zip(rules)
            .map(|(op, r)| match op {
                Operand::Primitive(_) => "exact".to_string(),
                Operand::Mesh { .. } => format!("{r:?}").to_lowercase(),
            })
            .collect();
        s.sign_rule = names.join(",");
    }
    let (open, holes) = ctx.open_cells()?;
    s.holes_closed = holes.closed;
    s.holes_left_open = holes.left_open;
    s.open_cells = open.as_ref().map_or(0, |o| o.len() as u64);
    let (mut kept, mut removed) = (0, 0);
    let mut loose: Vec<(u32, u32)> = Vec::new();
    for t in 0..plan.tasks("reconstruct") {
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
        let room = plan.options.max_listed.saturating_sub(s.non_canonical_list.len());
        s.non_canonical_list.extend(r.non_canonical_list.iter().take(room));
        kept += r.filter_kept;
        removed += r.filter_removed;
        s.inconsistent_lines += r.repair.inconsistent_lines;
        s.synthesized_vertices += r.repair.synthesized_vertices;
        s.merged_edges += r.repair.merged_edges;
        s.dropped_intercepts += r.repair.dropped_intercepts;
    }
    (s.output_boundary_edges, s.output_boundary_loops) = crate::stages::boundary_of(&loose);
    if plan.strict() || rules.first() == Some(&SignRule::Orient) {
        s.intercepts_kept = kept;
        s.intercepts_removed = removed;
    } else {
        s.intercepts_kept = s.intercepts_found - s.dropped_intercepts;
        s.intercepts_removed = s.dropped_intercepts;
    }
    Ok(s)
}

/// The summary of a finished staged run in `dir` (for `mint stage run`'s
/// last task and `mint slurm --wait`), with wall times per stage measured
/// from the plan's writing to each stage's last task.
pub fn summarize_dir(dir: &Path, progress: &dyn Progress) -> Result<ResampleSummary, PipelineError> {
    let plan = Plan::load(dir)?;
    let scene = plan.job.scene()?;
    let mem = plan.tuning.mem_bytes;
    let stages = plan.stages.clone();
    let ctx = Ctx::new(dir, plan, scene, 1, mem, progress);
    let mut s = summarize(&ctx)?;
    // Wall times of a run whose tasks ran elsewhere: from the plan's
    // writing to each stage's last finished task (directory times).
    let mtime = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if let Some(start) = mtime(&dir.join(PLAN_FILE)) {
        let mut prev = start;
        let mut secs = std::collections::HashMap::new();
        for st in &stages {
            let end = (0..st.tasks).filter_map(|t| mtime(&task_dir(dir, &st.name, t))).max().unwrap_or(prev).max(prev);
            secs.insert(st.name.clone(), end.duration_since(prev).map_or(0.0, |d| d.as_secs_f64()));
            prev = end;
        }
        let sec = |n: &str| secs.get(n).copied().unwrap_or(0.0);
        s.seconds_bounds = sec("bounds");
        s.seconds_discretize = sec("discretize");
        s.seconds_census = sec("census");
        s.seconds_reconstruct = sec("reconstruct") + sec("reopen");
        s.seconds_write = sec("write");
        s.seconds_total = prev.duration_since(start).map_or(0.0, |d| d.as_secs_f64());
    }
    s.work_dir = Some(dir.display().to_string());
    s.distributed = true;
    Ok(s)
}

/// One stage's progress in a work directory.
#[derive(Debug, Clone, Serialize)]
pub struct StageStatus {
    pub name: String,
    pub tasks: u32,
    pub done: u32,
    /// Task directories being written (or abandoned by a process that died).
    pub running: u32,
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
        let done = (0..st.tasks).filter(|&t| is_done(dir, &st.name, t)).count() as u32;
        let running = temp_tasks(dir, &st.name).len() as u32;
        stages.push(StageStatus {
            name: st.name.clone(),
            tasks: st.tasks,
            done,
            running,
            left: st.tasks - done,
            bytes: disk_bytes(&dir.join(&st.name)),
        });
    }
    Ok(RunStatus {
        dir: dir.display().to_string(),
        job: plan.job.name(),
        output: plan.output.display().to_string(),
        parts: plan.parts,
        slabs: plan.slabs,
        complete: stages.iter().all(|s| s.left == 0),
        bytes: stages.iter().map(|s| s.bytes).sum(),
        stages,
    })
}
