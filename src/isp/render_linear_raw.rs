//! The render of a LinearRaw image (already demosaiced, three samples per pixel): per
//! sample LinearizationTable, black subtraction (BlackLevel per sample and repeat cell,
//! plus BlackLevelDeltaH/V) and scaling by `white - black_max` of that sample (DNG
//! chapter 5, as [`crate::normalize::Normalizer`] does for a CFA site), clipped to [0, 1];
//! OpcodeList2's MapPolynomial curves (the linearization of 8-bit lossy DNGs,
//! `linear_raw_opcodes.rs`); white balance by the neutral; the camera -> linear sRGB matrix; DefaultCrop and
//! orientation. No demosaicing: the demosaic option is ignored. `render.rs` dispatches
//! here when [`RawMeta::linear_raw`](crate::raw::meta::RawMeta::linear_raw) is set.

use super::color::normalize_neutral;
use super::linear_raw_opcodes::{apply as apply_maps, map_polynomials};
use super::render::{
    apply_geometry, color_matrix, matrix_row, resolve_neutral, Bands, RenderOptions, BAND,
};
use super::RgbImage;
use crate::error::{Error, Result};
use crate::raw::meta::LinearRaw;
use crate::raw::RawImage;
use rayon::prelude::*;

fn linear_raw(img: &RawImage) -> Result<&LinearRaw> {
    img.meta
        .linear_raw
        .as_ref()
        .ok_or_else(|| Error::invalid("not a LinearRaw image"))
}

/// Normalized, white-balanced camera RGB of the active area, each sample clipped to
/// [0, 1] (no colour matrix, no crop, no orientation).
pub fn camera_rgb(img: &RawImage, neutral: [f64; 3]) -> Result<RgbImage> {
    img.validate()?;
    let lr = linear_raw(img)?;
    let spp = usize::from(lr.samples_per_pixel);
    if spp != 3 {
        return Err(Error::unsupported(format!(
            "LinearRaw with {spp} samples per pixel (3 supported)"
        )));
    }
    let n = normalize_neutral(neutral)?;
    let inv = [1.0 / n[0], 1.0, 1.0 / n[2]];
    let levels = &img.meta.levels;
    let (rr, rc) = levels.black_repeat;
    let dh = levels.black_delta_h.iter().cloned().fold(0.0, f64::max);
    let dv = levels.black_delta_v.iter().cloned().fold(0.0, f64::max);
    // Per sample: 1 / (white - black_max), black_max over the repeat cells plus deltas.
    let mut inv_scale = [0.0f64; 3];
    for (s, is) in inv_scale.iter_mut().enumerate() {
        let bmax = (0..rr * rc)
            .map(|c| lr.black[c * spp + s])
            .fold(f64::NEG_INFINITY, f64::max)
            + dh
            + dv;
        *is = 1.0 / (lr.white[s] - bmax);
    }
    let lut = img
        .meta
        .linearization_table
        .as_deref()
        .filter(|t| !t.is_empty());
    let lin = |x: u16| -> f64 {
        match lut {
            Some(t) => f64::from(t[usize::from(x).min(t.len() - 1)]),
            None => f64::from(x),
        }
    };
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let stride = img.width * spp;
    let mut rgb = RgbImage::try_new(w, h)?;
    let data = &img.data;
    rgb.data
        .par_chunks_mut(3 * w.max(1))
        .enumerate()
        .for_each(|(r, out)| {
            let src = &data[(r + top) * stride + left * spp..][..w * spp];
            for (c, (o, x)) in out
                .chunks_exact_mut(3)
                .zip(src.chunks_exact(spp))
                .enumerate()
            {
                for s in 0..3 {
                    let b = lr.black_at(levels, s, r, c);
                    let y = (lin(x[s]) - b) * inv_scale[s];
                    o[s] = if y.is_nan() {
                        0.0
                    } else {
                        y.clamp(0.0, 1.0) as f32
                    };
                }
            }
        });
    // OpcodeList2's MapPolynomial curves (linear_raw_opcodes.rs), then white balance.
    if let Some(list) = &img.meta.opcode_lists[1] {
        let maps = map_polynomials(list)?;
        apply_maps(&mut rgb, &maps);
    }
    let invf = inv.map(|v| v as f32);
    rgb.data.par_chunks_mut(3 * w.max(1)).for_each(|row| {
        for px in row.chunks_exact_mut(3) {
            for (v, k) in px.iter_mut().zip(invf) {
                *v = (*v * k).clamp(0.0, 1.0);
            }
        }
    });
    Ok(rgb)
}

/// Linear sRGB render (see the module docs); the LinearRaw form of
/// [`super::render::render_linear`].
pub fn render_linear(img: &RawImage, opts: &RenderOptions) -> Result<RgbImage> {
    let n = resolve_neutral(&img.meta, opts.neutral)?;
    let m = color_matrix(&img.meta, n)?;
    let mf = m.map(|r| r.map(|v| v as f32));
    let mut rgb = camera_rgb(img, n)?;
    let w = rgb.width.max(1);
    rgb.data
        .par_chunks_mut(3 * w)
        .for_each(|row| matrix_row(row, &mf));
    Ok(apply_geometry(rgb, &img.meta, opts.crop, opts.orient))
}

/// [`render_linear`] handed to `f` band by band ([`BAND`] rows), as
/// [`super::render::render_linear_bands`] does; always `Some`.
pub fn render_linear_bands<T, F>(
    img: &RawImage,
    opts: &RenderOptions,
    f: F,
) -> Result<Option<Bands<T>>>
where
    T: Send,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    let rgb = render_linear(img, opts)?;
    let (ow, oh) = (rgb.width, rgb.height);
    let bands: Result<Vec<T>> = rgb
        .data
        .par_chunks(3 * ow.max(1) * BAND)
        .enumerate()
        .map(|(bi, rows)| f(bi * BAND, ow, rows))
        .collect();
    Ok(Some(Bands {
        width: ow,
        height: oh,
        bands: bands?,
    }))
}

/// White-balanced camera RGB with DefaultCrop and orientation if asked (the network
/// input's form; see [`super::render::render_input`]).
pub fn render_camera(
    img: &RawImage,
    neutral: [f64; 3],
    crop: bool,
    orient: bool,
) -> Result<RgbImage> {
    Ok(apply_geometry(
        camera_rgb(img, neutral)?,
        &img.meta,
        crop,
        orient,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::{Bayer, Levels};

    fn image(w: usize, h: usize, data: Vec<u16>, black: Vec<f64>, white: Vec<f64>) -> RawImage {
        let mut meta = RawMeta::new_bayer(Bayer::RGGB, 16, 0.0, 1.0);
        meta.cfa.rows = 0;
        meta.cfa.cols = 0;
        meta.cfa.pattern.clear();
        meta.as_shot_neutral = Some([1.0, 1.0, 1.0]);
        meta.levels = Levels {
            black_repeat: (1, 1),
            black: vec![black[0]],
            black_delta_h: vec![],
            black_delta_v: vec![],
            white: white[0],
        };
        meta.linear_raw = Some(LinearRaw {
            samples_per_pixel: 3,
            black,
            white,
        });
        RawImage {
            width: w,
            height: h,
            data,
            meta,
        }
    }

    #[test]
    fn normalizes_each_sample_with_its_own_levels() {
        // One pixel: (black + half range) per sample gives 0.5 in every channel.
        let img = image(
            1,
            1,
            vec![60, 110, 2060],
            vec![10.0, 20.0, 60.0],
            vec![110.0, 200.0, 4060.0],
        );
        let rgb = camera_rgb(&img, [1.0, 1.0, 1.0]).unwrap();
        assert_eq!(rgb.data, vec![0.5, 0.5, 0.5]);
        // White balance divides by the neutral (green = 1), then clips.
        let rgb = camera_rgb(&img, [0.5, 1.0, 0.25]).unwrap();
        assert_eq!(rgb.data, vec![1.0, 0.5, 1.0]);
    }

    #[test]
    fn refused_where_a_cfa_is_needed_and_extremes_stay_finite() {
        let img = image(
            2,
            1,
            vec![0, 0, 0, 65535, 65535, 65535],
            vec![0.0; 3],
            vec![65535.0; 3],
        );
        assert!(img
            .bayer()
            .unwrap_err()
            .to_string()
            .contains("already demosaiced"));
        let out = render_linear(&img, &RenderOptions::default()).unwrap();
        assert!(out
            .data
            .iter()
            .all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
        assert_eq!(out.width * out.height, 2);
    }

    #[test]
    fn bands_equal_the_whole_render() {
        let (w, h) = (5, 70);
        let data: Vec<u16> = (0..w * h * 3).map(|i| (i * 7919 % 4096) as u16).collect();
        let img = image(w, h, data, vec![10.0, 20.0, 30.0], vec![4095.0; 3]);
        let opts = RenderOptions::default();
        let whole = render_linear(&img, &opts).unwrap();
        let bands = render_linear_bands(&img, &opts, |_, _, rows| Ok(rows.to_vec()))
            .unwrap()
            .unwrap();
        assert_eq!((bands.width, bands.height), (whole.width, whole.height));
        assert_eq!(bands.bands.len(), h.div_ceil(BAND));
        assert_eq!(bands.bands.concat(), whole.data);
    }

    proptest::proptest! {
        #[test]
        fn any_samples_and_levels_render_finite_in_range(
            data in proptest::collection::vec(proptest::num::u16::ANY, 18),
            black in proptest::collection::vec(0u16..5000, 3),
            span in proptest::collection::vec(1u16..60000, 3),
            neutral in proptest::collection::vec(0.01f64..100.0, 3),
        ) {
            let b: Vec<f64> = black.iter().map(|&x| f64::from(x)).collect();
            let w: Vec<f64> = black.iter().zip(&span).map(|(&x, &s)| f64::from(x) + f64::from(s)).collect();
            let img = image(3, 2, data, b, w);
            let opts = RenderOptions { neutral: Some([neutral[0], neutral[1], neutral[2]]), ..RenderOptions::default() };
            let out = render_linear(&img, &opts).unwrap();
            proptest::prop_assert!(out.data.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
        }
    }
}
