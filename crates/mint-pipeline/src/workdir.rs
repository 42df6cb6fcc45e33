//! The work directory of a staged run, and how a task's result gets there.
//!
//! ```text
//! DIR/plan.json                     the plan: plain JSON, its checksum inside (see `plan`)
//! DIR/<stage>/<task>/result.json    a finished task: "crc32 XXXXXXXX" line, then JSON
//! DIR/<stage>/<task>/...            its data files (shards, vertices, faces, hole cells)
//! DIR/<stage>/.<task>.tmp-<pid>-<n> a task being written (or abandoned by a dead process)
//! ```
//! A task writes everything into its own temporary directory, syncs it,
//! and renames it to `<task>` at the end: a task directory either does not
//! exist or is complete, whatever kills the process, and tasks of one stage
//! on different machines never touch the same file. Two processes racing on
//! one task both succeed; the second rename finds the first one's result
//! and discards its own. Nothing is ever appended to a shared file and no
//! lock is taken, so DIR may live on NFS-like shared storage.
//!
//! Every data file is checksummed (CRC-32, in the task's result), and every
//! reader checks length and checksum, so a truncated or damaged result is
//! reported with its path, never used.
//!
//! A task's files are synced to disk when it commits, so that a run can be
//! resumed after a crash, except in a work directory marked temporary
//! ([`TEMPORARY_FILE`], the engine's own when no `--work` is given):
//! nothing resumes those (the next run removes them), and the syncs cost a
//! small run a fifth of its time.

use crate::error::PipelineError;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

mint_core::choice! {
    /// A stage of the engine, in the order they run (see `stages`).
    pub enum Stage {
        Bounds => "bounds",
        Discretize => "discretize",
        Census => "census",
        Reconstruct => "reconstruct",
        Reopen => "reopen",
        Write => "write",
    }
}

impl Stage {
    /// The stage's directory name inside the work directory.
    pub fn dir_name(self) -> &'static str {
        mint_core::choice::Choice::name(self)
    }
}

/// The plan's file name inside the work directory.
pub const PLAN_FILE: &str = "plan.json";
/// A finished task's result file.
pub const RESULT_FILE: &str = "result.json";

/// The directory of a finished task.
pub fn task_dir(dir: &Path, stage: Stage, task: u32) -> PathBuf {
    dir.join(stage.dir_name()).join(format!("{task:05}"))
}

fn io<'a>(path: &'a Path, op: &'static str) -> impl FnOnce(std::io::Error) -> PipelineError + 'a {
    move |source| PipelineError::Temp { path: path.to_path_buf(), op, source }
}

/// Writes `bytes` to `path` through a temporary file beside it, synced and
/// renamed: readers see the old file or the whole new one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PipelineError> {
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    let write = || -> std::io::Result<()> {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(path, "writing")(e)
    })
}

/// Serializes `value` as checksummed JSON: a first line `crc32 XXXXXXXX`
/// (of the JSON text that follows), then the JSON.
pub fn checked_json<T: Serialize>(value: &T) -> Vec<u8> {
    let json = serde_json::to_string_pretty(value).expect("task results serialize");
    let mut out = format!("crc32 {:08x}\n", crc32fast::hash(json.as_bytes())).into_bytes();
    out.extend_from_slice(json.as_bytes());
    out.push(b'\n');
    out
}

/// Reads checksummed JSON written by [`checked_json`].
pub fn read_checked_json<T: DeserializeOwned>(path: &Path) -> Result<T, PipelineError> {
    let bytes = std::fs::read(path).map_err(io(path, "reading"))?;
    let bad = |what: &str| PipelineError::stage(path, format!("{what}; remove its task directory and run the task again"));
    let nl = bytes.iter().position(|&b| b == b'\n').ok_or_else(|| bad("damaged task result (no checksum line)"))?;
    let head = std::str::from_utf8(&bytes[..nl]).map_err(|_| bad("damaged task result (checksum line)"))?;
    let want = head.strip_prefix("crc32 ").and_then(|h| u32::from_str_radix(h.trim(), 16).ok());
    let body = &bytes[nl + 1..];
    let body = body.strip_suffix(b"\n").unwrap_or(body);
    match want {
        Some(w) if w == crc32fast::hash(body) => {}
        Some(_) => return Err(bad("damaged task result (checksum mismatch)")),
        None => return Err(bad("damaged task result (checksum line)")),
    }
    serde_json::from_slice(body).map_err(|e| bad(&format!("unreadable task result ({e})")))
}

/// True when the task's directory holds a result.
pub fn is_done(dir: &Path, stage: Stage, task: u32) -> bool {
    task_dir(dir, stage, task).join(RESULT_FILE).is_file()
}

/// Reads a finished task's result; one line naming the task when it is
/// missing or damaged.
pub fn read_result<T: DeserializeOwned>(dir: &Path, stage: Stage, task: u32) -> Result<T, PipelineError> {
    let path = task_dir(dir, stage, task).join(RESULT_FILE);
    if !path.is_file() {
        return Err(PipelineError::stage(
            dir,
            format!("stage '{stage}' task {task} is not done (run `mint stage run {} {stage} {task}` first)", dir.display()),
        ));
    }
    read_checked_json(&path)
}

/// The file whose presence marks a work directory as temporary: its
/// tasks are not synced to disk (see the module's notes).
pub const TEMPORARY_FILE: &str = "temporary";

/// Marks work directory `dir` as temporary.
pub fn mark_temporary(dir: &Path) -> Result<(), PipelineError> {
    let p = dir.join(TEMPORARY_FILE);
    File::create(&p).map(|_| ()).map_err(io(&p, "creating the work directory"))
}

/// A task being written: a temporary directory renamed into place by
/// [`TaskBuild::commit`], removed if dropped uncommitted.
pub struct TaskBuild {
    tmp: PathBuf,
    target: PathBuf,
    committed: bool,
    /// Whether the commit syncs the task's files (not in a temporary work
    /// directory).
    durable: bool,
    _owner: OwnerLock,
}

/// Syncs every file and directory under `dir`, `dir` last.
fn sync_tree(dir: &Path) -> std::io::Result<()> {
    for e in std::fs::read_dir(dir)? {
        let e = e?;
        let t = e.file_type()?;
        if t.is_dir() {
            sync_tree(&e.path())?;
        } else if t.is_file() {
            File::open(e.path())?.sync_all()?;
        }
    }
    // (Some file systems refuse to sync a directory; its entries are then
    // as durable as they can be made.)
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

impl TaskBuild {
    /// Starts writing task `task` of `stage`.
    pub fn begin(dir: &Path, stage: Stage, task: u32) -> Result<TaskBuild, PipelineError> {
        let stage_dir = dir.join(stage.dir_name());
        std::fs::create_dir_all(&stage_dir).map_err(io(&stage_dir, "creating the stage directory"))?;
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.subsec_nanos()).unwrap_or(0);
        let tmp = stage_dir.join(format!(".{task:05}.tmp-{}-{nanos}", std::process::id()));
        // Copies of this task abandoned by a process that died.
        let mine = format!(".{task:05}.tmp-");
        for (p, owner) in temp_tasks(dir, stage) {
            if owner == Owner::Dead && p.file_name().is_some_and(|n| n.to_string_lossy().starts_with(&mine)) {
                let _ = std::fs::remove_dir_all(p);
            }
        }
        std::fs::create_dir(&tmp).map_err(io(&tmp, "creating a task directory"))?;
        let owner = match OwnerLock::of_dir(&tmp) {
            Ok(o) => o,
            Err(e) => {
                let _ = std::fs::remove_dir_all(&tmp);
                return Err(e);
            }
        };
        let durable = !dir.join(TEMPORARY_FILE).exists();
        Ok(TaskBuild { tmp, target: task_dir(dir, stage, task), committed: false, durable, _owner: owner })
    }

    /// Where the task writes its files.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Writes the result, syncs, and renames the directory into place. If
    /// another process finished the same task first, keeps its result.
    pub fn commit<T: Serialize>(mut self, result: &T) -> Result<(), PipelineError> {
        let path = self.tmp.join(RESULT_FILE);
        let write = || -> std::io::Result<()> {
            let mut f = File::create(&path)?;
            f.write_all(&checked_json(result))?;
            drop(f);
            // The data files, the result and their directory entries.
            if self.durable {
                sync_tree(&self.tmp)?;
            }
            Ok(())
        };
        write().map_err(io(&path, "writing a task result"))?;
        // The lock file stays out of the result; the lock itself is held
        // (through the open file) until this build is dropped.
        let _ = std::fs::remove_file(self.tmp.join(OWNER_FILE));
        match std::fs::rename(&self.tmp, &self.target) {
            Ok(()) => {
                self.committed = true;
                if let Some(parent) = self.target.parent().and_then(|p| File::open(p).ok()).filter(|_| self.durable) {
                    let _ = parent.sync_all();
                }
                Ok(())
            }
            Err(_) if self.target.join(RESULT_FILE).is_file() => Ok(()), // another process won; drop removes ours
            Err(e) => Err(io(&self.target, "renaming a finished task into place")(e)),
        }
    }
}

impl Drop for TaskBuild {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

/// Length and checksum of a data file, as its writer saw it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileSum {
    pub len: u64,
    pub crc32: u32,
}

/// A buffered writer that checksums what it writes, a buffer at a time
/// (a checksum update per 12-byte record costs more than the copy).
pub struct SumWriter {
    path: PathBuf,
    out: File,
    buf: Vec<u8>,
    crc: crc32fast::Hasher,
    len: u64,
}

/// [`SumWriter`]'s buffer.
const SUM_BUFFER: usize = 1 << 20;

impl SumWriter {
    pub fn create(path: PathBuf) -> Result<SumWriter, PipelineError> {
        let f = File::create(&path).map_err(io(&path, "creating a task file"))?;
        Ok(SumWriter { path, out: f, buf: Vec::with_capacity(SUM_BUFFER), crc: crc32fast::Hasher::new(), len: 0 })
    }

    pub fn write(&mut self, bytes: &[u8]) -> Result<(), PipelineError> {
        if self.buf.len() + bytes.len() > SUM_BUFFER {
            self.flush_buffer()?;
        }
        self.len += bytes.len() as u64;
        if bytes.len() > SUM_BUFFER {
            self.crc.update(bytes);
            return self.out.write_all(bytes).map_err(io(&self.path, "writing a task file"));
        }
        self.buf.extend_from_slice(bytes);
        Ok(())
    }

    fn flush_buffer(&mut self) -> Result<(), PipelineError> {
        self.crc.update(&self.buf);
        self.out.write_all(&self.buf).map_err(io(&self.path, "writing a task file"))?;
        self.buf.clear();
        Ok(())
    }

    /// Flushes; returns the file's length and checksum. (The task's commit
    /// syncs it.)
    pub fn finish(mut self) -> Result<FileSum, PipelineError> {
        self.flush_buffer()?;
        Ok(FileSum { len: self.len, crc32: self.crc.finalize() })
    }
}

/// Streams a data file in records of `N` bytes to `each`, checking its
/// length and checksum against `want` (a mismatch is reported before the
/// caller's work is committed, since nothing is renamed until the end).
pub fn read_records<const N: usize>(
    path: &Path,
    want: FileSum,
    mut each: impl FnMut(&[u8; N]) -> Result<(), PipelineError>,
) -> Result<(), PipelineError> {
    let damaged = |what: String| PipelineError::stage(path, format!("{what}: the task result is damaged; remove its task directory and run the task again"));
    let f = File::open(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => damaged("missing".into()),
        _ => io(path, "opening a task file")(e),
    })?;
    let len = f.metadata().map_err(io(path, "reading a task file"))?.len();
    if len != want.len {
        return Err(damaged(format!("{len} bytes, {} were written", want.len)));
    }
    // Blocks of whole records, each checksummed at once (a checksum
    // update per 12-byte record costs more than the read).
    let mut rd = f;
    let mut crc = crc32fast::Hasher::new();
    let per_block = ((1usize << 20) / N).max(1);
    let mut block = vec![0u8; per_block * N];
    let mut left = len / N as u64;
    while left > 0 {
        let n = (left.min(per_block as u64)) as usize;
        let bytes = &mut block[..n * N];
        rd.read_exact(bytes).map_err(io(path, "reading a task file"))?;
        crc.update(bytes);
        for rec in bytes.chunks_exact(N) {
            each(rec.try_into().expect("a record of N bytes"))?;
        }
        left -= n as u64;
    }
    if crc.finalize() != want.crc32 {
        return Err(damaged("checksum mismatch".into()));
    }
    Ok(())
}

/// Bytes of all files under `path` (0 if it does not exist).
pub fn disk_bytes(path: &Path) -> u64 {
    let Ok(rd) = std::fs::read_dir(path) else {
        return std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    };
    rd.flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => disk_bytes(&e.path()),
            _ => e.metadata().map(|m| m.len()).unwrap_or(0),
        })
        .sum()
}

/// Temporary task directories present in a stage (tasks being written, or
/// abandoned by a process that died), each with the state of its owner.
pub fn temp_tasks(dir: &Path, stage: Stage) -> Vec<(PathBuf, Owner)> {
    let Ok(rd) = std::fs::read_dir(dir.join(stage.dir_name())) else { return Vec::new() };
    let mut v: Vec<PathBuf> = rd.flatten().map(|e| e.path()).filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().contains(".tmp-"))).collect();
    v.sort();
    v.into_iter().map(|p| {
        let o = owner_of(&p);
        (p, o)
    }).collect()
}

/// Who holds a temporary directory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Owner {
    /// A live process holds its lock.
    Live,
    /// Its lock is free: the process that made it died.
    Dead,
    /// It has no lock file (being set up or committed, or made by an older
    /// mint); treated as live.
    Unknown,
}

/// The state of the owner of the directory `dir` (see [`OwnerLock`]). The
/// lock is taken and released at once when free. On a shared file system
/// this needs working `flock` (NFSv4 and Lustre with `flock` do).
pub fn owner_of(dir: &Path) -> Owner {
    match File::open(dir.join(OWNER_FILE)) {
        Err(_) => Owner::Unknown,
        Ok(f) if try_flock(&f) => Owner::Dead,
        Ok(_) => Owner::Live,
    }
}

/// The owner lock of a temporary work directory: an exclusive
/// `flock` held by the live run that made it, for as long as it runs. A
/// directory whose lock can be taken belongs to a run that died (SIGKILL,
/// power loss), and the next run in the same folder removes it.
pub struct OwnerLock(#[allow(dead_code)] File);

/// The owner lock's file inside a temporary work directory.
pub const OWNER_FILE: &str = ".owner";

fn try_flock(f: &File) -> bool {
    use std::os::fd::AsRawFd;
    // SAFETY: flock on a descriptor this File owns; no memory is involved.
    unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) == 0 }
}

impl OwnerLock {
    /// Takes the lock of the directory `dir`: the file is locked under a
    /// temporary name and renamed into place, so that no other run can ever
    /// see it unlocked while this one lives.
    pub fn of_dir(dir: &Path) -> Result<OwnerLock, PipelineError> {
        let tmp = dir.join(format!("{OWNER_FILE}.{}", std::process::id()));
        let f = File::create(&tmp).map_err(io(&tmp, "creating the owner lock"))?;
        if !try_flock(&f) {
            return Err(PipelineError::stage(&tmp, "cannot lock a file this run just made"));
        }
        let _ = writeln!(&f, "{}", std::process::id());
        std::fs::rename(&tmp, dir.join(OWNER_FILE)).map_err(io(&tmp, "placing the owner lock"))?;
        Ok(OwnerLock(f))
    }
}

/// Removes the directories of `root` named `prefix…` that a dead run left:
/// those whose [`OWNER_FILE`] nobody holds. Directories without one (a run
/// being set up, or an older mint) are left alone. Returns what was removed.
pub fn remove_dead(root: &Path, prefix: &str) -> Vec<PathBuf> {
    let Ok(rd) = std::fs::read_dir(root) else { return Vec::new() };
    let mut removed = Vec::new();
    for e in rd.flatten() {
        if !e.file_name().to_string_lossy().starts_with(prefix) || !e.file_type().map(|t| t.is_dir()).unwrap_or(false) {
            continue;
        }
        let path = e.path();
        if owner_of(&path) == Owner::Dead && std::fs::remove_dir_all(&path).is_ok() {
            removed.push(path);
        }
    }
    removed.sort();
    removed
}
