//! The synthetic scene shared by the integration tests: a bumpy sphere
//! (mint-gen's scan-like surface without defects: star-shaped, no symmetry,
//! so registration is well posed), scanned from 8 views with depth noise.

use glam::DVec3;
use mint_range::synth::{perturb, synthesize, SynthOptions, SyntheticScan};
use mint_range::{MeshOptions, Rigid, ScanMesh};

pub struct Scene {
    pub truth: mint_core::TriMesh,
    pub scans: Vec<SyntheticScan>,
    pub meshes: Vec<ScanMesh>,
    pub center: DVec3,
    pub diag: f64,
    pub sigma: f64,
}

pub const SIGMA: f64 = 0.001;

pub fn scene() -> Scene {
    scene_with(60_000, 0.25, 160)
}

pub fn scene_with(faces: u64, amplitude: f64, resolution: u32) -> Scene {
    let mut truth = mint_core::TriMesh::default();
    let opts = mint_gen::ScanOptions { holes: 0, flips: 0, patches: 0, slivers: 0, noise_amplitude: amplitude, ..Default::default() };
    mint_gen::scan_like(faces, 3, &opts, &mut truth).unwrap();
    scene_of(truth, 8, resolution, 5)
}

/// `truth` scanned from `views` views of `resolution`² samples with depth
/// noise [`SIGMA`] (noise seed `seed`).
pub fn scene_of(truth: mint_core::TriMesh, views: usize, resolution: u32, seed: u64) -> Scene {
    let scans = synthesize(&truth.positions, &truth.faces, &SynthOptions { views, resolution, noise: SIGMA, seed, ..Default::default() }).unwrap();
    let meshes = scans.iter().map(|s| ScanMesh::from_range_image(&s.name, &s.image, &MeshOptions::default()).unwrap()).collect();
    let (lo, hi) = mint_range::scan_mesh::bbox(truth.positions.iter().copied());
    let (lo, hi) = (DVec3::from(lo), DVec3::from(hi));
    let center = 0.5 * (lo + hi);
    let diag = (hi - lo).length();
    Scene { truth, scans, meshes, center, diag, sigma: SIGMA }
}

/// True poses, with every view but the first (the anchor) moved by up to
/// `deg` degrees and `frac` of the diagonal.
pub fn perturbed(s: &Scene, deg: f64, frac: f64, seed: u64) -> Vec<Rigid> {
    let mut rng = mint_mesh::SplitMix64::new(seed);
    s.scans
        .iter()
        .enumerate()
        .map(|(i, sc)| if i == 0 { sc.pose } else { perturb(&sc.pose, s.center, deg, frac * s.diag, &mut rng) })
        .collect()
}

/// Rotation error in degrees and the displacement of the scene centre.
pub fn pose_errors(truth: &Rigid, got: &Rigid, center: DVec3) -> (f64, f64) {
    let d = truth.inverse().after(got);
    let c_local = truth.inverse().apply(center);
    (d.angle().to_degrees(), truth.apply(c_local).distance(got.apply(c_local)))
}
