//! LSB-first bit writer over a growable byte buffer (RFC 1951 section 3.1.1 bit order).
//!
//! The writer keeps up to 63 pending bits in a `u64` and flushes them with one unconditional
//! 8-byte store: the output vector is grown (zero-filled) ahead of time by [`BitWriter::reserve`]
//! and truncated to the real length by [`BitWriter::finish`], so a flush is a single slice
//! copy whose bounds check never fails.

/// LSB-first bit writer appending to a `Vec<u8>`.
pub(crate) struct BitWriter<'a> {
    buf: &'a mut Vec<u8>,
    /// Next byte to write in `buf`.
    pos: usize,
    /// Pending bits, the oldest in the least significant position.
    bits: u64,
    /// Number of pending bits, at most 63.
    n: u32,
}

impl<'a> BitWriter<'a> {
    /// A writer appending after the current end of `buf`.
    pub(crate) fn new(buf: &'a mut Vec<u8>) -> Self {
        let pos = buf.len();
        BitWriter {
            buf,
            pos,
            bits: 0,
            n: 0,
        }
    }

    /// Make room for at least `bytes` more bytes (plus the 8-byte flush slack).
    pub(crate) fn reserve(&mut self, bytes: usize) {
        let need = self.pos + bytes + 16;
        if self.buf.len() < need {
            // grow geometrically so that many small reservations stay linear
            let grow = need.max(self.buf.len() + self.buf.len() / 2);
            self.buf.resize(grow, 0);
        }
    }

    /// Bits already used in the current (incomplete) byte, 0..=7.
    pub(crate) fn bit_offset(&self) -> u32 {
        self.n & 7
    }

    /// Store the pending bits and keep only the incomplete last byte pending.
    #[inline(always)]
    fn flush(&mut self) {
        if self.pos + 8 > self.buf.len() {
            self.reserve(8);
        }
        self.buf[self.pos..self.pos + 8].copy_from_slice(&self.bits.to_le_bytes());
        let nb = self.n >> 3;
        self.pos += nb as usize;
        // nb <= 7, so the shift is at most 56
        self.bits >>= nb * 8;
        self.n &= 7;
    }

    /// Append the `n` low bits of `v` (`n <= 56`, `v < 2^n`).
    #[inline(always)]
    pub(crate) fn put(&mut self, v: u64, n: u32) {
        debug_assert!(n <= 56 && (n == 64 || v >> n == 0));
        if self.n + n > 63 {
            self.flush();
        }
        self.bits |= v << self.n;
        self.n += n;
    }

    /// Append a table entry `code << 8 | len` (`len <= 56`).
    #[cfg(test)]
    pub(crate) fn put_entry(&mut self, e: u32) {
        self.put(u64::from(e >> 8), e & 0xff);
    }

    /// Pad with zero bits to the next byte boundary.
    pub(crate) fn align(&mut self) {
        let pad = (8 - (self.n & 7)) & 7;
        self.put(0, pad);
    }

    /// Append whole bytes; the writer must be byte-aligned.
    pub(crate) fn put_bytes(&mut self, bytes: &[u8]) {
        debug_assert_eq!(self.n & 7, 0);
        self.flush();
        debug_assert_eq!(self.n, 0);
        let end = self.pos + bytes.len();
        if self.buf.len() < end + 8 {
            self.reserve(bytes.len());
        }
        self.buf[self.pos..end].copy_from_slice(bytes);
        self.pos = end;
    }

    /// The writer's state as plain locals for a hot loop: flush with at most 7 pending bits
    /// first, so the loop may add up to 57 bits between [`RawBits::flush`] calls. The buffer
    /// must have been [`BitWriter::reserve`]d for everything the loop writes.
    pub(crate) fn raw(&mut self) -> RawBits<'_> {
        self.flush();
        RawBits {
            buf: self.buf.as_mut_slice(),
            pos: self.pos,
            bits: self.bits,
            n: self.n,
        }
    }

    /// Take back the state of a [`BitWriter::raw`] loop.
    pub(crate) fn set_raw(&mut self, (pos, bits, n): (usize, u64, u32)) {
        self.pos = pos;
        self.bits = bits;
        self.n = n;
    }

    /// Flush everything (padding the last byte with zeros), truncate the buffer to the written
    /// length and return the number of bytes appended.
    pub(crate) fn finish(mut self) -> usize {
        self.align();
        self.flush();
        self.buf.truncate(self.pos);
        self.pos
    }
}

/// Writer state in locals (see [`BitWriter::raw`]).
pub(crate) struct RawBits<'b> {
    buf: &'b mut [u8],
    pos: usize,
    pub(crate) bits: u64,
    pub(crate) n: u32,
}

impl RawBits<'_> {
    /// Store `bits` at the current byte (unconditional 8-byte store; panics if the buffer
    /// was not reserved, a bug, never input-dependent).
    #[inline(always)]
    pub(crate) fn store(&mut self, bits: u64) {
        self.buf[self.pos..self.pos + 8].copy_from_slice(&bits.to_le_bytes());
    }

    /// Move the byte position on by `nb` complete bytes.
    #[inline(always)]
    pub(crate) fn advance(&mut self, nb: u32) {
        self.pos += nb as usize;
    }

    /// The state to hand back with [`BitWriter::set_raw`].
    pub(crate) fn into_state(self) -> (usize, u64, u32) {
        (self.pos, self.bits, self.n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lsb_first_order() {
        let mut v = vec![0xAA];
        let mut w = BitWriter::new(&mut v);
        w.put(1, 1);
        w.put(0b10, 2);
        w.put(0x1f, 5);
        w.put(0x1234, 16);
        w.put(1, 3);
        w.finish();
        assert_eq!(v, vec![0xAA, 0b1111_1101, 0x34, 0x12, 0x01]);
    }

    #[test]
    fn raw_matches_put() {
        let entries: Vec<u32> = (0..1001u32)
            .map(|i| {
                let len = 1 + (i % 14);
                ((i * 7919) & ((1 << len) - 1)) << 8 | len
            })
            .collect();
        let mut a = Vec::new();
        let mut w = BitWriter::new(&mut a);
        w.put(1, 3);
        w.reserve(entries.len() * 2);
        let mut st = w.raw();
        for e in &entries {
            st.bits |= u64::from(e >> 8) << st.n;
            st.n += e & 0xff;
            st.store(st.bits);
            st.advance(st.n >> 3);
            st.bits >>= (st.n >> 3) * 8;
            st.n &= 7;
        }
        let state = st.into_state();
        w.set_raw(state);
        w.put(5, 3);
        w.finish();
        let mut b = Vec::new();
        let mut w = BitWriter::new(&mut b);
        w.put(1, 3);
        for &e in &entries {
            w.put_entry(e);
        }
        w.put(5, 3);
        w.finish();
        assert_eq!(a, b);
    }

    #[test]
    fn bytes_after_align() {
        let mut v = Vec::new();
        let mut w = BitWriter::new(&mut v);
        w.put(0b101, 3);
        w.align();
        w.put_bytes(&[1, 2, 3]);
        w.put(0xff, 8);
        assert_eq!(w.finish(), 5);
        assert_eq!(v, vec![0b101, 1, 2, 3, 0xff]);
    }
}
