use super::*;

/// A stream for [`encode`]: `w x h` pixels of `nc` components of `p` bits, predictor
/// `pred`, point transform `pt`, restart interval `ri` (0 = none).
#[derive(Clone, Copy)]
pub(crate) struct Stream {
    pub(crate) w: usize,
    pub(crate) h: usize,
    pub(crate) nc: usize,
    pub(crate) p: u8,
    pub(crate) pred: u8,
    pub(crate) pt: u8,
    pub(crate) ri: usize,
}

/// Tiny reference encoder for tests: one Huffman table with categories 0..=16 all 5-bit
/// codes, any predictor, optional restart interval.
pub(crate) fn encode(stream: Stream, samples: &[u16]) -> Vec<u8> {
    let Stream {
        w,
        h,
        nc,
        p,
        pred,
        pt,
        ri,
    } = stream;
    let mut o = vec![0xFF, 0xD8];
    // SOF3
    o.extend_from_slice(&[0xFF, 0xC3]);
    let l = 8 + 3 * nc;
    o.extend_from_slice(&(l as u16).to_be_bytes());
    o.push(p);
    o.extend_from_slice(&(h as u16).to_be_bytes());
    o.extend_from_slice(&(w as u16).to_be_bytes());
    o.push(nc as u8);
    for c in 0..nc {
        o.extend_from_slice(&[c as u8 + 1, 0x11, 0]);
    }
    // DHT: 17 symbols of length 5.
    o.extend_from_slice(&[0xFF, 0xC4]);
    o.extend_from_slice(&((2 + 17 + 17) as u16).to_be_bytes());
    o.push(0x00);
    let mut counts = [0u8; 16];
    counts[4] = 17;
    o.extend_from_slice(&counts);
    o.extend((0..17u8).collect::<Vec<_>>());
    if ri > 0 {
        o.extend_from_slice(&[0xFF, 0xDD, 0, 4]);
        o.extend_from_slice(&(ri as u16).to_be_bytes());
    }
    // SOS
    o.extend_from_slice(&[0xFF, 0xDA]);
    o.extend_from_slice(&((6 + 2 * nc) as u16).to_be_bytes());
    o.push(nc as u8);
    for c in 0..nc {
        o.extend_from_slice(&[c as u8 + 1, 0x00]);
    }
    o.extend_from_slice(&[pred, 0, pt]);
    let mut bw = BitW::default();
    let rl = w * nc;
    let x: Vec<i32> = samples.iter().map(|&s| (s >> pt) as i32).collect();
    let mut left = ri;
    let mut rst = 0u8;
    let mut rcol: Option<usize> = Some(0);
    let mut first = true;
    for r in 0..h {
        for col in 0..w {
            if ri > 0 {
                if left == 0 {
                    bw.flush(&mut o);
                    o.extend_from_slice(&[0xFF, 0xD0 + rst]);
                    rst = (rst + 1) & 7;
                    left = ri;
                    rcol = Some(col);
                    first = true;
                }
                left -= 1;
            }
            for c in 0..nc {
                let i = r * rl + col * nc + c;
                let prd = if rcol == Some(col) && first {
                    1 << (p - pt - 1)
                } else if first {
                    x[i - nc]
                } else if col == 0 {
                    x[i - rl]
                } else {
                    let (ra, rb, rc) = (x[i - nc], x[i - rl], x[i - rl - nc]);
                    match pred {
                        1 => ra,
                        2 => rb,
                        3 => rc,
                        4 => ra + rb - rc,
                        5 => ra + ((rb - rc) >> 1),
                        6 => rb + ((ra - rc) >> 1),
                        _ => (ra + rb) >> 1,
                    }
                };
                let mut d = (x[i] - prd) & 0xFFFF;
                if d >= 32768 {
                    d -= 65536;
                }
                if d == -32768 {
                    bw.put(16, 5);
                    continue;
                }
                let s = if d == 0 {
                    0
                } else {
                    32 - (d.unsigned_abs()).leading_zeros()
                };
                bw.put(s, 5);
                if s > 0 {
                    let v = if d < 0 { d + (1 << s) - 1 } else { d };
                    bw.put(v as u32, s);
                }
            }
        }
        first = false;
        rcol = None;
    }
    bw.flush(&mut o);
    o.extend_from_slice(&[0xFF, 0xD9]);
    o
}

#[derive(Default)]
struct BitW {
    acc: u64,
    n: u32,
    bytes: Vec<u8>,
}
impl BitW {
    fn put(&mut self, v: u32, n: u32) {
        self.acc = (self.acc << n) | (v as u64 & ((1u64 << n) - 1));
        self.n += n;
        while self.n >= 8 {
            let b = (self.acc >> (self.n - 8)) as u8;
            self.bytes.push(b);
            if b == 0xFF {
                self.bytes.push(0);
            }
            self.n -= 8;
        }
    }
    fn flush(&mut self, o: &mut Vec<u8>) {
        if self.n > 0 {
            let pad = 8 - self.n;
            self.put((1 << pad) - 1, pad);
        }
        o.append(&mut self.bytes);
    }
}

fn pseudo(n: usize, bits: u8, seed: u32) -> Vec<u16> {
    let mut s = seed.wrapping_mul(2654435761).wrapping_add(1);
    (0..n)
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            let smooth = ((i % 37) as u32 * 50) & ((1 << bits) - 1);
            ((smooth ^ (s & 0x3F)) & ((1u32 << bits) - 1)) as u16
        })
        .collect()
}

#[test]
fn round_trips_all_predictors_and_components() {
    for nc in 1..=4 {
        for pred in 1..=7u8 {
            for &p in &[8u8, 12, 14, 16] {
                let (w, h) = (13, 7);
                let s = pseudo(w * h * nc, p, pred as u32 + nc as u32);
                let enc = encode(
                    Stream {
                        w,
                        h,
                        nc,
                        p,
                        pred,
                        pt: 0,
                        ri: 0,
                    },
                    &s,
                );
                let d = decode(&enc).unwrap();
                assert_eq!((d.width, d.height, d.components), (w, h, nc));
                assert_eq!(d.data, s, "nc {nc} pred {pred} p {p}");
            }
        }
    }
}

#[test]
fn restart_intervals_and_point_transform() {
    for &ri in &[1usize, 5, 13, 26] {
        let (w, h, nc) = (13, 6, 2);
        let s: Vec<u16> = pseudo(w * h * nc, 12, ri as u32)
            .into_iter()
            .map(|v| v & !3)
            .collect();
        let enc = encode(
            Stream {
                w,
                h,
                nc,
                p: 12,
                pred: 6,
                pt: 2,
                ri,
            },
            &s,
        );
        let d = decode(&enc).unwrap();
        assert_eq!(d.data, s, "ri {ri}");
    }
}

#[test]
fn truncated_and_garbage_streams_fail_cleanly() {
    let s = pseudo(64 * 8, 14, 3);
    let enc = encode(
        Stream {
            w: 64,
            h: 8,
            nc: 1,
            p: 14,
            pred: 1,
            pt: 0,
            ri: 0,
        },
        &s,
    );
    for cut in [0, 1, 2, 10, 30, enc.len() / 2, enc.len() - 3] {
        assert!(decode(&enc[..cut]).is_err(), "cut {cut}");
    }
    let mut bad = enc.clone();
    for i in (40..bad.len()).step_by(7) {
        bad[i] ^= 0x5A;
    }
    let _ = decode(&bad); // must not panic
}

#[test]
fn huge_frame_header_is_refused_before_allocation() {
    let mut enc = encode(
        Stream {
            w: 4,
            h: 4,
            nc: 1,
            p: 12,
            pred: 1,
            pt: 0,
            ri: 0,
        },
        &[0; 16],
    );
    // SOF3 height/width at bytes 7..11.
    enc[7..11].copy_from_slice(&[0xFF, 0xFF, 0xFF, 0xFF]);
    assert!(decode(&enc).is_err());
}
