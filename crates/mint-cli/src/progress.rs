//! Progress bars for the pipelines' phases (indicatif), hidden when stderr
//! is not a terminal or with `--quiet`, and the Ctrl-C flag the pipelines
//! poll to stop cleanly.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mint_pipeline::{Phase, Progress};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Instant;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Installs the Ctrl-C handler once. The first Ctrl-C (or SIGTERM, or
/// SIGHUP: the `termination` feature of `ctrlc`) asks the running pipeline
/// to stop (it removes its temporary files and exits with 130); a second
/// one exits at once. SIGXFSZ is ignored, so that a file-size limit
/// (`ulimit -f`, `prlimit --fsize`) makes the write fail with "File too
/// large" and the temporary files are removed, instead of killing the
/// process with its debris.
pub fn install_ctrlc() {
    // SAFETY: setting a signal's disposition at startup, before any thread
    // exists, has no memory-safety preconditions. SIGXFSZ ignored: a file
    // too large is an error we report. SIGPIPE to its default: a closed
    // stdout (`mint check x.ply | head -0`) ends the command quietly with
    // the conventional status, like every Unix tool, instead of a panic in
    // `println!` (Rust ignores SIGPIPE by default). mint prints to stdout
    // only results, after its outputs are written.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
}

/// True once the user pressed Ctrl-C, or an embedding asked this thread's
/// run to stop.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst) || crate::out::cancelled()
}

/// Progress bars on stderr, one per phase; embedded (see `crate::out`),
/// reports to the embedding's callback instead, and stops when it asks.
pub struct Bars {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
    hooks: Option<crate::out::Hooks>,
    /// The embedding's view of the current phase: name, done, total, and
    /// when it was last told.
    phase: Mutex<(&'static str, u64, u64, Option<Instant>)>,
}

impl Bars {
    pub fn new(quiet: bool) -> Bars {
        Bars { quiet, bar: Mutex::new(None), hooks: crate::out::hooks(), phase: Mutex::new(("", 0, 0, None)) }
    }

    /// Tells the embedding's callback, at most every 50 ms unless `force`.
    fn tell(&self, force: bool) {
        let Some(report) = self.hooks.as_ref().and_then(|h| h.progress.as_ref()) else { return };
        let mut p = self.phase.lock().unwrap();
        let now = Instant::now();
        if force || p.3.is_none_or(|t| now.duration_since(t).as_millis() >= 50) {
            p.3 = Some(now);
            let (name, done, total) = (p.0, p.1, p.2);
            drop(p);
            report(name, done, total);
        }
    }
}

impl Progress for Bars {
    fn start(&self, phase: Phase, total: u64) {
        if let Some(h) = &self.hooks {
            if h.progress.is_some() {
                *self.phase.lock().unwrap() = (phase.name(), 0, total, None);
                self.tell(true);
            }
            return;
        }
        if self.quiet {
            return;
        }
        let target = ProgressDrawTarget::stderr(); // hidden when not a terminal
        let bar = if total > 0 { ProgressBar::with_draw_target(Some(total), target) } else { ProgressBar::with_draw_target(None, target) };
        let style = if total > 0 {
            ProgressStyle::with_template("{prefix:>12} [{bar:40}] {human_pos}/{human_len} {per_sec} eta {eta}")
        } else {
            ProgressStyle::with_template("{prefix:>12} {spinner} {human_pos} {per_sec}")
        };
        bar.set_style(style.unwrap().progress_chars("=> "));
        bar.set_prefix(phase.name());
        *self.bar.lock().unwrap() = Some(bar);
    }
    fn advance(&self, n: u64) {
        if self.hooks.is_some() {
            self.phase.lock().unwrap().1 += n;
            self.tell(false);
            return;
        }
        if let Some(b) = self.bar.lock().unwrap().as_ref() {
            b.inc(n);
        }
    }
    fn finish(&self) {
        if self.hooks.is_some() {
            let mut p = self.phase.lock().unwrap();
            if p.2 > 0 {
                p.1 = p.2;
            }
            drop(p);
            self.tell(true);
            return;
        }
        if let Some(b) = self.bar.lock().unwrap().take() {
            b.finish_and_clear();
        }
    }
    fn cancelled(&self) -> bool {
        INTERRUPTED.load(Ordering::SeqCst) || self.hooks.as_ref().is_some_and(|h| h.cancel.load(Ordering::Relaxed))
    }
}
