//! Synthetic voxel volumes for `mint gen volume`: every sample a formula of
//! its index, so a volume of any size streams out slice by slice (memory
//! of one slice and per-axis tables) and the same dimensions give the same
//! bytes on any machine.
//!
//! - [`VolumeKind::Field`]: a smooth scalar field (0 .. 4000, iso 1000 is
//!   its surface) holding a ball, a torus whose tube is 2% of the volume's
//!   size, a thin oblique sheet 1.5 voxels thick at any resolution (the
//!   thin feature a coarse grid must not lose, and that a volume's border
//!   cuts), and a separable ripple of under half a voxel, so that
//!   crossings fall anywhere along the grid lines without breaking the sheet.
//! - [`VolumeKind::Labels`]: a label map of three touching solids (1: a
//!   ball, 2: a box against it, 3: a torus through both) on 0: the shared
//!   boundaries that `--labels` must mesh without gaps.
//!
//! Coordinates: u = (index + 0.5) / dims, in [0, 1) per axis.

/// Which volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VolumeKind {
    Field,
    Labels,
}

/// The iso value whose surface is the field's shapes.
pub const FIELD_ISO: f32 = 1000.0;

/// Fills `out` (dims[0] · dims[1] values, x fastest) with slice `k`.
pub fn volume_slice(kind: VolumeKind, dims: [u64; 3], k: u64, out: &mut [f32]) {
    let (nx, ny) = (dims[0] as usize, dims[1] as usize);
    assert_eq!(out.len(), nx * ny);
    let n = dims.iter().copied().max().unwrap_or(1) as f64;
    let u = |i: u64, d: usize| (i as f64 + 0.5) / dims[d] as f64;
    let z = u(k, 2);
    let xs: Vec<f64> = (0..dims[0]).map(|i| u(i, 0)).collect();
    let ripple_x: Vec<f64> = xs.iter().map(|&x| (x * 23.0).sin()).collect();
    for j in 0..ny {
        let y = u(j as u64, 1);
        let ry = (y * 17.0).sin();
        let rz = (z * 29.0).sin();
        let row = &mut out[j * nx..(j + 1) * nx];
        for (i, v) in row.iter_mut().enumerate() {
            let x = xs[i];
            *v = match kind {
                VolumeKind::Field => {
                    // Signed distances (negative inside) in units of the volume's size.
                    let ball = ((x - 0.35).powi(2) + (y - 0.4).powi(2) + (z - 0.45).powi(2)).sqrt() - 0.22;
                    let (tx, ty, tz) = (x - 0.65, y - 0.6, z - 0.55);
                    let torus = (((tx * tx + ty * ty).sqrt() - 0.2).powi(2) + tz * tz).sqrt() - 0.02;
                    // The sheet: |plane distance| less than 0.75 voxel.
                    let plane = (0.3 * x + 0.2 * y + 0.93 * z - 0.6) / (0.09f64 + 0.04 + 0.8649).sqrt();
                    let sheet = plane.abs() - 0.75 / n;
                    let d = ball.min(torus).min(sheet);
                    let ripple = 0.15 / n * (ripple_x[i] + ry + rz);
                    // 1000 at the surface, 0 .. 4000 over ±0.05 of the size.
                    (1000.0 - 20_000.0 * (d + ripple)).clamp(0.0, 4000.0) as f32
                }
                VolumeKind::Labels => {
                    let ball = (x - 0.4).powi(2) + (y - 0.5).powi(2) + (z - 0.5).powi(2) < 0.2 * 0.2;
                    let boxed = (0.55..0.85).contains(&x) && (0.3..0.7).contains(&y) && (0.3..0.7).contains(&z);
                    let (tx, ty, tz) = (x - 0.55, y - 0.5, z - 0.5);
                    let torus = ((tx * tx + tz * tz).sqrt() - 0.25).powi(2) + ty * ty < 0.05 * 0.05;
                    if torus {
                        3.0
                    } else if ball {
                        1.0
                    } else if boxed {
                        2.0
                    } else {
                        0.0
                    }
                }
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_field_has_every_shape_and_the_labels_touch() {
        let dims = [64, 64, 64];
        let mut s = vec![0f32; 64 * 64];
        let (mut inside, mut total) = (0, 0);
        let mut labels = [0u64; 4];
        for k in 0..64 {
            volume_slice(VolumeKind::Field, dims, k, &mut s);
            inside += s.iter().filter(|&&v| v >= FIELD_ISO).count();
            total += s.len();
            volume_slice(VolumeKind::Labels, dims, k, &mut s);
            for &v in &s {
                labels[v as usize] += 1;
            }
        }
        assert!(inside > total / 50 && inside < total / 3, "{inside} of {total}");
        assert!(labels.iter().all(|&c| c > 100), "{labels:?}");
        // Deterministic.
        let mut a = vec![0f32; 64 * 64];
        volume_slice(VolumeKind::Field, dims, 7, &mut a);
        volume_slice(VolumeKind::Field, dims, 7, &mut s);
        assert_eq!(a, s);
    }
}
