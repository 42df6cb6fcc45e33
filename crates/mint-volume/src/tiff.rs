//! TIFF stacks, the usual micro-CT export: a folder of single-page TIFF
//! files (one slice each, ordered by the numbers in their names, so that
//! `slice_2.tif` comes before `slice_10.tif`; ties by the whole name), or
//! one multi-page file (an ImageJ stack, one page per slice). Decoding is
//! the `tiff` crate's (uncompressed, LZW, deflate, PackBits; strips or
//! tiles); a page is decoded whole, so memory is one slice.
//!
//! Contract: grey samples only (one channel of 8 to 64 bits, unsigned,
//! signed or float); every page or file has the first one's size and
//! sample type, else one line names it and both. Spacing: 1 on every axis
//! and no frame, unless the file is ImageJ's (its `ImageDescription` holds
//! `ImageJ=`), whose `spacing=` gives the slice step and XResolution /
//! YResolution (pixels per unit) the in-plane spacing.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use tiff::decoder::{ifd::Value, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

use crate::decode::Sample;
use crate::source::SliceSource;
use crate::{diagonal_affine, Frame, VolumeError, VolumeInfo};

fn is_tiff_name(p: &Path) -> bool {
    p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).is_some_and(|e| e == "tif" || e == "tiff")
}

/// True when the folder holds TIFF files (it is then read as a stack).
pub(crate) fn is_stack_dir(dir: &Path) -> Result<bool, VolumeError> {
    let rd = std::fs::read_dir(dir).map_err(|e| VolumeError::io(dir, "listing the folder", e))?;
    Ok(rd.flatten().any(|e| e.path().is_file() && is_tiff_name(&e.path())))
}

/// A name's sort key: its runs of digits as numbers, the rest as text.
fn natural_key(name: &str) -> Vec<(u8, u128, String)> {
    let mut key = Vec::new();
    let mut chars = name.chars().peekable();
    while let Some(&c) = chars.peek() {
        let mut run = String::new();
        let digit = c.is_ascii_digit();
        while let Some(&d) = chars.peek() {
            if d.is_ascii_digit() != digit {
                break;
            }
            run.push(d);
            chars.next();
        }
        if digit {
            key.push((0, run.parse::<u128>().unwrap_or(u128::MAX), run));
        } else {
            key.push((1, 0, run));
        }
    }
    key
}

fn tiff_err(path: &Path, what: &str, e: tiff::TiffError) -> VolumeError {
    match e {
        tiff::TiffError::UnsupportedError(u) => VolumeError::unsupported(path, format!("{what}: {u}")),
        tiff::TiffError::IoError(io) => VolumeError::io(path, what, io),
        other => VolumeError::format(path, format!("{what}: {}", one_line(&other.to_string()))),
    }
}

fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

/// What a page is: its size and sample type.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Page {
    width: u32,
    height: u32,
    sample: Sample,
}

fn limits(bytes: usize) -> Limits {
    let mut l = Limits::default();
    l.decoding_buffer_size = l.decoding_buffer_size.max(bytes.saturating_add(1 << 20));
    l
}

fn decoder(path: &Path) -> Result<Decoder<BufReader<File>>, VolumeError> {
    let f = File::open(path).map_err(|e| VolumeError::io(path, "opening", e))?;
    Decoder::new(BufReader::new(f)).map_err(|e| tiff_err(path, "reading the TIFF header", e))
}

/// The current page's size and sample type; grey only.
fn page(d: &mut Decoder<BufReader<File>>, path: &Path, index: usize) -> Result<Page, VolumeError> {
    let where_ = format!("page {index}");
    let (width, height) = d.dimensions().map_err(|e| tiff_err(path, &where_, e))?;
    let bits = match d.colortype().map_err(|e| tiff_err(path, &where_, e))? {
        ColorType::Gray(b) => b,
        other => return Err(VolumeError::unsupported(path, format!("{where_}: colour type {other:?}: mint reads grey (one-channel) stacks"))),
    };
    let format = d.find_tag_unsigned::<u16>(Tag::SampleFormat).map_err(|e| tiff_err(path, &where_, e))?.unwrap_or(1);
    let sample = match (format, bits) {
        (1, 8) => Sample::U8,
        (1, 16) => Sample::U16,
        (1, 32) => Sample::U32,
        (1, 64) => Sample::U64,
        (2, 8) => Sample::I8,
        (2, 16) => Sample::I16,
        (2, 32) => Sample::I32,
        (2, 64) => Sample::I64,
        (3, 32) => Sample::F32,
        (3, 64) => Sample::F64,
        _ => return Err(VolumeError::unsupported(path, format!("{where_}: {bits}-bit samples of SampleFormat {format}"))),
    };
    if width == 0 || height == 0 {
        return Err(VolumeError::format(path, format!("{where_}: an image of {width} x {height} pixels")));
    }
    Ok(Page { width, height, sample })
}

/// ImageJ's spacing: (x, y, z) when the description says `ImageJ=`.
fn imagej_spacing(d: &mut Decoder<BufReader<File>>) -> Option<[f64; 3]> {
    let desc = d.get_tag_ascii_string(Tag::ImageDescription).ok()?;
    if !desc.contains("ImageJ=") {
        return None;
    }
    let z = desc.lines().find_map(|l| l.strip_prefix("spacing=")).and_then(|v| v.trim().parse::<f64>().ok()).filter(|v| *v > 0.0 && v.is_finite()).unwrap_or(1.0);
    let res = |tag: Tag, d: &mut Decoder<BufReader<File>>| -> f64 {
        match d.find_tag(tag) {
            Ok(Some(Value::Rational(n, m))) if n > 0 && m > 0 => m as f64 / n as f64,
            Ok(Some(Value::Float(f))) if f > 0.0 => 1.0 / f as f64,
            Ok(Some(Value::Double(f))) if f > 0.0 => 1.0 / f,
            _ => 1.0,
        }
    };
    Some([res(Tag::XResolution, d), res(Tag::YResolution, d), z])
}

pub(crate) fn open(path: &Path) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    if path.is_dir() {
        let rd = std::fs::read_dir(path).map_err(|e| VolumeError::io(path, "listing the folder", e))?;
        let mut files: Vec<PathBuf> = rd.flatten().map(|e| e.path()).filter(|p| p.is_file() && is_tiff_name(p)).collect();
        files.sort_by_cached_key(|p| (natural_key(&p.file_name().unwrap_or_default().to_string_lossy()), p.clone()));
        let Some(first) = files.first() else { return Err(VolumeError::format(path, "no .tif or .tiff file in the folder")) };
        let mut d = decoder(first)?;
        let p0 = page(&mut d, first, 0)?;
        let spacing = imagej_spacing(&mut d);
        for f in &files[1..] {
            let p = page(&mut decoder(f)?, f, 0)?;
            if p != p0 {
                return Err(VolumeError::format(
                    f,
                    format!("{} x {} {} pixels, but {} has {} x {} {}: every slice of a stack has the same size and type", p.width, p.height, p.sample.name(), first.display(), p0.width, p0.height, p0.sample.name()),
                ));
            }
        }
        let info = info_of(p0, files.len() as u64, spacing, files.clone());
        Ok((info, Box::new(TiffSlices { files, multipage: false, page: p0, open: None })))
    } else {
        let mut d = decoder(path)?;
        let p0 = page(&mut d, path, 0)?;
        let spacing = imagej_spacing(&mut d);
        let mut pages = 1u64;
        while d.more_images() {
            d.next_image().map_err(|e| tiff_err(path, &format!("page {pages}"), e))?;
            let p = page(&mut d, path, pages as usize)?;
            if p != p0 {
                return Err(VolumeError::format(
                    path,
                    format!("page {pages}: {} x {} {} pixels, but page 0 has {} x {} {}: every page of a stack has the same size and type", p.width, p.height, p.sample.name(), p0.width, p0.height, p0.sample.name()),
                ));
            }
            pages += 1;
            if pages > 1 << 24 {
                return Err(VolumeError::format(path, "more than 16 million pages"));
            }
        }
        let info = info_of(p0, pages, spacing, vec![path.to_path_buf()]);
        Ok((info, Box::new(TiffSlices { files: vec![path.to_path_buf()], multipage: true, page: p0, open: None })))
    }
}

fn info_of(p: Page, slices: u64, spacing: Option<[f64; 3]>, files: Vec<PathBuf>) -> VolumeInfo {
    VolumeInfo {
        dims: [p.width as u64, p.height as u64, slices],
        sample: p.sample,
        index_to_world: diagonal_affine(spacing.unwrap_or([1.0; 3]), [0.0; 3]),
        frame: Frame::Unnamed,
        slope: 1.0,
        intercept: 0.0,
        format: "TIFF stack",
        files,
        sequential_only: false,
    }
}

/// The slices of a stack: one file each, or pages of one file (with the
/// decoder kept at the last page read, so that reading in order walks
/// each directory once).
struct TiffSlices {
    files: Vec<PathBuf>,
    multipage: bool,
    page: Page,
    open: Option<(Decoder<BufReader<File>>, u64)>,
}

impl TiffSlices {
    /// Decodes slice `k` into `out`.
    fn decode_slice(&mut self, k: u64, out: &mut [f32]) -> Result<(), VolumeError> {
        let path = if self.multipage { self.files[0].clone() } else { self.files[k as usize].clone() };
        let bytes = out.len() * self.page.sample.size();
        let d = if self.multipage {
            if self.open.as_ref().is_none_or(|(_, at)| *at > k) {
                self.open = Some((decoder(&path)?.with_limits(limits(bytes)), 0));
            }
            let (d, at) = self.open.as_mut().unwrap();
            while *at < k {
                d.next_image().map_err(|e| tiff_err(&path, &format!("page {}", *at + 1), e))?;
                *at += 1;
            }
            d
        } else {
            self.open = Some((decoder(&path)?.with_limits(limits(bytes)), 0));
            &mut self.open.as_mut().unwrap().0
        };
        let what = if self.multipage { format!("page {k}") } else { "slice".to_string() };
        if page(d, &path, k as usize)? != self.page {
            return Err(VolumeError::format(&path, format!("{what}: not the size and type it had when the stack was opened")));
        }
        let img = d.read_image().map_err(|e| tiff_err(&path, &what, e))?;
        let n = out.len();
        macro_rules! copy {
            ($v:expr) => {{
                if $v.len() < n {
                    return Err(VolumeError::format(&path, format!("{what}: {} samples decoded, {n} expected (truncated)", $v.len())));
                }
                for (o, &x) in out.iter_mut().zip($v.iter()) {
                    *o = x as f32;
                }
            }};
        }
        match img {
            DecodingResult::U8(v) => copy!(v),
            DecodingResult::U16(v) => copy!(v),
            DecodingResult::U32(v) => copy!(v),
            DecodingResult::U64(v) => copy!(v),
            DecodingResult::I8(v) => copy!(v),
            DecodingResult::I16(v) => copy!(v),
            DecodingResult::I32(v) => copy!(v),
            DecodingResult::I64(v) => copy!(v),
            DecodingResult::F32(v) => copy!(v),
            DecodingResult::F64(v) => copy!(v),
            DecodingResult::F16(_) => return Err(VolumeError::unsupported(&path, format!("{what}: 16-bit float samples"))),
        }
        Ok(())
    }
}

impl SliceSource for TiffSlices {
    fn read_slice(&mut self, k: u64, out: &mut [f32], stats: &mut crate::SampleStats) -> Result<(), VolumeError> {
        self.decode_slice(k, out)?;
        crate::sample_stats(out, stats);
        Ok(())
    }

    fn try_clone(&self) -> Result<Box<dyn SliceSource>, VolumeError> {
        Ok(Box::new(TiffSlices { files: self.files.clone(), multipage: self.multipage, page: self.page, open: None }))
    }

    fn random_access(&self) -> bool {
        // (A multi-page file is walked from directory to directory.)
        !self.multipage
    }

    fn stored(&mut self, k0: u64, count: u64) -> Vec<crate::ahead::Stored> {
        if self.multipage {
            return Vec::new();
        }
        let files = self.files.iter().skip(k0 as usize).take(count as usize);
        files.map(|f| crate::ahead::Stored { path: f.clone(), at: 0, len: None }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OpenOptions, Volume};

    /// A little-endian baseline TIFF: pages of `w` x `h` grey samples of
    /// `bits` (8 or 16, uncompressed, one strip), or RGB when `rgb`.
    fn tiff_file(w: u16, h: u16, bits: u16, rgb: bool, pages: &[Vec<u16>]) -> Vec<u8> {
        let spp: u16 = if rgb { 3 } else { 1 };
        let per = (w as usize) * (h as usize) * (bits as usize / 8) * spp as usize;
        let entries = 9u32;
        let ifd_len = 2 + 12 * entries + 4;
        let mut out = b"II*\x00".to_vec();
        out.extend(8u32.to_le_bytes());
        let mut at = 8u32;
        for (p, samples) in pages.iter().enumerate() {
            let data = at + ifd_len;
            let next = if p + 1 < pages.len() { data + per as u32 } else { 0 };
            let mut e: Vec<(u16, u16, u32)> = vec![(256, 3, w as u32), (257, 3, h as u32), (258, 3, bits as u32), (259, 3, 1), (262, 3, if rgb { 2 } else { 1 }), (273, 4, data), (277, 3, spp as u32), (278, 3, h as u32), (279, 4, per as u32)];
            e.sort();
            out.extend((entries as u16).to_le_bytes());
            for (tag, ty, v) in e {
                out.extend(tag.to_le_bytes());
                out.extend(ty.to_le_bytes());
                out.extend(1u32.to_le_bytes());
                if ty == 3 {
                    out.extend((v as u16).to_le_bytes());
                    out.extend([0, 0]);
                } else {
                    out.extend(v.to_le_bytes());
                }
            }
            out.extend(next.to_le_bytes());
            for &s in samples.iter().take(per / (bits as usize / 8)) {
                if bits == 8 {
                    out.push(s as u8);
                } else {
                    out.extend(s.to_le_bytes());
                }
            }
            at = data + per as u32;
        }
        out
    }

    #[test]
    fn a_folder_stack_in_natural_order() {
        let d = tempfile::tempdir().unwrap();
        // Written in a shuffled order; names sort as 1, 2, …, 12.
        for k in [7u16, 1, 12, 3, 10, 2, 5, 11, 4, 9, 6, 8] {
            let page: Vec<u16> = (0..6).map(|i| k * 100 + i).collect();
            std::fs::write(d.path().join(format!("img_{k}.tif")), tiff_file(3, 2, 16, false, &[page])).unwrap();
        }
        std::fs::write(d.path().join("readme.txt"), "not a slice").unwrap();
        let mut v = Volume::open(d.path(), &OpenOptions::default()).unwrap();
        assert_eq!((v.info().dims, v.info().sample, v.info().format), ([3, 2, 12], Sample::U16, "TIFF stack"));
        let mut s = vec![0.0; 6 * 12];
        v.read_slices(0, 12, &mut s).unwrap();
        for k in 0..12 {
            assert_eq!(s[k * 6], ((k + 1) * 100) as f32, "slice {k}");
        }
        assert_eq!(s[6 * 11 + 5], 1205.0);
    }

    #[test]
    fn a_multipage_file_and_what_it_refuses() {
        let d = tempfile::tempdir().unwrap();
        let pages: Vec<Vec<u16>> = (0..4).map(|k| (0..12).map(|i| k * 10 + i).collect()).collect();
        let f = d.path().join("stack.tif");
        std::fs::write(&f, tiff_file(4, 3, 8, false, &pages)).unwrap();
        let mut v = Volume::open(&f, &OpenOptions::default()).unwrap();
        assert_eq!((v.info().dims, v.info().sample), ([4, 3, 4], Sample::U8));
        let mut s = vec![0.0; 12];
        v.read_slices(2, 1, &mut s).unwrap();
        assert_eq!(s[0], 20.0);
        v.read_slices(1, 1, &mut s).unwrap();
        assert_eq!(s[11], 21.0, "an earlier page reopens the file");
        // Truncated: an error naming the file, not a panic.
        let bytes = std::fs::read(&f).unwrap();
        let t = d.path().join("t.tif");
        std::fs::write(&t, &bytes[..bytes.len() - 7]).unwrap();
        let r = Volume::open(&t, &OpenOptions::default()).and_then(|mut v| {
            let n = v.info().slice_len() * v.info().dims[2] as usize;
            v.read_slices(0, v.info().dims[2], &mut vec![0.0; n])
        });
        let e = r.unwrap_err().to_string();
        assert!(e.contains("t.tif") && !e.contains('\n'), "{e}");
        // RGB: unsupported, named.
        let c = d.path().join("rgb.tif");
        std::fs::write(&c, tiff_file(2, 2, 8, true, &[vec![0; 12]])).unwrap();
        let e = Volume::open(&c, &OpenOptions::default()).unwrap_err().to_string();
        assert!(e.contains("rgb.tif") && e.contains("grey"), "{e}");
        // Mixed sizes in a folder.
        let m = d.path().join("mixed");
        std::fs::create_dir(&m).unwrap();
        std::fs::write(m.join("a1.tif"), tiff_file(2, 2, 16, false, &[vec![1; 4]])).unwrap();
        std::fs::write(m.join("a2.tif"), tiff_file(3, 2, 16, false, &[vec![1; 6]])).unwrap();
        let e = Volume::open(&m, &OpenOptions::default()).unwrap_err().to_string();
        assert!(e.contains("a2.tif") && e.contains("same size"), "{e}");
    }

    #[test]
    fn natural_order() {
        let mut v = vec!["s10.tif", "s2.tif", "s1.tif", "s02.tif", "a.tif"];
        v.sort_by_cached_key(|n| (natural_key(n), n.to_string()));
        assert_eq!(v, ["a.tif", "s1.tif", "s02.tif", "s2.tif", "s10.tif"]);
    }
}
