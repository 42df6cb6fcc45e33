//! DICOM series: a folder of single-frame DICOM images (one slice per
//! file, any file names) read as one volume. [`open`] reads every file's
//! header only (dicom-object, stopping before PixelData), keeps the files
//! with the `DICM` preamble that hold an image (Rows present; a DICOMDIR,
//! text files and other non-DICOM files are skipped), and checks that they
//! form one regular grid: one SeriesInstanceUID, the same Rows/Columns,
//! bits, pixel representation, ImageOrientationPatient (within 1e-4) and
//! PixelSpacing, distinct positions along the slice normal
//! `n = row_dir × col_dir`, and a uniform step (a gap of about k steps is
//! named as a missing slice). Slices are ordered by `dot(IPP, n)`.
//!
//! The affine: column 0 is `row_dir · PixelSpacing[1]` (i runs along a
//! row, across columns), column 1 `col_dir · PixelSpacing[0]`, column 2
//! the actual step `(IPP_last − IPP_first)/(n − 1)` (so a gantry tilt is
//! kept), column 3 the first sorted slice's IPP; frame LPS. A single slice
//! steps `SpacingBetweenSlices`, else `SliceThickness`, else 1 mm along n.
//!
//! Transfer syntaxes: Implicit VR Little Endian, Explicit VR Little and
//! Big Endian, and the compressed ones `crate::dicom_pixels` decodes (RLE
//! Lossless, JPEG Baseline 8-bit, JPEG Lossless Process 14 and its
//! first-order prediction form). Any other compressed or a deflated
//! syntax fails at [`open`] with one Unsupported line naming it and a
//! conversion command.
//! Samples: 8, 16 or 32 bits allocated, one sample per pixel, MONOCHROME1
//! or MONOCHROME2; the stored value is masked to BitsStored (taken from
//! HighBit down) and sign-extended when PixelRepresentation is 1, then
//! each slice's own RescaleSlope/RescaleIntercept applies. MONOCHROME1
//! (inverted display) values are kept as stored: the rescale gives the
//! physical value, the inversion is a display convention only.
//! Enhanced multi-frame files (NumberOfFrames > 1 with a
//! PerFrameFunctionalGroupsSequence item per frame) are read as the
//! series of their frames: each frame's position, orientation, spacing and
//! rescale come from its own functional groups, then the shared ones, then
//! the top level; frames are read one at a time from where the length walk
//! found the pixels (native: at their offset; encapsulated: the frame's
//! fragments by the basic offset table, or one fragment a frame). Other
//! multi-frame files (no per-frame positions) are refused in one line.
//!
//! Every file's element lengths are walked first (`crate::dicom_lengths`),
//! so no declared length larger than the file reaches the parser.
//!
//! Memory: one parsed file at a time (the header pass keeps only a few
//! numbers per slice; a slice read parses one file and its PixelData).
//! Every value read from a file is checked: bad input is a one-line
//! [`VolumeError`] naming the file and the tag, never a panic.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use dicom_core::value::{PrimitiveValue, Value};
use dicom_object::mem::InMemDicomObject;
use dicom_object::{FileMetaTable, OpenFileOptions, Tag};
use dicom_transfer_syntax_registry::{TransferSyntaxIndex, TransferSyntaxRegistry};

use crate::decode::Sample;
use crate::dicom_lengths::PixelData;
use crate::dicom_pixels::{decode_frame, Codec, FrameShape};
use crate::source::SliceSource;
use crate::{Frame, VolumeError, VolumeInfo};

/// The most frames a multi-frame file may declare.
const MAX_FRAMES: i64 = 1 << 20;

/// The attributes read (names as in PS3.6).
mod tags {
    use dicom_object::Tag;
    pub const SOP_CLASS_UID: Tag = Tag(0x0008, 0x0016);
    pub const SLICE_THICKNESS: Tag = Tag(0x0018, 0x0050);
    pub const SPACING_BETWEEN_SLICES: Tag = Tag(0x0018, 0x0088);
    pub const SERIES_INSTANCE_UID: Tag = Tag(0x0020, 0x000E);
    pub const IMAGE_POSITION_PATIENT: Tag = Tag(0x0020, 0x0032);
    pub const IMAGE_ORIENTATION_PATIENT: Tag = Tag(0x0020, 0x0037);
    pub const SAMPLES_PER_PIXEL: Tag = Tag(0x0028, 0x0002);
    pub const PHOTOMETRIC_INTERPRETATION: Tag = Tag(0x0028, 0x0004);
    pub const NUMBER_OF_FRAMES: Tag = Tag(0x0028, 0x0008);
    pub const ROWS: Tag = Tag(0x0028, 0x0010);
    pub const COLUMNS: Tag = Tag(0x0028, 0x0011);
    pub const PIXEL_SPACING: Tag = Tag(0x0028, 0x0030);
    pub const BITS_ALLOCATED: Tag = Tag(0x0028, 0x0100);
    pub const BITS_STORED: Tag = Tag(0x0028, 0x0101);
    pub const HIGH_BIT: Tag = Tag(0x0028, 0x0102);
    pub const PIXEL_REPRESENTATION: Tag = Tag(0x0028, 0x0103);
    pub const RESCALE_INTERCEPT: Tag = Tag(0x0028, 0x1052);
    pub const RESCALE_SLOPE: Tag = Tag(0x0028, 0x1053);
    pub const PIXEL_DATA: Tag = Tag(0x7FE0, 0x0010);
    // Multi-frame functional groups (PS3.3 C.7.6.16) and their macros.
    pub const SHARED_GROUPS: Tag = Tag(0x5200, 0x9229);
    pub const PER_FRAME_GROUPS: Tag = Tag(0x5200, 0x9230);
    pub const PLANE_POSITION: Tag = Tag(0x0020, 0x9113);
    pub const PLANE_ORIENTATION: Tag = Tag(0x0020, 0x9116);
    pub const PIXEL_MEASURES: Tag = Tag(0x0028, 0x9110);
    pub const PIXEL_VALUE_TRANSFORMATION: Tag = Tag(0x0028, 0x9145);
}

/// The Media Storage Directory SOP class (a DICOMDIR).
const DICOMDIR_CLASS: &str = "1.2.840.10008.1.3.10";

/// `(gggg,eeee) Name`, for messages.
fn place(tag: Tag, name: &str) -> String {
    format!("({:04X},{:04X}) {name}", tag.0, tag.1)
}

/// An error and its sources, on one line.
fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        let m = c.to_string();
        if !s.contains(&m) {
            s.push_str(": ");
            s.push_str(&m);
        }
        src = c.source();
    }
    s.replace('\n', " ")
}

/// The file's name (for naming a second file in a message).
/// Whether two paths name one file (by canonical path, else as given).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

fn short(p: &Path) -> String {
    p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| p.display().to_string())
}

/// What one file's header says.
#[derive(Clone, Debug)]
struct Header {
    path: PathBuf,
    series: String,
    rows: u64,
    cols: u64,
    bits_allocated: u32,
    bits_stored: u32,
    high_bit: u32,
    signed: bool,
    iop: [f64; 6],
    ipp: [f64; 3],
    /// Row spacing (between rows), column spacing (between columns).
    ps: [f64; 2],
    slope: f64,
    intercept: f64,
    syntax: Syntax,
    thickness: Option<f64>,
    between: Option<f64>,
    /// In a multi-frame file: which frame, and where the file's pixels are.
    frame: Option<FrameOf>,
}

/// A frame of a multi-frame file.
#[derive(Clone, Debug)]
struct FrameOf {
    /// 0-based.
    index: u32,
    count: u32,
    pixels: std::sync::Arc<PixelData>,
}

impl Header {
    /// The file's name, and the frame's number (1-based) in a multi-frame file.
    fn label(&self) -> String {
        match &self.frame {
            Some(f) => format!("{} frame {}", short(&self.path), f.index + 1),
            None => short(&self.path),
        }
    }
}

/// Whether the file starts with a 128-byte preamble and `DICM`.
fn is_dicom(path: &Path) -> Result<bool, VolumeError> {
    let f = File::open(path).map_err(|e| VolumeError::io(path, "opening", e))?;
    let mut head = Vec::with_capacity(132);
    f.take(132).read_to_end(&mut head).map_err(|e| VolumeError::io(path, "reading", e))?;
    Ok(head.len() == 132 && &head[128..132] == b"DICM")
}

/// How a transfer syntax stores the pixels mint reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Syntax {
    /// Explicit VR Big Endian (samples in big-endian order).
    big_endian: bool,
    /// Encapsulated pixel data of a codec mint decodes.
    codec: Option<Codec>,
}

/// The transfer syntaxes mint reads, for messages.
const READ: &str = "Implicit VR Little Endian, Explicit VR Little or Big Endian, RLE Lossless, JPEG Baseline (8-bit) and JPEG Lossless";

/// How the transfer syntax `uid` stores pixels, or why mint cannot read
/// it (an Unsupported error about `path`).
fn check_transfer_syntax(path: &Path, uid: &str) -> Result<Syntax, VolumeError> {
    match uid {
        "1.2.840.10008.1.2" | "1.2.840.10008.1.2.1" => return Ok(Syntax { big_endian: false, codec: None }),
        "1.2.840.10008.1.2.2" => return Ok(Syntax { big_endian: true, codec: None }),
        "1.2.840.10008.1.2.1.99" => {
            return Err(VolumeError::unsupported(
                path,
                format!("transfer syntax Deflated Explicit VR Little Endian (1.2.840.10008.1.2.1.99) is not one mint reads ({READ}): convert with `gdcmconv --raw` or `dcmconv +te`"),
            ))
        }
        _ => {}
    }
    if let Some(codec) = Codec::of(uid) {
        return Ok(Syntax { big_endian: false, codec: Some(codec) });
    }
    let msg = match TransferSyntaxRegistry.get(uid) {
        Some(ts) if ts.is_encapsulated_pixel_data() => format!(
            "transfer syntax {} ({uid}) is compressed with a codec mint has no decoder for; mint reads {READ}: convert with `gdcmconv --raw` or `dcmdjpeg`",
            ts.name()
        ),
        Some(ts) => format!("transfer syntax {} ({uid}) is not one mint reads ({READ}): convert with `gdcmconv --raw`", ts.name()),
        None => format!("transfer syntax {uid} is unknown; mint reads {READ}: convert with `gdcmconv --raw`"),
    };
    Err(VolumeError::unsupported(path, msg))
}

/// An optional integer attribute (absent or empty: `None`).
fn int_of(obj: &InMemDicomObject, path: &Path, tag: Tag, name: &str) -> Result<Option<i64>, VolumeError> {
    let Some(e) = obj.get(tag) else { return Ok(None) };
    if e.to_str().map(|s| s.trim_matches(|c: char| c == '\0' || c.is_whitespace()).is_empty()).unwrap_or(false) {
        return Ok(None);
    }
    e.to_int::<i64>()
        .map(Some)
        .map_err(|err| VolumeError::format(path, format!("{}: not an integer: {}", place(tag, name), chain(&err))))
}

/// A required integer attribute.
fn int_req(obj: &InMemDicomObject, path: &Path, tag: Tag, name: &str) -> Result<i64, VolumeError> {
    int_of(obj, path, tag, name)?.ok_or_else(|| VolumeError::format(path, format!("{} is missing", place(tag, name))))
}

/// An optional list of finite numbers of length `n` (0: any length ≥ 1).
fn floats_of(obj: &InMemDicomObject, path: &Path, tag: Tag, name: &str, n: usize) -> Result<Option<Vec<f64>>, VolumeError> {
    let Some(e) = obj.get(tag) else { return Ok(None) };
    if e.to_str().map(|s| s.trim_matches(|c: char| c == '\0' || c.is_whitespace()).is_empty()).unwrap_or(false) {
        return Ok(None);
    }
    let v = e
        .to_multi_float64()
        .map_err(|err| VolumeError::format(path, format!("{}: not a list of numbers: {}", place(tag, name), chain(&err))))?;
    if (n > 0 && v.len() != n) || v.is_empty() {
        return Err(VolumeError::format(path, format!("{}: {} values, expected {}", place(tag, name), v.len(), n.max(1))));
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(VolumeError::format(path, format!("{}: {:?} is not finite", place(tag, name), v)));
    }
    Ok(Some(v))
}

/// A required list of `n` numbers.
fn floats_req(obj: &InMemDicomObject, path: &Path, tag: Tag, name: &str, n: usize) -> Result<Vec<f64>, VolumeError> {
    floats_of(obj, path, tag, name, n)?.ok_or_else(|| VolumeError::format(path, format!("{} is missing", place(tag, name))))
}

/// An optional text attribute, trimmed.
fn text_of(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    let s = obj.get(tag)?.to_str().ok()?;
    let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    (!s.is_empty()).then(|| s.to_string())
}

/// Where attribute `tag` of functional group macro `seq` is: in the first
/// of `groups` (a frame's own, the shared ones) whose `seq` item holds it,
/// or else at the top level.
fn holder<'a>(top: &'a InMemDicomObject, groups: [Option<&'a InMemDicomObject>; 2], seq: Tag, tag: Tag) -> &'a InMemDicomObject {
    groups.into_iter().flatten().filter_map(|g| g.get(seq).and_then(|e| e.items()).and_then(|i| i.first())).find(|o| o.get(tag).is_some()).unwrap_or(top)
}

/// Reads the header of the DICOM file `path` (up to PixelData): one
/// [`Header`] per frame, none when it holds no image (a DICOMDIR, a
/// structure set, a report).
fn read_header(path: &Path) -> Result<Vec<Header>, VolumeError> {
    // Every declared length against the file, before dicom-object sizes a
    // buffer by one (see `crate::dicom_lengths`).
    // The walk also says where the pixels are (for frames of multi-frame
    // files). Mapped, not read: a multi-frame file can be gigabytes.
    let file = File::open(path).map_err(|e| VolumeError::io(path, "opening", e))?;
    // SAFETY: a read-only map of an input mint never writes; another
    // process truncating the file meanwhile can fault the process (SIGBUS),
    // the trade-off mint-io's mapped inputs document.
    let map = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| VolumeError::io(path, "mapping", e))?;
    let pixels = match crate::dicom_lengths::layout(&map) {
        Some(layout) => crate::dicom_lengths::pixel_data(&map, layout).map_err(|m| VolumeError::format(path, format!("{m}: truncated or corrupted")))?,
        None => None,
    };
    drop(map);
    // A syntax mint does not read is named before any parser inflates or
    // decodes the file.
    if let Some(uid) = meta_transfer_syntax(path) {
        check_transfer_syntax(path, &uid)?;
    }
    let obj = match OpenFileOptions::new().read_until(tags::PIXEL_DATA).open_file(path) {
        Ok(o) => o,
        Err(e) => {
            // Say why when the meta group names a syntax we cannot read.
            if let Some(uid) = meta_transfer_syntax(path) {
                check_transfer_syntax(path, &uid)?;
            }
            return Err(VolumeError::format(path, format!("cannot read the DICOM header (truncated or corrupted file?): {}", chain(&e))));
        }
    };
    if obj.meta().media_storage_sop_class_uid() == DICOMDIR_CLASS || text_of(&obj, tags::SOP_CLASS_UID).as_deref() == Some(DICOMDIR_CLASS) {
        return Ok(Vec::new());
    }
    if obj.get(tags::ROWS).is_none() {
        return Ok(Vec::new());
    }
    let syntax = check_transfer_syntax(path, obj.meta().transfer_syntax())?;
    let spp = int_of(&obj, path, tags::SAMPLES_PER_PIXEL, "SamplesPerPixel")?.unwrap_or(1);
    if spp != 1 {
        return Err(VolumeError::unsupported(
            path,
            format!("{}: colour (SamplesPerPixel {spp}); mint reads one sample per pixel (grayscale) only", place(tags::SAMPLES_PER_PIXEL, "SamplesPerPixel")),
        ));
    }
    if let Some(pi) = text_of(&obj, tags::PHOTOMETRIC_INTERPRETATION) {
        if pi != "MONOCHROME1" && pi != "MONOCHROME2" {
            return Err(VolumeError::unsupported(
                path,
                format!("{}: {pi}; mint reads MONOCHROME1 or MONOCHROME2 only", place(tags::PHOTOMETRIC_INTERPRETATION, "PhotometricInterpretation")),
            ));
        }
    }
    let frames = int_of(&obj, path, tags::NUMBER_OF_FRAMES, "NumberOfFrames")?.unwrap_or(1);
    if !(1..=MAX_FRAMES).contains(&frames) {
        return Err(VolumeError::format(path, format!("{}: {frames} is not a usable number of frames", place(tags::NUMBER_OF_FRAMES, "NumberOfFrames"))));
    }
    let dim = |tag: Tag, name: &str| -> Result<u64, VolumeError> {
        let v = int_req(&obj, path, tag, name)?;
        if !(1..=65535).contains(&v) {
            return Err(VolumeError::format(path, format!("{}: {v} is not a usable size", place(tag, name))));
        }
        Ok(v as u64)
    };
    let rows = dim(tags::ROWS, "Rows")?;
    let cols = dim(tags::COLUMNS, "Columns")?;
    let ba = int_req(&obj, path, tags::BITS_ALLOCATED, "BitsAllocated")?;
    if !matches!(ba, 8 | 16 | 32) {
        return Err(VolumeError::unsupported(path, format!("{}: {ba}; mint reads 8, 16 or 32 bits per sample", place(tags::BITS_ALLOCATED, "BitsAllocated"))));
    }
    let bs = int_of(&obj, path, tags::BITS_STORED, "BitsStored")?.unwrap_or(ba);
    if !(1..=ba).contains(&bs) {
        return Err(VolumeError::format(path, format!("{}: {bs} with BitsAllocated {ba}", place(tags::BITS_STORED, "BitsStored"))));
    }
    let hb = int_of(&obj, path, tags::HIGH_BIT, "HighBit")?.unwrap_or(bs - 1);
    if hb < bs - 1 || hb >= ba {
        return Err(VolumeError::format(path, format!("{}: {hb} with BitsStored {bs} and BitsAllocated {ba}", place(tags::HIGH_BIT, "HighBit"))));
    }
    let pr = int_of(&obj, path, tags::PIXEL_REPRESENTATION, "PixelRepresentation")?.unwrap_or(0);
    if !matches!(pr, 0 | 1) {
        return Err(VolumeError::format(path, format!("{}: {pr} (0 unsigned or 1 signed)", place(tags::PIXEL_REPRESENTATION, "PixelRepresentation"))));
    }
    // Compressed pixels too short for the frames the header claims are
    // refused before any slice is sized by the header.
    if let (Some(codec), Some(PixelData::Encapsulated { items })) = (syntax.codec, &pixels) {
        let have: u64 = items.iter().skip(1).map(|&(_, n)| n as u64).sum();
        let need = frames as u64 * crate::dicom_pixels::min_bytes(codec, FrameShape { rows, cols, bits_allocated: ba as u32 });
        if have < need {
            return Err(VolumeError::format(
                path,
                format!("{}: {have} bytes of fragments cannot hold {frames} frame{} of {cols} x {rows} samples: truncated, or Rows/Columns wrong", place(tags::PIXEL_DATA, "PixelData"), if frames == 1 { "" } else { "s" }),
            ));
        }
    }
    let series = text_of(&obj, tags::SERIES_INSTANCE_UID).unwrap_or_default();
    // Functional groups (enhanced images): a frame's own, then the shared
    // ones, then the top level.
    let shared = obj.get(tags::SHARED_GROUPS).and_then(|e| e.items()).and_then(|i| i.first());
    let per_frame = obj.get(tags::PER_FRAME_GROUPS).and_then(|e| e.items()).unwrap_or(&[]);
    let frame_data = if frames > 1 {
        if per_frame.len() as i64 != frames {
            return Err(VolumeError::unsupported(
                path,
                format!(
                    "{}: a multi-frame image of {frames} frames with {} items of {}; mint reads enhanced multi-frame images (a position per frame) and series of single-frame files (split it with `dcmsplit` or `gdcmtar --split`)",
                    place(tags::NUMBER_OF_FRAMES, "NumberOfFrames"),
                    per_frame.len(),
                    place(tags::PER_FRAME_GROUPS, "PerFrameFunctionalGroupsSequence")
                ),
            ));
        }
        let pixels = match pixels {
            Some(p) => std::sync::Arc::new(p),
            None => return Err(VolumeError::format(path, format!("{} is missing", place(tags::PIXEL_DATA, "PixelData")))),
        };
        Some(pixels)
    } else {
        None
    };
    let mut out = Vec::with_capacity(frames as usize);
    for f in 0..frames as usize {
        let fg = if frames > 1 { per_frame.get(f) } else { per_frame.first() };
        let at = |seq: Tag, tag: Tag| -> &InMemDicomObject { holder(&obj, [fg, shared], seq, tag) };
        let iop_v = floats_req(at(tags::PLANE_ORIENTATION, tags::IMAGE_ORIENTATION_PATIENT), path, tags::IMAGE_ORIENTATION_PATIENT, "ImageOrientationPatient", 6)?;
        let ipp_v = floats_req(at(tags::PLANE_POSITION, tags::IMAGE_POSITION_PATIENT), path, tags::IMAGE_POSITION_PATIENT, "ImagePositionPatient", 3)?;
        let ps_v = floats_req(at(tags::PIXEL_MEASURES, tags::PIXEL_SPACING), path, tags::PIXEL_SPACING, "PixelSpacing", 2)?;
        if ps_v.iter().any(|&s| s <= 0.0) {
            return Err(VolumeError::format(path, format!("{}: {:?} must be positive", place(tags::PIXEL_SPACING, "PixelSpacing"), ps_v)));
        }
        let one = |seq: Tag, tag: Tag, name: &str| -> Result<Option<f64>, VolumeError> { Ok(floats_of(at(seq, tag), path, tag, name, 1)?.map(|v| v[0])) };
        let slope = one(tags::PIXEL_VALUE_TRANSFORMATION, tags::RESCALE_SLOPE, "RescaleSlope")?.unwrap_or(1.0);
        let intercept = one(tags::PIXEL_VALUE_TRANSFORMATION, tags::RESCALE_INTERCEPT, "RescaleIntercept")?.unwrap_or(0.0);
        if slope == 0.0 {
            return Err(VolumeError::format(path, format!("{}: 0", place(tags::RESCALE_SLOPE, "RescaleSlope"))));
        }
        // Judged on the widest stored samples read (32 bits, either sign).
        crate::decode::check_rescale(crate::Sample::I32, slope, intercept)
            .and_then(|_| crate::decode::check_rescale(crate::Sample::U32, slope, intercept))
            .map_err(|m| VolumeError::format(path, format!("{}: {m}", place(tags::RESCALE_SLOPE, "RescaleSlope"))))?;
        let thickness = one(tags::PIXEL_MEASURES, tags::SLICE_THICKNESS, "SliceThickness")?.filter(|&t| t > 0.0);
        let between = one(tags::PIXEL_MEASURES, tags::SPACING_BETWEEN_SLICES, "SpacingBetweenSlices")?.filter(|&t| t > 0.0);
        out.push(Header {
            path: path.to_path_buf(),
            series: series.clone(),
            rows,
            cols,
            bits_allocated: ba as u32,
            bits_stored: bs as u32,
            high_bit: hb as u32,
            signed: pr == 1,
            iop: std::array::from_fn(|i| iop_v[i]),
            ipp: std::array::from_fn(|i| ipp_v[i]),
            ps: [ps_v[0], ps_v[1]],
            slope,
            intercept,
            syntax,
            thickness,
            between,
            frame: frame_data.as_ref().map(|p| FrameOf { index: f as u32, count: frames as u32, pixels: p.clone() }),
        });
    }
    Ok(out)
}

/// The transfer syntax the file meta group names, if it can be read.
fn meta_transfer_syntax(path: &Path) -> Option<String> {
    let mut f = File::open(path).ok()?;
    f.seek(SeekFrom::Start(128)).ok()?;
    let meta = FileMetaTable::from_reader(BufReader::new(f.take(1 << 16))).ok()?;
    Some(meta.transfer_syntax().to_string())
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The layout every slice shares.
#[derive(Clone, Copy, Debug)]
struct Layout {
    rows: u64,
    cols: u64,
    bits_allocated: u32,
    bits_stored: u32,
    high_bit: u32,
    signed: bool,
}

/// What a slice read needs of one file.
#[derive(Clone, Debug)]
struct SliceMeta {
    path: PathBuf,
    slope: f64,
    intercept: f64,
    syntax: Syntax,
    frame: Option<FrameOf>,
}

/// Opens a DICOM series in the folder `dir`: the one `pick` names (a
/// SeriesInstanceUID, or a number from 1 in the folder's list), else the
/// series of the file `of_file`, else the folder's only series.
pub(crate) fn open(dir: &Path, pick: Option<&str>, of_file: Option<&Path>) -> Result<(VolumeInfo, Box<dyn SliceSource>), VolumeError> {
    let rd = std::fs::read_dir(dir).map_err(|e| VolumeError::io(dir, "listing the folder", e))?;
    let mut paths = Vec::new();
    for ent in rd {
        let ent = ent.map_err(|e| VolumeError::io(dir, "listing the folder", e))?;
        let p = ent.path();
        if p.is_file() {
            paths.push(p);
        }
    }
    paths.sort();
    let mut heads: Vec<Header> = Vec::new();
    let mut dicom_files = 0usize;
    for p in &paths {
        if !is_dicom(p)? {
            continue;
        }
        dicom_files += 1;
        heads.extend(read_header(p)?);
    }
    if heads.is_empty() {
        return Err(VolumeError::format(
            dir,
            format!(
                "no DICOM image in the folder ({} files, {} of them DICOM with no image): give a folder of DICOM slices",
                paths.len(),
                dicom_files
            ),
        ));
    }
    // One series: the one asked for, the given file's, or the only one.
    let mut series: Vec<(String, usize, PathBuf)> = Vec::new();
    for h in &heads {
        match series.iter_mut().find(|s| s.0 == h.series) {
            Some(s) => s.1 += 1,
            None => series.push((h.series.clone(), 1, h.path.clone())),
        }
    }
    let list = || -> String {
        series
            .iter()
            .enumerate()
            .map(|(i, (uid, n, p))| format!("{}: {} ({n} image{}, e.g. {})", i + 1, if uid.is_empty() { "(no SeriesInstanceUID)" } else { uid }, if *n == 1 { "" } else { "s" }, short(p)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let chosen = match (pick, of_file) {
        (Some(p), _) if !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()) => match p.parse::<usize>().ok().filter(|&n| n >= 1 && n <= series.len()) {
            Some(n) => series[n - 1].0.clone(),
            None => return Err(VolumeError::new(crate::VolumeErrorKind::Value, dir, format!("no series number {p}: the folder holds {} series: {}", series.len(), list()))),
        },
        (Some(p), _) => match series.iter().find(|s| s.0 == p) {
            Some(s) => s.0.clone(),
            None => return Err(VolumeError::new(crate::VolumeErrorKind::Value, dir, format!("no series with SeriesInstanceUID {p}: the folder holds {}", list()))),
        },
        (None, Some(f)) => match heads.iter().find(|h| same_file(&h.path, f)) {
            Some(h) => h.series.clone(),
            None => return Err(VolumeError::format(f, "not a DICOM image (no pixel data, or not DICOM): give a slice of the series, or its folder")),
        },
        (None, None) if series.len() > 1 => {
            return Err(VolumeError::format(
                dir,
                format!("the folder holds {} series (0020,000E) SeriesInstanceUID: {}; choose one (--dicom-series N or UID, or give one of its files)", series.len(), list()),
            ));
        }
        (None, None) => series[0].0.clone(),
    };
    heads.retain(|h| h.series == chosen);
    // The same grid in every file.
    let h0 = heads[0].clone();
    for h in &heads[1..] {
        let differ = |what: String| -> VolumeError { VolumeError::format(&h.path, format!("{what}, but {} has {}", h0.label(), "the first value")) };
        let _ = differ;
        let msg = if (h.rows, h.cols) != (h0.rows, h0.cols) {
            Some(format!("{} x {} (Columns x Rows), but {} is {} x {}", h.cols, h.rows, h0.label(), h0.cols, h0.rows))
        } else if (h.bits_allocated, h.bits_stored, h.high_bit, h.signed) != (h0.bits_allocated, h0.bits_stored, h0.high_bit, h0.signed) {
            Some(format!(
                "BitsAllocated/BitsStored/HighBit/PixelRepresentation {}/{}/{}/{}, but {} has {}/{}/{}/{}",
                h.bits_allocated, h.bits_stored, h.high_bit, h.signed as u8, h0.label(), h0.bits_allocated, h0.bits_stored, h0.high_bit, h0.signed as u8
            ))
        } else if h.iop.iter().zip(&h0.iop).any(|(a, b)| (a - b).abs() > 1e-4) {
            Some(format!("(0020,0037) ImageOrientationPatient {:?}, but {} has {:?}", h.iop, h0.label(), h0.iop))
        } else if h.ps.iter().zip(&h0.ps).any(|(a, b)| (a - b).abs() > 1e-4 * b.abs().max(1.0)) {
            Some(format!("(0028,0030) PixelSpacing {:?}, but {} has {:?}", h.ps, h0.label(), h0.ps))
        } else {
            None
        };
        if let Some(m) = msg {
            return Err(VolumeError::format(&h.path, format!("{}not the same grid as the rest of the series: {m}", h.frame.as_ref().map(|f| format!("frame {}: ", f.index + 1)).unwrap_or_default())));
        }
    }
    // Directions.
    let mut row = [h0.iop[0], h0.iop[1], h0.iop[2]];
    let mut col = [h0.iop[3], h0.iop[4], h0.iop[5]];
    let (nr, nc) = (norm(row), norm(col));
    if (nr - 1.0).abs() > 1e-2 || (nc - 1.0).abs() > 1e-2 || dot(row, col).abs() > 1e-2 {
        return Err(VolumeError::format(
            &h0.path,
            format!("(0020,0037) ImageOrientationPatient {:?}: the row and column directions are not orthogonal unit vectors", h0.iop),
        ));
    }
    row = row.map(|v| v / nr);
    col = col.map(|v| v / nc);
    let n = cross(row, col);
    let nn = norm(n);
    let n = n.map(|v| v / nn);
    // Order along the normal.
    let mut order: Vec<(f64, usize)> = heads.iter().enumerate().map(|(i, h)| (dot(h.ipp, n), i)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(heads[a.1].path.cmp(&heads[b.1].path)));
    let sorted: Vec<&Header> = order.iter().map(|&(_, i)| &heads[i]).collect();
    let pos: Vec<f64> = order.iter().map(|&(d, _)| d).collect();
    for w in 0..sorted.len().saturating_sub(1) {
        if (pos[w + 1] - pos[w]).abs() < 1e-4 {
            return Err(VolumeError::format(
                &sorted[w + 1].path,
                format!("(0020,0032) ImagePositionPatient: the same slice position ({:.4} mm along the normal) as {}: duplicate slices", pos[w], sorted[w].label()),
            ));
        }
    }
    let count = sorted.len();
    let step_vec: [f64; 3] = if count == 1 {
        let s = h0.between.or(h0.thickness).unwrap_or(1.0);
        n.map(|v| v * s)
    } else {
        let steps: Vec<f64> = pos.windows(2).map(|w| w[1] - w[0]).collect();
        let mut sorted_steps = steps.clone();
        sorted_steps.sort_by(f64::total_cmp);
        let median = sorted_steps[(sorted_steps.len() - 1) / 2];
        for (w, &g) in steps.iter().enumerate() {
            let (a, b) = (sorted[w], sorted[w + 1]);
            if g >= 1.5 * median {
                let k = (g / median).round() as i64 - 1;
                return Err(VolumeError::format(
                    &a.path,
                    format!(
                        "slice missing between {} (position {:.4}) and {} (position {:.4}): a step of {:.4} mm where the series steps {:.4} mm (about {} slice{} missing)",
                        a.label(),
                        pos[w],
                        b.label(),
                        pos[w + 1],
                        g,
                        median,
                        k.max(1),
                        if k > 1 { "s" } else { "" }
                    ),
                ));
            }
            if (g - median).abs() > 0.01 * median + 1e-5 {
                return Err(VolumeError::format(
                    &a.path,
                    format!(
                        "non-uniform slice spacing between {} (position {:.4}) and {} (position {:.4}): a step of {:.4} mm where the series steps {:.4} mm",
                        a.label(),
                        pos[w],
                        b.label(),
                        pos[w + 1],
                        g,
                        median
                    ),
                ));
            }
        }
        let (first, last) = (sorted[0].ipp, sorted[count - 1].ipp);
        let sv: [f64; 3] = std::array::from_fn(|r| (last[r] - first[r]) / (count - 1) as f64);
        // Every slice on the line through the first and the last.
        let tol = 0.01 * norm(sv) + 1e-3;
        for (k, h) in sorted.iter().enumerate() {
            let expect: [f64; 3] = std::array::from_fn(|r| first[r] + k as f64 * sv[r]);
            let off = norm(std::array::from_fn(|r| h.ipp[r] - expect[r]));
            if off > tol {
                return Err(VolumeError::format(
                    &h.path,
                    format!(
                        "(0020,0032) ImagePositionPatient {:?} is {:.4} mm off the line of slices from {} to {}: the slices do not form one grid",
                        h.ipp,
                        off,
                        sorted[0].label(),
                        sorted[count - 1].label()
                    ),
                ));
            }
        }
        sv
    };
    let layout = Layout {
        rows: h0.rows,
        cols: h0.cols,
        bits_allocated: h0.bits_allocated,
        bits_stored: h0.bits_stored,
        high_bit: h0.high_bit,
        signed: h0.signed,
    };
    // A file shorter than one slice's samples cannot hold them
    // (uncompressed).
    let slice_bytes = layout.rows * layout.cols * (layout.bits_allocated as u64 / 8);
    for h in sorted.iter().filter(|h| h.syntax.codec.is_none()) {
        let len = std::fs::metadata(&h.path).map_err(|e| VolumeError::io(&h.path, "reading", e))?.len();
        if len < slice_bytes {
            return Err(VolumeError::format(
                &h.path,
                format!(
                    "(7FE0,0010) PixelData: the file holds {len} bytes, fewer than the {slice_bytes} of one slice ({} x {} x {} bits): truncated",
                    layout.cols, layout.rows, layout.bits_allocated
                ),
            ));
        }
    }
    // A multi-frame file's native pixels hold all its frames.
    for h in &sorted {
        if let Some(FrameOf { index: 0, count, pixels }) = &h.frame {
            if let PixelData::Native { len, .. } = **pixels {
                if (len as u64) < *count as u64 * slice_bytes {
                    return Err(VolumeError::format(
                        &h.path,
                        format!(
                            "(7FE0,0010) PixelData holds {len} bytes, fewer than the {} of {count} frames of {} x {} x {} bits: truncated",
                            *count as u64 * slice_bytes,
                            layout.cols,
                            layout.rows,
                            layout.bits_allocated
                        ),
                    ));
                }
            }
        }
    }
    let first = sorted[0];
    let mut m = [[0.0; 4]; 3];
    for r in 0..3 {
        m[r][0] = row[r] * h0.ps[1];
        m[r][1] = col[r] * h0.ps[0];
        m[r][2] = step_vec[r];
        m[r][3] = first.ipp[r];
    }
    let sample = match (layout.bits_allocated, layout.signed) {
        (8, false) => Sample::U8,
        (8, true) => Sample::I8,
        (16, false) => Sample::U16,
        (16, true) => Sample::I16,
        (32, false) => Sample::U32,
        _ => Sample::I32,
    };
    let info = VolumeInfo {
        dims: [layout.cols, layout.rows, count as u64],
        sample,
        index_to_world: m,
        frame: Frame::Lps,
        slope: first.slope,
        intercept: first.intercept,
        format: match (sorted.iter().all(|h| h.syntax.codec == h0.syntax.codec), h0.syntax.codec) {
            (false, _) => "DICOM series (mixed compression)",
            (true, None) => "DICOM series",
            (true, Some(Codec::Rle)) => "DICOM series (RLE Lossless)",
            (true, Some(Codec::JpegBaseline)) => "DICOM series (JPEG Baseline, lossy)",
            (true, Some(Codec::JpegLossless { .. })) => "DICOM series (JPEG Lossless)",
        },
        files: {
            // Each file once (a multi-frame file holds several slices).
            let mut seen = std::collections::HashSet::new();
            sorted.iter().filter(|h| seen.insert(h.path.clone())).map(|h| h.path.clone()).collect()
        },
        sequential_only: false,
    };
    let slices = sorted
        .iter()
        .map(|h| SliceMeta { path: h.path.clone(), slope: h.slope, intercept: h.intercept, syntax: h.syntax, frame: h.frame.clone() })
        .collect();
    Ok((info, Box::new(DicomSlices { layout, slices })))
}

/// One slice per file.
struct DicomSlices {
    layout: Layout,
    slices: Vec<SliceMeta>,
}

/// The PixelData bytes in the file's byte order (dicom-object decodes OW
/// into 16-bit words in native order; put them back).
fn stream_bytes(p: &PrimitiveValue, big_endian: bool) -> Option<Vec<u8>> {
    macro_rules! words {
        ($v:expr) => {
            $v.iter().flat_map(|w| if big_endian { w.to_be_bytes() } else { w.to_le_bytes() }).collect::<Vec<u8>>()
        };
    }
    Some(match p {
        PrimitiveValue::U8(v) => v.to_vec(),
        PrimitiveValue::U16(v) => words!(v),
        PrimitiveValue::I16(v) => words!(v),
        PrimitiveValue::U32(v) => words!(v),
        PrimitiveValue::I32(v) => words!(v),
        PrimitiveValue::Empty => Vec::new(),
        _ => return None,
    })
}

/// Decodes `need` samples of `layout` from `bytes` into `out`: mask to
/// BitsStored below HighBit, sign-extend if signed, rescale.
fn decode_samples(bytes: &[u8], layout: &Layout, big_endian: bool, slope: f64, intercept: f64, out: &mut [f32]) {
    let bpp = (layout.bits_allocated / 8) as usize;
    let bs = layout.bits_stored;
    let shift = layout.high_bit + 1 - bs;
    let mask: u32 = if bs >= 32 { u32::MAX } else { (1u32 << bs) - 1 };
    let sign = 1u32 << (bs - 1);
    let plain = slope == 1.0 && intercept == 0.0;
    for (o, c) in out.iter_mut().zip(bytes.chunks_exact(bpp)) {
        let raw: u32 = match (bpp, big_endian) {
            (1, _) => c[0] as u32,
            (2, false) => u16::from_le_bytes([c[0], c[1]]) as u32,
            (2, true) => u16::from_be_bytes([c[0], c[1]]) as u32,
            (_, false) => u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
            (_, true) => u32::from_be_bytes([c[0], c[1], c[2], c[3]]),
        };
        let u = (raw >> shift) & mask;
        let v: f64 = if layout.signed && u & sign != 0 { (u as i64 - (1i64 << bs)) as f64 } else { u as f64 };
        *o = if plain { v as f32 } else { (v * slope + intercept) as f32 };
    }
}

/// The layout of samples as `codec` hands them back: a JPEG decoder's
/// come right-aligned (the stored value in the low BitsStored bits),
/// whatever HighBit says; RLE keeps the stored bytes as they are.
fn decoded_layout(l: &Layout, codec: Option<Codec>) -> Layout {
    match codec {
        Some(Codec::JpegBaseline | Codec::JpegLossless { .. }) => Layout { high_bit: l.bits_stored - 1, ..*l },
        _ => *l,
    }
}

/// Slice `k`, frame `f` of a multi-frame file, read from where the walk
/// found its pixels: native samples at their offset, or the frame's
/// fragments (by the basic offset table, or one fragment a frame).
fn read_frame(k: u64, s: &SliceMeta, f: &FrameOf, l: &Layout, out: &mut [f32]) -> Result<(), VolumeError> {
    let pd = place(tags::PIXEL_DATA, "PixelData");
    let at = |m: String| VolumeError::format(&s.path, format!("slice {k} (frame {}): {pd}: {m}", f.index + 1));
    let need = (l.rows * l.cols) as usize;
    let bpp = (l.bits_allocated / 8) as usize;
    let mut file = File::open(&s.path).map_err(|e| VolumeError::io(&s.path, "opening", e))?;
    let mut read_at = |offset: usize, len: usize| -> Result<Vec<u8>, VolumeError> {
        let mut b = vec![0u8; len];
        file.seek(SeekFrom::Start(offset as u64)).and_then(|_| file.read_exact(&mut b)).map_err(|e| VolumeError::io(&s.path, &format!("reading frame {} at byte {offset}", f.index + 1), e))?;
        Ok(b)
    };
    let (bytes, big_endian) = match (&*f.pixels, s.syntax.codec) {
        (PixelData::Native { offset, len }, None) => {
            // The open checked that the value holds every frame.
            let start = f.index as usize * need * bpp;
            if start + need * bpp > *len {
                return Err(at(format!("{len} bytes hold no frame {}", f.index + 1)));
            }
            (read_at(offset + start, need * bpp)?, s.syntax.big_endian)
        }
        (PixelData::Encapsulated { items }, Some(codec)) => {
            let Some((&(bot_at, bot_len), frags)) = items.split_first() else { return Err(at("no basic offset table item".into())) };
            if frags.is_empty() {
                return Err(at("no fragments".into()));
            }
            let count = f.count as usize;
            let i = f.index as usize;
            let range = if bot_len > 0 {
                if bot_len != 4 * count {
                    return Err(at(format!("a basic offset table of {bot_len} bytes for {count} frames")));
                }
                let bot = read_at(bot_at, bot_len)?;
                let off = |j: usize| u32::from_le_bytes([bot[4 * j], bot[4 * j + 1], bot[4 * j + 2], bot[4 * j + 3]]) as usize;
                // Item j's offset from the first fragment's item.
                let rel = |j: usize| frags[j].0 - frags[0].0;
                let first = (0..frags.len()).find(|&j| rel(j) == off(i)).ok_or_else(|| at(format!("the offset table's {} for frame {} starts no fragment", off(i), i + 1)))?;
                let end = if i + 1 < count { (first..frags.len()).find(|&j| rel(j) >= off(i + 1)).unwrap_or(frags.len()) } else { frags.len() };
                first..end
            } else if frags.len() == count {
                i..i + 1
            } else {
                return Err(at(format!("{} fragments for {count} frames and no offset table: mint cannot tell the frames apart", frags.len())));
            };
            let mut pieces = Vec::with_capacity(range.len());
            for &(o, n) in &frags[range] {
                pieces.push(read_at(o, n)?);
            }
            let mut bytes = Vec::new();
            decode_frame(codec, &pieces, FrameShape { rows: l.rows, cols: l.cols, bits_allocated: l.bits_allocated }, &mut bytes).map_err(at)?;
            (bytes, false)
        }
        (PixelData::Native { .. }, Some(_)) => return Err(at("not encapsulated, but the transfer syntax is a compressed one".into())),
        (PixelData::Encapsulated { .. }, None) => return Err(at("encapsulated (compressed), but the transfer syntax is not a compressed one".into())),
    };
    if bytes.len() < need * bpp {
        return Err(at(format!("{} bytes, fewer than the {} of a frame", bytes.len(), need * bpp)));
    }
    decode_samples(&bytes[..need * bpp], &decoded_layout(l, s.syntax.codec), big_endian, s.slope, s.intercept, out);
    Ok(())
}

impl DicomSlices {
    /// Decodes slice `k` into `out`.
    fn decode_slice(&mut self, k: u64, out: &mut [f32]) -> Result<(), VolumeError> {
        let Some(s) = self.slices.get(k as usize) else {
            let p = self.slices.first().map(|s| s.path.clone()).unwrap_or_default();
            return Err(VolumeError::new(crate::VolumeErrorKind::Value, &p, format!("slice {k} of a series of {}", self.slices.len())));
        };
        let l = self.layout;
        let need = (l.rows * l.cols) as usize;
        if out.len() != need {
            return Err(VolumeError::new(crate::VolumeErrorKind::Value, &s.path, format!("slice {k}: {} values asked, a slice holds {need}", out.len())));
        }
        if let Some(f) = &s.frame {
            return read_frame(k, s, f, &l, out);
        }
        let obj = OpenFileOptions::new()
            .read_to(tags::PIXEL_DATA)
            .open_file(&s.path)
            .map_err(|e| VolumeError::format(&s.path, format!("slice {k}: cannot read the DICOM file (truncated or corrupted?): {}", chain(&e))))?;
        let pd = place(tags::PIXEL_DATA, "PixelData");
        let e = obj.get(tags::PIXEL_DATA).ok_or_else(|| VolumeError::format(&s.path, format!("slice {k}: {pd} is missing")))?;
        let bpp = (l.bits_allocated / 8) as usize;
        let (bytes, big_endian) = match (e.value(), s.syntax.codec) {
            (Value::PixelSequence(seq), Some(codec)) => {
                let shape = FrameShape { rows: l.rows, cols: l.cols, bits_allocated: l.bits_allocated };
                let mut bytes = Vec::new();
                decode_frame(codec, seq.fragments(), shape, &mut bytes).map_err(|m| VolumeError::format(&s.path, format!("slice {k}: {pd}: {m}")))?;
                (bytes, false)
            }
            (Value::PixelSequence(_), None) => {
                return Err(VolumeError::format(&s.path, format!("slice {k}: {pd} is encapsulated (compressed), but the transfer syntax is not a compressed one")))
            }
            (Value::Primitive(_), Some(_)) => {
                return Err(VolumeError::format(&s.path, format!("slice {k}: {pd} is not encapsulated, but the transfer syntax is a compressed one")))
            }
            (Value::Primitive(prim), None) => {
                let b = stream_bytes(prim, s.syntax.big_endian).ok_or_else(|| VolumeError::format(&s.path, format!("slice {k}: {pd} holds values of an unexpected type")))?;
                (b, s.syntax.big_endian)
            }
            (Value::Sequence(_), _) => return Err(VolumeError::format(&s.path, format!("slice {k}: {pd} is a sequence, not samples"))),
        };
        if bytes.len() < need * bpp {
            return Err(VolumeError::format(
                &s.path,
                format!(
                    "slice {k}: {pd} holds {} bytes, fewer than the {} of Rows x Columns x BitsAllocated/8 ({} x {} x {}/8): truncated",
                    bytes.len(),
                    need * bpp,
                    l.rows,
                    l.cols,
                    l.bits_allocated
                ),
            ));
        }
        decode_samples(&bytes[..need * bpp], &decoded_layout(&l, s.syntax.codec), big_endian, s.slope, s.intercept, out);
        Ok(())
    }
}

impl SliceSource for DicomSlices {
    fn read_slice(&mut self, k: u64, out: &mut [f32], stats: &mut crate::SampleStats) -> Result<(), VolumeError> {
        self.decode_slice(k, out)?;
        crate::sample_stats(out, stats);
        Ok(())
    }

    fn try_clone(&self) -> Result<Box<dyn SliceSource>, VolumeError> {
        Ok(Box::new(DicomSlices { layout: self.layout, slices: self.slices.clone() }))
    }

    fn random_access(&self) -> bool {
        true
    }

    fn stored(&mut self, k0: u64, count: u64) -> Vec<crate::ahead::Stored> {
        // Single-frame files, read whole (a multi-frame file's frames are
        // read where they lie).
        let slices = self.slices.iter().skip(k0 as usize).take(count as usize).filter(|s| s.frame.is_none());
        slices.map(|s| crate::ahead::Stored { path: s.path.clone(), at: 0, len: None }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OpenOptions, Volume};

    fn shared() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/volumes/ct-chest-dicom-series-lungpetctdx")
    }

    fn slice(n: usize) -> Vec<u8> {
        std::fs::read(shared().join(format!("1-{n:02}.dcm"))).unwrap()
    }

    /// `bytes` with the explicit-VR (short length) element `tag` of the
    /// data set set to `value` (its length changed as needed).
    fn edit(bytes: &[u8], tag: (u16, u16), value: &[u8]) -> Vec<u8> {
        let t = [tag.0.to_le_bytes(), tag.1.to_le_bytes()].concat();
        let i = (132..bytes.len() - 8).find(|&i| bytes[i..i + 4] == t[..] && bytes[i + 4..i + 6].iter().all(u8::is_ascii_uppercase)).unwrap();
        let len = u16::from_le_bytes([bytes[i + 6], bytes[i + 7]]) as usize;
        let mut v = value.to_vec();
        if v.len() % 2 == 1 {
            v.push(if &bytes[i + 4..i + 6] == b"UI" { 0 } else { b' ' });
        }
        let mut out = bytes[..i + 6].to_vec();
        out.extend((v.len() as u16).to_le_bytes());
        out.extend(&v);
        out.extend(&bytes[i + 8 + len..]);
        out
    }

    fn folder(files: &[(&str, Vec<u8>)]) -> tempfile::TempDir {
        let d = tempfile::tempdir().unwrap();
        for (name, b) in files {
            std::fs::write(d.path().join(name), b).unwrap();
        }
        d
    }

    fn open_err(d: &tempfile::TempDir) -> String {
        Volume::open(d.path(), &OpenOptions::default()).unwrap_err().to_string()
    }

    #[test]
    fn the_shared_series_is_placed_where_its_headers_say() {
        let mut v = Volume::open(&shared(), &OpenOptions::default()).unwrap();
        let i = v.info().clone();
        assert_eq!((i.dims, i.sample, i.frame, i.slope, i.intercept), ([512, 512, 30], Sample::U16, Frame::Lps, 1.0, -1024.0));
        assert!((i.spacing(2) - 8.0).abs() < 1e-9 && (i.spacing(0) - 0.646484375).abs() < 1e-12);
        // The lowest slice (z = 80) is the first; 1-01.dcm is at z = 312, the last.
        assert_eq!(i.world([0.0, 0.0, 0.0]), [-173.1767578125, -294.1767578125, 80.0]);
        assert_eq!(i.world([0.0, 0.0, 29.0])[2], 312.0);
        assert!(i.files[29].ends_with("1-01.dcm"));
        let mut s = vec![0.0; 512 * 512];
        v.read_slices(29, 1, &mut s).unwrap();
        let (lo, hi) = s.iter().fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(lo >= -1024.0 && hi <= 3071.0 && hi > 500.0, "{lo} .. {hi}");
    }

    #[test]
    fn an_oblique_series_in_any_file_order() {
        // Three slices turned 30 degrees about z, saved under names that do not sort by position.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let iop = format!("{c:.6}\\{s:.6}\\0\\{:.6}\\{c:.6}\\0", -s);
        let files: Vec<(&str, Vec<u8>)> = [("b.dcm", 2), ("c.dcm", 1), ("a.dcm", 3)].iter().map(|&(n, k)| (n, edit(&slice(k), (0x0020, 0x0037), iop.as_bytes()))).collect();
        let d = folder(&files);
        let v = Volume::open(d.path(), &OpenOptions::default()).unwrap();
        let i = v.info();
        assert_eq!(i.dims[2], 3);
        // Slice 1-03 is the lowest (z = 296); voxel (i, j, k) = IPP + i·ps·row + j·ps·col + k·step.
        let ps = 0.646484375;
        let (ipp, row, col) = ([-173.1767578125, -294.1767578125, 296.0], [c, s, 0.0], [-s, c, 0.0]);
        let w = i.world([10.0, 20.0, 2.0]);
        let want: [f64; 3] = std::array::from_fn(|r| ipp[r] + 10.0 * ps * row[r] + 20.0 * ps * col[r] + [0.0, 0.0, 16.0][r]);
        for r in 0..3 {
            assert!((w[r] - want[r]).abs() < 1e-4, "{w:?} vs {want:?}");
        }
        assert!(i.files[0].ends_with("a.dcm") && i.files[1].ends_with("b.dcm") && i.files[2].ends_with("c.dcm"));
    }

    #[test]
    fn series_that_are_not_one_grid_are_named() {
        // A missing slice.
        let d = folder(&[("1.dcm", slice(1)), ("2.dcm", slice(2)), ("4.dcm", slice(4)), ("5.dcm", slice(5))]);
        let e = open_err(&d);
        assert!(e.contains("slice missing between") && e.contains("about 1 slice missing"), "{e}");
        // Mixed sizes.
        let d = folder(&[("1.dcm", slice(1)), ("2.dcm", edit(&slice(2), (0x0028, 0x0010), &256u16.to_le_bytes())), ("3.dcm", slice(3))]);
        let e = open_err(&d);
        assert!(e.contains("2.dcm") && e.contains("not the same grid"), "{e}");
        // Mixed orientations.
        let d = folder(&[("1.dcm", slice(1)), ("2.dcm", edit(&slice(2), (0x0020, 0x0037), b"0\\1\\0\\-1\\0\\0")), ("3.dcm", slice(3))]);
        assert!(open_err(&d).contains("not the same grid"), "{}", open_err(&d));
        // Two series.
        let d = folder(&[("1.dcm", slice(1)), ("2.dcm", edit(&slice(2), (0x0020, 0x000E), b"1.2.3.4")), ("3.dcm", slice(3))]);
        let e = open_err(&d);
        assert!(e.contains("holds 2 series"), "{e}");
        // A truncated slice, and a length claiming more than the file: one line, no panic.
        let b = slice(1);
        let d = folder(&[("1.dcm", b[..b.len() - 5000].to_vec()), ("2.dcm", slice(2))]);
        let e = open_err(&d);
        assert!(e.contains("1.dcm") && e.contains("truncated"), "{e}");
        let mut huge = slice(2);
        let at = 2552; // inside the element headers before PixelData
        huge[at..at + 2].copy_from_slice(&0xFFF0u16.to_le_bytes());
        let d = folder(&[("1.dcm", slice(1)), ("2.dcm", huge)]);
        let e = open_err(&d);
        assert!(!e.contains('\n') && e.contains("2.dcm"), "{e}");
        // Non-DICOM files beside the series are skipped.
        let d = folder(&[("1.dcm", slice(1)), ("2.dcm", slice(2)), ("notes.txt", b"hello".to_vec())]);
        assert_eq!(Volume::open(d.path(), &OpenOptions::default()).unwrap().info().dims[2], 2);
    }

    fn compressed(what: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/dicom-compressed").join(what)
    }

    #[test]
    fn one_series_of_several_is_chosen_by_uid_number_or_file() {
        // Slices 1, 2 of the shared series and 3, 4, 5 moved to series 1.2.3.4.
        let other = |n: usize| edit(&slice(n), (0x0020, 0x000E), b"1.2.3.4");
        let d = folder(&[("a1.dcm", slice(1)), ("a2.dcm", slice(2)), ("b3.dcm", other(3)), ("b4.dcm", other(4)), ("b5.dcm", other(5)), ("notes.dcm", b"not dicom".to_vec())]);
        let e = open_err(&d);
        assert!(e.contains("holds 2 series") && e.contains("1: ") && e.contains("2: 1.2.3.4 (3 images, e.g. b3.dcm)") && e.contains("--dicom-series"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        let with = |pick: &str| OpenOptions { dicom_series: Some(pick.to_string()), ..OpenOptions::default() };
        let own_uid = {
            let v = Volume::open(&d.path().join("a1.dcm"), &OpenOptions::default()).unwrap();
            assert_eq!(v.info().dims[2], 2, "a .dcm file reads its own series");
            v.info().files.len()
        };
        assert_eq!(own_uid, 2);
        for (pick, slices) in [("1", 2u64), ("2", 3), ("1.2.3.4", 3)] {
            let mut v = Volume::open(d.path(), &with(pick)).unwrap();
            assert_eq!(v.info().dims[2], slices, "--dicom-series {pick}");
            let mut s = vec![0.0; (v.info().slice_len() as u64 * slices) as usize];
            v.read_slices(0, slices, &mut s).unwrap();
        }
        assert_eq!(Volume::open(&d.path().join("b4.dcm"), &OpenOptions::default()).unwrap().info().dims[2], 3);
        // The option wins over the file's own series.
        assert_eq!(Volume::open(&d.path().join("b4.dcm"), &with("1")).unwrap().info().dims[2], 2);
        for (pick, want) in [("3", "no series number 3: the folder holds 2 series"), ("0", "no series number 0"), ("9.9.9", "no series with SeriesInstanceUID 9.9.9")] {
            let e = Volume::open(d.path(), &with(pick)).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains("2: 1.2.3.4") && !e.contains('\n'), "{pick}: {e}");
        }
        let e = Volume::open(&d.path().join("notes.dcm"), &OpenOptions::default()).unwrap_err().to_string();
        assert!(e.contains("notes.dcm") && e.contains("not a DICOM image"), "{e}");
    }

    fn slices(dir: &Path) -> (VolumeInfo, Vec<f32>) {
        let mut v = Volume::open(dir, &OpenOptions::default()).unwrap();
        let i = v.info().clone();
        let n = (i.dims[0] * i.dims[1] * i.dims[2]) as usize;
        let mut s = vec![0.0; n];
        v.read_slices(0, i.dims[2], &mut s).unwrap();
        (i, s)
    }

    #[test]
    fn compressed_series_read_as_their_uncompressed_originals() {
        let plain = folder(&[("1-01.dcm", slice(1)), ("1-02.dcm", slice(2))]);
        let (pi, ps) = slices(plain.path());
        for (what, format) in [("rle", "DICOM series (RLE Lossless)"), ("jpeg-lossless-sv1", "DICOM series (JPEG Lossless)")] {
            let (ci, cs) = slices(&compressed(what));
            assert_eq!(ci.format, format);
            assert_eq!((ci.dims, ci.index_to_world, ci.sample, ci.slope, ci.intercept), (pi.dims, pi.index_to_world, pi.sample, pi.slope, pi.intercept), "{what}");
            assert!(cs == ps, "{what}: the samples differ");
        }
        // One slice: Process 14 (selection value 6) and lossy 8-bit baseline.
        let one = folder(&[("1-01.dcm", slice(1))]);
        let (_, ps) = slices(one.path());
        let (_, cs) = slices(&compressed("jpeg-lossless-p14"));
        assert!(cs == ps, "jpeg-lossless-p14: the samples differ");
        let (bi, bs) = slices(&compressed("jpeg-baseline"));
        assert_eq!((bi.sample, bi.slope, bi.intercept), (Sample::U8, 16.05882, -2047.0));
        // Quantised to 8 bits (16 HU a step) and lossy: a mean error of a
        // few HU; a wrong decoder is off by hundreds.
        let mean = bs.iter().zip(&ps).map(|(a, b)| (a - b).abs() as f64).sum::<f64>() / ps.len() as f64;
        assert!(mean < 12.0, "baseline mean error {mean} HU");
    }

    #[test]
    fn damaged_compressed_slices_are_one_line() {
        let good = std::fs::read(compressed("jpeg-lossless-sv1").join("1-01.dcm")).unwrap();
        let rle = std::fs::read(compressed("rle").join("1-01.dcm")).unwrap();
        // Truncated inside the fragments, and bytes flipped inside them.
        for (name, b) in [("sv1", &good), ("rle", &rle)] {
            let d = folder(&[("1.dcm", b[..b.len() - 3000].to_vec())]);
            let e = open_err(&d);
            assert!(e.contains("1.dcm") && !e.contains('\n'), "{name}: {e}");
            for k in 1..12 {
                let mut f = b.clone();
                let at = f.len() - 1000 * k * k;
                for x in &mut f[at..at + 64] {
                    *x ^= 0x5A;
                }
                let d = folder(&[("1.dcm", f)]);
                if let Ok(mut v) = Volume::open(d.path(), &OpenOptions::default()) {
                    let mut s = vec![0.0; 512 * 512];
                    if let Err(e) = v.read_slices(0, 1, &mut s) {
                        let e = e.to_string();
                        assert!(e.contains("1.dcm") && !e.contains('\n'), "{name}: {e}");
                    }
                }
            }
        }
        // A syntax without a decoder here is named, with what mint reads.
        let ext = edit(&good, (0x0002, 0x0010), b"1.2.840.10008.1.2.4.51");
        let d = folder(&[("1.dcm", ext)]);
        let e = open_err(&d);
        assert!(e.contains("JPEG Extended") && e.contains("no decoder") && e.contains("JPEG Lossless"), "{e}");
    }


    fn multiframe(what: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/dicom-multiframe").join(what)
    }

    /// `file` alone in a folder.
    fn alone(file: &Path) -> tempfile::TempDir {
        folder(&[("1.dcm", std::fs::read(file).unwrap())])
    }

    #[test]
    fn enhanced_multi_frame_files_read_as_the_series_of_their_frames() {
        let (si, ss) = slices(&multiframe("single"));
        assert_eq!(si.dims, [64, 64, 3]);
        for what in ["enhanced.dcm", "enhanced-rle.dcm", "enhanced-jpeg-lossless.dcm"] {
            let d = alone(&multiframe(what));
            let (mi, ms) = slices(d.path());
            // Frames stored 1-02, 1-01, 1-03 come out ordered by position.
            assert_eq!((mi.dims, mi.index_to_world, mi.slope, mi.intercept), (si.dims, si.index_to_world, si.slope, si.intercept), "{what}");
            assert!(ms == ss, "{what}: the samples differ");
            assert_eq!(mi.files.len(), 1);
        }
        // Frames are placed by their own positions: the world point of
        // voxel (0, 0, 2) is the highest slice's (z = 312).
        assert_eq!(si.world([0.0, 0.0, 2.0])[2], 312.0);
    }

    #[test]
    fn damaged_multi_frame_files_are_one_line() {
        let b = std::fs::read(multiframe("enhanced.dcm")).unwrap();
        // NumberOfFrames 4 with 3 per-frame items, and 2 with 3.
        for n in ["4", "2"] {
            let d = folder(&[("1.dcm", edit(&b, (0x0028, 0x0008), n.as_bytes()))]);
            let e = open_err(&d);
            assert!(e.contains("1.dcm") && e.contains("PerFrameFunctionalGroupsSequence") && !e.contains('\n'), "{e}");
        }
        let d = folder(&[("1.dcm", edit(&b, (0x0028, 0x0008), b"0"))]);
        assert!(open_err(&d).contains("not a usable number of frames"));
        // Rows and Columns claimed far beyond what the fragments can hold.
        let rle = std::fs::read(multiframe("enhanced-rle.dcm")).unwrap();
        let big = edit(&edit(&rle, (0x0028, 0x0010), &65535u16.to_le_bytes()), (0x0028, 0x0011), &65535u16.to_le_bytes());
        let e = open_err(&folder(&[("1.dcm", big)]));
        assert!(e.contains("cannot hold 3 frames of 65535 x 65535"), "{e}");
        // Truncated pixels.
        let d = folder(&[("1.dcm", b[..b.len() - 100].to_vec())]);
        let e = open_err(&d);
        assert!(e.contains("1.dcm") && e.contains("truncated"), "{e}");
        // Compressed frames with bytes flipped: errors name the frame, or a value.
        for what in ["enhanced-rle.dcm", "enhanced-jpeg-lossless.dcm"] {
            let c = std::fs::read(multiframe(what)).unwrap();
            for k in 1..40 {
                let mut f = c.clone();
                let at = f.len() - 300 * k;
                for x in &mut f[at..at + 16] {
                    *x ^= 0x5A;
                }
                let d = folder(&[("1.dcm", f)]);
                match Volume::open(d.path(), &OpenOptions::default()) {
                    Err(e) => assert!(!e.to_string().contains('\n')),
                    Ok(mut v) => {
                        let mut s = vec![0.0; 64 * 64 * 3];
                        if let Err(e) = v.read_slices(0, 3, &mut s) {
                            assert!(e.to_string().contains("1.dcm") && !e.to_string().contains('\n'), "{e}");
                        }
                    }
                }
            }
        }
    }

}
