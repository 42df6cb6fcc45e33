//! Submitting a staged run to a Slurm cluster, by shelling out to Slurm's
//! own commands (the Rust Slurm crates are unmaintained): one sbatch script
//! per stage in `DIR/slurm/`, each a job array of the stage's tasks running
//! `mint stage run DIR STAGE $SLURM_ARRAY_TASK_ID`, submitted with
//! `sbatch --parsable`, each depending on the one before with `afterok` and
//! `--kill-on-invalid-dep=yes` (a failed task cancels the rest). Progress is
//! read from the work directory itself, so [`wait`] needs only `squeue` to
//! know when nothing of the run is left in the queue.

use crate::error::PipelineError;
use crate::engine::status;
use crate::plan::Plan;
use crate::workdir::write_atomic;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// How to submit.
#[derive(Debug, Clone, Default)]
pub struct SlurmOptions {
    /// The mint executable the tasks run (an absolute path every node sees).
    pub mint: PathBuf,
    /// Extra sbatch options (partition, account, time…), one per element.
    pub sbatch_args: Vec<String>,
    /// Extra options of `mint stage run` (e.g. `--threads 4`); the
    /// plan's tuning gives every task its memory and dereferencing.
    pub task_args: Vec<String>,
}

/// One stage's job array.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StageJob {
    pub stage: crate::plan::Stage,
    pub tasks: u32,
    pub script: PathBuf,
    /// The job id sbatch printed (`None` until submitted).
    pub job_id: Option<String>,
}

/// Splits a shell-like option string as a POSIX shell would (quotes and
/// backslashes; no expansions).
pub fn split_args(s: &str) -> Result<Vec<String>, String> {
    shell_words::split(s).map_err(|e| format!("{e} in \"{s}\""))
}

fn quote(s: &str) -> String {
    shell_words::quote(s).into_owned()
}

/// Writes `DIR/slurm/NN-STAGE.sbatch` for every stage of the plan.
pub fn write_scripts(dir: &Path, plan: &Plan, o: &SlurmOptions) -> Result<Vec<StageJob>, PipelineError> {
    let sdir = dir.join("slurm");
    std::fs::create_dir_all(&sdir).map_err(|source| PipelineError::Temp { path: sdir.clone(), op: "creating the script directory", source })?;
    let mut jobs = Vec::new();
    for (i, st) in plan.stages.iter().enumerate() {
        let script = sdir.join(format!("{i:02}-{}.sbatch", st.name));
        let log = sdir.join(format!("{}-%a.log", st.name));
        let dep = if i == 0 { String::new() } else { format!(" --dependency=afterok:<job id of {}> --kill-on-invalid-dep=yes", plan.stages[i - 1].name) };
        let extra: Vec<String> = o.task_args.iter().map(|a| quote(a)).collect();
        let sbatch_extra: String = o.sbatch_args.iter().map(|a| format!(" {}", quote(a))).collect();
        let text = format!(
            "#!/bin/bash\n\
             # mint staged run, stage {i} '{name}': {n} task(s) of {plan}.\n\
             # Written by `mint slurm`. To submit by hand, in stage order:\n\
             #   sbatch --parsable{dep}{sbatch_extra} {script}\n\
             #SBATCH --job-name=mint-{name}\n\
             #SBATCH --array=0-{last}\n\
             #SBATCH --output={log}\n\
             #SBATCH --open-mode=append\n\
             set -eu\n\
             exec {mint} stage run {dirq} {name} \"$SLURM_ARRAY_TASK_ID\" --quiet{sep}{extra}\n",
            name = st.name.dir_name(),
            n = st.tasks,
            plan = dir.join(crate::workdir::PLAN_FILE).display(),
            script = script.display(),
            last = st.tasks.saturating_sub(1),
            log = log.display(),
            mint = quote(&o.mint.display().to_string()),
            dirq = quote(&dir.display().to_string()),
            sep = if extra.is_empty() { "" } else { " " },
            extra = extra.join(" "),
        );
        write_atomic(&script, text.as_bytes())?;
        jobs.push(StageJob { stage: st.name, tasks: st.tasks, script, job_id: None });
    }
    Ok(jobs)
}

fn slurm_command(name: &str) -> Command {
    Command::new(name)
}

/// Submits the scripts in order, each depending on the one before.
pub fn submit(jobs: &mut [StageJob], o: &SlurmOptions) -> Result<(), PipelineError> {
    let mut prev: Option<String> = None;
    for job in jobs.iter_mut() {
        let mut cmd = slurm_command("sbatch");
        cmd.arg("--parsable");
        if let Some(p) = &prev {
            cmd.arg(format!("--dependency=afterok:{p}")).arg("--kill-on-invalid-dep=yes");
        }
        cmd.args(&o.sbatch_args).arg(&job.script);
        let out = cmd.output().map_err(|e| {
            PipelineError::stage(
                &job.script,
                format!("cannot run sbatch ({e}): is this a Slurm submit host? The scripts are written; submit them by hand, or use --dry-run"),
            )
        })?;
        if !out.status.success() {
            let msg = String::from_utf8_lossy(&out.stderr).lines().find(|l| !l.trim().is_empty()).unwrap_or("no message").trim().to_string();
            return Err(PipelineError::stage(&job.script, format!("sbatch failed: {msg}")));
        }
        let text = String::from_utf8_lossy(&out.stdout);
        let id = text.trim().split(';').next().unwrap_or("").trim().to_string();
        if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
            return Err(PipelineError::stage(&job.script, format!("sbatch printed no job id ({:?})", text.trim())));
        }
        job.job_id = Some(id.clone());
        prev = Some(id);
    }
    Ok(())
}

/// Job ids of `ids` still in the queue (pending or running). An error of
/// squeue about unknown ids (jobs long finished) counts as none.
fn queued(ids: &[String]) -> Result<Vec<String>, PipelineError> {
    let out = slurm_command("squeue")
        .args(["-h", "-o", "%A %T", "-j", &ids.join(",")])
        .output()
        .map_err(|e| PipelineError::stage("squeue", format!("cannot run squeue: {e}")))?;
    if !out.status.success() {
        return Ok(Vec::new());
    }
    Ok(String::from_utf8_lossy(&out.stdout).lines().filter_map(|l| l.split_whitespace().next().map(str::to_string)).collect())
}

/// Follows a submitted run until its work directory is complete (`Ok`) or
/// none of its jobs is left in the queue with tasks undone (`Err`, naming
/// the stage and its logs). Calls `tick` with the status every poll.
pub fn wait(dir: &Path, jobs: &[StageJob], poll: Duration, tick: &mut dyn FnMut(&crate::engine::RunStatus)) -> Result<(), PipelineError> {
    let ids: Vec<String> = jobs.iter().filter_map(|j| j.job_id.clone()).collect();
    loop {
        let st = status(dir)?;
        tick(&st);
        if st.complete {
            return Ok(());
        }
        if queued(&ids)?.is_empty() {
            // Nothing left in the queue: look once more (a last task may have
            // just finished), then report the first incomplete stage.
            std::thread::sleep(Duration::from_millis(500));
            let st = status(dir)?;
            if st.complete {
                return Ok(());
            }
            let stage = st.stages.iter().find(|s| s.left > 0).expect("an incomplete stage");
            return Err(PipelineError::stage(
                dir,
                format!(
                    "the run stopped: stage '{}' has {} of {} tasks not done and no job is left in the queue ({}); see {}/slurm/{}-*.log, fix the cause, and run `mint slurm` again with the same --work to resume",
                    stage.name,
                    stage.left,
                    stage.tasks,
                    failure_cause(dir, stage.name, stage.tasks),
                    dir.display(),
                    stage.name
                ),
            ));
        }
        std::thread::sleep(poll);
    }
}

/// What the logs of a stage's undone tasks say: the last `mint: error:`
/// line of the first task that has one, or that the tasks left none (killed
/// by a signal, the node lost, or never started).
pub fn failure_cause(dir: &Path, stage: crate::workdir::Stage, tasks: u32) -> String {
    let undone: Vec<u32> = (0..tasks).filter(|&t| !crate::workdir::is_done(dir, stage, t)).collect();
    for &t in &undone {
        let log = dir.join("slurm").join(format!("{}-{t}.log", stage.dir_name()));
        let Ok(text) = std::fs::read(&log) else { continue };
        let text = String::from_utf8_lossy(&text);
        if let Some(line) = text.lines().rev().find_map(|l| l.trim().strip_prefix("mint: error:")) {
            return format!("task {t}: {}", line.trim());
        }
    }
    let first = undone.first().copied().unwrap_or(0);
    format!("task {first} left no error in its log: killed by a signal, its node lost, or never started")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn option_strings_split_like_a_shell() {
        assert_eq!(split_args("--partition=batch  --time 1:00:00").unwrap(), ["--partition=batch", "--time", "1:00:00"]);
        assert_eq!(split_args(r#"--comment "two words" -J 'a b' x\ y"#).unwrap(), ["--comment", "two words", "-J", "a b", "x y"]);
        assert_eq!(split_args("").unwrap(), Vec::<String>::new());
        assert!(split_args("'open").is_err());
    }

    #[test]
    fn quoting_survives_single_quotes() {
        let q = quote("a'b c");
        assert_eq!(split_args(&q).unwrap(), ["a'b c"]);
    }
}
