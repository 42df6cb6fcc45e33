//! Choosing the precision of an output's coordinates. f32 halves a file
//! and is what most tools expect, but its spacing grows with the magnitude:
//! near 5.4·10⁶ (a UTM northing, in metres) f32 values are 0.5 apart, so a
//! geo-referenced mesh with centimetre detail collapses onto a half-metre
//! lattice; and a model a hundred-billionth of a unit across underflows.
//! Writers therefore store f32 only when it places every coordinate of the
//! output's box within a tolerance the caller states (for a resampling, a
//! thousandth of a cell), and f64 otherwise. Formats that hold only f32
//! (STL, 3DS) refuse such an output with one line naming the fix.

use crate::error::Error;
use crate::format::Format;
use std::path::Path;

pub use crate::coords::{f32_error, max_abs, origin_for};

/// Why an output is written in f64 when it is (`None`: f32 places every
/// coordinate of the box `[lo, hi]` within `tolerance`). The text names
/// the magnitude, f32's error there and the tolerance.
pub fn needs_f64(lo: [f64; 3], hi: [f64; 3], tolerance: f64) -> Option<String> {
    let m = max_abs(lo, hi);
    let err = f32_error(m);
    (err > tolerance || !(tolerance > 0.0)).then(|| format!("f32 rounds coordinates near {m:.6e} by up to {err:.3e}, more than the {tolerance:.3e} allowed"))
}

/// The precision chosen for an output: `double` when asked (`--double`)
/// or when [`needs_f64`] says so, with the reason; an f32-only `format`
/// that would need f64 is refused with one line naming `path` and the fix.
pub fn choose(path: &Path, format: Format, asked_double: bool, lo: [f64; 3], hi: [f64; 3], tolerance: f64) -> Result<(bool, String), Error> {
    let backend = crate::formats::backend(format);
    if backend.origin {
        // f32 offsets from the box's centre (or none, near the origin).
        let o = origin_for(lo, hi);
        let (rlo, rhi) = ([0, 1, 2].map(|d| lo[d] - o[d]), [0, 1, 2].map(|d| hi[d] - o[d]));
        if asked_double {
            return Err(Error::unsupported(path, format!("{format} stores f32 positions only, so --double cannot apply: write .ply or .obj for f64")));
        }
        return match needs_f64(rlo, rhi, tolerance) {
            None if o == [0.0; 3] => Ok((false, "f32".into())),
            None => Ok((false, format!("f32 relative to an origin ({:.6e}, {:.6e}, {:.6e}) in the node's translation", o[0], o[1], o[2]))),
            Some(why) => Err(Error::unsupported(
                path,
                format!("{format} stores f32 positions, and even relative to the box's centre {why}: write .ply or .obj (f64), or scale the input up (tiny models)"),
            )),
        };
    }
    if asked_double {
        return Ok((true, "f64 (asked with --double)".into()));
    }
    match needs_f64(lo, hi, tolerance) {
        None => Ok((false, "f32".into())),
        Some(why) if backend.f32_only => Err(Error::unsupported(
            path,
            format!("{} stores f32 coordinates, and {why}: write .ply or .obj (f64), or move the input towards the origin (large coordinates) or scale it up (tiny ones)", format),
        )),
        Some(why) => Ok((true, format!("f64: {why}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_error_is_half_the_spacing_of_f32_values() {
        for x in [1.0f64, 3.7, 1e-3, 5.4e6, 123456.789, 1e30, 1e-40] {
            let f = x as f32;
            let (up, down) = (f32::from_bits(f.to_bits() + 1) as f64, f32::from_bits(f.to_bits().saturating_sub(1)) as f64);
            let spacing = (up - f as f64).max(f as f64 - down);
            assert!(f32_error(x) >= (x - f as f64).abs(), "{x}: rounding error above the bound");
            assert!(f32_error(x) <= spacing, "{x}: bound {} above the spacing {spacing}", f32_error(x));
        }
        assert_eq!(f32_error(5.4e6), 0.25);
        assert_eq!(f32_error(1e39), f64::INFINITY);
        assert_eq!(f32_error(f64::NAN), f64::INFINITY);
    }

    #[test]
    fn utm_coordinates_and_tiny_models_need_f64() {
        let utm = ([512335.25, 5412335.5, 110.0], [512355.25, 5412355.5, 130.0]);
        assert!(needs_f64(utm.0, utm.1, 0.2 * 1e-3).is_some());
        assert!(needs_f64([-1.0; 3], [1.0; 3], 0.02 * 1e-3).is_none());
        assert!(needs_f64([-1e-100; 3], [1e-100; 3], 1e-102 * 1e-3).is_some());
        let p = Path::new("out.stl");
        let e = choose(p, Format::Stl, false, utm.0, utm.1, 2e-4).unwrap_err().to_string();
        assert!(e.starts_with("out.stl: ") && e.contains("write .ply or .obj") && !e.contains('\n'), "{e}");
        assert_eq!(choose(Path::new("o.ply"), Format::Ply, false, utm.0, utm.1, 2e-4).unwrap().0, true);
        assert_eq!(choose(Path::new("o.ply"), Format::Ply, false, [-1.0; 3], [1.0; 3], 2e-5).unwrap(), (false, "f32".to_string()));
    }
}
