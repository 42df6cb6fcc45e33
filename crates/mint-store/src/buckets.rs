//! Bucketed spill: the one place where mint distributes fixed-size records
//! into numbered buckets under a memory budget and reads each bucket back.
//!
//! This is the distribution step of an external sort (Lindstrom & Silva
//! 2001 dereference a mesh this way; `mint check` groups edges this way).
//! [`Buckets::push`] appends a record to bucket `b` in memory; when the
//! buffers' allocated capacity reaches the budget, every bucket's buffer is
//! appended to its own file in the spill directory and freed, so disk is
//! touched only when the records do not fit, and the budget bounds what is
//! allocated, not just what is used. [`Buckets::finish`] turns the writer into a
//! [`BucketReader`], which hands each bucket's records back in push order,
//! in batches, so a bucket larger than memory is never held whole.
//! [`Buckets::take`] hands one finished bucket out while the others are
//! still being written, which frees its share of the budget.
//!
//! Files are plain concatenations of `R::SIZE`-byte records with no header;
//! they live only for one run, inside a directory the caller owns and
//! removes (the pipeline uses a `tempfile::TempDir`). Each bucket's file is
//! removed as soon as it has been read.

use crate::StoreError;
use std::fs::File;
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};

/// A fixed-size record that can be spilled.
pub trait Record: Copy + Send {
    /// Bytes per record on disk.
    const SIZE: usize;
    /// Appends the record's `SIZE` bytes (little-endian) to `out`.
    fn put(&self, out: &mut Vec<u8>);
    /// Reads a record from the first `SIZE` bytes of `b`.
    fn get(b: &[u8]) -> Self;
}

/// Records per batch handed out by [`BucketReader::read`].
const READ_BATCH: usize = 1 << 16;

/// Distributes records into buckets; see the module docs.
pub struct Buckets<R: Record> {
    dir: PathBuf,
    name: String,
    /// Per bucket: its full pages.
    buffers: Vec<Vec<Vec<R>>>,
    /// Per bucket: the page being filled (no capacity before the bucket's
    /// first record), kept apart so that a push reaches it in one step.
    open: Vec<Vec<R>>,
    spilled: Vec<u64>,
    /// Per bucket: how many times it was taken (part of its file's name,
    /// so that a taken file is never appended to).
    taken: Vec<u32>,
    /// Records per page (pages are allocated whole).
    page: usize,
    /// Records the allocated pages have room for, in all.
    held: usize,
    limit: usize,
    bytes_spilled: u64,
    scratch: Vec<u8>,
}

impl<R: Record> Buckets<R> {
    /// `n` buckets whose files are `DIR/NAME-BUCKET.bin`, with at most
    /// `budget` bytes of buffers allocated (at least a few KiB).
    pub fn new(dir: &Path, name: &str, n: usize, budget: u64) -> Buckets<R> {
        let n = n.max(1);
        let limit = (budget / std::mem::size_of::<R>().max(1) as u64).clamp(1024, usize::MAX as u64 / 2) as usize;
        // Small enough that every bucket can hold a few pages, and under
        // malloc's mmap threshold (128 KiB), so that freed pages are reused
        // from the heap instead of being unmapped and faulted in again.
        let page = (limit / (4 * n)).clamp(64, (64 << 10) / std::mem::size_of::<R>().max(1));
        Buckets {
            dir: dir.to_path_buf(),
            name: name.to_string(),
            buffers: (0..n).map(|_| Vec::new()).collect(),
            open: (0..n).map(|_| Vec::new()).collect(),
            spilled: vec![0; n],
            taken: vec![0; n],
            page,
            held: 0,
            limit,
            bytes_spilled: 0,
            scratch: Vec::new(),
        }
    }

    /// Number of buckets.
    pub fn len(&self) -> usize {
        self.buffers.len()
    }

    /// Always false: there is at least one bucket.
    pub fn is_empty(&self) -> bool {
        false
    }

    fn path(&self, b: usize) -> PathBuf {
        bucket_path(&self.dir, &self.name, b, self.taken[b])
    }

    /// Takes bucket `b`'s records so far out of the writer, to be read
    /// now (on any thread), and frees their memory from the budget. Later
    /// pushes to `b` start the bucket afresh.
    pub fn take(&mut self, b: usize) -> Bucket<R> {
        let file = (self.spilled[b] > 0).then(|| (self.path(b), self.spilled[b]));
        self.spilled[b] = 0;
        self.taken[b] += 1;
        let mut memory = std::mem::take(&mut self.buffers[b]);
        let open = std::mem::take(&mut self.open[b]);
        if open.capacity() > 0 {
            memory.push(open);
        }
        self.held -= memory.len() * self.page;
        Bucket { file, memory }
    }

    /// Appends `r` to bucket `b`.
    #[inline]
    pub fn push(&mut self, b: usize, r: R) -> Result<(), StoreError> {
        let page = &mut self.open[b];
        if page.len() < page.capacity() {
            page.push(r);
            return Ok(());
        }
        self.new_page_and_push(b, r)
    }

    /// [`Buckets::push`] when bucket `b` has no room: a new page, after
    /// spilling if the page would pass the budget.
    #[cold]
    fn new_page_and_push(&mut self, b: usize, r: R) -> Result<(), StoreError> {
        let full = std::mem::take(&mut self.open[b]);
        if full.capacity() > 0 {
            self.buffers[b].push(full);
        }
        if self.held + self.page > self.limit {
            self.spill()?;
        }
        let mut page = Vec::with_capacity(self.page);
        page.push(r);
        self.open[b] = page;
        self.held += self.page;
        Ok(())
    }

    /// Appends every bucket's pages to its file and frees them.
    fn spill(&mut self) -> Result<(), StoreError> {
        for b in 0..self.buffers.len() {
            let open = std::mem::take(&mut self.open[b]);
            if !open.is_empty() {
                self.buffers[b].push(open);
            }
            if self.buffers[b].is_empty() {
                continue;
            }
            let path = self.path(b);
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&path)
                .map_err(|source| StoreError::Io { path: path.clone(), op: "creating a spill file", source })?;
            for page in &self.buffers[b] {
                self.scratch.clear();
                for r in page {
                    r.put(&mut self.scratch);
                }
                f.write_all(&self.scratch).map_err(|source| StoreError::Io { path: path.clone(), op: "writing a spill file", source })?;
                self.spilled[b] += page.len() as u64;
                self.bytes_spilled += self.scratch.len() as u64;
            }
            self.buffers[b] = Vec::new();
        }
        self.held = 0;
        Ok(())
    }

    /// Stops writing; the records can now be read back bucket by bucket.
    pub fn finish(mut self) -> BucketReader<R> {
        for (pages, open) in self.buffers.iter_mut().zip(std::mem::take(&mut self.open)) {
            if !open.is_empty() {
                pages.push(open);
            }
        }
        BucketReader { dir: self.dir, name: self.name, buffers: self.buffers, spilled: self.spilled, taken: self.taken, bytes_spilled: self.bytes_spilled }
    }

    /// Bytes written to disk so far.
    pub fn bytes_spilled(&self) -> u64 {
        self.bytes_spilled
    }
}

fn bucket_path(dir: &Path, name: &str, b: usize, taken: u32) -> PathBuf {
    match taken {
        0 => dir.join(format!("{name}-{b:05}.bin")),
        t => dir.join(format!("{name}-{b:05}.{t}.bin")),
    }
}

/// Reads back what a [`Buckets`] wrote.
pub struct BucketReader<R: Record> {
    dir: PathBuf,
    name: String,
    buffers: Vec<Vec<Vec<R>>>,
    spilled: Vec<u64>,
    taken: Vec<u32>,
    bytes_spilled: u64,
}

impl<R: Record> BucketReader<R> {
    /// Number of buckets.
    pub fn len(&self) -> usize {
        self.buffers.len()
    }

    /// Always false: there is at least one bucket.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Bytes written to disk in all (0 when everything fitted in memory).
    pub fn bytes_spilled(&self) -> u64 {
        self.bytes_spilled
    }

    /// Records in bucket `b`.
    pub fn count(&self, b: usize) -> u64 {
        self.spilled[b] + self.buffers[b].iter().map(|p| p.len() as u64).sum::<u64>()
    }

    /// Calls `f` with bucket `b`'s records in push order, in batches, then
    /// frees the bucket (its memory and its file). A file shorter than the
    /// writer left it is reported as corrupt.
    pub fn read(&mut self, b: usize, f: impl FnMut(&[R])) -> Result<(), StoreError> {
        self.take(b).read(f)
    }

    /// Takes bucket `b` out of the reader, to be read elsewhere (another
    /// thread); the reader keeps an empty bucket in its place.
    pub fn take(&mut self, b: usize) -> Bucket<R> {
        let file = (self.spilled[b] > 0).then(|| (bucket_path(&self.dir, &self.name, b, self.taken[b]), self.spilled[b]));
        self.spilled[b] = 0;
        Bucket { file, memory: std::mem::take(&mut self.buffers[b]) }
    }
}

/// One bucket's records, taken from a [`BucketReader`].
pub struct Bucket<R: Record> {
    file: Option<(PathBuf, u64)>,
    memory: Vec<Vec<R>>,
}

impl<R: Record> Bucket<R> {
    /// The records, page by page in push order, when none of them is on
    /// disk; `None` when some are.
    pub fn pages(&self) -> Option<&[Vec<R>]> {
        self.file.is_none().then_some(&self.memory[..])
    }

    /// Calls `f` with the records in push order, in batches, then removes
    /// the bucket's file.
    pub fn read(self, mut f: impl FnMut(&[R])) -> Result<(), StoreError> {
        if let Some((path, count)) = self.file {
            let file = File::open(&path).map_err(|source| StoreError::Io { path: path.clone(), op: "opening a spill file", source })?;
            let mut rd = BufReader::with_capacity(1 << 20, file);
            let mut left = count;
            let mut bytes = vec![0u8; READ_BATCH * R::SIZE];
            let mut batch: Vec<R> = Vec::with_capacity(READ_BATCH);
            while left > 0 {
                let n = (left as usize).min(READ_BATCH);
                rd.read_exact(&mut bytes[..n * R::SIZE]).map_err(|e| match e.kind() {
                    std::io::ErrorKind::UnexpectedEof => StoreError::Corrupt { path: path.clone(), what: "the spill file is shorter than written".into() },
                    _ => StoreError::Io { path: path.clone(), op: "reading a spill file", source: e },
                })?;
                batch.clear();
                batch.extend(bytes[..n * R::SIZE].chunks_exact(R::SIZE).map(R::get));
                f(&batch);
                left -= n as u64;
            }
            drop(rd);
            std::fs::remove_file(&path).map_err(|source| StoreError::Io { path: path.clone(), op: "removing a spill file", source })?;
        }
        for page in self.memory {
            f(&page);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    struct Pair(u32, u64);

    impl Record for Pair {
        const SIZE: usize = 12;
        fn put(&self, out: &mut Vec<u8>) {
            out.extend_from_slice(&self.0.to_le_bytes());
            out.extend_from_slice(&self.1.to_le_bytes());
        }
        fn get(b: &[u8]) -> Self {
            Pair(u32::from_le_bytes(b[..4].try_into().unwrap()), u64::from_le_bytes(b[4..12].try_into().unwrap()))
        }
    }

    fn roundtrip(budget: u64) -> (Vec<Vec<Pair>>, u64) {
        let dir = tempfile::tempdir().unwrap();
        let mut w = Buckets::<Pair>::new(dir.path(), "t", 7, budget);
        let mut x = 12345u64;
        for i in 0..50_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            w.push((x >> 33) as usize % 7, Pair((x >> 40) as u32, i)).unwrap();
        }
        let mut r = w.finish();
        let spilled = r.bytes_spilled();
        let mut out = Vec::new();
        for b in 0..r.len() {
            let mut v = Vec::new();
            r.read(b, |batch| v.extend_from_slice(batch)).unwrap();
            out.push(v);
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "every spill file is removed once read");
        (out, spilled)
    }

    #[test]
    fn spilled_and_in_memory_buckets_read_back_the_same_records_in_push_order() {
        let (mem, s0) = roundtrip(1 << 30);
        let (disk, s1) = roundtrip(12 * 1024);
        assert_eq!(s0, 0);
        assert!(s1 > 0);
        assert_eq!(mem, disk);
        for b in &mem {
            assert!(b.windows(2).all(|w| w[0].1 < w[1].1), "push order is kept");
        }
        assert_eq!(mem.iter().map(Vec::len).sum::<usize>(), 50_000);
    }

    #[test]
    fn a_bucket_taken_while_writing_holds_what_was_pushed_and_frees_its_budget() {
        let dir = tempfile::tempdir().unwrap();
        // A budget of a few pages: bucket 0 spills, is taken, then refills.
        let mut w = Buckets::<Pair>::new(dir.path(), "t", 3, 24 * 1024);
        let mut first = Vec::new();
        for i in 0..20_000u64 {
            w.push((i % 3) as usize, Pair(7, i)).unwrap();
        }
        assert!(w.bytes_spilled() > 0);
        w.take(0).read(|batch| first.extend_from_slice(batch)).unwrap();
        assert_eq!(first, (0..20_000).filter(|i| i % 3 == 0).map(|i| Pair(7, i)).collect::<Vec<_>>());
        for i in 20_000..40_000u64 {
            w.push((i % 3) as usize, Pair(8, i)).unwrap();
        }
        let mut r = w.finish();
        let mut again = Vec::new();
        r.read(0, |batch| again.extend_from_slice(batch)).unwrap();
        assert_eq!(again, (20_000..40_000).filter(|i| i % 3 == 0).map(|i| Pair(8, i)).collect::<Vec<_>>());
        for b in 1..3 {
            let mut v = Vec::new();
            r.read(b, |batch| v.extend_from_slice(batch)).unwrap();
            assert_eq!(v.len(), (0..40_000).filter(|i| i % 3 == b as u64).count());
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "every spill file is removed once read");
    }

    #[test]
    fn a_truncated_spill_file_is_reported() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = Buckets::<Pair>::new(dir.path(), "t", 1, 0);
        for i in 0..5000 {
            w.push(0, Pair(1, i)).unwrap();
        }
        let mut r = w.finish();
        let f = dir.path().join("t-00000.bin");
        let len = std::fs::metadata(&f).unwrap().len();
        std::fs::OpenOptions::new().write(true).open(&f).unwrap().set_len(len - 5).unwrap();
        let e = r.read(0, |_| {}).unwrap_err();
        assert!(e.to_string().contains("shorter"), "{e}");
    }
}
