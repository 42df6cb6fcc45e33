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
    /// Decodes `bytes` (exactly `out.len()` samples) into `out`.
    pub fn decode(&self, bytes: &[u8], out: &mut [f32]) {
        debug_assert_eq!(bytes.len(), out.len() * self.sample.size());
        let plain = self.slope == 1.0 && self.intercept == 0.0;
        let (s, b) = (self.slope, self.intercept);
        macro_rules! run {
            ($t:ty, $n:expr) => {{
                for (o, c) in out.iter_mut().zip(bytes.chunks_exact($n)) {
                    let a: [u8; $n] = c.try_into().unwrap();
                    let v = if self.big_endian { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) };
                    *o = if plain { v as f32 } else { (v as f64 * s + b) as f32 };
                }
            }};
        }
        match self.sample {
            Sample::U8 => {
                for (o, &v) in out.iter_mut().zip(bytes) {
                    *o = if plain { v as f32 } else { (v as f64 * s + b) as f32 };
                }
            }
            Sample::I8 => run!(i8, 1),
            Sample::U16 => run!(u16, 2),
            Sample::I16 => run!(i16, 2),
            Sample::U32 => run!(u32, 4),
            Sample::I32 => run!(i32, 4),
            Sample::U64 => run!(u64, 8),
            Sample::I64 => run!(i64, 8),
            Sample::F32 => run!(f32, 4),
            Sample::F64 => run!(f64, 8),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_byte_orders_and_the_rescale() {
        let d = Decoder { sample: Sample::I16, big_endian: false, slope: 1.0, intercept: 0.0 };
        let mut out = [0.0f32; 2];
        d.decode(&[0x01, 0x00, 0xff, 0xff], &mut out);
        assert_eq!(out, [1.0, -1.0]);
        let d = Decoder { sample: Sample::U16, big_endian: true, slope: 2.0, intercept: -1024.0 };
        d.decode(&[0x01, 0x00, 0x00, 0x02], &mut out);
        assert_eq!(out, [-512.0, -1020.0]);
        let d = Decoder { sample: Sample::F64, big_endian: false, slope: 1.0, intercept: 0.0 };
        let mut one = [0.0f32];
        d.decode(&0.5f64.to_le_bytes(), &mut one);
        assert_eq!(one, [0.5]);
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
