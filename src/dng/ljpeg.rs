//! Lossless JPEG decoder (ITU T.81 process 14: SOF3, Huffman coded, 1-4 components,
//! predictors 1-7, point transform, restart markers, 2-16 bit precision).
//!
//! DNG stores each tile or strip of a Compression 7 image as one such stream; converters
//! often encode a tile of width `W` as a 2-component frame of width `W/2`. [`decode`] returns
//! the frame's samples interleaved (`width * components` per row); the DNG reader maps them
//! onto the tile row-major, which covers both layouts.

use crate::error::{Error, Result};

/// Most samples (width * height * components) one stream may decode to.
pub const MAX_SAMPLES: usize = 1 << 28;

/// A decoded lossless JPEG frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Decoded {
    /// Frame width (samples per line per component).
    pub width: usize,
    /// Frame height (lines).
    pub height: usize,
    /// Number of components (1..=4).
    pub components: usize,
    /// Sample precision in bits (2..=16).
    pub precision: u8,
    /// `width * height * components` samples, row-major, components interleaved.
    pub data: Vec<u16>,
}

#[derive(Clone)]
struct Huffman {
    /// Fast table: for the next 9 bits, (symbol, code length) or length 0 = slow path.
    fast: Vec<(u8, u8)>,
    /// Per code length 1..=16: (max code, value offset) for canonical decoding.
    maxcode: [i32; 18],
    valptr: [i32; 17],
    mincode: [i32; 17],
    values: Vec<u8>,
}

const FAST_BITS: u32 = 9;

impl Huffman {
    fn new(counts: &[u8; 16], values: Vec<u8>) -> Result<Huffman> {
        let total: usize = counts.iter().map(|&c| c as usize).sum();
        if total != values.len() || total == 0 || total > 256 {
            return Err(Error::malformed("lossless JPEG: bad Huffman table size"));
        }
        let mut fast = vec![(0u8, 0u8); 1 << FAST_BITS];
        let mut maxcode = [-1i32; 18];
        let mut valptr = [0i32; 17];
        let mut mincode = [0i32; 17];
        let mut code: i32 = 0;
        let mut k = 0usize;
        for len in 1..=16usize {
            let n = counts[len - 1] as usize;
            valptr[len] = k as i32;
            mincode[len] = code;
            for _ in 0..n {
                if code >= (1 << len) {
                    return Err(Error::malformed(
                        "lossless JPEG: Huffman table has too many codes",
                    ));
                }
                if len as u32 <= FAST_BITS {
                    let shift = FAST_BITS - len as u32;
                    let start = (code as usize) << shift;
                    let sym = values.get(k).copied().unwrap_or(0);
                    for f in fast.iter_mut().skip(start).take(1 << shift) {
                        *f = (sym, len as u8);
                    }
                }
                code += 1;
                k += 1;
            }
            maxcode[len] = if n > 0 { code - 1 } else { -1 };
            code <<= 1;
        }
        maxcode[17] = i32::MAX;
        Ok(Huffman {
            fast,
            maxcode,
            valptr,
            mincode,
            values,
        })
    }
}

/// Bit reader over entropy-coded data: removes 0xFF00 stuffing and stops at markers
/// (feeding zero bits past a marker, as T.81 decoders do).
struct Bits<'a> {
    data: &'a [u8],
    pos: usize,
    acc: u64,
    nbits: u32,
    /// Set once a marker (0xFF followed by non-zero) was hit.
    marker: Option<u8>,
    /// Zero bits fed past the end of data or a marker.
    padded: u32,
}

impl<'a> Bits<'a> {
    fn new(data: &'a [u8], pos: usize) -> Self {
        Bits {
            data,
            pos,
            acc: 0,
            nbits: 0,
            marker: None,
            padded: 0,
        }
    }
    #[inline]
    fn refill(&mut self) {
        // Fast path: eight bytes without 0xFF are taken in one go.
        if self.marker.is_none() {
            if let Some(chunk) = self.data.get(self.pos..self.pos + 8) {
                let mut b = [0u8; 8];
                b.copy_from_slice(chunk);
                let w = u64::from_be_bytes(b);
                let x = !w;
                let has_ff = x.wrapping_sub(0x0101_0101_0101_0101) & !x & 0x8080_8080_8080_8080;
                let take = (64 - self.nbits) / 8;
                if has_ff == 0 && take > 0 {
                    let add = w >> (64 - 8 * take);
                    self.acc |= add << (64 - self.nbits - 8 * take);
                    self.pos += take as usize;
                    self.nbits += 8 * take;
                    return;
                }
            }
        }
        while self.nbits <= 56 {
            let mut byte = 0u8;
            if self.marker.is_none() {
                match self.data.get(self.pos) {
                    Some(&0xFF) => match self.data.get(self.pos + 1) {
                        Some(&0) => {
                            byte = 0xFF;
                            self.pos += 2;
                        }
                        Some(&m) => self.marker = Some(m),
                        None => {
                            self.pos += 1;
                            byte = 0xFF;
                        }
                    },
                    Some(&b) => {
                        byte = b;
                        self.pos += 1;
                    }
                    None => self.padded += 8,
                }
            } else {
                self.padded += 8;
            }
            self.acc |= (byte as u64) << (56 - self.nbits);
            self.nbits += 8;
        }
    }
    #[inline]
    fn peek(&mut self, n: u32) -> u32 {
        if self.nbits < n {
            self.refill();
        }
        (self.acc >> (64 - n)) as u32
    }
    #[inline]
    fn consume(&mut self, n: u32) {
        self.acc <<= n;
        self.nbits -= n;
    }
    #[inline]
    fn get(&mut self, n: u32) -> u32 {
        if n == 0 {
            return 0;
        }
        let v = self.peek(n);
        self.consume(n);
        v
    }
    fn too_far(&self) -> bool {
        // Padding bits consumed (more fed than still buffered): the stream ran out.
        self.padded > self.nbits
    }
    #[inline]
    fn decode(&mut self, h: &Huffman) -> Result<u8> {
        let look = self.peek(FAST_BITS) as usize;
        if let Some(&(sym, len)) = h.fast.get(look) {
            if len > 0 {
                self.consume(len as u32);
                return Ok(sym);
            }
        }
        let all = self.peek(16) as i32;
        for len in (FAST_BITS as usize + 1)..=16 {
            let code = all >> (16 - len);
            if code <= h.maxcode[len] {
                self.consume(len as u32);
                let idx = h.valptr[len] + code - h.mincode[len];
                return h
                    .values
                    .get(idx as usize)
                    .copied()
                    .ok_or_else(|| Error::malformed("lossless JPEG: Huffman code out of range"));
            }
        }
        Err(Error::malformed("lossless JPEG: invalid Huffman code"))
    }
    /// Skip to after the next RST marker (byte aligned), resetting the bit buffer.
    fn restart(&mut self) -> Result<()> {
        self.acc = 0;
        self.nbits = 0;
        self.marker = None;
        self.padded = 0;
        // Find 0xFF 0xD0..=0xD7.
        while let Some(&b) = self.data.get(self.pos) {
            if b == 0xFF {
                match self.data.get(self.pos + 1) {
                    Some(&m) if (0xD0..=0xD7).contains(&m) => {
                        self.pos += 2;
                        return Ok(());
                    }
                    Some(&0xFF) => self.pos += 1,
                    Some(_) => self.pos += 2,
                    None => break,
                }
            } else {
                self.pos += 1;
            }
        }
        Err(Error::malformed("lossless JPEG: expected a restart marker"))
    }
}

struct Component {
    id: u8,
    table: usize,
}

fn u16be(d: &[u8], p: usize) -> Result<u16> {
    match (d.get(p), d.get(p + 1)) {
        (Some(&a), Some(&b)) => Ok(u16::from_be_bytes([a, b])),
        _ => Err(Error::malformed("lossless JPEG: truncated header")),
    }
}

/// A SOF3 (lossless) frame header: precision, height, width and component ids.
fn parse_sof3(seg: &[u8]) -> Result<(u8, usize, usize, Vec<u8>)> {
    let p = *seg.first().unwrap_or(&0);
    let h = u16be(seg, 1)? as usize;
    let w = u16be(seg, 3)? as usize;
    let nf = *seg.get(5).unwrap_or(&0) as usize;
    if !(2..=16).contains(&p) {
        return Err(Error::unsupported(format!(
            "lossless JPEG precision {p} bits (2..16 supported)"
        )));
    }
    if !(1..=4).contains(&nf) {
        return Err(Error::unsupported(format!(
            "lossless JPEG with {nf} components (1..4 supported)"
        )));
    }
    if h == 0 || w == 0 {
        return Err(Error::malformed(
            "lossless JPEG: zero frame width or height",
        ));
    }
    let mut ids = Vec::with_capacity(nf);
    for c in 0..nf {
        let b = seg
            .get(6 + 3 * c..9 + 3 * c)
            .ok_or_else(|| Error::malformed("lossless JPEG: truncated SOF3"))?;
        if b[1] != 0x11 {
            return Err(Error::unsupported(format!(
                "lossless JPEG sampling factors {}x{} (only 1x1)",
                b[1] >> 4,
                b[1] & 15
            )));
        }
        ids.push(b[0]);
    }
    Ok((p, h, w, ids))
}

/// A DHT segment: its Huffman tables into `tables`.
fn parse_dht(seg: &[u8], tables: &mut [Option<Huffman>; 4]) -> Result<()> {
    let mut s = seg;
    while !s.is_empty() {
        let tc_th = s[0];
        let th = (tc_th & 15) as usize;
        if th > 3 {
            return Err(Error::malformed("lossless JPEG: Huffman table id > 3"));
        }
        let counts: [u8; 16] = s
            .get(1..17)
            .and_then(|c| c.try_into().ok())
            .ok_or_else(|| Error::malformed("lossless JPEG: truncated DHT"))?;
        let n: usize = counts.iter().map(|&c| c as usize).sum();
        let vals = s
            .get(17..17 + n)
            .ok_or_else(|| Error::malformed("lossless JPEG: truncated DHT"))?;
        tables[th] = Some(Huffman::new(&counts, vals.to_vec())?);
        s = &s[17 + n..];
    }
    Ok(())
}

/// Decode one lossless JPEG stream.
pub fn decode(data: &[u8]) -> Result<Decoded> {
    if data.get(0..2) != Some(&[0xFF, 0xD8]) {
        return Err(Error::malformed(
            "lossless JPEG: stream does not start with SOI",
        ));
    }
    let mut pos = 2usize;
    let mut tables: [Option<Huffman>; 4] = [None, None, None, None];
    let mut frame: Option<(u8, usize, usize, Vec<u8>)> = None; // precision, h, w, ids
    let mut restart_interval = 0usize;
    loop {
        // Find the next marker (skip fill bytes).
        let Some(&ff) = data.get(pos) else {
            return Err(Error::malformed(
                "lossless JPEG: no SOS marker before end of data",
            ));
        };
        if ff != 0xFF {
            return Err(Error::malformed(format!(
                "lossless JPEG: expected a marker at byte {pos}"
            )));
        }
        let Some(&m) = data.get(pos + 1) else {
            return Err(Error::malformed("lossless JPEG: truncated marker"));
        };
        pos += 2;
        match m {
            0xFF => {
                pos -= 1;
                continue;
            }
            0xD8 | 0x01 | 0xD0..=0xD7 => continue,
            0xD9 => return Err(Error::malformed("lossless JPEG: EOI before any scan")),
            _ => {}
        }
        let len = u16be(data, pos)? as usize;
        if len < 2 {
            return Err(Error::malformed("lossless JPEG: bad segment length"));
        }
        let seg = data
            .get(pos + 2..pos + len)
            .ok_or_else(|| Error::malformed("lossless JPEG: truncated segment"))?;
        pos += len;
        match m {
            0xC3 => frame = Some(parse_sof3(seg)?),
            0xC0..=0xC2 | 0xC5..=0xC7 | 0xC9..=0xCB | 0xCD..=0xCF => {
                return Err(Error::unsupported(format!(
                    "JPEG process SOF{} (only lossless SOF3 is supported)",
                    m - 0xC0
                )))
            }
            0xC4 => parse_dht(seg, &mut tables)?,
            0xDD => restart_interval = u16be(seg, 0)? as usize,
            0xDA => {
                let (p, h, w, ids) = frame
                    .take()
                    .ok_or_else(|| Error::malformed("lossless JPEG: SOS before SOF3"))?;
                let ns = *seg.first().unwrap_or(&0) as usize;
                if ns != ids.len() {
                    return Err(Error::unsupported(format!(
                        "lossless JPEG scan with {ns} of {} components (non-interleaved scans)",
                        ids.len()
                    )));
                }
                let mut comps = Vec::with_capacity(ns);
                for c in 0..ns {
                    let b = seg
                        .get(1 + 2 * c..3 + 2 * c)
                        .ok_or_else(|| Error::malformed("lossless JPEG: truncated SOS"))?;
                    let table = (b[1] >> 4) as usize;
                    if table > 3 || tables[table].is_none() {
                        return Err(Error::malformed(format!(
                            "lossless JPEG: scan uses undefined Huffman table {table}"
                        )));
                    }
                    comps.push(Component { id: b[0], table });
                }
                for (c, id) in comps.iter().zip(&ids) {
                    if c.id != *id {
                        // Tolerated: some encoders number components differently in SOS.
                        let _ = id;
                    }
                }
                let tail = seg
                    .get(1 + 2 * ns..4 + 2 * ns)
                    .ok_or_else(|| Error::malformed("lossless JPEG: truncated SOS"))?;
                let predictor = tail[0];
                let pt = tail[2] & 15;
                if predictor > 7 {
                    return Err(Error::malformed(format!(
                        "lossless JPEG: predictor {predictor} (1..7)"
                    )));
                }
                if pt >= p {
                    return Err(Error::malformed(
                        "lossless JPEG: point transform >= precision",
                    ));
                }
                let hts: Vec<&Huffman> = comps
                    .iter()
                    .filter_map(|c| tables[c.table].as_ref())
                    .collect();
                return scan(
                    data,
                    pos,
                    ScanParams {
                        precision: p,
                        height: h,
                        width: w,
                        predictor,
                        pt,
                        restart_interval,
                    },
                    &hts,
                );
            }
            _ => {} // APPn, COM, DQT, ...: skipped
        }
    }
}

struct ScanParams {
    precision: u8,
    height: usize,
    width: usize,
    predictor: u8,
    pt: u8,
    restart_interval: usize,
}

fn scan(data: &[u8], pos: usize, sp: ScanParams, hts: &[&Huffman]) -> Result<Decoded> {
    let nc = hts.len();
    let row_len = sp
        .width
        .checked_mul(nc)
        .ok_or_else(|| Error::limits("lossless JPEG frame too large"))?;
    let total = row_len
        .checked_mul(sp.height)
        .filter(|&t| t <= MAX_SAMPLES)
        .ok_or_else(|| {
            Error::limits(format!(
                "lossless JPEG frame {}x{}x{} exceeds {} samples",
                sp.width, sp.height, nc, MAX_SAMPLES
            ))
        })?;
    // Every sample costs at least one bit: refuse frames the data cannot hold before
    // allocating for them.
    let avail_bits = (data.len().saturating_sub(pos)).saturating_mul(8);
    if total > avail_bits {
        return Err(Error::malformed(format!(
            "lossless JPEG: {} bytes of data cannot hold a {}x{}x{} frame",
            data.len().saturating_sub(pos),
            sp.width,
            sp.height,
            nc
        )));
    }
    let mut out = crate::limits::try_filled(0u16, total, "a lossless JPEG frame")?;
    let mut bits = Bits::new(data, pos);
    let default_pred: i32 = 1 << (sp.precision - sp.pt - 1);
    if sp.restart_interval == 0 {
        scan_simple(
            &mut bits,
            &mut out,
            row_len,
            nc,
            sp.predictor,
            default_pred,
            hts,
        )?;
        return finish(out, sp, nc);
    }
    let mask: i32 = 0xFFFF;
    let mut mcus_left = sp.restart_interval;
    // Row in which the current restart interval began and column: the first line of an
    // interval predicts from the left only.
    let mut first_line = true;
    let mut restart_col: Option<usize> = Some(0);
    let mut prev_start = 0usize;
    for row in 0..sp.height {
        let start = row * row_len;
        let (done, cur_and_rest) = out.split_at_mut(start);
        let prev = done.get(prev_start..prev_start + row_len);
        let cur = &mut cur_and_rest[..row_len];
        for col in 0..sp.width {
            if sp.restart_interval > 0 {
                if mcus_left == 0 {
                    bits.restart()?;
                    mcus_left = sp.restart_interval;
                    restart_col = Some(col);
                    first_line = true;
                }
                mcus_left -= 1;
            }
            for (c, ht) in hts.iter().enumerate() {
                let i = col * nc + c;
                let pred: i32 = if restart_col == Some(col) && first_line {
                    default_pred
                } else if first_line {
                    // Left neighbour (first line of the scan or restart interval).
                    i32::from(cur[i - nc])
                } else if col == 0 {
                    i32::from(prev.and_then(|p| p.get(i).copied()).unwrap_or(0))
                } else {
                    let ra = i32::from(cur[i - nc]);
                    let p = prev.unwrap_or(&[]);
                    let rb = i32::from(*p.get(i).unwrap_or(&0));
                    let rc = i32::from(*p.get(i - nc).unwrap_or(&0));
                    match sp.predictor {
                        1 => ra,
                        2 => rb,
                        3 => rc,
                        4 => ra + rb - rc,
                        5 => ra + ((rb - rc) >> 1),
                        6 => rb + ((ra - rc) >> 1),
                        7 => (ra + rb) >> 1,
                        _ => 0,
                    }
                };
                cur[i] = ((pred + read_diff(&mut bits, ht)?) & mask) as u16;
            }
            if bits.too_far() {
                return Err(Error::malformed(
                    "lossless JPEG: entropy-coded data ends before the frame is complete",
                ));
            }
        }
        first_line = false;
        restart_col = None;
        prev_start = start;
    }
    finish(out, sp, nc)
}

fn finish(mut out: Vec<u16>, sp: ScanParams, nc: usize) -> Result<Decoded> {
    if sp.pt > 0 {
        for v in &mut out {
            *v <<= sp.pt;
        }
    }
    Ok(Decoded {
        width: sp.width,
        height: sp.height,
        components: nc,
        precision: sp.precision,
        data: out,
    })
}

/// One difference value.
#[inline(always)]
fn read_diff(bits: &mut Bits<'_>, h: &Huffman) -> Result<i32> {
    let s = bits.decode(h)?;
    Ok(match s {
        0 => 0,
        16 => 32768,
        1..=15 => {
            let v = bits.get(s as u32) as i32;
            if v < (1 << (s - 1)) {
                v - (1 << s) + 1
            } else {
                v
            }
        }
        _ => {
            return Err(Error::malformed(format!(
                "lossless JPEG: difference category {s} > 16"
            )))
        }
    })
}

/// Decode a scan without restart intervals: row 0 predicts from the left, column 0 from
/// above, the rest with the selected predictor (one tight loop per predictor).
fn scan_simple(
    bits: &mut Bits<'_>,
    out: &mut [u16],
    row_len: usize,
    nc: usize,
    predictor: u8,
    default_pred: i32,
    hts: &[&Huffman],
) -> Result<()> {
    let ended =
        || Error::malformed("lossless JPEG: entropy-coded data ends before the frame is complete");
    let mut rows = out.chunks_exact_mut(row_len);
    let Some(first) = rows.next() else {
        return Ok(());
    };
    for (i, ht) in hts.iter().enumerate() {
        if let Some(v) = first.get_mut(i) {
            *v = ((default_pred + read_diff(bits, ht)?) & 0xFFFF) as u16;
        }
    }
    for i in nc..row_len {
        let ra = i32::from(first[i - nc]);
        first[i] = ((ra + read_diff(bits, hts[i % nc])?) & 0xFFFF) as u16;
    }
    if bits.too_far() {
        return Err(ended());
    }
    let mut prev: &[u16] = first;
    for cur in rows {
        for (i, ht) in hts.iter().enumerate() {
            if let (Some(v), Some(&b)) = (cur.get_mut(i), prev.get(i)) {
                *v = ((i32::from(b) + read_diff(bits, ht)?) & 0xFFFF) as u16;
            }
        }
        macro_rules! run {
            (|$ra:ident, $rb:ident, $rc:ident| $e:expr) => {{
                let mut c = 0usize;
                for i in nc..row_len {
                    let $ra = i32::from(cur[i - nc]);
                    let $rb = i32::from(prev[i]);
                    let $rc = i32::from(prev[i - nc]);
                    let _ = (&$ra, &$rb, &$rc);
                    cur[i] = (($e + read_diff(bits, hts[c])?) & 0xFFFF) as u16;
                    c += 1;
                    if c == nc {
                        c = 0;
                    }
                }
            }};
        }
        match predictor {
            1 => run!(|ra, rb, rc| ra),
            2 => run!(|ra, rb, rc| rb),
            3 => run!(|ra, rb, rc| rc),
            4 => run!(|ra, rb, rc| ra + rb - rc),
            5 => run!(|ra, rb, rc| ra + ((rb - rc) >> 1)),
            6 => run!(|ra, rb, rc| rb + ((ra - rc) >> 1)),
            7 => run!(|ra, rb, rc| (ra + rb) >> 1),
            _ => run!(|ra, rb, rc| 0),
        }
        if bits.too_far() {
            return Err(ended());
        }
        prev = cur;
    }
    Ok(())
}

#[cfg(test)]
#[path = "ljpeg_tests.rs"]
mod tests;
