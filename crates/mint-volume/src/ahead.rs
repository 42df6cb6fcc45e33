//! Reading slices ahead: a thread of its own reads the stored bytes of the
//! slices a reader will ask for next into the system's cache, and drops
//! them, while the slices read before are worked on. A volume larger than
//! memory then costs about its reading or its work, not the sum.
//!
//! `posix_fadvise(WILLNEED)` alone does not do this: Linux reads at most
//! one read-ahead window (128 KiB to a few MiB) of the range it is given.
//! Reads are in pieces of [`PIECE`] bytes into one buffer; a piece the
//! cache already holds whole (`mincore`) is not read again, so a volume in
//! the cache costs no copy. Everything here is a hint: errors are ignored
//! (the reader that follows reports them), and dropping the
//! [`ReadAhead`] stops its thread within one piece.

use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;

/// A byte range of a data file that holds samples: `len` bytes from `at`
/// (`None`: to the end of the file).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Stored {
    pub path: PathBuf,
    pub at: u64,
    pub len: Option<u64>,
}

/// The bytes read at once, and the memory a read-ahead holds.
pub(crate) const PIECE: usize = 1 << 20;

/// The read-ahead thread and the queue of its requests (of which it reads
/// the newest).
pub(crate) struct ReadAhead {
    queue: Option<Sender<Vec<Stored>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl ReadAhead {
    /// Starts the thread, or `None` when the system has no thread to give.
    pub fn start() -> Option<ReadAhead> {
        let (tx, rx) = channel::<Vec<Stored>>();
        let stop = Arc::new(AtomicBool::new(false));
        let halt = stop.clone();
        let thread = std::thread::Builder::new()
            .name("mint-read-ahead".into())
            .spawn(move || {
                let mut buf = vec![0u8; PIECE];
                let mut open: Option<(PathBuf, File)> = None;
                while let Ok(mut ranges) = rx.recv() {
                    // Only the newest request: the reader has reached (and
                    // read itself) what older ones asked for.
                    while let Ok(newer) = rx.try_recv() {
                        ranges = newer;
                    }
                    for r in ranges {
                        if halt.load(Ordering::Relaxed) {
                            return;
                        }
                        if open.as_ref().is_none_or(|(p, _)| *p != r.path) {
                            open = File::open(&r.path).ok().map(|f| (r.path.clone(), f));
                        }
                        if let Some((_, f)) = &open {
                            warm(f, &r, &mut buf, &halt);
                        }
                    }
                }
            })
            .ok()?;
        Some(ReadAhead { queue: Some(tx), stop, thread: Some(thread) })
    }

    /// Asks for `ranges` to be read, in place of any request the thread has
    /// not started.
    pub fn ask(&self, ranges: Vec<Stored>) {
        if let Some(q) = &self.queue {
            if !ranges.is_empty() {
                let _ = q.send(ranges);
            }
        }
    }
}

impl Drop for ReadAhead {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        self.queue = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Reads range `r` of `f` piece by piece, skipping pieces already cached.
fn warm(f: &File, r: &Stored, buf: &mut [u8], halt: &AtomicBool) {
    let Ok(size) = f.metadata().map(|m| m.len()) else { return };
    let end = match r.len {
        Some(n) => r.at.saturating_add(n).min(size),
        None => size,
    };
    let mut at = r.at;
    let mut resident = Vec::new();
    // A span's residency is asked at once (one mapping), then its pieces
    // not wholly cached are read.
    while at < end && !halt.load(Ordering::Relaxed) {
        let span = (end - at).min(SPAN);
        let page = residency(f, at, span as usize, &mut resident);
        let mut piece_at = at;
        while piece_at < at + span && !halt.load(Ordering::Relaxed) {
            let n = ((at + span - piece_at) as usize).min(buf.len());
            let cached = page.is_some_and(|page| {
                let first = ((piece_at / page) - (at / page)) as usize;
                let last = ((piece_at + n as u64 - 1) / page - at / page) as usize;
                resident[first..=last].iter().all(|&b| b & 1 == 1)
            });
            if !cached && f.read_at(&mut buf[..n], piece_at).is_err() {
                return;
            }
            piece_at += n as u64;
        }
        at += span;
    }
}

/// The bytes whose residency one mapping asks (64 MiB: 16 KiB of answers).
const SPAN: u64 = 64 << 20;

/// Which pages of bytes `at .. at + n` of `f` are in the system's cache:
/// `resident[i] & 1` for the `i`-th page from the one holding `at`, and
/// the page size; `None` when that cannot be told.
fn residency(f: &File, at: u64, n: usize, resident: &mut Vec<u8>) -> Option<u64> {
    // SAFETY: sysconf has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    if page <= 0 || n == 0 {
        return None;
    }
    let page = page as u64;
    let start = at / page * page;
    let len = (at + n as u64 - start) as usize;
    resident.clear();
    resident.resize(len.div_ceil(page as usize), 0);
    // SAFETY: a read-only mapping of an open file, never read through
    // (mincore only looks at which pages are resident, so a file cut
    // short meanwhile cannot fault), unmapped before returning; it starts
    // on a page boundary as mmap asks, and `resident` has a byte a page.
    unsafe {
        use std::os::unix::io::AsRawFd;
        let p = libc::mmap(std::ptr::null_mut(), len, libc::PROT_READ, libc::MAP_SHARED, f.as_raw_fd(), start as libc::off_t);
        if p == libc::MAP_FAILED {
            return None;
        }
        let ok = libc::mincore(p, len, resident.as_mut_ptr()) == 0;
        libc::munmap(p, len);
        ok.then_some(page)
    }
}

/// Whether every page of bytes `at .. at + n` of `f` is cached.
#[cfg(test)]
fn cached(f: &File, at: u64, n: usize) -> bool {
    let mut r = Vec::new();
    residency(f, at, n, &mut r).is_some() && r.iter().all(|&b| b & 1 == 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cached_file_reads_as_cached_and_warming_stops_when_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.raw");
        std::fs::write(&p, vec![7u8; 3 * PIECE + 5]).unwrap();
        let f = File::open(&p).unwrap();
        // Just written: in the cache.
        assert!(cached(&f, 0, PIECE));
        assert!(cached(&f, PIECE as u64 + 3, 100));
        let mut buf = vec![0u8; PIECE];
        let halt = AtomicBool::new(false);
        // Ranges past the end, to the end, and empty read nothing and fail nothing.
        for len in [Some(10 * PIECE as u64), None, Some(0)] {
            warm(&f, &Stored { path: p.clone(), at: 5, len }, &mut buf, &halt);
        }
        // Out of the cache (written through, then dropped), then read ahead.
        // (Beside the sources: a disk, where dropping pages works; a
        // temporary folder may be in memory.)
        let disk = tempfile::tempdir_in(env!("CARGO_MANIFEST_DIR")).unwrap();
        let q = disk.path().join("ahead.raw");
        std::fs::write(&q, vec![3u8; 2 * PIECE]).unwrap();
        let g = File::open(&q).unwrap();
        g.sync_all().unwrap();
        use std::os::unix::io::AsRawFd;
        // SAFETY: a valid descriptor; the call only advises.
        unsafe { libc::posix_fadvise(g.as_raw_fd(), 0, 0, libc::POSIX_FADV_DONTNEED) };
        let dropped = !cached(&g, 0, 2 * PIECE);
        warm(&g, &Stored { path: q.clone(), at: PIECE as u64, len: Some(PIECE as u64) }, &mut buf, &halt);
        if dropped {
            assert!(cached(&g, PIECE as u64, PIECE), "the range read ahead is cached");
        } else {
            // (tmpfs, some overlay and network file systems keep them.)
            eprintln!("note: the system kept the pages of {} in its cache; the read-ahead's effect was not checked", q.display());
        }
        let ahead = ReadAhead::start().unwrap();
        ahead.ask(vec![Stored { path: p.clone(), at: 0, len: None }, Stored { path: dir.path().join("missing"), at: 0, len: None }]);
        drop(ahead);
    }
}
