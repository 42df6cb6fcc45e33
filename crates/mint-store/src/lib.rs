//! The on-disk intercept store.
//!
//! During discretization every [`Intercept`] is appended to one *shard* file
//! chosen by its slab-axis plane: shard `b` holds planes
//! `b * planes_per_shard .. (b + 1) * planes_per_shard`. Shards are plain
//! concatenations of 16-byte little-endian records in arrival order (the
//! format is in docs/FORMATS.md); order inside a shard does not matter
//! because every reader sorts by [`Intercept::sort_key`]. The store also
//! counts records per plane, which is what the slab planner needs to size
//! slabs to the memory budget before any shard is read back.
//!
//! Reading a plane range streams the shards that overlap it and keeps only
//! the records in range, so memory follows what is kept, not shard size.
//!
//! All files live in one temporary directory under the caller's temp root; it
//! is deleted when the [`ShardStore`] is dropped, on success, error or
//! cancellation alike.

use mint_core::intercept::FAMILY_S;
use mint_core::Intercept;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// Most shard files open at once while writing.
pub const MAX_SHARDS: u32 = 256;
const RECORD: usize = 16;
const WRITE_BUFFER: usize = 64 * 1024;

/// Store failures; each names the file involved.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// Creating, writing or reading a shard failed (full disk, permissions…).
    #[error("{path}: {op}: {source}")]
    Io { path: PathBuf, op: &'static str, source: std::io::Error },
    /// A shard's length is not a whole number of records: it was truncated
    /// or changed by another process while mint ran.
    #[error("{path}: shard length {len} is not a multiple of {RECORD} bytes (truncated or modified during the run)")]
    Corrupt { path: PathBuf, len: u64 },
}

fn io_err<'a>(path: &'a Path, op: &'static str) -> impl FnOnce(std::io::Error) -> StoreError + 'a {
    move |source| StoreError::Io { path: path.to_path_buf(), op, source }
}

/// The shards of one run, with per-plane record counts.
pub struct ShardStore {
    dir: tempfile::TempDir,
    planes: u32,
    planes_per_shard: u32,
    writers: Vec<Option<BufWriter<File>>>,
    counts: Vec<u64>,
    bytes_written: u64,
}

impl ShardStore {
    /// Creates an empty store for `planes` slab-axis planes in a new
    /// temporary directory under `tmp_root`.
    pub fn create(tmp_root: &Path, planes: u32) -> Result<ShardStore, StoreError> {
        let dir = tempfile::Builder::new()
            .prefix(".mint-shards-")
            .tempdir_in(tmp_root)
            .map_err(io_err(tmp_root, "creating the shard directory"))?;
        let planes = planes.max(1);
        let planes_per_shard = planes.div_ceil(MAX_SHARDS);
        let shards = planes.div_ceil(planes_per_shard);
        Ok(ShardStore {
            dir,
            planes,
            planes_per_shard,
            writers: (0..shards).map(|_| None).collect(),
            counts: vec![0; planes as usize],
            bytes_written: 0,
        })
    }

    /// The temporary directory holding the shards.
    pub fn dir(&self) -> &Path {
        self.dir.path()
    }

    fn shard_path(&self, shard: u32) -> PathBuf {
        self.dir.path().join(format!("shard-{shard:05}.bin"))
    }

    /// Appends records (any planes, any order).
    pub fn append(&mut self, records: &[Intercept]) -> Result<(), StoreError> {
        for r in records {
            debug_assert!(r.plane < self.planes);
            let shard = r.plane / self.planes_per_shard;
            if self.writers[shard as usize].is_none() {
                let path = self.shard_path(shard);
                let f = File::create(&path).map_err(io_err(&path, "creating a shard"))?;
                self.writers[shard as usize] = Some(BufWriter::with_capacity(WRITE_BUFFER, f));
            }
            let w = self.writers[shard as usize].as_mut().unwrap();
            if let Err(e) = w.write_all(&r.to_le_bytes()) {
                let path = self.shard_path(shard);
                return Err(io_err(&path, "writing a shard")(e));
            }
            self.counts[r.plane as usize] += 1;
        }
        self.bytes_written += (records.len() * RECORD) as u64;
        Ok(())
    }

    /// Flushes and closes all shard writers. Call before reading.
    pub fn finish_writing(&mut self) -> Result<(), StoreError> {
        for shard in 0..self.writers.len() {
            if let Some(mut w) = self.writers[shard].take() {
                let path = self.shard_path(shard as u32);
                w.flush().map_err(io_err(&path, "writing a shard"))?;
            }
        }
        Ok(())
    }

    /// Records stored per plane (families A, B of plane k and S of layer k).
    pub fn plane_counts(&self) -> &[u64] {
        &self.counts
    }

    /// Total bytes appended.
    pub fn bytes_written(&self) -> u64 {
        self.bytes_written
    }

    /// Reads planes `first ..= last` into one vector per plane (unsorted).
    /// For the last plane, only family-A and -B records are kept when
    /// `boundary_last` is set (the slab above owns its layer).
    pub fn read_planes(&self, first: u32, last: u32, boundary_last: bool) -> Result<Vec<Vec<Intercept>>, StoreError> {
        let mut out: Vec<Vec<Intercept>> = (first..=last)
            .map(|k| {
                let n = self.counts.get(k as usize).copied().unwrap_or(0);
                Vec::with_capacity(n as usize)
            })
            .collect();
        if first >= self.planes {
            return Ok(out);
        }
        let last_in = last.min(self.planes - 1);
        let mut buf = vec![0u8; 1 << 20];
        for shard in first / self.planes_per_shard..=last_in / self.planes_per_shard {
            let path = self.shard_path(shard);
            let file = match File::open(&path) {
                Ok(f) => f,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue, // never written: empty
                Err(e) => return Err(io_err(&path, "opening a shard")(e)),
            };
            let len = file.metadata().map_err(io_err(&path, "reading a shard"))?.len();
            if len % RECORD as u64 != 0 {
                return Err(StoreError::Corrupt { path, len });
            }
            let mut reader = BufReader::with_capacity(1 << 16, file);
            let mut remaining = len as usize;
            while remaining > 0 {
                let n = remaining.min(buf.len());
                reader.read_exact(&mut buf[..n]).map_err(io_err(&path, "reading a shard"))?;
                remaining -= n;
                for rec in buf[..n].chunks_exact(RECORD) {
                    let r = Intercept::from_le_bytes(rec);
                    if r.plane < first || r.plane > last {
                        continue;
                    }
                    if boundary_last && r.plane == last && r.family() == FAMILY_S {
                        continue;
                    }
                    out[(r.plane - first) as usize].push(r);
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mint_core::intercept::{FAMILY_A, FAMILY_B};

    #[test]
    fn records_come_back_by_plane_and_the_directory_is_removed() {
        let root = tempfile::tempdir().unwrap();
        let dir;
        {
            let mut s = ShardStore::create(root.path(), 1000).unwrap();
            dir = s.dir().to_path_buf();
            let mut recs = Vec::new();
            for k in 0..1000u32 {
                for fam in [FAMILY_A, FAMILY_B, FAMILY_S] {
                    recs.push(Intercept::new(k, fam, k % 7, 1.5 + k as f64, k % 2 == 0));
                }
            }
            s.append(&recs).unwrap();
            s.finish_writing().unwrap();
            assert_eq!(s.plane_counts().iter().sum::<u64>(), 3000);
            assert_eq!(s.plane_counts()[17], 3);
            let planes = s.read_planes(10, 20, true).unwrap();
            assert_eq!(planes.len(), 11);
            assert!(planes[..10].iter().all(|p| p.len() == 3));
            assert_eq!(planes[10].len(), 2, "boundary plane keeps A and B only");
            assert!(planes[3].iter().all(|r| r.plane == 13));
            let all = s.read_planes(0, 999, false).unwrap();
            assert_eq!(all.iter().map(|p| p.len()).sum::<usize>(), 3000);
            assert!(dir.exists());
        }
        assert!(!dir.exists(), "shard directory removed on drop");
    }

    #[test]
    fn a_truncated_shard_is_reported_with_its_path() {
        let root = tempfile::tempdir().unwrap();
        let mut s = ShardStore::create(root.path(), 4).unwrap();
        s.append(&[Intercept::new(1, FAMILY_A, 0, 1.5, true)]).unwrap();
        s.finish_writing().unwrap();
        let shard = std::fs::read_dir(s.dir()).unwrap().next().unwrap().unwrap().path();
        let f = std::fs::OpenOptions::new().write(true).open(&shard).unwrap();
        f.set_len(10).unwrap();
        let e = s.read_planes(0, 3, false).unwrap_err();
        assert!(e.to_string().contains("shard-"), "{e}");
    }
}
