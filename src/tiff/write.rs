//! TIFF writer: an IFD tree builder with a deterministic, aligned layout.
//!
//! Layout of an encoded file:
//!
//! ```text
//! header (8 bytes) | IFD0 directory, IFD0 out-of-line values | IFD0's child IFDs (SubIFDs,
//! Exif, ...) in pre-order, each directory followed by its values | next IFD of the chain ...
//! | image data chunks (strips or tiles) of every IFD, in IFD order
//! ```
//!
//! Guarantees: entries of every IFD sorted by tag and unique; every IFD, every out-of-line
//! value and every strip/tile starts at an even offset; offsets are LONG (32-bit, so a file is
//! at most 4 GiB); pointer tags (SubIFDs, ExifIFD, ...) and StripOffsets/TileOffsets are
//! filled in by the writer, so a caller can never write stale offsets. Strips of even length
//! are contiguous (no padding between them), which old dcraw-style readers rely on.

use super::ByteOrder;
use crate::error::{Error, Result};
use crate::tiff::tags;
use crate::tiff::value::Value;
use std::collections::BTreeMap;

/// Strips or tiles of an image IFD.
#[derive(Debug, Clone, PartialEq)]
pub enum Chunks {
    /// Strips: written as StripOffsets (273) / StripByteCounts (279).
    Strips(Vec<Vec<u8>>),
    /// Tiles: written as TileOffsets (324) / TileByteCounts (325).
    Tiles(Vec<Vec<u8>>),
    /// Strips of these byte counts whose bytes the caller of [`write_tiff_head`] writes
    /// after the head, in order, at the offsets it returns (they must be the file's last
    /// chunks).
    StreamedStrips(Vec<u32>),
}

impl Chunks {
    /// The (offsets, byte counts) tags.
    fn tags(&self) -> (u16, u16) {
        match self {
            Chunks::Strips(_) | Chunks::StreamedStrips(_) => {
                (tags::STRIP_OFFSETS, tags::STRIP_BYTE_COUNTS)
            }
            Chunks::Tiles(_) => (tags::TILE_OFFSETS, tags::TILE_BYTE_COUNTS),
        }
    }
    /// The byte count of every chunk.
    fn lens(&self) -> Vec<u64> {
        match self {
            Chunks::Strips(c) | Chunks::Tiles(c) => c.iter().map(|c| c.len() as u64).collect(),
            Chunks::StreamedStrips(l) => l.iter().map(|&l| l as u64).collect(),
        }
    }
}

/// What [`write_tiff_head`] leaves to its caller: where the streamed strips go, and where
/// IFD0's out-of-line values are (to patch one in place once the data it depends on has
/// been written).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tail {
    ifd0_values: BTreeMap<u16, u64>,
    /// (offset, byte count) of each streamed strip, in file order.
    pub strips: Vec<(u64, u64)>,
    /// Bytes written so far (the head and every chunk before the streamed strips).
    pub written: u64,
    /// Length of the whole file (the last strip plus its alignment padding).
    pub end: u64,
}

impl Tail {
    /// File offset of the value of `tag` of IFD0, if it is stored out of line.
    pub fn ifd0_value_offset(&self, tag: u16) -> Option<u64> {
        self.ifd0_values.get(&tag).copied()
    }
}

/// One IFD to write: its entries, child IFDs behind pointer tags, and image data.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Ifd {
    entries: BTreeMap<u16, Value>,
    children: BTreeMap<u16, Vec<Ifd>>,
    chunks: Option<Chunks>,
}

/// Tags whose values the writer computes itself (offsets and pointers).
fn is_writer_managed(tag: u16, children: &BTreeMap<u16, Vec<Ifd>>) -> bool {
    matches!(
        tag,
        tags::STRIP_OFFSETS | tags::STRIP_BYTE_COUNTS | tags::TILE_OFFSETS | tags::TILE_BYTE_COUNTS
    ) || children.contains_key(&tag)
}

impl Ifd {
    /// An empty IFD.
    pub fn new() -> Ifd {
        Ifd::default()
    }
    /// Set (or replace) an entry.
    pub fn set(&mut self, tag: u16, value: Value) {
        self.entries.insert(tag, value);
    }
    /// Set an entry unless the tag is already present.
    pub fn set_if_absent(&mut self, tag: u16, value: Value) {
        self.entries.entry(tag).or_insert(value);
    }
    /// Remove an entry.
    pub fn remove(&mut self, tag: u16) -> Option<Value> {
        self.entries.remove(&tag)
    }
    /// The value of an entry.
    pub fn get(&self, tag: u16) -> Option<&Value> {
        self.entries.get(&tag)
    }
    /// Tags of the entries set so far (sorted).
    pub fn tags(&self) -> impl Iterator<Item = u16> + '_ {
        self.entries.keys().copied()
    }
    /// Attach child IFDs behind a pointer tag (330 SubIFDs, 34665 ExifIFD, 34853 GPS ...).
    /// The tag is written as LONG offsets.
    pub fn set_children(&mut self, tag: u16, ifds: Vec<Ifd>) {
        self.entries.remove(&tag);
        if ifds.is_empty() {
            self.children.remove(&tag);
        } else {
            self.children.insert(tag, ifds);
        }
    }
    /// Image data of this IFD.
    pub fn set_chunks(&mut self, chunks: Chunks) {
        self.chunks = Some(chunks);
    }
}

fn align2(x: u64) -> u64 {
    (x + 1) & !1
}

/// Byte-order aware buffer writer.
struct Out {
    buf: Vec<u8>,
    big: bool,
}

impl Out {
    fn u16(&mut self, v: u16) {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.buf.extend_from_slice(&b);
    }
    fn u32(&mut self, v: u32) {
        let b = if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.buf.extend_from_slice(&b);
    }
    fn pad_to(&mut self, pos: u64) {
        // Positions are computed by the layout pass; they never go backwards.
        let pos = pos as usize;
        if self.buf.len() < pos {
            self.buf.resize(pos, 0);
        }
    }
}

/// Encode a value's elements in the given byte order.
pub fn encode_value(v: &Value, order: ByteOrder) -> Vec<u8> {
    let mut o = Out {
        buf: Vec::with_capacity(v.byte_len()),
        big: order == ByteOrder::Big,
    };
    match v {
        Value::Byte(b) | Value::Ascii(b) | Value::Undefined(b) => o.buf.extend_from_slice(b),
        Value::SByte(b) => o.buf.extend(b.iter().map(|&x| x as u8)),
        Value::Short(s) => s.iter().for_each(|&x| o.u16(x)),
        Value::SShort(s) => s.iter().for_each(|&x| o.u16(x as u16)),
        Value::Long(s) | Value::Ifd(s) => s.iter().for_each(|&x| o.u32(x)),
        Value::SLong(s) => s.iter().for_each(|&x| o.u32(x as u32)),
        Value::Rational(s) => s.iter().for_each(|&(n, d)| {
            o.u32(n);
            o.u32(d)
        }),
        Value::SRational(s) => s.iter().for_each(|&(n, d)| {
            o.u32(n as u32);
            o.u32(d as u32)
        }),
        Value::Float(s) => s.iter().for_each(|&x| o.u32(x.to_bits())),
        Value::Double(s) => s.iter().for_each(|&x| {
            let b = if o.big {
                x.to_bits().to_be_bytes()
            } else {
                x.to_bits().to_le_bytes()
            };
            o.buf.extend_from_slice(&b)
        }),
    }
    o.buf
}

/// A flattened IFD with its final entry list.
struct Node<'a> {
    ifd: &'a Ifd,
    /// Final entries (tag, value); pointer and offset values hold placeholders until filled.
    entries: Vec<(u16, Value)>,
    /// Node indices of children per pointer tag.
    child_nodes: Vec<(u16, Vec<usize>)>,
    /// Next IFD in the chain (node index).
    next: Option<usize>,
    dir_offset: u64,
    value_offsets: Vec<u64>,
    chunk_offsets: Vec<u64>,
}

fn flatten<'a>(ifd: &'a Ifd, nodes: &mut Vec<Node<'a>>) -> Result<usize> {
    if nodes.len() > 10_000 {
        return Err(Error::limits("too many IFDs to write"));
    }
    let idx = nodes.len();
    nodes.push(Node {
        ifd,
        entries: vec![],
        child_nodes: vec![],
        next: None,
        dir_offset: 0,
        value_offsets: vec![],
        chunk_offsets: vec![],
    });
    let mut child_nodes = vec![];
    for (&tag, kids) in &ifd.children {
        let mut ids = vec![];
        for k in kids {
            ids.push(flatten(k, nodes)?);
        }
        child_nodes.push((tag, ids));
    }
    if let Some(n) = nodes.get_mut(idx) {
        n.child_nodes = child_nodes;
    }
    Ok(idx)
}

/// Encode a TIFF file whose IFD chain is `chain` (IFD0, IFD1, ...) into memory.
pub fn encode_tiff(order: ByteOrder, chain: &[Ifd]) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    write_tiff(order, chain, &mut out)?;
    Ok(out)
}

/// Write a TIFF file whose IFD chain is `chain` to `sink`: the directories and values are
/// assembled in memory, the (large) strips and tiles are streamed straight from the IFDs.
pub fn write_tiff<W: std::io::Write>(order: ByteOrder, chain: &[Ifd], sink: &mut W) -> Result<()> {
    let tail = write_tiff_head(order, chain, sink)?;
    if !tail.strips.is_empty() {
        return Err(Error::invalid(
            "streamed strips are written by the caller of write_tiff_head",
        ));
    }
    Ok(())
}

/// [`write_tiff`] up to the [`Chunks::StreamedStrips`] (if any): the head and every chunk
/// before them. The caller writes the strips at the returned offsets (zero padding between
/// them), pads the file to [`Tail::end`], and may patch IFD0 values.
pub fn write_tiff_head<W: std::io::Write>(
    order: ByteOrder,
    chain: &[Ifd],
    sink: &mut W,
) -> Result<Tail> {
    if chain.is_empty() {
        return Err(Error::invalid("a TIFF file needs at least one IFD"));
    }
    let mut nodes: Vec<Node> = vec![];
    let mut prev: Option<usize> = None;
    for ifd in chain {
        let idx = flatten(ifd, &mut nodes)?;
        if let Some(p) = prev {
            nodes[p].next = Some(idx);
        }
        prev = Some(idx);
    }

    final_entries(&mut nodes)?;
    let cursor = layout(&mut nodes)?;
    fill_pointers(&mut nodes);
    // Serialize the directories and values (everything before the first chunk).
    let head_len = nodes
        .iter()
        .filter_map(|n| n.chunk_offsets.first())
        .min()
        .copied()
        .unwrap_or(cursor);
    let head = serialize_head(&nodes, order, head_len);
    sink.write_all(&head)?;
    let mut tail = Tail {
        ifd0_values: nodes[0]
            .entries
            .iter()
            .zip(&nodes[0].value_offsets)
            .filter(|(_, &off)| off != 0)
            .map(|((tag, _), &off)| (*tag, off))
            .collect(),
        strips: vec![],
        written: head_len,
        end: cursor,
    };
    // Stream the chunks, with their alignment padding.
    let mut pos = head_len;
    for n in &nodes {
        let Some(ch) = &n.ifd.chunks else { continue };
        for (i, (len, &off)) in ch.lens().into_iter().zip(&n.chunk_offsets).enumerate() {
            match ch {
                Chunks::StreamedStrips(_) => tail.strips.push((off, len)),
                Chunks::Strips(c) | Chunks::Tiles(c) => {
                    if !tail.strips.is_empty() {
                        return Err(Error::invalid(
                            "streamed strips must be the last chunks of a file",
                        ));
                    }
                    if off > pos {
                        sink.write_all(&vec![0u8; (off - pos) as usize])?;
                    }
                    sink.write_all(&c[i])?;
                    pos = off + len;
                }
            }
        }
    }
    if tail.strips.is_empty() && cursor > pos {
        sink.write_all(&vec![0u8; (cursor - pos) as usize])?;
        pos = cursor;
    }
    tail.written = pos;
    Ok(tail)
}

/// Each node's final entry list, with placeholders for the offsets (their sizes are
/// already final).
fn final_entries(nodes: &mut [Node]) -> Result<()> {
    for n in nodes.iter_mut() {
        let mut entries: BTreeMap<u16, Value> = n
            .ifd
            .entries
            .iter()
            .filter(|(t, _)| !is_writer_managed(**t, &n.ifd.children))
            .map(|(t, v)| (*t, v.clone()))
            .collect();
        for (tag, ids) in &n.child_nodes {
            entries.insert(*tag, Value::Long(vec![0; ids.len()]));
        }
        if let Some(ch) = &n.ifd.chunks {
            let (off_tag, cnt_tag) = ch.tags();
            let lens = ch.lens();
            entries.insert(off_tag, Value::Long(vec![0; lens.len()]));
            let mut counts = Vec::with_capacity(lens.len());
            for &len in &lens {
                counts.push(
                    u32::try_from(len)
                        .map_err(|_| Error::limits("strip or tile larger than 4 GiB"))?,
                );
            }
            entries.insert(cnt_tag, Value::Long(counts));
        }
        if entries.len() > u16::MAX as usize {
            return Err(Error::limits("too many entries in one IFD"));
        }
        n.entries = entries.into_iter().collect();
    }

    Ok(())
}

/// Place every directory, value and chunk: each node's offsets; the file's length.
fn layout(nodes: &mut [Node]) -> Result<u64> {
    let mut cursor: u64 = 8;
    for n in nodes.iter_mut() {
        cursor = align2(cursor);
        n.dir_offset = cursor;
        cursor += 2 + 12 * n.entries.len() as u64 + 4;
        n.value_offsets = Vec::with_capacity(n.entries.len());
        for (_, v) in &n.entries {
            let len = v.byte_len() as u64;
            if len > 4 {
                cursor = align2(cursor);
                n.value_offsets.push(cursor);
                cursor += len;
            } else {
                n.value_offsets.push(0);
            }
        }
    }
    for n in nodes.iter_mut() {
        if let Some(ch) = &n.ifd.chunks {
            for len in ch.lens() {
                cursor = align2(cursor);
                n.chunk_offsets.push(cursor);
                cursor += len;
            }
        }
    }
    if cursor > u32::MAX as u64 {
        return Err(Error::limits(format!(
            "output of {cursor} bytes exceeds the 4 GiB TIFF limit"
        )));
    }

    Ok(cursor)
}

/// Fill in the SubIFD pointers and the chunk offsets of every node.
fn fill_pointers(nodes: &mut [Node]) {
    let dir_offsets: Vec<u64> = nodes.iter().map(|n| n.dir_offset).collect();
    for n in nodes.iter_mut() {
        let child_vals: Vec<(u16, Vec<u32>)> = n
            .child_nodes
            .iter()
            .map(|(t, ids)| (*t, ids.iter().map(|&i| dir_offsets[i] as u32).collect()))
            .collect();
        let chunk_tag = n.ifd.chunks.as_ref().map(|c| c.tags().0);
        let chunk_vals: Vec<u32> = n.chunk_offsets.iter().map(|&o| o as u32).collect();
        for (tag, v) in n.entries.iter_mut() {
            if let Some((_, offs)) = child_vals.iter().find(|(t, _)| t == tag) {
                *v = Value::Long(offs.clone());
            } else if Some(*tag) == chunk_tag {
                *v = Value::Long(chunk_vals.clone());
            }
        }
    }
}

/// The bytes of the directories and values: everything before the first chunk at
/// `head_len`.
fn serialize_head(nodes: &[Node], order: ByteOrder, head_len: u64) -> Vec<u8> {
    let dir_offsets: Vec<u64> = nodes.iter().map(|n| n.dir_offset).collect();
    let big = order == ByteOrder::Big;
    let mut o = Out {
        buf: Vec::with_capacity(head_len as usize),
        big,
    };
    o.buf.extend_from_slice(if big { b"MM" } else { b"II" });
    o.u16(42);
    o.u32(nodes[0].dir_offset as u32);
    for n in nodes {
        o.pad_to(n.dir_offset);
        o.u16(n.entries.len() as u16);
        for ((tag, v), &voff) in n.entries.iter().zip(&n.value_offsets) {
            o.u16(*tag);
            o.u16(v.field_type() as u16);
            o.u32(v.count() as u32);
            let bytes = encode_value(v, order);
            if bytes.len() > 4 {
                o.u32(voff as u32);
            } else {
                let mut inline = [0u8; 4];
                inline[..bytes.len()].copy_from_slice(&bytes);
                o.buf.extend_from_slice(&inline);
            }
        }
        o.u32(n.next.map(|i| dir_offsets[i] as u32).unwrap_or(0));
        for ((_, v), &voff) in n.entries.iter().zip(&n.value_offsets) {
            if voff != 0 {
                o.pad_to(voff);
                o.buf.extend_from_slice(&encode_value(v, order));
            }
        }
    }
    o.pad_to(head_len);
    o.buf
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rd16(b: &[u8], at: usize, big: bool) -> u16 {
        let a = [b[at], b[at + 1]];
        if big {
            u16::from_be_bytes(a)
        } else {
            u16::from_le_bytes(a)
        }
    }
    fn rd32(b: &[u8], at: usize, big: bool) -> u32 {
        let a = [b[at], b[at + 1], b[at + 2], b[at + 3]];
        if big {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        }
    }

    /// Walk one IFD: returns (tag, type, count, value-or-offset) rows and the next offset.
    fn walk(b: &[u8], off: usize, big: bool) -> (Vec<(u16, u16, u32, u32)>, u32) {
        let n = rd16(b, off, big) as usize;
        let rows = (0..n)
            .map(|i| {
                let e = off + 2 + 12 * i;
                (
                    rd16(b, e, big),
                    rd16(b, e + 2, big),
                    rd32(b, e + 4, big),
                    rd32(b, e + 8, big),
                )
            })
            .collect();
        (rows, rd32(b, off + 2 + 12 * n, big))
    }

    #[test]
    fn sorted_aligned_offsets_and_children() {
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let big = order == ByteOrder::Big;
            let mut exif = Ifd::new();
            exif.set(tags::EXPOSURE_TIME, Value::Rational(vec![(1, 60)]));
            let mut sub = Ifd::new();
            sub.set(tags::NEW_SUBFILE_TYPE, Value::Long(vec![0]));
            sub.set_chunks(Chunks::Tiles(vec![vec![1, 2, 3], vec![4, 5, 6, 7]]));
            let mut ifd0 = Ifd::new();
            ifd0.set(tags::SOFTWARE, Value::ascii("abc")); // 4 bytes: inline
            ifd0.set(tags::MAKE, Value::ascii("odd")); // 4 bytes
            ifd0.set(tags::MODEL, Value::ascii("x")); // 2 bytes
            ifd0.set(tags::UNIQUE_CAMERA_MODEL, Value::ascii("four5")); // 6: out of line
            ifd0.set(tags::IMAGE_WIDTH, Value::Long(vec![3]));
            ifd0.set(tags::STRIP_OFFSETS, Value::Long(vec![12345])); // overridden
            ifd0.set_children(tags::SUB_IFDS, vec![sub]);
            ifd0.set_children(tags::EXIF_IFD, vec![exif]);
            ifd0.set_chunks(Chunks::Strips(vec![vec![9; 5], vec![8; 6]]));
            let mut ifd1 = Ifd::new();
            ifd1.set(tags::NEW_SUBFILE_TYPE, Value::Long(vec![1]));
            let b = encode_tiff(order, &[ifd0, ifd1]).unwrap();
            assert_eq!(&b[..2], if big { b"MM" } else { b"II" });
            assert_eq!(rd16(&b, 2, big), 42);
            let off0 = rd32(&b, 4, big) as usize;
            let (rows, next) = walk(&b, off0, big);
            let tags_: Vec<u16> = rows.iter().map(|r| r.0).collect();
            let mut sorted = tags_.clone();
            sorted.sort();
            sorted.dedup();
            assert_eq!(tags_, sorted);
            for r in &rows {
                let size = crate::tiff::value::FieldType::from_code(r.1)
                    .unwrap()
                    .size();
                if size * r.2 as usize > 4 {
                    assert_eq!(r.3 % 2, 0, "tag {} value at odd offset", r.0);
                }
            }
            // Strips: offsets even, data right.
            let so = rows.iter().find(|r| r.0 == tags::STRIP_OFFSETS).unwrap();
            let sc = rows
                .iter()
                .find(|r| r.0 == tags::STRIP_BYTE_COUNTS)
                .unwrap();
            assert_eq!((so.2, sc.2), (2, 2));
            let o1 = rd32(&b, so.3 as usize, big) as usize;
            let o2 = rd32(&b, so.3 as usize + 4, big) as usize;
            assert_eq!(o1 % 2, 0);
            assert_eq!(o2 % 2, 0);
            assert_eq!(&b[o1..o1 + 5], &[9; 5]);
            assert_eq!(&b[o2..o2 + 6], &[8; 6]);
            // UniqueCameraModel out of line.
            let ucm = rows
                .iter()
                .find(|r| r.0 == tags::UNIQUE_CAMERA_MODEL)
                .unwrap();
            assert_eq!(&b[ucm.3 as usize..ucm.3 as usize + 6], b"four5\0");
            // SubIFD with tiles.
            let s = rows.iter().find(|r| r.0 == tags::SUB_IFDS).unwrap();
            assert_eq!((s.1, s.2), (4, 1));
            assert_eq!(s.3 % 2, 0);
            let (srows, snext) = walk(&b, s.3 as usize, big);
            assert_eq!(snext, 0);
            let to = srows.iter().find(|r| r.0 == tags::TILE_OFFSETS).unwrap();
            let t2 = rd32(&b, to.3 as usize + 4, big) as usize;
            assert_eq!(t2 % 2, 0);
            assert_eq!(&b[t2..t2 + 4], &[4, 5, 6, 7]);
            // Exif.
            let e = rows.iter().find(|r| r.0 == tags::EXIF_IFD).unwrap();
            let (erows, _) = walk(&b, e.3 as usize, big);
            assert_eq!(erows.len(), 1);
            let r = erows[0].3 as usize;
            assert_eq!((rd32(&b, r, big), rd32(&b, r + 4, big)), (1, 60));
            // Chain.
            assert_ne!(next, 0);
            let (rows1, next1) = walk(&b, next as usize, big);
            assert_eq!(next1, 0);
            assert_eq!(rows1, vec![(tags::NEW_SUBFILE_TYPE, 4, 1, 1)]);
        }
    }

    #[test]
    fn even_strips_are_contiguous_and_output_deterministic() {
        let mut ifd = Ifd::new();
        ifd.set(tags::IMAGE_WIDTH, Value::Short(vec![2]));
        ifd.set_chunks(Chunks::Strips(vec![vec![1; 4], vec![2; 4], vec![3; 2]]));
        let a = encode_tiff(ByteOrder::Little, std::slice::from_ref(&ifd)).unwrap();
        let b = encode_tiff(ByteOrder::Little, &[ifd]).unwrap();
        assert_eq!(a, b);
        let n = a.len();
        assert_eq!(&a[n - 10..], &[1, 1, 1, 1, 2, 2, 2, 2, 3, 3]);
    }

    #[test]
    fn empty_chain_is_an_error() {
        assert!(encode_tiff(ByteOrder::Little, &[]).is_err());
    }
}
