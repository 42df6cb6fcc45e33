//! NRRD (Teem's "nearly raw raster data", <https://teem.sourceforge.net/nrrd/format.html>):
//! a text header of `field: value` lines, attached (`.nrrd`, data after
//! the first blank line) or detached (`.nhdr` naming `data file`s: one
//! file, a list after `LIST`, or a printf pattern `name.%d min max step`
//! with one or more slices per file). Encodings `raw` and `gzip`/`gz`;
//! `ascii`/`text`, `bzip2` and `hex` are refused with one line.
//!
//! World frame: `space directions` and `space origin` give the affine
//! (columns are the directions of the three axes), `space` names the frame
//! (`left-posterior-superior` → LPS, `right-anterior-superior` → RAS,
//! `scanner-xyz` and the `3D-*-handed` spaces → scanner). Without them,
//! `spacings` (default 1) on a diagonal, origin 0. Cell-centred data is
//! assumed (a voxel's centre at its index), as medical NRRDs are.
//! A 4-D NRRD whose first or last axis has size 1 is read as 3-D.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::decode::{Decoder, Sample};
use crate::source::{sample_count, Compression, FileSlices, Skip, SliceSource};
use crate::{check_data_files, diagonal_affine, Frame, VolumeError, VolumeInfo};

/// The most header bytes read before giving up (a header is a few hundred).
const MAX_HEADER: usize = 1 << 20;

struct Header {
    dims: Vec<u64>,
    sample: Option<Sample>,
    big_endian: Option<bool>,
    encoding: Option<Compression>,
    spacings: Option<Vec<f64>>,
    directions: Option<Vec<Option<[f64; 3]>>>,
    origin: Option<[f64; 3]>,
    frame: Frame,
    data: Option<DataFiles>,
    byte_skip: i64,
    line_skip: u64,
}

enum DataFiles {
    /// The data follows the header in this file.
    Attached,
    Files(Vec<PathBuf>),
}

pub(crate) fn open(path: &Path) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    let mut f = std::fs::File::open(path).map_err(|e| VolumeError::io(path, "opening the header", e))?;
    let mut head = Vec::new();
    (&mut f).take(MAX_HEADER as u64).read_to_end(&mut head).map_err(|e| VolumeError::io(path, "reading the header", e))?;
    let (h, header_end) = parse(path, &head)?;
    // The axes: three, or four with one of size 1 at either end.
    let dims: [u64; 3] = match h.dims.as_slice() {
        [a, b, c] => [*a, *b, *c],
        [1, a, b, c] | [a, b, c, 1] => [*a, *b, *c],
        d => return Err(VolumeError::unsupported(path, format!("dimension {}: mint reads 3-D scalar volumes", d.len()))),
    };
    let lead = if h.dims.len() == 4 && h.dims[0] == 1 { 1 } else { 0 };
    sample_count(path, dims)?;
    let sample = h.sample.ok_or_else(|| VolumeError::format(path, "no `type` field"))?;
    let big_endian = match h.big_endian {
        Some(b) => b,
        None if sample.size() == 1 => false,
        None => return Err(VolumeError::format(path, format!("no `endian` field for {}-byte samples", sample.size()))),
    };
    let compression = h.encoding.ok_or_else(|| VolumeError::format(path, "no `encoding` field"))?;
    // The affine.
    let mut m = diagonal_affine([1.0; 3], [0.0; 3]);
    if let Some(dirs) = &h.directions {
        let dirs: Vec<[f64; 3]> = dirs.iter().skip(lead).take(3).flatten().copied().collect();
        if dirs.len() != 3 {
            return Err(VolumeError::format(path, "`space directions`: three spatial axes need a direction each (not `none`)"));
        }
        for (c, d) in dirs.iter().enumerate() {
            for r in 0..3 {
                m[r][c] = d[r];
            }
        }
    } else if let Some(sp) = &h.spacings {
        let sp: Vec<f64> = sp.iter().skip(lead).take(3).copied().collect();
        for (c, s) in sp.iter().enumerate() {
            m[c][c] = if s.is_nan() { 1.0 } else { *s };
        }
    }
    if let Some(o) = h.origin {
        for r in 0..3 {
            m[r][3] = o[r];
        }
    }
    // The data.
    let (files, skip) = match h.data.unwrap_or(DataFiles::Attached) {
        DataFiles::Attached => {
            if h.line_skip > 0 || h.byte_skip != 0 {
                return Err(VolumeError::unsupported(path, "`line skip` or `byte skip` in an attached header"));
            }
            if compression != Compression::None {
                // The compressed stream starts after the header.
                return finish(path, dims, sample, big_endian, compression, m, h.frame, vec![path.to_path_buf()], SkipAt::Compressed(header_end as u64));
            }
            (vec![path.to_path_buf()], Skip::Bytes(header_end as u64))
        }
        DataFiles::Files(files) => {
            let skip = if h.byte_skip == -1 {
                Skip::FromEnd
            } else if h.byte_skip < 0 {
                return Err(VolumeError::format(path, format!("`byte skip: {}`: only -1 or a byte count", h.byte_skip)));
            } else {
                Skip::Bytes(h.byte_skip as u64)
            };
            if h.line_skip > 0 {
                if files.len() != 1 || compression != Compression::None {
                    return Err(VolumeError::unsupported(path, "`line skip` with several data files or compressed data"));
                }
                let at = line_offset(&files[0], h.line_skip)?;
                let Skip::Bytes(b) = skip else { return Err(VolumeError::unsupported(path, "`line skip` with `byte skip: -1`")) };
                (files, Skip::Bytes(at + b))
            } else {
                (files, skip)
            }
        }
    };
    finish(path, dims, sample, big_endian, compression, m, h.frame, files, SkipAt::Plain(skip))
}

enum SkipAt {
    Plain(Skip),
    /// Compressed data starting at this byte of the file (attached header).
    Compressed(u64),
}

#[allow(clippy::too_many_arguments)]
fn finish(
    path: &Path,
    dims: [u64; 3],
    sample: Sample,
    big_endian: bool,
    compression: Compression,
    m: [[f64; 4]; 3],
    frame: Frame,
    files: Vec<PathBuf>,
    skip: SkipAt,
) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    let decoder = Decoder { sample, big_endian, slope: 1.0, intercept: 0.0 };
    let src: Box<dyn SliceSource> = match skip {
        SkipAt::Plain(skip) => Box::new(FileSlices::new(files.clone(), dims[2], dims[0] * dims[1], skip, compression, decoder)?),
        SkipAt::Compressed(at) => Box::new(FileSlices::new(files.clone(), dims[2], dims[0] * dims[1], Skip::Bytes(0), compression, decoder)?.with_file_start(at)),
    };
    let mut all = vec![path.to_path_buf()];
    all.extend(files.into_iter().filter(|f| f != path));
    let info = VolumeInfo {
        dims,
        sample,
        index_to_world: m,
        frame,
        slope: 1.0,
        intercept: 0.0,
        format: "NRRD",
        files: all,
        sequential_only: compression != Compression::None,
    };
    Ok((info, src))
}

/// The byte after the `n`-th line end of `file`.
fn line_offset(file: &Path, n: u64) -> Result<u64, VolumeError> {
    let f = std::fs::File::open(file).map_err(|e| VolumeError::io(file, "opening the data file", e))?;
    let mut r = std::io::BufReader::new(f);
    let mut at = 0u64;
    let mut line = Vec::new();
    for i in 0..n {
        line.clear();
        let got = std::io::BufRead::read_until(&mut r, b'\n', &mut line).map_err(|e| VolumeError::io(file, "skipping lines", e))?;
        if got == 0 {
            return Err(VolumeError::format(file, format!("`line skip: {n}`: the file has only {i} lines")));
        }
        at += got as u64;
    }
    Ok(at)
}

fn parse(path: &Path, bytes: &[u8]) -> Result<(Header, usize), VolumeError> {
    let err = |line: usize, msg: String| VolumeError::format(path, format!("line {line}: {msg}"));
    if !bytes.starts_with(b"NRRD000") {
        return Err(VolumeError::format(path, "line 1: not an NRRD header (no `NRRD000x` magic)"));
    }
    let mut h = Header {
        dims: Vec::new(),
        sample: None,
        big_endian: None,
        encoding: None,
        spacings: None,
        directions: None,
        origin: None,
        frame: Frame::Unnamed,
        data: None,
        byte_skip: 0,
        line_skip: 0,
    };
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut at = 0usize;
    let mut lineno = 0usize;
    let mut dimension: Option<usize> = None;
    let mut list_files: Option<Vec<PathBuf>> = None;
    let mut data_line = 0;
    loop {
        let rest = &bytes[at..];
        let Some(nl) = rest.iter().position(|&b| b == b'\n') else {
            if list_files.is_some() || rest.is_empty() {
                at = bytes.len();
                break;
            }
            return Err(err(lineno + 1, if bytes.len() >= MAX_HEADER { "the header is longer than 1 MiB".into() } else { "the header ends without a line end".into() }));
        };
        lineno += 1;
        let raw = &rest[..nl];
        at += nl + 1;
        let line = std::str::from_utf8(raw).map_err(|_| err(lineno, "not text".into()))?.trim_end_matches('\r');
        if lineno == 1 {
            continue;
        }
        if let Some(files) = list_files.as_mut() {
            // After `data file: LIST`, every remaining line names a file.
            if line.is_empty() {
                break;
            }
            files.push(dir.join(line.trim()));
            continue;
        }
        if line.is_empty() {
            break;
        }
        if line.starts_with('#') {
            continue;
        }
        let Some((key, value)) = line.split_once(':').filter(|(_, v)| !v.starts_with('=')) else {
            // `key:=value` pairs are free-form metadata.
            if line.contains(":=") {
                continue;
            }
            return Err(err(lineno, format!("`{line}` is not a `field: value` line")));
        };
        let (key, value) = (key.trim().to_ascii_lowercase(), value.trim());
        match key.as_str() {
            "dimension" => dimension = Some(value.parse().map_err(|_| err(lineno, format!("dimension: `{value}`")))?),
            "sizes" => {
                let n = dimension.ok_or_else(|| err(lineno, "sizes before dimension".into()))?;
                let v: Vec<u64> = value.split_whitespace().map(|t| t.parse::<u64>()).collect::<Result<_, _>>().map_err(|_| err(lineno, format!("sizes: `{value}` is not {n} whole numbers")))?;
                if v.len() != n {
                    return Err(err(lineno, format!("sizes: {} values for dimension {n}", v.len())));
                }
                h.dims = v;
            }
            "type" => {
                let t = value.to_ascii_lowercase();
                let t = t.trim_end_matches(" int");
                h.sample = Some(match t {
                    "signed char" | "int8" | "int8_t" => Sample::I8,
                    "uchar" | "unsigned char" | "uint8" | "uint8_t" => Sample::U8,
                    "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => Sample::I16,
                    "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => Sample::U16,
                    "int" | "signed int" | "int32" | "int32_t" | "signed" => Sample::I32,
                    "uint" | "unsigned int" | "uint32" | "uint32_t" | "unsigned" => Sample::U32,
                    "longlong" | "long long" | "long long int" | "signed long long" | "signed long long int" | "int64" | "int64_t" => Sample::I64,
                    "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => Sample::U64,
                    "float" => Sample::F32,
                    "double" => Sample::F64,
                    _ => return Err(VolumeError::unsupported(path, format!("line {lineno}: type `{value}`"))),
                });
            }
            "endian" => {
                h.big_endian = Some(match value.to_ascii_lowercase().as_str() {
                    "little" => false,
                    "big" => true,
                    _ => return Err(err(lineno, format!("endian: `{value}` (little or big)"))),
                })
            }
            "encoding" => {
                h.encoding = Some(match value.to_ascii_lowercase().as_str() {
                    "raw" => Compression::None,
                    "gzip" | "gz" => Compression::Gzip,
                    other => return Err(VolumeError::unsupported(path, format!("line {lineno}: encoding `{other}` (mint reads raw and gzip)"))),
                })
            }
            "spacings" => {
                let n = dimension.ok_or_else(|| err(lineno, "spacings before dimension".into()))?;
                let v: Vec<f64> = value.split_whitespace().map(|t| if t.eq_ignore_ascii_case("nan") { Ok(f64::NAN) } else { t.parse::<f64>() }).collect::<Result<_, _>>().map_err(|_| err(lineno, format!("spacings: `{value}`")))?;
                if v.len() != n {
                    return Err(err(lineno, format!("spacings: {} values for dimension {n}", v.len())));
                }
                h.spacings = Some(v);
            }
            "space" => {
                h.frame = match value.to_ascii_lowercase().as_str() {
                    "left-posterior-superior" | "lps" => Frame::Lps,
                    "right-anterior-superior" | "ras" => Frame::Ras,
                    "scanner-xyz" | "3d-right-handed" | "3d-left-handed" => Frame::Scanner,
                    other => return Err(VolumeError::unsupported(path, format!("line {lineno}: space `{other}` (mint reads 3-D spaces)"))),
                }
            }
            "space dimension" => {
                if value != "3" {
                    return Err(VolumeError::unsupported(path, format!("line {lineno}: space dimension {value}")));
                }
                h.frame = Frame::Scanner;
            }
            "space directions" => {
                let mut dirs = Vec::new();
                for tok in value.split_whitespace() {
                    if tok == "none" {
                        dirs.push(None);
                        continue;
                    }
                    let inner = tok.strip_prefix('(').and_then(|t| t.strip_suffix(')')).ok_or_else(|| err(lineno, format!("space directions: `{tok}` is not `(x,y,z)`")))?;
                    let v: Vec<f64> = inner.split(',').map(|t| t.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| err(lineno, format!("space directions: `{tok}`")))?;
                    if v.len() != 3 {
                        return Err(err(lineno, format!("space directions: `{tok}` is not three numbers")));
                    }
                    dirs.push(Some([v[0], v[1], v[2]]));
                }
                h.directions = Some(dirs);
            }
            "space origin" => {
                let inner = value.strip_prefix('(').and_then(|t| t.strip_suffix(')')).ok_or_else(|| err(lineno, format!("space origin: `{value}` is not `(x,y,z)`")))?;
                let v: Vec<f64> = inner.split(',').map(|t| t.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| err(lineno, format!("space origin: `{value}`")))?;
                if v.len() != 3 {
                    return Err(err(lineno, "space origin: not three numbers".into()));
                }
                h.origin = Some([v[0], v[1], v[2]]);
            }
            "byte skip" => h.byte_skip = value.parse().map_err(|_| err(lineno, format!("byte skip: `{value}`")))?,
            "line skip" => h.line_skip = value.parse().map_err(|_| err(lineno, format!("line skip: `{value}`")))?,
            "data file" | "datafile" => {
                data_line = lineno;
                let toks: Vec<&str> = value.split_whitespace().collect();
                if toks.first().is_some_and(|t| t.eq_ignore_ascii_case("LIST")) {
                    list_files = Some(Vec::new());
                } else if toks.len() >= 4 && toks[0].contains('%') {
                    let n = |t: &str| t.parse::<i64>().map_err(|_| err(lineno, format!("data file: `{t}` in `{value}` is not a whole number")));
                    let (lo, hi, step) = (n(toks[1])?, n(toks[2])?, n(toks[3])?);
                    let names = pattern_files(toks[0], lo, hi, step).map_err(|why| err(lineno, format!("data file: `{value}`: {why}")))?;
                    h.data = Some(DataFiles::Files(names.into_iter().map(|f| dir.join(f)).collect()));
                } else if toks.len() == 1 {
                    h.data = Some(DataFiles::Files(vec![dir.join(toks[0])]));
                } else {
                    return Err(err(lineno, format!("data file: `{value}`")));
                }
            }
            _ => {} // kinds, centerings, labels, units, content, …: not needed
        }
    }
    if let Some(files) = list_files {
        if files.is_empty() {
            return Err(VolumeError::format(path, "data file: LIST names no file"));
        }
        h.data = Some(DataFiles::Files(files));
    }
    if let Some(DataFiles::Files(files)) = &h.data {
        check_data_files(path, data_line, files)?;
    }
    if h.dims.is_empty() {
        return Err(VolumeError::format(path, "no `sizes` field"));
    }
    if let (Some(d), Some(n)) = (&h.directions, dimension) {
        if d.len() != n {
            return Err(VolumeError::format(path, format!("space directions: {} entries for dimension {n}", d.len())));
        }
    }
    Ok((h, at))
}

/// The most files a `pattern lo hi step` data file line may name (one
/// slice each, at least).
const MAX_PATTERN_FILES: i128 = 1 << 20;

/// The file names of `pattern` for `lo, lo + step, …` up to `hi` (NRRD's
/// `data file: name%03d lo hi step`, MetaImage's `ElementDataFile`), or why
/// not: an empty or endless range, or not a pattern with one `%d`.
pub(crate) fn pattern_files(pattern: &str, lo: i64, hi: i64, step: i64) -> Result<Vec<String>, String> {
    let (l, h, s) = (lo as i128, hi as i128, step as i128);
    if s == 0 || (h - l).signum() * s.signum() < 0 || (h - l) / s >= MAX_PATTERN_FILES {
        return Err(format!("the range {lo}..{hi} by {step} is empty or endless (at most {MAX_PATTERN_FILES} files)"));
    }
    (0..=(h - l) / s)
        .map(|c| printf_int(pattern, (l + c * s) as i64).ok_or_else(|| format!("`{pattern}` is not a pattern with one %d")))
        .collect()
}

/// `pattern` with its one `%d`/`%0Nd`/`%Nd` replaced by `i`.
pub(crate) fn printf_int(pattern: &str, i: i64) -> Option<String> {
    let p = pattern.find('%')?;
    let rest = &pattern[p + 1..];
    let d = rest.find(|c: char| !c.is_ascii_digit())?;
    if !matches!(rest.as_bytes()[d], b'd' | b'u' | b'i') || rest[d + 1..].contains('%') {
        return None;
    }
    let spec = &rest[..d];
    // (A width is a few digits; a huge one, found by fuzzing, made the
    // formatter ask for petabytes.)
    let width: usize = if spec.is_empty() { 0 } else { spec.parse().ok().filter(|&w| w <= 32)? };
    let num = if spec.starts_with('0') { format!("{i:0width$}") } else { format!("{i:width$}") };
    Some(format!("{}{}{}", &pattern[..p], num, &rest[d + 1..]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OpenOptions, Volume};

    fn data(rel: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/volumes").join(rel)
    }

    #[test]
    fn the_shared_head_reads_one_file_per_slice() {
        let mut v = Volume::open(&data("ct-head-headsq-nrrd/quarter.nhdr"), &OpenOptions::default()).unwrap();
        let info = v.info().clone();
        assert_eq!(info.dims, [64, 64, 93]);
        assert_eq!(info.sample, Sample::I16);
        assert_eq!(info.files.len(), 94);
        assert!(info.files[93].ends_with("quarter.93"));
        assert_eq!((info.spacing(0), info.spacing(1), info.spacing(2)), (3.2, 3.2, 1.5));
        assert_eq!(info.frame, Frame::Scanner);
        let mut s = vec![0.0; 64 * 64 * 93];
        v.read_slices(0, 93, &mut s).unwrap();
        let (lo, hi) = s.iter().fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert_eq!((lo, hi), (0.0, 3926.0), "the provenance's range");
        // Slice 40 alone, from a clone, is the same.
        let mut c = v.try_clone().unwrap();
        let mut one = vec![0.0; 64 * 64];
        c.read_slices(40, 1, &mut one).unwrap();
        assert_eq!(one, s[40 * 4096..41 * 4096]);
    }

    #[test]
    fn patterns_expand_like_printf() {
        assert_eq!(printf_int("quarter.%d", 7).unwrap(), "quarter.7");
        assert_eq!(printf_int("s%03d.raw", 7).unwrap(), "s007.raw");
        assert_eq!(printf_int("s%3d.raw", 7).unwrap(), "s  7.raw");
        assert!(printf_int("s%s.raw", 7).is_none());
        assert!(printf_int("s%d%d.raw", 7).is_none());
        // Found by fuzzing: a width of 16 digits made the formatter panic.
        assert!(printf_int("s%8000000000800d.raw", 7).is_none());
    }

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn attached_raw_and_gzip_with_directions() {
        let dir = tempfile::tempdir().unwrap();
        let samples: Vec<u8> = (0..24u16).flat_map(|v| v.to_be_bytes()).collect();
        let head = "NRRD0004\ntype: unsigned short\ndimension: 3\nsizes: 2 3 4\nendian: big\nspace: right-anterior-superior\nspace directions: (0,2,0) (-1,0,0) (0,0,3)\nspace origin: (10,20,30)\n";
        let mut raw = format!("{head}encoding: raw\n\n").into_bytes();
        raw.extend(&samples);
        let p = write(dir.path(), "a.nrrd", &raw);
        let mut v = Volume::open(&p, &OpenOptions::default()).unwrap();
        assert_eq!(v.info().frame, Frame::Ras);
        assert_eq!(v.info().world([1.0, 1.0, 1.0]), [9.0, 22.0, 33.0]);
        let mut s = vec![0.0; 24];
        v.read_slices(0, 4, &mut s).unwrap();
        assert_eq!(s, (0..24).map(|v| v as f32).collect::<Vec<_>>());
        // The same samples gzip-compressed after the header.
        let mut gz = format!("{head}encoding: gzip\n\n").into_bytes();
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        std::io::Write::write_all(&mut e, &samples).unwrap();
        gz.extend(e.finish().unwrap());
        let p = write(dir.path(), "b.nrrd", &gz);
        let mut v = Volume::open(&p, &OpenOptions::default()).unwrap();
        assert!(v.info().sequential_only);
        let mut t = vec![0.0; 6];
        v.read_slices(3, 1, &mut t).unwrap();
        assert_eq!(t, s[18..]);
        v.read_slices(1, 1, &mut t).unwrap();
        assert_eq!(t, s[6..12], "an earlier slice restarts the stream");
    }

    #[test]
    fn bad_headers_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let cases: &[(&str, &str)] = &[
            ("NRRD0004\ntype: short\ndimension: 3\nsizes: 2 3\n", "line 4: sizes: 2 values for dimension 3"),
            ("NRRD0004\ntype: quaternion\n", "line 2: type `quaternion`"),
            ("NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n\n\x01\x02", "the dimensions do not match the data"),
            ("NRRD0004\ntype: short\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\nendian: little\nencoding: raw\n\n", "overflow"),
            ("NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: bzip2\n\n", "encoding `bzip2`"),
            ("NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\ndata file: missing.raw\n", "missing.raw"),
            ("NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\ndata file: s%d.raw 1 0 1\n", "empty or endless"),
            ("NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nspace directions: (1,0,0) (1,0,0) (0,0,1)\nendian: little\nencoding: raw\n\n1234567812345678", "degenerate"),
            ("PNG", "not an NRRD header"),
            ("NRRD0004\nsizes 2 2 2\n", "line 2: `sizes 2 2 2` is not a `field: value` line"),
        ];
        for (i, (text, want)) in cases.iter().enumerate() {
            let p = write(dir.path(), &format!("c{i}.nhdr"), text.as_bytes());
            let e = Volume::open(&p, &OpenOptions::default()).unwrap_err().to_string();
            assert!(e.contains(want), "case {i}: {e}");
            assert!(e.starts_with(&dir.path().display().to_string()), "names the file: {e}");
            assert!(!e.contains('\n'));
        }
    }

    #[test]
    fn a_truncated_gzip_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let mut gz = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n\n".to_vec();
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        std::io::Write::write_all(&mut e, &[7u8; 40]).unwrap();
        gz.extend(e.finish().unwrap());
        let p = write(dir.path(), "t.nrrd", &gz);
        let mut v = Volume::open(&p, &OpenOptions::default()).unwrap();
        let mut s = vec![0.0; 64];
        let e = v.read_slices(0, 4, &mut s).unwrap_err().to_string();
        assert!(e.contains("ends inside slice 2"), "{e}");
    }
}
