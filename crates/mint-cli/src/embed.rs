//! mint's commands run by another program in its process (the Python
//! package): [`run_embedded`] parses a command line and runs it with its
//! reports captured (`crate::out`), and sorts a failure into an
//! [`ErrorKind`] for typed exceptions; [`exit_status`] is the command line
//! itself, for the binary's `main` and the wheel's `mint` script. Nothing
//! in the crate imports this module.

use std::sync::atomic::Ordering;

use clap::Parser;

use crate::out::{self, Captured, Hooks};

/// Why an embedded command failed.
#[derive(Debug)]
pub enum EmbedError {
    /// The arguments do not parse (clap's message, first line).
    Usage(String),
    /// The run stopped because the embedding set its cancel flag.
    Cancelled(String),
    /// The command failed: its one-line message, and the error for callers
    /// that want to tell kinds apart ([`error_kind`]).
    Failed { message: String, kind: ErrorKind },
}

/// The kind of a failure, for typed exceptions in embeddings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The input is malformed, out of range, or not what the command needs.
    Input,
    /// Reading or writing a file failed (missing file, permission, full disk).
    Io,
    /// The memory budget is too small for the job.
    Budget,
    /// Anything else.
    Other,
}

/// Runs one command line (`argv[0]` is the command name, e.g.
/// `["resample", "in.ply", "out.ply", "--cells", "1000"]`) in this process,
/// as the `mint` binary would, but capturing what it reports. Nothing is
/// printed but lines a command writes for people (`--json` is added when
/// the command takes it). The same output bytes as the command line.
pub fn run_embedded(argv: &[String], hooks: Hooks) -> Result<Captured, EmbedError> {
    let full: Vec<String> = std::iter::once("mint".to_string()).chain(argv.iter().cloned()).collect();
    let cli = crate::cli::Cli::try_parse_from(&full).map_err(|e| {
        // clap's message up to its usage line, on one line.
        let text = e.to_string();
        let words: Vec<&str> = text.lines().take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more")).map(str::trim).filter(|l| !l.is_empty()).collect();
        let what = argv.first().map(|c| format!("mint {c}: ")).unwrap_or_default();
        EmbedError::Usage(format!("{what}{}", words.join(" ").trim_start_matches("error: ")))
    })?;
    let cancel = hooks.cancel.clone();
    out::begin(hooks);
    let result = crate::cli::run(cli);
    let captured = out::finish();
    match result {
        Ok(()) => Ok(captured),
        Err(e) => {
            let message = one_line(&e);
            if cancel.load(Ordering::SeqCst) {
                Err(EmbedError::Cancelled(message))
            } else {
                Err(EmbedError::Failed { message, kind: error_kind(&e) })
            }
        }
    }
}

/// Sorts an error into a kind by the types in its chain.
pub fn error_kind(e: &anyhow::Error) -> ErrorKind {
    for cause in e.chain() {
        if let Some(io) = cause.downcast_ref::<mint_io::Error>() {
            return io_kind(io);
        }
        if let Some(p) = cause.downcast_ref::<mint_pipeline::PipelineError>() {
            if let Some(k) = pipeline_kind(p) {
                return k;
            }
        }
        if let Some(c) = cause.downcast_ref::<mint_check::CheckError>() {
            use mint_check::CheckError as C;
            match c {
                C::Io(e) => return io_kind(e),
                C::Store(_) | C::Temp { .. } => return ErrorKind::Io,
                C::Limit { .. } => return ErrorKind::Input,
                C::Cancelled => {}
            }
        }
        if let Some(r) = cause.downcast_ref::<mint_render::RenderError>() {
            use mint_render::RenderError as R;
            match r {
                R::Io(e) => return io_kind(e),
                R::Write { .. } => return ErrorKind::Io,
                R::Empty { .. } => return ErrorKind::Input,
                R::Option(_) | R::Cancelled => {}
            }
        }
        if let Some(r) = cause.downcast_ref::<mint_range::RangeError>() {
            use mint_range::RangeError as R;
            match r {
                R::Io(e) => return io_kind(e),
                R::MissingScan { .. } | R::File { .. } => return ErrorKind::Io,
                R::Cancelled | R::InvalidOption { .. } => {}
                _ => return ErrorKind::Input,
            }
        }
        if let Some(c) = cause.downcast_ref::<mint_contour::ContourError>() {
            use mint_contour::ContourError as C;
            match c {
                C::Mesh(e) => return io_kind(e),
                C::Io { .. } => return ErrorKind::Io,
                C::Profile(_) | C::Dicom(_) | C::Input { .. } => return ErrorKind::Input,
                _ => {}
            }
        }
        if let Some(v) = cause.downcast_ref::<mint_volume::VolumeError>() {
            return volume_kind(v);
        }
        if cause.downcast_ref::<mint_mesh::MeshError>().is_some() {
            return ErrorKind::Input;
        }
        if cause.downcast_ref::<std::io::Error>().is_some() {
            return ErrorKind::Io;
        }
    }
    ErrorKind::Other
}

fn io_kind(e: &mint_io::Error) -> ErrorKind {
    match e.kind() {
        mint_io::error::ErrorKind::Io => ErrorKind::Io,
        _ => ErrorKind::Input,
    }
}

/// A volume file's error: the operating system's, or the file's (a bad
/// header or data, an unsupported variant, a bad request).
fn volume_kind(v: &mint_volume::VolumeError) -> ErrorKind {
    match v.kind() {
        mint_volume::VolumeErrorKind::Io => ErrorKind::Io,
        _ => ErrorKind::Input,
    }
}

fn pipeline_kind(p: &mint_pipeline::PipelineError) -> Option<ErrorKind> {
    use mint_pipeline::PipelineError as P;
    match p {
        P::Io(e) => Some(io_kind(e)),
        P::Store(_) => Some(ErrorKind::Io),
        P::Budget { .. } => Some(ErrorKind::Budget),
        P::Temp { .. } => Some(ErrorKind::Io),
        P::InFile { source, .. } => pipeline_kind(source),
        P::Volume(v) => Some(volume_kind(v)),
        P::NonFinite { .. } | P::NonFiniteResult { .. } | P::TransformOverflow { .. } | P::Empty { .. } | P::Unbounded { .. } | P::Scene(_) | P::Grid { .. } => Some(ErrorKind::Input),
        _ => None,
    }
}

/// Runs the `mint` command line with these arguments (`argv[0]` is the
/// program name) and returns its exit status: the binary's `main`, and the
/// `mint` command that the Python wheel installs. `--help`, `--version` and
/// usage errors exit the process from here, as clap does.
pub fn exit_status(argv: Vec<std::ffi::OsString>) -> u8 {
    let cli = crate::cli::Cli::parse_from(argv);
    crate::progress::install_ctrlc();
    status_of(crate::cli::run(cli))
}

/// The exit status of a command's result, printing the error as one line.
fn status_of(result: anyhow::Result<()>) -> u8 {
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("mint: error: {}", one_line(&e));
            if crate::progress::interrupted() {
                130
            } else {
                1
            }
        }
    }
}

/// An error and its causes on one line (a cause already quoted is not
/// repeated).
fn one_line(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    msg.replace('\n', " ")
}
