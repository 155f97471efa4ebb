//! `day2night._native.night_pair`: the synthesis of one `NightPairs` item with its arrays
//! made in their final layout in Rust (the packed, normalized Bayer crops and the CHW
//! target), so an item costs what the synthesis of its crop costs: no plan or report
//! converted to Python objects, no intermediate arrays. The values equal
//! `pack_bayer(synthesize(...)["noisy"][iso], raw.meta, top, left)` and
//! `synthesize(...)["target"].transpose(2, 0, 1)` exactly (python/tests/test_pairs.py).

use crate::args::{self, Iso, Seed, Variant};
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use crate::raw::Raw;
use crate::synth_options::{job_config, job_for};
use day2night::raw::crop::Crop;
use day2night::raw::Levels;
use day2night::synth::night::{synthesize as lib_synthesize, Request};
use day2night::{Error, RawImage};
use numpy::ndarray::{Array3, Array4};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The per-position black levels (CFA positions (0,0), (0,1), (1,0), (1,1) of a plane whose
/// top-left sample is at active-area (top, left)) and the scale `white - max(black)`, as
/// `pack_bayer` computes them (in f64, then f32).
fn pack_levels(levels: &Levels, top: usize, left: usize) -> Result<([f32; 4], f32), Error> {
    let (rr, rc) = levels.black_repeat;
    let mut black = [0f32; 4];
    for i in 0..2 {
        for j in 0..2 {
            let k = ((top + i) % rr.max(1)) * rc + (left + j) % rc.max(1);
            let b = levels.black.get(k).copied().ok_or_else(|| {
                Error::invalid(format!(
                    "BlackLevel has {} values for a {rr}x{rc} repeat pattern",
                    levels.black.len()
                ))
            })?;
            black[2 * i + j] = b as f32;
        }
    }
    let max_black = levels
        .black
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let scale = levels.white - max_black;
    if scale.is_nan() || scale <= 0.0 {
        return Err(Error::invalid(format!(
            "black level {max_black} >= white level {}",
            levels.white
        )));
    }
    Ok((black, scale as f32))
}

/// A Bayer plane (even height and width) packed to 4 x h/2 x w/2 float32, `(x - black) /
/// scale` per CFA position: one pass over the plane, each row pair feeding the four planes.
fn pack(img: &RawImage, black: &[f32; 4], scale: f32) -> Vec<f32> {
    let (w, n) = (img.width, img.width / 2 * (img.height / 2));
    let mut out = vec![0f32; 4 * n];
    let (p01, p23) = out.split_at_mut(2 * n);
    let (p0, p1) = p01.split_at_mut(n);
    let (p2, p3) = p23.split_at_mut(n);
    let w2 = w / 2;
    for ((((rows, o0), o1), o2), o3) in img
        .data
        .chunks_exact(2 * w)
        .zip(p0.chunks_exact_mut(w2))
        .zip(p1.chunks_exact_mut(w2))
        .zip(p2.chunks_exact_mut(w2))
        .zip(p3.chunks_exact_mut(w2))
    {
        let (r0, r1) = rows.split_at(w);
        deinterleave(r0, o0, o1, black[0], black[1], scale);
        deinterleave(r1, o2, o3, black[2], black[3], scale);
    }
    out
}

/// The even samples of `row` normalized into `a`, the odd ones into `b`.
#[inline]
fn deinterleave(row: &[u16], a: &mut [f32], b: &mut [f32], ba: f32, bb: f32, scale: f32) {
    for ((px, a), b) in row.chunks_exact(2).zip(a.iter_mut()).zip(b.iter_mut()) {
        *a = (f32::from(px[0]) - ba) / scale;
        *b = (f32::from(px[1]) - bb) / scale;
    }
}

/// Interleaved RGB (h x w x 3) to planar (3 x h x w).
fn planar(rgb: &[f32], n: usize) -> Vec<f32> {
    let mut out = vec![0f32; 3 * n];
    let (r, gb) = out.split_at_mut(n);
    let (g, b) = gb.split_at_mut(n);
    for (((px, r), g), b) in rgb.chunks_exact(3).zip(r).zip(g).zip(b) {
        *r = px[0];
        *g = px[1];
        *b = px[2];
    }
    out
}

/// One training pair on a crop: ``synthesize(raw, seed, variant, mode, isos=(iso,),
/// crop=crop, **options)`` with the outputs in their training layout: ``noisy`` and
/// ``clean`` (4 x h/2 x w/2 float32, packed and normalized as ``pack_bayer``), ``target``
/// (3 x h x w float32, linear Rec.709). Used by ``NightPairs``.
#[pyfunction]
#[pyo3(signature = (raw, seed, variant, iso, crop, mode="local", **options))]
pub fn night_pair<'py>(
    raw: &Bound<'py, Raw>,
    seed: Seed,
    variant: Variant,
    iso: Iso,
    crop: &Bound<'py, PyAny>,
    mode: &str,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let py = raw.py();
    let (seed, variant, iso) = (seed.0, variant.0, iso.0);
    let a = raw.get().day.raw.active_area();
    let Crop {
        top,
        left,
        height,
        width,
    } = args::crop(crop, a.width(), a.height())?;
    if height % 2 != 0 || width % 2 != 0 {
        return Err(value_err(format!(
            "crop {height}x{width}: the packed Bayer layout needs an even size"
        )));
    }
    let cfg = job_config(mode, vec![iso], true, options)?;
    let r = raw.get();
    let day = r.cfa_day()?;
    let file_name = r.file_name.clone();
    let (noisy, clean, target, plan) = py
        .detach(move || {
            on_pool(move || {
                let job = job_for(&cfg)?;
                let plan = day.with_frame_mean(job.plan(&day, &file_name, seed, variant)?.plan)?;
                let req = Request {
                    target: true,
                    input: false,
                    crop: Some(Crop {
                        top,
                        left,
                        height,
                        width,
                    }),
                };
                let night = lib_synthesize(&day.raw, &plan, &req)?;
                let (black, scale) = pack_levels(&day.raw.meta.levels, top, left)?;
                let noisy_img = night
                    .noisy
                    .iter()
                    .find(|(i, _)| *i == iso)
                    .map(|(_, img)| img)
                    .ok_or_else(|| Error::invalid(format!("no noisy raw at ISO {iso}")))?;
                // a burst's frames, frame 00 first (one frame without a burst)
                let frames = crate::burst::frames_of(&night, iso, noisy_img);
                let t = night
                    .target
                    .as_ref()
                    .ok_or_else(|| Error::invalid("no target rendered"))?;
                if frames
                    .iter()
                    .any(|f| (f.height, f.width) != (height, width))
                    || (night.clean.height, night.clean.width) != (height, width)
                    || (t.height, t.width) != (height, width)
                {
                    return Err(Error::invalid(
                        "the crop's outputs do not have the crop's size",
                    ));
                }
                // The three layouts on the calling thread's workers.
                let ((noisy, clean), target) = rayon::join(
                    || {
                        rayon::join(
                            || {
                                let mut v = Vec::new();
                                for f in &frames {
                                    v.extend(pack(f, &black, scale));
                                }
                                v
                            },
                            || pack(&night.clean, &black, scale),
                        )
                    },
                    || planar(&t.data, height * width),
                );
                Ok((noisy, clean, target, plan))
            })
        })
        .map_err(py_err)?;
    let shape = |c: usize, h: usize, w: usize, v: Vec<f32>| -> PyResult<Bound<'py, PyAny>> {
        Ok(Array3::from_shape_vec((c, h, w), v)
            .map_err(|e| value_err(e.to_string()))?
            .into_pyarray(py)
            .into_any())
    };
    let d = PyDict::new(py);
    match crate::burst::transform_arrays(py, &plan)? {
        // a burst: (N, 4, h/2, w/2), the frames' affines and valid rectangles
        Some((affine, valid)) => {
            let n = noisy.len() / (height * width);
            let a = Array4::from_shape_vec((n, 4, height / 2, width / 2), noisy)
                .map_err(|e| value_err(e.to_string()))?;
            d.set_item("noisy", a.into_pyarray(py))?;
            d.set_item("transforms", affine)?;
            d.set_item("valid", valid)?;
        }
        None => d.set_item("noisy", shape(4, height / 2, width / 2, noisy)?)?,
    }
    d.set_item("clean", shape(4, height / 2, width / 2, clean)?)?;
    d.set_item("target", shape(3, height, width, target)?)?;
    Ok(d)
}
