//! Hand-written TIFF parser: byte order, IFD chains, SubIFD trees (tag 330) and the Exif IFD,
//! every entry decoded to a [`Value`] in native form.
//!
//! Hostile input is expected: every offset and count is checked with checked arithmetic, the
//! number of entries per IFD, the number of IFDs, the nesting depth and the total bytes of
//! decoded values are limited ([`Limits`]), and IFD offsets already visited are refused, so a
//! cyclic chain ends with an error instead of a loop.

use super::ByteOrder;
use crate::error::{Error, Result};
use crate::tiff::tags;
use crate::tiff::value::{Entry, FieldType, Value};
use std::collections::HashSet;

/// Limits applied while parsing untrusted TIFF files.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Most entries accepted in one IFD.
    pub max_entries_per_ifd: usize,
    /// Most IFDs (chain + SubIFDs + Exif) in one file.
    pub max_ifds: usize,
    /// Deepest SubIFD nesting.
    pub max_depth: usize,
    /// Most bytes of decoded entry values over the whole file.
    pub max_value_bytes: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_entries_per_ifd: 4096,
            max_ifds: 256,
            max_depth: 4,
            max_value_bytes: 256 << 20,
        }
    }
}

/// One parsed IFD with its child IFDs.
#[derive(Debug, Clone, PartialEq)]
pub struct Ifd {
    /// File offset of the IFD.
    pub offset: u32,
    /// Entries in file order (entries with an unknown field type are skipped).
    pub entries: Vec<Entry>,
    /// Entries whose value could not be read (tag, reason): e.g. an offset past the end.
    pub bad_entries: Vec<(u16, String)>,
    /// SubIFDs (tag 330), in order.
    pub sub_ifds: Vec<Ifd>,
    /// The Exif IFD (tag 34665), if any.
    pub exif: Option<Box<Ifd>>,
    /// The GPS IFD (tag 34853), if any.
    pub gps: Option<Box<Ifd>>,
}

impl Ifd {
    /// The value of `tag`, if present and readable.
    pub fn get(&self, tag: u16) -> Option<&Value> {
        self.entries.iter().find(|e| e.tag == tag).map(|e| &e.value)
    }
    /// True if the tag is present (readable or not).
    pub fn has(&self, tag: u16) -> bool {
        self.get(tag).is_some() || self.bad_entries.iter().any(|(t, _)| *t == tag)
    }
    /// The value of a required tag, or an error naming it (and why it was unreadable).
    pub fn require(&self, tag: u16) -> Result<&Value> {
        if let Some(v) = self.get(tag) {
            return Ok(v);
        }
        if let Some((_, why)) = self.bad_entries.iter().find(|(t, _)| *t == tag) {
            return Err(Error::malformed(format!(
                "{} (tag {}) is unreadable: {}",
                tags::tag_name(tag),
                tag,
                why
            )));
        }
        Err(Error::malformed(format!(
            "required tag {} ({}) is missing",
            tags::tag_name(tag),
            tag
        )))
    }
    /// First element of `tag` as u32 (unsigned integer types only).
    pub fn u32(&self, tag: u16) -> Option<u32> {
        self.get(tag).and_then(|v| v.get_u32(0))
    }
    /// First element of a required tag as u32.
    pub fn require_u32(&self, tag: u16) -> Result<u32> {
        self.require(tag)?.get_u32(0).ok_or_else(|| {
            Error::malformed(format!(
                "{} (tag {}) is not an unsigned integer",
                tags::tag_name(tag),
                tag
            ))
        })
    }
    /// ASCII tag as a string.
    pub fn string(&self, tag: u16) -> Option<String> {
        self.get(tag).and_then(|v| v.as_string())
    }
}

/// A parsed TIFF file: byte order and the IFD0 chain (IFD0, IFD1, ...).
#[derive(Debug, Clone, PartialEq)]
pub struct Tiff {
    /// Byte order.
    pub byte_order: ByteOrder,
    /// The main IFD chain; never empty.
    pub ifds: Vec<Ifd>,
}

impl Tiff {
    /// IFD0.
    pub fn ifd0(&self) -> &Ifd {
        // `parse` guarantees at least one IFD; fall back defensively anyway.
        &self.ifds[0]
    }
}

/// Parse a TIFF file with the default limits.
pub fn parse(bytes: &[u8]) -> Result<Tiff> {
    parse_with_limits(bytes, &Limits::default())
}

/// Byte-order aware reader over the whole file.
#[derive(Clone, Copy)]
pub struct Reader<'a> {
    /// The file bytes.
    pub bytes: &'a [u8],
    /// Byte order.
    pub order: ByteOrder,
}

impl<'a> Reader<'a> {
    /// `len` bytes at `off`, or an error.
    pub fn slice(&self, off: usize, len: usize) -> Result<&'a [u8]> {
        off.checked_add(len)
            .and_then(|end| self.bytes.get(off..end))
            .ok_or_else(|| {
                Error::malformed(format!(
                    "{} bytes at offset {} run past the end of the {}-byte file",
                    len,
                    off,
                    self.bytes.len()
                ))
            })
    }
    fn u16_at(&self, off: usize) -> Result<u16> {
        let b = self.slice(off, 2)?;
        Ok(self.u16(b))
    }
    fn u32_at(&self, off: usize) -> Result<u32> {
        let b = self.slice(off, 4)?;
        Ok(self.u32(b))
    }
    fn u16(&self, b: &[u8]) -> u16 {
        let a = [
            b.first().copied().unwrap_or(0),
            b.get(1).copied().unwrap_or(0),
        ];
        match self.order {
            ByteOrder::Little => u16::from_le_bytes(a),
            ByteOrder::Big => u16::from_be_bytes(a),
        }
    }
    fn u32(&self, b: &[u8]) -> u32 {
        let mut a = [0u8; 4];
        for (d, s) in a.iter_mut().zip(b) {
            *d = *s;
        }
        match self.order {
            ByteOrder::Little => u32::from_le_bytes(a),
            ByteOrder::Big => u32::from_be_bytes(a),
        }
    }
    fn u64(&self, b: &[u8]) -> u64 {
        let mut a = [0u8; 8];
        for (d, s) in a.iter_mut().zip(b) {
            *d = *s;
        }
        match self.order {
            ByteOrder::Little => u64::from_le_bytes(a),
            ByteOrder::Big => u64::from_be_bytes(a),
        }
    }
    /// Decode `count` values of type `ft` from `raw` (exactly `count * ft.size()` bytes).
    pub fn decode(&self, ft: FieldType, raw: &[u8]) -> Value {
        match ft {
            FieldType::Byte => Value::Byte(raw.to_vec()),
            FieldType::Ascii => Value::Ascii(raw.to_vec()),
            FieldType::Undefined => Value::Undefined(raw.to_vec()),
            FieldType::SByte => Value::SByte(raw.iter().map(|&b| b as i8).collect()),
            FieldType::Short => Value::Short(raw.chunks_exact(2).map(|c| self.u16(c)).collect()),
            FieldType::SShort => {
                Value::SShort(raw.chunks_exact(2).map(|c| self.u16(c) as i16).collect())
            }
            FieldType::Long => Value::Long(raw.chunks_exact(4).map(|c| self.u32(c)).collect()),
            FieldType::Ifd => Value::Ifd(raw.chunks_exact(4).map(|c| self.u32(c)).collect()),
            FieldType::SLong => {
                Value::SLong(raw.chunks_exact(4).map(|c| self.u32(c) as i32).collect())
            }
            FieldType::Float => Value::Float(
                raw.chunks_exact(4)
                    .map(|c| f32::from_bits(self.u32(c)))
                    .collect(),
            ),
            FieldType::Double => Value::Double(
                raw.chunks_exact(8)
                    .map(|c| f64::from_bits(self.u64(c)))
                    .collect(),
            ),
            FieldType::Rational => Value::Rational(
                raw.chunks_exact(8)
                    .map(|c| (self.u32(&c[..4]), self.u32(&c[4..])))
                    .collect(),
            ),
            FieldType::SRational => Value::SRational(
                raw.chunks_exact(8)
                    .map(|c| (self.u32(&c[..4]) as i32, self.u32(&c[4..]) as i32))
                    .collect(),
            ),
        }
    }
}

struct Parser<'a> {
    r: Reader<'a>,
    limits: Limits,
    visited: HashSet<u32>,
    ifd_count: usize,
    value_bytes: usize,
}

/// Parse a TIFF file with explicit limits.
pub fn parse_with_limits(bytes: &[u8], limits: &Limits) -> Result<Tiff> {
    let head = bytes.get(0..8).ok_or_else(|| {
        Error::malformed(format!(
            "file too short for a TIFF header ({} bytes)",
            bytes.len()
        ))
    })?;
    let order = match (head[0], head[1]) {
        (b'I', b'I') => ByteOrder::Little,
        (b'M', b'M') => ByteOrder::Big,
        _ => {
            return Err(Error::malformed(
                "not a TIFF file (no II/MM byte-order mark)",
            ))
        }
    };
    let r = Reader { bytes, order };
    let magic = r.u16(&head[2..4]);
    match magic {
        42 => {}
        43 => return Err(Error::unsupported("BigTIFF is not supported")),
        m => {
            return Err(Error::malformed(format!(
                "not a TIFF file (magic number {m}, expected 42)"
            )))
        }
    }
    let first = r.u32(&head[4..8]);
    let mut p = Parser {
        r,
        limits: *limits,
        visited: HashSet::new(),
        ifd_count: 0,
        value_bytes: 0,
    };
    let mut ifds = Vec::new();
    let mut next = first;
    if next == 0 {
        return Err(Error::malformed("TIFF header points to no IFD (offset 0)"));
    }
    while next != 0 {
        if ifds.len() >= p.limits.max_ifds {
            return Err(Error::limits(format!(
                "more than {} IFDs in the main chain",
                p.limits.max_ifds
            )));
        }
        match p.ifd(next, 0) {
            Ok((ifd, n)) => {
                ifds.push(ifd);
                next = n;
            }
            // A broken link after IFD0 (thumbnails, previews) does not hide the IFD0 we have.
            Err(e) if ifds.is_empty() => return Err(e),
            Err(_) => break,
        }
    }
    Ok(Tiff {
        byte_order: order,
        ifds,
    })
}

impl<'a> Parser<'a> {
    /// Parse the IFD at `off`; returns it and the offset of the next IFD in its chain.
    fn ifd(&mut self, off: u32, depth: usize) -> Result<(Ifd, u32)> {
        if depth > self.limits.max_depth {
            return Err(Error::limits(format!(
                "SubIFDs nested deeper than {}",
                self.limits.max_depth
            )));
        }
        if !self.visited.insert(off) {
            return Err(Error::malformed(format!(
                "IFD at offset {off} is referenced twice (cyclic IFD chain)"
            )));
        }
        self.ifd_count += 1;
        if self.ifd_count > self.limits.max_ifds {
            return Err(Error::limits(format!(
                "more than {} IFDs in the file",
                self.limits.max_ifds
            )));
        }
        let base = off as usize;
        let n = self.r.u16_at(base).map_err(|_| {
            Error::malformed(format!("IFD offset {off} is past the end of the file"))
        })? as usize;
        if n == 0 {
            return Err(Error::malformed(format!(
                "IFD at offset {off} has no entries"
            )));
        }
        let table = self.r.slice(base + 2, n * 12).map_err(|_| {
            Error::malformed(format!(
                "IFD at offset {off} with {n} entries runs past the end of the {}-byte file",
                self.r.bytes.len()
            ))
        })?;
        if n > self.limits.max_entries_per_ifd {
            return Err(Error::limits(format!(
                "IFD at offset {off} claims {n} entries (limit {})",
                self.limits.max_entries_per_ifd
            )));
        }
        let next = self.r.u32_at(base + 2 + n * 12).unwrap_or(0);
        let mut ifd = Ifd {
            offset: off,
            entries: Vec::with_capacity(n),
            bad_entries: Vec::new(),
            sub_ifds: Vec::new(),
            exif: None,
            gps: None,
        };
        for e in table.chunks_exact(12) {
            let tag = self.r.u16(&e[0..2]);
            let code = self.r.u16(&e[2..4]);
            let count = self.r.u32(&e[4..8]) as usize;
            let Some(ft) = FieldType::from_code(code) else {
                ifd.bad_entries
                    .push((tag, format!("unknown field type {code}")));
                continue;
            };
            let Some(len) = count.checked_mul(ft.size()) else {
                ifd.bad_entries
                    .push((tag, format!("count {count} overflows")));
                continue;
            };
            let raw = if len <= 4 {
                e.get(8..8 + len).unwrap_or(&[])
            } else {
                let voff = self.r.u32(&e[8..12]) as usize;
                match self.r.slice(voff, len) {
                    Ok(s) => s,
                    Err(_) => {
                        ifd.bad_entries.push((
                            tag,
                            format!(
                                "{count} values of type {code} at offset {voff} run past the end of the {}-byte file",
                                self.r.bytes.len()
                            ),
                        ));
                        continue;
                    }
                }
            };
            self.value_bytes = self.value_bytes.saturating_add(len);
            if self.value_bytes > self.limits.max_value_bytes {
                return Err(Error::limits(format!(
                    "entry values exceed {} bytes in total",
                    self.limits.max_value_bytes
                )));
            }
            ifd.entries.push(Entry {
                tag,
                value: self.r.decode(ft, raw),
            });
        }
        // Child IFDs.
        if let Some(v) = ifd.get(tags::SUB_IFDS) {
            let offs: Vec<u32> = v.to_u32_vec().unwrap_or_default();
            if offs.is_empty() {
                return Err(Error::malformed(format!(
                    "SubIFDs tag in IFD at offset {off} holds no offsets"
                )));
            }
            for o in offs {
                let (sub, _) = self
                    .ifd(o, depth + 1)
                    .map_err(|e| prefix(e, &format!("SubIFD at offset {o}")))?;
                ifd.sub_ifds.push(sub);
            }
        }
        if let Some(o) = ifd.u32(tags::EXIF_IFD) {
            // A broken Exif IFD loses the Exif fields, not the image.
            if let Ok((exif, _)) = self.ifd(o, depth + 1) {
                ifd.exif = Some(Box::new(exif));
            }
        }
        if let Some(o) = ifd.u32(tags::GPS_IFD) {
            // Likewise a broken GPS IFD loses the location only.
            if let Ok((gps, _)) = self.ifd(o, depth + 1) {
                ifd.gps = Some(Box::new(gps));
            }
        }
        Ok((ifd, next))
    }
}

fn prefix(e: Error, what: &str) -> Error {
    match e {
        Error::Malformed(m) => Error::Malformed(format!("{what}: {m}")),
        Error::Limits(m) => Error::Limits(format!("{what}: {m}")),
        Error::Unsupported(m) => Error::Unsupported(format!("{what}: {m}")),
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn le_tiff(entries: &[(u16, u16, u32, u32)], next: u32) -> Vec<u8> {
        let mut b = b"II*\0\x08\0\0\0".to_vec();
        b.extend_from_slice(&(entries.len() as u16).to_le_bytes());
        for &(t, ty, c, v) in entries {
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&ty.to_le_bytes());
            b.extend_from_slice(&c.to_le_bytes());
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&next.to_le_bytes());
        b
    }

    #[test]
    fn parses_inline_values_le() {
        let b = le_tiff(&[(256, 3, 1, 640), (257, 4, 1, 480)], 0);
        let t = parse(&b).unwrap();
        assert_eq!(t.byte_order, ByteOrder::Little);
        assert_eq!(t.ifd0().u32(256), Some(640));
        assert_eq!(t.ifd0().u32(257), Some(480));
    }

    #[test]
    fn gps_ifd_is_read_and_a_broken_one_is_ignored() {
        // IFD0 (8): 2 entries -> 8 + 2 + 24 + 4 = 38; GPS IFD at 38: GPSVersionID, GPSAltitudeRef.
        let mut b = le_tiff(&[(256, 3, 1, 7), (tags::GPS_IFD, 4, 1, 38)], 0);
        b.extend_from_slice(&2u16.to_le_bytes());
        for (t, ty, c, v) in [(0u16, 1u16, 4u32, 0x0000_0302u32), (5, 1, 1, 1)] {
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&ty.to_le_bytes());
            b.extend_from_slice(&c.to_le_bytes());
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&0u32.to_le_bytes());
        let t = parse(&b).unwrap();
        let gps = t.ifd0().gps.as_deref().expect("GPS IFD");
        assert_eq!(gps.get(0), Some(&Value::Byte(vec![2, 3, 0, 0])));
        assert_eq!(gps.get(5), Some(&Value::Byte(vec![1])));
        // pointer past the end, or back at IFD0 (a cycle): the image still parses
        for off in [10_000u32, 8] {
            let b = le_tiff(&[(256, 3, 1, 7), (tags::GPS_IFD, 4, 1, off)], 0);
            let t = parse(&b).unwrap();
            assert_eq!(t.ifd0().u32(256), Some(7), "offset {off}");
        }
    }

    #[test]
    fn cyclic_chain_is_cut() {
        // next IFD points back to IFD0: the chain ends after IFD0 (no loop).
        let b = le_tiff(&[(256, 3, 1, 1)], 8);
        let t = parse(&b).unwrap();
        assert_eq!(t.ifds.len(), 1);
    }

    #[test]
    fn cyclic_subifd_is_an_error() {
        let b = le_tiff(&[(330, 4, 1, 8)], 0);
        let e = parse(&b).unwrap_err();
        assert!(e.to_string().contains("cyclic"), "{e}");
    }

    #[test]
    fn huge_entry_count_is_refused() {
        let mut b = b"II*\0\x08\0\0\0".to_vec();
        b.extend_from_slice(&0xffffu16.to_le_bytes());
        b.resize(8 + 2 + 0xffff * 12, 0);
        let e = parse(&b).unwrap_err();
        assert!(matches!(e, Error::Limits(_)), "{e}");
    }

    #[test]
    fn out_of_range_value_is_recorded() {
        let b = le_tiff(&[(273, 4, 100, 1_000_000)], 0);
        let t = parse(&b).unwrap();
        assert!(t.ifd0().get(273).is_none());
        assert!(t
            .ifd0()
            .require(273)
            .unwrap_err()
            .to_string()
            .contains("past the end"));
    }

    #[test]
    fn big_endian_values() {
        let mut b = b"MM\0*\0\0\0\x08".to_vec();
        b.extend_from_slice(&1u16.to_be_bytes());
        b.extend_from_slice(&256u16.to_be_bytes());
        b.extend_from_slice(&3u16.to_be_bytes());
        b.extend_from_slice(&1u32.to_be_bytes());
        b.extend_from_slice(&[0x12, 0x34, 0, 0]);
        b.extend_from_slice(&0u32.to_be_bytes());
        let t = parse(&b).unwrap();
        assert_eq!(t.ifd0().u32(256), Some(0x1234));
    }
}
