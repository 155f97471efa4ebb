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
/// Shortest run searched for: shorter runs stay literals. On the EXR planes runs of 3..7
/// bytes are mostly of the plane's most frequent byte, which then keeps a short literal code;
/// 8 gave the smallest output there (docs/deflate.md) and fewer matches to write.
const FIND_RUN: usize = 8;
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

/// One distance-1 match: `len` (3..=258) bytes at `pos` (relative to the chunk start) equal
/// to the byte before them.
#[derive(Clone, Copy)]
struct Run {
    pos: u32,
    len: u32,
}

/// Reusable scratch state of the encoder.
pub(crate) struct BlockEncoder {
    runs: Vec<Run>,
    /// Equal-to-previous bitmap of the current chunk.
    eq: Vec<u64>,
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

/// Eight interleaved byte histograms (summed at the end): the data is concentrated on a few
/// values, so one table would serialize on store-to-load forwarding of the same counter.
struct Hist8([[u32; 256]; 8]);

impl Hist8 {
    #[inline(always)]
    fn add(&mut self, data: &[u8]) {
        let h = &mut self.0;
        let chunks = data.chunks_exact(8);
        let rest = chunks.remainder();
        for c in chunks {
            let w = u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]);
            h[0][(w & 0xff) as usize] += 1;
            h[1][(w >> 8 & 0xff) as usize] += 1;
            h[2][(w >> 16 & 0xff) as usize] += 1;
            h[3][(w >> 24 & 0xff) as usize] += 1;
            h[4][(w >> 32 & 0xff) as usize] += 1;
            h[5][(w >> 40 & 0xff) as usize] += 1;
            h[6][(w >> 48 & 0xff) as usize] += 1;
            h[7][(w >> 56) as usize] += 1;
        }
        for (k, &b) in rest.iter().enumerate() {
            h[k][usize::from(b)] += 1;
        }
    }

    fn sum_into(&self, out: &mut [u32]) {
        for (i, x) in out.iter_mut().enumerate().take(256) {
            *x = self.0.iter().map(|t| t[i]).sum();
        }
    }
}

/// Bit k set where `a[k] == b[k]` (SWAR: exact zero-byte flags of `a ^ b`, gathered into
/// 8 bits per word with one multiplication).
#[inline(always)]
fn eq_mask64(a: &[u8; 64], b: &[u8; 64]) -> u64 {
    const L: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    let mut m = 0u64;
    for (k, (x, y)) in a.chunks_exact(8).zip(b.chunks_exact(8)).enumerate() {
        let x = u64::from_le_bytes([x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]]);
        let y = u64::from_le_bytes([y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7]]);
        let d = x ^ y;
        // 0x80 in each byte of d that is zero: no carries cross bytes since 0x7f + 0x7f < 0x100
        let z = !(((d & L).wrapping_add(L)) | d | L);
        // byte i's flag (bit 8i + 7 of z) to bit 56 + i: the partial products of lower bytes
        // land on distinct bits below 56, so nothing carries into the top byte
        let bits = ((z >> 7).wrapping_mul(0x0102_0408_1020_4080)) >> 56;
        m |= bits << (8 * k);
    }
    m
}

/// `eq[w]` bit k = whether `input[start + 64 w + k]` equals the byte before it (false for
/// position 0 and past `end`).
///
/// Compiled twice, the second time for AVX2 and BMI1/2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2+bmi1+bmi2+lzcnt"))]
#[inline(never)]
fn eq_bitmap(input: &[u8], start: usize, end: usize, eq: &mut Vec<u64>) {
    // one load per cache line first: many independent loads in flight pull a chunk that is
    // not in cache in much faster than the compute-heavy loop below would
    let mut x = 0u8;
    for c in input[start..end].chunks(64) {
        x ^= c[0];
    }
    std::hint::black_box(x);
    let n = end - start;
    eq.clear();
    eq.resize(n.div_ceil(64) + 1, 0);
    let mut w = 0;
    let mut p = start;
    if p == 0 && n >= 65 {
        // no predecessor for position 0: compare positions 1..=64 and shift
        let a: &[u8; 64] = input[1..65].try_into().unwrap_or(&[0; 64]);
        let b: &[u8; 64] = input[0..64].try_into().unwrap_or(&[0; 64]);
        eq[0] = eq_mask64(a, b) << 1;
        w = 1;
        p = 64;
    }
    if p > 0 {
        while p + 64 <= end {
            let a: &[u8; 64] = input[p..p + 64].try_into().unwrap_or(&[0; 64]);
            let b: &[u8; 64] = input[p - 1..p + 63].try_into().unwrap_or(&[0; 64]);
            eq[w] = eq_mask64(a, b);
            w += 1;
            p += 64;
        }
    }
    // tail (and tiny first chunks) byte by byte
    while p < end {
        if p > 0 && input[p] == input[p - 1] {
            let k = p - start;
            eq[k / 64] |= 1 << (k % 64);
        }
        p += 1;
    }
}

impl BlockEncoder {
    pub(crate) fn new() -> Self {
        let mut fixed = Tables::new();
        // distance code 0 of the fixed 5-bit distance code is 00000
        fixed.fill(&fixed_lengths(), 0, 5);
        BlockEncoder {
            runs: Vec::new(),
            eq: Vec::new(),
            huff: HuffmanBuilder::default(),
            cl_stream: Vec::new(),
            cl_lens: [0; 19],
            hclen: 4,
            fixed,
            dynamic: Tables::new(),
        }
    }

    /// Find the runs of at least [`FIND_RUN`] bytes equal to their predecessor in
    /// `input[start..end]` (the byte before `start`, if any, counts as a predecessor), store them
    /// split into matches of 3..=258 in
    /// `runs` and count the remaining literal bytes into `lit_hist`.
    fn scan_runs(&mut self, input: &[u8], start: usize, end: usize, lit_hist: &mut [u32]) {
        scan_runs(self, input, start, end, lit_hist);
    }

    /// [`BlockEncoder::scan_runs`]'s body.
    #[inline(always)]
    fn scan_runs_body(&mut self, input: &[u8], start: usize, end: usize, lit_hist: &mut [u32]) {
        self.runs.clear();
        eq_bitmap(input, start, end, &mut self.eq);
        let eq = &self.eq;
        let runs = &mut self.runs;
        let n = end - start;
        let nw = eq.len() - 1; // last word is a zero sentinel
        let mut hist = Hist8([[0; 256]; 8]);
        // bit k of starts(i): positions k..k + FIND_RUN (relative to word i) all
        // equal-to-previous, i.e. a run worth a match may start at k
        let starts = |i: usize| {
            let (e, f) = (eq[i], eq[i + 1]);
            let mut m = e;
            for s in 1..FIND_RUN as u32 {
                m &= e >> s | f << (64 - s);
            }
            m
        };
        let mut pos = 0usize; // next unprocessed position relative to start
        let mut i = 0usize;
        let mut t = if nw > 0 { starts(0) } else { 0 };
        loop {
            // next run start at or after pos
            while t == 0 {
                i += 1;
                if i >= nw {
                    break;
                }
                t = starts(i);
            }
            if t == 0 {
                break;
            }
            let k = i * 64 + t.trailing_zeros() as usize;
            // length: ones of eq from k on
            let mut j = k / 64;
            let mut e = eq[j] >> (k % 64);
            let mut len = (!e).trailing_zeros() as usize;
            if len == 64 - k % 64 {
                loop {
                    j += 1;
                    e = eq[j];
                    let o = (!e).trailing_zeros() as usize;
                    len += o;
                    if o < 64 {
                        break;
                    }
                }
            }
            hist.add(&input[start + pos..start + k]);
            // positions relative to the chunk (at most 16 MiB) fit in u32 for any input size
            push_run(runs, k, len);
            pos = k + len;
            // continue the search after the run
            i = pos / 64;
            if i >= nw {
                break;
            }
            t = starts(i) & (!0u64 << (pos % 64));
        }
        hist.add(&input[start + pos.min(n)..end]);
        hist.sum_into(lit_hist);
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
        // symbol frequencies
        let mut freq = [0u32; NLIT];
        self.scan_runs(input, start, end, &mut freq[..256]);
        freq[EOB] = 1;
        let mut extra_bits: u64 = 0;
        for r in &self.runs {
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
        // exact: the first header pads from the current bit offset, later ones from a byte
        // boundary (3 + 5 bits); so choosing by these costs keeps the stream no longer than
        // all-stored (5 bytes per piece)
        let pieces = data.len().div_ceil(MAX_STORED).max(1) as u64;
        let off = u64::from(w.bit_offset());
        let first_pad = (8 - (off + 3) % 8) % 8;
        let stored_bits = 3 + first_pad + 32 + (pieces - 1) * 40 + 8 * data.len() as u64;

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

/// [`BlockEncoder::scan_runs`], compiled twice like [`write_symbols`].
#[multiversion::multiversion(targets("x86_64+avx2+bmi1+bmi2+lzcnt"))]
#[inline(never)]
fn scan_runs(enc: &mut BlockEncoder, input: &[u8], start: usize, end: usize, lit_hist: &mut [u32]) {
    enc.scan_runs_body(input, start, end, lit_hist);
}

/// The literals and matches of `input[start..end]` then end-of-block, through `t`. The caller
/// reserved room for the whole block in `w`.
///
/// Compiled twice, the second time for AVX2 and BMI1/2 (shifts by a variable count,
/// trailing-zero counts), picked at run time: integer arithmetic only, so the same bytes
/// (docs/benchmarks.md, "AVX2 copies of the hot loops").
#[multiversion::multiversion(targets("x86_64+avx2+bmi1+bmi2+lzcnt"))]
#[inline(never)]
fn write_symbols(
    t: &Tables,
    runs: &[Run],
    input: &[u8],
    start: usize,
    end: usize,
    w: &mut BitWriter<'_>,
) {
    if t.max_lit_len <= 14 {
        write_symbols_k::<4>(t, runs, input, start, end, w);
    } else {
        write_symbols_k::<3>(t, runs, input, start, end, w);
    }
}

/// [`write_symbols`] adding `K` (3 or 4) literals between flushes: at most 7 pending bits plus
/// K codes of at most 15 (K = 3) or 14 (K = 4) bits.
#[inline(always)]
fn write_symbols_k<const K: usize>(
    t: &Tables,
    runs: &[Run],
    input: &[u8],
    start: usize,
    end: usize,
    w: &mut BitWriter<'_>,
) {
    let lit = &t.lit;
    let mut st = w.raw();
    let (mut bits, mut n) = (st.bits, st.n);
    // store the pending bits, keep the (at most 7) bits of the last incomplete byte
    macro_rules! flush {
        () => {{
            st.store(bits);
            let nb = n >> 3;
            st.advance(nb);
            bits >>= nb * 8;
            n &= 7;
        }};
    }
    // the literal run `lits`, leaving at most 7 pending bits
    macro_rules! literals {
        ($lits:expr) => {{
            let lits: &[u8] = $lits;
            let chunks = lits.chunks_exact(K);
            let rest = chunks.remainder();
            for c in chunks {
                // combine codes pairwise to shorten the dependency chain through `n`
                let e0 = lit[usize::from(c[0])];
                let e1 = lit[usize::from(c[1])];
                let e2 = lit[usize::from(c[2])];
                let (l0, l1, l2) = (e0 & 0xff, e1 & 0xff, e2 & 0xff);
                let c01 = u64::from(e0 >> 8) | u64::from(e1 >> 8) << l0;
                let (code, len) = if K == 4 {
                    let e3 = lit[usize::from(c[3])];
                    let c23 = u64::from(e2 >> 8) | u64::from(e3 >> 8) << l2;
                    (c01 | c23 << (l0 + l1), l0 + l1 + l2 + (e3 & 0xff))
                } else {
                    (c01 | u64::from(e2 >> 8) << (l0 + l1), l0 + l1 + l2)
                };
                bits |= code << n;
                n += len;
                flush!();
            }
            for &b in rest {
                let e = lit[usize::from(b)];
                bits |= u64::from(e >> 8) << n;
                n += e & 0xff;
            }
            flush!();
        }};
    }
    // one entry of at most 21 bits after `literals!`
    macro_rules! entry {
        ($e:expr) => {{
            let e: u32 = $e;
            bits |= u64::from(e >> 8) << n;
            n += e & 0xff;
            flush!();
        }};
    }
    let mut pos = start;
    for r in runs {
        let p = start + r.pos as usize;
        literals!(&input[pos..p]);
        entry!(t.run[r.len as usize]);
        pos = p + r.len as usize;
    }
    literals!(&input[pos..end]);
    entry!(t.eob);
    st.bits = bits;
    st.n = n;
    let state = st.into_state();
    w.set_raw(state);
}

/// Split a run of `len` bytes at `pos` into matches of 3..=258 (a tail of 1-2 bytes stays
/// literal).
#[inline]
fn push_run(runs: &mut Vec<Run>, mut pos: usize, mut len: usize) {
    while len >= MIN_RUN {
        let mut take = len.min(MAX_RUN);
        if len - take > 0 && len - take < MIN_RUN {
            take = len - MIN_RUN;
        }
        runs.push(Run {
            pos: pos as u32,
            len: take as u32,
        });
        pos += take;
        len -= take;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq_mask_matches_bytewise() {
        let mut s = 12345u64;
        for _ in 0..200 {
            let mut a = [0u8; 64];
            let mut b = [0u8; 64];
            for k in 0..64 {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                a[k] = (s >> 60) as u8;
                b[k] = if (s >> 40) & 1 == 0 {
                    a[k]
                } else {
                    (s >> 52) as u8
                };
            }
            let want = (0..64).fold(0u64, |m, k| m | u64::from(a[k] == b[k]) << k);
            assert_eq!(eq_mask64(&a, &b), want);
        }
        assert_eq!(eq_mask64(&[7; 64], &[7; 64]), !0);
        assert_eq!(eq_mask64(&[0; 64], &[0x80; 64]), 0);
    }

    #[test]
    fn len_symbols() {
        for (len, &s) in LEN_SYM.iter().enumerate().skip(3) {
            let s = usize::from(s);
            let base = usize::from(LEN_BASE[s]);
            assert!(len >= base && len - base < 1 << LEN_EXTRA[s], "{len}");
        }
        assert_eq!(LEN_SYM[258], 28);
        assert_eq!(LEN_SYM[257], 27);
    }
}
