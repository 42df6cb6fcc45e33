//! `mint_mesh._mint`, the Rust half of the Python package: it runs mint's
//! commands in this process through `mint_cli::embed::run_embedded` (the same
//! code, options and output bytes as the `mint` binary), and moves meshes
//! between numpy arrays and files with mint-io's one writer and one loader.
//! The Python half (`mint_mesh/__init__.py`) checks arguments, names
//! options and raises the typed exceptions.
//!
//! A command runs on a thread of its own while the calling thread, without
//! the GIL, waits for its progress reports and calls the Python callback,
//! and checks for signals every 50 ms: Ctrl-C sets the run's cancel flag,
//! the run stops as the command line's does (temporary files and partial
//! outputs removed), and the `KeyboardInterrupt` is raised then.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use mint_cli::embed::{EmbedError, ErrorKind};
use mint_cli::out::Hooks;
use crossbeam_channel as channel;
use numpy::{IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

enum Msg {
    Progress(String, u64, u64),
    Done(std::thread::Result<Result<mint_cli::out::Captured, EmbedError>>),
}

/// Runs one mint command line (without the program name). Returns
/// `(ok, kind, message, json_documents, warnings)`: `kind` is "usage",
/// "input", "io", "budget", "cancelled" or "other" when `ok` is false.
/// `progress(phase, done, total)` is called from this thread; returning
/// `False` stops the run; an exception it raises stops the run and is
/// raised here. Ctrl-C stops the run and raises `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (argv, progress=None))]
#[allow(clippy::type_complexity)]
fn run(py: Python<'_>, argv: Vec<String>, progress: Option<Py<PyAny>>) -> PyResult<(bool, String, String, Vec<String>, Vec<String>)> {
    let cancel = Arc::new(AtomicBool::new(false));
    let (tx, rx) = channel::unbounded::<Msg>();
    let report = progress.as_ref().map(|_| {
        let tx = tx.clone();
        Arc::new(move |phase: &str, done: u64, total: u64| {
            let _ = tx.send(Msg::Progress(phase.to_string(), done, total));
        }) as Arc<mint_cli::out::ProgressFn>
    });
    let hooks = Hooks { progress: report, cancel: cancel.clone() };
    let worker = std::thread::Builder::new()
        .name("mint-run".into())
        .spawn(move || {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| mint_cli::embed::run_embedded(&argv, hooks)));
            let _ = tx.send(Msg::Done(r));
        })
        .map_err(|e| PyRuntimeError::new_err(format!("mint: cannot start a thread: {e}")))?;
    // The first error raised on this side (Ctrl-C, the callback's own), and
    // whether the callback asked to stop.
    let mut raised: Option<PyErr> = None;
    let mut stopped_by_callback = false;
    let outcome = loop {
        match py.detach(|| rx.recv_timeout(Duration::from_millis(50))) {
            Ok(Msg::Done(r)) => break r,
            Ok(Msg::Progress(phase, done, total)) => {
                if let (Some(cb), None) = (&progress, &raised) {
                    if !cancel.load(Ordering::SeqCst) {
                        match cb.call1(py, (phase, done, total)) {
                            Ok(v) => {
                                if v.bind(py).is(&*pyo3::types::PyBool::new(py, false)) {
                                    stopped_by_callback = true;
                                    cancel.store(true, Ordering::SeqCst);
                                }
                            }
                            Err(e) => {
                                raised = Some(e);
                                cancel.store(true, Ordering::SeqCst);
                            }
                        }
                    }
                }
            }
            Err(channel::RecvTimeoutError::Timeout) => {}
            Err(channel::RecvTimeoutError::Disconnected) => {
                break Err(Box::new("the run's thread ended without a result") as Box<dyn std::any::Any + Send>);
            }
        }
        if raised.is_none() {
            if let Err(e) = py.check_signals() {
                raised = Some(e);
                cancel.store(true, Ordering::SeqCst);
            }
        }
    };
    let _ = worker.join();
    if let Some(e) = raised {
        return Err(e);
    }
    let s = |x: &str| x.to_string();
    Ok(match outcome {
        Err(panic) => {
            let what = panic.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| panic.downcast_ref::<String>().cloned()).unwrap_or_default();
            (false, s("other"), format!("internal error (please report it): {what}"), vec![], vec![])
        }
        Ok(Ok(c)) => (true, String::new(), String::new(), c.json.iter().map(|v| v.to_string()).collect(), c.warnings),
        Ok(Err(EmbedError::Usage(m))) => (false, s("usage"), m, vec![], vec![]),
        Ok(Err(EmbedError::Cancelled(m))) => {
            let m = if stopped_by_callback { "stopped by the progress callback; no output written".to_string() } else { m };
            (false, s("cancelled"), m, vec![], vec![])
        }
        Ok(Err(EmbedError::Failed { message, kind })) => {
            let k = match kind {
                ErrorKind::Input => "input",
                ErrorKind::Io => "io",
                ErrorKind::Budget => "budget",
                ErrorKind::Other => "other",
            };
            (false, s(k), message, vec![], vec![])
        }
    })
}

/// The `mint` command line with these arguments (`argv[0]` is the program
/// name); returns its exit status. For the `mint` script the wheel installs.
#[pyfunction]
fn cli_main(py: Python<'_>, argv: Vec<String>) -> u8 {
    py.detach(|| mint_cli::embed::exit_status(argv.into_iter().map(Into::into).collect()))
}

/// A mesh file, whole: `(vertices float64 (N, 3), faces int64 (M, 3),
/// colours uint8 (N, 4) or None)`. Polygons are fanned into triangles.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>, Option<Bound<'py, PyArray2<u8>>>)> {
    let read = py.detach(|| -> Result<_, mint_io::Error> {
        let whole = mint_io::read_mesh_with(&path, mint_io::ReadOptions::default(), || true)?;
        let colours = mint_io::read_vertex_colours(&path)?;
        let v = flatten(whole.positions);
        let f: Vec<i64> = whole.faces.iter().flatten().map(|&i| i as i64).collect();
        let c: Option<Vec<u8>> = colours.map(|c| c.into_iter().flatten().collect());
        Ok((v, f, c))
    });
    let (v, f, c) = read.map_err(|e| mint_error(py, "input", &e.to_string()))?;
    let (nv, nf) = (v.len() / 3, f.len() / 3);
    let v = v.into_pyarray(py).reshape([nv, 3])?;
    let f = f.into_pyarray(py).reshape([nf, 3])?;
    let c = match c {
        Some(c) => Some(c.into_pyarray(py).reshape([nv, 4])?),
        None => None,
    };
    Ok((v, f, c))
}

/// Writes a binary PLY (vertices as doubles, or floats when given float32;
/// colours as RGBA bytes when given) through mint-io's writer: beside the
/// target, renamed into place when complete. The Python side has checked
/// shapes, finiteness and index ranges.
#[pyfunction]
#[pyo3(signature = (path, vertices, faces, colors=None))]
fn write_ply(py: Python<'_>, path: PathBuf, vertices: &Bound<'_, PyAny>, faces: &Bound<'_, PyAny>, colors: Option<PyReadonlyArray2<'_, u8>>) -> PyResult<()> {
    enum V<'a> {
        F64(&'a [f64]),
        F32(&'a [f32]),
    }
    enum F<'a> {
        I64(&'a [i64]),
        I32(&'a [i32]),
        U32(&'a [u32]),
    }
    let (v64, v32) = (vertices.extract::<PyReadonlyArray2<f64>>().ok(), vertices.extract::<PyReadonlyArray2<f32>>().ok());
    let (f64_, f32_, fu32) = (faces.extract::<PyReadonlyArray2<i64>>().ok(), faces.extract::<PyReadonlyArray2<i32>>().ok(), faces.extract::<PyReadonlyArray2<u32>>().ok());
    let bad = |what: &str| pyo3::exceptions::PyValueError::new_err(format!("{what} must be a C-contiguous (N, 3) array"));
    let vs = match (&v64, &v32) {
        (Some(a), _) => V::F64(a.as_slice().map_err(|_| bad("vertices"))?),
        (_, Some(a)) => V::F32(a.as_slice().map_err(|_| bad("vertices"))?),
        _ => return Err(bad("vertices (float32 or float64)")),
    };
    let fs = match (&f64_, &f32_, &fu32) {
        (Some(a), _, _) => F::I64(a.as_slice().map_err(|_| bad("faces"))?),
        (_, Some(a), _) => F::I32(a.as_slice().map_err(|_| bad("faces"))?),
        (_, _, Some(a)) => F::U32(a.as_slice().map_err(|_| bad("faces"))?),
        _ => return Err(bad("faces (int32, int64 or uint32)")),
    };
    let cs: Option<(&[u8], usize)> = match &colors {
        Some(c) => Some((c.as_slice().map_err(|_| bad("colors"))?, c.shape()[1])),
        None => None,
    };
    let result = py.detach(|| -> Result<(), mint_io::Error> {
        let double = matches!(vs, V::F64(_));
        let opts = mint_io::WriteOptions { double, colours: cs.is_some(), ..Default::default() };
        let mut w = mint_io::MeshWriter::create(&path, mint_io::Format::Ply, opts)?;
        match (vs, cs) {
            (V::F64(a), None) => w.write_vertices(triples(a))?,
            (vs, cs) => {
                // Converted a chunk at a time (float32, or with colours).
                let n = match vs {
                    V::F64(a) => a.len() / 3,
                    V::F32(a) => a.len() / 3,
                };
                let mut chunk: Vec<[f64; 3]> = Vec::with_capacity(CHUNK.min(n));
                for start in (0..n).step_by(CHUNK) {
                    let end = (start + CHUNK).min(n);
                    chunk.clear();
                    chunk.extend((start..end).map(|i| match vs {
                        V::F64(a) => [a[3 * i], a[3 * i + 1], a[3 * i + 2]],
                        V::F32(a) => [a[3 * i] as f64, a[3 * i + 1] as f64, a[3 * i + 2] as f64],
                    }));
                    match cs {
                        Some((c, k)) => {
                            for (i, p) in (start..end).zip(&chunk) {
                                let r = &c[k * i..k * i + k];
                                w.write_vertex_rgba(*p, [r[0], r[1], r[2], if k == 4 { r[3] } else { 255 }])?;
                            }
                        }
                        None => w.write_vertices(&chunk)?,
                    }
                }
            }
        }
        match fs {
            F::U32(a) => w.write_faces(triples(a))?,
            fs => {
                let m = match fs {
                    F::I64(a) => a.len() / 3,
                    F::I32(a) => a.len() / 3,
                    F::U32(a) => a.len() / 3,
                };
                let mut chunk: Vec<[u32; 3]> = Vec::with_capacity(CHUNK.min(m));
                for start in (0..m).step_by(CHUNK) {
                    chunk.clear();
                    // In range: the Python side checked 0 <= index < vertices.
                    chunk.extend((start..(start + CHUNK).min(m)).map(|t| match fs {
                        F::I64(a) => [a[3 * t] as u32, a[3 * t + 1] as u32, a[3 * t + 2] as u32],
                        F::I32(a) => [a[3 * t] as u32, a[3 * t + 1] as u32, a[3 * t + 2] as u32],
                        F::U32(a) => [a[3 * t], a[3 * t + 1], a[3 * t + 2]],
                    }));
                    w.write_faces(&chunk)?;
                }
            }
        }
        w.finish()?;
        Ok(())
    });
    result.map_err(|e| mint_error(py, if e.kind() == mint_io::error::ErrorKind::Io { "io" } else { "input" }, &e.to_string()))
}

/// `v`'s triples as one flat vector, without copying.
fn flatten(v: Vec<[f64; 3]>) -> Vec<f64> {
    let mut v = std::mem::ManuallyDrop::new(v);
    let (ptr, len, cap) = (v.as_mut_ptr(), v.len(), v.capacity());
    // SAFETY: the allocation held `cap` triples of f64 with f64's alignment;
    // it now holds `3 cap` f64, of which the first `3 len` are initialised.
    unsafe { Vec::from_raw_parts(ptr.cast::<f64>(), 3 * len, 3 * cap) }
}

/// Records converted at a time when the arrays' type is not the writer's.
const CHUNK: usize = 1 << 16;

/// `a` (3 n values, C order) as n triples, in place.
fn triples<T>(a: &[T]) -> &[[T; 3]] {
    // SAFETY: `[T; 3]` has `T`'s alignment and three `T`s' size, and the
    // length is a whole number of triples (the arrays are (n, 3)).
    unsafe { std::slice::from_raw_parts(a.as_ptr().cast::<[T; 3]>(), a.len() / 3) }
}

/// A PNG file as a uint8 array (H, W, 3) (or (H, W, 4) with alpha).
#[pyfunction]
fn read_png<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, numpy::PyArray3<u8>>> {
    let decoded = py.detach(|| -> Result<(Vec<u8>, usize, usize, usize), String> {
        let file = std::fs::File::open(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
        decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = decoder.read_info().map_err(|e| format!("{}: {e}", path.display()))?;
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).map_err(|e| format!("{}: {e}", path.display()))?;
        let k = info.color_type.samples();
        buf.truncate(info.height as usize * info.width as usize * k);
        Ok((buf, info.height as usize, info.width as usize, k))
    });
    let (buf, h, w, k) = decoded.map_err(|m| mint_error(py, "input", &m))?;
    Ok(buf.into_pyarray(py).reshape([h, w, k])?)
}

/// The exception class of `kind` from `mint_mesh._errors`, with `message`.
fn mint_error(py: Python<'_>, kind: &str, message: &str) -> PyErr {
    match py.import("mint_mesh._errors").and_then(|m| m.getattr("error_of")).and_then(|f| f.call1((kind, message))) {
        Ok(e) => PyErr::from_value(e),
        Err(e) => e,
    }
}

#[pymodule]
fn _mint(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_ply, m)?)?;
    m.add_function(wrap_pyfunction!(read_png, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
