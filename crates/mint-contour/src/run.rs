//! File-to-file drivers of the contour commands, the only part of this crate
//! that touches files besides the DICOM reader ([`crate::rtstruct`]):
//! [`reconstruct_file`] (`mint contours` on a profile) and
//! [`reconstruct_sections`] (on an ROI of an RT structure set),
//! [`slice_file`] (`mint slice`) and [`optimize_file`] (`mint optimize`).
//! Each returns a [`RunStats`] (time, counts, the parameters used and the
//! method's own counters), which the CLI writes as the `--stats` JSON file.
//!
//! Output goes through [`SpillSink`]: vertices stream into a
//! [`mint_io::MeshWriter`] (a temporary file beside the target), faces into
//! an anonymous spill file, appended after the last vertex at
//! [`SpillSink::finish`], which renames the output into place. An error or
//! a cancellation drops both, so no partial output is ever left.
//!
//! Memory: reconstruction streams sections (the marching-cubes method reads
//! the profile twice: once for the bounding box and the section offsets,
//! once to reconstruct); slicing streams the mesh's faces and holds the
//! segments of all planes; the optimizer holds the whole mesh.

use crate::angle::{AngleOptions, AngleReconstructor, AngleStats};
use crate::error::ContourError;
use crate::mc::{McOptions, McReconstructor, McStats, StackSummary};
use crate::optimize::{optimize, OptimizeStats};
use crate::profile::{Planimeter, ProfileOptions, ProfileReader, ProfileWriter, Section, StackFrame};
use crate::slice::{SliceStats, Slicer};
use mint_core::progress::Progress;
use mint_core::{MeshSink, SinkError};
use mint_io::{AtomicFile, Format, MeshReader, MeshWriter, ReadOptions, TriangleChunk, WriteOptions};
use serde::Serialize;
use std::io::{BufReader, BufWriter, Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A [`MeshSink`] that accepts faces before later vertices: vertices go to
/// the output file, faces to a spill file until [`finish`](SpillSink::finish).
pub struct SpillSink {
    writer: MeshWriter,
    faces: BufWriter<std::fs::File>,
    spill_name: PathBuf,
    vertices: u64,
    face_count: u64,
}

impl SpillSink {
    /// Starts writing `output` (format by extension); the face spill file
    /// lives, nameless, in the output's directory.
    pub fn create(output: &Path, write: WriteOptions) -> Result<SpillSink, ContourError> {
        let format = Format::from_path(output)?;
        let writer = MeshWriter::create(output, format, write)?;
        let dir = output.parent().filter(|p| !p.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
        let spill_name = dir.join("(face spill)");
        let file = tempfile::tempfile_in(&dir).map_err(|e| ContourError::io(&spill_name, "cannot create the face spill file", e))?;
        Ok(SpillSink { writer, faces: BufWriter::with_capacity(1 << 20, file), spill_name, vertices: 0, face_count: 0 })
    }

    /// Appends the faces after the vertices and renames the output into place.
    pub fn finish(self) -> Result<mint_io::WriteSummary, ContourError> {
        let SpillSink { mut writer, faces, spill_name, face_count, .. } = self;
        let mut file = faces.into_inner().map_err(|e| ContourError::io(&spill_name, "cannot write the face spill file", e.into_error()))?;
        file.rewind().map_err(|e| ContourError::io(&spill_name, "cannot rewind the face spill file", e))?;
        let mut rd = BufReader::with_capacity(1 << 20, file);
        let mut b = [0u8; 12];
        for _ in 0..face_count {
            rd.read_exact(&mut b).map_err(|e| ContourError::io(&spill_name, "cannot read the face spill file", e))?;
            writer.write_face([0, 1, 2].map(|k| u32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap())))?;
        }
        Ok(writer.finish()?)
    }
}

impl MeshSink for SpillSink {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), SinkError> {
        self.vertices += 1;
        Ok(self.writer.write_vertex(p)?)
    }
    fn face(&mut self, f: [u32; 3]) -> Result<(), SinkError> {
        debug_assert!(f.iter().all(|&i| (i as u64) < self.vertices), "a face before its vertices");
        let mut b = [0u8; 12];
        for k in 0..3 {
            b[4 * k..4 * k + 4].copy_from_slice(&f[k].to_le_bytes());
        }
        self.face_count += 1;
        Ok(self.faces.write_all(&b)?)
    }
}

/// The reconstruction method of `mint contours`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Cross-section triangulation with the angle criterion.
    Angle(AngleOptions),
    /// Marching cubes on the contours.
    Mc(McOptions),
}

/// Method-specific counters.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum MethodStats {
    Angle(AngleStats),
    Mc(McStats),
    Slice(SliceStats),
    Optimize(OptimizeStats),
}

/// The status file of a run (`--stats FILE.json`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RunStats {
    /// `contours`, `slice` or `optimize`.
    pub command: String,
    pub input: String,
    pub output: String,
    /// The parameters used, defaults included.
    pub parameters: std::collections::BTreeMap<String, Value>,
    pub seconds: f64,
    /// Output size (for `slice`: sections written and contour vertices).
    pub vertices: u64,
    pub faces: u64,
    /// Input size: contour vertices and sections, or mesh vertices and faces.
    pub input_vertices: u64,
    pub input_faces_or_sections: u64,
    /// What the method counted.
    pub details: MethodStats,
    /// `contours` only: the planimetric and the mesh volume.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub volume: Option<VolumeReport>,
}

/// The volume of a reconstruction two ways (`mint contours`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct VolumeReport {
    /// The planimetric volume of the input stack
    /// ([`Planimeter`](crate::profile::Planimeter)): contour areas, holes
    /// subtracted, times the section spacing.
    pub planimetric: f64,
    /// The signed volume enclosed by the output mesh as written (f32
    /// coordinates unless `--double`); meaningful when it is closed.
    pub mesh: f64,
    /// `(mesh - planimetric) / planimetric`, or `None` when the
    /// planimetric volume is 0.
    pub relative_difference: Option<f64>,
}

/// The signed volume of the mesh file `path` (divergence theorem, about
/// its first vertex), streamed: faces in chunks, positions from the file.
pub fn mesh_volume(path: &Path) -> Result<f64, ContourError> {
    let mut reader = MeshReader::open(path, ReadOptions::default())?;
    let mut chunk = TriangleChunk::new();
    let mut origin: Option<[f64; 3]> = None;
    let mut six = 0.0;
    while reader.next_chunk(&mut chunk)? {
        for t in &chunk.positions {
            let o = *origin.get_or_insert(t[0]);
            let [a, b, c] = t.map(|p| [p[0] - o[0], p[1] - o[1], p[2] - o[2]]);
            six += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
        }
    }
    Ok(six / 6.0)
}

/// A parameter value in [`RunStats::parameters`].
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum Value {
    Bool(bool),
    Int(u64),
    Float(f64),
    Text(String),
}

fn params(list: &[(&str, Value)]) -> std::collections::BTreeMap<String, Value> {
    list.iter().map(|(k, v)| (k.to_string(), v.clone())).collect()
}

fn open_profile(path: &Path, opts: ProfileOptions) -> Result<ProfileReader<BufReader<std::fs::File>>, ContourError> {
    let f = std::fs::File::open(path).map_err(|e| ContourError::io(path, "cannot open for reading", e))?;
    Ok(ProfileReader::new(BufReader::with_capacity(1 << 20, f), path, opts))
}

/// Validated sections in stack order, opened once per pass of a
/// reconstruction: a profile streamed from its file, or sections already
/// in memory (an ROI of an RT structure set).
trait SectionSource {
    fn next_section(&mut self) -> Result<Option<Section>, ContourError>;
    /// The stack frame, once the first section is out.
    fn frame(&self) -> Option<StackFrame>;
    /// Contour vertices returned so far.
    fn vertices(&self) -> u64;
}

impl<R: std::io::BufRead> SectionSource for ProfileReader<R> {
    fn next_section(&mut self) -> Result<Option<Section>, ContourError> {
        ProfileReader::next_section(self)
    }
    fn frame(&self) -> Option<StackFrame> {
        ProfileReader::frame(self)
    }
    fn vertices(&self) -> u64 {
        self.stats().vertices
    }
}

struct InMemory<'a> {
    frame: StackFrame,
    rest: std::slice::Iter<'a, Section>,
    vertices: u64,
}

impl SectionSource for InMemory<'_> {
    fn next_section(&mut self) -> Result<Option<Section>, ContourError> {
        let s = self.rest.next().cloned();
        self.vertices += s.as_ref().map_or(0, |s| s.vertex_count() as u64);
        Ok(s)
    }
    fn frame(&self) -> Option<StackFrame> {
        Some(self.frame)
    }
    fn vertices(&self) -> u64 {
        self.vertices
    }
}

type Opener<'a> = dyn Fn() -> Result<Box<dyn SectionSource + 'a>, ContourError> + 'a;

/// `mint contours`: reconstructs the profile `input` into the mesh `output`.
/// Progress is reported per section (phases [`crate::phases::SECTIONS`] and
/// [`crate::phases::CONTOURS`]) and cancellation polled as often.
pub fn reconstruct_file(input: &Path, output: &Path, method: Method, write: WriteOptions, progress: &dyn Progress) -> Result<RunStats, ContourError> {
    let open = matches!(method, Method::Angle(AngleOptions { open: true, .. }));
    let popts = ProfileOptions { check_intersections: !open, ..ProfileOptions::default() };
    let opener = || -> Result<Box<dyn SectionSource>, ContourError> { Ok(Box::new(open_profile(input, popts)?)) };
    reconstruct(input, &opener, output, method, write, progress)
}

/// `mint contours` on sections already read and validated (an ROI of an
/// RT structure set, [`crate::rtstruct::Roi::stack`]); `input` names them
/// in the stats. Otherwise as [`reconstruct_file`].
pub fn reconstruct_sections(
    input: &Path,
    frame: StackFrame,
    sections: &[Section],
    output: &Path,
    method: Method,
    write: WriteOptions,
    progress: &dyn Progress,
) -> Result<RunStats, ContourError> {
    if sections.is_empty() {
        return Err(ContourError::input(input, "no sections to reconstruct"));
    }
    let opener = || -> Result<Box<dyn SectionSource + '_>, ContourError> { Ok(Box::new(InMemory { frame, rest: sections.iter(), vertices: 0 })) };
    reconstruct(input, &opener, output, method, write, progress)
}

fn reconstruct(input: &Path, sources: &Opener<'_>, output: &Path, method: Method, write: WriteOptions, progress: &dyn Progress) -> Result<RunStats, ContourError> {
    let t = Instant::now();
    // Refuse an unknown output format before reading anything.
    Format::from_extension(output).ok_or_else(|| ContourError::input(output, "unknown output format: use .ply, .obj, .stl, .off, .mesh, .raw, .wrl or .3ds"))?;
    let open = matches!(method, Method::Angle(AngleOptions { open: true, .. }));
    let check = || {
        progress.advance(1);
        if progress.cancelled() {
            Err(ContourError::Cancelled)
        } else {
            Ok(())
        }
    };
    let mut planimeter = Planimeter::default();
    let (details, sections, in_vertices, parameters) = match method {
        Method::Mc(o) => {
            // Pass 1: bounding box and offsets (validates the whole file first).
            let mut r = sources()?;
            let mut summary = None;
            progress.start(crate::phases::SECTIONS, 0);
            while let Some(s) = r.next_section()? {
                let sm = summary.get_or_insert_with(|| StackSummary::new(r.frame().unwrap()));
                sm.add(&s);
                planimeter.add(&s);
                check()?;
            }
            progress.finish();
            let summary = summary.expect("a valid profile has a section");
            // Pass 2: reconstruct while streaming.
            let mut sink = SpillSink::create(output, write)?;
            let mut mc = McReconstructor::new(&summary, o, input)?;
            let mut r = sources()?;
            progress.start(crate::phases::CONTOURS, summary.offsets.len() as u64);
            while let Some(s) = r.next_section()? {
                mc.push(&s, &mut sink)?;
                check()?;
            }
            let st = mc.finish(&mut sink)?;
            progress.finish();
            sink.finish()?;
            let p = params(&[("method", Value::Text("mc".into())), ("cubes", Value::Int(o.cubes as u64)), ("caps", Value::Bool(o.caps))]);
            (MethodStats::Mc(st), summary.offsets.len() as u64, summary.vertices, p)
        }
        Method::Angle(o) => {
            let mut sink = SpillSink::create(output, write)?;
            let mut a = AngleReconstructor::new(o);
            let mut r = sources()?;
            let mut n = 0u64;
            // extend_ends: the first section waits for the second (the
            // first spacing); the last one is known at the end.
            let extend = o.extend_ends && o.caps && !o.open;
            let mut first: Option<Section> = None;
            let (mut last, mut prev_offset, mut last_gap) = (None::<Section>, 0.0, 0.0);
            progress.start(crate::phases::CONTOURS, 0);
            while let Some(s) = r.next_section()? {
                if !o.open {
                    planimeter.add(&s);
                }
                n += 1;
                if !extend {
                    a.push(&s, &mut sink)?;
                } else if n == 1 {
                    prev_offset = s.offset;
                    first = Some(s);
                } else {
                    if let Some(f) = first.take() {
                        let frame = r.frame().expect("a frame after the first section");
                        a.push(&f.moved(&frame, f.offset - 0.5 * (s.offset - f.offset)), &mut sink)?;
                        a.push(&f, &mut sink)?;
                    }
                    a.push(&s, &mut sink)?;
                    last_gap = s.offset - prev_offset;
                    prev_offset = s.offset;
                    last = Some(s);
                }
                check()?;
            }
            if let Some(f) = first.take() {
                // A one-section stack: no spacing to extend by.
                a.push(&f, &mut sink)?;
            }
            if let Some(l) = &last {
                let frame = r.frame().expect("a frame after the first section");
                a.push(&l.moved(&frame, l.offset + 0.5 * last_gap), &mut sink)?;
            }
            let st = a.finish(&mut sink)?;
            progress.finish();
            sink.finish()?;
            let p = params(&[
                ("method", Value::Text("angle".into())),
                ("threshold", Value::Float(o.threshold)),
                ("open", Value::Bool(o.open)),
                ("caps", Value::Bool(o.caps)),
                ("extend_ends", Value::Bool(o.extend_ends)),
            ]);
            (MethodStats::Angle(st), n, r.vertices(), p)
        }
    };
    let (vertices, faces) = match &details {
        MethodStats::Mc(s) => (s.vertices, s.faces),
        MethodStats::Angle(s) => (s.vertices, s.faces),
        _ => unreachable!(),
    };
    // Open polylines bound no area: no volume to compare.
    let volume = if open {
        None
    } else {
        let (planimetric, mesh) = (planimeter.volume(), mesh_volume(output)?);
        let relative_difference = (planimetric != 0.0).then(|| (mesh - planimetric) / planimetric);
        Some(VolumeReport { planimetric, mesh, relative_difference })
    };
    Ok(RunStats {
        command: "contours".into(),
        input: input.display().to_string(),
        output: output.display().to_string(),
        parameters,
        seconds: t.elapsed().as_secs_f64(),
        vertices,
        faces,
        input_vertices: in_vertices,
        input_faces_or_sections: sections,
        details,
        volume,
    })
}

/// `mint slice`: cuts the mesh `input` by `sections` planes across `axis`
/// (0, 1, 2 for x, y, z) into the profile `output`. Progress is reported
/// in bytes of the input ([`crate::phases::SLICE`]), cancellation polled per chunk
/// of faces.
pub fn slice_file(input: &Path, output: &Path, sections: u32, axis: usize, progress: &dyn Progress) -> Result<RunStats, ContourError> {
    let t = Instant::now();
    if sections == 0 {
        return Err(ContourError::input(output, "--sections must be at least 1"));
    }
    let mut reader = MeshReader::open(input, ReadOptions::default())?;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..reader.vertex_count() {
        let c = reader.vertex(i)[axis];
        if c.is_finite() {
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    if !(lo < hi) {
        return Err(ContourError::input(input, "the mesh has no extent along the slicing axis"));
    }
    let mut slicer = Slicer::new(axis, lo, hi, sections);
    let mut chunk = TriangleChunk::new();
    let mut faces = 0u64;
    progress.start(crate::phases::SLICE, reader.bytes_total());
    let mut reported = reader.bytes_done();
    while reader.next_chunk(&mut chunk)? {
        for (ids, p) in chunk.indices.iter().zip(&chunk.positions) {
            slicer.add(*ids, *p);
        }
        faces += chunk.len() as u64;
        progress.advance(reader.bytes_done() - reported);
        reported = reader.bytes_done();
        if progress.cancelled() {
            return Err(ContourError::Cancelled);
        }
    }
    progress.finish();
    let mut st = SliceStats::default();
    let levels = slicer.finish(&mut st);
    if levels.is_empty() {
        return Err(ContourError::input(input, "no plane met the mesh: nothing to write"));
    }
    let file = AtomicFile::create(output)?;
    let name = ["x", "y", "z"][axis];
    let comments = vec![
        format!("sliced from {} by mint: {} planes along {name} from {lo} to {hi}", input.display(), sections),
        format!("{} sections kept, {} open chains closed, {} contours dropped", st.sections, st.chains_closed, st.contours_dropped),
    ];
    let io = |e| ContourError::io(output, "cannot write", e);
    let mut w = ProfileWriter::new(BufWriter::with_capacity(1 << 20, file), &comments).map_err(io)?;
    for (_, contours) in &levels {
        w.section(contours).map_err(io)?;
    }
    let file = w.finish().map_err(io)?.into_inner().map_err(|e| io(e.into_error()))?;
    file.commit()?;
    Ok(RunStats {
        command: "slice".into(),
        input: input.display().to_string(),
        output: output.display().to_string(),
        parameters: params(&[("sections", Value::Int(sections as u64)), ("axis", Value::Text(name.into()))]),
        seconds: t.elapsed().as_secs_f64(),
        vertices: st.vertices,
        faces: 0,
        input_vertices: reader.vertex_count() as u64,
        input_faces_or_sections: faces,
        details: MethodStats::Slice(st),
        volume: None,
    })
}

/// Reads a whole mesh: positions and faces (`mint_io::read_mesh`).
pub fn load_mesh(path: &Path) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>), ContourError> {
    Ok(mint_io::read_mesh(path)?)
}

/// `mint optimize`: the normal optimizer from `input` to `output`.
pub fn optimize_file(input: &Path, output: &Path, angle_deg: f64, write: WriteOptions) -> Result<RunStats, ContourError> {
    let t = Instant::now();
    if !(0.0..=180.0).contains(&angle_deg) {
        return Err(ContourError::input(input, format!("--angle {angle_deg} is not between 0 and 180 degrees")));
    }
    let format = Format::from_path(output)?;
    let (positions, faces) = load_mesh(input)?;
    let (mesh, st) = optimize(&positions, &faces, angle_deg);
    let mut w = MeshWriter::create(output, format, write)?;
    for p in &mesh.positions {
        w.write_vertex(*p)?;
    }
    for f in &mesh.faces {
        w.write_face(*f)?;
    }
    w.finish()?;
    Ok(RunStats {
        command: "optimize".into(),
        input: input.display().to_string(),
        output: output.display().to_string(),
        parameters: params(&[("angle", Value::Float(angle_deg))]),
        seconds: t.elapsed().as_secs_f64(),
        vertices: mesh.positions.len() as u64,
        faces: mesh.faces.len() as u64,
        input_vertices: positions.len() as u64,
        input_faces_or_sections: faces.len() as u64,
        details: MethodStats::Optimize(st),
        volume: None,
    })
}
