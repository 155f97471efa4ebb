//! Length-limited Huffman code construction and canonical codes (RFC 1951 section 3.2.2).
//!
//! Optimal lengths come from Moffat and Katajainen's in-place algorithm ("In-place calculation
//! of minimum-redundancy codes", 1995) on the symbols sorted by frequency; lengths over the limit
//! are then folded back with the Kraft-sum repair used by zlib and miniz (move the overflowing
//! leaves to the limit, then lengthen the deepest shorter codes until the code is complete).
//! Every code built here is complete (Kraft sum exactly 1): when fewer than two symbols are
//! used, a second symbol is given a length-1 code too, because some inflaters reject the
//! incomplete one-code trees that RFC 1951 otherwise allows.

/// Scratch space reused between calls (no allocation per block once warm).
#[derive(Default)]
pub(crate) struct HuffmanBuilder {
    /// `freq << 16 | symbol` of the used symbols, sorted ascending.
    sorted: Vec<u64>,
    /// Frequencies, then code lengths, in `sorted` order.
    work: Vec<u32>,
}

/// Deepest code the unlimited construction can produce with `u32` frequency sums, rounded up.
const MAX_DEPTH: usize = 64;

impl HuffmanBuilder {
    /// Code lengths for `freqs` into `lens` (same length, at most 65536 symbols), none longer
    /// than `max_len` (1..=15), 0 for unused symbols. The total frequency must fit in `u32`.
    pub(crate) fn lengths(&mut self, freqs: &[u32], max_len: u32, lens: &mut [u8]) {
        debug_assert_eq!(freqs.len(), lens.len());
        debug_assert!((1..=15).contains(&max_len) && freqs.len() <= 1 << 16);
        lens.fill(0);
        self.sorted.clear();
        self.sorted.extend(
            freqs
                .iter()
                .enumerate()
                .filter(|(_, &f)| f > 0)
                .map(|(s, &f)| u64::from(f) << 16 | s as u64),
        );
        if self.sorted.len() < 2 {
            // one or no symbol: two length-1 codes (the used one and a neighbour)
            let s = self.sorted.first().map_or(0, |&k| (k & 0xffff) as usize);
            let other = if s == 0 { 1 } else { s - 1 };
            if let Some(l) = lens.get_mut(s) {
                *l = 1;
            }
            if let Some(l) = lens.get_mut(other) {
                *l = 1;
            }
            return;
        }
        self.sorted.sort_unstable();
        self.work.clear();
        self.work
            .extend(self.sorted.iter().map(|&k| (k >> 16) as u32));
        minimum_redundancy(&mut self.work);

        // count codes per length, folding anything deeper than max_len into max_len
        let max = max_len as usize;
        let mut count = [0u32; MAX_DEPTH + 1];
        for &l in &self.work {
            count[(l as usize).min(max)] += 1;
        }
        let mut total: u64 = (1..=max).map(|i| u64::from(count[i]) << (max - i)).sum();
        let full = 1u64 << max;
        while total > full {
            // drop one leaf from the deepest level and split a shorter leaf into two
            count[max] -= 1;
            if let Some(i) = (1..max).rev().find(|&i| count[i] != 0) {
                count[i] -= 1;
                count[i + 1] += 2;
            }
            total -= 1;
        }

        // most frequent symbols (end of `sorted`) get the shortest codes
        let mut syms = self.sorted.iter().rev();
        for (len, &c) in count.iter().enumerate().take(max + 1).skip(1) {
            for _ in 0..c {
                if let Some(&k) = syms.next() {
                    if let Some(l) = lens.get_mut((k & 0xffff) as usize) {
                        *l = len as u8;
                    }
                }
            }
        }
    }
}

/// Moffat-Katajainen: `a` holds frequencies sorted ascending (at least two); on return it
/// holds the optimal code length of each (unbounded depth).
fn minimum_redundancy(a: &mut [u32]) {
    let n = a.len();
    if n < 2 {
        if let Some(x) = a.first_mut() {
            *x = 1;
        }
        return;
    }
    // phase 1: build the tree in place; a[i] becomes the parent index of internal node i
    a[0] += a[1];
    let mut root = 0usize;
    let mut leaf = 2usize;
    for next in 1..n - 1 {
        if leaf >= n || a[root] < a[leaf] {
            a[next] = a[root];
            a[root] = next as u32;
            root += 1;
        } else {
            a[next] = a[leaf];
            leaf += 1;
        }
        if leaf >= n || (root < next && a[root] < a[leaf]) {
            a[next] += a[root];
            a[root] = next as u32;
            root += 1;
        } else {
            a[next] += a[leaf];
            leaf += 1;
        }
    }
    // phase 2: internal node depths
    a[n - 2] = 0;
    for next in (0..n.saturating_sub(2)).rev() {
        a[next] = a[a[next] as usize] + 1;
    }
    // phase 3: leaf depths
    let mut avbl: i64 = 1;
    let mut used: i64 = 0;
    let mut dpth: u32 = 0;
    let mut root = n as i64 - 2;
    let mut next = n as i64 - 1;
    while avbl > 0 {
        while root >= 0 && a[root as usize] == dpth {
            used += 1;
            root -= 1;
        }
        while avbl > used {
            a[next as usize] = dpth;
            next -= 1;
            avbl -= 1;
        }
        avbl = 2 * used;
        dpth += 1;
        used = 0;
    }
}

/// Canonical codes for `lens` (RFC 1951 3.2.2), bit-reversed for LSB-first output, into
/// `codes` (same length). Lengths must describe a valid (complete or under-full) code.
pub(crate) fn canonical_codes(lens: &[u8], codes: &mut [u16]) {
    let mut bl_count = [0u16; 16];
    for &l in lens {
        bl_count[usize::from(l & 15)] += 1;
    }
    bl_count[0] = 0;
    let mut next_code = [0u16; 16];
    let mut code: u16 = 0;
    for bits in 1..16 {
        code = (code + bl_count[bits - 1]) << 1;
        next_code[bits] = code;
    }
    for (c, &l) in codes.iter_mut().zip(lens) {
        if l == 0 {
            *c = 0;
            continue;
        }
        let l = usize::from(l & 15);
        *c = reverse(next_code[l], l as u32);
        next_code[l] = next_code[l].wrapping_add(1);
    }
}

/// The `n` low bits of `code` in reverse order.
#[inline]
pub(crate) fn reverse(code: u16, n: u32) -> u16 {
    if n == 0 {
        0
    } else {
        code.reverse_bits() >> (16 - n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kraft(lens: &[u8]) -> f64 {
        lens.iter()
            .filter(|&&l| l > 0)
            .map(|&l| 0.5f64.powi(l as i32))
            .sum()
    }

    #[test]
    fn two_symbols_and_fewer() {
        let mut b = HuffmanBuilder::default();
        let mut lens = [9u8; 5];
        b.lengths(&[0, 0, 0, 0, 0], 15, &mut lens);
        assert_eq!(lens, [1, 1, 0, 0, 0]);
        b.lengths(&[0, 0, 7, 0, 0], 15, &mut lens);
        assert_eq!(lens, [0, 1, 1, 0, 0]);
        b.lengths(&[3, 0, 0, 0, 0], 15, &mut lens);
        assert_eq!(lens, [1, 1, 0, 0, 0]);
        b.lengths(&[3, 0, 0, 0, 100], 15, &mut lens);
        assert_eq!(lens, [1, 0, 0, 0, 1]);
    }

    #[test]
    fn optimal_small() {
        let mut b = HuffmanBuilder::default();
        let mut lens = [0u8; 4];
        b.lengths(&[1, 1, 2, 4], 15, &mut lens);
        assert_eq!(lens, [3, 3, 2, 1]);
        let mut lens = [0u8; 4];
        b.lengths(&[5, 5, 5, 5], 15, &mut lens);
        assert_eq!(lens, [2, 2, 2, 2]);
    }

    #[test]
    fn fibonacci_is_limited_and_complete() {
        // Fibonacci frequencies give a maximally deep unlimited tree
        let mut f = vec![1u32, 1];
        while f.len() < 40 {
            let n = f[f.len() - 1] + f[f.len() - 2];
            f.push(n);
        }
        let mut b = HuffmanBuilder::default();
        for max in [7u32, 9, 15] {
            let mut lens = vec![0u8; f.len()];
            b.lengths(&f, max, &mut lens);
            assert!(lens.iter().all(|&l| l >= 1 && l as u32 <= max), "{lens:?}");
            assert_eq!(kraft(&lens), 1.0);
            // more frequent never longer
            for i in 1..f.len() {
                assert!(lens[i] <= lens[i - 1]);
            }
        }
    }

    #[test]
    fn canonical_rfc_example() {
        // RFC 1951 3.2.2: lengths (3,3,3,3,3,2,4,4) give codes 010,011,100,101,110,00,1110,1111
        let lens = [3u8, 3, 3, 3, 3, 2, 4, 4];
        let mut codes = [0u16; 8];
        canonical_codes(&lens, &mut codes);
        let want = [0b010u16, 0b011, 0b100, 0b101, 0b110, 0b00, 0b1110, 0b1111];
        for i in 0..8 {
            assert_eq!(codes[i], reverse(want[i], lens[i] as u32));
        }
    }
}
