//! Volumes out, slice by slice: [`VolumeWriter`] writes NRRD (`.nrrd`
//! attached, `.nhdr` + `.raw` detached), MetaImage (`.mha`, `.mhd` +
//! `.raw`), NIfTI-1 (`.nii`) or bare samples (`.raw`), little-endian and
//! uncompressed, each file beside its target and renamed into place at
//! [`VolumeWriter::finish`] (nothing is left on error or drop). Values are
//! rounded to the nearest integer and clamped to the sample type's range.
//! It is what `mint gen volume` writes through: any size, memory of one
//! slice.

use std::io::Write;
use std::path::{Path, PathBuf};

use mint_io::AtomicFile;

use crate::decode::Sample;
use crate::{Frame, VolumeError, VolumeErrorKind};

/// An output format, chosen by the target's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeFormat {
    /// `.nrrd`: header and data in one file.
    NrrdAttached,
    /// `.nhdr`: header, data in a `.raw` file beside it.
    NrrdDetached,
    /// `.mha`: header and data in one file.
    MetaImageAttached,
    /// `.mhd`: header, data in a `.raw` file beside it.
    MetaImageDetached,
    /// `.nii`: NIfTI-1, header and data in one file.
    Nifti,
    /// `.raw`: samples only (give dimensions and type when reading back).
    Raw,
}

impl VolumeFormat {
    /// The format for `path`'s extension.
    pub fn of(path: &Path) -> Option<VolumeFormat> {
        let n = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        let e = n.rsplit('.').next()?;
        Some(match e {
            "nrrd" => VolumeFormat::NrrdAttached,
            "nhdr" => VolumeFormat::NrrdDetached,
            "mha" => VolumeFormat::MetaImageAttached,
            "mhd" => VolumeFormat::MetaImageDetached,
            "nii" => VolumeFormat::Nifti,
            "raw" => VolumeFormat::Raw,
            _ => return None,
        })
    }
}

/// Streams a volume out one slice at a time.
pub struct VolumeWriter {
    dims: [u64; 3],
    sample: Sample,
    header: Option<AtomicFile>,
    data: AtomicFile,
    buf: Vec<u8>,
    written: u64,
    paths: Vec<PathBuf>,
}

impl VolumeWriter {
    /// Starts writing a volume of `dims` samples of type `sample` at
    /// `path`, placed by `index_to_world` in `frame` (written where the
    /// format can say it; `.raw` keeps nothing but the samples).
    pub fn create(path: &Path, dims: [u64; 3], sample: Sample, index_to_world: [[f64; 4]; 3], frame: Frame) -> Result<VolumeWriter, VolumeError> {
        let format = VolumeFormat::of(path).ok_or_else(|| {
            VolumeError::new(VolumeErrorKind::Value, path, "unknown volume extension: write .nrrd, .nhdr, .mha, .mhd, .nii or .raw")
        })?;
        crate::source::sample_count(path, dims)?;
        let atomic = |p: &Path| AtomicFile::create(p).map_err(|e| VolumeError::new(VolumeErrorKind::Io, p, e.to_string()));
        let m = &index_to_world;
        let col = |c: usize| format!("({},{},{})", m[0][c], m[1][c], m[2][c]);
        let spacing: [f64; 3] = std::array::from_fn(|c| (m[0][c].powi(2) + m[1][c].powi(2) + m[2][c].powi(2)).sqrt());
        let raw_path = path.with_extension("raw");
        let raw_name = raw_path.file_name().unwrap().to_string_lossy().into_owned();
        let space = match frame {
            Frame::Lps => "space: left-posterior-superior\n",
            Frame::Ras => "space: right-anterior-superior\n",
            Frame::Scanner | Frame::Unnamed => "space: scanner-xyz\n",
        };
        let nrrd_type = match sample {
            Sample::U8 => "uint8",
            Sample::I8 => "int8",
            Sample::U16 => "uint16",
            Sample::I16 => "int16",
            Sample::U32 => "uint32",
            Sample::I32 => "int32",
            Sample::U64 => "uint64",
            Sample::I64 => "int64",
            Sample::F32 => "float",
            Sample::F64 => "double",
        };
        let nrrd = |data: Option<&str>| {
            format!(
                "NRRD0004\n# written by mint\ntype: {nrrd_type}\ndimension: 3\n{space}sizes: {} {} {}\nspace directions: {} {} {}\nspace origin: ({},{},{})\nkinds: domain domain domain\nendian: little\nencoding: raw\n{}\n",
                dims[0], dims[1], dims[2], col(0), col(1), col(2), m[0][3], m[1][3], m[2][3],
                data.map(|d| format!("data file: {d}\n")).unwrap_or_default()
            )
        };
        let met_type = match sample {
            Sample::U8 => "MET_UCHAR",
            Sample::I8 => "MET_CHAR",
            Sample::U16 => "MET_USHORT",
            Sample::I16 => "MET_SHORT",
            Sample::U32 => "MET_UINT",
            Sample::I32 => "MET_INT",
            Sample::U64 => "MET_ULONG_LONG",
            Sample::I64 => "MET_LONG_LONG",
            Sample::F32 => "MET_FLOAT",
            Sample::F64 => "MET_DOUBLE",
        };
        let mhd = |data: &str| {
            let dir: Vec<String> = (0..3).flat_map(|c| (0..3).map(move |r| (r, c))).map(|(r, c)| format!("{}", if spacing[c] > 0.0 { m[r][c] / spacing[c] } else { 0.0 })).collect();
            // ITK's TransformMatrix lists the direction matrix row by row.
            let rows: Vec<String> = (0..3).flat_map(|r| (0..3).map(move |c| (r, c))).map(|(r, c)| dir[c * 3 + r].clone()).collect();
            format!(
                "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = False\nTransformMatrix = {}\nOffset = {} {} {}\nElementSpacing = {} {} {}\nDimSize = {} {} {}\nElementType = {met_type}\nElementDataFile = {data}\n",
                rows.join(" "), m[0][3], m[1][3], m[2][3], spacing[0], spacing[1], spacing[2], dims[0], dims[1], dims[2]
            )
        };
        let (header, mut data, head_bytes, paths) = match format {
            VolumeFormat::NrrdAttached => (None, atomic(path)?, nrrd(None).into_bytes(), vec![path.to_path_buf()]),
            VolumeFormat::MetaImageAttached => (None, atomic(path)?, mhd("LOCAL").into_bytes(), vec![path.to_path_buf()]),
            VolumeFormat::NrrdDetached | VolumeFormat::MetaImageDetached => {
                let mut h = atomic(path)?;
                let text = if format == VolumeFormat::NrrdDetached { nrrd(Some(&raw_name)) } else { mhd(&raw_name) };
                h.as_file_mut().write_all(text.as_bytes()).map_err(|e| VolumeError::io(path, "writing the header", e))?;
                (Some(h), atomic(&raw_path)?, Vec::new(), vec![path.to_path_buf(), raw_path.clone()])
            }
            VolumeFormat::Nifti => {
                let code = match sample {
                    Sample::U8 => 2,
                    Sample::I16 => 4,
                    Sample::I32 => 8,
                    Sample::F32 => 16,
                    Sample::F64 => 64,
                    Sample::I8 => 256,
                    Sample::U16 => 512,
                    Sample::U32 => 768,
                    Sample::I64 => 1024,
                    Sample::U64 => 1280,
                };
                if dims.iter().any(|&d| d > i16::MAX as u64) {
                    return Err(VolumeError::new(VolumeErrorKind::Value, path, "NIfTI-1 holds at most 32767 samples along an axis"));
                }
                // NIfTI is RAS: an LPS affine turns by negating x and y.
                let mut s = index_to_world;
                if frame == Frame::Lps {
                    for c in 0..4 {
                        s[0][c] = -s[0][c];
                        s[1][c] = -s[1][c];
                    }
                }
                let code_s = if frame == Frame::Unnamed { 0 } else { 1 };
                (None, atomic(path)?, crate::nifti::header(dims, code, (sample.size() * 8) as i16, s, code_s), vec![path.to_path_buf()])
            }
            VolumeFormat::Raw => (None, atomic(path)?, Vec::new(), vec![path.to_path_buf()]),
        };
        data.as_file_mut().write_all(&head_bytes).map_err(|e| VolumeError::io(path, "writing the header", e))?;
        Ok(VolumeWriter { dims, sample, header, data, buf: Vec::new(), written: 0, paths })
    }

    /// Writes the next slice (`dims[0] · dims[1]` values, i fastest).
    pub fn write_slice(&mut self, values: &[f32]) -> Result<(), VolumeError> {
        let n = (self.dims[0] * self.dims[1]) as usize;
        let target = self.paths.last().unwrap().clone();
        if values.len() != n || self.written == self.dims[2] {
            return Err(VolumeError::new(VolumeErrorKind::Value, &target, format!("slice {} of {} values, expected {} of {n}", self.written, values.len(), self.dims[2])));
        }
        self.buf.clear();
        self.buf.reserve(n * self.sample.size());
        macro_rules! ints {
            ($t:ty) => {
                for &v in values {
                    let r = if v.is_nan() { 0.0 } else { (v as f64).round().clamp(<$t>::MIN as f64, <$t>::MAX as f64) };
                    self.buf.extend_from_slice(&(r as $t).to_le_bytes());
                }
            };
        }
        match self.sample {
            Sample::U8 => ints!(u8),
            Sample::I8 => ints!(i8),
            Sample::U16 => ints!(u16),
            Sample::I16 => ints!(i16),
            Sample::U32 => ints!(u32),
            Sample::I32 => ints!(i32),
            Sample::U64 => ints!(u64),
            Sample::I64 => ints!(i64),
            Sample::F32 => values.iter().for_each(|v| self.buf.extend_from_slice(&v.to_le_bytes())),
            Sample::F64 => values.iter().for_each(|v| self.buf.extend_from_slice(&(*v as f64).to_le_bytes())),
        }
        self.data.as_file_mut().write_all(&self.buf).map_err(|e| VolumeError::io(&target, &format!("writing slice {}", self.written), e))?;
        self.written += 1;
        Ok(())
    }

    /// Checks that every slice was written and renames the files into
    /// place; returns their paths (header first).
    pub fn finish(self) -> Result<Vec<PathBuf>, VolumeError> {
        let target = self.paths.last().unwrap().clone();
        if self.written != self.dims[2] {
            return Err(VolumeError::new(VolumeErrorKind::Value, &target, format!("{} of {} slices written", self.written, self.dims[2])));
        }
        let io = |p: &Path, e: mint_io::Error| VolumeError::new(VolumeErrorKind::Io, p, e.to_string());
        self.data.commit().map_err(|e| io(&target, e))?;
        if let Some(h) = self.header {
            h.commit().map_err(|e| io(&self.paths[0], e))?;
        }
        Ok(self.paths)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OpenOptions, RawSpec, Volume};

    #[test]
    fn every_format_reads_back_the_same_samples_and_placement() {
        let dir = tempfile::tempdir().unwrap();
        let dims = [3u64, 4, 5];
        let m = [[0.0, -2.0, 0.0, 1.5], [1.0, 0.0, 0.0, -7.0], [0.0, 0.0, 3.0, 2.0]];
        let values: Vec<f32> = (0..60).map(|v| v as f32 * 10.0 - 100.0).collect();
        for name in ["a.nrrd", "b.nhdr", "c.mha", "d.mhd", "e.nii", "f.raw"] {
            let p = dir.path().join(name);
            let mut w = VolumeWriter::create(&p, dims, Sample::I16, m, Frame::Lps).unwrap();
            for k in 0..5 {
                w.write_slice(&values[k * 12..(k + 1) * 12]).unwrap();
            }
            let files = w.finish().unwrap();
            assert!(files.iter().all(|f| f.exists()));
            let opts = if name.ends_with(".raw") {
                OpenOptions { raw: Some(RawSpec { dims, sample: Sample::I16, big_endian: false, spacing: [1.0; 3], header_bytes: 0 }), dicom_series: None }
            } else {
                OpenOptions::default()
            };
            let mut v = Volume::open(&p, &opts).unwrap();
            let mut back = vec![0.0; 60];
            v.read_slices(0, 5, &mut back).unwrap();
            assert_eq!(back, values, "{name}");
            if !name.ends_with(".raw") {
                let w = v.info().world([1.0, 2.0, 3.0]);
                let mut want: [f64; 3] = std::array::from_fn(|r| m[r][0] + 2.0 * m[r][1] + 3.0 * m[r][2] + m[r][3]);
                if name.ends_with(".nii") {
                    assert_eq!(v.info().frame, Frame::Ras);
                    want[0] = -want[0];
                    want[1] = -want[1];
                } else if !name.ends_with(".nrrd") && !name.ends_with(".nhdr") {
                    assert_eq!(v.info().frame, Frame::Lps);
                }
                for d in 0..3 {
                    assert!((w[d] - want[d]).abs() < 1e-5, "{name}: {w:?} vs {want:?}");
                }
            }
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 8, "no temporary file left");
    }

    #[test]
    fn sample_stats_count_nan_and_skip_infinities() {
        // Lengths around the 16 lanes and the 4096 chunks; every value
        // finite (the packed fold), a tenth each NaN and infinities, or one
        // odd value in one chunk (that chunk folded again): the same as
        // the plain fold.
        let mut rng = 0x9E37_79B9_7F4A_7C15u64;
        let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
        for (len, mix) in [0usize, 1, 15, 16, 17, 4095, 4096, 4097, 9000].into_iter().flat_map(|l| (0..5).map(move |m| (l, m))) {
            let mut v: Vec<f32> = (0..len)
                .map(|_| {
                    rng ^= rng << 13;
                    rng ^= rng >> 7;
                    rng ^= rng << 17;
                    match (mix, rng % 10) {
                        (0, k) if k < 3 => odd[k as usize],
                        _ => (rng >> 40) as f32 - 8e6,
                    }
                })
                .collect();
            if mix >= 2 && len > 0 {
                let at = (rng as usize) % len;
                v[at] = odd[mix - 2];
            }
            let mut st = crate::SampleStats::default();
            crate::sample_stats(&v, &mut st);
            let finite: Vec<f32> = v.iter().copied().filter(|x| x.is_finite()).collect();
            let want = (!finite.is_empty()).then(|| [finite.iter().copied().fold(f32::INFINITY, f32::min), finite.iter().copied().fold(f32::NEG_INFINITY, f32::max)]);
            assert_eq!(st.range, want, "len {len}, mix {mix}");
            assert_eq!(st.nan, v.iter().filter(|x| x.is_nan()).count() as u64, "len {len}, mix {mix}");
        }
        let mut st = crate::SampleStats::default();
        crate::sample_stats(&[f32::INFINITY, f32::NAN], &mut st);
        assert_eq!((st.range, st.nan), (None, 1));
    }

    #[test]
    fn slices_read_on_threads_equal_the_serial_read_and_name_the_first_bad_slice() {
        let dir = tempfile::tempdir().unwrap();
        let dims = [5u64, 3, 11];
        let values: Vec<f32> = (0..165).map(|v| (v * 7 % 23) as f32 - 5.0).collect();
        // Uncompressed (read on threads) and gzip (one stream, read in order).
        for name in ["a.nhdr", "b.nrrd", "c.nii.gz"] {
            let p = dir.path().join(name);
            let plain = dir.path().join(name.trim_end_matches(".gz"));
            let mut w = VolumeWriter::create(&plain, dims, Sample::I16, crate::diagonal_affine([1.0; 3], [0.0; 3]), Frame::Lps).unwrap();
            for k in 0..11 {
                w.write_slice(&values[k * 15..(k + 1) * 15]).unwrap();
            }
            w.finish().unwrap();
            if plain != p {
                let mut z = flate2::write::GzEncoder::new(std::fs::File::create(&p).unwrap(), flate2::Compression::fast());
                std::io::Write::write_all(&mut z, &std::fs::read(&plain).unwrap()).unwrap();
                z.finish().unwrap();
            }
            let mut v = Volume::open(&p, &OpenOptions::default()).unwrap();
            // Read-ahead hints, in range or not, change nothing.
            for (k0, count) in [(0u64, 11u64), (10, 100), (50, 3), (u64::MAX, 2)] {
                v.read_ahead(k0, count);
            }
            for threads in [1, 2, 3, 4, 16] {
                for (k0, count) in [(0u64, 11u64), (3, 5), (10, 1), (4, 0)] {
                    let mut back = vec![f32::NAN; count as usize * 15];
                    v.read_slices_on(k0, count, &mut back, threads).unwrap();
                    assert_eq!(back, values[k0 as usize * 15..(k0 + count) as usize * 15], "{name}, {threads} threads, slices {k0}+{count}");
                }
            }
            let mut short = vec![0.0; 14];
            assert!(v.read_slices_on(0, 1, &mut short, 2).is_err(), "{name}: a buffer of the wrong size");
        }
        // A raw file that shrank after it was opened: slices 7.. are gone,
        // and whatever the threads, the error names slice 7.
        let p = dir.path().join("d.raw");
        std::fs::write(&p, values.iter().flat_map(|&v| (v as i16).to_le_bytes()).collect::<Vec<u8>>()).unwrap();
        let opts = OpenOptions { raw: Some(RawSpec { dims, sample: Sample::I16, big_endian: false, spacing: [1.0; 3], header_bytes: 0 }), dicom_series: None };
        for threads in [1, 2, 3, 4] {
            let mut v = Volume::open(&p, &opts).unwrap();
            std::fs::OpenOptions::new().write(true).open(&p).unwrap().set_len(7 * 15 * 2).unwrap();
            let mut back = vec![0.0; 165];
            let e = v.read_slices_on(0, 11, &mut back, threads).unwrap_err().to_string();
            assert!(e.contains("slice 7 "), "{threads} threads: {e}");
            std::fs::write(&p, values.iter().flat_map(|&v| (v as i16).to_le_bytes()).collect::<Vec<u8>>()).unwrap();
        }
    }

    #[test]
    fn an_unfinished_volume_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.nhdr");
        let mut w = VolumeWriter::create(&p, [2, 2, 2], Sample::U8, crate::diagonal_affine([1.0; 3], [0.0; 3]), Frame::Unnamed).unwrap();
        w.write_slice(&[1.0, 2.0, 300.0, -4.0]).unwrap();
        assert!(w.finish().unwrap_err().to_string().contains("1 of 2 slices written"));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
