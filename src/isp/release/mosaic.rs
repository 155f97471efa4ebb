//! The release's raw stages up to its demosaic input: the visible raw as LibRaw reports it
//! (the active area, LinearizationTable applied), the release's second crop, normalization
//! by black and white, white balance by the neutral, and the 14-bit codes its demosaic
//! takes (`(v * 16383)` truncated).

use super::meta::{Black, ReleaseMeta};
use crate::error::{Error, Result};
use crate::raw::RawImage;

/// The 14-bit scale of the release's demosaic input.
pub const CODE_SCALE: f64 = 16383.0;

/// A CFA plane of codes, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Codes {
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
    /// `width * height` codes in [0, 16383].
    pub data: Vec<u16>,
}

/// The release's image window in active-area coordinates: (top, left, height, width).
/// NumPy's slicing of the active area by the ActiveArea rectangle, clamped to its size.
pub fn window(raw: &RawImage, meta: &ReleaseMeta) -> Result<(usize, usize, usize, usize)> {
    let a = raw.active_area();
    let (ah, aw) = (a.height(), a.width());
    let (top, left, bottom, right) = match meta.second_crop {
        Some([t, l, b, r]) => (t.min(ah), l.min(aw), b.min(ah), r.min(aw)),
        None => (0, 0, ah, aw),
    };
    let (h, w) = (bottom.saturating_sub(top), right.saturating_sub(left));
    if h < 2 || w < 2 {
        let by = match meta.second_crop {
            Some(r) => format!(", cropped again by ActiveArea {r:?},"),
            None => String::new(),
        };
        return Err(Error::unsupported(format!(
            "--isp release: the {aw}x{ah} active area{by} leaves {w}x{h} pixels (the \
             release needs at least 2x2)"
        )));
    }
    Ok((top, left, h, w))
}

/// The white-balanced 14-bit codes of the release's image window.
pub fn codes(raw: &RawImage, meta: &ReleaseMeta) -> Result<Codes> {
    let (top, left, h, w) = window(raw, meta)?;
    let a = raw.active_area();
    let (y0, x0) = (a.top as usize + top, a.left as usize + left);
    let table = raw
        .meta
        .linearization_table
        .as_deref()
        .filter(|t| !t.is_empty());
    let linear = |v: u16| -> u16 {
        match table {
            Some(t) => t[(v as usize).min(t.len() - 1)],
            None => v,
        }
    };
    let site = |r: usize, c: usize| ((r & 1) << 1) | (c & 1);
    let n = meta.neutral;
    let mut data = crate::limits::try_filled(0u16, w * h, "the release's CFA codes")?;
    for (r, row) in data.chunks_exact_mut(w).enumerate() {
        let src = &raw.data[(y0 + r) * raw.width + x0..][..w];
        for (c, (o, &v)) in row.iter_mut().zip(src).enumerate() {
            let s = site(r, c);
            let neutral = n[meta.cfa[s] as usize];
            let x = linear(v);
            let wb = match meta.black {
                // float32 throughout, as NumPy computes a float32 array with Python floats.
                Black::Scalar(b) => {
                    let d = (x as f32 - b as f32).max(0.0);
                    f64::from(d / (meta.white - b) as f32 / neutral as f32)
                }
                // A float64 mask: float64 throughout.
                Black::Sites(bs) => {
                    let d = (x as f64 - bs[s]).max(0.0);
                    d / (meta.white - bs[s]) / neutral
                }
            };
            *o = (wb.clamp(0.0, 1.0) * CODE_SCALE) as u16;
        }
    }
    Ok(Codes {
        width: w,
        height: h,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::{Bayer, RawMeta, Rect};

    fn raw(w: usize, h: usize, meta: RawMeta) -> RawImage {
        RawImage {
            width: w,
            height: h,
            data: (0..w * h).map(|i| (i * 37 % 4096) as u16).collect(),
            meta,
        }
    }

    /// The window is the active area cut again by ActiveArea's own numbers, clamped; the
    /// codes follow the stated arithmetic site by site (float32 with one black level).
    #[test]
    fn second_crop_and_codes() {
        let mut m = RawMeta::new_bayer(Bayer::GRBG, 12, 100.0, 4000.0);
        m.active_area = Some(Rect {
            top: 2,
            left: 4,
            bottom: 12,
            right: 16,
        });
        let r = raw(16, 12, m);
        let meta = ReleaseMeta::of(&r, Some([0.5, 1.0, 0.8])).unwrap();
        // Active area 12 x 10; cut by rows 2..12, columns 4..16 -> rows 2..10, columns 4..12.
        assert_eq!(window(&r, &meta).unwrap(), (2, 4, 8, 8));
        let c = codes(&r, &meta).unwrap();
        assert_eq!((c.width, c.height), (8, 8));
        for (i, code) in c.data.iter().enumerate() {
            let (y, x) = (i / 8, i % 8);
            let v = r.get(2 + 2 + y, 4 + 4 + x);
            let n = [0.5f32, 1.0, 0.8][Bayer::GRBG.color_at(y, x) as usize];
            let want = ((v as f32 - 100.0).max(0.0) / 3900.0 / n).clamp(0.0, 1.0);
            assert_eq!(*code, (f64::from(want) * 16383.0) as u16);
        }
    }

    #[test]
    fn a_crop_that_leaves_nothing_is_an_error() {
        let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        m.active_area = Some(Rect {
            top: 6,
            left: 0,
            bottom: 8,
            right: 8,
        });
        let r = raw(8, 8, m);
        let meta = ReleaseMeta::of(&r, None).unwrap();
        let e = window(&r, &meta).unwrap_err().to_string();
        assert!(e.contains("release"), "{e}");
    }
}
