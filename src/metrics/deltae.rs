//! CIEDE2000 colour difference (CIE 142-2001, as formulated by Sharma, Wu and Dalal,
//! "The CIEDE2000 color-difference formula: implementation notes, supplementary test data,
//! and mathematical observations", Color Res. Appl. 30(1), 2005), with kL = kC = kH = 1.
//!
//! Images are converted sRGB -> XYZ -> CIELAB with the D65 white (x 0.3127, y 0.3290):
//! display-encoded values are decoded with the inverse sRGB OETF first (linear images,
//! e.g. EXR, are used as they are), then the IEC 61966-2-1 sRGB -> XYZ matrix, the same
//! conversion as colour-science's `sRGB_to_XYZ` + `XYZ_to_Lab`.

use super::check_same_size;
use crate::color::matrix3::mul_vec;
use crate::color::srgb::eotf as srgb_eotf;
use crate::color::xyz::{xy_to_xyz, D65_XY, SRGB_TO_XYZ};
use crate::error::Result;
use crate::isp::RgbImage;
use rayon::prelude::*;

/// A CIELAB colour.
pub type Lab = [f64; 3];

/// CIELAB of linear sRGB (D65 white).
pub fn linear_srgb_to_lab(rgb: [f64; 3]) -> Lab {
    let xyz = mul_vec(&SRGB_TO_XYZ, rgb);
    let wn = xy_to_xyz(D65_XY);
    let f = |t: f64| {
        if t > 216.0 / 24389.0 {
            t.cbrt()
        } else {
            (24389.0 / 27.0 * t + 16.0) / 116.0
        }
    };
    let (fx, fy, fz) = (f(xyz[0] / wn[0]), f(xyz[1] / wn[1]), f(xyz[2] / wn[2]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// CIEDE2000 difference between two CIELAB colours.
pub fn ciede2000(lab1: Lab, lab2: Lab) -> f64 {
    let [l1, a1, b1] = lab1;
    let [l2, a2, b2] = lab2;
    let pow7 = |v: f64| v.powi(7);
    let c1 = a1.hypot(b1);
    let c2 = a2.hypot(b2);
    let cbar = 0.5 * (c1 + c2);
    let g = 0.5 * (1.0 - (pow7(cbar) / (pow7(cbar) + pow7(25.0))).sqrt());
    let a1p = (1.0 + g) * a1;
    let a2p = (1.0 + g) * a2;
    let c1p = a1p.hypot(b1);
    let c2p = a2p.hypot(b2);
    let hue = |b: f64, a: f64| {
        if a == 0.0 && b == 0.0 {
            0.0
        } else {
            let h = b.atan2(a).to_degrees();
            if h < 0.0 {
                h + 360.0
            } else {
                h
            }
        }
    };
    let h1p = hue(b1, a1p);
    let h2p = hue(b2, a2p);
    let dlp = l2 - l1;
    let dcp = c2p - c1p;
    let cc = c1p * c2p;
    let dhp = if cc == 0.0 {
        0.0
    } else {
        let d = h2p - h1p;
        if d.abs() <= 180.0 {
            d
        } else if d > 180.0 {
            d - 360.0
        } else {
            d + 360.0
        }
    };
    let dhp_big = 2.0 * cc.sqrt() * (dhp.to_radians() / 2.0).sin();
    let lbar = 0.5 * (l1 + l2);
    let cbarp = 0.5 * (c1p + c2p);
    let hbarp = if cc == 0.0 {
        h1p + h2p
    } else if (h1p - h2p).abs() <= 180.0 {
        0.5 * (h1p + h2p)
    } else if h1p + h2p < 360.0 {
        0.5 * (h1p + h2p + 360.0)
    } else {
        0.5 * (h1p + h2p - 360.0)
    };
    let cosd = |d: f64| d.to_radians().cos();
    let t =
        1.0 - 0.17 * cosd(hbarp - 30.0) + 0.24 * cosd(2.0 * hbarp) + 0.32 * cosd(3.0 * hbarp + 6.0)
            - 0.20 * cosd(4.0 * hbarp - 63.0);
    let dtheta = 30.0 * (-((hbarp - 275.0) / 25.0).powi(2)).exp();
    let rc = 2.0 * (pow7(cbarp) / (pow7(cbarp) + pow7(25.0))).sqrt();
    let l50 = (lbar - 50.0).powi(2);
    let sl = 1.0 + 0.015 * l50 / (20.0 + l50).sqrt();
    let sc = 1.0 + 0.045 * cbarp;
    let sh = 1.0 + 0.015 * cbarp * t;
    let rt = -(2.0 * dtheta).to_radians().sin() * rc;
    let (x, y, z) = (dlp / sl, dcp / sc, dhp_big / sh);
    (x * x + y * y + z * z + rt * y * z).max(0.0).sqrt()
}

/// CIELAB of one pixel's RGB, linear sRGB (`linear`) or display-encoded sRGB (decoded with
/// the inverse OETF first). Values are used unclipped.
fn pixel_lab(px: &[f32], linear: bool) -> Lab {
    let v = [px[0], px[1], px[2]].map(|c| {
        if linear {
            c as f64
        } else {
            srgb_eotf(c) as f64
        }
    });
    linear_srgb_to_lab(v)
}

/// CIEDE2000 of each pixel of one row (interleaved RGB) of `pred` against `target`.
fn row_delta_e<'a>(
    pred_row: &'a [f32],
    target_row: &'a [f32],
    pred_linear: bool,
    target_linear: bool,
) -> impl Iterator<Item = f64> + 'a {
    pred_row
        .chunks_exact(3)
        .zip(target_row.chunks_exact(3))
        .map(move |(a, b)| ciede2000(pixel_lab(a, pred_linear), pixel_lab(b, target_linear)))
}

/// Mean CIEDE2000 between two images; `*_linear` says whether an image holds linear sRGB
/// (true, e.g. EXR) or display-encoded sRGB (false, e.g. PNG). Values are used unclipped.
pub fn mean_delta_e_2000(
    pred: &RgbImage,
    target: &RgbImage,
    pred_linear: bool,
    target_linear: bool,
) -> Result<f64> {
    check_same_size(pred, target)?;
    let sum: f64 = pred
        .data
        .par_chunks(3 * pred.width)
        .zip(target.data.par_chunks(3 * pred.width))
        .map(|(ra, rb)| row_delta_e(ra, rb, pred_linear, target_linear).sum::<f64>())
        .collect::<Vec<f64>>()
        .iter()
        .sum();
    Ok(sum / (pred.width * pred.height) as f64)
}

/// CIEDE2000 of each pixel, row-major (`width * height` values), with the conversions of
/// [`mean_delta_e_2000`] (whose value is these values' mean): the per-pixel map of a report.
pub fn delta_e_2000_map(
    pred: &RgbImage,
    target: &RgbImage,
    pred_linear: bool,
    target_linear: bool,
) -> Result<Vec<f64>> {
    check_same_size(pred, target)?;
    let mut out = vec![0.0; pred.width * pred.height];
    out.par_chunks_mut(pred.width)
        .zip(pred.data.par_chunks(3 * pred.width))
        .zip(target.data.par_chunks(3 * pred.width))
        .for_each(|((o, ra), rb)| {
            o.iter_mut()
                .zip(row_delta_e(ra, rb, pred_linear, target_linear))
                .for_each(|(o, d)| *o = d);
        });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 34 test pairs of Sharma, Wu and Dalal (2005), Table 1: L1 a1 b1 L2 a2 b2 dE00.
    const SHARMA: [[f64; 7]; 34] = [
        [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
        [50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615],
        [50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412],
        [
            50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000,
        ],
        [
            50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000,
        ],
        [
            50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000,
        ],
        [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
        [50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461],
        [50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065],
        [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
        [50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977],
        [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
        [50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000],
        [
            60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644,
        ],
        [
            63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630,
        ],
        [61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731],
        [35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645],
        [
            22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373,
        ],
        [36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146],
        [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
        [90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381],
        [6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377],
        [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
    ];

    #[test]
    fn sharma_wu_dalal_test_pairs() {
        for (i, r) in SHARMA.iter().enumerate() {
            let d = ciede2000([r[0], r[1], r[2]], [r[3], r[4], r[5]]);
            // the table is rounded to 4 decimals
            assert!(
                (d - r[6]).abs() <= 0.5e-4 + 1e-9,
                "pair {}: {d} vs {}",
                i + 1,
                r[6]
            );
            // symmetric
            let e = ciede2000([r[3], r[4], r[5]], [r[0], r[1], r[2]]);
            assert!((d - e).abs() < 1e-9, "pair {} not symmetric", i + 1);
        }
    }

    #[test]
    fn lab_of_white_and_black() {
        let w = linear_srgb_to_lab([1.0, 1.0, 1.0]);
        assert!(
            (w[0] - 100.0).abs() < 1e-2 && w[1].abs() < 0.05 && w[2].abs() < 0.05,
            "{w:?}"
        );
        assert_eq!(linear_srgb_to_lab([0.0; 3]), [0.0, 0.0, 0.0]);
    }

    #[test]
    fn image_mean() {
        let a = RgbImage::new(3, 2);
        let mut b = RgbImage::new(3, 2);
        assert_eq!(mean_delta_e_2000(&a, &b, false, false).unwrap(), 0.0);
        b.data.iter_mut().for_each(|v| *v = 0.5);
        let d = mean_delta_e_2000(&a, &b, false, false).unwrap();
        let want = ciede2000([0.0; 3], linear_srgb_to_lab([srgb_eotf(0.5) as f64; 3]));
        assert!((d - want).abs() < 1e-9);
    }

    #[test]
    fn map_is_the_mean_per_pixel() {
        let (w, h) = (7, 5);
        let mut a = RgbImage::new(w, h);
        let mut b = RgbImage::new(w, h);
        // a deterministic spread of colours, some out of [0, 1]
        for (i, v) in a.data.iter_mut().enumerate() {
            *v = ((i * 37 % 101) as f32) / 90.0 - 0.05;
        }
        for (i, v) in b.data.iter_mut().enumerate() {
            *v = ((i * 53 % 97) as f32) / 96.0;
        }
        for (pl, tl) in [(false, false), (true, false), (false, true), (true, true)] {
            let m = delta_e_2000_map(&a, &b, pl, tl).unwrap();
            assert_eq!(m.len(), w * h);
            for (k, d) in m.iter().enumerate() {
                let (pa, pb) = (&a.data[3 * k..3 * k + 3], &b.data[3 * k..3 * k + 3]);
                assert_eq!(*d, ciede2000(pixel_lab(pa, pl), pixel_lab(pb, tl)));
            }
            // the mean sums row by row: the same order gives the same bits
            let rows: f64 = m.chunks(w).map(|r| r.iter().sum::<f64>()).sum();
            let mean = mean_delta_e_2000(&a, &b, pl, tl).unwrap();
            assert_eq!(rows / (w * h) as f64, mean);
        }
        assert!(delta_e_2000_map(&a, &RgbImage::new(w, h + 1), false, false).is_err());
    }
}
