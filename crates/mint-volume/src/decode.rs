//! Sample types and their decoding: stored bytes (either byte order) to
//! `f32` with a rescale (`v · slope + intercept`). Every integer type up to
//! 16 bits is exact in `f32`; 32- and 64-bit integers and `f64` round to
//! the nearest `f32` (24 bits of mantissa, far finer than any scanner).

/// A stored sample type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sample {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit.
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// Unsigned 64-bit.
    U64,
    /// Signed 64-bit.
    I64,
    /// IEEE 754 single.
    F32,
    /// IEEE 754 double.
    F64,
}

impl Sample {
    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            Sample::U8 | Sample::I8 => 1,
            Sample::U16 | Sample::I16 => 2,
            Sample::U32 | Sample::I32 | Sample::F32 => 4,
            Sample::U64 | Sample::I64 | Sample::F64 => 8,
        }
    }

    /// The name used on the command line and in summaries (`u16`, `f32`, …).
    pub fn name(self) -> &'static str {
        match self {
            Sample::U8 => "u8",
            Sample::I8 => "i8",
            Sample::U16 => "u16",
            Sample::I16 => "i16",
            Sample::U32 => "u32",
            Sample::I32 => "i32",
            Sample::U64 => "u64",
            Sample::I64 => "i64",
            Sample::F32 => "f32",
            Sample::F64 => "f64",
        }
    }

    /// Parses [`Sample::name`] and the usual aliases (`uint16`, `short`,
    /// `float`, …).
    pub fn parse(s: &str) -> Option<Sample> {
        Some(match s.to_ascii_lowercase().as_str() {
            "u8" | "uint8" | "uchar" | "unsigned char" => Sample::U8,
            "i8" | "int8" | "char" | "signed char" => Sample::I8,
            "u16" | "uint16" | "ushort" | "unsigned short" => Sample::U16,
            "i16" | "int16" | "short" => Sample::I16,
            "u32" | "uint32" | "uint" | "unsigned int" => Sample::U32,
            "i32" | "int32" | "int" => Sample::I32,
            "u64" | "uint64" => Sample::U64,
            "i64" | "int64" => Sample::I64,
            "f32" | "float" | "float32" => Sample::F32,
            "f64" | "double" | "float64" => Sample::F64,
            _ => return None,
        })
    }

    /// True for floating-point types (the ones that can hold NaN).
    pub fn is_float(self) -> bool {
        matches!(self, Sample::F32 | Sample::F64)
    }

    /// The smallest and largest stored value of an integer type (`None`
    /// for floats).
    pub fn int_range(self) -> Option<(f64, f64)> {
        Some(match self {
            Sample::U8 => (0.0, u8::MAX as f64),
            Sample::I8 => (i8::MIN as f64, i8::MAX as f64),
            Sample::U16 => (0.0, u16::MAX as f64),
            Sample::I16 => (i16::MIN as f64, i16::MAX as f64),
            Sample::U32 => (0.0, u32::MAX as f64),
            Sample::I32 => (i32::MIN as f64, i32::MAX as f64),
            Sample::U64 => (0.0, u64::MAX as f64),
            Sample::I64 => (i64::MIN as f64, i64::MAX as f64),
            Sample::F32 | Sample::F64 => return None,
        })
    }
}

/// Whether the rescale `v · slope + intercept` keeps every stored value of
/// an integer `sample` type finite as an f32 (a header with an absurd
/// slope would otherwise turn integers into infinities). `Err` says why,
/// for the caller's one line.
pub(crate) fn check_rescale(sample: Sample, slope: f64, intercept: f64) -> Result<(), String> {
    if !slope.is_finite() || !intercept.is_finite() {
        return Err(format!("rescale slope {slope} and intercept {intercept} are not finite"));
    }
    if let Some((lo, hi)) = sample.int_range() {
        let max = f32::MAX as f64;
        if [lo, hi].iter().any(|&v| (v * slope + intercept).abs() > max) {
            return Err(format!("rescale slope {slope} and intercept {intercept} take {} values beyond the range of 32-bit floats", sample.name()));
        }
    }
    Ok(())
}

/// How stored bytes become values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Decoder {
    pub sample: Sample,
    pub big_endian: bool,
    pub slope: f64,
    pub intercept: f64,
}

impl Decoder {
    /// Decodes `bytes` (exactly `out.len()` samples) into `out`, returning
    /// for integer samples the smallest and
    /// largest value decoded, folded on the integers in the same pass and
    /// then rescaled: the rescale and the rounding to `f32` are monotone,
    /// so the ends of the integers give the ends of the values (swapped
    /// for a negative slope), and [`check_rescale`] keeps them finite.
    /// `None` for floats, which may hold NaN and infinities (fold those
    /// with `sample_stats`), and for no samples.
    pub fn decode_range(&self, bytes: &[u8], out: &mut [f32]) -> Option<[f32; 2]> {
        debug_assert_eq!(bytes.len(), out.len() * self.sample.size());
        let plain = self.slope == 1.0 && self.intercept == 0.0;
        let (s, b) = (self.slope, self.intercept);
        let be = self.big_endian;
        // One loop per byte order and rescale, so that neither is decided
        // per sample.
        macro_rules! ints {
            ($t:ty, $n:expr) => {{
                let (le, bee) = (|a: [u8; $n]| <$t>::from_le_bytes(a), |a: [u8; $n]| <$t>::from_be_bytes(a));
                let ends = match (be, plain) {
                    (false, true) => fold_ints(bytes, out, le, |v| v as f32),
                    (true, true) => fold_ints(bytes, out, bee, |v| v as f32),
                    (false, false) => fold_ints(bytes, out, le, |v| (v as f64 * s + b) as f32),
                    (true, false) => fold_ints(bytes, out, bee, |v| (v as f64 * s + b) as f32),
                };
                let value = |v: $t| if plain { v as f32 } else { (v as f64 * s + b) as f32 };
                ends.map(|(lo, hi)| {
                    let (a, z) = (value(lo), value(hi));
                    if a <= z {
                        [a, z]
                    } else {
                        [z, a]
                    }
                })
            }};
        }
        macro_rules! floats {
            ($t:ty, $n:expr) => {{
                for (o, c) in out.iter_mut().zip(bytes.chunks_exact($n)) {
                    let a: [u8; $n] = c.try_into().unwrap();
                    let v = if be { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) };
                    *o = if plain { v as f32 } else { (v as f64 * s + b) as f32 };
                }
                None
            }};
        }
        match self.sample {
            Sample::U8 => ints!(u8, 1),
            Sample::I8 => ints!(i8, 1),
            Sample::U16 => ints!(u16, 2),
            Sample::I16 => ints!(i16, 2),
            Sample::U32 => ints!(u32, 4),
            Sample::I32 => ints!(i32, 4),
            Sample::U64 => ints!(u64, 8),
            Sample::I64 => ints!(i64, 8),
            Sample::F32 => floats!(f32, 4),
            Sample::F64 => floats!(f64, 8),
        }
    }
}

/// Decodes `N`-byte integers of `bytes` into `out` by `read` and `value`,
/// returning the smallest and largest integer (`None` for none).
#[inline(always)]
fn fold_ints<T: Copy + Ord, const N: usize>(bytes: &[u8], out: &mut [f32], read: impl Fn([u8; N]) -> T, value: impl Fn(T) -> f32) -> Option<(T, T)> {
    let mut pairs = out.iter_mut().zip(bytes.chunks_exact(N));
    let (o, c) = pairs.next()?;
    let first = read(c.try_into().unwrap());
    *o = value(first);
    let (mut lo, mut hi) = (first, first);
    for (o, c) in pairs {
        let v = read(c.try_into().unwrap());
        lo = lo.min(v);
        hi = hi.max(v);
        *o = value(v);
    }
    Some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_byte_orders_and_the_rescale() {
        let d = Decoder { sample: Sample::I16, big_endian: false, slope: 1.0, intercept: 0.0 };
        let mut out = [0.0f32; 2];
        d.decode_range(&[0x01, 0x00, 0xff, 0xff], &mut out);
        assert_eq!(out, [1.0, -1.0]);
        let d = Decoder { sample: Sample::U16, big_endian: true, slope: 2.0, intercept: -1024.0 };
        d.decode_range(&[0x01, 0x00, 0x00, 0x02], &mut out);
        assert_eq!(out, [-512.0, -1020.0]);
        let d = Decoder { sample: Sample::F64, big_endian: false, slope: 1.0, intercept: 0.0 };
        let mut one = [0.0f32];
        d.decode_range(&0.5f64.to_le_bytes(), &mut one);
        assert_eq!(one, [0.5]);
    }

    const ALL: [Sample; 10] = [Sample::U8, Sample::I8, Sample::U16, Sample::I16, Sample::U32, Sample::I32, Sample::U64, Sample::I64, Sample::F32, Sample::F64];

    proptest::proptest! {
        /// The range folded on the integers is the range of the values
        /// decoded, for every type, byte order and rescale (negative and
        /// zero slopes too), and the values are each sample's own.
        #[test]
        fn the_integer_range_is_the_range_of_the_values(t in 0usize..10, be: bool, rescale in 0usize..4, bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..200)) {
            let sample = ALL[t];
            let (slope, intercept) = [(1.0, 0.0), (2.5, -1024.0), (-3.0, 7.0), (0.0, 5.0)][rescale];
            let d = Decoder { sample, big_endian: be, slope, intercept };
            let n = bytes.len() / sample.size();
            let bytes = &bytes[..n * sample.size()];
            let mut out = vec![f32::NAN; n];
            let range = d.decode_range(bytes, &mut out);
            for (i, c) in bytes.chunks_exact(sample.size()).enumerate() {
                let mut a = [0u8; 8];
                a[..c.len()].copy_from_slice(c);
                if be {
                    a[..c.len()].reverse();
                }
                // Integers exactly, floats as f64; each rounds once to f32.
                let (int, float): (Option<i128>, f64) = match sample {
                    Sample::U8 => (Some(a[0] as i128), 0.0),
                    Sample::I8 => (Some(a[0] as i8 as i128), 0.0),
                    Sample::U16 => (Some(u16::from_le_bytes([a[0], a[1]]) as i128), 0.0),
                    Sample::I16 => (Some(i16::from_le_bytes([a[0], a[1]]) as i128), 0.0),
                    Sample::U32 => (Some(u32::from_le_bytes(a[..4].try_into().unwrap()) as i128), 0.0),
                    Sample::I32 => (Some(i32::from_le_bytes(a[..4].try_into().unwrap()) as i128), 0.0),
                    Sample::U64 => (Some(u64::from_le_bytes(a) as i128), 0.0),
                    Sample::I64 => (Some(i64::from_le_bytes(a) as i128), 0.0),
                    Sample::F32 => (None, f32::from_le_bytes(a[..4].try_into().unwrap()) as f64),
                    Sample::F64 => (None, f64::from_le_bytes(a)),
                };
                let plain = (slope, intercept) == (1.0, 0.0);
                let want = match int {
                    Some(v) if plain => v as f32,
                    Some(v) => (v as f64 * slope + intercept) as f32,
                    None if plain => float as f32,
                    None => (float * slope + intercept) as f32,
                };
                proptest::prop_assert!(out[i] == want || (out[i].is_nan() && want.is_nan()), "sample {}: {} against {}", i, out[i], want);
            }
            if sample.is_float() || n == 0 {
                proptest::prop_assert_eq!(range, None);
            } else {
                let lo = out.iter().copied().fold(f32::INFINITY, f32::min);
                let hi = out.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                proptest::prop_assert_eq!(range, Some([lo, hi]));
            }
        }
    }

    #[test]
    fn names_round_trip() {
        for s in [Sample::U8, Sample::I8, Sample::U16, Sample::I16, Sample::U32, Sample::I32, Sample::U64, Sample::I64, Sample::F32, Sample::F64] {
            assert_eq!(Sample::parse(s.name()), Some(s));
        }
        assert_eq!(Sample::parse("short"), Some(Sample::I16));
        assert_eq!(Sample::parse("complex"), None);
    }
}
