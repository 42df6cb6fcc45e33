//! mint's own range-grid file (`.rgrid`): a grid of depths and how to turn
//! them into points, for scanners and tools that do not write PLY range
//! images. [`read_depth_grid`] gives a [`RangeImage`]; [`write_depth_grid`]
//! writes an orthographic image (as `mint scan` makes) back.
//!
//! The format (also in docs/FORMATS.md): a text header of one keyword and
//! its values per line, then the depths.
//!
//! ```text
//! mint_range_grid 1
//! format ascii
//! cols 640
//! rows 480
//! projection orthographic X0 Y0 DX DY
//! comment anything
//! end_header
//! ```
//!
//! (`format` is `ascii` or `binary_little_endian`; `projection` is
//! `orthographic X0 Y0 DX DY` or `pinhole FX FY CX CY`. Lines starting with
//! `comment` are the only comments.)
//!
//! - `projection orthographic X0 Y0 DX DY`: the sample of cell (col, row)
//!   with depth d is `(X0 + col·DX, Y0 + row·DY, d)`; the scanner looks
//!   down −z (z grows toward it), as a translating line scanner does.
//! - `projection pinhole FX FY CX CY`: a camera at the origin looking down
//!   −z; depth d is the distance along the optical axis, and the sample is
//!   `((col − CX)·d/FX, (CY − row)·d/FY, −d)`. Confidence in mint uses one
//!   view direction per scan (+z here), which is exact for orthographic
//!   scans and an approximation away from the image centre for pinhole
//!   ones.
//! - Data, row-major from row 0: `ascii` — one line per row of `cols`
//!   numbers, `nan` (any case, optionally signed) or `-` for a cell
//!   without a sample;
//!   `binary_little_endian` — `rows·cols` IEEE `f32`, NaN for no sample,
//!   right after the newline of `end_header`.
//!
//! Errors name the file and the header line, the data row and column, or
//! the byte offset: a wrong count of numbers in a row, a truncated file,
//! trailing data, a non-numeric or infinite depth, a missing keyword.

use crate::error::RangeError;
use crate::range_image::RangeImage;
use std::io::Write;
use std::path::Path;

/// How depths become points; see the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    Orthographic { x0: f64, y0: f64, dx: f64, dy: f64 },
    Pinhole { fx: f64, fy: f64, cx: f64, cy: f64 },
}

impl Projection {
    fn point(&self, col: u32, row: u32, d: f64) -> [f64; 3] {
        let (c, r) = (col as f64, row as f64);
        match *self {
            Projection::Orthographic { x0, y0, dx, dy } => [x0 + c * dx, y0 + r * dy, d],
            Projection::Pinhole { fx, fy, cx, cy } => [(c - cx) * d / fx, (cy - r) * d / fy, -d],
        }
    }
}

/// The data encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GridEncoding {
    Ascii,
    BinaryLittleEndian,
}

fn err(path: &Path, at: impl Into<String>, message: impl Into<String>) -> RangeError {
    RangeError::GridSyntax { path: path.to_path_buf(), at: at.into(), message: message.into() }
}

/// True for files that start with the `.rgrid` magic line.
pub fn is_depth_grid(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 15];
    std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head)).is_ok() && &head == b"mint_range_grid"
}

/// Reads a `.rgrid` file; see the module docs.
pub fn read_depth_grid(path: &Path) -> Result<RangeImage, RangeError> {
    let bytes = std::fs::read(path).map_err(|source| RangeError::File { path: path.to_path_buf(), what: "cannot read the range grid", source })?;
    // The header: lines up to `end_header`.
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let (mut cols, mut rows, mut encoding, mut projection) = (None, None, None, None);
    loop {
        line_no += 1;
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err(path, format!("line {line_no}"), "the header ends before end_header"));
        };
        let line = std::str::from_utf8(&bytes[pos..pos + len]).map_err(|_| err(path, format!("line {line_no}"), "the header is not text"))?;
        pos += len + 1;
        let line = line.trim_end_matches('\r');
        let words: Vec<&str> = line.split_whitespace().collect();
        let at = format!("line {line_no}");
        if line_no == 1 {
            if line != "mint_range_grid 1" {
                return Err(err(path, at, "not a mint range grid (the first line must be 'mint_range_grid 1')"));
            }
            continue;
        }
        match words.first().copied() {
            None | Some("comment") => {}
            Some("end_header") => break,
            Some("format") => {
                encoding = Some(match words.get(1..) {
                    Some(["ascii"]) => GridEncoding::Ascii,
                    Some(["binary_little_endian"]) => GridEncoding::BinaryLittleEndian,
                    _ => return Err(err(path, at, "format must be 'ascii' or 'binary_little_endian'")),
                })
            }
            Some(k @ ("cols" | "rows")) => {
                let n = words.get(1).and_then(|w| w.parse::<u32>().ok()).filter(|&n| n > 0 && words.len() == 2).ok_or_else(|| err(path, &at, format!("'{k}' needs one positive integer")))?;
                if k == "cols" {
                    cols = Some(n)
                } else {
                    rows = Some(n)
                }
            }
            Some("projection") => {
                let kind = words.get(1).copied().unwrap_or("");
                let rest: Vec<f64> = words[2.min(words.len())..]
                    .iter()
                    .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| err(path, &at, format!("'{w}' is not a finite number"))))
                    .collect::<Result<_, _>>()?;
                if rest.len() != 4 {
                    return Err(err(path, at, format!("'projection {kind}' needs 4 numbers, found {}", rest.len())));
                }
                projection = Some(match kind {
                    "orthographic" if rest[2] != 0.0 && rest[3] != 0.0 => Projection::Orthographic { x0: rest[0], y0: rest[1], dx: rest[2], dy: rest[3] },
                    "pinhole" if rest[0] > 0.0 && rest[1] > 0.0 => Projection::Pinhole { fx: rest[0], fy: rest[1], cx: rest[2], cy: rest[3] },
                    "orthographic" => return Err(err(path, at, "orthographic spacings DX and DY must not be 0")),
                    "pinhole" => return Err(err(path, at, "pinhole focal lengths FX and FY must be positive")),
                    _ => return Err(err(path, at, "projection must be 'orthographic X0 Y0 DX DY' or 'pinhole FX FY CX CY'")),
                });
            }
            Some(other) => return Err(err(path, at, format!("unknown keyword '{other}'"))),
        }
    }
    let missing = |k: &str| err(path, "header", format!("'{k}' is missing"));
    let cols = cols.ok_or_else(|| missing("cols"))?;
    let rows = rows.ok_or_else(|| missing("rows"))?;
    let encoding = encoding.ok_or_else(|| missing("format"))?;
    let projection = projection.ok_or_else(|| missing("projection"))?;
    let n = cols as u64 * rows as u64;
    if n > u32::MAX as u64 {
        return Err(err(path, "header", format!("{cols} x {rows} cells is too many")));
    }
    // Nothing is sized from the header before the data confirms it: a
    // header can claim any size.
    let mut depths: Vec<f64> = Vec::new();
    match encoding {
        GridEncoding::BinaryLittleEndian => {
            let need = n as usize * 4;
            let have = bytes.len() - pos;
            if have < need {
                return Err(err(path, format!("byte {}", bytes.len()), format!("truncated: {rows} x {cols} depths need {need} bytes after the header, found {have}")));
            }
            if have > need {
                return Err(err(path, format!("byte {}", pos + need), format!("{} bytes of unexpected data after the last depth", have - need)));
            }
            depths.reserve_exact(n as usize);
            for (k, ch) in bytes[pos..].chunks_exact(4).enumerate() {
                let v = f32::from_le_bytes([ch[0], ch[1], ch[2], ch[3]]) as f64;
                if v.is_infinite() {
                    return Err(err(path, format!("byte {} (row {}, col {})", pos + 4 * k, k as u32 / cols, k as u32 % cols), "infinite depth"));
                }
                depths.push(v);
            }
        }
        GridEncoding::Ascii => {
            let text = std::str::from_utf8(&bytes[pos..]).map_err(|e| err(path, format!("byte {}", pos + e.valid_up_to()), "the ascii data is not text"))?;
            let mut row = 0u32;
            for (k, line) in text.lines().enumerate() {
                let at_line = line_no + 1 + k;
                if line.trim().is_empty() {
                    continue;
                }
                if row == rows {
                    return Err(err(path, format!("line {at_line}"), format!("more than the {rows} rows the header declares")));
                }
                let before = depths.len();
                for (c, w) in line.split_whitespace().enumerate() {
                    let v = if w == "-" || w.trim_start_matches(['-', '+']).eq_ignore_ascii_case("nan") {
                        f64::NAN
                    } else {
                        w.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| err(path, format!("line {at_line} (row {row}, col {c})"), format!("'{w}' is not a finite depth or nan")))?
                    };
                    depths.push(v);
                }
                let got = depths.len() - before;
                if got != cols as usize {
                    return Err(err(path, format!("line {at_line} (row {row})"), format!("{got} depths, the header declares {cols} columns")));
                }
                row += 1;
            }
            if row != rows {
                return Err(err(path, "end of file", format!("truncated: {row} of {rows} rows")));
            }
        }
    }
    let mut cells = vec![None; n as usize];
    let mut points = Vec::new();
    for (k, &d) in depths.iter().enumerate() {
        if d.is_nan() {
            continue;
        }
        cells[k] = Some(points.len() as u32);
        points.push(projection.point(k as u32 % cols, k as u32 / cols, d));
    }
    if points.is_empty() {
        return Err(RangeError::empty(path, "the range grid has no samples"));
    }
    Ok(RangeImage { cols, rows, cells, points })
}

/// Writes an orthographic range image as a `.rgrid`, atomically: its
/// samples must lie on the lattice `(X0 + col·DX, Y0 + row·DY)` (within
/// 1e-6 of a spacing), as `mint scan`'s do; the depth is z.
pub fn write_depth_grid(path: &Path, im: &RangeImage, encoding: GridEncoding, comments: &[String]) -> Result<(), RangeError> {
    let p = |c: u32, r: u32| im.at(c, r).map(|i| im.points[i as usize]);
    // The lattice from the samples: DX from two samples in a row, DY in a
    // column (any two will do when the image is a lattice; checked below).
    let mut first = None;
    let (mut dx, mut dy) = (None, None);
    for r in 0..im.rows {
        for c in 0..im.cols {
            if let Some(q) = p(c, r) {
                match first {
                    None => first = Some((c, r, q)),
                    Some((c0, r0, q0)) => {
                        if dx.is_none() && c != c0 {
                            dx = Some((q[0] - q0[0]) / (c as f64 - c0 as f64));
                        }
                        if dy.is_none() && r != r0 {
                            dy = Some((q[1] - q0[1]) / (r as f64 - r0 as f64));
                        }
                    }
                }
            }
        }
    }
    let (c0, r0, q0) = first.ok_or_else(|| RangeError::empty(path, "the range image has no samples"))?;
    let (dx, dy) = (dx.unwrap_or(1.0), dy.unwrap_or(1.0));
    if !(dx.is_finite() && dy.is_finite() && dx != 0.0 && dy != 0.0) {
        return Err(err(path, "writing", format!("the samples do not form an orthographic lattice (spacing {dx}, {dy}); write a PLY range image instead")));
    }
    let (x0, y0) = (q0[0] - c0 as f64 * dx, q0[1] - r0 as f64 * dy);
    let tol = 1e-6 * dx.abs().max(dy.abs());
    for r in 0..im.rows {
        for c in 0..im.cols {
            if let Some(q) = p(c, r) {
                if (q[0] - (x0 + c as f64 * dx)).abs() > tol || (q[1] - (y0 + r as f64 * dy)).abs() > tol {
                    return Err(err(path, format!("writing col {c}, row {r}"), "the sample is off the orthographic lattice; write a PLY range image instead"));
                }
            }
        }
    }
    let io_err = |e: std::io::Error| RangeError::File { path: path.to_path_buf(), what: "cannot write the range grid", source: e };
    let mut buf = Vec::new();
    let enc = match encoding {
        GridEncoding::Ascii => "ascii",
        GridEncoding::BinaryLittleEndian => "binary_little_endian",
    };
    write!(buf, "mint_range_grid 1\nformat {enc}\ncols {}\nrows {}\nprojection orthographic {x0:e} {y0:e} {dx:e} {dy:e}\n", im.cols, im.rows).map_err(io_err)?;
    for c in comments {
        writeln!(buf, "comment {}", c.replace(['\n', '\r'], " ")).map_err(io_err)?;
    }
    buf.extend_from_slice(b"end_header\n");
    for r in 0..im.rows {
        for c in 0..im.cols {
            let z = p(c, r).map_or(f64::NAN, |q| q[2]);
            match encoding {
                GridEncoding::BinaryLittleEndian => buf.extend_from_slice(&(z as f32).to_le_bytes()),
                GridEncoding::Ascii => {
                    if c > 0 {
                        buf.push(b' ');
                    }
                    if z.is_nan() {
                        buf.extend_from_slice(b"nan");
                    } else {
                        write!(buf, "{}", z as f32).map_err(io_err)?;
                    }
                }
            }
        }
        if encoding == GridEncoding::Ascii {
            buf.push(b'\n');
        }
    }
    let mut f = mint_io::AtomicFile::create(path)?;
    f.as_file_mut().write_all(&buf).map_err(io_err)?;
    f.commit()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image() -> RangeImage {
        // 4 x 3, one hole, on the lattice x = 0.5 + 0.25 col, y = 1 - 0.5 row.
        let mut cells = Vec::new();
        let mut points = Vec::new();
        for r in 0..3u32 {
            for c in 0..4u32 {
                if (c, r) == (2, 1) {
                    cells.push(None);
                } else {
                    cells.push(Some(points.len() as u32));
                    points.push([0.5 + 0.25 * c as f64, 1.0 - 0.5 * r as f64, 0.125 * (c + r) as f64]);
                }
            }
        }
        RangeImage { cols: 4, rows: 3, cells, points }
    }

    #[test]
    fn both_encodings_round_trip() {
        let d = tempfile::tempdir().unwrap();
        for enc in [GridEncoding::Ascii, GridEncoding::BinaryLittleEndian] {
            let f = d.path().join("a.rgrid");
            write_depth_grid(&f, &image(), enc, &["test".into()]).unwrap();
            assert!(is_depth_grid(&f));
            let back = read_depth_grid(&f).unwrap();
            assert_eq!(back.cells, image().cells);
            for (a, b) in back.points.iter().zip(&image().points) {
                assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-6), "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn pinhole_points_lie_on_their_rays() {
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("p.rgrid");
        std::fs::write(&f, "mint_range_grid 1\nformat ascii\ncols 2\nrows 1\nprojection pinhole 100 100 0.5 0\nend_header\n2 nan\n").unwrap();
        let im = read_depth_grid(&f).unwrap();
        assert_eq!(im.cells, vec![Some(0), None]);
        assert_eq!(im.points[0], [-0.01, 0.0, -2.0]);
    }

    #[test]
    fn bad_files_name_the_place() {
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("b.rgrid");
        let head = "mint_range_grid 1\nformat ascii\ncols 3\nrows 2\nprojection orthographic 0 0 1 1\nend_header\n";
        let cases: [(String, &str); 7] = [
            (format!("{head}1 2 3\n4 5\n"), "line 8 (row 1): 2 depths, the header declares 3 columns"),
            (format!("{head}1 2 3\n"), "end of file: truncated: 1 of 2 rows"),
            (format!("{head}1 2 3\n4 x 6\n"), "line 8 (row 1, col 1): 'x' is not a finite depth or nan"),
            (format!("{head}1 2 3\n4 5 inf\n"), "'inf' is not a finite depth or nan"),
            (head.replace("cols 3\n", ""), "header: 'cols' is missing"),
            (head.replace("orthographic 0 0 1 1", "orthographic 0 0 1"), "line 5: 'projection orthographic' needs 4 numbers, found 3"),
            ("mint_range_grid 1\nformat binary_little_endian\ncols 3\nrows 2\nprojection orthographic 0 0 1 1\nend_header\nabcd".to_string(), "truncated: 2 x 3 depths need 24 bytes after the header, found 4"),
        ];
        // A header may claim anything; nothing is allocated from it before
        // the data confirms it.
        std::fs::write(&f, "mint_range_grid 1\nformat binary_little_endian\ncols 65535\nrows 65535\nprojection orthographic 0 0 1 1\nend_header\nabcd").unwrap();
        let e = read_depth_grid(&f).unwrap_err().to_string();
        assert!(e.contains("truncated: 65535 x 65535 depths need 17179344900 bytes after the header, found 4"), "{e}");
        for (text, want) in cases {
            std::fs::write(&f, text).unwrap();
            let e = read_depth_grid(&f).unwrap_err().to_string();
            assert!(e.starts_with(&f.display().to_string()) && e.contains(want) && !e.contains('\n'), "{e}\nwant: {want}");
        }
    }
}
