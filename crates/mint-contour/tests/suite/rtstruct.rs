//! DICOM RT structure sets read directly (`mint_contour::rtstruct`): the
//! sections of the real files equal those of their text extraction, every
//! ROI of both files reconstructs closed, crossing-free and near its
//! planimetric volume by both methods, and bad files (not DICOM, not an RT
//! structure set, truncated, corrupted) give one line naming the file. The
//! real files come from `../shared/data` (skipped without it, a failure
//! under `MINT_REQUIRE_DATA=1`); the hand-built DICOM objects need nothing.
use super::util::data_dir;
use mint_contour::angle::AngleOptions;
use mint_contour::mc::McOptions;
use mint_contour::profile::{read_all, ProfileOptions, Section};
use mint_contour::rtstruct::{self, Layout, StackOptions, StructureSet};
use mint_contour::run::{self, Method, MethodStats};
use mint_contour::{ContourError, DicomErrorKind};
use mint_io::WriteOptions;
use std::path::{Path, PathBuf};

/// Never asks to stop, shows nothing.
const NEVER: &mint_core::progress::NoProgress = &mint_core::progress::NoProgress;

fn breast(data: &Path) -> PathBuf {
    data.join("rtstruct_dicompyler_breast/rtss.dcm")
}

fn phantom(data: &Path) -> PathBuf {
    data.join("rtstruct_pydicom_phantom/rtstruct.dcm")
}

/// The contours of one ROI of a `rtstruct_to_contours.py` text file as a
/// profile (ROI names there have `_` for spaces).
fn text_profile(txt: &str, roi: &str) -> String {
    let mut out = String::from("pro\n");
    let mut in_roi = false;
    let mut first_in_slice = false;
    for line in txt.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"ROI") => in_roi = w.get(2) == Some(&roi),
            Some(&"SLICE") if in_roi => first_in_slice = true,
            Some(&"CONTOUR") if in_roi => {
                out.push_str(if first_in_slice { "section\n" } else { "contour\n" });
                first_in_slice = false;
            }
            Some(x) if in_roi && (x.starts_with('-') || x.as_bytes()[0].is_ascii_digit()) => {
                out.push_str(line);
                out.push('\n');
            }
            _ => {}
        }
    }
    out
}

/// Same planes in the same order, same points in the same order.
fn assert_same_sections(name: &str, a: &[Section], b: &[Section]) {
    assert_eq!(a.len(), b.len(), "{name}: section count");
    for (s, t) in a.iter().zip(b) {
        assert_eq!(s.offset, t.offset, "{name}: section {}", s.index);
        assert_eq!(s.contours.len(), t.contours.len(), "{name}: contours of section {}", s.index);
        for (c, d) in s.contours.iter().zip(&t.contours) {
            assert_eq!(c.points, d.points, "{name}: section {} points", s.index);
            assert_eq!(c.uv, d.uv, "{name}: section {} projected points", s.index);
        }
    }
}

#[test]
fn dicom_sections_equal_the_text_extraction() {
    let Some(data) = data_dir() else { return };
    for (dcm, txt, rois) in [
        (breast(&data), "rtstruct_dicompyler_breast/rtss_contours.txt", &["BODY", "Lt Lung", "Heart", "Tumor Bed", "Borders"][..]),
        (phantom(&data), "rtstruct_pydicom_phantom/rtstruct_contours.txt", &["patient"][..]),
    ] {
        let set = StructureSet::read(&dcm).unwrap();
        let txt = std::fs::read_to_string(data.join(txt)).unwrap();
        for name in rois {
            let (frame, from_dicom) = set.find(name).unwrap().stack(&dcm, StackOptions::default()).unwrap();
            let pro = text_profile(&txt, &name.replace(' ', "_"));
            let (pframe, from_text) = read_all(pro.as_bytes(), Path::new("text.pro"), ProfileOptions::default()).unwrap();
            assert_eq!((frame.u, frame.v, frame.n), (pframe.u, pframe.v, pframe.n), "{name}");
            assert_same_sections(name, &from_dicom, &from_text);
            eprintln!("{name}: {} sections equal", from_dicom.len());
        }
    }
}

#[test]
fn rois_are_listed_with_counts() {
    let Some(data) = data_dir() else { return };
    let set = StructureSet::read(&breast(&data)).unwrap();
    let rows: Vec<(i64, String, usize, usize)> =
        set.rois.iter().map(|r| r.summary(StackOptions::default())).map(|s| (s.number, s.name, s.contours, s.slices)).collect();
    let expect = [
        (1, "BODY", 141, 98),
        (2, "Areola", 0, 0),
        (3, "Borders", 2, 2),
        (4, "Breast", 48, 47),
        (5, "Heart", 33, 33),
        (6, "Lt Lung", 165, 80),
        (7, "Nodes", 4, 4),
        (8, "Scar", 6, 6),
        (9, "Tumor Bed", 18, 18),
        (10, "Tumor Bed Block", 24, 24),
    ];
    assert_eq!(rows, expect.map(|(n, s, c, k)| (n, s.to_string(), c, k)));
    assert_eq!(set.find("Lt_Lung").unwrap().number, 6);
    assert_eq!(set.find("6").unwrap().name, "Lt Lung");
    let e = set.find("Liver").unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}: no ROI named 'Liver'; the ROIs are: 1 'BODY', 2 'Areola'", breast(&data).display())), "{e}");
    // The phantom: one closed ROI, two POINT ROIs.
    let set = StructureSet::read(&phantom(&data)).unwrap();
    let rows: Vec<(String, usize, usize)> = set.rois.iter().map(|r| r.summary(StackOptions::default())).map(|s| (s.name, s.closed, s.slices)).collect();
    assert_eq!(rows, vec![("patient".to_string(), 3, 3), ("Isocenter 1".to_string(), 0, 0), ("Isocenter 2".to_string(), 0, 0)]);
    let e = set.find("Isocenter 1").unwrap().stack(&phantom(&data), StackOptions::default()).unwrap_err().to_string();
    assert!(e.ends_with("rtstruct.dcm: ROI 2 'Isocenter 1': contour 1 is POINT: only CLOSED_PLANAR contours bound a solid"), "{e}");
}

/// One ROI rebuilt by one method with caps, checked as `mint check` does.
struct Row {
    faces: u64,
    watertight: bool,
    pairs: u64,
    mesh: f64,
    planimetric: f64,
    seconds: f64,
}

fn rebuild(dcm: &Path, frame: mint_contour::profile::StackFrame, sections: &[Section], out: &Path, method: Method) -> Row {
    let st = run::reconstruct_sections(dcm, frame, sections, out, method, WriteOptions::default(), NEVER).unwrap();
    let (mut positions, mut faces) = run::load_mesh(out).unwrap();
    mint_mesh::weld(&mut positions, &mut faces);
    let r = mint_mesh::check(&positions, &faces);
    let x = mint_mesh::selfx::self_intersections(&positions, &faces, 4);
    let v = st.volume.clone().unwrap();
    if let MethodStats::Mc(d) = &st.details {
        assert_eq!(d.non_canonical_cells, 0);
    }
    Row { faces: st.faces, watertight: r.watertight, pairs: x.pairs as u64, mesh: v.mesh, planimetric: v.planimetric, seconds: st.seconds }
}

/// Known shortfall, bounded instead of held to 3%: marching cubes puts
/// its between-section vertices where the signed distance, interpolated
/// along each grid line, changes sign. The Scar is 3 mm wide and moves 5
/// to 9 mm per slice, so a node inside one slice's contour is far from the
/// next one's and the solid ends early: -12.9% of the planimetric volume at
/// 64 cubes, -9.9% at 128, -8.4% at 512 (not a resolution effect). The
/// angle method, whose strips join the contours themselves, holds it
/// within 3%.
const KNOWN_SHORTFALL: &[(&str, &str, f64)] = &[("Scar", "mc", 0.11)];

/// Every ROI with closed contours, both methods with caps (angle with the
/// end caps half a spacing out, as `mint contours` does for RT structure
/// sets; mc at 128 cubes): watertight, no intersecting faces, volume within
/// 3% of the planimetric volume. Prints the table of docs/PERFORMANCE.md.
#[test]
fn every_roi_of_both_files_reconstructs_closed_without_crossings() {
    let Some(data) = data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    eprintln!("| file | ROI | sections | contours | method | faces | watertight | crossing pairs | mesh volume (mm³) | planimetric (mm³) | difference | stack (s) | rebuild (s) |");
    eprintln!("|---|---|--:|--:|---|--:|---|--:|--:|--:|--:|--:|--:|");
    for dcm in [breast(&data), phantom(&data)] {
        let t = std::time::Instant::now();
        let set = StructureSet::read(&dcm).unwrap();
        let read = t.elapsed().as_secs_f64();
        for roi in &set.rois {
            if !roi.has_closed_contours() {
                continue;
            }
            let t = std::time::Instant::now();
            let (frame, sections) = roi.stack(&dcm, StackOptions::default()).unwrap();
            let stack = t.elapsed().as_secs_f64();
            let contours: usize = sections.iter().map(|s| s.contours.len()).sum();
            for (mname, method) in [
                ("angle", Method::Angle(AngleOptions { caps: true, extend_ends: true, ..Default::default() })),
                ("mc", Method::Mc(McOptions { cubes: 128, caps: true, ..Default::default() })),
            ] {
                let out = dir.path().join(format!("{}-{mname}.ply", roi.number));
                let r = rebuild(&dcm, frame, &sections, &out, method);
                let diff = (r.mesh - r.planimetric) / r.planimetric;
                eprintln!(
                    "| {} | {} | {} | {contours} | {mname} | {} | {} | {} | {:.1} | {:.1} | {:+.2}% | {stack:.3} | {:.3} |",
                    dcm.file_name().unwrap().to_string_lossy(),
                    roi.name,
                    sections.len(),
                    r.faces,
                    if r.watertight { "yes" } else { "NO" },
                    r.pairs,
                    r.mesh,
                    r.planimetric,
                    100.0 * diff,
                    r.seconds
                );
                let bound = KNOWN_SHORTFALL.iter().find(|k| k.0 == roi.name && k.1 == mname).map_or(0.03, |k| k.2);
                if !r.watertight || r.pairs != 0 || diff.abs() > bound {
                    failures.push(format!(
                        "{} {mname}: watertight {}, {} crossing pairs, volume difference {:+.2}%",
                        roi.label(),
                        r.watertight,
                        r.pairs,
                        100.0 * diff
                    ));
                }
            }
        }
        eprintln!("{}: read in {read:.3}s", dcm.display());
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

fn dicom_err(r: Result<StructureSet, ContourError>) -> mint_contour::DicomError {
    match r {
        Err(ContourError::Dicom(e)) => e,
        other => panic!("expected a DICOM error, got {other:?}"),
    }
}

#[test]
fn bad_files_get_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    // Not DICOM at all, with a .dcm name.
    let p = dir.path().join("notes.dcm");
    std::fs::write(&p, "pro\nsection 0 0 0 1 0 0 0 1 0\n").unwrap();
    assert_eq!(rtstruct::sniff(&p).unwrap(), None);
    let e = dicom_err(StructureSet::read(&p));
    assert_eq!(e.kind, DicomErrorKind::NotDicom);
    assert_eq!(
        e.to_string(),
        format!("{}: not a DICOM file: no 'DICM' marker after a 128-byte preamble or at the start, and no data set at the start", p.display())
    );
    // Empty.
    std::fs::write(&p, "").unwrap();
    assert_eq!(dicom_err(StructureSet::read(&p)).kind, DicomErrorKind::NotDicom);
    // A preamble and DICM, then nothing.
    let mut b = vec![0u8; 128];
    b.extend_from_slice(b"DICM");
    std::fs::write(&p, &b).unwrap();
    let e = dicom_err(StructureSet::read(&p));
    assert_eq!(e.kind, DicomErrorKind::Corrupt);
    assert!(!e.to_string().contains('\n'));
}

/// A CT-like DICOM object built by hand: readable, not an RT structure set.
#[test]
fn a_non_rt_dicom_file_is_refused() {
    use dicom_core::{DataElement, PrimitiveValue, Tag, VR};
    use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
    let dir = tempfile::tempdir().unwrap();
    let obj = InMemDicomObject::from_element_iter([
        DataElement::new(Tag(0x0008, 0x0016), VR::UI, PrimitiveValue::from("1.2.840.10008.5.1.4.1.1.2")),
        DataElement::new(Tag(0x0008, 0x0018), VR::UI, PrimitiveValue::from("1.2.3.4.5")),
        DataElement::new(Tag(0x0008, 0x0060), VR::CS, PrimitiveValue::from("CT")),
    ]);
    let file = obj
        .with_meta(
            FileMetaTableBuilder::new()
                .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.2")
                .media_storage_sop_instance_uid("1.2.3.4.5")
                .transfer_syntax("1.2.840.10008.1.2.1"),
        )
        .unwrap();
    // Named without .dcm: found by content.
    let p = dir.path().join("slice0001");
    file.write_to_file(&p).unwrap();
    assert_eq!(rtstruct::sniff(&p).unwrap(), Some(Layout::Preamble));
    let e = dicom_err(StructureSet::read(&p));
    assert_eq!(e.kind, DicomErrorKind::NotRtStruct);
    assert_eq!(e.to_string(), format!("{}: not an RT structure set: its Modality is 'CT', not RTSTRUCT", p.display()));
    // No Modality and no ROI Contour Sequence.
    let obj = InMemDicomObject::from_element_iter([DataElement::new(Tag(0x0010, 0x0010), VR::PN, PrimitiveValue::from("Test^Patient"))]);
    let file = obj
        .with_meta(
            FileMetaTableBuilder::new().media_storage_sop_class_uid("1.2.3").media_storage_sop_instance_uid("1.2.3.4").transfer_syntax("1.2.840.10008.1.2"),
        )
        .unwrap();
    file.write_to_file(&p).unwrap();
    let e = dicom_err(StructureSet::read(&p));
    assert_eq!(e.to_string(), format!("{}: not an RT structure set: it has no ROI Contour Sequence (3006,0039)", p.display()));
}

/// An RT structure set written by dicom-rs in explicit VR little endian
/// (the real files are implicit VR), nested sequences and all, reads back:
/// the length check walks explicit VR and `SQ` elements too.
#[test]
fn an_explicit_vr_structure_set_written_by_dicom_rs_reads_back() {
    use dicom_core::value::DataSetSequence;
    use dicom_core::{DataElement, PrimitiveValue, Tag, VR};
    use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
    let el = |g: u16, e: u16, vr: VR, v: &str| DataElement::new(Tag(g, e), vr, PrimitiveValue::from(v));
    let seq = |g: u16, e: u16, items: Vec<InMemDicomObject>| DataElement::new(Tag(g, e), VR::SQ, DataSetSequence::from(items));
    let contour = |z: f64| {
        let pts = [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]].map(|q| format!("{}\\{}\\{z}", q[0], q[1])).join("\\");
        InMemDicomObject::from_element_iter([el(0x3006, 0x0042, VR::CS, "CLOSED_PLANAR"), el(0x3006, 0x0046, VR::IS, "4"), el(0x3006, 0x0050, VR::DS, &pts)])
    };
    let obj = InMemDicomObject::from_element_iter([
        el(0x0008, 0x0016, VR::UI, "1.2.840.10008.5.1.4.1.1.481.3"),
        el(0x0008, 0x0018, VR::UI, "1.2.3.4.5"),
        el(0x0008, 0x0060, VR::CS, "RTSTRUCT"),
        seq(0x3006, 0x0020, vec![InMemDicomObject::from_element_iter([el(0x3006, 0x0022, VR::IS, "3"), el(0x3006, 0x0026, VR::LO, "Block")])]),
        seq(
            0x3006,
            0x0039,
            vec![InMemDicomObject::from_element_iter([seq(0x3006, 0x0040, vec![contour(2.5), contour(0.0), contour(5.0)]), el(0x3006, 0x0084, VR::IS, "3")])],
        ),
    ]);
    let file = obj
        .with_meta(
            FileMetaTableBuilder::new()
                .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.481.3")
                .media_storage_sop_instance_uid("1.2.3.4.5")
                .transfer_syntax("1.2.840.10008.1.2.1"),
        )
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("block.dcm");
    file.write_to_file(&p).unwrap();
    let set = StructureSet::read(&p).unwrap();
    assert_eq!(set.rois.len(), 1);
    let (frame, s) = set.find("Block").unwrap().stack(&p, StackOptions::default()).unwrap();
    assert_eq!(s.iter().map(|s| s.offset).collect::<Vec<_>>(), vec![0.0, 2.5, 5.0]);
    assert_eq!(s[1].contours[0].points[2], [4.0, 3.0, 2.5]);
    let out = dir.path().join("block.ply");
    let r = rebuild(&p, frame, &s, &out, Method::Angle(AngleOptions { caps: true, extend_ends: true, ..Default::default() }));
    assert!(r.watertight && r.pairs == 0);
    assert!((r.planimetric - 12.0 * 7.5).abs() < 1e-9 && (r.mesh - r.planimetric).abs() < 1e-3, "{} {}", r.mesh, r.planimetric);
}

#[test]
fn real_files_edited_into_bad_ones_are_refused_without_panics() {
    let Some(data) = data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read(breast(&data)).unwrap();
    let p = dir.path().join("bad.dcm");
    // The Modality edited (same length: the file stays well formed).
    let at = good.windows(8).position(|w| w == b"RTSTRUCT").unwrap();
    let mut b = good.clone();
    b[at..at + 8].copy_from_slice(b"MR      ");
    std::fs::write(&p, &b).unwrap();
    let e = dicom_err(StructureSet::read(&p));
    assert_eq!(e.to_string(), format!("{}: not an RT structure set: its Modality is 'MR', not RTSTRUCT", p.display()));
    // Truncated at several places.
    for cut in [140, 200, 1000, good.len() / 2, good.len() - 7] {
        std::fs::write(&p, &good[..cut]).unwrap();
        let e = dicom_err(StructureSet::read(&p));
        assert_eq!(e.kind, DicomErrorKind::Corrupt, "cut at {cut}: {e}");
        assert!(e.to_string().starts_with(&p.display().to_string()) && !e.to_string().contains('\n'), "{e}");
    }
    // A length field made huge, small, or an item's overrunning its
    // sequence: refused before parsing, at once (the parser would zero-fill
    // a buffer of the claimed length first: 3.9 GB for the first one).
    let tag = good[good.len() / 2..].windows(4).position(|w| w == [0x06, 0x30, 0x50, 0x00]).unwrap() + good.len() / 2;
    let item = good[good.len() / 2..].windows(4).position(|w| w == [0xFE, 0xFF, 0x00, 0xE0]).unwrap() + good.len() / 2;
    for (at, len) in [(tag + 4, 0xF000_0000u32), (tag + 4, 10_000), (item + 4, 0x7F00_0000)] {
        let mut b = good.clone();
        b[at..at + 4].copy_from_slice(&len.to_le_bytes());
        std::fs::write(&p, &b).unwrap();
        let t = std::time::Instant::now();
        let e = dicom_err(StructureSet::read(&p));
        eprintln!("length {len} at byte {at}: {e} ({:.3}s)", t.elapsed().as_secs_f64());
        assert_eq!(e.kind, DicomErrorKind::Corrupt, "{e}");
        assert!(e.message.contains("claims") || e.message.contains("overruns"), "{e}");
    }
    // Bytes flipped in the middle: an error naming the file or, where the
    // flip hits only coordinates, a file that still reads; never a panic.
    for at in [good.len() / 3, good.len() / 2, 2 * good.len() / 3] {
        let mut b = good.clone();
        for x in &mut b[at..at + 64] {
            *x = !*x;
        }
        std::fs::write(&p, &b).unwrap();
        match StructureSet::read(&p) {
            Ok(set) => {
                for roi in &set.rois {
                    if let Err(e) = roi.stack(&p, StackOptions::default()) {
                        let m = e.to_string();
                        assert!(m.starts_with(&p.display().to_string()) && !m.contains('\n'), "{m}");
                    }
                }
            }
            Err(e) => {
                let m = e.to_string();
                assert!(m.starts_with(&p.display().to_string()) && !m.contains('\n'), "{m}");
                eprintln!("flipped at {at}: {m}");
            }
        }
    }
}
