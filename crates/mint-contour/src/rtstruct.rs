//! DICOM RT Structure Sets (RTSTRUCT) in, read with dicom-rs
//! (`dicom-object`), with no text step in between. [`layout`] tells a
//! DICOM file from a profile by its first bytes; [`StructureSet::read`]
//! parses one into [`Roi`]s of [`RoiContour`]s (points as stored: patient
//! coordinates in mm); [`Roi::stack`] turns one ROI into the
//! [`StackFrame`] and [`Section`]s the reconstructions take, the same
//! sections a profile of the same contours gives.
//!
//! # What is read
//! - Modality (0008,0060): must be `RTSTRUCT` when present.
//! - Structure Set ROI Sequence (3006,0020): ROI Number (3006,0022) and
//!   ROI Name (3006,0026) of each ROI.
//! - ROI Contour Sequence (3006,0039), required: per item the Referenced
//!   ROI Number (3006,0084) and the Contour Sequence (3006,0040), whose
//!   items hold Contour Geometric Type (3006,0042), Number of Contour
//!   Points (3006,0046) and Contour Data (3006,0050), `x\y\z` triplets.
//!
//! ROIs come in the order of the ROI Contour Sequence, then ROIs that are
//! only named (no contours). Everything else (images, frames of reference,
//! colours, observations) is ignored. A contour is named in messages by
//! its 1-based position in its ROI's Contour Sequence ("contour 12").
//!
//! # From contours to a stack ([`Roi::stack`])
//! RTSTRUCT contours carry no slice index and no image orientation (that
//! lives in the CT series); the planes come from the points:
//! 1. Only `CLOSED_PLANAR` contours bound a solid: a `POINT`,
//!    `OPEN_PLANAR` or `OPEN_NONPLANAR` contour refuses the ROI, naming it.
//! 2. Consecutive repeated points and a closing repeat are dropped (as for
//!    profiles); at least 3 distinct points must remain.
//! 3. The stack normal is the sum of the contours' Newell normals (area
//!    weighted), each turned to agree with the largest one (holes may wind
//!    either way); contours tilted more than 5 degrees from the largest
//!    one are left out of the sum, and refused at step 5.
//! 4. The frame: if every contour is constant in the same coordinate (an
//!    axial, sagittal or coronal stack) the axis frame, whose projection
//!    copies coordinates; else a frame around the normal, turned so that
//!    its largest component is positive. Sections come in increasing order
//!    along the frame's normal (for axial stacks: increasing z).
//! 5. Every contour's points lie within [`StackOptions::plane_tolerance`]
//!    of its mid-plane along the normal; else the contour is reported as
//!    tilted (planar, but not parallel to the stack) or as not planar.
//! 6. Contours are sorted by their offset along the normal and grouped
//!    into sections: a contour within the tolerance of the first contour
//!    of the current section joins it. Within a section the contours keep
//!    their file order; several contours of a plane are outer boundaries,
//!    holes and islands by nesting, as from a profile.
//! 7. The contours of each plane must be simple and pairwise disjoint
//!    (the exact test profiles use, [`crate::geom2d::first_crossing`]).
//!
//! Why a tolerance in millimetres: DICOM patient coordinates are in mm and
//! Contour Data are decimal strings (DS, at most 16 characters), usually
//! written to 0.01 mm; a point of an oblique plane written so lies up to
//! about 0.009 mm off it. The default 0.02 mm absorbs that and stays far
//! below any slice spacing in use (0.5 mm and up). Axis-aligned stacks are
//! exact and need no tolerance.
//!
//! # File layouts ([`Layout`])
//! Read by content, whatever the extension: the standard file (a 128-byte
//! preamble, `DICM`, the file meta group, the data set); the same without
//! the preamble; and a bare data set with no meta group (some old files,
//! such as pydicom's `rtstruct.dcm`), recognised by a first tag in group
//! 0008, read as implicit VR little endian, or explicit VR if the two
//! bytes after the tag are VR letters.
//!
//! Limits: contours drawn with the keyhole technique (a hole joined to its
//! outer contour by a zero-width channel, as the standard suggests) touch
//! themselves and are refused. Memory: the file, its parsed object and the
//! ROIs' points, a few times the file size. Before parsing, every element
//! length is checked against the bytes that hold it (`check_lengths`):
//! dicom-parser zero-fills a buffer of the claimed length before reading,
//! so one corrupted length field made it reserve up to 4 GiB (3.9 GB
//! resident, 3 s) before failing; now it is a one-line error at once.

use crate::error::{ContourError, DicomError, DicomErrorKind as K};
use crate::geom2d::{first_crossing, P2};
use crate::profile::{newell, Contour, Section, StackFrame};
use dicom_object::file::ReadPreamble;
use dicom_object::mem::InMemElement;
use dicom_object::{InMemDicomObject, OpenFileOptions};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// The attributes read (names as in the DICOM dictionary, PS3.6).
mod tags {
    use dicom_object::Tag;
    pub const MODALITY: Tag = Tag(0x0008, 0x0060);
    pub const STRUCTURE_SET_LABEL: Tag = Tag(0x3006, 0x0002);
    pub const STRUCTURE_SET_ROI_SEQUENCE: Tag = Tag(0x3006, 0x0020);
    pub const ROI_NUMBER: Tag = Tag(0x3006, 0x0022);
    pub const ROI_NAME: Tag = Tag(0x3006, 0x0026);
    pub const ROI_CONTOUR_SEQUENCE: Tag = Tag(0x3006, 0x0039);
    pub const CONTOUR_SEQUENCE: Tag = Tag(0x3006, 0x0040);
    pub const CONTOUR_GEOMETRIC_TYPE: Tag = Tag(0x3006, 0x0042);
    pub const NUMBER_OF_CONTOUR_POINTS: Tag = Tag(0x3006, 0x0046);
    pub const CONTOUR_DATA: Tag = Tag(0x3006, 0x0050);
    pub const REFERENCED_ROI_NUMBER: Tag = Tag(0x3006, 0x0084);
}

/// The only contour type that bounds a solid.
pub const CLOSED_PLANAR: &str = "CLOSED_PLANAR";

pub use mint_volume::dicom_lengths::{layout, Layout};
use mint_volume::dicom_lengths::check_lengths;

/// The DICOM layout of the file at `path` by content (reads at most its
/// first 132 bytes), or `None` if it is not DICOM.
pub fn sniff(path: &Path) -> Result<Option<Layout>, ContourError> {
    use std::io::Read;
    let f = std::fs::File::open(path).map_err(|e| ContourError::io(path, "cannot open for reading", e))?;
    let mut head = Vec::with_capacity(132);
    f.take(132).read_to_end(&mut head).map_err(|e| ContourError::io(path, "cannot read", e))?;
    Ok(layout(&head))
}

/// One contour of an ROI, as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct RoiContour {
    /// 1-based position in the ROI's Contour Sequence: its name in messages.
    pub item: usize,
    /// Contour Geometric Type, trimmed (`CLOSED_PLANAR`, `POINT`, ...).
    pub kind: String,
    /// Contour Data as points (mm, patient coordinates), in file order.
    pub points: Vec<[f64; 3]>,
    /// Why the contour's data cannot be used, if it cannot (checked when
    /// its ROI is stacked, so that the other ROIs stay readable).
    pub defect: Option<String>,
}

/// One ROI (region of interest) of a structure set.
#[derive(Debug, Clone, PartialEq)]
pub struct Roi {
    /// ROI Number.
    pub number: i64,
    /// ROI Name, trimmed (`ROI <number>` when the file names none).
    pub name: String,
    /// Its contours, in file order.
    pub contours: Vec<RoiContour>,
}

/// What `mint contours --list-rois` shows of an ROI.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RoiSummary {
    pub number: i64,
    pub name: String,
    /// All contours, of any type.
    pub contours: usize,
    /// `CLOSED_PLANAR` contours.
    pub closed: usize,
    /// Distinct planes of the closed contours (grouped as [`Roi::stack`]
    /// does, without its checks).
    pub slices: usize,
    /// Points of all contours.
    pub points: usize,
}

/// Options of [`Roi::stack`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StackOptions {
    /// How far (mm) a point may lie from its contour's plane, and contours
    /// of one section from one another, along the normal. Default 0.02.
    pub plane_tolerance: f64,
}

impl Default for StackOptions {
    fn default() -> Self {
        StackOptions { plane_tolerance: 0.02 }
    }
}

/// A parsed RT structure set: its ROIs and their contours.
#[derive(Debug, Clone, PartialEq)]
pub struct StructureSet {
    /// The file, for messages.
    pub path: PathBuf,
    /// Structure Set Label, if any.
    pub label: Option<String>,
    /// The ROIs, in the order described in the module docs.
    pub rois: Vec<Roi>,
}

impl StructureSet {
    /// Reads the file at `path` (any [`Layout`]); one-line errors name it:
    /// not DICOM, unreadable (truncated, corrupted), or not an RT
    /// structure set.
    pub fn read(path: &Path) -> Result<StructureSet, ContourError> {
        use dicom_transfer_syntax_registry::entries::{EXPLICIT_VR_LITTLE_ENDIAN, IMPLICIT_VR_LITTLE_ENDIAN};
        // Look before reading it all: a large file that is not DICOM.
        let lay = sniff(path)?;
        let bytes = match lay {
            Some(_) => std::fs::read(path).map_err(|e| ContourError::io(path, "cannot read", e))?,
            None => Vec::new(),
        };
        let Some(lay) = lay.and_then(|_| layout(&bytes)) else {
            return Err(DicomError::new(
                K::NotDicom,
                path,
                "not a DICOM file: no 'DICM' marker after a 128-byte preamble or at the start, and no data set at the start",
            )
            .into());
        };
        // dicom-parser zero-fills a buffer of each value's claimed length
        // before reading it: check every length against the bytes there are.
        if let Err(m) = check_lengths(&bytes, lay) {
            return Err(DicomError::new(K::Corrupt, path, format!("cannot read the DICOM data (truncated or corrupted file?): {m}")).into());
        }
        let corrupt =
            |e: &dyn std::error::Error| DicomError::new(K::Corrupt, path, format!("cannot read the DICOM data (truncated or corrupted file?): {}", chain(e)));
        let meta = |b: &[u8]| OpenFileOptions::new().read_preamble(ReadPreamble::Never).from_reader(b).map(|f| f.into_inner());
        let obj = match lay {
            Layout::Preamble => meta(&bytes[128..]).map_err(|e| corrupt(&e))?,
            Layout::Meta => meta(&bytes[..]).map_err(|e| corrupt(&e))?,
            Layout::Bare { explicit } => {
                let ts = if explicit { EXPLICIT_VR_LITTLE_ENDIAN } else { IMPLICIT_VR_LITTLE_ENDIAN };
                InMemDicomObject::read_dataset_with_ts(&bytes[..], &ts.erased()).map_err(|e| corrupt(&e))?
            }
        };
        Self::from_object(&obj, path)
    }

    /// The structure set in a parsed DICOM object; `path` names it in
    /// errors.
    pub fn from_object(obj: &InMemDicomObject, path: &Path) -> Result<StructureSet, ContourError> {
        let not_rt = |m: String| -> ContourError { DicomError::new(K::NotRtStruct, path, m).into() };
        let modality = text(obj.get(tags::MODALITY));
        if let Some(m) = &modality {
            if m != "RTSTRUCT" {
                return Err(not_rt(format!("not an RT structure set: its Modality is '{m}', not RTSTRUCT")));
            }
        }
        let Some(rcs) = obj.get(tags::ROI_CONTOUR_SEQUENCE) else {
            return Err(not_rt("not an RT structure set: it has no ROI Contour Sequence (3006,0039)".into()));
        };
        let Some(rcs) = rcs.items() else {
            return Err(not_rt("not an RT structure set: its ROI Contour Sequence (3006,0039) is not a sequence".into()));
        };
        // Names by number, in definition order.
        let mut named: Vec<(i64, String)> = Vec::new();
        for it in obj.get(tags::STRUCTURE_SET_ROI_SEQUENCE).and_then(|e| e.items()).unwrap_or(&[]) {
            if let Some(n) = it.get(tags::ROI_NUMBER).and_then(|e| e.to_int::<i64>().ok()) {
                named.push((n, text(it.get(tags::ROI_NAME)).unwrap_or_default()));
            }
        }
        let name_of = |n: i64| named.iter().find(|r| r.0 == n).map(|r| r.1.clone()).filter(|s| !s.is_empty()).unwrap_or_else(|| format!("ROI {n}"));
        let mut rois: Vec<Roi> = Vec::new();
        for (k, it) in rcs.iter().enumerate() {
            let Some(number) = it.get(tags::REFERENCED_ROI_NUMBER).and_then(|e| e.to_int::<i64>().ok()) else {
                return Err(
                    DicomError::new(K::Corrupt, path, format!("item {} of the ROI Contour Sequence has no Referenced ROI Number (3006,0084)", k + 1)).into()
                );
            };
            let idx = match rois.iter().position(|r| r.number == number) {
                Some(i) => i,
                None => {
                    rois.push(Roi { number, name: name_of(number), contours: Vec::new() });
                    rois.len() - 1
                }
            };
            let items = it.get(tags::CONTOUR_SEQUENCE).and_then(|e| e.items()).unwrap_or(&[]);
            for c in items {
                let item = rois[idx].contours.len() + 1;
                rois[idx].contours.push(read_contour(c, item));
            }
        }
        for (n, _) in &named {
            if !rois.iter().any(|r| r.number == *n) {
                rois.push(Roi { number: *n, name: name_of(*n), contours: Vec::new() });
            }
        }
        Ok(StructureSet { path: path.to_path_buf(), label: text(obj.get(tags::STRUCTURE_SET_LABEL)), rois })
    }

    /// The ROI called `name`: its exact name; else the one name equal up to
    /// case with spaces and underscores alike (`Lt_Lung` finds `Lt Lung`);
    /// else, if `name` is a number, the ROI with that number. No match, or
    /// several, is a one-line error listing the ROIs.
    pub fn find(&self, name: &str) -> Result<&Roi, ContourError> {
        let norm = |s: &str| s.trim().to_lowercase().replace(' ', "_");
        let exact: Vec<&Roi> = self.rois.iter().filter(|r| r.name == name).collect();
        let loose: Vec<&Roi> = self.rois.iter().filter(|r| norm(&r.name) == norm(name)).collect();
        let hits = if !exact.is_empty() { exact } else { loose };
        match hits.len() {
            1 => return Ok(hits[0]),
            0 => {}
            _ => {
                let nums: Vec<String> = hits.iter().map(|r| r.number.to_string()).collect();
                return Err(DicomError::new(
                    K::NoSuchRoi,
                    &self.path,
                    format!("several ROIs are named '{name}' (numbers {}): give the number instead", nums.join(", ")),
                )
                .into());
            }
        }
        if let Ok(n) = name.trim().parse::<i64>() {
            if let Some(r) = self.rois.iter().find(|r| r.number == n) {
                return Ok(r);
            }
        }
        let all: Vec<String> = self.rois.iter().map(|r| format!("{} '{}'", r.number, r.name)).collect();
        Err(DicomError::new(K::NoSuchRoi, &self.path, format!("no ROI named '{name}'; the ROIs are: {}", all.join(", "))).into())
    }
}

/// One item of a Contour Sequence; unusable data is kept as a defect.
fn read_contour(c: &InMemDicomObject, item: usize) -> RoiContour {
    let kind = text(c.get(tags::CONTOUR_GEOMETRIC_TYPE)).unwrap_or_default();
    let mut out = RoiContour { item, kind, points: Vec::new(), defect: None };
    let values = match c.get(tags::CONTOUR_DATA).map(|e| e.to_multi_float64()) {
        None => Vec::new(),
        Some(Ok(v)) => v,
        Some(Err(_)) => {
            out.defect = Some("its Contour Data (3006,0050) are not numbers".into());
            return out;
        }
    };
    if values.len() % 3 != 0 {
        out.defect = Some(format!("its Contour Data hold {} values, not a multiple of 3", values.len()));
        return out;
    }
    if values.iter().any(|v| !v.is_finite()) {
        out.defect = Some("its Contour Data hold a value that is not a finite number".into());
        return out;
    }
    out.points = values.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    if let Some(n) = c.get(tags::NUMBER_OF_CONTOUR_POINTS).and_then(|e| e.to_int::<i64>().ok()) {
        if n != out.points.len() as i64 {
            out.defect = Some(format!("its Number of Contour Points is {n} but its Contour Data hold {} points", out.points.len()));
        }
    }
    out
}

/// A text attribute, trimmed of the DS/CS padding; `None` if absent or not text.
fn text(e: Option<&InMemElement>) -> Option<String> {
    e.and_then(|e| e.to_str().ok()).map(|s| s.trim_matches(|c: char| c.is_whitespace() || c == '\0').to_string())
}

/// An error and its sources on one line.
fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(x) = src {
        let m = x.to_string();
        if !s.contains(&m) {
            s.push_str(": ");
            s.push_str(&m);
        }
        src = x.source();
    }
    s.replace(['\n', '\r'], " ")
}

/// Points without consecutive repeats and without a closing repeat.
fn distinct(points: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut v: Vec<[f64; 3]> = Vec::with_capacity(points.len());
    for &p in points {
        if v.last() != Some(&p) {
            v.push(p);
        }
    }
    while v.len() > 1 && v.last() == v.first() {
        v.pop();
    }
    v
}

/// The stack normal of contours (step 3 of the module docs), `None` if
/// they have no area.
fn stack_normal(contours: &[Vec<[f64; 3]>]) -> Option<[f64; 3]> {
    let normals: Vec<DVec3> = contours.iter().map(|c| DVec3::from(newell(c))).collect();
    let big = normals.iter().copied().max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))?;
    if !(big.length_squared() > 0.0) {
        return None;
    }
    // Contours tilted against the largest one do not pull the normal
    // (they are refused, by name, when their points are projected).
    let cos_max = 5f64.to_radians().cos();
    let mut n = DVec3::ZERO;
    for &m in &normals {
        let d = m.dot(big);
        if d.abs() < cos_max * (m.length_squared() * big.length_squared()).sqrt() {
            continue;
        }
        let s = if d < 0.0 { -1.0 } else { 1.0 };
        n += s * m;
    }
    Some(n.to_array())
}

/// The frame of step 4, `None` if the contours have no area.
fn stack_frame(contours: &[Vec<[f64; 3]>]) -> Option<StackFrame> {
    if let Some(d) = (0..3).find(|&d| contours.iter().all(|c| c.iter().all(|p| p[d] == c[0][d]))) {
        return Some(StackFrame::axis(d, 1.0));
    }
    let mut n = stack_normal(contours)?;
    let k = (0..3).max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs())).unwrap();
    if n[k] < 0.0 {
        n = n.map(|x| -x);
    }
    Some(StackFrame::around(n))
}

/// Groups of indices (step 6): `mids` sorted stably, a new group when a
/// value is more than `tol` past the first of the current group.
fn group_planes(mids: &[f64], tol: f64) -> Vec<Vec<usize>> {
    let mut order: Vec<usize> = (0..mids.len()).collect();
    order.sort_by(|&a, &b| mids[a].total_cmp(&mids[b]));
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for i in order {
        match groups.last_mut() {
            Some(g) if mids[i] - mids[g[0]] <= tol => g.push(i),
            _ => groups.push(vec![i]),
        }
    }
    for g in &mut groups {
        g.sort_unstable();
    }
    groups
}

impl Roi {
    /// `ROI 6 'Lt Lung'`: the ROI in messages.
    pub fn label(&self) -> String {
        format!("ROI {} '{}'", self.number, self.name)
    }

    /// Counts for `--list-rois`.
    pub fn summary(&self, opts: StackOptions) -> RoiSummary {
        let closed: Vec<Vec<[f64; 3]>> =
            self.contours.iter().filter(|c| c.kind == CLOSED_PLANAR && c.defect.is_none()).map(|c| distinct(&c.points)).filter(|c| c.len() >= 3).collect();
        let slices = match stack_frame(&closed) {
            Some(f) => {
                let mids: Vec<f64> = closed
                    .iter()
                    .map(|c| {
                        let s = c.iter().map(|&p| f.project(p).1);
                        let (lo, hi) = s.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
                        0.5 * (lo + hi)
                    })
                    .collect();
                group_planes(&mids, opts.plane_tolerance).len()
            }
            None => 0,
        };
        RoiSummary {
            number: self.number,
            name: self.name.clone(),
            contours: self.contours.len(),
            closed: self.contours.iter().filter(|c| c.kind == CLOSED_PLANAR).count(),
            slices,
            points: self.contours.iter().map(|c| c.points.len()).sum(),
        }
    }

    /// Does the ROI have a `CLOSED_PLANAR` contour?
    pub fn has_closed_contours(&self) -> bool {
        self.contours.iter().any(|c| c.kind == CLOSED_PLANAR)
    }

    /// The ROI as a stack of sections (see the module docs for the steps
    /// and checks); `path` names the file in errors, which also name the
    /// ROI and the contour.
    pub fn stack(&self, path: &Path, opts: StackOptions) -> Result<(StackFrame, Vec<Section>), ContourError> {
        let err = |kind, msg: String| -> ContourError { DicomError::new(kind, path, format!("{}: {msg}", self.label())).into() };
        if self.contours.is_empty() {
            return Err(err(K::Empty, "has no contours: nothing to reconstruct".into()));
        }
        // 1-2. Closed contours with usable data, repeats dropped.
        let mut items = Vec::with_capacity(self.contours.len());
        let mut pts: Vec<Vec<[f64; 3]>> = Vec::with_capacity(self.contours.len());
        for c in &self.contours {
            if c.kind != CLOSED_PLANAR {
                let kind = if c.kind.is_empty() { "of no Contour Geometric Type" } else { c.kind.as_str() };
                return Err(err(K::NotClosed, format!("contour {} is {kind}: only {CLOSED_PLANAR} contours bound a solid", c.item)));
            }
            if let Some(d) = &c.defect {
                return Err(err(K::BadContour, format!("contour {}: {d}", c.item)));
            }
            let p = distinct(&c.points);
            if p.len() < 3 {
                return Err(err(K::BadContour, format!("contour {} has {} distinct points; a closed contour needs at least 3", c.item, p.len())));
            }
            items.push(c.item);
            pts.push(p);
        }
        // 3-4. The normal and the frame.
        let Some(frame) = stack_frame(&pts) else {
            return Err(err(K::BadContour, "its contours have no area (their points are collinear)".into()));
        };
        // 5. Each contour in one plane across the normal.
        let tol = opts.plane_tolerance;
        let mut uvs: Vec<Vec<P2>> = Vec::with_capacity(pts.len());
        let mut spans: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
        for (i, p) in pts.iter().enumerate() {
            let mut uv = Vec::with_capacity(p.len());
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for &q in p {
                let (a, s) = frame.project(q);
                if !(a[0].is_finite() && a[1].is_finite() && s.is_finite()) {
                    return Err(err(K::BadContour, format!("contour {}: a point is too large to project", items[i])));
                }
                uv.push(a);
                lo = lo.min(s);
                hi = hi.max(s);
            }
            if hi - lo > 2.0 * tol {
                return Err(err(K::NotParallel, off_plane(p, frame.n, hi - lo, tol, items[i])));
            }
            uvs.push(uv);
            spans.push((lo, hi));
        }
        // 6. Sections along the normal.
        let mids: Vec<f64> = spans.iter().map(|s| 0.5 * (s.0 + s.1)).collect();
        let groups = group_planes(&mids, tol);
        let mut sections = Vec::with_capacity(groups.len());
        for (index, g) in groups.iter().enumerate() {
            let lo = g.iter().map(|&i| spans[i].0).fold(f64::INFINITY, f64::min);
            let hi = g.iter().map(|&i| spans[i].1).fold(f64::NEG_INFINITY, f64::max);
            let contours: Vec<Contour> = g.iter().map(|&i| Contour { points: pts[i].clone(), uv: uvs[i].clone(), line: items[i] as u64 }).collect();
            let s = Section { index, line: items[g[0]] as u64, offset: 0.5 * (lo + hi), contours };
            // 7. Simple, disjoint contours.
            let polys: Vec<&[P2]> = s.contours.iter().map(|c| c.uv.as_slice()).collect();
            if let Some(((c1, e1), (c2, e2))) = first_crossing(&polys) {
                let at = place(&frame, s.offset);
                let (a, b) = (items[g[c1]], items[g[c2]]);
                let m = if c1 == c2 {
                    format!("contour {a} ({at}) crosses or touches itself (its edges from points {} and {}): contours must be simple", e1 + 1, e2 + 1)
                } else {
                    format!(
                        "contours {a} and {b} ({at}) cross or touch (edges from their points {} and {}): contours of a plane must be disjoint",
                        e1 + 1,
                        e2 + 1
                    )
                };
                return Err(err(K::SelfIntersecting, m));
            }
            sections.push(s);
        }
        Ok((frame, sections))
    }
}

/// Where a section lies, for messages: `z = -95.44 mm`, or the offset
/// along an oblique normal.
fn place(frame: &StackFrame, offset: f64) -> String {
    match (0..3).find(|&d| frame.n[d] == 1.0) {
        Some(d) => format!("{} = {offset} mm", ["x", "y", "z"][d]),
        None => format!("{offset:.4} mm along the normal ({:.4}, {:.4}, {:.4})", frame.n[0], frame.n[1], frame.n[2]),
    }
}

/// Why a contour is not in a plane across `n`: tilted, or not planar.
fn off_plane(p: &[[f64; 3]], n: [f64; 3], spread: f64, tol: f64, item: usize) -> String {
    let own = DVec3::from(newell(p));
    let len = own.length();
    let c = p.iter().fold(DVec3::ZERO, |s, &q| s + DVec3::from(q)) / p.len() as f64;
    let planar = len > 0.0 && p.iter().all(|&q| ((DVec3::from(q) - c).dot(own) / len).abs() <= tol);
    if planar {
        let deg = (own.dot(DVec3::from(n)).abs() / len).min(1.0).acos().to_degrees();
        format!("contour {item} is planar but tilted by {deg:.3} degrees from the stack's planes: contours must lie in parallel planes")
    } else {
        format!("contour {item} is not planar: its points spread {spread:.4} mm along the stack normal (tolerance {tol} mm either side)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(c: [f64; 2], r: f64, z: f64) -> Vec<[f64; 3]> {
        vec![[c[0] - r, c[1] - r, z], [c[0] + r, c[1] - r, z], [c[0] + r, c[1] + r, z], [c[0] - r, c[1] + r, z]]
    }

    fn roi(contours: Vec<(&str, Vec<[f64; 3]>)>) -> Roi {
        let contours = contours.into_iter().enumerate().map(|(i, (k, p))| RoiContour { item: i + 1, kind: k.to_string(), points: p, defect: None }).collect();
        Roi { number: 7, name: "Test ROI".into(), contours }
    }

    fn stack(r: &Roi) -> Result<(StackFrame, Vec<Section>), ContourError> {
        r.stack(Path::new("t.dcm"), StackOptions::default())
    }

    fn err(r: &Roi) -> DicomError {
        match stack(r) {
            Err(ContourError::Dicom(e)) => e,
            other => panic!("expected a DICOM error, got {other:?}"),
        }
    }

    #[test]
    fn layouts_are_told_by_content() {
        let mut f = vec![0u8; 140];
        f[128..132].copy_from_slice(b"DICM");
        assert_eq!(layout(&f), Some(Layout::Preamble));
        assert_eq!(layout(b"DICM\x02\x00\x00\x00UL"), Some(Layout::Meta));
        assert_eq!(layout(b"\x08\x00\x05\x00\x0a\x00\x00\x00ISO_IR 100"), Some(Layout::Bare { explicit: false }));
        assert_eq!(layout(b"\x08\x00\x05\x00CS\x0a\x00ISO_IR 100"), Some(Layout::Bare { explicit: true }));
        assert_eq!(layout(b"pro\nsection 0 0 0 1 0 0 0 1 0\n"), None);
        assert_eq!(layout(b""), None);
        assert_eq!(layout(&[0u8; 131]), None);
    }

    /// Contours given out of order, with a hole and a closing repeat,
    /// become sections in increasing z, contours in file order per plane.
    #[test]
    fn axial_contours_are_grouped_and_ordered_by_z() {
        let mut outer = square([0.0, 0.0], 4.0, 3.0);
        outer.push(outer[0]);
        let r = roi(vec![
            (CLOSED_PLANAR, square([0.0, 0.0], 4.0, 6.0)),
            (CLOSED_PLANAR, outer),
            (CLOSED_PLANAR, square([0.0, 0.0], 1.0, 3.0)),
            (CLOSED_PLANAR, square([0.0, 0.0], 4.0, 0.0)),
        ]);
        let (f, s) = stack(&r).unwrap();
        assert_eq!(f.n, [0.0, 0.0, 1.0]);
        assert_eq!(s.iter().map(|s| s.offset).collect::<Vec<_>>(), vec![0.0, 3.0, 6.0]);
        assert_eq!(s.iter().map(|s| s.contours.iter().map(|c| c.line).collect::<Vec<_>>()).collect::<Vec<_>>(), vec![vec![4], vec![2, 3], vec![1]]);
        assert_eq!(s[1].contours[0].points.len(), 4, "closing repeat dropped");
        assert_eq!(s[1].contours[0].uv[2], [4.0, 4.0], "axis frames copy coordinates");
        assert_eq!(s[1].solid_area(), 64.0 - 4.0);
        assert_eq!(s.iter().map(|s| s.index).collect::<Vec<_>>(), vec![0, 1, 2]);
    }

    /// A sagittal stack (planes x = c) keeps exact coordinates too.
    #[test]
    fn sagittal_stacks_use_the_x_axis_frame() {
        let sq = |x: f64| vec![[x, 0.0, 0.0], [x, 2.0, 0.0], [x, 2.0, 2.0], [x, 0.0, 2.0]];
        let r = roi(vec![(CLOSED_PLANAR, sq(1.5)), (CLOSED_PLANAR, sq(-1.5))]);
        let (f, s) = stack(&r).unwrap();
        assert_eq!(f.n, [1.0, 0.0, 0.0]);
        assert_eq!(s.iter().map(|s| s.offset).collect::<Vec<_>>(), vec![-1.5, 1.5]);
        assert_eq!(s[0].contours[0].uv[2], [2.0, 2.0]);
    }

    /// Planes x + z = c: an oblique stack gets a frame around its normal.
    #[test]
    fn oblique_stacks_use_the_normal_of_the_points() {
        let tri = |c: f64| vec![[0.0, 0.0, c], [1.0, 0.0, c - 1.0], [0.0, 1.0, c]];
        let r = roi(vec![(CLOSED_PLANAR, tri(2.0)), (CLOSED_PLANAR, tri(0.0)), (CLOSED_PLANAR, tri(1.0))]);
        let (f, s) = stack(&r).unwrap();
        assert!((f.n[0] - f.n[2]).abs() < 1e-15 && f.n[0] > 0.0, "{:?}", f.n);
        assert_eq!(s.len(), 3);
        assert!(s[0].offset < s[1].offset && s[1].offset < s[2].offset);
        assert_eq!(s.iter().map(|s| s.line).collect::<Vec<_>>(), vec![2, 3, 1]);
        // Points written to 0.01 mm are still one plane.
        let r = roi(vec![(CLOSED_PLANAR, vec![[0.0, 0.0, 2.0], [1.0, 0.0, 1.005], [0.0, 1.0, 2.0]]), (CLOSED_PLANAR, tri(1.0))]);
        assert_eq!(stack(&r).unwrap().1.len(), 2);
    }

    #[test]
    fn open_and_point_contours_are_refused_naming_roi_and_contour() {
        let r = roi(vec![(CLOSED_PLANAR, square([0.0, 0.0], 1.0, 0.0)), ("POINT", vec![[0.0, 0.0, 0.0]])]);
        let e = err(&r);
        assert_eq!(e.kind, K::NotClosed);
        assert_eq!(e.to_string(), "t.dcm: ROI 7 'Test ROI': contour 2 is POINT: only CLOSED_PLANAR contours bound a solid");
        let r = roi(vec![("OPEN_PLANAR", square([0.0, 0.0], 1.0, 0.0))]);
        assert_eq!(err(&r).message, "ROI 7 'Test ROI': contour 1 is OPEN_PLANAR: only CLOSED_PLANAR contours bound a solid");
        let e = err(&roi(vec![]));
        assert_eq!((e.kind, e.message.as_str()), (K::Empty, "ROI 7 'Test ROI': has no contours: nothing to reconstruct"));
    }

    #[test]
    fn bad_geometry_gets_one_line() {
        // Tilted by 45 degrees against the others.
        let tilted = vec![[0.0, 0.0, 10.0], [1.0, 0.0, 11.0], [0.0, 1.0, 10.0]];
        let r = roi(vec![(CLOSED_PLANAR, square([0.0, 0.0], 1.0, 0.0)), (CLOSED_PLANAR, square([0.0, 0.0], 1.0, 3.0)), (CLOSED_PLANAR, tilted)]);
        let e = err(&r);
        assert_eq!(e.kind, K::NotParallel);
        assert_eq!(
            e.message,
            "ROI 7 'Test ROI': contour 3 is planar but tilted by 45.000 degrees from the stack's planes: contours must lie in parallel planes"
        );
        // Bent.
        let mut bent = square([0.0, 0.0], 1.0, 3.0);
        bent.insert(2, [1.5, 0.0, 3.5]);
        let r = roi(vec![(CLOSED_PLANAR, square([0.0, 0.0], 2.0, 0.0)), (CLOSED_PLANAR, square([0.0, 0.0], 2.0, 6.0)), (CLOSED_PLANAR, bent)]);
        let e = err(&r);
        assert!(e.message.starts_with("ROI 7 'Test ROI': contour 3 is not planar: its points spread"), "{e}");
        // Two contours of one plane that overlap.
        let r = roi(vec![(CLOSED_PLANAR, square([0.0, 0.0], 1.0, 0.0)), (CLOSED_PLANAR, square([1.0, 0.0], 1.0, 0.0))]);
        let e = err(&r);
        assert_eq!(e.kind, K::SelfIntersecting);
        assert!(e.message.starts_with("ROI 7 'Test ROI': contours 1 and 2 (z = 0 mm) cross or touch"), "{e}");
        // A bow tie.
        let r = roi(vec![(CLOSED_PLANAR, vec![[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])]);
        assert!(err(&r).message.contains("contour 1 (z = 0 mm) crosses or touches itself"), "{}", err(&r));
        // Too few points, and a defect found on read.
        let r = roi(vec![(CLOSED_PLANAR, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])]);
        assert_eq!(err(&r).message, "ROI 7 'Test ROI': contour 1 has 2 distinct points; a closed contour needs at least 3");
        let mut r = roi(vec![(CLOSED_PLANAR, square([0.0, 0.0], 1.0, 0.0))]);
        r.contours[0].defect = Some("its Number of Contour Points is 5 but its Contour Data hold 4 points".into());
        assert_eq!(err(&r).message, "ROI 7 'Test ROI': contour 1: its Number of Contour Points is 5 but its Contour Data hold 4 points");
    }

    #[test]
    fn summaries_count_planes() {
        let r = roi(vec![
            (CLOSED_PLANAR, square([0.0, 0.0], 4.0, 0.0)),
            (CLOSED_PLANAR, square([0.0, 0.0], 1.0, 0.0)),
            (CLOSED_PLANAR, square([0.0, 0.0], 4.0, 3.0)),
            ("POINT", vec![[0.0, 0.0, 9.0]]),
        ]);
        let s = r.summary(StackOptions::default());
        assert_eq!((s.contours, s.closed, s.slices, s.points), (4, 3, 2, 13));
    }
}
