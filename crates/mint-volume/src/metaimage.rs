//! MetaImage (ITK/VTK, <https://itk.org/Wiki/ITK/MetaIO/Documentation>): a
//! text header of `Key = Value` lines, detached (`.mhd` naming an
//! `ElementDataFile`) or attached (`.mha`, `ElementDataFile = LOCAL`, the
//! data after that line). Data in one file, a `LIST` of files (one per
//! slice, names on the lines after) or a printf pattern `name%03d.raw min
//! max step`; `CompressedData = True` is one zlib stream.
//!
//! World frame: ITK writes physical points in LPS. `Offset` (or
//! `Position`/`Origin`) is voxel (0,0,0)'s centre, `TransformMatrix` (or
//! `Rotation`/`Orientation`, row-major as written: its rows are the axes'
//! directions) turns the axes, `ElementSpacing` scales them. A header
//! without a matrix or offset is still LPS-placed at the origin (ITK's
//! convention), and named so.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::decode::{Decoder, Sample};
use crate::source::{sample_count, Compression, FileSlices, Skip, SliceSource};
use crate::{Frame, VolumeError, VolumeInfo};

const MAX_HEADER: u64 = 1 << 20;

pub(crate) fn open(path: &Path) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    let mut f = std::fs::File::open(path).map_err(|e| VolumeError::io(path, "opening the header", e))?;
    let mut head = Vec::new();
    (&mut f).take(MAX_HEADER).read_to_end(&mut head).map_err(|e| VolumeError::io(path, "reading the header", e))?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let err = |line: usize, msg: String| VolumeError::format(path, format!("line {line}: {msg}"));

    let mut ndims = None;
    let mut dims: Option<Vec<u64>> = None;
    let mut spacing: Option<Vec<f64>> = None;
    let mut offset: Option<Vec<f64>> = None;
    let mut matrix: Option<Vec<f64>> = None;
    let mut sample = None;
    let mut msb = false;
    let mut compressed = false;
    let mut header_size: i64 = 0;
    let mut channels = 1u64;
    let mut data: Option<(Vec<PathBuf>, u64)> = None; // files and the byte where LOCAL data starts
    let mut at = 0usize;
    let mut lineno = 0;
    while at < head.len() {
        let rest = &head[at..];
        let nl = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        lineno += 1;
        let line = std::str::from_utf8(&rest[..nl]).map_err(|_| err(lineno, "not text".into()))?.trim();
        at += (nl + 1).min(rest.len());
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (key, value) = line.split_once('=').ok_or_else(|| err(lineno, format!("`{line}` is not a `Key = Value` line")))?;
        let (key, value) = (key.trim(), value.trim());
        let nums = |n: Option<usize>| -> Result<Vec<f64>, VolumeError> {
            let v: Vec<f64> = value.split_whitespace().map(str::parse).collect::<Result<_, _>>().map_err(|_| err(lineno, format!("{key}: `{value}` is not numbers")))?;
            if let Some(n) = n.filter(|&n| v.len() != n) {
                return Err(err(lineno, format!("{key}: {} values, expected {n}", v.len())));
            }
            Ok(v)
        };
        let truth = || value.eq_ignore_ascii_case("true") || value == "1";
        match key {
            "NDims" => ndims = Some(value.parse::<usize>().map_err(|_| err(lineno, format!("NDims: `{value}`")))?),
            "DimSize" => {
                let v: Vec<u64> = value.split_whitespace().map(str::parse).collect::<Result<_, _>>().map_err(|_| err(lineno, format!("DimSize: `{value}` is not whole numbers")))?;
                dims = Some(v);
            }
            "ElementSpacing" => spacing = Some(nums(None)?),
            "Offset" | "Position" | "Origin" => offset = Some(nums(None)?),
            "TransformMatrix" | "Rotation" | "Orientation" => matrix = Some(nums(None)?),
            "ElementType" => {
                sample = Some(match value {
                    "MET_UCHAR" => Sample::U8,
                    "MET_CHAR" => Sample::I8,
                    "MET_USHORT" => Sample::U16,
                    "MET_SHORT" => Sample::I16,
                    "MET_UINT" | "MET_ULONG" => Sample::U32,
                    "MET_INT" | "MET_LONG" => Sample::I32,
                    "MET_ULONG_LONG" => Sample::U64,
                    "MET_LONG_LONG" => Sample::I64,
                    "MET_FLOAT" => Sample::F32,
                    "MET_DOUBLE" => Sample::F64,
                    other => return Err(VolumeError::unsupported(path, format!("line {lineno}: ElementType {other}"))),
                })
            }
            "ElementByteOrderMSB" | "BinaryDataByteOrderMSB" => msb = truth(),
            "CompressedData" => compressed = truth(),
            "HeaderSize" => header_size = value.parse().map_err(|_| err(lineno, format!("HeaderSize: `{value}`")))?,
            "ElementNumberOfChannels" => channels = value.parse().map_err(|_| err(lineno, format!("ElementNumberOfChannels: `{value}`")))?,
            "ObjectType" if !value.eq_ignore_ascii_case("Image") => {
                return Err(VolumeError::unsupported(path, format!("line {lineno}: ObjectType {value} (mint reads images)")));
            }
            "ElementDataFile" => {
                let toks: Vec<&str> = value.split_whitespace().collect();
                if value.eq_ignore_ascii_case("LOCAL") {
                    data = Some((vec![path.to_path_buf()], at as u64));
                } else if toks.first().is_some_and(|t| t.eq_ignore_ascii_case("LIST")) {
                    let mut files = Vec::new();
                    for l in std::str::from_utf8(&head[at..]).map_err(|_| err(lineno, "the file list is not text".into()))?.lines() {
                        files.extend(l.split_whitespace().map(|t| dir.join(t)));
                    }
                    data = Some((files, 0));
                } else if toks.len() >= 4 && toks[0].contains('%') {
                    let n = |t: &str| t.parse::<i64>().map_err(|_| err(lineno, format!("ElementDataFile: `{t}` is not a whole number")));
                    let (lo, hi, step) = (n(toks[1])?, n(toks[2])?, n(toks[3])?);
                    if step <= 0 {
                        return Err(err(lineno, format!("ElementDataFile: the step {step} is not positive")));
                    }
                    let names = crate::nrrd::pattern_files(toks[0], lo, hi, step).map_err(|why| err(lineno, format!("ElementDataFile: {why}")))?;
                    data = Some((names.into_iter().map(|n| dir.join(n)).collect(), 0));
                } else {
                    data = Some((vec![dir.join(value)], 0));
                }
                if let Some((files, _)) = &data {
                    crate::check_data_files(path, lineno, files)?;
                }
                break; // ElementDataFile is the header's last line
            }
            _ => {}
        }
    }
    let n = ndims.ok_or_else(|| VolumeError::format(path, "no NDims"))?;
    let d = dims.ok_or_else(|| VolumeError::format(path, "no DimSize"))?;
    if d.len() != n {
        return Err(VolumeError::format(path, format!("DimSize has {} values for NDims {n}", d.len())));
    }
    let dims: [u64; 3] = match d.as_slice() {
        [a, b, c] => [*a, *b, *c],
        [a, b] => [*a, *b, 1],
        [a, b, c, 1] => [*a, *b, *c],
        _ => return Err(VolumeError::unsupported(path, format!("NDims {n}: mint reads 3-D scalar volumes"))),
    };
    if channels != 1 {
        return Err(VolumeError::unsupported(path, format!("ElementNumberOfChannels {channels}: mint reads scalar volumes")));
    }
    sample_count(path, dims)?;
    let sample = sample.ok_or_else(|| VolumeError::format(path, "no ElementType"))?;
    let (files, local) = data.ok_or_else(|| VolumeError::format(path, "no ElementDataFile"))?;
    let sp = spacing.unwrap_or_else(|| vec![1.0; n]);
    if sp.len() < n.min(3) {
        return Err(VolumeError::format(path, format!("ElementSpacing has {} values for NDims {n}", sp.len())));
    }
    let k = n.min(3);
    let mut m = [[0.0; 4]; 3];
    let rot = match &matrix {
        Some(r) if r.len() == k * k => r.clone(),
        Some(r) => return Err(VolumeError::format(path, format!("TransformMatrix has {} values for NDims {n}", r.len()))),
        None => (0..k * k).map(|i| if i / k == i % k { 1.0 } else { 0.0 }).collect(),
    };
    for c in 0..3 {
        let s = if c < k { sp[c] } else { 1.0 };
        for r in 0..3 {
            // ITK writes the direction matrix row by row; column c of the
            // direction matrix is axis c's direction.
            let dir_rc = if r < k && c < k { rot[r * k + c] } else if r == c { 1.0 } else { 0.0 };
            m[r][c] = dir_rc * s;
        }
    }
    if let Some(o) = &offset {
        for r in 0..k.min(o.len()) {
            m[r][3] = o[r];
        }
    }
    let decoder = Decoder { sample, big_endian: msb, slope: 1.0, intercept: 0.0 };
    let compression = if compressed { Compression::Zlib } else { Compression::None };
    let slice_len = dims[0] * dims[1];
    let src = if local > 0 {
        if header_size != 0 {
            return Err(VolumeError::unsupported(path, "HeaderSize with LOCAL data"));
        }
        if compressed {
            FileSlices::new(files.clone(), dims[2], slice_len, Skip::Bytes(0), compression, decoder)?.with_file_start(local)
        } else {
            FileSlices::new(files.clone(), dims[2], slice_len, Skip::Bytes(local), compression, decoder)?
        }
    } else {
        let skip = match header_size {
            -1 => Skip::FromEnd,
            h if h >= 0 => Skip::Bytes(h as u64),
            h => return Err(VolumeError::format(path, format!("HeaderSize {h}: only -1 or a byte count"))),
        };
        FileSlices::new(files.clone(), dims[2], slice_len, skip, compression, decoder)?
    };
    let mut all = vec![path.to_path_buf()];
    all.extend(files.into_iter().filter(|f| f != path));
    let info = VolumeInfo {
        dims,
        sample,
        index_to_world: m,
        frame: Frame::Lps,
        slope: 1.0,
        intercept: 0.0,
        format: "MetaImage",
        files: all,
        sequential_only: compressed,
    };
    Ok((info, Box::new(src)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OpenOptions, Volume};

    #[test]
    fn the_shared_mr_head() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/volumes/mr-head-mhd-vtk/HeadMRVolume.mhd");
        let mut v = Volume::open(&p, &OpenOptions::default()).unwrap();
        assert_eq!(v.info().dims, [48, 62, 42]);
        assert_eq!(v.info().sample, Sample::U8);
        assert_eq!(v.info().world([1.0, 1.0, 1.0]), [4.0, 4.0, 4.0]);
        let mut s = vec![0.0; 48 * 62 * 42];
        v.read_slices(0, 42, &mut s).unwrap();
        assert!(s.iter().any(|&x| x > 100.0));
    }

    #[test]
    fn attached_zlib_with_a_matrix() {
        let dir = tempfile::tempdir().unwrap();
        let samples: Vec<u8> = (0..24u16).flat_map(|v| v.to_le_bytes()).collect();
        let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        std::io::Write::write_all(&mut e, &samples).unwrap();
        let mut file = b"ObjectType = Image\nNDims = 3\nDimSize = 2 3 4\nElementSpacing = 1 2 3\nOffset = 5 6 7\nTransformMatrix = 0 1 0 -1 0 0 0 0 1\nElementType = MET_USHORT\nCompressedData = True\nElementDataFile = LOCAL\n".to_vec();
        file.extend(e.finish().unwrap());
        let p = dir.path().join("a.mha");
        std::fs::write(&p, &file).unwrap();
        let mut v = Volume::open(&p, &OpenOptions::default()).unwrap();
        // Axis i runs along column 0 of the matrix, (0, -1, 0), scaled by 1.
        assert_eq!(v.info().world([1.0, 0.0, 0.0]), [5.0, 5.0, 7.0]);
        assert_eq!(v.info().world([0.0, 1.0, 0.0]), [7.0, 6.0, 7.0]);
        let mut s = vec![0.0; 24];
        v.read_slices(0, 4, &mut s).unwrap();
        assert_eq!(s[23], 23.0);
    }

    #[test]
    fn a_short_data_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("d.raw"), [0u8; 20]).unwrap();
        let p = dir.path().join("a.mhd");
        std::fs::write(&p, "NDims = 3\nDimSize = 3 3 3\nElementType = MET_UCHAR\nElementDataFile = d.raw\n").unwrap();
        let e = Volume::open(&p, &OpenOptions::default()).unwrap_err().to_string();
        assert!(e.contains("d.raw: holds 20 bytes") && e.contains("do not match"), "{e}");
        std::fs::write(&p, "NDims = 3\nDimSize = 3 3\nElementType = MET_UCHAR\nElementDataFile = d.raw\n").unwrap();
        let e = Volume::open(&p, &OpenOptions::default()).unwrap_err().to_string();
        assert!(e.contains("DimSize has 2 values for NDims 3"), "{e}");
    }
}
