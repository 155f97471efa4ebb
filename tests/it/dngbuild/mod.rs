//! A tiny, independent DNG builder for reader tests: any byte order, bit depth (packed
//! MSB-first for 9..15 bits), strips or tiles, uncompressed or lossless JPEG (1 component or
//! the 2-component half-width layout), raw in IFD0 or in a SubIFD behind a preview, and
//! arbitrary tag overrides. Written from the TIFF/DNG specs, not from the library's writer.
#![allow(dead_code)]

use day2night::tiff::value::Value;

#[derive(Clone, Copy, Debug)]
pub enum Pixels {
    Strips {
        rows: usize,
    },
    Tiles {
        w: usize,
        h: usize,
    },
    LjpegTiles {
        w: usize,
        h: usize,
        two_components: bool,
    },
    LjpegStrips {
        rows: usize,
    },
}

#[derive(Clone, Debug)]
pub struct Builder {
    pub big_endian: bool,
    pub width: usize,
    pub height: usize,
    pub bits: u16,
    pub pixels: Vec<u16>,
    pub layout: Pixels,
    pub raw_in_sub: bool,
    pub overrides: Vec<(u16, Value)>,
    pub remove: Vec<u16>,
    pub exif: Vec<(u16, Value)>,
    /// Applied last to IFD0 when the raw is in a SubIFD (e.g. to make the preview NSFT 0).
    pub ifd0_set: Vec<(u16, Value)>,
}

impl Builder {
    /// A w x h RGGB image with a deterministic pattern at `bits` bits.
    pub fn new(width: usize, height: usize, bits: u16) -> Self {
        let max = (1u32 << bits) - 1;
        let pixels = (0..width * height)
            .map(|i| {
                let (r, c) = (i / width, i % width);
                ((r as u32 * 131 + c as u32 * 17 + (r * c) as u32 % 97) % (max + 1)) as u16
            })
            .collect();
        Builder {
            big_endian: false,
            width,
            height,
            bits,
            pixels,
            layout: Pixels::Strips { rows: 3 },
            raw_in_sub: false,
            overrides: vec![],
            remove: vec![],
            exif: vec![],
            ifd0_set: vec![],
        }
    }
    pub fn set(mut self, tag: u16, v: Value) -> Self {
        self.overrides.retain(|(t, _)| *t != tag);
        self.overrides.push((tag, v));
        self
    }
    /// Attach the bytes of OpcodeList`n` (1, 2 or 3; e.g. from
    /// `day2night::dng::opcodes::encode_list`) to the raw IFD, and declare DNG backward
    /// version 1.3 (the version that introduced opcode lists).
    pub fn opcode_list(self, n: u8, bytes: Vec<u8>) -> Self {
        let tag = match n {
            1 => 51008,
            2 => 51009,
            3 => 51022,
            _ => panic!("OpcodeList{n} does not exist"),
        };
        self.set(tag, Value::Undefined(bytes))
            .set(50707, Value::Byte(vec![1, 3, 0, 0]))
    }
    pub fn without(mut self, tag: u16) -> Self {
        self.remove.push(tag);
        self
    }

    fn raw_tags(&self) -> Vec<(u16, Value)> {
        let white = (1u32 << self.bits) - 1;
        let mut t = vec![
            (254, Value::Long(vec![0])),
            (256, Value::Long(vec![self.width as u32])),
            (257, Value::Long(vec![self.height as u32])),
            (258, Value::Short(vec![self.bits])),
            (262, Value::Short(vec![32803])),
            (277, Value::Short(vec![1])),
            (284, Value::Short(vec![1])),
            (33421, Value::Short(vec![2, 2])),
            (33422, Value::Byte(vec![0, 1, 1, 2])),
            (50710, Value::Byte(vec![0, 1, 2])),
            (50711, Value::Short(vec![1])),
            (50714, Value::Long(vec![0])),
            (50717, Value::Long(vec![white])),
        ];
        let comp = match self.layout {
            Pixels::Strips { .. } | Pixels::Tiles { .. } => 1,
            _ => 7,
        };
        t.push((259, Value::Short(vec![comp])));
        t
    }

    fn ifd0_tags(&self) -> Vec<(u16, Value)> {
        vec![
            (271, Value::ascii("TestMake")),
            (272, Value::ascii("TestModel")),
            (274, Value::Short(vec![1])),
            (50706, Value::Byte(vec![1, 4, 0, 0])),
            (50707, Value::Byte(vec![1, 1, 0, 0])),
            (50708, Value::ascii("TestMake TestModel")),
            (
                50721,
                Value::SRational(vec![
                    (10000, 10000),
                    (0, 1),
                    (0, 1),
                    (0, 1),
                    (10000, 10000),
                    (0, 1),
                    (0, 1),
                    (0, 1),
                    (10000, 10000),
                ]),
            ),
            (50778, Value::Short(vec![21])),
            (50728, Value::Rational(vec![(1, 2), (1, 1), (3, 5)])),
        ]
    }

    /// Encode the whole file.
    pub fn build(&self) -> Vec<u8> {
        let mut f = Out {
            buf: vec![0; 8],
            big: self.big_endian,
        };
        if self.big_endian {
            f.buf[0..4].copy_from_slice(b"MM\0*");
        } else {
            f.buf[0..4].copy_from_slice(b"II*\0");
        }
        // Pixel blocks.
        let (blocks, mut geom) = self.encode_blocks();
        let mut offs = Vec::new();
        let mut counts = Vec::new();
        for b in &blocks {
            f.align();
            offs.push(f.buf.len() as u32);
            counts.push(b.len() as u32);
            f.buf.extend_from_slice(b);
        }
        let tiled = matches!(
            self.layout,
            Pixels::Tiles { .. } | Pixels::LjpegTiles { .. }
        );
        if tiled {
            geom.push((324, Value::Long(offs)));
            geom.push((325, Value::Long(counts)));
        } else {
            geom.push((273, Value::Long(offs)));
            geom.push((279, Value::Long(counts)));
        }
        let mut raw = self.raw_tags();
        raw.extend(geom);
        let mut ifd0 = self.ifd0_tags();
        let exif_off = if self.exif.is_empty() {
            None
        } else {
            Some(f.ifd(self.exif.clone()))
        };
        let apply = |mut v: Vec<(u16, Value)>, this: &Builder, own: &dyn Fn(u16) -> bool| {
            for (t, val) in &this.overrides {
                if own(*t) {
                    v.retain(|(x, _)| x != t);
                    v.push((*t, val.clone()));
                }
            }
            v.retain(|(t, _)| !this.remove.contains(t));
            v
        };
        let first = if self.raw_in_sub {
            // Overrides of tags already in the raw IFD (or raw-IFD DNG tags) go there.
            let raw_tag = |t: u16| matches!(t, 254..=262 | 273..=279 | 284 | 322..=325 | 33421 | 33422 | 50710..=50717 | 50719 | 50720 | 50829 | 51008 | 51009 | 51022);
            let raw = apply(raw, self, &raw_tag);
            let sub = f.ifd(raw);
            // IFD0: a 2x2 RGB 8-bit preview.
            f.align();
            let pv = f.buf.len() as u32;
            f.buf.extend_from_slice(&[128u8; 12]);
            ifd0.extend([
                (254, Value::Long(vec![1])),
                (256, Value::Long(vec![2])),
                (257, Value::Long(vec![2])),
                (258, Value::Short(vec![8, 8, 8])),
                (259, Value::Short(vec![1])),
                (262, Value::Short(vec![2])),
                (273, Value::Long(vec![pv])),
                (277, Value::Short(vec![3])),
                (278, Value::Long(vec![2])),
                (279, Value::Long(vec![12])),
                (330, Value::Long(vec![sub])),
            ]);
            if let Some(e) = exif_off {
                ifd0.push((34665, Value::Long(vec![e])));
            }
            let mut ifd0 = apply(ifd0, self, &|t| !raw_tag(t));
            for (t, v) in &self.ifd0_set {
                ifd0.retain(|(x, _)| x != t);
                ifd0.push((*t, v.clone()));
            }
            f.ifd(ifd0)
        } else {
            ifd0.extend(raw);
            if let Some(e) = exif_off {
                ifd0.push((34665, Value::Long(vec![e])));
            }
            let ifd0 = apply(ifd0, self, &|_| true);
            f.ifd(ifd0)
        };
        let b = f.u32b(first);
        f.buf[4..8].copy_from_slice(&b);
        f.buf
    }

    fn encode_blocks(&self) -> (Vec<Vec<u8>>, Vec<(u16, Value)>) {
        let (w, h) = (self.width, self.height);
        let px = |r: usize, c: usize| -> u16 {
            // Pad beyond the image by replicating the edge.
            self.pixels[r.min(h - 1) * w + c.min(w - 1)]
        };
        match self.layout {
            Pixels::Strips { rows } => {
                let mut blocks = Vec::new();
                for y0 in (0..h).step_by(rows) {
                    let mut b = Vec::new();
                    for r in y0..(y0 + rows).min(h) {
                        let row: Vec<u16> = (0..w).map(|c| px(r, c)).collect();
                        pack(&row, self.bits, self.big_endian, &mut b);
                    }
                    blocks.push(b);
                }
                (blocks, vec![(278, Value::Long(vec![rows as u32]))])
            }
            Pixels::Tiles { w: tw, h: th } => {
                let mut blocks = Vec::new();
                for y0 in (0..h).step_by(th) {
                    for x0 in (0..w).step_by(tw) {
                        let mut b = Vec::new();
                        for r in y0..y0 + th {
                            let row: Vec<u16> = (x0..x0 + tw).map(|c| px(r, c)).collect();
                            pack(&row, self.bits, self.big_endian, &mut b);
                        }
                        blocks.push(b);
                    }
                }
                (
                    blocks,
                    vec![
                        (322, Value::Long(vec![tw as u32])),
                        (323, Value::Long(vec![th as u32])),
                    ],
                )
            }
            Pixels::LjpegTiles {
                w: tw,
                h: th,
                two_components,
            } => {
                let mut blocks = Vec::new();
                for y0 in (0..h).step_by(th) {
                    for x0 in (0..w).step_by(tw) {
                        let s: Vec<u16> = (y0..y0 + th)
                            .flat_map(|r| (x0..x0 + tw).map(move |c| (r, c)))
                            .map(|(r, c)| px(r, c))
                            .collect();
                        let (fw, nc) = if two_components { (tw / 2, 2) } else { (tw, 1) };
                        blocks.push(lj92(fw, th, nc, self.bits as u8, &s));
                    }
                }
                (
                    blocks,
                    vec![
                        (322, Value::Long(vec![tw as u32])),
                        (323, Value::Long(vec![th as u32])),
                    ],
                )
            }
            Pixels::LjpegStrips { rows } => {
                let mut blocks = Vec::new();
                for y0 in (0..h).step_by(rows) {
                    let s: Vec<u16> = (y0..(y0 + rows).min(h))
                        .flat_map(|r| (0..w).map(move |c| (r, c)))
                        .map(|(r, c)| px(r, c))
                        .collect();
                    blocks.push(lj92(w, s.len() / w, 1, self.bits as u8, &s));
                }
                (blocks, vec![(278, Value::Long(vec![rows as u32]))])
            }
        }
    }
}

/// Pack one row: 8 bit bytes, 16 bit in file order, other depths MSB-first, padded to a byte.
pub fn pack(row: &[u16], bits: u16, big: bool, out: &mut Vec<u8>) {
    match bits {
        8 => out.extend(row.iter().map(|&v| v as u8)),
        16 => {
            for &v in row {
                out.extend_from_slice(&if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                });
            }
        }
        _ => {
            let mut acc: u64 = 0;
            let mut n = 0u32;
            for &v in row {
                acc = (acc << bits) | v as u64;
                n += bits as u32;
                while n >= 8 {
                    out.push((acc >> (n - 8)) as u8);
                    n -= 8;
                }
            }
            if n > 0 {
                out.push((acc << (8 - n)) as u8);
            }
        }
    }
}

struct Out {
    buf: Vec<u8>,
    big: bool,
}

impl Out {
    fn align(&mut self) {
        if self.buf.len() % 2 == 1 {
            self.buf.push(0);
        }
    }
    fn u16b(&self, v: u16) -> [u8; 2] {
        if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    }
    fn u32b(&self, v: u32) -> [u8; 4] {
        if self.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    }
    fn value_bytes(&self, v: &Value) -> Vec<u8> {
        let mut b = Vec::new();
        match v {
            Value::Byte(x) | Value::Ascii(x) | Value::Undefined(x) => b.extend_from_slice(x),
            Value::SByte(x) => b.extend(x.iter().map(|&v| v as u8)),
            Value::Short(x) => x.iter().for_each(|&v| b.extend(self.u16b(v))),
            Value::SShort(x) => x.iter().for_each(|&v| b.extend(self.u16b(v as u16))),
            Value::Long(x) | Value::Ifd(x) => x.iter().for_each(|&v| b.extend(self.u32b(v))),
            Value::SLong(x) => x.iter().for_each(|&v| b.extend(self.u32b(v as u32))),
            Value::Rational(x) => x.iter().for_each(|&(n, d)| {
                b.extend(self.u32b(n));
                b.extend(self.u32b(d))
            }),
            Value::SRational(x) => x.iter().for_each(|&(n, d)| {
                b.extend(self.u32b(n as u32));
                b.extend(self.u32b(d as u32))
            }),
            Value::Float(x) => x.iter().for_each(|&v| b.extend(self.u32b(v.to_bits()))),
            Value::Double(x) => x.iter().for_each(|&v| {
                let bits = v.to_bits();
                b.extend(if self.big {
                    bits.to_be_bytes()
                } else {
                    bits.to_le_bytes()
                })
            }),
        }
        b
    }
    /// Write an IFD (entries sorted) with out-of-line values after it; returns its offset.
    fn ifd(&mut self, mut entries: Vec<(u16, Value)>) -> u32 {
        entries.sort_by_key(|(t, _)| *t);
        self.align();
        let start = self.buf.len();
        let n = entries.len();
        let mut data_off = start + 2 + n * 12 + 4;
        let mut table = Vec::new();
        let mut data = Vec::new();
        table.extend(self.u16b(n as u16));
        for (t, v) in &entries {
            table.extend(self.u16b(*t));
            table.extend(self.u16b(v.field_type() as u16));
            table.extend(self.u32b(v.count() as u32));
            let vb = self.value_bytes(v);
            if vb.len() <= 4 {
                let mut x = vb.clone();
                x.resize(4, 0);
                table.extend(x);
            } else {
                table.extend(self.u32b(data_off as u32));
                data.extend_from_slice(&vb);
                if vb.len() % 2 == 1 {
                    data.push(0);
                }
                data_off += vb.len() + vb.len() % 2;
            }
        }
        table.extend(self.u32b(0));
        self.buf.extend(table);
        self.buf.extend(data);
        start as u32
    }
}

/// Minimal lossless JPEG encoder (predictor 1 = left, first column from above), with one
/// Huffman table of 17 five-bit codes. Independent of the library's decoder and encoder.
pub fn lj92(w: usize, h: usize, nc: usize, p: u8, s: &[u16]) -> Vec<u8> {
    let mut o = vec![0xFF, 0xD8, 0xFF, 0xC3];
    o.extend(((8 + 3 * nc) as u16).to_be_bytes());
    o.push(p);
    o.extend((h as u16).to_be_bytes());
    o.extend((w as u16).to_be_bytes());
    o.push(nc as u8);
    for c in 0..nc {
        o.extend([c as u8, 0x11, 0]);
    }
    o.extend([0xFF, 0xC4, 0, 36, 0]);
    let mut counts = [0u8; 16];
    counts[4] = 17;
    o.extend(counts);
    o.extend(0..17u8);
    o.extend([0xFF, 0xDA]);
    o.extend(((6 + 2 * nc) as u16).to_be_bytes());
    o.push(nc as u8);
    for c in 0..nc {
        o.extend([c as u8, 0]);
    }
    o.extend([1, 0, 0]);
    let rl = w * nc;
    let (mut acc, mut n): (u64, u32) = (0, 0);
    let mut bytes = Vec::new();
    let mut put = |v: u32, len: u32, bytes: &mut Vec<u8>| {
        acc = (acc << len) | (v as u64 & ((1u64 << len) - 1));
        n += len;
        while n >= 8 {
            let b = (acc >> (n - 8)) as u8;
            bytes.push(b);
            if b == 0xFF {
                bytes.push(0);
            }
            n -= 8;
        }
    };
    for r in 0..h {
        for col in 0..w {
            for c in 0..nc {
                let i = r * rl + col * nc + c;
                let pred: i32 = if r == 0 && col == 0 {
                    1 << (p - 1)
                } else if col == 0 {
                    s[i - rl] as i32
                } else {
                    s[i - nc] as i32
                };
                let mut d = (s[i] as i32 - pred) & 0xFFFF;
                if d >= 32768 {
                    d -= 65536;
                }
                if d == -32768 {
                    put(16, 5, &mut bytes);
                    continue;
                }
                let cat = if d == 0 {
                    0
                } else {
                    32 - d.unsigned_abs().leading_zeros()
                };
                put(cat, 5, &mut bytes);
                if cat > 0 {
                    let v = if d < 0 { d + (1 << cat) - 1 } else { d };
                    put(v as u32, cat, &mut bytes);
                }
            }
        }
    }
    // Complete the last byte with 1-bits (any leftover bits are dropped).
    put(0x7F, 7, &mut bytes);
    o.extend(bytes);
    o.extend([0xFF, 0xD9]);
    o
}

/// A little-endian DNG of `blob` (at offset 8) and IFD0 = the usual raw tags of a
/// `width` x `height` 16-bit RGGB image plus `layout` (offsets, counts, geometry), given the
/// blob's offset. For hostile files whose blocks share data.
pub fn dng_around_blob(
    width: usize,
    height: usize,
    compression: u16,
    blob: &[u8],
    layout: impl FnOnce(u32) -> Vec<(u16, Value)>,
) -> Vec<u8> {
    let mut f = Out {
        buf: b"II*\0\0\0\0\0".to_vec(),
        big: false,
    };
    let blob_off = f.buf.len() as u32;
    f.buf.extend_from_slice(blob);
    let b = Builder::new(2, 2, 16);
    let mut tags = b.ifd0_tags();
    tags.extend(
        b.raw_tags()
            .into_iter()
            .filter(|(t, _)| !matches!(t, 256 | 257 | 259)),
    );
    tags.extend([
        (256, Value::Long(vec![width as u32])),
        (257, Value::Long(vec![height as u32])),
        (259, Value::Short(vec![compression])),
    ]);
    tags.extend(layout(blob_off));
    let first = f.ifd(tags);
    let b = f.u32b(first);
    f.buf[4..8].copy_from_slice(&b);
    f.buf
}

/// The LJ92 tile bomb: a 16384 x 16384 image in 4096 tiles of 256 x 256 that all point to
/// one 8 KiB lossless JPEG stream (one 1-bit Huffman code: every difference is 0). ~41 KB.
pub fn bomb_lj92_tiles() -> Vec<u8> {
    let (tw, th) = (256usize, 256usize);
    let mut s = vec![0xFF, 0xD8, 0xFF, 0xC3, 0, 11, 16];
    s.extend((th as u16).to_be_bytes());
    s.extend((tw as u16).to_be_bytes());
    s.extend([1, 0, 0x11, 0]);
    // DHT: class 0 id 0, one code of length 1 for category 0.
    s.extend([0xFF, 0xC4, 0, 20, 0, 1]);
    s.extend([0u8; 15]);
    s.push(0);
    s.extend([0xFF, 0xDA, 0, 8, 1, 0, 0, 1, 0, 0]);
    s.extend(std::iter::repeat_n(0u8, tw * th / 8));
    s.extend([0xFF, 0xD9]);
    let n = (16384 / tw) * (16384 / th);
    let len = s.len() as u32;
    dng_around_blob(16384, 16384, 7, &s, |off| {
        vec![
            (322, Value::Long(vec![tw as u32])),
            (323, Value::Long(vec![th as u32])),
            (324, Value::Long(vec![off; n])),
            (325, Value::Long(vec![len; n])),
        ]
    })
}

/// The strip bomb: a 16384 x 16384 16-bit image in 16384 one-row strips that all point to
/// the same 32 KiB row. ~164 KB.
pub fn bomb_strips() -> Vec<u8> {
    let w = 16384usize;
    let row: Vec<u8> = (0..w)
        .flat_map(|i| ((i % 4096) as u16).to_le_bytes())
        .collect();
    dng_around_blob(w, 16384, 1, &row, |off| {
        vec![
            (273, Value::Long(vec![off; 16384])),
            (278, Value::Long(vec![1])),
            (279, Value::Long(vec![(2 * w) as u32; 16384])),
        ]
    })
}
