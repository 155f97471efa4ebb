//! Binned statistics of a burst ([`BurstAccumulator`]): per-pixel sums of the frames added
//! one at a time, split into even and odd frames (see the [module documentation](super)).

use super::{bin_index, camera_of, iso_of, Acc, BinStat, SourceStats, MIN_BURST_FRAMES, NBINS};
use crate::calibrate::{check_same_capture, SameCapture};
use crate::error::{Error, Result};
use crate::normalize::Normalizer;
use crate::raw::{Bayer, RawImage};

/// Streaming per-pixel statistics of a burst: frames are added one at a time.
#[derive(Debug)]
pub struct BurstAccumulator {
    first: RawImage,
    norm: Normalizer,
    frames: usize,
    /// Per pixel, per half (even/odd frames): sum and sum of squares of linearized values.
    sums: Vec<[u64; 4]>,
    clipped: Vec<bool>,
}

impl BurstAccumulator {
    /// Start with the first frame.
    pub fn new(first: RawImage) -> Result<Self> {
        let norm = Normalizer::new(&first)?;
        first.bayer()?;
        iso_of(&first)?;
        let a = first.active_area();
        let n = a.width() * a.height();
        let mut acc = BurstAccumulator {
            norm,
            frames: 0,
            sums: vec![[0; 4]; n],
            clipped: vec![false; n],
            first: RawImage {
                width: first.width,
                height: first.height,
                data: vec![],
                meta: first.meta.clone(),
            },
        };
        acc.add_unchecked(&first);
        acc.first.data = first.data;
        Ok(acc)
    }

    /// Add a frame; errors unless it matches the first in geometry, CFA, levels and ISO.
    pub fn add(&mut self, img: &RawImage) -> Result<()> {
        // Compare metadata without the pixel data.
        let probe = RawImage {
            width: img.width,
            height: img.height,
            data: vec![],
            meta: img.meta.clone(),
        };
        let mut first = RawImage {
            width: self.first.width,
            height: self.first.height,
            data: vec![],
            meta: self.first.meta.clone(),
        };
        first.meta.storage = None;
        check_same_capture(
            &first,
            &probe,
            SameCapture {
                iso: true,
                levels: true,
            },
        )?;
        img.validate()?;
        if img.data == self.first.data {
            return Err(Error::invalid(
                "frame is identical to the first frame of the burst (the same file twice?)",
            ));
        }
        self.add_unchecked(img);
        Ok(())
    }

    fn add_unchecked(&mut self, img: &RawImage) {
        let a = img.active_area();
        let (w, h) = (a.width(), a.height());
        let half = 2 * (self.frames % 2);
        for r in 0..h {
            let start = (r + a.top as usize) * img.width + a.left as usize;
            let Some(row) = img.data.get(start..start + w) else {
                continue;
            };
            for (c, &x) in row.iter().enumerate() {
                let i = r * w + c;
                let l = self.norm.linearize(x);
                if x == 0 || l >= self.norm.white {
                    self.clipped[i] = true;
                }
                let l = l as u64;
                self.sums[i][half] += l;
                self.sums[i][half + 1] += l * l;
            }
        }
        self.frames += 1;
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Per-pixel mean and variance, binned. Errors with fewer than two frames.
    pub fn finish(self) -> Result<SourceStats> {
        let n = self.frames as u64;
        if n < MIN_BURST_FRAMES as u64 {
            return Err(Error::invalid(format!(
                "a burst needs at least {MIN_BURST_FRAMES} frames (split-half variance estimate), got {n}"
            )));
        }
        let bayer = self.first.bayer()?;
        let a = self.first.active_area();
        let (w, h) = (a.width(), a.height());
        let scale = self.norm.scale;
        let mut accs = vec![[Acc::default(); 4]; NBINS];
        let mut clipped = [0u64; 4];
        // Frames per half: even frames 0, 2, 4, ... and odd frames 1, 3, ...
        let ne = n.div_ceil(2);
        let no = n / 2;
        let split = no >= 2; // always true past the frame-count check
        let moments = |s: u64, ss: u64, k: u64| -> (f64, f64) {
            let (s, ss, kk) = (s as u128, ss as u128, k as u128);
            let var = (kk * ss - s * s) as f64 / (k * (k - 1)) as f64;
            (s as f64 / k as f64, var)
        };
        for r in 0..h {
            for c in 0..w {
                let i = r * w + c;
                let p = Bayer::position(r, c);
                if self.clipped[i] {
                    clipped[p] += 1;
                    continue;
                }
                let [se, sse, so, sso] = self.sums[i];
                let black = self.norm.black_at(r, c);
                let norm = |m: f64| (m - black) / scale;
                // (binning mean, measured mean, measured variance, dof)
                let mut samples: [(f64, f64, f64, f64); 2] = [(0.0, 0.0, 0.0, 0.0); 2];
                let used = if split {
                    let (me, ve) = moments(se, sse, ne);
                    let (mo, vo) = moments(so, sso, no);
                    samples[0] = (norm(mo), norm(me), ve, (ne - 1) as f64);
                    samples[1] = (norm(me), norm(mo), vo, (no - 1) as f64);
                    2
                } else {
                    let (m, v) = moments(se + so, sse + sso, n);
                    samples[0] = (norm(m), norm(m), v, (n - 1) as f64);
                    1
                };
                for (k, &(yb, ym, v, dof)) in samples[..used].iter().enumerate() {
                    if let Some(b) = bin_index(yb) {
                        let acc = &mut accs[b][p];
                        // Pixels are counted once (by the first half's binning).
                        acc.n += u64::from(k == 0);
                        acc.sy += ym * dof;
                        acc.sv += v / (scale * scale) * dof;
                        acc.sr += dof;
                    }
                }
            }
        }
        let bins = std::array::from_fn(|p| {
            accs.iter()
                .filter(|a| a[p].sr > 0.0)
                .map(|a| {
                    let a = a[p];
                    BinStat {
                        mean: a.sy / a.sr,
                        var: a.sv / a.sr,
                        dof: a.sr,
                        pixels: a.n,
                    }
                })
                .collect()
        });
        Ok(SourceStats {
            kind: "burst",
            iso: iso_of(&self.first)?,
            bayer,
            black: self.first.meta.levels.black_max(),
            white: self.first.meta.levels.white,
            camera: camera_of(&self.first),
            bins,
            clipped,
            frames: self.frames,
        })
    }
}
