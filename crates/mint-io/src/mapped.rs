//! Read-only byte views of whole files, the only place mint-io memory-maps.
//!
//! [`Mapped::open`] maps an input file; [`SpillFile`] collects values that a
//! reader must be able to fetch by index later (vertex positions parsed from
//! text, for example) in an anonymous temporary file, and
//! [`SpillFile::into_mapped`] maps it. Mapping keeps positions off the heap:
//! the kernel pages them in and out, so memory use does not grow with the
//! mesh and RLIMIT_DATA does not count them.
//!
//! Mapping is an explicit choice with a fallback: when a file cannot be
//! mapped (a pipe, a special file, a file system without mmap), its bytes are
//! streamed into an anonymous temporary file which is mapped instead, so
//! memory still does not scale with the file.

use std::fs::File;
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use memmap2::{Advice, Mmap};

use crate::error::Error;

/// A read-only mapping of a whole file (possibly empty).
#[derive(Debug)]
pub(crate) struct Mapped {
    map: Option<Mmap>,
}

impl Mapped {
    /// Maps the file at `path` read-only. If mapping fails or the path is not
    /// a regular file, copies the stream into an anonymous temporary file in
    /// `spill_dir` and maps that.
    pub(crate) fn open(path: &Path, spill_dir: &Path) -> Result<Mapped, Error> {
        let mut file = File::open(path).map_err(|e| Error::io(path, "cannot open for reading", e))?;
        let meta = file.metadata().map_err(|e| Error::io(path, "cannot stat", e))?;
        if meta.is_dir() {
            return Err(Error::io(path, "cannot read", io::Error::other("is a directory")));
        }
        if meta.is_file() {
            if meta.len() == 0 {
                return Ok(Mapped { map: None });
            }
            // SAFETY: mapping a file is only sound while nobody truncates or
            // rewrites it under us. mint treats its inputs as immutable for
            // the duration of a read: it maps them read-only and never writes
            // them, and outputs are always written to a fresh temporary file
            // and renamed (see `AtomicFile`), so mint itself never modifies a
            // mapped file. Another process truncating an input while it is
            // being read can still make the process fault (SIGBUS); this is
            // the documented trade-off of memory-mapped input, as in ripgrep.
            if let Ok(map) = unsafe { Mmap::map(&file) } {
                return Ok(Mapped { map: Some(map) });
            }
        }
        // Fallback: stream into an anonymous temporary file and map that.
        let mut spill = SpillFile::new(spill_dir, path)?;
        let mut buf = vec![0u8; 1 << 20];
        loop {
            let n = match file.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(Error::io(path, "cannot read", e)),
            };
            spill.write_bytes(&buf[..n])?;
        }
        spill.into_mapped()
    }

    /// A view of nothing.
    pub(crate) fn empty() -> Mapped {
        Mapped { map: None }
    }

    /// The bytes of the file.
    #[inline]
    pub(crate) fn bytes(&self) -> &[u8] {
        match &self.map {
            Some(m) => m,
            None => &[],
        }
    }

    /// Tells the kernel that `range` will be read front to back (read ahead
    /// aggressively). Advice is a hint: failures are ignored.
    pub(crate) fn advise_sequential(&self, start: usize, len: usize) {
        self.advise(Advice::Sequential, start, len);
    }

    /// Tells the kernel that `range` will be needed soon.
    pub(crate) fn advise_willneed(&self, start: usize, len: usize) {
        self.advise(Advice::WillNeed, start, len);
    }

    fn advise(&self, advice: Advice, start: usize, len: usize) {
        if let Some(m) = &self.map {
            let start = start.min(m.len());
            let len = len.min(m.len() - start);
            if len > 0 {
                let _ = m.advise_range(advice, start, len);
            }
        }
    }
}

/// An anonymous temporary file being filled with bytes, to be mapped once
/// complete. The file has no name (it is unlinked at creation), so nothing
/// else can open it and it disappears when the last handle or mapping goes.
pub(crate) struct SpillFile {
    out: BufWriter<File>,
    /// The input the spill belongs to, for error messages.
    about: PathBuf,
    dir: PathBuf,
    len: u64,
}

impl SpillFile {
    /// Creates an anonymous temporary file in `dir`; errors name `about`
    /// (the input being read) and `dir`.
    pub(crate) fn new(dir: &Path, about: &Path) -> Result<SpillFile, Error> {
        let file = tempfile::tempfile_in(dir).map_err(|e| {
            Error::io(about, &format!("cannot create a spill file in '{}'", dir.display()), e)
        })?;
        Ok(SpillFile { out: BufWriter::with_capacity(1 << 20, file), about: about.to_path_buf(), dir: dir.to_path_buf(), len: 0 })
    }

    #[inline]
    pub(crate) fn write_bytes(&mut self, b: &[u8]) -> Result<(), Error> {
        self.len += b.len() as u64;
        self.out.write_all(b).map_err(|e| self.err(e))
    }

    /// Appends three little-endian f64.
    #[inline]
    pub(crate) fn write_point(&mut self, p: [f64; 3]) -> Result<(), Error> {
        let mut b = [0u8; 24];
        b[0..8].copy_from_slice(&p[0].to_le_bytes());
        b[8..16].copy_from_slice(&p[1].to_le_bytes());
        b[16..24].copy_from_slice(&p[2].to_le_bytes());
        self.write_bytes(&b)
    }

    /// Bytes written so far.
    pub(crate) fn len(&self) -> u64 {
        self.len
    }

    fn err(&self, e: io::Error) -> Error {
        Error::io(&self.about, &format!("cannot write the spill file in '{}'", self.dir.display()), e)
    }

    /// Flushes and maps the file.
    pub(crate) fn into_mapped(self) -> Result<Mapped, Error> {
        let about = self.about.clone();
        let dir = self.dir.clone();
        let file = self.out.into_inner().map_err(|e| {
            Error::io(&about, &format!("cannot write the spill file in '{}'", dir.display()), e.into_error())
        })?;
        if self.len == 0 {
            return Ok(Mapped { map: None });
        }
        // SAFETY: the spill file is anonymous (unlinked at creation), so no
        // other process can open it, and we own the only handle; nothing
        // writes to it after this point.
        let map = unsafe { Mmap::map(&file) }
            .map_err(|e| Error::io(&about, &format!("cannot map the spill file in '{}'", dir.display()), e))?;
        Ok(Mapped { map: Some(map) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spill_round_trip_and_empty() {
        let dir = std::env::temp_dir();
        let mut s = SpillFile::new(&dir, Path::new("x")).unwrap();
        s.write_point([1.0, -2.5, 3.25]).unwrap();
        assert_eq!(s.len(), 24);
        let m = s.into_mapped().unwrap();
        assert_eq!(f64::from_le_bytes(m.bytes()[8..16].try_into().unwrap()), -2.5);
        let e = SpillFile::new(&dir, Path::new("x")).unwrap().into_mapped().unwrap();
        assert!(e.bytes().is_empty());
    }

    #[test]
    fn missing_file_is_io_error_naming_it() {
        let e = Mapped::open(Path::new("/nonexistent/mint/q.ply"), &std::env::temp_dir()).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Io);
        assert!(e.to_string().starts_with("/nonexistent/mint/q.ply: cannot open for reading"));
    }
}
