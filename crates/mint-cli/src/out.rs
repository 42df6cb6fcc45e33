//! Where a command's results go. On the command line: `--json` summaries on
//! stdout, warnings on stderr. Embedded (the Python package runs the same
//! commands in its own process, through `crate::embed`): summaries and
//! warnings are captured and handed back, progress goes to a callback, and
//! a flag of the caller's stops the run as Ctrl-C would. Commands write
//! through [`json`] and [`warn`] and never learn which of the two they serve.
//! A leaf: it imports no other module of the crate.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::Result;

/// A progress report: (phase name, units done, units in all; 0 when unknown).
pub type ProgressFn = dyn Fn(&str, u64, u64) + Send + Sync;

/// What an embedding gives a run: where progress goes, and the flag that
/// stops it (checked wherever the command line checks for Ctrl-C).
#[derive(Clone)]
pub struct Hooks {
    /// Called as phases start and advance (from any thread, at most every
    /// few milliseconds per phase).
    pub progress: Option<Arc<ProgressFn>>,
    /// Set by the embedding to stop the run cleanly (temporary files and
    /// partial outputs removed), as Ctrl-C does on the command line.
    pub cancel: Arc<AtomicBool>,
}

/// What an embedded command reported instead of printing.
#[derive(Debug, Default, Clone)]
pub struct Captured {
    /// The `--json` documents, in the order printed (usually one).
    pub json: Vec<serde_json::Value>,
    /// The warning lines (without the `mint: warning: ` prefix).
    pub warnings: Vec<String>,
}

struct Embedded {
    hooks: Hooks,
    captured: Captured,
}

thread_local! {
    static EMBEDDED: RefCell<Option<Embedded>> = const { RefCell::new(None) };
}

/// Makes this thread's commands report to an embedding until [`finish`].
pub(crate) fn begin(hooks: Hooks) {
    EMBEDDED.with(|e| *e.borrow_mut() = Some(Embedded { hooks, captured: Captured::default() }));
}

/// Ends this thread's embedding and returns what its commands reported.
pub(crate) fn finish() -> Captured {
    EMBEDDED.with(|e| e.borrow_mut().take()).map(|e| e.captured).unwrap_or_default()
}

/// The hooks of the embedded run on this thread, if any.
pub(crate) fn hooks() -> Option<Hooks> {
    EMBEDDED.with(|e| e.borrow().as_ref().map(|e| e.hooks.clone()))
}

/// Prints a `--json` document on stdout, or captures it.
pub(crate) fn json<T: serde::Serialize + ?Sized>(v: &T) -> Result<()> {
    let captured = EMBEDDED.with(|e| -> Result<bool> {
        match e.borrow_mut().as_mut() {
            Some(e) => {
                e.captured.json.push(serde_json::to_value(v)?);
                Ok(true)
            }
            None => Ok(false),
        }
    })?;
    if !captured {
        println!("{}", serde_json::to_string_pretty(v)?);
    }
    Ok(())
}

/// Prints a warning line on stderr (also with `--quiet` and `--json`), or
/// captures it.
pub(crate) fn warn(w: &str) {
    let captured = EMBEDDED.with(|e| match e.borrow_mut().as_mut() {
        Some(e) => {
            e.captured.warnings.push(w.to_string());
            true
        }
        None => false,
    });
    if !captured {
        eprintln!("mint: warning: {w}");
    }
}

/// True when the embedded run on this thread was asked to stop.
pub(crate) fn cancelled() -> bool {
    EMBEDDED.with(|e| e.borrow().as_ref().is_some_and(|e| e.hooks.cancel.load(Ordering::Relaxed)))
}

