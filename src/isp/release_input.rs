//! The night ISP's network input as the authors' release builds it (their camera pipeline
//! up to its demosaic stage; docs/experiment.md): black/white normalization per 2x2 CFA
//! site, white balance by a neutral, 14-bit quantization, OpenCV's bilinear Bayer demosaic
//! in integers, then a table from the 14-bit codes to the float values (`code / 16383`,
//! optionally raised to a gamma).
//!
//! The arithmetic is that of the Python package's `day2night.train.preprocess` (float32
//! per sample, in the same order), so [`release_codes`] gives the codes its
//! `network_input_array` looks up, sample for sample; the Python package passes its own
//! table (numpy's `float32 ** gamma`) so that the floats are the same bits too.
//!
//! Steps on a CFA plane (`top`, `left`: its offset in the active area, which selects the
//! CFA phase and the BlackLevel pattern's phase):
//! 1. LinearizationTable, when one is given: `table[min(x, len - 1)]`;
//! 2. `max(x - black, 0) / (white - black)` per 2x2 site (BlackLevelDeltaH/V not applied);
//! 3. divided by the neutral component of the site's colour, clipped to [0, 1];
//! 4. `(v * 16383) as u16` (truncated), demosaiced: at a red or blue site green is
//!    `(a + b + c + d + 2) >> 2` of the 4 neighbours and the other colour that of the 4
//!    diagonals; at a green site each other colour is `(a + b + 1) >> 1` of its two
//!    neighbours; the first and last rows and columns copy their inner neighbours.

use crate::error::{Error, Result};
use crate::raw::{Bayer, Levels};

/// The 14-bit scale of the release's demosaic stage.
pub const RELEASE_SCALE: u16 = 16383;

/// The release's gamma exponent (`x ** (1 / 2.2)`).
pub const RELEASE_GAMMA: f64 = 1.0 / 2.2;

/// Per 2x2 site of a plane (order (0,0), (0,1), (1,0), (1,1)): its colour, black level,
/// `white - black` and neutral component, in the float32 arithmetic of the release.
#[derive(Debug, Clone, Copy)]
struct Sites {
    black: [f32; 4],
    scale: [f32; 4],
    neutral: [f32; 4],
    colour: [usize; 4],
}

impl Sites {
    fn new(
        levels: &Levels,
        bayer: Bayer,
        neutral: [f64; 3],
        top: usize,
        left: usize,
    ) -> Result<Sites> {
        if neutral.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(Error::invalid(format!(
                "neutral {neutral:?}: need 3 positive finite components"
            )));
        }
        let (rr, rc) = levels.black_repeat;
        let values = &levels.black;
        if rr == 0 || rc == 0 || (values.len() != 1 && values.len() != rr * rc) {
            return Err(Error::invalid(format!(
                "black level {values:?} does not fill its {rr}x{rc} repeat pattern"
            )));
        }
        let mut s = Sites {
            black: [0.0; 4],
            scale: [0.0; 4],
            neutral: [0.0; 4],
            colour: [0; 4],
        };
        for k in 0..4 {
            let (i, j) = (k >> 1, k & 1);
            let b = if values.len() == 1 {
                values[0]
            } else {
                values[((top + i) % rr) * rc + (left + j) % rc]
            };
            let scale = levels.white - b;
            if scale.is_nan() || scale <= 0.0 {
                return Err(Error::invalid(format!(
                    "black level {b} >= white level {}",
                    levels.white
                )));
            }
            let c = bayer.color_at(top + i, left + j) as usize;
            s.black[k] = b as f32;
            s.scale[k] = scale as f32;
            s.colour[k] = c;
            s.neutral[k] = neutral[c] as f32;
        }
        Ok(s)
    }
}

/// The demosaiced 14-bit codes of the release's network input of a CFA `plane` (`width` x
/// `height`, row-major, at active-area offset (`top`, `left`)): `height * width * 3` codes
/// (R, G, B interleaved), steps 1-4 of the module documentation. `levels` and `bayer` are
/// the frame's, `neutral` the white balance (camera RGB, any scale), `linearization` the
/// frame's LinearizationTable for stored samples (None for linear samples). The plane must
/// be at least 3 x 3.
/// A CFA plane cut from a frame: its samples (`width` x `height`, row-major) and where it
/// sits in the active area (`top`, `left`: the CFA phase).
#[derive(Debug, Clone, Copy)]
pub struct CfaPlane<'a> {
    /// The samples.
    pub data: &'a [u16],
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
    /// Row of the plane's first sample in the active area.
    pub top: usize,
    /// Column of the plane's first sample in the active area.
    pub left: usize,
}

/// What the release's input needs to know of the frame a plane comes from.
#[derive(Debug, Clone, Copy)]
pub struct FrameFacts<'a> {
    /// The frame's black and white levels.
    pub levels: &'a Levels,
    /// The frame's CFA pattern at the active area's origin.
    pub bayer: Bayer,
    /// The white balance (camera RGB, any scale).
    pub neutral: [f64; 3],
    /// The frame's LinearizationTable for stored samples (None for linear samples).
    pub linearization: Option<&'a [u16]>,
}

/// The demosaiced 14-bit codes of the release's network input of a CFA `plane` from the
/// frame `frame`: `height * width * 3` codes (R, G, B interleaved), steps 1-4 of the
/// module documentation. The plane must be at least 3 x 3.
pub fn release_codes(plane: &CfaPlane<'_>, frame: &FrameFacts<'_>) -> Result<Vec<u16>> {
    let CfaPlane {
        data: plane,
        width,
        height,
        top,
        left,
    } = *plane;
    let FrameFacts {
        levels,
        bayer,
        neutral,
        linearization,
    } = *frame;
    check_plane(plane.len(), width, height)?;
    let s = Sites::new(levels, bayer, neutral, top, left)?;
    let lin = linearization.filter(|t| !t.is_empty());
    // Steps 1-3 and the quantization, per sample: the same float32 operations as numpy's.
    let quant = |v: f32, k: usize| -> u16 {
        let v = (v - s.black[k]).max(0.0) / s.scale[k];
        let v = (v / s.neutral[k]).clamp(0.0, 1.0);
        (v * RELEASE_SCALE as f32) as u16
    };
    let mut q = vec![0u16; width * height];
    for (r, (src, dst)) in plane
        .chunks_exact(width)
        .zip(q.chunks_exact_mut(width))
        .enumerate()
    {
        let (k0, k1) = ((r & 1) << 1, ((r & 1) << 1) | 1);
        match lin {
            Some(t) => {
                let at = |x: u16| t[(x as usize).min(t.len() - 1)] as f32;
                for (i, (&x, d)) in src.iter().zip(dst.iter_mut()).enumerate() {
                    *d = quant(at(x), k0 | (i & 1));
                }
            }
            None => quant_row(src, dst, &s, [k0, k1]),
        }
    }
    Ok(demosaic_codes(&q, width, height, &s.colour))
}

/// Steps 1-3 and the quantization of one row of linear samples whose even columns are site
/// `k[0]` and odd ones `k[1]`: [`release_codes`]'s expression per sample, with the site's
/// constants selected by the column's parity (a flat loop the compiler turns into
/// whole-register operations; the same float32 operations, so the same codes).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn quant_row(src: &[u16], dst: &mut [u16], s: &Sites, k: [usize; 2]) {
    let pick = |a: &[f32; 4]| [a[k[0]], a[k[1]]];
    let (black, scale, neutral) = (pick(&s.black), pick(&s.scale), pick(&s.neutral));
    for (i, (&x, d)) in src.iter().zip(dst.iter_mut()).enumerate() {
        // a select, not an index: an index into the pairs kept the loop scalar
        let (b, sc, n) = if i & 1 == 0 {
            (black[0], scale[0], neutral[0])
        } else {
            (black[1], scale[1], neutral[1])
        };
        let v = (x as f32 - b).max(0.0) / sc;
        // `max` then `min` rather than `clamp`: NaN becomes 0 here, where `clamp` kept it
        // and the cast made it code 0, so the codes are the same
        #[allow(clippy::manual_clamp)] // on purpose: NaN must become 0, not stay NaN
        let v = (v / n).max(0.0).min(1.0);
        *d = trunc_code(v * RELEASE_SCALE as f32);
    }
}

/// `t as u16` for `t` in `[0, 16383]`, by float arithmetic the compiler keeps in whole
/// registers (the saturating `as` cast is converted one sample at a time on x86-64):
/// adding 2^23 rounds `t` to the nearest integer `r` (exact in that binade), and `r - 1`
/// is the truncation where `r` rounded up.
#[inline(always)]
fn trunc_code(t: f32) -> u16 {
    let r = (t + 8_388_608.0).to_bits().wrapping_sub(0x4B00_0000) as i32;
    (r - i32::from(r as f32 > t)) as u16
}

/// OpenCV's bilinear Bayer demosaic (`cv2.cvtColor(q, COLOR_BAYER_*2RGB)`) of 14-bit (or
/// any 16-bit) codes `q` (`width` x `height`, row-major, at least 3 x 3) whose pattern at
/// the origin is `bayer`: `height * width * 3` codes (R, G, B interleaved), step 4 of the
/// module documentation without the quantization. The input store of the Python package
/// (`day2night.train.cache`) demosaics its stored codes again with it.
pub fn demosaic_bilinear(q: &[u16], width: usize, height: usize, bayer: Bayer) -> Result<Vec<u16>> {
    check_plane(q.len(), width, height)?;
    let colour: [usize; 4] = std::array::from_fn(|k| bayer.color_at(k >> 1, k & 1) as usize);
    Ok(demosaic_codes(q, width, height, &colour))
}

/// A plane of `len` samples is `width` x `height` and at least 3 x 3.
fn check_plane(len: usize, width: usize, height: usize) -> Result<()> {
    if width < 3 || height < 3 {
        return Err(Error::invalid(format!(
            "bilinear demosaic needs at least 3x3 samples, got {width}x{height}"
        )));
    }
    if Some(len) != width.checked_mul(height) {
        return Err(Error::invalid(format!(
            "the plane holds {len} samples, not {width}x{height}"
        )));
    }
    Ok(())
}

/// The demosaic of checked codes: the inner samples, then the borders.
fn demosaic_codes(q: &[u16], width: usize, height: usize, colour: &[usize; 4]) -> Vec<u16> {
    let mut out = vec![0u16; width * height * 3];
    demosaic_inner(q, width, height, colour, &mut out);
    // Borders: the first and last rows copy their inner neighbours, then the first and last
    // columns (OpenCV's rule, as the release sees it).
    let row = 3 * width;
    out.copy_within(row..2 * row, 0);
    out.copy_within((height - 2) * row..(height - 1) * row, (height - 1) * row);
    for r in 0..height {
        let o = r * row;
        out.copy_within(o + 3..o + 6, o);
        out.copy_within(o + row - 6..o + row - 3, o + row - 3);
    }
    out
}

/// The bilinear demosaic of the inner samples (rows and columns 1..n-1).
///
/// Each row holds two colours, at its even and odd columns: the row is computed by a copy
/// of the loop made for that pair, so that no sample branches on its colour (the same
/// integer arithmetic per sample, so the same codes; a pattern that is no Bayer row takes
/// the general loop).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn demosaic_inner(q: &[u16], w: usize, h: usize, colour: &[usize; 4], out: &mut [u16]) {
    for y in 1..h - 1 {
        let rows = Rows {
            up: &q[(y - 1) * w..y * w],
            mid: &q[y * w..(y + 1) * w],
            dn: &q[(y + 1) * w..(y + 2) * w],
        };
        let orow = &mut out[3 * y * w..3 * (y + 1) * w];
        let k0 = (y & 1) << 1;
        match (colour[k0], colour[k0 | 1]) {
            (0, 1) => bayer_row::<0, 1>(&rows, orow),
            (1, 0) => bayer_row::<1, 0>(&rows, orow),
            (1, 2) => bayer_row::<1, 2>(&rows, orow),
            (2, 1) => bayer_row::<2, 1>(&rows, orow),
            (ce, co) => {
                for x in 1..w - 1 {
                    let (c, c_other) = if x & 1 == 0 { (ce, co) } else { (co, ce) };
                    orow[3 * x..3 * x + 3].copy_from_slice(&rows.rgb(x, c, c_other));
                }
            }
        }
    }
}

/// The rows above, at and below the one being demosaiced.
struct Rows<'a> {
    up: &'a [u16],
    mid: &'a [u16],
    dn: &'a [u16],
}

impl Rows<'_> {
    /// RGB at inner column `x`, whose colour is `c`; `c_other` is the row's other colour.
    #[inline(always)]
    fn rgb(&self, x: usize, c: usize, c_other: usize) -> [u16; 3] {
        let Rows { up, mid, dn } = *self;
        let (l, r) = (mid[x - 1] as u32, mid[x + 1] as u32);
        let (u, d) = (up[x] as u32, dn[x] as u32);
        let v = mid[x];
        if c == 1 {
            // the row's other colour from the horizontal neighbours, the column's from the
            // vertical ones
            let hor = ((l + r + 1) >> 1) as u16;
            let ver = ((u + d + 1) >> 1) as u16;
            if c_other == 0 {
                [hor, v, ver]
            } else {
                [ver, v, hor]
            }
        } else {
            let g = ((l + r + u + d + 2) >> 2) as u16;
            let diag = up[x - 1] as u32 + up[x + 1] as u32 + dn[x - 1] as u32 + dn[x + 1] as u32;
            let other = ((diag + 2) >> 2) as u16;
            if c == 0 {
                [v, g, other]
            } else {
                [other, g, v]
            }
        }
    }
}

/// [`demosaic_inner`]'s loop over one row whose even columns are colour `CE` and odd ones
/// `CO`: the columns two at a time, each with its colour fixed.
#[inline(always)]
fn bayer_row<const CE: usize, const CO: usize>(rows: &Rows<'_>, orow: &mut [u16]) {
    let w = rows.mid.len();
    let mut x = 1;
    while x + 1 < w - 1 {
        // x is odd here, x + 1 even
        let a = rows.rgb(x, CO, CE);
        let b = rows.rgb(x + 1, CE, CO);
        let o = &mut orow[3 * x..3 * x + 6];
        o[..3].copy_from_slice(&a);
        o[3..].copy_from_slice(&b);
        x += 2;
    }
    if x < w - 1 {
        orow[3 * x..3 * x + 3].copy_from_slice(&rows.rgb(x, CO, CE));
    }
}

/// The table from the 14-bit codes to the network's values: `code / 16383` in float32,
/// raised to `gamma` (None: linear) with Rust's `powf` (the Python package passes numpy's
/// own table instead, whose `**` may differ from `powf` by an ulp).
pub fn release_table(gamma: Option<f64>) -> Vec<f32> {
    let scale = RELEASE_SCALE as f32;
    (0..=RELEASE_SCALE)
        .map(|c| {
            let v = c as f32 / scale;
            match gamma {
                Some(g) => v.powf(g as f32),
                None => v,
            }
        })
        .collect()
}

/// Check a code table: one value per 14-bit code.
pub fn check_table(table: &[f32]) -> Result<()> {
    if table.len() != RELEASE_SCALE as usize + 1 {
        return Err(Error::invalid(format!(
            "the code table holds {} values, need {} (one per 14-bit code)",
            table.len(),
            RELEASE_SCALE as usize + 1
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trunc_code_is_the_cast() {
        let mut ts: Vec<f32> = Vec::new();
        // every integer code, its neighbours and the halves between them
        for k in 0..=RELEASE_SCALE {
            let t = k as f32;
            ts.extend([
                t,
                t.next_down(),
                t.next_up(),
                t + 0.5,
                (t + 0.5).next_down(),
            ]);
        }
        // a spread of the float32 inputs in [0, 1], scaled as the quantizer scales them
        let one = 1.0f32.to_bits();
        ts.extend(
            (0..one)
                .step_by(9_973)
                .map(|b| f32::from_bits(b) * RELEASE_SCALE as f32),
        );
        ts.extend([0.0, -0.0, RELEASE_SCALE as f32]);
        for t in ts {
            if (0.0..=RELEASE_SCALE as f32).contains(&t) {
                assert_eq!(trunc_code(t), t as u16, "{t}");
            }
        }
    }

    fn levels(black: Vec<f64>, repeat: (usize, usize), white: f64) -> Levels {
        Levels {
            black_repeat: repeat,
            black,
            black_delta_h: vec![],
            black_delta_v: vec![],
            white,
        }
    }

    /// The steps written out per pixel, as the module documentation states them.
    fn reference(
        plane: &[u16],
        w: usize,
        h: usize,
        top: usize,
        left: usize,
        bayer: Bayer,
    ) -> Vec<u16> {
        let black = [60.0f32, 64.5, 66.0, 70.0];
        let n = [0.6f32, 1.0, 0.3];
        let q: Vec<u16> = (0..w * h)
            .map(|i| {
                let (r, c) = (i / w, i % w);
                let b = black[((top + r) % 2) * 2 + (left + c) % 2];
                let v = (plane[i] as f32 - b).max(0.0) / (1023.0 - b);
                let v = (v / n[bayer.color_at(top + r, left + c) as usize]).clamp(0.0, 1.0);
                (v * 16383.0) as u16
            })
            .collect();
        reference_demosaic(&q, w, h, top, left, bayer)
    }

    /// The bilinear demosaic written out per pixel.
    fn reference_demosaic(
        q: &[u16],
        w: usize,
        h: usize,
        top: usize,
        left: usize,
        bayer: Bayer,
    ) -> Vec<u16> {
        let at = |r: usize, c: usize| q[r * w + c] as u32;
        let mut out = vec![0u16; w * h * 3];
        for y in 0..h {
            for x in 0..w {
                let (r, c) = (y.clamp(1, h - 2), x.clamp(1, w - 2));
                let col = bayer.color_at(top + r, left + c) as usize;
                let mut rgb = [0u32; 3];
                rgb[col] = at(r, c);
                if col == 1 {
                    let hc = bayer.color_at(top + r, left + c + 1) as usize;
                    rgb[hc] = (at(r, c - 1) + at(r, c + 1) + 1) >> 1;
                    rgb[2 - hc] = (at(r - 1, c) + at(r + 1, c) + 1) >> 1;
                } else {
                    rgb[1] = (at(r - 1, c) + at(r + 1, c) + at(r, c - 1) + at(r, c + 1) + 2) >> 2;
                    rgb[2 - col] = (at(r - 1, c - 1)
                        + at(r - 1, c + 1)
                        + at(r + 1, c - 1)
                        + at(r + 1, c + 1)
                        + 2)
                        >> 2;
                }
                for k in 0..3 {
                    out[3 * (y * w + x) + k] = rgb[k] as u16;
                }
            }
        }
        out
    }

    #[test]
    fn codes_follow_the_documented_steps_for_every_phase_and_offset() {
        let (w, h) = (11usize, 8usize);
        let plane: Vec<u16> = (0..w * h).map(|i| ((i * 7919) % 1100) as u16).collect();
        let lv = levels(vec![60.0, 64.5, 66.0, 70.0], (2, 2), 1023.0);
        for bayer in Bayer::ALL {
            for (top, left) in [(0, 0), (1, 0), (0, 1), (3, 5)] {
                let got = release_codes(
                    &CfaPlane {
                        data: &plane,
                        width: w,
                        height: h,
                        top,
                        left,
                    },
                    &FrameFacts {
                        levels: &lv,
                        bayer,
                        neutral: [0.6, 1.0, 0.3],
                        linearization: None,
                    },
                )
                .unwrap();
                assert_eq!(
                    got,
                    reference(&plane, w, h, top, left, bayer),
                    "{bayer:?} {top} {left}"
                );
            }
        }
    }

    #[test]
    fn demosaic_alone_follows_the_documented_rule_for_every_phase_and_size() {
        for (w, h) in [(3usize, 3usize), (4, 5), (11, 8), (7, 9)] {
            let q: Vec<u16> = (0..w * h).map(|i| ((i * 7919) % 16384) as u16).collect();
            for bayer in Bayer::ALL {
                let got = demosaic_bilinear(&q, w, h, bayer).unwrap();
                assert_eq!(
                    got,
                    reference_demosaic(&q, w, h, 0, 0, bayer),
                    "{bayer:?} {w}x{h}"
                );
            }
        }
        let e = demosaic_bilinear(&[0; 6], 3, 2, Bayer::RGGB).unwrap_err();
        assert!(e.to_string().contains("3x3"), "{e}");
        let e = demosaic_bilinear(&[0; 8], 3, 3, Bayer::RGGB).unwrap_err();
        assert!(e.to_string().contains("holds 8"), "{e}");
    }

    #[test]
    fn linearization_and_bad_arguments() {
        let lv = levels(vec![64.0], (1, 1), 1023.0);
        let plane = vec![10u16; 16];
        let table: Vec<u16> = (0..8).map(|x| 100 * x).collect();
        // every sample beyond the table's end maps to its last entry (700)
        let c = release_codes(
            &CfaPlane {
                data: &plane,
                width: 4,
                height: 4,
                top: 0,
                left: 0,
            },
            &FrameFacts {
                levels: &lv,
                bayer: Bayer::RGGB,
                neutral: [1.0; 3],
                linearization: Some(&table),
            },
        )
        .unwrap();
        let want = ((700.0f32 - 64.0) / 959.0 * 16383.0) as u16;
        assert!(c.iter().all(|&v| v == want), "{c:?}");
        let bad = |r: Result<Vec<u16>>, what: &str| {
            let e = r.unwrap_err().to_string();
            assert!(e.contains(what), "{e}");
        };
        bad(
            release_codes(
                &CfaPlane {
                    data: &plane,
                    width: 2,
                    height: 8,
                    top: 0,
                    left: 0,
                },
                &FrameFacts {
                    levels: &lv,
                    bayer: Bayer::RGGB,
                    neutral: [1.0; 3],
                    linearization: None,
                },
            ),
            "3x3",
        );
        bad(
            release_codes(
                &CfaPlane {
                    data: &plane,
                    width: 5,
                    height: 3,
                    top: 0,
                    left: 0,
                },
                &FrameFacts {
                    levels: &lv,
                    bayer: Bayer::RGGB,
                    neutral: [1.0; 3],
                    linearization: None,
                },
            ),
            "holds 16",
        );
        bad(
            release_codes(
                &CfaPlane {
                    data: &plane,
                    width: 4,
                    height: 4,
                    top: 0,
                    left: 0,
                },
                &FrameFacts {
                    levels: &lv,
                    bayer: Bayer::RGGB,
                    neutral: [1.0, 0.0, 1.0],
                    linearization: None,
                },
            ),
            "neutral",
        );
        let hi = levels(vec![1023.0], (1, 1), 1023.0);
        bad(
            release_codes(
                &CfaPlane {
                    data: &plane,
                    width: 4,
                    height: 4,
                    top: 0,
                    left: 0,
                },
                &FrameFacts {
                    levels: &hi,
                    bayer: Bayer::RGGB,
                    neutral: [1.0; 3],
                    linearization: None,
                },
            ),
            ">= white",
        );
        assert!(check_table(&release_table(None)).is_ok());
        assert!(check_table(&[0.0; 3]).is_err());
        let t = release_table(Some(RELEASE_GAMMA));
        assert_eq!((t[0], t[16383]), (0.0, 1.0));
        assert!((t[8192] - (8192.0f32 / 16383.0).powf(1.0 / 2.2)).abs() == 0.0);
    }
}
