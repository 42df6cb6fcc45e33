//! Where slices come from. One [`SliceSource`] trait with two owners of
//! data layout: [`FileSlices`] (samples stored in one or more files, each
//! holding a run of whole slices after a header, raw or gzip/zlib
//! compressed: raw volumes, NRRD, MetaImage, NIfTI) and the DICOM and TIFF
//! readers (one decoded image per slice). Uncompressed files are read with
//! positioned reads (any slice order, any number of clones); compressed
//! ones as a stream that restarts when asked for an earlier slice.

use std::fs::File;
use std::io::{BufReader, Read};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use crate::ahead::Stored;
use crate::decode::Decoder;
use crate::{diagonal_affine, sample_stats, SampleStats, Frame, RawSpec, VolumeError, VolumeErrorKind, VolumeInfo};

/// Reads one slice at a time. Implementations own their file handles.
pub(crate) trait SliceSource: Send {
    /// Decodes slice `k` (`out.len()` = i × j samples) into `out`, and
    /// folds the values' NaN count and range into `stats`
    /// ([`crate::sample_stats`], or as the decoder finds them).
    fn read_slice(&mut self, k: u64, out: &mut [f32], stats: &mut SampleStats) -> Result<(), VolumeError>;
    /// An independent reader of the same data.
    fn try_clone(&self) -> Result<Box<dyn SliceSource>, VolumeError>;
    /// Whether any slice costs what the next one does (no stream to wind
    /// forward), so that runs of slices can be read by several readers.
    fn random_access(&self) -> bool;
    /// The stored bytes of slices `k0 .. k0 + count`, for reading them
    /// ahead into the system's cache; none where reading ahead cannot
    /// help (compressed streams, multi-page files). A hint: errors are
    /// the read's.
    fn stored(&mut self, _k0: u64, _count: u64) -> Vec<Stored> {
        Vec::new()
    }
}

/// The bytes of an uncompressed slice read and decoded at once: a piece
/// stays in a core's cache between the two.
const PIECE_BYTES: usize = 128 << 10;

/// How a data file is compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Compression {
    None,
    /// gzip members (NRRD `gzip`, `.nii.gz`).
    Gzip,
    /// A zlib stream (MetaImage `CompressedData = True`).
    Zlib,
}

/// Where the samples start in a data file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Skip {
    /// After this many bytes (of the decompressed stream when compressed).
    Bytes(u64),
    /// The samples are the file's last bytes (NRRD `byte skip: -1`,
    /// MetaImage `HeaderSize = -1`); uncompressed only.
    FromEnd,
}

/// Samples in files, `per_file` whole slices each, in order.
pub(crate) struct FileSlices {
    files: Vec<PathBuf>,
    per_file: u64,
    skip: Skip,
    compression: Compression,
    decoder: Decoder,
    slice_bytes: u64,
    /// Bytes of the file before the compressed stream (an attached header).
    file_start: u64,
    buf: Vec<u8>,
    /// The open file and the sample start in it (uncompressed).
    open: Option<(usize, File, u64)>,
    /// The open stream, its file and the next slice it yields (compressed).
    stream: Option<(usize, Box<dyn Read + Send>, u64)>,
}

impl FileSlices {
    /// A source over `files`; checks that every uncompressed file holds
    /// its slices (the header's dimensions match the data).
    pub fn new(
        files: Vec<PathBuf>,
        slices: u64,
        slice_len: u64,
        skip: Skip,
        compression: Compression,
        decoder: Decoder,
    ) -> Result<FileSlices, VolumeError> {
        let first = files.first().cloned().unwrap_or_default();
        if files.is_empty() {
            return Err(VolumeError::format(&first, "no data file"));
        }
        if slices % files.len() as u64 != 0 {
            return Err(VolumeError::format(
                &files[0],
                format!("{} slices do not split evenly over {} data files", slices, files.len()),
            ));
        }
        let per_file = slices / files.len() as u64;
        let slice_bytes = slice_len
            .checked_mul(decoder.sample.size() as u64)
            .filter(|&b| b <= isize::MAX as u64 / 4)
            .ok_or_else(|| VolumeError::format(&files[0], "one slice is larger than memory can address"))?;
        if compression != Compression::None && skip == Skip::FromEnd {
            return Err(VolumeError::format(&files[0], "a header size of -1 (data at the end) cannot be used with compressed data"));
        }
        if compression == Compression::None {
            let need = per_file.checked_mul(slice_bytes).ok_or_else(|| VolumeError::format(&files[0], "dimensions overflow"))?;
            for f in &files {
                let len = std::fs::metadata(f).map_err(|e| VolumeError::io(f, "reading the data file", e))?.len();
                let start = match skip {
                    Skip::Bytes(b) => b,
                    Skip::FromEnd => len.saturating_sub(need),
                };
                if len < start.saturating_add(need) {
                    return Err(VolumeError::format(
                        f,
                        format!(
                            "holds {len} bytes, but the header's dimensions need {need} ({per_file} slice(s) of {slice_bytes} bytes) from byte {start}: the dimensions do not match the data, or the file is truncated"
                        ),
                    ));
                }
            }
        }
        Ok(FileSlices { files, per_file, skip, compression, decoder, slice_bytes, file_start: 0, buf: Vec::new(), open: None, stream: None })
    }

    /// A compressed stream that starts `at` bytes into its file (after an
    /// attached header).
    pub fn with_file_start(mut self, at: u64) -> FileSlices {
        self.file_start = at;
        self
    }

    /// Reads bytes `from .. from + buf.len()` of slice `local` of file `f`.
    fn read_plain(&mut self, f: usize, local: u64, from: u64, buf: &mut [u8]) -> Result<(), VolumeError> {
        self.open_plain(f)?;
        let (_, file, start) = self.open.as_ref().unwrap();
        let at = start + local * self.slice_bytes + from;
        file.read_exact_at(buf, at)
            .map_err(|e| VolumeError::io(&self.files[f], &format!("reading slice {} at byte {at}", f as u64 * self.per_file + local), e))
    }

    /// Makes data file `f` the open one.
    fn open_plain(&mut self, f: usize) -> Result<(), VolumeError> {
        if self.open.as_ref().map(|o| o.0) != Some(f) {
            let path = &self.files[f];
            let file = File::open(path).map_err(|e| VolumeError::io(path, "opening the data file", e))?;
            let start = match self.skip {
                Skip::Bytes(b) => b,
                Skip::FromEnd => {
                    let len = file.metadata().map_err(|e| VolumeError::io(path, "reading the data file", e))?.len();
                    len - self.per_file * self.slice_bytes
                }
            };
            self.open = Some((f, file, start));
        }
        Ok(())
    }

    fn read_stream(&mut self, f: usize, local: u64) -> Result<(), VolumeError> {
        let restart = match &self.stream {
            Some((sf, _, next)) => *sf != f || *next > local,
            None => true,
        };
        if restart {
            let path = &self.files[f];
            let mut file = File::open(path).map_err(|e| VolumeError::io(path, "opening the data file", e))?;
            std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(self.file_start)).map_err(|e| VolumeError::io(path, "opening the data file", e))?;
            let reader = BufReader::with_capacity(1 << 20, file);
            let mut r: Box<dyn Read + Send> = match self.compression {
                Compression::Gzip => Box::new(flate2::read::MultiGzDecoder::new(reader)),
                Compression::Zlib => Box::new(flate2::read::ZlibDecoder::new(reader)),
                Compression::None => unreachable!(),
            };
            if let Skip::Bytes(b) = self.skip {
                let got = std::io::copy(&mut (&mut r).take(b), &mut std::io::sink())
                    .map_err(|e| VolumeError::format(path, format!("decompressing the header: {e}")))?;
                if got < b {
                    return Err(VolumeError::format(path, format!("the decompressed data ends at byte {got}, before the samples start at {b} (truncated)")));
                }
            }
            self.stream = Some((f, r, 0));
        }
        let path = self.files[f].clone();
        let (_, r, next) = self.stream.as_mut().unwrap();
        while *next <= local {
            let k = f as u64 * self.per_file + *next;
            if let Err(e) = r.read_exact(&mut self.buf) {
                self.stream = None;
                return Err(if e.kind() == std::io::ErrorKind::UnexpectedEof {
                    VolumeError::format(&path, format!("the compressed data ends inside slice {k} (truncated, or the dimensions do not match the data)"))
                } else {
                    VolumeError::format(&path, format!("decompressing slice {k}: {e}"))
                });
            }
            *next += 1;
        }
        Ok(())
    }
}

impl SliceSource for FileSlices {
    fn read_slice(&mut self, k: u64, out: &mut [f32], stats: &mut SampleStats) -> Result<(), VolumeError> {
        let (f, local) = ((k / self.per_file) as usize, k % self.per_file);
        if self.compression == Compression::None {
            // In pieces, each decoded while its bytes are still in cache.
            let size = self.decoder.sample.size();
            let per = (PIECE_BYTES / size).max(1);
            let mut buf = std::mem::take(&mut self.buf);
            buf.resize(per.min(out.len()) * size, 0);
            let mut result = Ok(());
            for (p, piece) in out.chunks_mut(per).enumerate() {
                let bytes = &mut buf[..piece.len() * size];
                result = self.read_plain(f, local, (p * per * size) as u64, bytes);
                if result.is_err() {
                    break;
                }
                fold(self.decoder.decode_range(bytes, piece), piece, stats);
            }
            self.buf = buf;
            return result;
        }
        self.buf.resize(self.slice_bytes as usize, 0);
        self.read_stream(f, local)?;
        fold(self.decoder.decode_range(&self.buf, out), out, stats);
        Ok(())
    }

    fn try_clone(&self) -> Result<Box<dyn SliceSource>, VolumeError> {
        Ok(Box::new(FileSlices {
            files: self.files.clone(),
            per_file: self.per_file,
            skip: self.skip,
            compression: self.compression,
            decoder: self.decoder,
            slice_bytes: self.slice_bytes,
            file_start: self.file_start,
            buf: Vec::new(),
            open: None,
            stream: None,
        }))
    }

    fn random_access(&self) -> bool {
        self.compression == Compression::None
    }

    fn stored(&mut self, k0: u64, count: u64) -> Vec<Stored> {
        let mut out = Vec::new();
        if self.compression != Compression::None {
            return out;
        }
        // File by file: the byte range of the slices each holds.
        let mut k = k0;
        while k < k0 + count {
            let (f, local) = ((k / self.per_file) as usize, k % self.per_file);
            let n = (self.per_file - local).min(k0 + count - k);
            if f >= self.files.len() || self.open_plain(f).is_err() {
                break;
            }
            if let Some((_, _, start)) = &self.open {
                out.push(Stored { path: self.files[f].clone(), at: start + local * self.slice_bytes, len: Some(n * self.slice_bytes) });
            }
            k += n;
        }
        out
    }
}

/// Folds into `stats` the range a decoder found (integers: no NaN), or
/// the values' own statistics (floats).
fn fold(range: Option<[f32; 2]>, values: &[f32], stats: &mut SampleStats) {
    match range {
        Some(r) => stats.merge(&SampleStats { nan: 0, range: Some(r) }),
        None => sample_stats(values, stats),
    }
}

/// The number of samples of a volume of `dims`, or an error naming `path`
/// when the product overflows or a dimension is zero.
pub(crate) fn sample_count(path: &Path, dims: [u64; 3]) -> Result<u64, VolumeError> {
    if dims.iter().any(|&d| d == 0) {
        return Err(VolumeError::format(path, format!("dimensions {} x {} x {}: a volume needs at least one sample along each axis", dims[0], dims[1], dims[2])));
    }
    dims.iter()
        .try_fold(1u64, |a, &d| a.checked_mul(d))
        .filter(|&n| n <= 1 << 48)
        .ok_or_else(|| VolumeError::format(path, format!("dimensions {} x {} x {} overflow (more than 2^48 samples)", dims[0], dims[1], dims[2])))
}

/// Checks what every reader produced: sizes that a slice buffer can hold,
/// a finite, invertible affine and a finite rescale.
pub(crate) fn check_info(path: &Path, info: &VolumeInfo) -> Result<(), VolumeError> {
    sample_count(path, info.dims)?;
    if info.dims[0].saturating_mul(info.dims[1]) > 1 << 32 {
        return Err(VolumeError::format(path, format!("one slice of {} x {} samples is too large", info.dims[0], info.dims[1])));
    }
    let m = &info.index_to_world;
    if m.iter().flatten().any(|v| !v.is_finite()) {
        return Err(VolumeError::format(path, "the spacing, origin or direction is not a finite number"));
    }
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let scale = (0..3).map(|d| info.spacing(d)).product::<f64>();
    if !(det.abs() > 1e-9 * scale) || scale == 0.0 {
        return Err(VolumeError::format(path, "the voxel axes are degenerate (a zero spacing, or two directions that coincide)"));
    }
    if !info.slope.is_finite() || !info.intercept.is_finite() || info.slope == 0.0 {
        return Err(VolumeError::format(path, format!("rescale slope {} and intercept {} are not usable", info.slope, info.intercept)));
    }
    Ok(())
}

/// A raw volume: every part of the layout from the caller.
pub(crate) fn open_raw(path: &Path, raw: &RawSpec) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    sample_count(path, raw.dims)?;
    if raw.spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(VolumeError::new(VolumeErrorKind::Value, path, format!("raw spacing {:?} must be positive", raw.spacing)));
    }
    let decoder = Decoder { sample: raw.sample, big_endian: raw.big_endian, slope: 1.0, intercept: 0.0 };
    let src = FileSlices::new(vec![path.to_path_buf()], raw.dims[2], raw.dims[0] * raw.dims[1], Skip::Bytes(raw.header_bytes), Compression::None, decoder)?;
    let info = VolumeInfo {
        dims: raw.dims,
        sample: raw.sample,
        index_to_world: diagonal_affine(raw.spacing, [0.0; 3]),
        frame: Frame::Unnamed,
        slope: 1.0,
        intercept: 0.0,
        format: "raw",
        files: vec![path.to_path_buf()],
        sequential_only: false,
    };
    Ok((info, Box::new(src)))
}
