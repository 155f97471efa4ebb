//! Training pairs of one synthesized crop for the night ISP (issue 31, fresh synthesis):
//! the release's network input ([`crate::isp::release_input`]) of the crop's noisy (or
//! clean) night raw and the 8-bit display target of its linear render, made without
//! anything else ([`crop_pair`]), and the cutting of an image into the network's
//! `patch` x `patch` tiles ([`cut_patches`]).
//!
//! The crop is synthesized by [`super::night::synthesize_into`] (the path of
//! `synthesize(raw, crop=...)`), so its clean, noisy and target pixels are those of
//! [`super::night::synthesize`] for the same plan; a sink turns them into the network
//! input and the 8-bit target as they are made. Only the ISO the input needs gets noise
//! (none for a clean input): the other planned ISOs are dropped from the plan, which
//! changes nothing of the clean raw, the target or the kept ISO (each ISO's noise has its
//! own seed in the plan).

use super::night::{synthesize_into, NightSink, Request, TargetOut};
use super::relight::RunReport;
use super::Plan;
use crate::encode::png::encode_u8;
use crate::error::{Error, Result};
use crate::isp::release_input::{release_codes, CfaPlane, FrameFacts};
use crate::isp::tone::DisplayTone;
use crate::raw::crop::Crop;
use crate::raw::RawImage;
use std::sync::Mutex;

/// Which night raw of the crop the network input is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairInput {
    /// The clean night raw.
    Clean,
    /// The noisy night raw of this planned ISO.
    Noisy(u32),
}

/// The network input and target of one crop.
#[derive(Debug, Clone)]
pub struct CropPair {
    /// Crop width and height.
    pub width: usize,
    /// Crop height.
    pub height: usize,
    /// The release's demosaiced 14-bit codes of the input, `height * width * 3` (RGB
    /// interleaved), white-balanced by the plan's night neutral
    /// ([`crate::isp::release_input::release_codes`]; map them through a code table).
    pub codes: Vec<u16>,
    /// The 8-bit display encoding of the crop's linear target, `height * width * 3`.
    pub target: Vec<u8>,
    /// The run's report (a constant target is among its warnings).
    pub report: RunReport,
}

/// The network input (of `input`) and the 8-bit `tone` target of the active-area
/// rectangle `crop` of `plan`'s night variant of `day`. The crop's offsets must be even.
pub fn crop_pair(
    day: &RawImage,
    plan: &Plan,
    crop: Crop,
    input: PairInput,
    tone: DisplayTone,
) -> Result<CropPair> {
    let mut plan = plan.clone();
    match input {
        PairInput::Clean => plan.noise.clear(),
        PairInput::Noisy(iso) => {
            plan.noise.retain(|n| n.iso == iso);
            if plan.noise.is_empty() {
                return Err(Error::invalid(format!(
                    "ISO {iso} is not among the plan's ISOs"
                )));
            }
        }
    }
    let bayer = day.bayer()?;
    let sink = PairSink {
        input,
        tone,
        codes_of: &|img: &RawImage| {
            release_codes(
                &CfaPlane {
                    data: &img.data,
                    width: img.width,
                    height: img.height,
                    top: crop.top,
                    left: crop.left,
                },
                &FrameFacts {
                    levels: &day.meta.levels,
                    bayer,
                    neutral: plan.night_neutral,
                    linearization: None,
                },
            )
        },
        codes: Mutex::new(None),
        target: Mutex::new(None),
    };
    let req = Request {
        target: true,
        input: false,
        crop: Some(crop),
    };
    let out = synthesize_into(day, &plan, &req, &sink)?;
    let missing = || Error::invalid("the crop's synthesis made no network input or no target");
    let codes = take(&sink.codes).ok_or_else(missing)?;
    let target = take(&sink.target).ok_or_else(missing)?;
    Ok(CropPair {
        width: crop.width,
        height: crop.height,
        codes,
        target,
        report: out.report,
    })
}

struct PairSink<'a> {
    input: PairInput,
    tone: DisplayTone,
    codes_of: &'a (dyn Fn(&RawImage) -> Result<Vec<u16>> + Sync),
    codes: Mutex<Option<Vec<u16>>>,
    target: Mutex<Option<Vec<u8>>>,
}

impl NightSink for PairSink<'_> {
    type Band = ();
    fn clean(&self, clean: &RawImage) -> Result<()> {
        if self.input == PairInput::Clean {
            *lock(&self.codes) = Some((self.codes_of)(clean)?);
        }
        Ok(())
    }
    fn noisy(&self, iso: u32, frame: u32, noisy: &RawImage) -> Result<()> {
        if frame == 0 && self.input == PairInput::Noisy(iso) {
            *lock(&self.codes) = Some((self.codes_of)(noisy)?);
        }
        Ok(())
    }
    fn target(&self, target: TargetOut<()>) -> Result<()> {
        match target {
            TargetOut::Image(rgb) => {
                *lock(&self.target) = Some(encode_u8(&rgb, self.tone));
                Ok(())
            }
            TargetOut::Bands(_) => Err(Error::invalid("a crop's target comes as one image")),
        }
    }
}

/// A poisoned lock only means another task panicked; its data is still the data.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn take<T>(m: &Mutex<Option<T>>) -> Option<T> {
    lock(m).take()
}

/// Cut an interleaved `height` x `width` x 3 image into the `(height / patch) * (width /
/// patch)` non-overlapping `patch` x `patch` tiles of its row-major grid (the remainder
/// dropped), each channel-first: element `[k][c][i][j]` is `f(img[(gy * patch + i) *
/// width + gx * patch + j][c])` for tile `k = gy * (width / patch) + gx`.
pub fn cut_patches<T: Copy, U: Copy + Default>(
    img: &[T],
    width: usize,
    height: usize,
    patch: usize,
    f: impl Fn(T) -> U,
) -> Result<Vec<U>> {
    let (gw, gh) = grid(img, width, height, patch)?;
    let plane = patch * patch;
    // One tile at a time into a small cache-resident scratch tile, appended whole: the
    // output is filled in order (no zeroed buffer written twice: the zeroing of a fresh
    // allocation was a tenth of a fresh item's time).
    let mut out = vec![U::default(); gw * gh * 3 * plane];
    for (k, tile) in out.chunks_exact_mut(3 * plane).enumerate() {
        write_tile(img, width, patch, (k / gw, k % gw), &f, tile);
    }
    Ok(out)
}

/// [`cut_patches`] into `out`, which must hold exactly the `(height / patch) * (width /
/// patch) * 3 * patch * patch` values of the tiles (a caller's buffer: the training loader
/// passes a slice of its batch, so that the patches are written where they are used).
pub fn cut_patches_into<T: Copy, U: Copy>(
    img: &[T],
    width: usize,
    height: usize,
    patch: usize,
    f: impl Fn(T) -> U,
    out: &mut [U],
) -> Result<()> {
    let (gw, gh) = grid(img, width, height, patch)?;
    let plane = patch * patch;
    if out.len() != gw * gh * 3 * plane {
        return Err(Error::invalid(format!(
            "the {gw} x {gh} patches of {patch} x {patch} x 3 need {} values, the buffer holds {}",
            gw * gh * 3 * plane,
            out.len()
        )));
    }
    for (k, tile) in out.chunks_exact_mut(3 * plane).enumerate() {
        write_tile(img, width, patch, (k / gw, k % gw), &f, tile);
    }
    Ok(())
}

/// The tile grid's columns and rows, after checking the image's length and the patch.
fn grid<T>(img: &[T], width: usize, height: usize, patch: usize) -> Result<(usize, usize)> {
    if patch == 0 || img.len() != width * height * 3 {
        return Err(Error::invalid(format!(
            "cannot cut {patch} x {patch} patches from {} samples of a {width} x {height} x 3 image",
            img.len()
        )));
    }
    Ok((width / patch, height / patch))
}

/// Tile `(gy, gx)` of `img`, channel-first, into `tile` (`3 * patch * patch` values). Each
/// source row is read once and its three channels written at once: reading it once per
/// channel cost a 512 x 512 crop's cutting 13.4 M instructions against 8.7 M now
/// (callgrind of `benches/fresh.rs`; docs/benchmarks.md).
#[inline]
fn write_tile<T: Copy, U>(
    img: &[T],
    width: usize,
    patch: usize,
    (gy, gx): (usize, usize),
    f: &impl Fn(T) -> U,
    tile: &mut [U],
) {
    let plane = patch * patch;
    let (t0, rest) = tile.split_at_mut(plane);
    let (t1, t2) = rest.split_at_mut(plane);
    for (i, ((d0, d1), d2)) in t0
        .chunks_exact_mut(patch)
        .zip(t1.chunks_exact_mut(patch))
        .zip(t2.chunks_exact_mut(patch))
        .enumerate()
    {
        let src = &img[3 * ((gy * patch + i) * width + gx * patch)..][..3 * patch];
        for (((px, a), b), c) in src
            .chunks_exact(3)
            .zip(d0.iter_mut())
            .zip(d1.iter_mut())
            .zip(d2.iter_mut())
        {
            *a = f(px[0]);
            *b = f(px[1]);
            *c = f(px[2]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::isp::release_input::{release_codes, CfaPlane, FrameFacts};
    use crate::raw::Bayer;
    use crate::synth::night::synthesize;
    use crate::synth::{Calibration, SynthOptions};

    #[test]
    fn cut_patches_is_the_row_major_grid_channel_first() {
        let (w, h, p) = (5usize, 4usize, 2usize);
        let img: Vec<u32> = (0..(w * h * 3) as u32).collect();
        let t = cut_patches(&img, w, h, p, |v| v as f32).unwrap();
        assert_eq!(t.len(), 2 * 2 * 3 * p * p);
        for k in 0..4 {
            let (gy, gx) = (k / 2, k % 2);
            for c in 0..3 {
                for i in 0..p {
                    for j in 0..p {
                        let want = img[3 * ((gy * p + i) * w + gx * p + j) + c] as f32;
                        assert_eq!(t[((k * 3 + c) * p + i) * p + j], want);
                    }
                }
            }
        }
        let mut into = vec![0.0f32; t.len()];
        cut_patches_into(&img, w, h, p, |v| v as f32, &mut into).unwrap();
        assert_eq!(into, t);
        assert!(cut_patches_into(&img, w, h, p, |v| v as f32, &mut into[1..]).is_err());
        assert!(cut_patches_into(&img, w, h, 0, |v| v as f32, &mut into).is_err());
        assert!(cut_patches(&img, w, h, 0, |v| v).is_err());
        assert!(cut_patches(&img[1..], w, h, p, |v| v).is_err());
    }

    /// The pair equals what the in-memory synthesis of the same plan and crop gives, put
    /// through the release input and the 8-bit encoding.
    #[test]
    fn crop_pair_equals_the_synthesis_of_the_crop() {
        let (w, h) = (96usize, 72usize);
        let data = (0..w * h)
            .map(|i| 64 + ((i * 7919 + (i / w) * 131) % 900) as u16)
            .collect();
        let mut meta = crate::raw::RawMeta::new_bayer(Bayer::GRBG, 10, 64.0, 1023.0);
        meta.as_shot_neutral = Some([0.55, 1.0, 0.7]);
        meta.exif.iso = Some(100);
        let day = RawImage {
            width: w,
            height: h,
            data,
            meta,
        };
        let opts = SynthOptions {
            isos: vec![1600, 3200],
            ..SynthOptions::default()
        };
        let cal = Calibration::embedded(&opts).unwrap();
        let p = crate::synth::Planner::new(&day, &opts)
            .calibration(&cal)
            .name("d.dng")
            .seed(3)
            .variant(1)
            .plan()
            .unwrap()
            .plan;
        let crop = Crop {
            top: 10,
            left: 14,
            height: 32,
            width: 48,
        };
        let req = Request {
            target: true,
            input: false,
            crop: Some(crop),
        };
        let night = synthesize(&day, &p, &req).unwrap();
        let tone = DisplayTone::Srgb;
        let target = encode_u8(night.target.as_ref().unwrap(), tone);
        let codes = |img: &RawImage| {
            release_codes(
                &CfaPlane {
                    data: &img.data,
                    width: 48,
                    height: 32,
                    top: 10,
                    left: 14,
                },
                &FrameFacts {
                    levels: &day.meta.levels,
                    bayer: Bayer::GRBG,
                    neutral: p.night_neutral,
                    linearization: None,
                },
            )
            .unwrap()
        };
        for (input, plane) in [
            (PairInput::Clean, &night.clean),
            (PairInput::Noisy(1600), &night.noisy[0].1),
            (PairInput::Noisy(3200), &night.noisy[1].1),
        ] {
            let pair = crop_pair(&day, &p, crop, input, tone).unwrap();
            assert_eq!(pair.target, target, "{input:?}");
            assert_eq!(pair.codes, codes(plane), "{input:?}");
        }
        let e = crop_pair(&day, &p, crop, PairInput::Noisy(800), tone).unwrap_err();
        assert!(e.to_string().contains("ISO 800"), "{e}");
    }
}
