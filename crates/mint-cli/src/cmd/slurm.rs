//! `mint slurm`: a resample, bool or csg run on a Slurm cluster: the plan
//! (as `mint stage plan`), one sbatch script per stage, submitted as job
//! arrays that depend on each other, and on request followed to the end.
//! Calls `mint_pipeline::slurm::{write_scripts, submit, wait}`.

use crate::jobs::JobCommand;
use crate::progress::Bars;
use crate::summary::print_resample_summary;
use anyhow::{Context, Result};
use clap::Args;
use mint_pipeline::slurm::{self, SlurmOptions};

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

pub fn cmd_slurm(a: SlurmArgs) -> Result<()> {
    let (plan, dir) = a.job.plan()?;
    let (json, quiet) = (a.job.report().json(), a.job.report().quiet());
    // Jobs run wherever Slurm starts them: name the work directory absolutely.
    let dir = mint_pipeline::spec::absolute(&dir);
    let mint = std::env::current_exe().context("finding the mint executable")?;
    // Every task reads its memory budget and dereferencing from the plan.
    let mut task_args = Vec::new();
    if let Some(n) = a.task_threads {
        task_args.extend(["--threads".to_string(), n.to_string()]);
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
        crate::out::json(&jobs)?;
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
