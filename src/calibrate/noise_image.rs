//! `calibrate noise --from-image`: noise models from ordinary day images, one ISO point per
//! input ISO, by the single-image Poisson-Gaussian estimate synth itself falls back on
//! ([`crate::noise::estimate`](mod@crate::noise::estimate), docs/noise.md). Images at the same ISO are combined per
//! position by inverse-variance weights of their fits; an image whose fit cannot be trusted
//! is left out with a warning (an ISO none of whose images can be trusted is an error).

use super::format::{IsoModel, PositionFit};
use crate::diagnostics::{Code, Diagnostics};
use crate::error::{Error, Result};
use crate::noise::estimate::{estimate, EstimateOptions, NoiseEstimate};
use crate::raw::RawImage;
use std::collections::BTreeMap;

/// One input's estimate, with the levels its parameters are in.
#[derive(Debug, Clone)]
pub struct ImageEstimate {
    /// Input name (for messages).
    pub name: String,
    /// Exif ISO (or the assumed one).
    pub iso: u32,
    /// Black level (max over the plane), DN.
    pub black: f64,
    /// White level, DN.
    pub white: f64,
    /// The estimate.
    pub estimate: NoiseEstimate,
}

/// Estimate the noise of one image (its Exif ISO must be known: `--assume-iso` sets it).
pub fn estimate_image(name: &str, img: &RawImage, opts: &EstimateOptions) -> Result<ImageEstimate> {
    let iso = img.meta.exif.iso.filter(|&i| i > 0).ok_or_else(|| {
        Error::invalid(
            "the image has no Exif ISO: the noise model is indexed by ISO (calibrate noise \
             --assume-iso N gives one)",
        )
    })?;
    // The range every reader of the model takes (synth refuses a model at another ISO).
    crate::bounds::iso("the image's ISO", iso)?;
    Ok(ImageEstimate {
        name: name.into(),
        iso,
        black: img.meta.levels.black_max(),
        white: img.meta.levels.white,
        estimate: estimate(img, opts)?,
    })
}

/// One model per ISO from image estimates, and warnings (untrusted images left out; images
/// of different levels at one ISO). Errors when no image of some ISO can be trusted.
pub fn from_image_estimates(images: &[ImageEstimate]) -> Result<(Vec<IsoModel>, Diagnostics)> {
    let mut by_iso: BTreeMap<u32, Vec<&ImageEstimate>> = BTreeMap::new();
    for e in images {
        by_iso.entry(e.iso).or_default().push(e);
    }
    let mut warnings = Diagnostics::new();
    let mut out = vec![];
    for (iso, list) in by_iso {
        let mut trusted = vec![];
        for e in list {
            match e.estimate.trusted() {
                Ok(_) => trusted.push(e),
                Err(why) => warnings.warn(
                    Code::CalibrateImageUntrusted,
                    format!(
                        "{}: the noise estimated from the image cannot be trusted ({why}); left out",
                        e.name
                    ),
                ),
            }
        }
        let Some(first) = trusted.first() else {
            return Err(Error::invalid(format!(
                "ISO {iso}: no image gives a noise estimate that can be trusted (see the \
                 warnings); calibrate from a burst (--burst) or a pair (--pair) instead"
            )));
        };
        if trusted
            .iter()
            .any(|e| e.black != first.black || e.white != first.white)
        {
            warnings.warn(
                Code::CalibrateLevelsDiffer,
                format!(
                    "ISO {iso}: the images have different black or white levels; their normalized \
                 estimates are combined as they are"
                ),
            );
        }
        let scale = first.white - first.black;
        let q = first.estimate.quantization_variance_removed;
        let fits: Vec<PositionFit> = (0..4)
            .map(|p| {
                // Inverse-variance weights per parameter (equal weights when an error is 0).
                let pe: Vec<_> = trusted.iter().map(|e| &e.estimate.positions[p]).collect();
                let wmean = |v: &dyn Fn(usize) -> (f64, f64)| -> (f64, f64) {
                    if pe.len() == 1 {
                        // One image: its own figures, bit for bit (what synth uses).
                        return v(0);
                    }
                    let (mut sw, mut s) = (0.0, 0.0);
                    for i in 0..pe.len() {
                        let (x, se) = v(i);
                        let w = if se > 0.0 { 1.0 / (se * se) } else { 1.0 };
                        sw += w;
                        s += w * x;
                    }
                    (s / sw, (1.0 / sw).sqrt())
                };
                let (s, s_se) = wmean(&|i| (pe[i].s, pe[i].s_stderr));
                let (o, o_se) = wmean(&|i| (pe[i].o, pe[i].o_stderr));
                let beta1 = s * scale;
                PositionFit {
                    position: p,
                    color: pe[0].color.clone(),
                    s,
                    o,
                    s_stderr: Some(s_se),
                    o_stderr: Some(o_se),
                    beta1,
                    beta2: o * scale * scale - first.black * beta1,
                    r2: None,
                    chi2_reduced: None,
                    bins: pe.iter().map(|x| x.bins).sum(),
                    // Each smooth block holds 4 sites of this position.
                    pixels: 4 * pe.iter().map(|x| x.smooth_blocks).sum::<u64>(),
                    clipped_pixels: 4 * pe.iter().map(|x| x.clipped_blocks).sum::<u64>(),
                }
            })
            .collect();
        out.push(IsoModel {
            iso,
            positions: std::array::from_fn(|p| [fits[p].s, fits[p].o]),
            source: "image_estimate".into(),
            black: first.black,
            white: first.white,
            inputs: trusted.len(),
            quantization_variance_removed: q,
            fits,
        });
    }
    Ok((out, warnings))
}
