//! One row of the clean pass's light arithmetic ([`super::relight`]): the per-row scratch
//! buffers, the prepared lights, and mode `local`'s sum over the ambient light, the local
//! lights (a weighted mean) and the bulbs (added), as flat loops that select each column's
//! CFA factor by its parity.

use super::masks::{MaskRow, PreparedMask};

/// A light of the plan with its mask prepared for the pass's columns.
pub(super) struct Prepared {
    pub(super) mask: PreparedMask,
    pub(super) illum: [f32; 3],
    pub(super) gain: f32,
    pub(super) weight: f32,
}

/// One thread's row buffers: the scaled white-balanced input `ye`, the light sum's
/// numerator and denominator, a mask row, and the row's black levels.
pub(super) struct Scratch {
    pub(super) ye: Vec<f32>,
    pub(super) num: Vec<f32>,
    pub(super) den: Vec<f32>,
    pub(super) m: Vec<f32>,
    pub(super) blk: Vec<f64>,
}

impl Scratch {
    pub(super) fn new(w: usize) -> Scratch {
        Scratch {
            ye: vec![0.0; w],
            num: vec![0.0; w],
            den: vec![0.0; w],
            m: vec![0.0; w],
            blk: Vec::new(),
        }
    }
}

/// [`parity`] for f64 pairs.
#[inline]
pub(super) fn parity2(k: [f64; 2], c0: usize) -> [f64; 2] {
    if c0 & 1 == 0 {
        k
    } else {
        [k[1], k[0]]
    }
}

/// The per-colour factors of a row segment starting at column `c0` (even/odd offsets).
#[inline]
pub(super) fn parity(k: [f32; 2], c0: usize) -> [f32; 2] {
    if c0 & 1 == 0 {
        k
    } else {
        [k[1], k[0]]
    }
}

/// Apply `f(num, den, ye, mask, k)` element-wise, where `k` is `k[0]` at the even and
/// `k[1]` at the odd positions of the slices (the CFA factor of the column's colour).
///
/// One flat loop with the factor selected by the index's parity: the compiler turns it
/// into whole-register operations (the select is a blend of two broadcast factors). An
/// earlier shape, eight columns at a time through fixed-size arrays, made the compiler
/// vectorize across the chunks instead and spend most of its instructions on shuffles
/// (docs/benchmarks.md, "Flat loops where the compiler had gone wrong"). The arithmetic
/// per element is the same, so are the bits.
#[inline(always)]
fn pairwise<F: Fn(&mut f32, &mut f32, f32, f32, f32)>(
    num: &mut [f32],
    den: &mut [f32],
    ye: &[f32],
    m: &[f32],
    k: [f32; 2],
    f: F,
) {
    pairwise_masked((num, den, ye), m, |v| v, k, f);
}

/// [`pairwise`] with sample `i`'s mask `mask(cols[i])`: a filled mask row with the
/// identity, or a [`MaskRow`]'s expression computed where it is used.
#[inline(always)]
fn pairwise_masked<T: Copy, G: Fn(T) -> f32, F: Fn(&mut f32, &mut f32, f32, f32, f32)>(
    (num, den, ye): (&mut [f32], &mut [f32], &[f32]),
    cols: &[T],
    mask: G,
    k: [f32; 2],
    f: F,
) {
    let n = cols.len().min(num.len()).min(den.len()).min(ye.len());
    let (num, den, ye, cols) = (&mut num[..n], &mut den[..n], &ye[..n], &cols[..n]);
    for i in 0..n {
        let kk = if i & 1 == 0 { k[0] } else { k[1] };
        f(&mut num[i], &mut den[i], ye[i], mask(cols[i]), kk);
    }
}

/// Apply `f(num, den, ye, mask, k)` over light `p`'s columns of row `r` (the scratch
/// buffers' segment starts at active-area column `x0`), with `k` the CFA factors of the
/// even and odd active-area columns. A separable mask is computed in the loop; an exact
/// one is filled into the scratch's mask row first.
#[inline(always)]
fn over_light<F: Fn(&mut f32, &mut f32, f32, f32, f32)>(
    p: &Prepared,
    r: usize,
    x0: usize,
    k: [f32; 2],
    scr: &mut Scratch,
    f: F,
) {
    let Scratch {
        ye, num, den, m, ..
    } = scr;
    let (c0, c1) = p.mask.cols;
    let (i0, i1) = (c0 - x0, c1 - x0);
    let bufs = (&mut num[i0..i1], &mut den[i0..i1], &ye[i0..i1]);
    let k = parity(k, c0);
    match p.mask.row_view(r) {
        Some(MaskRow::Release { rf, cols, floor }) => {
            pairwise_masked(bufs, cols, |cf| (rf * cf).max(floor) as f32, k, f)
        }
        Some(MaskRow::Separable { rf, cols, floor }) => {
            pairwise_masked(bufs, cols, |cf| (rf * cf).max(floor), k, f)
        }
        None => {
            let mm = &mut m[..c1 - c0];
            p.mask.fill_row(r, mm);
            pairwise(bufs.0, bufs.1, bufs.2, mm, k, f);
        }
    }
}

/// Local relighting of active-area row `r` over the segment of the scratch buffers, whose
/// first sample is active-area column `x0` (the masks' column ranges lie inside it).
///
/// Compiled twice, the second time for AVX2, picked at run time: the same
/// operations per element, so the same bits (docs/benchmarks.md, "AVX2 copies of the hot
/// loops").
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(super) fn local_row(
    r: usize,
    x0: usize,
    cols: [usize; 2],
    ambient: &[Prepared],
    locals: &[Prepared],
    bulbs: &[Prepared],
    scr: &mut Scratch,
) {
    // Ambient: mask 1 everywhere.
    match ambient.first() {
        Some(a) => {
            let k = parity([a.illum[cols[0]] * a.gain, a.illum[cols[1]] * a.gain], x0);
            let w = a.weight;
            let Scratch {
                ye, num, den, m, ..
            } = &mut *scr;
            // the lights' loop (`m` is not read)
            pairwise(num, den, ye, m, k, |n, d, y, _, k| {
                *n = w * (y * k).clamp(0.0, 1.0);
                *d = w;
            });
        }
        None => {
            scr.num.fill(0.0);
            scr.den.fill(0.0);
        }
    }
    for p in locals.iter().filter(|p| p.mask.on_row(r)) {
        let k = [p.illum[cols[0]] * p.gain, p.illum[cols[1]] * p.gain];
        let w = p.weight;
        over_light(p, r, x0, k, scr, |n, d, y, mv, k| {
            let wm = w * mv;
            *n += wm * (y * k).clamp(0.0, 1.0);
            *d += wm;
        });
    }
    for (n, &d) in scr.num.iter_mut().zip(scr.den.iter()) {
        *n /= d.max(1e-30);
    }
    for p in bulbs.iter().filter(|p| p.mask.on_row(r)) {
        let k = [p.illum[cols[0]], p.illum[cols[1]]];
        let g = p.gain;
        over_light(p, r, x0, k, scr, |n, _, y, mv, k| {
            *n += g * mv * (y * k).clamp(0.0, 1.0);
        });
    }
    for n in scr.num.iter_mut() {
        *n = if n.is_nan() { 0.0 } else { n.clamp(0.0, 1.0) };
    }
}
