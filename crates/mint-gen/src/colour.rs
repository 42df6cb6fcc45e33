//! A colour field for synthetic meshes (`mint gen … --color`): smooth
//! gradients with sharp borders, a pure function of the position, so that
//! any mesh of any size gets the same colours where its surfaces meet, and
//! benchmarks and tests know the colour everywhere.
//!
//! Smooth part: each channel a sine of one coordinate (periods of about
//! two units). Sharp part: the cells of a lattice of quarter units, in a
//! checkerboard, the odd ones darkened to about a third: borders lie on
//! the planes `x, y, z = k / 4`.

/// The colour (RGBA, alpha 255) at `p`.
pub fn colour_at(p: [f64; 3]) -> [u8; 4] {
    let smooth = [0.5 + 0.5 * (3.0 * p[0]).sin(), 0.5 + 0.5 * (3.0 * p[1] + 1.0).sin(), 0.5 + 0.5 * (3.0 * p[2] + 2.0).sin()];
    let cell = (4.0 * p[0]).floor() + (4.0 * p[1]).floor() + (4.0 * p[2]).floor();
    let dark = cell.rem_euclid(2.0) == 1.0;
    let k = if dark { 0.35 } else { 1.0 };
    let c = smooth.map(|v| (255.0 * k * v).round().clamp(0.0, 255.0) as u8);
    [c[0], c[1], c[2], 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_border_is_sharp_and_the_field_smooth_inside_a_cell() {
        // Across x = 0.25 the checkerboard flips: a step of about a third.
        let (a, b) = (colour_at([0.2499, 0.1, 0.1]), colour_at([0.2501, 0.1, 0.1]));
        assert!(a[1] > 2 * b[1] || b[1] > 2 * a[1], "{a:?} {b:?}");
        // Inside a cell, nearby points have nearby colours.
        let (c, d) = (colour_at([0.1, 0.1, 0.1]), colour_at([0.1001, 0.1, 0.1]));
        assert!((0..3).all(|k| (c[k] as i32 - d[k] as i32).abs() <= 1), "{c:?} {d:?}");
        assert_eq!(c[3], 255);
    }
}
