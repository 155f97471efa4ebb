//! OpcodeList2 MapPolynomial on a LinearRaw render. Adobe's lossy DNG (and other 8-bit
//! LinearRaw writers) store perceptually coded samples and put the curve back to linear,
//! per plane, in OpcodeList2 as MapPolynomial opcodes: without them the render is washed out
//! and colour-cast. This applies exactly those (on linear reference values in [0, 1], after
//! black subtraction and scaling, before white balance, as the DNG specification orders
//! OpcodeList2; results clipped to [0, 1] as the Adobe DNG SDK does); every other opcode of
//! a LinearRaw file is left to the general opcode stage of the ISP.

use super::RgbImage;
use crate::dng::opcodes::AreaSpec;
use crate::error::{Error, Result};

/// MapPolynomial's opcode id.
const MAP_POLYNOMIAL: u32 = 8;
/// The specification's largest degree.
const MAX_DEGREE: u32 = 8;

/// One MapPolynomial: its area (relative to the active area) and coefficients c0..cN.
#[derive(Debug, Clone, PartialEq)]
pub struct MapPolynomial {
    /// Area, planes and pitch.
    pub area: AreaSpec,
    /// c0..cN.
    pub coefficients: Vec<f64>,
}

fn be32(b: &[u8], at: usize) -> Option<u32> {
    b.get(at..at + 4)
        .map(|s| u32::from_be_bytes([s[0], s[1], s[2], s[3]]))
}

/// The MapPolynomial opcodes of an opcode list (big-endian), in order; other opcodes are
/// skipped. Errors name the opcode when the list or a MapPolynomial is malformed.
pub fn map_polynomials(list: &[u8]) -> Result<Vec<MapPolynomial>> {
    let bad = |m: String| Error::malformed(format!("OpcodeList2: {m}"));
    let count = be32(list, 0).ok_or_else(|| bad("shorter than its count".into()))?;
    let mut at = 4usize;
    let mut out = Vec::new();
    for i in 0..count {
        let (Some(id), Some(len)) = (be32(list, at), be32(list, at + 12)) else {
            return Err(bad(format!("opcode {i} header runs past the list")));
        };
        let start = at + 16;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= list.len())
            .ok_or_else(|| bad(format!("opcode {i} ({len} bytes) runs past the list")))?;
        let p = &list[start..end];
        if id == MAP_POLYNOMIAL {
            let f =
                |k: usize| be32(p, 4 * k).ok_or_else(|| bad(format!("MapPolynomial {i} is short")));
            let area = AreaSpec {
                top: f(0)?,
                left: f(1)?,
                bottom: f(2)?,
                right: f(3)?,
                plane: f(4)?,
                planes: f(5)?,
                row_pitch: f(6)?,
                col_pitch: f(7)?,
            };
            let degree = f(8)?;
            if degree > MAX_DEGREE || area.row_pitch == 0 || area.col_pitch == 0 {
                return Err(bad(format!(
                    "MapPolynomial {i}: degree {degree} (0..{MAX_DEGREE}) or a zero pitch"
                )));
            }
            let mut coefficients = Vec::with_capacity(degree as usize + 1);
            for k in 0..=degree as usize {
                let b = p
                    .get(36 + 8 * k..44 + 8 * k)
                    .ok_or_else(|| bad(format!("MapPolynomial {i} is short")))?;
                let mut a = [0u8; 8];
                a.copy_from_slice(b);
                let c = f64::from_be_bytes(a);
                if !c.is_finite() {
                    return Err(bad(format!("MapPolynomial {i}: non-finite coefficient")));
                }
                coefficients.push(c);
            }
            out.push(MapPolynomial { area, coefficients });
        }
        at = end;
    }
    Ok(out)
}

/// Apply `maps` to the 3-plane image (active-area coordinates), clipping to [0, 1].
pub fn apply(rgb: &mut RgbImage, maps: &[MapPolynomial]) {
    let (w, h) = (rgb.width, rgb.height);
    for m in maps {
        let a = &m.area;
        let (top, bottom) = (a.top as usize, (a.bottom as usize).min(h));
        let (left, right) = (a.left as usize, (a.right as usize).min(w));
        let first = a.plane as usize;
        let last = first.saturating_add(a.planes as usize).min(3);
        for r in (top..bottom).step_by(a.row_pitch as usize) {
            let row = &mut rgb.data[r * 3 * w..(r + 1) * 3 * w];
            for c in (left..right).step_by(a.col_pitch as usize) {
                for s in first..last {
                    let x = f64::from(row[3 * c + s]);
                    let y = m.coefficients.iter().rev().fold(0.0, |acc, &k| acc * x + k);
                    row[3 * c + s] = if y.is_nan() {
                        0.0
                    } else {
                        y.clamp(0.0, 1.0) as f32
                    };
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn list(ops: &[(u32, Vec<u8>)]) -> Vec<u8> {
        let mut b = (ops.len() as u32).to_be_bytes().to_vec();
        for (id, p) in ops {
            b.extend(id.to_be_bytes());
            b.extend([1, 3, 0, 0]);
            b.extend(0u32.to_be_bytes());
            b.extend((p.len() as u32).to_be_bytes());
            b.extend(p);
        }
        b
    }

    fn poly(plane: u32, c: &[f64]) -> Vec<u8> {
        let mut p = Vec::new();
        for v in [0, 0, 2, 2, plane, 1, 1, 1, c.len() as u32 - 1] {
            p.extend(v.to_be_bytes());
        }
        for v in c {
            p.extend(v.to_be_bytes());
        }
        p
    }

    #[test]
    fn parses_and_applies_per_plane_skipping_others() {
        let l = list(&[
            (9, vec![0; 12]),
            (8, poly(1, &[0.0, 0.5])),
            (8, poly(2, &[0.1, 0.0, 1.0])),
        ]);
        let maps = map_polynomials(&l).unwrap();
        assert_eq!(maps.len(), 2);
        let mut img = RgbImage::new(2, 2);
        img.data.iter_mut().for_each(|v| *v = 0.5);
        apply(&mut img, &maps);
        assert_eq!(&img.data[..3], &[0.5, 0.25, 0.35]);
    }

    #[test]
    fn malformed_lists_are_errors() {
        assert!(map_polynomials(&[0, 0]).is_err());
        let mut l = list(&[(8, poly(0, &[0.0, 1.0]))]);
        l.truncate(l.len() - 3);
        assert!(map_polynomials(&l).is_err());
        let l = list(&[(8, poly(0, &[f64::NAN]))]);
        assert!(map_polynomials(&l).is_err());
        let huge = list(&[(8, poly(0, &[0.0; 12]))]);
        assert!(map_polynomials(&huge).is_err());
    }
}
