//! `mint scan`: synthetic range images with ground truth. [`synthesize`]
//! casts a grid of parallel rays at a mesh from each of `views` viewpoints
//! (an orthographic scanner, like the Cyberware's translation scans) and
//! returns one [`SyntheticScan`] per view: a [`RangeImage`] in the view's
//! own frame and the true pose of that frame. [`perturb`] moves poses by
//! random rigid motions of bounded size, to test registration.
//!
//! Geometry of a view: viewpoints are the Fibonacci-sphere directions
//! (`views` points spread evenly over the sphere; González, "Measurement
//! of areas on a sphere using Fibonacci and latitude–longitude lattices",
//! 2010). View `k` looks at the centre `c` of the mesh's bounding box from
//! direction `u_k`: its frame has origin `c`, z axis `u_k` (towards the
//! scanner, mint's default [`crate::MeshOptions::toward_scanner`]), x and
//! y axes completing a right-handed frame. Cell (col, row) of the image is
//! the ray parallel to −z through local `x = (col − (n−1)/2)·s`, `y =
//! ((n−1)/2 − row)·s`, with `n = resolution` and `s = 1.05·D/n` for the
//! box diagonal `D`, so every view sees the whole mesh. A sample is the
//! first hit; it is dropped when the surface there is seen at more than
//! `max_angle` from its normal (real scanners lose grazing samples) or
//! from behind. Noise: a Gaussian error of standard deviation `noise`
//! along the ray (depth), as triangulation scanners have.
//!
//! Randomness comes from the seed only (SplitMix64, Box–Muller), so a seed
//! gives the same scans on every machine.

use crate::error::RangeError;
use crate::geom::Rigid;
use crate::range_image::RangeImage;
use crate::raycast::RayBvh;
use crate::scan_mesh::face_normal;
use glam::DVec3;
use mint_mesh::SplitMix64;

/// Options of [`synthesize`]; every field has a documented default.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthOptions {
    /// Number of viewpoints. Default 8.
    pub views: usize,
    /// Samples across the window (the image is `resolution²` cells).
    /// Default 200.
    pub resolution: u32,
    /// Standard deviation of the depth noise, in model units. Default 0.
    pub noise: f64,
    /// Seed of the noise. Default 1.
    pub seed: u64,
    /// Samples whose surface normal is more than this many degrees from the
    /// view direction are dropped. Default 80.
    pub max_angle_deg: f64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions { views: 8, resolution: 200, noise: 0.0, seed: 1, max_angle_deg: 80.0 }
    }
}

/// One synthetic view.
#[derive(Debug, Clone)]
pub struct SyntheticScan {
    /// `view_00`, `view_01`, ...
    pub name: String,
    /// The range image, in the view's frame.
    pub image: RangeImage,
    /// The true pose (view frame → world).
    pub pose: Rigid,
    /// Unit direction from the centre to the viewpoint (world).
    pub direction: DVec3,
}

/// `n` unit directions spread evenly over the sphere (Fibonacci lattice).
pub fn view_directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f64;
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The frame of a view from unit direction `u` at centre `c`.
pub fn view_pose(u: DVec3, c: DVec3) -> Rigid {
    let z = u.normalize_or_zero();
    let helper = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = (helper - z * helper.dot(z)).normalize_or_zero();
    let y = z.cross(x);
    // Columns are the local axes in world coordinates.
    Rigid { r: [[x.x, y.x, z.x], [x.y, y.y, z.y], [x.z, y.z, z.z]], t: c.to_array() }
}

/// A standard normal deviate (Box–Muller).
pub fn gaussian(rng: &mut SplitMix64) -> f64 {
    let u1 = 1.0 - rng.next_f64();
    let u2 = rng.next_f64();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// Casts the views; see the module docs. Errors: an empty mesh or options
/// out of range (`views` in 1..=1000, `resolution` in 2..=4096, finite
/// non-negative `noise`, `max_angle_deg` in (0, 90]).
pub fn synthesize(positions: &[[f64; 3]], faces: &[[u32; 3]], opts: &SynthOptions) -> Result<Vec<SyntheticScan>, RangeError> {
    if !(1..=1000).contains(&opts.views) {
        return Err(RangeError::option("views", format!("{} is not in 1..=1000", opts.views)));
    }
    if !(2..=4096).contains(&opts.resolution) {
        return Err(RangeError::option("resolution", format!("{} is not in 2..=4096", opts.resolution)));
    }
    if !(opts.noise.is_finite() && opts.noise >= 0.0) {
        return Err(RangeError::option("noise", format!("{} is not a finite non-negative number", opts.noise)));
    }
    if !(opts.max_angle_deg > 0.0 && opts.max_angle_deg <= 90.0) {
        return Err(RangeError::option("max_angle", format!("{} is not in (0, 90]", opts.max_angle_deg)));
    }
    if faces.is_empty() {
        return Err(RangeError::option("mesh", "the mesh has no faces"));
    }
    let (lo, hi) = crate::scan_mesh::bbox(faces.iter().flatten().map(|&i| positions[i as usize]));
    let (lo, hi) = (DVec3::from(lo), DVec3::from(hi));
    let c = (lo + hi) * 0.5;
    let diag = (hi - lo).length();
    let n = opts.resolution;
    let s = 1.05 * diag / n as f64;
    let far = diag;
    let cos_max = opts.max_angle_deg.to_radians().cos();
    let bvh = RayBvh::new(positions, faces);
    let mut out = Vec::with_capacity(opts.views);
    for (k, u) in view_directions(opts.views).into_iter().enumerate() {
        let pose = view_pose(u, c);
        let dir = -u;
        let mut rng = SplitMix64::for_stream(opts.seed, k as u64);
        let mut cells = Vec::with_capacity((n * n) as usize);
        let mut points = Vec::new();
        let half = (n - 1) as f64 * 0.5;
        for row in 0..n {
            for col in 0..n {
                let x = (col as f64 - half) * s;
                let y = (half - row as f64) * s;
                let o = pose.apply(DVec3::new(x, y, far));
                let hit = bvh.first_hit(o, dir, 0.0, 2.0 * far).filter(|h| {
                    let f = faces[h.face as usize];
                    let nrm = face_normal(positions, f).normalize_or_zero();
                    nrm.dot(u) >= cos_max
                });
                match hit {
                    Some(h) => {
                        let depth = far - h.t + if opts.noise > 0.0 { opts.noise * gaussian(&mut rng) } else { 0.0 };
                        cells.push(Some(points.len() as u32));
                        points.push([x, y, depth]);
                    }
                    None => cells.push(None),
                }
            }
        }
        out.push(SyntheticScan { name: format!("view_{k:02}"), image: RangeImage { cols: n, rows: n, cells, points }, pose, direction: u });
    }
    Ok(out)
}

/// `pose` moved by a random rigid motion about `center`: a rotation by an
/// angle uniform in `[0, max_deg]` about a uniformly random axis through
/// `center`, then a translation of length uniform in `[0, max_shift]` in a
/// uniformly random direction.
pub fn perturb(pose: &Rigid, center: DVec3, max_deg: f64, max_shift: f64, rng: &mut SplitMix64) -> Rigid {
    let axis = random_unit(rng);
    let angle = max_deg.to_radians() * rng.next_f64();
    let shift = random_unit(rng) * (max_shift * rng.next_f64());
    moved_about(pose, center, axis, angle, shift)
}

/// `pose` moved by exactly `deg` degrees about a uniformly random axis
/// through `center` and by exactly `shift` in a uniformly random direction
/// (the starts of the registration tests and benchmarks).
pub fn move_exactly(pose: &Rigid, center: DVec3, deg: f64, shift: f64, rng: &mut SplitMix64) -> Rigid {
    let axis = random_unit(rng);
    let shift = random_unit(rng) * shift;
    moved_about(pose, center, axis, deg.to_radians(), shift)
}

/// `p ↦ R(p − c) + c + shift` after `pose`, `R` the rotation by `angle`
/// about `axis`.
fn moved_about(pose: &Rigid, center: DVec3, axis: DVec3, angle: f64, shift: DVec3) -> Rigid {
    let rot = Rigid::from_axis_angle(axis, angle);
    Rigid { r: rot.r, t: (center - rot.rotate(center) + shift).to_array() }.after(pose)
}

fn random_unit(rng: &mut SplitMix64) -> DVec3 {
    loop {
        let v = DVec3::new(2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0);
        let n = v.length();
        if n > 1e-3 && n <= 1.0 {
            return v * (1.0 / n);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_of_a_sphere_land_on_the_sphere() {
        let mut m = mint_core::TriMesh::default();
        mint_gen::sphere([0.5, -0.25, 1.0], 1.0, 20_000, &mut m).unwrap();
        let scans = synthesize(&m.positions, &m.faces, &SynthOptions { views: 4, resolution: 64, ..Default::default() }).unwrap();
        assert_eq!(scans.len(), 4);
        for sc in &scans {
            let mut n = 0;
            for p in &sc.image.points {
                let w = sc.pose.apply(*p);
                let r = (DVec3::from(w) - DVec3::new(0.5, -0.25, 1.0)).length();
                // Flat facets of a 20k-face sphere are within 2e-3 of it.
                assert!((r - 1.0).abs() < 2e-3, "{r}");
                n += 1;
            }
            // A disk of radius sin(80°) out of a square of side 1.05·2√3:
            // about π·0.985²/(3.637²) of 4096 cells.
            assert!((850..1000).contains(&n), "{n}");
            assert!(sc.pose.orthogonality_error() < 1e-12);
        }
        let dirs = view_directions(8);
        for d in &dirs {
            assert!((d.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn perturbations_stay_within_bounds() {
        let mut rng = SplitMix64::new(7);
        let c = DVec3::new(1.0, 2.0, 3.0);
        for _ in 0..100 {
            let p = perturb(&Rigid::IDENTITY, c, 5.0, 0.1, &mut rng);
            assert!(p.angle().to_degrees() <= 5.0 + 1e-9);
            // The centre moves by the translation only.
            assert!((p.apply(c) - c).length() <= 0.1 + 1e-12);
        }
    }
}
