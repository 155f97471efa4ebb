//! The render of a LinearRaw image (already demosaiced, three samples per pixel), in the
//! Adobe DNG SDK's stage order: OpcodeList1 on the stored values; per sample
//! LinearizationTable, black subtraction (BlackLevel per sample and repeat cell, plus
//! BlackLevelDeltaH/V) and scaling by `white - black_max` of that sample (DNG chapter 5, as
//! [`crate::normalize::Normalizer`] does for a CFA site), clipped to [0, 1]; OpcodeList2
//! (e.g. the MapPolynomial curves that linearize 8-bit lossy DNGs) and then OpcodeList3 on
//! that 3-plane image (a LinearRaw stage-2 image is already the SDK's stage-3 image); white
//! balance by the neutral; the camera -> linear sRGB matrix; DefaultCrop and orientation.
//! The opcodes are those of the shared stage ([`super::opcodes`], with the LinearRaw rules of
//! [`super::opcodes::unsupported_reason_linear_raw`]) and follow
//! [`RenderOptions::opcodes`](super::render::RenderOptions::opcodes). No demosaicing: the
//! demosaic option is ignored. Every execution of `render.rs` runs this whole-frame form
//! when [`RawMeta::linear_raw`](crate::raw::meta::RawMeta::linear_raw) is set.

use super::color::normalize_neutral;
use super::drive::Pipe;
use super::opcodes::pipeline::{apply_list3, finish_geometry, stage1_planes, Stage3};
use super::opcodes::{self, apply_region, OpcodeMode, Prepared, Region, StageRect};
use super::render_parts::{Bands, BAND};
use super::rgb::RgbImage;
use super::stages::{Samples, Stage};
use crate::dng::opcodes::ListId;
use crate::error::{Error, Result};
use crate::raw::meta::LinearRaw;
use crate::raw::RawImage;
use rayon::prelude::*;
use std::borrow::Cow;

fn linear_raw(img: &RawImage) -> Result<&LinearRaw> {
    img.meta
        .linear_raw
        .as_ref()
        .ok_or_else(|| Error::invalid("not a LinearRaw image"))
}

/// Normalized camera RGB of the active area with the opcodes `p` applied (none: `None`),
/// each sample in [0, 1], and its extent in active-area coordinates (smaller than the
/// active area after an OpcodeList3 TrimBounds; `rgb` covers exactly the extent).
fn stage_rgb(
    img: &RawImage,
    p: Option<&Prepared>,
    samples: &Samples,
) -> Result<(RgbImage, StageRect)> {
    img.validate()?;
    let lr = linear_raw(img)?;
    let spp = usize::from(lr.samples_per_pixel);
    if spp != 3 {
        return Err(Error::unsupported(format!(
            "LinearRaw with {spp} samples per pixel (3 supported)"
        )));
    }
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
    let list = |id: ListId| p.map_or(&[][..], |p| p.list(id));
    // Stage 1: OpcodeList1 on the stored values (stored-image coordinates).
    let l1 = list(ListId::List1);
    let data: Cow<[u16]> = if l1.is_empty() {
        Cow::Borrowed(&img.data)
    } else {
        Cow::Owned(stage1_planes(
            l1,
            &img.data,
            spp,
            (0, 0, img.width, img.height),
            (img.width, img.height),
        ))
    };
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let (top, left) = (a.top as usize, a.left as usize);
    let stride = img.width * spp;
    let mut rgb = RgbImage::try_new(w, h)?;
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
                    let y = samples.between(Stage::Normalize, Stage::Opcodes2, y, s);
                    o[s] = if y.is_nan() {
                        0.0
                    } else {
                        y.clamp(0.0, 1.0) as f32
                    };
                }
            }
        });
    let extent = StageRect::of_size(w, h);
    // Stage 2: OpcodeList2 on the linear reference values (active-area coordinates).
    let l2 = list(ListId::List2);
    if !l2.is_empty() {
        let mut reg = Region {
            data: &mut rgb.data,
            top: 0,
            left: 0,
            width: w,
            height: h,
            planes: 3,
            extent,
            range: 1.0,
        };
        apply_region(l2, &mut reg);
    }
    // Stage 3: OpcodeList3 on the same image (nothing to demosaic), before white balance.
    let l3 = list(ListId::List3);
    if l3.is_empty() {
        return Ok((rgb, extent));
    }
    let mut s3 = Stage3 {
        rgb,
        top: 0,
        left: 0,
        extent,
    };
    apply_list3(l3, &mut s3)?;
    Ok((s3.rgb, s3.extent))
}

/// The sample stages after OpcodeList2 (white balance by the neutral, clipped to [0, 1]),
/// on every sample: here after OpcodeList3, as the DNG SDK runs a LinearRaw image.
fn white_balance(rgb: &mut RgbImage, samples: &Samples) {
    let w = rgb.width.max(1);
    rgb.data.par_chunks_mut(3 * w).for_each(|row| {
        for px in row.chunks_exact_mut(3) {
            for (k, v) in px.iter_mut().enumerate() {
                *v = samples.between(Stage::Opcodes2, Stage::Demosaic, *v, k);
            }
        }
    });
}

/// White-balanced camera RGB before geometry.
fn balanced(img: &RawImage, neutral: [f64; 3], mode: OpcodeMode) -> Result<RgbImage> {
    let samples = Samples::new(normalize_neutral(neutral)?);
    let p = opcodes::active_image(img, mode)?;
    let (mut rgb, _) = stage_rgb(img, p.as_ref(), &samples)?;
    white_balance(&mut rgb, &samples);
    Ok(rgb)
}

/// Normalized, white-balanced camera RGB of the active area, each sample clipped to
/// [0, 1], the file's opcodes applied (no colour matrix, no crop, no orientation; after
/// an OpcodeList3 TrimBounds, the trimmed rectangle).
pub fn camera_rgb(img: &RawImage, neutral: [f64; 3]) -> Result<RgbImage> {
    camera_rgb_with(img, neutral, OpcodeMode::Apply)
}

/// [`camera_rgb`] with the opcode lists applied or ignored.
pub fn camera_rgb_with(img: &RawImage, neutral: [f64; 3], mode: OpcodeMode) -> Result<RgbImage> {
    balanced(img, neutral, mode)
}

/// The render of the pipe's LinearRaw image (see the module docs): its whole-frame walk,
/// for every [`super::render::Execution`] that makes one.
pub(crate) fn render(pipe: &Pipe) -> Result<RgbImage> {
    let img = pipe.img;
    let rows = pipe.rows();
    // The samples are normalized per plane by `stage_rgb` (LinearRaw levels, not the CFA
    // normalizer), and they are already demosaiced: the demosaic stage is the identity.
    let samples = pipe.samples();
    let (mut rgb, b) = stage_rgb(img, pipe.opcodes(), &samples)?;
    white_balance(&mut rgb, &samples);
    let w = rgb.width.max(1);
    rgb.data.par_chunks_mut(3 * w).for_each(|row| rows.run(row));
    let a = img.active_area();
    let (crop, orient) = pipe.geometry();
    finish_geometry(rgb, b, &img.meta, (a.width(), a.height()), crop, orient)
}

/// [`render`] handed to `f` band by band ([`BAND`] rows) after `start(width, height)`, as
/// [`super::render::render_bands`] does.
pub(crate) fn bands<T, S, F>(pipe: &Pipe, start: S, f: F) -> Result<Bands<T>>
where
    T: Send,
    S: FnOnce(usize, usize) -> Result<()>,
    F: Fn(usize, usize, &[f32]) -> Result<T> + Sync,
{
    let rgb = render(pipe)?;
    let (ow, oh) = (rgb.width, rgb.height);
    start(ow, oh)?;
    let band = 3 * ow * BAND;
    let bands = super::bands::in_order(oh.div_ceil(BAND), |bi, _| {
        let rows = &rgb.data[bi * band..((bi + 1) * band).min(rgb.data.len())];
        f(bi * BAND, ow, rows)
    })?;
    Ok(Bands {
        width: ow,
        height: oh,
        bands,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dng::opcodes::{
        encode_list, AreaSpec, Opcode, OpcodeKind, OpcodeList, FLAG_OPTIONAL,
    };
    use crate::isp::render::{render as render_linear, render_bands, RenderOptions};
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

    fn area(plane: u32, planes: u32, (bottom, right): (u32, u32)) -> AreaSpec {
        AreaSpec {
            top: 0,
            left: 0,
            bottom,
            right,
            plane,
            planes,
            row_pitch: 1,
            col_pitch: 1,
        }
    }

    fn poly(plane: u32, c: &[f64]) -> Opcode {
        Opcode::new(
            OpcodeKind::MapPolynomial {
                area: area(plane, 1, (2, 2)),
                coefficients: c.to_vec(),
            },
            0,
        )
    }

    fn with_list(img: &mut RawImage, id: ListId, opcodes: Vec<Opcode>) {
        img.meta.opcode_lists[id.index()] = Some(encode_list(&OpcodeList { opcodes }));
    }

    /// A 2x2 image of 0.5 in every sample (black 0, white 100).
    fn half() -> RawImage {
        image(2, 2, vec![50; 12], vec![0.0; 3], vec![100.0; 3])
    }

    #[test]
    fn opcode_list2_map_polynomial_per_plane_through_the_shared_stage() {
        // The linearization curves of an Adobe lossy DNG: one MapPolynomial per plane.
        let mut img = half();
        with_list(
            &mut img,
            ListId::List2,
            vec![poly(1, &[0.0, 0.5]), poly(2, &[0.1, 0.0, 1.0])],
        );
        let rgb = camera_rgb(&img, [1.0, 1.0, 1.0]).unwrap();
        assert_eq!(&rgb.data[..3], &[0.5, 0.25, 0.35]);
        assert_eq!(rgb.data.chunks(3).filter(|p| p[1] == 0.25).count(), 4);
        // Results are pinned into [0, 1]; white balance comes after the curves.
        with_list(
            &mut img,
            ListId::List2,
            vec![poly(0, &[-1.0]), poly(2, &[3.0])],
        );
        let rgb = camera_rgb(&img, [1.0, 1.0, 2.0]).unwrap();
        assert_eq!(&rgb.data[..3], &[0.0, 0.5, 0.5]);
        // --opcodes ignore leaves them out; the render follows RenderOptions::opcodes.
        let rgb = camera_rgb_with(&img, [1.0, 1.0, 1.0], OpcodeMode::Ignore).unwrap();
        assert!(rgb.data.iter().all(|&v| v == 0.5));
        let opts = |opcodes| RenderOptions {
            neutral: Some([1.0, 1.0, 1.0]),
            opcodes,
            ..RenderOptions::default()
        };
        assert_ne!(
            render_linear(&img, &opts(OpcodeMode::Apply)).unwrap(),
            render_linear(&img, &opts(OpcodeMode::Ignore)).unwrap()
        );
    }

    #[test]
    fn malformed_lists_are_errors_unless_ignored() {
        let mut img = half();
        with_list(&mut img, ListId::List2, vec![poly(0, &[0.0, 1.0])]);
        let list = img.meta.opcode_lists[1].as_mut().unwrap();
        list.truncate(list.len() - 3);
        let e = camera_rgb(&img, [1.0; 3]).unwrap_err().to_string();
        assert!(e.contains("OpcodeList2"), "{e}");
        assert!(camera_rgb_with(&img, [1.0; 3], OpcodeMode::Ignore).is_ok());
        for c in [vec![f64::NAN], vec![0.0; 12]] {
            with_list(&mut img, ListId::List2, vec![poly(0, &c)]);
            assert!(camera_rgb(&img, [1.0; 3]).is_err(), "{c:?}");
        }
    }

    #[test]
    fn unsupported_opcodes_are_skipped_when_optional_else_errors() {
        let mut img = half();
        let bad_pixels = |flags| {
            Opcode::new(
                OpcodeKind::FixBadPixelsConstant {
                    constant: 0,
                    bayer_phase: 0,
                },
                flags,
            )
        };
        // Bad pixels repair a CFA mosaic: a LinearRaw image has none.
        with_list(
            &mut img,
            ListId::List2,
            vec![bad_pixels(FLAG_OPTIONAL), poly(0, &[0.25])],
        );
        let p = opcodes::prepare(&img.meta, OpcodeMode::Apply)
            .unwrap()
            .unwrap();
        assert_eq!(p.report.applied.len(), 1);
        assert!(p.report.warnings()[0]
            .message
            .contains("OpcodeList2: FixBadPixelsConstant (id 4)"));
        assert_eq!(camera_rgb(&img, [1.0; 3]).unwrap().data[0], 0.25);
        with_list(&mut img, ListId::List2, vec![bad_pixels(0)]);
        let e = camera_rgb(&img, [1.0; 3]).unwrap_err().to_string();
        assert!(e.contains("not optional"), "{e}");
        assert!(camera_rgb_with(&img, [1.0; 3], OpcodeMode::Ignore).is_ok());
    }

    #[test]
    fn list1_on_stored_values_and_list3_before_white_balance() {
        // List 1: stored units, whole stored image (2x2 here).
        let mut img = half();
        with_list(
            &mut img,
            ListId::List1,
            vec![Opcode::new(
                OpcodeKind::ScalePerRow {
                    area: area(0, 3, (2, 2)),
                    scales: vec![2.0, 1.0],
                },
                0,
            )],
        );
        let rgb = camera_rgb(&img, [1.0; 3]).unwrap();
        assert_eq!(&rgb.data[..6], &[1.0; 6]);
        assert_eq!(&rgb.data[6..], &[0.5; 6]);
        // List 3 on the camera values (not white balanced), TrimBounds shrinking the image.
        let mut img = half();
        with_list(
            &mut img,
            ListId::List3,
            vec![
                Opcode::new(
                    OpcodeKind::MapPolynomial {
                        area: area(0, 1, (2, 2)),
                        coefficients: vec![0.0, 1.5],
                    },
                    0,
                ),
                Opcode::new(
                    OpcodeKind::TrimBounds {
                        bounds: [0, 1, 2, 2],
                    },
                    0,
                ),
            ],
        );
        let rgb = camera_rgb(&img, [0.5, 1.0, 1.0]).unwrap();
        assert_eq!((rgb.width, rgb.height), (1, 2));
        assert_eq!(&rgb.data[..3], &[1.0, 0.5, 0.5]);
        let out = render_linear(&img, &RenderOptions::default()).unwrap();
        assert_eq!((out.width, out.height), (1, 2));
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
        let bands = render_bands(&img, &opts, |_, _| Ok(()), |_, _, rows| Ok(rows.to_vec()))
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
