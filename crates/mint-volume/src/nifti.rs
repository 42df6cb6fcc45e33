//! NIfTI-1 (<https://nifti.nimh.nih.gov/nifti-1/>): a 348-byte binary
//! header then the samples, in one file (`.nii`, `.nii.gz`: magic `n+1`,
//! data at `vox_offset`) or a pair (`.hdr` + `.img`, magic `ni1`). Byte
//! order from `sizeof_hdr` (348 in the file's order). NIfTI-2 (540-byte
//! header) and 4-D data with more than one volume are refused with one line.
//!
//! World frame: RAS+ (NIfTI's scanner or standard space). The affine is
//! the `sform` when `sform_code > 0`, else the `qform` quaternion when
//! `qform_code > 0` (with `pixdim[0]` = -1 flipping k), else `pixdim`
//! scaling alone (frame unnamed). `scl_slope`/`scl_inter` rescale values
//! (a slope of 0 means none).

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::decode::{Decoder, Sample};
use crate::source::{sample_count, Compression, FileSlices, Skip, SliceSource};
use crate::{diagonal_affine, Frame, VolumeError, VolumeInfo};

pub(crate) fn open(path: &Path) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    let name = path.to_string_lossy().to_ascii_lowercase();
    let gz = name.ends_with(".gz");
    let file = std::fs::File::open(path).map_err(|e| VolumeError::io(path, "opening the header", e))?;
    let mut h = [0u8; 348];
    let got = if gz {
        read_full(flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file)), &mut h)
    } else {
        read_full(file, &mut h)
    }
    .map_err(|e| VolumeError::format(path, format!("reading the header: {e}")))?;
    if got < 348 {
        return Err(VolumeError::format(path, format!("the header is {got} bytes, NIfTI-1 needs 348 (truncated, or not NIfTI)")));
    }
    let le = i32::from_le_bytes(h[0..4].try_into().unwrap());
    let be = i32::from_be_bytes(h[0..4].try_into().unwrap());
    let big = match (le, be) {
        (348, _) => false,
        (_, 348) => true,
        (540, _) | (_, 540) => return Err(VolumeError::unsupported(path, "NIfTI-2 (540-byte header): convert to NIfTI-1")),
        _ => return Err(VolumeError::format(path, format!("bytes 0..4: sizeof_hdr is {le}, not 348 (not a NIfTI-1 file)"))),
    };
    let i16_at = |o: usize| if big { i16::from_be_bytes([h[o], h[o + 1]]) } else { i16::from_le_bytes([h[o], h[o + 1]]) };
    let f32_at = |o: usize| {
        let b: [u8; 4] = h[o..o + 4].try_into().unwrap();
        (if big { f32::from_be_bytes(b) } else { f32::from_le_bytes(b) }) as f64
    };
    let magic = &h[344..348];
    let pair = match magic {
        b"n+1\0" => false,
        b"ni1\0" => true,
        _ => return Err(VolumeError::format(path, "bytes 344..348: no NIfTI-1 magic (`n+1` or `ni1`)")),
    };
    let dim: Vec<i64> = (0..8).map(|i| i16_at(40 + 2 * i) as i64).collect();
    if !(1..=7).contains(&dim[0]) {
        return Err(VolumeError::format(path, format!("dim[0] = {}: not 1..7", dim[0])));
    }
    let nd = dim[0] as usize;
    let size = |i: usize| if i <= nd { dim[i] } else { 1 };
    for i in 1..=nd {
        if dim[i] < 1 {
            return Err(VolumeError::format(path, format!("dim[{i}] = {}: dimensions must be positive", dim[i])));
        }
    }
    let extra: i64 = (4..=7).map(size).product();
    if extra != 1 {
        return Err(VolumeError::unsupported(path, format!("{nd}-D data with {extra} volumes (dim[4..] = {:?}): mint reads one 3-D volume; extract it first", &dim[4..=nd.max(4)])));
    }
    let dims = [size(1) as u64, size(2) as u64, size(3) as u64];
    sample_count(path, dims)?;
    let datatype = i16_at(70);
    let sample = match datatype {
        2 => Sample::U8,
        4 => Sample::I16,
        8 => Sample::I32,
        16 => Sample::F32,
        64 => Sample::F64,
        256 => Sample::I8,
        512 => Sample::U16,
        768 => Sample::U32,
        1024 => Sample::I64,
        1280 => Sample::U64,
        d => return Err(VolumeError::unsupported(path, format!("datatype {d} (complex, RGB or unknown): mint reads scalar volumes"))),
    };
    let bitpix = i16_at(72);
    if bitpix as usize != sample.size() * 8 {
        return Err(VolumeError::format(path, format!("bitpix {bitpix} does not match datatype {datatype} ({} bits)", sample.size() * 8)));
    }
    let pixdim: Vec<f64> = (0..8).map(|i| f32_at(76 + 4 * i)).collect();
    let vox_offset = f32_at(108);
    let (mut slope, mut inter) = (f32_at(112), f32_at(116));
    if slope == 0.0 || !slope.is_finite() {
        (slope, inter) = (1.0, 0.0);
    }
    if !inter.is_finite() {
        inter = 0.0;
    }
    crate::decode::check_rescale(sample, slope, inter).map_err(|m| VolumeError::format(path, format!("scl_slope, scl_inter: {m}")))?;
    let (qform_code, sform_code) = (i16_at(252), i16_at(254));
    let (m, frame) = if sform_code > 0 {
        let mut m = [[0.0; 4]; 3];
        for r in 0..3 {
            for c in 0..4 {
                m[r][c] = f32_at(280 + 16 * r + 4 * c);
            }
        }
        (m, Frame::Ras)
    } else if qform_code > 0 {
        let (b, c, d) = (f32_at(256), f32_at(260), f32_at(264));
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let r = [
            [a * a + b * b - c * c - d * d, 2.0 * (b * c - a * d), 2.0 * (b * d + a * c)],
            [2.0 * (b * c + a * d), a * a + c * c - b * b - d * d, 2.0 * (c * d - a * b)],
            [2.0 * (b * d - a * c), 2.0 * (c * d + a * b), a * a + d * d - b * b - c * c],
        ];
        let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        let s = [pixdim[1], pixdim[2], pixdim[3] * qfac];
        let mut m = [[0.0; 4]; 3];
        for row in 0..3 {
            for col in 0..3 {
                m[row][col] = r[row][col] * s[col];
            }
        }
        m[0][3] = f32_at(268);
        m[1][3] = f32_at(272);
        m[2][3] = f32_at(276);
        (m, Frame::Ras)
    } else {
        let s = [1, 2, 3].map(|i| if pixdim[i] > 0.0 && pixdim[i].is_finite() { pixdim[i] } else { 1.0 });
        (diagonal_affine(s, [0.0; 3]), Frame::Unnamed)
    };
    let decoder = Decoder { sample, big_endian: big, slope, intercept: inter };
    let slice_len = dims[0] * dims[1];
    let (data, skip): (PathBuf, u64) = if pair {
        let stem = path.to_string_lossy();
        let img = if let Some(s) = stem.strip_suffix(".hdr") { format!("{s}.img") } else if let Some(s) = stem.strip_suffix(".hdr.gz") { format!("{s}.img.gz") } else { format!("{stem}.img") };
        (PathBuf::from(img), 0)
    } else {
        if !(vox_offset >= 348.0 && vox_offset < 1e12 && vox_offset.fract() == 0.0) {
            return Err(VolumeError::format(path, format!("vox_offset {vox_offset}: the data must start at a whole byte at or after 348")));
        }
        (path.to_path_buf(), vox_offset as u64)
    };
    let compression = if data.to_string_lossy().to_ascii_lowercase().ends_with(".gz") { Compression::Gzip } else { Compression::None };
    let src = FileSlices::new(vec![data.clone()], dims[2], slice_len, Skip::Bytes(skip), compression, decoder)?;
    let mut files = vec![path.to_path_buf()];
    if data != path {
        files.push(data);
    }
    let info = VolumeInfo {
        dims,
        sample,
        index_to_world: m,
        frame,
        slope,
        intercept: inter,
        format: "NIfTI-1",
        files,
        sequential_only: compression != Compression::None,
    };
    Ok((info, Box::new(src)))
}

fn read_full(mut r: impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// A NIfTI-1 header (`n+1`, little-endian, vox_offset 352) for tests and
/// [`crate::writer`]: dims, datatype code, bits, the sform rows and its code.
pub(crate) fn header(dims: [u64; 3], datatype: i16, bitpix: i16, srow: [[f64; 4]; 3], sform_code: i16) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let d = [3i16, dims[0] as i16, dims[1] as i16, dims[2] as i16, 1, 1, 1, 1];
    for (i, v) in d.iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    h[70..72].copy_from_slice(&datatype.to_le_bytes());
    h[72..74].copy_from_slice(&bitpix.to_le_bytes());
    let pix = [1.0f32, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0];
    for (i, v) in pix.iter().enumerate() {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&v.to_le_bytes());
    }
    for c in 0..3 {
        let s = (srow[0][c].powi(2) + srow[1][c].powi(2) + srow[2][c].powi(2)).sqrt() as f32;
        h[80 + 4 * c..84 + 4 * c].copy_from_slice(&s.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[254..256].copy_from_slice(&sform_code.to_le_bytes());
    for r in 0..3 {
        for c in 0..4 {
            let o = 280 + 16 * r + 4 * c;
            h[o..o + 4].copy_from_slice(&(srow[r][c] as f32).to_le_bytes());
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OpenOptions, Volume};

    fn shared(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/volumes/ct-body-nifti-totalsegmentator").join(name)
    }

    #[test]
    fn the_shared_abdominal_cts() {
        let mut v = Volume::open(&shared("example_ct.nii.gz"), &OpenOptions::default()).unwrap();
        let i = v.info().clone();
        assert_eq!((i.dims, i.sample, i.frame), ([122, 101, 112], Sample::I32, Frame::Ras));
        assert!((0..3).all(|d| (i.spacing(d) - 3.0).abs() < 1e-6));
        let mut s = vec![0.0; i.slice_len() * 112];
        v.read_slices(0, 112, &mut s).unwrap();
        let (lo, hi) = s.iter().fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert_eq!((lo, hi), (-1207.0, 3382.0), "the provenance's range");
        let sm = Volume::open(&shared("example_ct_sm.nii.gz"), &OpenOptions::default()).unwrap();
        assert_eq!((sm.info().dims, sm.info().sample), ([122, 101, 30], Sample::I16));
        assert_eq!(sm.info().index_to_world, i.index_to_world, "the same affine");
    }

    #[test]
    fn an_oblique_sform_puts_a_known_voxel_where_the_header_says() {
        let dir = tempfile::tempdir().unwrap();
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let srow = [[2.0 * c, -3.0 * s, 0.0, 10.0], [2.0 * s, 3.0 * c, 0.0, -20.0], [0.0, 0.0, 4.0, 5.0]];
        let mut f = header([3, 2, 2], 4, 16, srow, 2);
        f.extend((0..12i16).flat_map(|v| v.to_le_bytes()));
        let p = dir.path().join("o.nii");
        std::fs::write(&p, &f).unwrap();
        let mut v = Volume::open(&p, &OpenOptions::default()).unwrap();
        let w = v.info().world([2.0, 1.0, 1.0]);
        let want = [10.0 + 4.0 * c - 3.0 * s, -20.0 + 4.0 * s + 3.0 * c, 9.0];
        for d in 0..3 {
            assert!((w[d] - want[d]).abs() < 1e-5, "{w:?} vs {want:?}");
        }
        let mut out = vec![0.0; 6];
        v.read_slices(1, 1, &mut out).unwrap();
        assert_eq!(out, [6.0, 7.0, 8.0, 9.0, 10.0, 11.0]);
    }

    #[test]
    fn bad_headers_say_what() {
        let dir = tempfile::tempdir().unwrap();
        let good = header([2, 2, 2], 4, 16, [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]], 1);
        let mut cases: Vec<(Vec<u8>, &str)> = Vec::new();
        cases.push((good[..100].to_vec(), "the header is 100 bytes"));
        let mut t = good.clone();
        t.extend([0u8; 10]);
        cases.push((t, "do not match the data"));
        let mut t = good.clone();
        t[70..72].copy_from_slice(&32i16.to_le_bytes());
        cases.push((t, "datatype 32"));
        let mut t = good.clone();
        t[48..50].copy_from_slice(&5i16.to_le_bytes());
        t[40..42].copy_from_slice(&4i16.to_le_bytes());
        cases.push((t, "extract it first"));
        let mut t = good.clone();
        t[344..348].copy_from_slice(b"xyz\0");
        cases.push((t, "no NIfTI-1 magic"));
        for (i, (bytes, want)) in cases.into_iter().enumerate() {
            let p = dir.path().join(format!("c{i}.nii"));
            std::fs::write(&p, &bytes).unwrap();
            let e = Volume::open(&p, &OpenOptions::default()).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains(&format!("c{i}.nii")), "case {i}: {e}");
        }
    }
}
