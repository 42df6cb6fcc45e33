//! Scan sets: which scans make a model and where each one sits. A
//! [`ScanSet`] is a list of [`ScanEntry`] (the file name as written, its
//! resolved path, and its pose as a [`Rigid`] from the scan's own frame to
//! the world) plus whatever else the file said, kept so it can be written
//! back. [`ScanSet::read`] parses either convention by extension;
//! [`ScanSet::write`] writes either one atomically (temporary file beside
//! the target, renamed at the end).
//!
//! Conventions:
//! - **Stanford `.conf`** (the Stanford 3D Scanning Repository, e.g.
//!   `bun.conf`): one record per line, `camera tx ty tz qx qy qz qw` (the
//!   viewer, kept as is), `bmesh FILE tx ty tz qx qy qz qw` (a scan),
//!   `mesh NAME ...` (a reference without a file, kept as is). The pose
//!   means `p_world = R(q)ᵀ·p + t` with `R(q)` the usual rotation matrix of
//!   the unit quaternion written `x y z w`: rotate by the conjugate, then
//!   translate. This was verified numerically on the bunny and dragon sets
//!   (every other reading leaves errors of 15–50 mm; see
//!   `../shared/data/PROVENANCE.md`).
//! - **MeshLab `.aln`**: the number of meshes, then per mesh its file name,
//!   a `#` comment line and a 4×4 row-major matrix `M` with
//!   `p_world = M·p`; a final `0` line.
//!
//! Paths in the file are relative to the set file's directory. Blank lines
//! and lines starting with `#` are ignored in `.conf` files, except one:
//!
//! **Flagged scans.** `mint align` keeps a scan it could not register in the
//! set, at its initial pose, with the reason ([`ScanEntry::failed`]): in a
//! `.conf` as a comment line `# mint: failed: REASON` right before the
//! scan's `bmesh` record, in an `.aln` as the scan's `#` comment line
//! (`# mint: failed: REASON`). Other programs read both as comments; mint
//! reads the flag back, and `mint zipper` skips flagged scans unless told
//! otherwise.

use crate::error::RangeError;
use crate::geom::Rigid;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Which convention a set file follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SetFormat {
    /// Stanford `.conf` (`bmesh FILE t q`, `p_world = R(q)ᵀp + t`).
    Conf,
    /// MeshLab `.aln` (4×4 matrix, `p_world = M·p`).
    Aln,
}

impl SetFormat {
    /// By extension: `.aln` is MeshLab's, anything else Stanford's.
    pub fn from_path(path: &Path) -> SetFormat {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) {
            Some(e) if e == "aln" => SetFormat::Aln,
            _ => SetFormat::Conf,
        }
    }
}

/// One scan of a set.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanEntry {
    /// The name as written in the set file.
    pub file: String,
    /// `file` resolved against the set file's directory.
    pub path: PathBuf,
    /// Scan frame → world.
    pub pose: Rigid,
    /// 1-based line of the entry in the set file (0 if not read from one).
    pub line: usize,
    /// `Some(reason)`: `mint align` could not register this scan; its pose
    /// is the one it started from (see the module docs).
    pub failed: Option<String>,
}

/// The comment that flags a scan (see the module docs).
const FAILED: &str = "# mint: failed:";

/// The reason of a flag comment line, if `line` is one.
fn flag_of(line: &str) -> Option<String> {
    line.trim().strip_prefix(FAILED).map(|r| r.trim().to_string())
}

/// The flag comment for `reason`, on one line.
fn flag_line(reason: &str) -> String {
    let one: String = reason.chars().map(|c| if c.is_control() { ' ' } else { c }).collect();
    format!("{FAILED} {}", one.trim())
}

/// A scan set; see the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanSet {
    /// The scans, in file order.
    pub entries: Vec<ScanEntry>,
    /// Other `.conf` records (`camera`, `mesh`), written back verbatim
    /// before the scans.
    pub other_lines: Vec<String>,
    /// The directory paths are relative to.
    pub dir: PathBuf,
}

/// The pose of a `.conf` record: `p_world = R(q)ᵀ·p + t`.
pub fn pose_from_conf(t: [f64; 3], q: [f64; 4]) -> Rigid {
    let r = Rigid::from_quat(q, [0.0; 3]);
    Rigid { r: crate::geom::transpose(r.r), t }
}

/// The `(t, q)` of a `.conf` record for `pose` (inverse of [`pose_from_conf`]).
pub fn pose_to_conf(pose: &Rigid) -> ([f64; 3], [f64; 4]) {
    let rt = Rigid { r: crate::geom::transpose(pose.r), t: [0.0; 3] };
    (pose.t, rt.quat())
}

fn numbers(path: &Path, line: usize, toks: &[&str], what: &str) -> Result<Vec<f64>, RangeError> {
    toks.iter()
        .map(|t| match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(RangeError::syntax(path, line, format!("{what}: '{t}' is not a finite number"))),
        })
        .collect()
}

impl ScanSet {
    /// An empty set whose paths are relative to `dir`.
    pub fn new(dir: &Path) -> ScanSet {
        ScanSet { entries: Vec::new(), other_lines: Vec::new(), dir: dir.to_path_buf() }
    }

    /// Reads a `.conf` or `.aln` file (by extension). Errors name the file
    /// and line: a record with the wrong number of fields, a number that
    /// does not parse, a quaternion far from unit length (|q| outside
    /// [0.99, 1.01]), a matrix that is not a rigid motion, or a set with no
    /// scans. Scan files are not opened here.
    pub fn read(path: &Path) -> Result<ScanSet, RangeError> {
        let text = std::fs::read_to_string(path).map_err(|e| RangeError::File { path: path.to_path_buf(), what: "cannot read the scan set", source: e })?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let set = match SetFormat::from_path(path) {
            SetFormat::Conf => Self::parse_conf(path, &text, &dir)?,
            SetFormat::Aln => Self::parse_aln(path, &text, &dir)?,
        };
        if set.entries.is_empty() {
            return Err(RangeError::syntax(path, text.lines().count().max(1), "the set lists no scans"));
        }
        Ok(set)
    }

    fn parse_conf(path: &Path, text: &str, dir: &Path) -> Result<ScanSet, RangeError> {
        let mut set = ScanSet::new(dir);
        // A flag comment applies to the record right after it.
        let mut flag: Option<String> = None;
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let l = raw.trim();
            if l.is_empty() {
                continue;
            }
            if l.starts_with('#') {
                flag = flag_of(l);
                continue;
            }
            let failed = flag.take();
            let toks: Vec<&str> = l.split_whitespace().collect();
            match toks[0] {
                "bmesh" => {
                    if toks.len() != 9 {
                        return Err(RangeError::syntax(path, line, format!("bmesh needs 8 fields (file tx ty tz qx qy qz qw), found {}", toks.len() - 1)));
                    }
                    let v = numbers(path, line, &toks[2..], "bmesh pose")?;
                    let q = [v[3], v[4], v[5], v[6]];
                    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
                    if !(0.99..=1.01).contains(&n) {
                        return Err(RangeError::syntax(path, line, format!("quaternion ({}, {}, {}, {}) has length {n:.4}, not 1", q[0], q[1], q[2], q[3])));
                    }
                    set.entries.push(ScanEntry { file: toks[1].to_string(), path: dir.join(toks[1]), pose: pose_from_conf([v[0], v[1], v[2]], q), line, failed });
                }
                "camera" | "mesh" => set.other_lines.push(l.to_string()),
                other => {
                    return Err(RangeError::syntax(path, line, format!("unknown record '{other}' (expected camera, bmesh or mesh)")));
                }
            }
        }
        Ok(set)
    }

    fn parse_aln(path: &Path, text: &str, dir: &Path) -> Result<ScanSet, RangeError> {
        let mut set = ScanSet::new(dir);
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty());
        let (line, first) = lines.next().ok_or_else(|| RangeError::syntax(path, 1, "empty .aln file (expected the number of meshes)"))?;
        let n: usize = first.parse().map_err(|_| RangeError::syntax(path, line, format!("expected the number of meshes, found '{first}'")))?;
        let mut last = line;
        for k in 0..n {
            let (line, name) = lines
                .by_ref()
                .find(|(_, l)| !l.starts_with('#'))
                .ok_or_else(|| RangeError::syntax(path, last, format!("the file ends before mesh {} of {n}", k + 1)))?;
            let mut m = [[0.0; 4]; 4];
            let mut last_row = line;
            let mut failed = None;
            for (r, row) in m.iter_mut().enumerate() {
                let (rl, rt) = lines
                    .by_ref()
                    .find(|(_, l)| {
                        if r == 0 && failed.is_none() {
                            failed = flag_of(l);
                        }
                        !l.starts_with('#')
                    })
                    .ok_or_else(|| RangeError::syntax(path, last_row, format!("the file ends inside the matrix of '{name}' (row {} of 4)", r + 1)))?;
                let toks: Vec<&str> = rt.split_whitespace().collect();
                if toks.len() != 4 {
                    return Err(RangeError::syntax(path, rl, format!("matrix row of '{name}' needs 4 numbers, found {}", toks.len())));
                }
                let v = numbers(path, rl, &toks, "matrix")?;
                row.copy_from_slice(&v);
                last_row = rl;
            }
            let pose = Rigid { r: [[m[0][0], m[0][1], m[0][2]], [m[1][0], m[1][1], m[1][2]], [m[2][0], m[2][1], m[2][2]]], t: [m[0][3], m[1][3], m[2][3]] };
            let bottom_ok = m[3][0].abs() < 1e-6 && m[3][1].abs() < 1e-6 && m[3][2].abs() < 1e-6 && (m[3][3] - 1.0).abs() < 1e-6;
            if !bottom_ok || pose.orthogonality_error() > 1e-3 {
                return Err(RangeError::syntax(path, last_row, format!("the matrix of '{name}' is not a rigid motion")));
            }
            set.entries.push(ScanEntry { file: name.to_string(), path: dir.join(name), pose: pose.orthonormalized(), line, failed });
            last = last_row;
        }
        Ok(set)
    }

    /// The entries not flagged as failed, and the flagged ones apart.
    pub fn split_failed(&self) -> (ScanSet, Vec<ScanEntry>) {
        let (failed, ok): (Vec<ScanEntry>, Vec<ScanEntry>) = self.entries.iter().cloned().partition(|e| e.failed.is_some());
        (ScanSet { entries: ok, ..self.clone() }, failed)
    }

    /// The set as text in `format`.
    pub fn to_text(&self, format: SetFormat) -> String {
        let mut s = String::new();
        match format {
            SetFormat::Conf => {
                for l in &self.other_lines {
                    s.push_str(l);
                    s.push('\n');
                }
                for e in &self.entries {
                    if let Some(why) = &e.failed {
                        s.push_str(&flag_line(why));
                        s.push('\n');
                    }
                    let (t, q) = pose_to_conf(&e.pose);
                    s.push_str(&format!("bmesh {} {} {} {} {} {} {} {}\n", e.file, t[0], t[1], t[2], q[0], q[1], q[2], q[3]));
                }
            }
            SetFormat::Aln => {
                s.push_str(&format!("{}\n", self.entries.len()));
                for e in &self.entries {
                    let comment = e.failed.as_deref().map_or_else(|| "#".to_string(), flag_line);
                    s.push_str(&format!("{}\n{comment}\n", e.file));
                    for row in e.pose.to_matrix4() {
                        s.push_str(&format!("{} {} {} {}\n", row[0], row[1], row[2], row[3]));
                    }
                }
                s.push_str("0\n");
            }
        }
        s
    }

    /// Writes the set to `path` in `format`, atomically.
    pub fn write(&self, path: &Path, format: SetFormat) -> Result<(), RangeError> {
        let mut f = mint_io::AtomicFile::create(path)?;
        f.as_file_mut()
            .write_all(self.to_text(format).as_bytes())
            .map_err(|e| RangeError::File { path: path.to_path_buf(), what: "cannot write the scan set", source: e })?;
        f.commit()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conf_round_trips_and_keeps_other_records() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.conf");
        std::fs::write(&p, "camera 0 -0.1 -0.7 0 1 0 0\n\nbmesh a.ply 0.1 0.2 0.3 0.00548449 -0.294635 -0.0038555 0.955586\n# comment\nbmesh b.ply 0 0 0 0 0 0 1\n").unwrap();
        let s = ScanSet::read(&p).unwrap();
        assert_eq!(s.entries.len(), 2);
        assert_eq!(s.entries[0].line, 3);
        assert_eq!(s.entries[1].path, dir.path().join("b.ply"));
        assert_eq!(s.other_lines, vec!["camera 0 -0.1 -0.7 0 1 0 0".to_string()]);
        // p_world = R(q)^T p + t: the rotation is the conjugate's.
        let q = [0.00548449, -0.294635, -0.0038555, 0.955586];
        let r = Rigid::from_quat(q, [0.0; 3]);
        let p0 = [1.0, 2.0, 3.0];
        let want = crate::geom::mat_vec(crate::geom::transpose(r.r), glam::DVec3::from(p0)) + glam::DVec3::new(0.1, 0.2, 0.3);
        let got = s.entries[0].pose.apply(p0);
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-12);
        }
        let out = dir.path().join("b.conf");
        s.write(&out, SetFormat::Conf).unwrap();
        let s2 = ScanSet::read(&out).unwrap();
        for (a, b) in s.entries.iter().zip(&s2.entries) {
            assert_eq!(a.file, b.file);
            let (ang, shift) = crate::geom::pose_error(&a.pose, &b.pose, &[[0.0; 3], [1.0, 1.0, 1.0]]);
            assert!(ang < 1e-9 && shift < 1e-12, "{ang} {shift}");
        }
        // Through .aln and back.
        let aln = dir.path().join("c.aln");
        s.write(&aln, SetFormat::Aln).unwrap();
        let s3 = ScanSet::read(&aln).unwrap();
        assert_eq!(s3.entries.len(), 2);
        for (a, b) in s.entries.iter().zip(&s3.entries) {
            let (ang, shift) = crate::geom::pose_error(&a.pose, &b.pose, &[[0.0; 3], [1.0, 1.0, 1.0]]);
            assert!(ang < 1e-9 && shift < 1e-12, "{ang} {shift}");
        }
    }

    /// A flagged scan keeps its flag through `.conf` and `.aln`, and in
    /// both directions between them; other comments flag nothing.
    #[test]
    fn failed_flags_round_trip_through_conf_and_aln() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.conf");
        std::fs::write(&p, "# a comment\nbmesh a.ply 0 0 0 0 0 0 1\n# mint: failed: no overlap\nbmesh b.ply 1 2 3 0 0 0 1\n# mint: failed: stale\n\nbmesh c.ply 0 0 0 0 0 0 1\n").unwrap();
        let s = ScanSet::read(&p).unwrap();
        let flags: Vec<Option<&str>> = s.entries.iter().map(|e| e.failed.as_deref()).collect();
        assert_eq!(flags, [None, Some("no overlap"), Some("stale")]);
        let mut s = s;
        s.entries[2].failed = Some("two\nlines\tand tabs".into());
        for (name, format) in [("b.aln", SetFormat::Aln), ("b.conf", SetFormat::Conf)] {
            let out = dir.path().join(name);
            s.write(&out, format).unwrap();
            let back = ScanSet::read(&out).unwrap();
            let flags: Vec<Option<&str>> = back.entries.iter().map(|e| e.failed.as_deref()).collect();
            assert_eq!(flags, [None, Some("no overlap"), Some("two lines and tabs")], "{name}");
            assert_eq!(back.entries[1].pose, s.entries[1].pose, "{name}");
            let again = dir.path().join(format!("again-{name}"));
            back.write(&again, SetFormat::from_path(&again)).unwrap();
            assert_eq!(std::fs::read_to_string(&again).unwrap(), std::fs::read_to_string(&out).unwrap());
        }
        let (ok, failed) = s.split_failed();
        assert_eq!(ok.entries.len(), 1);
        assert_eq!(failed.len(), 2);
    }

    #[test]
    fn malformed_sets_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let cases: [(&str, &str, &str); 6] = [
            ("a.conf", "bmesh a.ply 0 0 0 0 0 1\n", "a.conf:1: bmesh needs 8 fields (file tx ty tz qx qy qz qw), found 7"),
            ("b.conf", "camera 0 0 0 0 0 0 1\nbmesh a.ply 0 0 x 0 0 0 1\n", "b.conf:2: bmesh pose: 'x' is not a finite number"),
            ("c.conf", "bmesh a.ply 0 0 0 0 0 0 2\n", "c.conf:1: quaternion (0, 0, 0, 2) has length 2.0000, not 1"),
            ("d.conf", "camera 0 0 0 0 0 0 1\n", "d.conf:1: the set lists no scans"),
            ("e.aln", "1\na.ply\n#\n1 0 0 0\n0 1 0 0\n0 0 2 0\n0 0 0 1\n0\n", "e.aln:7: the matrix of 'a.ply' is not a rigid motion"),
            ("f.aln", "2\na.ply\n#\n1 0 0 0\n0 1 0 0\n", "f.aln:5: the file ends inside the matrix of 'a.ply' (row 3 of 4)"),
        ];
        for (name, text, want) in cases {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            let e = ScanSet::read(&p).unwrap_err().to_string();
            assert_eq!(e, format!("{}/{want}", dir.path().display()));
        }
    }
}
