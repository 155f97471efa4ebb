//! Lossless JPEG (ITU T.81 process 14, SOF3) encoder for DNG tiles.
//!
//! One scan, all components interleaved, predictor 1 (left neighbour of the same component;
//! the first row predicts from the left, the first column from above, the very first sample
//! from `2^(P-1)`), point transform 0, one optimal Huffman table (built per tile from the
//! actual difference categories, code lengths limited to 16 bits as in T.81 Annex K.2) shared
//! by all components, 0xFF bytes in the entropy-coded data followed by a stuffed 0x00.
//!
//! DNG writers encode a Bayer tile of `W x H` samples as a `W/2 x H` image with two
//! components, so that each component runs over samples of the same CFA colour along a row;
//! [`encode`] takes the samples in that interleaved order (which is simply the raw row order).

use crate::error::{Error, Result};

/// Encode `samples` (row-major, `width * components` per row, components interleaved) as a
/// lossless JPEG with predictor 1 and `precision` bits per sample (2..=16).
pub fn encode(
    samples: &[u16],
    width: usize,
    height: usize,
    components: usize,
    precision: u8,
) -> Result<Vec<u8>> {
    if !(2..=16).contains(&precision) {
        return Err(Error::invalid(format!(
            "lossless JPEG precision {precision} is outside 2..=16"
        )));
    }
    if !(1..=4).contains(&components) {
        return Err(Error::invalid(format!(
            "lossless JPEG with {components} components (1..=4 allowed)"
        )));
    }
    if width == 0 || height == 0 || width > 65535 || height > 65535 {
        return Err(Error::invalid(format!(
            "lossless JPEG size {width}x{height} outside 1..=65535"
        )));
    }
    let row_len = width * components;
    if samples.len() != row_len * height {
        return Err(Error::invalid(format!(
            "lossless JPEG got {} samples for {}x{}x{}",
            samples.len(),
            width,
            height,
            components
        )));
    }
    let max = (1u32 << precision) - 1;
    if let Some(&bad) = samples.iter().find(|&&s| s as u32 > max) {
        return Err(Error::invalid(format!(
            "sample {bad} does not fit lossless JPEG precision {precision}"
        )));
    }

    // Pass 1: differences as (category, bits) and category histogram.
    let mut diffs: Vec<i32> = Vec::with_capacity(samples.len());
    let first = 1i32 << (precision - 1);
    for y in 0..height {
        let row = &samples[y * row_len..(y + 1) * row_len];
        for x in 0..row_len {
            let pred = if x >= components {
                row[x - components] as i32
            } else if y > 0 {
                samples[(y - 1) * row_len + x] as i32
            } else {
                first
            };
            // Differences are taken modulo 2^16 (T.81 H.1.2.1).
            let mut d = (row[x] as i32 - pred) & 0xFFFF;
            if d >= 0x8000 {
                d -= 0x10000;
            }
            diffs.push(d);
        }
    }
    let mut freq = [0u64; 17];
    for &d in &diffs {
        freq[category(d) as usize] += 1;
    }
    let (bits, huffval) = optimal_table(&freq);
    let (codes, sizes) = code_table(&bits, &huffval);

    let mut out = Vec::with_capacity(samples.len() + 64);
    out.extend_from_slice(&[0xFF, 0xD8]); // SOI
                                          // DHT: class 0 (DC/lossless), id 0.
    out.extend_from_slice(&[0xFF, 0xC4]);
    let dht_len = 2 + 1 + 16 + huffval.len();
    out.extend_from_slice(&(dht_len as u16).to_be_bytes());
    out.push(0x00);
    out.extend_from_slice(&bits);
    out.extend_from_slice(&huffval);
    // SOF3.
    out.extend_from_slice(&[0xFF, 0xC3]);
    out.extend_from_slice(&((8 + 3 * components) as u16).to_be_bytes());
    out.push(precision);
    out.extend_from_slice(&(height as u16).to_be_bytes());
    out.extend_from_slice(&(width as u16).to_be_bytes());
    out.push(components as u8);
    for c in 0..components {
        out.extend_from_slice(&[c as u8 + 1, 0x11, 0]);
    }
    // SOS: predictor 1 (Ss), Se 0, Ah/Al 0.
    out.extend_from_slice(&[0xFF, 0xDA]);
    out.extend_from_slice(&((6 + 2 * components) as u16).to_be_bytes());
    out.push(components as u8);
    for c in 0..components {
        out.extend_from_slice(&[c as u8 + 1, 0x00]);
    }
    out.extend_from_slice(&[1, 0, 0]);

    let mut bw = BitWriter {
        out: &mut out,
        acc: 0,
        n: 0,
    };
    for &d in &diffs {
        let s = category(d);
        let (code, size) = (codes[s as usize] as u64, sizes[s as usize]);
        if s > 0 && s < 16 {
            // Code and magnitude bits in one go (at most 16 + 15 bits).
            let v = (if d < 0 { d - 1 } else { d }) as u64 & ((1u64 << s) - 1);
            bw.put((code << s) | v, size + s);
        } else {
            bw.put(code, size);
        }
    }
    bw.flush();
    out.extend_from_slice(&[0xFF, 0xD9]); // EOI
    Ok(out)
}

/// SSSS: number of bits of |d| (0 for 0; 16 for 32768).
#[inline]
fn category(d: i32) -> u8 {
    (32 - d.unsigned_abs().leading_zeros()) as u8
}

struct BitWriter<'a> {
    out: &'a mut Vec<u8>,
    acc: u64,
    n: u32,
}

impl BitWriter<'_> {
    #[inline]
    fn put(&mut self, bits: u64, len: u8) {
        if len == 0 {
            return;
        }
        self.acc = (self.acc << len) | (bits & ((1u64 << len) - 1));
        self.n += len as u32;
        while self.n >= 8 {
            self.n -= 8;
            let b = (self.acc >> self.n) as u8;
            self.out.push(b);
            if b == 0xFF {
                self.out.push(0x00);
            }
        }
        self.acc &= (1u64 << self.n) - 1;
    }
    fn flush(&mut self) {
        if self.n > 0 {
            let pad = 8 - self.n as u8;
            self.put((1u64 << pad) - 1, pad);
        }
    }
}

/// Optimal Huffman table (T.81 Annex K.2) for the 17 categories: returns (BITS[1..=16],
/// HUFFVAL). A reserved dummy symbol keeps the all-ones code unused.
fn optimal_table(freq_in: &[u64; 17]) -> ([u8; 16], Vec<u8>) {
    let mut freq = [0u64; 18];
    freq[..17].copy_from_slice(freq_in);
    freq[17] = 1; // reserved symbol
    let mut codesize = [0usize; 18];
    let mut others = [usize::MAX; 18];
    loop {
        // v1: least frequency (>0), largest index on ties; v2: next least.
        let mut v1 = usize::MAX;
        let mut v2 = usize::MAX;
        for i in 0..18 {
            if freq[i] == 0 {
                continue;
            }
            if v1 == usize::MAX || freq[i] <= freq[v1] {
                v2 = v1;
                v1 = i;
            } else if v2 == usize::MAX || freq[i] <= freq[v2] {
                v2 = i;
            }
        }
        if v2 == usize::MAX {
            break;
        }
        freq[v1] += freq[v2];
        freq[v2] = 0;
        codesize[v1] += 1;
        let mut c = v1;
        while others[c] != usize::MAX {
            c = others[c];
            codesize[c] += 1;
        }
        others[c] = v2;
        codesize[v2] += 1;
        let mut c = v2;
        while others[c] != usize::MAX {
            c = others[c];
            codesize[c] += 1;
        }
    }
    let mut bits = [0usize; 40];
    for &cs in &codesize {
        if cs > 0 {
            bits[cs.min(39)] += 1;
        }
    }
    // Limit code lengths to 16 (K.2 Figure K.3).
    let mut i = 39;
    while i > 16 {
        while bits[i] > 0 {
            let mut j = i - 2;
            while bits[j] == 0 {
                j -= 1;
            }
            bits[i] -= 2;
            bits[i - 1] += 1;
            bits[j + 1] += 2;
            bits[j] -= 1;
        }
        i -= 1;
    }
    // Remove the reserved symbol's code (the longest one).
    let mut i = 16;
    while bits[i] == 0 {
        i -= 1;
    }
    bits[i] -= 1;
    // HUFFVAL: symbols sorted by code size, then by value.
    let mut huffval = vec![];
    for size in 1..=39 {
        for (sym, &cs) in codesize.iter().enumerate().take(17) {
            if cs == size {
                huffval.push(sym as u8);
            }
        }
    }
    let mut out = [0u8; 16];
    for (k, o) in out.iter_mut().enumerate() {
        *o = bits[k + 1] as u8;
    }
    (out, huffval)
}

/// Canonical codes from BITS/HUFFVAL: (code, size) per symbol 0..=16.
fn code_table(bits: &[u8; 16], huffval: &[u8]) -> ([u16; 17], [u8; 17]) {
    let mut codes = [0u16; 17];
    let mut sizes = [0u8; 17];
    let mut code: u32 = 0;
    let mut k = 0;
    for (len_idx, &count) in bits.iter().enumerate() {
        for _ in 0..count {
            if let Some(&sym) = huffval.get(k) {
                codes[sym as usize] = code as u16;
                sizes[sym as usize] = len_idx as u8 + 1;
            }
            code += 1;
            k += 1;
        }
        code <<= 1;
    }
    (codes, sizes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tiny independent decoder for the encoder's own output (predictor 1 only).
    pub(crate) fn decode_p1(data: &[u8]) -> (usize, usize, usize, Vec<u16>) {
        let mut i = 2;
        let mut lookup: Vec<(u16, u8, u8)> = vec![];
        let (mut w, mut h, mut nc, mut p) = (0, 0, 0, 0u8);
        loop {
            assert_eq!(data[i], 0xFF);
            let m = data[i + 1];
            let len = u16::from_be_bytes([data[i + 2], data[i + 3]]) as usize;
            let seg = &data[i + 4..i + 2 + len];
            match m {
                0xC4 => {
                    let bits = &seg[1..17];
                    let vals = &seg[17..];
                    let mut code = 0u16;
                    let mut k = 0;
                    for (l, &c) in bits.iter().enumerate() {
                        for _ in 0..c {
                            lookup.push((code, l as u8 + 1, vals[k]));
                            code += 1;
                            k += 1;
                        }
                        code <<= 1;
                    }
                }
                0xC3 => {
                    p = seg[0];
                    h = u16::from_be_bytes([seg[1], seg[2]]) as usize;
                    w = u16::from_be_bytes([seg[3], seg[4]]) as usize;
                    nc = seg[5] as usize;
                }
                0xDA => {
                    i += 2 + len;
                    break;
                }
                _ => panic!("marker {m:x}"),
            }
            i += 2 + len;
        }
        // Unstuff.
        let mut bytes = vec![];
        while i < data.len() {
            if data[i] == 0xFF {
                if data[i + 1] == 0 {
                    bytes.push(0xFF);
                    i += 2;
                    continue;
                }
                break;
            }
            bytes.push(data[i]);
            i += 1;
        }
        let mut pos = 0usize;
        let bit = |pos: &mut usize| -> u32 {
            let b = (bytes[*pos / 8] >> (7 - *pos % 8)) & 1;
            *pos += 1;
            b as u32
        };
        let rl = w * nc;
        let mut out = vec![0u16; rl * h];
        for y in 0..h {
            for x in 0..rl {
                let mut code = 0u16;
                let mut len = 0u8;
                let s = loop {
                    code = (code << 1) | bit(&mut pos) as u16;
                    len += 1;
                    if let Some(e) = lookup.iter().find(|e| e.0 == code && e.1 == len) {
                        break e.2;
                    }
                    assert!(len < 17);
                };
                let d: i32 = if s == 0 {
                    0
                } else if s == 16 {
                    32768
                } else {
                    let mut v = 0u32;
                    for _ in 0..s {
                        v = (v << 1) | bit(&mut pos);
                    }
                    if v < (1 << (s - 1)) {
                        v as i32 - (1 << s) + 1
                    } else {
                        v as i32
                    }
                };
                let pred = if x >= nc {
                    out[y * rl + x - nc] as i32
                } else if y > 0 {
                    out[(y - 1) * rl + x] as i32
                } else {
                    1 << (p - 1)
                };
                out[y * rl + x] = ((pred + d) & 0xFFFF) as u16;
            }
        }
        (w, h, nc, out)
    }

    #[test]
    fn round_trips_through_reference_decoder() {
        let mut s = 12345u32;
        let mut rnd = || {
            s = s.wrapping_mul(1103515245).wrapping_add(12345);
            s >> 8
        };
        for &(w, h, nc, p) in &[
            (8usize, 4usize, 2usize, 12u8),
            (1, 1, 1, 16),
            (5, 7, 2, 16),
            (16, 16, 2, 14),
            (3, 2, 4, 8),
        ] {
            let max = (1u32 << p) - 1;
            let samples: Vec<u16> = (0..w * h * nc)
                .map(|i| {
                    if i % 7 == 0 {
                        max as u16
                    } else {
                        (rnd() & max) as u16
                    }
                })
                .collect();
            let enc = encode(&samples, w, h, nc, p).unwrap();
            let (dw, dh, dnc, dec) = decode_p1(&enc);
            assert_eq!((dw, dh, dnc), (w, h, nc));
            assert_eq!(dec, samples, "{w}x{h}x{nc} P{p}");
            assert_eq!(&enc[enc.len() - 2..], &[0xFF, 0xD9]);
        }
    }

    #[test]
    fn extreme_differences_and_constant_input() {
        // 0 -> 65535 -> 0 gives differences of +-32768-ish and category 16.
        let samples = vec![0u16, 65535, 0, 65535, 32768, 0, 65535, 1];
        let enc = encode(&samples, 4, 2, 1, 16).unwrap();
        assert_eq!(decode_p1(&enc).3, samples);
        let flat = vec![700u16; 64 * 64];
        let enc = encode(&flat, 32, 64, 2, 12).unwrap();
        assert_eq!(decode_p1(&enc).3, flat);
        assert!(
            enc.len() < 700,
            "constant tile should compress: {}",
            enc.len()
        );
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(encode(&[5000], 1, 1, 1, 12).is_err());
        assert!(encode(&[1, 2], 1, 1, 1, 12).is_err());
        assert!(encode(&[1], 1, 1, 1, 1).is_err());
        assert!(encode(&[], 0, 1, 1, 12).is_err());
    }
}
