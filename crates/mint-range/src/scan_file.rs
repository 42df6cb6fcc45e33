//! `mint scan` as a library call: [`scan_file`] reads a mesh, synthesizes
//! range scans of it from several views ([`crate::synth`]), and writes a
//! scan set into a directory: one range image per view (PLY or depth grid),
//! its triangulation beside it (`NAME.mesh.ply`), `scans.conf` with the
//! true poses and, when asked, `scans-perturbed.conf` with every pose but
//! the first moved at random. The CLI only parses, calls and prints.

use crate::depth_grid::{write_depth_grid, GridEncoding};
use crate::error::RangeError;
use crate::scan_mesh::{MeshOptions, ScanMesh};
use crate::scanset::{ScanEntry, ScanSet, SetFormat};
use crate::synth::{perturb, synthesize, SynthOptions, SyntheticScan};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// How each range image is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// A PLY range image (the Stanford scans' layout).
    Ply,
    /// mint's depth grid, binary or text (docs/FORMATS.md).
    Grid(GridEncoding),
}

/// Options of [`scan_file`].
#[derive(Debug, Clone)]
pub struct ScanFileOptions {
    pub synth: SynthOptions,
    pub format: ImageFormat,
    /// `scans-perturbed.conf`: every pose but the first turned by up to
    /// this many degrees and moved by up to this fraction of the mesh's
    /// bounding-box diagonal (both 0: no such file).
    pub perturb_deg: f64,
    pub perturb_frac: f64,
}

/// What [`scan_file`] wrote.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ScanFileSummary {
    pub views: usize,
    pub samples: usize,
    /// The files written, relative to the output directory.
    pub files: Vec<String>,
    pub perturbed: bool,
}

/// The files [`scan_file`] would write for `scans`, relative to the
/// directory (for the caller's refusal to overwrite an input).
pub fn scan_file_names(scans: &[SyntheticScan], format: ImageFormat) -> Vec<String> {
    let ext = if format == ImageFormat::Ply { "ply" } else { "rgrid" };
    let mut v = vec!["scans.conf".to_string(), "scans-perturbed.conf".to_string()];
    v.extend(scans.iter().flat_map(|sc| [format!("{}.{ext}", sc.name), format!("{}.mesh.ply", sc.name)]));
    v
}

/// Synthesizes the scans of the mesh `positions`/`faces` (read by the
/// caller from `mesh`, named in the files' comments) into `out_dir`; see
/// the module docs. `check` is called with every path before anything is
/// written (the CLI refuses paths that are inputs).
pub fn scan_file(
    mesh: &Path,
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    out_dir: &Path,
    opts: &ScanFileOptions,
    check: &dyn Fn(&Path) -> Result<(), String>,
) -> Result<ScanFileSummary, RangeError> {
    let io = |path: &Path, what: &str, e: std::io::Error| RangeError::from(mint_io::Error::io(path, what, e));
    let scans = synthesize(positions, faces, &opts.synth)?;
    if out_dir.exists() && !out_dir.is_dir() {
        return Err(RangeError::Output { path: out_dir.to_path_buf(), message: "is not a directory; give a directory for the scans".into() });
    }
    let files = scan_file_names(&scans, opts.format);
    for f in &files {
        let path = out_dir.join(f);
        check(&path).map_err(|message| RangeError::Output { path, message })?;
    }
    std::fs::create_dir_all(out_dir).map_err(|e| io(out_dir, "cannot create the output directory", e))?;
    let mut set = ScanSet::new(out_dir);
    let comments = [format!("mint scan of {}", mesh.display())];
    let mut samples = 0;
    for sc in &scans {
        let file = match opts.format {
            ImageFormat::Ply => {
                let file = format!("{}.ply", sc.name);
                sc.image.write_ply(&out_dir.join(&file), &comments)?;
                file
            }
            ImageFormat::Grid(enc) => {
                let file = format!("{}.rgrid", sc.name);
                write_depth_grid(&out_dir.join(&file), &sc.image, enc, &comments)?;
                file
            }
        };
        samples += sc.image.points.len();
        if let Ok(m) = ScanMesh::from_range_image(&sc.name, &sc.image, &MeshOptions::default()) {
            let mpath = out_dir.join(format!("{}.mesh.ply", sc.name));
            let mut w = mint_io::MeshWriter::create(&mpath, mint_io::Format::Ply, Default::default())?;
            for p in &m.positions {
                w.write_vertex(*p)?;
            }
            for f in &m.faces {
                w.write_face(*f)?;
            }
            w.finish()?;
        }
        set.entries.push(ScanEntry { file, path: PathBuf::new(), pose: sc.pose, line: 0, failed: None });
    }
    set.write(&out_dir.join("scans.conf"), SetFormat::Conf)?;
    let perturbed = opts.perturb_deg > 0.0 || opts.perturb_frac > 0.0;
    if perturbed {
        let (lo, hi) = crate::scan_mesh::bbox(faces.iter().flatten().map(|&i| positions[i as usize]));
        let (lo, hi) = (DVec3::from(lo), DVec3::from(hi));
        let c = 0.5 * (lo + hi);
        let diag = lo.distance(hi);
        let mut rng = mint_mesh::SplitMix64::new(opts.synth.seed ^ 0x5eed);
        let mut p = set.clone();
        for e in p.entries.iter_mut().skip(1) {
            e.pose = perturb(&e.pose, c, opts.perturb_deg, opts.perturb_frac * diag, &mut rng);
        }
        p.write(&out_dir.join("scans-perturbed.conf"), SetFormat::Conf)?;
    }
    Ok(ScanFileSummary { views: scans.len(), samples, files, perturbed })
}
