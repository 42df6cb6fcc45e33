//! `mint stage plan|run|status`: the staged engine driven one task per
//! process, by hand or by a script. The job and its options are parsed by
//! the same argument groups as `resample`, `bool` and `csg` (`JobCommand`
//! in `jobs`), so a staged run accepts every option of a one-process run.
//! Calls `mint_pipeline::plan_run`, `run_task`, `status` and
//! `summarize_dir`.

use crate::jobs::{choice, JobCommand, JsonArg, QuietArg};
use crate::progress::Bars;
use crate::summary::print_resample_summary;
use crate::units::{human_bytes, parse_bytes};
use anyhow::Result;
use clap::{Args, Subcommand};
use mint_pipeline::{Deref, Stage};
use std::path::PathBuf;

#[derive(Subcommand, Debug)]
pub enum StageCommand {
    /// Write DIR/plan.json for a resample, bool or csg run (needs --work DIR) and print it.
    #[command(subcommand)]
    Plan(JobCommand),
    /// Run one task of one stage (a no-op if it is already done).
    Run(RunArgs),
    /// Show, per stage, the tasks done, running, stale (left by a dead process) and left, and the bytes on disk.
    Status(StatusArgs),
}

#[derive(Args, Debug)]
pub struct RunArgs {
    /// The work directory (holding plan.json).
    pub dir: PathBuf,
    /// The stage (`mint stage status DIR` lists this plan's).
    #[arg(value_parser = choice::<Stage>())]
    pub stage: Stage,
    /// The task number, from 0.
    pub task: u32,
    /// Worker threads, 0 for all cores [default: the plan's]. The output is the same for any value.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Heap budget of this task [default: the plan's].
    #[arg(long, value_parser = parse_bytes)]
    pub mem: Option<u64>,
    /// How a discretize task dereferences faces (see `mint resample --help`) [default: the plan's].
    #[arg(long, value_parser = choice::<Deref>())]
    pub deref: Option<Deref>,
    #[command(flatten)]
    pub quiet: QuietArg,
}

#[derive(Args, Debug)]
pub struct StatusArgs {
    /// The work directory.
    pub dir: PathBuf,
    #[command(flatten)]
    pub json: JsonArg,
}

pub fn cmd_stage(c: StageCommand) -> Result<()> {
    match c {
        StageCommand::Plan(job) => {
            let (plan, dir) = job.plan()?;
            print!("{}", plan.to_json());
            if !job.report().quiet() {
                let tasks: Vec<String> = plan.stages.iter().map(|s| format!("{} {}", s.name, s.tasks)).collect();
                eprintln!("planned {} in {} ({} tasks: {})", plan.spec.job.name(), dir.display(), plan.stages.iter().map(|s| s.tasks).sum::<u32>(), tasks.join(", "));
            }
            Ok(())
        }
        StageCommand::Run(a) => {
            let bars = Bars::new(a.quiet.quiet);
            let t = std::time::Instant::now();
            let topts = mint_pipeline::TaskOptions { threads: a.threads, mem_bytes: a.mem, deref: a.deref };
            let outcome = mint_pipeline::run_task(&a.dir, a.stage, a.task, &topts, &bars)?;
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
            if a.stage == Stage::Write && !a.quiet.quiet {
                let s = mint_pipeline::summarize_dir(&a.dir, &bars)?;
                let plan = mint_pipeline::Plan::load(&a.dir)?;
                print_resample_summary(&s, false, false, a.mem.unwrap_or(plan.tuning.mem_bytes))?;
            }
            Ok(())
        }
        StageCommand::Status(a) => {
            let st = mint_pipeline::status(&a.dir)?;
            if a.json.json {
                crate::out::json(&st)?;
            } else {
                print_status(&st);
            }
            Ok(())
        }
    }
}

fn print_status(st: &mint_pipeline::RunStatus) {
    println!("{} -> {}  ({} parts, {} slabs, {} on disk)", st.job, st.output, st.parts, st.slabs, human_bytes(st.bytes));
    println!("  {:<12} {:>6} {:>6} {:>8} {:>6} {:>6} {:>10}", "stage", "tasks", "done", "running", "stale", "left", "bytes");
    for s in &st.stages {
        println!("  {:<12} {:>6} {:>6} {:>8} {:>6} {:>6} {:>10}", s.name, s.tasks, s.done, s.running, s.stale, s.left, human_bytes(s.bytes));
    }
    let stale: u32 = st.stages.iter().map(|s| s.stale).sum();
    if stale > 0 {
        println!("  stale: {stale} task{} left half-written by a process that died (no live process holds {}); running {} again redoes and removes {}",
            if stale > 1 { "s" } else { "" }, if stale > 1 { "them" } else { "it" }, if stale > 1 { "them" } else { "it" }, if stale > 1 { "them" } else { "it" });
    }
    println!("  {}", if st.complete { "complete: the output is written" } else { "not complete" });
}
