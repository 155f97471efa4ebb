//! Burst merging (the paper's ground truth: the mean of 30 aligned ISO-50 frames).
//!
//! Frames must share stored size, ActiveArea, CFA, levels (black, white,
//! LinearizationTable) and Exif ISO; the first mismatch is a clear error. Samples are
//! linearized and summed exactly (u64). The output keeps every bit of the mean in a 16-bit
//! container by scaling the levels with an integer factor `K`:
//!
//! - `K = N` (the frame count) when `N * white <= 65535`: the output samples ARE the sums,
//!   exactly, with `BlackLevel * N` and `WhiteLevel * N` (e.g. 30 frames of a 10-bit camera:
//!   white 30690). Nothing is rounded.
//! - otherwise `K = floor(65535 / white)` (at least 1): samples are `round(sum * K / N)`,
//!   levels scaled by `K`; the rounding error is at most `0.5 / K` DN of the mean.
//!
//! Normalized values (`(x - black) / (white - black)`) are unchanged by the scaling, so every
//! reader that applies BlackLevel/WhiteLevel (the DNG SDK, LibRaw/rawpy, day2night) sees the
//! mean. LinearizationTable is applied before summing and dropped from the output.
//! A site saturated (>= white) in any frame is written as the output white level, so it stays
//! marked saturated. Metadata comes from the first frame; NoiseProfile (S, O) is divided by `N`
//! (the variance of a mean of N independent frames).

use super::{check_same_capture, SameCapture};
use crate::error::{Error, Result};
use crate::normalize::Normalizer;
use crate::raw::RawImage;

/// What a merge did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MergeReport {
    /// Frames averaged.
    pub frames: usize,
    /// Level scale factor K.
    pub scale_factor: u32,
    /// True when the output holds the exact sums (K = N).
    pub exact: bool,
    /// Output white level.
    pub white: f64,
    /// Output black level (max over the plane).
    pub black: f64,
    /// Sites saturated in at least one frame (written as white).
    pub saturated_sites: u64,
}

/// Why `paths` cannot be a burst when one file comes twice, naming it: the same file given
/// twice (the same path after resolving `.`, `..` and links; a path that cannot be resolved,
/// a missing one, is compared as given and fails when read) would count double in the mean.
/// `day2night merge` and Python's `merge` refuse it so; None when the files are distinct.
pub fn repeated_frame(paths: &[std::path::PathBuf]) -> Option<String> {
    let mut seen = std::collections::HashMap::with_capacity(paths.len());
    for (i, path) in paths.iter().enumerate() {
        let key = std::fs::canonicalize(path).unwrap_or_else(|_| path.clone());
        if let Some(j) = seen.insert(key, i) {
            return Some(format!(
                "{}: merge got this frame twice (paths {j} and {i} of {}): a burst's frames \
                 are distinct files, and a frame given twice would count double",
                path.display(),
                paths.len()
            ));
        }
    }
    None
}

/// Streaming merger: frames are added one at a time.
#[derive(Debug)]
pub struct Merger {
    first: RawImage,
    norm: Normalizer,
    sum: Vec<u64>,
    sat: Vec<bool>,
    frames: usize,
}

fn meta_only(img: &RawImage) -> RawImage {
    RawImage {
        width: img.width,
        height: img.height,
        data: vec![],
        meta: img.meta.clone(),
    }
}

impl Merger {
    /// Start with the first frame.
    pub fn new(first: RawImage) -> Result<Self> {
        let norm = Normalizer::new(&first)?;
        let mut m = Merger {
            norm,
            sum: vec![0; first.data.len()],
            sat: vec![false; first.data.len()],
            frames: 0,
            first: meta_only(&first),
        };
        m.add_unchecked(&first);
        Ok(m)
    }

    /// Add a frame; errors unless it matches the first frame (see module docs).
    pub fn add(&mut self, img: &RawImage) -> Result<()> {
        check_same_capture(
            &self.first,
            &meta_only(img),
            SameCapture {
                iso: true,
                levels: true,
            },
        )?;
        img.validate()?;
        self.add_unchecked(img);
        Ok(())
    }

    fn add_unchecked(&mut self, img: &RawImage) {
        for ((s, t), &x) in self.sum.iter_mut().zip(self.sat.iter_mut()).zip(&img.data) {
            let l = self.norm.linearize(x);
            if l >= self.norm.white {
                *t = true;
            }
            *s += l as u64;
        }
        self.frames += 1;
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The merged image. Errors with fewer than two frames.
    pub fn finish(self) -> Result<(RawImage, MergeReport)> {
        let n = self.frames as u64;
        if n < 2 {
            return Err(Error::invalid(format!(
                "merging needs at least 2 frames, got {n} (a single frame is already its own mean)"
            )));
        }
        let white = self.norm.white;
        let k: u64 = if white * n as f64 <= 65535.0 {
            n
        } else {
            ((65535.0 / white).floor() as u64).max(1)
        };
        let kf = k as f64;
        let white_out = (white * kf).min(65535.0);
        let white_dn = white_out.round() as u64;
        let mut saturated = 0u64;
        let data: Vec<u16> = self
            .sum
            .iter()
            .zip(&self.sat)
            .map(|(&s, &sat)| {
                let v = if sat {
                    saturated += 1;
                    white_dn
                } else {
                    // round(s * k / n), half up, exact in integers.
                    ((2 * s * k + n) / (2 * n)).min(white_dn)
                };
                v.min(65535) as u16
            })
            .collect();
        let mut meta = self.first.meta.clone();
        meta.linearization_table = None;
        meta.bits_per_sample = 16;
        meta.storage = None;
        let l = &mut meta.levels;
        l.black.iter_mut().for_each(|b| *b *= kf);
        l.black_delta_h.iter_mut().for_each(|b| *b *= kf);
        l.black_delta_v.iter_mut().for_each(|b| *b *= kf);
        l.white = white_out;
        if let Some(np) = meta.noise_profile.as_mut() {
            np.iter_mut().for_each(|(s, o)| {
                *s /= n as f64;
                *o /= n as f64;
            });
        }
        let report = MergeReport {
            frames: self.frames,
            scale_factor: k as u32,
            exact: k == n,
            white: white_out,
            black: meta.levels.black_max(),
            saturated_sites: saturated,
        };
        let img = RawImage {
            width: self.first.width,
            height: self.first.height,
            data,
            meta,
        };
        img.validate()?;
        Ok((img, report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::normalize::{normalize, NormalizeOptions};
    use crate::raw::meta::RawMeta;
    use crate::raw::Bayer;

    fn frame(vals: &[u16], white: f64, iso: u32) -> RawImage {
        let mut meta = RawMeta::new_bayer(Bayer::RGGB, 10, 64.0, white);
        meta.exif.iso = Some(iso);
        meta.noise_profile = Some(vec![(1e-3, 1e-5)]);
        RawImage {
            width: 2,
            height: 2,
            data: vals.to_vec(),
            meta,
        }
    }

    #[test]
    fn exact_sum_for_small_white() {
        let mut m = Merger::new(frame(&[100, 200, 300, 1023], 1023.0, 50)).unwrap();
        m.add(&frame(&[101, 202, 303, 900], 1023.0, 50)).unwrap();
        m.add(&frame(&[103, 200, 300, 900], 1023.0, 50)).unwrap();
        let (img, r) = m.finish().unwrap();
        assert_eq!(img.data, vec![304, 602, 903, 3069]);
        assert!(r.exact && r.scale_factor == 3 && r.saturated_sites == 1);
        assert_eq!(img.meta.levels.black, vec![192.0]);
        assert_eq!(img.meta.noise_profile, Some(vec![(1e-3 / 3.0, 1e-5 / 3.0)]));
        // Normalized values equal the mean of the frames' normalized values.
        let p = normalize(&img, NormalizeOptions::default()).unwrap();
        let want = ((304.0 / 3.0) - 64.0) / 959.0;
        assert!((p.data[0] as f64 - want).abs() < 1e-6);
    }

    #[test]
    fn rounded_mean_for_large_white() {
        let mut m = Merger::new(frame(&[1000, 2000, 3000, 4000], 30000.0, 50)).unwrap();
        for _ in 0..2 {
            m.add(&frame(&[1001, 2000, 3000, 4000], 30000.0, 50))
                .unwrap();
        }
        let (img, r) = m.finish().unwrap();
        // 3 x 30000 > 65535, so K = 2: round(3002 * 2 / 3) = round(2001.33) = 2001.
        assert_eq!(r.scale_factor, 2);
        assert!(!r.exact);
        assert_eq!(img.data[0], 2001);
        assert_eq!(img.meta.levels.white, 60000.0);
    }

    #[test]
    fn mismatches_are_named() {
        let mut m = Merger::new(frame(&[1, 2, 3, 4], 1023.0, 50)).unwrap();
        let e = m.add(&frame(&[1, 2, 3, 4], 1023.0, 100)).unwrap_err();
        assert!(e.to_string().contains("ISO 100"), "{e}");
        let e = m.add(&frame(&[1, 2, 3, 4], 4095.0, 50)).unwrap_err();
        assert!(e.to_string().contains("white level"), "{e}");
        let mut f = frame(&[1, 2, 3, 4], 1023.0, 50);
        f.meta.cfa.pattern = Bayer::BGGR.0.to_vec();
        let e = m.add(&f).unwrap_err();
        assert!(e.to_string().contains("CFA pattern BGGR"), "{e}");
        let big = RawImage {
            width: 4,
            height: 1,
            ..frame(&[1, 2, 3, 4], 1023.0, 50)
        };
        let e = m.add(&big).unwrap_err();
        assert!(e.to_string().contains("size 4x1"), "{e}");
        let one = Merger::new(frame(&[1, 2, 3, 4], 1023.0, 50)).unwrap();
        assert!(one.finish().unwrap_err().to_string().contains("at least 2"));
    }
}
