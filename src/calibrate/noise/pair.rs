//! Binned statistics of a clean/noisy pair ([`pair_stats`]).

use super::{bin_index, camera_of, iso_of, Acc, BinStat, SourceStats, NBINS};
use crate::calibrate::{check_same_capture, SameCapture};
use crate::error::{Error, Result};
use crate::normalize::Normalizer;
use crate::raw::{Bayer, RawImage};

/// Binned residual statistics of a clean/noisy pair (ISO and levels from the noisy frame).
/// Both are normalized with their own levels, so the clean may be a `merge` output (levels
/// scaled by the frame count); they must share geometry and CFA. The residual variance also
/// holds the clean frame's own noise: a merge of N frames at the noisy frame's ISO adds 1/N.
pub fn pair_stats(clean: &RawImage, noisy: &RawImage) -> Result<SourceStats> {
    check_same_capture(
        clean,
        noisy,
        SameCapture {
            iso: false,
            levels: false,
        },
    )?;
    let norm = Normalizer::new(noisy)?;
    let cnorm = Normalizer::new(clean)?;
    let bayer = noisy.bayer()?;
    let iso = iso_of(noisy)?;
    if clean.data == noisy.data {
        return Err(Error::invalid(
            "the clean and noisy frames are identical: no residual to measure",
        ));
    }
    let a = noisy.active_area();
    let (w, h) = (a.width(), a.height());
    let mut accs = vec![[Acc::default(); 4]; NBINS];
    let mut clipped = [0u64; 4];
    for r in 0..h {
        let start = (r + a.top as usize) * noisy.width + a.left as usize;
        let (Some(rc), Some(rn)) = (
            clean.data.get(start..start + w),
            noisy.data.get(start..start + w),
        ) else {
            continue;
        };
        for (c, (&xc, &xn)) in rc.iter().zip(rn).enumerate() {
            let p = Bayer::position(r, c);
            let (lc, ln) = (cnorm.linearize(xc), norm.linearize(xn));
            if xc == 0 || xn == 0 || lc >= cnorm.white || ln >= norm.white {
                clipped[p] += 1;
                continue;
            }
            let y = cnorm.normalize(xc, r, c);
            if let Some(b) = bin_index(y) {
                let yn = norm.normalize(xn, r, c);
                let d = yn - y;
                let acc = &mut accs[b][p];
                acc.n += 1;
                // Binned by the clean value, but the bin's intensity is the mean of the NOISY
                // values: their noise is independent of the binning, so it estimates
                // E[x | bin] without the shrinkage the clean frame's own noise would bring.
                acc.sy += yn;
                acc.sr += d;
                acc.srr += d * d;
            }
        }
    }
    let bins = std::array::from_fn(|p| {
        accs.iter()
            .filter(|a| a[p].n > 1)
            .map(|a| {
                let a = a[p];
                let nf = a.n as f64;
                BinStat {
                    mean: a.sy / nf,
                    var: ((a.srr - a.sr * a.sr / nf) / (nf - 1.0)).max(0.0),
                    dof: nf - 1.0,
                    pixels: a.n,
                }
            })
            .collect()
    });
    Ok(SourceStats {
        kind: "pair",
        iso,
        bayer,
        black: noisy.meta.levels.black_max(),
        white: noisy.meta.levels.white,
        camera: camera_of(noisy),
        bins,
        clipped,
        frames: 2,
    })
}
