//! The on-disk intercept store.
//!
//! During discretization every [`Intercept`] is appended by a
//! [`ShardWriter`] to one *shard* file chosen by its slab-axis plane: shard
//! `b` holds planes `b * planes_per_shard .. (b + 1) * planes_per_shard`.
//! Shards are plain concatenations of 16-byte little-endian records (20
//! bytes in a coloured store: the record, then its RGBA colour) in
//! arrival order (the format is in docs/FORMATS.md); order inside a shard
//! does not matter because every reader sorts by [`Intercept::sort_key`],
//! a total order. The writer counts records per plane and checksums every
//! shard (CRC-32); [`ShardWriter::finish`] returns both as a
//! [`ShardManifest`], which the caller stores beside the shards.
//!
//! A [`ShardSet`] reads plane ranges back from any number of such stores
//! (one per part of the input, written by different processes or machines),
//! streaming the shards that overlap the range, keeping only records in
//! range, and checking each shard's length and checksum against its
//! manifest, so a truncated or corrupted file is reported, never read as
//! data. Memory follows what is kept, not shard size.
//!
//! [`Budget`] hands out every share of a run's memory budget (`--mem`):
//! the buckets', the slabs', `check`'s.
//!
//! The store does not own its directory: the staged engine (mint-pipeline)
//! decides where shards live and when they are removed.

pub mod budget;
pub mod buckets;

pub use buckets::{Bucket, BucketReader, Buckets, Record};
pub use budget::{default_mem_bytes, Budget};
use mint_core::colour::{Rgba, Tinted, WHITE};
use mint_core::intercept::FAMILY_S;
use mint_core::Intercept;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// Most shard files per store.
pub const MAX_SHARDS: u32 = 256;
/// Bytes per stored record.
pub const RECORD: usize = 16;
/// Bytes per stored record in a coloured store (the record and its RGBA).
pub const COLOURED_RECORD: usize = 20;
const WRITE_BUFFER: usize = 64 * 1024;

/// Store failures; each names the file involved.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// Creating, writing or reading a shard failed (full disk, permissions…).
    #[error("{path}: {op}: {source}")]
    Io { path: PathBuf, op: &'static str, source: std::io::Error },
    /// A shard's length or checksum is not the one its writer recorded: it
    /// was truncated, damaged, or changed by another process. Fix: re-run
    /// the task that wrote it (remove its task directory first).
    #[error("{path}: {what} (the shard was truncated or damaged after it was written; re-run the task that wrote it)")]
    Corrupt { path: PathBuf, what: String },
}

fn io_err<'a>(path: &'a Path, op: &'static str) -> impl FnOnce(std::io::Error) -> StoreError + 'a {
    move |source| StoreError::Io { path: path.to_path_buf(), op, source }
}

/// One shard file as its writer left it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardFile {
    /// Shard number (its planes are `index * planes_per_shard ..`).
    pub index: u32,
    /// Length in bytes.
    pub len: u64,
    /// CRC-32 (IEEE) of the whole file.
    pub crc32: u32,
}

/// What a finished [`ShardWriter`] wrote: enough to read the shards back
/// and to check them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardManifest {
    /// Slab-axis planes covered (records have `plane < planes`).
    pub planes: u32,
    pub planes_per_shard: u32,
    /// Records per plane (families A and B of plane k, S of layer k).
    pub counts: Vec<u64>,
    /// The shard files that exist (shards never written are empty).
    pub shards: Vec<ShardFile>,
    /// Records carry their colour ([`COLOURED_RECORD`] bytes each).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub colour: bool,
}

impl ShardManifest {
    /// Checks what the manifest claims against the `planes` its grid has and
    /// the shape [`ShardWriter`] gives: the plane count, planes per shard,
    /// one count per plane, shards in order within range, lengths that are
    /// whole records. `Err` says what is wrong.
    pub fn validate(&self, planes: u32) -> Result<(), String> {
        let planes = planes.max(1);
        if self.planes != planes {
            return Err(format!("a shard manifest for {} planes, the grid has {planes}", self.planes));
        }
        let pps = planes.div_ceil(MAX_SHARDS);
        if self.planes_per_shard != pps {
            return Err(format!("{} planes per shard, {pps} expected", self.planes_per_shard));
        }
        if self.counts.len() != planes as usize {
            return Err(format!("{} plane counts for {planes} planes", self.counts.len()));
        }
        let shards = planes.div_ceil(pps);
        if !self.shards.windows(2).all(|w| w[0].index < w[1].index) || self.shards.iter().any(|s| s.index >= shards) {
            return Err(format!("shard numbers out of order or past {shards}"));
        }
        let record = self.record_bytes() as u64;
        if let Some(s) = self.shards.iter().find(|s| s.len % record != 0) {
            return Err(format!("shard {} of {} bytes, not whole records", s.index, s.len));
        }
        let total: u128 = self.counts.iter().map(|&c| c as u128).sum();
        if total * record as u128 != self.shards.iter().map(|s| s.len as u128).sum::<u128>() {
            return Err("plane counts that do not add up to the shards' records".into());
        }
        Ok(())
    }

    /// Bytes per record in this store's shards.
    pub fn record_bytes(&self) -> usize {
        if self.colour {
            COLOURED_RECORD
        } else {
            RECORD
        }
    }

    /// Total records.
    pub fn records(&self) -> u64 {
        self.counts.iter().sum()
    }
    /// Total bytes of the shard files.
    pub fn bytes(&self) -> u64 {
        self.shards.iter().map(|s| s.len).sum()
    }
}

/// The file name of shard `index`.
pub fn shard_name(index: u32) -> String {
    format!("shard-{index:05}.bin")
}

struct OpenShard {
    file: BufWriter<File>,
    crc: crc32fast::Hasher,
    len: u64,
}

/// The most bytes of records written and checksummed at once.
const RUN_BYTES: usize = 1 << 16;

/// What a [`ShardWriter`] held at one point ([`ShardWriter::checkpoint`]).
pub struct Checkpoint {
    shards: Vec<Option<(u64, crc32fast::Hasher)>>,
    counts: Vec<u64>,
}

/// Appends records to the shards of one store in an existing directory.
pub struct ShardWriter {
    dir: PathBuf,
    planes: u32,
    planes_per_shard: u32,
    open: Vec<Option<OpenShard>>,
    counts: Vec<u64>,
    colour: bool,
    /// The bytes of the run of records being appended.
    scratch: Vec<u8>,
}

impl ShardWriter {
    /// A writer of coloured records ([`COLOURED_RECORD`] bytes each) for
    /// `planes` planes into `dir`; records appended without a colour get
    /// [`WHITE`].
    pub fn create_coloured(dir: &Path, planes: u32) -> ShardWriter {
        ShardWriter { colour: true, ..ShardWriter::create(dir, planes) }
    }

    /// True when the records carry colour.
    pub fn coloured(&self) -> bool {
        self.colour
    }

    /// A writer for `planes` slab-axis planes into `dir` (which must exist).
    pub fn create(dir: &Path, planes: u32) -> ShardWriter {
        let planes = planes.max(1);
        let planes_per_shard = planes.div_ceil(MAX_SHARDS);
        let shards = planes.div_ceil(planes_per_shard);
        ShardWriter {
            dir: dir.to_path_buf(),
            planes,
            planes_per_shard,
            open: (0..shards).map(|_| None).collect(),
            counts: vec![0; planes as usize],
            colour: false,
            scratch: Vec::new(),
        }
    }

    /// Appends records (any planes below `planes`, any order); a coloured
    /// store gives them [`WHITE`].
    pub fn append(&mut self, records: &[Intercept]) -> Result<(), StoreError> {
        self.append_with(records, |_| WHITE)
    }

    /// Appends records with their colours (`colours[i]` is `records[i]`'s;
    /// an uncoloured store drops them).
    pub fn append_coloured(&mut self, records: &[Intercept], colours: &[Rgba]) -> Result<(), StoreError> {
        assert_eq!(records.len(), colours.len());
        self.append_with(records, |i| colours[i])
    }

    fn append_with(&mut self, records: &[Intercept], colour: impl Fn(usize) -> Rgba) -> Result<(), StoreError> {
        let record = if self.colour { COLOURED_RECORD } else { RECORD };
        // Runs of records bound for one shard are written and checksummed
        // at once (a checksum update per 16-byte record costs more than the
        // copy); the state after the call is the same.
        let mut run = std::mem::take(&mut self.scratch);
        let mut at = 0;
        while at < records.len() {
            let shard = (records[at].plane / self.planes_per_shard) as usize;
            run.clear();
            let mut end = at;
            while end < records.len() && (records[end].plane / self.planes_per_shard) as usize == shard && run.len() < RUN_BYTES {
                let r = &records[end];
                debug_assert!(r.plane < self.planes);
                run.extend_from_slice(&r.to_le_bytes());
                if self.colour {
                    run.extend_from_slice(&colour(end));
                }
                end += 1;
            }
            if self.open[shard].is_none() {
                let path = self.dir.join(shard_name(shard as u32));
                let f = File::create(&path).map_err(io_err(&path, "creating a shard"))?;
                self.open[shard] = Some(OpenShard { file: BufWriter::with_capacity(WRITE_BUFFER, f), crc: crc32fast::Hasher::new(), len: 0 });
            }
            let s = self.open[shard].as_mut().unwrap();
            if let Err(e) = s.file.write_all(&run) {
                let path = self.dir.join(shard_name(shard as u32));
                return Err(io_err(&path, "writing a shard")(e));
            }
            s.crc.update(&run);
            s.len += ((end - at) * record) as u64;
            for r in &records[at..end] {
                self.counts[r.plane as usize] += 1;
            }
            at = end;
        }
        self.scratch = run;
        Ok(())
    }

    /// A point to come back to with [`ShardWriter::rollback`]: what every
    /// shard and plane holds now.
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            shards: self.open.iter().map(|s| s.as_ref().map(|s| (s.len, s.crc.clone()))).collect(),
            counts: self.counts.clone(),
        }
    }

    /// Forgets every record appended since `cp` (a reader that found out
    /// late that it must start again another way): shards are cut back to
    /// their length then, and those opened since are removed.
    pub fn rollback(&mut self, cp: Checkpoint) -> Result<(), StoreError> {
        for (index, (s, was)) in self.open.iter_mut().zip(cp.shards).enumerate() {
            let path = self.dir.join(shard_name(index as u32));
            match (s.take(), was) {
                (None, _) => {}
                (Some(open), None) => {
                    drop(open.file.into_inner().map_err(|e| io_err(&path, "writing a shard")(e.into_error()))?);
                    std::fs::remove_file(&path).map_err(io_err(&path, "removing a shard"))?;
                }
                (Some(open), Some((len, crc))) => {
                    let f = open.file.into_inner().map_err(|e| io_err(&path, "writing a shard")(e.into_error()))?;
                    f.set_len(len).map_err(io_err(&path, "cutting a shard back"))?;
                    let mut f = f;
                    std::io::Seek::seek(&mut f, std::io::SeekFrom::Start(len)).map_err(io_err(&path, "cutting a shard back"))?;
                    *s = Some(OpenShard { file: BufWriter::with_capacity(WRITE_BUFFER, f), crc, len });
                }
            }
        }
        self.counts = cp.counts;
        Ok(())
    }

    /// Flushes and closes every shard; returns the manifest. (Syncing the
    /// shards to disk is the caller's: the engine's task commit does it.)
    pub fn finish(self) -> Result<ShardManifest, StoreError> {
        let mut shards = Vec::new();
        for (index, s) in self.open.into_iter().enumerate() {
            if let Some(s) = s {
                let path = self.dir.join(shard_name(index as u32));
                s.file.into_inner().map_err(|e| io_err(&path, "writing a shard")(e.into_error()))?;
                shards.push(ShardFile { index: index as u32, len: s.len, crc32: s.crc.finalize() });
            }
        }
        Ok(ShardManifest { planes: self.planes, planes_per_shard: self.planes_per_shard, counts: self.counts, shards, colour: self.colour })
    }
}

/// Several stores read as one: the records of a plane are those of every
/// store, in store order.
#[derive(Debug, Clone, Default)]
pub struct ShardSet {
    parts: Vec<(PathBuf, ShardManifest)>,
}

impl ShardSet {
    /// An empty set.
    pub fn new() -> ShardSet {
        ShardSet::default()
    }

    /// Adds the store in `dir` described by `manifest`.
    pub fn push(&mut self, dir: PathBuf, manifest: ShardManifest) {
        self.parts.push((dir, manifest));
    }

    /// Records per plane, summed over the stores (length: the most planes
    /// of any store).
    pub fn plane_counts(&self) -> Vec<u64> {
        let n = self.parts.iter().map(|(_, m)| m.counts.len()).max().unwrap_or(0);
        let mut c = vec![0u64; n];
        for (_, m) in &self.parts {
            for (a, b) in c.iter_mut().zip(&m.counts) {
                *a += b;
            }
        }
        c
    }

    /// Reads planes `first ..= last` into one vector per plane (unsorted).
    /// For the last plane, only family-A and -B records are kept when
    /// `boundary_last` is set (the slab above owns its layer).
    pub fn read_planes(&self, first: u32, last: u32, boundary_last: bool) -> Result<Vec<Vec<Intercept>>, StoreError> {
        self.read_planes_as(first, last, boundary_last, |r, _| r)
    }

    /// True when any store of the set holds colours.
    pub fn coloured(&self) -> bool {
        self.parts.iter().any(|(_, m)| m.colour)
    }

    /// [`ShardSet::read_planes`] with each record's colour ([`WHITE`] from
    /// stores without colour).
    pub fn read_planes_coloured(&self, first: u32, last: u32, boundary_last: bool) -> Result<Vec<Vec<Tinted>>, StoreError> {
        self.read_planes_as(first, last, boundary_last, |r, c| (r, c))
    }

    fn read_planes_as<T>(&self, first: u32, last: u32, boundary_last: bool, make: impl Fn(Intercept, Rgba) -> T) -> Result<Vec<Vec<T>>, StoreError> {
        let counts = self.plane_counts();
        let mut out: Vec<Vec<T>> =
            (first..=last).map(|k| Vec::with_capacity(counts.get(k as usize).copied().unwrap_or(0) as usize)).collect();
        let mut buf = vec![0u8; 1 << 20];
        for (dir, m) in &self.parts {
            if first >= m.planes {
                continue;
            }
            let last_in = last.min(m.planes - 1);
            let (s0, s1) = (first / m.planes_per_shard, last_in / m.planes_per_shard);
            // Records per plane as read, against the manifest's counts: a
            // shard whose checksum was made to match but whose records
            // were cut, added or moved to other planes is refused.
            let mut seen = vec![0u64; (last_in - first + 1) as usize];
            for shard in m.shards.iter().filter(|s| s.index >= s0 && s.index <= s1) {
                let path = dir.join(shard_name(shard.index));
                read_shard(&path, shard, m.record_bytes(), &mut buf, |r, c| {
                    if r.plane < first || r.plane > last {
                        return;
                    }
                    if r.plane <= last_in {
                        seen[(r.plane - first) as usize] += 1;
                    }
                    if boundary_last && r.plane == last && r.family() == FAMILY_S {
                        return;
                    }
                    out[(r.plane - first) as usize].push(make(r, c));
                })?;
            }
            for (i, &n) in seen.iter().enumerate() {
                let k = first + i as u32;
                let want = m.counts.get(k as usize).copied().unwrap_or(0);
                if n != want {
                    return Err(StoreError::Corrupt {
                        path: dir.join(shard_name(k / m.planes_per_shard)),
                        what: format!("plane {k} holds {n} records, its manifest says {want}"),
                    });
                }
            }
        }
        Ok(out)
    }
}

/// Streams one shard's records to `keep`, checking its length and checksum.
fn read_shard(path: &Path, want: &ShardFile, record: usize, buf: &mut [u8], mut keep: impl FnMut(Intercept, Rgba)) -> Result<(), StoreError> {
    let mut file = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(StoreError::Corrupt { path: path.to_path_buf(), what: "the shard is missing".into() })
        }
        Err(e) => return Err(io_err(path, "opening a shard")(e)),
    };
    let len = file.metadata().map_err(io_err(path, "reading a shard"))?.len();
    if len != want.len {
        return Err(StoreError::Corrupt { path: path.to_path_buf(), what: format!("{len} bytes, {} were written", want.len) });
    }
    let mut crc = crc32fast::Hasher::new();
    let mut remaining = len as usize;
    // Whole records per read.
    let size = buf.len() / record * record;
    while remaining > 0 {
        let n = remaining.min(size);
        file.read_exact(&mut buf[..n]).map_err(io_err(path, "reading a shard"))?;
        remaining -= n;
        crc.update(&buf[..n]);
        for rec in buf[..n].chunks_exact(record) {
            let colour = if record == COLOURED_RECORD { rec[RECORD..].try_into().unwrap() } else { WHITE };
            keep(Intercept::from_le_bytes(rec), colour);
        }
    }
    let got = crc.finalize();
    if got != want.crc32 {
        return Err(StoreError::Corrupt { path: path.to_path_buf(), what: format!("checksum {got:08x}, {:08x} was written", want.crc32) });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use mint_core::intercept::{FAMILY_A, FAMILY_B};

    fn records(planes: u32) -> Vec<Intercept> {
        let mut recs = Vec::new();
        for k in 0..planes {
            for fam in [FAMILY_A, FAMILY_B, FAMILY_S] {
                recs.push(Intercept::new(k, fam, k % 7, 1.5 + k as f64, k % 2 == 0));
            }
        }
        recs
    }

    #[test]
    fn records_come_back_by_plane_from_several_stores() {
        let root = tempfile::tempdir().unwrap();
        let mut set = ShardSet::new();
        let recs = records(1000);
        for (i, half) in recs.chunks(1500).enumerate() {
            let dir = root.path().join(format!("part-{i}"));
            std::fs::create_dir(&dir).unwrap();
            let mut w = ShardWriter::create(&dir, 1000);
            w.append(half).unwrap();
            let m = w.finish().unwrap();
            assert_eq!(m.records(), 1500);
            set.push(dir, m);
        }
        let counts = set.plane_counts();
        assert_eq!(counts.iter().sum::<u64>(), 3000);
        assert_eq!(counts[17], 3);
        let planes = set.read_planes(10, 20, true).unwrap();
        assert_eq!(planes.len(), 11);
        assert!(planes[..10].iter().all(|p| p.len() == 3));
        assert_eq!(planes[10].len(), 2, "boundary plane keeps A and B only");
        assert!(planes[3].iter().all(|r| r.plane == 13));
        let all = set.read_planes(0, 999, false).unwrap();
        assert_eq!(all.iter().map(|p| p.len()).sum::<usize>(), 3000);
    }

    #[test]
    fn coloured_records_come_back_with_their_colours_and_plain_stores_give_white() {
        let root = tempfile::tempdir().unwrap();
        let recs = records(300);
        let cols: Vec<Rgba> = (0..recs.len()).map(|i| [i as u8, (i >> 8) as u8, 7, 200]).collect();
        let (a, b) = (root.path().join("a"), root.path().join("b"));
        std::fs::create_dir(&a).unwrap();
        std::fs::create_dir(&b).unwrap();
        let mut w = ShardWriter::create_coloured(&a, 300);
        w.append_coloured(&recs[..600], &cols[..600]).unwrap();
        let ma = w.finish().unwrap();
        assert!(ma.colour && ma.bytes() == 600 * COLOURED_RECORD as u64);
        ma.validate(300).unwrap();
        let mut w = ShardWriter::create(&b, 300);
        w.append(&recs[600..]).unwrap();
        let mb = w.finish().unwrap();
        let mut set = ShardSet::new();
        set.push(a, ma);
        set.push(b, mb);
        assert!(set.coloured());
        let planes = set.read_planes_coloured(0, 299, false).unwrap();
        let mut got: Vec<(u32, u32, u64, Rgba)> = planes.iter().flatten().map(|(r, c)| (r.plane, r.line, r.signed_value.to_bits(), *c)).collect();
        let mut want: Vec<(u32, u32, u64, Rgba)> = recs.iter().enumerate().map(|(i, r)| (r.plane, r.line, r.signed_value.to_bits(), if i < 600 { cols[i] } else { WHITE })).collect();
        got.sort();
        want.sort();
        assert_eq!(got, want);
        // The geometry alone reads the same from either kind of store.
        assert_eq!(set.read_planes(0, 299, false).unwrap().iter().map(|p| p.len()).sum::<usize>(), 900);
    }

    #[test]
    fn a_rollback_leaves_the_store_as_at_its_checkpoint() {
        let root = tempfile::tempdir().unwrap();
        let (a, b) = (root.path().join("a"), root.path().join("b"));
        std::fs::create_dir(&a).unwrap();
        std::fs::create_dir(&b).unwrap();
        let recs = records(1000);
        let (first, later) = recs.split_at(700);
        // `a`: the first records, then records that are taken back (some in
        // shards already open, some in shards opened since), then the rest.
        let mut w = ShardWriter::create(&a, 1000);
        w.append(&first[..300]).unwrap();
        let cp = w.checkpoint();
        w.append(&first[300..]).unwrap();
        w.append(later).unwrap();
        w.rollback(cp).unwrap();
        w.append(&first[300..]).unwrap();
        let ma = w.finish().unwrap();
        let mut w = ShardWriter::create(&b, 1000);
        w.append(first).unwrap();
        let mb = w.finish().unwrap();
        assert_eq!(ma, mb, "the same manifest (lengths, checksums, counts) as without the records taken back");
        assert_eq!(std::fs::read_dir(&a).unwrap().count(), mb.shards.len(), "shards opened after the checkpoint are removed");
        let mut set = ShardSet::new();
        set.push(a, ma);
        assert_eq!(set.read_planes(0, 999, false).unwrap().iter().map(|p| p.len()).sum::<usize>(), 700);
    }

    #[test]
    fn a_truncated_or_damaged_shard_is_reported_with_its_path() {
        let root = tempfile::tempdir().unwrap();
        let mut w = ShardWriter::create(root.path(), 4);
        w.append(&[Intercept::new(1, FAMILY_A, 0, 1.5, true), Intercept::new(1, FAMILY_B, 0, 2.5, false)]).unwrap();
        let m = w.finish().unwrap();
        let mut set = ShardSet::new();
        set.push(root.path().to_path_buf(), m);
        let shard = root.path().join(shard_name(1));
        let mut bytes = std::fs::read(&shard).unwrap();
        bytes[9] ^= 1;
        std::fs::write(&shard, &bytes).unwrap();
        let e = set.read_planes(0, 3, false).unwrap_err();
        assert!(e.to_string().contains("shard-00001.bin") && e.to_string().contains("checksum"), "{e}");
        std::fs::write(&shard, &bytes[..10]).unwrap();
        let e = set.read_planes(0, 3, false).unwrap_err();
        assert!(e.to_string().contains("10 bytes, 32 were written"), "{e}");
        std::fs::remove_file(&shard).unwrap();
        let e = set.read_planes(0, 3, false).unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
    }
}
