//! `mint stage plan|run|status` and `mint slurm`: the staged engine driven
//! one task per process, by hand, by a script or by Slurm. The job and its
//! options are parsed by the same argument groups as `resample`, `bool` and
//! `csg`, so a staged run accepts every option of a one-process run.

use crate::jobs::{default_mem, DerefArg, grid_options, print_resample_summary, resample_input, resample_options, scene_inputs, BoolArgs, BoolOpArg, CsgArgs, ResampleArgs};
use crate::progress::Bars;
use crate::units::{human_bytes, parse_bytes};
use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use mint_pipeline::slurm::{self, SlurmOptions};
use mint_pipeline::{Job, Plan, ResampleOptions};
use std::path::{Path, PathBuf};

#[derive(Subcommand, Debug)]
pub enum StageCommand {
    /// Write DIR/plan.json for a resample, bool or csg run (needs --work DIR) and print it.
    #[command(subcommand)]
    Plan(JobCommand),
    /// Run one task of one stage (a no-op if it is already done).
    Run(RunArgs),
    /// Show, per stage, the tasks done, running and left, and the bytes on disk.
    Status(StatusArgs),
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

#[derive(Args, Debug)]
pub struct RunArgs {
    /// The work directory (holding plan.json).
    pub dir: PathBuf,
    /// The stage: bounds, discretize, census, holes, reconstruct or write
    /// (`mint stage status DIR` lists this plan's).
    pub stage: String,
    /// The task number, from 0.
    pub task: u32,
    /// Worker threads [default: all cores]. The output is the same for any value.
    #[arg(long, default_value_t = 0, hide_default_value = true)]
    pub threads: usize,
    /// Heap budget of this task [default: the plan's].
    #[arg(long, value_parser = parse_bytes)]
    pub mem: Option<u64>,
    /// How a discretize task dereferences faces (see `mint resample --help`).
    #[arg(long, value_enum, default_value_t = DerefArg::Auto)]
    pub deref: DerefArg,
    /// No progress bars; one line when the task is done.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Args, Debug)]
pub struct StatusArgs {
    /// The work directory.
    pub dir: PathBuf,
    /// Print as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct SlurmArgs {
    #[command(subcommand)]
    pub job: JobCommand,
    /// Extra sbatch options for every job array, e.g. "--partition=batch --time=2:00:00".
    #[arg(long, global = true, value_name = "ARGS", allow_hyphen_values = true)]
    pub sbatch: Option<String>,
    /// Write the sbatch scripts into DIR/slurm and submit nothing.
    #[arg(long, global = true)]
    pub dry_run: bool,
    /// Follow the run until it ends; exit 0 only if the output was written.
    #[arg(long, global = true)]
    pub wait: bool,
    /// Threads of each task [default: all the cores Slurm gives it].
    #[arg(long, global = true, value_name = "N")]
    pub task_threads: Option<usize>,
}

/// The job, its options and its output, from a job command's arguments.
/// Range images are triangulated into the work directory first.
fn job_of(c: &JobCommand) -> Result<(Job, ResampleOptions, PathBuf, bool, bool)> {
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

fn abs(p: &Path) -> PathBuf {
    mint_pipeline::plan::absolute(p)
}

fn plan_of(c: &JobCommand) -> Result<(Plan, PathBuf, bool, bool)> {
    let (job, opts, output, json, quiet) = job_of(c)?;
    let Some(dir) = opts.work_dir.clone() else { bail!("a staged run needs --work DIR (a directory every task can reach)") };
    let plan = mint_pipeline::plan_run(job, None, &output, &opts, &dir)?;
    Ok((plan, dir, json, quiet))
}

pub fn cmd_stage(c: StageCommand) -> Result<()> {
    match c {
        StageCommand::Plan(job) => {
            let (plan, dir, _, quiet) = plan_of(&job)?;
            println!("{}", serde_json::to_string_pretty(&plan)?);
            if !quiet {
                let tasks: Vec<String> = plan.stages.iter().map(|s| format!("{} {}", s.name, s.tasks)).collect();
                eprintln!("planned {} in {} ({} tasks: {})", plan.job.name(), dir.display(), plan.stages.iter().map(|s| s.tasks).sum::<u32>(), tasks.join(", "));
            }
            Ok(())
        }
        StageCommand::Run(a) => {
            let bars = Bars::new(a.quiet);
            let t = std::time::Instant::now();
            let topts = mint_pipeline::TaskOptions { threads: a.threads, mem_bytes: a.mem, deref: a.deref.to_deref() };
            let outcome = mint_pipeline::run_task(&a.dir, &a.stage, a.task, &topts, &bars)?;
            match outcome {
                mint_pipeline::TaskOutcome::AlreadyDone => eprintln!("{} {}: already done", a.stage, a.task),
                mint_pipeline::TaskOutcome::Ran => eprintln!(
                    "{} {}: done in {:.2}s, peak heap {}",
                    a.stage,
                    a.task,
                    t.elapsed().as_secs_f64(),
                    human_bytes(crate::alloc::peak_heap())
                ),
            }
            if a.stage == "write" && !a.quiet {
                let s = mint_pipeline::summarize_dir(&a.dir, &bars)?;
                print_resample_summary(&s, false, false, default_mem())?;
            }
            Ok(())
        }
        StageCommand::Status(a) => {
            let st = mint_pipeline::status(&a.dir)?;
            if a.json {
                println!("{}", serde_json::to_string_pretty(&st)?);
            } else {
                print_status(&st);
            }
            Ok(())
        }
    }
}

fn print_status(st: &mint_pipeline::RunStatus) {
    println!("{} -> {}  ({} parts, {} slabs, {} on disk)", st.job, st.output, st.parts, st.slabs, human_bytes(st.bytes));
    println!("  {:<12} {:>6} {:>6} {:>8} {:>6} {:>10}", "stage", "tasks", "done", "running", "left", "bytes");
    for s in &st.stages {
        println!("  {:<12} {:>6} {:>6} {:>8} {:>6} {:>10}", s.name, s.tasks, s.done, s.running, s.left, human_bytes(s.bytes));
    }
    println!("  {}", if st.complete { "complete: the output is written" } else { "not complete" });
}

pub fn cmd_slurm(a: SlurmArgs) -> Result<()> {
    let (plan, dir, json, quiet) = plan_of(&a.job)?;
    // Jobs run wherever Slurm starts them: name the work directory absolutely.
    let dir = abs(&dir);
    let mint = std::env::current_exe().context("finding the mint executable")?;
    let mut task_args = Vec::new();
    if let Some(n) = a.task_threads {
        task_args.extend(["--threads".to_string(), n.to_string()]);
    }
    task_args.extend(["--mem".to_string(), plan.tuning.mem_bytes.to_string()]);
    let deref = match job_of(&a.job)?.1.deref {
        mint_pipeline::Deref::Auto => DerefArg::Auto,
        mint_pipeline::Deref::Mmap => DerefArg::Mmap,
        mint_pipeline::Deref::Sort => DerefArg::Sort,
    };
    if deref != DerefArg::Auto {
        task_args.extend(["--deref".to_string(), deref.name().to_string()]);
    }
    let sbatch_args = match &a.sbatch {
        Some(s) => slurm::split_args(s).map_err(|e| anyhow::anyhow!("--sbatch: {e}"))?,
        None => Vec::new(),
    };
    let o = SlurmOptions { mint, sbatch_args, task_args };
    let mut jobs = slurm::write_scripts(&dir, &plan, &o)?;
    if a.dry_run {
        for j in &jobs {
            println!("{}", j.script.display());
        }
        if !quiet {
            eprintln!("wrote {} sbatch scripts into {}/slurm (nothing submitted)", jobs.len(), dir.display());
        }
        return Ok(());
    }
    slurm::submit(&mut jobs, &o)?;
    if json && !a.wait {
        println!("{}", serde_json::to_string_pretty(&jobs)?);
    } else {
        for j in &jobs {
            println!("{} {} ({} tasks)", j.job_id.as_deref().unwrap_or("?"), j.stage, j.tasks);
        }
    }
    if !a.wait {
        if !quiet {
            eprintln!("submitted; follow with `mint stage status {}`", dir.display());
        }
        return Ok(());
    }
    let t = std::time::Instant::now();
    let mut last = String::new();
    slurm::wait(&dir, &jobs, std::time::Duration::from_millis(500), &mut |st| {
        if quiet || json {
            return;
        }
        let line: Vec<String> = st.stages.iter().map(|s| format!("{} {}/{}", s.name, s.done, s.tasks)).collect();
        let line = line.join(", ");
        if line != last {
            eprintln!("[{:>6.1}s] {line}", t.elapsed().as_secs_f64());
            last = line;
        }
    })?;
    let bars = Bars::new(true);
    let s = mint_pipeline::summarize_dir(&dir, &bars)?;
    print_resample_summary(&s, json, quiet, plan.tuning.mem_bytes)?;
    Ok(())
}
