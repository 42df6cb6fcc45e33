//! [`AtomicFile`]: write a file under a temporary name beside its target,
//! then rename it into place. A reader of the target sees either the old
//! file or the complete new one, never a partial write; if the writer fails
//! or is dropped without [`AtomicFile::commit`], the temporary file is
//! removed and the target is untouched.
//!
//! The temporary file is named `.<target name>.mint-tmp<random>` in the
//! target's directory (the same file system, so the rename is atomic; the
//! repository's `.gitignore` ignores `*.mint-tmp*`). `commit` flushes the
//! data to disk (`fsync`) before the rename and syncs the directory after
//! it, so a crash leaves either the old or the new file.

use std::fs::{File, Permissions};
use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

use crate::error::Error;

/// A file written beside `target` and renamed onto it by [`commit`].
/// Dropping it uncommitted deletes the temporary file.
///
/// [`commit`]: AtomicFile::commit
#[derive(Debug)]
pub struct AtomicFile {
    target: PathBuf,
    temp: NamedTempFile,
}

impl AtomicFile {
    /// Creates the temporary file beside `path`. Fails (with the target
    /// named) if the directory does not exist or is not writable.
    pub fn create(path: &Path) -> Result<AtomicFile, Error> {
        let name = path
            .file_name()
            .ok_or_else(|| Error::io(path, "cannot create", io::Error::other("the path has no file name")))?;
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let prefix = format!(".{}.mint-tmp", name.to_string_lossy());
        let temp = tempfile::Builder::new()
            .prefix(&prefix)
            .permissions(default_permissions())
            .tempfile_in(&dir)
            .map_err(|e| Error::io(path, "cannot create a temporary file beside the output", e))?;
        Ok(AtomicFile { target: path.to_path_buf(), temp })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.target
    }

    /// The temporary path being written.
    pub fn temp_path(&self) -> &Path {
        self.temp.path()
    }

    /// The open temporary file.
    pub fn as_file_mut(&mut self) -> &mut File {
        self.temp.as_file_mut()
    }

    /// Syncs the data, renames the temporary file onto the target (replacing
    /// it) and syncs the directory. On failure the temporary file is removed.
    pub fn commit(self) -> Result<(), Error> {
        let AtomicFile { target, temp } = self;
        temp.as_file().sync_all().map_err(|e| Error::io(&target, "cannot flush the output to disk", e))?;
        temp.persist(&target).map_err(|e| Error::io(&target, "cannot rename the temporary file onto the output", e.error))?;
        if let Some(dir) = target.parent() {
            let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
            // Best effort: some file systems do not support syncing a directory.
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
        }
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.temp.as_file_mut().write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.temp.as_file_mut().write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.temp.as_file_mut().flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.temp.as_file_mut().seek(pos)
    }
}

/// rw for everyone, reduced by the process umask as for any new file
/// (tempfile's default would be owner-only).
#[cfg(unix)]
fn default_permissions() -> Permissions {
    use std::os::unix::fs::PermissionsExt;
    Permissions::from_mode(0o666)
}

#[cfg(not(unix))]
fn default_permissions() -> Permissions {
    let f = tempfile::tempfile().and_then(|f| f.metadata());
    f.map(|m| m.permissions()).expect("a temporary file's permissions")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect()
    }

    #[test]
    fn commit_renames_and_drop_cleans_up() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.bin");
        let mut f = AtomicFile::create(&target).unwrap();
        assert!(f.temp_path().file_name().unwrap().to_string_lossy().starts_with(".out.bin.mint-tmp"));
        f.write_all(b"hello").unwrap();
        f.seek(SeekFrom::Start(0)).unwrap();
        f.write_all(b"J").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"Jello");
        assert_eq!(leftovers(dir.path()), vec!["out.bin".to_string()]);

        let mut g = AtomicFile::create(&target).unwrap();
        g.write_all(b"partial").unwrap();
        drop(g);
        assert_eq!(std::fs::read(&target).unwrap(), b"Jello");
        assert_eq!(leftovers(dir.path()), vec!["out.bin".to_string()]);
    }

    #[test]
    fn missing_directory_is_an_io_error_naming_the_target() {
        let e = AtomicFile::create(Path::new("/nonexistent-mint-dir/x.ply")).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Io);
        let s = e.to_string();
        assert!(s.starts_with("/nonexistent-mint-dir/x.ply: cannot create a temporary file"), "{s}");
        assert_eq!(s.lines().count(), 1);
    }
}
