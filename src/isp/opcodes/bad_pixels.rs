//! FixBadPixelsConstant (opcode 4) and FixBadPixelsList (opcode 5), on the CFA stages
//! (OpcodeList1 and 2). A bad sample is replaced by the mean of the good samples of the
//! same colour nearest to it, searched in rings: for green sites (given the BayerPhase: 0
//! red at (0, 0), 1 green-red, 2 green-blue, 3 blue) the 4 diagonal and 4 axial (distance
//! 2) neighbours, then the next ring (distance 2 diagonals, distance 4 axial and the
//! knight-like (1, 3) sites); for red and blue sites the axial neighbours at distance 2,
//! then the diagonal ones at (2, 2), then the axial ones at distance 4. A sample with no
//! good neighbour within distance 4 keeps its value. Neighbours are read from the values
//! before the fix, so the result does not depend on the order of the bad pixels.
//!
//! The Adobe DNG SDK's `dng_bad_pixels` interpolates from same-colour neighbours in a
//! similar way but with its own patterns and weights; the difference only concerns the
//! repaired samples (documented in docs/isp.md).
//!
//! FixBadPixelsConstant: a sample is bad when its 16-bit value (`round(x * 65535 / range)`,
//! the stored value at stage 1) equals the constant. FixBadPixelsList: the listed points
//! (row, column) and rectangles (top, left, bottom, right), in stage coordinates.

use super::Region;

/// Largest distance (rows or columns) at which a replacement is searched.
pub const REACH: usize = 4;

type Ring = &'static [(isize, isize)];

const GREEN: [Ring; 2] = [
    &[
        (-1, -1),
        (-1, 1),
        (1, -1),
        (1, 1),
        (0, -2),
        (0, 2),
        (-2, 0),
        (2, 0),
    ],
    &[
        (-2, -2),
        (-2, 2),
        (2, -2),
        (2, 2),
        (0, -4),
        (0, 4),
        (-4, 0),
        (4, 0),
        (-1, -3),
        (-1, 3),
        (1, -3),
        (1, 3),
        (-3, -1),
        (-3, 1),
        (3, -1),
        (3, 1),
    ],
];

const RED_BLUE: [Ring; 3] = [
    &[(0, -2), (0, 2), (-2, 0), (2, 0)],
    &[(-2, -2), (-2, 2), (2, -2), (2, 2)],
    &[(0, -4), (0, 4), (-4, 0), (4, 0)],
];

/// True when stage pixel (r, c) is a green site of a Bayer mosaic of phase `phase`.
pub fn is_green(phase: u32, r: usize, c: usize) -> bool {
    let odd = (r + c) % 2 == 1;
    match phase {
        1 | 2 => !odd,
        _ => odd,
    }
}

/// Replace the samples `list` of `reg` (one plane), those marked in `bad` (region-sized).
/// Only marked samples are written and only unmarked ones are read, so the pass reads the
/// values from before it whatever the order. Returns whether any sample changed.
fn fix(reg: &mut Region, phase: u32, bad: &[bool], list: &[usize]) -> bool {
    let (w, h) = (reg.width, reg.height);
    let mut changed = false;
    for &i in list {
        let (y, x) = (i / w, i % w);
        let (r, c) = (reg.top + y, reg.left + x);
        let rings: &[Ring] = if is_green(phase, r, c) {
            &GREEN
        } else {
            &RED_BLUE
        };
        for ring in rings {
            let (mut sum, mut n) = (0.0f64, 0u32);
            for &(dy, dx) in ring.iter() {
                let (yy, xx) = (y as isize + dy, x as isize + dx);
                if yy < 0 || xx < 0 || yy >= h as isize || xx >= w as isize {
                    continue;
                }
                let j = yy as usize * w + xx as usize;
                if !bad[j] {
                    sum += reg.data[j] as f64;
                    n += 1;
                }
            }
            if n > 0 {
                let v = (sum / n as f64) as f32;
                changed |= v.to_bits() != reg.data[i].to_bits();
                reg.data[i] = v;
                break;
            }
        }
    }
    changed
}

/// FixBadPixelsConstant on a CFA region.
pub fn fix_constant(reg: &mut Region, constant: u32, phase: u32) {
    fix_constant_repeated(reg, constant, phase, 1)
}

/// `times` FixBadPixelsConstant opcodes in a row (same constant and phase) on a CFA region,
/// with the samples of `times` separate passes: each pass after the first looks only at the
/// samples the pass before repaired (the others did not change, so they are still good) and
/// keeps those whose new value still reads as the constant; the passes stop early when one
/// changes nothing (the next would see the same values).
pub fn fix_constant_repeated(reg: &mut Region, constant: u32, phase: u32, times: usize) {
    if reg.planes != 1 || times == 0 {
        return;
    }
    let to16 = 65535.0 / reg.range;
    let is_bad = |v: f32| ((v * to16).round() as i64) == constant as i64;
    let mut bad: Vec<bool> = reg.data.iter().map(|&v| is_bad(v)).collect();
    let mut list: Vec<usize> = (0..bad.len()).filter(|&i| bad[i]).collect();
    for pass in 0..times {
        if list.is_empty() || !fix(reg, phase, &bad, &list) || pass + 1 == times {
            return;
        }
        list.retain(|&i| {
            let still = is_bad(reg.data[i]);
            bad[i] = still;
            still
        });
    }
}

/// FixBadPixelsList on a CFA region.
pub fn fix_list(reg: &mut Region, phase: u32, points: &[[u32; 2]], rects: &[[u32; 4]]) {
    if reg.planes != 1 {
        return;
    }
    let (w, h, top, left) = (reg.width, reg.height, reg.top, reg.left);
    let mut bad = vec![false; w * h];
    let mut mark = |r0: usize, c0: usize, r1: usize, c1: usize| {
        let (r0, r1) = (r0.max(top), r1.min(top + h));
        let (c0, c1) = (c0.max(left), c1.min(left + w));
        for r in r0..r1 {
            for c in c0..c1 {
                bad[(r - top) * w + (c - left)] = true;
            }
        }
    };
    for p in points {
        let (r, c) = (p[0] as usize, p[1] as usize);
        mark(r, c, r.saturating_add(1), c.saturating_add(1));
    }
    for q in rects {
        mark(q[0] as usize, q[1] as usize, q[2] as usize, q[3] as usize);
    }
    let list: Vec<usize> = (0..bad.len()).filter(|&i| bad[i]).collect();
    fix(reg, phase, &bad, &list);
}

#[cfg(test)]
mod tests {
    use super::super::StageRect;
    use super::*;

    fn region(data: &mut [f32], w: usize, h: usize, range: f32) -> Region<'_> {
        Region {
            data,
            top: 0,
            left: 0,
            width: w,
            height: h,
            planes: 1,
            extent: StageRect::of_size(w, h),
            range,
        }
    }

    #[test]
    fn constant_pixels_take_the_mean_of_their_colour() {
        // 8x8 RGGB mosaic: value = 100 * colour index + position-free
        let (w, h) = (8, 8);
        let mut d: Vec<f32> = (0..w * h)
            .map(|i| {
                let (r, c) = (i / w, i % w);
                if is_green(0, r, c) {
                    2000.0 + c as f32
                } else if r % 2 == 0 {
                    1000.0 + r as f32
                } else {
                    3000.0
                }
            })
            .collect();
        d[4 * w + 4] = 0.0; // red site (even, even) -> bad (constant 0)
        d[3 * w + 4] = 0.0; // green site (odd + even) -> bad
        let mut reg = region(&mut d, w, h, 65535.0);
        fix_constant(&mut reg, 0, 0);
        // red (4,4): axial neighbours (4,2) (4,6) (2,4) (6,4): 1004, 1004, 1002, 1006
        assert_eq!(d[4 * w + 4], 1004.0);
        // green (3,4): diagonals (2,3) (2,5) (4,3) (4,5) + axial (3,2) (3,6) (1,4) (5,4)
        let want = (2003.0 + 2005.0 + 2003.0 + 2005.0 + 2002.0 + 2006.0 + 2004.0 + 2004.0) / 8.0;
        assert_eq!(d[3 * w + 4], want);
    }

    #[test]
    fn list_points_and_rects_and_hopeless_cases() {
        let (w, h) = (6, 6);
        let mut d = vec![0.5f32; w * h];
        d[2 * w + 2] = 0.9;
        let mut reg = region(&mut d, w, h, 1.0);
        fix_list(&mut reg, 0, &[[2, 2], [100, 100]], &[]);
        assert_eq!(d[2 * w + 2], 0.5);
        // the whole image is bad: nothing to take from, values kept
        let mut d = vec![0.25f32; 9];
        let mut reg = region(&mut d, 3, 3, 1.0);
        fix_list(&mut reg, 1, &[], &[[0, 0, 3, 3]]);
        assert_eq!(d, vec![0.25; 9]);
    }

    /// The reference: one pass per opcode, each with its own mask over every sample.
    fn separate_passes(d: &mut [f32], w: usize, h: usize, constant: u32, times: usize) {
        for _ in 0..times {
            let mut reg = region(d, w, h, 65535.0);
            let bad: Vec<bool> = reg
                .data
                .iter()
                .map(|&v| v.round() as i64 == constant as i64)
                .collect();
            let list: Vec<usize> = (0..bad.len()).filter(|&i| bad[i]).collect();
            fix(&mut reg, 0, &bad, &list);
        }
    }

    #[test]
    fn repeated_constant_fixes_equal_separate_passes() {
        // A blob of bad samples larger than the search reach needs several passes; a pair
        // of neighbours whose mean is the constant stays bad after the first.
        let (w, h) = (40, 30);
        let mut s = 7u64;
        let base: Vec<f32> = (0..w * h)
            .map(|i| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let (r, c) = (i / w, i % w);
                if (8..22).contains(&r) && (5..25).contains(&c) {
                    100.0
                } else {
                    ((s >> 33) % 200) as f32
                }
            })
            .collect();
        for times in [1, 2, 3, 5, 4096] {
            let mut a = base.clone();
            separate_passes(&mut a, w, h, 100, times.min(64));
            let mut b = base.clone();
            fix_constant_repeated(&mut region(&mut b, w, h, 65535.0), 100, 0, times);
            // 64 passes reach the fixed point of this blob, so 4096 give the same samples
            assert_eq!(a, b, "{times} passes");
        }
    }

    #[test]
    fn phases() {
        assert!(!is_green(0, 0, 0) && is_green(0, 0, 1));
        assert!(is_green(1, 0, 0) && is_green(2, 1, 1));
        assert!(!is_green(3, 1, 1));
    }
}
