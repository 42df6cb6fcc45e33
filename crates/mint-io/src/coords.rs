//! Where f32 can place a coordinate: the rounding error at a magnitude,
//! and the origin a format that stores f32 offsets (glTF's node
//! translation) should carry. Pure arithmetic, shared by the precision
//! choice and the glTF writer.

/// The largest error of rounding a coordinate of magnitude at most
/// `max_abs` to f32: half the spacing of f32 values there (of denormals,
/// 2⁻¹⁴⁹, below the normal range); infinite beyond f32's range.
pub fn f32_error(max_abs: f64) -> f64 {
    if !(max_abs <= f32::MAX as f64) {
        return f64::INFINITY;
    }
    if max_abs < f32::MIN_POSITIVE as f64 {
        return 2f64.powi(-150);
    }
    // The binary exponent of max_abs: f32 values in [2^e, 2^(e+1)) are 2^(e-23) apart.
    let e = ((max_abs.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    2f64.powi(e - 24)
}

/// The largest magnitude of a coordinate in the box `[lo, hi]`.
pub fn max_abs(lo: [f64; 3], hi: [f64; 3]) -> f64 {
    (0..3).map(|d| lo[d].abs().max(hi[d].abs())).fold(0.0, f64::max)
}

/// The origin the writer puts in the node's translation for a box
/// `[lo, hi]`: none (zero) when the model lies within its own size of the
/// origin, else the box centre.
pub fn origin_for(lo: [f64; 3], hi: [f64; 3]) -> [f64; 3] {
    if !(0..3).all(|d| lo[d] <= hi[d]) {
        return [0.0; 3];
    }
    let extent = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let far = max_abs(lo, hi);
    if far <= 2.0 * extent {
        [0.0; 3]
    } else {
        [0, 1, 2].map(|d| lo[d] + 0.5 * (hi[d] - lo[d]))
    }
}

