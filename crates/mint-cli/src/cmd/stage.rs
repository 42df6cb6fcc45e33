//! `mint stage plan|run|status`: the staged engine driven one task per
//! process, by hand or by a script. The job and its options are parsed by
//! the same argument groups as `resample`, `bool` and `csg` (`JobCommand`
//! in `jobs`), so a staged run accepts every option of a one-process run.
//! Calls `mint_pipeline::plan_run`, `run_task`, `status` and
//! `summarize_dir`.

use crate::jobs::{default_mem, plan_of, DerefArg, JobCommand};
use crate::progress::Bars;
use crate::summary::print_resample_summary;
use crate::units::{human_bytes, parse_bytes};
use anyhow::Result;
use clap::{Args, Subcommand};
use std::path::PathBuf;

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
