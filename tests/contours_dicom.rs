//! `mint contours` on DICOM RT structure sets, as a user meets it: files
//! found by content, `--list-rois`, `--roi`, `--all-rois`, and one-line
//! errors with a non-zero exit for files that are not DICOM, not an RT
//! structure set, or cut short. The DICOM files are written here byte by
//! byte (implicit VR little endian, the encoding of the real test data), so
//! nothing from `../shared/data` is needed.

use crate::cli::{ok, p, run};

/// One implicit-VR little-endian element: tag, 4-byte length, value
/// (padded to even length with `pad`).
fn element(group: u16, elem: u16, value: &[u8], pad: u8) -> Vec<u8> {
    let mut v = value.to_vec();
    if v.len() % 2 == 1 {
        v.push(pad);
    }
    let mut out = Vec::with_capacity(8 + v.len());
    out.extend_from_slice(&group.to_le_bytes());
    out.extend_from_slice(&elem.to_le_bytes());
    out.extend_from_slice(&(v.len() as u32).to_le_bytes());
    out.extend_from_slice(&v);
    out
}

fn text(group: u16, elem: u16, s: &str) -> Vec<u8> {
    element(group, elem, s.as_bytes(), b' ')
}

/// A sequence of items, each the concatenation of its elements, all with
/// defined lengths.
fn sequence(group: u16, elem: u16, items: &[Vec<u8>]) -> Vec<u8> {
    let mut body = Vec::new();
    for it in items {
        body.extend_from_slice(&0xFFFEu16.to_le_bytes());
        body.extend_from_slice(&0xE000u16.to_le_bytes());
        body.extend_from_slice(&(it.len() as u32).to_le_bytes());
        body.extend_from_slice(it);
    }
    element(group, elem, &body, 0)
}

fn contour(kind: &str, points: &[[f64; 3]]) -> Vec<u8> {
    let data: Vec<String> = points.iter().flat_map(|q| q.iter().map(|x| x.to_string())).collect();
    [text(0x3006, 0x0042, kind), text(0x3006, 0x0046, &points.len().to_string()), text(0x3006, 0x0050, &data.join("\\"))].concat()
}

/// An RT structure set with the given Modality: ROI 1 "Box" (a 10 x 6
/// rectangle on 4 slices, 2 mm apart, given out of order) and ROI 2
/// "Iso" (one POINT). With `preamble`, a standard file: 128 bytes, DICM,
/// the file meta group (explicit VR); without, a bare data set.
fn rtstruct(modality: &str, preamble: bool) -> Vec<u8> {
    let rect = |z: f64| [[0.0, 0.0, z], [10.0, 0.0, z], [10.0, 6.0, z], [0.0, 6.0, z]];
    let rois = sequence(
        0x3006,
        0x0020,
        &[[text(0x3006, 0x0022, "1"), text(0x3006, 0x0026, "Box")].concat(), [text(0x3006, 0x0022, "2"), text(0x3006, 0x0026, "Iso")].concat()],
    );
    let boxes: Vec<Vec<u8>> = [4.0, 0.0, 6.0, 2.0].iter().map(|&z| contour("CLOSED_PLANAR", &rect(z))).collect();
    let roi_contours = sequence(
        0x3006,
        0x0039,
        &[
            [sequence(0x3006, 0x0040, &boxes), text(0x3006, 0x0084, "1")].concat(),
            [sequence(0x3006, 0x0040, &[contour("POINT", &[[5.0, 3.0, 3.0]])]), text(0x3006, 0x0084, "2")].concat(),
        ],
    );
    let data = [text(0x0008, 0x0060, modality), text(0x3006, 0x0002, "test"), rois, roi_contours].concat();
    if !preamble {
        return data;
    }
    // The file meta group, explicit VR little endian.
    let ex = |elem: u16, vr: &[u8; 2], value: &[u8]| {
        let mut v = value.to_vec();
        if v.len() % 2 == 1 {
            v.push(0);
        }
        let mut out = vec![0x02, 0x00];
        out.extend_from_slice(&elem.to_le_bytes());
        out.extend_from_slice(vr);
        if vr == b"OB" {
            out.extend_from_slice(&[0, 0]);
            out.extend_from_slice(&(v.len() as u32).to_le_bytes());
        } else {
            out.extend_from_slice(&(v.len() as u16).to_le_bytes());
        }
        out.extend_from_slice(&v);
        out
    };
    let meta = [
        ex(0x0001, b"OB", &[0, 1]),
        ex(0x0002, b"UI", b"1.2.840.10008.5.1.4.1.1.481.3"),
        ex(0x0003, b"UI", b"1.2.3.4.5.6"),
        ex(0x0010, b"UI", b"1.2.840.10008.1.2"),
        ex(0x0012, b"UI", b"1.2.3.4"),
    ]
    .concat();
    let mut out = vec![0u8; 128];
    out.extend_from_slice(b"DICM");
    out.extend_from_slice(&ex(0x0000, b"UL", &(meta.len() as u32).to_le_bytes()));
    out.extend_from_slice(&meta);
    out.extend_from_slice(&data);
    out
}

/// The error line of a failed run (exactly one line on stderr).
fn fails(args: &[&str]) -> String {
    let o = run(args);
    assert!(!o.status.success(), "mint {args:?} should fail");
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(err.lines().count(), 1, "one line expected: {err}");
    assert!(err.starts_with("mint: error: "), "{err}");
    err
}

#[test]
fn rois_are_listed_rebuilt_and_written_one_per_file() {
    let dir = tempfile::tempdir().unwrap();
    // By content: no .dcm name, with and without the preamble.
    for (name, preamble) in [("rs_with_preamble", true), ("rs_bare", false)] {
        let f = dir.path().join(name);
        std::fs::write(&f, rtstruct("RTSTRUCT", preamble)).unwrap();
        let list = ok(&["contours", p(&f), "--list-rois"]);
        assert!(list.contains("RT structure set 'test', 2 ROIs"), "{list}");
        let rows: Vec<Vec<&str>> = list.lines().skip(2).map(|l| l.split_whitespace().collect()).collect();
        assert_eq!(rows, vec![vec!["1", "Box", "4", "4", "4", "16"], vec!["2", "Iso", "1", "0", "0", "1"]]);
        // Angle: end caps half a spacing out, so the box holds 10 x 6 x 8.
        let out = dir.path().join(format!("{name}-box.ply"));
        let st = dir.path().join(format!("{name}.json"));
        ok(&["contours", p(&f), p(&out), "--roi", "box", "--method", "angle", "--caps", "--quiet", "--stats", p(&st)]);
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&st).unwrap()).unwrap();
        assert_eq!(v["input_faces_or_sections"], 4);
        assert_eq!(v["parameters"]["roi"], "Box");
        assert_eq!(v["parameters"]["extend_ends"], true);
        let (mesh, plan) = (v["volume"]["mesh"].as_f64().unwrap(), v["volume"]["planimetric"].as_f64().unwrap());
        assert!((plan - 480.0).abs() < 1e-9 && (mesh - 480.0).abs() < 1e-3, "{mesh} {plan}");
        let check = ok(&["check", p(&out)]);
        assert!(check.contains(": watertight (closed, 2-manifold, consistently oriented)"), "{check}");
    }
    // --all-rois: Box written, the POINT ROI skipped with a warning.
    let f = dir.path().join("rs.dcm");
    std::fs::write(&f, rtstruct("RTSTRUCT", true)).unwrap();
    let outdir = dir.path().join("rois");
    let o = run(&["contours", p(&f), "--all-rois", p(&outdir), "--method", "mc", "--caps"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("mint: warning: ") && err.contains("ROI 2 'Iso' has no closed contours"), "{err}");
    let files: Vec<String> = std::fs::read_dir(&outdir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(files, vec!["Box.ply".to_string()]);
    // The POINT ROI asked for by name: refused, naming ROI and contour.
    let e = fails(&["contours", p(&f), p(&dir.path().join("iso.ply")), "--roi", "Iso", "--method", "mc"]);
    assert!(e.ends_with("rs.dcm: ROI 2 'Iso': contour 1 is POINT: only CLOSED_PLANAR contours bound a solid\n"), "{e}");
    assert!(!dir.path().join("iso.ply").exists());
}

#[test]
fn bad_dicom_inputs_get_one_line_and_a_failure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.ply");
    // Not DICOM, with a .dcm name.
    let f = dir.path().join("notes.dcm");
    std::fs::write(&f, "these are notes, not a structure set\n").unwrap();
    let e = fails(&["contours", p(&f), p(&out), "--roi", "Box", "--method", "mc"]);
    assert!(e.contains("notes.dcm: not a DICOM file"), "{e}");
    // DICOM, but not an RT structure set.
    let f = dir.path().join("ct.dcm");
    std::fs::write(&f, rtstruct("CT", true)).unwrap();
    let e = fails(&["contours", p(&f), "--list-rois"]);
    assert!(e.contains("ct.dcm: not an RT structure set: its Modality is 'CT', not RTSTRUCT"), "{e}");
    // Cut short, and a length field corrupted.
    let good = rtstruct("RTSTRUCT", true);
    for (name, bytes) in [
        ("cut.dcm", good[..good.len() - 40].to_vec()),
        ("len.dcm", {
            let mut b = good.clone();
            let at = b.windows(4).position(|w| w == [0x06, 0x30, 0x50, 0x00]).unwrap();
            b[at + 4..at + 8].copy_from_slice(&0xF000_0000u32.to_le_bytes());
            b
        }),
    ] {
        let f = dir.path().join(name);
        std::fs::write(&f, bytes).unwrap();
        let e = fails(&["contours", p(&f), p(&out), "--roi", "Box", "--method", "angle", "--caps"]);
        assert!(e.contains(&format!("{name}: cannot read the DICOM data (truncated or corrupted file?)")), "{e}");
    }
    assert!(!out.exists());
    // The DICOM options on a profile, and a DICOM file without them.
    let pro = dir.path().join("a.pro");
    std::fs::write(&pro, "pro\nsection 0 0 0 1 0 0 0 1 0\nsection 0 0 1 1 0 1 0 1 1\n").unwrap();
    let e = fails(&["contours", p(&pro), p(&out), "--roi", "Box", "--method", "mc"]);
    assert!(e.contains("--roi, --all-rois and --list-rois apply to DICOM RT structure sets"), "{e}");
    let f = dir.path().join("rs.dcm");
    std::fs::write(&f, &good).unwrap();
    let e = fails(&["contours", p(&f), p(&out), "--method", "mc"]);
    assert!(e.contains("choose the ROI with --roi NAME"), "{e}");
    let e = fails(&["contours", p(&f), p(&out), "--roi", "Liver", "--method", "mc"]);
    assert!(e.contains("no ROI named 'Liver'; the ROIs are: 1 'Box', 2 'Iso'"), "{e}");
}
