//! The block encoder: literals plus distance-1 matches ("runs"), one dynamic-Huffman block per
//! chunk of input, with fixed-Huffman and stored fallbacks chosen by exact bit cost.

use super::bits::BitWriter;
use super::huffman::{canonical_codes, HuffmanBuilder};

/// Literal/length alphabet size actually used (0..=285).
const NLIT: usize = 286;
/// End-of-block symbol.
const EOB: usize = 256;
/// Longest match.
const MAX_RUN: usize = 258;
/// Shortest match.
const MIN_RUN: usize = 3;
/// Largest stored block.
const MAX_STORED: usize = 65535;

/// Base length of length symbols 257..=285.
const LEN_BASE: [u16; 29] = [
    3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31, 35, 43, 51, 59, 67, 83, 99, 115, 131,
    163, 195, 227, 258,
];
/// Extra bits of length symbols 257..=285.
const LEN_EXTRA: [u8; 29] = [
    0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0,
];

/// Length symbol index (0..29, symbol 257 + index) of each match length 0..=258 (3.. valid).
const LEN_SYM: [u8; 259] = {
    let mut t = [0u8; 259];
    let mut s = 0;
    while s < 29 {
        let base = LEN_BASE[s] as usize;
        let n = if s == 28 { 1 } else { 1 << LEN_EXTRA[s] };
        let mut k = 0;
        // length 258 belongs to symbol 285 only (227 + 31 would also reach it)
        while k < n && base + k <= 258 {
            t[base + k] = s as u8;
            k += 1;
        }
        s += 1;
    }
    t[258] = 28;
    t
};

/// Code-length alphabet transmission order (RFC 1951 3.2.7).
const CL_ORDER: [usize; 19] = [
    16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15,
];

/// One distance-1 match: `len` (3..=258) bytes at `pos` equal to the byte before `pos`.
#[derive(Clone, Copy)]
struct Run {
    pos: u32,
    len: u32,
}

/// Reusable scratch state of the encoder.
pub(crate) struct BlockEncoder {
    runs: Vec<Run>,
    huff: HuffmanBuilder,
    /// Code-length stream of the current dynamic header: `symbol | extra << 8`.
    cl_stream: Vec<u16>,
    /// Code-length code lengths and HCLEN of the current dynamic header.
    cl_lens: [u8; 19],
    hclen: usize,
    fixed: Tables,
    dynamic: Tables,
}

/// Per-block code tables, entries `code << 8 | len` with codes bit-reversed.
struct Tables {
    lit: [u32; 256],
    /// Whole match (length code, extra bits, distance-1 code) per length 0..=258.
    run: [u32; 259],
    eob: u32,
    /// Longest literal code, to pick the flush interval.
    max_lit_len: u32,
}

impl Tables {
    fn new() -> Self {
        Tables {
            lit: [0; 256],
            run: [0; 259],
            eob: 0,
            max_lit_len: 0,
        }
    }

    /// Fill from lit/len code lengths `ll` (286) and the code (`dcode`, `dlen`) of distance 1.
    /// (`ll` may be longer: the fixed code has 288 lengths.)
    fn fill(&mut self, ll: &[u8], dcode: u32, dlen: u32) {
        let mut codes = [0u16; 288];
        let ll = &ll[..ll.len().min(288)];
        let codes = &mut codes[..ll.len()];
        canonical_codes(ll, codes);
        let mut max = 0;
        for ((t, &c), &l) in self.lit.iter_mut().zip(&codes[..256]).zip(&ll[..256]) {
            *t = u32::from(c) << 8 | u32::from(l);
            max = max.max(u32::from(l));
        }
        self.max_lit_len = max;
        self.eob = u32::from(codes[EOB]) << 8 | u32::from(ll[EOB]);
        for (len, t) in self.run.iter_mut().enumerate().skip(MIN_RUN) {
            let s = usize::from(LEN_SYM[len]);
            let (c, l) = (u32::from(codes[257 + s]), u32::from(ll[257 + s]));
            let extra = u32::from(LEN_EXTRA[s]);
            let ev = (len - usize::from(LEN_BASE[s])) as u32;
            let code = c | ev << l | dcode << (l + extra);
            *t = code << 8 | (l + extra + dlen);
        }
    }
}

/// Fixed literal/length code lengths (RFC 1951 3.2.6), all 288 of them (the unused symbols
/// 286 and 287 take part in the canonical code construction).
fn fixed_lengths() -> [u8; 288] {
    let mut l = [0u8; 288];
    for (i, x) in l.iter_mut().enumerate() {
        *x = match i {
            0..=143 => 8,
            144..=255 => 9,
            256..=279 => 7,
            _ => 8,
        };
    }
    l
}

/// Exact 0x80 in every byte of `x` that is zero, 0 elsewhere.
#[inline(always)]
fn zero_bytes(x: u64) -> u64 {
    const L: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    !(((x & L).wrapping_add(L)) | x | L)
}

#[inline(always)]
fn load(b: &[u8], i: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[i..i + 8]);
    u64::from_le_bytes(a)
}

/// Byte histogram of `data` (four interleaved tables to break store-to-load dependencies).
fn histogram(data: &[u8], hist: &mut [u32; 256]) {
    let mut h = [[0u32; 256]; 4];
    let chunks = data.chunks_exact(8);
    let rest = chunks.remainder();
    for c in chunks {
        let w = u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]);
        h[0][(w & 0xff) as usize] += 1;
        h[1][(w >> 8 & 0xff) as usize] += 1;
        h[2][(w >> 16 & 0xff) as usize] += 1;
        h[3][(w >> 24 & 0xff) as usize] += 1;
        h[0][(w >> 32 & 0xff) as usize] += 1;
        h[1][(w >> 40 & 0xff) as usize] += 1;
        h[2][(w >> 48 & 0xff) as usize] += 1;
        h[3][(w >> 56) as usize] += 1;
    }
    for &b in rest {
        h[0][usize::from(b)] += 1;
    }
    for (i, x) in hist.iter_mut().enumerate() {
        *x = h[0][i] + h[1][i] + h[2][i] + h[3][i];
    }
}

impl BlockEncoder {
    pub(crate) fn new() -> Self {
        let mut fixed = Tables::new();
        // distance code 0 of the fixed 5-bit distance code is 00000
        fixed.fill(&fixed_lengths(), 0, 5);
        BlockEncoder {
            runs: Vec::new(),
            huff: HuffmanBuilder::default(),
            cl_stream: Vec::new(),
            cl_lens: [0; 19],
            hclen: 4,
            fixed,
            dynamic: Tables::new(),
        }
    }

    /// Find the runs of bytes equal to their predecessor in `input[start..end]` (the byte before
    /// `start`, if any, counts as a predecessor) and store them split into matches of 3..=258.
    fn scan_runs(&mut self, input: &[u8], start: usize, end: usize) {
        self.runs.clear();
        let end = end.min(input.len());
        let mut j = start.max(1);
        while j < end {
            if j + 8 <= end {
                // x has a zero byte where input[j + k] == input[j + k - 1]
                let x = load(input, j) ^ load(input, j - 1);
                let z = zero_bytes(x);
                if z == 0 {
                    j += 8;
                    continue;
                }
                // first position starting three equal-to-predecessor bytes in this word
                let m = z & (z >> 8) & (z >> 16);
                if m == 0 {
                    // a triple may still start at offsets 6 or 7
                    j += if z >> 48 == 0 { 8 } else { 6 };
                    continue;
                }
                j += (m.trailing_zeros() / 8) as usize;
            } else if input[j] != input[j - 1] {
                j += 1;
                continue;
            }
            // input[j] == input[j - 1]: measure the run
            let v = input[j - 1];
            let vv = u64::from_ne_bytes([v; 8]);
            let mut k = j + 1;
            let mut open = true;
            while k + 8 <= end {
                let x = load(input, k) ^ vv;
                if x != 0 {
                    k += (x.trailing_zeros() / 8) as usize;
                    open = false;
                    break;
                }
                k += 8;
            }
            if open {
                while k < end && input[k] == v {
                    k += 1;
                }
            }
            self.push_run(j, k - j);
            j = k;
        }
    }

    /// Split a run of `len` bytes at `pos` into matches of 3..=258 (a tail of 1-2 bytes stays
    /// literal).
    #[inline]
    fn push_run(&mut self, mut pos: usize, mut len: usize) {
        while len >= MIN_RUN {
            let mut take = len.min(MAX_RUN);
            if len - take > 0 && len - take < MIN_RUN {
                take = len - MIN_RUN;
            }
            self.runs.push(Run {
                pos: pos as u32,
                len: take as u32,
            });
            pos += take;
            len -= take;
        }
    }

    /// Encode `input[start..end]` as one or more blocks (`last`: the final ones).
    pub(crate) fn encode_chunk(
        &mut self,
        input: &[u8],
        start: usize,
        end: usize,
        last: bool,
        w: &mut BitWriter<'_>,
    ) {
        let data = &input[start..end];
        let mut hist = [0u32; 256];
        histogram(data, &mut hist);
        self.scan_runs(input, start, end);

        // symbol frequencies
        let mut freq = [0u32; NLIT];
        freq[..256].copy_from_slice(&hist);
        freq[EOB] = 1;
        let mut extra_bits: u64 = 0;
        for r in &self.runs {
            let v = input[r.pos as usize - 1];
            freq[usize::from(v)] -= r.len;
            let s = usize::from(LEN_SYM[r.len as usize]);
            freq[257 + s] += 1;
            extra_bits += u64::from(LEN_EXTRA[s]);
        }
        let nruns = self.runs.len() as u64;

        // dynamic code
        let mut ll = [0u8; NLIT];
        self.huff.lengths(&freq, 15, &mut ll);
        let hlit = 257 + ll[257..].iter().rposition(|&l| l > 0).map_or(0, |p| p + 1);
        let dl = [1u8, 1];
        let header_bits = self.build_cl_stream(&ll[..hlit], &dl);
        let sym_bits = |lens: &[u8]| -> u64 {
            freq.iter()
                .zip(lens)
                .map(|(&f, &l)| u64::from(f) * u64::from(l))
                .sum::<u64>()
        };
        let dyn_bits = 3 + header_bits + sym_bits(&ll) + extra_bits + nruns;
        let fixed_bits = 3 + sym_bits(&fixed_lengths()) + extra_bits + 5 * nruns;
        let pieces = data.len().div_ceil(MAX_STORED).max(1) as u64;
        let stored_bits = pieces * (3 + 7 + 32) + 8 * data.len() as u64;

        if stored_bits < dyn_bits.min(fixed_bits) {
            self.write_stored(data, last, w);
            return;
        }
        let bhead = u64::from(last);
        if fixed_bits <= dyn_bits {
            w.reserve((fixed_bits / 8) as usize + 16);
            w.put(bhead | 1 << 1, 3);
            write_symbols(&self.fixed, &self.runs, input, start, end, w);
        } else {
            w.reserve((dyn_bits / 8) as usize + 16);
            w.put(bhead | 2 << 1, 3);
            self.write_dynamic_header(hlit, w);
            // distance code 0 has length 1 and code 0 in the two-code distance tree
            self.dynamic.fill(&ll, 0, 1);
            write_symbols(&self.dynamic, &self.runs, input, start, end, w);
        }
    }

    /// Stored blocks for `data` (RFC 1951 3.2.4).
    fn write_stored(&mut self, data: &[u8], last: bool, w: &mut BitWriter<'_>) {
        let mut pieces = data.chunks(MAX_STORED).peekable();
        if data.is_empty() {
            w.put(u64::from(last), 3);
            w.align();
            w.put(0xffff_0000, 32);
            return;
        }
        while let Some(p) = pieces.next() {
            let fin = last && pieces.peek().is_none();
            w.put(u64::from(fin), 3);
            w.align();
            let n = p.len() as u64;
            w.put(n | (n ^ 0xffff) << 16, 32);
            w.put_bytes(p);
        }
    }

    /// Build the run-length coded code-length sequence of `ll` then `dl` into `cl_stream`, its
    /// Huffman code into `cl_lens`, and return the header size in bits after BTYPE.
    fn build_cl_stream(&mut self, ll: &[u8], dl: &[u8]) -> u64 {
        let s = &mut self.cl_stream;
        s.clear();
        let all = ll.iter().chain(dl).copied();
        let n = ll.len() + dl.len();
        let mut prev: Option<u8> = None;
        let mut run = 0usize;
        // emit a run of `run` copies of `v`
        let flush = |s: &mut Vec<u16>, v: u8, mut run: usize| {
            if v == 0 {
                while run >= 11 {
                    let k = run.min(138);
                    s.push(18 | ((k - 11) as u16) << 8);
                    run -= k;
                }
                if run >= 3 {
                    s.push(17 | ((run - 3) as u16) << 8);
                    run = 0;
                }
            } else {
                s.push(u16::from(v));
                run -= 1;
                while run >= 3 {
                    let k = run.min(6);
                    s.push(16 | ((k - 3) as u16) << 8);
                    run -= k;
                }
            }
            for _ in 0..run {
                s.push(u16::from(v));
            }
        };
        for (i, l) in all.enumerate() {
            match prev {
                Some(p) if p == l => run += 1,
                Some(p) => {
                    flush(s, p, run);
                    run = 1;
                }
                None => run = 1,
            }
            prev = Some(l);
            if i + 1 == n {
                flush(s, l, run);
            }
        }
        let mut cf = [0u32; 19];
        for &e in s.iter() {
            cf[usize::from(e & 0xff)] += 1;
        }
        let mut cl = [0u8; 19];
        self.huff.lengths(&cf, 7, &mut cl);
        self.cl_lens = cl;
        let hclen = 4 + CL_ORDER[4..]
            .iter()
            .rposition(|&i| cl[i] > 0)
            .map_or(0, |p| p + 1);
        self.hclen = hclen;
        let mut bits = 5 + 5 + 4 + 3 * hclen as u64;
        for &e in s.iter() {
            let sym = usize::from(e & 0xff);
            bits += u64::from(cl[sym]) + cl_extra(sym);
        }
        bits
    }

    /// Write HLIT/HDIST/HCLEN, the code-length code and the code lengths.
    fn write_dynamic_header(&self, hlit: usize, w: &mut BitWriter<'_>) {
        w.put((hlit - 257) as u64, 5);
        w.put(1, 5); // HDIST = 2
        w.put((self.hclen - 4) as u64, 4);
        for &i in &CL_ORDER[..self.hclen] {
            w.put(u64::from(self.cl_lens[i]), 3);
        }
        let mut codes = [0u16; 19];
        canonical_codes(&self.cl_lens, &mut codes);
        for &e in &self.cl_stream {
            let sym = usize::from(e & 0xff);
            w.put(u64::from(codes[sym]), u32::from(self.cl_lens[sym]));
            let eb = cl_extra(sym) as u32;
            if eb > 0 {
                w.put(u64::from(e >> 8), eb);
            }
        }
    }
}

/// Extra bits after code-length symbol `sym`.
fn cl_extra(sym: usize) -> u64 {
    match sym {
        16 => 2,
        17 => 3,
        18 => 7,
        _ => 0,
    }
}

/// The literals and matches of `input[start..end]` then end-of-block, through `t`.
fn write_symbols(
    t: &Tables,
    runs: &[Run],
    input: &[u8],
    start: usize,
    end: usize,
    w: &mut BitWriter<'_>,
) {
    let lits = |w: &mut BitWriter<'_>, s: &[u8]| {
        if t.max_lit_len <= 14 {
            w.put_literals::<4>(s, &t.lit);
        } else {
            w.put_literals::<3>(s, &t.lit);
        }
    };
    let mut pos = start;
    for r in runs {
        let p = r.pos as usize;
        lits(w, &input[pos..p]);
        w.put_entry(t.run[r.len as usize]);
        pos = p + r.len as usize;
    }
    lits(w, &input[pos..end]);
    w.put_entry(t.eob);
}
