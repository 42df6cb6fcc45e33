//! Where the merge steps ([`crate::zipper`], [`crate::consensus`],
//! [`crate::grid_merge`]) get their scans: a [`ScanSource`] hands out one
//! scan at a time, so those steps hold the growing model and one scan, not
//! every scan of the set.
//!
//! Two sources: a slice of scans already in memory (tests, library users),
//! and [`ScanFiles`], which loads the scans of a set file on demand and
//! keeps the most recently used ones while their estimated size stays
//! within a memory budget (a single scan larger than the budget is still
//! read, alone; during the first pass, which learns the scans' sizes, one
//! scan may come on top of the budget until the others are dropped). With a budget larger than the set, each scan is
//! read once; with a small one, scans are read again when needed (the
//! results are the same either way: sources only change when a scan is
//! read, never what it contains).

use crate::error::RangeError;
use crate::scan_mesh::{load_scan, MeshOptions, ScanMesh};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A scan borrowed from a slice or shared from a cache.
pub enum ScanRef<'a> {
    Borrowed(&'a ScanMesh),
    Shared(Arc<ScanMesh>),
}

impl std::ops::Deref for ScanRef<'_> {
    type Target = ScanMesh;
    fn deref(&self) -> &ScanMesh {
        match self {
            ScanRef::Borrowed(s) => s,
            ScanRef::Shared(s) => s,
        }
    }
}

/// Scans by index, one at a time.
pub trait ScanSource {
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The sampling distance of scan `i`, known without loading it again.
    fn sampling(&self, i: usize) -> f64;
    /// Scan `i`.
    fn scan(&self, i: usize) -> Result<ScanRef<'_>, RangeError>;
    /// The largest sampling distance (s of the merge tolerances).
    fn max_sampling(&self) -> f64 {
        (0..self.len()).map(|i| self.sampling(i)).fold(0.0, f64::max)
    }
}

impl ScanSource for [ScanMesh] {
    fn len(&self) -> usize {
        <[ScanMesh]>::len(self)
    }
    fn sampling(&self, i: usize) -> f64 {
        self[i].sampling
    }
    fn scan(&self, i: usize) -> Result<ScanRef<'_>, RangeError> {
        Ok(ScanRef::Borrowed(&self[i]))
    }
}

impl ScanSource for Vec<ScanMesh> {
    fn len(&self) -> usize {
        self.as_slice().len()
    }
    fn sampling(&self, i: usize) -> f64 {
        self[i].sampling
    }
    fn scan(&self, i: usize) -> Result<ScanRef<'_>, RangeError> {
        Ok(ScanRef::Borrowed(&self[i]))
    }
}

impl ScanMesh {
    /// Estimated heap bytes of this scan (its arrays).
    pub fn heap_bytes(&self) -> usize {
        let n = self.positions.len();
        let f = self.faces.len();
        n * (24 + 24 + 8 + 1) + f * (12 + 1 + 8) + self.levels.iter().map(|l| 4 * l.len()).sum::<usize>()
    }
}

/// The scans of a set file, loaded on demand within a memory budget.
pub struct ScanFiles {
    paths: Vec<PathBuf>,
    opts: MeshOptions,
    sampling: Vec<f64>,
    budget: usize,
    cache: Mutex<Cache>,
}

#[derive(Default)]
struct Cache {
    scans: Vec<Option<Arc<ScanMesh>>>,
    /// Estimated size of each scan once it has been read (0 before).
    sizes: Vec<usize>,
    last_used: Vec<u64>,
    clock: u64,
    bytes: usize,
    loads: usize,
    peak_bytes: usize,
}

impl ScanFiles {
    /// Checks that every scan of `set` can be opened (else
    /// [`RangeError::MissingScan`] naming the set file and line), then reads
    /// each once to learn its sampling distance, keeping what fits in
    /// `budget` bytes.
    pub fn open(set: &crate::ScanSet, set_path: &Path, opts: &MeshOptions, budget: usize) -> Result<ScanFiles, RangeError> {
        Self::open_with(set, set_path, opts, budget, &mint_core::progress::NoProgress)
    }

    /// [`ScanFiles::open`], reporting each scan read
    /// ([`crate::phases::LOAD_SCANS`](crate::phases::LOAD_SCANS)) and
    /// stopping with [`RangeError::Cancelled`] when asked.
    pub fn open_with(set: &crate::ScanSet, set_path: &Path, opts: &MeshOptions, budget: usize, progress: &dyn mint_core::progress::Progress) -> Result<ScanFiles, RangeError> {
        for e in &set.entries {
            if let Err(source) = std::fs::File::open(&e.path) {
                return Err(RangeError::MissingScan { set: set_path.to_path_buf(), line: e.line, scan: e.path.clone(), source });
            }
        }
        let n = set.entries.len();
        let mut files = ScanFiles {
            paths: set.entries.iter().map(|e| e.path.clone()).collect(),
            opts: opts.clone(),
            sampling: vec![0.0; n],
            budget,
            cache: Mutex::new(Cache { scans: vec![None; n], sizes: vec![0; n], last_used: vec![0; n], ..Default::default() }),
        };
        progress.start(crate::phases::LOAD_SCANS, n as u64);
        for i in 0..n {
            if progress.cancelled() {
                return Err(RangeError::Cancelled);
            }
            let s = files.scan(i)?.sampling;
            files.sampling[i] = s;
            progress.advance(1);
        }
        progress.finish();
        Ok(files)
    }

    /// How many times a scan file was read, and the largest estimated size
    /// of the scans held at once.
    pub fn loads(&self) -> (usize, usize) {
        let c = self.cache.lock().expect("the scan cache is never poisoned");
        (c.loads, c.peak_bytes)
    }
}

impl Cache {
    /// Drops the least recently used scans other than `keep` while more
    /// than `limit` bytes are held.
    fn evict(&mut self, keep: usize, limit: usize) {
        while self.bytes > limit {
            let victim = (0..self.scans.len()).filter(|&j| j != keep && self.scans[j].is_some()).min_by_key(|&j| self.last_used[j]);
            let Some(j) = victim else { break };
            self.scans[j] = None;
            self.bytes -= self.sizes[j];
        }
    }
}

impl ScanSource for ScanFiles {
    fn len(&self) -> usize {
        self.paths.len()
    }
    fn sampling(&self, i: usize) -> f64 {
        self.sampling[i]
    }
    fn scan(&self, i: usize) -> Result<ScanRef<'_>, RangeError> {
        let mut c = self.cache.lock().expect("the scan cache is never poisoned");
        c.clock += 1;
        let now = c.clock;
        c.last_used[i] = now;
        if let Some(s) = &c.scans[i] {
            return Ok(ScanRef::Shared(s.clone()));
        }
        // Make room first when the size is known (every read after the
        // first pass of `open`), so the budget holds with the new scan in.
        let known = c.sizes[i];
        c.evict(i, self.budget.saturating_sub(known));
        let scan = Arc::new(load_scan(&self.paths[i], &self.opts)?);
        c.loads += 1;
        c.sizes[i] = scan.heap_bytes();
        c.bytes += c.sizes[i];
        c.scans[i] = Some(scan.clone());
        c.peak_bytes = c.peak_bytes.max(c.bytes);
        c.evict(i, self.budget);
        Ok(ScanRef::Shared(scan))
    }
}
