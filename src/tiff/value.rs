//! TIFF field types and values, independent of byte order.
//!
//! Values are held decoded (native integers/floats), so an entry read from a big-endian file
//! can be written into a little-endian one unchanged in meaning.

use serde::Serialize;

/// TIFF 6.0 / BigTIFF field type codes used by DNG.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[repr(u16)]
pub enum FieldType {
    /// 1: unsigned 8-bit.
    Byte = 1,
    /// 2: NUL-terminated 7-bit ASCII.
    Ascii = 2,
    /// 3: unsigned 16-bit.
    Short = 3,
    /// 4: unsigned 32-bit.
    Long = 4,
    /// 5: two LONGs, numerator and denominator.
    Rational = 5,
    /// 6: signed 8-bit.
    SByte = 6,
    /// 7: opaque bytes.
    Undefined = 7,
    /// 8: signed 16-bit.
    SShort = 8,
    /// 9: signed 32-bit.
    SLong = 9,
    /// 10: two SLONGs.
    SRational = 10,
    /// 11: IEEE f32.
    Float = 11,
    /// 12: IEEE f64.
    Double = 12,
    /// 13: 32-bit IFD offset.
    Ifd = 13,
}

impl FieldType {
    /// Decode a type code; `None` for codes DNG never uses (BigTIFF 16-18, unknown).
    pub fn from_code(code: u16) -> Option<Self> {
        use FieldType::*;
        Some(match code {
            1 => Byte,
            2 => Ascii,
            3 => Short,
            4 => Long,
            5 => Rational,
            6 => SByte,
            7 => Undefined,
            8 => SShort,
            9 => SLong,
            10 => SRational,
            11 => Float,
            12 => Double,
            13 => Ifd,
            _ => return None,
        })
    }
    /// Size in bytes of one value of this type.
    pub fn size(self) -> usize {
        use FieldType::*;
        match self {
            Byte | Ascii | SByte | Undefined => 1,
            Short | SShort => 2,
            Long | SLong | Float | Ifd => 4,
            Rational | SRational | Double => 8,
        }
    }
}

/// A decoded field value (all elements of one entry).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Value {
    /// BYTE values.
    Byte(Vec<u8>),
    /// ASCII bytes, including any NUL terminator(s) as stored.
    Ascii(Vec<u8>),
    /// SHORT values.
    Short(Vec<u16>),
    /// LONG values.
    Long(Vec<u32>),
    /// RATIONAL values as (numerator, denominator).
    Rational(Vec<(u32, u32)>),
    /// SBYTE values.
    SByte(Vec<i8>),
    /// UNDEFINED bytes.
    Undefined(Vec<u8>),
    /// SSHORT values.
    SShort(Vec<i16>),
    /// SLONG values.
    SLong(Vec<i32>),
    /// SRATIONAL values as (numerator, denominator).
    SRational(Vec<(i32, i32)>),
    /// FLOAT values.
    Float(Vec<f32>),
    /// DOUBLE values.
    Double(Vec<f64>),
    /// IFD offsets.
    Ifd(Vec<u32>),
}

impl Value {
    /// The field type of this value.
    pub fn field_type(&self) -> FieldType {
        match self {
            Value::Byte(_) => FieldType::Byte,
            Value::Ascii(_) => FieldType::Ascii,
            Value::Short(_) => FieldType::Short,
            Value::Long(_) => FieldType::Long,
            Value::Rational(_) => FieldType::Rational,
            Value::SByte(_) => FieldType::SByte,
            Value::Undefined(_) => FieldType::Undefined,
            Value::SShort(_) => FieldType::SShort,
            Value::SLong(_) => FieldType::SLong,
            Value::SRational(_) => FieldType::SRational,
            Value::Float(_) => FieldType::Float,
            Value::Double(_) => FieldType::Double,
            Value::Ifd(_) => FieldType::Ifd,
        }
    }
    /// Number of elements (the TIFF "count").
    pub fn count(&self) -> usize {
        match self {
            Value::Byte(v) | Value::Ascii(v) | Value::Undefined(v) => v.len(),
            Value::Short(v) => v.len(),
            Value::Long(v) | Value::Ifd(v) => v.len(),
            Value::Rational(v) => v.len(),
            Value::SByte(v) => v.len(),
            Value::SShort(v) => v.len(),
            Value::SLong(v) => v.len(),
            Value::SRational(v) => v.len(),
            Value::Float(v) => v.len(),
            Value::Double(v) => v.len(),
        }
    }
    /// Encoded size in bytes.
    pub fn byte_len(&self) -> usize {
        self.count() * self.field_type().size()
    }
    /// Element `i` as f64 (rationals divided; a zero denominator gives `None`).
    pub fn get_f64(&self, i: usize) -> Option<f64> {
        match self {
            Value::Byte(v) | Value::Undefined(v) => v.get(i).map(|&x| x as f64),
            Value::Ascii(_) => None,
            Value::Short(v) => v.get(i).map(|&x| x as f64),
            Value::Long(v) | Value::Ifd(v) => v.get(i).map(|&x| x as f64),
            Value::Rational(v) => v
                .get(i)
                .and_then(|&(n, d)| (d != 0).then(|| n as f64 / d as f64)),
            Value::SByte(v) => v.get(i).map(|&x| x as f64),
            Value::SShort(v) => v.get(i).map(|&x| x as f64),
            Value::SLong(v) => v.get(i).map(|&x| x as f64),
            Value::SRational(v) => v
                .get(i)
                .and_then(|&(n, d)| (d != 0).then(|| n as f64 / d as f64)),
            Value::Float(v) => v.get(i).map(|&x| x as f64),
            Value::Double(v) => v.get(i).copied(),
        }
    }
    /// All elements as f64; `None` if any is not numeric or has a zero denominator.
    pub fn to_f64_vec(&self) -> Option<Vec<f64>> {
        (0..self.count()).map(|i| self.get_f64(i)).collect()
    }
    /// Element `i` as u32 if it is an unsigned integer type.
    pub fn get_u32(&self, i: usize) -> Option<u32> {
        match self {
            Value::Byte(v) | Value::Undefined(v) => v.get(i).map(|&x| x as u32),
            Value::Short(v) => v.get(i).map(|&x| x as u32),
            Value::Long(v) | Value::Ifd(v) => v.get(i).copied(),
            _ => None,
        }
    }
    /// All elements as u32 (unsigned integer types only).
    pub fn to_u32_vec(&self) -> Option<Vec<u32>> {
        (0..self.count()).map(|i| self.get_u32(i)).collect()
    }
    /// ASCII value as a string, cut at the first NUL, trailing spaces trimmed.
    pub fn as_string(&self) -> Option<String> {
        match self {
            Value::Ascii(b) => {
                let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
                Some(String::from_utf8_lossy(&b[..end]).trim_end().to_string())
            }
            _ => None,
        }
    }
    /// The raw bytes of BYTE/UNDEFINED/ASCII values.
    pub fn as_bytes(&self) -> Option<&[u8]> {
        match self {
            Value::Byte(b) | Value::Undefined(b) | Value::Ascii(b) => Some(b),
            _ => None,
        }
    }
    /// An ASCII value with one NUL terminator.
    pub fn ascii(s: &str) -> Self {
        let mut b = s.as_bytes().to_vec();
        b.push(0);
        Value::Ascii(b)
    }
    /// Encode an f64 as SRATIONAL with a fixed denominator (exact for typical matrix values
    /// to 1e-6); clamps to the representable range.
    pub fn srational_from_f64(values: &[f64]) -> Self {
        Value::SRational(values.iter().map(|&x| srational(x)).collect())
    }
    /// Encode non-negative f64 values as RATIONAL (clamped at 0).
    pub fn rational_from_f64(values: &[f64]) -> Self {
        Value::Rational(values.iter().map(|&x| rational(x)).collect())
    }
}

fn srational(x: f64) -> (i32, i32) {
    if !x.is_finite() {
        return (0, 1);
    }
    const DEN: f64 = 1_000_000.0;
    let n = (x * DEN).round();
    if n.abs() <= i32::MAX as f64 {
        (n as i32, DEN as i32)
    } else {
        let d = (i32::MAX as f64 / x.abs()).floor().max(1.0);
        (
            (x * d).round().clamp(i32::MIN as f64, i32::MAX as f64) as i32,
            d as i32,
        )
    }
}

fn rational(x: f64) -> (u32, u32) {
    if !x.is_finite() || x <= 0.0 {
        return (0, 1);
    }
    const DEN: f64 = 1_000_000.0;
    let n = (x * DEN).round();
    if n <= u32::MAX as f64 {
        (n as u32, DEN as u32)
    } else {
        let d = (u32::MAX as f64 / x).floor().max(1.0);
        ((x * d).round().min(u32::MAX as f64) as u32, d as u32)
    }
}

/// One IFD entry: a tag number and its decoded value.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Entry {
    /// Tag number.
    pub tag: u16,
    /// Decoded value.
    pub value: Value,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rationals_round_trip_typical_values() {
        for &x in &[0.0, 1.0, -0.5, 0.123456, 2.477, -1.5e3] {
            let v = Value::srational_from_f64(&[x]);
            assert!((v.get_f64(0).unwrap() - x).abs() < 1e-6, "{x}");
        }
        let big = Value::srational_from_f64(&[1e7]);
        assert!((big.get_f64(0).unwrap() - 1e7).abs() / 1e7 < 1e-6);
        assert_eq!(Value::rational_from_f64(&[-1.0]).get_f64(0), Some(0.0));
        assert_eq!(Value::srational_from_f64(&[f64::NAN]).get_f64(0), Some(0.0));
    }

    #[test]
    fn ascii_cut_at_nul() {
        assert_eq!(Value::ascii("Canon").as_string().as_deref(), Some("Canon"));
        assert_eq!(
            Value::Ascii(b"ab\0cd".to_vec()).as_string().as_deref(),
            Some("ab")
        );
    }
}
