//! mint-volume: voxel volumes in and out, slice by slice, with their world
//! frame. CT, MRI and micro-CT volumes are hundreds of megabytes to tens
//! of gigabytes, so nothing here holds a whole volume: [`Volume::open`]
//! parses a header into a [`VolumeInfo`] (dimensions, sample type, the
//! index-to-world affine, the frame the file declares, rescale slope and
//! intercept, the files that hold the data) and [`Volume::read_slices`]
//! decodes a range of slices (index `k`, the slowest axis in every format)
//! into `f32` values with the rescale applied. [`VolumeWriter`] streams
//! slices out (for `mint gen volume`), beside the target and renamed into
//! place.
//!
//! Formats: raw ([`RawSpec`], everything given by the caller), MetaImage
//! (`.mhd` + data, `.mha`), NRRD (attached or detached header, raw or gzip,
//! one data file or one file per slice), NIfTI-1 (`.nii`, `.nii.gz`,
//! `.hdr` + `.img`), DICOM series (a folder of slices, ordered by position
//! along the slice normal) and TIFF stacks (a folder of single-page files,
//! or one multi-page file). Modules: [`error`], `decode` (sample types and
//! byte order), `source` (contiguous, gzip and per-slice data), `nrrd`,
//! `metaimage`, `nifti`, `dicom`, `tiff`, [`writer`].
//!
//! Contract and non-goals: scalar volumes only (one channel, three
//! dimensions; a fourth dimension of size 1 is accepted); a header is
//! trusted for nothing: every size is checked against the data it names
//! before a slice is read, and every failure is one [`VolumeError`] line
//! naming the file and the place in it. Compressed data (gzip, zlib) reads
//! sequentially: reading slice `k` after slice `k + 1` starts the stream
//! again ([`VolumeInfo::sequential_only`] says so).

#![warn(missing_docs)]

mod ahead;
mod decode;
mod dicom;
pub mod dicom_lengths;
mod dicom_pixels;
pub mod error;
mod metaimage;
mod nifti;
mod nrrd;
mod source;
mod tiff;
pub mod writer;

use std::path::{Path, PathBuf};

pub use decode::Sample;
pub use error::{VolumeError, VolumeErrorKind};
pub use writer::{VolumeFormat, VolumeWriter};

use source::SliceSource;

/// The world frame a file declares for its index-to-world affine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// DICOM's patient frame: +x to the patient's left, +y posterior, +z
    /// superior (DICOM, MetaImage/ITK, NRRD `left-posterior-superior`).
    Lps,
    /// NIfTI's frame: +x right, +y anterior, +z superior (NIfTI sform/qform
    /// codes 1..4, NRRD `right-anterior-superior`).
    Ras,
    /// Scanner or other frame the file names without an anatomical
    /// meaning (NRRD `scanner-xyz`, `3D-right-handed`, …).
    Scanner,
    /// No frame: spacing only (a raw volume, NRRD without `space`, NIfTI
    /// with both codes 0).
    Unnamed,
}

impl Frame {
    /// The name the summary prints.
    pub fn name(&self) -> &'static str {
        match self {
            Frame::Lps => "LPS (patient)",
            Frame::Ras => "RAS (patient)",
            Frame::Scanner => "scanner",
            Frame::Unnamed => "voxel spacing (no frame declared)",
        }
    }
}

/// What a volume's header says: everything needed to place and read it.
#[derive(Clone, Debug)]
pub struct VolumeInfo {
    /// Samples along i (fastest), j and k (slices, slowest).
    pub dims: [u64; 3],
    /// The stored sample type.
    pub sample: Sample,
    /// world = M · (i, j, k, 1): columns are the step along i, j, k and the
    /// position of voxel (0, 0, 0)'s centre, in the file's units (mm for
    /// medical formats).
    pub index_to_world: [[f64; 4]; 3],
    /// The frame `index_to_world` maps into.
    pub frame: Frame,
    /// Stored value × slope + intercept is the value [`Volume::read_slices`]
    /// returns (DICOM rescale, NIfTI scl_*); 1 and 0 elsewhere. For DICOM a
    /// slice may carry its own pair; this is the first slice's.
    pub slope: f64,
    /// See `slope`.
    pub intercept: f64,
    /// The format's name ("NRRD", "MetaImage", "NIfTI-1", "DICOM series",
    /// "TIFF stack", "raw").
    pub format: &'static str,
    /// Every file the volume is read from (header first): what a staged run
    /// fingerprints.
    pub files: Vec<PathBuf>,
    /// True when slices come from a compressed stream: read them in
    /// increasing order.
    pub sequential_only: bool,
}

impl VolumeInfo {
    /// Samples in one slice (i × j).
    pub fn slice_len(&self) -> usize {
        (self.dims[0] * self.dims[1]) as usize
    }

    /// The length of one voxel step along index axis `d` in world units.
    pub fn spacing(&self, d: usize) -> f64 {
        let m = &self.index_to_world;
        (m[0][d] * m[0][d] + m[1][d] * m[1][d] + m[2][d] * m[2][d]).sqrt()
    }

    /// The world position of index (i, j, k) (fractional indices allowed).
    pub fn world(&self, ijk: [f64; 3]) -> [f64; 3] {
        let m = &self.index_to_world;
        std::array::from_fn(|r| m[r][0] * ijk[0] + m[r][1] * ijk[1] + m[r][2] * ijk[2] + m[r][3])
    }
}

/// A raw volume's layout, all of it given by the caller (nothing in the
/// file says it).
#[derive(Clone, Debug)]
pub struct RawSpec {
    /// Samples along i, j, k.
    pub dims: [u64; 3],
    /// Stored sample type.
    pub sample: Sample,
    /// Big-endian samples (default little).
    pub big_endian: bool,
    /// Voxel spacing along i, j, k (default 1).
    pub spacing: [f64; 3],
    /// Bytes to skip at the start of the file (default 0).
    pub header_bytes: u64,
}

/// How to open a volume.
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    /// Read the file as raw samples with this layout (required for `.raw`
    /// and any file without a header mint knows).
    pub raw: Option<RawSpec>,
    /// Of a DICOM folder that holds several series, the one to read: its
    /// SeriesInstanceUID, or its number (from 1) in the list that opening
    /// the folder without it gives. Without it a folder must hold one
    /// series, and a `.dcm` file reads its own.
    pub dicom_series: Option<String>,
}

/// What a read saw of the samples (after the rescale): how many were NaN,
/// and the range of the finite ones (`None` when none was).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SampleStats {
    /// NaN samples.
    pub nan: u64,
    /// The least and greatest finite sample.
    pub range: Option<[f32; 2]>,
}

impl SampleStats {
    /// Both reads together.
    pub fn merge(&mut self, o: &SampleStats) {
        self.nan += o.nan;
        self.range = match (self.range, o.range) {
            (Some(a), Some(b)) => Some([a[0].min(b[0]), a[1].max(b[1])]),
            (a, b) => a.or(b),
        };
    }
}

/// Adds the NaN count and the finite range of `values` to `stats`.
/// Chunk by chunk, a branch-free fold over 16 lanes (packed compares and
/// blends) takes the bounds and notes whether any value is not finite; a
/// comparison with NaN is false, so NaN never moves a bound. Only a chunk
/// with a NaN or an infinity is folded again, value by value, counting NaN
/// and leaving infinities out of the range (they are not values of it).
pub(crate) fn sample_stats(values: &[f32], stats: &mut SampleStats) {
    const L: usize = 16;
    let (mut lo, mut hi, mut nan) = (f32::INFINITY, f32::NEG_INFINITY, 0u64);
    for c in values.chunks(4096) {
        let (mut l, mut h, mut odd) = ([f32::INFINITY; L], [f32::NEG_INFINITY; L], [0u32; L]);
        let mut lanes = c.chunks_exact(L);
        for v in &mut lanes {
            for k in 0..L {
                let x = v[k];
                l[k] = if x < l[k] { x } else { l[k] };
                h[k] = if x > h[k] { x } else { h[k] };
                odd[k] |= (x.to_bits() & 0x7f80_0000 == 0x7f80_0000) as u32;
            }
        }
        let rest = lanes.remainder();
        if odd.iter().any(|&o| o != 0) || rest.iter().any(|x| !x.is_finite()) {
            for &x in c {
                if x.is_finite() {
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
                nan += x.is_nan() as u64;
            }
            continue;
        }
        for k in 0..L {
            lo = if l[k] < lo { l[k] } else { lo };
            hi = if h[k] > hi { h[k] } else { hi };
        }
        for &x in rest {
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    stats.nan += nan;
    if lo <= hi {
        stats.range = Some(match stats.range {
            Some([a, b]) => [a.min(lo), b.max(hi)],
            None => [lo, hi],
        });
    }
}

/// An open volume: its header and a reader of its slices.
pub struct Volume {
    info: VolumeInfo,
    source: Box<dyn SliceSource>,
    /// More readers of the same data, for [`Volume::read_slices_on`].
    helpers: Vec<Box<dyn SliceSource>>,
    /// The thread of [`Volume::read_ahead`], started by its first call.
    ahead: Option<ahead::ReadAhead>,
}

impl std::fmt::Debug for Volume {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Volume").field("info", &self.info).finish_non_exhaustive()
    }
}

impl Volume {
    /// Opens `path`: a header file (`.nhdr`, `.nrrd`, `.mhd`, `.mha`,
    /// `.nii`, `.nii.gz`, `.hdr`), a folder (a DICOM series or a TIFF
    /// stack), a `.dcm` file (its folder's series), a `.tif`/`.tiff` file
    /// (its pages), or raw samples with [`OpenOptions::raw`]. Checks the
    /// header against the data's size; reads no slice.
    pub fn open(path: &Path, options: &OpenOptions) -> Result<Volume, VolumeError> {
        let (info, source) = if let Some(raw) = &options.raw {
            source::open_raw(path, raw)?
        } else {
            let name = path.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
            let ext = |e: &str| name.ends_with(e);
            if path.is_dir() {
                if tiff::is_stack_dir(path)? {
                    tiff::open(path)?
                } else {
                    dicom::open(path, options.dicom_series.as_deref(), None)?
                }
            } else if ext(".nhdr") || ext(".nrrd") {
                nrrd::open(path)?
            } else if ext(".mhd") || ext(".mha") {
                metaimage::open(path)?
            } else if ext(".nii") || ext(".nii.gz") || ext(".hdr") {
                nifti::open(path)?
            } else if ext(".dcm") {
                dicom::open(path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")), options.dicom_series.as_deref(), Some(path))?
            } else if ext(".tif") || ext(".tiff") {
                tiff::open(path)?
            } else {
                return Err(VolumeError::new(
                    VolumeErrorKind::Unsupported,
                    path,
                    "not a volume mint knows (.nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz, .hdr, .dcm, .tif or a folder of DICOM or TIFF slices); for raw samples give their dimensions and type (--raw-dims, --raw-type)",
                ));
            }
        };
        source::check_info(path, &info)?;
        Ok(Volume { info, source, helpers: Vec::new(), ahead: None })
    }

    /// The header.
    pub fn info(&self) -> &VolumeInfo {
        &self.info
    }

    /// Reads slices `k0 .. k0 + count` into `out` (length `count` ×
    /// [`VolumeInfo::slice_len`]), sample (i, j) of slice k at
    /// `(k - k0) · slice_len + j · dims[0] + i`, rescaled to `f32`.
    pub fn read_slices(&mut self, k0: u64, count: u64, out: &mut [f32]) -> Result<(), VolumeError> {
        self.read_slices_on(k0, count, out, 1).map(|_| ())
    }

    /// [`Volume::read_slices`] on up to `threads` threads when the volume
    /// reads any slice as cheaply as the next (uncompressed files, one file
    /// a slice): one run of consecutive slices a thread, each read and
    /// decoded by a reader of its own (kept for the next call; each holds
    /// at most one slice of the file's bytes, [`Volume::reader_bytes`]).
    /// Each slice is decoded alone, so the values do not depend on
    /// `threads`; of several errors, the first slice's is returned. Returns
    /// the samples' statistics, each slice's taken by its thread while the
    /// slice is still in cache.
    pub fn read_slices_on(&mut self, k0: u64, count: u64, out: &mut [f32], threads: usize) -> Result<SampleStats, VolumeError> {
        let n = self.info.slice_len();
        let end = k0.checked_add(count).filter(|&e| e <= self.info.dims[2]);
        if end.is_none() || out.len() as u64 != count * n as u64 {
            return Err(VolumeError::new(
                VolumeErrorKind::Value,
                &self.info.files[0],
                format!("slices {k0}..{} asked of a volume of {} slices into {} values", k0.saturating_add(count), self.info.dims[2], out.len()),
            ));
        }
        let t = (threads.max(1) as u64).min(count).max(1) as usize;
        let mut stats = SampleStats::default();
        if t == 1 || n == 0 || !self.source.random_access() {
            for (c, chunk) in out.chunks_exact_mut(n.max(1)).enumerate().take(count as usize) {
                self.source.read_slice(k0 + c as u64, chunk, &mut stats)?;
            }
            return Ok(stats);
        }
        while self.helpers.len() < t - 1 {
            let h = self.source.try_clone()?;
            self.helpers.push(h);
        }
        let run = |src: &mut Box<dyn SliceSource>, first: u64, values: &mut [f32]| -> Result<SampleStats, VolumeError> {
            let mut stats = SampleStats::default();
            for (c, chunk) in values.chunks_exact_mut(n).enumerate() {
                src.read_slice(first + c as u64, chunk, &mut stats)?;
            }
            Ok(stats)
        };
        let mut results: Vec<Result<SampleStats, VolumeError>> = Vec::with_capacity(t);
        std::thread::scope(|s| {
            let mut rest = &mut out[..];
            let mut runs = Vec::with_capacity(t);
            for r in 0..t as u64 {
                let (a, b) = (count * r / t as u64, count * (r + 1) / t as u64);
                let (mine, tail) = std::mem::take(&mut rest).split_at_mut((b - a) as usize * n);
                rest = tail;
                runs.push((k0 + a, mine));
            }
            let mut runs = runs.into_iter();
            let (first, mine) = runs.next().expect("one run at least");
            let handles: Vec<_> = runs.zip(self.helpers.iter_mut()).map(|((at, values), src)| s.spawn(move || run(src, at, values))).collect();
            results.push(run(&mut self.source, first, mine));
            for h in handles {
                results.push(h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)));
            }
        });
        for r in results {
            stats.merge(&r?);
        }
        Ok(stats)
    }

    /// Starts reading slices `k0 .. k0 + count` into the system's cache on
    /// a thread of the volume's own (uncompressed data; one file a slice),
    /// in place of any earlier request not yet started, so that reading them later
    /// overlaps with work on the slices read before. Only a hint: nothing
    /// is checked or returned, and a read of those slices reports any
    /// error. The thread holds [`Volume::READ_AHEAD_BYTES`] and ends with
    /// the volume.
    pub fn read_ahead(&mut self, k0: u64, count: u64) {
        let end = k0.saturating_add(count).min(self.info.dims[2]);
        if k0 >= end {
            return;
        }
        let ranges = self.source.stored(k0, end - k0);
        if ranges.is_empty() {
            return;
        }
        if self.ahead.is_none() {
            self.ahead = ahead::ReadAhead::start();
        }
        if let Some(a) = &self.ahead {
            a.ask(ranges);
        }
    }

    /// The memory the thread of [`Volume::read_ahead`] holds.
    pub const READ_AHEAD_BYTES: u64 = ahead::PIECE as u64;

    /// The bytes each extra reader of [`Volume::read_slices_on`] holds: one
    /// slice of samples as stored.
    pub fn reader_bytes(&self) -> u64 {
        self.info.slice_len() as u64 * self.info.sample.size() as u64
    }

    /// A second reader of the same volume (its own file handles), for a
    /// task on another thread.
    pub fn try_clone(&self) -> Result<Volume, VolumeError> {
        Ok(Volume { info: self.info.clone(), source: self.source.try_clone()?, helpers: Vec::new(), ahead: None })
    }
}

/// Checks the data files a header names (`header`, line `line`): names
/// without control characters, each an existing file. A missing data file
/// is the header's fault, so the error names the header and its line.
pub(crate) fn check_data_files(header: &Path, line: usize, files: &[PathBuf]) -> Result<(), VolumeError> {
    for f in files {
        let name = f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if f.as_os_str().to_string_lossy().chars().any(char::is_control) {
            return Err(VolumeError::format(header, format!("line {line}: data file {:?} holds a control character", f.as_os_str())));
        }
        if !f.is_file() {
            let what = if f.is_dir() { "is a folder" } else { "does not exist" };
            return Err(VolumeError::format(header, format!("line {line}: data file `{name}` {what} ({})", f.display())));
        }
    }
    Ok(())
}

/// The world frame for an axis-aligned affine built from spacing and an
/// origin (NRRD without directions, MetaImage without a matrix, raw).
pub(crate) fn diagonal_affine(spacing: [f64; 3], origin: [f64; 3]) -> [[f64; 4]; 3] {
    let mut m = [[0.0; 4]; 3];
    for r in 0..3 {
        m[r][r] = spacing[r];
        m[r][3] = origin[r];
    }
    m
}
